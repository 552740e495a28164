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
from controllers.export.step import EXPORTABLE, step_function
from fcomp.errors import FcompError


@dataclass
class ExportResult:
    """What :func:`export_controller` did (SI units; times in s)."""

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
            "step_time_max": self.step_time_max, "timed_steps": self.timed_steps,
            "compiler": self.compiler, "step": self.note, "python_reference": self.reference,
            "state_layout": [{"name": n, "size": k} for n, k in self.layout],
        }


def export_controller(name: str, model: Any, folder: Path, *,
                      options: Mapping[str, Any] | None = None, plant: Any = None,
                      task: str = "seed002-sine", duration: float = 0.6,
                      timing_steps: int = 100_000, seed: int = 0,
                      on_stage: Callable[[str], None] | None = None) -> ExportResult:
    """Export controller ``name`` built on ``model`` (a
    :class:`~controllers.plant_model.ControlModel`: plant and friction) as C into ``folder``;
    compile, check in closed loop against ``plant`` (default: the model's own plant, the
    controller's friction as the true one) and time it (module docstring)."""
    from controllers import CONTROLLERS, make_controller
    from controllers.base import Reference
    from controllers.mpc_fixed import FixedIterationMPC
    from controllers.plant_model import MEASURED, equilibrium

    CONTROLLERS.get(name)
    if name not in EXPORTABLE:
        raise FcompError(f"export: controller {name} is not exported (exported: "
                         f"{', '.join(EXPORTABLE)})")
    if timing_steps < 100_000:
        raise FcompError(f"export: time at least 100000 steps, got {timing_steps}")
    if not (math.isfinite(duration) and duration > 0):
        raise FcompError(f"export: the check's duration must be positive, got {duration}")
    say = on_stage or (lambda _s: None)
    ctrl = (FixedIterationMPC(model, **dict(options or {})) if name == "mpc"
            else make_controller(name, model, **dict(options or {})))
    step = step_function(ctrl)
    unit = "A (servo-valve current)" if model.plant_name == "hydraulic" else \
        "normalised valve command (-1..1)"
    # the example's measurement: at rest at mid-stroke, holding the load
    x_eq, _ = equilibrium(model.plant, 0.5 * model.stroke)
    names = model.plant.state_names
    y_ex = np.array([x_eq[names.index(k)] for k in MEASURED])
    if name == "mpc":  # fcomp_ctrl_init: the Python reset there (it solves the equilibrium)
        ctrl.reset(0.0, y_ex, Reference(float(y_ex[0]), 0.0, 0.0))
        step.state0 = python_state(ctrl)
    files = write_c(step, folder, controller=name, plant=model.describe(), unit=unit,
                    u_max=model.u_max, dt=ctrl.dt, y_example=y_ex,
                    r_example=0.5 * model.stroke + 0.001)
    cc = find_compiler()
    res = ExportResult(controller=name, files=files, equivalent=None, max_rel_diff=None,
                       max_state_rel_diff=None, free_run_max_rel_diff=None,
                       free_run_max_abs_diff=None, steps_checked=0, step_time_median=None,
                       step_time_max=None, timed_steps=0, compiler=cc, note=step.note,
                       layout=step.layout,
                       reference=f"{type(ctrl).__module__}.{type(ctrl).__qualname__}")
    if cc is None:
        forced = os.environ.get("FCOMP_CC")
        where = (f"FCOMP_CC={forced} is not found" if forced is not None
                 else "none of $CC, cc, gcc, clang is on the PATH")
        res.warnings.append(f"no C compiler found ({where}): the C code is written to {folder} "
                            "but not compiled, checked or timed")
        return res
    with tempfile.TemporaryDirectory() as tmp:
        say("compiling")
        try:
            lib = CompiledController(folder, cc, step.n_state, Path(tmp), n_ref=step.n_ref)
        except FcompError as exc:  # a broken toolchain: the code stays written
            res.warnings.append(f"{exc}; the C code is written to {folder} but not checked "
                                "or timed")
            return res
        say("checking")
        chk = check_equivalence(ctrl, lib, plant if plant is not None else model.plant,
                                layout=step.layout, start_from_init=name != "mpc", task=task,
                                duration=duration, seed=seed)
        say("timing")
        times = lib.bench(timing_steps, chk.Y, chk.REF)
    res.equivalent = bool(chk.max_rel_diff <= RTOL and chk.max_state_rel_diff <= RTOL)
    res.max_rel_diff = chk.max_rel_diff
    res.max_state_rel_diff = chk.max_state_rel_diff
    res.free_run_max_rel_diff = chk.free_max_rel_diff
    res.free_run_max_abs_diff = chk.free_max_abs_diff
    res.steps_checked = int(chk.u_free.size)
    res.step_time_median = float(np.median(times))
    res.step_time_max = float(np.max(times))
    res.timed_steps = int(times.size)
    if not res.equivalent:
        res.warnings.append(f"the compiled step differs from the Python controller's: relative "
                            f"{chk.max_rel_diff:.3g} on the command, {chk.max_state_rel_diff:.3g} "
                            f"on the state (tolerance {RTOL:g})")
    return res
