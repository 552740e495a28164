"""Design the next experiment (``fcomp design``): when the record cannot tell, what to measure.

One concept per module: the rig file (:mod:`.rig`), the diagnosis's open questions
(:mod:`.questions`), the alternatives of untested effects (:mod:`.alternatives`), the motion
primitives (:mod:`.primitives`), the criteria (:mod:`.criteria`), the optimiser
(:mod:`.optimiser`), the programme files (:mod:`.programme`), the whole (:mod:`.design`).
"""

from fcomp.planning.design import DesignResult, design
from fcomp.planning.rig import TEMPLATE, Rig, read_rig

__all__ = ["TEMPLATE", "DesignResult", "Rig", "design", "read_rig"]
