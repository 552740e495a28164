"""Synthetic rig measurements with hidden effects: the test bench of the diagnosis.

The generator is *independent* of the code it tests: it never imports
:mod:`fcomp.models`, :mod:`fcomp.effects`, :mod:`fcomp.trajectory`,
:mod:`fcomp.identification`, :mod:`fcomp.diagnosis` or
:mod:`fcomp.reconstruction`, and integrates its own truth friction on a
fine time grid, driven by an analytic motion. Every hidden effect has
several *shapes* (laws; :data:`SHAPES`, the first being the original
generator's), and records come at two rig scales (:data:`SCALES`) in seven
measurement styles (:data:`STYLES`), optionally with nuisance variation
(``vary=True``), so that a diagnosis can be tested on data it was not tuned
to.

Modules
-------
:mod:`~fcomp.synthetic.catalogue`
    effects, shapes and their default parameters (``"effect:shape"`` names).
:mod:`~fcomp.synthetic.laws`, :mod:`~fcomp.synthetic.dynamics`
    the laws: static maps and level factors; states integrated exactly.
:mod:`~fcomp.synthetic.friction`
    the bases and the assembly of the truth friction (:func:`truth_friction`).
:mod:`~fcomp.synthetic.motion`
    motion plans: slides over two decades of speed, reversals with and without
    a stop, dwells of 0.05-3 s, presliding loops, sweeps, pressure changes.
:mod:`~fcomp.synthetic.scales`
    the ``pneumatic`` and ``hydraulic`` rigs, their sensors and effect sizes.
:mod:`~fcomp.synthetic.sensors`
    the measurement styles.
:mod:`~fcomp.synthetic.nuisance`
    the variation drawn with ``vary=True``.

Example
-------
>>> rec = generate(["stribeck:lorentzian"], scale="hydraulic", style="pressures",
...                vary=True, seed=3, name="case-3")            # doctest: +SKIP
>>> rec.measurement.write("case-3.csv")                          # doctest: +SKIP
>>> rec.truth.describe()["hidden"]                               # doctest: +SKIP
'stribeck:lorentzian'
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from fcomp.errors import FcompError
from fcomp.measurement import Measurement
from fcomp.synthetic import nuisance
from fcomp.synthetic.catalogue import (
    CATALOGUE,
    DIMENSIONS,
    HIDDEN_DEFAULTS,
    OUTSIDE,
    SHAPES,
    Law,
    Shape,
    effect_shapes,
    resolve,
)
from fcomp.synthetic.friction import BASES, check_compatible, truth_friction
from fcomp.synthetic.laws import recording_errors
from fcomp.synthetic.motion import plan_record
from fcomp.synthetic.records import SyntheticRecord, SyntheticTruth
from fcomp.synthetic.scales import SCALES, Scale, Sensors, TruthParams, get_scale
from fcomp.synthetic.sensors import (
    STYLES,
    FineSignals,
    Style,
    get_style,
    measure,
    position_step,
)

__all__ = [
    "BASES", "CATALOGUE", "DIMENSIONS", "HIDDEN_DEFAULTS", "OUTSIDE", "SCALES", "SHAPES",
    "STYLES", "Law", "Scale", "Sensors", "Shape", "Style", "SyntheticRecord", "SyntheticTruth",
    "TruthParams", "effect_shapes", "generate", "truth_friction",
]


def generate(
    hidden: Sequence[str] | Mapping[str, Mapping[str, float]] = (),
    *,
    base: str = "lugre",
    params: TruthParams | None = None,
    experiments: int = 3,
    duration: float = 12.0,
    rate: float | None = None,
    pressures: Sequence[float] | None = None,
    noise_std: float | None = None,
    noise_tau: float | None = None,
    resolution: float | None = None,
    pressure_noise: float | None = None,
    include_velocity: bool = False,
    seed: int = 0,
    fine: int = 10,
    scale: str = "pneumatic",
    style: str = "load-cell",
    vary: bool = False,
    sensors: Sensors | None = None,
    name: str | None = None,
) -> SyntheticRecord:
    """A synthetic rig measurement with ``hidden`` effects.

    Parameters
    ----------
    hidden
        Hidden effects as ``"effect"`` (its first shape) or ``"effect:shape"``
        (:data:`SHAPES`), or a mapping of them to law-parameter overrides
        (:data:`CATALOGUE` lists every shape's parameters; defaults are carried to
        the scale by :data:`DIMENSIONS`, overrides are taken as given).
    base
        Base friction law: one of :data:`BASES`.
    params
        Base friction and rig parameters (default: the scale's; not varied if given).
    experiments
        Number of experiments (each at its own pressure levels).
    duration
        Total recorded duration (s), shared among the experiments.
    rate
        Sample rate (Hz); default 500, or drawn from 500/1000/2000 with ``vary``.
    pressures
        Pressure-sum levels ``p1 + p2`` (gauge, Pa) the experiments cycle through
        (default: the scale's).
    noise_std, noise_tau
        Standard deviation (N) and correlation time (s) of the AR(1) force noise.
    resolution
        Position quantisation (encoder resolution, m).
    pressure_noise
        White noise on each pressure sensor (Pa, standard deviation).
    include_velocity
        Also write the exact velocity column ``v`` (styles without a velocity sensor).
    seed
        Random seed (motions, noise, and with ``vary`` the nuisance draws).
    fine
        Integration sub-steps per sample interval.
    scale
        Rig scale: ``"pneumatic"``, ``"hydraulic"``, ``"small-pneumatic"`` or
        ``"heavy-hydraulic"`` (:data:`SCALES`).
    style
        Measurement style (:data:`STYLES`).
    vary
        Draw nuisance values around the scale's preset (:mod:`fcomp.synthetic.nuisance`);
        the sensor and noise arguments above, when given, are kept as given.
    sensors
        Sensor characteristics (default: the scale's); the sensor arguments above
        override single fields.
    name
        The record's name in the sidecar (default ``synthetic-EFFECTS``, which names the
        hidden effects: pass a neutral name for blind benchmarks).

    The default arguments give the original generator's record, bit for bit.
    """
    if experiments < 1 or duration <= 0 or (rate is not None and rate <= 0) or fine < 1:
        raise FcompError("experiments, duration, rate and fine must be positive")
    sc = get_scale(scale)
    st = get_style(style, include_velocity)
    laws = resolve(hidden, sc.factors)
    check_compatible(base, laws)
    P = params or sc.params
    sens = sensors or sc.sensors
    drawn: dict[str, float] = {}
    if vary:  # its own random stream: the motion and noise stay those of the seed
        rng_vary = np.random.default_rng([seed, 1])
        if params is None:
            P, drawn = nuisance.vary_params(P, sc, rng_vary)
        if sensors is None:
            sens = nuisance.vary_sensors(sens, sc, rng_vary)
            if st.analog:
                sens = nuisance.vary_analog(sens, np.random.default_rng([seed, 3]))
        if rate is None:
            rate = float(rng_vary.choice(nuisance.RATES))
        laws, factors = nuisance.vary_laws(laws, rng_vary)
        drawn.update(factors)
        drawn["rate"] = float(rate)
    given: dict[str, Any] = {"noise_std": noise_std, "noise_tau": noise_tau,
                             "resolution": resolution, "pressure_noise": pressure_noise}
    overrides: dict[str, Any] = {k: float(v) for k, v in given.items() if v is not None}
    sens = replace(sens, **overrides)
    rate = 500.0 if rate is None else float(rate)
    levels = list(sc.pressures if pressures is None else pressures)
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate / fine
    motion = plan_record(rng, experiments=experiments, duration=duration, dt=dt,
                         stroke=P.stroke, levels=levels, a_max=sc.a_max,
                         loop_amplitude=sc.loop_amplitude)
    S_mid = float(np.mean(levels))
    # friction: the state is carried from experiment to experiment (same rig, same seal)
    fric, vn, an = truth_friction(P, base, laws, motion.t, motion.v, motion.a, motion.x,
                                  motion.S, dt, S_mid)
    channel, physical = recording_errors(laws, motion.t, motion.v, an, P.mass)
    recorded = fric.copy()
    for term in channel:
        recorded += term
    phys = None
    if physical:
        phys = np.sum(physical, axis=0)
        recorded += phys
    dm = laws["inertia-error"]["dm"] if "inertia-error" in laws else 0.0
    mass_sidecar = float(max(P.mass - dm, 0.0))
    sig = FineSignals(t=motion.t, x=motion.x, v=vn, a=an, S=motion.S,
                      experiment=motion.experiment, friction=fric, recorded=recorded,
                      physical=phys, dt=dt, idx=np.arange(0, motion.t.size, fine))
    rec = measure(st, sens, sig, P, mass_sidecar, rate, include_velocity, rng,
                  np.random.default_rng([seed, 2]))
    meta = _sidecar(st, sc, P, mass_sidecar, laws, name, seed, rate, position_step(st, sens, P))
    idx = sig.idx
    truth = SyntheticTruth(
        F=recorded[idx], friction=fric[idx], v=vn[idx], a=an[idx], noise=rec.noise, base=base,
        hidden={e: law.params for e, law in laws.items()}, params=P, noise_std=rec.noise_std,
        shapes={e: law.shape.name for e, law in laws.items()}, scale=sc.name, style=st.name,
        rate=rate, sensors=sens, nuisance=drawn)
    return SyntheticRecord(Measurement(rec.columns, meta), truth)


def _sidecar(style: Style, scale: Scale, P: TruthParams, mass: float, laws: Mapping[str, Law],
             name: str | None, seed: int, rate: float, resolution: float) -> dict[str, Any]:
    """The sidecar a user of this rig would write (no truth in it, except a default name)."""
    if style.force == "drive":
        kind = "friction-rig"
        rig: dict[str, Any] = {"stroke": P.stroke, "mass": mass, "orientation": "horizontal"}
    else:
        kind = scale.kind
        rig = {"bore": P.bore, "rod": P.rod, "stroke": P.stroke, "mass": mass,
               "orientation": "horizontal"}
    return {
        "name": name or "synthetic-" + ("-".join(laws) if laws else "none"),
        "kind": kind,
        "pressure": "gauge",
        "rig": rig,
        "synthetic": {"generator": "fcomp.synthetic", "seed": int(seed), "rate": float(rate),
                      "position_resolution": float(resolution)},
    }
