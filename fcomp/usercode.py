"""The user's own Python code (``--effects FILE.py``): running it, and blaming it by name.

``--effects FILE.py`` *executes* ``FILE.py`` with the user's rights, as
``python FILE.py`` would (README, "Security"). Its mistakes are the user's,
and are reported as such: one line naming the file, the line and the error,
never "internal error ... please report it". Every file executed here is
remembered, so that an error raised later from inside it (an effect's
``extra_force`` called during a fit) is traced back to it too
(:func:`blame`).
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import re
import sys
import traceback
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType, TracebackType
from typing import NoReturn

from fcomp.errors import FcompError

#: Real paths of the user files executed so far -> the path as the user gave it.
USER_FILES: dict[str, str] = {}
#: Module name -> (the path as given, the source) of every user file executed, so that
#: worker processes (local or on a cluster) can execute the same code before they
#: unpickle jobs that use it (:func:`user_sources`, :func:`load_sources`).
SOURCES: dict[str, tuple[str, str]] = {}


def run_module(path: Path, module_name: str, what: str) -> ModuleType:
    """Execute the user's ``path`` as module ``module_name``; one line on any failure.

    ``what`` names the file's role in messages (``"effects module"``).
    """
    real = os.path.realpath(path)
    USER_FILES[real] = str(path)
    spec = importlib.util.spec_from_file_location(module_name, path)
    if spec is None or spec.loader is None:
        raise FcompError(f"{path}: cannot import as a Python module")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    try:
        SOURCES[module_name] = (str(path), Path(path).read_text(encoding="utf-8",
                                                                 errors="replace"))
        with _no_hard_exit():
            spec.loader.exec_module(module)
    except BaseException as exc:  # SystemExit too: a plugin must not end the command
        # not loaded, whatever stopped it: never executed again in a later worker process
        sys.modules.pop(spec.name, None)
        SOURCES.pop(module_name, None)
        if isinstance(exc, KeyboardInterrupt):  # Ctrl-C, or the file raised it
            raise
        if isinstance(exc, SyntaxError):
            at = f"{path} line {exc.lineno}" if exc.lineno else str(path)
            raise FcompError(f"{at}: the {what} has a syntax error ({exc.msg})") from None
        where = locate(exc) or str(path)
        raise FcompError(f"{where}: importing the {what} failed: {_describe(exc)}") from None
    return module


def user_sources() -> tuple[tuple[str, str, str], ...]:
    """``(module name, path, source)`` of every user file executed in this process."""
    return tuple((name, path, src) for name, (path, src) in SOURCES.items())


def load_sources(items: tuple[tuple[str, str, str], ...]) -> None:
    """Execute the user files of another process (:func:`user_sources`) here, once each.

    Run by every worker process before it takes jobs (a pool's initializer, a
    Dask ``client.run``): a job that carries a user's effect is unpickled by
    importing its module, which only exists where the file was executed.
    Errors raised later from this code still name the user's file and line.
    """
    import types

    for name, path, source in items:
        if name in sys.modules:
            continue
        USER_FILES[os.path.realpath(path)] = path
        SOURCES[name] = (path, source)
        module = types.ModuleType(name)
        module.__file__ = path
        sys.modules[name] = module
        with _no_hard_exit():
            exec(compile(source, os.path.realpath(path), "exec"), module.__dict__)


class _HardExit(SystemExit):
    """``os._exit(code)`` called by a user file while it was executed."""


@contextlib.contextmanager
def _no_hard_exit() -> Iterator[None]:
    """While a user file runs, ``os._exit`` raises :class:`_HardExit` instead of ending the
    process on the spot (with nothing written and nothing said)."""
    def refuse(status: int) -> NoReturn:
        raise _HardExit(status)

    real = os._exit
    os._exit = refuse
    try:
        yield
    finally:
        os._exit = real


def _describe(exc: BaseException) -> str:
    if isinstance(exc, _HardExit):
        return f"it called os._exit({exc.code!r}); a plugin must not end the command"
    if isinstance(exc, SystemExit):
        return f"it called sys.exit({exc.code!r}); a plugin must not end the command"
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _frames(exc: BaseException) -> list[tuple[str, int, str]]:
    """``(file, line, function)`` of every frame of ``exc`` and its causes, innermost last."""
    out: list[tuple[str, int, str]] = []
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        seen.add(id(e))
        tb: TracebackType | None = e.__traceback__
        for fs in traceback.extract_tb(tb):
            out.append((fs.filename, fs.lineno or 0, fs.name))
        remote = getattr(e, "tb", None)  # concurrent.futures' _RemoteTraceback text
        if isinstance(remote, str):
            for m in re.finditer(r'File "([^"]+)", line (\d+), in (\S+)', remote):
                out.append((m.group(1), int(m.group(2)), m.group(3)))
        e = e.__cause__ or e.__context__
    return out


def locate(exc: BaseException) -> str | None:
    """``FILE line N[, in FUNC]`` of the innermost frame of ``exc`` in a user file, or ``None``."""
    if not USER_FILES:
        return None
    hits = [f for f in _frames(exc) if os.path.realpath(f[0]) in USER_FILES]
    if not hits:
        return None
    file, line, func = hits[-1]
    shown = USER_FILES[os.path.realpath(file)]
    return f"{shown} line {line}" + ("" if func == "<module>" else f", in {func}")


def blame(exc: BaseException, what: str = "--effects module") -> str | None:
    """One line blaming the user's file if ``exc`` was raised from inside one, else ``None``:
    ``FILE line N, in FUNC: Error: text (an error in your --effects module, not in fcomp)``."""
    where = locate(exc)
    if where is None:
        return None
    return f"{where}: {_describe(exc)} (an error in your {what}, not in fcomp)"
