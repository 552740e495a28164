"""Measurement styles: which sensors a rig has, and what each of them records.

=====================  ==============================================================
style                  columns (besides ``t``, ``experiment``) and sensors
=====================  ==============================================================
``load-cell``          ``x`` (encoder), ``p1``, ``p2``, ``F``: friction measured by a
                       load cell (AR(1) noise); the original generator's record
``tacho``              the same plus ``v`` from a tachometer: first-order lag, gain
                       error, bias, white plus AR(1) noise
``encoder-velocity``   the same plus ``v`` as a drive computes it: counts over a
                       window of samples (backward difference) of the quantised
                       encoder, whose read head vibrates by a fraction of a count
``pressures``          ``x``, ``p1``, ``p2`` only: the tool reconstructs ``F`` from the
                       force balance (sensor noise and a ~1 ms first-order lag)
``pressures-tacho``    ``pressures`` plus the tachometer ``v``
``coarse-encoder``     ``load-cell`` with the position 10-20x coarser
``drive-force``        ``x``, ``F_ext``: a friction rig; the rod is driven and a load
                       cell measures the drive force, ``F = F_ext - m*a`` (horizontal,
                       no pressures); mass in the sidecar, no bore
``potentiometer``      ``load-cell`` with an analog position sensor instead of the
                       encoder (linear potentiometer, LVDT, eddy-current sensor):
                       white noise :attr:`Sensors.analog_noise` read by a 16-bit
                       converter over the stroke (seed 001's rig)
``potentiometer-       ``pressures`` with that analog position (seed 000's rig)
pressures``
=====================  ==============================================================

The force noise of a load cell is AR(1) (:attr:`Sensors.noise_color` ``"ar1"``) or
1/f (``"pink"``, :func:`pink`, then on the pressure transducers of the
``pressures`` styles too, whose noise is otherwise white). On a vertical rig
(:func:`measure`'s ``gravity``) the chamber pressures and the drive force carry
the weight of the moving mass; a load cell does not.

The two analog styles are not in the diagnosis matrix's default styles
(:data:`fcomp.synthetic.matrix.MATRIX_STYLES`): they check a sensor it was not
tuned on.

Every style writes the sidecar a real user would: ``kind`` (the scale's
cylinder, or ``friction-rig``), ``pressure = "gauge"``, ``[rig]`` with the
geometry the tool needs and the (possibly wrong, see ``inertia-error``)
moving mass. The truth is never written.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from fcomp.errors import FcompError
from fcomp.synthetic.dynamics import lowpass
from fcomp.synthetic.friction import chamber_pressures
from fcomp.synthetic.scales import Sensors, TruthParams


@dataclass(frozen=True)
class Style:
    """A measurement style.

    Attributes
    ----------
    name
        Registry name.
    force
        How the force is measured: ``"load-cell"`` (an ``F`` column, plus the chamber
        pressures), ``"pressures"`` (only ``p1``, ``p2``), ``"drive"`` (``F_ext``).
    velocity
        ``None``, ``"tacho"`` or ``"encoder"``: the ``v`` column's sensor.
    coarse
        Position quantised :attr:`Sensors.coarse` times coarser.
    analog
        Position from an analog sensor: white noise :attr:`Sensors.analog_noise`,
        then a converter of :data:`ANALOG_BITS` bits over the stroke.
    """

    name: str
    force: str
    velocity: str | None = None
    coarse: bool = False
    analog: bool = False

    @property
    def columns(self) -> tuple[str, ...]:
        """The columns this style writes, in order."""
        cols = ["t", "x"]
        if self.velocity is not None:
            cols.append("v")
        if self.force != "drive":
            cols += ["p1", "p2"]
        if self.force == "load-cell":
            cols.append("F")
        if self.force == "drive":
            cols.append("F_ext")
        return (*cols, "experiment")


#: The measurement styles by name.
STYLES: dict[str, Style] = {s.name: s for s in (
    Style("load-cell", "load-cell"),
    Style("tacho", "load-cell", "tacho"),
    Style("encoder-velocity", "load-cell", "encoder"),
    Style("pressures", "pressures"),
    Style("pressures-tacho", "pressures", "tacho"),
    Style("coarse-encoder", "load-cell", coarse=True),
    Style("drive-force", "drive"),
    Style("potentiometer", "load-cell", analog=True),
    Style("potentiometer-pressures", "pressures", analog=True),
)}
#: Bits of the converter that reads an analog position sensor over the stroke.
ANALOG_BITS = 16


def get_style(name: str, include_velocity: bool = False) -> Style:
    """The :class:`Style` called ``name`` (checked against ``include_velocity``)."""
    try:
        style = STYLES[name]
    except KeyError:
        raise FcompError(f"unknown style {name!r}; known: {', '.join(STYLES)}") from None
    if style.velocity is not None and include_velocity:
        raise FcompError(f"style {name!r} records a velocity of its own: "
                         "include_velocity (the exact v) does not apply")
    return style


def ar1(rng: np.random.Generator, n: int, std: float, tau: float, dt: float) -> np.ndarray:
    """Stationary AR(1) noise of standard deviation ``std`` and correlation time ``tau``.

    ``e_k = phi*e_{k-1} + w_k``, ``phi = exp(-dt/tau)``, ``w ~ N(0, std^2*(1 - phi^2))``,
    started from the stationary distribution.
    """
    phi = math.exp(-dt / tau)
    w = rng.normal(0.0, std * math.sqrt(1 - phi * phi), n)
    prev = rng.normal(0.0, std)
    y, _ = lfilter([1.0], [1.0, -phi], w, zi=[phi * prev])
    return np.asarray(y)


#: Spectra of the force-channel noise (:attr:`Sensors.noise_color`).
NOISE_COLORS = ("ar1", "pink")


def pink(rng: np.random.Generator, n: int, std: float) -> np.ndarray:
    """1/f ("pink") noise of standard deviation ``std`` over ``n`` samples.

    Spectral shaping of white noise: ``n`` standard normal values are
    transformed (real FFT), every bin ``k >= 1`` is divided by ``sqrt(k)`` (a power
    spectral density ``~ 1/f`` from the lowest frequency of the record, ``1/(n*dt)``,
    up to the Nyquist frequency), the mean (bin 0) is set to zero, and the inverse
    transform is scaled to the sample standard deviation ``std``. Equal power per
    decade: the record wanders slowly by about ``std`` as well as jittering from sample
    to sample; the ends join smoothly (circular). Fewer than four samples: white.
    """
    w = rng.normal(0.0, 1.0, n)
    if n < 4 or std == 0:
        return std * w
    W = np.fft.rfft(w)
    W[0] = 0.0
    W[1:] /= np.sqrt(np.arange(1, W.size))
    y = np.fft.irfft(W, n)
    return y * (std / float(np.std(y)))


def force_noise(rng: np.random.Generator, n: int, std: float, sens: Sensors, dt: float
                ) -> np.ndarray:
    """Noise of the force channel in the colour :attr:`Sensors.noise_color` (``dt``: the
    nominal sample interval of the AR(1) law)."""
    if sens.noise_color == "ar1":
        return ar1(rng, n, std, sens.noise_tau, dt)
    if sens.noise_color == "pink":
        return pink(rng, n, std)
    raise FcompError(f"unknown noise colour {sens.noise_color!r}; known: "
                     f"{', '.join(NOISE_COLORS)}")


@dataclass(frozen=True)
class FineSignals:
    """The truth on the fine grid, as the sensors see it (SI).

    Attributes
    ----------
    t, x, v, a, S, experiment : (n,)
        Time, position, node velocity and acceleration, pressure sum, experiment number.
    friction : (n,) N
        Friction alone.
    recorded : (n,) N
        What a perfect force channel would give the tool: friction plus the
        recording errors (``truth.F``).
    physical : (n,) N
        The non-friction forces that really act on the piston (in the force balance).
    dt : s
        Fine step.
    idx : (N,)
        Fine-grid indices of the samples.
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    S: np.ndarray
    experiment: np.ndarray
    friction: np.ndarray
    recorded: np.ndarray
    physical: np.ndarray | None
    dt: float
    idx: np.ndarray


