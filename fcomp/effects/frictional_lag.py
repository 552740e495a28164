"""The ``frictional-lag`` effect (structural): the Stribeck curve following the speed late.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`FrictionalLag`; its docstring is the physics).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any, ClassVar

from fcomp.effects.record import DiagnosisForm, RecordView
from fcomp.effects.structural import StructuralEffect, features_of
from fcomp.models.lugre_family import FAMILY_SPECS, FEATURE_PARAMS
from fcomp.parameters import make_params_class

if TYPE_CHECKING:
    from fcomp.models.base import FeatureFamily, FrictionModel


FrictionalLagParams = make_params_class("FrictionalLagParams", [
    dataclasses.replace(FAMILY_SPECS["vb"], default=math.inf),
    *(FAMILY_SPECS[n] for n in ("tau_hp", "tau_hn", "tau_h0", "tau_L", "w_L")),
], owner="effect frictional-lag")


class FrictionalLag(StructuralEffect):
    """Frictional lag: the Stribeck curve follows the velocity late.

    The lubricant film thickens while sliding and drains while decelerating
    or resting, so friction on the accelerating branch is higher than on the
    decelerating one, and break-away after a dwell is higher than after a
    short stop. A model without it leaves a residual that is a loop against
    ``v`` (sign depending on whether ``|v|`` rises or falls) and that grows with
    time since the last reversal. Two forms (configuration ``form``):

    ``"film"`` (default)
        the lubricant-film state ``h`` of the modified LuGre model (models.md
        1.4, seed 002 Eqs. 8-11), with different time constants for building,
        draining and dwell; defaults ``vb = inf`` make ``h`` identically zero.
    ``"speed-lag"``
        Hess & Soom (1990): the curve is evaluated at a lagged speed,
        ``dvL/dt = (|v| - vL)/tau_L``, blended by ``w_L`` (the ``speed-lag`` of
        :mod:`fcomp.models.lugre_family`); the steady-state map is unchanged;
        ``w_L = 0`` (the default) is no lag.
    """

    name = "frictional-lag"
    FORMS: ClassVar[tuple[str, ...]] = ("film", "speed-lag")
    adds = frozenset({"film", "film-lag"})
    marks = frozenset({"film-lag"})
    requires = frozenset({"stribeck"})
    Params = FrictionalLagParams
    signature = "residual loop against v: rising and falling |v| branches differ"
    experiment = "velocity sweeps up and down at several rates; dwell before restart"
    dynamic = True

    @classmethod
    def diagnosis_forms(cls) -> tuple[DiagnosisForm, ...]:
        """Both forms, the film and the lagged speed."""
        return DiagnosisForm.each(cls.FORMS)

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """A small grid of time constants: 10 and 50 ms (at least 5 and 25 samples); for the
        film, its speed ``vb`` at one and four Stribeck speeds; for the lagged speed, the
        whole lag and half of it."""
        flat = view.params
        vs = flat.get("vs", flat.get("vs_pos", 0.1 * view.scales.speed))
        dt = view.scales.dt
        taus = (max(5 * dt, 0.01), max(25 * dt, 0.05))
        if (form or "film") == "speed-lag":
            return [{"tau_L": tau, "w_L": w} for tau in (*taus, 0.2) for w in (1.0, 0.5)]
        out = []
        for vb in (vs, 4 * vs):
            for tau in taus:
                out.append({"vb": vb, "tau_hp": tau, "tau_hn": tau, "tau_h0": 1.0})
        return out

    @classmethod
    def config_in(cls, model: FrictionModel) -> dict[str, Any]:
        """``speed-lag`` when the model follows a lagged speed, else ``film``."""
        features = features_of(model) or frozenset()
        return {"form": "speed-lag" if "speed-lag" in features else "film"}

    def applies_to(self, model: FrictionModel) -> bool:
        features = features_of(model)
        return (features is not None and "film-lag" not in features
                and "speed-lag" not in features)

    def check(self, model: FrictionModel, fam: FeatureFamily) -> None:
        """Refuse a model that has a lag already, or no Stribeck term to act on."""
        if self.applies_to(model) and "stribeck" not in fam.features:
            raise ValueError(
                f"effect 'frictional-lag' needs the Stribeck term: add 'stribeck' to "
                f"{fam.describe()!r} first"
            )
        super().check(model, fam)

    def added_features(self) -> set[str]:
        """The lagged speed, or the film and its lag (the form)."""
        return {"speed-lag"} if self.form == "speed-lag" else set(self.adds)

    def new_values(self, fam: FeatureFamily) -> dict[str, float]:
        """The form's own parameters; a film the model has already keeps its ``vb``."""
        values = dict(self.params.flat())
        lag = FEATURE_PARAMS["speed-lag"]
        if self.form == "speed-lag":
            return {k: values[k] for k in lag}
        values = {k: v for k, v in values.items() if k not in lag}
        if "film" in fam.features:  # static film already present: keep its vb
            values = {k: v for k, v in values.items() if not k.startswith("vb")}
        return values
