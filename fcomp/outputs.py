"""Writing results safely: never onto an input, always whole.

Every command that writes follows the same rules (README, "Outputs"):

1. **Never onto an input.** An output that *is* an input (compared after
   resolving symbolic and hard links), the sidecar ``.toml`` of an input
   measurement, or a folder that *contains* an input (or the current
   folder) is refused before any work is done (:class:`InputSet`).
2. **Files are written whole.** Each file goes to a temporary name in its
   own folder and is renamed into place once complete; the files of one
   result (a measurement's CSV and TOML) are renamed together, with
   interrupts held off for those few microseconds (:func:`write_files`).
3. **Folders are swapped whole.** Reports, studies and the demo are built in
   a temporary sibling folder, which replaces the old folder only once the
   run has finished (:func:`staged_folder`). A failed or interrupted run
   leaves the old result or nothing, never a mixture, and no empty folder.
4. **Replacing a result is the rule**: an existing output file is replaced
   (atomically); an existing output folder is replaced if it is empty or
   was written by fcomp (it holds the marker file :data:`MARKER`, or only
   the files of that kind of result); any other folder is refused, since
   replacing it would delete the user's files.

A process killed outright (``SIGKILL``, power loss) can leave a hidden
temporary ``.NAME.*.tmp`` next to the output; the output itself is still
the old one or the new one.
"""

from __future__ import annotations

import errno
import os
import shutil
import signal
import tempfile
import threading
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from fnmatch import fnmatch
from pathlib import Path

from fcomp.errors import FcompError

#: File written into every output folder: fcomp may replace such a folder whole.
MARKER = ".fcomp-output"


def _real(path: Path) -> Path:
    return Path(os.path.realpath(path))


def same_file(a: Path, b: Path) -> bool:
    """Whether ``a`` and ``b`` name the same file (symbolic or hard links included)."""
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return _real(a) == _real(b)


def _within(inner: Path, folder: Path) -> bool:
    return _real(inner).is_relative_to(_real(folder))


@dataclass(frozen=True)
class _Input:
    option: str  # how the user gave it, for messages: "DATA", "--effects", ...
    path: Path
    sidecar_of: Path | None = None  # set for the sidecar of a measurement


class InputSet:
    """The files a command reads; refuses outputs that would overwrite one of them.

    >>> inputs = InputSet()
    >>> inputs.measurement(Path("run.csv"))   # run.csv and its sidecar run.toml
    >>> inputs.check_file("--json", Path("run.toml"))  # doctest: +SKIP
    Traceback (most recent call last):
    FcompError: --json run.toml: is the sidecar of the input run.csv; ...
    """

    def __init__(self) -> None:
        self.items: list[_Input] = []

    def file(self, path: str | Path, option: str = "input") -> None:
        """A file the command reads."""
        self.items.append(_Input(option, Path(path)))

    def measurement(self, path: str | Path, option: str = "input") -> None:
        """A measurement ``NAME.csv``: the file and its sidecar ``NAME.toml`` (present or not:
        writing there would give the measurement a sidecar that is not its own)."""
        p = Path(path)
        self.items.append(_Input(option, p))
        if p.suffix.lower() != ".toml":
            self.items.append(_Input(option, p.with_suffix(".toml"), sidecar_of=p))

    def check_file(self, option: str, path: Path) -> None:
        """Refuse writing the file ``path`` if it is an input or an input's sidecar."""
        for item in self.items:
            if same_file(path, item.path):
                what = (f"the sidecar of the input {item.sidecar_of}" if item.sidecar_of
                        else f"the input file {item.path}" if str(item.path) == str(path)
                        else f"the input file {item.path} (the same file)")
                raise FcompError(f"{option} {path}: is {what}; fcomp never writes over its "
                                 "input, choose another output name")

    def check_folder(self, option: str, path: Path) -> None:
        """Refuse replacing the folder ``path`` if it contains an input or the current folder."""
        for item in self.items:
            if same_file(item.path, path):
                raise FcompError(f"{option} {path}: is the input file {item.path}; fcomp never "
                                 "writes over its input, choose another folder")
            if item.sidecar_of is None and _within(item.path, path):
                raise FcompError(f"{option} {path}: contains the input {item.path}; fcomp "
                                 "replaces its output folder whole, choose another folder")
        if _within(Path.cwd(), path):
            raise FcompError(f"{option} {path}: contains the current folder; fcomp replaces "
                             "its output folder whole, choose a folder inside it")


