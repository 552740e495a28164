"""``fcomp`` entry point (the console script and ``python -m fcomp.cli.main``).

Kept tiny on purpose: it imports nothing heavy, so that Ctrl-C and SIGTERM are the
command's from its first moment (:mod:`fcomp.cli.signals`). The handlers are installed
first; the command line itself -- the parser, every command, numpy and the rest --
is imported after (:mod:`fcomp.cli.app`). A signal landing while those load ends the
command like one landing later: its one line (``fcomp: interrupted``, exit status 130;
``fcomp: terminated``, 143), no traceback, nothing written.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import Any

from fcomp.cli import signals


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); its exit status."""
    old = signals.install()
    try:
        try:
            from fcomp.cli.app import run

            return run(argv)
        except KeyboardInterrupt as exc:  # a signal while loading, parsing or finishing
            line, code = signals.STOPPED.get(type(exc), signals.STOPPED[signals.Interrupted])
            sys.stderr.write(line + "\n")
            return code
    finally:
        signals.restore(old)


def __getattr__(name: str) -> Any:
    """The command line's other names (``build_parser``, ``plain``, ``COMMANDS``), from
    :mod:`fcomp.cli.app`, loaded when asked for."""
    if name.startswith("__"):
        raise AttributeError(name)
    from fcomp.cli import app

    try:
        return getattr(app, name)
    except AttributeError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None


if __name__ == "__main__":
    raise SystemExit(main())
