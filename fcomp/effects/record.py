"""What an effect's diagnosis hooks read: the record, the current fit, and small estimates.

A diagnosis (:mod:`fcomp.diagnosis`) asks every registered effect the same
questions through the hooks of :class:`~fcomp.effects.Effect` (``guess``,
``unsuitable``, ``held``, ``diagnosis_forms``, ``diagnosis_config``). Their
argument is a :class:`RecordView`: a frozen, plain view of the record and of
the model fitted so far, built by the diagnosis from its own objects, so that
the effects layer needs nothing of the diagnosis (which sits above it).
:class:`DiagnosisForm` is one alternative form of an effect the diagnosis
refits side by side.

The estimates below are shared by the effects' guesses and by the fits
above them: a least-squares slope, the columns of a regression a record can
tell apart, the Stribeck hump (:func:`stribeck_start` starts the
identification, :func:`stribeck_hump_start` the diagnosis's baseline and its
``stribeck`` candidate), the chambers whose pressure a record holds constant
(:func:`constant_chambers`, for the laws in the pressures).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from fcomp.conditioning import Scales


@dataclass(frozen=True)
class RecordView:
    """The record and the current fit as an effect's diagnosis hooks see them (SI units).

    Every array has one entry per sample of the record (all experiments
    concatenated).

    Attributes
    ----------
    signals
        Signal name -> samples: ``t``, ``v``, ``a``, ``x``, ``p1``, ``p2``, ``s``
        (the side, +1/-1); read them with :meth:`signal`.
    y
        The measured (or reconstructed) friction force to match, N.
    F_hat
        The current model's prediction, N.
    residual
        ``y - F_hat``, N.
    train
        Boolean mask of the training samples (guesses read only these).
    params
        Flat parameter values of the current model (``Fc``, ``sigma0``, ...).
    values
        The current fit's values (``params`` plus ``mass`` where it is fitted).
    scales
        Magnitudes of the record (:class:`fcomp.conditioning.Scales`: force, speed,
        acceleration, stroke, resolution, pressure, ``dt``).
    v_rest
        Speed below which the record is at rest, m/s.
    d_pre
        Presliding length of the record (displacement to break away), m.
    t_dwell
        Shortest rest that counts as a dwell, s.
    dwell_starts
        ``(sample, dwell time)`` of every start after a rest of at least ``t_dwell``.
    fits_mass
        Whether the mass is fitted (driving-force data without a known mass).
    steady_state
        Whether the samples are independent steady-state points (no motion).
    available, reasons
        Signal name -> whether it is measured and informative; -> why not.
    source
        Where the force to match came from: ``"F"`` (a force column, a load cell
        on the friction), ``"reconstructed"`` (``p1*A1 - p2*A2 - m*a`` with the rig's
        mass) or ``"driving-force"`` (the same, the mass fitted); ``""`` unknown.
    force_channels
        The measured columns that force is made of: ``("F",)``, or those of
        ``p1``, ``p2``, ``F_ext`` (a driving force).
    """

    signals: Mapping[str, np.ndarray]
    y: np.ndarray
    F_hat: np.ndarray
    residual: np.ndarray
    train: np.ndarray
    params: Mapping[str, float]
    values: Mapping[str, float]
    scales: Scales
    v_rest: float
    d_pre: float
    t_dwell: float
    dwell_starts: tuple[tuple[int, float], ...] = ()
    fits_mass: bool = False
    steady_state: bool = False
    available: Mapping[str, bool] = field(default_factory=lambda: MappingProxyType({}))
    reasons: Mapping[str, str] = field(default_factory=lambda: MappingProxyType({}))
    source: str = ""
    force_channels: tuple[str, ...] = ()

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.y.size)

    def signal(self, name: str) -> np.ndarray:
        """A signal by name (``t``, ``v``, ``a``, ``x``, ``p1``, ``p2``, ``s``)."""
        return self.signals[name]

    @property
    def moving(self) -> np.ndarray:
        """Training samples faster than rest."""
        return self.train & (np.abs(self.signal("v")) > self.v_rest)

    @property
    def level(self) -> float:
        """Typical predicted friction while moving (median ``|F_hat|``), else the force scale."""
        m = self.moving
        return float(np.median(np.abs(self.F_hat[m]))) if m.any() else self.scales.force


@dataclass(frozen=True)
class DiagnosisForm:
    """One form of an effect that a diagnosis refits side by side with its others.

    Attributes
    ----------
    name
        The form's label (reported as the candidate's ``form``; passed to
        :meth:`~fcomp.effects.Effect.guess`); ``None`` for an effect with one form.
    config
        Configuration of the effect instance in this form (e.g. ``{"form": "speed-lag"}``).
    held
        Parameters this form holds at their no-op values (not refitted).
    """

    name: str | None = None
    config: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    held: tuple[str, ...] = ()

    @classmethod
    def each(cls, forms: tuple[str, ...]) -> tuple[DiagnosisForm, ...]:
        """One form per law of an effect's ``FORMS``, labelled and configured by its name."""
        return tuple(cls(f, {"form": f}) for f in forms)


