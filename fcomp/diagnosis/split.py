"""Held-out splits: by experiment or by contiguous segment, never by shuffled samples.

Friction residuals are strongly autocorrelated and the friction state carries
the history of the motion, so a sample-wise random split would score a model
on samples whose neighbours it was fitted to. The diagnosis therefore holds
out whole pieces of the record:

``experiment``
    whole experiments are held out: the 2nd, 5th, 8th, ... (every third,
    starting with the second) -- about a third of them, at least one, never
    all. Needs two or more experiments.
``segment``
    each experiment is cut into contiguous blocks of about
    ``max(1 s, duration/30)`` (at least three blocks per experiment, at least
    20 samples each); every third block is held out, the pattern shifted from
    one experiment to the next.
``auto``
    ``experiment`` with four or more experiments, else ``segment``.

The model is always *simulated* over the whole record (its states depend
only on the measured motion, never on the measured force), and only the
force of the training samples enters a fit, so the held-out error is a true
prediction error. Warm-up samples (:mod:`.regimes`) are in neither set.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fcomp.diagnosis.data import DiagnosisData
from fcomp.errors import FcompError

STRATEGIES = ("auto", "experiment", "segment")
#: Fewest samples of a block in the ``segment`` split.
MIN_BLOCK = 20


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
    """

    train: np.ndarray
    test: np.ndarray
    strategy: str
    description: str


def make_split(data: DiagnosisData, valid: np.ndarray, strategy: str = "auto") -> Split:
    """The held-out split of ``data`` (see the module docstring)."""
    if strategy not in STRATEGIES:
        raise FcompError(f"split {strategy!r}: choose one of {', '.join(STRATEGIES)}")
    n_exp = len(data.experiments)
    if strategy == "auto":
        strategy = "experiment" if n_exp >= 4 else "segment"
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
        desc = (f"by experiment: {len(held)} of {n_exp} held out "
                f"({', '.join(data.experiments[i].label for i in held)})")
        split = Split(valid & ~test, valid & test, "experiment", desc)
    else:
        split = _segment_split(data, valid)
    if split.test.sum() < 10 or split.train.sum() < 10:
        raise FcompError(f"the record is too short for a held-out split ({int(valid.sum())} "
                         "usable samples); record longer or give more experiments")
    return split


def _segment_split(data: DiagnosisData, valid: np.ndarray) -> Split:
    test = np.zeros(data.n, dtype=bool)
    total = data.scales.duration
    target = max(1.0, total / 30.0)
    n_blocks_all = 0
    for k, e in enumerate(data.experiments):
        t = e.data.sig["t"]
        dur = float(t[-1] - t[0])
        nb = max(3, int(round(dur / target)))
        nb = max(1, min(nb, e.n // MIN_BLOCK))
        edges = np.linspace(0, e.n, nb + 1).round().astype(int)
        for b in range(nb):
            if (b + k) % 3 == 1:
                test[e.start + edges[b]:e.start + edges[b + 1]] = True
        n_blocks_all += nb
    desc = (f"by contiguous segment: every third of {n_blocks_all} blocks "
            f"(about {target:.3g} s each) held out")
    return Split(valid & ~test, valid & test, "segment", desc)
