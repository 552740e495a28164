"""The margins ``fcomp plant check`` reports: the tuned loop over the grid, and each controller.

:func:`analyse` takes a controller model and its tuning
(:class:`controllers.tuning.Tuning`) and gives a :class:`LoopSummary`:

* the PID family's loop with the tuning at *every* grid point, both breaks
  (:mod:`controllers.loop_analysis.pid_family`, the Jacobian of the exported step
  written out; :func:`controllers.loop_analysis.design.ratios`);
* that loop at mid stroke (nominal, sliding) and at its worst point refined
  (:func:`controllers.loop_analysis.analysis.refine`: crossings by bisection, the
  open loops as python-control systems for Bode and Nyquist plots);
* every force-based controller as coded (Jacobians of its exported step,
  :func:`controllers.loop_analysis.analysis.controller_margins`): ``pid`` and
  ``pid-ff`` over the whole grid (at rest the feedforward is zero: the same loop),
  ``lugre-observer`` and ``ekf`` where the piston rests in pre-sliding (where their
  friction models are linear at rest, as the plant's seal is; sliding, their bristle
  saturates and their estimate follows the steady-state map) -- the EKF at nominal
  parameters along the stroke (its covariance's Riccati recursion per point makes it
  the slowest to linearise).

:meth:`LoopSummary.as_dict` is the ``"margins"`` field of ``plant check --json``:
``gain``, ``phase_deg`` (the smallest over the grid and both breaks), ``ms`` (the
largest), ``worst`` (the point with the least margin: where, which parameters,
which friction regime, which break, its margins), ``mid``, ``requirement``,
``meets``, ``grid`` (every point), ``controllers``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from controllers.loop_analysis.analysis import (
    ControllerMargins,
    RefinedLoop,
    controller_margins,
    mid_point,
    nominal_points,
    refine,
)
from controllers.loop_analysis.design import ratios
from controllers.loop_analysis.grid import PlantGrid, worst_index
from controllers.loop_analysis.margins import (
    MAX_SENSITIVITY,
    MIN_GAIN_MARGIN,
    MIN_PHASE_MARGIN,
    LoopMargins,
    loop_margins_from,
)
from controllers.loop_analysis.pid_family import pid_family_ss

#: Where each controller is analysed (module docstring).
CONTROLLER_POINTS = {"pid": "all", "pid-ff": "all", "lugre-observer": "resting",
                     "ekf": "resting, nominal"}


@dataclass
class LoopSummary:
    """The loop analysis of a tuned plant (module docstring)."""

    grid: PlantGrid
    arrays: dict[str, dict[str, np.ndarray]]
    worst: int
    worst_break: str
    mid: int
    refined: dict[str, RefinedLoop]
    controllers: dict[str, ControllerMargins] = field(default_factory=dict)
    failed: dict[str, str] = field(default_factory=dict)

    def margins_at(self, point: int, brk: str) -> LoopMargins:
        return loop_margins_from(self.arrays[brk], (point,))

    @property
    def meets(self) -> bool:
        return all(self.margins_at(i, b).shortfall() is None
                   for i in range(len(self.grid)) for b in self.arrays)

    def extremes(self) -> tuple[float, float, float]:
        """The smallest gain and phase margins and the largest Ms over the grid, both
        breaks."""
        gm = min(float(np.min(a["gain"])) for a in self.arrays.values())
        pm = min(float(np.min(a["phase"])) for a in self.arrays.values())
        ms = max(float(np.max(a["ms"])) for a in self.arrays.values())
        return gm, pm, ms

    def as_dict(self) -> dict[str, Any]:
        """The ``"margins"`` field (module docstring); infinities as ``null``."""
        def num(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        def point(i: int, brk: str | None = None) -> dict[str, Any]:
            d = self.grid.points[i].as_dict()
            if brk is not None:
                d["break"] = brk
                d.update(_short(self.margins_at(i, brk)))
            return d

        gm, pm, ms = self.extremes()
        refined = self.refined
        return {
            "gain": num(gm), "phase_deg": num(pm), "ms": num(ms),
            "worst": {**point(self.worst, self.worst_break),
                      "refined": refined["worst"].margins[self.worst_break].as_dict(),
                      "why": self.margins_at(self.worst, self.worst_break).shortfall()},
            "mid": {"point": point(self.mid),
                    **{b: m.as_dict() for b, m in refined["mid"].margins.items()}},
            "requirement": {"gain": MIN_GAIN_MARGIN, "phase_deg": MIN_PHASE_MARGIN,
                            "ms": MAX_SENSITIVITY},
            "meets": self.meets,
            "breaks": list(self.arrays),
            "delay": self.grid.delay, "control_rate": 1.0 / self.grid.dt,
            "grid": [{**point(i), **{b: _short(self.margins_at(i, b)) for b in self.arrays}}
                     for i in range(len(self.grid))],
            "controllers": {name: _controller_dict(self.grid, cm)
                            for name, cm in self.controllers.items()},
            "controllers_failed": dict(self.failed),
        }


def _short(m: LoopMargins) -> dict[str, Any]:
    def num(v: float) -> float | None:
        return float(v) if math.isfinite(v) else None

    return {"gain": num(m.gain), "phase_deg": num(m.phase), "ms": num(m.ms),
            "stable": m.stable, "growth": num(m.growth), "mode_hz": num(m.mode_hz)}


def _controller_dict(grid: PlantGrid, cm: ControllerMargins) -> dict[str, Any]:
    i, brk = cm.worst()
    m = cm.at(i, brk)
    mid = mid_point(grid)
    out = {"points": len(cm.points), "where": CONTROLLER_POINTS.get(cm.name, "all"),
           "worst": {**grid.points[i].as_dict(), "break": brk, **_short(m),
                     "why": m.shortfall()}}
    if mid in cm.points:
        out["mid"] = {b: _short(cm.at(mid, b)) for b in cm.arrays}
    return out


def _points(grid: PlantGrid, where: str) -> list[int]:
    if where == "resting":
        return [i for i in range(len(grid)) if grid.points[i].presliding is not None]
    if where == "resting, nominal":
        return [i for i in nominal_points(grid) if grid.points[i].presliding == 1.0]
    return list(range(len(grid)))


def analyse(model: Any, tuning: Any, controllers: tuple[str, ...] = ("pid", "pid-ff",
                                                                     "lugre-observer", "ekf")
            ) -> LoopSummary:
    """The loop analysis of ``model`` with ``tuning`` (module docstring); a controller that
    cannot be built on the model (the LuGre observer without a bristle state) is listed in
    :attr:`LoopSummary.failed` with its reason."""
    from controllers import make_controller
    from controllers.loop_analysis.controller import LinearController
    from controllers.tuning import model_grid
    from fcomp.errors import FcompError

    grid = model_grid(model)
    fam = tuning.family()
    _r, arrays = ratios(grid, fam)
    worst, brk = worst_index(arrays)
    mid = mid_point(grid)
    s, Jy, Jv = grid.slopes
    refined = {}
    for label, i in (("mid", mid), ("worst", worst)):
        A, B, C, D = pid_family_ss(fam, s[i:i + 1], Jy[i:i + 1], Jv[i:i + 1], *grid.areas,
                                   grid.dt)
        lp = grid.plants[i]
        lc = LinearController(A=A[0], B=B[0], C=C[0], D=D[0], states=("I", "v_f", "x_prev"),
                              dt=grid.dt, state=np.zeros(3), measurement=lp.measurement,
                              command=lp.command)
        refined[label] = refine(grid, i, lc)
    out = LoopSummary(grid, arrays, worst, brk, mid, refined)
    model.use_tuning(tuning)
    for name in controllers:
        try:
            ctrl = make_controller(name, model)
            out.controllers[name] = controller_margins(grid, ctrl,
                                                       _points(grid, CONTROLLER_POINTS[name]),
                                                       name=name)
        except FcompError as exc:
            out.failed[name] = str(exc).splitlines()[0]
    return out


__all__ = ["CONTROLLER_POINTS", "LoopSummary", "analyse"]
