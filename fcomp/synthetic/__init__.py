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
to. Conditions beyond those: a logger's irregular or gapped stamps
(``stamps``), a periodic disturbance (``pulsation``), pink force noise
(``noise_color``), a vertical rig (``orientation``), a presliding-dominated
motion (``motion="presliding"``) and a soft seal (``bristle``); the
diagnosis matrix crosses its cases with them (:mod:`fcomp.synthetic.matrix`).

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
:mod:`~fcomp.synthetic.matrix`
    the diagnosis matrix: cases (rows x kinds x styles x scales x conditions x
    seeds) and the judge of a diagnosis JSON.

Example
-------
>>> rec = generate(["stribeck:lorentzian"], scale="hydraulic", style="pressures",
...                vary=True, seed=3, name="case-3")            # doctest: +SKIP
>>> rec.measurement.write("case-3.csv")                          # doctest: +SKIP
>>> rec.truth.describe()["hidden"]                               # doctest: +SKIP
'stribeck:lorentzian'
"""

from __future__ import annotations

import math
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
from fcomp.synthetic.laws import G, recording_errors
from fcomp.synthetic.motion import MOTIONS, Motion, plan_record
from fcomp.synthetic.records import SyntheticRecord, SyntheticTruth
from fcomp.synthetic.scales import SCALES, Scale, Sensors, TruthParams, get_scale
from fcomp.synthetic.sensors import (
    NOISE_COLORS,
    STYLES,
    FineSignals,
    Style,
    get_style,
    measure,
    position_step,
)

__all__ = [
    "BASES", "CATALOGUE", "DIMENSIONS", "HIDDEN_DEFAULTS", "MOTIONS", "NOISE_COLORS",
    "ORIENTATIONS", "OUTSIDE", "SCALES", "SHAPES", "STAMPS", "STYLES", "Law", "Scale", "Sensors", "Shape", "Style", "SyntheticRecord", "SyntheticTruth",
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
    stamps: str = "uniform",
    pulsation: tuple[float, float] | None = None,
    noise_color: str | None = None,
    orientation: str = "horizontal",
    motion: str = "standard",
    bristle: float | None = None,
    plan: Motion | None = None,
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
    stamps
        How the logger stamps its samples (:data:`STAMPS`): ``"uniform"``;
        ``"irregular"``, intervals of 0.5, 1 and 1.5 nominal intervals drawn at random
        (exact stamps of a logger polled by a non-real-time task); ``"gapped"``, uniform
        with logger pauses of 0.2-0.6 s inside every experiment; ``"jitter"``, every
        interval the nominal one times a log-normal factor (a scheduler's jitter, 35 %
        spread, down to a tenth of the nominal interval); ``"bursts"``, samples taken in
        bursts of 4-16 at a tenth to a fifth of the nominal interval and a wait between
        bursts, the mean rate nominal (a buffered or polled acquisition whose true sample
        times are stamped: most intervals far shorter than the mean); ``"drops"``, uniform
        with 2 % of the samples lost singly and runs of 5-15 lost samples (a logger that
        misses samples under load, shorter than a pause).
    pulsation
        ``(frequency Hz, amplitude N)``: a periodic disturbance unrelated to the motion
        (a pump's pulsation, mains hum) on the force channel -- on the load cell, or on
        ``p1`` (amplitude divided by the bore area) when the force comes from the
        pressures -- with a random phase. Not part of the truth ``F``.
    noise_color
        Spectrum of the force-channel noise (overrides :attr:`Sensors.noise_color`):
        ``"ar1"`` (the default: AR(1), ``noise_tau``) or ``"pink"`` (1/f noise of the
        same standard deviation by spectral shaping of white noise,
        :func:`fcomp.synthetic.sensors.pink`; with the ``pressures`` styles on both
        pressure transducers, whose noise is otherwise white).
    orientation
        How the cylinder is mounted (:data:`ORIENTATIONS`, the sidecar's
        ``rig.orientation``): ``"horizontal"``; ``"vertical-up"`` (``"vertical"``), extending
        upward, so the weight ``m*g`` of the moving mass opposes extension (``s = +1``);
        ``"vertical-down"`` (``s = -1``). The chamber pressures and a drive force balance
        friction + ``m*a`` + ``m*g*s``; a load cell measures the friction as before. With
        a wrong sidecar mass (``inertia-error``) the tool subtracts a wrong weight too:
        for the styles whose force comes from a balance, ``truth.F`` carries ``dm*g*s``.
    motion
        Motion plan (:data:`fcomp.synthetic.motion.MOTIONS`): ``"standard"`` or
        ``"presliding"`` -- many small displacement cycles (amplitudes in the scale's
        :attr:`Scale.presliding_amplitude`, 10-250 um pneumatic) at 0.5-8 Hz and only
        a few slides of about 20 mm (:func:`fcomp.synthetic.motion.schedule_presliding`).
    bristle
        Presliding stiffness of the seal (N/m), kept as given (after ``vary``): the LuGre
        base's ``sigma0``, with ``sigma1`` times ``sqrt(bristle/sigma0)`` (the same
        damping ratio), and every hidden law parameter of dimension ``stiffness``
        (:data:`DIMENSIONS`: presliding ``k``) set to it, those of dimension
        ``presliding-length`` (Maxwell-slip ``d_max``) divided by ``bristle/sigma0``. A
        soft seal: ``bristle=1.5e4`` on the pneumatic rig (a 25 mm pneumatic seal, a
        presliding range ``Fc/sigma0`` of 2 mm instead of 0.15 mm).

    plan
        A given fine-grid motion (:class:`fcomp.synthetic.motion.Motion`, e.g. a designed
        programme recorded: :func:`fcomp.synthetic.motion.along`) instead of the scheduled
        one; ``experiments``, ``duration`` and ``motion`` are then not used.

    The default arguments give the original generator's record, bit for bit.
    """
    if experiments < 1 or duration <= 0 or (rate is not None and rate <= 0) or fine < 1:
        raise FcompError("experiments, duration, rate and fine must be positive")
    if stamps not in STAMPS:
        raise FcompError(f"unknown stamps {stamps!r}; known: {', '.join(STAMPS)}")
    orient = ORIENTATION_ALIASES.get(orientation, orientation)
    if orient not in ORIENTATIONS:
        raise FcompError(f"unknown orientation {orientation!r}; known: "
                         f"{', '.join([*ORIENTATIONS, *ORIENTATION_ALIASES])}")
    if noise_color is not None and noise_color not in NOISE_COLORS:
        raise FcompError(f"unknown noise colour {noise_color!r}; known: "
                         f"{', '.join(NOISE_COLORS)}")
    if motion not in MOTIONS:
        raise FcompError(f"unknown motion {motion!r}; known: {', '.join(MOTIONS)}")
    if bristle is not None and not (math.isfinite(bristle) and bristle > 0):
        raise FcompError(f"bristle must be a positive stiffness (N/m), got {bristle!r}")
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
    if bristle is not None:
        P, laws = soften(P, laws, float(bristle))
    given: dict[str, Any] = {"noise_std": noise_std, "noise_tau": noise_tau,
                             "resolution": resolution, "pressure_noise": pressure_noise}
    overrides: dict[str, Any] = {k: float(v) for k, v in given.items() if v is not None}
    if noise_color is not None:
        overrides["noise_color"] = noise_color
    sens = replace(sens, **overrides)
    if sens.noise_color not in NOISE_COLORS:
        raise FcompError(f"unknown noise colour {sens.noise_color!r}; known: "
                         f"{', '.join(NOISE_COLORS)}")
    rate = 500.0 if rate is None else float(rate)
    levels = list(sc.pressures if pressures is None else pressures)
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate / fine
    if plan is None:
        plan = plan_record(rng, experiments=experiments, duration=duration, dt=dt,
                           stroke=P.stroke, levels=levels, a_max=sc.a_max,
                           loop_amplitude=sc.loop_amplitude, motion=motion,
                           presliding_amplitude=sc.presliding_amplitude)
    elif abs(plan.dt - dt) > 1e-9 * dt:
        raise FcompError(f"the given plan's fine step {plan.dt:g} s is not 1/(rate*fine) = "
                         f"{dt:g} s")
    S_mid = float(np.mean(levels))
    # friction: the state is carried from experiment to experiment (same rig, same seal)
    gravity = G * ORIENTATIONS[orient]  # g*s: the weight m*g*s opposes extension
    fric, vn, an = truth_friction(P, base, laws, plan.t, plan.v, plan.a, plan.x,
                                  plan.S, dt, S_mid, weight=P.mass * gravity)
    channel, physical = recording_errors(laws, plan.t, plan.v, an, P.mass)
    recorded = fric.copy()
    for term in channel:
        recorded += term
    phys = None
    if physical:
        phys = np.sum(physical, axis=0)
        recorded += phys
    dm = laws["inertia-error"]["dm"] if "inertia-error" in laws else 0.0
    mass_sidecar = float(max(P.mass - dm, 0.0))
    if gravity != 0.0 and st.force != "load-cell" and mass_sidecar != P.mass:
        recorded += (P.mass - mass_sidecar) * gravity  # the tool subtracts the wrong weight
    sig = FineSignals(t=plan.t, x=plan.x, v=vn, a=an, S=plan.S,
                      experiment=plan.experiment, friction=fric, recorded=recorded,
                      physical=phys, dt=dt,
                      idx=sample_indices(stamps, plan.t.size, fine, plan.experiment,
                                         rate, np.random.default_rng([seed, 4])))
    rec = measure(st, sens, sig, P, mass_sidecar, rate, include_velocity, rng,
                  np.random.default_rng([seed, 2]), gravity=gravity)
    if pulsation is not None:
        _pulsate(rec.columns, st, P, pulsation, np.random.default_rng([seed, 5]))
    meta = _sidecar(st, sc, P, mass_sidecar, laws, name, seed, rate, position_step(st, sens, P),
                    orient)
    idx = sig.idx
    truth = SyntheticTruth(
        F=recorded[idx], friction=fric[idx], v=vn[idx], a=an[idx], noise=rec.noise, base=base,
        hidden={e: law.params for e, law in laws.items()}, params=P, noise_std=rec.noise_std,
        shapes={e: law.shape.name for e, law in laws.items()}, scale=sc.name, style=st.name,
        rate=rate, sensors=sens, nuisance=drawn, orientation=orient, motion=motion)
    return SyntheticRecord(Measurement(rec.columns, meta), truth)


