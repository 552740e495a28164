"""The ``direction-asymmetry`` effect: other levels, and viscous slope, for ``v < 0``.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`DirectionAsymmetry`; its docstring is the physics).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from fcomp.backend import Backend
from fcomp.effects.base import Effect, scale_levels
from fcomp.effects.record import DiagnosisForm, RecordView, ls_slope
from fcomp.parameters import ParamValues, make_params_class, spec

if TYPE_CHECKING:
    from fcomp.models.base import Signals


DirectionAsymmetryParams = make_params_class("DirectionAsymmetryParams", [
    spec("r_neg", "-", 1.0, 0.0, 10.0, "ratio of the v < 0 levels to the v > 0 levels",
         lower_open=True, directional=False),
    spec("rv_neg", "-", 1.0, 0.0, 10.0, "ratio of the viscous slope for v < 0 to that "
         "for v > 0 (models with a viscous term)", directional=False),
], owner="effect direction-asymmetry")


class DirectionAsymmetry(Effect):
    """Direction asymmetry: a separate friction level, and viscous slope, for ``v < 0``.

    Rod and piston seals are not symmetric (lip direction, rod seal only on
    one side, seed 002 Fig. 4): extending and retracting friction differ. The
    levels of ``v < 0`` are ``r_neg`` times those of ``v > 0``, and the viscous
    slope ``rv_neg`` times (the rod seal's film is sheared only one way; a
    model with a viscous term). A
    symmetric model leaves a residual even in ``v``: a step at every reversal,
    growing with speed on one side when the slopes differ.
    """

    name = "direction-asymmetry"
    Params = DirectionAsymmetryParams
    factors = ("direction",)
    confounded = ("force-offset", "area-error")
    signature = "residual even in v: same-sign offset in both directions, step at reversals"
    experiment = "the same speed profile in both directions of travel, with the force zero " \
        "known (see force-offset)"
    experiments = {
        kind: "the same speed profile extending and retracting, with the force zero known "
              "(see force-offset)" for kind in ("pneumatic-cylinder", "hydraulic-cylinder")
    }

    def modify_levels(self, be: Backend, L: dict, w: list[Any], sig: Signals,
                      P: ParamValues) -> dict:
        return scale_levels(L, be.if_else(sig.s > 0, 1.0, P("r_neg")))

    def extra_force(self, be: Backend, sig: Signals, P: ParamValues) -> tuple[Any, Any]:
        visc = next((P(n) for n in ("sigma2", "B") if P.has(n)), None)
        if visc is None:  # no viscous term to differ between the directions
            return 0.0, 0.0
        return (P("rv_neg") - 1.0) * visc * be.fmin(sig.v, 0.0), 0.0

    @classmethod
    def diagnosis_forms(cls) -> tuple[DiagnosisForm, ...]:
        """The levels alone (the viscous ratio held at 1), and levels with the viscous ratio."""
        return (DiagnosisForm("levels", held=("rv_neg",)), DiagnosisForm("levels-viscous"))

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The ratio of the median retracting to extending force; with the viscous ratio,
        the slope of the residual while retracting relative to the viscous one."""
        form = form or "levels-viscous"
        m = view.moving
        v, y = view.signal("v"), view.y
        pos, neg = m & (v > 0), m & (v < 0)
        if pos.sum() < 3 or neg.sum() < 3:
            return [{"r_neg": 1.0}]
        a, b = float(np.median(y[pos])), float(np.median(-y[neg]))
        ratio = b / a if a > 0 and b > 0 else 1.0
        starts = [{"r_neg": float(np.clip(ratio, 0.2, 5.0))}]
        flat = view.params
        visc = flat.get("sigma2", flat.get("B", 0.0))
        if visc > 0 and form != "levels":
            c = ls_slope(view.residual[neg], v[neg])
            starts.append({"r_neg": 1.0, "rv_neg": float(np.clip(1.0 + c / visc, 0.1, 9.0))})
        return starts
