"""The ``inertia-error`` effect: a wrong moving mass in the reconstructed force.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`InertiaError`; its docstring is the physics).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from fcomp.backend import Backend
from fcomp.effects.base import Effect
from fcomp.effects.record import RecordView, ls_slope
from fcomp.parameters import ParamValues, make_params_class, spec

if TYPE_CHECKING:
    from fcomp.models.base import Signals


InertiaErrorParams = make_params_class("InertiaErrorParams", [
    spec("dm", "kg", 0.0, -math.inf, math.inf, "mass error (true minus assumed)", directional=False),
], owner="effect inertia-error")


class InertiaError(Effect):
    """Inertia error: a mass correction ``dm*a`` in the reconstructed force.

    The friction force reconstructed as ``p1*A1 - p2*A2 - m*a`` carries
    ``-(m_true - m)*a`` when the moving mass is wrong (forgotten fittings,
    oil in the rod, a load). A model without it leaves a residual
    proportional to the acceleration at every speed, largest at reversals of
    a fast sine, independent of the friction's sign.
    """

    name = "inertia-error"
    Params = InertiaErrorParams
    of_measurement = True
    # sigma2*T*a while sliding is dm*a there; a force reconstructed from the pressures is
    # F + m*a, so an area error carries a share of m*a too
    confounded = ("viscous-lead", "area-error")
    signature = "residual proportional to acceleration at all speeds"
    experiment = "the same motion with a known added mass"
    needs = ("a",)
    dynamic = True

    def extra_force(self, be: Backend, sig: Signals, P: ParamValues) -> tuple[Any, Any]:
        return 0.0, P("dm")

    def unsuitable(self, view: RecordView) -> str | None:
        """A fitted mass already holds any mass error."""
        return ("the mass is already fitted (no rig.mass): a mass error is part of it"
                if view.fits_mass else None)

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The residual regressed on the acceleration."""
        m = view.train
        return [{"dm": ls_slope(view.residual[m], view.signal("a")[m])}]
