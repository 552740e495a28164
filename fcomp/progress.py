"""Progress of long work: one callback protocol, one way to report it, one bar.

Every long piece of work in fcomp with a known total -- a simulation over many
samples, a batch of parallel jobs (:func:`fcomp.parallel.run_tasks`) -- tells
its progress the same way: a :class:`ProgressCallback`
``callback(done, total)`` is called with the amount of work done so far out of
``total``, in the units of the work (jobs for a batch, seconds of simulated
time from the start of the run for a simulation), so ``done/total`` is the
fraction done.

* **Passing it down.** A function that runs a batch takes the callback as an
  argument (``run_tasks(..., progress=callback)``). Work that sits deep under
  layers that do not pass it along (the engine inside a plant inside a study)
  reports to the innermost ``with reporting(callback):`` block instead, through
  :func:`report`; :func:`receiver` tells whether anyone listens (the engine then
  runs in pieces to report between them).
* **Drawing it.** :func:`progress_bar` is a tqdm bar on stderr (or, in a worker
  process whose bars are relayed, one drawn by the parent,
  :class:`ProgressRelay`); :func:`ticker` is the callback that advances a bar
  by the jobs done.
* **Work without a total** (a diagnosis's fits: how many depends on what it
  finds) counts one unit at a time, saying which: a :data:`Tick`
  ``tick(what)``, drawn by :func:`counter` (:func:`quiet` draws nothing).

A bar offers ``update(n)``, ``set_postfix_str(text, refresh=True)``,
``close()``, ``n`` and ``total`` (tqdm's names) whichever kind it is.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, Protocol, TypeVar

#: The unit of the work counted: ``int`` (jobs) or ``float`` (seconds of simulated time).
Unit = TypeVar("Unit", int, float, contravariant=True)


class ProgressCallback(Protocol[Unit]):
    """``callback(done, total)``: ``done`` units of work of ``total`` are finished.

    Called with ``0 < done <= total`` after each finished piece, in order (a
    batch that is run again starts again from its first piece). It must be
    quick and must not raise: it runs inside the work it reports.
    ``ProgressCallback[int]`` counts jobs (:func:`fcomp.parallel.run_tasks`),
    ``ProgressCallback[float]`` seconds of simulated time (:func:`report`).
    """

    def __call__(self, done: Unit, total: Unit, /) -> None: ...


#: The callbacks of the open :func:`reporting` blocks, innermost last.
_RECEIVERS: list[ProgressCallback[float]] = []


@contextmanager
def reporting(callback: ProgressCallback[float]) -> Iterator[None]:
    """Send the progress that the work inside the block :func:`report`\\ s to ``callback``."""
    _RECEIVERS.append(callback)
    try:
        yield
    finally:
        _RECEIVERS.pop()


def receiver() -> ProgressCallback[float] | None:
    """The callback of the innermost :func:`reporting` block, or ``None`` outside one."""
    return _RECEIVERS[-1] if _RECEIVERS else None


def report(done: float, total: float) -> None:
    """Tell the innermost :func:`reporting` block how far the work is (no-op outside one)."""
    if _RECEIVERS:
        _RECEIVERS[-1](done, total)


def ticker(bar: Any) -> ProgressCallback[int]:
    """A callback advancing ``bar`` by the jobs finished since its last call; it serves
    several batches in turn (``done`` starting again from 1)."""
    seen = [0]

    def tick(done: int, total: int) -> None:
        bar.update(done - seen[0] if done >= seen[0] else done)
        seen[0] = done if done < total else 0

    return tick


# ------------------------------------------------------------------ bars
#: Where this process's progress bars go instead of the terminal: a queue read by the
#: :class:`ProgressRelay` of the parent process (set in a worker by :func:`relay_progress`).
_RELAY: Any = None


def relay_progress(queue: Any) -> None:
    """Send the progress bars of this process (:func:`progress_bar`) to ``queue``, where the
    parent's :class:`ProgressRelay` draws them; ``None`` draws them here again."""
    global _RELAY
    _RELAY = queue


@contextmanager
def running(name: str) -> Iterator[None]:
    """Name, on the head bar of the parent's :class:`ProgressRelay`, the work this process
    does inside the block (``study all``: the studies running now); nothing without a
    relay (:func:`relay_progress`)."""
    queue = _RELAY
    if queue is None:
        yield
        return
    key = f"{os.getpid()}:{name}"
    queue.put(("running", key, name))
    try:
        yield
    finally:
        queue.put(("ran", key))


