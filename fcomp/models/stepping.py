"""The sampled step of a friction model: exponential Rosenbrock-Euler, one source.

Between samples ``t_k`` and ``t_{k+1}`` the signals are held at their interval
means (:func:`midpoint_signals`) and the states advance by the *exponential
Rosenbrock-Euler* step with the diagonal of the exact (CasADi) Jacobian
``J = diag(df/dx)`` (Hochbruck & Ostermann, "Exponential integrators", Acta
Numerica 19, 2010, Sec. 2.4)::

    x_{k+1} = x_k + h*phi1(h*J)*f(x_k),   phi1(y) = (exp(y) - 1)/y,

``substeps`` times per interval (:func:`exponential_euler`). For the LuGre
family it is *exact* for a held velocity: the bristle equation ``dz/dt = v -
sigma0*|v|*z/g`` is linear in ``z`` at fixed ``v``, the film equation linear in
``h``. States with hard limits are projected back onto their admissible set
after every step (:meth:`~fcomp.models.base.FrictionModel.project`).

:func:`friction_step` builds the step as one CasADi function of ``(x,
signals, dt, params)``; :func:`step_loop` rolls it over a record, compiled to
native code (:mod:`fcomp.compiled`) and cached per model structure, so one
compiled loop serves every parameter value. :func:`motion_kernel` is the
whole friction along a motion in one native loop: signal preparation, step
and force. The engine along a motion
(:mod:`fcomp.trajectory`), the exact sensitivities of identification
(:mod:`fcomp.identification.sensitivity`), the carrier of the hysteresis model
(:mod:`fcomp.models.hysteresis`) and the LuGre observer
(:mod:`controllers.lugre_observer`) all take their step from here.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from fcomp.backend import CASADI
from fcomp.compiled import EXPORT, HIDDEN, MINMAX, Keyed, Loop, load_library, stepping_loop
from fcomp.models.base import SIGNAL_NAMES, FrictionModel, Signals
from fcomp.parameters import ParamValues


def phi1(y: Any) -> Any:
    """``phi1(y) = (exp(y) - 1)/y`` as a CasADi expression (``1 + y/2`` near 0)."""
    return ca.if_else(ca.fabs(y) < 1e-8, 1.0 + 0.5 * y, ca.expm1(y) / y)


def exponential_euler(f: Any, x: Any, h: Any, exact: list[Any | None] | None = None) -> Any:
    """One exponential Rosenbrock-Euler step ``x + h*phi1(h*J)*f`` of ``dx/dt = f(x)``.

    ``f`` is the right-hand side as a CasADi expression of the symbol ``x``;
    ``J`` the diagonal of its Jacobian. Where ``exact`` gives a state's value
    after the step in closed form
    (:meth:`~fcomp.models.base.FrictionModel.base_exact_steps`), that is taken
    instead. Returns the new state (expression of ``x``).
    """
    step = x + h * phi1(h * ca.diag(ca.jacobian(f, x))) * f
    if exact is not None and any(e is not None for e in exact):
        step = ca.vertcat(*[step[i] if e is None else e for i, e in enumerate(exact)])
    return step


def structure_key(model: FrictionModel) -> tuple:
    """Identity of a model's equations: models with equal keys share compiled code."""
    return (
        type(model),
        tuple((type(e), tuple(sorted(e.config.items()))) for e in model.effects),
        tuple(model.flat_params()),
    )


def friction_step(model: FrictionModel, substeps: int = 1) -> ca.Function:
    """The CasADi step ``(x, sig, dt, p) -> x_next`` of the scheme above.

    ``sig`` is the interval-mean signal vector ``[v, a, x, p1, p2, s]``, ``p``
    the flat parameters in the order of :meth:`FrictionModel.flat_params`.
    Identification differentiates this same step for exact sensitivities.
    """
    model.require_symbolic()
    nx = model.n_states
    names = list(model.flat_params())
    x = ca.SX.sym("x", nx)
    sig, sigv = Signals.symbolic()
    dt = ca.SX.sym("dt")
    p, P = ParamValues.symbolic(names)
    h = dt / substeps
    xl = [x[i] for i in range(nx)]
    one = exponential_euler(ca.vertcat(*model.rhs(CASADI, xl, sig, P)), x, h,
                            model.exact_steps(CASADI, xl, sig, P, h))
    proj = ca.vertcat(*model.project(CASADI, xl, sig, P))
    xk = x
    for _ in range(substeps):
        xk = ca.substitute(proj, x, ca.substitute(one, x, xk))
    return ca.Function("fcomp_friction_step", [x, sigv, dt, p], [xk])


#: Most model structures whose compiled kernels are kept (each cache, least recently used out).
KERNEL_CACHE_SIZE = 64


def _keyed(model: FrictionModel) -> Keyed[FrictionModel]:
    """``model`` as the key of the kernel caches: by :func:`structure_key`."""
    return Keyed(model, structure_key(model))


@lru_cache(maxsize=KERNEL_CACHE_SIZE)
def _loop(structure: Keyed[FrictionModel], substeps: int, compiled: bool) -> Loop:
    return stepping_loop(friction_step(structure.value, substeps), compiled=compiled)


