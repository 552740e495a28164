"""The ``presliding`` effect (structural): bristle compliance before gross sliding.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`Presliding`; its docstring is the physics).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, ClassVar

from fcomp.effects.base import Effect
from fcomp.effects.record import DiagnosisForm, RecordView
from fcomp.effects.structural import StructuralEffect, family_of, features_of
from fcomp.models.lugre_family import FAMILY_SPECS, Structure
from fcomp.parameters import make_params_class, spec

if TYPE_CHECKING:
    from fcomp.models.base import FeatureFamily, FrictionModel


PreslidingParams = make_params_class("PreslidingParams", [
    spec("sigma0", "N/m", math.inf, 0.0, math.inf, "bristle stiffness (inf: rigid, no-op)",
         lower_open=True, directional=False),
    spec("sigma1", "Ns/m", 0.0, 0.0, math.inf, "bristle damping", directional=False),
    FAMILY_SPECS["i_pre"],
    FAMILY_SPECS["ba_pre"],
], owner="effect presliding")


class Presliding(StructuralEffect):
    """Pre-sliding: bristle compliance ``sigma0`` (the step from a static map to LuGre).

    Before gross sliding the seal deforms elastically: the force builds up
    over micrometres of displacement instead of jumping at ``v = 0``. A
    static model leaves residual spikes at every velocity reversal and a
    force-displacement loop (instead of a step) at small amplitude; the
    residual follows displacement since reversal, not velocity. The default
    ``sigma0 = inf`` is the rigid limit (the static map itself: a no-op).
    The bristle's approach to sliding is LuGre's exponential by default;
    Dahl's exponent ``i_pre`` (``bristle-exponent`` of
    :mod:`fcomp.models.lugre_family`) makes it softer or stiffer, and a
    break-away deflection ``ba_pre`` (``bristle-break``: the elasto-plastic
    bristle of Dupont et al. 2002) keeps it purely elastic up to that share of
    its steady deflection. Two forms (configuration ``form``):

    ``"bristle"`` (default)
        the exponent, no break;
    ``"elasto-plastic"``
        the break as well: below it, and whenever ``z`` and ``v`` have opposite
        signs, the bristle is a spring (it unloads elastically after a
        reversal, where LuGre's bristle relaxes faster than a spring can).
        ``ba_pre = 0`` is not LuGre: the unloading is elastic.

    A diagnosis fits both, the elasto-plastic one with LuGre's exponent.
    """

    name = "presliding"
    FORMS: ClassVar[tuple[str, ...]] = ("bristle", "elasto-plastic")
    adds = frozenset({"presliding", "damping", "bristle-exponent"})
    marks = frozenset({"presliding", "damping"})
    Params = PreslidingParams
    factors = ("distance-since-reversal",)
    signature = "residual spikes at reversals that follow displacement since reversal"
    experiment = "small-amplitude displacement cycles (well below break-away)"
    dynamic = True

    @classmethod
    def diagnosis_forms(cls) -> tuple[DiagnosisForm, ...]:
        """Dahl's exponent without a break (``bristle``), and the elasto-plastic break with
        LuGre's exponent (``elasto-plastic``): two published laws of the approach to sliding."""
        return (DiagnosisForm("bristle", {"form": "bristle"}),
                DiagnosisForm("elasto-plastic", {"form": "elasto-plastic"}, held=("i_pre",)))

    @classmethod
    def forms_for(cls, model: FrictionModel) -> tuple[DiagnosisForm, ...]:
        """One form on a model with a bristle already (Dahl: only the damping is added)."""
        features = features_of(model)
        has = features is not None and "presliding" in features
        return cls.diagnosis_forms()[:1] if has else cls.diagnosis_forms()

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The stiffness from the presliding length, a factor of four either side; the
        bristle exponent stiffer and softer than LuGre's, or the break at a fifth, half
        and four fifths of the steady deflection."""
        s0 = view.level / view.d_pre
        if form == "elasto-plastic":
            return [{"sigma0": s0, "ba_pre": 0.5}, {"sigma0": 4 * s0, "ba_pre": 0.5},
                    {"sigma0": s0 / 4, "ba_pre": 0.5}, {"sigma0": s0, "ba_pre": 0.2},
                    {"sigma0": s0, "ba_pre": 0.8}]
        return [{"sigma0": s0}, {"sigma0": 4 * s0}, {"sigma0": s0 / 4},
                {"sigma0": s0, "i_pre": 0.5}, {"sigma0": s0, "i_pre": 2.0}]

    def attach(self, model: FrictionModel) -> FrictionModel:
        """The bristle (:meth:`term`); rigid bristles (``sigma0 = inf``, the default) are
        the static map itself, so on a model without a bristle the effect rides along."""
        fam = family_of(model, self.name)
        if "presliding" not in fam.features and math.isinf(self.params.scalar("sigma0")):
            return Effect.attach(self, model)  # rigid bristles: the static map, unchanged
        return super().attach(model)

    def term(self, fam: FeatureFamily) -> Structure:
        """On Dahl (compliant bristles already) only the damping: the model's own ``sigma0``
        is kept and ``sigma1 = 0`` (the default) is a no-op; else the bristle of the form."""
        if _dahl(fam):
            return Structure(self.name, frozenset({"damping"}),
                             {"sigma1": self.params.scalar("sigma1")})
        return super().term(fam)

    @classmethod
    def config_in(cls, model: FrictionModel) -> dict[str, Any]:
        """``elasto-plastic`` when the bristle has its break-away deflection, else ``bristle``."""
        features = features_of(model) or frozenset()
        return {"form": "elasto-plastic" if "bristle-break" in features else "bristle"}

    def added_features(self) -> set[str]:
        """The bristle, its damping and exponent; the break in the elasto-plastic form."""
        return set(self.adds) | ({"bristle-break"} if self.form == "elasto-plastic" else set())

    def new_values(self, fam: FeatureFamily) -> dict[str, float]:
        """The bristle's values (the break's only where the form has it)."""
        return {k: v for k, v in self.params.flat().items()
                if k != "ba_pre" or self.form == "elasto-plastic"}


def _dahl(fam: FeatureFamily) -> bool:
    """Whether ``fam`` has the bristle but not its damping (Dahl's model)."""
    return "presliding" in fam.features and "damping" not in fam.features
