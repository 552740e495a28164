"""The records a diagnosis works on: experiments, signals, the force to match, and data scales.

A diagnosis reads one or several measurements. Each is cut into
*experiments* -- runs whose friction states start afresh -- where its
``experiment`` column changes (a user column, data-format.md keeps it) and at
time gaps longer than :data:`GAP_FACTOR` sample intervals (:func:`fcomp.reconstruction.sampling_interval`; a logger's
pause, inside a labelled experiment too). Per experiment the force to match and the motion come from
:func:`fcomp.identification.target.fit_data` (a measured ``F``; else the
friction reconstructed as ``p1*A1 - p2*A2 - m*a + F_ext``, models.md 2; else
the driving force with the mass fitted). Velocity and acceleration missing
from the file are derived from ``x`` by the zero-phase filter of
:mod:`fcomp.reconstruction` with a cutoff set from the sample rate
(:func:`default_cutoff`), so that presliding transients of a few
milliseconds are not smeared.

*Steady-state* records (sidecar ``[diagnosis] samples = "steady-state"``)
hold independent steady-state points (each row a force at a constant
velocity, e.g. the tables of seed 001) rather than a motion; only static
models and memoryless effects can be compared with them.

:class:`~fcomp.conditioning.Scales` (defined with the signal conditioning, below
the effects, whose diagnosis hooks read it; importable from here too) holds the
magnitudes every threshold and bound of the diagnosis is derived from (force,
speed, acceleration, stroke, pressure, position resolution), so nothing is tuned
to one rig.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

import fcomp.diagnosis.pauses as pauses
from fcomp.conditioning import (
    Conditioning,
    Motion,
    Scales,
    condition_motion,
    force_cutoff,
    motion_ensemble,
    resolution,
    rest_noise,
    sample_rate,
)
from fcomp.errors import FcompError
from fcomp.identification.plausibility import RigContext
from fcomp.identification.target import FitData, fit_data
from fcomp.measurement import Measurement
from fcomp.reconstruction import driving_force, interval_of, sampling_interval

#: A time step longer than this many median steps starts a new experiment.
GAP_FACTOR = 20.0
#: Fewest samples an experiment must have.
MIN_SAMPLES = 20
STEADY_STATE = "steady-state"


@dataclass(frozen=True)
class Experiment:
    """One experiment: its fit data, its place in the concatenated arrays, alternative
    motions as consistent with its measured position (:func:`fcomp.conditioning.motion_ensemble`),
    the samples inserted across a logger's pause (:mod:`.pauses`; None: none), and the
    experiment of the record's design it is a piece of (``design``: the pieces of one file
    cut at logger pauses share it, whether or not a pause is bridged; -1: its own)."""

    label: str
    data: FitData
    start: int
    stop: int
    alternatives: tuple[Motion, ...] = ()
    bridged: np.ndarray | None = None
    design: int = -1

    @property
    def n(self) -> int:
        return self.stop - self.start

    @cached_property
    def digest(self) -> str:
        """A digest of the experiment's stamps, motion and force (:func:`content_digest`):
        what choices that must not depend on names or order (the held-out blocks, the
        sessions) are keyed on."""
        s = self.data.sig
        return content_digest(s["t"], s["x"], s["v"], self.data.y)


@dataclass
class DiagnosisData:
    """All experiments of a diagnosis, with the signals they hold and their scales.

    Attributes
    ----------
    experiments
        The experiments, in the order given.
    available
        Signal name -> whether it is measured and informative: ``"x"``
        (measured position), ``"p1"``/``"p2"`` (measured, ``p1 + p2`` varies).
    reasons
        Signal name -> why it is not available (for the report).
    scales
        The data scales.
    steady_state
        Whether the samples are independent steady-state points.
    source
        Where the force came from (``"F"``, ``"reconstructed"``, ``"driving-force"``).
    labels
        Experiment labels.
    signals
        Per measurement file: how its motion was conditioned
        (:class:`fcomp.conditioning.Conditioning`); empty for steady-state points.
    rig
        What the (first) record's sidecar says about the rig (kind, mass,
        geometry), for the plausibility of fits.
    kind
        The rig kind of the (first) record's sidecar (``""`` if not given): it words
        the experiments advised (:func:`fcomp.effects.experiment_for`).
    force_channels
        The measured columns the force to match is made of, in every record:
        ``("F",)`` for a force column, else those of ``p1``, ``p2``, ``F_ext``
        (:func:`fcomp.reconstruction.driving_force`).
    """

    experiments: list[Experiment]
    available: dict[str, bool]
    reasons: dict[str, str]
    scales: Scales
    steady_state: bool
    source: str
    labels: list[str] = field(default_factory=list)
    signals: list[Conditioning] = field(default_factory=list)
    kind: str = ""
    rig: RigContext = field(default_factory=RigContext)
    force_channels: tuple[str, ...] = ()

    @property
    def n(self) -> int:
        return self.experiments[-1].stop

    @property
    def fits_mass(self) -> bool:
        """Whether the mass is fitted (driving-force data without a known mass)."""
        return self.experiments[0].data.inertia is not None

    @property
    def fits_lag(self) -> bool:
        """Whether the lag of the force channel is fitted: every record's force is a
        driving force (pressures, ``F_ext``) through the parallel filtering."""
        return all(e.data.drive_rate is not None for e in self.experiments)

    def signal(self, name: str) -> np.ndarray:
        """A signal (``t``, ``v``, ``a``, ``x``, ``p1``, ``p2``, ``s``) concatenated over experiments."""
        return np.concatenate([e.data.sig[name] for e in self.experiments])

    @property
    def y(self) -> np.ndarray:
        """The force to match (N), concatenated."""
        return np.concatenate([e.data.y for e in self.experiments])

    @property
    def bridged(self) -> np.ndarray:
        """The samples inserted across logger pauses (:mod:`.pauses`), concatenated: in no
        fit, score, noise floor or spectrum."""
        return np.concatenate([np.zeros(e.n, dtype=bool) if e.bridged is None else e.bridged
                               for e in self.experiments])

    def experiment_index(self) -> np.ndarray:
        """Experiment number (0-based) of every sample."""
        return np.concatenate([np.full(e.n, i) for i, e in enumerate(self.experiments)])


def _cut(meas: Measurement) -> list[tuple[Measurement, np.ndarray, int]]:
    """Experiments of one measurement, each with its bridged samples and the number of the
    experiment of the record's design it belongs to (the runs between changes of the
    ``experiment`` column; a logger's pause never starts one): cut where the
    ``experiment`` column changes, and at long time gaps -- a logger's pause inside a
    labelled experiment too -- unless the motion on both sides shows what the piston did
    through it (a rest, or a slide one way: the pause is bridged, :mod:`.pauses`); across
    any other pause the piston's motion is unknown, so the friction states start afresh
    after it."""
    t = meas.t
    interval = sampling_interval(t)
    labels = np.diff(meas["experiment"]) != 0 if "experiment" in meas else \
        np.zeros(max(len(meas) - 1, 0), dtype=bool)
    pause = np.append((np.diff(t) > GAP_FACTOR * interval) & ~labels, False)
    meas, bridged, pause = pauses.bridge(meas, pause, interval)
    gaps = pause[:-1]
    design = np.zeros(len(meas), dtype=int)
    if "experiment" in meas:
        runs = np.diff(meas["experiment"]) != 0
        gaps = gaps | runs
        design[1:] = np.cumsum(runs)
    change = np.nonzero(gaps)[0] + 1
    bounds = [0, *change.tolist(), len(meas)]
    out = []
    for k, (a, b) in enumerate(zip(bounds[:-1], bounds[1:], strict=True)):
        if b - a < MIN_SAMPLES:
            continue
        mask = np.zeros(len(meas), dtype=bool)
        mask[a:b] = True
        sub = meas.select(mask)
        if len(bounds) > 2:
            sub.meta["name"] = f"{meas.label}[{k + 1}]"
        out.append((sub, bridged[a:b], int(design[a])))
    if not out:
        raise FcompError(f"{meas.label}: no experiment with at least {MIN_SAMPLES} samples")
    return out


def _condition(subs: list[Measurement], cutoff_hz: float | None
               ) -> tuple[list[Measurement], Conditioning]:
    """The experiments of one file with conditioned ``v``, ``a`` columns (:mod:`fcomp.conditioning`)."""
    if not all("x" in m or "v" in m for m in subs):
        raise FcompError(f"{subs[0].label}: a diagnosis needs a position 'x' or velocity 'v' "
                         "column")
    pieces = [(m.t, m.get("x"), m.get("v")) for m in subs]
    # the raw force whose transitions at the reversals the band must keep
    forces = None
    if all("F" in m or any(k in m for k in ("p1", "p2", "F_ext")) for m in subs):
        forces = [m["F"] if "F" in m else driving_force(m) for m in subs]
    motions, cond = condition_motion(pieces, cutoff_hz=cutoff_hz, forces=forces)
    out = []
    for m, mo in zip(subs, motions, strict=True):
        a = np.where(mo.rest, 0.0, m["a"]) if "a" in m else mo.a
        out.append(m.with_columns(v=mo.v, a=a))
    return out, cond


def _force_band(subs: list[Measurement], motions: list[Measurement], cond: Conditioning
                ) -> Conditioning:
    """``cond`` with the force source and the band of the parallel filtering (reconstructed)."""
    if "F" in subs[0] or not any(k in subs[0] for k in ("p1", "p2", "F_ext")):
        return dataclasses.replace(cond, force="F" if "F" in subs[0] else "")
    mass = subs[0].rig.get("mass")
    longest = max(range(len(subs)), key=lambda i: len(subs[i]))
    m, mo = subs[longest], motions[longest]
    rest = (mo["v"] == 0.0) & (mo["a"] == 0.0)
    noise = rest_noise(m.t, driving_force(m), rest)
    fs = sample_rate(m.t)
    if mass is None or not math.isfinite(noise):
        return dataclasses.replace(cond, force="driving-force" if mass is None else
                                   "reconstructed", force_cutoff_hz=cond.cutoff_hz)
    fc = force_cutoff(fs, cond.cutoff_hz, cond.x_noise, float(mass), noise)
    return dataclasses.replace(cond, force="reconstructed", force_cutoff_hz=fc)


def _steady_state(meas: Measurement) -> bool:
    diag = meas.meta.get("diagnosis", {})
    mode = diag.get("samples", "motion") if isinstance(diag, dict) else "motion"
    if mode not in ("motion", STEADY_STATE):
        raise FcompError(f"{meas.label}: sidecar diagnosis.samples must be 'motion' or "
                         f"'{STEADY_STATE}', got {mode!r}")
    return mode == STEADY_STATE


def _force_channels(meas: Measurement) -> set[str]:
    """The measured columns the force to match is made of (:attr:`DiagnosisData.force_channels`)."""
    if "F" in meas:
        return {"F"}
    return {k for k in ("p1", "p2", "F_ext") if k in meas}


def content_digest(*arrays: np.ndarray, text: str = "") -> str:
    """A digest of numbers (and ``text``): what a record holds, never what it is called."""
    digest = hashlib.sha1(usedforsecurity=False)
    digest.update(text.encode())
    for a in arrays:
        digest.update(np.ascontiguousarray(a, dtype=float).tobytes())
    return digest.hexdigest()


#: Sidecar keys that describe the rig and the record's conventions (what the order of records
#: may depend on besides their columns; names, sources and notes never).
_RIG_KEYS = ("kind", "pressure", "rig", "diagnosis")


def _canonical_key(meas: Measurement) -> tuple[float, str, str]:
    """A key that orders records by what they hold, never by their names.

    The mean gauge pressure sum first (records of one seal at several pressure
    levels come in pressure order, as a person reads them), then a digest of the
    columns and of the sidecar's description of the rig (``kind``, ``pressure``,
    ``rig``, ``diagnosis``; never its name, source or notes); the name decides only
    between records identical in every number and every rig value, whose order
    changes no result. File names and the order files
    are given in are no information: renamed or reordered, the same records give
    the same answer to the bit.
    """
    psum = sum((meas[k] for k in ("p1", "p2") if k in meas), np.zeros(len(meas)))
    meta = {k: v for k, v in meas.meta.items() if k in _RIG_KEYS}
    names = sorted(meas.columns)
    return (float(np.mean(psum)) if len(meas) else 0.0,
            content_digest(meas.t, *(meas[n] for n in names),
                           text=json.dumps([names, meta], sort_keys=True, default=str)),
            meas.label)


def sessions(data: DiagnosisData) -> list[list[int]]:
    """The experiments of ``data`` grouped into sessions that share one clock.

    Files are separate experiments unless their stamps say otherwise: an
    experiment continues a session when its first stamp comes after the
    session's last one (the pieces of one file cut at logger pauses, or files
    of one logger whose clock runs on). Of several sessions it could continue,
    the one that ended last (ties by content); experiments whose stamps overlap
    (files that each start at zero) are sessions of their own. The grouping
    depends on the stamps and contents alone, never on names or on the order the
    files were given. Returns lists of experiment indices, each in time order.
    """
    t = data.signal("t")
    spans = sorted(((float(t[e.start]), float(t[e.stop - 1]), e.digest, i)
                    for i, e in enumerate(data.experiments)))
    groups: list[list[int]] = []
    ends: list[tuple[float, str]] = []
    for t0, t1, label, i in spans:
        open_ = [g for g, (end, _) in enumerate(ends) if end < t0]
        if open_:
            g = max(open_, key=lambda k: ends[k])
            groups[g].append(i)
            ends[g] = (t1, label)
        else:
            groups.append([i])
            ends.append((t1, label))
    return groups


def prepare(
    measurements: Measurement | Sequence[Measurement],
    *,
    cutoff_hz: float | None = None,
) -> DiagnosisData:
    """The :class:`DiagnosisData` of one or several measurements (see the module docstring).

    Raises
    ------
    FcompError
        When a record has no motion signal, no force to match, too few
        samples, or mixes steady-state points with motion records.
    """
    meas_list = [measurements] if isinstance(measurements, Measurement) else list(measurements)
    if not meas_list:
        raise FcompError("no measurement to diagnose")
    # the order the files are named in is no information: every answer is the same in any
    # order (a clock, where one is needed, comes from the stamps, :func:`sessions`)
    meas_list.sort(key=_canonical_key)
    modes = {_steady_state(m) for m in meas_list}
    if len(modes) > 1:
        raise FcompError("the records mix steady-state points and motion records; "
                         "diagnose them separately")
    steady = modes.pop()
    experiments: list[Experiment] = []
    sources = set()
    start = 0
    x_measured = all("x" in m for m in meas_list)
    p_measured = all("p1" in m or "p2" in m for m in meas_list)  # a missing one: 0 gauge
    signals: list[Conditioning] = []
    n_designs = 0
    for meas in meas_list:
        cut = [(meas, None, 0)] if steady else _cut(meas)
        subs = [m for m, _, _ in cut]
        band = None
        if steady:
            if "v" not in meas:
                raise FcompError(f"{meas.label}: steady-state points need a 'v' column")
            subs = [meas.with_columns(a=meas["a"] if "a" in meas else np.zeros(len(meas)))]
        alternatives: list[tuple[Motion, ...]] = [()] * len(subs)
        if not steady:
            conditioned, cond = _condition(subs, cutoff_hz)
            cond = _force_band(subs, conditioned, cond)
            signals.append(dataclasses.replace(cond, label=meas.label))
            if "x" in meas:
                alternatives = [tuple(motion_ensemble(m.t, m["x"], cond)) for m in subs]
            subs, band = conditioned, cond.force_cutoff_hz
        designs: dict[int, int] = {}
        for sub, alts, (_, bridged, unit) in zip(subs, alternatives, cut, strict=True):
            d = fit_data(sub, force_cutoff_hz=band)
            sources.add(d.source)
            experiments.append(Experiment(sub.label, d, start, start + d.n, alts,
                                          bridged if bridged is not None and bridged.any()
                                          else None, designs.setdefault(unit, n_designs)))
            n_designs = max(n_designs, experiments[-1].design + 1)
            start += d.n
    if len(sources) > 1:
        raise FcompError(f"the records give the force in different ways ({', '.join(sorted(sources))}); "
                         "give every record an F column, or none")
    if any((e.data.inertia is None) != (experiments[0].data.inertia is None)
           for e in experiments):
        raise FcompError("some records give rig.mass and others not; give it for all or none")
    data = DiagnosisData(experiments, {}, {}, _scales(experiments), steady, sources.pop(),
                         [e.label for e in experiments], signals,
                         str(meas_list[0].meta.get("kind", "")),
                         RigContext.from_meta(meas_list[0].meta),
                         tuple(sorted(set.intersection(*map(_force_channels, meas_list)))))
    _availability(data, x_measured, p_measured)
    return data


def _scales(experiments: list[Experiment]) -> Scales:
    cat = {k: np.concatenate([e.data.sig[k] for e in experiments])
           for k in ("t", "v", "a", "x", "p1", "p2")}
    y = np.concatenate([e.data.y for e in experiments])
    speed = np.abs(cat["v"])
    top = float(np.percentile(speed, 99.0))
    moving = speed > 0.02 * top if top > 0 else np.zeros(speed.size, dtype=bool)
    force = float(np.median(np.abs(y[moving]))) if moving.any() else float(np.median(np.abs(y)))
    if not force > 0:
        force = float(np.max(np.abs(y))) or 1.0
    psum = cat["p1"] + cat["p2"]
    dts = np.concatenate([np.diff(e.data.sig["t"]) for e in experiments])
    x = cat["x"]
    return Scales(
        force=force,
        speed=float(np.percentile(speed, 95.0)) or top or 1e-3,
        accel=float(np.percentile(np.abs(cat["a"]), 95.0)) or 1.0,
        x_min=float(np.percentile(x, 1.0)),
        x_max=float(np.percentile(x, 99.0)),
        resolution=float(min(np.median([resolution(e.data.sig["x"]) for e in experiments]),
                             1e-3)),
        p_mid=float(np.mean(psum)),
        p_span=float(np.percentile(psum, 99.0) - np.percentile(psum, 1.0)),
        dt=interval_of(dts),
        duration=float(sum(e.data.sig["t"][-1] - e.data.sig["t"][0] for e in experiments)),
    )


def _availability(data: DiagnosisData, x_measured: bool, p_measured: bool) -> None:
    sc = data.scales
    ok_x = x_measured and sc.x_max - sc.x_min > 20.0 * sc.resolution
    data.available["x"] = ok_x
    if not x_measured:
        data.reasons["x"] = "no measured position column 'x'"
    elif not ok_x:
        data.reasons["x"] = "the position hardly varies"
    ok_p = p_measured and sc.p_span > max(1000.0, 0.05 * abs(sc.p_mid))
    for k in ("p1", "p2"):
        data.available[k] = ok_p
        if not p_measured:
            data.reasons[k] = "no pressure column (p1, p2)"
        elif not ok_p:
            data.reasons[k] = (f"p1 + p2 hardly varies (range {sc.p_span:.3g} Pa around "
                               f"{sc.p_mid:.3g} Pa)")
    data.available["a"] = not data.steady_state and not math.isclose(sc.accel, 0.0)
    if not data.available["a"]:
        data.reasons["a"] = "no acceleration in the data (steady-state points)"