class RelayedBar:
    """A progress bar of a worker process, drawn by the parent (:class:`ProgressRelay`): the
    part of tqdm's interface the package uses (module docstring)."""

    def __init__(self, queue: Any, label: str, total: int | None, unit: str) -> None:
        self.queue = queue
        self.key = f"{os.getpid()}:{id(self)}"
        self.n = 0
        self.total = total
        queue.put(("open", self.key, label, total, unit))

    def update(self, n: int = 1) -> None:
        self.n += n
        self.queue.put(("update", self.key, n))

    def set_postfix_str(self, text: str, refresh: bool = True) -> None:
        self.queue.put(("postfix", self.key, text))

    def close(self) -> None:
        self.queue.put(("close", self.key))


class ProgressRelay:
    """Draw on this terminal the progress bars of worker processes (a context manager).

    :attr:`queue` goes to the workers (a :mod:`multiprocessing` manager's queue, which
    can be passed to a pool's jobs), whose :func:`progress_bar` calls then
    arrive here after :func:`relay_progress`; a thread draws one tqdm bar per worker bar,
    each on its own line, below ``head`` (the parent's own bar, whose postfix names the work
    running now, :func:`running`). ``enabled=False`` (or stderr not a terminal): nothing is
    drawn and :attr:`queue` is ``None``.
    """

    def __init__(self, *, enabled: bool = True, head: Any = None) -> None:
        self.enabled = enabled and on_terminal()
        self.head = head
        self.queue: Any = None

    def __enter__(self) -> ProgressRelay:
        if self.enabled:
            import multiprocessing
            import threading

            self._manager = multiprocessing.Manager()
            self.queue = self._manager.Queue()
            self._thread = threading.Thread(target=self._draw, daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.queue is not None:
            self.queue.put(None)
            self._thread.join()
            self._manager.shutdown()
            self.queue = None

    def _draw(self) -> None:
        from tqdm import tqdm

        bars: dict[str, Any] = {}
        lines: list[str | None] = []  # the screen line of each open bar
        names: dict[str, str] = {}  # the work running now (:func:`running`), in start order
        while (msg := self.queue.get()) is not None:
            kind, key = msg[0], msg[1]
            if kind in ("running", "ran"):
                if kind == "running":
                    names[key] = msg[2]
                else:
                    names.pop(key, None)
                if self.head is not None:
                    self.head.set_postfix_str(f"running {', '.join(names.values())}"
                                              if names else "")
            elif kind == "open":
                line = lines.index(None) if None in lines else len(lines)
                lines[line:line + 1] = [key]
                bars[key] = tqdm(total=msg[3], desc=msg[2], unit=msg[4], file=sys.stderr,
                                 position=line + 1, leave=False, dynamic_ncols=True)
            elif key in bars and kind == "update":
                bars[key].update(msg[2])
            elif key in bars and kind == "postfix":
                bars[key].set_postfix_str(msg[2])
            elif key in bars and kind == "close":
                bars.pop(key).close()
                lines[lines.index(key)] = None
        for bar in bars.values():
            bar.close()


def progress_bar(label: str, total: int | None, *, enabled: bool = True, unit: str = "run"
                 ) -> Any:
    """A tqdm progress bar on stderr of ``total`` ``unit``\\ s (``None``: not known in
    advance, a counter), left off the screen at the end; shown only when ``enabled`` and
    stderr is a terminal (:func:`on_terminal`), else a bar that draws nothing: no bar ever
    goes into a file or a pipe. In a worker whose bars are relayed (:func:`relay_progress`)
    the parent process draws it (on its terminal only, :class:`ProgressRelay`)."""
    from tqdm import tqdm

    if enabled and _RELAY is not None:
        return RelayedBar(_RELAY, label, total, unit)
    return tqdm(total=total, desc=label, unit=unit, file=sys.stderr, leave=False,
                disable=not (enabled and on_terminal()), dynamic_ncols=True)


def on_terminal() -> bool:
    """Whether stderr is a terminal: the only place progress is drawn."""
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):  # replaced by an object without it, or closed
        return False


#: One unit of work done, named (``tick("refit of dwell-time")``): work without a total.
Tick = Callable[[str], None]


def quiet(what: str) -> None:
    """A :data:`Tick` that shows nothing."""


@contextmanager
def counter(label: str, *, enabled: bool = True, unit: str = "run") -> Iterator[Tick]:
    """A :data:`Tick` advancing a :func:`progress_bar` without a total by one, with what was
    done beside it; the bar is closed on leaving."""
    bar = progress_bar(label, None, enabled=enabled, unit=unit)

    def tick(what: str) -> None:
        bar.set_postfix_str(what, refresh=False)
        bar.update(1)

    try:
        yield tick
    finally:
        bar.close()


__all__ = ["ProgressCallback", "Tick", "counter", "quiet", "ProgressRelay", "RelayedBar", "on_terminal",
           "progress_bar", "receiver", "relay_progress", "report", "reporting", "running", "ticker"]