def step_loop(model: FrictionModel, substeps: int = 1, compiled: bool = True) -> Loop:
    """The compiled loop ``(x0, M, dt, p) -> X`` of :func:`friction_step` (cached by
    :func:`structure_key`): ``M`` the interval-mean signals ``(N-1, 6)``."""
    return _loop(_keyed(model), substeps, compiled)


def midpoint_signals(sig: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Interval-mean signals ``(6, N-1)`` in :data:`~fcomp.models.base.SIGNAL_NAMES` order,
    and ``dt``; the side of an interval at rest is the side at its start."""
    mid = {k: 0.5 * (sig[k][1:] + sig[k][:-1]) for k in ("v", "a", "x", "p1", "p2")}
    s_mid = np.sign(mid["v"])
    s_mid = np.where(s_mid == 0, sig["s"][:-1], s_mid)
    M = np.vstack([mid["v"], mid["a"], mid["x"], mid["p1"], mid["p2"], s_mid])
    return M, np.diff(sig["t"])


# ------------------------------------------------------------ the motion kernel
_MOTION_DRIVER = r"""
/* fcomp's friction along a motion in one pass (fcomp.models.stepping.motion_kernel):
   at every sample the side s (sign(v), held at v = 0), the position (trapezoidal integral
   of v when not given), the force F_k = FORCE(x_k, sig_k, p); then the interval means,
   dt and the step x_{k+1} = STEP(x_k, mid_k, dt_k, p). The model functions are generated
   once per side (s = +1, -1 substituted), and flattened into this loop. Returns 1 if a
   signal is not finite or the time not strictly increasing, else 0. */
#if defined(__GNUC__)
#define FCOMP_FLATTEN __attribute__((flatten))
#else
#define FCOMP_FLATTEN
#endif
FCOMP_EXPORT FCOMP_FLATTEN int fcomp_motion(int n, const double* restrict t,
    const double* restrict v, const double* restrict a, const double* restrict xs,
    const double* restrict p1, const double* restrict p2, int xint, int stx, int st1, int st2,
    const double* restrict x0, const double* restrict p, double* restrict X,
    double* restrict F, double* restrict out) {
  const casadi_real* arg[SZ_ARG];
  casadi_real* res[SZ_RES];
  casadi_int iw[SZ_IW];
  casadi_real w[SZ_W];
  double cur[6], mid[6], dt = 0.0, chk = 0.0, s, vn, an, xn, p1n, p2n, xi, xg;
  double *ov = out, *oa = out + n, *ox = out + 2 * n, *op1 = out + 3 * n, *op2 = out + 4 * n,
         *os = out + 5 * n;
  int bad = 0, j, k;
  for (j = 0; j < NX; ++j) X[j] = x0[j];
  cur[0] = v[0]; cur[1] = a[0]; cur[2] = xint ? 0.0 : xs[0]; cur[3] = p1[0]; cur[4] = p2[0];
  s = cur[0] < 0 ? -1.0 : 1.0;
  cur[5] = s;
  chk += t[0] - t[0];
  for (k = 0;; ++k) {
    ov[k] = cur[0]; oa[k] = cur[1]; ox[k] = cur[2]; op1[k] = cur[3]; op2[k] = cur[4]; os[k] = s;
    chk += (cur[0] - cur[0]) + (cur[1] - cur[1]) + (cur[2] - cur[2]) + (cur[3] - cur[3])
           + (cur[4] - cur[4]);
    arg[0] = X + k * NX; arg[1] = cur; arg[2] = p; res[0] = F + k;
    if (s > 0) FORCE_POS(arg, res, iw, w, 0); else FORCE_NEG(arg, res, iw, w, 0);
    if (k == n - 1) break;
    dt = t[k + 1] - t[k];
    bad |= !(dt > 0);
    chk += dt - dt;
    vn = v[k + 1]; an = a[k + 1];
    xi = cur[2] + 0.5 * (vn + cur[0]) * dt; xg = xs[(k + 1) * stx];
    xn = xint ? xi : xg;
    p1n = p1[(k + 1) * st1]; p2n = p2[(k + 1) * st2];
    mid[0] = 0.5 * (vn + cur[0]); mid[1] = 0.5 * (an + cur[1]); mid[2] = 0.5 * (xn + cur[2]);
    mid[3] = 0.5 * (p1n + cur[3]); mid[4] = 0.5 * (p2n + cur[4]);
    mid[5] = mid[0] > 0 ? 1.0 : (mid[0] < 0 ? -1.0 : s);
#if NX > 0
    arg[0] = X + k * NX; arg[1] = mid; arg[2] = &dt; arg[3] = p; res[0] = X + (k + 1) * NX;
    if (mid[5] > 0) STEP_POS(arg, res, iw, w, 0); else STEP_NEG(arg, res, iw, w, 0);
#endif
    s = vn > 0 ? 1.0 : (vn < 0 ? -1.0 : s);
    cur[0] = vn; cur[1] = an; cur[2] = xn; cur[3] = p1n; cur[4] = p2n; cur[5] = s;
  }
  return bad || chk != 0.0;
}
"""


@dataclass(frozen=True)
class MotionKernel:
    """Friction along a sampled motion in one native pass (:func:`motion_kernel`).

    Calling it with the time ``t``, the signals ``v``, ``a`` (arrays of the
    samples), ``x`` (array, one value, or ``None``: the trapezoidal integral
    of ``v`` from 0), ``p1``, ``p2`` (arrays or one value), the initial state
    and the flat parameters (in :meth:`FrictionModel.flat_params` order)
    returns ``(X, F, S)``: the states ``(N, n_states)``, the force ``(N,)``
    and the signals ``(6, N)`` in :data:`~fcomp.models.base.SIGNAL_NAMES`
    order (the side ``s`` computed); ``None`` when a signal is not finite or
    the time is not strictly increasing (the caller reports which).
    """

    run: Callable[..., int]
    n_states: int

    def __call__(self, t: np.ndarray, v: np.ndarray, a: np.ndarray, x: np.ndarray | None,
                 p1: np.ndarray, p2: np.ndarray, x0: np.ndarray, p: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        n = t.size
        X = np.empty((n, self.n_states))
        F = np.empty(n)
        S = np.empty((6, n))
        xs = _ZERO if x is None else x
        bad = self.run(n, t.ctypes.data, v.ctypes.data, a.ctypes.data, xs.ctypes.data,
                       p1.ctypes.data, p2.ctypes.data, int(x is None), int(xs.size > 1),
                       int(p1.size > 1), int(p2.size > 1), x0.ctypes.data, p.ctypes.data,
                       X.ctypes.data, F.ctypes.data, S.ctypes.data)
        return None if bad else (X, F, S)


_ZERO = np.zeros(1)


def _sided(name: str, inputs: list[ca.SX], out: ca.SX, side: ca.SX) -> list[ca.Function]:
    """``inputs -> out`` with the side symbol ``side`` set to +1 and to -1 (the side's
    parameter choices fold away); one function when ``out`` does not read the side."""
    if not ca.depends_on(out, side):
        return [ca.Function(name, inputs, [out])]
    return [ca.Function(f"{name}_{tag}", inputs, [ca.substitute(out, side, ca.SX(val))])
            for tag, val in (("pos", 1.0), ("neg", -1.0))]


@lru_cache(maxsize=KERNEL_CACHE_SIZE)
def _motion_kernel(structure: Keyed[FrictionModel], substeps: int) -> MotionKernel | None:
    model = structure.value
    nx = model.n_states
    x = ca.SX.sym("x", nx)
    sig, sigv = Signals.symbolic()
    p, P = ParamValues.symbolic(list(model.flat_params()))
    F = ca.SX(model.force(CASADI, [x[i] for i in range(nx)], sig, P))
    fns = _sided("fcomp_motion_force", [x, sigv, p], F, sig.s)
    names = {"FORCE_POS": fns[0].name(), "FORCE_NEG": fns[-1].name()}
    if nx:
        mid = ca.SX.sym("mid", len(SIGNAL_NAMES))
        dt = ca.SX.sym("dt")
        xn = friction_step(model, substeps)(x, mid, dt, p)
        steps = _sided("fcomp_motion_step", [x, mid, dt, p], xn, mid[SIGNAL_NAMES.index("s")])
        names |= {"STEP_POS": steps[0].name(), "STEP_NEG": steps[-1].name()}
        fns += steps
    sizes = {"SZ_ARG": max(f.sz_arg() for f in fns), "SZ_RES": max(f.sz_res() for f in fns),
             "SZ_IW": max(f.sz_iw() for f in fns) + 1, "SZ_W": max(f.sz_w() for f in fns) + 1}
    macros = "".join(f"#define {k} {v}\n" for k, v in {**names, **sizes, "NX": nx}.items())
    dll = load_library(fns, EXPORT + macros + _MOTION_DRIVER, prelude=HIDDEN + MINMAX)
    if dll is None:
        return None
    fn = dll.fcomp_motion
    vp, ci = ctypes.c_void_p, ctypes.c_int
    fn.argtypes = [ci, vp, vp, vp, vp, vp, vp, ci, ci, ci, ci, vp, vp, vp, vp, vp]
    fn.restype = ci
    return MotionKernel(fn, nx)


def motion_kernel(model: FrictionModel, substeps: int = 1) -> MotionKernel | None:
    """The native kernel of the friction along a motion (cached by :func:`structure_key`):
    signal preparation, :func:`friction_step` and the force at every sample in one loop.

    The scheme is that of :func:`midpoint_signals` and :func:`friction_step` with
    the force of :meth:`FrictionModel.force` at the samples, sample for sample.
    Each model function is generated twice, with the side ``s = +1`` and ``s =
    -1`` substituted (the side's parameter choices fold away), and inlined into
    one C loop that never leaves native code (:data:`~fcomp.compiled.HIDDEN`,
    :data:`~fcomp.compiled.MINMAX`). ``None`` without a C compiler or a
    usable compile cache (:mod:`fcomp.compiled`; callers then take the stepping
    loop and numpy).
    """
    model.require_symbolic()
    return _motion_kernel(_keyed(model), substeps)
