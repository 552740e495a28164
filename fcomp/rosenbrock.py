"""Rosenbrock (linearly implicit) methods: frozen tableaus and one generic step.

A Rosenbrock method advances ``dx/dt = f(t, x)`` by ``h`` with ``s`` stages,
each one linear solve with the same matrix (Hairer & Wanner, *Solving ODEs
II*, 2nd ed., Springer 1996, Sec. IV.7, in the form of their ``rodas.f``)::

    (I/(h*gamma) - J) K_i = f(t + alpha_i*h, x + sum_j a_ij K_j) + h*gamma_i*f_t
                            + sum_j c_ij/h K_j,                          i = 1..s
    x_new = x + sum_i m_i K_i,        err = sum_i e_i K_i,

``J = df/dx`` and ``f_t = df/dt`` at ``(t, x)`` (for an input ``u(t) = u_0 +
du*t``: ``f_t = df/du*du``). A method is its :class:`RosenbrockTableau`, a
frozen value (diffrax keeps its tableaus the same way); :func:`rosenbrock_stages`
is the one step that reads it, written against array operations only, so
the same code is the numeric step of the engine's Python driver (numpy,
LU-solved), the symbolic step of discrete-time models (CasADi,
:func:`rosenbrock_step`) and, rendered from the same tableau, the stage loop
of the compiled driver (:mod:`fcomp.simulation`).

Tableaus
--------
:data:`RODAS4`
    4th order, L-stable, stiffly accurate, embedded 3rd-order error
    estimate (Hairer & Wanner's ``rodas.f``, METH = 1): the simulation engine.
:data:`LINEARLY_IMPLICIT_EULER`
    one stage, ``gamma = 1``, ``m = 1``: ``x_new = x + h*(I - h*J)^-1*f``,
    first order, L-stable and smooth in ``x`` and ``u`` -- the controllers'
    prediction model (:func:`linearly_implicit_euler`: the EKF's step and,
    with its step Jacobians, the MPC's).

Step-size control (:class:`StepControl`): ``h_new = h*clip(safety*en^(-1/q),
fac_min, fac_max)`` with ``en`` the RMS of the scaled error and ``q`` the
tableau's controller order; the compiled driver receives the same constants.

The compiled driver (``fcomp/csrc/rosenbrock_step.c``) is a C template whose
coefficients are filled from a tableau and a control by :func:`c_coefficients`:
the numbers are written once, here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np


@dataclass(frozen=True)
class RosenbrockTableau:
    """The coefficients of a Rosenbrock method in the form of the module docstring.

    Attributes
    ----------
    name
        Method name.
    gamma
        Diagonal ``gamma`` of the stage matrix ``I/(h*gamma) - J``.
    a, c
        Lower-triangular stage couplings (row ``i`` has ``i`` entries).
    m, e
        Solution and error weights (one per stage).
    alpha, gammas
        Stage times and the sums ``gamma_i`` of the non-autonomous terms.
    order
        Exponent of the step-size controller: ``min(order, embedded order) + 1``.
    """

    name: str
    gamma: float
    a: tuple[tuple[float, ...], ...]
    c: tuple[tuple[float, ...], ...]
    m: tuple[float, ...]
    e: tuple[float, ...]
    alpha: tuple[float, ...]
    gammas: tuple[float, ...]
    order: int

    @property
    def stages(self) -> int:
        return len(self.m)

    def __post_init__(self) -> None:
        s = self.stages
        rows_ok = all(len(self.a[i]) == i and len(self.c[i]) == i for i in range(s))
        if not (rows_ok and len(self.a) == len(self.c) == len(self.e) == len(self.alpha)
                == len(self.gammas) == s):
            raise ValueError(f"tableau {self.name}: inconsistent coefficient shapes")


RODAS4 = RosenbrockTableau(
    name="rodas4",
    gamma=0.25,
    a=(
        (),
        (1.544,),
        (0.9466785280815826, 0.2557011698983284),
        (3.314825187068521, 2.896124015972201, 0.9986419139977817),
        (1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950),
        (1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950, 1.0),
    ),
    c=(
        (),
        (-5.6688,),
        (-2.430093356833875, -0.2063599157091915),
        (-0.1073529058151375, -9.594562251023355, -20.47028614809616),
        (7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160),
        (8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136,
         -6.058818238834054),
    ),
    m=(1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950, 1.0, 1.0),
    e=(0.0, 0.0, 0.0, 0.0, 0.0, 1.0),
    alpha=(0.0, 0.386, 0.21, 0.63, 1.0, 1.0),
    gammas=(0.25, -0.1043, 0.1035, -0.03620000000000023, 0.0, 0.0),
    order=4,
)

LINEARLY_IMPLICIT_EULER = RosenbrockTableau(
    name="linearly-implicit-euler", gamma=1.0, a=((),), c=((),), m=(1.0,), e=(0.0,),
    alpha=(0.0,), gammas=(1.0,), order=1,
)


def _combine(terms: list[tuple[float, Any]]) -> Any:
    """``sum(w*K)`` over the terms with a non-zero weight (``None`` if there are none)."""
    out = None
    for w, k in terms:
        if w != 0.0:
            out = w * k if out is None else out + w * k
    return out


def rosenbrock_stages(tab: RosenbrockTableau, x: Any, h: Any,
                      rhs: Callable[[int, Any], Any],
                      solve: Callable[[Any], Any]) -> tuple[Any, Any]:
    """One step of the method ``tab`` (module docstring): ``(x_new, err)``.

    Parameters
    ----------
    tab
        The tableau.
    x, h
        State and step size (numpy arrays / floats, or CasADi SX).
    rhs
        ``rhs(i, Y_i)``: stage ``i``'s ``f(t + alpha_i*h, Y_i) + h*gamma_i*f_t``.
    solve
        ``solve(r)``: ``(I/(h*gamma) - J)^-1 r`` (the caller factorises once).
    """
    K: list[Any] = []
    for i in range(tab.stages):
        shift = _combine(list(zip(tab.a[i], K, strict=True)))
        r = rhs(i, x if shift is None else x + shift)
        for j, cij in enumerate(tab.c[i]):
            r = r + (cij / h) * K[j]
        K.append(solve(r))
    step = _combine(list(zip(tab.m, K, strict=True)))
    err = _combine(list(zip(tab.e, K, strict=True)))
    return x + step, (0.0 * K[0] if err is None else err)


@dataclass(frozen=True)
class StepControl:
    """Step-size control of the adaptive drivers (module docstring)."""

    safety: float = 0.9
    fac_min: float = 0.2
    fac_max: float = 6.0

    def factor(self, en: float, order: int) -> float:
        """The step-size factor for the scaled error norm ``en``."""
        fac = self.fac_max if en == 0 else min(self.fac_max, self.safety * en ** (-1.0 / order))
        return max(fac, self.fac_min)


STEP_CONTROL = StepControl()


def _c_array(rows: Any, width: int | None = None) -> str:
    """A C initialiser of the numbers ``rows`` (``width``: rows padded with zeros to it)."""
    if width is None:
        return "{" + ", ".join(repr(float(v)) for v in rows) + "}"
    return "{" + ", ".join(_c_array(list(r) + [0.0] * (width - len(r))) for r in rows) + "}"


def c_coefficients(tab: RosenbrockTableau, control: StepControl) -> dict[str, str]:
    """The method's placeholders of the compiled driver ``fcomp/csrc/rosenbrock_step.c`` as
    C literals (:func:`fcomp.compiled.c_source`): the stage count ``NS``, the controller
    order ``ORDER``, ``GAMMA``, the stage couplings ``RA``, ``RC`` (row ``i`` padded with
    zeros to ``max(s - 1, 1)`` entries), the weights ``RM``, ``RE``, the stage times
    ``ALPHA``, the sums ``GAMS`` (module docstring) and the control's ``SAFETY``,
    ``FACMIN``, ``FACMAX`` (:class:`StepControl`). Floats are written by :func:`repr`, which
    round-trips: the C constants are the Python ones, bit for bit."""
    width = max(tab.stages - 1, 1)
    return {
        "NS": str(tab.stages), "ORDER": str(tab.order), "GAMMA": repr(tab.gamma),
        "RA": _c_array(tab.a, width), "RC": _c_array(tab.c, width), "RM": _c_array(tab.m),
        "RE": _c_array(tab.e), "ALPHA": _c_array(tab.alpha), "GAMS": _c_array(tab.gammas),
        "SAFETY": repr(control.safety), "FACMIN": repr(control.fac_min),
        "FACMAX": repr(control.fac_max),
    }


def rosenbrock_step(
    f: Callable[[Any, Any], Any], x: Any, u: Any, du: Any, h: Any, scale: Any = None,
    tab: RosenbrockTableau = RODAS4,
) -> tuple[Any, Any]:
    """One step of ``dx/dt = f(x, u)``, ``du/dt = du``, as CasADi SX expressions.

    Parameters
    ----------
    f
        ``f(x, u) -> dx/dt`` on CasADi SX column vectors.
    x, u, du, h
        State, input at the start of the step, input rate (0 for a held
        input) and step size (SX).
    scale
        Nominal magnitude of each state. The step is computed for ``x/scale``
        (mathematically the same step: Rosenbrock methods are invariant under
        a constant scaling of the state) so that the linear solves see a
        well-scaled matrix -- a hydraulic Jacobian spans 1e-6 m to 1e7 Pa.
    tab
        The method (default :data:`RODAS4`).

    Returns
    -------
    x_new, err
        The state after the step and the embedded error estimate (SX).
    """
    if scale is not None:
        xn, err = rosenbrock_step(lambda a, b: f(a * scale, b) / scale, x / scale, u, du, h,
                                  tab=tab)
        return xn * scale, err * scale
    xs = ca.SX.sym("xs", x.size1())
    us = ca.SX.sym("us", u.size1())
    fx = f(xs, us)
    J = ca.substitute(ca.jacobian(fx, xs), ca.vertcat(xs, us), ca.vertcat(x, u))
    ft = ca.mtimes(ca.substitute(ca.jacobian(fx, us), ca.vertcat(xs, us), ca.vertcat(x, u)), du)
    M = ca.SX.eye(x.size1()) / (h * tab.gamma) - J

    def rhs(i: int, y: Any) -> Any:
        return f(y, u + (tab.alpha[i] * h) * du) + (h * tab.gammas[i]) * ft

    return rosenbrock_stages(tab, x, h, rhs, lambda r: ca.solve(M, r))


def linearly_implicit_euler(f: ca.Function, dt: float, scales: np.ndarray | None,
                            substeps: int = 1, *, sensitivities: bool = False) -> ca.Function:
    """``(x, u, p) -> x_next`` by ``substeps`` linearly implicit Euler steps over ``dt`` (s).

    Each step of ``h = dt/substeps`` is the one-stage Rosenbrock method
    :data:`LINEARLY_IMPLICIT_EULER` with the input held, solved in the scaled
    states ``xi = x/scales``: ``x_next = x + S*(I/h - S^-1 J S)^-1 S^-1 f`` with
    ``S = diag(scales)`` (unscaled, ``I - h*J`` of the hydraulic servo spans
    1e-6 .. 1e12 and the symbolic solve loses the valve state to rounding;
    scaled it is close to the identity).

    ``scales`` ``None`` makes the scales the function's fourth input ``s``
    (``(x, u, p, s) -> ...``, the same arithmetic): the scales of a model
    follow its parameters (a bristle state's scale is ``g/sigma0``), and as an
    input they let one compiled function serve every parameter value.

    With ``sensitivities`` the function returns ``(x_next, A, B)``, the step's
    own Jacobians with the change of ``J`` along the step neglected (an
    inexact-Jacobian SQP's): ``A_1 = S*M^-1*S^-1/h``, ``M = I/h - S^-1 J S``,
    ``B_1 = h*A_1*df/du``, chained over the substeps.
    """
    if substeps < 1:
        raise ValueError("substeps must be >= 1")
    nx = f.size1_in(0)
    tab = LINEARLY_IMPLICIT_EULER
    x = ca.SX.sym("x", nx)
    u = ca.SX.sym("u", f.size1_in(1))
    p = ca.SX.sym("p", f.size1_in(2))
    ins, names = [x, u, p], ["x", "u", "p"]
    S: ca.SX | ca.DM
    Si: ca.SX | ca.DM
    if scales is None:
        s = ca.SX.sym("s", nx)
        S, Si = s, 1.0 / s
        ins, names = [*ins, s], [*names, "s"]
    else:
        sc = np.asarray(scales, dtype=float).ravel()
        if sc.size != nx or not np.all(sc > 0):
            raise ValueError("scales must be one positive number per state")
        S, Si = ca.DM(sc), ca.DM(1.0 / sc)
    h = dt / substeps
    fx = f(x, u, p)
    M = ca.SX.eye(nx) / (h * tab.gamma) - ca.jacobian(fx, x) * (Si @ S.T)

    def rhs(i: int, y: Any) -> Any:
        return Si * fx  # the state at the step's start: one stage

    zero = ca.SX.zeros(nx)  # the stages give the scaled increment; x + S*increment
    if not sensitivities:
        dxi, _ = rosenbrock_stages(tab, zero, h, rhs, lambda r: ca.solve(M, r))
        one = ca.Function("linearly_implicit_euler_step", ins, [ca.cse(x + S * dxi)])
        xk = x
        for _ in range(substeps):
            xk = one(xk, *ins[1:])
        return ca.Function("linearly_implicit_euler", ins, [ca.cse(xk)], names, ["x_next"])
    Minv = ca.solve(M, ca.SX.eye(nx))
    dxi, _ = rosenbrock_stages(tab, zero, h, rhs, lambda r: ca.mtimes(Minv, r))
    A1 = ca.mtimes(ca.diag(S), ca.mtimes(Minv, ca.diag(Si))) / (h * tab.gamma)
    one = ca.Function("linearly_implicit_euler_substep", ins,
                      [ca.cse(x + S * dxi), ca.cse(A1),
                       ca.cse(h * ca.mtimes(A1, ca.jacobian(fx, u)))])
    x_next, A, B = one(*ins)
    for _ in range(substeps - 1):
        x_next, A2, B2 = one(x_next, *ins[1:])
        A, B = ca.mtimes(A2, A), ca.mtimes(A2, B) + B2
    return ca.Function("linearly_implicit_euler_sens", ins,
                       [ca.cse(x_next), ca.cse(A), ca.cse(B)], names,
                       ["x_next", "A", "B"])
