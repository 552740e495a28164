"""Read what a process writes to a pseudo-terminal (test helper)."""

from __future__ import annotations

import os
import select
import subprocess


def drain(master: int, proc: subprocess.Popen | None = None) -> bytes:
    """Everything readable from the pty ``master`` until it closes, or -- with ``proc`` --
    until ``proc`` has ended and nothing is left to read (0.5 s of quiet); without ``proc``
    0.5 s of quiet ends it."""
    seen = b""
    while True:
        if select.select([master], [], [], 0.5)[0]:
            try:
                chunk = os.read(master, 4096)
            except OSError:  # the slave side closed (Linux)
                break
            if not chunk:
                break
            seen += chunk
        elif proc is None or proc.poll() is not None:
            break
    return seen
