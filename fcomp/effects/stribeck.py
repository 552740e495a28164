"""The ``stribeck`` effect (structural): friction falling from break-away to Coulomb with speed.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`Stribeck`; its docstring is the physics).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from fcomp.effects.record import RecordView, stribeck_hump_start
from fcomp.effects.structural import StructuralEffect
from fcomp.models.lugre_family import FAMILY_SPECS
from fcomp.parameters import make_params_class, spec

if TYPE_CHECKING:
    from fcomp.models.base import FeatureFamily


StribeckEffectParams = make_params_class("StribeckEffectParams", [
    spec("Fs_excess", "N", 0.0, 0.0, math.inf, "Fs - Fc, break-away excess over Coulomb"),
    spec("vs", "m/s", 0.01, 0.0, math.inf, "Stribeck velocity", lower_open=True),
    spec("n", "-", 2.0, 0.0, 10.0, "Stribeck exponent", lower_open=True),
    FAMILY_SPECS["kappa_s"],
], owner="effect stribeck")


class Stribeck(StructuralEffect):
    """Stribeck effect: friction falls from the break-away level ``Fs`` to ``Fc`` with speed.

    At low speed the seal rides on boundary contacts; as speed grows a
    hydrodynamic film carries part of the load and friction drops over a
    characteristic speed ``vs``. A model without it under-predicts the force
    at low speed and at break-away: the residual is a hump at small ``|v|``
    decaying over a few ``vs``, with peaks right after each start. The curve's
    exponent ``n`` and form ``kappa_s`` (exponential to rational, the
    ``stribeck-form`` of :mod:`fcomp.models.lugre_family`) cover the shapes
    reported for seals (Armstrong-Helouvry 1991; Hess & Soom 1990).
    """

    name = "stribeck"
    adds = frozenset({"stribeck", "stribeck-form"})
    marks = frozenset({"stribeck"})
    Params = StribeckEffectParams
    factors = ("speed",)
    signature = "residual hump at low |v| decaying with speed; peaks after starts"
    experiment = "slow constant-speed runs (0.1-10 vs) in both directions"

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The low-speed hump of the force (:func:`~fcomp.effects.record.stribeck_hump_start`):
        its speed and a factor of four either side; the fat-tailed rational form too."""
        flat = view.params
        v = view.signal("v")
        m = view.train
        Fc = flat.get("Fc", flat.get("Fc_pos", view.level))
        B = flat.get("B", flat.get("sigma2", 0.0))
        Fs, vs = stribeck_hump_start(v[m], view.y[m], Fc, B, view.v_rest)
        exc = max(Fs - Fc, 0.1 * Fc)
        # the exponential form, and the fat-tailed rational one (its form has no gradient at 0)
        return [{"Fs_excess": exc, "vs": vs}, {"Fs_excess": exc, "vs": 4 * vs},
                {"Fs_excess": exc, "vs": vs / 4}, {"Fs_excess": exc, "vs": vs, "kappa_s": 0.7}]

    def new_values(self, fam: FeatureFamily) -> dict[str, float]:
        """The curve's parameters and ``Fs = Fc + Fs_excess`` (each side for directional
        levels)."""
        flat = fam.params.flat()
        p = self.params
        exc = p.scalar("Fs_excess")
        out: dict[str, float] = {"vs": p.scalar("vs"), "n": p.scalar("n"),
                                 "kappa_s": p.scalar("kappa_s")}
        if "Fc" in flat:
            out["Fs"] = flat["Fc"] + exc
        else:
            out["Fs_pos"] = flat["Fc_pos"] + exc
            out["Fs_neg"] = flat["Fc_neg"] + exc
        return out
