"""The ``viscous-lead`` effect (structural): fluid friction leading the velocity.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`ViscousLead`; its docstring is the physics).
"""

from __future__ import annotations

import math

from fcomp.effects.record import RecordView, ls_slope
from fcomp.effects.structural import StructuralEffect
from fcomp.parameters import make_params_class, spec

ViscousLeadParams = make_params_class("ViscousLeadParams", [
    spec("T", "s", 0.0, 0.0, math.inf, "time constant of the fluid-friction lead",
         directional=False)], owner="effect viscous-lead")


class ViscousLead(StructuralEffect):
    """Lead of fluid friction, ``sigma2*(v + T*dv/dt)`` (NMLGM, seed 000 Eq. 8).

    The film does not respond instantly: in the fluid-lubrication regime the
    viscous force leads the velocity, so the force-velocity plot shows a
    hysteresis loop at high speed whose width grows with acceleration. A
    model without it leaves a residual proportional to the acceleration ``a``
    during fast sliding.
    """

    name = "viscous-lead"
    #: a force proportional to the acceleration while sliding: a moving mass's, too
    confounded = ("inertia-error",)
    adds = frozenset({"lead"})
    requires = frozenset({"viscous"})
    Params = ViscousLeadParams
    signature = "residual proportional to acceleration while sliding fast"
    experiment = "sinusoidal velocity at two or more frequencies, same amplitude"
    needs = ("a",)
    dynamic = True

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """``T`` from the residual regressed on ``sigma2*a``."""
        flat = view.params
        visc = flat.get("sigma2", flat.get("B", flat.get("sigma2_pos", 0.0)))
        a = view.signal("a")
        m = view.train
        sc = view.scales
        T = ls_slope(view.residual[m], visc * a[m]) if visc > 0 else 0.0
        return [{"T": T if T > 0 else 0.05 * sc.speed / sc.accel}]
