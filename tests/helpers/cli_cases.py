"""Bad-input cases run through the command line in this process (test helper).

A :class:`Case` is a command line and what it must do; :func:`check_case` runs it in a
folder of inputs (the *lab*) and checks the contract of every command (README, "Bad
input"): an error is exit status 2 and exactly one line ``fcomp: error: ...`` naming the
problem (``match``), never a traceback; a warning case is exit status 0 with its
``fcomp: warning: ...`` line; nothing in the lab changes, and an error leaves no file
behind (:func:`snapshot` before and after).
"""

from __future__ import annotations

import hashlib
import os
import shlex
from dataclasses import dataclass
from pathlib import Path

import pytest

from fcomp.cli.main import main


@dataclass(frozen=True)
class Case:
    """One command line and what it must do: exit ``code``; ``match``: texts the error (or,
    for code 0, the warning) line must hold; ``lines``: how many ``fcomp: error:`` lines
    (``None``: one or more -- ``plant check`` prints one per bad value); ``outputs``: the
    files a success writes (replacing those of an earlier case)."""

    args: str
    code: int = 2
    match: tuple[str, ...] = ()
    lines: int | None = 1
    outputs: tuple[str, ...] = ()


def snapshot(folder: Path) -> dict[str, str]:
    """Every file and folder under ``folder`` (hidden ones too) -> SHA-256 (``dir`` for
    folders, ``link:TARGET`` for links)."""
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = str(p.relative_to(folder))
        if p.is_symlink():
            out[rel] = "link:" + os.readlink(p)
        elif p.is_dir():
            out[rel] = "dir"
        else:
            out[rel] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def run_cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """``fcomp ARGS`` in this process: exit status, stdout, stderr."""
    try:
        code = main(args)
    except SystemExit as exc:  # argparse
        code = int(exc.code or 0)
    out = capsys.readouterr()
    return code, out.out, out.err


def check_case(lab: Path, case: Case, capsys: pytest.CaptureFixture[str],
               monkeypatch: pytest.MonkeyPatch) -> str:
    """Run ``case`` in ``lab`` and check it (module docstring); its stderr."""
    monkeypatch.chdir(lab)
    before = snapshot(lab)
    code, _, err = run_cli(shlex.split(case.args), capsys)
    assert "Traceback" not in err and "internal error" not in err, err
    assert code == case.code, err
    lines = err.splitlines()
    if case.code == 2:
        assert len(lines) == case.lines if case.lines is not None else lines, err
        assert all(s.startswith("fcomp: error: ") for s in lines), err
        for m in case.match:
            assert any(m in s for s in lines), (m, err)
        assert snapshot(lab) == before, "a refused command changed the lab"
    else:
        for m in case.match:
            assert any(m in s and s.startswith("fcomp: warning:") for s in lines), (m, err)
        after = snapshot(lab)
        assert all(after.get(k) == v for k, v in before.items() if k not in case.outputs), \
            "an input changed"
    return err