def check_distinct(outputs: Sequence[tuple[str, Path, bool]]) -> None:
    """Refuse two outputs of one command that overlap: ``(option, path, is_folder)`` each."""
    for i, (opt_a, a, dir_a) in enumerate(outputs):
        for opt_b, b, dir_b in outputs[i + 1:]:
            clash = same_file(a, b) or (dir_a and _within(b, a)) or (dir_b and _within(a, b))
            if clash:
                raise FcompError(f"{opt_a} {a} and {opt_b} {b}: the two outputs overlap; "
                                 "give them separate places")


# ------------------------------------------------------ checked before the work
def name_max(folder: Path) -> int:
    """The longest file name (bytes) the file system of ``folder`` takes (255 on the
    usual ones)."""
    try:
        return int(os.pathconf(folder, "PC_NAME_MAX"))
    except (OSError, ValueError, AttributeError):
        return 255


def _exists(path: Path) -> bool:
    """Whether ``path`` exists; a name the system cannot even look up (too long) does not."""
    try:
        os.stat(path)
    except (OSError, ValueError):
        return False
    return True


def _existing_folder(path: Path) -> Path:
    """The nearest folder of ``path``'s parents that exists (where writing starts)."""
    p = path.parent
    while not _exists(p) and p != p.parent:
        p = p.parent
    return p


def check_name_length(option: str, path: Path) -> None:
    """Refuse an output whose name -- or a folder to create on the way -- is longer than
    the file system takes (before anything looks the path up: such a name fails every
    call, "File name too long")."""
    where = _existing_folder(path)
    limit = name_max(where)
    p = path
    while p != where and p != p.parent:
        size = len(os.fsencode(p.name))
        if size > limit:
            raise FcompError(f"{option} {path}: the name {p.name[:24]}... is {size} bytes "
                             f"long, more than the {limit} a file name may have here; choose "
                             "a shorter one")
        p = p.parent


def check_writable(option: str, path: Path) -> None:
    """Refuse, before any work, an output ``path`` (a file, or a folder fcomp builds) that
    cannot be written: a name (or a folder to create on the way) longer than the file
    system takes (:func:`check_name_length`), or a folder where this process may not create
    files (read-only, no permission, a read-only file system) -- found by creating and
    removing a hidden file there, as writing will. A device or named pipe (``/dev/null``)
    is written as it is and not probed."""
    check_name_length(option, path)
    if _exists(path) and not path.is_file() and not path.is_dir():
        return
    where = _existing_folder(path)
    if not where.is_dir():
        return  # a file where a folder should be: said by the callers' own checks
    try:
        fd, probe = tempfile.mkstemp(prefix=".fcomp-probe.", suffix=".tmp", dir=where)
    except OSError as exc:
        folder = "the current folder" if where == Path(".") else f"the folder {where}"
        raise FcompError(f"{option} {path}: cannot write into {folder} ({exc.strerror or exc}); "
                         "choose another place (nothing was done)") from None
    os.close(fd)
    os.unlink(probe)


def temporary_prefix(name: str, folder: Path, suffix: str = ".tmp") -> str:
    """The prefix of the hidden temporary sibling of ``name``: ``.NAME.``, the name cut
    short where the whole temporary name (``.NAME.`` + 8 random characters + ``suffix``)
    would be longer than the file system takes -- a legal 250-character output name
    must not fail on its temporary's name."""
    room = name_max(folder) - len(os.fsencode(suffix)) - 8 - 2
    raw = os.fsencode(name)
    if len(raw) > room:
        name = raw[:max(room, 1)].decode("utf-8", errors="ignore")
    return f".{name}."


