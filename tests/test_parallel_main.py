"""A plain script and a notebook call the API with parallelism on (issue 27, item 2).

Worker processes never run the caller's ``__main__`` (:func:`fcomp.parallel.pool_context`):
a script without an ``if __name__ == "__main__":`` guard is not run again in every worker
(it was, and the pool broke: ``BrokenProcessPool``). What is defined in ``__main__``
itself cannot reach such workers: those jobs run here with one warning
(:func:`fcomp.parallel.shippable`). Each case runs in a fresh interpreter.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from fcomp.errors import FcompWarning
from fcomp.parallel import main_objects, pool_context, process_pool, shippable

ROOT = Path(__file__).resolve().parents[1]

#: A small diagnosis on two worker processes: three candidates, one step.
DIAGNOSE = """
rec = fcomp.simulate("motion", "lugre", "sine:amplitude=0.01,frequency=0.5", duration=2.0,
                     params="canudas1995")
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    d = fcomp.diagnose(rec, "coulomb-viscous", n_jobs=2, max_steps=1, check_baseline=False,
                       candidates=EFFECTS)
print("RESULT", d.verdict_, d.rms_baseline_ > 0)
print("SERIAL", sum(getattr(w.message, "code", "") == "serial" for w in caught))
"""

#: An effect written in the caller's own ``__main__`` (a notebook cell).
INLINE_EFFECT = """
from fcomp.effects import Effect, register_effect
from fcomp.parameters import make_params_class, spec


class Cogging(Effect):
    \"\"\"A force periodic in the position.\"\"\"

    name = "cogging-inline"
    Params = make_params_class("CoggingInlineParams", [
        spec("A_cog", "N", 0.0, -1e4, 1e4, "amplitude", directional=False),
        spec("phi_cog", "-", 0.0, -4.0, 4.0, "phase", directional=False),
    ], owner="effect cogging-inline")
    needs = ("x",)
    signature = "residual periodic in x"
    experiment = "slow strokes"

    def extra_force(self, be, sig, P):
        return P("A_cog") * be.sin(2 * be.pi * sig.x / 0.01 + P("phi_cog")), 0.0


register_effect(Cogging)
"""


def _run(code: str, *, script: Path | None = None, timeout: float = 240.0
         ) -> subprocess.CompletedProcess[str]:
    """Run ``code`` in a fresh interpreter: as the file ``script``, or on stdin
    (``python -``: a ``__main__`` without a file of its own, as a notebook's)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    if script is not None:
        script.write_text(code)
        return subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                              timeout=timeout, env=env, cwd=script.parent)
    return subprocess.run([sys.executable, "-"], input=code, capture_output=True, text=True,
                          timeout=timeout, env=env)


def _check(out: subprocess.CompletedProcess[str], serial: int) -> None:
    assert out.returncode == 0, out.stderr[-2000:]
    assert "BrokenProcessPool" not in out.stderr
    assert out.stdout.count("TOP-LEVEL") == 1, out.stdout  # not run again in a worker
    results = [line for line in out.stdout.splitlines() if line.startswith("RESULT")]
    assert len(results) == 1 and results[0].endswith("True"), out.stdout
    assert f"SERIAL {serial}" in out.stdout, out.stdout


def test_an_unguarded_script_diagnoses_on_worker_processes(tmp_path: Path) -> None:
    code = ("import warnings\nimport fcomp\nprint('TOP-LEVEL')\n"
            "EFFECTS = ['stribeck', 'presliding', 'frictional-lag']\n" + DIAGNOSE)
    _check(_run(code, script=tmp_path / "plain.py"), serial=0)


def test_a_notebook_like_main_with_an_inline_effect_runs_it_here_with_one_warning() -> None:
    code = ("import warnings\nimport fcomp\nprint('TOP-LEVEL')\n" + INLINE_EFFECT
            + "EFFECTS = ['cogging-inline', 'stribeck', 'presliding']\n" + DIAGNOSE)
    _check(_run(code), serial=1)


def test_run_tasks_in_an_unguarded_spawn_script(tmp_path: Path) -> None:
    """The pool of :func:`fcomp.parallel.run_tasks` (``fit`` over records, sweeps, studies)
    with ``spawn`` workers, the default on macOS and Windows; a function of the script
    itself runs here, with one warning."""
    code = textwrap.dedent("""
        import multiprocessing
        import operator
        import warnings
        from fcomp.parallel import run_tasks
        multiprocessing.set_start_method("spawn")
        print("TOP-LEVEL")

        def square(x):
            return x * x

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            neg = run_tasks(operator.neg, [1, 2, 3, 4], workers=2)
            sq = run_tasks(square, [1, 2, 3], workers=2)
        print("RESULT", neg == [-1, -2, -3, -4] and sq == [1, 4, 9])
        print("SERIAL", sum(getattr(w.message, "code", "") == "serial" for w in caught))
    """)
    _check(_run(code, script=tmp_path / "tasks.py", timeout=120.0), serial=1)


class _Local:
    """A class of this module, which a worker imports by name."""


def test_main_objects_names_what_a_worker_could_not_import() -> None:
    import types

    main = types.ModuleType("__main__")
    exec("class Here:\n    class Inner:\n        pass\ndef f():\n    pass\n", main.__dict__)
    saved = sys.modules["__main__"]
    sys.modules["__main__"] = main
    try:
        found = main_objects([main.Here(), main.Here.Inner, main.f, _Local(), 3.0])
    finally:
        sys.modules["__main__"] = saved
    assert found == ["Here", "f"]
    assert main_objects(_Local(), {"a": [1.0]}) == []


def test_fresh_pools_hide_main_and_fork_pools_ship_anything() -> None:
    assert pool_context(spawn=True).get_start_method() == "spawn"
    pool = process_pool(2, spawn=True)
    try:
        with pytest.warns(FcompWarning, match="Thing is defined in the caller's __main__"):
            assert not shippable(pool, _main_thing())
        assert shippable(pool, _Local())
    finally:
        pool.shutdown()
    if "fork" in __import__("multiprocessing").get_all_start_methods():
        import multiprocessing

        fork = __import__("concurrent.futures").futures.ProcessPoolExecutor(
            1, mp_context=multiprocessing.get_context("fork"))
        try:
            assert shippable(fork, _main_thing())
        finally:
            fork.shutdown()


def _main_thing() -> object:
    cls = type("Thing", (), {"__module__": "__main__"})
    return cls()


@pytest.mark.parametrize("name", ["__spec__", "__file__"])
def test_the_callers_main_is_back_after_a_worker_starts(name: str) -> None:
    main = sys.modules["__main__"]
    before = getattr(main, name, None)
    pool = process_pool(1, spawn=True)
    try:
        assert pool.submit(abs, -2).result(timeout=60) == 2
    finally:
        pool.shutdown()
    assert sys.modules["__main__"] is main
    assert getattr(main, name, None) is before
