"""How a command is stopped: Ctrl-C (SIGINT) and SIGTERM raise :class:`Interrupted` and
:class:`Terminated` in the main thread from the first moment of the command (this module
imports nothing but :mod:`signal`, so the entry point installs it before any heavy import).

The first signal stops the command: the exception unwinds it, staged outputs are removed
(:mod:`fcomp.outputs`), worker processes are ended (:func:`fcomp.parallel.stop`), and the
command prints its one line (``fcomp: interrupted``, exit 130; ``fcomp: terminated``, exit
143). Further signals are ignored from then on, while it cleans up and exits: a second
Ctrl-C would otherwise interrupt that clean-up itself (workers left running, the exit
waiting for them, a traceback from the interpreter's shutdown).

Python runs a signal handler between any two steps of the main thread -- also inside a
place that cannot pass an exception on: a fork's ``after_in_parent`` hooks (``logging``
has one; every compiler or worker start runs them), a ``__del__``, a weak-reference
callback. There the exception is printed as ``Exception ignored in ...`` and dropped,
and the command would run on, deaf to further signals. Such a lost stop is caught by
:func:`sys.unraisablehook` (:func:`_lost`): nothing is printed, and the signal is sent
again a moment later, to land where it stops the command.
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Callable
from typing import Any

#: The signals that stop a command.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that staged outputs are cleaned up."""


class Interrupted(KeyboardInterrupt):
    """SIGINT (Ctrl-C): told apart from a ``KeyboardInterrupt`` a plugin raises itself."""


#: What a stopped command prints and its exit status.
STOPPED: dict[type[KeyboardInterrupt], tuple[str, int]] = {
    Terminated: ("fcomp: terminated", 143), Interrupted: ("fcomp: interrupted", 130)}


class _State:
    stopped: type[KeyboardInterrupt] | None = None


STATE = _State()


def _handler(kind: type[KeyboardInterrupt]) -> Callable[[int, Any], None]:
    def handler(signum: int, frame: Any) -> None:
        for s in STOP_SIGNALS:  # the first one stops the command; the clean-up runs on
            signal.signal(s, signal.SIG_IGN)
        STATE.stopped = kind
        raise kind()

    return handler


#: Seconds after which a stop that landed where it could not be raised is sent again.
RESEND = 0.01

#: The unraisable hook :func:`install` replaced.
_HOOK: dict[str, Any] = {}


def _lost(unraisable: Any) -> None:
    """``sys.unraisablehook``: a stop raised where exceptions are dropped is sent again (no
    ``Exception ignored`` printed); anything else goes to the hook there was."""
    kind = unraisable.exc_type
    if isinstance(kind, type) and kind in STOPPED:
        import threading

        sig = signal.SIGTERM if kind is Terminated else signal.SIGINT
        signal.signal(sig, _handler(kind))  # the first one again: this one was dropped
        threading.Timer(RESEND, os.kill, (os.getpid(), sig)).start()
        return
    (_HOOK.get("old") or sys.__unraisablehook__)(unraisable)


def install() -> dict[signal.Signals, Any] | None:
    """Make SIGTERM and SIGINT raise :class:`Terminated` and :class:`Interrupted` (main
    thread only; a process started with SIGINT ignored keeps ignoring it); returns the
    handlers to :func:`restore` (None: nothing installed)."""
    old = {s: signal.getsignal(s) for s in STOP_SIGNALS}
    try:
        signal.signal(signal.SIGTERM, _handler(Terminated))
    except ValueError:  # not the main thread: signals are the main thread's
        return None
    STATE.stopped = None
    if old[signal.SIGINT] is signal.default_int_handler:
        signal.signal(signal.SIGINT, _handler(Interrupted))
    if sys.unraisablehook is not _lost:
        _HOOK["old"] = sys.unraisablehook
        sys.unraisablehook = _lost
    return old


def restore(old: dict[signal.Signals, Any] | None) -> None:
    """Put back the handlers :func:`install` replaced -- unless a signal stopped the
    command: the process is ending, and later signals stay ignored until it has."""
    if old is None or STATE.stopped is not None:
        return
    for s, h in old.items():
        signal.signal(s, h)
    if sys.unraisablehook is _lost:
        sys.unraisablehook = _HOOK.pop("old", sys.__unraisablehook__)
