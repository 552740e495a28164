"""Advice a diagnosis gives that matches what the record already holds and the options that
exist.

The plausibility warnings of a fit (:mod:`fcomp.identification.plausibility`)
end with the experiment that would determine a parameter ("to determine it:
identical motions at two or more chamber pressure levels") and, for a mass the
record cannot weigh, the options to give it. A diagnosis knows more than a fit:
the record's design (:mod:`.design`) and the command it runs under. So

* an experiment the record already holds -- motions at two or more pressure
  levels when it has four, constant-speed runs at two or more speeds when it
  has them -- is not advised again: the warning says what the record holds, and
  names the experiment that separates the factors the design confounds with
  it, if any (:attr:`.design.Design.confounded`), else that the value is bent by
  what the model lacks (see the verdict);
* options a command does not have are not advised (``fcomp diagnose`` has no
  ``--mass``: the moving mass goes into the sidecar, ``rig.mass``).
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from fcomp.diagnosis.design import Design
from fcomp.effects import EFFECTS
from fcomp.identification.plausibility import FitWarning

_ADVICE = re.compile(r"; to determine (it|them): (.+)$")
#: Options the diagnosis does not have, as the fit's warnings name them, and what to say.
_NO_OPTION = ((" or --mass", ""), (", or --mass", ""))


def held_by(design: Design, effect: str) -> str | None:
    """What the record already holds of the experiment that isolates ``effect`` (words),
    or None when it does not hold it: two or more pressure levels for a law in the
    pressure, two or more speeds in each direction for a law in the speed."""
    factors = getattr(EFFECTS.get(effect), "factors", ())
    if "pressure" in factors and len(design.pressure_levels) >= 2:
        lv = sorted(design.pressure_levels)
        return (f"the record already holds identical motions at {len(lv)} pressure levels "
                f"({lv[0] / 1e5:.3g} to {lv[-1] / 1e5:.3g} bar)")
    if "speed" in factors and all(len(design.speed_levels(d)) >= 2 for d in design.speed):
        speeds = ", ".join(f"{d} {len(design.speed_levels(d))}" for d in design.speed)
        return f"the record already holds runs at several speeds in each direction ({speeds})"
    return None


def _separating(design: Design, effect: str) -> str | None:
    """The experiment separating a factor of ``effect`` from one the design confounds it
    with, or None."""
    factors = getattr(EFFECTS.get(effect), "factors", ())
    for c in design.confounded:
        if set(factors) & set(c.factors):
            return c.separates
    return None


def reword(warnings: Sequence[FitWarning], design: Design | None, kind: str
           ) -> list[FitWarning]:
    """``warnings`` with the advice matched to the record and to ``fcomp diagnose``'s options
    (module docstring)."""
    experiments = {}
    for name in EFFECTS.names():
        try:
            experiments[EFFECTS.get(name).experiment_for(kind)] = name
        except (KeyError, ValueError):
            continue
    out = []
    for w in warnings:
        message = w.message
        for old, new in _NO_OPTION:
            message = message.replace(old, new)
        m = _ADVICE.search(message) if design is not None else None
        if m is not None and design is not None:
            kept, said = [], []
            for exp in m.group(2).split("; or "):
                effect = experiments.get(exp.strip().rstrip("."))
                held = held_by(design, effect) if effect else None
                if held is None:
                    kept.append(exp)
                    continue
                sep = _separating(design, effect) if effect else None
                said.append(held)
                if sep is not None and sep not in kept:
                    kept.append(sep)
            if said:
                head = message[:m.start()]
                what = "; ".join(said)
                tail = (f"; to determine {m.group(1)}: {'; or '.join(kept)}" if kept else
                        "; the value is bent by what the model lacks, not by the record "
                        "(see the verdict)")
                message = f"{head} ({what}){tail}"
        out.append(FitWarning(w.code, w.parameter, message) if message != w.message else w)
    return out


__all__ = ["held_by", "reword"]
