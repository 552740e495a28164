"""One-line progress displays of a command on a terminal (nothing in files or pipes)."""

from __future__ import annotations

import sys
import threading
import time
from typing import Any


class Progress:
    """A one-line progress display of a long simulation, on a terminal only.

    Shown once the run has taken ``delay`` s, updated at most twice a second,
    erased at the end: nothing is left on the screen, nothing goes to a
    redirected stderr.
    """

    def __init__(self, label: str, total: float, *, enabled: bool = True,
                 delay: float = 2.0) -> None:
        self.label, self.total, self.delay = label, total, delay
        self.enabled = enabled and sys.stderr.isatty()
        self.shown = False
        self._cm: Any = None

    def __enter__(self) -> Progress:
        from fcomp.progress import reporting

        self.start = self.last = time.monotonic()
        if self.enabled:
            self._cm = reporting(lambda done, total: self.update(done / total, done))
            self._cm.__enter__()
        return self

    def update(self, fraction: float, t: float) -> None:
        now = time.monotonic()
        if now - self.start < self.delay or now - self.last < 0.5 or fraction <= 0:
            return
        self.last = now
        spent = now - self.start
        left = spent * (1.0 - fraction) / fraction
        sys.stderr.write(f"\r{self.label}: {100 * fraction:.0f} % (t = {t:.4g} of "
                         f"{self.total:g} s, {_clock(spent)} spent, about {_clock(left)} left; "
                         "Ctrl-C stops)\x1b[K")
        sys.stderr.flush()
        self.shown = True

    def __exit__(self, *exc: Any) -> None:
        if self._cm is not None:
            self._cm.__exit__(*exc)
        if self.shown:
            sys.stderr.write("\r\x1b[K")
            sys.stderr.flush()


class Activity:
    """A one-line "still working" display for a step of unknown length (a fit), terminal only.

    Shown once the step has taken ``delay`` s: the label and the time spent,
    refreshed every half second by a background thread, erased at the end.
    """

    def __init__(self, label: str, *, enabled: bool = True, delay: float = 2.0) -> None:
        self.label, self.delay = label, delay
        self.enabled = enabled and sys.stderr.isatty()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.shown = False

    def _run(self) -> None:
        start = time.monotonic()
        while not self._stop.wait(0.5):
            spent = time.monotonic() - start
            if spent >= self.delay:
                sys.stderr.write(f"\r{self.label}: {_clock(spent)} spent (Ctrl-C stops)\x1b[K")
                sys.stderr.flush()
                self.shown = True

    def __enter__(self) -> Activity:
        if self.enabled:
            self._thread = threading.Thread(target=self._run, daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._thread is not None:
            self._stop.set()
            self._thread.join()
        if self.shown:
            sys.stderr.write("\r\x1b[K")
            sys.stderr.flush()


def _clock(seconds: float) -> str:
    m, s = divmod(int(seconds), 60)
    h, m = divmod(m, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"
