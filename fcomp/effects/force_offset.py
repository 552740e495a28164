"""The ``force-offset`` effect: a constant bias of the force measurement.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`ForceOffset`; its docstring is the physics).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from fcomp.backend import Backend
from fcomp.effects.base import Effect
from fcomp.effects.record import RecordView
from fcomp.parameters import ParamValues, make_params_class, spec

if TYPE_CHECKING:
    from fcomp.models.base import Signals


ForceOffsetParams = make_params_class("ForceOffsetParams", [
    spec("offset", "N", 0.0, -math.inf, math.inf, "constant force offset", directional=False),
], owner="effect force-offset")


class ForceOffset(Effect):
    """Force offset: a constant bias of the force sensor or pressure transducers.

    Load-cell zero drift or a pressure-sensor offset adds a constant to the
    measured force. A model without it leaves a residual with a non-zero
    mean of the same sign in both directions, unrelated to ``v``, ``x`` or
    the pressures.
    """

    name = "force-offset"
    Params = ForceOffsetParams
    # the same force while sliding: only rest tells; at one pressure level an area error
    # is a constant too
    confounded = ("direction-asymmetry", "area-error")
    #: a fit's ``offset`` (``fcomp fit --offset``) is this effect's parameter
    fit_extra = "offset"
    of_measurement = True
    signature = "residual with a constant non-zero mean in both directions"
    experiment = "a zero reading of the force measurement at rest with nothing driving or " \
        "loading the actuator"
    experiments = {
        "pneumatic-cylinder": "a zero-force reading at rest with the chambers vented",
        "hydraulic-cylinder": "a zero-force reading at rest with the pump off and both "
                              "chambers relieved to tank",
        "friction-rig": "a zero reading of the load cell at rest with the drive disconnected",
        "electromechanical-axis": "a zero reading of the motor force with the drive disabled "
                                  "(current-sensor offset) and a level check of the axis (a "
                                  "tilt adds a constant m*g*sin(angle))",
    }

    def extra_force(self, be: Backend, sig: Signals, P: ParamValues) -> tuple[Any, Any]:
        return P("offset"), 0.0

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The mean training residual."""
        return [{"offset": float(np.mean(view.residual[view.train]))}]
