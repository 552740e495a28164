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
* the caller's ``__main__`` -- a script, ``python -``, a notebook's kernel -- is
  **never run again** in a worker (:func:`pool_context`): fcomp's jobs are its own
  functions, which a worker imports by module name, so a plain script without an
  ``if __name__ == "__main__":`` guard just works. Something defined *in* the
  caller's ``__main__`` (an effect class written in a notebook cell) cannot reach
  such a worker: those jobs run here, one after another, with one warning
  (:func:`shippable`);
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

import multiprocessing
import multiprocessing.context
import os
import pickle
import signal
import sys
import threading
import types
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor, as_completed
from contextlib import AbstractContextManager, contextmanager, suppress
from pathlib import Path
from typing import Any, TypeVar

from fcomp.errors import FcompError, FcompWarning, term
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
    on macOS and Windows) rather than forked. Its workers never run the caller's
    ``__main__`` (:func:`pool_context`) and leave Ctrl-C and SIGTERM to the parent
    (:func:`stopping`)."""
    return HeldPool(max_workers=workers, mp_context=pool_context(spawn),
                 initializer=_worker_start, initargs=(user_sources(),))


class HeldPool(ProcessPoolExecutor):
    """A process pool that starts each worker with Ctrl-C and SIGTERM held off until the
    worker is registered in the pool: a signal landing just as a worker started used to
    leave it out of the pool's list, so :func:`stop` did not end it and the command hung
    at exit waiting for it. The worker itself starts with the signals held, too, until
    its first act (:func:`worker_signals`, which every initializer must call) has set
    its own handling."""

    def _spawn_process(self) -> None:
        from fcomp.outputs import signals_held

        with signals_held():
            super()._spawn_process()  # type: ignore[misc]


#: Held while a worker process starts with the caller's ``__main__`` hidden.
_HIDING = threading.Lock()


class _MainHidden:
    """A process that starts without the caller's ``__main__``.

    A fresh (``spawn``, ``forkserver``) process is told by
    :func:`multiprocessing.spawn.get_preparation_data` to run the parent's main
    module again -- by its file (``python script.py``) or its module name
    (``python -m``) -- so that functions defined there unpickle. fcomp's jobs
    never need it, and running it is wrong: a script without an ``if __name__ ==
    "__main__":`` guard runs again in every worker, starts pools there and the
    pool breaks (``BrokenProcessPool``). While the process starts, ``__main__``
    is a bare module (no ``__spec__``, no ``__file__``), so the worker is told
    nothing about it. ``fork`` is not used instead: forking a process that runs
    threads (a progress relay, BLAS, the user's own) is unsafe.
    """

    def start(self) -> None:
        with _HIDING:
            main = sys.modules.get("__main__")
            sys.modules["__main__"] = types.ModuleType("__main__")
            try:
                super().start()  # type: ignore[misc]
            finally:
                if main is None:
                    sys.modules.pop("__main__", None)
                else:
                    sys.modules["__main__"] = main


class _SpawnProcess(_MainHidden, multiprocessing.context.SpawnProcess):
    pass


class _SpawnContext(multiprocessing.context.SpawnContext):
    Process = _SpawnProcess


_CONTEXTS: dict[str, multiprocessing.context.BaseContext] = {"spawn": _SpawnContext()}
if hasattr(multiprocessing.context, "ForkServerContext"):  # not on Windows
    class _ForkServerProcess(_MainHidden, multiprocessing.context.ForkServerProcess):
        pass

    class _ForkServerContext(multiprocessing.context.ForkServerContext):
        Process = _ForkServerProcess

    _CONTEXTS["forkserver"] = _ForkServerContext()


def pool_context(spawn: bool = False) -> multiprocessing.context.BaseContext:
    """The :mod:`multiprocessing` context of fcomp's local pools: ``spawn`` (or, by default,
    this platform's start method) with workers that never run the caller's ``__main__``
    (:class:`_MainHidden`); ``fork`` copies the parent and runs nothing again."""
    method = "spawn" if spawn else multiprocessing.get_start_method()
    if method != "fork":
        _quiet_tracker()
    return _CONTEXTS.get(method) or multiprocessing.get_context(method)


def _quiet_tracker() -> None:
    """Start :mod:`multiprocessing`'s resource tracker, if it is not running yet, with its
    standard error on the null device.

    Workers started fresh (``spawn``, ``forkserver``) register their queues' semaphores
    with the tracker, and a worker fcomp ends on purpose (a baseline check found not
    needed, a command stopped by Ctrl-C: :func:`stop`) cannot unregister them. The tracker
    unlinks them once every process that shares it has ended -- that is its job -- and
    then prints ``UserWarning: resource_tracker: There appear to be 5 leaked semaphore
    objects`` on the command's standard error, after its answer (seen at the end of every
    ``diagnose --jobs 2`` whose check was not needed). Those lines are multiprocessing's
    bookkeeping of a designed end, not the user's concern; the unlinking still happens.
    A tracker already running (the caller's own) is left as it is."""
    from multiprocessing import resource_tracker

    tracker = resource_tracker._resource_tracker
    if getattr(tracker, "_fd", None) is not None:
        return
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
    except OSError:
        return
    saved = -1
    try:
        saved = os.dup(2)
        os.dup2(devnull, 2)
        resource_tracker.ensure_running()
    except OSError:
        pass
    finally:
        if saved >= 0:
            os.dup2(saved, 2)
            os.close(saved)
        os.close(devnull)


def fresh_workers(pool: Executor | None) -> bool:
    """Whether ``pool`` is a local pool whose workers start fresh (``spawn``,
    ``forkserver``): they have none of the caller's ``__main__``."""
    if not isinstance(pool, ProcessPoolExecutor):
        return False
    ctx = getattr(pool, "_mp_context", None)
    return ctx is not None and ctx.get_start_method() != "fork"


class _Sink:
    def write(self, data: bytes) -> int:
        return len(data)


def main_objects(*objs: Any) -> list[str]:
    """The names of what pickling ``objs`` would take from the caller's ``__main__``
    (classes, functions, instances of its classes), in the order met."""
    found: list[str] = []

    class Finder(pickle.Pickler):
        def reducer_override(self, obj: Any) -> Any:
            kind = obj if isinstance(obj, type | types.FunctionType) else type(obj)
            if getattr(kind, "__module__", None) == "__main__":
                name = getattr(kind, "__qualname__", repr(kind))
                if not any(name == f or name.startswith(f + ".") for f in found):
                    found.append(name)  # a class's nested ones (its Params) go unnamed
            return NotImplemented

    # what cannot be pickled at all: the pool's own pickling says what is wrong
    with suppress(pickle.PicklingError, TypeError, AttributeError, ValueError):
        Finder(_Sink(), protocol=pickle.HIGHEST_PROTOCOL).dump(objs)
    return found


#: The ``__main__`` names :func:`shippable` has warned about in this process (once each).
_WARNED: set[tuple[str, ...]] = set()


def shippable(pool: Executor | None, *objs: Any) -> bool:
    """Whether jobs carrying ``objs`` can go to ``pool``'s workers.

    Not when ``pool`` starts fresh workers (:func:`fresh_workers`) and ``objs`` use
    something defined in the caller's ``__main__`` (an effect class written in a
    notebook cell or in the script itself): the workers do not run ``__main__``
    (:class:`_MainHidden`), so they could not unpickle it. Such jobs run here, one
    after another, with one :class:`~fcomp.errors.FcompWarning` (``serial``, once per
    process for the same names) saying how to run them in parallel. (Shipping them by value, ``cloudpickle``, would not
    bring their results back: a worker's copy of the class is not the caller's.)
    """
    if not fresh_workers(pool):
        return True
    names = main_objects(*objs)
    if not names:
        return True
    if tuple(names) in _WARNED:
        return False
    _WARNED.add(tuple(names))
    warnings.warn(FcompWarning(
        "serial", f"{', '.join(names)} is defined in the caller's __main__ (the script or "
        "the notebook), which worker processes do not run: these jobs run here, one after "
        "another; define it in a module you import (or an effects file, "
        f"{term('effects_module')} FILE.py) to run them in parallel"), stacklevel=3)
    return False


def _worker_start(sources: tuple[tuple[str, str, str], ...]) -> None:
    """A local worker's first act: Ctrl-C at a terminal reaches every process of the group,
    and the parent alone answers it (it stops the workers, :func:`stopping`: no traceback
    from each); SIGTERM ends the worker at once, whatever a forked parent installed. Then
    the user's files are executed (:func:`fcomp.usercode.load_sources`)."""
    worker_signals()
    load_sources(sources)


def worker_signals() -> None:
    """The signals of a worker of a :class:`HeldPool`: Ctrl-C ignored (the parent answers
    it), SIGTERM at its default whatever a forked parent installed, and both released --
    held by the parent while it started this process, so that one landing during the
    start (an interpreter importing its modules) prints no traceback."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})


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
    for pid in [*(d for d in descendants(pids) if not _tracker(d)), *pids]:  # the innermost first: no new orphan meanwhile
        with suppress(ProcessLookupError, PermissionError):  # ended meanwhile, or not ours
            os.kill(pid, signal.SIGTERM)


#: Seconds :func:`end_children` gives processes to end on SIGTERM before it kills them.
END_GRACE = 1.0


def end_children(grace: float = END_GRACE, keep: Iterable[int] = ()) -> list[int]:
    """End every process this one started that is still running -- the last act of a
    command stopped by a signal: nothing of it is left running. ``keep``: processes that
    were there before the command (a notebook's own, when the command runs in one) and
    are not ended.

    :func:`stop` ends the workers a pool lists; this ends the rest: a worker a pool was
    still starting (in another thread, or with the signals held: it takes SIGTERM only
    once started), the processes workers started, and -- when this process leads its
    process group, as a command run from a shell does -- any other member of the group
    that is one of fcomp's processes (a worker's own worker whose parent ended first; not
    the other programs of a pipeline, ``fcomp ... | tee log``). SIGTERM first; whatever is left
    after ``grace`` s (a process still starting with its signals held) is killed
    (SIGKILL). Returns the processes signalled.
    """
    import time

    multiprocessing.active_children()  # reaps the ended ones
    spared = {os.getpid(), *keep}
    pids = [p for p in descendants([os.getpid()]) if p not in spared and not _tracker(p)]
    if os.getpgrp() == os.getpid():  # a worker's worker whose parent ended first
        pids += [p for p in group_members(os.getpid())
                 if p not in pids and p not in spared and _ours(p) and not _tracker(p)]
    for pid in pids:
        with suppress(ProcessLookupError, PermissionError):
            os.kill(pid, signal.SIGTERM)
    end = time.monotonic() + grace
    while time.monotonic() < end and any(_running(p) for p in pids):
        multiprocessing.active_children()
        time.sleep(0.02)
    for pid in pids:
        if _running(pid):
            with suppress(ProcessLookupError, PermissionError):
                os.kill(pid, signal.SIGKILL)
    multiprocessing.active_children()
    return pids


def processes() -> dict[int, tuple[str, int, int]]:
    """Every process: pid -> ``(state, parent pid, process group)`` (from ``/proc``; empty
    where there is none). ``state`` ``"Z"`` is a process that has ended and is not yet
    reaped."""
    out: dict[int, tuple[str, int, int]] = {}
    try:
        entries = os.listdir("/proc")
    except OSError:
        return out
    for entry in entries:
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as f:
                stat = f.read()
        except OSError:  # ended meanwhile
            continue
        fields = stat[stat.rfind(b")") + 2:].split()  # after "pid (name) "
        if len(fields) > 2 and fields[1].isdigit() and fields[2].lstrip(b"-").isdigit():
            out[int(entry)] = (fields[0].decode(), int(fields[1]), int(fields[2]))
    return out


def _running(pid: int) -> bool:
    """Whether ``pid`` is a process that has not ended (a zombie has)."""
    found = processes().get(pid)
    if found is not None:
        return found[0] != "Z"
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, PermissionError):
        return False
    return not Path("/proc").is_dir()  # no /proc: alive as far as can be told


def _ours(pid: int) -> bool:
    """Whether ``pid`` runs what this process runs (a forked worker: the same command line)
    or a process multiprocessing started (``spawn_main``, ``forkserver``)."""
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            theirs = f.read()
        with open(f"/proc/{os.getpid()}/cmdline", "rb") as f:
            own = f.read()
    except OSError:
        return False
    return theirs == own or b"multiprocessing" in theirs


def _tracker(pid: int) -> bool:
    """Whether ``pid`` is :mod:`multiprocessing`'s resource tracker. It is spared: it ignores
    SIGTERM, so it would be killed -- and the next semaphore released at this process's
    exit would start a fresh tracker that prints a ``KeyError`` traceback for each name it
    never registered (seen after Ctrl-C in a diagnosis). Left alone, it ends by itself
    once the processes that share it have, unlinking whatever they left."""
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return b"multiprocessing.resource_tracker" in f.read()
    except OSError:
        return False


def group_members(pgid: int) -> list[int]:
    """The processes of process group ``pgid`` that have not ended."""
    return [pid for pid, (state, _, group) in processes().items()
            if group == pgid and state != "Z"]


def descendants(pids: Sequence[int]) -> list[int]:
    """The processes started by ``pids`` and by theirs, innermost first (from ``/proc``;
    none where there is no ``/proc``)."""
    parents: dict[int, list[int]] = {}
    for pid, (_, parent, _) in processes().items():
        parents.setdefault(parent, []).append(pid)
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
        if not shippable(pool, fn, items):
            return run_tasks(fn, items, workers=1, progress=progress)
        futures = {pool.submit(fn, item): i for i, item in enumerate(items)}
        for done, fut in enumerate(as_completed(futures), start=1):
            results[futures[fut]] = fut.result()
            if progress:
                progress(done, total)
    return results


__all__ = ["HeldPool", "check_scheduler", "dask_client", "descendants", "end_children", "executor",
           "fresh_workers", "group_members", "main_objects", "processes",
           "pool_context", "process_pool", "run_tasks", "shippable", "stop", "stopping", "worker_signals"]