# ----------------------------------------------------------------- files
def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextmanager
def signals_held() -> Iterator[None]:
    """Hold off Ctrl-C and SIGTERM (delivered afterwards) for a few renames."""
    if threading.current_thread() is threading.main_thread() and hasattr(signal,
                                                                          "pthread_sigmask"):
        old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
        try:
            yield
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)
    else:  # pragma: no cover - threads and platforms without signal masks
        yield


def _make_parents(folder: Path) -> list[Path]:
    """Create ``folder`` and missing parents; return those created (deepest last)."""
    created: list[Path] = []
    missing = []
    p = folder
    while not p.exists():
        missing.append(p)
        if p.parent == p:
            break
        p = p.parent
    if p.exists() and not p.is_dir():
        raise FcompError(f"{p}: is a file, not a folder; cannot write into it")
    for d in reversed(missing):
        try:
            d.mkdir()
        except FileExistsError:
            continue
        except OSError as exc:
            _remove_empty(created)
            raise FcompError(f"{d}: cannot create the folder ({exc.strerror or exc})") from None
        created.append(d)
    return created


def _remove_empty(folders: list[Path]) -> None:
    for d in reversed(folders):
        try:
            d.rmdir()
        except OSError:
            break


def write_files(files: Mapping[Path, str | bytes]) -> None:
    """Write every file to a temporary name next to it, then rename them all into place.

    Nothing appears under a final name unless every file could be written;
    folders created on the way are removed again on failure. A file that
    exists keeps its permissions; a new one gets the usual ``0666 & ~umask``.
    A symbolic link stays a link (the file it points to is replaced); a
    device or named pipe (``/dev/stdout``) is written to directly.
    """
    for path in files:
        if path.is_dir():
            raise FcompError(f"{path}: is a directory, cannot write a file there")
    special = {p: c for p, c in files.items() if p.exists() and not p.is_file()}
    for path, content in special.items():  # /dev/stdout, a named pipe: written as they are
        try:
            with open(path, "wb") as fh:
                fh.write(content.encode("utf-8") if isinstance(content, str) else content)
        except OSError as exc:
            raise FcompError(f"{path}: cannot write ({exc.strerror or exc})") from None
    # through a symbolic link: replace the file it points to, keep the link
    files = {_real(p) if p.is_symlink() else p: c for p, c in files.items() if p not in special}
    created: list[Path] = []
    tmps: dict[Path, Path] = {}
    done = False
    path = next(iter(files), Path())
    try:
        for path in files:
            created += _make_parents(path.parent)
        for path, content in files.items():
            fd, name = tempfile.mkstemp(prefix=temporary_prefix(path.name, path.parent),
                                        suffix=".tmp", dir=path.parent)
            tmps[path] = Path(name)
            data = content.encode("utf-8") if isinstance(content, str) else content
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
                fh.flush()
                os.fsync(fh.fileno())
            mode = (path.stat().st_mode & 0o7777) if path.is_file() else (0o666 & ~_umask())
            os.chmod(name, mode)
        with signals_held():
            for path, tmp in tmps.items():
                os.replace(tmp, path)
            done = True
    except OSError as exc:  # named by the file asked for, never by its temporary name
        raise FcompError(f"{path}: cannot write ({exc.strerror or exc}); nothing was "
                         "written") from None
    finally:
        if not done:
            for tmp in tmps.values():
                tmp.unlink(missing_ok=True)
            _remove_empty(created)


def write_text(path: str | Path, text: str) -> Path:
    """:func:`write_files` for one text file; returns the path."""
    path = Path(path)
    write_files({path: text})
    return path


# --------------------------------------------------------------- folders
#: Files that make up each kind of fcomp output folder (for folders written before the
#: marker): a folder holding only these, and sub-folders of the same kind, is fcomp's.
FOLDER_KINDS: dict[str, tuple[str, ...]] = {
    "study": ("summary.json", "*.html", "fig-*.png", "*.png", "*.svg"),
    "report": ("report.html", "*.png", "*.svg"),
    "demo": ("demo-*.csv", "demo-*.toml", "demo.png"),
    "programme": ("experiment_*.csv", "experiment_*.toml"),
    "export": ("fcomp_ctrl*.c", "fcomp_ctrl*.h", "example.c", "example", "Makefile", "*.o",
               "libfcomp_ctrl.a", "libfcomp_ctrl.so"),
}


