"""Friction force reconstructed from a measurement (seed 000, Eq. 1; models.md section 2).

.. math::

    F = p_1 A_1 - p_2 A_2 - m a - m g s + F_{ext},
    \\qquad A_1 = \\tfrac{\\pi}{4} D^2,\\; A_2 = \\tfrac{\\pi}{4}(D^2 - d^2)

with gauge pressures (absolute ones are converted with the sidecar's
``p_atm``, default 101325 Pa), ``s = +1`` for a cylinder extending upward,
``-1`` extending downward, ``0`` horizontal (``rig.orientation``), and
``F_ext`` the external force pushing in the extending direction. ``F`` is the
friction force, positive opposing extension (data-format.md). A missing
``p1``/``p2`` column is a chamber open to atmosphere (0 gauge); ``rig.rod`` is
required when ``p2`` is present, ``rig.bore`` when either pressure is.

Velocity and acceleration come from the position ``x`` by zero-phase
filtering and differentiation, exactly:

1. **Time grid.** If the sampling is uniform (every interval within 1 % of the
   mean interval) the samples are used as they are. Otherwise ``x`` is linearly
   interpolated onto a uniform grid whose step is the median interval, the
   steps below are done there, and the results are linearly interpolated back
   to the measurement's own times (across a long gap this gives a constant
   velocity and no acceleration).
2. **Zero-phase low-pass.** A Butterworth filter of order ``order`` with -3 dB
   frequency ``cutoff_hz`` is run forward and backward
   (:func:`scipy.signal.sosfiltfilt`): no phase lag, magnitude response
   ``|H|^2`` (-6 dB at ``cutoff_hz``, roll-off ``40*order`` dB/decade). The
   ends are padded by odd reflection over ``3/cutoff_hz`` seconds; the first
   and last ``~1/cutoff_hz`` seconds are less accurate than the rest. Seed 000
   used a first-order acausal low-pass at 10 Hz on the acceleration:
   ``order=1, cutoff_hz=10`` is that filter; the default ``order=2`` rolls off
   faster than double differentiation amplifies noise (+40 dB/decade), which
   matters with encoder quantisation.
3. **Differentiation.** ``v`` and ``a`` are second-order central differences
   (:func:`numpy.gradient`) of the filtered position and of ``v``. Because the
   filter is linear and time invariant this equals differentiating first and
   filtering after (the seed's order) away from the ends.

Pressures and ``F_ext`` are used unfiltered (as in seed 000) unless
``filter_forces=True``, which passes the whole driving force through the same
zero-phase filter so that every term of ``F`` has the same bandwidth.
"""

from __future__ import annotations

import ctypes
import math
from collections.abc import Callable
from functools import lru_cache
from typing import Any

import numpy as np

from fcomp.errors import FcompError
from fcomp.measurement import ORIENTATIONS, G, Measurement
from fcomp.piston import piston_areas

#: Largest relative deviation of a sample interval from the mean for "uniform" sampling.
UNIFORM_TOL = 0.01
#: Largest uniform grid the resampling step builds (samples).
MAX_GRID = 50_000_000


#: Intervals per block of :func:`sampling_interval`.
INTERVAL_BLOCK = 64


def sampling_interval(t: np.ndarray) -> float:
    """The interval (s) a record's stamps sample at: the median interval, unless it is less
    than half the typical mean interval over blocks of :data:`INTERVAL_BLOCK` intervals (the
    median of the blocks' means), which is then taken.

    The median stands for a logger's interval whether it is uniform, jittered or
    alternates short and long intervals, and ignores its pauses. A logger that takes its
    samples in bursts (a buffered or polled acquisition stamping the true sample times: a
    few samples a tenth of the mean interval apart, then a wait) has most intervals far
    shorter than its rate: with their median as the interval every wait between bursts
    was a "pause" that cut the record into pieces of a burst each (at least 20 samples
    kept: most of the record thrown away), and a grid at that interval would hold ten
    times the samples. The blocks' means see through the bursts and, being a median, not
    the pauses.
    """
    return interval_of(np.diff(np.asarray(t, dtype=float)))


def interval_of(dt: np.ndarray) -> float:
    """:func:`sampling_interval` of the intervals ``dt`` (s) themselves."""
    if not dt.size:
        return 0.0
    med = float(np.median(dt))
    m = dt.size // INTERVAL_BLOCK
    if m < 1:
        return med
    typical = float(np.median(dt[: m * INTERVAL_BLOCK].reshape(m, INTERVAL_BLOCK).mean(axis=1)))
    return typical if med < 0.5 * typical else med


