"""Held-out splits: by contiguous segment in every experiment, never by shuffled samples.

Friction residuals are strongly autocorrelated and the friction state carries
the history of the motion, so a sample-wise random split would score a model
on samples whose neighbours it was fitted to. The diagnosis therefore holds
out whole pieces of the record:

``segment`` (the default, ``auto``)
    each experiment of the record's design (a file, or a run of its ``experiment``
    column; the pieces a logger's pauses cut it into together) is cut into contiguous
    blocks of about
    ``max(1 s, its duration/30)`` (at least three blocks per experiment, at least
    20 samples each); every third block is held out, so that an experiment's split
    depends on it alone: not on its name, its place among the records, or the
    other records diagnosed with it. Every experiment -- every pressure level, every
    file -- is in both sets (a split *stratified* by experiment): an effect that
    shows between operating points can be judged. Where the blocks from the second
    hold out too few or too many of the experiment's usable samples (warm-up, a
    short experiment), of the pattern's three phases the one nearest a third is
    taken.
``experiment``
    whole experiments are held out: the 2nd, 5th, 8th, ... (every third,
    starting with the second) -- about a third of them, at least one, never
    all. Needs two or more experiments; the strictest test of prediction, but
    an operating point met in one experiment only cannot be judged.

The model is always *simulated* over the whole record (its states depend
only on the measured motion, never on the measured force), and only the
force of the training samples enters a fit, so the held-out error is a true
prediction error. Warm-up samples (:mod:`.regimes`) are in neither set.

**Coverage** (:func:`coverage`): the held-out samples are counted per
experiment and per operating point -- pressure level (terciles of
``p1 + p2``), speed class (creep, slow, medium, fast: below 1, 10, 50 and
above 50 % of the speed scale) and direction. An operating point with at least
:data:`COVERED_SHARE` of the usable samples but fewer than
``max(MIN_HELD, HELD_SHARE of them)`` held out cannot be judged: a
``heldout-coverage`` warning names it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from fcomp.diagnosis.data import DiagnosisData
from fcomp.errors import FcompError
from fcomp.identification.plausibility import FitWarning

STRATEGIES = ("auto", "experiment", "segment")
#: Fewest samples of a block in the ``segment`` split.
MIN_BLOCK = 20
#: An operating point with this share of the usable samples must be judged ...
COVERED_SHARE = 0.02
#: ... by at least this many held-out samples ...
MIN_HELD = 30
#: ... and this share of its own usable samples.
HELD_SHARE = 0.05
#: Speed classes of the coverage, as fractions of the speed scale.
SPEED_CLASSES = ((0.0, 0.01, "creep"), (0.01, 0.1, "slow"), (0.1, 0.5, "medium"),
                 (0.5, np.inf, "fast"))


@dataclass(frozen=True)
class Split:
    """A train/held-out split of the samples.

    Attributes
    ----------
    train, test : (N,) bool
        Training and held-out samples (disjoint, both within the valid samples).
    strategy : str
        ``"experiment"`` or ``"segment"``.
    description : str
        One line for reports.
    coverage : dict
        Held-out and training samples per experiment and operating point
        (:func:`coverage`).
    warnings : list of FitWarning
        ``heldout-coverage``: what the held-out samples cannot judge.
    """

    train: np.ndarray
    test: np.ndarray
    strategy: str
    description: str
    coverage: dict = field(default_factory=dict)
    warnings: list[FitWarning] = field(default_factory=list)


def make_split(data: DiagnosisData, valid: np.ndarray, strategy: str = "auto") -> Split:
    """The held-out split of ``data`` (see the module docstring)."""
    if strategy not in STRATEGIES:
        raise FcompError(f"split {strategy!r}: choose one of {', '.join(STRATEGIES)}")
    n_exp = len(data.experiments)
    if strategy == "auto":
        strategy = "segment"
    if strategy == "experiment":
        if n_exp < 2:
            raise FcompError("a split by experiment needs two or more experiments "
                             "(give several files or an 'experiment' column); use split "
                             "'segment'")
        test = np.zeros(data.n, dtype=bool)
        held = [i for i in range(n_exp) if i % 3 == 1]
        for i in held:
            e = data.experiments[i]
            test[e.start:e.stop] = True
        usable = [(data.experiments[i].label, int((valid & test)[data.experiments[i].start:
                                                                data.experiments[i].stop].sum()))
                  for i in held]
        desc = (f"by experiment: {len(held)} of {n_exp} held out ("
                + ", ".join(f"{lab} ({n} usable samples)" if n else f"{lab} (warm-up only)"
                            for lab, n in usable) + ")")
        split = Split(valid & ~test, valid & test, "experiment", desc)
    else:
        split = _segment_split(data, valid)
    if split.test.sum() < 10 or split.train.sum() < 10:
        raise FcompError(f"the record is too short for a held-out split ({int(valid.sum())} "
                         "usable samples); record longer or give more experiments")
    cov, warns = coverage(data, split.train, split.test)
    return dataclasses.replace(split, coverage=cov, warnings=warns)


#: Blocks of the ``segment`` split per experiment (at least :data:`BLOCK_SECONDS` long each):
#: the former rule's thirty over the whole record, for one experiment the same split.
BLOCKS = 30
#: Shortest block of the ``segment`` split (s).
BLOCK_SECONDS = 1.0
#: The share of an experiment's usable samples its held-out blocks may hold.
HELD_RANGE = (0.2, 0.45)


def _units(data: DiagnosisData) -> list[list[int]]:
    """The experiments of the record's design, each as the indices of its pieces: the pieces
    of one file cut at logger pauses together (:attr:`.data.Experiment.design`)."""
    units: list[list[int]] = []
    for i, e in enumerate(data.experiments):
        if e.design >= 0 and units and data.experiments[units[-1][-1]].design == e.design:
            units[-1].append(i)
        else:
            units.append([i])
    return units


def _segment_split(data: DiagnosisData, valid: np.ndarray) -> Split:
    """Every experiment of the record's design cut into its own blocks, every third held
    out (module docstring).

    Each experiment's blocks and pattern depend on that experiment alone: its own
    duration (:data:`BLOCKS` blocks of at least :data:`BLOCK_SECONDS`) and its own usable
    samples (every third block from the second; of the pattern's three phases the one
    holding out nearest a third of them when that holds out a share outside
    :data:`HELD_RANGE`). Before, the block length came from the whole record's duration
    and the pattern's phase from the experiment's place in the list, so a renamed file
    (its place in the name order) or one more file changed which samples every other
    experiment held out (the same records renamed: a baseline error of 2.80 N against
    2.94 N). One experiment alone is split as before.

    The experiment is the design's (a file, or a run of its ``experiment`` column), not
    the pieces a logger's pauses cut it into: its blocks are counted over its measured
    samples, never over those inserted across a bridged pause, so whether a pause is
    bridged or cuts (:mod:`.pauses`) the same samples are held out. Split by piece, a
    pause bridged in one O-ring file (four pieces became three) moved every block of that
    file and turned the pair found on 1, 3, 5 bar into nothing added.
    """
    test = np.zeros(data.n, dtype=bool)
    bridged = data.bridged
    n_blocks_all, lengths = 0, []
    for unit in _units(data):
        pieces = [data.experiments[i] for i in unit]
        at = np.concatenate([np.arange(e.start, e.stop) for e in pieces])
        at = at[~bridged[at]]
        dur = float(pieces[-1].data.sig["t"][-1] - pieces[0].data.sig["t"][0])
        target = max(BLOCK_SECONDS, dur / BLOCKS)
        nb = max(3, int(round(dur / target)))
        nb = max(1, min(nb, at.size // MIN_BLOCK))
        edges = np.linspace(0, at.size, nb + 1).round().astype(int)
        ok = valid[at]
        usable = max(int(ok.sum()), 1)
        # the pattern from the second block (one record alone is split as it always was),
        # unless it holds out too few or too many of the usable samples (its blocks in the
        # warm-up, or a short experiment): then of the three phases the one nearest a third
        patterns = [[b for b in range(nb) if (b + shift) % 3 == 1] for shift in range(3)]
        shares = [sum(int(ok[edges[b]:edges[b + 1]].sum()) for b in bs) / usable
                  for bs in patterns]
        pick = 0 if HELD_RANGE[0] <= shares[0] <= HELD_RANGE[1] else \
            min(range(3), key=lambda k: abs(shares[k] - 1.0 / 3.0))
        for b in patterns[pick]:
            test[at[edges[b]:edges[b + 1]]] = True
        n_blocks_all += nb
        lengths.append(dur / nb)
    typical = float(np.median(lengths)) if lengths else BLOCK_SECONDS
    desc = (f"by contiguous segment in every experiment: every third of {n_blocks_all} "
            f"blocks (about {typical:.3g} s each) held out")
    return Split(valid & ~test, valid & test, "segment", desc)


def coverage(data: DiagnosisData, train: np.ndarray, test: np.ndarray
             ) -> tuple[dict, list[FitWarning]]:
    """Training and held-out samples per experiment and operating point, and what cannot be
    judged (see the module docstring)."""
    usable = train | test
    total = max(int(usable.sum()), 1)
    groups: dict[str, dict[str, np.ndarray]] = {"experiment": {}, "direction": {},
                                                "speed": {}}
    idx = data.experiment_index()
    for i, e in enumerate(data.experiments):
        groups["experiment"][e.label] = idx == i
    v = data.signal("v")
    groups["direction"] = {"extending (v > 0)": v > 0, "retracting (v < 0)": v < 0}
    speed = np.abs(v) / max(data.scales.speed, 1e-300)
    moving = speed > 0
    for lo, hi, name in SPEED_CLASSES:
        groups["speed"][name] = moving & (speed > lo) & (speed <= hi)
    if data.available.get("p1", False):
        psum = data.signal("p1") + data.signal("p2")
        q1, q2 = np.percentile(psum[usable], [100 / 3, 200 / 3])
        groups["pressure"] = {f"p1+p2 below {q1:.3g} Pa": psum < q1,
                              f"p1+p2 {q1:.3g} to {q2:.3g} Pa": (psum >= q1) & (psum < q2),
                              f"p1+p2 above {q2:.3g} Pa": psum >= q2}
    out: dict[str, dict[str, dict[str, int]]] = {}
    warns = []
    for kind, bins in groups.items():
        out[kind] = {}
        for name, mask in bins.items():
            n_all = int((usable & mask).sum())
            n_test = int((test & mask).sum())
            out[kind][name] = {"train": int((train & mask).sum()), "heldout": n_test}
            if n_all >= COVERED_SHARE * total and n_test < max(MIN_HELD, HELD_SHARE * n_all):
                warns.append(FitWarning("heldout-coverage", None, (
                    f"{kind} {name}: {n_test} held-out of {n_all} usable samples; what the "
                    f"models do there is not judged (record more of it, or give it as an "
                    f"experiment of its own)")))
    return out, warns