def _fcomp_folder(path: Path, kind: str) -> bool:
    """Whether ``path`` is empty or fcomp's (the marker, or only fcomp's files of ``kind``)."""
    entries = list(path.iterdir())
    if not entries or (path / MARKER).is_file():
        return True
    for e in entries:
        if e.is_dir() and not e.is_symlink():
            if not _fcomp_folder(e, kind):
                return False
        elif not any(fnmatch(e.name, pat) for pat in FOLDER_KINDS[kind]):
            return False
    return True


def check_folder_target(option: str, path: Path, kind: str) -> None:
    """Refuse an output folder fcomp may not replace (before any work is done)."""
    check_name_length(option, path)
    if path.exists() and not path.is_dir():
        raise FcompError(f"{option} {path}: exists and is not a directory")
    if _within(Path.cwd(), path):
        raise FcompError(f"{option} {path}: contains the current folder; fcomp replaces its "
                         "output folder whole, choose a folder inside it")
    if path.is_dir():
        try:
            ok = _fcomp_folder(path, kind)
        except OSError as exc:
            raise FcompError(f"{option} {path}: cannot read the folder "
                             f"({exc.strerror or exc})") from None
        if not ok:
            raise FcompError(f"{option} {path}: exists and holds files fcomp did not write; "
                             "fcomp replaces its output folder whole, so give a new or empty "
                             "folder (or one fcomp wrote)")
    parent = _real(path).parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise FcompError(f"{option} {path}: {parent} is a file, not a folder")


#: Errors of the storage itself (a full disk or quota, a read-only or failing device).
_STORAGE = {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG, errno.EIO}


def _storage_error(exc: BaseException, folder: Path) -> bool:
    """Whether ``exc`` is the storage failing under ``folder`` (or under no file name)."""
    if not isinstance(exc, OSError) or exc.errno not in _STORAGE:
        return False
    return exc.filename is None or _within(Path(str(exc.filename)), folder)


@contextmanager
def staged_folder(path: str | Path, option: str, kind: str,
                  note: str = "") -> Iterator[Path]:
    """Build an output folder in a temporary sibling and swap it into place on success.

    Yields the temporary folder to write into. On success the marker
    :data:`MARKER` (with ``note``, e.g. the command) is added and the
    folder replaces ``path`` (the old one stays whole until then); on any
    error or interrupt the temporary folder is removed and ``path`` is
    left as it was.
    """
    final = _real(Path(path))
    check_folder_target(option, Path(path), kind)
    created = _make_parents(final.parent)
    try:
        tmp = Path(tempfile.mkdtemp(prefix=temporary_prefix(final.name, final.parent),
                                    suffix=".tmp", dir=final.parent))
    except OSError as exc:
        _remove_empty(created)
        raise FcompError(f"{option} {path}: cannot create a folder next to it "
                         f"({exc.strerror or exc})") from None
    old: Path | None = None
    try:
        os.chmod(tmp, 0o777 & ~_umask())
        yield tmp
        (tmp / MARKER).write_text("Written by fcomp" + (f": {note}" if note else "") + ".\n"
                                  "fcomp replaces this folder whole when asked to write here "
                                  "again.\n")
        with signals_held():
            if final.exists():
                old = Path(tempfile.mkdtemp(prefix=temporary_prefix(final.name, final.parent,
                                                                    ".old"),
                                            suffix=".old", dir=final.parent))
                os.rename(final, old / final.name)
            os.rename(tmp, final)
    except BaseException as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        if old is not None and not final.exists():  # put the old result back
            os.rename(old / final.name, final)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        _remove_empty(created)
        if _storage_error(exc, tmp):  # a full disk while writing: the folder asked for
            assert isinstance(exc, OSError)
            raise FcompError(f"{option} {path}: cannot write ({exc.strerror or exc}); nothing "
                             "was written") from None
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)

