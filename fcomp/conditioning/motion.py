"""Which velocity drives the friction states of a record, and why (:func:`condition_motion`;
the overview: :mod:`fcomp.conditioning`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from fcomp.conditioning.events import event_band, event_time_scale
from fcomp.conditioning.position import (
    MIN_REST,
    band,
    default_cutoff,
    derived_velocity_noise,
    position_noise,
    position_rest,
    resolution,
    sample_rate,
    speed_scale,
)
from fcomp.conditioning.velocity import (
    GAIN_TOL,
    MIN_R2,
    VelocityCalibration,
    calibrate_velocity,
    robust_std,
    velocity_rest,
)
from fcomp.errors import FcompError
from fcomp.reconstruction import differentiate, smooth


@dataclass(frozen=True)
class Conditioning:
    """What drives the friction states of one record, and why (the JSON ``signals``).

    Attributes
    ----------
    velocity : str
        ``"x"`` (``dx/dt``), ``"v"`` (the calibrated column) or ``"fused"``.
    reason : str
        Why, in one sentence.
    cutoff_hz : Hz
        Band of the derived velocity and acceleration.
    crossover_hz : Hz or None
        Cross-over of the fusion (``"fused"`` only).
    x_resolution, x_noise : m or None
        Position resolution and noise (None without a position).
    vx_noise : m/s or None
        Noise of ``dx/dt`` in its band.
    column : VelocityCalibration or None
        Calibration of the ``v`` column, if there is one.
    rest : str
        ``"position"``, ``"velocity"`` or ``"none"``: what rest was read off.
    rest_share : -
        Share of samples held at rest.
    force : str
        ``"F"``, ``"reconstructed"`` or ``"driving-force"`` (set by the caller).
    force_cutoff_hz : Hz or None
        Band of the parallel filtering of force and prediction (None: unfiltered).
    label : str
        The record's name (set by the caller).
    event_time_s : s or None
        The time scale of the record's events (the faster quartile of the force's
        10-90 % transitions at its reversals, :mod:`fcomp.conditioning.events`) that
        raised ``cutoff_hz``; None when not measured.
    """

    velocity: str
    reason: str
    cutoff_hz: float
    crossover_hz: float | None
    x_resolution: float | None
    x_noise: float | None
    vx_noise: float | None
    column: VelocityCalibration | None
    rest: str
    rest_share: float
    force: str = ""
    force_cutoff_hz: float | None = None
    label: str = ""
    event_time_s: float | None = None

    def to_dict(self) -> dict:
        """Plain JSON-ready values (nan -> None)."""
        def clean(v):
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            if isinstance(v, float) and not math.isfinite(v):
                return None
            return v

        return clean(asdict(self))


@dataclass(frozen=True)
class Motion:
    """The conditioned motion of one piece (experiment) of a record (SI)."""

    v: np.ndarray
    a: np.ndarray
    rest: np.ndarray


def condition_motion(pieces: Sequence[tuple[np.ndarray, np.ndarray | None, np.ndarray | None]],
                     *, cutoff_hz: float | None = None,
                     forces: Sequence[np.ndarray] | None = None
                     ) -> tuple[list[Motion], Conditioning]:
    """The conditioned motion of every piece of one record, and how it was made.

    Parameters
    ----------
    pieces
        ``(t, x, v_col)`` per experiment of one file (s, m, m/s); ``x`` or
        ``v_col`` may be None (the same for every piece). One calibration of the
        ``v`` column is pooled over the pieces.
    cutoff_hz
        Band of the derivation filter (default :func:`default_cutoff` of the
        longest piece, raised to keep the record's events where ``forces`` are
        given (:func:`~fcomp.conditioning.events.event_band`), or a tenth of the
        sample rate without a position).
    forces
        The raw force of each piece (a load cell, or the driving force), whose
        transitions at the reversals set the events' time scale
        (:func:`~fcomp.conditioning.events.event_time_scale`).
    """
    t0, x0, v0 = max(pieces, key=lambda p: p[0].size)
    fs = sample_rate(t0)
    if x0 is None and v0 is None:
        raise FcompError("a motion needs a position 'x' or a velocity 'v' column")
    if x0 is None:
        return _from_velocity(pieces, cutoff_hz if cutoff_hz is not None else 0.1 * fs)
    fc = cutoff_hz if cutoff_hz is not None else default_cutoff(t0, x0)
    sx = max(position_noise(x) for _, x, _ in pieces if x is not None)
    t_event, raised = None, ""
    if cutoff_hz is None and forces is not None:
        fc_noise = fc
        fc, t_event = _event_band(pieces, forces, fc, fs, sx, speed_scale(t0, x0))
        if fc > fc_noise and t_event is not None:
            raised = (f"; band {fc:.3g} Hz, not {fc_noise:.3g} Hz, to keep the force's "
                      f"transitions at the reversals ({1e3 * t_event:.0f} ms)")
    q = min(resolution(x) for _, x, _ in pieces if x is not None)
    derived = []
    for t, x, _ in pieces:
        assert x is not None
        _, v_x, a_x = differentiate(t, x, cutoff_hz=fc, label="x")
        rest, _ = position_rest(t, x, sx)
        derived.append((v_x, a_x, rest))
    vx_noise = derived_velocity_noise(sx, fc, fs)
    velocity, reason, cross, cal = "x", "no velocity column: dx/dt of the position", None, None
    if v0 is not None:
        cols = [p[2] for p in pieces if p[2] is not None]
        cal = calibrate_velocity([p[0] for p in pieces], cols,
                                 [d[0] for d in derived], [d[2] for d in derived], fc)
        velocity, reason, cross, fc = _choose(cal, sx, fc, fs, speed_scale(t0, x0),
                                              cutoff_hz is not None)
    out = []
    for (t, _, v_col), (v, a, rest) in zip(pieces, derived, strict=True):
        if velocity == "fused":
            assert cross is not None and cal is not None and v_col is not None
            vc = cal.apply(t, v_col)
            low = smooth(t, v, cutoff_hz=cross, label="dx/dt")
            high = vc - smooth(t, vc, cutoff_hz=cross, label="v")
            v = smooth(t, low + high, cutoff_hz=fc, label="v")
            a = np.gradient(v, t)
        out.append(Motion(np.where(rest, 0.0, v), np.where(rest, 0.0, a), rest))
    share = float(np.mean(np.concatenate([m.rest for m in out])))
    return out, Conditioning(velocity, reason + raised, fc, cross, q, sx, vx_noise, cal,
                             "position", share, event_time_s=t_event)


def _event_band(pieces: Sequence[tuple[np.ndarray, np.ndarray | None, np.ndarray | None]],
                forces: Sequence[np.ndarray], fc: float, fs: float, sx: float,
                speed: float) -> tuple[float, float | None]:
    """The derivation band ``fc`` raised to keep the record's events, and their time scale
    (:mod:`fcomp.conditioning.events`): the reversals read off ``dx/dt`` in the
    noise-limited band ``fc``, their transitions off the raw ``forces``."""
    found = []
    for (t, x, _), f in zip(pieces, forces, strict=True):
        if x is None or f is None or t.size < 4 * MIN_REST:
            continue
        _, v, _ = differentiate(t, x, cutoff_hz=fc, label="x")
        found.append((t, v, f))
    t_event = event_time_scale(found)
    return event_band(fs, fc, t_event, speed,
                      lambda f: derived_velocity_noise(sx, f, fs)), t_event


def _from_velocity(pieces: Sequence[tuple[np.ndarray, np.ndarray | None, np.ndarray | None]],
                   fc: float) -> tuple[list[Motion], Conditioning]:
    """Rest, bias and noise read off the velocity alone (no position)."""
    found = []
    for t, _, v_col in pieces:
        assert v_col is not None
        found.append(velocity_rest(t, v_col, fc))
    at_rest = np.concatenate([p[2][r] for p, (r, _, _) in zip(pieces, found, strict=True)
                              if p[2] is not None])
    bias = float(np.median(at_rest)) if at_rest.size >= MIN_REST else 0.0
    noise = robust_std(at_rest) if at_rest.size >= MIN_REST else math.nan
    cal = VelocityCalibration(bias, 1.0, 0.0, noise, math.nan, int(at_rest.size))
    out = []
    for (t, _, v_col), (rest, _, _) in zip(pieces, found, strict=True):
        assert v_col is not None
        v = smooth(t, cal.apply(t, v_col), cutoff_hz=fc, label="v")
        a = np.gradient(v, t)
        out.append(Motion(np.where(rest, 0.0, v), np.where(rest, 0.0, a), rest))
    share = float(np.mean(np.concatenate([m.rest for m in out])))
    reason = (f"no position column: the measured velocity, bias {bias:.2g} m/s removed "
              "(rest read off the velocity)" if at_rest.size >= MIN_REST else
              "no position column: the measured velocity (no rest found to estimate a bias)")
    return out, Conditioning("v", reason, fc, None, None, None, None, cal,
                             "velocity" if at_rest.size >= MIN_REST else "none", share)


def _choose(cal: VelocityCalibration, sx: float, fc_x: float, fs: float, speed: float,
            fixed: bool) -> tuple[str, str, float | None, float]:
    """``(velocity, reason, crossover, band)`` for a calibrated column (module docstring).

    The fused velocity's noise in a band ``fc`` is that of ``dx/dt`` up to the
    cross-over ``f*`` plus the column's white noise from ``f*`` to ``fc``; its
    band is chosen by the same rule as ``dx/dt``'s (:func:`band`), unless the
    user fixed it.
    """
    if not (math.isfinite(cal.r2) and cal.r2 >= MIN_R2 and abs(cal.gain - 1.0) <= GAIN_TOL):
        return ("x", f"the v column disagrees with dx/dt (gain {cal.gain:.3g}, explains "
                f"{100 * max(cal.r2, 0.0) if math.isfinite(cal.r2) else 0:.0f} % of it while "
                "moving): dx/dt of the position", None, fc_x)
    if not math.isfinite(cal.noise):
        return "x", "the v column's noise is unknown (no rest in the record): dx/dt", None, fc_x
    # densities (one-sided, white): column noise^2/(fs/2); dx/dt (2*pi*f)^2*sx^2/(fs/2)
    cross = cal.noise / (2.0 * math.pi * max(sx, 1e-300))

    def fused_noise(fc: float) -> float:
        low = derived_velocity_noise(sx, min(fc, cross), fs)
        return math.sqrt(low**2 + cal.noise**2 * max(fc - cross, 0.0) / (0.5 * fs))

    fc = fc_x if fixed else max(fc_x, band(fs, speed, fused_noise))
    if cross >= fc:
        return ("x", f"dx/dt is cleaner than the v column up to the cutoff ({fc:.3g} Hz): "
                f"column noise {cal.noise:.2g} m/s", None, fc)
    cross = max(cross, 0.01 * fc)
    return ("fused", f"dx/dt below {cross:.3g} Hz, the v column (bias {cal.bias:.2g} m/s "
            f"removed, lag {1e3 * cal.lag:.2g} ms, gain {cal.gain:.3g}) above, up to "
            f"{fc:.3g} Hz: their noise densities cross there", cross, fc)

