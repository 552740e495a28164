"""Plant models, registered by name (models.md section 3)."""

from __future__ import annotations

from fcomp.models.base import FrictionModel
from fcomp.paramsets import ParameterSet
from fcomp.registry import Registry
from plants.base import Plant
from plants.motion import MotionPlant

PLANTS: Registry[type[Plant]] = Registry("plant")
PLANTS.register("motion", MotionPlant)


def make_plant(name: str, friction: FrictionModel, params: str | ParameterSet | None = None) -> Plant:
    """A plant by name with a friction model and a parameter set (name or object)."""
    return PLANTS.get(name)(friction, params)


__all__ = ["PLANTS", "Plant", "make_plant"]
