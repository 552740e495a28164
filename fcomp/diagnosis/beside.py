"""The baseline check run beside the main search, in processes of its own.

The baseline check (:func:`.loop.baseline_check`) diagnoses the record again from a
baseline of the other kind; by default (``check_baseline="auto"``) only when the first
answer is doubtful, which is known only once the first diagnosis has ended. Run after it,
the check doubled the time of every doubtful answer (the four O-ring files: 58 s of a
123 s diagnosis), while the first diagnosis's serial phases -- the baseline fit, the
polish of each accepted model, the backward check -- left a core idle.

So the check starts at once, beside the main search, in a process of its own with its
own candidate workers (:class:`CheckBeside`): asked for (``True``) at the priority of
this process; only possibly needed (``"auto"``) at a lower one (:data:`SPECULATIVE_NICE`),
so that it takes the time the main search leaves idle rather than slowing it. When the
first answer is in, the check is awaited if it is needed and ended (with every process
it started) if not. Its fits count on in the one progress bar (its ticks come back over
a queue). The answer is the check's own: the same configuration with the other baseline,
on the record as prepared (a periodic disturbance the main search took off is found by the
check itself).

Where no second process is to be had -- one worker asked for (``n_jobs=1``), a Dask
scheduler, a baseline or an effect defined in the caller's ``__main__`` -- the check runs
after the first diagnosis, as before.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import queue as queue_mod
from collections.abc import Callable, Iterator
from concurrent.futures import Future
from typing import Any

from fcomp.diagnosis.data import DiagnosisData
from fcomp.diagnosis.regimes import segment
from fcomp.diagnosis.result import OTHER_BASELINE, DiagnosisResult
from fcomp.diagnosis.workers import n_workers, worker_pool
from fcomp.errors import FcompError
from fcomp.parallel import HeldPool, main_objects, pool_context, stop, worker_signals
from fcomp.progress import Tick
from fcomp.usercode import load_sources, user_sources

#: Niceness added to a check that may not be needed (``check_baseline="auto"``): it runs in
#: the time the main search leaves idle.
SPECULATIVE_NICE = 10
#: Seconds between looks at the check's progress while it is awaited.
POLL_SECONDS = 0.5

#: The queue this process's ticks go to (set in the check's process).
_TICKS: Any = None


def other_name(config: Any, data: DiagnosisData) -> str | None:
    """The baseline of the other kind for ``config`` on ``data`` (as
    :func:`.result.other_baseline`, from the configuration before any fit), or None."""
    model = config.model
    if model.n_states:
        return OTHER_BASELINE["dynamic"]
    if data.steady_state or not segment(data).starts:
        return None
    return OTHER_BASELINE["static"]


def _start(sources: tuple[tuple[str, str, str], ...], ticks: Any, nice: int) -> None:
    """The check process's first act: the signals of a pool worker (the parent answers
    Ctrl-C and ends it), its priority, its tick queue and the user's code."""
    global _TICKS
    worker_signals()
    if nice:
        with contextlib.suppress(OSError):
            os.nice(nice)
    _TICKS = ticks
    load_sources(sources)


def _tick(what: str) -> None:
    with contextlib.suppress(Exception):  # progress only: never the check's failure
        _TICKS.put_nowait(what)


def run_check(diagnose: Callable[..., Any], config: Any, data: DiagnosisData
              ) -> DiagnosisResult | str:
    """The check's diagnosis (``diagnose``, :func:`.loop.diagnose`) in its process (its own
    candidate workers, started here and inheriting its priority); a string says why no
    answer came."""
    try:
        with worker_pool(config.n_jobs, None, len(config.names) if config.search else 0
                         ) as pool:
            result = diagnose(config, data, pool, _tick)[0]
    except FcompError as exc:
        return str(exc).splitlines()[0] if str(exc) else "failed"
    return dataclasses.replace(result, check={"ran": False, "why": "not asked for"})


class CheckBeside:
    """The baseline check started beside the main search (module docstring).

    Use :func:`check_beside`; :meth:`result` gives the check's answer (waiting for it),
    :meth:`cancel` ends it. ``tick`` passes the check's progress on to the main bar.
    """

    def __init__(self, diagnose: Callable[..., Any], config: Any, data: DiagnosisData,
                 tick: Tick, speculative: bool) -> None:
        ctx = pool_context(spawn=True)
        self._ticks = ctx.Queue()
        self._outer = tick
        self._pool = HeldPool(
            max_workers=1, mp_context=ctx, initializer=_start,
            initargs=(user_sources(), self._ticks, SPECULATIVE_NICE if speculative else 0))
        self.baseline = config.baseline
        self._future: Future[DiagnosisResult | str] = self._pool.submit(run_check, diagnose,
                                                                         config, data)
        self.done = False
        self._outer(f"baseline check: {config.baseline} (beside)")

    def tick(self, what: str) -> None:
        """The main search's tick, with the check's ticks since the last one passed on."""
        self._drain()
        self._outer(what)

    def _drain(self) -> None:
        while True:
            try:
                what = self._ticks.get_nowait()
            except (queue_mod.Empty, OSError, ValueError):
                return
            self._outer(f"check: {what}")

    def result(self) -> DiagnosisResult | None:
        """The check's answer (waited for), or None when it failed (its reason in ``why``)."""
        while True:
            try:
                out = self._future.result(timeout=POLL_SECONDS)
                break
            except TimeoutError:
                self._drain()
        self._drain()
        self.close()
        self.done = True
        if isinstance(out, str):
            self.why = out
            return None
        return out

    def cancel(self) -> None:
        """End the check now, with every process it started."""
        stop(self._pool)
        self.close()
        self.done = True

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)
        with contextlib.suppress(Exception):
            self._ticks.close()
            self._ticks.join_thread()

    why: str = ""


def can_run_beside(config: Any, *extra: Any) -> bool:
    """Whether the check can run in a process of its own: two or more workers, no Dask
    scheduler, and nothing of the caller's ``__main__`` in the configuration."""
    if config.check_baseline is False or config.scheduler or n_workers(config.n_jobs) < 2:
        return False
    return not main_objects(config, *extra)


@contextlib.contextmanager
def check_beside(diagnose: Callable[..., Any], config: Any, data: DiagnosisData, tick: Tick
                 ) -> Iterator[CheckBeside | None]:
    """The check (``diagnose`` with the other baseline) started beside the main search where
    it can be (:func:`can_run_beside`), or None; ended on leaving unless its answer was
    taken (:meth:`CheckBeside.result`)."""
    other = other_name(config, data) if can_run_beside(config) else None
    if other is None:
        yield None
        return
    second = dataclasses.replace(config, baseline=other, add=(), check_baseline=False)
    beside = CheckBeside(diagnose, second, data, tick,
                         speculative=config.check_baseline == "auto")
    try:
        yield beside
    finally:
        if not beside.done:
            beside.cancel()
