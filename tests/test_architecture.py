"""Architecture: the layers of ``pyproject.toml`` (import-linter) and no import cycles.

The packages are layered ``studies -> controllers -> plants -> fcomp`` (no exceptions: the
CLI and the API reach the packages above through ``fcomp.registry``), and inside ``fcomp``
numerics -> data -> models/effects -> identification -> diagnosis -> cli
(``[tool.importlinter]``).
The cycle check counts every import, also those inside functions.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest
from helpers.import_graph import cycles, graph

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ["fcomp", "plants", "controllers", "studies"]

def test_no_import_cycles() -> None:
    """No circle at all, counting imports inside functions (no allow-list)."""
    bad = cycles(graph(ROOT, PACKAGES))
    assert not bad, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in bad)


def test_cycle_check_sees_lazy_imports(tmp_path: Path) -> None:
    """A circle closed by an import inside a function is a circle."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from pkg.b import f\n")
    (pkg / "b.py").write_text("def f():\n    from pkg import a\n    return a\n")
    (pkg / "c.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                              "    from pkg import a\n")
    assert cycles(graph(tmp_path, ["pkg"])) == [["pkg.a", "pkg.b"]]


def test_layer_contracts_hold() -> None:
    exe = shutil.which("lint-imports")
    if exe is None:
        pytest.fail("lint-imports is not installed: install the test extra "
                    "(pip install -e '.[test]', package import-linter)")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    proc = subprocess.run([exe, "--no-cache", "--no-logo", "--config", str(ROOT / "pyproject.toml")],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-4000:]
    assert "0 broken" in proc.stdout, proc.stdout[-2000:]
