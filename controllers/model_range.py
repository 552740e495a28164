"""Whether a friction model runs where it was fitted, and whether the plant can move it.

A model fitted on one record describes the seal over that record's positions,
speeds and pressures. A closed loop on another plant file runs it wherever its
tasks go (:func:`loop_use`, :func:`task_span`): a ``position-dependence`` fitted on a
25 mm O-ring record over ``x`` in [-37, 2.7] mm is a cubic in ``x`` that, at
150 mm on a 300 mm axis, multiplies the friction by some 200 (5 N becomes 1 kN).
Whatever a comparison then finds is a property of the extrapolated polynomial, not of
the seal.

Before any run of ``sweep``, ``compensate`` and ``export``, three checks say so:

* **beyond the ranges a model file was fitted on** (:func:`fitted_range_warnings`):
  the speeds, pressures and positions the file records (``fitted_range``) against
  those the loops meet, by :func:`fcomp.modelfile.check_range`; a model whose law is
  meaningless there is refused (:class:`fcomp.modelfile.OutOfRangeError`);
* **outside the fitted window** (:func:`range_warnings`): a model whose effects are
  configured for a position window (``x_min``, ``x_max``: the record's range the
  diagnosis gave ``position-dependence``) and the tasks' positions outside it, with
  the steady friction level there against its largest inside;
* **friction beyond the force** (:func:`range_warnings`): a true friction whose
  steady level at the tasks' positions and speeds reaches :data:`FORCE_SHARE` of the
  force the actuator has left after holding its load -- a plant that can hardly move.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from controllers.tasks import Task, get_task
from fcomp.models import FrictionModel

#: Share of the actuator's free force (after the load) a friction level may take.
FORCE_SHARE = 0.5
#: Speeds (m/s) the steady levels are evaluated at (beside the tasks' largest).
SPEEDS = (1e-3, 1e-2)


@dataclass(frozen=True)
class Span:
    """Where the tasks take the piston: positions ``[x_lo, x_hi]`` (m, absolute) and the
    largest reference speed ``v_max`` (m/s); the chambers' gauge pressures ``p`` (Pa) at
    which pressure-dependent levels are evaluated."""

    x_lo: float
    x_hi: float
    v_max: float
    p: float = 0.0


def loop_use(plant_file: Any, tasks: Sequence[Task | str], fast: bool
             ) -> dict[str, tuple[float, float]]:
    """The positions (m), velocities (m/s) and gauge chamber pressures (Pa) a closed loop on
    ``plant_file`` (a :class:`~plants.planfile.PlantFile`) meets on ``tasks``: the
    references' absolute positions and speeds, and the pressures between the valve's
    return and its supply."""
    stroke = float(plant_file.values["stroke"])
    xs: list[float] = []
    vs: list[float] = []
    for task in (get_task(t) if isinstance(t, str) else t for t in tasks):
        t = np.linspace(0.0, task.run_duration(fast), 2001)
        r, dr, _ = task.sample(t)
        x = task.start_position(stroke) + r
        xs += [float(x.min()), float(x.max())]
        vs += [float(dr.min()), float(dr.max())]
    v = plant_file.values
    p_atm = float(v["p_atm"])
    low = float(v.get("pt", p_atm)) if plant_file.kind == "hydraulic" else p_atm
    out = {"p": (low - p_atm, float(v["ps"]) - p_atm)}
    if xs:
        out["x"] = (min(xs), max(xs))
        out["v"] = (min(vs), max(vs))
    return out


def task_span(plant_file: Any, tasks: Sequence[Task | str], fast: bool) -> Span:
    """The :class:`Span` of :func:`loop_use`: the positions and the largest speed the tasks
    reach, and the chambers' gauge pressure halfway between the valve's return and supply."""
    use = loop_use(plant_file, tasks, fast)
    (x_lo, x_hi), (v_lo, v_hi) = use.get("x", (0.0, 0.0)), use.get("v", (0.0, 0.0))
    p_lo, p_hi = use["p"]
    return Span(x_lo, x_hi, max(abs(v_lo), abs(v_hi)), max(0.5 * (p_lo + p_hi), 0.0))


def position_window(model: FrictionModel) -> tuple[float, float] | None:
    """The position window (m) the model's effects were configured for (``x_min``,
    ``x_max`` of their configuration: the record's range), or ``None``."""
    lo, hi = math.inf, -math.inf
    for e in model.effects:
        cfg = e.config
        if "x_min" in cfg and "x_max" in cfg:
            lo, hi = min(lo, float(cfg["x_min"])), max(hi, float(cfg["x_max"]))
    return (lo, hi) if lo < hi else None


