"""The simulation engine: one integrator for every plant, open and closed loop.

A plant hands the engine an :class:`OdeModel`: the CasADi function
``f(x, u, p) -> dx/dt`` of its equations (written once against the backend,
:mod:`fcomp.backend`), the names of its states and inputs and a nominal
magnitude (*scale*) per state. The engine integrates it over a grid of
sample instants ``t_0 < t_1 < ... < t_N`` and returns the state at every
instant.

Inputs between samples
----------------------
The input is given at the sample instants. Between ``t_k`` and ``t_{k+1}``
it is either *held* (``hold="zoh"``, zero-order hold: the sampled-data
closed loop, a controller output held until the next sample) or *linearly
interpolated* (``hold="linear"``, first-order hold: an open-loop input such
as a sine, error ``h^2/8*|u''|`` for an output interval ``h``). Every
integration step ends exactly on the sample instants, so the kinks of the
held input are never stepped over.

Methods (:data:`METHODS`, selected by name like ``solve_ivp``'s)
-----------------------------------------------------------------
``rodas4`` (default)
    The 4th-order, L-stable, stiffly accurate Rosenbrock method RODAS4
    (Hairer & Wanner, *Solving ODEs II*, 2nd ed., Springer 1996, Sec. IV.7,
    coefficients of their ``rodas.f``) with its embedded 3rd-order error
    estimate and step-size control. Each step uses the *exact* Jacobians
    ``df/dx`` and ``df/du`` (CasADi, symbolic) and one LU factorisation with
    partial pivoting of ``I/(h*gamma) - J`` in scaled variables ``x/scale``
    (a hydraulic Jacobian spans 1e-6 m to 1e7 Pa); the input enters as a
    known function of time (its rate ``du/dt`` through the non-autonomous
    terms), so the method is exact for the held or linear input. The
    model's ``f`` and Jacobians are generated as C by CasADi and compiled
    with the adaptive loop over all samples (:func:`fcomp.compiled.load_library`):
    no Python per step. The loop is the C template ``fcomp/csrc/rosenbrock_step.c``
    (package data), its coefficients filled from the tableau
    (:func:`fcomp.rosenbrock.c_coefficients`); the kernels of the last
    :data:`KERNEL_CACHE_SIZE` model structures are kept (:func:`clear_kernel_cache`). Without a C compiler the same loop runs in Python
    (same decisions, slower). The same RODAS4 step is also available as a
    CasADi expression (:func:`rosenbrock_step`), for the discrete-time model
    of :meth:`OdeModel.discrete_step`.
``radau``, ``bdf``, ``lsoda``
    :func:`scipy.integrate.solve_ivp` with the CasADi right-hand side and the
    exact Jacobian (reference methods; slower).

Accuracy
--------
Step sizes are chosen so that the estimated local error of every state
satisfies ``|err_i| <= atol*scale_i + rtol*|x_i|`` (RMS over the states
below 1). ``scale_i`` is the plant's nominal magnitude of the state (stroke
for position, supply pressure for pressures, ...), so ``atol`` is a
*relative* number like ``rtol``. Defaults ``rtol = atol = 1e-6``
(:data:`DEFAULT_TOLERANCES`); the tests compare against an independent
integration at ``1e-10`` and document the global error reached.

Failures
--------
A step size below ``h_min`` (default ``1e-13`` s), more than ``max_steps``
steps, or a non-finite state raises :class:`~fcomp.errors.ConvergenceError`
naming the time at which the integration stopped. ``max_steps`` bounds the
whole run of :func:`integrate`, whatever the method (for ``radau``, ``bdf``
and ``lsoda`` it counts their accepted steps), and the whole open-loop run
of a plant with discrete-memory friction (:mod:`plants.discrete_memory`);
a closed loop (:class:`Stepper`) bounds each sample.

Progress
--------
Inside ``with fcomp.progress.reporting(callback):`` long runs report
``callback(done, total)`` in seconds of simulated time from the start of the
run (:mod:`fcomp.progress`; the command line shows it on a terminal through
:func:`progress`); the run is then integrated in pieces of whole sample
intervals, which changes nothing in the RODAS4 result (its step size carries
over, its decisions are made per interval).

Closed loops
------------
:class:`Stepper` advances a model by one controller sample with the input
held: ``reset(x0)``, then ``step(u) -> x`` for every sample (the step size
carries over from sample to sample), or ``advance(u, dt)`` for an interval of
any length -- the stepper contract of :mod:`fcomp.stepper`. The plants build
it with :meth:`plants.base.OdePlant.stepper`.
"""

