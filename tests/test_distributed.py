"""Scale-out on an existing Dask cluster: ``--scheduler ADDRESS`` on sweep, compensate, fit,
diagnose, study.

The test starts a real scheduler and a worker as separate processes on
localhost (``dask-scheduler`` and ``dask-worker``, run as ``python -m
distributed.cli.dask_scheduler`` / ``dask_worker`` so that they use this
interpreter), on free ports, runs commands with ``--scheduler
tcp://127.0.0.1:PORT`` and compares their results with the local run; the
processes are always torn down.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import distributed  # noqa: F401  (the test extras install it: a missing one is a failure)
import pytest

from fcomp.cli.main import main

pytestmark = pytest.mark.slow  # runs real scheduler and worker processes

ROOT = Path(__file__).resolve().parents[1]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=20)


@pytest.fixture(scope="module")
def scheduler(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """The address of a scheduler with one worker, both real processes on localhost."""
    tmp = tmp_path_factory.mktemp("dask")
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    procs: list[subprocess.Popen] = []
    log = (tmp / "dask.log").open("w")
    try:
        procs.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
             "--port", str(port), "--no-dashboard"], env=env, stdout=log, stderr=log,
            cwd=tmp))
        procs.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nworkers", "1",
             "--nthreads", "1", "--no-dashboard", "--host", "127.0.0.1", "--local-directory",
             str(tmp / "worker")], env=env, stdout=log, stderr=log, cwd=tmp))
        deadline = time.monotonic() + 90
        while True:
            try:
                with distributed.Client(address, timeout=5) as client:
                    client.wait_for_workers(1, timeout=60)
                break
            except (OSError, TimeoutError):
                if time.monotonic() > deadline or any(p.poll() is not None for p in procs):
                    log.flush()
                    pytest.fail("the Dask scheduler and worker did not start:\n"
                                + (tmp / "dask.log").read_text()[-3000:])
                time.sleep(1.0)
        yield address
    finally:
        for p in reversed(procs):
            _stop(p)
        log.close()


def _json(args: list[str], out: Path) -> dict:
    code = main([*args, "--json", str(out), "--no-progress"])
    assert code == 0
    return json.loads(out.read_text())


def test_sweep_on_the_cluster_gives_the_local_results(scheduler: str, tmp_path: Path) -> None:
    args = ["sweep", "--controllers", "pid,pid-ff", "--samples", "3"]
    local = _json([*args, "--jobs", "1"], tmp_path / "local.json")
    remote = _json([*args, "--scheduler", scheduler], tmp_path / "remote.json")
    assert remote == local
    assert len(local["runs"]) == 6 and all(r["status"] == "ok" for r in local["runs"])


def test_grid_on_the_cluster_gives_the_local_results(scheduler: str, tmp_path: Path) -> None:
    args = ["sweep", "--controllers", "pid-ff", "--grid", "Fc=0.5,1", "--controller-friction",
            "lugre,nmlgm"]
    local = _json([*args, "--jobs", "1"], tmp_path / "local.json")
    remote = _json([*args, "--scheduler", scheduler], tmp_path / "remote.json")
    assert remote == local and len(local["points"]) == 4


def test_compensate_on_the_cluster_gives_the_local_results(scheduler: str,
                                                           tmp_path: Path) -> None:
    """``compensate --scheduler``: the runs (a user's reference among them, a task the
    workers get pickled) and the draws are those of the local run."""
    from fcomp.models import make_model

    lugre = make_model("lugre", params="seed002-type1")
    lugre.save(tmp_path / "base.json")
    lugre.with_effects("direction-asymmetry").with_params(r_neg=1.5).save(tmp_path / "true.json")
    (tmp_path / "ref.csv").write_text("t,x_ref\n0,0.15\n0.3,0.152\n0.8,0.152\n")
    args = ["compensate", "--plant-params", str(ROOT / "docs" / "examples" / "axis50.toml"),
            "--friction", str(tmp_path / "true.json"), "--controller-friction",
            f"{tmp_path / 'base.json'},{tmp_path / 'true.json'}", "--controllers", "pid-ff",
            "--reference", str(tmp_path / "ref.csv"), "--samples", "2"]
    local = _json([*args, "--jobs", "1"], tmp_path / "local.json")
    remote = _json([*args, "--scheduler", scheduler], tmp_path / "remote.json")
    assert remote == local
    assert len(local["runs"]) == 2 and all(r["status"] == "ok" for r in local["runs"])


@pytest.fixture(scope="module")
def records(tmp_path_factory: pytest.TempPathFactory) -> list[str]:
    from fcomp.synthetic import generate

    folder = tmp_path_factory.mktemp("records")
    out = []
    for seed in (1, 2):
        path = folder / f"rec{seed}.csv"
        generate(["force-offset"], duration=12.0, experiments=2, seed=seed).measurement.write(
            path)
        out.append(str(path))
    return out


def test_fit_over_records_on_the_cluster(scheduler: str, records: list[str],
                                         tmp_path: Path) -> None:
    args = ["fit", *records, "--friction", "coulomb-viscous", "--offset"]
    local = _json([*args, "--jobs", "1"], tmp_path / "local.json")
    remote = _json([*args, "--scheduler", scheduler], tmp_path / "remote.json")
    assert remote == local
    assert [r["data"] for r in local["records"]] == records


def test_diagnose_on_the_cluster(scheduler: str, records: list[str], tmp_path: Path) -> None:
    args = ["diagnose", records[0], "--friction", "coulomb-viscous", "--no-baseline-check",
            "--candidates", "force-offset,viscous,dwell-time", "--max-steps", "1"]
    local = _json([*args, "--jobs", "1"], tmp_path / "local.json")
    remote = _json([*args, "--scheduler", scheduler], tmp_path / "remote.json")
    # the model file records its command line, which differs
    assert "--scheduler" in remote["model_file"]["source"].pop("command")
    assert "--scheduler" not in local["model_file"]["source"].pop("command")
    assert remote == local
    assert {c["effect"] for c in local["candidates"]} == {"force-offset", "dwell-time"}


def test_study_on_the_cluster(scheduler: str, tmp_path: Path,
                              monkeypatch: pytest.MonkeyPatch) -> None:
    """The compensators study (cut to one plant and task) on the cluster and locally."""
    import studies.compensators as comp

    monkeypatch.setattr(comp, "PLANTS", ("hydraulic",))
    monkeypatch.setattr(comp, "TASK_ORDER", ("steps",))
    monkeypatch.setattr(comp, "LOW_VELOCITY", ())
    monkeypatch.setattr(comp.CompensatorsStudy, "_tracking_figures", lambda *a: None)
    monkeypatch.setattr(comp.CompensatorsStudy, "_friction_figures", lambda *a: None)
    monkeypatch.setattr(comp.CompensatorsStudy, "_do_mpc", staticmethod(lambda fast: {
        "available": False, "note": "left out in this test"}))
    summaries = {}
    for name, extra in (("local", ["--jobs", "1"]), ("remote", ["--scheduler", scheduler])):
        out = tmp_path / name
        assert main(["study", "compensators", "--fast", "--out", str(out), "--no-progress",
                     *extra]) == 0
        summaries[name] = json.loads((out / "summary.json").read_text())

    def stable(s: dict) -> list:
        return [(r["controller"], r["task"], r["rms_error"], r["max_error"]) for r in s["results"]]

    assert stable(summaries["remote"]) == stable(summaries["local"])
    rob = {n: {c: d["rms_error"]["values"] for c, d in s["robustness"]["hydraulic"].items()}
           for n, s in summaries.items()}
    assert rob["remote"] == rob["local"]


def test_unreachable_scheduler_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    code = main(["sweep", "--controllers", "pid", "--samples", "1", "--scheduler",
                 f"tcp://127.0.0.1:{_free_port()}", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and "cannot connect to the Dask scheduler" in err, err
    assert len(err.strip().splitlines()) == 1
