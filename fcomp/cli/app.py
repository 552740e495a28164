"""The ``fcomp`` command line behind its entry point (:mod:`fcomp.cli.main`): the parser of
the sub-commands, and one-line errors with exit status 2 on bad input.

Each sub-command lives in its own module of :mod:`fcomp.cli` with
``add_parser(subparsers)`` and ``run(args) -> int``; :data:`COMMANDS` lists them.

What every command shares, enforced here:

* a problem with the input is one line ``fcomp: error: ...`` on stderr and
  exit status 2, never a traceback; an error raised from inside the user's
  ``--effects`` module names that file and line (:mod:`fcomp.usercode`);
* warnings (``fcomp: warning: ...``) are printed after a successful run, on
  stderr, grouped: one line each, or one counted line for several of one kind
  (:func:`fcomp.conclusions.grouped_warnings`); Python and numpy warnings raised on the way are collected
  and printed the same way, never as raw multi-line warnings; a failed run
  prints only its error line;
* Ctrl-C and SIGTERM interrupt cleanly (:mod:`fcomp.cli.signals`, installed by the
  entry point before this module is imported): outputs are staged, so an
  interrupted run leaves the old result or nothing (exit 130, or 143 for
  SIGTERM);
* standard output that cannot be written (closed, a full disk) is one error line; a
  reader that stopped reading (``fcomp plant template ... | head``) ends the command
  quietly (exit status 141, as a shell reports a process ended by a broken pipe).
"""

from __future__ import annotations

import argparse
import importlib
import os
import re
import sys
import warnings
from collections.abc import Sequence
from typing import Any

from fcomp.cli import common, emit
from fcomp.cli.signals import STOPPED, Interrupted
from fcomp.errors import FcompError
from fcomp.version import __version__

COMMANDS = ("simulate", "fit", "compare", "diagnose", "design", "sweep", "compensate", "study", "plant",
            "export", "import_", "demo", "list_")


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors and exit status 2, its help in plain text
    (:class:`fcomp.cli.common.HelpFormatter`, whatever formatter a command asks for)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs["formatter_class"] = common.HelpFormatter
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> None:  # type: ignore[override]
        sys.stderr.write(f"{self.prog}: error: {plain(message)} (see --help)\n")
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


_NUMPY_SCALAR = re.compile(r"np\.(?:float|int|uint|complex)\d*\(([^()]*)\)|np\.(True|False)_")


def plain(message: str) -> str:
    """``message`` as one line, numpy scalars written as plain numbers."""
    text = " ".join(str(message).split())
    return _NUMPY_SCALAR.sub(lambda m: m.group(1) or m.group(2), text)


def run(argv: Sequence[str] | None = None) -> int:
    """The command line ``argv`` (default ``sys.argv[1:]``) run; its exit status."""
    from fcomp.parallel import descendants

    before = set(descendants([os.getpid()]))  # a caller's own processes: never ended here
    parser = build_parser()
    args = parser.parse_args(argv)
    common.ARGV[:] = list(sys.argv[1:] if argv is None else argv)
    common.WARNINGS.clear()
    common.WRITTEN.clear()
    with warnings.catch_warnings(record=True) as caught:
        emit.PYTHON_WARNINGS = caught
        try:
            code = _run(args, before)
        finally:
            emit.PYTHON_WARNINGS = None
        if code == 0:
            for w in caught:
                common.warn(*common.python_warning(w))
    if code == 0:  # a failed run prints its one error line and nothing else
        from fcomp.conclusions import grouped_warnings

        common.say_deprecated(args)

        where = "in the JSON (--json OUT)"
        if hasattr(args, "json"):  # say which file, or that none was written
            where = ("(give --json OUT to keep them)" if args.json is None else
                     "(on standard output)" if args.json == "-" else f"({args.json})")
            where = "in the JSON " + where
        for line in grouped_warnings(common.WARNINGS, where):
            sys.stderr.write(f"fcomp: warning: {plain(line)}\n")
    return _flushed(code)


def _flushed(code: int) -> int:
    """``code``, once standard output is written out: a full disk is the run's error, a
    reader gone (a broken pipe) ends it quietly."""
    try:
        if sys.stdout is not None:
            sys.stdout.flush()
    except BrokenPipeError:
        return _pipe_closed()
    except OSError as exc:
        _discard_stdout()
        return _error(f"standard output: cannot write ({exc.strerror or exc})")
    return code


def _discard_stdout() -> None:
    """Send what is left in standard output's buffer nowhere (the interpreter would try
    again at exit and print the error as ``Exception ignored``)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, AttributeError, ValueError):
        pass


def _pipe_closed() -> int:
    _discard_stdout()
    return 141


def _error(message: str) -> int:
    sys.stderr.write(f"fcomp: error: {plain(message)}\n")
    return 2


def _run(args: argparse.Namespace, before: set[int] | None = None) -> int:
    from fcomp.usercode import blame

    try:
        return int(args.func(args) or 0)
    except FcompError as exc:  # the library's terms, written as this command's options
        return _error(exc.render(common.OPTIONS))
    except KeyboardInterrupt as exc:
        stopped = STOPPED.get(type(exc))
        # raised by the user's code itself, not by a signal: an error of that code
        culprit = None if stopped is not None else blame(exc)
        if culprit is not None:
            return _error(culprit)
        line, code = stopped or STOPPED[Interrupted]
        if stopped is not None:  # nothing of a stopped command left running
            from fcomp.parallel import end_children

            end_children(keep=before or ())
        sys.stderr.write(line + "\n")
        return code
    except BrokenPipeError:
        return _pipe_closed()
    except SystemExit as exc:  # only the user's code would: it must not end the command
        return _error(blame(exc) or f"a plugin called sys.exit({exc.code!r})")
    except RecursionError as exc:
        return _error(blame(exc) or "the computation recursed too deeply (RecursionError)")
    except MemoryError:
        fewer = ("lower --rate or --duration" if hasattr(args, "rate") and hasattr(args, "duration")
                 else "use fewer or shorter records")
        return _error(f"out of memory; {fewer}")
    except Exception as exc:
        culprit = blame(exc)
        if culprit is not None:
            return _error(culprit)
        if isinstance(exc, ValueError | KeyError | OSError):
            if isinstance(exc, OSError) and exc.filename:
                return _error(f"{exc.filename}: {exc.strerror or exc}")
            text = str(exc).strip()
            return _error(text.splitlines()[0] if text else type(exc).__name__)
        if os.environ.get("FCOMP_DEBUG"):
            raise
        sys.stderr.write(
            f"fcomp: internal error: {type(exc).__name__}: {plain(str(exc))} "
            "(set FCOMP_DEBUG=1 for the traceback and please report it)\n"
        )
        return 1