from __future__ import annotations

import ctypes
import math
import re
from abc import ABC, abstractmethod
from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache
from typing import Any, ClassVar

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg import lu_factor, lu_solve

from fcomp.compiled import Keyed, c_source, load_library
from fcomp.errors import ConvergenceError, FcompError, term
from fcomp.progress import receiver, report
from fcomp.registry import Registry
from fcomp.rosenbrock import (
    RODAS4,
    STEP_CONTROL,
    c_coefficients,
    linearly_implicit_euler,
    rosenbrock_stages,
    rosenbrock_step,
)
from fcomp.stepper import SampledStepper

#: The advice when a run needs more steps than allowed.
_RAISE_OR_LOOSEN = f"raise {term('max_steps')}, or loosen {term('rtol')}/{term('atol')}"

#: Schemes of :meth:`OdeModel.discrete_step` (fixed steps, input held).
SCHEMES = ("rodas4", "linearly-implicit-euler")


def step_budget(tol: Tolerances, stats: Stats, t: float, name: str) -> Tolerances:
    """``tol`` with ``max_steps`` lowered to what is left of the run's budget after ``stats``;
    :class:`ConvergenceError` when nothing is left."""
    left = tol.max_steps - (stats.steps + stats.rejected)
    if left < 1:
        raise ConvergenceError(
            f"simulation of {name} stopped at t = {t:.6g} s: more than {term('max_steps')} = "
            f"{tol.max_steps} steps were needed ({_RAISE_OR_LOOSEN})")
    return tol if left == tol.max_steps else replace(tol, max_steps=left)

# ------------------------------------------------------------------ RODAS4
#: The engine's method (:data:`fcomp.rosenbrock.RODAS4`) and its step-size control.
TABLEAU = RODAS4
CONTROL = STEP_CONTROL

