"""The ``nonlocal-memory`` effect (structural): presliding that remembers reversal points.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`NonlocalMemory`; its docstring is the physics).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar

from fcomp.effects.record import RecordView
from fcomp.effects.structural import StructuralEffect, features_of
from fcomp.models.hysteresis import (
    HYSTERESIS_CONSTRAINTS,
    NONLOCAL_MEMORY_DEFAULTS,
    HysteresisTerm,
    hysteresis_specs,
)
from fcomp.models.lugre_family import FAMILY_SPECS, FEATURE_PARAMS, Structure
from fcomp.parameters import make_params_class

if TYPE_CHECKING:
    from fcomp.conditioning import Scales
    from fcomp.models.base import FeatureFamily, FrictionModel


NonlocalMemoryParams = make_params_class(
    "NonlocalMemoryParams",
    [*hysteresis_specs(NONLOCAL_MEMORY_DEFAULTS),
     *(FAMILY_SPECS[n] for n in FEATURE_PARAMS["elements"])],
    owner="effect nonlocal-memory", constraints=HYSTERESIS_CONSTRAINTS,
)


class NonlocalMemory(StructuralEffect):
    """Nonlocal memory: pre-sliding friction that remembers earlier reversal points.

    In pre-sliding the asperity junctions of the seal deform elastically and
    plastically: the force-displacement curve after each reversal starts
    stiff and softens, and its course depends on the earlier reversal points,
    not only on the current state (seed 000 Figs. 10-11): minor loops close,
    and once the displacement passes an earlier reversal point the curve goes
    on as if the minor loop had never happened (wiping-out). The LuGre bristle
    is one spring with local memory (stiffness ``sigma0`` after every reversal,
    lens-shaped loops). A model without this effect leaves residuals at small
    displacements that follow the displacement since the last reversal: the
    model is too soft just after a reversal and the loop shape is wrong, and
    after a minor loop an offset remains that the data erase once the earlier
    reversal point is passed.

    Two forms (configuration ``form``; models.md 1.8: "the hysteresis function
    of 1.6 (or GMS elements)"):

    ``"hysteresis"`` (default)
        seed 000's hysteresis function ``F(z)`` in place of ``sigma0*z``
        (:mod:`fcomp.models.hysteresis`, Tables 2-3; discrete turning-point
        memory, numeric only). Its defaults -- zero segment widths and
        amplitudes -- make every transition curve the continuation with slope
        ``sigma0``: a no-op.
    ``"maxwell-slip"``
        the bristle split into parallel Maxwell-slip elements (the ``elements``
        feature of :mod:`fcomp.models.lugre_family`: ``ms_spread``, ``ms_shape``;
        continuous states, exact sensitivities). ``ms_spread = 1`` is the
        bristle itself: a no-op. The diagnosis fits this form.

    Needs a bristle state (``presliding``).
    """

    name = "nonlocal-memory"
    FORMS: ClassVar[tuple[str, ...]] = ("hysteresis", "maxwell-slip")
    Params = NonlocalMemoryParams
    factors = ("distance-since-reversal",)
    signature = ("small-displacement residual following travel since reversal; minor-loop "
                 "offsets erased past earlier reversal points")
    experiment = "small displacement cycles with nested minor loops (seed 000 Figs. 10, 16)"
    dynamic = True
    #: within the presliding travel after a reversal or a start; in steady sliding every
    #: element slips and the force is the bristle's (matrix seeds 131/149: 99-100 % of
    #: the held-out fall of true nonlocal-memory records lies there, 47 % where
    #: nonlocal-memory absorbed a pressure law's misfit)
    acts_in = ("pre-sliding", "reversal", "dwell/break-away")

    @classmethod
    def diagnosis_config(cls, scales: Scales) -> dict[str, Any]:
        """The form with continuous states and exact sensitivities."""
        return {"form": "maxwell-slip"}

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """Maxwell-slip elements carrying most of the level, spread over one and two decades.

        The slip displacement of the softest element starts at three presliding
        lengths (the fitted bristle's ``Fc/sigma0``, else the record's); the
        elements' stiffness either constant (GMS) or scaling with the slip level
        (constant slip displacements), their shares equal. The bristle keeps its
        fitted stiffness for the share it still carries.
        """
        flat = view.params
        level = flat.get("Fc", flat.get("Fc_pos", view.level))
        s0 = flat.get("sigma0", level / view.d_pre)
        d_pre = level / s0 if s0 > 0 else view.d_pre
        out = []
        for spread, scaling in ((10.0, 0.0), (100.0, 0.0), (10.0, 1.0), (100.0, 1.0)):
            out.append({"ms_share": 0.9, "ms_dmax": 3.0 * d_pre, "ms_spread": spread,
                        "ms_shape": 0.0, "ms_scaling": scaling})
        return out

    @classmethod
    def config_in(cls, model: FrictionModel) -> dict[str, Any]:
        """``hysteresis`` for a model with the turning-point memory, else ``maxwell-slip``."""
        return {"form": "hysteresis" if model.discrete_memory() is not None else "maxwell-slip"}

    def applies_to(self, model: FrictionModel) -> bool:
        features = features_of(model)
        return (features is not None and "presliding" in features
                and "elements" not in features and model.discrete_memory() is None)

    def check(self, model: FrictionModel, fam: FeatureFamily) -> None:
        """Refuse a model without a bristle to replace, or with a memory already."""
        if "presliding" not in fam.features:
            raise ValueError(
                f"effect 'nonlocal-memory' replaces the bristle force sigma0*z: add "
                f"'presliding' to {fam.describe()!r} first"
            )
        super().check(model, fam)

    def term(self, fam: FeatureFamily) -> Structure:
        """The Maxwell-slip elements (a feature), or the hysteresis function in place of
        ``sigma0*z`` (:class:`~fcomp.models.hysteresis.HysteresisTerm`)."""
        flat = self.params.flat()
        shape = FEATURE_PARAMS["elements"]
        if self.form == "maxwell-slip":
            return Structure(self.name, frozenset({"elements"}), {k: flat[k] for k in shape})
        return HysteresisTerm(self.name, frozenset(),
                              {k: v for k, v in flat.items() if k not in shape})