def steady_level(model: FrictionModel, x: np.ndarray, speeds: np.ndarray, p: float) -> float:
    """The largest ``|F_ss|`` (N) of ``model`` over positions ``x`` and speeds ``+-speeds``."""
    xs, vs = np.meshgrid(np.asarray(x, dtype=float), np.asarray(speeds, dtype=float))
    level = 0.0
    for sign in (1.0, -1.0):
        F = model.steady_state(sign * vs.ravel(), x=xs.ravel(), p1=p, p2=p)
        level = max(level, float(np.nanmax(np.abs(F))))
    return level


def range_warnings(label: str, model: FrictionModel, span: Span, *, truth: bool,
                   free_force: float | None = None) -> list[tuple[str, str]]:
    """``(code, message)`` of the checks of the module docstring for the model ``label``:
    ``outside-fitted-range`` (any model), ``friction-beyond-force`` (a truth, given the
    actuator's ``free_force`` in N)."""
    out: list[tuple[str, str]] = []
    speeds = np.array(sorted({*SPEEDS, max(span.v_max, SPEEDS[0])}))
    xs = np.linspace(span.x_lo, span.x_hi, 9)
    window = position_window(model)
    if window is not None and (span.x_lo < window[0] or span.x_hi > window[1]):
        inside = steady_level(model, np.linspace(*window, 9), speeds, span.p)
        there = steady_level(model, xs, speeds, span.p)
        role = "as the plant's friction" if truth else "as a controller's model"
        out.append(("outside-fitted-range",
                    f"{label} ({model.describe()}, {role}) runs at x = "
                    f"{span.x_lo * 1e3:.4g}..{span.x_hi * 1e3:.4g} mm, outside the "
                    f"{window[0] * 1e3:.4g}..{window[1] * 1e3:.4g} mm its position effect "
                    f"was fitted on: its friction there reaches {there:.4g} N against "
                    f"{inside:.4g} N inside (x{there / max(inside, 1e-12):.3g}); the "
                    "results describe the extrapolated model, not your seal"))
    if truth and free_force is not None and free_force > 0:
        level = steady_level(model, xs, speeds, span.p)
        if level >= FORCE_SHARE * free_force:
            out.append(("friction-beyond-force",
                        f"{label} ({model.describe()}) as the plant's friction reaches "
                        f"{level:.4g} N where the tasks run, {level / free_force * 100:.0f} % "
                        f"of the {free_force:.4g} N the actuator has left after holding "
                        "its load: the plant can hardly move"))
    return out


def fitted_range_warnings(specs: Iterable[tuple[str, Any]], plant_file: Any,
                          tasks: Sequence[Task | str], fast: bool, effects: str | None = None
                          ) -> list[tuple[str, str]]:
    """``(option, line)`` for each model file of ``specs`` (``(option, spec)`` pairs; a
    spec that is not a ``.json`` file is skipped) used by the loops beyond the ranges it
    was fitted on (:func:`fcomp.modelfile.check_range`).

    Raises
    ------
    fcomp.modelfile.OutOfRangeError
        A model whose law is meaningless where the loops take it.
    """
    from fcomp.modelfile import check_range, is_model_file, read_model

    use = loop_use(plant_file, tasks, fast)
    out: list[tuple[str, str]] = []
    seen: set[str] = set()
    for option, spec in specs:
        if not isinstance(spec, str) or not is_model_file(spec) or spec in seen:
            continue
        seen.add(spec)
        model = read_model(spec, effects).model
        out += [(option, line) for line in check_range(model, label=spec, **use)]
    return out


__all__ = ["FORCE_SHARE", "Span", "fitted_range_warnings", "loop_use", "position_window",
           "range_warnings", "steady_level", "task_span"]
