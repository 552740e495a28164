"""Steady states of a cylinder plant: at rest holding its load, and in steady motion.

Both solve the plant's own equations (:meth:`plants.base.OdePlant.casadi_functions`)
with the piston held at a position ``x_pos`` and the friction states zero,
scaled by the plant's state scales, by Newton's method with the exact
Jacobian (``scipy.optimize.root``):

:func:`equilibrium`
    at rest (``v = 0``): the chamber pressures, the valve states and the
    command ``u`` for which no state but ``x`` changes -- the load held;
:func:`steady_motion`
    under a given constant command ``u``: the speed ``v``, the chamber
    pressures and the valve states for which nothing but ``x`` changes -- the
    speed the valve allows (the valve-limited speed at full command).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
from scipy.optimize import root

from fcomp.errors import ConvergenceError


def _solve(plant: Any, x_pos: float, free: list[str], u: float | None,
           guess: dict[str, float], what: str, zero: list[str] | None = None
           ) -> tuple[np.ndarray, float]:
    """The state at ``x_pos`` with the states ``free`` (and ``u`` if ``None``) unknown and
    the derivatives of the states ``zero`` (default: all but ``x`` and the friction
    states) zero; the other states at ``guess`` or their defaults."""
    names = plant.state_names
    fr = set(plant.friction.state_names)
    zero = zero if zero is not None else [n for n in names if n != "x" and n not in fr]
    eqs = [names.index(n) for n in zero]
    rhs = plant.casadi_functions()["rhs"]
    x0 = plant.initial_state({"x": x_pos, **guess})
    idx = [names.index(n) for n in free]
    scale = np.asarray(plant.ode_model().scales, dtype=float)
    xs = ca.SX.sym("xs", len(free))
    us = ca.SX.sym("u")
    state = ca.DM(x0)
    state = ca.vertcat(*[xs[idx.index(i)] * scale[i] if i in idx else state[i]
                         for i in range(len(names))])
    f = rhs(state, us if u is None else u)
    res = ca.vertcat(*[f[i] / scale[i] for i in eqs])
    z = ca.vertcat(xs, us) if u is None else xs
    F = ca.Function("eq", [z], [res, ca.jacobian(res, z)])
    z0 = x0[idx] / scale[idx]
    if u is None:
        z0 = np.concatenate([z0, [0.0]])
    sol = root(lambda q: np.asarray(F(q)[0]).ravel(), z0,
               jac=lambda q: np.asarray(F(q)[1]), method="hybr", tol=1e-13)
    resid = np.abs(np.asarray(F(sol.x)[0])).max()
    if not sol.success and resid > 1e-9:
        raise ConvergenceError(f"no {what} of plant {plant.name} at x = {x_pos} m "
                               f"({sol.message})")
    out = x0.copy()
    out[idx] = sol.x[:len(idx)] * scale[idx]
    return out, (float(sol.x[-1]) if u is None else float(u))


def unreachable(plant: Any, load: bool = True) -> str | None:
    """Why no command can hold (``load``) or move the piston, said before any iteration
    (``None``: nothing rules it out): a valve that passes no flow, a supply not above the
    return, or -- ``load`` -- a load beyond the force the pressures can give
    (:func:`plants.mechanics.force_range`). Without this, each is only "the iteration is
    not making good progress"."""
    from plants.mechanics import force_range, hold_force

    p = plant.plant_params.flat()
    if "kv" in p:  # the hydraulic servo valve: Q = cd*w*(U + kv*u)*sqrt(2*dp/rho)
        if p["cd"] * p["w"] == 0.0 or p["kv"] == 0.0:
            return (f"its valve's flow does not follow the command (kv = {p['kv']:g} m/A, cd = "
                    f"{p['cd']:g}, w = {p['w']:g} m): no command moves the piston or holds a "
                    "load")
        low, name = p["pt"], "the return pt"
    elif "A_valve" in p:  # the pneumatic valve
        if p["A_valve"] == 0.0:
            return "its valve passes no flow (A_valve = 0): no command moves the piston"
        low, name = p["p_atm"], "the atmosphere p_atm"
    else:
        return None
    if not p["ps"] > low:
        return (f"its supply ps = {p['ps']:g} Pa is not above {name} = {low:g} Pa (absolute): "
                "the valve cannot drive the piston")
    if load:
        f_low, f_high = force_range(p)
        hold = hold_force(p)
        if not f_low < hold < f_high:
            return (f"holding its load takes {hold:.4g} N (F_load {p['F_load']:g} N with the "
                    f"weight), beyond the {f_low:.4g} to {f_high:.4g} N its pressures can give")
    return None


