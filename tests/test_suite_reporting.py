"""The suite names a failing test the moment it fails (issue 42 item 15): on a 10-minute
run under load the names came only in the summary at the end.

A small suite of two tests runs in a real pytest process with this suite's
``conftest.py``: the first fails, the second prints a mark when it starts. The
``FAILED`` line of the first must come before that mark -- an order, not a time, so the
machine's load cannot change the verdict.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent

SMALL_SUITE = '''
def test_first_fails():
    assert 1 + 1 == 3, "made to fail"


def test_second_runs_after():
    print("SECOND-STARTS")
'''


@pytest.mark.slow
def test_a_failing_test_is_named_before_the_next_one_runs(tmp_path: Path) -> None:
    shutil.copy(TESTS / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / "test_small.py").write_text(SMALL_SUITE)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(TESTS), str(TESTS.parent)]))
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-s", "-p", "no:cacheprovider", "-p",
         "no:randomly", "-o", "addopts=", "test_small.py"],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    out = proc.stdout
    assert proc.returncode == 1, out + proc.stderr
    named = out.find("FAILED test_small.py::test_first_fails (")
    assert named >= 0, out
    assert named < out.index("SECOND-STARTS"), out
    assert "1 failed, 1 passed" in out
