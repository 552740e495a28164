"""Independent jobs run in parallel: local processes by default, or a Dask cluster.

Every command that runs many independent jobs -- the closed-loop runs of
``fcomp study compensators`` and ``fcomp sweep``, the fits of ``fcomp fit``
over several records, the candidate refits of ``fcomp diagnose`` -- runs them
through here:

* **local processes** (default): a :class:`concurrent.futures.ProcessPoolExecutor`
  with ``workers`` processes (default: the CPU count); one worker runs the jobs
  in this process;
* the user's own code (``--effects`` files) is executed in every worker first,
  so jobs carrying a user's effect unpickle there;
* **an existing Dask distributed cluster** (``scheduler="tcp://host:8786"``,
  the command line's ``--scheduler ADDRESS``): the jobs go to its workers
  (started with ``dask scheduler`` / ``dask worker``, or by a cluster manager),
  which must have fcomp installed. The cluster is only used, never started or
  stopped here.

A job is a picklable function and argument: it carries everything it needs,
so a result does not depend on where it ran (the tests compare a cluster's
results with the local ones). Results come back in the order of the jobs;
``progress(done, total)`` (a :class:`fcomp.progress.ProgressCallback`, counting
jobs) is called as they arrive. The commands' progress bars (:func:`progress_bar`,
:func:`ticker`, :class:`ProgressRelay`, :func:`relay_progress`) are those of
:mod:`fcomp.progress`, importable from here as well.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor, as_completed
from contextlib import AbstractContextManager, contextmanager, suppress
from typing import Any, TypeVar

from fcomp.errors import FcompError, term
from fcomp.progress import ProgressCallback
from fcomp.usercode import load_sources, user_sources

#: The BLAS libraries of this process (:mod:`threadpoolctl`), found at the first
#: :func:`one_blas_thread`.
_BLAS: Any = None


def one_blas_thread() -> AbstractContextManager[Any]:
    """A context in which numpy's and scipy's BLAS/LAPACK run on one thread.

    The fits' linear algebra is tall and thin (``N x p`` with ``p`` at most a few
    tens): a second BLAS thread gains nothing there, and where the other core is
    busy -- a second worker process, the user's other work -- OpenBLAS's threads
    wait on each other. Measured on the 2-core machine beside other work: the QR
    of a 36 000 x 13 Jacobian 40 ms on OpenBLAS's threads against 4.3 ms on one,
    and a 12 s LuGre diagnosis 117 s against 52 s. Only the code inside the
    context is limited; the user's own numpy keeps its threads.
    """
    global _BLAS
    if _BLAS is None:
        from threadpoolctl import ThreadpoolController

        _BLAS = ThreadpoolController()
    return _BLAS.limit(limits=1, user_api="blas")


T = TypeVar("T")
R = TypeVar("R")

#: Seconds to wait for a Dask scheduler to answer.
CONNECT_TIMEOUT = 10.0


def check_scheduler(address: str | None) -> str | None:
    """``address`` as a Dask scheduler address (``tcp://host:port``, ``host:port``), checked
    for its form only; ``None`` stays ``None``."""
    if address is None:
        return None
    text = address.strip()
    if not text:
        raise FcompError(f"{term('scheduler')}: no address given (an empty argument)")
    rest = text.split("://", 1)[1] if "://" in text else text
    if ":" not in rest and "/" not in rest:
        raise FcompError(f"{term('scheduler')} {address}: give the scheduler's address with "
                         "its port, e.g. tcp://127.0.0.1:8786")
    return text


@contextmanager
def dask_client(address: str) -> Iterator[Any]:
    """A :class:`distributed.Client` connected to the scheduler at ``address`` (closed at the
    end); one clear line when Dask is missing or the scheduler does not answer."""
    try:
        from distributed import Client
    except ImportError:
        raise FcompError(f"{term('scheduler')} needs Dask distributed: pip install "
                         "'fcomp[distributed]'") from None
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as exc:
        raise FcompError(f"{term('scheduler')} {address}: cannot connect to the Dask "
                         f"scheduler ({str(exc).splitlines()[0] if str(exc) else 'no answer'})"
                         ) from None
    try:
        yield client
    finally:
        client.close()


@contextmanager
def executor(scheduler: str | None = None, workers: int | None = None
             ) -> Iterator[Executor | None]:
    """A :class:`concurrent.futures.Executor` for jobs: the Dask cluster's at ``scheduler``,
    else a local process pool of ``workers`` (``None`` when one worker: run here)."""
    if scheduler:
        with dask_client(scheduler) as client:
            if user_sources():  # the user's --effects code, on every worker of the cluster
                client.run(load_sources, user_sources())
            yield client.get_executor(pure=False)
        return
    n = workers if workers is not None else (os.cpu_count() or 1)
    if n < 1:
        raise FcompError(f"workers must be a positive number, got {workers}")
    if n == 1:
        yield None
        return
    with stopping(process_pool(n)) as pool:
        yield pool


def process_pool(workers: int, *, spawn: bool = False) -> ProcessPoolExecutor:
    """A local process pool whose workers first execute the user's own code (``--effects``
    files, :func:`fcomp.usercode.load_sources`); ``spawn`` starts them fresh (the default
    on macOS and Windows) rather than forked. Its workers leave Ctrl-C and SIGTERM to the
    parent (:func:`stopping`)."""
    import multiprocessing

    ctx = multiprocessing.get_context("spawn") if spawn else None
    return ProcessPoolExecutor(max_workers=workers, mp_context=ctx,
                               initializer=_worker_start, initargs=(user_sources(),))


def _worker_start(sources: tuple[tuple[str, str, str], ...]) -> None:
    """A local worker's first act: Ctrl-C at a terminal reaches every process of the group,
    and the parent alone answers it (it stops the workers, :func:`stopping`: no traceback
    from each); SIGTERM ends the worker at once, whatever a forked parent installed. Then
    the user's files are executed (:func:`fcomp.usercode.load_sources`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    load_sources(sources)


