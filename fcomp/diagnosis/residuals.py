"""Where a model's force error lies: per regime, and the worst windows.

:func:`regime_errors` gives the RMS error (N) of a residual over a mask (the
held-out samples) within each regime of :mod:`.regimes`; :func:`worst_segments`
finds the windows where the model fails most. Both are used by the loop
(:mod:`.loop`), the comparison of one model (:mod:`.compare`) and the figures
(:mod:`.report`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fcomp.diagnosis.regimes import REGIMES, Segmentation


def regime_errors(residual: np.ndarray, seg: Segmentation, mask: np.ndarray
                  ) -> dict[str, dict[str, float | int | None]]:
    """Per regime and ``"all"``: RMS of ``residual`` (N) over ``mask`` and the sample count."""
    out: dict[str, dict[str, float | int | None]] = {}
    for i, name in enumerate(REGIMES):
        sel = mask & (seg.regime == i)
        n = int(sel.sum())
        out[name] = {"rms": float(np.sqrt(np.mean(residual[sel] ** 2))) if n else None, "n": n}
    n = int(mask.sum())
    out["all"] = {"rms": float(np.sqrt(np.mean(residual[mask] ** 2))) if n else None, "n": n}
    return out


@dataclass(frozen=True)
class Segment:
    """A window of samples ``[start, stop)`` and its RMS error (N)."""

    start: int
    stop: int
    rms: float


def worst_segments(residual: np.ndarray, mask: np.ndarray, width: int, count: int = 3,
                   boundaries: Sequence[int] = ()) -> list[Segment]:
    """The ``count`` non-overlapping windows of ``width`` samples with the largest RMS.

    Only windows lying entirely in ``mask`` (e.g. the held-out samples) and not
    crossing an experiment boundary are considered.
    """
    n = residual.size
    width = max(1, min(width, n))
    sq = np.where(mask, residual**2, 0.0)
    c = np.concatenate([[0.0], np.cumsum(sq)])
    cm = np.concatenate([[0], np.cumsum(mask.astype(int))])
    starts = np.arange(0, n - width + 1)
    full = (cm[starts + width] - cm[starts]) == width
    for b in boundaries:
        full &= ~((starts < b) & (starts + width > b))
    score = np.where(full, (c[starts + width] - c[starts]) / width, -1.0)
    out: list[Segment] = []
    taken = np.zeros(n, dtype=bool)
    for k in np.argsort(-score):
        if score[k] < 0 or len(out) >= count:
            break
        if taken[k:k + width].any():
            continue
        taken[k:k + width] = True
        out.append(Segment(int(k), int(k + width), float(math.sqrt(score[k]))))
    return out