@dataclass(frozen=True)
class Recorded:
    """The measured columns and, in force units, the noise the force channel carries."""

    columns: dict[str, np.ndarray]
    noise: np.ndarray
    noise_std: float


def lag(sig: FineSignals, u: np.ndarray, tau: float) -> np.ndarray:
    """First-order sensor lag of a fine-grid signal, restarted in steady state at every
    experiment (the record has a 1 s gap between experiments, in which a sensor settles)."""
    out = np.empty_like(u)
    starts = np.flatnonzero(np.diff(sig.experiment)) + 1
    for part in np.split(np.arange(u.size), starts):
        out[part] = lowpass(u[part], tau, sig.dt)
    return out


def position_step(style: Style, sens: Sensors, P: TruthParams) -> float:
    """The quantum (m) of the position ``style`` records: the encoder's resolution
    (:attr:`Sensors.coarse` times it for ``coarse``), or the converter's step over the
    stroke for an analog sensor."""
    if style.analog:
        return P.stroke / 2**ANALOG_BITS
    return sens.resolution * (sens.coarse if style.coarse else 1.0)


def quantise(x: np.ndarray, resolution: float) -> np.ndarray:
    """Encoder reading: ``x`` rounded to the nearest multiple of ``resolution`` (m)."""
    return np.round(x / resolution) * resolution if resolution > 0 else x


def encoder_velocity(xq: np.ndarray, t: np.ndarray, window: int) -> np.ndarray:
    """Counts over ``window`` samples: ``(x_k - x_{k-N})/(t_k - t_{k-N})`` (fewer at the start).

    The first sample has no earlier count: 0.
    """
    j = np.maximum(np.arange(xq.size) - window, 0)
    out = np.zeros_like(xq)
    out[1:] = (xq[1:] - xq[j[1:]]) / (t[1:] - t[j[1:]])
    return out


