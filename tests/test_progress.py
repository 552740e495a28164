"""One progress mechanism (fcomp/progress.py): the callback, reporting from deep inside, bars."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers.terminal import drain

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


# ------------------------------------------- progress on a terminal only (issue 27)
class _Head:
    """The part of a bar a :class:`ProgressRelay` head uses, recording its postfixes."""

    def __init__(self) -> None:
        self.postfixes: list[str] = []

    def set_postfix_str(self, text: str, refresh: bool = True) -> None:
        self.postfixes.append(text)


def test_the_relay_names_the_running_work_on_its_head_bar(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """``study all`` on a terminal: the studies running now are named beside the bar of
    finished ones (what :func:`running` sends from each worker)."""
    from fcomp import progress

    monkeypatch.setattr(progress, "on_terminal", lambda: True)
    head = _Head()
    with progress.ProgressRelay(head=head) as relay:
        progress.relay_progress(relay.queue)
        try:
            with progress.running("missing-physics"), progress.running("compensators"):
                pass
        finally:
            progress.relay_progress(None)
    assert head.postfixes == ["running missing-physics",
                              "running missing-physics, compensators",
                              "running missing-physics", ""]


def test_a_study_of_all_says_it_is_running() -> None:
    """:func:`studies.all.run_study` names its study to the parent while it runs."""
    import queue

    from studies.all import StudyJob, run_study
    from studies.base import StudyConfig

    class Tiny:
        title = summary = "tiny"
        paper = None

        def main(self, config: object) -> dict:
            return {"meta": {"finding": None}}

        def headline(self, results: dict) -> str:
            return "done"

    q: queue.Queue = queue.Queue()
    run = run_study(StudyJob("tiny", Tiny(), StudyConfig(out="unused"), q))  # type: ignore[arg-type]
    assert run["status"] == "ok"
    msgs = [q.get_nowait() for _ in range(q.qsize())]
    assert [m[0] for m in msgs] == ["running", "ran"] and msgs[0][2] == "tiny"


def test_no_bar_goes_into_a_file_or_a_pipe(capsys: pytest.CaptureFixture[str]) -> None:
    """Bars and counters are drawn on a terminal only: stderr captured (a pipe) gets
    nothing, whatever the caller asked (the diagnosis's counter used to write there)."""
    from fcomp.progress import counter

    bar = progress_bar("sweep", 3, enabled=True)
    bar.update(3)
    bar.close()
    with counter("diagnose", unit="fit") as tick:
        tick("baseline lugre")
    assert capsys.readouterr().err == ""


def _small_record(folder: Path) -> Path:
    from fcomp.synthetic import generate

    path = folder / "small.csv"
    generate(["pressure-dependence"], base="coulomb-viscous", duration=6.0, experiments=2,
             rate=250.0, seed=1).measurement.write(path)
    return path


DIAGNOSE = ["diagnose", "small.csv", "--friction", "coulomb-viscous", "--baseline-check",
            "--max-steps", "1", "--jobs", "1", "--candidates", "pressure-dependence",
            "--json", "d.json"]


@pytest.mark.slow
def test_diagnose_writes_no_progress_into_a_pipe(tmp_path: Path) -> None:
    """``fcomp diagnose`` with stderr to a pipe: no bar, no carriage return."""
    import subprocess
    import sys

    _small_record(tmp_path)
    proc = subprocess.run([sys.executable, "-m", "fcomp.cli.main", *DIAGNOSE], cwd=tmp_path,
                          capture_output=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert b"\r" not in proc.stderr and b"fit/s" not in proc.stderr and b"diagnose:" not in \
        proc.stderr, proc.stderr


@pytest.mark.slow
def test_diagnose_draws_one_bar_on_a_terminal(tmp_path: Path) -> None:
    """On a terminal (a pseudo-terminal here) ``fcomp diagnose`` shows its bar, one bar for
    the whole diagnosis: the baseline check counts on in it (it used to open a second
    bar from 0), and the bar is erased at the end."""
    import fcntl
    import os
    import pty
    import struct
    import subprocess
    import sys
    import termios

    _small_record(tmp_path)
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))  # a window
    proc = subprocess.Popen([sys.executable, "-m", "fcomp.cli.main", *DIAGNOSE], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=slave)
    os.close(slave)
    seen = drain(master, proc)
    os.close(master)
    proc.communicate(timeout=600)
    assert proc.returncode == 0
    text = seen.decode()
    assert "diagnose: " in text and "fit/s" in text, text
    assert text.count("diagnose: 0fit") == 1, text  # the check's fits counted on
    bar = text.split("fcomp: warning")[0]  # the warnings follow the finished run
    assert bar.rstrip(" ").endswith("\r"), text  # erased: the line blanked at the end


@pytest.mark.slow
@pytest.mark.xdist_group("site")
def test_study_all_writes_no_progress_into_a_pipe() -> None:
    """``fcomp study all --fast`` with stderr to a pipe (the shared site's run): no bar of
    the studies, of any study or diagnosis."""
    from helpers.browser import build_site

    _, code, err = build_site()
    assert code == 0
    assert "\r" not in err and "study/s" not in err and "run/s" not in err, err[-2000:]


@pytest.mark.parametrize(("name", "module"), [("presliding", "studies.presliding_runs"),
                                              ("friction-models", "studies.friction_models")])
def test_no_progress_reaches_the_bar_of_every_study(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, name: str, module: str) -> None:
    """``fcomp study NAME --no-progress`` (``StudyConfig.progress`` false): the study's own
    bar is off too, on a terminal as well (two studies drew theirs regardless)."""
    import importlib

    from studies import STUDIES
    from studies.base import StudyConfig

    class SeenError(Exception):
        pass

    asked: list[tuple[str, bool]] = []

    def bar(label: str, total: int | None, *, enabled: bool = True, unit: str = "run") -> None:
        asked.append((label, enabled))
        raise SeenError  # enough: the run itself is not the point

    monkeypatch.setattr(importlib.import_module(module), "progress_bar", bar)
    with pytest.raises(SeenError):
        STUDIES.get(name).main(StudyConfig(out=tmp_path / "out", fast=True, progress=False))
    assert asked == [(name, False)]
    assert not (tmp_path / "out").exists()
