"""The Python face of fcomp: the main calls of the command line as functions.

``import fcomp`` offers them (and the classes behind them) at the top level::

    import fcomp

    rec = fcomp.simulate("motion", "lugre", "sine:amplitude=0.01,frequency=0.5",
                         duration=4.0, params="canudas1995")
    f = fcomp.fit(rec, "lugre")                     # FrictionFit: params_, stderr_, rms_
    c = fcomp.compare(f.model_, rec)                 # Comparison: rms, regimes, plot()
    d = fcomp.diagnose(rec, "coulomb-viscous")       # Diagnosis: added_, verdict_

Each function is what its command does (``fcomp simulate``, ``fcomp fit``,
``fcomp compare``, ``fcomp diagnose``), minus the files: it takes and
returns objects (:class:`~fcomp.measurement.Measurement`, models, results).
A measurement argument may also be the path of a measurement file.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from fcomp.diagnosis import Comparison, Diagnosis
from fcomp.diagnosis import compare as compare_force
from fcomp.identification import FrictionFit
from fcomp.inputs import parse_input
from fcomp.measurement import Measurement
from fcomp.modelfile import is_model_file, load_model
from fcomp.models import FrictionModel, make_model
from fcomp.paramsets import ParameterSet
from fcomp.registry import PLANT_TOOLS, PLANTS

Data = Measurement | str | Path


def read(path: str | Path) -> Measurement:
    """The measurement file ``path`` (CSV and its TOML sidecar)."""
    return Measurement.read(path)


def _measurements(data: Data | Sequence[Data]) -> Measurement | list[Measurement]:
    if isinstance(data, Measurement):
        return data
    if isinstance(data, str | Path):
        return Measurement.read(data)
    return [d if isinstance(d, Measurement) else Measurement.read(d) for d in data]


def fit(data: Data, model: str | FrictionModel, **options: Any) -> FrictionFit:
    """Identify ``model`` from the measurement ``data`` (``fcomp fit``).

    ``options`` are those of :class:`~fcomp.identification.FrictionFit`
    (``offset``, ``mass``, ``fixed``, ``free``, ``directional``, ...). Returns the
    fitted estimator: ``params_``, ``stderr_``, ``ci_``, ``rms_``, ``warnings_``,
    ``model_`` (the model with the fitted values), ``to_dict()``.
    """
    meas = _measurements(data)
    if isinstance(meas, list):
        if len(meas) != 1:
            from fcomp.identification import fit_records  # noqa: F401 (documented alternative)

            raise ValueError("fit takes one measurement; fcomp.identification.fit_records fits "
                             "one parameter vector to several records")
        meas = meas[0]
    return FrictionFit(model, **options).fit(meas)


def compare(model: str | FrictionModel, data: Data | Sequence[Data], *, fit: bool = False,
            mass: float | None = None, split: str = "auto", cutoff_hz: float | None = None,
            plant: str | None = None, plant_params: str | ParameterSet | None = None
            ) -> Comparison:
    """One given model beside records (``fcomp compare``).

    The force domain is :func:`fcomp.diagnosis.compare` (``fit``, ``mass``,
    ``split``, ``cutoff_hz`` as there); with ``plant`` the plant of that name is
    also simulated with each record's command ``u`` and compared in ``x``,
    ``p1``, ``p2`` (:func:`plants.comparison.compare_plant`, with the parameter
    set ``plant_params``: a name, or a plant file's
    :meth:`~plants.planfile.PlantFile.parameter_set`), the results in ``Comparison.plant``.
    """
    meas = _measurements(data)
    records = [meas] if isinstance(meas, Measurement) else meas
    comp = compare_force(model, meas, fit=fit, mass=mass, split=split, cutoff_hz=cutoff_hz)
    if plant is None:
        return comp
    compare_plant = PLANT_TOOLS.get("compare_plant")
    return replace(comp, plant=[compare_plant(m, plant, comp.result.model, params=plant_params)
                                for m in records])


def diagnose(data: Data | Sequence[Data], baseline: str | FrictionModel,
             **options: Any) -> Diagnosis:
    """Find the missing physics (``fcomp diagnose``): :class:`~fcomp.diagnosis.Diagnosis`
    with ``options`` (``effects``, ``add``, ``split``, ``max_steps``, ...), fitted."""
    return Diagnosis(baseline, **options).fit(_measurements(data))


def simulate(plant: str, friction: str | FrictionModel,
             input: str | Callable[[np.ndarray], np.ndarray], duration: float, *,
             rate: float = 1000.0, params: str | None = None,
             x0: Mapping[str, float] | None = None, **engine: Any) -> Measurement:
    """Simulate ``plant`` with the friction model ``friction`` (``fcomp simulate``).

    ``friction`` is a model, a model name, or a model file (``.json``,
    :func:`fcomp.modelfile.load_model`); the measurement terms of a fitted model or a
    model file (the record's mass, offset, lag) are dropped with a warning: the plant
    has its own moving mass. ``input`` is a SPEC (``sine:amplitude=A,frequency=F``, ``step:amplitude=A``,
    ``csv:PATH``) or a function of time; ``params`` a parameter set (default: the
    plant's, which also gives a model named by ``friction`` its values);
    ``engine`` the integrator options (``method``, ``rtol``, ``atol``,
    ``max_steps``, ``coupling``). Returns the run as a measurement.
    """
    cls = PLANTS.get(plant)
    pset = params if params is not None else getattr(cls, "default_params", None)
    if isinstance(friction, str) and is_model_file(friction):
        model = load_model(friction)
    else:
        model = make_model(friction, params=pset) if isinstance(friction, str) else friction
    model = _seal(model)
    u = parse_input(input) if isinstance(input, str) else input
    run = cls(model, pset).simulate(u, duration, rate, x0=dict(x0) if x0 else None, **engine)
    if isinstance(input, str):
        run.meta.setdefault("simulation", {})["input"] = input
    return run


def _seal(model: FrictionModel) -> FrictionModel:
    """``model`` as plant friction: a fitted model's measurement terms (the record's mass,
    offset, lag) dropped with one warning -- the plant has its own moving mass."""
    terms = model.measurement
    if not terms:
        return model
    import warnings

    from fcomp.errors import FcompWarning

    warnings.warn(FcompWarning("measurement-terms", (
        f"{model.describe()}: measurement terms {', '.join(terms)} dropped: they describe "
        "the record the model was fitted to, not the seal, and are not part of the plant "
        "friction" + ("; the plant's moving mass is its own (rig.mass of its parameters)"
                      if "mass" in terms else ""))), stacklevel=3)
    return model.with_measurement(None)


#: The plant-domain names this module offers, defined by the plants (:mod:`plants.comparison`)
#: and reached through their registry.
_PLANT_NAMES = ("PlantComparison", "compare_plant")


def __getattr__(name: str) -> Any:
    """``PlantComparison`` and ``compare_plant``, from the plants' registry."""
    if name in _PLANT_NAMES:
        return PLANT_TOOLS.get(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["Comparison", "Diagnosis", "FrictionFit", "Measurement",  # noqa: F822 (__getattr__)
           "PlantComparison", "compare", "compare_plant", "diagnose", "fit", "make_model", "read",
           "simulate"]
