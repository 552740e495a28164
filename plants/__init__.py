"""Plant models, registered by name (models.md section 3)."""

from __future__ import annotations

from fcomp.models.base import FrictionModel
from fcomp.paramsets import ParameterSet
from fcomp.registry import Registry
from plants.base import OdePlant, Plant
from plants.force_rig import ForceRig
from plants.hydraulic import HydraulicPlant
from plants.motion import MotionPlant
from plants.pneumatic import PneumaticPlant
from plants.presliding_rig import PreslidingRig

PLANTS: Registry[type[Plant]] = Registry("plant")
for _cls in (MotionPlant, HydraulicPlant, PneumaticPlant, PreslidingRig, ForceRig):
    PLANTS.register(_cls.name, _cls)


def make_plant(name: str, friction: FrictionModel, params: str | ParameterSet | None = None) -> Plant:
    """A plant by name with a friction model and a parameter set (name or object)."""
    return PLANTS.get(name)(friction, params)


__all__ = ["PLANTS", "OdePlant", "Plant", "make_plant"]