def _grid(t: np.ndarray, label: str) -> tuple[np.ndarray, bool]:
    """The uniform time grid the filter runs on, and whether it is ``t`` itself."""
    n = t.size
    span = float(t[-1] - t[0])
    mean = span / (n - 1)
    dt = np.diff(t)
    if np.max(np.abs(dt - mean)) <= UNIFORM_TOL * mean:
        return t, True
    h = sampling_interval(t)
    m = int(math.floor(span / h + 1e-9)) + 1
    if m > MAX_GRID:
        raise FcompError(f"{label}: sampling too irregular to resample (median interval {h:g} s "
                         f"over {span:g} s)")
    return t[0] + h * np.arange(m), False


def _interp_matrix(x: np.ndarray, q: np.ndarray) -> Any:
    """The sparse matrix of ``np.interp``'s linear interpolation from samples at ``x`` to ``q``
    (ends held): row ``r`` holds ``1 - w`` at ``i`` and ``w`` at ``i + 1``, so that ``M @ y``
    is ``(1 - w)*y[i] + w*y[i + 1]`` to the bit, for one signal or many columns at once."""
    from scipy.sparse import csr_matrix

    i = np.clip(np.searchsorted(x, q, side="right") - 1, 0, x.size - 2)
    w = np.clip((q - x[i]) / (x[i + 1] - x[i]), 0.0, 1.0)
    return csr_matrix((np.column_stack([1.0 - w, w]).ravel(),
                       np.column_stack([i, i + 1]).ravel(), np.arange(0, 2 * q.size + 1, 2)),
                      shape=(q.size, x.size))


@lru_cache(maxsize=256)
def _sos_zi(order: int, cutoff_hz: float, fs: float) -> np.ndarray:
    """``sosfilt_zi`` of the design (a linear solve), once per ``(order, cutoff, rate)``."""
    from scipy.signal import sosfilt_zi

    return sosfilt_zi(_butterworth(order, cutoff_hz, fs))


#: C of :func:`_filtfilt` (one call: odd extension, forward pass, backward pass, the ends
#: cut), for a row-major ``(n, k)`` array, every column at each sample: scipy's ``sosfilt``
#: (direct form II transposed, ``scipy/signal/_sosfilt.pyx``) with its operations in its
#: order, so the result is scipy's to the bit; a 13-column prediction and its
#: sensitivities are filtered about three times faster than by two ``sosfilt`` calls
#: along axis 0, which loop column by column over a transposed copy.
_FILTFILT_C = r"""
#include <string.h>
static void fcomp_sos_pass(long N, int k, int ns, const double *sos, const double *zi,
                           double *buf, double *z, int backward) {
  const double *first = buf + (backward ? (N - 1) * k : 0);
  for (int q = 0; q < 2 * ns; ++q)
    for (int j = 0; j < k; ++j) z[q * k + j] = zi[q] * first[j];
  for (long r = 0; r < N; ++r) {
    double *row = buf + (backward ? N - 1 - r : r) * k;
    for (int s = 0; s < ns; ++s) {
      const double *c = sos + 6 * s;
      const double b0 = c[0], b1 = c[1], b2 = c[2], a1 = c[4], a2 = c[5];
      double *z0 = z + 2 * s * k, *z1 = z0 + k;
      for (int j = 0; j < k; ++j) {
        const double xc = row[j];
        const double xn = b0 * xc + z0[j];
        z0[j] = b1 * xc - a1 * xn + z1[j];
        z1[j] = b2 * xc - a2 * xn;
        row[j] = xn;
      }
    }
  }
}
#if defined(__GNUC__)
__attribute__((visibility("default")))
#endif
int fcomp_filtfilt(int n, int k, int p, int ns, const double *sos, const double *zi,
                   const double *x, double *work, double *z, double *out) {
  const long N = (long)n + 2L * p;
  for (long r = 0; r < p; ++r)
    for (int j = 0; j < k; ++j) {
      work[r * k + j] = 2 * x[j] - x[(p - r) * k + j];
      work[(p + n + r) * k + j] = 2 * x[(long)(n - 1) * k + j] - x[(n - 2 - r) * k + j];
    }
  memcpy(work + (long)p * k, x, sizeof(double) * (size_t)n * (size_t)k);
  fcomp_sos_pass(N, k, ns, sos, zi, work, z, 0);
  fcomp_sos_pass(N, k, ns, sos, zi, work, z, 1);
  memcpy(out, work + (long)p * k, sizeof(double) * (size_t)n * (size_t)k);
  return 0;
}
"""


