"""Identification of friction models from measurements, with uncertainties.

:class:`FrictionFit` is the estimator (``fcomp fit``); the stages it uses are
public too: :func:`~fcomp.identification.static.steady_state_points` and
:func:`~fcomp.identification.static.fit_steady_state` (seed 002's
steady-state characteristic), :class:`~fcomp.identification.dynamic.TrajectoryProblem`
with exact sensitivities (:class:`~fcomp.identification.sensitivity.SensitivityLoop`),
:func:`~fcomp.identification.uncertainty.estimate` (autocorrelation-robust
standard errors), :func:`~fcomp.identification.plausibility.check_fit` (the plausibility
warnings of any fit's estimates). docs/identification.md describes the procedure.
"""

from fcomp.identification.estimator import FrictionFit, default_free
from fcomp.identification.plausibility import FitWarning, RigContext, check_fit
from fcomp.identification.static import (
    SteadyStatePoints,
    fit_steady_state,
    steady_state_points,
)
from fcomp.identification.target import FitData, fit_data

__all__ = [
    "FitData", "FitWarning", "FrictionFit", "RigContext", "SteadyStatePoints", "check_fit",
    "default_free", "fit_data", "fit_steady_state", "steady_state_points",
]