#: Mounting -> ``s`` of the weight ``m*g*s`` opposing extension (:func:`generate`'s
#: ``orientation``; written here from data-format.md's definition, not imported).
ORIENTATIONS = {"horizontal": 0.0, "vertical-up": 1.0, "vertical-down": -1.0}
#: Other names :func:`generate` takes for an orientation.
ORIENTATION_ALIASES = {"vertical": "vertical-up"}


def soften(P: TruthParams, laws: Mapping[str, Law], bristle: float
           ) -> tuple[TruthParams, dict[str, Law]]:
    """Base and laws with the presliding stiffness ``bristle`` (N/m, :func:`generate`'s
    ``bristle``): ``sigma0 = bristle``, ``sigma1`` times ``sqrt(bristle/sigma0)``;
    law parameters of dimension ``stiffness`` set to ``bristle``, of dimension
    ``presliding-length`` divided by ``bristle/sigma0``."""
    r = bristle / P.sigma0
    out: dict[str, Law] = {}
    for effect, law in laws.items():
        params = dict(law.params)
        for k, v in law.params.items():
            dim = DIMENSIONS.get(k)
            if dim == "stiffness":
                params[k] = bristle
            elif dim == "presliding-length":
                params[k] = v / r
        out[effect] = Law(law.shape, params)
    return replace(P, sigma0=bristle, sigma1=P.sigma1 * math.sqrt(r)), out