# ------------------------------------------------------------------- model
@dataclass(frozen=True)
class OdeModel:
    """An ODE ``dx/dt = f(x, u, p)`` as the engine sees it.

    Attributes
    ----------
    name
        Label for messages and compiled-code names (C identifier characters).
    rhs
        CasADi function ``(x[nx], u[nu], p[np]) -> dx[nx]`` built on SX.
    state_names, input_names
        Names of the states and inputs.
    scales
        Nominal magnitude of every state (its unit), used by the error norm.
    key
        Structural identity: models with equal keys share compiled code.
    """

    name: str
    rhs: ca.Function
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    scales: np.ndarray
    key: tuple = ()

    @property
    def nx(self) -> int:
        return len(self.state_names)

    @property
    def nu(self) -> int:
        return len(self.input_names)

    @property
    def tag(self) -> str:
        """``name`` as a C / CasADi identifier (letters, digits, single underscores)."""
        tag = re.sub(r"[^A-Za-z0-9]+", "_", self.name).strip("_")
        return tag if tag[:1].isalpha() else "m_" + tag

    @cached_property
    def n_params(self) -> int:
        return int(self.rhs.size1_in(2))

    def symbols(self) -> tuple[Any, Any, Any]:
        """Fresh SX symbols ``(x, u, p)``."""
        return ca.SX.sym("x", self.nx), ca.SX.sym("u", self.nu), ca.SX.sym("p", self.n_params)

    def discrete_step(self, dt: float, substeps: int = 1, *, scheme: str = "rodas4",
                      sensitivities: bool = False, scale_input: bool = False) -> ca.Function:
        """``step(x, u, p) -> x(t + dt)``: ``substeps`` fixed steps of ``scheme``, input held.

        The discrete-time model of the plant for predictions and filters:
        differentiable in CasADi (exact Jacobians with :func:`casadi.jacobian`).
        ``scheme`` is ``"rodas4"`` (4th order, :data:`fcomp.rosenbrock.RODAS4`)
        or ``"linearly-implicit-euler"`` (first order, L-stable and smooth: the
        prediction model of the EKF and the MPC,
        :func:`fcomp.rosenbrock.linearly_implicit_euler`); with
        ``sensitivities`` the latter also returns its step Jacobians ``A``, ``B``,
        and with ``scale_input`` takes the state scales as a fourth input ``s``
        (``step(x, u, p, s)``: one compiled function for every parameter value,
        though the scales of the friction states follow the parameters).
        """
        if not (math.isfinite(dt) and dt > 0):
            raise FcompError(f"discrete step: dt must be a positive number of seconds, got {dt}")
        if substeps < 1:
            raise FcompError(f"discrete step: substeps must be >= 1, got {substeps}")
        if scheme not in SCHEMES:
            raise FcompError(f"discrete step: scheme must be one of {', '.join(SCHEMES)}, "
                             f"got {scheme!r}")
        if scheme == "linearly-implicit-euler":
            x, u, p = self.symbols()
            f = ca.Function("f", [x, u, p], [self.rhs(x, u, p)])
            return linearly_implicit_euler(f, dt, None if scale_input else self.scales,
                                           substeps, sensitivities=sensitivities)
        if sensitivities or scale_input:
            raise FcompError("discrete step: step Jacobians and scales as an input are given "
                             "for the linearly-implicit-euler scheme")
        x, u, p = self.symbols()
        h = dt / substeps
        xk = x
        scale = ca.DM(self.scales)
        for _ in range(substeps):
            xk, _err = rosenbrock_step(lambda a, b: self.rhs(a, b, p), xk, u,
                                       ca.SX.zeros(self.nu), ca.SX(h), scale)
        return ca.Function(f"{self.tag}_discrete", [x, u, p], [ca.cse(xk)],
                           ["x", "u", "p"], ["x_next"])


# -------------------------------------------------------------- tolerances
@dataclass(frozen=True)
class Tolerances:
    """Error control of the engine (see the module docstring).

    Attributes
    ----------
    rtol, atol
        Relative tolerance and absolute tolerance *in units of each state's
        scale* (both dimensionless).
    h_min
        Smallest step (s) before the integration is declared failed.
    max_steps
        Largest number of steps (accepted + rejected) of one run.
    h0
        First trial step (s).
    """

    rtol: float = 1e-6
    atol: float = 1e-6
    h_min: float = 1e-13
    max_steps: int = 10_000_000
    h0: float = 1e-6

    def __post_init__(self) -> None:
        for name in ("rtol", "atol"):
            val = getattr(self, name)
            if not (isinstance(val, int | float) and math.isfinite(val) and 1e-14 <= val <= 0.1):
                raise FcompError(f"{term(name)} must be a number between 1e-14 and 0.1, "
                                 f"got {val!r}")
        if not (math.isfinite(self.h_min) and self.h_min > 0):
            raise FcompError(f"h_min must be a positive number of seconds, got {self.h_min!r}")
        if not (isinstance(self.max_steps, int) and self.max_steps >= 1):
            raise FcompError(f"{term('max_steps')} must be a positive integer, "
                             f"got {self.max_steps!r}")
        if not (math.isfinite(self.h0) and self.h0 > 0):
            raise FcompError(f"h0 must be a positive number of seconds, got {self.h0!r}")


DEFAULT_TOLERANCES = Tolerances()


@dataclass
class Stats:
    """Work done by one run: accepted and rejected steps, right-hand-side calls."""

    steps: int = 0
    rejected: int = 0
    nfev: int = 0
    njev: int = 0

    def add(self, other: Stats) -> None:
        """Accumulate the work of another run."""
        self.steps += other.steps
        self.rejected += other.rejected
        self.nfev += other.nfev
        self.njev += other.njev

    def as_dict(self) -> dict[str, int]:
        return {"steps": self.steps, "rejected": self.rejected, "nfev": self.nfev,
                "njev": self.njev}


