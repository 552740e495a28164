"""The equivalence check: the compiled controller in closed loop against the Python
plant, the Python controller stepped in lock step (:mod:`controllers.export`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from controllers.export.compiled import CompiledController
from controllers.safety import CAUSE, CONSEC, FAULTS, GOOD, LATCHED
from fcomp.errors import FcompError

#: Relative tolerance of the equivalence check.
RTOL = 1e-9


def python_state(ctrl: Any) -> np.ndarray:
    """The Python controller's state in the exported layout (:class:`StepExport`):
    ``started = 1`` once it has stepped; reset but not yet stepped, ``started = 0`` (the
    exported step then resets itself from the measurement, as the Python reset did, and
    the friction estimate has no previous value for its lead); behind the fail-safe layer
    (:class:`controllers.safety.FailSafe`), the law's state (not started while the layer
    has not started it) followed by the layer's."""
    from controllers.ekf import EKFController
    from controllers.feedforward import PIDFeedforwardController
    from controllers.lugre_observer import LuGreObserverController
    from controllers.mpc_fixed import FixedIterationMPC
    from controllers.safety import FailSafe

    if isinstance(ctrl, FailSafe):
        inner = python_state(ctrl.inner)
        if not isinstance(ctrl.inner, FixedIterationMPC) and not ctrl.started:
            inner[0] = 0.0
        return np.concatenate([inner, np.asarray(ctrl.state, dtype=float)])
    if isinstance(ctrl, FixedIterationMPC):
        kf = ctrl.ekf.kf
        lam = ctrl.solver._lam
        N = ctrl.problem.horizon
        return np.concatenate([np.asarray(kf.x, dtype=float)[:, 0],
                               np.asarray(kf.P, dtype=float).ravel(order="F"),
                               [ctrl._u_prev], np.asarray(ctrl.solver.U, dtype=float),
                               np.zeros(2 * N) if lam is None else np.asarray(lam, dtype=float)])
    law = ctrl.law
    # not stepped since its reset: the exported step resets itself from the measurement
    # (started = 0), as the Python reset did; that is also where the lead has no
    # previous estimate
    started = 0.0 if ctrl._F_prev is None else 1.0
    parts = [np.array([started, law.integral, law.v_f, law.x_prev], dtype=float)]
    if isinstance(ctrl, LuGreObserverController):
        parts += [np.asarray(ctrl.x_hat, dtype=float).ravel(), np.array([ctrl._side])]
    elif isinstance(ctrl, EKFController):
        kf = ctrl.ekf.kf
        parts += [np.asarray(kf.x, dtype=float)[:, 0],
                  np.asarray(kf.P, dtype=float).ravel(order="F"), np.array([ctrl._u_prev])]
    elif isinstance(ctrl, PIDFeedforwardController) and ctrl.dynamic:
        parts += [np.asarray(ctrl.x_ff, dtype=float).ravel(), np.array([ctrl._side])]
    if ctrl.uses_friction and ctrl.friction_lead:
        parts.append(np.array([0.0 if ctrl._F_prev is None else ctrl._F_prev]))
    return np.concatenate(parts)


