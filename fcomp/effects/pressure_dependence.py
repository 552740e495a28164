"""The ``pressure-dependence`` effect: friction levels scaled by the chamber pressures.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`PressureDependence`; its docstring is the physics).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from fcomp.backend import Backend
from fcomp.effects.base import Effect, scale_levels
from fcomp.effects.record import (
    DiagnosisForm,
    RecordView,
    constant_chambers,
    distinct_columns,
    ls_slope,
)
from fcomp.parameters import ParamValues, make_params_class, spec

if TYPE_CHECKING:
    from fcomp.models.base import Signals


PressureDependenceParams = make_params_class("PressureDependenceParams", [
    spec("kp", "1/Pa", 0.0, -1e-3, 1e-3, "relative level change per pascal of p1 + p2 (at "
         "p_ref)"),
    spec("kd", "1/Pa", 0.0, -1e-3, 1e-3, "relative level change per pascal of p1 - p2",
         directional=False),
    spec("kq", "1/Pa^2", 0.0, -math.inf, math.inf, "curvature of the linear law in p1 + p2",
         directional=False),
    spec("p_ref", "Pa", 0.0, -math.inf, math.inf, "reference gauge pressure sum (fixed)",
         directional=False),
    spec("d_ref", "Pa", 0.0, -math.inf, math.inf, "reference pressure difference (fixed)",
         directional=False),
    spec("p_sat", "Pa", 5e5, 1e3, 1e8, "saturation pressure of the saturating form",
         directional=False),
    spec("p_exp", "-", 1.0, 0.1, 3.0, "exponent of the power form", directional=False),
    spec("kpv", "1/Pa", 0.0, -1e-3, 1e-3, "relative change of the viscous coefficient per "
         "pascal of p1 + p2", directional=False),
], owner="effect pressure-dependence")

#: The laws of the level factor in ``p1 + p2`` (the effect's ``form``; the first is the
#: default, the law of files written before the others existed).
PRESSURE_FORMS = ("linear", "saturating", "power")
#: Parameters each form does not use (fixed: they do not change its force).
_UNUSED = {"linear": ("p_sat", "p_exp"), "saturating": ("kq", "p_exp"),
           "power": ("kq", "p_sat")}
#: A saturating exponent beyond this is taken as this (the factor is floored anyway).
_EXP_LIMIT = 50.0


class PressureDependence(Effect):
    """Pressure dependence: the levels scale with the chamber pressures (gauge).

    Chamber pressure energises lip seals: the normal force on the seal, and
    so the friction, grows with pressure (seed 000 Fig. 12, seed 001 Eq. 1;
    the Coulomb and break-away levels and the Stribeck speed change with the
    pressures in Tran & Yanada 2013). The piston seal sees both chambers and a
    rod seal only the rod side, so the chambers weigh differently; an energised
    lip saturates. With ``S = p1 + p2``, ``dS = S - p_ref`` and ``D = p1 - p2``
    the levels are scaled, ``(Fc, Fs) -> (Fc, Fs)*g``, by the factor of the
    ``form``::

        linear      g = 1 + kp*dS + kq*dS^2 + kd*(D - d_ref)
        saturating  g = 1 + kp*p_sat*(1 - exp(-dS/p_sat)) + kd*(D - d_ref)
        power       g = 1 + kp*(p_ref/p_exp)*((S/p_ref)^p_exp - 1) + kd*(D - d_ref)

    and the viscous coefficient by ``1 + kpv*dS`` (``sigma2``, ``B``: the film's
    shear grows with the contact width). ``kp`` is the relative change per
    pascal at ``p_ref`` in every form. The *saturating* form is a contact force
    that tends to a limit as the pressure grows (``p_sat`` the pressure over
    which the energised part saturates; linear for ``p_sat`` far above the
    record's pressures); the *power* form an empirical power of the pressure
    (``p_exp < 1`` grows ever slower; 1 is linear). ``kd`` weighs the chambers
    apart (``kd = 0``: equally), ``kq`` bends the linear law. A model without the
    effect leaves a residual whose magnitude follows the pressures: runs at
    high pressure sit above the fit, runs at low pressure below, with the same
    sign as the friction. ``p_ref`` and ``d_ref`` are held fixed (not fitted), and
    so is each parameter a form does not use. The factor is floored at 1 %
    (:data:`~fcomp.effects.base.LEVEL_FLOOR`): a law fitted on a few pressure
    levels must not make the level negative at a pressure the fit never weighed.

    A diagnosis fits the linear law, the level and the chamber weight alone
    (``kq``, ``kpv`` held), and once the effect is accepted tries the other laws
    (:meth:`refined_forms`: saturating, power, the viscous part scaled too, the
    slope ``kp`` of each direction its own -- a lip energised from one side changes
    the friction of one stroke more than the other's), each kept only when the
    acceptance rule accepts it against the law it would replace on the held-out
    data.
    """

    name = "pressure-dependence"
    Params = PressureDependenceParams
    factors = ("pressure",)
    FORMS = PRESSURE_FORMS
    needs = ("p1", "p2")
    signature = "residual magnitude correlates with p1 + p2, sign follows friction"
    experiment = "identical motions at two or more chamber pressure levels"
    experiments = {
        "hydraulic-cylinder": "identical motions at two or more supply pressures (or loads, "
                              "which move both chamber pressures)",
        "friction-rig": "identical motions at two or more normal-force (contact pressure) "
                        "levels",
        "electromechanical-axis": "identical motions with two or more payloads or screw "
                                  "preloads (the normal force on guides and nut; the axis "
                                  "has no fluid pressure)",
    }

    @property
    def fixed(self) -> tuple[str, ...]:
        """Never fitted: the references, and the parameters the form does not use."""
        return ("p_ref", "d_ref", *_UNUSED[self.form])

    def factor(self, be: Backend, sig: Signals, P: ParamValues) -> Any:
        """The level factor ``g`` of the form (class docstring), before the floor."""
        S = sig.p1 + sig.p2
        dS = S - P("p_ref")
        kp = P("kp", sig.s)
        if self.form == "saturating":
            ps = P("p_sat")
            shape = -kp * ps * be.expm1(be.fmin(-dS / ps, _EXP_LIMIT))
        elif self.form == "power":
            pr = be.fmax(P("p_ref"), 1.0)
            m = P("p_exp")
            shape = kp * pr / m * (be.power(be.fmax(S / pr, 1e-6), m) - 1.0)
        else:
            shape = kp * dS + P("kq") * dS * dS
        return 1.0 + shape + P("kd") * (sig.p1 - sig.p2 - P("d_ref"))

    def modify_levels(self, be: Backend, L: dict, w: list[Any], sig: Signals,
                      P: ParamValues) -> dict:
        return scale_levels(L, self.factor(be, sig, P), be=be)

    def extra_force(self, be: Backend, sig: Signals, P: ParamValues) -> tuple[Any, Any]:
        """The viscous term's change with the pressure, ``kpv*dS*visc*v``."""
        visc = next((P(n) for n in ("sigma2", "B") if P.has(n)), None)
        if visc is None:
            return 0.0, 0.0
        return P("kpv") * (sig.p1 + sig.p2 - P("p_ref")) * visc * sig.v, 0.0

    @classmethod
    def diagnosis_forms(cls) -> tuple[DiagnosisForm, ...]:
        """The linear law of the level and the chamber weight (curvature and viscous part
        held): the candidate the search judges."""
        return (DiagnosisForm("linear", {"form": "linear"}, held=("kq", "kpv")),)

    @classmethod
    def refined_forms(cls) -> tuple[DiagnosisForm, ...]:
        """The laws tried once the effect is accepted (class docstring)."""
        return (DiagnosisForm("saturating", {"form": "saturating"}, held=("kq", "kpv")),
                DiagnosisForm("power", {"form": "power"}, held=("kq", "kpv")),
                DiagnosisForm("linear-viscous", {"form": "linear"}, held=("kq",)),
                DiagnosisForm("saturating-viscous", {"form": "saturating"}, held=("kq",)),
                DiagnosisForm("directional", {"form": "linear"}, held=("kq", "kpv")))

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The level change per pascal of ``p1 + p2`` by least squares; then with the
        chambers weighed apart and a curvature too (the sign-corrected residual regressed
        on ``|F_hat|*(dS, dD, dS^2)``). For a refined form (:meth:`refined_forms`) only its
        own parameters: the law accepted starts it (``p_sat`` a half, one and two pressure
        spans; ``p_exp`` 0.5 and 0.75; ``kpv`` the residual regressed on ``dS*visc*v``)."""
        if form not in (None, "linear"):
            return self._refined_guess(view, form)
        m = view.moving
        s = np.sign(view.signal("v"))
        p1, p2 = view.signal("p1"), view.signal("p2")
        d_ref = float(np.mean(p1 - p2))
        dS = p1 + p2 - view.scales.p_mid
        dD = p1 - p2 - d_ref
        F = np.abs(view.F_hat)
        rs = (s * view.residual)[m]
        kp = ls_slope(rs, (F * dS)[m])
        bound = 0.9 / max(float(np.max(np.abs(dS))), 1.0)
        ref = {"p_ref": view.scales.p_mid, "d_ref": d_ref}
        cols = np.column_stack([F * dS, F * dD, F * dS * dS])[m]
        use = distinct_columns(cols)
        coef = np.zeros(3)
        coef[use], *_ = np.linalg.lstsq(cols[:, use], rs, rcond=None)
        bd = 0.9 / max(float(np.max(np.abs(dD))), 1.0)
        bq = 0.9 / max(float(np.max(dS * dS)), 1.0)
        full = {"kp": float(np.clip(coef[0], -bound, bound)),
                "kd": float(np.clip(coef[1], -bd, bd)),
                "kq": float(np.clip(coef[2], -bq, bq))}
        return [{"kp": float(np.clip(kp, -bound, bound)), **ref}, {**full, **ref}]

    def _refined_guess(self, view: RecordView, form: str) -> list[dict[str, float]]:
        sc = view.scales
        span = max(sc.p_span, 1e3)
        if form == "directional":  # each direction its own slope, from the one accepted
            kp = view.params.get("kp", 0.0)
            return [{"kp_pos": kp, "kp_neg": kp}]
        if form.startswith("saturating"):
            starts = [{"p_sat": k * span} for k in (0.5, 1.0, 2.0)]
        elif form == "power":
            if not sc.p_mid > 0:
                return []
            starts = [{"p_exp": 0.5}, {"p_exp": 0.75}]
        else:
            starts = [{}]
        if form.endswith("viscous"):
            flat = view.params
            visc = flat.get("sigma2", flat.get("B", 0.0))
            m = view.moving
            col = ((view.signal("p1") + view.signal("p2") - flat.get("p_ref", sc.p_mid))
                   * visc * view.signal("v"))[m]
            kpv = ls_slope(view.residual[m], col) if visc > 0 else 0.0
            bound = 0.9 / span
            starts = [{**st, "kpv": float(np.clip(kpv, -bound, bound))} for st in starts]
        return starts

    def held(self, view: RecordView) -> list[str]:
        """The chamber weight ``kd`` and the curvature ``kq`` where the record cannot tell
        them from the level change ``kp``, at their no-op value 0.

        One chamber vented or held at a constant pressure (``p2 = 0`` on a
        single-acting cylinder; :func:`constant_chambers`): ``p1 - p2`` and
        ``p1 + p2`` then differ by a constant, only ``kp + kd`` is determined, and
        ``kd`` is held (the chambers weighed equally) rather than left to trade
        against ``kp`` up to a bound. Otherwise the columns the record cannot tell
        apart (:func:`~fcomp.effects.record.distinct_columns`; two pressure levels:
        the square is a line). Both chambers constant: all three (the level alone).
        """
        m = view.moving
        p1, p2 = view.signal("p1"), view.signal("p2")
        still = constant_chambers(view, m)
        if len(still) == 2:
            return ["kp", "kd", "kq"]
        dS = (p1 + p2 - view.scales.p_mid)[m]
        dD = (p1 - p2)[m] - float(np.mean((p1 - p2)[m]))
        use = distinct_columns(np.column_stack([dS, dD, dS * dS - np.mean(dS * dS)]))
        if still:
            use = [i for i in use if i != 1]
        return [n for i, n in enumerate(("kp", "kd", "kq")) if i not in use]
