"""Plant models, registered by name (models.md section 3).

Importing the package fills fcomp's registries (:mod:`fcomp.registry`, entry
point ``fcomp.plants``): the plant classes in :data:`PLANTS`, and in
``PLANT_TOOLS`` the plant-domain comparison and the plant-file reader that
``fcomp.compare`` and the command line use.
"""

from __future__ import annotations

from fcomp import registry
from fcomp.models.base import FrictionModel
from fcomp.paramsets import ParameterSet
from fcomp.registry import Registry
from plants.base import OdePlant, Plant
from plants.comparison import PlantComparison, compare_plant
from plants.force_rig import ForceRig
from plants.hydraulic import HydraulicPlant
from plants.motion import MotionPlant
from plants.planfile import read_plant_file
from plants.pneumatic import PneumaticPlant
from plants.presliding_rig import PreslidingRig

PLANTS: Registry[type[Plant]] = registry.PLANTS
for _cls in (MotionPlant, HydraulicPlant, PneumaticPlant, PreslidingRig, ForceRig):
    PLANTS.register(_cls.name, _cls)
for _tool in (compare_plant, PlantComparison, read_plant_file):
    registry.PLANT_TOOLS.register(_tool.__name__, _tool)


def make_plant(name: str, friction: FrictionModel, params: str | ParameterSet | None = None) -> Plant:
    """A plant by name with a friction model and a parameter set (name or object)."""
    return PLANTS.get(name)(friction, params)


__all__ = ["PLANTS", "OdePlant", "Plant", "make_plant"]