# ----------------------------------------------------------------- methods
class Integrator(ABC):
    """Base of the integration methods: ``run`` integrates over sample intervals.

    ``run(x0, U, dU, dt, p, tol, h, t0)`` integrates from ``x0`` over the
    intervals ``dt[k]`` with the input ``U[k] + dU[k]*(t - t_k)`` on interval
    ``k`` and returns ``(X, stats, h)``: the states at the ``n + 1`` instants,
    the work done and the step size to continue with; ``t0`` (s) is the time
    of ``x0``, for messages.
    """

    name: ClassVar[str] = ""

    def __init__(self, model: OdeModel) -> None:
        self.model = model

    @abstractmethod
    def run(self, x0: np.ndarray, U: np.ndarray, dU: np.ndarray, dt: np.ndarray,
            p: np.ndarray, tol: Tolerances, h: float,
            t0: float = 0.0) -> tuple[np.ndarray, Stats, float]:
        """Integrate over the sample intervals (the contract in the class docstring)."""


#: Models whose compiled kernels are kept (least recently used dropped first).
KERNEL_CACHE_SIZE = 64


@lru_cache(maxsize=KERNEL_CACHE_SIZE)
def _model_functions(structure: Keyed[OdeModel]) -> tuple[ca.Function, ca.Function]:
    """``f(x, u, p) -> dx`` and ``jac(x, u, p) -> (df/dx, df/du)`` (dense), C-friendly names."""
    model = structure.value
    x, u, p = model.symbols()
    f = model.rhs(x, u, p)
    F = ca.Function(f"fcomp_f_{model.tag}", [x, u, p], [f])
    Jf = ca.Function(f"fcomp_j_{model.tag}", [x, u, p],
                     [ca.densify(ca.jacobian(f, x)), ca.densify(ca.jacobian(f, u))])
    return F, Jf


@lru_cache(maxsize=KERNEL_CACHE_SIZE)
def _rodas_library(structure: Keyed[OdeModel]) -> Any:
    """The compiled adaptive loop of ``structure``'s model (``fcomp/csrc/rosenbrock_step.c``
    filled with the model's functions and the tableau), or ``None`` without a compiler."""
    F, Jf = _model_functions(structure)
    model = structure.value
    driver = c_source("rosenbrock_step.c", {
        "F": F.name(), "J": Jf.name(), "NX": str(model.nx), "NU": str(model.nu),
        **c_coefficients(TABLEAU, CONTROL)})
    dll = load_library([F, Jf], driver)
    if dll is None:
        return None
    c_fn = dll.fcomp_ode
    dp = ctypes.POINTER(ctypes.c_double)
    c_fn.argtypes = [ctypes.c_int] + [dp] * 10
    c_fn.restype = ctypes.c_int
    return c_fn


def clear_kernel_cache() -> None:
    """Forget the kernels of every model (they are built again on next use; the compiled
    libraries stay in the on-disk cache of :mod:`fcomp.compiled`)."""
    _rodas_library.cache_clear()
    _model_functions.cache_clear()