@lru_cache(maxsize=1)
def _native_filtfilt() -> Callable[[np.ndarray, int, np.ndarray, np.ndarray], np.ndarray] | None:
    """The compiled :data:`_FILTFILT_C` (:func:`fcomp.compiled.load_c`) as ``run(x, padlen,
    sos, zi) -> y`` for a C-contiguous ``x`` of one or two dimensions, or ``None`` without a
    C compiler or usable cache (:func:`_filtfilt` then calls scipy: the same result)."""
    from fcomp.compiled import load_c

    lib = load_c("fcomp_filtfilt", _FILTFILT_C)
    if lib is None:
        return None
    fn = lib.fcomp_filtfilt
    dp = ctypes.POINTER(ctypes.c_double)
    fn.argtypes = [ctypes.c_int] * 4 + [dp] * 6
    fn.restype = ctypes.c_int

    def run(x: np.ndarray, padlen: int, sos: np.ndarray, zi: np.ndarray) -> np.ndarray:
        n, k = x.shape[0], (x.shape[1] if x.ndim == 2 else 1)
        out = np.empty_like(x)
        work = np.empty((n + 2 * padlen) * k)
        z = np.empty(zi.size * k)
        args = (np.ascontiguousarray(sos), np.ascontiguousarray(zi), x, work, z, out)
        fn(n, k, padlen, sos.shape[0], *(a.ctypes.data_as(dp) for a in args))
        return out

    return run


def _filtfilt(order: int, cutoff_hz: float, fs: float, x: np.ndarray, padlen: int
              ) -> np.ndarray:
    """``scipy.signal.sosfiltfilt(sos, x, axis=0, padtype="odd", padlen=padlen)`` for the
    Butterworth design of :func:`_butterworth`, step for step as scipy does it (odd
    extension, initial conditions scaled by the first sample, forward, backward) with the
    initial conditions (``sosfilt_zi``, a linear solve) computed once per design: a fit
    filters its prediction and sensitivities with one design thousands of times. Runs the
    compiled :data:`_FILTFILT_C` where a C compiler is at hand, else scipy's ``sosfilt``
    twice; both give the same bits."""
    sos = _butterworth(order, cutoff_hz, fs)
    zi = _sos_zi(order, cutoff_hz, fs)
    native = _native_filtfilt() if x.ndim <= 2 and x.shape[0] < 2**31 - 2 * padlen else None
    if native is not None:
        return native(np.ascontiguousarray(x, dtype=float), padlen, sos, zi)
    from scipy.signal import sosfilt

    zi = zi.reshape(zi.shape[0], 2, *([1] * (x.ndim - 1)))  # broadcast over the columns
    if padlen > 0:
        ext = np.concatenate((2 * x[:1] - x[padlen:0:-1], x,
                              2 * x[-1:] - x[-2:-(padlen + 2):-1]), axis=0)
    else:
        ext = x
    y, _ = sosfilt(sos, ext, axis=0, zi=zi * ext[:1])
    y, _ = sosfilt(sos, y[::-1], axis=0, zi=zi * y[-1:])
    y = y[::-1]
    return y[padlen:-padlen] if padlen > 0 else y


class _Resampler:
    """The uniform grid of :func:`_grid` for a time vector, and the linear maps to it and back,
    computed once per time vector: a fit filters every prediction and every sensitivity column
    of a non-uniformly stamped record on the same grid."""

    def __init__(self, t: np.ndarray, label: str) -> None:
        self.tu, self.same = _grid(t, label)
        self.fs = (self.tu.size - 1) / float(self.tu[-1] - self.tu[0])
        if not self.same:
            self.to_grid = _interp_matrix(t, self.tu)
            self.back = _interp_matrix(self.tu, t)

    def filtfilt(self, y: np.ndarray, cutoff_hz: float, order: int, label: str) -> np.ndarray:
        """:func:`zero_phase_lowpass` of ``y`` (samples along axis 0) on the uniform grid."""
        yu = y if self.same else self.to_grid @ y
        out = zero_phase_lowpass(yu, self.fs, cutoff_hz, order, label=label)
        return out if self.same else self.back @ out


