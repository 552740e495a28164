"""A cylinder plant linearised at rest holding its load, and sampled with a zero-order hold.

The loop analysis of :mod:`controllers.loop_analysis` needs the plant as the
controller sees it between two samples: the valve command held over the
period ``dt`` (zero-order hold), the position and the two chamber pressures
measured at the sampling instants. At a piston position ``x_pos`` the plant's
own equations (:meth:`plants.base.OdePlant.casadi_functions`: the valve's
spool dynamics, the orifice-law (hydraulic) or ISO 6358 (pneumatic) flows with
their flow gain and flow-pressure coefficient, the chambers with ``beta/V``
or ``kappa*p/V`` at that position, the piston and its load) are linearised
exactly (CasADi's Jacobian) at the equilibrium that holds the load there
(:func:`plants.equilibrium.equilibrium`, end stops not touched)::

    d(dx)/dt = A dx + B du,      dy = C dx,      y = [x, p1, p2]

Friction enters as its **sliding slope** ``c`` (N s/m, the seal's viscous
damping, ``dv/dt -= c/m*v``) on a piston without friction states: the loop of
a sliding piston, with no pre-sliding stiffness (a bristle spring at rest
would add stiffness and damping that hold only within micrometres). The
sampled form is the exact zero-order-hold discretisation (``control.c2d``,
``'zoh'``: ``Ad = exp(A dt)``, ``Bd = int_0^dt exp(A s) ds B``; Franklin,
Powell & Workman, *Digital Control of Dynamic Systems*, 3rd ed., 1998,
sec. 4.3).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from scipy.linalg import expm

from fcomp.errors import FcompError

#: The measured outputs, in the order of a controller's measurement ``y``.
MEASURED = ("x", "p1", "p2")


@dataclass(frozen=True)
class LinearPlant:
    """A plant linearised at rest at one position and sampled (module docstring).

    Attributes
    ----------
    A, B : numpy.ndarray
        Continuous-time Jacobians ``df/dx``, ``df/du`` at the equilibrium.
    Ad, Bd : numpy.ndarray
        Their zero-order-hold discretisation at ``dt``.
    C : numpy.ndarray
        ``(3, n)``: the measured states ``x, p1, p2`` (absolute pressures, as the
        sensors give them).
    Ad, Bd : numpy.ndarray
        ``exp(A dt)`` and ``int_0^dt exp(A s) ds B`` (``Bd`` of shape ``(n, 1)``).
    Fd : numpy.ndarray
        ``(n, 1)``: the same for a force (N) on the piston, extending, held over the
        period (a load step, the disturbance friction is).
    state_names : tuple of str
        The plant's states (no friction states).
    state : numpy.ndarray
        The equilibrium state.
    command : float
        The valve command holding the load there.
    position : float
        The piston position (m).
    dt : float
        Sample period (s).
    """

    A: np.ndarray
    B: np.ndarray
    Ad: np.ndarray
    Bd: np.ndarray
    C: np.ndarray
    state_names: tuple[str, ...]
    state: np.ndarray
    command: float
    position: float
    dt: float
    Fd: np.ndarray | None = None

    @property
    def measurement(self) -> np.ndarray:
        """The measurement ``y = [x, p1, p2]`` at the equilibrium."""
        return self.C @ self.state

    def column_mode(self) -> tuple[float, float]:
        """Natural frequency (rad/s) and damping ratio of the oil (air) column: the fastest
        oscillating pair of the block ``v, p1, p2`` (valve held), or its fastest real pole."""
        idx = [self.state_names.index(n) for n in ("v", "p1", "p2")]
        poles = np.linalg.eigvals(self.A[np.ix_(idx, idx)])
        pair = [p for p in poles if abs(p.imag) > 0]
        p = max(pair or list(poles), key=abs)
        wn = float(abs(p))
        return wn, (float(-p.real / wn) if wn > 0 else 1.0)


class Linearisation:
    """Linearisations of one plant at many positions and parameter values (module docstring).

    The CasADi Jacobians and the equilibrium's residual are built once
    (:class:`plants.equilibrium.Equilibria`), the parameter vector ``p``
    (:meth:`plants.base.OdePlant.param_vector`) an input.

    Parameters
    ----------
    plant : plants.base.OdePlant
        A cylinder plant. Its friction is either a memoryless map -- the sliding piston:
        pass a frictionless one (:func:`plants.check.frictionless`) and the sliding slope as
        ``damping`` -- or a model with the bristle state ``z`` (pre-sliding at rest: the
        seal's stiffness ``sigma0`` and damping ``sigma1`` linearised with the plant).
    dt : float
        Sample period (s) of the zero-order hold.
    """

    def __init__(self, plant: Any, dt: float) -> None:
        from plants.equilibrium import Equilibria

        fr = plant.friction
        if fr.static_map and fr.n_states:
            raise FcompError(f"the loop analysis linearises a sliding piston (a friction map "
                             f"without states) or one at rest in pre-sliding (a bristle state "
                             f"z); {fr.describe()} is neither")
        self.plant = plant
        self.dt = float(dt)
        self.names = tuple(plant.state_names)
        self.static = bool(fr.static_map)
        fns = plant.casadi_functions(symbolic_params=True)
        self._jac = fns["jacobians"]
        x = ca.SX.sym("x", len(self.names))
        u = ca.SX.sym("u", 1)
        p = ca.SX.sym("p", fns["rhs"].size1_in(2))
        i_load = list(plant.flat_params()).index("F_load")  # opposes extension
        self._load = ca.Function("load_jac", [x, u, p],
                                 [-ca.jacobian(fns["rhs"](x, u, p), p)[:, i_load]])
        self.equilibria = Equilibria(plant)
        self.C = np.zeros((len(MEASURED), len(self.names)))
        for row, n in enumerate(MEASURED):
            self.C[row, self.names.index(n)] = 1.0
        self.stroke = float(plant.plant_params.flat()["stroke"])
        self._v_eps = float(fr.flat_params().get("v_eps", 1e-5))
        self._scales = np.concatenate([np.asarray(plant.ode_model().scales, dtype=float),
                                       [1.0]])

    def at(self, x_pos: float, p: np.ndarray | None = None, damping: float = 0.0,
           equilibrium: tuple[np.ndarray, float] | None = None) -> LinearPlant:
        """The plant with parameters ``p`` (default its own) linearised at rest at ``x_pos``.

        ``damping`` (N s/m) is the sliding slope of a memoryless friction (ignored, and
        refused if not 0, with a bristle state); ``equilibrium`` ``(state, u)`` skips the
        solve (the same load held by another friction regime).
        """
        if not 0.0 < x_pos < self.stroke:
            raise FcompError(f"position {x_pos:g} m is outside the stroke (0, {self.stroke:g}) m")
        if p is None:
            p = self.plant.param_vector()
        if equilibrium is None:
            x0, u0 = self.equilibria.solve(x_pos, p)
        else:
            x0, u0 = equilibrium
            x0 = np.concatenate([x0, self.plant.initial_state()[len(x0):]])
        A, B, _C, _D = (np.asarray(m, dtype=float) for m in self._jac(x0, [u0], p))
        load = np.asarray(self._load(x0, [u0], p), dtype=float).ravel()
        iv = self.names.index("v")
        mass = float(p[list(self.plant.flat_params()).index("mass")])
        if self.static:
            # At rest a static map's Karnopp stick band (plants.mechanics) clips the stuck
            # force between its break-away levels; for a frictionless piston both are 0 and
            # the Jacobian of that clip at the tie is a subgradient (a quarter of the applied
            # force's derivatives and a damping m/(4*tau_stick) taken off the piston's
            # row), not physics. The piston's row is taken just outside the band
            # (v = 2*v_eps, where the map of a frictionless piston is 0 and smooth), its
            # velocity entry the friction's sliding slope.
            slide = np.asarray(x0, dtype=float).copy()
            slide[iv] = 2.0 * self._v_eps
            A_s, B_s, _c, _d = (np.asarray(m, dtype=float) for m in self._jac(slide, [u0], p))
            A[iv], B[iv] = A_s[iv], B_s[iv]
            load[iv] = float(np.asarray(self._load(slide, [u0], p)).ravel()[iv])
            A[iv, iv] = -float(damping) / mass
        elif damping:
            raise FcompError("a friction model with a bristle state brings its own damping")
        names = self.names
        if "z" in names:
            # At rest the bristle follows the piston, dz/dt = v (the decay sigma0*|v|*z/g
            # vanishes): x - z is conserved, an uncontrollable pole at s = 0 that only
            # moves the bristle's anchor. With the anchor at the equilibrium, z = x - x0:
            # the z-column joins the x-column and z leaves the state.
            ix, iz = names.index("x"), names.index("z")
            A[:, ix] += A[:, iz]
            keep = [i for i in range(len(names)) if i != iz]
            A, B = A[np.ix_(keep, keep)], B[keep]
            x0 = np.asarray(x0, dtype=float)[keep]
            names = tuple(names[i] for i in keep)
            load = load[keep]
            scales = self._scales[[*keep, len(self.names)]]
        else:
            scales = self._scales
        n = A.shape[0]
        M = np.zeros((n + 2, n + 2))  # inputs: the command, a force on the piston
        M[:n, :n], M[:n, n] = A * self.dt, B[:, 0] * self.dt
        M[:n, n + 1] = load * self.dt
        D = np.concatenate([scales, [mass]])  # exp(D^-1 M D) = D^-1 exp(M) D
        Ms = M * (1.0 / D)[:, None] * D[None, :]
        Ms[np.abs(Ms) < 1e-15 * np.abs(Ms).max()] = 0.0  # round-off dust (subnormals are slow)
        E = D[:, None] * expm(Ms) / D[None, :]
        C = np.zeros((len(MEASURED), n))
        for row, m in enumerate(MEASURED):
            C[row, names.index(m)] = 1.0
        return LinearPlant(A=A, B=B, Ad=E[:n, :n], Bd=E[:n, n:n + 1], C=C,
                           state_names=names, state=np.asarray(x0, dtype=float),
                           command=float(u0), position=float(x_pos), dt=self.dt,
                           Fd=E[:n, n + 1:n + 2])


def linearise(plant: Any, x_pos: float, dt: float, damping: float = 0.0) -> LinearPlant:
    """The plant linearised at rest at ``x_pos`` and sampled at ``dt`` (:class:`Linearisation`,
    once).

    Parameters
    ----------
    plant : plants.base.OdePlant
        A cylinder plant, frictionless (the sliding piston, with the slope ``damping``) or
        with a bristle-state friction (pre-sliding at rest); its parameters are those
        analysed.
    x_pos : float
        Piston position (m), inside the stroke.
    dt : float
        Sample period (s) of the zero-order hold.
    damping : float
        The friction's sliding slope ``c`` (N s/m) of a frictionless piston.

    Raises
    ------
    FcompError
        A friction neither frictionless-map nor bristle, a position outside the stroke.
    ConvergenceError
        No equilibrium holds the load there.
    """
    return Linearisation(plant, dt).at(x_pos, damping=damping)


__all__ = ["MEASURED", "LinearPlant", "Linearisation", "linearise"]