# ------------------------------------------------------------------ estimates
def ls_slope(r: np.ndarray, col: np.ndarray) -> float:
    """Least-squares coefficient of ``r ~ c*col`` (0 for a zero column)."""
    den = float(col @ col)
    return float(col @ r) / den if den > 0 else 0.0


def distinct_columns(cols: np.ndarray, max_corr: float = 0.98) -> list[int]:
    """Indices of the columns kept in order, each dropped that is nearly a multiple of a
    combination of the kept ones (its residual after projection is below
    ``sqrt(1 - max_corr^2)`` of its norm)."""
    kept: list[int] = []
    for j in range(cols.shape[1]):
        c = cols[:, j]
        norm = float(np.linalg.norm(c))
        if norm == 0:
            continue
        if kept:
            basis = cols[:, kept]
            coef, *_ = np.linalg.lstsq(basis, c, rcond=None)
            if np.linalg.norm(c - basis @ coef) < np.sqrt(1 - max_corr**2) * norm:
                continue
        kept.append(j)
    return kept


def _speed_bins(speed: np.ndarray, level: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centres, medians of ``level`` and sample counts in 16 geometric speed bins
    (those with 3 samples)."""
    edges = np.geomspace(speed.min(), speed.max() * (1 + 1e-9), 16)
    idx = np.clip(np.digitize(speed, edges) - 1, 0, edges.size - 2)
    centres, medians, counts = [], [], []
    for b in range(edges.size - 1):
        sel = idx == b
        if sel.sum() >= 3:
            centres.append(math.sqrt(edges[b] * edges[b + 1]))
            medians.append(float(np.median(level[sel])))
            counts.append(float(sel.sum()))
    return np.array(centres), np.array(medians), np.array(counts)


def stribeck_start(v: np.ndarray, f: np.ndarray, Fc: float, B: float,
                   v_min: float) -> tuple[float, float]:
    """``(Fs, vs)`` from the low-speed hump of ``sign(v)*f - B*|v|`` (one direction's samples)."""
    speed = np.abs(v)
    m = speed >= v_min
    if m.sum() < 10:
        return 1.2 * Fc, max(v_min, 1e-6)
    speed = speed[m]
    c, mu, _ = _speed_bins(speed, np.sign(v[m]) * f[m] - B * speed)
    if not c.size:
        return 1.2 * Fc, max(v_min, 1e-6)
    k = int(np.argmax(mu))
    Fs = max(float(mu[k]), 1.05 * Fc)
    target = Fc + (Fs - Fc) / math.e
    after = np.nonzero((c > c[k]) & (mu <= target))[0]
    vs = float(c[after[0]]) if after.size else float(c[min(k + 1, c.size - 1)])
    return Fs, max(vs, v_min)


def stribeck_hump_start(v: np.ndarray, f: np.ndarray, Fc: float, B: float,
                        v_min: float) -> tuple[float, float]:
    """``(Fs, vs)`` of the low-speed hump of ``sign(v)*f``, fitted with its own slope (diagnosis).

    The level ``sign(v)*f`` is binned by speed (16 bins, geometric, medians) and
    ``a + b*exp(-(|v|/vs)^2) + k*|v|`` fitted to the bins for each bin centre as
    ``vs`` (linear least squares in ``a, b, k`` with ``b >= 0``, each bin weighted
    by the square root of its samples: the few samples passing through the low
    speeds during an acceleration must not outweigh thousands at a creep or a
    stroke speed); the ``vs`` with
    the least squared error is taken and ``Fs = Fc + b``. The slope ``k`` is free
    rather than the given ``B``: a viscous coefficient that differs between the
    directions, or a shear-thinning term, leaves a level that still rises with
    speed after ``B*|v|`` is taken off, and the largest bin would then be read as
    the hump (a ``vs`` at the top speed). Without a hump (``b = 0`` everywhere):
    :func:`stribeck_start`, which ``fcomp fit`` starts from.
    """
    speed = np.abs(v)
    m = speed >= v_min
    c, level, count = _speed_bins(speed[m], np.sign(v[m]) * f[m]) if m.sum() >= 10 else (
        np.zeros(0), np.zeros(0), np.zeros(0))
    w = np.sqrt(count)  # a bin's median is known to ~1/sqrt(its samples)
    best: tuple[float, float, float] | None = None  # (sse, b, vs)
    if c.size >= 4:
        for vs in c:
            A = np.column_stack([np.ones_like(c), np.exp(-((c / vs) ** 2)), c])
            coef, *_ = np.linalg.lstsq(A * w[:, None], level * w, rcond=None)
            if not coef[1] > 0:
                continue
            sse = float(np.sum((w * (A @ coef - level)) ** 2))
            if best is None or sse < best[0]:
                best = (sse, float(coef[1]), float(vs))
    if best is not None:
        return max(Fc + best[1], 1.05 * Fc), max(best[2], v_min)
    return stribeck_start(v, f, Fc, B, v_min)



# ------------------------------------------------------------------ chambers
#: A chamber pressure whose 1st-99th percentile range over the samples weighed is at most
#: this share of that of ``p1 + p2`` (or 1 kPa) is constant for the pressure laws: a vented
#: chamber (``p2 = 0`` gauge) or one held by a regulator.
CONSTANT_PRESSURE_SHARE = 0.02


def constant_chambers(view: RecordView, mask: np.ndarray | None = None) -> list[str]:
    """The chambers (``"p1"``, ``"p2"``) whose pressure is constant over ``mask`` (default
    the training samples): identically zero (vented, or no column: 0 gauge) or varying by
    at most :data:`CONSTANT_PRESSURE_SHARE` of the range of ``p1 + p2`` (at least 1 kPa).
    A law's coefficient of such a pressure is a constant force or level: the record cannot
    tell it from the friction level or a force offset."""
    m = view.train if mask is None else mask
    if not m.any():
        return ["p1", "p2"]
    p1, p2 = view.signal("p1")[m], view.signal("p2")[m]

    def span(p: np.ndarray) -> float:
        lo, hi = np.percentile(p, [1.0, 99.0])
        return float(hi - lo)

    tol = max(1000.0, CONSTANT_PRESSURE_SHARE * span(p1 + p2))
    return [n for n, p in (("p1", p1), ("p2", p2))
            if not np.any(p != p[0]) or span(p) <= tol]


__all__ = ["CONSTANT_PRESSURE_SHARE", "DiagnosisForm", "RecordView", "constant_chambers",
           "distinct_columns", "ls_slope", "stribeck_hump_start", "stribeck_start"]