class Rodas4(Integrator):
    """Adaptive RODAS4, compiled to C (see the module docstring)."""

    name = "rodas4"

    def __init__(self, model: OdeModel, *, compiled: bool = True) -> None:
        super().__init__(model)
        # models of equal keys share their kernels (else the model itself is the key)
        structure = Keyed(model, model.key or (model.name, id(model)))
        self.F, self.Jf = _model_functions(structure)
        self.c_fn = _rodas_library(structure) if compiled else None
        self._one: list[np.ndarray] | None = None  # buffers of one-interval calls (closed loops)
        self._one_ptrs: list[Any] = []

    @property
    def compiled(self) -> bool:
        return self.c_fn is not None

    def _buffers(self, n: int) -> list[np.ndarray]:
        m = self.model
        shapes = [(m.nx,), (n, m.nu), (n, m.nu), (n,), (m.n_params,), (m.nx,), (4,), (1,),
                  (n + 1, m.nx), (6,)]
        if n == 1 and self._one is not None:
            return self._one
        bufs = [np.zeros(sh) for sh in shapes]
        if n == 1 and self.c_fn is not None:
            dp = ctypes.POINTER(ctypes.c_double)
            self._one, self._one_ptrs = bufs, [b.ctypes.data_as(dp) for b in bufs]
        return bufs

    def run(self, x0: np.ndarray, U: np.ndarray, dU: np.ndarray, dt: np.ndarray,
            p: np.ndarray, tol: Tolerances, h: float,
            t0: float = 0.0) -> tuple[np.ndarray, Stats, float]:
        m = self.model
        n = dt.size
        bufs = self._buffers(n)
        x0b, Ub, dUb, dtb, pb, scb, optb, h_io, X, info = bufs
        x0b[:] = x0
        Ub[:] = np.reshape(U, (n, m.nu))
        dUb[:] = np.reshape(dU, (n, m.nu))
        dtb[:] = dt
        pb[:] = p
        scb[:] = m.scales
        optb[:] = (tol.rtol, tol.atol, tol.h_min, float(tol.max_steps))
        h_io[0] = h
        X[:] = np.nan
        info[:] = 0.0
        if self.c_fn is not None:
            if n == 1:
                self.c_fn(1, *self._one_ptrs)
            else:
                dp = ctypes.POINTER(ctypes.c_double)
                self.c_fn(n, *(a.ctypes.data_as(dp) for a in bufs))
        else:
            self._run_python(*bufs)
        X = X.copy()
        status = int(info[0])
        steps = int(info[4] + info[5])
        stats = Stats(steps=int(info[4]), rejected=int(info[5]), nfev=6 * steps,
                      njev=int(info[4]))
        if status:
            k = int(info[1])
            t_fail = t0 + float(np.sum(dt[:k]) + info[2])
            why = {1: f"the step size fell below h_min = {tol.h_min:g} s",
                   2: f"more than {term('max_steps')} = {tol.max_steps} steps were needed",
                   3: "the model gave a non-finite value"}[status]
            hint = (_RAISE_OR_LOOSEN if status == 2 else
                    f"check the parameters and the initial state, or loosen {term('rtol')}/"
                    f"{term('atol')}")
            raise ConvergenceError(
                f"simulation of {m.name} did not converge at t = {t_fail:.6g} s: {why} ({hint})")
        return X, stats, float(h_io[0])

    def _attempt(self, lu: Any, x: np.ndarray, f0: np.ndarray, ft: np.ndarray, u0: np.ndarray,
                 du: np.ndarray, t: float, hs: float, p: np.ndarray,
                 sc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One step of the tableau from ``x`` at ``t`` (the stage matrix LU-factorised in the
        scaled states): :func:`fcomp.rosenbrock.rosenbrock_stages` with numpy."""
        tab = TABLEAU

        def rhs(st: int, Y: np.ndarray) -> np.ndarray:
            if st == 0:
                fy = f0
            else:
                fy = np.asarray(self.F(Y, u0 + du * (t + tab.alpha[st] * hs), p),
                                dtype=float).ravel()
            return fy + hs * tab.gammas[st] * ft

        return rosenbrock_stages(tab, x, hs, rhs, lambda r: sc * lu_solve(lu, r / sc))

    def _run_python(self, x0: np.ndarray, U: np.ndarray, dU: np.ndarray, dt: np.ndarray,
                    p: np.ndarray, sc: np.ndarray, opts: np.ndarray, h_io: np.ndarray,
                    X: np.ndarray, info: np.ndarray) -> None:
        """The C driver's loop in Python (no compiler available); the same decisions."""
        rtol, atol, hmin, max_steps = opts
        h = float(h_io[0])
        nacc, nrej = 0, 0
        x = x0.copy()
        X[0] = x
        status, k, t = 0, 0, 0.0
        Dinv = 1.0 / sc
        tab = TABLEAU
        for k in range(dt.size):  # noqa: B007 - k reported on failure
            T = dt[k]
            rejected, fresh = False, False
            t = 0.0
            while T - t > 1e-12 * T:
                hs, clipped = h, False
                if hs >= T - t or (T - t) - hs < 0.01 * hs:
                    hs, clipped = T - t, True
                if not fresh:
                    uu = U[k] + dU[k] * t
                    f0 = np.asarray(self.F(x, uu, p), dtype=float).ravel()
                    Jx, Ju = (np.asarray(a, dtype=float) for a in self.Jf(x, uu, p))
                    ft = Ju @ dU[k]
                    if not (np.all(np.isfinite(f0)) and np.all(np.isfinite(Jx))
                            and np.all(np.isfinite(ft))):
                        status = 3
                        break
                    fresh = True
                Mt = np.eye(x.size) / (hs * tab.gamma) - Dinv[:, None] * Jx * sc[None, :]
                en = 1e10
                with np.errstate(all="ignore"):
                    try:
                        xn, err = self._attempt(lu_factor(Mt, check_finite=True), x, f0, ft,
                                                U[k], dU[k], t, hs, p, sc)
                        e = err / (atol * sc + rtol * np.maximum(np.abs(x), np.abs(xn)))
                        en = float(np.sqrt(np.mean(e * e)))
                        if not (np.all(np.isfinite(xn)) and math.isfinite(en)):
                            en = 1e10
                    except (ValueError, np.linalg.LinAlgError):
                        en = 1e10
                fac = CONTROL.factor(en, tab.order)
                if en <= 1.0:
                    x, t, nacc, fresh = xn, t + hs, nacc + 1, False
                    if rejected:
                        fac = min(fac, 1.0)
                    rejected = False
                    hn = hs * fac
                    h = max(h, hn) if (clipped and fac >= 1.0) else hn
                else:
                    nrej += 1
                    rejected = True
                    h = hs * fac
                    if h < hmin:
                        status = 1
                        break
                if nacc + nrej >= max_steps:
                    status = 2
                    break
            if status:
                break
            X[k + 1] = x
        h_io[0] = h
        info[:] = [status, k if status else dt.size, t, h, nacc, nrej]


class _StepLimitError(Exception):
    def __init__(self, t: float) -> None:
        super().__init__(t)
        self.t = t


class SolveIvp(Integrator):
    """:func:`scipy.integrate.solve_ivp` with the CasADi right-hand side and exact Jacobian."""

    scipy_method: ClassVar[str] = "Radau"

    def __init__(self, model: OdeModel) -> None:
        super().__init__(model)
        x, u, p = model.symbols()
        f = model.rhs(x, u, p)
        self.f = ca.Function("f", [x, u, p], [f])
        self.jac = ca.Function("jac_x", [x, u, p], [ca.jacobian(f, x)])

    def run(self, x0: np.ndarray, U: np.ndarray, dU: np.ndarray, dt: np.ndarray,
            p: np.ndarray, tol: Tolerances, h: float,
            t0: float = 0.0) -> tuple[np.ndarray, Stats, float]:
        m = self.model
        n = dt.size
        U = U.reshape(n, m.nu)
        dU = dU.reshape(n, m.nu)
        knots = np.concatenate([[0.0], np.cumsum(dt)])
        atol = tol.atol * m.scales
        stats = Stats()
        ends = U + dU * dt[:, None]
        continuous = n > 0 and np.allclose(ends[:-1], U[1:], rtol=1e-12, atol=1e-15)
        pieces = [(0, n)] if continuous else [(k, k + 1) for k in range(n)]
        X = np.empty((n + 1, m.nx))
        X[0] = x0
        x = np.asarray(x0, dtype=float)
        counter = [0]
        for a, b in pieces:
            ta, tb = knots[a], knots[b]

            def u_at(t: float, a: int = a, b: int = b) -> np.ndarray:
                k = min(max(int(np.searchsorted(knots, t, side="right")) - 1, a), b - 1)
                return U[k] + dU[k] * (t - knots[k])

            def fun(t: float, y: np.ndarray) -> np.ndarray:
                return np.asarray(self.f(y, u_at(t), p)).ravel()

            def jac(t: float, y: np.ndarray) -> np.ndarray:
                return np.asarray(self.jac(y, u_at(t), p))

            def limit(t: float, y: np.ndarray) -> float:  # called once per accepted step
                counter[0] += 1
                if counter[0] > tol.max_steps:
                    raise _StepLimitError(t)
                return 1.0

            try:
                sol = solve_ivp(fun, (ta, tb), x, method=self.scipy_method,
                                t_eval=knots[a + 1:b + 1], rtol=tol.rtol, atol=atol,
                                first_step=min(h, tb - ta), jac=jac, events=limit)
            except _StepLimitError as stop:
                raise ConvergenceError(
                    f"simulation of {m.name} did not converge at t = {t0 + stop.t:.6g} s "
                    f"({self.name}): more than {term('max_steps')} = {tol.max_steps} steps "
                    f"were needed ({_RAISE_OR_LOOSEN})") from None
            if sol.status != 0 or not np.all(np.isfinite(sol.y)):
                raise ConvergenceError(
                    f"simulation of {m.name} did not converge between t = {t0 + ta:.6g} s "
                    f"and {t0 + tb:.6g} s ({self.name}): {sol.message}"
                )
            X[a + 1:b + 1] = sol.y.T
            x = sol.y[:, -1]
            stats.steps += int(sol.t.size)
            stats.nfev += int(sol.nfev)
            stats.njev += int(sol.njev)
        return X, stats, h


class Radau(SolveIvp):
    """``solve_ivp(method="Radau")`` (implicit Runge-Kutta, order 5)."""

    name = "radau"
    scipy_method = "Radau"


class BDF(SolveIvp):
    """``solve_ivp(method="BDF")`` (variable-order backward differentiation)."""

    name = "bdf"
    scipy_method = "BDF"


class LSODA(SolveIvp):
    """``solve_ivp(method="LSODA")`` (stiffness switching)."""

    name = "lsoda"
    scipy_method = "LSODA"


METHODS: Registry[type[Integrator]] = Registry("integration method")
for _cls in (Rodas4, Radau, BDF, LSODA):
    METHODS.register(_cls.name, _cls)


def make_integrator(model: OdeModel, method: str = "rodas4") -> Integrator:
    """The integrator ``method`` (a name of :data:`METHODS`) for ``model``."""
    return METHODS.get(method)(model)


# ---------------------------------------------------------------- drivers
HOLDS = ("linear", "zoh")


def input_rates(t: np.ndarray, U: np.ndarray, hold: str) -> np.ndarray:
    """Input rate on every interval: 0 (``zoh``) or the slope to the next sample (``linear``)."""
    if hold not in HOLDS:
        raise FcompError(f"hold must be one of {', '.join(HOLDS)}, got {hold!r}")
    dt = np.diff(t)
    if hold == "zoh":
        return np.zeros((dt.size, U.shape[1]))
    return np.diff(U, axis=0) / dt[:, None]


@dataclass
class Trajectory:
    """States at the sample instants and the work done (SI units)."""

    t: np.ndarray
    X: np.ndarray
    U: np.ndarray
    stats: Stats = field(default_factory=Stats)
    method: str = "rodas4"
    tolerances: Tolerances = DEFAULT_TOLERANCES
    hold: str = "linear"


def integrate(
    model: OdeModel,
    x0: np.ndarray,
    t: np.ndarray,
    U: np.ndarray,
    p: np.ndarray,
    *,
    hold: str = "linear",
    method: str = "rodas4",
    tolerances: Tolerances = DEFAULT_TOLERANCES,
) -> Trajectory:
    """Integrate ``model`` from ``x0`` over the sample instants ``t`` with inputs ``U``.

    Parameters
    ----------
    model
        The ODE (from a plant's :meth:`~plants.base.OdePlant.ode_model`).
    x0
        Initial state at ``t[0]`` (the model's units).
    t
        Sample instants (s), strictly increasing.
    U
        Inputs at the instants, ``(len(t), nu)``.
    p
        Parameter vector of ``model.rhs``.
    hold
        ``"linear"`` (open loop) or ``"zoh"`` (sampled-data closed loop).
    method
        A name of :data:`METHODS`.
    tolerances
        :class:`Tolerances`.
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
        raise FcompError("simulation times must be finite and strictly increasing (>= 2)")
    U = np.asarray(U, dtype=float).reshape(t.size, model.nu)
    if not np.all(np.isfinite(U)):
        raise FcompError(f"the input of {model.name} has non-finite values")
    x0 = np.asarray(x0, dtype=float).ravel()
    if x0.size != model.nx or not np.all(np.isfinite(x0)):
        raise FcompError(f"initial state of {model.name} must be {model.nx} finite values "
                         f"({', '.join(model.state_names)})")
    dU = input_rates(t, U, hold)
    integ = make_integrator(model, method)
    dt = np.diff(t)
    pv = np.asarray(p, float)
    if receiver() is None:
        X, stats, _h = integ.run(x0, U[:-1], dU, dt, pv, tolerances, tolerances.h0)
    else:  # in pieces of whole intervals, reporting as it goes (same result)
        n = dt.size
        X = np.empty((n + 1, model.nx))
        X[0] = x0
        stats = Stats()
        h = tolerances.h0
        piece = max(1, n // 200)
        for a in range(0, n, piece):
            b = min(a + piece, n)
            tol = step_budget(tolerances, stats, float(t[a]), model.name)
            Xp, st, h = integ.run(X[a], U[a:b], dU[a:b], dt[a:b], pv, tol, h, float(t[a]))
            X[a + 1:b + 1] = Xp[1:]
            stats.add(st)
            report(float(t[b] - t[0]), float(t[-1] - t[0]))
    return Trajectory(t=t, X=X, U=U, stats=stats, method=method, tolerances=tolerances,
                      hold=hold)


class Stepper(SampledStepper):
    """Advance a model one controller sample at a time, input held (sampled-data loop).

    The stepper contract of :mod:`fcomp.stepper` for the engine: ``advance(u, dt)``
    integrates the model over ``dt`` with ``u`` held (RODAS4's step size carried from
    interval to interval), and ``step(u)`` is ``advance(u, dt)`` over the sample time
    given at creation.

    >>> st = plant.stepper(dt=1e-3)          # doctest: +SKIP
    >>> st.reset()                           # default initial state
    >>> for k in range(n):
    ...     u = controller.step(st.t, measure(st.x), ref)
    ...     st.step(u)

    Attributes
    ----------
    t, x
        Current time (s) and state.
    dt
        The sample time of :meth:`step` (s).
    stats
        Work done since the last :meth:`reset`.
    """

    def __init__(self, model: OdeModel, dt: float, p: np.ndarray, x0: np.ndarray, *,
                 method: str = "rodas4", tolerances: Tolerances = DEFAULT_TOLERANCES) -> None:
        if not (math.isfinite(dt) and dt > 0):
            raise FcompError(f"sample time must be a positive number of seconds, got {dt}")
        self.model = model
        self.dt = float(dt)
        self.p = np.asarray(p, dtype=float)
        self.tolerances = tolerances
        self.integrator = make_integrator(model, method)
        self._x0 = np.asarray(x0, dtype=float).copy()
        self._dU = np.zeros((1, model.nu))
        self.reset()

    @property
    def name(self) -> str:
        return self.model.name

    @property
    def state_names(self) -> tuple[str, ...]:
        return self.model.state_names

    @property
    def input_names(self) -> tuple[str, ...]:
        return self.model.input_names

    def initial_state(self) -> np.ndarray:
        """The initial state given at creation."""
        return self._x0

    def _start(self, x: np.ndarray) -> None:
        self.h = self.tolerances.h0
        self.stats = Stats()

    def _advance(self, u: np.ndarray, dt: float) -> np.ndarray:
        X, st, self.h = self.integrator.run(self.x, u[None, :], self._dU, np.array([dt]),
                                            self.p, self.tolerances, self.h, self.t)
        self.stats.add(st)
        return X[-1].copy()

    def step(self, u: Any) -> np.ndarray:
        """Hold ``u`` for one sample time :attr:`dt`; the state at the end of it."""
        return self.advance(u, self.dt)
