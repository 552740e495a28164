"""The whole export: build the controller, write its C, compile, check and time it
(:func:`export_controller`; :mod:`controllers.export`)."""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from controllers.export.cfiles import write_c
from controllers.export.check import RTOL, check_equivalence, python_state
from controllers.export.compiled import CompiledController, find_compiler
from controllers.export.step import EXPORTABLE, guarded_step_function
from fcomp.errors import FcompError

#: Most compiled steps :func:`export_controller` times (two float64 times each are kept in
#: memory: 80 MB).
MAX_TIMING_STEPS = 5_000_000
#: Longest closed loop of the fault check (s).
MAX_FAULT_CHECK = 10.0


@dataclass
class ExportResult:
    """What :func:`export_controller` did (SI units; times in s).

    ``step_time_median`` and ``step_time_max`` are the CPU time of the compiled step (its own
    cost); ``step_time_wall_median`` and ``step_time_wall_max`` the wall clock, whose worst
    also holds the time the operating system gave the processor to other processes.
    ``fault_check`` is the check on hostile input (:func:`controllers.export.check.
    hostile_script`); ``equivalent`` holds for both checks.
    """

    controller: str
    files: list[Path]
    equivalent: bool | None
    max_rel_diff: float | None
    max_state_rel_diff: float | None
    free_run_max_rel_diff: float | None
    free_run_max_abs_diff: float | None
    steps_checked: int
    step_time_median: float | None
    step_time_max: float | None
    timed_steps: int
    compiler: str | None
    note: str
    layout: list[tuple[str, int]]
    reference: str = ""
    warnings: list[str] = field(default_factory=list)
    step_time_wall_median: float | None = None
    step_time_wall_max: float | None = None
    rate: float | None = None
    plant_rate: float | None = None
    fail_safe: dict[str, Any] = field(default_factory=dict)
    fault_check: dict[str, Any] | None = None

    def as_dict(self) -> dict[str, Any]:
        return {
            "controller": self.controller, "files": [str(f) for f in self.files],
            "equivalent": self.equivalent, "max_rel_diff": self.max_rel_diff,
            "max_state_rel_diff": self.max_state_rel_diff, "rtol": RTOL,
            "free_run_max_rel_diff": self.free_run_max_rel_diff,
            "free_run_max_abs_diff": self.free_run_max_abs_diff,
            "free_run_equivalent": (None if self.free_run_max_rel_diff is None
                                    else self.free_run_max_rel_diff <= RTOL),
            "steps_checked": self.steps_checked, "step_time_median": self.step_time_median,
            "step_time_max": self.step_time_max, "step_time_clock": "cpu",
            "step_time_wall_median": self.step_time_wall_median,
            "step_time_wall_max": self.step_time_wall_max, "timed_steps": self.timed_steps,
            "rate": self.rate, "plant_rate": self.plant_rate,
            "sample_time": None if not self.rate else 1.0 / self.rate,
            "compiler": self.compiler, "step": self.note, "python_reference": self.reference,
            "state_layout": [{"name": n, "size": k} for n, k in self.layout],
            "fail_safe": self.fail_safe, "fault_check": self.fault_check,
        }


def check_friction(model: Any, y: np.ndarray) -> None:
    """Refuse a controller friction model whose steady-state force at +-1 mm/s or +-0.1 m/s
    is not finite or exceeds the actuator's whole force range ``F_max - F_min`` (the axis
    could never move: values such as ``Fc = Fs = 1e308``), in one line."""
    span = float(model.force_max - model.force_min)
    v = np.array([-0.1, -1e-3, 1e-3, 0.1])
    p1, p2 = model.gauge(y)
    with np.errstate(all="ignore"):
        try:
            F = np.asarray(model.friction.steady_state(v, x=float(y[0]), p1=p1, p2=p2),
                           dtype=float)
        except (OverflowError, FloatingPointError, ZeroDivisionError, ValueError) as exc:
            raise FcompError(f"export: the controller's friction model "
                             f"{model.friction.describe()} cannot be evaluated ({exc}); check "
                             "its values") from None
    bad = ~np.isfinite(F) | (np.abs(F) > span)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise FcompError(f"export: the controller's friction model {model.friction.describe()} "
                         f"gives {F[k]:.3g} N at {v[k]:g} m/s, beyond the actuator's whole "
                         f"force range ({span:.4g} N): the axis could not move; check the "
                         "model's values")


