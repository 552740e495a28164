"""Shared configuration of the test suite.

Markers (declared in ``pyproject.toml``, ``--strict-markers``):

``slow``
    tests that build the study site, run real processes or long diagnoses
    (seconds to a minute each). CI runs everything (``pytest -q -n auto --dist
    loadgroup``, the README's command); while working, ``pytest -q -m "not slow"``
    skips them.
``xdist_group("site")``
    the tests reading the study site of :func:`site` / :func:`helpers.browser.study_summary`:
    with ``--dist loadgroup`` they run in one pytest-xdist worker, which builds the
    site once (each worker process would build its own). The tests using a module-scoped
    fixture are grouped by their module the same way (:func:`pytest_collection_modifyitems`).

Helpers shared by several test modules live in the package :mod:`helpers`
(``tests/helpers/``), importable because pytest puts ``tests/`` on the path.

A failing test is named the moment it fails (:func:`pytest_runtest_logreport`), not only
in the summary at the end of a 10-minute run: with ``-n auto`` the line comes from the
controller as each worker reports. Tests that run real processes wait on conditions, not
clocks (:mod:`helpers.processes`): a loaded machine makes them slower, never wrong.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from helpers.browser import build_site


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int | None:
    """``-n auto``: the CPUs this process may use, not the host's cores.

    pytest-xdist asks psutil for the physical cores, which in a container are the
    host's (a CI runner allowed two CPUs can see 64, and 64 workers of about
    0.6 GB each would not fit). Here: the CPUs of this process's affinity,
    bounded by a cgroup v2 CPU quota where one is set. ``PYTEST_XDIST_AUTO_NUM_WORKERS``
    still decides when given (xdist's own rule, ``None`` here).
    """
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return None
    n = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else \
        (os.cpu_count() or 1)
    try:
        quota, period = Path("/sys/fs/cgroup/cpu.max").read_text().split()[:2]
        if quota != "max":
            n = min(n, math.ceil(int(quota) / int(period)))
    except (OSError, ValueError):
        pass
    return max(1, n)


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist reads the groups
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """A test that uses a module-scoped fixture runs in the worker of its module's others
    (``xdist_group`` of the module's name, unless it has a group): ``--dist loadgroup``
    otherwise sends them to both workers, and each builds the fixture -- a compensate
    comparison or a diagnosis of a minute, twice."""
    for item in items:
        if item.get_closest_marker("xdist_group") is not None:
            continue
        info = getattr(item, "_fixtureinfo", None)
        defs = info.name2fixturedefs.values() if info is not None else ()
        if any(d and str(d[-1].scope) in ("module", "Scope.Module") for d in defs):
            module = getattr(item, "module", None)
            item.add_marker(pytest.mark.xdist_group(getattr(module, "__name__", "module")))


@pytest.hookimpl(trylast=True)  # after the reporter's own progress letter
def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    """Name a failing test at once, on its own line (``FAILED node (phase, seconds)``)."""
    if not report.failed:
        return
    import sys

    phase = "" if report.when == "call" else f"{report.when}, "
    line = f"FAILED {report.nodeid} ({phase}{report.duration:.1f} s)"
    if _REPORTER.get("worker"):  # an xdist worker: the controller says it
        return
    config = _REPORTER.get("config")
    reporter: Any = config.pluginmanager.get_plugin("terminalreporter") if config else None
    if reporter is not None:
        reporter.write("\n")  # after the progress letter the reporter has just written
        reporter.write_line(line, red=True, bold=True)
        reporter.flush()
    else:
        sys.stderr.write(line + "\n")


#: This run's configuration (``"config"``), and whether this process is an xdist worker.
_REPORTER: dict[str, Any] = {}


def pytest_configure(config: pytest.Config) -> None:
    _REPORTER["worker"] = hasattr(config, "workerinput")
    _REPORTER["config"] = config


@pytest.fixture(autouse=True)
def _user_code_stays_in_its_test() -> Iterator[None]:
    """What a test's user module registers (effects, models) and the list of user files the
    worker processes re-run are undone after the test: a diagnosis elsewhere in the suite
    takes every registered effect as a candidate and must not meet another test's."""
    import sys

    from fcomp.effects import EFFECTS
    from fcomp.models import MODELS
    from fcomp.usercode import SOURCES, USER_FILES

    saved = [(reg, dict(reg._items)) for reg in (EFFECTS, MODELS)]
    files, sources = dict(USER_FILES), dict(SOURCES)
    yield
    for reg, items in saved:
        reg._items.clear()
        reg._items.update(items)
    USER_FILES.clear()
    USER_FILES.update(files)
    for name in set(SOURCES) - set(sources):  # the user modules the test executed
        sys.modules.pop(name, None)
    SOURCES.clear()  # what a later test's spawned workers execute first: a sys.exit(3)
    SOURCES.update(sources)  # plugin of another test ended a diagnosis's baseline check


@pytest.fixture(scope="session")
def site() -> Path:
    """The folder of this test process's ``fcomp study all --fast`` site (it must have run)."""
    out, code, err = build_site()
    assert code == 0, f"fcomp study all --fast exited {code}:\n{err[-3000:]}"
    return out
