"""The hostile cases of ``benchmarks/hostile_cases.py``, shared with the tests (test helper).

The runner holds the hostile inputs of issue 42 -- plant-file variants, model files,
references -- and writes them into a folder (:func:`write_lab`); the tests run the same
inputs in this process, so the table the runner counts is the table the suite checks.
"""

from __future__ import annotations

import importlib.util
import sys
from functools import cache
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[2]


@cache
def runner() -> ModuleType:
    """The module ``benchmarks/hostile_cases.py`` (loaded by path: ``benchmarks`` is no
    package)."""
    path = ROOT / "benchmarks" / "hostile_cases.py"
    spec = importlib.util.spec_from_file_location("hostile_cases", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["hostile_cases"] = module  # dataclasses look their module up by name
    spec.loader.exec_module(module)
    return module


def write_lab(folder: Path) -> Path:
    """The runner's inputs written into ``folder`` (returned)."""
    runner().write_lab(folder, ROOT)
    return folder
