"""What a closed loop asks of a friction model: the positions, speeds and chamber pressures
its tasks meet on a plant, checked against the ranges a model file was fitted on
(:func:`fcomp.modelfile.check_range`).

``sweep``, ``compensate`` and ``export`` run fitted models -- the plant's true friction,
the controllers' models -- on tasks of their own: a model fitted on a 40 mm stroke at
2-7 bar may be asked for 150 mm at 65 bar. Before any run, :func:`range_warnings` gives a
warning line for each model file used beyond its fitted ranges, and refuses a model
whose law is meaningless there (:class:`fcomp.modelfile.OutOfRangeError`).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from controllers.tasks import Task


def loop_use(plant_file: Any, tasks: Sequence[Task], fast: bool) -> dict[str, tuple[float, float]]:
    """The positions (m), velocities (m/s) and gauge chamber pressures (Pa) a closed loop on
    ``plant_file`` (a :class:`~plants.planfile.PlantFile`) meets on ``tasks``: the
    references' absolute positions and speeds, and the pressures between the valve's
    return and its supply."""
    stroke = float(plant_file.values["stroke"])
    xs: list[float] = []
    vs: list[float] = []
    for task in tasks:
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


def range_warnings(specs: Iterable[tuple[str, Any]], plant_file: Any, tasks: Sequence[Task],
                   fast: bool, effects: str | None = None) -> list[tuple[str, str]]:
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


__all__ = ["loop_use", "range_warnings"]