def equilibrium(plant: Any, x_pos: float) -> tuple[np.ndarray, float]:
    """State at rest at ``x_pos`` holding the load, and the valve command doing it.

    Unknowns: the chamber pressures, the valve states and the command ``u``;
    equations: zero derivative of ``v``, ``p1``, ``p2`` and the valve
    states, with ``x = x_pos``, ``v = 0`` and friction states zero. A plant that
    cannot hold its load (:func:`unreachable`) is refused with the cause first.
    """
    why = unreachable(plant)
    if why is not None:
        raise ConvergenceError(f"no equilibrium of plant {plant.name} at x = {x_pos} m: {why}")
    fr = set(plant.friction.state_names)
    free = [n for n in plant.state_names if n not in ("x", "v") and n not in fr]
    return _solve(plant, x_pos, free, None, {}, "equilibrium")


def steady_motion(plant: Any, x_pos: float, u: float, v_guess: float) -> np.ndarray:
    """State in steady motion through ``x_pos`` under the constant command ``u``.

    Unknowns: the speed, the chamber pressures and the valve states (started from
    ``v_guess`` m/s and the default state); equations: zero derivative of all of
    them. Friction states are held at zero (a frictionless piston, or a static map).
    """
    why = unreachable(plant, load=False)
    if why is not None:
        raise ConvergenceError(f"no steady motion of plant {plant.name} at x = {x_pos} m: "
                               f"{why}")
    fr = set(plant.friction.state_names)
    free = [n for n in plant.state_names if n != "x" and n not in fr]
    # the valve first (its states follow the command alone), then everything from there
    valve = [n for n in free if n not in ("v", "p1", "p2")]
    start, _ = _solve(plant, x_pos, valve, u, {"v": v_guess}, "steady valve", zero=valve)
    guess = {n: float(start[plant.state_names.index(n)]) for n in valve}
    state, _ = _solve(plant, x_pos, free, u, {"v": v_guess, **guess}, "steady motion")
    return state


class Equilibria:
    """Equilibria at rest of one plant at many positions and parameter values.

    :func:`equilibrium`'s equations (at rest, ``v = 0``, friction states zero: the
    chamber pressures, the valve states and the command ``u`` holding the load), with the
    CasADi residual and its Jacobian built *once*, the position and the parameter vector
    ``p`` (:meth:`plants.base.OdePlant.param_vector`) its inputs -- the loop analysis
    solves hundreds (:mod:`controllers.loop_analysis`).
    """

    def __init__(self, plant: Any) -> None:
        names = list(plant.state_names)
        fr = set(plant.friction.state_names)
        self.plant = plant
        self.free = [n for n in names if n not in ("x", "v") and n not in fr]
        zero = [n for n in names if n != "x" and n not in fr]
        rhs = plant.casadi_functions(symbolic_params=True)["rhs"]
        scale = np.asarray(plant.ode_model().scales, dtype=float)
        idx = [names.index(n) for n in self.free]
        self.idx, self.scale = idx, scale
        zs = ca.SX.sym("z", len(idx) + 1)
        pos = ca.SX.sym("pos")
        p = ca.SX.sym("p", rhs.size1_in(2))
        rest = plant.initial_state()  # v = 0 and the friction states at rest
        rest[names.index("v")] = 0.0
        state = []
        for i, n in enumerate(names):
            if i in idx:
                state.append(zs[idx.index(i)] * scale[i])
            elif n == "x":
                state.append(pos)
            else:
                state.append(float(rest[i]))
        self._rest = rest
        f = rhs(ca.vertcat(*state), zs[-1], p)
        res = ca.vertcat(*[f[names.index(n)] / scale[names.index(n)] for n in zero])
        self._F = ca.Function("equilibria", [zs, pos, p], [res, ca.jacobian(res, zs)])
        self._names = names
        self._last: np.ndarray | None = None

    def solve(self, x_pos: float, p: np.ndarray) -> tuple[np.ndarray, float]:
        """The state at rest at ``x_pos`` holding the load, and its command, for the
        parameters ``p``; started from the last solution (or the default state)."""
        F = self._F
        if self._last is None:
            x0 = self.plant.initial_state({"x": x_pos})
            z0 = np.concatenate([x0[self.idx] / self.scale[self.idx], [0.0]])
        else:
            z0 = self._last
        sol = root(lambda q: np.asarray(F(q, x_pos, p)[0]).ravel(), z0,
                   jac=lambda q: np.asarray(F(q, x_pos, p)[1]), method="hybr", tol=1e-13)
        resid = np.abs(np.asarray(F(sol.x, x_pos, p)[0])).max()
        if not sol.success and resid > 1e-9:
            raise ConvergenceError(f"no equilibrium of plant {self.plant.name} at x = {x_pos} m "
                                   f"({sol.message})")
        self._last = sol.x
        out = self._rest.copy()
        out[self._names.index("x")] = x_pos
        out[self.idx] = sol.x[:-1] * self.scale[self.idx]
        return out, float(sol.x[-1])


__all__ = ["Equilibria", "equilibrium", "steady_motion", "unreachable"]