@dataclass
class CheckResult:
    """The lock-step closed loop of :func:`check_equivalence` (SI units).

    Attributes
    ----------
    u_python
        The Python controller's commands.
    u_step
        The compiled step's commands from the Python controller's state at every sample
        (the step, compared step for step).
    u_free
        The commands of the compiled controller running on its own state (these drive
        the plant).
    state_rel_diff
        Per sample, the largest difference of the compiled step's next state from the
        Python controller's, relative per block to the block's largest value over the run
        (:func:`block_difference`).
    Y, REF
        Measurements and references of the run (for the timing loop).
    u_max
        The valve range (floor of the relative differences).
    """

    u_python: np.ndarray
    u_step: np.ndarray
    u_free: np.ndarray
    state_rel_diff: np.ndarray
    Y: np.ndarray
    REF: np.ndarray
    u_max: float
    fault_python: np.ndarray | None = None
    fault_free: np.ndarray | None = None
    du: float = math.inf

    @property
    def max_rel_diff(self) -> float:
        return float(np.max(relative_difference(self.u_step, self.u_python, self.u_max)))

    @property
    def free_max_rel_diff(self) -> float:
        return float(np.max(relative_difference(self.u_free, self.u_python, self.u_max)))

    @property
    def free_max_abs_diff(self) -> float:
        return float(np.max(np.abs(self.u_free - self.u_python)))

    @property
    def max_state_rel_diff(self) -> float:
        return float(np.max(self.state_rel_diff))

    @property
    def same_faults(self) -> bool | None:
        """Whether the free-running compiled controller's fault state (faults, in a row,
        latched, cause, good run) equals the Python layer's at every sample (None without
        the layer)."""
        if self.fault_python is None or self.fault_free is None:
            return None
        cols = [FAULTS, CONSEC, LATCHED, CAUSE, GOOD]
        return bool(np.array_equal(self.fault_python[:, cols], self.fault_free[:, cols]))

    @property
    def faults(self) -> int:
        """Faulty samples the Python layer counted (0 without the layer)."""
        return 0 if self.fault_python is None else int(self.fault_python[-1, FAULTS])

    @property
    def latches(self) -> int:
        """How often the Python layer latched the safe output."""
        if self.fault_python is None:
            return 0
        lat = self.fault_python[:, LATCHED] > 0.5
        return int(np.sum(lat[1:] & ~lat[:-1]) + lat[0])

    @property
    def recoveries(self) -> int:
        """How often the Python layer unlatched (recovered)."""
        if self.fault_python is None:
            return 0
        lat = self.fault_python[:, LATCHED] > 0.5
        return int(np.sum(~lat[1:] & lat[:-1]))

    @property
    def within_limits(self) -> bool:
        """Every command (Python and compiled) finite, within ``+-u_max`` and within
        ``du`` of the one before (the layer's output rule)."""
        ok = True
        for u in (self.u_python, self.u_free):
            ok = ok and bool(np.all(np.isfinite(u)) and np.all(np.abs(u) <= self.u_max))
            ok = ok and bool(np.all(np.abs(np.diff(u)) <= self.du * (1 + 1e-12)))
        return ok


def relative_difference(u_c: np.ndarray, u_py: np.ndarray, u_max: float) -> np.ndarray:
    """``|u_c - u_py| / max(|u_py|, 1e-6*u_max)``: relative, with a floor a millionth of the
    valve range (a command of exactly zero has no relative error of its own)."""
    return np.abs(u_c - u_py) / np.maximum(np.abs(u_py), 1e-6 * u_max)


