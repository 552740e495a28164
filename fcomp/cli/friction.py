"""The friction model of a command's options: a name or a model file, the values of
``--params``, ``--add-effect``, ``--set``."""

from __future__ import annotations

import argparse
from typing import Any

from fcomp.cli import emit
from fcomp.cli.emit import warn
from fcomp.cli.options import parse_assignments
from fcomp.effects import load_effects_module
from fcomp.errors import FcompError
from fcomp.models import FrictionModel, make_model


def build_model(name: str, params: str | None, args: argparse.Namespace) -> FrictionModel:
    """The friction model of the options (model, parameter set, effects, overrides)."""
    if args.effects is not None:
        load_effects_module(args.effects)
    model = make_model(name, params=params)
    if args.add_effect:
        model = model.with_effects(*args.add_effect)
    overrides = parse_assignments(args.set)
    return model.with_params(**overrides) if overrides else model


def model_source(data: list[str]) -> dict[str, Any]:
    """A model file's ``source`` for a command run on the records ``data``."""
    import shlex

    return {"command": "fcomp " + shlex.join(emit.ARGV) if emit.ARGV else None, "data": list(data)}


def friction_model(spec: str, params: str | None, args: argparse.Namespace, *,
                   use: str = "plant friction") -> FrictionModel:
    """The friction model a friction option names: a model file (``.json``, its
    measurement terms dropped with a warning) or a registered model with the values of
    ``params`` (a parameter set, a fit's JSON or a model file: :func:`model_with_params`).

    A file takes no ``params``; ``--add-effect`` and ``--set`` apply to it as to a name.
    """
    return _friction(spec, params, args, use, measured=False)[0]


def model_with_params(args: argparse.Namespace, *, use: str = "plant friction",
                      measured: bool = False, document: dict[str, Any] | None = None
                      ) -> tuple[FrictionModel, float | None]:
    """The model of ``--friction`` with the values of ``--params`` (``SET``, ``FIT.json``
    or ``MODEL.json``), ``--add-effect`` and ``--set``; and the moving mass (kg) a fit's
    JSON or a model file gives (``None`` otherwise).

    ``measured``: the model as fitted to its records (a model file's or a fit's offset
    kept as an effect; ``compare``); otherwise the seal's friction (measurement terms
    dropped with a warning). ``document``: the ``--params`` file already read
    (:func:`params_document`), not read again.
    """
    refuse_params_with_model_file(args.friction, args.params)
    return _friction(args.friction, args.params, args, use, measured=measured,
                     document=document)


def _friction(spec: str, params: str | None, args: argparse.Namespace, use: str, *,
              measured: bool, document: dict[str, Any] | None = None
              ) -> tuple[FrictionModel, float | None]:
    from fcomp.modelfile import is_model_file, read_model, seal_friction

    mass: float | None = None
    if is_model_file(spec):
        if params is not None and is_model_file(params):  # a set gives a plant's values
            raise FcompError(f"--params {params}: the model file {spec} gives the values; "
                             "change one with --set NAME=VALUE")
        if measured:
            mf = read_model(spec, args.effects)
            model, mass = mf.measured_model(), mf.mass
        else:
            model, dropped = seal_friction(spec, use, args.effects)
            if dropped:
                warn("measurement-terms", dropped, "friction")
    elif params is not None and is_model_file(params):
        model, mass = _values_file(spec, params, args.effects, use, measured, document)
    else:
        return build_model(spec, params, args), None
    if args.add_effect:
        model = model.with_effects(*args.add_effect)
    overrides = parse_assignments(args.set)
    return (model.with_params(**overrides) if overrides else model), mass


def warn_fitted_range(model: FrictionModel, label: str, option: str, **use: Any) -> None:
    """Warn (code ``fitted-range``) for each signal of ``use`` (``x``, ``v``, ``p``: what the
    command will meet) beyond the ranges ``model`` was fitted on; a use where the model is
    meaningless is refused (:func:`fcomp.modelfile.check_range`)."""
    from fcomp.modelfile import check_range

    for line in check_range(model, label=label, **use):
        warn("fitted-range", line, option)


def refuse_params_with_model_file(friction: str | None, params: str | None,
                                  plant_option: bool = False) -> None:
    """The one rule of every command (docs/cli.md): a model file (``--friction MODEL.json``)
    gives its friction's values, so ``--params`` beside it is refused -- change one value
    with ``--set``; ``plant_option``: the command takes the plant's values from
    ``--plant-params SET|PLANT.toml``, and the line says so."""
    from fcomp.modelfile import is_model_file

    if params is None or friction is None or not is_model_file(friction):
        return
    plant = "; the plant's values: --plant-params SET|PLANT.toml" if plant_option else ""
    raise FcompError(f"--params {params}: the model file {friction} gives the "
                     f"values; change one with --set NAME=VALUE{plant}")


def params_document(path: str) -> dict[str, Any]:
    """The JSON object of ``--params FILE.json`` (a fit's JSON or a model file), read once;
    one line naming the file on any problem."""
    from fcomp.textdata import read_json

    try:
        doc = read_json(path, "parameter file")
    except FcompError as exc:
        raise FcompError(f"--params {exc}") from None
    if not isinstance(doc, dict):
        raise FcompError(f"--params {path}: neither a fit's JSON nor a model file (a JSON "
                         "object is expected)")
    return doc


def _values_file(name: str, path: str, effects: str | None, use: str, measured: bool,
                 doc: dict[str, Any] | None = None) -> tuple[FrictionModel, float | None]:
    """The model ``name`` with the values of ``--params FILE.json``: a fit's JSON (``fcomp
    fit --json``) or a model file (``fcomp fit --save-model``) of that model (``doc``: the
    file already read)."""
    from fcomp.diagnosis.compare import model_from_fit
    from fcomp.modelfile import read_model

    source = f"--params {path}"
    doc = params_document(path) if doc is None else doc
    if isinstance(doc.get("records"), list):
        raise FcompError(f"{source}: the JSON of a fit of several records; give the fit of "
                         "one record")
    if doc.get("model") not in (None, name):
        raise FcompError(f"{source}: gives the values of {doc['model']}, not of {name}; "
                         f"give --friction {doc['model']}")
    if effects is not None:
        load_effects_module(effects)
    if "format" in doc or (not measured and isinstance(doc.get("model_file"), dict)):
        mf = read_model(doc, effects, label=source)
        if measured:
            return mf.measured_model(), mf.mass
        if mf.measurement_terms:
            warn("measurement-terms", mf.dropped_note(use).replace("model document", source),
                 "params")
        return mf.model, None
    return model_from_fit(doc, make_model(name), source=source)
