"""Signals from the first millisecond (issue 42, item 4): Ctrl-C and SIGTERM end every
command with its one line and exit status, no traceback, nothing written, no process left
-- while it still loads its modules, as a pool starts its workers, and when a second
Ctrl-C lands while the first one's clean-up runs.

The subprocess tests wait on conditions, not clocks (:mod:`helpers.processes`): "the
process has its SIGTERM handler" (the earliest moment fcomp can answer), "the workers
exist", "the first signal was taken" (the process now ignores further ones).
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers import processes
from helpers.processes import ROOT

pytestmark = pytest.mark.skipif(not Path("/proc/self/status").exists(),
                                reason="watches processes through /proc (Linux)")

LONG = ["simulate", "hydraulic", "--friction", "nmlgm-hysteresis", "--input",
        "sine:amplitude=4.5e-3,frequency=1", "--duration", "200", "--rate", "200",
        "-o", "long.csv"]
LINES = {signal.SIGINT: ("fcomp: interrupted", 130), signal.SIGTERM: ("fcomp: terminated", 143)}


def _ignores(pid: int, sig: int) -> bool:
    """Whether ``pid`` now ignores ``sig`` (``SigIgn``): an fcomp process does once the first
    signal has been taken and its clean-up runs."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    line = next(s for s in status.splitlines() if s.startswith("SigIgn:"))
    return bool(int(line.split()[1], 16) & (1 << (sig - 1)))


def _stopped(proc, sig: int, folder: Path, before: set[str]) -> str:  # type: ignore[no-untyped-def]
    out, err = proc.communicate(timeout=processes.PATIENCE)
    gone = processes.group_gone(proc.pid)
    line, code = LINES[sig]
    assert "Traceback" not in err.decode() and "Exception ignored" not in err.decode(), err
    assert (proc.returncode, err.decode(), out) == (code, line + "\n", b"")
    assert gone, "processes of the command left running"
    assert {p.name for p in folder.iterdir()} == before, "something was written"
    return err.decode()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_at_the_first_moment_is_one_line(tmp_path: Path, sig: int) -> None:
    """The signal sent as soon as the process has its handler -- the entry point installs
    it before importing anything heavy, so the command is still loading numpy, the parser
    and the commands: before, Ctrl-C then printed a 26-66 line traceback and SIGTERM ended
    the process without a word (exit -15)."""
    before = {p.name for p in tmp_path.iterdir()}
    proc = processes.start(LONG, tmp_path)
    assert processes.wait_for(lambda: processes.sigterm_caught(proc.pid), proc), \
        "the process never installed its SIGTERM handler"
    loading = "numpy" not in Path(f"/proc/{proc.pid}/maps").read_text()
    processes.send(proc, sig)
    _stopped(proc, sig, tmp_path, before)
    assert loading, "the handler came only once numpy was loaded: too late"


def test_a_second_ctrl_c_during_the_clean_up_is_ignored(tmp_path: Path) -> None:
    """Ctrl-C twice on a parallel sweep: the second lands while the first one's clean-up
    ends the workers (the process already ignores it). Before, it interrupted that clean-up:
    ``Exception ignored in threading._shutdown`` and its traceback after
    ``fcomp: interrupted``, and once 17.5 s waiting for workers nobody had ended."""
    before = {p.name for p in tmp_path.iterdir()}
    proc = processes.start(["sweep", "--samples", "20", "--jobs", "2", "--no-progress",
                            "--json", "s.json"], tmp_path)
    assert processes.wait_for(lambda: len(processes.children(proc.pid)) >= 2, proc), \
        "the sweep never started its workers"
    processes.send(proc, signal.SIGINT)
    assert processes.wait_for(lambda: _ignores(proc.pid, signal.SIGINT), proc)
    processes.send(proc, signal.SIGINT)
    _stopped(proc, signal.SIGINT, tmp_path, before)


# ------------------------------------------------------------- in this process
@contextlib.contextmanager
def _fcomp_signals() -> Iterator[None]:
    """fcomp's handlers in this (the test's) process, the test runner's put back after."""
    from fcomp.cli import signals

    saved = {s: signal.getsignal(s) for s in signals.STOP_SIGNALS}
    hook = sys.unraisablehook
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signals.install()
    try:
        yield
    finally:
        for s, h in saved.items():
            signal.signal(s, h)
        sys.unraisablehook = hook


def _sleep(seconds: float) -> float:
    time.sleep(seconds)
    return seconds


def _ended(procs: list, seconds: float = 30.0) -> bool:  # type: ignore[type-arg]
    end = time.monotonic() + seconds
    for p in procs:
        p.join(max(0.0, end - time.monotonic()))
    return not any(p.is_alive() for p in procs)


