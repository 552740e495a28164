"""The diagnosis's refits are plain values: they run in spawned processes and on Dask workers.

A refit job is ``refit_candidate(refit, proposal, current)``: the record and split
(:class:`~fcomp.diagnosis.refit.Refit`), the candidate model with its starts, the
current fit -- all picklable, nothing passed through module state. The same
diagnosis with two spawned worker processes and in one process gives the same
answer to the last digit; a job shipped to a Dask worker gives the same fit.
"""

from __future__ import annotations

import pickle

import distributed  # part of the test extra: a missing package fails, never skips
import numpy as np
import pytest

from fcomp.diagnosis import Diagnosis, catalogue
from fcomp.diagnosis.workers import longest_first, refit_candidate
from fcomp.synthetic import generate


@pytest.fixture(scope="module")
def record():
    return generate(["pressure-dependence"], base="lugre", duration=12.0, seed=1).measurement


def test_spawned_workers_give_the_serial_answer(record) -> None:
    par = Diagnosis("lugre", n_jobs=2, check_baseline=False).fit(record)
    ser = Diagnosis("lugre", n_jobs=1, check_baseline=False).fit(record)
    assert par.added_ == ser.added_ == ["pressure-dependence"]
    assert par.rms_final_ == ser.rms_final_
    assert par._search.pool is None  # the pool is closed with the fit
    assert [c.rms_heldout for c in par.candidates_] == [c.rms_heldout for c in ser.candidates_]


def test_a_refit_job_round_trips_and_runs_on_a_dask_worker(record) -> None:
    d = Diagnosis("lugre", n_jobs=1, search=False, check_baseline=False).fit(record)
    prop = catalogue.propose("pressure-dependence", d._search.context())
    job = (d._search.refit, prop, d.fit_)
    back = pickle.loads(pickle.dumps(job))
    here = refit_candidate(*job)
    assert not isinstance(here, str)
    assert refit_candidate(*back).values == here.values
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        there = client.submit(refit_candidate, *job).result()
    assert not isinstance(there, str)
    assert there.values == here.values
    np.testing.assert_array_equal(there.F_hat, here.F_hat)


def test_the_longest_refits_go_to_the_workers_first(record) -> None:
    """Longest-processing-time-first: what an effect's refit took at the previous step
    orders the next submission; refits not run yet go first, the models with more states
    first (the last of a batch would otherwise run alone while the other workers idle)."""
    d = Diagnosis("lugre", n_jobs=1, search=False, check_baseline=False).fit(record)
    ctx = d._search.context()
    props = [catalogue.propose(n, ctx) for n in ("force-offset", "dwell-time", "position-dependence")]
    assert props[1].model.n_states > props[0].model.n_states
    seconds: dict = {}
    assert longest_first(props, seconds)[0] == 1          # none timed: the extra state first
    seconds = {("force-offset", props[0].form): 9.0, ("dwell-time", props[1].form): 2.0,
               ("position-dependence", props[2].form): 4.0}
    assert longest_first(props, seconds) == [0, 2, 1]     # by the time each took
    del seconds[("position-dependence", props[2].form)]
    assert longest_first(props, seconds) == [2, 0, 1]     # one not timed yet goes first


def test_a_parallel_diagnosis_leaves_nothing_of_multiprocessing_on_stderr(record, tmp_path
                                                                         ) -> None:
    """``diagnose --jobs 2``: the baseline check starts beside the search in a process of its
    own with spawned workers, and is ended when the first answer needs no check. Ending it
    left its queues' semaphores to multiprocessing's resource tracker, which printed
    ``UserWarning: resource_tracker: There appear to be 5 leaked semaphore objects`` after
    the command's answer, on every such run. Standard error holds the command's own lines
    only."""
    import subprocess
    import sys

    record.write(tmp_path / "r.csv")
    proc = subprocess.run(
        [sys.executable, "-m", "fcomp.cli.main", "diagnose", "r.csv", "--friction", "lugre",
         "--jobs", "2", "--no-progress", "--json", "d.json"],
        cwd=tmp_path, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    assert "pressure-dependence" in proc.stdout
    strays = [line for line in proc.stderr.splitlines()
              if not line.startswith(("fcomp: ", "  "))]
    assert strays == [], proc.stderr
