"""Identification of friction models from measurements, with uncertainties.

:class:`FrictionFit` is the estimator (``fcomp fit``); how it fits a model is
a strategy (:mod:`.strategies`: :class:`StaticStrategy`, :class:`TrajectoryStrategy`,
:class:`DiscreteMemoryStrategy`, behind :class:`FitStrategy`) chaining the
stages of the fitting engine (:mod:`.engine`). :func:`fit_records` fits one
parameter vector to the masked samples of several records (:class:`Record`)
-- the engine's core, public for callers such as the diagnosis. The stages
are public too: :func:`~fcomp.identification.static.steady_state_points` and
:func:`~fcomp.identification.static.fit_steady_state` (seed 002's
steady-state characteristic), :class:`~fcomp.identification.dynamic.TrajectoryProblem`
with exact sensitivities (:class:`~fcomp.identification.sensitivity.SensitivityLoop`),
:func:`~fcomp.identification.uncertainty.estimate` (autocorrelation-robust
standard errors), :func:`~fcomp.identification.plausibility.check_fit` (the plausibility
warnings of any fit's estimates). docs/identification.md describes the procedure.
"""

from fcomp.identification.estimator import FrictionFit, default_free
from fcomp.identification.plausibility import FitWarning, RigContext, check_fit
from fcomp.identification.records import Record, RecordsFit, fit_records
from fcomp.identification.static import (
    SteadyStatePoints,
    fit_steady_state,
    steady_state_points,
)
from fcomp.identification.strategies import (
    DiscreteMemoryStrategy,
    FitStrategy,
    StaticStrategy,
    TrajectoryStrategy,
    strategy_for,
)
from fcomp.identification.target import FitData, fit_data

__all__ = [
    "DiscreteMemoryStrategy", "FitData", "FitStrategy", "FitWarning", "FrictionFit", "Record",
    "RecordsFit", "RigContext", "StaticStrategy", "SteadyStatePoints", "TrajectoryStrategy",
    "check_fit", "default_free", "fit_data", "fit_records", "fit_steady_state",
    "steady_state_points", "strategy_for",
]
