"""How soon a command answers Ctrl-C and SIGTERM, and how fast it stops: this tree beside a
baseline checkout, in one run (medians of ``--repeat`` runs, and their ratios).

* **answering**: seconds from starting ``python -m fcomp.cli.main simulate ...`` until the
  process has its SIGTERM handler (``SigCgt`` in ``/proc/PID/status``) -- before that, a
  Ctrl-C prints Python's traceback and SIGTERM ends it without a word;
* **stopping**: seconds from Ctrl-C (SIGINT to the process group, once the workers of
  ``sweep --jobs 2`` exist) until the command has exited and no process of it is left.

Usage::

    git worktree add /tmp/base 2d5cfbf
    python benchmarks/bench_signals.py --baseline /tmp/base [--repeat 10] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import signal
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(HERE / "tests"))
from helpers import processes  # noqa: E402

LONG = ["simulate", "hydraulic", "--friction", "nmlgm-hysteresis", "--input",
        "sine:amplitude=4.5e-3,frequency=1", "--duration", "200", "--rate", "200", "-o",
        "long.csv"]
SWEEP = ["sweep", "--samples", "20", "--jobs", "2", "--no-progress", "--json", "s.json"]


def _start(root: Path, args: list[str], cwd: Path):  # type: ignore[no-untyped-def]
    import os
    import subprocess

    env = dict(os.environ, PYTHONPATH=str(root))
    env.pop("FCOMP_DEBUG", None)
    return subprocess.Popen([sys.executable, "-m", "fcomp.cli.main", *args], cwd=cwd, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def answering(root: Path, cwd: Path) -> float:
    """Seconds until the command answers signals (its SIGTERM handler is installed)."""
    t0 = time.monotonic()
    proc = _start(root, LONG, cwd)
    processes.wait_for(lambda: processes.sigterm_caught(proc.pid), proc)
    took = time.monotonic() - t0
    processes.send(proc, signal.SIGTERM)
    proc.communicate(timeout=processes.PATIENCE)
    processes.group_gone(proc.pid)
    return took


def stopping(root: Path, cwd: Path) -> tuple[float, str]:
    """Seconds from Ctrl-C during the parallel work until nothing of the command is left,
    and its last stderr line."""
    proc = _start(root, SWEEP, cwd)
    processes.wait_for(lambda: len(processes.children(proc.pid)) >= 2, proc)
    sent = time.monotonic()
    processes.send(proc, signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=processes.PATIENCE)
    except Exception:  # a hang: counted at the limit
        err = b"(no end)"
    processes.wait_for(lambda: not processes.group(proc.pid))
    took = time.monotonic() - sent
    processes.group_gone(proc.pid, 1.0)
    lines = err.decode(errors="replace").strip().splitlines()
    return took, (lines[-1] if lines else "")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", required=True, help="a checkout of the baseline")
    ap.add_argument("--repeat", type=int, default=10)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    roots = {"baseline": Path(args.baseline).resolve(), "this": HERE}
    out: dict[str, dict[str, list]] = {k: {"answering": [], "stopping": [], "lines": []}
                                       for k in roots}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.repeat):  # A B A B: both under the same load
            for name, root in roots.items():
                out[name]["answering"].append(answering(root, Path(tmp)))
                took, line = stopping(root, Path(tmp))
                out[name]["stopping"].append(took)
                out[name]["lines"].append(line)
    print(f"{'':10s} {'answers signals after':>24s} {'stops after Ctrl-C':>20s}  last line")
    for name in roots:
        a, s = (statistics.median(out[name][k]) for k in ("answering", "stopping"))
        last = max(set(out[name]["lines"]), key=out[name]["lines"].count)
        print(f"{name:10s} {a:22.3f} s {s:18.2f} s  {last!r}")
    ratio = {k: statistics.median(out["this"][k]) / statistics.median(out["baseline"][k])
             for k in ("answering", "stopping")}
    print(f"ratio this/baseline: answering {ratio['answering']:.3f}, stopping "
          f"{ratio['stopping']:.2f}")
    if args.json:
        Path(args.json).write_text(json.dumps({"runs": out, "ratio": ratio}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
