"""Rig scales: the base friction, the rig, its sensors and the sizes of the hidden effects.

Four presets (:data:`SCALES`); the diagnosis matrix uses the first two by default,
the other two check magnitudes it was not tuned on:

``pneumatic`` (the default; the original generator's numbers)
    32/12 mm cylinder, 200 mm stroke, 1.2 kg moving mass, LuGre base with
    ``Fc = 30 N``, ``Fs = 45 N``, ``sigma0 = 2e5 N/m`` (presliding ~0.15 mm),
    pressure sums 1.5-5 bar gauge, load-cell noise 0.4 N (AR(1), 5 ms),
    pressure noise 300 Pa, 1 um encoder, accelerations up to 4 m/s^2.
``hydraulic``
    40/22 mm cylinder, 300 mm stroke, 20 kg moving mass, ``Fc = 300 N``,
    ``Fs = 450 N``, ``sigma0 = 4e7 N/m`` (presliding ~7.5 um), pressure sums
    6-24 MPa (chamber pressures ~2-14 MPa gauge), load-cell noise 3 N, pressure
    noise 5 kPa (a pressure-reconstructed force noise of ~7.7 N), 0.5 um
    encoder, accelerations up to 10 m/s^2, presliding loops of 3-80 um.
``small-pneumatic``
    10/4 mm cylinder, 80 mm stroke, 0.15 kg, ``Fc = 3 N``, ``Fs = 4.5 N``,
    ``sigma0 = 6e4 N/m`` (presliding ~50 um), load-cell noise 0.04 N.
``heavy-hydraulic``
    100/56 mm cylinder, 600 mm stroke, 150 kg, ``Fc = 2 kN``, ``Fs = 2.8 kN``,
    ``sigma0 = 2e8 N/m`` (presliding ~10 um), pressure sums 6-28 MPa, load-cell
    noise 15 N, pressure noise 4 kPa (a reconstructed force noise of ~40 N).

Effect sizes are carried from the pneumatic defaults by the physical
dimension of each parameter (:data:`fcomp.synthetic.catalogue.DIMENSIONS`):
forces scale with the friction level (x10), stiffnesses with level over
presliding length (x200), presliding lengths x1/20, pressure coefficients
with the inverse pressure level (x1/40), and so on (:attr:`Scale.factors`).
Dimensionless ratios and time constants stay: they are already relative to
the base level.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from fcomp.errors import FcompError


@dataclass(frozen=True)
class TruthParams:
    """Base friction and rig of the synthetic truth (SI).

    Attributes
    ----------
    Fc, Fs : N
        Coulomb and static levels (``Fs`` used by the ``stribeck`` and ``lugre`` bases).
    vs : m/s
        Stribeck velocity of the base curve (exponential, ``n = 2``).
    sigma0 : N/m
        Bristle stiffness (``lugre`` base).
    sigma1 : Ns/m
        Bristle damping (``lugre`` base).
    sigma2 : Ns/m
        Viscous coefficient (bases with a viscous term).
    mass : kg
        True moving mass.
    bore, rod, stroke : m
        Cylinder geometry (``A1 = pi/4*bore^2``, ``A2 = pi/4*(bore^2 - rod^2)``).
    """

    Fc: float = 30.0
    Fs: float = 45.0
    vs: float = 0.012
    sigma0: float = 2.0e5
    sigma1: float = 250.0
    sigma2: float = 60.0
    mass: float = 1.2
    bore: float = 0.032
    rod: float = 0.012
    stroke: float = 0.2

    @property
    def areas(self) -> tuple[float, float]:
        """Piston areas ``A1 = pi/4*bore^2`` and ``A2 = pi/4*(bore^2 - rod^2)`` (m^2).

        Written here on purpose, not taken from :mod:`fcomp.piston`: the generator is
        the independent reference of the reconstruction it tests (module docstring).
        """
        return math.pi / 4 * self.bore**2, math.pi / 4 * (self.bore**2 - self.rod**2)


@dataclass(frozen=True)
class Sensors:
    """Sensor characteristics of a rig (SI). Which of them a record uses depends on its style.

    Attributes
    ----------
    noise_std, noise_tau : N, s
        Force sensor (load cell) noise: AR(1), standard deviation and correlation time.
    resolution : m
        Encoder resolution (position quantum).
    pressure_noise : Pa
        White noise of each pressure transducer (standard deviation).
    pressure_lag : s
        First-order time constant of the pressure transducers (``pressures`` styles).
    tacho_white, tacho_coloured, tacho_tau : m/s, m/s, s
        Tachometer noise: white part, AR(1) part and the latter's correlation time.
    tacho_bias : m/s
        Tachometer offset (reads this at rest).
    tacho_gain : -
        Tachometer gain error: reads ``(1 + tacho_gain)*v``.
    tacho_lag : s
        First-order time constant of the tachometer.
    encoder_window : samples
        Encoder velocity: counts over this many sample intervals (1 = backward difference).
    encoder_jitter : m
        Vibration of the encoder read head (white, standard deviation) seen by the
        ``encoder-velocity`` style: near a count edge the count flickers even at rest.
    coarse : -
        Resolution multiplier of the ``coarse-encoder`` style.
    analog_noise : m
        White noise of an analog position sensor (``potentiometer`` styles).
    noise_color : str
        Spectrum of the force-channel noise (:data:`fcomp.synthetic.sensors.NOISE_COLORS`):
        ``"ar1"`` (the original generator's AR(1) of correlation time ``noise_tau``) or
        ``"pink"`` (1/f noise of the same standard deviation, on the load cell and, where
        the force comes from the pressures, on both pressure transducers;
        :func:`fcomp.synthetic.sensors.pink`).
    """

    noise_std: float
    noise_tau: float
    resolution: float
    pressure_noise: float
    pressure_lag: float
    tacho_white: float
    tacho_coloured: float
    tacho_tau: float
    tacho_bias: float
    tacho_gain: float
    tacho_lag: float
    encoder_window: int = 1
    encoder_jitter: float = 1.5e-7
    coarse: float = 15.0
    analog_noise: float = 2e-6
    noise_color: str = "ar1"


@dataclass(frozen=True)
class Scale:
    """A rig scale: base friction and rig, sensors, motion limits, effect-size factors.

    Attributes
    ----------
    name, kind
        Preset name and the sidecar ``kind`` of its cylinder.
    params
        Base friction and rig.
    pressures : Pa
        Pressure-sum levels ``p1 + p2`` (gauge) the experiments cycle through.
    sensors
        Default sensor characteristics.
    a_max : m/s^2
        Acceleration scale of the motion plans.
    loop_amplitude : m
        Range of the small displacement loops (presliding) of the motion plans.
    presliding_amplitude : m
        Range of the loop amplitudes of the presliding-dominated motion
        (``motion="presliding"``, :func:`fcomp.synthetic.motion.schedule_presliding`).
    factors
        Physical dimension -> factor on the effect defaults (pneumatic = 1).
    mass_range : kg
        Plausible moving masses (``vary``).
    resolutions : m
        Plausible encoder resolutions (``vary``).
    pressure_noise_range : Pa
        Plausible pressure-transducer noise (``vary``).
    """

    name: str
    kind: str
    params: TruthParams
    pressures: tuple[float, ...]
    sensors: Sensors
    a_max: float
    loop_amplitude: tuple[float, float]
    factors: Mapping[str, float] = field(default_factory=dict)
    mass_range: tuple[float, float] = (0.6, 2.5)
    resolutions: tuple[float, ...] = (5e-7, 1e-6, 2e-6, 5e-6)
    pressure_noise_range: tuple[float, float] = (150.0, 600.0)
    presliding_amplitude: tuple[float, float] = (1e-5, 2.5e-4)


PNEUMATIC = Scale(
    name="pneumatic", kind="pneumatic-cylinder", params=TruthParams(),
    pressures=(1.5e5, 3.0e5, 5.0e5),
    sensors=Sensors(noise_std=0.4, noise_tau=0.005, resolution=1e-6, pressure_noise=300.0,
                    pressure_lag=1e-3, tacho_white=1e-4, tacho_coloured=5e-5, tacho_tau=0.02,
                    tacho_bias=8e-5, tacho_gain=0.01, tacho_lag=2e-3),
    a_max=4.0, loop_amplitude=(2e-5, 3e-4),
)

#: Friction level ratio hydraulic/pneumatic (300 N / 30 N) and presliding-length ratio
#: (7.5 um / 150 um): the other factors follow from them.
_FORCE, _LENGTH, _PRESSURE = 10.0, 1.0 / 20.0, 40.0
HYDRAULIC = Scale(
    name="hydraulic", kind="hydraulic-cylinder",
    params=TruthParams(Fc=300.0, Fs=450.0, vs=0.01, sigma0=4.0e7, sigma1=3.0e3, sigma2=1.0e3,
                       mass=20.0, bore=0.04, rod=0.022, stroke=0.3),
    pressures=(6.0e6, 1.2e7, 2.4e7),
    sensors=Sensors(noise_std=3.0, noise_tau=0.003, resolution=5e-7, pressure_noise=5e3,
                    pressure_lag=1e-3, tacho_white=3e-4, tacho_coloured=1.5e-4, tacho_tau=0.02,
                    tacho_bias=1.5e-4, tacho_gain=0.01, tacho_lag=1.5e-3,
                    encoder_jitter=7.5e-8, analog_noise=1.5e-6),
    a_max=10.0, loop_amplitude=(3e-6, 8e-5),
    factors={"force": _FORCE, "damping": _FORCE, "stiffness": _FORCE / _LENGTH,
             "presliding-length": _LENGTH, "slide-length": 0.4,
             "per-pressure": 1.0 / _PRESSURE, "pressure": _PRESSURE,
             "mass-error": 8.0, "frequency": 2.5},
    mass_range=(10.0, 40.0), resolutions=(2.5e-7, 5e-7, 1e-6),
    pressure_noise_range=(4e3, 1e4), presliding_amplitude=(2.5e-6, 6e-5),
)

#: A miniature pneumatic cylinder (10/4 mm, 80 mm stroke, 0.15 kg): friction a tenth of
#: the pneumatic preset's, presliding a third, a finer load cell. Not in the matrix's
#: default scales: a check of magnitudes the diagnosis was not tuned on.
_SF, _SL = 0.1, 1.0 / 3.0
SMALL_PNEUMATIC = Scale(
    name="small-pneumatic", kind="pneumatic-cylinder",
    params=TruthParams(Fc=3.0, Fs=4.5, vs=0.015, sigma0=6.0e4, sigma1=50.0, sigma2=6.0,
                       mass=0.15, bore=0.010, rod=0.004, stroke=0.08),
    pressures=(1.5e5, 3.0e5, 5.0e5),
    sensors=Sensors(noise_std=0.04, noise_tau=0.005, resolution=1e-6, pressure_noise=300.0,
                    pressure_lag=1e-3, tacho_white=1e-4, tacho_coloured=5e-5, tacho_tau=0.02,
                    tacho_bias=8e-5, tacho_gain=0.01, tacho_lag=2e-3, analog_noise=1e-6),
    a_max=4.0, loop_amplitude=(1e-5, 1e-4),
    factors={"force": _SF, "damping": _SF, "stiffness": _SF / _SL,
             "presliding-length": _SL, "slide-length": 0.5,
             "per-pressure": 1.0, "pressure": 1.0, "mass-error": 0.125, "frequency": 1.6},
    mass_range=(0.08, 0.3), resolutions=(5e-7, 1e-6, 2e-6),
    pressure_noise_range=(150.0, 600.0), presliding_amplitude=(4e-6, 8e-5),
)

#: A heavy hydraulic cylinder (100/56 mm, 0.6 m stroke, 150 kg): friction about 70 times
#: the pneumatic preset's and presliding of 10 um. Not in the matrix's default scales.
_HF, _HL = 2000.0 / 30.0, 1.0 / 15.0
HEAVY_HYDRAULIC = Scale(
    name="heavy-hydraulic", kind="hydraulic-cylinder",
    params=TruthParams(Fc=2000.0, Fs=2800.0, vs=0.008, sigma0=2.0e8, sigma1=5.0e4,
                       sigma2=6.0e3, mass=150.0, bore=0.1, rod=0.056, stroke=0.6),
    pressures=(6.0e6, 1.4e7, 2.8e7),
    sensors=Sensors(noise_std=15.0, noise_tau=0.003, resolution=1e-6, pressure_noise=4e3,
                    pressure_lag=1e-3, tacho_white=3e-4, tacho_coloured=1.5e-4, tacho_tau=0.02,
                    tacho_bias=1.5e-4, tacho_gain=0.01, tacho_lag=1.5e-3,
                    encoder_jitter=7.5e-8, analog_noise=3e-6),
    a_max=5.0, loop_amplitude=(4e-6, 1e-4),
    factors={"force": _HF, "damping": _HF, "stiffness": _HF / _HL,
             "presliding-length": _HL, "slide-length": 0.4,
             "per-pressure": 1.0 / _PRESSURE, "pressure": _PRESSURE,
             "mass-error": 60.0, "frequency": 1.5},
    mass_range=(80.0, 300.0), resolutions=(5e-7, 1e-6, 2e-6),
    pressure_noise_range=(2e3, 8e3), presliding_amplitude=(4e-6, 1e-4),
)

#: The rig scales by name.
SCALES: dict[str, Scale] = {s.name: s for s in (PNEUMATIC, HYDRAULIC, SMALL_PNEUMATIC,
                                                HEAVY_HYDRAULIC)}


def get_scale(name: str) -> Scale:
    """The :class:`Scale` called ``name``."""
    try:
        return SCALES[name]
    except KeyError:
        raise FcompError(f"unknown scale {name!r}; known: {', '.join(SCALES)}") from None
