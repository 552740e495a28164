"""Gain margin, phase margin and peak sensitivity of sampled loops, many at once.

A loop transfer function ``L(z)`` broken at one point of the loop (the valve
command, the position sensor: :mod:`controllers.loop_analysis.loop`), closed by
unity negative feedback ``1 + L = 0``, is judged by (Franklin, Powell &
Emami-Naeini, *Feedback Control of Dynamic Systems*, 7th ed., 2015, sec. 6.4;
Skogestad & Postlethwaite, *Multivariable Feedback Control*, 2nd ed., 2005,
sec. 2.4.3)

* the **gain margin**: the closed loop with ``k*L`` changes stability where
  ``k*L(e^{jwT})`` passes through ``-1``, i.e. at the phase crossovers ``w_pc``
  (``L`` real and negative) for ``k = -1/L(e^{j w_pc T})``; ``gain_up`` is the
  smallest such ``k > 1``, ``gain_down`` the largest ``k < 1`` (a conditionally
  stable loop: an integral action on an integrating plant has one at low
  frequency), and ``gain = min(gain_up, 1/gain_down)``;
* the **phase margin**: at every gain crossover (``|L| = 1``) the angle between
  ``L`` and ``-1``, ``180 - |arg L|`` deg (a lag or a lead of that much puts
  ``L`` on ``-1``), the smallest over the crossovers;
* the **peak sensitivity** ``Ms = max_w |1/(1 + L)| = 1/min_w |1 + L|``, the
  inverse of the Nyquist curve's distance to ``-1``;

all valid for a closed loop that is stable (:attr:`LoopMargins.radius` ``< 1``,
from its eigenvalues); an unstable one has none (``gain = phase = 0``,
``ms = inf``). The requirement of the derived tuning (:mod:`controllers.tuning`)
is ``gain >= 2`` (6 dB), ``phase >= 30`` deg and ``ms <= 2``.

The responses are evaluated on a logarithmic frequency grid from 0.1 rad/s to
the Nyquist frequency ``pi/T`` (where ``L`` of a real system is real, so a
phase crossover there counts), the crossings interpolated linearly between grid
points (:func:`margins_of_responses`, vectorised over any leading axes), and
refined by bisection on the exact response where one loop is reported
(:func:`refined_margins`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

#: The requirement: gain margin (factor, 6 dB), phase margin (deg), peak sensitivity.
MIN_GAIN_MARGIN = 2.0
MIN_PHASE_MARGIN = 30.0
MAX_SENSITIVITY = 2.0
#: Points of the frequency grid (logarithmic, 0.1 rad/s to pi/T).
N_FREQUENCIES = 800
#: Lowest frequency of the grid (rad/s).
LOW_FREQUENCY = 0.1


def frequency_grid(dt: float, n: int = N_FREQUENCIES, low: float = LOW_FREQUENCY) -> np.ndarray:
    """``n`` frequencies (rad/s), logarithmic from ``low`` to the Nyquist frequency ``pi/dt``
    (included)."""
    return np.logspace(math.log10(low), math.log10(math.pi / dt), n)


@dataclass(frozen=True)
class LoopMargins:
    """The margins of one loop broken at one point (module docstring).

    Attributes
    ----------
    gain : float
        ``min(gain_up, 1/gain_down)`` (``inf`` without phase crossover; 0 if unstable).
    gain_up, gain_down : float
        The factors on ``L`` at which the closed loop first changes stability, up
        (``> 1``, ``inf`` if none) and down (``< 1``, 0 if none).
    phase : float
        Phase margin (deg; ``inf`` without gain crossover; 0 if unstable).
    ms : float
        Peak sensitivity ``max |1/(1 + L)|`` (``inf`` if unstable).
    phase_crossover : float
        Frequency (rad/s) of the gain margin's crossing.
    gain_crossover : float
        Frequency (rad/s) of the phase margin's crossing.
    ms_frequency : float
        Frequency (rad/s) of the peak sensitivity.
    radius : float
        Largest closed-loop pole magnitude ``max |z|`` (stable below 1).
    growth : float
        That pole's growth rate ``ln|z|/T`` (1/s; negative: it decays).
    mode_hz : float
        That pole's frequency ``|arg z|/(2 pi T)`` (Hz).
    """

    gain: float
    gain_up: float
    gain_down: float
    phase: float
    ms: float
    phase_crossover: float
    gain_crossover: float
    ms_frequency: float
    radius: float
    growth: float = math.nan
    mode_hz: float = math.nan

    @property
    def stable(self) -> bool:
        return bool(self.radius < 1.0)

    @property
    def gain_db(self) -> float:
        return 20 * math.log10(self.gain) if self.gain > 0 else -math.inf

    def shortfall(self, min_gain: float = MIN_GAIN_MARGIN, min_phase: float = MIN_PHASE_MARGIN,
                  max_ms: float = MAX_SENSITIVITY) -> str | None:
        """What is insufficient (one phrase), or None."""
        if not self.stable:
            return (f"the closed loop is unstable (a {self.mode_hz:.3g} Hz mode growing "
                    f"{self.growth:.3g}/s, |z| = {self.radius:.5f})")
        if self.gain < min_gain:
            return (f"gain margin {self.gain:.3g} ({self.gain_db:.1f} dB) < {min_gain:g} "
                    f"({20 * math.log10(min_gain):.0f} dB)")
        if self.phase < min_phase:
            return f"phase margin {self.phase:.1f} deg < {min_phase:g} deg"
        if self.ms > max_ms:
            return f"peak sensitivity Ms {self.ms:.3g} > {max_ms:g}"
        return None

    def worst_ratio(self) -> float:
        """``min(gain/2, phase/30, 2/Ms)``: below 1 where the requirement is not met (a
        single figure to rank points by; 0 if unstable)."""
        if not self.stable:
            return 0.0
        return min(self.gain / MIN_GAIN_MARGIN, self.phase / MIN_PHASE_MARGIN,
                   MAX_SENSITIVITY / self.ms)

    def describe(self) -> str:
        if not self.stable:
            return (f"unstable: a {self.mode_hz:.3g} Hz mode growing {self.growth:.3g}/s "
                    f"(closed-loop |z| = {self.radius:.5f})")
        gm = "inf" if math.isinf(self.gain) else f"{self.gain:.3g} ({self.gain_db:.1f} dB)"
        pm = "inf" if math.isinf(self.phase) else f"{self.phase:.1f} deg"
        return f"gain margin {gm}, phase margin {pm}, Ms {self.ms:.3g}"

    def as_dict(self) -> dict[str, Any]:
        """JSON form (``null`` for infinities)."""
        def num(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        return {"gain": num(self.gain), "gain_db": num(self.gain_db),
                "gain_up": num(self.gain_up), "gain_down": float(self.gain_down),
                "phase_deg": num(self.phase), "ms": num(self.ms),
                "phase_crossover": num(self.phase_crossover),
                "gain_crossover": num(self.gain_crossover),
                "ms_frequency": num(self.ms_frequency), "radius": float(self.radius),
                "growth": num(self.growth), "mode_hz": num(self.mode_hz),
                "stable": self.stable}


def margins_of_responses(L: np.ndarray, w: np.ndarray, pole: np.ndarray, dt: float
                         ) -> dict[str, np.ndarray]:
    """The margins of many loops from their responses ``L[..., f]`` at frequencies ``w[f]``
    and their closed loops' largest poles ``pole[...]`` (sample period ``dt``), vectorised
    over the leading axes, crossings interpolated linearly.

    Returns
    -------
    dict of numpy.ndarray
        ``gain``, ``gain_up``, ``gain_down``, ``phase``, ``ms``, ``phase_crossover``,
        ``gain_crossover``, ``ms_frequency``, ``radius``, ``growth``, ``mode_hz``, each of
        the leading shape; the
        unstable loops (``radius >= 1``) get ``gain = phase = 0``, ``ms = inf``.
    """
    L = np.asarray(L, dtype=complex)
    re, im = L.real, L.imag
    # phase crossovers: Im L changes sign (or vanishes) with Re L < 0
    a, b = im[..., :-1], im[..., 1:]
    cross = (a == 0) | (a * b < 0)
    t = np.where(cross, a / np.where(a - b == 0, 1.0, a - b), 0.0)
    rc = re[..., :-1] + t * (re[..., 1:] - re[..., :-1])
    wc = w[:-1] * (w[1:] / w[:-1]) ** t
    # the Nyquist frequency: L is real there
    last = re[..., -1:]
    cross = np.concatenate([cross, np.abs(im[..., -1:]) <= 1e-9 * np.abs(last)], axis=-1)
    rc = np.concatenate([rc, last], axis=-1)
    wc = np.concatenate([np.broadcast_to(wc, rc[..., :-1].shape), np.broadcast_to(
        w[-1:], last.shape)], axis=-1)
    neg = cross & (rc < 0)
    k = np.where(neg, -1.0 / np.where(rc < 0, rc, -1.0), np.nan)
    up = np.where(k > 1, k, np.inf)
    i_up = np.argmin(up, axis=-1)
    gain_up = np.take_along_axis(up, i_up[..., None], -1)[..., 0]
    down = np.where(k < 1, k, 0.0)
    i_dn = np.argmax(down, axis=-1)
    gain_down = np.take_along_axis(down, i_dn[..., None], -1)[..., 0]
    inv_down = np.where(gain_down > 0, 1.0 / np.where(gain_down > 0, gain_down, 1.0), np.inf)
    gain = np.minimum(gain_up, inv_down)
    w_up = np.take_along_axis(wc, i_up[..., None], -1)[..., 0]
    w_dn = np.take_along_axis(wc, i_dn[..., None], -1)[..., 0]
    w_pc = np.where(gain_up <= inv_down, w_up, w_dn)
    w_pc = np.where(np.isfinite(gain), w_pc, np.nan)
    # gain crossovers
    mag = np.abs(L)
    ma, mb = mag[..., :-1], mag[..., 1:]
    gc = (ma - 1.0) * (mb - 1.0) < 0
    tg = np.where(gc, (1.0 - ma) / np.where(mb - ma == 0, 1.0, mb - ma), 0.0)
    Lg = L[..., :-1] + tg * (L[..., 1:] - L[..., :-1])
    pm = np.where(gc, 180.0 - np.degrees(np.abs(np.angle(Lg))), np.inf)
    i_pm = np.argmin(pm, axis=-1)
    phase = np.take_along_axis(pm, i_pm[..., None], -1)[..., 0]
    wg = w[:-1] * (w[1:] / w[:-1]) ** tg
    w_gc = np.take_along_axis(wg, i_pm[..., None], -1)[..., 0]
    w_gc = np.where(np.isfinite(phase), w_gc, np.nan)
    dist = np.abs(1.0 + L)
    i_ms = np.argmin(dist, axis=-1)
    ms = 1.0 / np.take_along_axis(dist, i_ms[..., None], -1)[..., 0]
    w_ms = w[i_ms]
    pole = np.asarray(pole, dtype=complex)
    radius = np.abs(pole)
    growth = np.log(np.maximum(radius, 1e-300)) / dt
    mode_hz = np.abs(np.angle(pole)) / (2 * math.pi * dt)
    bad = ~(radius < 1.0)
    return {"gain": np.where(bad, 0.0, gain), "gain_up": gain_up, "gain_down": gain_down,
            "phase": np.where(bad, 0.0, phase), "ms": np.where(bad, np.inf, ms),
            "phase_crossover": w_pc, "gain_crossover": w_gc, "ms_frequency": w_ms,
            "radius": radius, "growth": growth, "mode_hz": mode_hz}


def requirement_ratio(L: np.ndarray, pole: np.ndarray, dt: float) -> np.ndarray:
    """``min(gain/2, phase/30, 2/Ms)`` of many loops (:func:`margins_of_responses`' figures,
    fewer of them, for a search); an unstable closed loop: minus its growth rate (1/s)."""
    re, im = L.real, L.imag
    a, b = im[..., :-1], im[..., 1:]
    cross = (a * b <= 0) & ((a != 0) | (b != 0))
    t = a / np.where(cross, a - b, 1.0)
    rc = np.where(cross, re[..., :-1] + t * (re[..., 1:] - re[..., :-1]), 0.0)
    k = np.where(rc < 0, -1.0 / np.where(rc < 0, rc, -1.0), np.nan)
    last = re[..., -1]
    k_end = np.where(last < 0, -1.0 / np.where(last < 0, last, -1.0), np.nan)
    k = np.concatenate([k, k_end[..., None]], axis=-1)
    with np.errstate(invalid="ignore"):
        up = np.nanmin(np.where(k > 1, k, np.inf), axis=-1)
        down = np.nanmax(np.where(k < 1, k, 0.0), axis=-1)
    gain = np.minimum(up, np.where(down > 0, 1.0 / np.where(down > 0, down, 1.0), np.inf))
    mag = np.abs(L)
    ma, mb = mag[..., :-1], mag[..., 1:]
    gc = (ma - 1.0) * (mb - 1.0) < 0
    tg = (1.0 - ma) / np.where(gc, mb - ma, 1.0)
    Lg = L[..., :-1] + tg * (L[..., 1:] - L[..., :-1])
    phase = np.min(np.where(gc, 180.0 - np.degrees(np.abs(np.angle(Lg))), np.inf), axis=-1)
    ms = 1.0 / np.min(np.abs(1.0 + L), axis=-1)
    ratio = np.minimum(np.minimum(gain / MIN_GAIN_MARGIN, phase / MIN_PHASE_MARGIN),
                       MAX_SENSITIVITY / ms)
    radius = np.abs(pole)
    return np.where(radius < 1.0, ratio, -np.log(np.maximum(radius, 1e-300)) / dt)


def refined_margins(response: Callable[[np.ndarray], np.ndarray], w: np.ndarray,
                    pole: complex, dt: float, iterations: int = 40) -> LoopMargins:
    """The margins of one loop, its crossings refined by bisection on the exact response.

    Parameters
    ----------
    response : callable
        ``L`` at an array of frequencies (rad/s).
    w : numpy.ndarray
        The frequency grid (:func:`frequency_grid`).
    pole : complex
        The closed loop's largest pole (``z``).
    dt : float
        The sample period (s).
    """
    L = response(w)
    radius = abs(pole)
    growth = math.log(max(radius, 1e-300)) / dt
    mode_hz = abs(np.angle(pole)) / (2 * math.pi * dt)

    def bisect(f: Callable[[float], float], lo: float, hi: float) -> float:
        flo = f(lo)
        for _ in range(iterations):
            mid = math.sqrt(lo * hi)
            fm = f(mid)
            if (fm < 0) == (flo < 0):
                lo, flo = mid, fm
            else:
                hi = mid
        return math.sqrt(lo * hi)

    def at(x: float) -> complex:
        return complex(response(np.array([x]))[0])

    ks: list[tuple[float, float]] = []
    im = L.imag
    for i in np.nonzero((im[:-1] == 0) | (im[:-1] * im[1:] < 0))[0]:
        wx = bisect(lambda x: at(x).imag, w[i], w[i + 1]) if im[i] != 0 else w[i]
        r = at(wx).real
        if r < 0:
            ks.append((-1.0 / r, wx))
    if abs(im[-1]) <= 1e-9 * abs(L[-1].real) and L[-1].real < 0:
        ks.append((-1.0 / L[-1].real, float(w[-1])))
    ups = [(k, x) for k, x in ks if k > 1]
    dns = [(k, x) for k, x in ks if k < 1]
    gain_up, w_up = min(ups, default=(math.inf, math.nan))
    gain_down, w_dn = max(dns, default=(0.0, math.nan))
    inv = 1.0 / gain_down if gain_down > 0 else math.inf
    gain, w_pc = (gain_up, w_up) if gain_up <= inv else (inv, w_dn)
    mag = np.abs(L)
    pms: list[tuple[float, float]] = []
    for i in np.nonzero((mag[:-1] - 1.0) * (mag[1:] - 1.0) < 0)[0]:
        wx = bisect(lambda x: abs(at(x)) - 1.0, w[i], w[i + 1])
        pms.append((180.0 - math.degrees(abs(np.angle(at(wx)))), wx))
    phase, w_gc = min(pms, default=(math.inf, math.nan))
    # the peak sensitivity: golden-section search around the grid's best
    dist = np.abs(1.0 + L)
    i = int(np.argmin(dist))
    lo, hi = w[max(i - 1, 0)], w[min(i + 1, len(w) - 1)]
    g = (math.sqrt(5.0) - 1.0) / 2.0
    x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
    for _ in range(iterations):
        if abs(1.0 + at(x1)) < abs(1.0 + at(x2)):
            hi, x2 = x2, x1
            x1 = hi - g * (hi - lo)
        else:
            lo, x1 = x1, x2
            x2 = lo + g * (hi - lo)
    w_ms = 0.5 * (lo + hi)
    ms = max(1.0 / abs(1.0 + at(w_ms)), 1.0 / float(dist[i]))
    if not radius < 1.0:
        return LoopMargins(0.0, gain_up, gain_down, 0.0, math.inf, w_pc, w_gc, w_ms, radius,
                           growth, mode_hz)
    return LoopMargins(gain, gain_up, gain_down, phase, ms, w_pc, w_gc, w_ms, radius, growth,
                       mode_hz)


def loop_margins_from(arrays: dict[str, np.ndarray], index: tuple[int, ...]) -> LoopMargins:
    """One loop's :class:`LoopMargins` out of :func:`margins_of_responses`' arrays."""
    return LoopMargins(**{k: float(v[index]) for k, v in arrays.items()})


__all__ = ["MAX_SENSITIVITY", "MIN_GAIN_MARGIN", "MIN_PHASE_MARGIN", "N_FREQUENCIES",
           "LoopMargins", "frequency_grid", "loop_margins_from", "margins_of_responses",
           "refined_margins", "requirement_ratio"]