@contextmanager
def stopping(pool: ProcessPoolExecutor) -> Iterator[ProcessPoolExecutor]:
    """``pool``, shut down on leaving: after its work, waiting for it; on an interrupt or an
    error, at once -- pending jobs cancelled and the workers ended, not waited for (a refit
    can take many seconds)."""
    try:
        yield pool
    except BaseException:
        stop(pool)
        raise
    pool.shutdown()


def stop(pool: Executor) -> None:
    """Cancel ``pool``'s pending jobs and end its local workers now, with every process they
    started (a study's worker runs a pool of its own: left alive, those processes would go
    on computing, and hold the pipes whose closing tells this process that its workers
    ended -- ``fcomp study all`` then hung at exit); a Dask client's jobs are cancelled, its
    workers are the cluster's."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    pids = [p.pid for p in procs if p.is_alive() and p.pid is not None]
    for pid in [*_descendants(pids), *pids]:  # the innermost first: no new orphan meanwhile
        with suppress(ProcessLookupError, PermissionError):  # ended meanwhile, or not ours
            os.kill(pid, signal.SIGTERM)


def _descendants(pids: Sequence[int]) -> list[int]:
    """The processes started by ``pids`` and by theirs, innermost first (from ``/proc``;
    none where there is no ``/proc``)."""
    parents: dict[int, list[int]] = {}
    try:
        entries = os.listdir("/proc")
    except OSError:
        return []
    for entry in entries:
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as f:
                stat = f.read()
        except OSError:  # ended meanwhile
            continue
        fields = stat[stat.rfind(b")") + 2:].split()  # after "pid (name) "
        if len(fields) > 1 and fields[1].isdigit():
            parents.setdefault(int(fields[1]), []).append(int(entry))
    found: list[int] = []
    todo = list(pids)
    while todo:
        kids = parents.get(todo.pop(), [])
        found += kids
        todo += kids
    return found[::-1]


def run_tasks(fn: Callable[[T], R], items: Sequence[T], *, workers: int | None = None,
              scheduler: str | None = None,
              progress: ProgressCallback[int] | None = None) -> list[R]:
    """``[fn(item) for item in items]``, run in parallel (see the module docstring)."""
    items = list(items)
    total = len(items)
    results: list[Any] = [None] * total
    if not scheduler and (total <= 1 or (workers or os.cpu_count() or 1) == 1):
        for i, item in enumerate(items):
            results[i] = fn(item)
            if progress:
                progress(i + 1, total)
        return results
    with executor(scheduler, min(workers or os.cpu_count() or 1, total)) as pool:
        assert pool is not None
        futures = {pool.submit(fn, item): i for i, item in enumerate(items)}
        for done, fut in enumerate(as_completed(futures), start=1):
            results[futures[fut]] = fut.result()
            if progress:
                progress(done, total)
    return results


__all__ = ["check_scheduler", "dask_client", "executor", "process_pool", "run_tasks", "stop",
           "stopping"]