_RESAMPLERS: dict[tuple[Any, ...], _Resampler] = {}


def _resampler(t: np.ndarray, label: str) -> _Resampler:
    """The :class:`_Resampler` of ``t`` (cached by the stamps' bytes, a few at a time)."""
    key = (t.size, float(t[0]), float(t[-1]), hash(np.ascontiguousarray(t).tobytes()))
    found = _RESAMPLERS.get(key)
    if found is None:
        found = _Resampler(t, label)
        if len(_RESAMPLERS) >= 64:
            _RESAMPLERS.pop(next(iter(_RESAMPLERS)))
        _RESAMPLERS[key] = found
    return found


@lru_cache(maxsize=256)
def _butterworth(order: int, cutoff_hz: float, fs: float) -> np.ndarray:
    from scipy.signal import butter  # here: importing it costs ~0.4 s at start

    return butter(order, cutoff_hz, fs=fs, output="sos")


def zero_phase_lowpass(y: np.ndarray, fs: float, cutoff_hz: float, order: int, *,
                       label: str = "signal") -> np.ndarray:
    """Butterworth low-pass run forward and backward (no phase lag), uniform samples.

    Parameters
    ----------
    y
        Uniformly sampled signal (samples along axis 0; columns are filtered alike).
    fs
        Sample rate, Hz.
    cutoff_hz
        -3 dB frequency of one pass (the forward-backward response is ``|H|^2``).
    order
        Butterworth order of one pass (1 reproduces seed 000's first-order filter).
    """
    if not isinstance(order, int) or isinstance(order, bool) or order < 1:
        raise FcompError(f"filter order must be a positive integer, got {order!r}")
    if not (cutoff_hz > 0 and cutoff_hz < 0.5 * fs):
        raise FcompError(f"{label}: cutoff {cutoff_hz:g} Hz must be positive and below half the "
                         f"sample rate ({0.5 * fs:g} Hz)")
    if y.shape[0] < 3:
        raise FcompError(f"{label}: at least three samples are needed to filter")
    padlen = min(y.shape[0] - 1, int(math.ceil(3.0 * fs / cutoff_hz)))
    return _filtfilt(order, float(cutoff_hz), float(fs), np.asarray(y, dtype=float), padlen)


def smooth(t: np.ndarray, y: np.ndarray, *, cutoff_hz: float = 10.0, order: int = 2,
           label: str = "signal") -> np.ndarray:
    """:func:`zero_phase_lowpass` of ``y(t)`` on any strictly increasing time vector.

    Non-uniform stamps: ``y`` is interpolated linearly onto a uniform grid of the
    median interval (:func:`_grid`), filtered there and interpolated back to ``t``
    (the grid and the maps are computed once per time vector, :class:`_Resampler`).
    """
    return _resampler(t, label).filtfilt(y, cutoff_hz, order, label)


def band_limit(t: np.ndarray, y: np.ndarray, cutoff_hz: float, *, order: int = 2
               ) -> np.ndarray:
    """:func:`smooth` along the first axis of ``y`` (one signal or columns ``(n, k)``).

    The cut-off is capped at 0.45 of the sample rate (a record averaged over
    blocks keeps its filter where it still can). Used for "parallel filtering":
    a fit whose target was low-passed passes its prediction and sensitivities
    through the same filter.
    """
    rs = _resampler(t, "prediction")
    fc = min(cutoff_hz, 0.45 * rs.fs)
    return rs.filtfilt(y, fc, order, "prediction")


def differentiate(t: np.ndarray, x: np.ndarray, *, cutoff_hz: float = 10.0, order: int = 2,
                  label: str = "signal") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Zero-phase filtered ``x`` and its first two derivatives at the times ``t``.

    Returns ``(x_f, v, a)``: the filtered position (m), velocity (m/s) and
    acceleration (m/s^2); see the module docstring for the method.
    """
    tu, same = _grid(t, label)
    xu = x if same else np.interp(tu, t, x)
    fs = (tu.size - 1) / float(tu[-1] - tu[0])
    xf = zero_phase_lowpass(xu, fs, cutoff_hz, order, label=label)
    v = np.gradient(xf, tu)
    a = np.gradient(v, tu)
    if same:
        return xf, v, a
    return np.interp(t, tu, xf), np.interp(t, tu, v), np.interp(t, tu, a)


def derivatives(meas: Measurement, *, cutoff_hz: float = 10.0,
                order: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """``(v, a)`` of a measurement's position column ``x`` (see :func:`differentiate`)."""
    _, v, a = differentiate(meas.t, meas["x"], cutoff_hz=cutoff_hz, order=order,
                            label=meas.label)
    return v, a


