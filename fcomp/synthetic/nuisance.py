"""Nuisance variation (``vary=True``): plausible rigs around a scale's preset, seeded.

So that no detector threshold can be tuned to one set of numbers, every
record may get its own:

* base friction: ``Fc``, the hump ``Fs - Fc``, ``vs``, ``sigma0``, ``sigma1``,
  ``sigma2`` each times U(0.7, 1.3);
* moving mass: log-uniform in the scale's :attr:`~fcomp.synthetic.scales.Scale.mass_range`;
* hidden-effect magnitudes (the shape's :attr:`~fcomp.synthetic.catalogue.Shape.magnitude`
  parameters) times U(0.6, 1.5);
* sample rate: one of 500, 1000, 2000 Hz;
* encoder resolution: one of the scale's :attr:`~fcomp.synthetic.scales.Scale.resolutions`;
  encoder velocity window 1, 2 or 4 samples; coarse-encoder factor 10-20;
* force noise times U(0.6, 1.6), its correlation time log-uniform x0.5-2; pressure
  noise log-uniform in the scale's range, pressure-sensor lag 0.5-2 ms;
* tachometer: noise times U(0.6, 1.6), bias log-uniform 2e-5-2e-4 m/s (x2 at the
  hydraulic scale) of random sign, gain error U(-1.5 %, 1.5 %), lag 1-3 ms;
* analog position sensor: noise times log-uniform x0.5-2 (:func:`vary_analog`).

Arguments given explicitly to :func:`fcomp.synthetic.generate` are kept as
given. Every drawn value is returned for the truth
(:attr:`fcomp.synthetic.SyntheticTruth.nuisance`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from fcomp.synthetic.catalogue import Law
from fcomp.synthetic.scales import Scale, Sensors, TruthParams

#: Sample rates (Hz) drawn from.
RATES = (500.0, 1000.0, 2000.0)
#: Range of the factor on the base friction parameters and on the effect magnitudes.
BASE_RANGE = (0.7, 1.3)
MAGNITUDE_RANGE = (0.6, 1.5)


def _log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def vary_params(P: TruthParams, scale: Scale, rng: np.random.Generator
                ) -> tuple[TruthParams, dict[str, float]]:
    """Base friction jittered by +-30 % and a moving mass in the scale's range.

    Returns the parameters and the factors drawn (``factor.NAME``).
    """
    f = {k: float(rng.uniform(*BASE_RANGE)) for k in ("Fc", "hump", "vs", "sigma0", "sigma1",
                                                       "sigma2")}
    Fc = P.Fc * f["Fc"]
    varied = replace(P, Fc=Fc, Fs=Fc + (P.Fs - P.Fc) * f["hump"], vs=P.vs * f["vs"],
                     sigma0=P.sigma0 * f["sigma0"], sigma1=P.sigma1 * f["sigma1"],
                     sigma2=P.sigma2 * f["sigma2"], mass=_log_uniform(rng, *scale.mass_range))
    return varied, {f"factor.{k}": v for k, v in f.items()}


def vary_sensors(sens: Sensors, scale: Scale, rng: np.random.Generator) -> Sensors:
    """Sensor characteristics drawn around the scale's (see the module docstring)."""
    big = 2.0 if scale.kind == "hydraulic-cylinder" else 1.0
    noise = float(rng.uniform(0.6, 1.6))
    tacho = float(rng.uniform(0.6, 1.6))
    return replace(
        sens,
        noise_std=sens.noise_std * noise,
        noise_tau=sens.noise_tau * _log_uniform(rng, 0.5, 2.0),
        resolution=float(rng.choice(scale.resolutions)),
        pressure_noise=_log_uniform(rng, *scale.pressure_noise_range),
        pressure_lag=float(rng.uniform(5e-4, 2e-3)),
        tacho_white=sens.tacho_white * tacho,
        tacho_coloured=sens.tacho_coloured * tacho,
        tacho_tau=sens.tacho_tau * _log_uniform(rng, 0.5, 2.0),
        tacho_bias=big * _log_uniform(rng, 2e-5, 2e-4) * float(rng.choice((-1.0, 1.0))),
        tacho_gain=float(rng.uniform(-0.015, 0.015)),
        tacho_lag=float(rng.uniform(1e-3, 3e-3)),
        encoder_window=int(rng.choice((1, 2, 4))),
        coarse=float(rng.uniform(10.0, 20.0)),
    )


def vary_analog(sens: Sensors, rng: np.random.Generator) -> Sensors:
    """An analog position sensor's noise times log-uniform x0.5-2 (its own stream, so the
    records of the other styles stay those of their seed)."""
    return replace(sens, analog_noise=sens.analog_noise * _log_uniform(rng, 0.5, 2.0))


def vary_laws(laws: dict[str, Law], rng: np.random.Generator) -> tuple[dict[str, Law],
                                                                        dict[str, float]]:
    """Effect magnitudes times U(0.6, 1.5); returns the new laws and the factors drawn."""
    out: dict[str, Law] = {}
    drawn: dict[str, float] = {}
    for effect, law in laws.items():
        k = float(rng.uniform(*MAGNITUDE_RANGE))
        drawn[f"magnitude.{effect}"] = k
        params = {p: v * k if p in law.shape.magnitude else v for p, v in law.params.items()}
        out[effect] = Law(law.shape, params)
    return out, drawn

