"""The alternative an untested effect is designed against: the final model with the effect
at a size worth finding.

The effect's parameters start at their absence (the registry's defaults); the first one
(the effect's leading term) whose change moves the force over the candidate primitives is set so that the largest force
change is :data:`RELEVANT` of the model's friction level (at least :data:`FLOORS` noise
floors), kept inside its bounds. A generic rule, no magnitude per effect.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fcomp.models.base import FrictionModel
from fcomp.planning.criteria import force

#: The size worth finding: this fraction of the friction level ...
RELEVANT = 0.1
#: ... and at least this many noise floors.
FLOORS = 2.0


def alternative(model: FrictionModel, effect: str, probes: Sequence[dict[str, np.ndarray]],
                base: Sequence[np.ndarray], sigma: float, p_ref: float | None = None
                ) -> tuple[FrictionModel, str] | None:
    """``model`` with ``effect`` at a size worth finding, and that size in words (None when
    no parameter of it moves the force along the probes)."""
    from fcomp.effects import make_effect

    eff = make_effect(effect)
    ref = {k: p_ref for k in ("p_ref",) if k in eff.params.flat() and p_ref is not None}
    if ref:  # the effect is absent at the pressure the record was taken at
        eff = eff.with_params(**ref)
    level = max(float(np.max(np.abs(f))) for f in base) if base else 1.0
    want = max(RELEVANT * level, FLOORS * sigma)
    best: tuple[float, str, float] | None = None
    fixed = set(getattr(eff, "fixed", ()))
    for name, value in eff.params.flat().items():
        if name in fixed or not np.isfinite(value):
            continue
        spec = eff.params.spec_of(name)
        lo, hi = spec.lower, spec.upper
        span = hi - lo if np.isfinite(hi - lo) else max(abs(value), 1.0)
        trial = value + 1e-2 * span
        if trial > hi:
            trial = value - 1e-2 * span
        try:
            m = model.with_effects(eff.with_params(**{name: trial}))
        except (ValueError, TypeError):
            continue
        dmax = max(float(np.max(np.abs(force(m, s) - b))) for s, b in zip(probes, base, strict=False))
        if dmax > 1e-9 * max(level, 1.0):  # the effect's leading term: its first parameter
            best = (dmax, name, trial - value)  # that moves the force
            break
    if best is None:
        return None
    dmax, name, delta = best
    value = float(eff.params.flat()[name]) + delta * want / dmax
    spec = eff.params.spec_of(name)
    value = float(np.clip(value, spec.lower, spec.upper))
    return (model.with_effects(eff.with_params(**{name: value})),
            f"{name} = {value:.4g} (a force change of about {want:.3g} N)")