def driving_force(meas: Measurement) -> np.ndarray:
    """``p1*A1 - p2*A2 + F_ext`` (N), gauge pressures; absent terms are zero.

    Raises
    ------
    FcompError
        If the measurement has none of ``p1``, ``p2``, ``F_ext``, or lacks the
        ``rig.bore`` (pressures) or ``rig.rod`` (``p2``) it needs.
    """
    if not any(k in meas for k in ("p1", "p2", "F_ext")):
        raise FcompError(f"{meas.label}: no force to reconstruct friction from: needs p1/p2 "
                         "(with rig.bore) and/or F_ext")
    total = np.zeros(len(meas))
    if "p1" in meas or "p2" in meas:
        bore = float(meas.rig_value("bore"))
        rod = float(meas.rig_value("rod")) if "p2" in meas else 0.0
        A1, A2 = piston_areas(bore, rod)
        if "p1" in meas:
            total += meas.gauge_pressure("p1") * A1
        if "p2" in meas:
            total -= meas.gauge_pressure("p2") * A2
    if "F_ext" in meas:
        total += meas["F_ext"]
    return total


def reconstruct_friction(meas: Measurement, *, cutoff_hz: float = 10.0, order: int = 2,
                         mass: float | None = None, filter_forces: bool = False) -> Measurement:
    """The measurement with columns ``v``, ``a`` and the friction force ``F`` added.

    ``F = p1*A1 - p2*A2 - m*a - m*g*s + F_ext`` (seed 000 Eq. 1, models.md
    section 2); see the module docstring for the filter and differentiation.

    Parameters
    ----------
    meas
        Needs ``x`` and at least one of ``p1``, ``p2``, ``F_ext``.
    cutoff_hz, order
        The zero-phase Butterworth low-pass (Hz; order of one pass).
    mass
        Moving mass, kg; default ``rig.mass`` of the sidecar (an error names the
        key if it is missing). ``0`` neglects inertia (quasi-static data).
    filter_forces
        Also pass the driving force through the same zero-phase filter.

    Returns
    -------
    Measurement
        All input columns plus ``v`` (m/s), ``a`` (m/s^2), ``F`` (N); existing
        ``v``, ``a``, ``F`` are replaced (listed in the sidecar). The sidecar gets
        a ``[reconstruction]`` table recording the method and its settings.
    """
    if "x" not in meas:
        raise FcompError(f"{meas.label}: friction reconstruction needs the position column 'x'")
    m = float(meas.rig_value("mass")) if mass is None else float(mass)
    if not (math.isfinite(m) and m >= 0):
        raise FcompError(f"{meas.label}: mass must be a non-negative number of kg, got {mass!r}")
    drive = driving_force(meas)
    v, a = derivatives(meas, cutoff_hz=cutoff_hz, order=order)
    if filter_forces:
        drive = smooth(meas.t, drive, cutoff_hz=cutoff_hz, order=order, label=meas.label)
    s = ORIENTATIONS[meas.rig.get("orientation", "horizontal")]
    F = drive - m * a - m * G * s
    meta: dict[str, Any] = dict(meas.meta)
    meta["reconstruction"] = {
        "equation": "F = p1*A1 - p2*A2 - m*a - m*g*s + F_ext (seed 000 Eq. 1)",
        "filter": "Butterworth, forward-backward (scipy.signal.sosfiltfilt)",
        "cutoff_hz": float(cutoff_hz),
        "order": int(order),
        "differentiation": "central differences of the filtered position",
        "mass": m,
        "filter_forces": bool(filter_forces),
        "resampled": not _grid(meas.t, meas.label)[1],
        "replaced": [k for k in ("v", "a", "F") if k in meas],
    }
    cols = dict(meas.columns)
    cols.update(v=v, a=a, F=F)
    return Measurement(cols, meta)
