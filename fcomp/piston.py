"""Piston geometry: the areas and chamber volumes of a single-rod cylinder, written once.

For a bore ``D`` and a rod ``d`` (m)::

    A1 = pi/4*D^2                (cap side)
    A2 = pi/4*(D^2 - d^2)        (rod side, the annulus)

and at piston position ``x`` (m from the cap end, stroke ``L``) with dead
volumes ``V10``, ``V20`` (m^3, tubing included)::

    V1 = V10 + A1*x,    V2 = V20 + A2*(L - x)

(models.md 3.1-3.3; seed 000 Eq. 1 and seed 002 Eqs. 1-4 use the same).
Pure arithmetic: the arguments may be floats, numpy arrays or CasADi
symbols, so the plants' symbolic equations, the reconstruction of friction
from measured pressures, the controllers' force limits and the studies all
read the geometry from here.
"""

from __future__ import annotations

import math
from typing import Any


def piston_areas(bore: Any, rod: Any = 0.0) -> tuple[Any, Any]:
    """Piston areas ``(A1, A2)`` (m^2) of a bore ``D`` and a rod ``d`` (m; module docstring)."""
    return math.pi / 4 * bore * bore, math.pi / 4 * (bore * bore - rod * rod)


def chamber_volumes(x: Any, stroke: Any, V10: Any, V20: Any, A1: Any, A2: Any
                    ) -> tuple[Any, Any]:
    """Chamber volumes ``(V1, V2)`` (m^3) at piston position ``x`` (module docstring)."""
    return V10 + A1 * x, V20 + A2 * (stroke - x)
