"""A built controller's margins over the grid, as coded (the Jacobians of its exported step).

:func:`controller_margins` linearises a controller at each grid point's operating
point (:class:`~controllers.loop_analysis.controller.StepLinearisation`) and
evaluates both break points there (:meth:`~controllers.loop_analysis.grid.PlantGrid.margins`);
:func:`refine` gives one point's margins with the crossings refined and the two
open loops as python-control systems (Bode, Nyquist). :class:`ControllerMargins`
holds the result: per point and break, the worst point, the mid-stroke nominal
point.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from controllers.loop_analysis.controller import LinearController, StepLinearisation
from controllers.loop_analysis.grid import PlantGrid, mid_point, nominal_points, worst_index
from controllers.loop_analysis.loop import (
    closed_loop_matrix,
    controller_response,
    dominant_pole,
    iosystems,
    unit_z,
)
from controllers.loop_analysis.margins import (
    LoopMargins,
    frequency_grid,
    loop_margins_from,
    refined_margins,
)

#: Frequencies of a refined (reported) loop.
REFINED_FREQUENCIES = 3000


@dataclass
class ControllerMargins:
    """A controller's margins over (part of) a grid.

    Attributes
    ----------
    name : str
        The controller's name.
    points : list of int
        The grid points analysed.
    arrays : dict
        ``{"valve": ..., "position": ...}``: per analysed point, the figures of
        :func:`~controllers.loop_analysis.margins.margins_of_responses`.
    linear : list of LinearController
        The controller linearised at each analysed point.
    """

    name: str
    points: list[int]
    arrays: dict[str, dict[str, np.ndarray]]
    linear: list[LinearController] = field(repr=False)
    #: Set by a rule that found no value of its gain meeting the requirement.
    structural: bool = False

    def worst(self) -> tuple[int, str]:
        """``(grid point, break)`` with the least margin."""
        i, brk = worst_index(self.arrays)
        return self.points[i], brk

    def at(self, point: int, brk: str) -> LoopMargins:
        """The (interpolated) margins at a grid point and break."""
        return loop_margins_from(self.arrays[brk], (self.points.index(point),))

    def linear_at(self, point: int) -> LinearController:
        return self.linear[self.points.index(point)]


def controller_margins(grid: PlantGrid, ctrl: Any, points: list[int] | None = None,
                       name: str | None = None) -> ControllerMargins:
    """The margins of the built controller ``ctrl`` at the grid's ``points`` (default all),
    linearised as coded (module docstring)."""
    from fcomp.parallel import one_blas_thread

    pts = list(range(len(grid))) if points is None else list(points)
    sub = grid.subset(pts)
    lin = StepLinearisation(ctrl)
    Y = np.array([grid.plants[i].measurement for i in pts])
    U = np.array([grid.plants[i].command for i in pts])
    with one_blas_thread():
        lcs = lin.at_many(Y, U)
        z = unit_z(sub.w, sub.dt)

        def controller(idx: np.ndarray) -> tuple[np.ndarray, ...]:
            A = np.stack([lcs[i].A for i in idx])
            B = np.stack([lcs[i].B for i in idx])
            C = np.stack([lcs[i].C for i in idx])
            D = np.stack([lcs[i].D for i in idx])
            return A, B, C, D, controller_response(A, B, C, D, z)

        arrays = sub.margins(controller)
    return ControllerMargins(name or getattr(ctrl, "name", "controller"), pts, arrays, lcs)


@dataclass(frozen=True)
class RefinedLoop:
    """One point's loop, refined for a report.

    Attributes
    ----------
    margins : dict of str to LoopMargins
        Per break, the margins with the crossings refined.
    systems : dict
        Per break, the open loop as a python-control state-space system.
    pole : complex
        The closed loop's largest pole (``z``).
    """

    margins: dict[str, LoopMargins]
    systems: dict[str, Any]
    pole: complex


def refine(grid: PlantGrid, point: int, lc: LinearController) -> RefinedLoop:
    """The loop at one grid point with the controller ``lc``: margins refined, systems."""
    lp = grid.plants[point]
    d, dt = grid.delay, grid.dt
    systems = iosystems(lp.Ad, lp.Bd, lp.C, lc.A, lc.B, lc.C, lc.D, d, dt)
    pole = complex(dominant_pole(closed_loop_matrix(lp.Ad, lp.Bd, lp.C, lc.A, lc.B, lc.C,
                                                    lc.D, d)))
    w = frequency_grid(dt, REFINED_FREQUENCIES)
    out = {}
    for brk, sys in systems.items():
        def response(x: np.ndarray, sys: Any = sys) -> np.ndarray:
            return np.asarray(sys(np.exp(1j * np.asarray(x) * dt)), dtype=complex).reshape(-1)

        out[brk] = refined_margins(response, w, pole, dt)
    return RefinedLoop(out, systems, pole)


def describe_worst(grid: PlantGrid, cm: ControllerMargins) -> str:
    """One phrase: the worst point, its break and what fails (or its margins)."""
    i, brk = cm.worst()
    m = cm.at(i, brk)
    where = "the valve command" if brk == "valve" else "the position sensor"
    return f"{m.shortfall() or m.describe()}, broken at {where}, at {grid.points[i].describe()}"


def growth_text(m: LoopMargins) -> str:
    """``'a 4.7 Hz mode growing 1.1/s'`` for an unstable loop, '' otherwise."""
    if m.stable:
        return ""
    return f"a {m.mode_hz:.3g} Hz mode growing {m.growth:.3g}/s"


__all__ = ["REFINED_FREQUENCIES", "ControllerMargins", "RefinedLoop", "controller_margins",
           "describe_worst", "growth_text", "mid_point", "nominal_points", "refine"]
