"""A friction model that travels: the model file (``docs/model-file.md``).

``fcomp fit ... --save-model M.json`` and ``fcomp diagnose ... --save-model
M.json`` write one (and put the same document into their JSON as
``"model_file"``); ``model.save(path)`` writes one from Python. Every option
that names a friction model also takes such a file (``simulate --friction
M.json``, ``compare --friction M.json``, the study and sweep friction options),
and so does :func:`load_model`::

    import fcomp

    model = fcomp.make_model("lugre", params="canudas1995").with_effects("dwell-time")
    model.save("lugre-dwell.json")
    same = fcomp.load_model("lugre-dwell.json")     # the same forces, bit for bit

The writing half is :mod:`fcomp.models.document` (the format is described
there); this module reads. A file this release cannot read -- not JSON, not a
model file, a newer ``version``, an unknown model or effect, a user effect
whose module is not given, a value out of its bounds -- raises
:class:`~fcomp.errors.FileFormatError`: one line naming the file and the
key (the command line prints it and exits with status 2).

Measurement terms (``measurement_terms``: force offset, inertia error, fitted
mass, channel lag) are read into :class:`ModelFile` apart from the friction:
:meth:`ModelFile.measured_model` puts the effects back (to compare with the
record), :func:`load_model` returns the seal's friction alone and warns
(``measurement-terms``) that it dropped them.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fcomp.effects import EFFECTS, Effect, load_effects_module
from fcomp.errors import FcompError, FcompWarning, FileFormatError, UnknownNameError, term
from fcomp.measurement import MAX_MASS
from fcomp.models import MODELS, FrictionModel, make_model
from fcomp.models.document import (
    FORMAT,
    MEASUREMENT_PARAMS,
    VERSION,
    model_document,
    save_model,
)
from fcomp.models.fitted_range import OutOfRangeError, check_range
from fcomp.parameters import MAX_VALUE, ParamSet, finite_number

#: Keys of a model file (``format`` .. ``source``).
KEYS = ("format", "version", "model", "description", "features", "effects", "params",
        "stderr", "measurement_terms", "fitted_range", "source",
        "undetermined")
#: Keys of one entry of ``effects``.
EFFECT_KEYS = ("name", "config", "module", "params")


@dataclass(frozen=True)
class ModelFile:
    """A model file read (:func:`read_model`).

    Attributes
    ----------
    model : FrictionModel
        The seal's friction: the model with its effects and values, without the
        measurement terms, carrying the file's standard errors of its values
        (:attr:`~fcomp.models.base.FrictionModel.stderr`).
    label : str
        The file as given (or ``"model document"``), for messages.
    measurement_effects : tuple of Effect
        ``force-offset`` / ``inertia-error`` effects of ``measurement_terms``.
    measurement_params : dict of str to float
        ``mass`` (kg), ``offset`` (N), ``lag`` (s) of ``measurement_terms``.
    stderr : dict of str to float
        Standard errors by flat name (those given).
    undetermined : dict of str to str
        Parameters the record did not determine -> why (the file's ``undetermined``):
        :func:`load_model` warns about them (``undetermined``).
    source : dict
        Where the model comes from.
    document : dict
        The document itself.
    """

    model: FrictionModel
    label: str
    measurement_effects: tuple[Effect, ...] = ()
    measurement_params: dict[str, float] = field(default_factory=dict)
    stderr: dict[str, float] = field(default_factory=dict)
    source: dict[str, Any] = field(default_factory=dict)
    document: dict[str, Any] = field(default_factory=dict)
    undetermined: dict[str, str] = field(default_factory=dict)

    def undetermined_note(self) -> str:
        """One line naming the values the record did not determine (empty: none)."""
        if not self.undetermined:
            return ""
        return (f"{self.label}: {', '.join(self.undetermined)} not determined by the record "
                "the model was fitted to (at a bound, not identified, or an interval through "
                "zero): their values shape the friction only where that record did; the "
                "file's \"undetermined\" says why for each")

    @property
    def measurement_terms(self) -> list[str]:
        """Names of the measurement terms the file holds (effects, then values)."""
        return [e.name for e in self.measurement_effects] + list(self.measurement_params)

    @property
    def mass(self) -> float | None:
        """The fitted moving mass (kg) of the measurement terms, or ``None``."""
        return self.measurement_params.get("mass")

    def measured_model(self) -> FrictionModel:
        """The model as fitted to its record: the friction with the measurement effects
        (a fit's ``offset`` as a ``force-offset`` effect), carrying ``mass`` and ``lag``
        -- values of the record, not of the friction (:attr:`mass`) -- as its
        :attr:`~fcomp.models.base.FrictionModel.measurement` (:func:`split_measurement`)."""
        model = self.model.with_effects(*self.measurement_effects) \
            if self.measurement_effects else self.model
        return split_measurement(model.with_measurement(self.measurement_params))[0] \
            .with_measurement({k: v for k, v in self.measurement_params.items()
                               if k != "offset"})

    def dropped_note(self, use: str = "plant friction") -> str:
        """One line saying which measurement terms are left out, and why (a plant's or a
        compensator's moving mass is its own, not the record's fitted one)."""
        mass = ("; the plant's moving mass is its own (rig.mass of its parameters)"
                if "mass" in self.measurement_params and "plant" in use else "")
        return (f"{self.label}: measurement terms {', '.join(self.measurement_terms)} dropped: "
                f"they describe the measurement, not the seal, and are not part of the "
                f"{use}{mass}")


def split_measurement(model: FrictionModel) -> tuple[FrictionModel, dict[str, float]]:
    """A model as it is compared with a record, and the terms of that record.

    The model's measurement terms (:attr:`~fcomp.models.base.FrictionModel.measurement`,
    a fit's ``mass``, ``offset``, ``lag``) are taken off: a constant ``offset`` becomes
    the ``force-offset`` effect that holds it (unless the model has one), ``mass`` (kg)
    and ``lag`` (s), which the comparison puts into the record's force balance, are
    returned.

    Returns
    -------
    model : FrictionModel
        The friction (with the offset's effect), without measurement terms.
    record_terms : dict of str to float
        ``mass`` and ``lag``, those the model carried.
    """
    terms = model.measurement
    if not terms:
        return model, {}
    out = model.with_measurement(None)
    offset = terms.pop("offset", None)
    if offset and all(e.name != "force-offset" for e in out.effects):
        out = out.with_effects(EFFECTS.get("force-offset")({"offset": offset}))
    return out, terms


def seal_friction(source: str | Path, use: str, effects_module: str | Path | None = None
                  ) -> tuple[FrictionModel, str | None]:
    """A model file's friction as a plant's or a controller's friction: the model without
    its measurement terms, and the line saying what was dropped (None: nothing was).

    Parameters
    ----------
    source : str or Path
        The model file.
    use : str
        What the friction becomes, for the line (``"plant friction"``, ...).
    effects_module : str or Path, optional
        The user's effects module the file may name (:func:`read_model`).
    """
    mf = read_model(source, effects_module)
    return mf.model, (mf.dropped_note(use) if mf.measurement_terms else None)


def is_model_file(spec: str | Path) -> bool:
    """Whether a friction option's value names a model file (ends in ``.json``) rather
    than a registered model."""
    return str(spec).lower().endswith(".json")


def read_model(source: str | Path | Mapping[str, Any],
               effects_module: str | Path | None = None, *, label: str | None = None
               ) -> ModelFile:
    """Read a model file (a path, or its document as a mapping).

    Parameters
    ----------
    source : str, Path or mapping
        The file, or the document itself. A fit's or diagnosis's JSON
        (``fcomp fit --json``) is read through its ``"model_file"``.
    effects_module : str or Path, optional
        A Python file registering the user effects the model uses (``--effects``;
        it is executed).
    label : str, optional
        How messages name a document given as a mapping (default ``"model document"``).

    Returns
    -------
    ModelFile

    Raises
    ------
    FileFormatError
        One line naming the file and the problem.
    """
    if effects_module is not None:
        load_effects_module(effects_module)
    if isinstance(source, Mapping):
        label, doc = label or "model document", dict(source)
    else:
        label, doc = str(source), _read_json(source)
    if "format" not in doc and isinstance(doc.get("model_file"), Mapping):
        doc = dict(doc["model_file"])  # the JSON of fcomp fit / diagnose
    _check_header(doc, label)
    params = _values(doc.get("params", {}), label, "params")
    model, m_effects = _build(doc, params, label)
    terms = _section(doc.get("measurement_terms", {}), label, "measurement_terms")
    unknown = sorted(set(terms) - {"effects", "params", "note"})
    if unknown:
        raise FileFormatError(f"{label}: measurement_terms has an unknown key {unknown[0]!r} "
                              "(known: effects, params, note)")
    for i, entry in enumerate(_list(terms.get("effects", []), label,
                                    "measurement_terms.effects")):
        where = f"measurement_terms.effects[{i}]"
        cls, config = _effect_class(entry, label, where)
        own = _values(entry.get("params", {}), label, f"{where}.params")
        m_effects.append(_effect(cls, own, config, label, where))
    m_params = _values(terms.get("params", {}), label, "measurement_terms.params")
    bad = sorted(set(m_params) - set(MEASUREMENT_PARAMS))
    if bad:
        raise FileFormatError(f"{label}: measurement_terms.params.{bad[0]} is not a measurement "
                              f"term (known: {', '.join(MEASUREMENT_PARAMS)})")
    _check_measurement(m_params, label)
    stderr = _values({k: v for k, v in _section(doc.get("stderr", {}), label,
                                                 "stderr").items() if v is not None},
                     label, "stderr")
    undetermined = _section(doc.get("undetermined", {}), label, "undetermined")
    bad_u = [k for k, v in undetermined.items() if not isinstance(v, str)]
    if bad_u:
        raise FileFormatError(f"{label}: undetermined.{bad_u[0]} must be text (why the value "
                              "is not determined)")
    if "fitted_range" in doc:
        try:
            model = model.with_fitted_range(doc["fitted_range"])
        except ValueError as exc:
            raise FileFormatError(f"{label}: {exc}") from None
    return ModelFile(model=model.with_stderr(stderr), label=label,
                     measurement_effects=tuple(m_effects),
                     measurement_params=m_params,
                     stderr=stderr,
                     source=dict(_section(doc.get("source", {}), label, "source")),
                     document=doc, undetermined=dict(undetermined))


def load_model(source: str | Path | Mapping[str, Any],
               effects_module: str | Path | None = None, *,
               measurement_terms: bool = False) -> FrictionModel:
    """The friction model of a model file (``fcomp.load_model``).

    Parameters
    ----------
    source : str, Path or mapping
        The file or its document (:func:`read_model`).
    effects_module : str or Path, optional
        The Python file registering the user effects the model uses.
    measurement_terms : bool
        ``False`` (default): the seal's friction; measurement terms in the file
        are dropped with a :class:`~fcomp.errors.FcompWarning`
        (``measurement-terms``). ``True``: the model as fitted to its record
        (:meth:`ModelFile.measured_model`).

    Returns
    -------
    FrictionModel
    """
    mf = read_model(source, effects_module)
    if mf.undetermined:
        warnings.warn(FcompWarning("undetermined", mf.undetermined_note()), stacklevel=2)
    if measurement_terms:
        return mf.measured_model()
    if mf.measurement_terms:
        warnings.warn(FcompWarning("measurement-terms", mf.dropped_note("friction model")),
                      stacklevel=2)
    return mf.model


# ----------------------------------------------------------------- reading
def _read_json(path: str | Path) -> dict[str, Any]:
    from fcomp.textdata import read_json

    doc = read_json(path, "model file", "; a model file is written by fcomp fit --save-model")
    if not isinstance(doc, dict):
        raise FileFormatError(f"{path}: not a model file (a JSON object is expected)")
    return doc


def _check_header(doc: Mapping[str, Any], label: str) -> None:
    if doc.get("format") != FORMAT:
        raise FileFormatError(f"{label}: not an fcomp model file (it needs \"format\": "
                              f"\"{FORMAT}\"; fcomp fit --save-model writes one)")
    version = doc.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise FileFormatError(f"{label}: version must be a positive integer, got "
                              f"{_shown(version)}")
    if version > VERSION:
        from fcomp.version import __version__

        raise FileFormatError(f"{label}: model file version {_shown(version)} is newer than fcomp "
                              f"{__version__} reads (version {VERSION}); upgrade fcomp")
    unknown = [k for k in doc if k not in KEYS]
    if unknown:
        raise FileFormatError(f"{label}: unknown key {unknown[0]!r} (known: {', '.join(KEYS)})")
    if not isinstance(doc.get("model"), str):
        raise FileFormatError(f"{label}: model must be a model name (fcomp list models)")


def _section(value: Any, label: str, key: str) -> dict[str, Any]:
    if not isinstance(value, Mapping):
        raise FileFormatError(f"{label}: {key} must be a JSON object")
    return dict(value)


def _list(value: Any, label: str, key: str) -> list[Any]:
    if not isinstance(value, list):
        raise FileFormatError(f"{label}: {key} must be a JSON list")
    return value


def _shown(value: Any) -> str:
    """``repr(value)``, cut short (a 400-digit number is not worth printing whole)."""
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:24]}... ({len(text)} characters)"


def _number(v: Any) -> float | None:
    """A JSON value as a float: a finite number (an integer too large for a float is not),
    or the strings ``"inf"``/``"-inf"``; ``None`` otherwise."""
    if isinstance(v, str):
        return float(v) if v in ("inf", "-inf") else None
    return finite_number(v)


def _values(section: Any, label: str, key: str) -> dict[str, float]:
    """A ``{name: number}`` section; ``"inf"``/``"-inf"`` are the infinities."""
    out: dict[str, float] = {}
    for k, v in _section(section, label, key).items():
        number = _number(v)
        if number is None:
            raise FileFormatError(f"{label}: {key}.{k} = {_shown(v)} is not a finite number in "
                                  "floating-point range (SI units; \"inf\" for infinity)")
        if math.isfinite(number) and abs(number) > MAX_VALUE:
            raise FileFormatError(f"{label}: {key}.{k} = {number:g} is beyond any plausible "
                                  "value in SI units (\"inf\" for infinity)")
        out[k] = number
    return out


#: Measurement term -> (lowest, highest, what it is): beyond, no record has such a value (a
#: moving mass as the sidecar's rig.mass allows it; a force channel lags by less than 1 s).
MEASUREMENT_RANGES: dict[str, tuple[float, float, str]] = {
    "mass": (0.0, MAX_MASS, "a moving mass"),
    "offset": (-MAX_VALUE, MAX_VALUE, "a constant force offset"),
    "lag": (-1.0, 1.0, "the lag of the force channel (negative: it leads)"),
}


def _check_measurement(values: Mapping[str, float], label: str) -> None:
    """The measurement terms within what a record can have (:data:`MEASUREMENT_RANGES`)."""
    for k, v in values.items():
        low, high, what = MEASUREMENT_RANGES[k]
        if not low <= v <= high:
            raise FileFormatError(f"{label}: measurement_terms.params.{k} = {v:g} "
                                  f"{MEASUREMENT_PARAMS[k]} is outside [{low:g}, {high:g}] "
                                  f"({what}; no fit gives such a value)")


def _effect_class(entry: Any, label: str, where: str) -> tuple[type[Effect], dict[str, Any]]:
    """The registered class and the configuration of an ``effects`` entry."""
    if not isinstance(entry, Mapping) or not isinstance(entry.get("name"), str):
        raise FileFormatError(f"{label}: {where} must be an object with an effect \"name\"")
    bad = [k for k in entry if k not in EFFECT_KEYS]
    if bad:
        raise FileFormatError(f"{label}: {where} has an unknown key {bad[0]!r} (known: "
                              f"{', '.join(EFFECT_KEYS)})")
    name = entry["name"]
    if name not in EFFECTS:
        module = entry.get("module")
        if module:
            raise FileFormatError(f"{label}: effect {name!r} is a user effect registered by "
                                  f"{module}: give that file with {term('effects_module')}")
        raise FileFormatError(f"{label}: unknown effect {name!r} (known: "
                              f"{', '.join(EFFECTS.names())}; a user effect needs its module, "
                              f"{term('effects_module')} MODULE.py)")
    return EFFECTS.get(name), _section(entry.get("config", {}), label, f"{where}.config")


def _accepts(params: ParamSet) -> set[str]:
    """The flat names a parameter set takes (``Fc``, and ``Fc_pos``/``Fc_neg`` where
    direction-dependent)."""
    out: set[str] = set()
    for s in type(params).SPECS:
        out.add(s.name)
        if s.directional:
            out |= {s.name + "_pos", s.name + "_neg"}
    return out


def _effect(cls: type[Effect], values: Mapping[str, float], config: Mapping[str, Any],
            label: str, where: str) -> Effect:
    """An effect instance with the values of ``values`` it takes and ``config``."""
    own = {k: v for k, v in values.items() if k in _accepts(cls.Params())}
    try:
        return cls(cls.Params.from_flat(own) if own else None, **config)
    except (ValueError, TypeError) as exc:
        raise FileFormatError(f"{label}: {where} ({cls.name}): {exc}") from None


def _build(doc: Mapping[str, Any], params: dict[str, float], label: str
           ) -> tuple[FrictionModel, list[Effect]]:
    """The model of ``doc`` (the named model, its effects attached in order, its values) and
    the measurement effects listed among its ``effects``.

    An effect of the measurement belongs in ``measurement_terms.effects``; a file written
    when it was still counted a friction effect (``area-error`` before it was known as an
    error of the force reconstruction) lists it among ``effects`` with its values in
    ``params``: it is read as the measurement term it is.
    """
    try:
        MODELS.get(doc["model"])
    except UnknownNameError as exc:
        raise FileFormatError(f"{label}: {exc}") from None
    model = make_model(doc["model"])
    consumed: set[str] = set()
    measured: list[Effect] = []
    for i, entry in enumerate(_list(doc.get("effects", []), label, "effects")):
        cls, config = _effect_class(entry, label, f"effects[{i}]")
        effect = _effect(cls, params, config, label, f"effects[{i}]")
        consumed |= {k for k in params if k in _accepts(effect.params)}
        if cls.of_measurement:
            measured.append(effect)
            continue
        try:
            model = effect.attach(model)
        except (ValueError, FcompError) as exc:
            raise FileFormatError(f"{label}: effects[{i}] ({cls.name}): {exc}") from None
    model = _with_values(model, params, consumed, label)
    features = doc.get("features")
    if features is not None and (not isinstance(features, list)
                                 or not all(isinstance(f, str) for f in features)):
        raise FileFormatError(f"{label}: features must be a list of names, got "
                              f"{_shown(features)}")
    fam = model.feature_family()
    if features is not None and fam is not None and sorted(fam.features) != sorted(features):
        raise FileFormatError(f"{label}: the model and its effects give the features "
                              f"{sorted(fam.features)}, the file says {sorted(features)} (the "
                              "order does not matter)")
    return model, measured


def _with_values(model: FrictionModel, params: Mapping[str, float], consumed: set[str],
                 label: str) -> FrictionModel:
    """``model`` with every value of ``params`` put into the model's or an effect's
    parameters (a direction-dependent name makes the parameter direction-dependent)."""
    owners = [model.params, *[e.params for e in model.effects]]
    shares: list[dict[str, float]] = [{} for _ in owners]
    for k, v in params.items():
        for i, owner in enumerate(owners):
            if k in _accepts(owner):
                shares[i][k] = v
                break
        else:
            if k not in consumed:
                raise FileFormatError(f"{label}: params.{k} is not a parameter of "
                                      f"{model.describe()!r} (known: "
                                      f"{', '.join(model.flat_params())})")
    try:
        new = type(model.params).from_flat(shares[0], base=model.params)
        effects = tuple(e.with_params(**s) if s else e
                        for e, s in zip(model.effects, shares[1:], strict=True))
    except ValueError as exc:
        raise FileFormatError(f"{label}: {exc}") from None
    return model._rebuild(new, effects)


__all__ = ["FORMAT", "VERSION", "ModelFile", "OutOfRangeError", "check_range", "is_model_file",
           "load_model", "model_document", "read_model", "save_model", "split_measurement"]
