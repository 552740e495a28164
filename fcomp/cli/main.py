"""``fcomp`` entry point: sub-commands, one-line errors, exit status 2 on bad input.

Each sub-command lives in its own module of :mod:`fcomp.cli` with
``add_parser(subparsers)`` and ``run(args) -> int``; :data:`COMMANDS` lists them.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence

from fcomp import __version__
from fcomp.errors import FcompError

COMMANDS = ("simulate", "fit", "diagnose", "study", "import_", "demo", "list_")


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors and exit status 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        sys.stderr.write(f"{self.prog}: error: {message} (see --help)\n")
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="fcomp",
        description="Friction models, identification, diagnosis and compensation for "
        "fluid-power servo actuators.",
    )
    parser.add_argument("--version", action="version", version=f"fcomp {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name in COMMANDS:
        try:
            mod = importlib.import_module(f"fcomp.cli.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"fcomp.cli.{name}":
                continue  # command not part of this build
            raise
        mod.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        code = int(args.func(args) or 0)
    except FcompError as exc:
        sys.stderr.write(f"fcomp: error: {exc}\n")
        return 2
    except (ValueError, KeyError, OSError) as exc:
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        sys.stderr.write(f"fcomp: error: {msg}\n")
        return 2
    except KeyboardInterrupt:
        sys.stderr.write("fcomp: interrupted\n")
        return 130
    except Exception as exc:  # a bug: still one line, the traceback on request
        if os.environ.get("FCOMP_DEBUG"):
            raise
        sys.stderr.write(
            f"fcomp: internal error: {type(exc).__name__}: {exc} "
            "(set FCOMP_DEBUG=1 for the traceback and please report it)\n"
        )
        return 1
    return code


if __name__ == "__main__":
    raise SystemExit(main())
