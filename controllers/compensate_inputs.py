"""The inputs of ``fcomp compensate``: the plant, the friction models, a user's reference.

Read once, each with one line naming the file and the problem when it is bad
(:class:`~fcomp.errors.FcompError`); used by :mod:`controllers.compensate`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from controllers.tasks import Task, check_fits_stroke, reference_task
from controllers.truths import Compared, rivals_of
from fcomp.errors import FcompError
from fcomp.models import FrictionModel


def warn_once(warns: list[dict[str, Any]], code: str, message: str,
              parameter: str | None) -> None:
    """Append the warning ``{"code", "parameter", "message"}`` (one line) unless it is there."""
    item = {"code": code, "parameter": parameter, "message": " ".join(message.split())}
    if item not in warns:
        warns.append(item)


def resolve_plant(plant: Any) -> Any:
    """A :class:`~plants.planfile.PlantFile`: itself, a plant file read (a path), or the
    built-in plant of a kind (``hydraulic``, ``pneumatic``)."""
    from plants.planfile import KINDS, PlantFile, builtin_plant_file, read_plant_file

    if isinstance(plant, PlantFile):
        return plant
    text = str(plant)
    if isinstance(plant, str) and plant in KINDS:
        return builtin_plant_file(plant)
    if not text.lower().endswith(".toml"):
        raise FcompError(f"plant {text!r}: give a plant file (.toml) or a built-in plant "
                         f"({', '.join(KINDS)})")
    return read_plant_file(plant)


def resolve_friction(spec: Any, plant_file: Any, use: str,
                     warnings: list[dict[str, Any]] | None = None,
                     effects: str | None = None) -> FrictionModel:
    """A friction model: itself, a model file read (its measurement terms dropped, with a
    warning appended to ``warnings``), or a registered name with the values of the
    built-in plant of the plant file's kind."""
    from fcomp.modelfile import is_model_file, seal_friction
    from fcomp.models import make_model

    if isinstance(spec, FrictionModel):
        return spec
    if is_model_file(spec):
        model, dropped = seal_friction(spec, use, effects)
        if dropped and warnings is not None:
            warn_once(warnings, "measurement-terms", dropped, str(spec))
        return model
    return make_model(str(spec), params=plant_file.friction_set)


def resolve_compared(spec: Any, plant_file: Any, warnings: list[dict[str, Any]],
                     effects: str | None = None) -> Compared:
    """A compared model (:class:`~controllers.truths.Compared`): the friction of
    :func:`resolve_friction` and, from a model file, its standard errors and the rivals
    its diagnosis wrote (:func:`controllers.truths.rivals_of`)."""
    from fcomp.modelfile import is_model_file, read_model

    model = resolve_friction(spec, plant_file, "controller friction", warnings, effects)
    if isinstance(spec, FrictionModel) or not is_model_file(spec):
        return Compared(model, source=f"{model.describe()}, values of {plant_file.friction_set}"
                        if not isinstance(spec, FrictionModel) else model.describe())
    mf = read_model(spec, effects)
    return Compared(model, stderr=dict(mf.stderr), rivals=rivals_of(mf.document, effects),
                    source=str(spec))


def model_label(spec: Any) -> str:
    """How results name a model: a file's stem, a registered model's name."""
    if isinstance(spec, FrictionModel):
        return spec.describe()
    return Path(str(spec)).stem if str(spec).lower().endswith(".json") else str(spec)


#: Longest user reference (s): every closed-loop run simulates all of it at the control
#: rate (an hour is 3.6 million steps at 1 kHz, per controller, model and draw).
MAX_REFERENCE_S = 3600.0


def read_reference(path: str | Path, stroke: float | None = None) -> Task:
    """A user's reference file as a task (:func:`controllers.tasks.reference_task`).

    The file is a CSV with the columns ``t`` (s) and ``x_ref`` (m, absolute
    position; other columns ignored): times finite and strictly increasing,
    at least two samples over at least 0.1 s, positions finite and, given the
    ``stroke`` (m), inside it with the 5 mm margins of every task.

    Raises
    ------
    FcompError
        One line naming the file and the first bad row.
    """
    from fcomp.textdata import (
        check_path,
        data_rows,
        first_bad,
        header_names,
        parse_rows,
        read_text,
    )

    label = str(path)
    p = check_path(path, "reference file")
    text = read_text(p, label, what="a reference (CSV)")
    names, start = header_names(label, text)
    for col in ("t", "x_ref"):
        if col not in names:
            raise FcompError(f"{label}: a reference needs the columns t and x_ref (s, m); "
                             f"the header has {', '.join(names)}")
    table = parse_rows(label, data_rows(text, start), ",", names, what="a reference")
    t = table.data[:, names.index("t")]
    x = table.data[:, names.index("x_ref")]
    for col, values in (("t", t), ("x_ref", x)):
        bad = first_bad(values)
        if bad is not None:
            raise FcompError(f"{label}: row {table.lines[bad]}, column {col}: not a finite "
                             "number")
    if t.size < 2:
        raise FcompError(f"{label}: a reference needs at least two samples")
    steps = np.diff(t)
    if np.any(steps <= 0):
        bad = int(np.argmax(steps <= 0)) + 1
        raise FcompError(f"{label}: row {table.lines[bad]}: time {t[bad]:g} s does not "
                         f"follow {t[bad - 1]:g} s (times must increase)")
    if t[-1] - t[0] < 0.1:
        raise FcompError(f"{label}: the reference lasts {t[-1] - t[0]:g} s; give at least "
                         "0.1 s")
    if t[-1] - t[0] > MAX_REFERENCE_S:  # every run simulates all of it, at the control rate
        raise FcompError(f"{label}: the reference lasts {t[-1] - t[0]:.4g} s, longer than the "
                         f"{MAX_REFERENCE_S:g} s a closed-loop run takes (each run simulates "
                         "every controller step of it); give a shorter stretch (is column t "
                         "in seconds?)")
    task = reference_task(t, x, name=p.stem)
    if stroke is not None:
        lo, hi = 0.005, stroke - 0.005
        out = np.flatnonzero((x < lo) | (x > hi))
        if out.size:
            i = int(out[0])
            raise FcompError(f"{label}: row {table.lines[i]}: x_ref = {x[i]:g} m is outside "
                             f"the stroke 0..{stroke:g} m less 5 mm margins")
        check_fits_stroke(task, task.start_position(stroke), stroke)
    return task


__all__ = ["MAX_REFERENCE_S", "model_label", "read_reference", "resolve_compared", "resolve_friction",
           "resolve_plant", "warn_once"]
