"""The ``viscous`` effect (structural): shear of the lubricant film, ``sigma2*v``.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`Viscous`; its docstring is the physics).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from fcomp.effects.record import RecordView, ls_slope
from fcomp.effects.structural import StructuralEffect
from fcomp.models.lugre_family import FAMILY_SPECS
from fcomp.parameters import make_params_class, spec

if TYPE_CHECKING:
    from fcomp.conditioning import Scales
    from fcomp.models.base import FeatureFamily


ViscousParams = make_params_class("ViscousParams", [
    spec("sigma2", "Ns/m", 0.0, 0.0, math.inf, "viscous coefficient"),
    FAMILY_SPECS["p_visc"], FAMILY_SPECS["v_ref"]], owner="effect viscous")


class Viscous(StructuralEffect):
    """Viscous friction ``sigma2*v``: shear of the lubricant film between seal and bore.

    The force grows with sliding speed, linearly for a Newtonian film; a
    shear-thinning lubricant or a film that thickens with speed makes it a
    power of the speed, ``sigma2*v*(|v|/v_ref)^(p_visc - 1)`` (the
    ``viscous-power`` of :mod:`fcomp.models.lugre_family`; ``v_ref`` is
    configuration, the record's speed scale in a diagnosis). A model without
    it leaves a residual odd in ``v`` that grows with speed, unrelated to
    position or pressure.
    """

    name = "viscous"
    CONFIG = ("v_ref",)
    adds = frozenset({"viscous", "viscous-power"})
    marks = frozenset({"viscous"})
    Params = ViscousParams
    factors = ("speed",)
    signature = "residual linear and odd in v, largest at high speed"
    experiment = "constant-speed runs at several speeds in both directions"

    @classmethod
    def diagnosis_config(cls, scales: Scales) -> dict[str, Any]:
        """The exponent's reference speed: the record's speed scale."""
        return {"v_ref": scales.speed}

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The slope of the residual against ``v`` while moving (Newtonian and thinning)."""
        m = view.moving
        c = ls_slope(view.residual[m], view.signal("v")[m])
        sc = view.scales
        c = c if c > 0 else 0.05 * sc.force / sc.speed
        return [{"sigma2": c}, {"sigma2": c, "p_visc": 0.6}]

    def new_values(self, fam: FeatureFamily) -> dict[str, float]:
        """The coefficient under the model's name for it (``sigma2``, ``B``), the exponent,
        and its reference speed (configuration where given)."""
        flat = self.params.flat()
        return {fam.viscous_name: flat["sigma2"], "p_visc": flat["p_visc"],
                "v_ref": float(self.config.get("v_ref", flat["v_ref"]))}