def _fault_check(ctrl: Any, lib: Any, plant: Any, layout: list[tuple[str, int]],
                 start_from_init: bool, task: str, duration: float, seed: int
                 ) -> dict[str, Any]:
    """The check on hostile input (:func:`~controllers.export.check.hostile_script`): its
    figures for the JSON."""
    from controllers.export.check import HOSTILE_EVENTS, hostile_script

    lim = ctrl.limits
    n_latch, n_recover = int(lim.n_latch), int(lim.n_recover)
    needed = 20 + 40 + 2 * n_latch + 13 + 2 * n_recover + 30
    dur = min(max(duration, needed * ctrl.dt), MAX_FAULT_CHECK)
    n = int(round(dur / ctrl.dt)) + 1
    chk = check_equivalence(ctrl, lib, plant, layout=layout, start_from_init=start_from_init,
                            task=task, duration=dur, seed=seed,
                            corrupt=hostile_script(n, float(ctrl.model.stroke), n_latch,
                                                   n_recover))
    equivalent = bool(chk.max_rel_diff <= RTOL and chk.max_state_rel_diff <= RTOL
                      and chk.same_faults and chk.within_limits)
    return {"equivalent": equivalent, "events": list(HOSTILE_EVENTS), "samples": n,
            "faults": chk.faults, "latches": chk.latches, "recoveries": chk.recoveries,
            "same_faults": chk.same_faults, "within_limits": chk.within_limits,
            "max_rel_diff": chk.max_rel_diff, "max_state_rel_diff": chk.max_state_rel_diff,
            "free_run_max_rel_diff": chk.free_max_rel_diff}


