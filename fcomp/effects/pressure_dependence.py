"""The ``pressure-dependence`` effect: friction levels scaled by the chamber pressures.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`PressureDependence`; its docstring is the physics).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from fcomp.backend import Backend
from fcomp.effects.base import Effect, scale_levels
from fcomp.effects.record import RecordView, constant_chambers, distinct_columns, ls_slope
from fcomp.parameters import ParamValues, make_params_class, spec

if TYPE_CHECKING:
    from fcomp.models.base import Signals


PressureDependenceParams = make_params_class("PressureDependenceParams", [
    spec("kp", "1/Pa", 0.0, -1e-3, 1e-3, "relative level change per pascal of p1 + p2"),
    spec("kd", "1/Pa", 0.0, -1e-3, 1e-3, "relative level change per pascal of p1 - p2",
         directional=False),
    spec("kq", "1/Pa^2", 0.0, -math.inf, math.inf, "curvature of the law in p1 + p2",
         directional=False),
    spec("p_ref", "Pa", 0.0, -math.inf, math.inf, "reference gauge pressure sum (fixed)",
         directional=False),
    spec("d_ref", "Pa", 0.0, -math.inf, math.inf, "reference pressure difference (fixed)",
         directional=False),
], owner="effect pressure-dependence")


class PressureDependence(Effect):
    """Pressure dependence: the levels scale with the chamber pressures (gauge).

    Chamber pressure energises lip seals: the normal force on the seal, and
    so the friction, grows with pressure (seed 000 Fig. 12, seed 001 Eq. 1).
    The piston seal sees both chambers and a rod seal only the rod side, so
    the chambers weigh differently; an energised lip saturates. With
    ``S = p1 + p2`` and ``D = p1 - p2``::

        (Fc, Fs) -> (Fc, Fs)*(1 + kp*(S - p_ref) + kd*(D - d_ref) + kq*(S - p_ref)^2)

    ``kd`` weighs the chambers apart (``kd = 0``: equally), ``kq`` bends the
    law (a saturating seal: ``kq < 0``). A model without it leaves a residual
    whose magnitude follows the pressures: runs at high pressure sit above the
    fit, runs at low pressure below, with the same sign as the friction.
    ``p_ref`` and ``d_ref`` are held fixed (not fitted). The factor is floored at
    1 % (:data:`~fcomp.effects.base.LEVEL_FLOOR`): a curvature fitted on a few
    pressure levels must not make the level negative at a pressure the fit
    never weighed.
    """

    name = "pressure-dependence"
    Params = PressureDependenceParams
    fixed: ClassVar[tuple[str, ...]] = ("p_ref", "d_ref")
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

    def modify_levels(self, be: Backend, L: dict, w: list[Any], sig: Signals,
                      P: ParamValues) -> dict:
        dS = sig.p1 + sig.p2 - P("p_ref")
        dD = sig.p1 - sig.p2 - P("d_ref")
        return scale_levels(L, 1.0 + P("kp", sig.s) * dS + P("kd") * dD + P("kq") * dS * dS,
                            be=be)

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The level change per pascal of ``p1 + p2`` by least squares; then with the
        chambers weighed apart and a curvature too (the sign-corrected residual regressed
        on ``|F_hat|*(dS, dD, dS^2)``)."""
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
