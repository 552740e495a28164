"""A friction model as a JSON document: the writing half of the model file.

The format (``docs/model-file.md``; read back by :mod:`fcomp.modelfile`)::

    {"format": "fcomp-model", "version": 1,
     "model": "lugre",                      # the registered model it was built from
     "description": "lugre + pressure-dependence",
     "features": [...],                     # LuGre family only: a check on reading
     "effects": [{"name": "pressure-dependence", "config": {}}, ...],
     "params": {"Fc": 120.0, ..., "kp": 1e-7},   # flat names, SI units
     "stderr": {"Fc": 1.2, ...},            # optional
     "undetermined": {"n": "at a bound ..."},  # optional: values not to be trusted
     "measurement_terms": {"effects": [...], "params": {"mass": 3.1}, "note": "..."},
     "source": {"program": "fcomp 0.1.0", ...}}

``effects`` lists, in order, the structural effects the model was built with
(its ``lineage``: ``stribeck``, ``presliding``, ... with the configuration
that chose their form) and then the add-on effects it carries, each with its
``config``; a user's effect also names the file that registered it
(``"module"``). Every parameter value, the effects' included, is in
``params``. Values that are not finite are written as the strings ``"inf"``
and ``"-inf"`` (strict JSON).

Measurement terms
-----------------
Some terms a fit or a diagnosis finds describe the *measurement*, not the
seal: a force offset (``force-offset``, or a fit's ``offset``), an inertia
error (``inertia-error``), a fitted moving mass (``mass``) and the lag of the
force channel (``lag``). They are kept in ``measurement_terms`` (effects with
their own parameters, and plain values), apart from the friction, so that a
comparison with the record can put them back while a plant or a compensator
uses the seal's friction alone.
"""

from __future__ import annotations

import json
import math
import numbers
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fcomp.errors import FileFormatError

if TYPE_CHECKING:
    from fcomp.models.base import FrictionModel

#: The ``format`` of a model file.
FORMAT = "fcomp-model"
#: The version this release writes (and the newest it reads).
VERSION = 1
#: Values of a fit or diagnosis that describe the measurement (name -> unit).
MEASUREMENT_PARAMS: dict[str, str] = {"mass": "kg", "offset": "N", "lag": "s"}
#: What ``measurement_terms`` is, written into every file that has some.
MEASUREMENT_NOTE = ("terms of the measurement, not of the seal (force offset, inertia "
                    "error, fitted mass, channel lag): used when the model is compared with "
                    "its record, dropped when it is plant friction or a compensator's model")


def number(value: float, key: str) -> float | str:
    """``value`` as a JSON value: a finite float, or ``"inf"``/``"-inf"``.

    Raises
    ------
    FileFormatError
        For NaN (``key`` names the value).
    """
    value = float(value)
    if math.isnan(value):
        raise FileFormatError(f"model file: {key} is NaN and cannot be written")
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return value


def _config(config: Mapping[str, Any], name: str) -> dict[str, Any]:
    """An effect's configuration as JSON values (numbers, strings, booleans)."""
    out: dict[str, Any] = {}
    for k, v in config.items():
        if isinstance(v, bool | str) or v is None:
            out[k] = v
        elif isinstance(v, numbers.Integral):
            out[k] = int(v)
        elif isinstance(v, numbers.Real):  # numpy scalars too
            out[k] = number(float(v), f"effect {name} config {k}")
        else:
            raise FileFormatError(f"model file: effect {name}: configuration {k} = {v!r} is "
                                  "not a number or a string and cannot be written")
    return out


def _effect_entry(effect: Any) -> dict[str, Any]:
    """``{"name", "config"[, "module"]}`` of an effect instance."""
    from fcomp.usercode import SOURCES

    entry: dict[str, Any] = {"name": effect.name, "config": _config(effect.config, effect.name)}
    module = type(effect).__module__
    if module in SOURCES:  # a user's effect: the file that registers it
        entry["module"] = SOURCES[module][0]
    return entry


