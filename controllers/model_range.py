"""Whether a friction model runs where it was fitted, and whether the plant can move it.

A model fitted on one record describes the seal over that record's positions,
speeds and pressures. A closed loop on another plant file runs it wherever its
tasks go: a ``position-dependence`` fitted on a 25 mm O-ring record over
``x`` in [-37, 2.7] mm is a cubic in ``x`` that, at 150 mm on a 300 mm
axis, multiplies the friction by some 200 (5 N becomes 1 kN). Whatever a
comparison then finds is a property of the extrapolated polynomial, not of the
seal.

:func:`range_warnings` says so, in two checks:

* **outside the fitted window**: a model whose effects are configured for a
  position window (``x_min``, ``x_max``: the record's range the diagnosis
  gave ``position-dependence``) and the tasks' positions outside it, with the
  steady friction level there against its largest inside;
* **friction beyond the force**: a true friction whose steady level at the
  tasks' positions and speeds reaches :data:`FORCE_SHARE` of the force the
  actuator has left after holding its load -- a plant that can hardly move.

Model files that carry the ranges they were fitted on (speed, pressure)
can add their own windows here: a check reads only :func:`position_window`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fcomp.models import FrictionModel

#: Share of the actuator's free force (after the load) a friction level may take.
FORCE_SHARE = 0.5
#: Speeds (m/s) the steady levels are evaluated at (beside the tasks' largest).
SPEEDS = (1e-3, 1e-2)


@dataclass(frozen=True)
class Span:
    """Where the tasks take the piston: positions ``[x_lo, x_hi]`` (m, absolute) and the
    largest reference speed ``v_max`` (m/s); the chambers' gauge pressures ``p`` (Pa) at
    which pressure-dependent levels are evaluated."""

    x_lo: float
    x_hi: float
    v_max: float
    p: float = 0.0


def position_window(model: FrictionModel) -> tuple[float, float] | None:
    """The position window (m) the model's effects were configured for (``x_min``,
    ``x_max`` of their configuration: the record's range), or ``None``."""
    lo, hi = math.inf, -math.inf
    for e in model.effects:
        cfg = e.config
        if "x_min" in cfg and "x_max" in cfg:
            lo, hi = min(lo, float(cfg["x_min"])), max(hi, float(cfg["x_max"]))
    return (lo, hi) if lo < hi else None


def steady_level(model: FrictionModel, x: np.ndarray, speeds: np.ndarray, p: float) -> float:
    """The largest ``|F_ss|`` (N) of ``model`` over positions ``x`` and speeds ``+-speeds``."""
    xs, vs = np.meshgrid(np.asarray(x, dtype=float), np.asarray(speeds, dtype=float))
    level = 0.0
    for sign in (1.0, -1.0):
        F = model.steady_state(sign * vs.ravel(), x=xs.ravel(), p1=p, p2=p)
        level = max(level, float(np.nanmax(np.abs(F))))
    return level


def range_warnings(label: str, model: FrictionModel, span: Span, *, truth: bool,
                   free_force: float | None = None) -> list[tuple[str, str]]:
    """``(code, message)`` of the checks of the module docstring for the model ``label``:
    ``outside-fitted-range`` (any model), ``friction-beyond-force`` (a truth, given the
    actuator's ``free_force`` in N)."""
    out: list[tuple[str, str]] = []
    speeds = np.array(sorted({*SPEEDS, max(span.v_max, SPEEDS[0])}))
    xs = np.linspace(span.x_lo, span.x_hi, 9)
    window = position_window(model)
    if window is not None and (span.x_lo < window[0] or span.x_hi > window[1]):
        inside = steady_level(model, np.linspace(*window, 9), speeds, span.p)
        there = steady_level(model, xs, speeds, span.p)
        role = "as the plant's friction" if truth else "as a controller's model"
        out.append(("outside-fitted-range",
                    f"{label} ({model.describe()}, {role}) runs at x = "
                    f"{span.x_lo * 1e3:.4g}..{span.x_hi * 1e3:.4g} mm, outside the "
                    f"{window[0] * 1e3:.4g}..{window[1] * 1e3:.4g} mm its position effect "
                    f"was fitted on: its friction there reaches {there:.4g} N against "
                    f"{inside:.4g} N inside (x{there / max(inside, 1e-12):.3g}); the "
                    "results describe the extrapolated model, not your seal"))
    if truth and free_force is not None and free_force > 0:
        level = steady_level(model, xs, speeds, span.p)
        if level >= FORCE_SHARE * free_force:
            out.append(("friction-beyond-force",
                        f"{label} ({model.describe()}) as the plant's friction reaches "
                        f"{level:.4g} N where the tasks run, {level / free_force * 100:.0f} % "
                        f"of the {free_force:.4g} N the actuator has left after holding "
                        "its load: the plant can hardly move"))
    return out


__all__ = ["FORCE_SHARE", "Span", "position_window", "range_warnings", "steady_level"]
