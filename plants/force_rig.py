"""Seed 001's force-driven rig (Fig. 3; models.md 3.5), default set ``seed000-cylinder1``.

A pneumatic cylinder with both chambers open to atmosphere (``p1 = p2 =
p_atm``, so ``F_cyl = 0``, seed 001 Eq. 3), its rod pushed by an external
force through a load cell. Input ``F_ext``: the external force on the rod
(N, positive extending). Equation of motion (models.md 3.5, 3.1)::

    m*dv/dt = F_ext - F - m*g*s + F_stop

States ``x, v`` plus the friction states. Seed 001's cylinders are 25 mm
bore like seed 000's cylinder 1, whose set is the default (geometry, mass
and friction); seed 001 rolled its horizontal rig by hand, mass given by
the set. Default initial state: mid-stroke, at rest, friction states zero.
"""

from __future__ import annotations

from typing import Any

from fcomp.backend import Backend
from fcomp.parameters import ParamValues, make_params_class
from fcomp.paramsets import ParameterSet
from plants.mechanics import PISTON_SPECS, Drive, PistonPlant, piston_values

ForceRigParams = make_params_class("ForceRigParams", PISTON_SPECS, owner="plant force-rig")


class ForceRig(PistonPlant):
    """Force-driven rig with open chambers (see the module docstring)."""

    name = "force-rig"
    default_params = "seed000-cylinder1"
    kind = "friction-rig"
    input_names = ("F_ext",)
    input_units = ("N",)
    Params = ForceRigParams
    output_names = ("x", "v", "a", "F", "F_ext")
    output_units = {"x": "m", "v": "m/s", "a": "m/s^2", "F": "N", "F_ext": "N"}

    @classmethod
    def params_from_set(cls, pset: ParameterSet | None) -> dict[str, Any]:
        return piston_values(pset)

    def drive(self, be: Backend, x: dict[str, Any], u: dict[str, Any],
              P: ParamValues) -> Drive:
        pa = P("p_atm")
        return Drive(u["F_ext"], pa, pa, extras={"F_ext": u["F_ext"]})