#: The logger's stamping (:func:`generate`'s ``stamps``).
STAMPS = ("uniform", "irregular", "gapped", "jitter", "bursts", "drops")
#: Spread (standard deviation of the log) of a ``"jitter"`` logger's intervals.
JITTER_SPREAD = 0.35
#: Samples per burst and their spacing (nominal intervals) of a ``"bursts"`` logger.
BURST_SIZE = (4, 16)
BURST_SPACING = (0.1, 0.2)
#: Share of single lost samples, and the runs of lost samples (count, length), of ``"drops"``.
DROP_SHARE = 0.02
DROP_RUNS = (3, (5, 15))
#: Length (s) of the logger pauses of ``stamps="gapped"``, drawn uniformly.
GAP_SPAN = (0.2, 0.6)


def sample_indices(stamps: str, n_fine: int, fine: int, experiment: np.ndarray, rate: float,
                   rng: np.random.Generator) -> np.ndarray:
    """Fine-grid indices of the recorded samples (:func:`generate`'s ``stamps``).

    ``"irregular"`` draws each interval from 0.5, 1 and 1.5 nominal intervals
    (``fine`` even: exact on the fine grid; odd: rounded), ``"gapped"`` drops one
    pause of :data:`GAP_SPAN` from the middle half of every experiment at least
    four pauses long. Uniform stamps are ``arange(0, n_fine, fine)``, bit for bit.
    """
    uniform = np.arange(0, n_fine, fine)
    if stamps == "uniform":
        return uniform
    if stamps == "jitter":  # each interval the nominal times a log-normal factor, >= 1 fine step
        steps = np.maximum(np.rint(fine * np.exp(rng.normal(0.0, JITTER_SPREAD,
                                                            2 * n_fine // fine + 2))), 1)
        idx = np.concatenate([[0], np.cumsum(steps.astype(int))])
        return idx[idx < n_fine]
    if stamps == "bursts":  # bursts at a fast clock, a wait between: the mean rate nominal
        out, k = [], 0
        while k < n_fine:
            size = int(rng.integers(BURST_SIZE[0], BURST_SIZE[1] + 1))
            gap = max(1, int(round(fine * rng.uniform(*BURST_SPACING))))
            out += [k + j * gap for j in range(size)]
            k += size * fine
        idx = np.array(out)
        return idx[idx < n_fine]
    if stamps == "drops":  # single lost samples and a few short runs of them
        keep = rng.random(uniform.size) >= DROP_SHARE
        count, (lo, hi) = DROP_RUNS
        for e in np.unique(experiment[uniform]):
            where = np.flatnonzero(experiment[uniform] == e)
            for _ in range(count):
                length = int(rng.integers(lo, hi + 1))
                if where.size > 4 * length:
                    a = int(rng.integers(where.size // 8, where.size - length))
                    keep[where[a:a + length]] = False
        keep[0] = True
        return uniform[keep]
    if stamps == "irregular":
        half = max(fine // 2, 1)
        steps = rng.choice([half, fine, fine + half], size=2 * n_fine // fine + 2)
        idx = np.concatenate([[0], np.cumsum(steps)])
        return idx[idx < n_fine]
    keep = np.ones(uniform.size, dtype=bool)
    ex = experiment[uniform]
    for e in np.unique(ex):
        where = np.flatnonzero(ex == e)
        gap = int(round(rng.uniform(*GAP_SPAN) * rate))
        if where.size < 4 * gap:
            continue
        lo = int(rng.integers(where.size // 4, 3 * where.size // 4 - gap))
        keep[where[lo:lo + gap]] = False
    return uniform[keep]


def _pulsation_force(t: np.ndarray, pulsation: tuple[float, float],
                     rng: np.random.Generator) -> np.ndarray:
    freq, amp = pulsation
    if not (freq > 0 and amp >= 0):
        raise FcompError(f"pulsation needs a positive frequency and an amplitude >= 0, "
                         f"got {pulsation!r}")
    return amp * np.sin(2.0 * np.pi * freq * t + rng.uniform(0.0, 2.0 * np.pi))


def _pulsate(cols: dict[str, np.ndarray], style: Style, P: TruthParams,
             pulsation: tuple[float, float], rng: np.random.Generator) -> None:
    """Add the periodic disturbance to the force channel of ``style`` (in place)."""
    wave = _pulsation_force(cols["t"], pulsation, rng)
    if style.force == "pressures":
        cols["p1"] = cols["p1"] + wave / P.areas[0]
    else:
        key = "F" if style.force == "load-cell" else "F_ext"
        cols[key] = cols[key] + wave


def _sidecar(style: Style, scale: Scale, P: TruthParams, mass: float, laws: Mapping[str, Law],
             name: str | None, seed: int, rate: float, resolution: float,
             orientation: str = "horizontal") -> dict[str, Any]:
    """The sidecar a user of this rig would write (no truth in it, except a default name)."""
    if style.force == "drive":
        kind = "friction-rig"
        rig: dict[str, Any] = {"stroke": P.stroke, "mass": mass, "orientation": orientation}
    else:
        kind = scale.kind
        rig = {"bore": P.bore, "rod": P.rod, "stroke": P.stroke, "mass": mass,
               "orientation": orientation}
    return {
        "name": name or "synthetic-" + ("-".join(laws) if laws else "none"),
        "kind": kind,
        "pressure": "gauge",
        "rig": rig,
        "synthetic": {"generator": "fcomp.synthetic", "seed": int(seed), "rate": float(rate),
                      "position_resolution": float(resolution)},
    }
