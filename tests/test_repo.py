"""Repository hygiene: the README's commands, CI script, lint."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _readme_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    block = re.search(r"```(?:bash|sh)?[^\n`]*\n(.*?)```", text, re.S)
    assert block, "README has no code block"
    return [line.strip() for line in block.group(1).splitlines() if line.strip()]


def test_ci_runs_the_readme_test_command() -> None:
    cmds = _readme_commands()
    assert len(cmds) >= 2
    ci = (ROOT / ".ci" / "run").read_text()
    assert cmds[1] in ci.splitlines(), "the second README command must be the CI test command"
    assert "pytest" in cmds[1]


def test_ruff_passes() -> None:
    ruff = shutil.which("ruff")
    cmd = [ruff] if ruff else [sys.executable, "-m", "ruff"]
    proc = subprocess.run([*cmd, "check", str(ROOT)], capture_output=True, text=True)
    if proc.returncode != 0 and "No module named ruff" in proc.stderr:
        pytest.fail("ruff is not installed: install the test extra (pip install -e '.[test]')")
    assert proc.returncode == 0, proc.stdout[-3000:]