def model_document(model: FrictionModel, *, stderr: Mapping[str, float] | None = None,
                   measurement: Mapping[str, float] | None = None,
                   source: Mapping[str, Any] | None = None,
                   undetermined: Mapping[str, str] | None = None) -> dict[str, Any]:
    """The model file's JSON document of ``model`` (module docstring).

    Parameters
    ----------
    model : FrictionModel
        The model with its values; its ``force-offset`` and ``inertia-error``
        effects go to ``measurement_terms``.
    stderr : mapping of str to float, optional
        Standard errors by flat name (names not in the file are left out; NaN
        is written as ``null``); default those the model carries
        (:attr:`~fcomp.models.base.FrictionModel.stderr`, a model file's read back).
    measurement : mapping of str to float, optional
        Measurement values of a fit or diagnosis (``mass``, ``offset``, ``lag``;
        others are ignored), beside (and over) those the model carries
        (:attr:`~fcomp.models.base.FrictionModel.measurement`).
    source : mapping, optional
        Where the model comes from (``command``, ``data``, ...), JSON values.
    undetermined : mapping of str to str, optional
        Parameters the record did not determine (at a bound of the box searched, not
        identified, an interval through zero) -> why, in words: written as
        ``undetermined`` so that a reader is warned before using them.

    Returns
    -------
    dict
        The document, ready for ``json.dumps(..., allow_nan=False)``.
    """
    from fcomp.effects.base import EFFECTS
    from fcomp.version import __version__

    lineage = tuple(getattr(model, "lineage", ()) or ())
    effects: list[dict[str, Any]] = []
    for name in lineage[1:]:
        config_in = getattr(EFFECTS.get(name), "config_in", None)
        effects.append({"name": name, "config": dict(config_in(model)) if config_in else {}})
    measured: list[dict[str, Any]] = []
    dropped: set[str] = set()
    for e in model.effects:
        entry = _effect_entry(e)
        if e.of_measurement:
            own = e.params.flat()
            entry["params"] = {k: number(v, f"params.{k}") for k, v in own.items()}
            dropped |= set(own)
            measured.append(entry)
        else:
            effects.append(entry)
    params = {k: number(v, f"params.{k}") for k, v in model.flat_params().items()
              if k not in dropped}
    flat = model.flat_params()  # an effect's own parameter (force-offset's offset) is not an extra
    terms = {**model.measurement, **dict(measurement or {})}
    extras = {k: number(v, f"measurement_terms.{k}") for k, v in terms.items()
              if k in MEASUREMENT_PARAMS and k not in flat and v is not None
              and not math.isnan(float(v))}
    doc: dict[str, Any] = {"format": FORMAT, "version": VERSION,
                           "model": lineage[0] if lineage else model.name,
                           "description": model.describe()}
    fam = model.feature_family()
    if fam is not None:
        doc["features"] = sorted(fam.features)
    doc["effects"] = effects
    doc["params"] = params
    if stderr is None:
        stderr = model.stderr
    if stderr:
        known = set(params) | set(extras) | dropped
        doc["stderr"] = {k: (None if math.isnan(float(v)) else number(v, f"stderr.{k}"))
                         for k, v in stderr.items() if k in known}
    if undetermined:
        known = set(params) | set(extras) | dropped
        doc["undetermined"] = {k: str(v) for k, v in undetermined.items() if k in known}
    if measured or extras:
        doc["measurement_terms"] = {"effects": measured, "params": extras,
                                    "note": MEASUREMENT_NOTE}
    if model.fitted_range:
        from fcomp.models.fitted_range import as_document

        doc["fitted_range"] = as_document(model.fitted_range)
    doc["source"] = {"program": f"fcomp {__version__}", **dict(source or {})}
    return doc


def document_text(doc: Mapping[str, Any]) -> str:
    """A model document as the file's text (strict JSON, indented)."""
    return json.dumps(doc, indent=2, allow_nan=False) + "\n"


def save_model(model: FrictionModel, path: str | Path, **document: Any) -> Path:
    """Write ``model`` as a model file to ``path`` (atomically: the old file or the new one).

    ``document`` are the keyword arguments of :func:`model_document`
    (``stderr``, ``measurement``, ``source``). Returns the path written.
    """
    from fcomp.outputs import write_text

    return write_text(path, document_text(model_document(model, **document)))
