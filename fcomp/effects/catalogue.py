"""The effect catalogue of models.md section 1.8: one module per effect, registered here.

Each effect is one module of :mod:`fcomp.effects` holding its law, its
diagnosis hints and its experiment wording; its class docstring is the
effect's physical explanation (what it is and what it leaves in the residual
of a model that lacks it). Defaults are no-ops: adding an effect with default
parameters does not change the force. The structural ones (terms of the
LuGre family) derive from :class:`~fcomp.effects.structural.StructuralEffect`.
A user's effect is registered with :func:`~fcomp.effects.register_effect`
instead.
"""

from __future__ import annotations

from fcomp.effects.area_error import AreaError
from fcomp.effects.base import EFFECTS, Effect
from fcomp.effects.direction_asymmetry import DirectionAsymmetry
from fcomp.effects.dwell_time import DwellTime
from fcomp.effects.force_offset import ForceOffset
from fcomp.effects.frictional_lag import FrictionalLag
from fcomp.effects.inertia_error import InertiaError
from fcomp.effects.nonlocal_memory import NonlocalMemory
from fcomp.effects.position_dependence import PositionDependence
from fcomp.effects.presliding import Presliding
from fcomp.effects.pressure_dependence import PressureDependence
from fcomp.effects.stribeck import Stribeck
from fcomp.effects.viscous import Viscous
from fcomp.effects.viscous_lead import ViscousLead

#: The catalogue's effect classes, in the order of models.md 1.8.
CATALOGUE: tuple[type[Effect], ...] = (
    Viscous, Stribeck, Presliding, FrictionalLag, DwellTime, DirectionAsymmetry,
    PressureDependence, PositionDependence, ViscousLead, InertiaError, ForceOffset,
    AreaError, NonlocalMemory,
)
for _cls in CATALOGUE:
    EFFECTS.register(_cls.name, _cls)
