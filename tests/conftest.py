"""Shared configuration of the test suite.

Markers (declared in ``pyproject.toml``, ``--strict-markers``):

``slow``
    tests that build the study site, run real processes or long diagnoses
    (seconds to a minute each). CI runs everything (``pytest -q``); while
    working, ``pytest -q -m "not slow"`` skips them.

Helpers shared by several test modules live in the package :mod:`helpers`
(``tests/helpers/``), importable because pytest puts ``tests/`` on the path.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers.browser import build_site


@pytest.fixture(scope="session")
def site() -> Path:
    """The folder of this test process's ``fcomp study all --fast`` site (it must have run)."""
    out, code, err = build_site()
    assert code == 0, f"fcomp study all --fast exited {code}:\n{err[-3000:]}"
    return out
