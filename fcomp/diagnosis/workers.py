"""The candidate refits of one step, run in worker processes or here.

The search (:mod:`.search`) is handed an executor and a progress callback;
it owns neither. :func:`worker_pool` makes the executor a diagnosis lends to
its search (a local ``spawn`` pool started beside the baseline fit, or a Dask
cluster's); :func:`refit_all` runs one step's proposals on it. Each job
carries everything it needs -- the record (:class:`.refit.Refit`, whose derived
records are rebuilt in the worker), the proposal and the current fit -- as plain
picklable values, so nothing passes through module state and the same job runs
on a Dask worker (:func:`refit_candidate`).
"""

from __future__ import annotations

import os
import time
from collections.abc import Iterator, Mapping, MutableMapping, Sequence
from concurrent.futures import Executor, as_completed
from contextlib import contextmanager

import fcomp.diagnosis.catalogue as catalogue
from fcomp.diagnosis.refit import FitResult, Refit
from fcomp.errors import FcompError
from fcomp.parallel import executor, process_pool, shippable, stop, stopping
from fcomp.progress import Tick

#: Evaluation budget of a refit without exact sensitivities (finite differences).
NONSYMBOLIC_NFEV = 8
#: How often (s) a step waiting on its local worker processes checks they are alive.
WATCH_SECONDS = 10.0


def n_workers(n_jobs: int | None) -> int:
    """The local worker processes to use (``n_jobs``; default the CPUs, at most 4)."""
    return n_jobs if n_jobs is not None else min(os.cpu_count() or 1, 4)


@contextmanager
def worker_pool(n_jobs: int | None, scheduler: str | None, candidates: int
                ) -> Iterator[Executor | None]:
    """The executor of a diagnosis's candidate refits, shut down on leaving.

    A Dask cluster's at ``scheduler``; else a local ``spawn`` pool (it runs the
    user's ``--effects`` code) of :func:`n_workers` processes, each started at once
    (a second or more to start and import fcomp: beside the baseline fit, not on the
    first step's critical path). ``None`` -- refit here -- for fewer than two
    ``candidates`` or one process.
    """
    n = n_workers(n_jobs)
    if candidates < 2 or (n < 2 and not scheduler):
        yield None
        return
    if scheduler:
        with executor(scheduler) as pool:
            yield pool
        return
    with stopping(process_pool(n, spawn=True)) as pool:
        for _ in range(n):
            pool.submit(_ready)
        yield pool


def _ready() -> None:
    """A worker's first job: nothing; unpickling it imports this module and what it needs."""


def refit_candidate(refit: Refit, prop: catalogue.Proposal, current: FitResult
                    ) -> FitResult | str:
    """Refit one proposal; a string says why it could not be.

    A model without exact sensitivities (discrete memory, finite-difference
    Jacobians, slow) is first *screened*: its data-driven start must lower the
    training error of the current model, else it is not refitted.
    """
    try:
        if not prop.model.symbolic:
            probe = refit.result(prop.model, {}, 0)
            if not probe.rms_train < current.rms_train:
                return ("screened out: its data-driven start does not lower the training error "
                        f"({probe.rms_train:.4g} N >= {current.rms_train:.4g} N)")
            return refit.fit(prop.model, prop.starts, prop.free, max_nfev=NONSYMBOLIC_NFEV)
        return refit.fit(prop.model, prop.starts, prop.free,
                         reference=refit.train_cost(current.model, current.values), fast=True)
    except (FcompError, ValueError, ArithmeticError) as exc:
        return f"refit failed: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}"


def timed_refit_candidate(refit: Refit, prop: catalogue.Proposal, current: FitResult
                          ) -> tuple[FitResult | str, float]:
    """:func:`refit_candidate` and the seconds it took where it ran (a worker's own clock)."""
    t0 = time.perf_counter()
    out = refit_candidate(refit, prop, current)
    return out, time.perf_counter() - t0


def refit_all(refit: Refit, proposals: Sequence[catalogue.Proposal], current: FitResult,
              pool: Executor | None, tick: Tick,
              seconds: MutableMapping[tuple[str, str | None], float]
              ) -> tuple[list[FitResult | str], Executor | None]:
    """Refit every proposal against ``current``: on ``pool`` where there are several.

    Returns the results (a string says why a refit failed) and the pool to use from
    now on (``None`` when a local pool lost its workers: its jobs were finished here;
    or when a model uses something of the caller's ``__main__`` its fresh workers do
    not have, :func:`fcomp.parallel.shippable`: every refit runs here).
    ``seconds`` records each refit's duration by effect and form (the order of the
    next step's jobs, :func:`longest_first`). A box a worker's fit had to widen is
    adopted by ``refit`` here.
    """
    results: list[FitResult | str] = [""] * len(proposals)
    if pool is not None and not shippable(pool, [p.model for p in proposals], current.model):
        stop(pool)  # a model of the caller's __main__: this diagnosis refits here from now on
        pool = None
    if pool is not None and len(proposals) >= 2:
        live: Executor = pool
        pending = {live.submit(timed_refit_candidate, refit, proposals[i], current): i
                   for i in longest_first(proposals, seconds)}
        while pending:
            try:
                for fut in as_completed(list(pending), timeout=WATCH_SECONDS):
                    i = pending.pop(fut)
                    results[i], took = fut.result()
                    seconds[(proposals[i].effect, proposals[i].form)] = took
                    tick(proposals[i].effect)
            except TimeoutError:
                if _workers_alive(live):
                    continue
                # the local pool lost its workers without a word (seen once in a
                # test run: futures pending, no process left): finish the jobs here
                for fut, i in pending.items():
                    fut.cancel()
                    results[i] = refit_candidate(refit, proposals[i], current)
                    tick(proposals[i].effect)
                pending.clear()
                stop(live)
                pool = None
    else:
        for i, prop in enumerate(proposals):
            # each job sees the boxes as they were, as a worker process would
            boxes = refit.box_state()
            results[i] = refit_candidate(refit, prop, current)
            refit.set_box_state(boxes)
            tick(prop.effect)
    for res in results:  # a box a worker's fit had to widen holds here too
        if isinstance(res, FitResult):
            refit.adopt_boxes(res)
    return results, pool


def longest_first(proposals: Sequence[catalogue.Proposal],
                  seconds: Mapping[tuple[str, str | None], float]) -> list[int]:
    """The order to submit ``proposals`` to the workers in: the longest jobs first.

    The refits of one step take from a fraction of a second (a static term)
    to many seconds (a memory model): submitted in catalogue order, the
    longest often started last and ran alone while the other workers idled
    (longest-processing-time-first scheduling). A job's length is what the
    same effect and form took at the previous step (``seconds``); one not run
    yet goes first, the models without exact sensitivities (finite differences)
    and then those with more states first. The results do not depend on the
    order (each job is independent).
    """
    def key(i: int) -> tuple[bool, float, bool, int]:
        prop = proposals[i]
        took = seconds.get((prop.effect, prop.form))
        return (took is not None, -(took or 0.0), prop.model.symbolic, -prop.model.n_states)

    return sorted(range(len(proposals)), key=key)


def _workers_alive(pool: Executor) -> bool:
    """Whether a local process pool still has a live worker (a pool of another kind, a Dask
    client, is taken to be alive: it reports its own failures)."""
    procs = getattr(pool, "_processes", None)
    if procs is None:
        return True
    return any(p.is_alive() for p in list(procs.values()))
