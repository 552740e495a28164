"""One progress mechanism (fcomp/progress.py): the callback, reporting from deep inside, bars."""

from __future__ import annotations

import numpy as np
import pytest

from fcomp.inputs import parse_input
from fcomp.models import make_model
from fcomp.parallel import run_tasks
from fcomp.progress import progress_bar, receiver, report, reporting, ticker
from plants import PLANTS


def test_reports_go_to_the_innermost_block_only() -> None:
    outer: list[tuple[float, float]] = []
    inner: list[tuple[float, float]] = []
    report(1, 2)                                   # nobody listens: nothing happens
    assert receiver() is None
    with reporting(lambda d, t: outer.append((d, t))):
        report(1, 4)
        with reporting(lambda d, t: inner.append((d, t))):
            report(2, 4)
        report(3, 4)
    assert receiver() is None
    assert outer == [(1, 4), (3, 4)] and inner == [(2, 4)]


def test_a_simulation_reports_its_simulated_time_and_gives_the_same_run() -> None:
    """Reporting runs the engine in pieces: the same numbers, ``done`` rising to ``total``."""
    plant = PLANTS.get("force-rig")(make_model("nmlgm"))
    u = parse_input("sine:amplitude=0.4,frequency=2")
    quiet = plant.simulate(u, 0.3, 1000.0)
    seen: list[tuple[float, float]] = []
    with reporting(lambda done, total: seen.append((done, total))):
        loud = plant.simulate(u, 0.3, 1000.0)
    np.testing.assert_array_equal(loud["x"], quiet["x"])
    done, total = np.array(seen).T
    assert np.all(np.diff(done) > 0) and np.all(total == pytest.approx(0.3))
    assert done[-1] == pytest.approx(0.3)


def _square(k: int) -> int:
    return k * k


class _Bar:
    """The part of a bar a ticker uses."""

    def __init__(self) -> None:
        self.n = 0

    def update(self, n: int = 1) -> None:
        self.n += n


def test_run_tasks_ticks_a_bar_by_the_jobs_done() -> None:
    bar = _Bar()
    tick = ticker(bar)
    assert run_tasks(_square, [1, 2, 3], workers=1, progress=tick) == [1, 4, 9]
    assert bar.n == 3
    assert run_tasks(_square, [4, 5, 6], workers=1, progress=tick) == [16, 25, 36]
    assert bar.n == 6


def test_a_bar_of_unknown_length_counts() -> None:
    """The form of a diagnosis's bar: no total, a postfix, one tick per fit."""
    bar = progress_bar("diagnose", None, unit="fit", enabled=False)
    bar.set_postfix_str("lugre", refresh=False)
    bar.update(1)
    assert bar.total is None
    bar.close()


def test_the_bars_live_in_the_progress_module_alone() -> None:
    """One progress mechanism: the bars are :mod:`fcomp.progress`'s, not re-exported."""
    from fcomp import parallel, progress

    for name in ("progress_bar", "ticker", "ProgressRelay", "RelayedBar", "relay_progress"):
        assert hasattr(progress, name) and not hasattr(parallel, name), name