def block_deviations(s_c: np.ndarray, s_py: np.ndarray, layout: list[tuple[str, int]]
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Per block of the state: ``(max|s_c - s_py|, max|s_py|)`` (entries equal or both NaN
    count as equal; one NaN against a number is ``inf``; non-finite values are left out of
    the scale)."""
    diffs, scales = np.zeros(len(layout)), np.zeros(len(layout))
    i = 0
    for j, (_name, k) in enumerate(layout):
        a, b = s_c[i:i + k], s_py[i:i + k]
        same = (a == b) | (np.isnan(a) & np.isnan(b))
        if not np.all(same):
            diff = np.abs(a - b)[~same]
            diffs[j] = float(np.max(np.where(np.isnan(diff), np.inf, diff)))
        fin = np.abs(b[np.isfinite(b)])
        scales[j] = float(fin.max()) if fin.size else 0.0
        i += k
    return diffs, scales


def block_difference(s_c: np.ndarray, s_py: np.ndarray, layout: list[tuple[str, int]],
                     scales: np.ndarray | None = None) -> float:
    """Largest over the state's blocks of ``max|s_c - s_py| / max(scale, 1e-300)``, the scale
    each block's ``max|s_py|`` here, or ``scales`` (e.g. the block's largest value over a
    run: a block of multipliers at rounding level, all near zero, is not judged against
    itself)."""
    diffs, here = block_deviations(s_c, s_py, layout)
    ref = here if scales is None else scales
    return float(np.max(diffs / np.maximum(ref, 1e-300), initial=0.0))


#: What :func:`hostile_script` does to a run, in order (module docstring of
#: :mod:`controllers.safety` for the rules the sequence exercises).
HOSTILE_EVENTS = (
    "x NaN", "p1 +inf", "p2 -inf", "r 1e300 (below the latch)", "x beyond the stroke",
    "x below the stroke", "dr NaN", "ddr inf", "a future reference NaN (mpc)",
    "sensor dropout: every channel NaN until latched, then good samples until recovered",
    "r 1e300 until latched, then good samples until recovered",
)


def hostile_script(n: int, stroke: float, n_latch: int, n_recover: int, start: int = 20
                   ) -> Callable[[int, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """The corruption of a run of ``n`` samples by :data:`HOSTILE_EVENTS`: a function
    ``(k, y, ref) -> (y, ref)`` (copies; ``ref = [r, dr, ddr, *future]``) for
    :func:`check_equivalence`. Single faults and short runs below the latch first, then a
    sensor dropout of ``n_latch + 10`` samples and a reference of 1e300 for ``n_latch + 3``
    samples, each followed by ``n_recover + 10`` good samples; events past ``n`` are left
    out."""
    k0 = start
    below = max(1, min(3, n_latch - 1))
    events: dict[int, Callable[[np.ndarray, np.ndarray], None]] = {}

    def put(k: int, fn: Callable[[np.ndarray, np.ndarray], None]) -> None:
        if k < n:
            events[k] = fn

    def setter(where: str, i: int, value: float) -> Callable[[np.ndarray, np.ndarray], None]:
        def fn(y: np.ndarray, ref: np.ndarray) -> None:
            (y if where == "y" else ref)[i] = value
        return fn

    put(k0, setter("y", 0, math.nan))
    put(k0 + 5, setter("y", 1, math.inf))
    put(k0 + 6, setter("y", 2, -math.inf))
    for j in range(below):
        put(k0 + 10 + j, setter("r", 0, 1e300))
    put(k0 + 20, setter("y", 0, stroke + 1.0))
    put(k0 + 21, setter("y", 0, -1.0))
    put(k0 + 30, setter("r", 1, math.nan))
    put(k0 + 31, setter("r", 2, math.inf))
    put(k0 + 32, lambda y, ref: ref.__setitem__(len(ref) - 1, math.nan) if len(ref) > 3
        else None)

    def dropout(y: np.ndarray, ref: np.ndarray) -> None:
        y[:] = math.nan

    k = k0 + 40
    for j in range(n_latch + 10):
        put(k + j, dropout)
    k += n_latch + 10 + n_recover + 10
    for j in range(n_latch + 3):
        put(k + j, setter("r", 0, 1e300))

    def corrupt(i: int, y: np.ndarray, ref: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        y, ref = np.array(y, dtype=float), np.array(ref, dtype=float)
        fn = events.get(i)
        if fn is not None:
            fn(y, ref)
        return y, ref

    return corrupt


def check_equivalence(ctrl: Any, compiled: CompiledController, plant: Any, *,
                      layout: list[tuple[str, int]] | None = None, start_from_init: bool = True,
                      task: str = "seed002-sine", duration: float = 0.6, noise: float = 1.0,
                      seed: int = 0,
                      corrupt: Callable[[int, np.ndarray, np.ndarray],
                                        tuple[np.ndarray, np.ndarray]] | None = None
                      ) -> CheckResult:
    """Run the compiled controller in closed loop against ``plant`` (the harness's plant
    integration and sensors) with the Python controller ``ctrl`` stepped on the same
    measurements and references.

    Two compiled instances run: one on its own state from ``fcomp_ctrl_init`` (its
    commands drive the plant: ``u_free``; without ``start_from_init``, from the Python
    controller's state after its reset, as the MPC needs), and one whose state is set to the Python
    controller's before every sample (``u_step``: the step itself, compared step for
    step, and its next state against the Python controller's).

    ``corrupt(k, y, ref) -> (y, ref)`` (e.g. :func:`hostile_script`) changes what both
    controllers receive at sample ``k`` (``ref = [r, dr, ddr, *future]``): the check on
    hostile input. Behind the fail-safe layer the fault state of the Python controller and
    of the free-running compiled one are recorded at every sample.
    """
    from controllers.base import Reference
    from controllers.harness import SensorModel
    from controllers.plant_model import equilibrium
    from controllers.safety import N_STATE, FailSafe
    from controllers.tasks import get_task

    model = ctrl.model
    tk = get_task(task)
    x_mid = 0.5 * model.stroke
    dt = ctrl.dt
    n = max(1, int(round(duration / dt)))
    t = np.arange(n + 1) * dt
    r, dr, ddr = tk.sample(t)
    r = r + x_mid
    if r.min() < 0.005 or r.max() > model.stroke - 0.005:
        raise FcompError(f"export: task {task} leaves the stroke within {duration} s")
    x0, _ = equilibrium(plant, x_mid)
    stepper = plant.stepper(dt, x0=x0, rtol=1e-5, atol=1e-5)
    sensors = SensorModel(model.sensors, noise, seed)
    names = plant.state_names
    meas = [names.index(k) for k in ("x", "p1", "p2")]
    state = stepper.reset()
    u_py, u_step, u_free = (np.zeros(n + 1) for _ in range(3))
    Y = np.zeros((n + 1, 3))
    preview = int(getattr(ctrl, "preview", 0))
    r_pad = np.concatenate([r, np.full(preview, r[-1])])
    REF = np.zeros((n + 1, 3 + preview))
    synced = compiled.instance()
    compiled.init()
    compiled.init(synced)
    lay = layout or [("state", compiled.n_state)]
    dev, scale = np.zeros((n + 1, len(lay))), np.zeros((n + 1, len(lay)))
    u_max = model.u_max
    guarded = isinstance(ctrl, FailSafe)
    fs_py, fs_c = (np.zeros((n + 1, N_STATE)) if guarded else None for _ in range(2))
    for k in range(n + 1):
        y = sensors.measure(state[meas])
        REF[k] = (r[k], dr[k], ddr[k], *r_pad[k + 1:k + 1 + preview])
        if corrupt is not None:
            y, REF[k] = corrupt(k, y, REF[k])
        Y[k] = y
        ref = Reference(float(REF[k, 0]), float(REF[k, 1]), float(REF[k, 2]),
                        tuple(float(v) for v in REF[k, 3:]))
        if k == 0:
            ctrl.reset(0.0, y, ref)
            if not start_from_init:  # the MPC's start needs the plant's equilibrium (Python)
                compiled.set_state(python_state(ctrl))
        compiled.set_state(python_state(ctrl), synced)
        u_step[k] = compiled.step(y, REF[k], synced)
        u_py[k] = ctrl.step(float(t[k]), y, ref)
        dev[k], scale[k] = block_deviations(compiled.state(synced), python_state(ctrl), lay)
        u_free[k] = compiled.step(y, REF[k])
        if fs_py is not None and fs_c is not None:
            fs_py[k] = ctrl.state
            fs_c[k] = compiled.state()[-N_STATE:]
        if not math.isfinite(u_free[k]):
            raise FcompError(f"export: the compiled controller returned {u_free[k]} at "
                             f"t = {t[k]:.4f} s")
        if k < n:
            state = stepper.step(min(max(u_free[k], -u_max), u_max))
    s_diff = np.max(dev / np.maximum(scale.max(axis=0), 1e-300), axis=1)
    return CheckResult(u_python=u_py, u_step=u_step, u_free=u_free, state_rel_diff=s_diff,
                       Y=Y, REF=REF, u_max=u_max, fault_python=fs_py, fault_free=fs_c,
                       du=model.du_max * dt)
