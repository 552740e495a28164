"""Pieces shared by the sub-commands: building models from options, output paths, JSON results."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from fcomp.effects import load_effects_module
from fcomp.errors import FcompError
from fcomp.models import FrictionModel, make_model


def add_model_options(p: argparse.ArgumentParser, *, flag: str = "--friction") -> None:
    p.add_argument("--add-effect", action="append", default=[], metavar="EFFECT",
                   help="add a catalogue (or registered) effect to the model; repeatable")
    p.add_argument("--effects", metavar="MODULE.py", default=None,
                   help="a Python file that registers the user's own effects")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="override a friction parameter (flat name, SI units); repeatable")


def parse_assignments(items: list[str], option: str = "--set") -> dict[str, float]:
    out: dict[str, float] = {}
    for item in items:
        if "=" not in item:
            raise FcompError(f"{option} {item!r}: expected NAME=VALUE")
        k, v = (s.strip() for s in item.split("=", 1))
        try:
            out[k] = float(v)
        except ValueError:
            raise FcompError(f"{option} {item!r}: {v!r} is not a number") from None
    return out


def build_model(name: str, params: str | None, args: argparse.Namespace) -> FrictionModel:
    """The friction model of the options (model, parameter set, effects, overrides)."""
    if args.effects:
        load_effects_module(args.effects)
    model = make_model(name, params=params)
    if args.add_effect:
        model = model.with_effects(*args.add_effect)
    overrides = parse_assignments(args.set)
    return model.with_params(**overrides) if overrides else model


def output_path(path: str, suffix: str = ".csv") -> Path:
    p = Path(path)
    if p.suffix != suffix:
        raise FcompError(f"-o {path}: the output must end in {suffix}")
    if p.exists() and p.is_dir():
        raise FcompError(f"-o {path}: is a directory")
    return p


def json_target(path: str | None) -> Path | None:
    """The file ``--json PATH`` writes to; ``None`` for standard output (``-``) or no ``--json``.

    Raises
    ------
    FcompError
        If ``path`` is a directory or its folder does not exist (checked
        before any work, so a failure never leaves a half-written result).
    """
    if path is None or path == "-":
        return None
    out = Path(path)
    if out.is_dir():
        raise FcompError(f"--json {path}: is a directory")
    if not out.parent.exists():
        raise FcompError(f"--json {path}: folder {out.parent} does not exist")
    return out


def result_text(doc: dict) -> str:
    """A command's JSON result as text (strict JSON: a NaN raises before anything is written)."""
    return json.dumps(doc, indent=2, allow_nan=False) + "\n"


def emit_result(text: str, json_arg: str | None, out: Path | None, summary: str) -> None:
    """Write a command's result: the JSON ``text`` alone to standard output for
    ``--json -``; otherwise the human ``summary``, then ``text`` to ``out``
    (atomically, so no half-written file is left) when ``--json OUT`` was given."""
    from fcomp.report import atomic_write_text

    if json_arg == "-":
        sys.stdout.write(text)
        return
    print(summary)
    if out is not None:
        atomic_write_text(out, text)
        print(f"wrote {out}")
