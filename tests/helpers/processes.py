"""Real ``fcomp`` processes in tests: started as a terminal starts them, watched through
``/proc``, waited for on conditions rather than clocks.

A test that sends a signal "after 2 s" tests the machine's load as much as the code: on
a busy machine the command may not have reached the point the test meant. These helpers
wait for what the test means instead -- the process has its signal handlers
(:func:`sigterm_caught`), it has started worker processes (:func:`children`), it has
written something (:func:`wait_for`) -- with a generous limit that only a hang reaches.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]

#: Seconds a condition may take on the most loaded machine before the test calls it a hang.
PATIENCE = 120.0


def env(**extra: str) -> dict[str, str]:
    """The environment of an ``fcomp`` process run from this checkout."""
    out = dict(os.environ, PYTHONPATH=str(ROOT), **extra)
    out.pop("FCOMP_DEBUG", None)
    return out


def start(args: list[str], cwd: Path, **kw: Any) -> subprocess.Popen:
    """``python -m fcomp.cli.main ARGS`` in a process group of its own, as a terminal's
    foreground job, with Ctrl-C at its default (a suite started as a background job of a
    non-interactive shell inherits SIGINT ignored, and Python keeps ignoring it)."""
    return subprocess.Popen(  # type: ignore[call-overload]
        [sys.executable, "-m", "fcomp.cli.main", *args], cwd=cwd, env=kw.pop("env", env()),
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL), **kw)


def wait_for(condition: Callable[[], bool], proc: subprocess.Popen | None = None,
             limit: float = PATIENCE) -> bool:
    """Poll ``condition`` until it holds (True), ``proc`` ended or ``limit`` s passed."""
    end = time.monotonic() + limit
    while time.monotonic() < end:
        if condition():
            return True
        if proc is not None and proc.poll() is not None:
            return condition()
        time.sleep(0.002)
    return False


def sigterm_caught(pid: int) -> bool:
    """Whether process ``pid`` has a handler for SIGTERM (``SigCgt`` of ``/proc/PID/status``):
    an ``fcomp`` process has one from its first moment, a Python process by default not."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    for line in status.splitlines():
        if line.startswith("SigCgt:"):
            return bool(int(line.split()[1], 16) & (1 << (signal.SIGTERM - 1)))
    return False


def children(pid: int) -> list[int]:
    """The processes ``pid`` has started (and theirs) that have not ended."""
    from fcomp.parallel import descendants, processes

    table = processes()
    return [p for p in descendants([pid]) if table.get(p, ("Z",))[0] != "Z"]


def alive(pids: list[int]) -> list[int]:
    """Those of ``pids`` that have not ended (ended ones nobody reaps do not count)."""
    from fcomp.parallel import processes

    table = processes()
    return [p for p in pids if table.get(p, ("Z",))[0] != "Z"]


def cmdline(pid: int) -> str:
    """Process ``pid``'s command line ('' once it has ended)."""
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(
            errors="replace")
    except OSError:
        return ""


def group(pgid: int) -> list[int]:
    """The live processes of process group ``pgid`` (ended ones nobody reaps do not count)."""
    from fcomp.parallel import group_members

    return group_members(pgid)


def group_gone(pgid: int, seconds: float = 10.0) -> bool:
    """Whether every process of group ``pgid`` has ended within ``seconds``; those left are
    killed (not to leave them running after the test)."""
    if wait_for(lambda: not group(pgid), limit=seconds):
        return True
    for pid in group(pgid):
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
    return False


def send(proc: subprocess.Popen, sig: int) -> None:
    """SIGINT to the whole group (Ctrl-C at a terminal), another signal to the process."""
    with contextlib.suppress(ProcessLookupError):
        if sig == signal.SIGINT:
            os.killpg(proc.pid, sig)
        else:
            proc.send_signal(sig)


def finish(proc: subprocess.Popen, limit: float = PATIENCE) -> tuple[bytes, bytes]:
    """``proc.communicate()`` within ``limit`` s; past it, a failure that shows what was left
    -- each process of its group with its state, the kernel function it waits in and its
    command line, and what the command wrote so far -- rather than a bare timeout (a hang
    seen once on a loaded machine and never again cannot be reproduced: its evidence is
    all there is)."""
    from fcomp.parallel import processes

    try:
        return proc.communicate(timeout=limit)
    except subprocess.TimeoutExpired:
        table = processes()
        rows = []
        for pid in [proc.pid, *group(proc.pid)]:
            with contextlib.suppress(OSError):
                wchan = Path(f"/proc/{pid}/wchan").read_text()
                state = table.get(pid, ("?", 0, 0))
                rows.append(f"  {pid} ppid {state[1]} {state[0]} {wchan or '-'}: "
                            f"{cmdline(pid)[:160]}")
        proc.kill()
        with contextlib.suppress(OSError):
            os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        raise AssertionError(
            f"not ended after {limit:.0f} s; left:\n" + "\n".join(rows)
            + f"\nstderr: {err.decode(errors='replace')[-2000:]}"
            + f"\nstdout: {out.decode(errors='replace')[-500:]}") from None
