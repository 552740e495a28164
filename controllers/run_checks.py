"""Whether a closed-loop run can be ranked: runs whose error is beyond what the task allows.

A comparison of compensators ranks runs by their errors. Some runs have errors
that say nothing about the compensator's quality but only that the loop did
not do the task at all; ranking them (or dividing by them) makes a ratio of
noise. :func:`run_flags` names such a run's faults from its metrics
(:mod:`controllers.metrics`), and :func:`run_status` turns them into the
run's status, ``"flagged: ..."``: reported with its errors, never ranked.

==================== ===========================================================
fault                 rule (``T`` = the reference's travel, ``max r - min r``)
==================== ===========================================================
never moved           the piston travelled less than :data:`MOVED_SHARE` of ``T``
                      (a step the loop never took: its error is the task itself)
saturated             the valve command sat at its limit in at least
                      :data:`SATURATED_SHARE` of the samples (the loop was not
                      in control: the valve was)
limit cycle           a hunting amplitude (half peak-to-peak of the error at the
                      holds and on the ramp's steady part) of at least
                      :data:`CYCLE_SHARE` of ``T`` (a quarter): the loop never
                      settles where the task holds still
solver failed         the controller's fallback law ran in more than
                      :data:`FALLBACK_SHARE` of the steps (an MPC whose
                      problem could not be solved)
lost                  a maximum error beyond the reference's whole travel
                      ``T`` (the loop went elsewhere)
==================== ===========================================================

A task that does not move (``T = 0``, a user's hold) is judged by the
solver's failures and the saturation alone. The shares are set where a
working loop is far away: the compensators of this package on the built-in
plants travel within a few percent of ``T``, hunt below a few percent of it
and never saturate for long.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

#: The least travel (share of the reference's) of a piston that moved.
MOVED_SHARE = 0.1
#: The share of samples at the valve limit that counts as saturated throughout.
SATURATED_SHARE = 0.9
#: The hunting amplitude (share of the reference's travel) that is a limit cycle: a quarter
#: of the travel (+-500 um on a 2 mm step); the stick-slip a compensator should remove on
#: the low-velocity ramp (+-350 um of its 2.7 mm with a plain PID on a stiff seal) is
#: ranked, not flagged.
CYCLE_SHARE = 0.25
#: The share of fallback steps that counts as a failed solver.
FALLBACK_SHARE = 0.1


def _num(value: Any) -> float:
    return float(value) if isinstance(value, int | float) and math.isfinite(value) else math.nan


def run_flags(metrics: Mapping[str, Any]) -> list[str]:
    """The faults of a run (module docstring) from its metrics
    (:meth:`controllers.metrics.Metrics.as_dict`), in words with their numbers; empty for
    a run to rank."""
    flags: list[str] = []
    span = _num(metrics.get("reference_travel"))
    travel = _num(metrics.get("travel"))
    moves = span > 0
    if moves and travel < MOVED_SHARE * span:
        flags.append(f"never moved: the piston travelled {travel * 1e6:.3g} um of the "
                     f"reference's {span * 1e6:.3g} um")
    sat = _num(metrics.get("saturated_share"))
    if sat >= SATURATED_SHARE:
        flags.append(f"saturated throughout: the valve command sat at its limit in "
                     f"{sat * 100:.0f} % of the samples")
    hunt = _num(metrics.get("hunting_amplitude"))
    if moves and hunt >= CYCLE_SHARE * span:
        flags.append(f"limit cycle: +-{hunt * 1e6:.3g} um where the task holds still "
                     f"({hunt / span * 100:.0f} % of its {span * 1e6:.3g} um travel)")
    steps = _num(metrics.get("steps"))
    fallbacks = _num(metrics.get("fallbacks"))
    if steps > 0 and fallbacks > FALLBACK_SHARE * steps:
        flags.append(f"solver failed: the fallback law ran in {fallbacks / steps * 100:.0f} % "
                     "of the steps")
    worst = _num(metrics.get("max_error"))
    if moves and worst > span and not any(f.startswith("never moved") for f in flags):
        flags.append(f"lost the reference: max error {worst * 1e6:.3g} um, beyond the task's "
                     f"whole travel {span * 1e6:.3g} um")
    return flags


def run_status(status: str, metrics: Mapping[str, Any] | None) -> str:
    """A run's status for ranking: ``"ok"``; ``"flagged: <faults>"`` for a run that ran but
    did not do the task (:func:`run_flags`); a failure's status as it is."""
    if status != "ok" or metrics is None:
        return status
    flags = run_flags(metrics)
    return "flagged: " + "; ".join(flags) if flags else "ok"


__all__ = ["CYCLE_SHARE", "FALLBACK_SHARE", "MOVED_SHARE", "SATURATED_SHARE", "run_flags",
           "run_status"]