def tacho(sig: FineSignals, sens: Sensors, rng: np.random.Generator) -> np.ndarray:
    """Tachometer reading at the samples (m/s).

    ``(1 + gain)*lag(v) + bias + white + AR(1)``: the true velocity through a
    first-order lag ``tacho_lag`` (on the fine grid), with the gain error, the
    offset, and noise of standard deviations ``tacho_white`` and
    ``tacho_coloured`` (correlation time ``tacho_tau``).
    """
    lagged = lag(sig, sig.v, sens.tacho_lag)[sig.idx]
    n = lagged.size
    dt_s = sig.dt * (sig.idx[1] - sig.idx[0]) if n > 1 else sig.dt
    noise = rng.normal(0.0, sens.tacho_white, n)
    if sens.tacho_coloured > 0:
        noise = noise + ar1(rng, n, sens.tacho_coloured, sens.tacho_tau, dt_s)
    return (1.0 + sens.tacho_gain) * lagged + sens.tacho_bias + noise


def measure(style: Style, sens: Sensors, sig: FineSignals, P: TruthParams, mass_sidecar: float,
            rate: float, include_velocity: bool, rng: np.random.Generator,
            rng_extra: np.random.Generator, gravity: float = 0.0) -> Recorded:
    """Record ``sig`` as the rig of ``style`` would (columns of :attr:`Style.columns`).

    ``rng`` draws the force and pressure noise (in the original generator's
    order), ``rng_extra`` the sensors the original generator did not have.
    ``gravity`` is ``g*s`` (m/s^2; ``s = +1`` for a cylinder extending upward, ``-1``
    downward, ``0`` horizontal): the weight ``m*g*s`` of the moving mass opposes
    extension, so the chamber pressures and the drive force carry it; a load cell
    between rod and seal does not (its ``F`` is the friction, as on a horizontal rig).
    The sidecar's mass carries the part the tool subtracts, ``sig.recorded`` the rest
    (``dm*g*s`` of an ``inertia-error``, added by :func:`fcomp.synthetic.generate`).
    """
    idx = sig.idx
    t_s = sig.t[idx]
    n = t_s.size
    a_s = sig.a[idx]
    recorded = sig.recorded[idx]
    dt_s = 1.0 / rate
    A1, A2 = P.areas
    cols: dict[str, np.ndarray] = {"t": t_s - t_s[0]}
    x_true = sig.x[idx]
    resolution = position_step(style, sens, P)
    if style.velocity == "encoder" and sens.encoder_jitter > 0:
        x_true = x_true + rng_extra.normal(0.0, sens.encoder_jitter, n)
    if style.analog:
        x_true = x_true + rng_extra.normal(0.0, sens.analog_noise, n)
    cols["x"] = quantise(x_true, resolution)
    if include_velocity:
        cols["v"] = sig.v[idx]
    elif style.velocity == "tacho":
        cols["v"] = tacho(sig, sens, rng_extra)
    elif style.velocity == "encoder":
        cols["v"] = encoder_velocity(cols["x"], t_s, sens.encoder_window)
    noise = np.zeros(n)
    noise_std = 0.0
    if style.force != "pressures":  # a load cell: on the friction, or on the drive
        if sens.noise_std > 0:
            noise = force_noise(rng, n, sens.noise_std, sens, dt_s)
        noise_std = sens.noise_std
    if style.force == "load-cell":
        F_net = sig.friction[idx]
        if sig.physical is not None:
            F_net = F_net + sig.physical[idx]
        F_net = F_net + P.mass * a_s
        if gravity != 0.0:
            F_net = F_net + P.mass * gravity
        p1, p2 = chamber_pressures(P, sig.S[idx], F_net)
    elif style.force == "pressures":  # the tool's balance must give the recorded force
        F_net = sig.recorded + mass_sidecar * sig.a
        if gravity != 0.0:
            F_net = F_net + mass_sidecar * gravity
        p1f, p2f = chamber_pressures(P, sig.S, F_net)
        p1 = lag(sig, p1f, sens.pressure_lag)[idx]
        p2 = lag(sig, p2f, sens.pressure_lag)[idx]
    if style.force != "drive":
        if style.force == "pressures" and sens.noise_color != "ar1":
            n1 = force_noise(rng, n, sens.pressure_noise, sens, dt_s)
            n2 = force_noise(rng, n, sens.pressure_noise, sens, dt_s)
        else:  # white (the original generator's transducers)
            n1 = rng.normal(0.0, sens.pressure_noise, n)
            n2 = rng.normal(0.0, sens.pressure_noise, n)
        cols["p1"] = p1 + n1
        cols["p2"] = p2 + n2
    if style.force == "load-cell":
        cols["F"] = recorded + noise
    elif style.force == "pressures":
        noise = n1 * A1 - n2 * A2
        noise_std = sens.pressure_noise * math.hypot(A1, A2)
    else:
        drive = recorded + mass_sidecar * a_s
        if gravity != 0.0:
            drive = drive + mass_sidecar * gravity
        cols["F_ext"] = drive + noise
    cols["experiment"] = sig.experiment[idx]
    return Recorded(cols, noise, float(noise_std))