_POOL_STARTS = """
import multiprocessing.context, os, signal, time
from fcomp.cli import signals
from fcomp.cli.signals import Terminated
from fcomp.parallel import process_pool, stopping

started = []
original = multiprocessing.context.ForkProcess.start


def start_then_signal(self):
    original(self)
    started.append(self)
    os.kill(os.getpid(), signal.SIGTERM)  # lands right after the worker's start


multiprocessing.context.ForkProcess.start = start_then_signal
signals.install()
try:
    with stopping(process_pool(2)) as pool:
        pool.submit(time.sleep, 30.0).result()
    print("not terminated")
except Terminated:
    print("terminated")
end = time.monotonic() + 30.0
for p in started:
    p.join(max(0.0, end - time.monotonic()))
print("started", len(started), "alive", sum(p.is_alive() for p in started))
"""


def test_a_signal_as_a_pool_starts_a_worker_does_not_leave_it_running() -> None:
    """SIGTERM landing just after a worker process was started but before the pool had it
    on its list: the worker was not ended, and the command hung at exit waiting for it
    (the closing note of issue 27). The pool now holds the signals while it starts and
    registers a worker, so the stop ends every worker it started. Run in a fresh
    interpreter: the pool's start method and the signal handling are process-wide, and a
    test runner's worker process carries what earlier tests left there."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run([sys.executable, "-c", _POOL_STARTS], env=env, capture_output=True,
                          text=True, timeout=180)
    lines = proc.stdout.split()
    assert "terminated" in proc.stdout.splitlines(), (proc.stdout, proc.stderr)
    started = int(lines[lines.index("started") + 1])
    alive = int(lines[lines.index("alive") + 1])
    assert started >= 1, "no worker was started"
    assert alive == 0, "a worker started as the signal landed is still running"


def test_the_stop_runs_whole_through_a_second_signal(monkeypatch: pytest.MonkeyPatch) -> None:
    """The first Ctrl-C stops the pool; a second one landing while ``parallel.stop`` ends
    the workers is ignored (it used to interrupt the stop, leaving workers running)."""
    import fcomp.parallel
    from fcomp.cli.signals import Interrupted
    from fcomp.parallel import process_pool, stopping

    original = fcomp.parallel.stop
    stops: list[int] = []

    def stop_through_a_second_signal(pool: object) -> None:
        os.kill(os.getpid(), signal.SIGINT)  # the second Ctrl-C, in the middle of the stop
        time.sleep(0.05)
        stops.append(1)
        original(pool)  # type: ignore[arg-type]

    monkeypatch.setattr(fcomp.parallel, "stop", stop_through_a_second_signal)
    with _fcomp_signals(), pytest.raises(Interrupted), stopping(process_pool(2)) as pool:
        futures = [pool.submit(_sleep, 30.0) for _ in range(2)]
        procs = list(pool._processes.values())  # type: ignore[attr-defined]
        os.kill(os.getpid(), signal.SIGINT)
        for f in futures:
            f.result()
    assert stops == [1], "the stop did not run to its end"
    assert _ended(procs), "workers left running"


def test_a_stop_landing_where_exceptions_are_dropped_is_sent_again(
        capsys: pytest.CaptureFixture[str]) -> None:
    """A signal handled inside a ``__del__`` (or a fork's hooks: ``logging`` has one, and
    every compiler or worker start runs them) raises where Python drops exceptions: it printed
    ``Exception ignored in ...`` and the command ran on, deaf to further signals (seen:
    ``compensate`` never ended after SIGTERM). The stop is now sent again and ends it, and
    nothing is printed."""
    from fcomp.cli.signals import Terminated

    class Dropper:
        def __del__(self) -> None:
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(10000):  # the handler runs here, inside __del__
                pass

    with _fcomp_signals(), pytest.raises(Terminated):
        Dropper()  # deleted at once: the signal lands inside __del__
        end = time.monotonic() + processes.PATIENCE
        while time.monotonic() < end:
            time.sleep(0.005)
    assert "Exception ignored" not in capsys.readouterr().err


def test_the_entry_point_imports_nothing_heavy() -> None:
    """The console script's module installs the handlers before anything heavy loads: it
    imports :mod:`signal` and fcomp's tiny modules only (numpy alone takes 0.1-0.5 s)."""
    import subprocess
    import sys

    code = ("import sys\nimport fcomp.cli.main\n"
            "print(','.join(sorted(m for m in sys.modules if m.startswith(('fcomp', 'numpy', "
            "'scipy', 'argparse')))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=processes.env(), cwd=ROOT, check=True).stdout.strip()
    assert out.split(",") == ["fcomp", "fcomp.cli", "fcomp.cli.main", "fcomp.cli.signals",
                              "fcomp.version"]
