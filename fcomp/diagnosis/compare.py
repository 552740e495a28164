"""Compare a model with measurements: force domain per regime, worst segments, plant domain.

Force domain
    The model is simulated along the measured motion and its force compared
    with the measured (or reconstructed, models.md 2) friction force:
    :func:`~.residuals.regime_errors` gives the RMS error (N) over the held-out samples of
    each regime of :mod:`.regimes`; :func:`~.residuals.worst_segments` finds the held-out
    windows where the model fails most; :func:`compare` does the whole thing
    for one given model -- with its own parameter values (a fitted model, a
    parameter set), judged on every usable sample, or with ``fit=True``
    fitted on the training samples first and judged on the held-out ones --
    and returns a :class:`Comparison` (JSON of ``fcomp compare``, figures by
    :meth:`Comparison.plot`, a report by :meth:`Comparison.write_report`).

Plant domain
    The plant domain (a valve command ``u`` and the responses ``x``, ``p1``,
    ``p2``) needs a plant, which lives above this package:
    :func:`plants.comparison.compare_plant`, and ``fcomp.compare(...,
    plant=NAME)`` (:mod:`fcomp.api`) that attaches it to a :class:`Comparison`.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fcomp.diagnosis.data import DiagnosisData, prepare
from fcomp.diagnosis.features import FeatureStrength, residual_structure
from fcomp.diagnosis.loop import Diagnosis
from fcomp.diagnosis.noise import noise_floor
from fcomp.diagnosis.refit import RIG_EXTRAS, FitResult, Refit
from fcomp.diagnosis.regimes import Segmentation, segment
from fcomp.diagnosis.residuals import Segment, regime_errors, worst_segments
from fcomp.diagnosis.split import Split, make_split
from fcomp.diagnosis.writers import HELD_OUT
from fcomp.errors import FcompError, term
from fcomp.identification.estimator import MEASURED, model_rms
from fcomp.identification.plausibility import FitWarning
from fcomp.identification.target import CUTOFF_HZ
from fcomp.measurement import Measurement
from fcomp.modelfile import split_measurement
from fcomp.models import FrictionModel, make_model

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from fcomp.diagnosis.figures import View


@dataclass(frozen=True, repr=False)
class Comparison:
    """A model compared with a record in the force domain (errors in N).

    Attributes
    ----------
    model
        The model compared (with the values it was compared with).
    rms
        The RMS error (N). Of a model compared as given: the one RMS of a model on a
        record (:func:`fcomp.identification.estimator.model_rms`), which ``fcomp fit``
        prints for the model it fitted (``rms_measured`` says so in words). Of a
        fitted comparison: :attr:`rms_scored`, over the held-out samples.
    rms_scored
        RMS error over the judged samples: the scored residual
        (:func:`~fcomp.diagnosis.scoring.scored_residual`, the logarithmic score of
        the model's prediction band with the noise floor, in N), which equals the
        plain error where the motion fixes the prediction and charges a band the
        model cannot place. The same measure decides in :mod:`.loop`, and is the one
        of :attr:`regimes`.
    rms_plain
        RMS of the plain residual ``y - F_model`` over the judged samples.
    rms_measured
        What :attr:`rms` is, in words.
    regimes
        Per regime and ``"all"``: ``{"rms", "n"}`` over the judged samples.
    worst
        The judged windows (about 0.25 s) where the model fails most.
    F_measured, F_model
        The force matched and the model's prediction at every sample.
    split
        How the samples were split (one line).
    data, segmentation, heldout, result
        The prepared record, its regimes, the train/held-out split and the
        model's :class:`~fcomp.diagnosis.refit.FitResult` (residual everywhere).
    judged, judged_label
        The samples the errors are computed on: the held-out ones of a fitted
        comparison, every usable one (after the warm-ups) of a given model.
    residual_features
        How strongly the residual follows each feature, strongest first.
    fitted
        Whether the model was fitted on the training samples first.
    noise_floor
        The record's noise floor (N): the error a perfect model would leave.
    warnings
        Plausibility of the fit (fitted comparisons) and what the comparison cannot judge.
    plant
        Plant-domain comparisons (:class:`plants.comparison.PlantComparison`), one per
        record, attached by ``fcomp.compare(..., plant=NAME)``.
    """

    model: FrictionModel
    rms: float
    regimes: dict[str, dict[str, float | int | None]]
    worst: list[Segment]
    F_measured: np.ndarray
    F_model: np.ndarray
    split: str
    data: DiagnosisData
    segmentation: Segmentation
    heldout: Split
    result: FitResult
    judged: np.ndarray
    judged_label: str
    residual_features: list[FeatureStrength]
    fitted: bool
    noise_floor: float
    warnings: list[FitWarning] = field(default_factory=list)
    plant: list[Any] = field(default_factory=list)
    values: dict[str, float] = field(default_factory=dict)
    rms_plain: float = math.nan
    rms_scored: float = math.nan
    rms_measured: str = ""

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``fcomp compare``: ``{"model", "rms", "regimes", "residual_features",
        "warnings", ...}`` (N; ``plant`` with the plant-domain errors in m and Pa)."""
        def num(x: float | None) -> float | None:
            return float(x) if x is not None and math.isfinite(x) else None

        lineage = getattr(self.model, "lineage", ()) or (self.model.name,)
        return {
            "model": lineage[0],
            "description": self.model.describe(),
            "effects": [e.name for e in self.model.effects],
            "fitted": self.fitted,
            "judged": self.judged_label,
            "rms": num(self.rms),
            "rms_measured": self.rms_measured,
            "rms_scored": num(self.rms_scored),
            "rms_plain": num(self.rms_plain),
            "noise_floor": num(self.noise_floor),
            "regimes": {k: {"rms": num(v["rms"]), "n": v["n"]}  # type: ignore[arg-type]
                        for k, v in self.regimes.items()},
            "residual_features": [{"feature": f.feature, "strength": round(f.strength, 4)}
                                  for f in self.residual_features],
            "worst": [{"t_start": float(self.data.signal("t")[w.start]),
                       "t_stop": float(self.data.signal("t")[w.stop - 1]),
                       "rms": w.rms} for w in self.worst],
            "params": {k: num(v) for k, v in {**self.model.flat_params(),
                                                **self.values}.items()},
            "split": self.split,
            "records": list(self.data.labels),
            "plant": {pc.label: {"plant": pc.plant, "rms": pc.rms} for pc in self.plant},
            "units": {"force": "N", "x": "m", "p1": "Pa", "p2": "Pa"},
            "warnings": [w.to_dict() for w in self.warnings],
        }

    def view(self) -> View:
        """What the figures draw: the record and this one model beside it."""
        from fcomp.diagnosis.figures import Series, View  # the figures draw with matplotlib

        return View(self.data, self.segmentation, self.judged, self.judged_label,
                    (Series(f"model: {self.model.describe()}", "final", self.result,
                            self.regimes),),
                    {f.feature: f.strength for f in self.residual_features}, None)

    def plot(self, name: str | None = None) -> Figure | dict[str, Figure]:
        """One figure by name (``regimes``, ``residuals``, ``loops``, ``worst``,
        ``before_after``; ``plant`` for the plant domain), or all of them by name."""
        from fcomp.diagnosis.figures import comparison_figures

        figs = comparison_figures(self, only=name)
        return figs if name is None else figs[name]

    def write_report(self, directory: str | Path, *, command: str | None = None,
                     values_from: str | None = None) -> Path:
        """Write ``DIRECTORY/report.html`` (self-contained) and return its path; ``values_from``
        says where the model's values come from (``"the fit file fit.json"``)."""
        from fcomp.diagnosis.report import write_comparison_report

        return write_comparison_report(self, directory, command=command,
                                       values_from=values_from)

    def __repr__(self) -> str:
        return (f"<Comparison {self.model.describe()}: RMS {self.rms:.4g} N (scored "
                f"{self.rms_scored:.4g} N over {int(self.judged.sum())} {self.judged_label} "
                "samples) of "
                f"{', '.join(self.data.labels[:3])}{' ...' if len(self.data.labels) > 3 else ''}"
                f"{'; fitted' if self.fitted else ''}>")

    def _repr_html_(self) -> str:
        from fcomp.diagnosis.report import comparison_html

        return comparison_html(self)


def model_from_fit(doc: Mapping[str, Any], model: FrictionModel | None = None,
                   source: str = "fit") -> tuple[FrictionModel, float | None]:
    """The fitted model of a fit's JSON (``fcomp fit --json``) and its moving mass.

    ``doc`` gives ``model``, ``effects``, ``params`` and the parameters held
    (``fixed``); ``mass`` becomes the returned mass and ``offset`` the effect that
    holds it (:func:`fcomp.effects.effect_holding`); ``mass`` and ``lag`` are carried
    by the model as its measurement terms (:attr:`FrictionModel.measurement`); direction-dependent values
    (``Fc_pos``, ...) make the model directional. ``model`` (default: the model ``doc`` names) is the model
    the values are put into. Raises :class:`FcompError` naming ``source`` for a
    document that is not a fit or values the model does not have.
    """
    from fcomp.effects import effect_holding
    from fcomp.identification.estimator import directional_model

    if not isinstance(doc, Mapping) or not isinstance(doc.get("params"), Mapping) \
            or not isinstance(doc.get("model"), str):
        raise FcompError(f"{source}: not the JSON of a fit (fcomp fit --json): it needs "
                         "'model' and 'params'")
    mdl = make_model(doc["model"]) if model is None else model
    have = {e.name for e in mdl.effects}
    offset_effect = effect_holding("offset")
    for e in doc.get("effects") or []:
        if e not in have and e != offset_effect.name:
            mdl = mdl.with_effects(e)
    values: dict[str, float] = {}
    for k, v in {**(doc.get("fixed") or {}), **doc["params"]}.items():
        try:
            values[k] = float(v)
        except (TypeError, ValueError):
            raise FcompError(f"{source}: params.{k} = {v!r} is not a number") from None
    mass = values.pop("mass", None)
    offset = values.pop("offset", None)
    lag = values.pop("lag", None)  # the lag of the record's force channel, not the model's
    if any(k not in mdl.flat_params() for k in values):
        directional = directional_model(mdl)
        if all(k in directional.flat_params() for k in values):
            mdl = directional
    unknown = sorted(k for k in values if k not in mdl.flat_params())
    if unknown:
        raise FcompError(f"{source}: model {mdl.describe()!r} has no parameter(s) "
                         f"{', '.join(unknown)}; was the fit of another model?")
    mdl = mdl.with_params(**values) if values else mdl
    if offset:
        mdl = mdl.with_effects(offset_effect({"offset": offset}))
    terms = {k: v for k, v in (("mass", mass), ("lag", lag)) if v is not None}
    return (mdl.with_measurement(terms) if terms else mdl), mass


def fitted_model(fit: Any) -> tuple[FrictionModel, float | None]:
    """The model of a fitted :class:`~fcomp.identification.FrictionFit` as :func:`compare`
    takes it: its fitted values, a fitted ``offset`` as the effect that holds it
    (:func:`fcomp.modelfile.split_measurement`), and the fitted (or given) mass."""

    model, terms = split_measurement(fit.model_)
    mass = terms.get("mass", fit.mass)
    return model, (None if mass is None else float(mass))


#: What :attr:`Comparison.rms` of a model compared as given is where the record cannot be
#: run along (:func:`fcomp.identification.estimator.model_rms` fails).
SCORED = ("the scored RMS error over the usable samples (the model cannot run along this "
          "record's motion as a fit does: steady-state points)")

#: Longest record a given model is compared on in full (longer ones are block-averaged
#: for the prediction's alternatives only; every score is on the full record).
COMPARE_SAMPLES = 200_000


#: A predicted force beyond this (N) is no cylinder's: the values given are wrong.
MAX_FORCE = 1e9


def compare(model: str | FrictionModel, data: Measurement | Sequence[Measurement] | DiagnosisData,
            *, fit: bool = False, mass: float | None = None, split: str = "auto",
            cutoff_hz: float | None = None) -> Comparison:
    """Compare ``model`` with ``data`` in the force domain.

    Parameters
    ----------
    model
        A model name (its default values) or a :class:`FrictionModel` with its values
        (a fitted one, a parameter set, effects added).
    data
        One or several measurements (several = several experiments).
    fit
        Fit the model on the training samples first (the baseline step of
        :class:`~fcomp.diagnosis.loop.Diagnosis`) and judge it on the held-out
        ones; by default the model is compared as given, on every usable sample.
    mass
        The moving mass (kg) for records that give a driving force and no
        ``rig.mass`` (a fit's ``params.mass``); fitted with ``fit``.
    split, cutoff_hz
        As for :class:`~fcomp.diagnosis.loop.Diagnosis`; ``cutoff_hz`` is also the
        cut-off of :attr:`Comparison.rms` of a model compared as given (default: a
        fit's, :data:`fcomp.identification.target.CUTOFF_HZ`, so that it is the RMS
        ``fcomp fit`` prints).

    The plant domain is added by ``fcomp.compare(..., plant=NAME)``
    (:func:`fcomp.api.compare`), since the plants live above this package.
    """
    mdl = make_model(model) if isinstance(model, str) else model
    if not isinstance(mdl, FrictionModel):
        raise FcompError(f"model must be a model name or a FrictionModel, got {model!r}")
    mdl, record_terms = split_measurement(mdl)  # a fitted model's mass, offset, lag
    warnings: list[FitWarning] = []
    if fit:
        diag = Diagnosis(mdl, search=False, split=split, cutoff_hz=cutoff_hz, n_jobs=1,
                         check_baseline=False).fit(data)
        d, seg, sp, res = diag.data_, diag.segmentation_, diag.split_, diag.fit_
        judged, label, floor = sp.test, "held-out", diag.noise_floor_.value
        warnings = list(diag.warnings_)
        values = {k: v for k, v in res.values.items() if k in RIG_EXTRAS}
    else:
        d = data if isinstance(data, DiagnosisData) else prepare(data, cutoff_hz=cutoff_hz)
        seg = segment(d)
        sp = make_split(d, seg.valid, split)
        floor = noise_floor(d, seg).value
        values = {}
        if d.fits_mass:
            mass = record_terms.get("mass") if mass is None else mass
            if mass is None:
                raise FcompError(f"{', '.join(d.labels[:3])}: the record gives a driving force "
                                 "and no rig.mass, so the friction force depends on the moving "
                                 f"mass: give {term('mass')} KG, a fit that estimated it "
                                 f"({term('params')} FIT.json, or in Python the fit's "
                                 "model_), or rig.mass in the record's sidecar")
            values["mass"] = float(mass)
        if "lag" in record_terms and d.fits_lag:
            values["lag"] = record_terms["lag"]
        refit = Refit(d, sp, seg.d_pre, max_samples=COMPARE_SAMPLES, noise=floor)
        with np.errstate(over="ignore", invalid="ignore"):  # judged just below
            res = refit.result(mdl, values, 0)
        judged, label = seg.valid, "usable"
    r = res.residual  # scored (:func:`.scoring.scored_residual`): what decides
    plain, located = res.plain_residual, res.located
    if not (np.abs(res.F_hat[judged]) < MAX_FORCE).all():  # also catches nan
        huge = {k: v for k, v in res.model.flat_params().items() if abs(v) > 1e100}
        raise FcompError(f"{', '.join(d.labels[:3])}: the model {res.model.describe()} gives "
                         f"forces beyond {MAX_FORCE:.0e} N or not finite on this record"
                         + (f" (values {', '.join(f'{k} = {v:.3g}' for k, v in huge.items())})"
                            if huge else "") + ": check the parameter values")
    scored = float(np.sqrt(np.mean(r[judged] ** 2))) if judged.any() else math.nan
    rms, how = scored, (HELD_OUT if fit else SCORED)
    if not fit and not isinstance(data, DiagnosisData):  # the one RMS of a model on a record
        with contextlib.suppress(ValueError):  # steady points a run cannot take (as in fit)
            carried = {"mass": values["mass"]} if "mass" in values else {}
            rms = model_rms(mdl.with_measurement(carried), data,
                            cutoff_hz=cutoff_hz if cutoff_hz is not None else CUTOFF_HZ)
            how = MEASURED
    width = max(10, int(round(0.25 / d.scales.dt)))
    bounds = [e.start for e in d.experiments[1:]]
    features = residual_structure(located, d, seg, sp.train, sp.test)
    return Comparison(res.model, rms, regime_errors(r, seg, judged),
                      worst_segments(plain, judged, width, 3, bounds), d.y, res.F_hat,
                      sp.description, d, seg, sp, res, judged, label, features, fit, floor,
                      warnings, [], values,
                      float(np.sqrt(np.mean(plain[judged] ** 2))) if judged.any() else math.nan,
                      scored, how)
