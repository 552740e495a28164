"""The Python face of fcomp: the main calls of the command line as functions.

``import fcomp`` offers them (and the classes behind them) at the top level::

    import fcomp

    rec = fcomp.simulate("motion", "lugre", "sine:amplitude=0.01,frequency=0.5",
                         duration=4.0, params="canudas1995")
    f = fcomp.fit(rec, "lugre")                     # FrictionFit: params_, stderr_, rms_
    c = fcomp.compare(rec, f.model_)                 # Comparison: rms, regimes, plot()
    d = fcomp.diagnose(rec, "coulomb-viscous")       # Diagnosis: added_, verdict_

Each function is what its command does (``fcomp simulate``, ``fcomp fit``,
``fcomp compare``, ``fcomp diagnose``), minus the files: it takes and
returns objects (:class:`~fcomp.measurement.Measurement`, models, results).
A measurement argument may also be the path of a measurement file. The order
is the same everywhere: the data first, then the friction model
(``fit(data, friction)``, ``compare(data, friction)``, ``diagnose(data,
friction)``), as the command line's ``--friction`` names it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from fcomp.diagnosis import Comparison, Diagnosis
from fcomp.diagnosis import compare as compare_force
from fcomp.errors import deprecated
from fcomp.identification import FrictionFit
from fcomp.inputs import parse_input
from fcomp.measurement import Measurement
from fcomp.modelfile import is_model_file, load_model, read_model
from fcomp.models import MODELS, FrictionModel, make_model
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


Friction = str | Path | FrictionModel


def _renamed(fn: str, old: str, new: str, value: Any, options: dict[str, Any]) -> Any:
    """The value of argument ``new`` of ``fn``, taken from its deprecated keyword ``old``
    in ``options`` (with a DeprecationWarning) when given so; both given: TypeError."""
    if old not in options:
        if value is None:
            raise TypeError(f"{fn}() missing required argument: {new!r}")
        return value
    if value is not None:
        raise TypeError(f"{fn}() got both {new}= and its deprecated spelling {old}=; give "
                        f"{new}=")
    deprecated(f"{fn}({old}=...)", f"{fn}({new}=...)", stacklevel=4)
    return options.pop(old)


def _is_friction(x: Any) -> bool:
    """Whether ``x`` names a friction model: a model, a registered name, a model file."""
    if isinstance(x, FrictionModel):
        return True
    if isinstance(x, str | Path):
        return is_model_file(x) or (isinstance(x, str) and x in MODELS.names())
    return False


def _friction(friction: Friction, mass: float | None) -> tuple[FrictionModel, float | None]:
    """The model (and the mass) of a friction argument: a model file is read as fitted to
    its record (measurement terms kept; its mass unless ``mass`` is given)."""
    if isinstance(friction, FrictionModel):
        return friction, mass
    if is_model_file(friction):
        mf = read_model(friction)
        return mf.measured_model(), mf.mass if mass is None else mass
    return make_model(str(friction)), mass


def fit(data: Data, friction: str | FrictionModel | None = None, **options: Any
        ) -> FrictionFit:
    """Identify the friction model ``friction`` from the measurement ``data`` (``fcomp
    fit``).

    ``options`` are those of :class:`~fcomp.identification.FrictionFit`
    (``offset``, ``mass``, ``fixed``, ``free``, ``directional``, ...). Returns the
    fitted estimator: ``params_``, ``stderr_``, ``ci_``, ``rms_``, ``warnings_``,
    ``model_`` (the model with the fitted values), ``to_dict()``. The keyword ``model=``
    is the deprecated spelling of ``friction=``.
    """
    friction = _renamed("fit", "model", "friction", friction, options)
    meas = _measurements(data)
    if isinstance(meas, list):
        if len(meas) != 1:
            from fcomp.identification import fit_records  # noqa: F401 (documented alternative)

            raise ValueError("fit takes one measurement; fcomp.identification.fit_records fits "
                             "one parameter vector to several records")
        meas = meas[0]
    return FrictionFit(friction, **options).fit(meas)


def compare(data: Data | Sequence[Data] | Friction | None = None,
            friction: Friction | Data | Sequence[Data] | None = None, *, fit: bool = False,
            mass: float | None = None, split: str = "auto", cutoff_hz: float | None = None,
            plant: str | None = None, plant_params: str | ParameterSet | None = None,
            jobs: int | None = None, scheduler: str | None = None,
            **deprecated_names: Any) -> Comparison:
    """One given friction model beside records (``fcomp compare``).

    Parameters
    ----------
    data
        One or several measurements (or their paths).
    friction
        The model: a :class:`~fcomp.models.FrictionModel` with its values, a model name
        (its default values) or a model file (its values, offset and mass as fitted
        to its record).
    fit, mass, split, cutoff_hz
        The force domain, as :func:`fcomp.diagnosis.compare` takes them.
    plant, plant_params
        Also simulate the plant of that name with each record's command ``u`` and
        compare ``x``, ``p1``, ``p2`` (:func:`plants.comparison.compare_plant`, with
        the parameter set ``plant_params``: a name, or a plant file's
        :meth:`~plants.planfile.PlantFile.parameter_set`), the results in
        ``Comparison.plant``.
    jobs, scheduler
        Where the plant-domain replays, one per record, run: ``jobs`` local processes
        (default: the CPU count) or the Dask distributed scheduler at ``scheduler``
        (:func:`fcomp.parallel.run_tasks`); the results are those of a serial run. The
        force domain is one computation over all records together (a joint split and,
        with ``fit``, one fit), so it runs in this process.

    The order ``compare(model, data)`` and the keyword ``model=`` are deprecated
    spellings (a :class:`DeprecationWarning`; they still work for one release).
    """
    friction = _renamed("compare", "model", "friction", friction, deprecated_names) \
        if "model" in deprecated_names else friction
    if deprecated_names:
        raise TypeError(f"compare() got an unexpected keyword argument "
                        f"{next(iter(deprecated_names))!r}")
    if data is None or friction is None:
        raise TypeError("compare() needs data and friction: compare(data, friction)")
    if _is_friction(data) and not _is_friction(friction):
        deprecated("compare(model, data)", "compare(data, friction)")
        data, friction = friction, data
    model, mass = _friction(friction, mass)  # type: ignore[arg-type]
    meas = _measurements(data)  # type: ignore[arg-type]
    records = [meas] if isinstance(meas, Measurement) else meas
    comp = compare_force(model, meas, fit=fit, mass=mass, split=split, cutoff_hz=cutoff_hz)
    if plant is None:
        return comp
    from fcomp.parallel import run_tasks

    replays = [(m, plant, comp.result.model, plant_params) for m in records]
    return replace(comp, plant=run_tasks(_replay, replays, workers=jobs, scheduler=scheduler))


def _replay(job: tuple[Measurement, str, FrictionModel, str | ParameterSet | None]) -> Any:
    """One record's plant-domain replay (:func:`compare`): a picklable job for a local
    process or a Dask worker."""
    meas, plant, model, params = job
    return PLANT_TOOLS.get("compare_plant")(meas, plant, model, params=params)


def diagnose(data: Data | Sequence[Data], friction: str | FrictionModel | None = None,
             **options: Any) -> Diagnosis:
    """Find the missing physics (``fcomp diagnose``) from the baseline friction model
    ``friction``: :class:`~fcomp.diagnosis.Diagnosis` with ``options`` (``candidates``,
    ``add``, ``split``, ``max_steps``, ...), fitted. The keyword ``baseline=`` is the
    deprecated spelling of ``friction=``."""
    friction = _renamed("diagnose", "baseline", "friction", friction, options)
    return Diagnosis(friction, **options).fit(_measurements(data))


def simulate(plant: str, friction: str | FrictionModel,
             input: str | Callable[[np.ndarray], np.ndarray], duration: float, *,
             rate: float = 1000.0, params: str | None = None,
             x0: Mapping[str, float] | None = None, **engine: Any) -> Measurement:
    """Simulate ``plant`` with the friction model ``friction`` (``fcomp simulate``).

    ``friction`` is a model, a model name, or a model file (``.json``,
    :func:`fcomp.modelfile.load_model`: its measurement terms dropped with a
    warning). ``input`` is a SPEC (``sine:amplitude=A,frequency=F``, ``step:amplitude=A``,
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
    u = parse_input(input) if isinstance(input, str) else input
    run = cls(model, pset).simulate(u, duration, rate, x0=dict(x0) if x0 else None, **engine)
    if isinstance(input, str):
        run.meta.setdefault("simulation", {})["input"] = input
    return run


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