def export_controller(name: str, model: Any, folder: Path, *,
                      options: Mapping[str, Any] | None = None, plant: Any = None,
                      task: str = "seed002-sine", duration: float = 0.6,
                      timing_steps: int = 100_000, seed: int = 0,
                      on_stage: Callable[[str], None] | None = None) -> ExportResult:
    """Export controller ``name`` built on ``model`` (a
    :class:`~controllers.plant_model.ControlModel`: plant and friction) behind the fail-safe
    layer (:mod:`controllers.safety`) as C into ``folder``; compile, check in closed loop
    against ``plant`` (default: the model's own plant, the controller's friction as the true
    one), on ordinary and on hostile input, and time it (module docstring).

    Raises
    ------
    FcompError
        An unknown or unexported controller, a timing count outside ``[100000,
        MAX_TIMING_STEPS]``, a friction model the axis could not move against
        (:func:`check_friction`), a check whose difference is not a number.
    """
    from controllers import CONTROLLERS, make_controller
    from controllers.base import Reference
    from controllers.mpc_fixed import FixedIterationMPC
    from controllers.plant_model import MEASURED, equilibrium
    from controllers.safety import FailSafe

    CONTROLLERS.get(name)
    if name not in EXPORTABLE:
        raise FcompError(f"export: controller {name} is not exported (exported: "
                         f"{', '.join(EXPORTABLE)})")
    if not 100_000 <= timing_steps <= MAX_TIMING_STEPS:
        raise FcompError(f"export: time between 100000 and {MAX_TIMING_STEPS} steps (two times "
                         f"of each are kept in memory), got {timing_steps}")
    if not (math.isfinite(duration) and duration > 0):
        raise FcompError(f"export: the check's duration must be positive, got {duration}")
    say = on_stage or (lambda _s: None)
    # the example's measurement: at rest at mid-stroke, holding the load
    x_eq, _ = equilibrium(model.plant, 0.5 * model.stroke)
    names = model.plant.state_names
    y_ex = np.array([x_eq[names.index(k)] for k in MEASURED])
    check_friction(model, y_ex)
    ctrl = (FailSafe(FixedIterationMPC(model, **dict(options or {}))) if name == "mpc"
            else make_controller(name, model, **dict(options or {})))
    step = guarded_step_function(ctrl)
    unit = "A (servo-valve current)" if model.plant_name == "hydraulic" else \
        "normalised valve command (-1..1)"
    if name == "mpc":  # fcomp_ctrl_init: the Python reset there (it solves the equilibrium)
        ctrl.reset(0.0, y_ex, Reference(float(y_ex[0]), 0.0, 0.0))
        step.state0 = python_state(ctrl)
    files = write_c(step, folder, controller=name, plant=model.describe(), unit=unit,
                    u_max=model.u_max, dt=ctrl.dt, y_example=y_ex,
                    r_example=0.5 * model.stroke + 0.001, limits=ctrl.limits)
    cc = find_compiler()
    res = ExportResult(controller=name, files=files, equivalent=None, max_rel_diff=None,
                       max_state_rel_diff=None, free_run_max_rel_diff=None,
                       free_run_max_abs_diff=None, steps_checked=0, step_time_median=None,
                       step_time_max=None, timed_steps=0, compiler=cc, note=step.note,
                       layout=step.layout,
                       reference=f"{type(ctrl.inner).__module__}."
                       f"{type(ctrl.inner).__qualname__}",
                       rate=float(ctrl.rate), plant_rate=float(model.control_rate),
                       fail_safe=_fail_safe_doc(ctrl))
    if not math.isclose(ctrl.rate, model.control_rate, rel_tol=1e-12):
        res.warnings.append(
            f"{name} runs at {ctrl.rate:g} Hz (a step every {1e3 * ctrl.dt:g} ms), the plant's "
            f"[control] rate is {model.control_rate:g} Hz: call fcomp_ctrl_step every "
            f"{1e3 * ctrl.dt:g} ms (FCOMP_CTRL_DT), or export with --option "
            f"rate={model.control_rate:g}")
    if cc is None:
        forced = os.environ.get("FCOMP_CC")
        where = (f"FCOMP_CC={forced} is not found" if forced is not None
                 else "none of $CC, cc, gcc, clang is on the PATH")
        res.warnings.append(f"no C compiler found ({where}): the C code is written to {folder} "
                            "but not compiled, checked or timed")
        return res
    true_plant = plant if plant is not None else model.plant
    with tempfile.TemporaryDirectory() as tmp:
        say("compiling")
        try:
            lib = CompiledController(folder, cc, step.n_state, Path(tmp), n_ref=step.n_ref)
        except FcompError as exc:  # a broken toolchain: the code stays written
            res.warnings.append(f"{exc}; the C code is written to {folder} but not compiled, "
                                "checked or timed")
            return res
        say("checking")
        chk = check_equivalence(ctrl, lib, true_plant, layout=step.layout,
                                start_from_init=name != "mpc", task=task, duration=duration,
                                seed=seed)
        say("checking on hostile input")
        res.fault_check = _fault_check(ctrl, lib, true_plant, step.layout, name != "mpc", task,
                                       duration, seed)
        say("timing")
        cpu, wall = lib.bench(timing_steps, chk.Y, chk.REF)
    figures = [chk.max_rel_diff, chk.max_state_rel_diff, res.fault_check["max_rel_diff"],
               res.fault_check["max_state_rel_diff"]]
    if not all(math.isfinite(v) for v in figures):
        raise FcompError(f"export: the equivalence check of {name} gave no number (relative "
                         f"differences {', '.join(f'{v:.3g}' for v in figures)}): the "
                         "controller's values are not usable on this plant")
    res.equivalent = bool(chk.max_rel_diff <= RTOL and chk.max_state_rel_diff <= RTOL
                          and res.fault_check["equivalent"])
    res.max_rel_diff = chk.max_rel_diff
    res.max_state_rel_diff = chk.max_state_rel_diff
    res.free_run_max_rel_diff = chk.free_max_rel_diff
    res.free_run_max_abs_diff = chk.free_max_abs_diff
    res.steps_checked = int(chk.u_free.size)
    res.step_time_median = float(np.median(cpu))
    res.step_time_max = float(np.max(cpu))
    res.step_time_wall_median = float(np.median(wall))
    res.step_time_wall_max = float(np.max(wall))
    res.timed_steps = int(cpu.size)
    if not res.equivalent:
        fc = res.fault_check
        res.warnings.append(
            f"the compiled step differs from the Python controller's: relative "
            f"{chk.max_rel_diff:.3g} on the command, {chk.max_state_rel_diff:.3g} on the "
            f"state; on hostile input {fc['max_rel_diff']:.3g} and "
            f"{fc['max_state_rel_diff']:.3g}, fault states "
            f"{'the same' if fc['same_faults'] else 'DIFFERENT'}, commands "
            f"{'within' if fc['within_limits'] else 'OUTSIDE'} the limits (tolerance {RTOL:g})")
    return res


def _fail_safe_doc(ctrl: Any) -> dict[str, Any]:
    """The fail-safe layer's numbers for the JSON (:class:`controllers.safety.Limits`)."""
    lim = ctrl.limits
    return {"safe_output": ctrl.model.settings.safe_output,
            "fault_latch": int(lim.n_latch), "fault_recover": int(lim.n_recover),
            "position_range": [lim.x_lo, lim.x_hi], "pressure_range": [lim.p_lo, lim.p_hi],
            "reference_velocity_max": lim.v_max, "reference_acceleration_max": lim.a_max,
            "u_max": lim.u_max, "du_per_step": lim.du}
