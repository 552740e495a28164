"""Reading numeric text files (measurement CSVs, input signals, importers) with clear errors.

One reader for every text table the package parses, so that all of them
accept the same things and report problems the same way:

* the path is checked first: an empty name, a folder, a missing or
  unreadable file each give one line naming what the user typed;
* text is UTF-8, with or without a byte-order mark (Excel's "CSV UTF-8");
  UTF-16 with a byte-order mark (Excel's "Unicode text") is read too; a
  binary file or another encoding is refused by name;
* blank lines and ``#`` comments are skipped;
* row numbers in messages are the file's line numbers as an editor shows
  them (the first line is 1), whatever was skipped before;
* an empty file or a header without data rows is one clean error, never
  numpy's "input contained no data" warning.

Data files are only ever parsed, never executed (README, "Security").
"""

from __future__ import annotations

import json
import math
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fcomp.errors import FcompError, FileFormatError


def check_path(path: str | Path, what: str = "file") -> Path:
    """``path`` as a :class:`Path` if it names an existing regular file; else one clear line."""
    text = str(path)
    if not text.strip():
        raise FcompError(f"no {what} name given (an empty argument)")
    p = Path(text)
    if p.is_dir():
        article = "an" if what[:1] in "aeiou" else "a"
        raise FcompError(f"{text}: is a folder, not {article} {what}")
    if not p.exists():
        raise FcompError(f"{text}: {what} not found")
    if not p.is_file():
        raise FcompError(f"{text}: is not a regular file")
    return p


def read_text(path: Path, label: str | None = None, what: str = "text") -> str:
    """The text of ``path`` (UTF-8 with or without BOM, or UTF-16 with BOM); ``what``
    the file should hold, for messages."""
    label = label or str(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise FcompError(f"{label}: cannot read ({exc.strerror or exc})") from None
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            return raw.decode("utf-16")
        except UnicodeDecodeError:
            raise FcompError(f"{label}: cannot read as {what}: not valid UTF-16 text") from None
    if b"\x00" in raw[:4096]:
        raise FcompError(f"{label}: cannot read as {what} (a binary file, not text)")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise FcompError(f"{label}: cannot read as {what}: not UTF-8 text (byte "
                         f"0x{raw[exc.start]:02x} on line {line}); save it as UTF-8") from None


class _DuplicateKeyError(Exception):
    def __init__(self, key: str) -> None:
        super().__init__(key)
        self.key = key


class _ConstantError(Exception):
    pass


def _pairs(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise _DuplicateKeyError(k)
        out[k] = v
    return out


def _constant(name: str) -> Any:
    raise _ConstantError(name)


#: Most digits of an integer Python converts from text (``sys.get_int_max_str_digits``).
INT_DIGITS = 4300


class HugeInteger(float):
    """An integer in a JSON file too long for Python to read (more than :data:`INT_DIGITS`
    digits): an infinite float -- refused wherever a finite number is due -- that says what
    it was (``<an integer of 5001 digits>``), so the message names its key."""

    digits: int

    def __new__(cls, text: str) -> HugeInteger:
        obj = super().__new__(cls, -math.inf if text.startswith("-") else math.inf)
        obj.digits = len(text.lstrip("-"))
        return obj

    def __repr__(self) -> str:
        return f"<an integer of {self.digits} digits>"

    __str__ = __repr__


def _int(text: str) -> Any:
    return int(text) if len(text.lstrip("-")) <= INT_DIGITS else HugeInteger(text)


def parse_json(text: str, label: str, hint: str = "") -> Any:
    """``text`` as strict JSON; one :class:`~fcomp.errors.FileFormatError` line naming
    ``label`` for anything else: invalid JSON (``hint``, e.g. which command writes such a
    file, appended), a key given twice in one object (JSON readers keep the last one
    silently: which was meant?), ``NaN`` or ``Infinity`` (not JSON), nesting too deep. An
    integer too long for Python (:data:`INT_DIGITS`) is read as a :class:`HugeInteger`, so
    that the key holding it is named where a finite number is due."""
    try:
        return json.loads(text, object_pairs_hook=_pairs, parse_constant=_constant,
                          parse_int=_int)
    except _DuplicateKeyError as exc:
        raise FileFormatError(f"{label}: the key {exc.key!r} is given twice in one object "
                              "(a JSON reader would keep the last one silently; keep one)"
                              ) from None
    except _ConstantError as exc:
        raise FileFormatError(f"{label}: {exc} is not a JSON number (strict JSON has no NaN "
                              "or Infinity)") from None
    except json.JSONDecodeError as exc:
        raise FileFormatError(f"{label}: not valid JSON ({exc.msg}, line {exc.lineno}){hint}"
                              ) from None
    except RecursionError:
        raise FileFormatError(f"{label}: nested too deep to read (arrays or objects inside "
                              "each other thousands of levels deep): not a file fcomp "
                              "writes") from None
    except ValueError as exc:  # an integer of more digits than Python converts (4300)
        digits = re.search(r"has (\d+) digits", str(exc))
        size = f"of {digits.group(1)} digits " if digits else ""
        raise FileFormatError(f"{label}: holds an integer {size}too long to read: not a value "
                              "any fcomp file holds") from None


def read_json(path: str | Path, what: str = "JSON file", hint: str = "") -> Any:
    """The strict JSON (:func:`parse_json`) of the file ``path``; every problem, the path's
    too (missing, a folder, not text), one :class:`~fcomp.errors.FileFormatError` line."""
    label = str(path)
    try:
        text = read_text(check_path(path, what), label, what="JSON")
    except FileFormatError:
        raise
    except FcompError as exc:
        raise FileFormatError(str(exc)) from None
    return parse_json(text, label, hint)


def _strip(line: str) -> str:
    i = line.find("#")
    return (line if i < 0 else line[:i]).strip()


@dataclass
class Table:
    """Numbers read from a text table.

    Attributes
    ----------
    data
        ``(rows, columns)`` floats.
    lines
        The file line number (1-based) of every row of ``data``.
    """

    data: np.ndarray
    lines: np.ndarray


def parse_rows(label: str, rows: list[tuple[int, str]], delimiter: str | None,
               names: list[str] | None = None, what: str = "numbers") -> Table:
    """Parse ``(line_number, text)`` rows of numbers separated by ``delimiter``
    (``None``: whitespace). Every row must have ``len(names)`` values (or as many
    as the first row)."""
    if not rows:
        raise FcompError(f"{label}: no data rows" + (" after the header" if names else ""))
    width = len(names) if names is not None else len(_split(rows[0][1], delimiter))
    lines = np.array([n for n, _ in rows], dtype=np.int64)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            data = np.loadtxt([r for _, r in rows], delimiter=delimiter, ndmin=2, dtype=float,
                              comments=None)
        if data.shape == (len(rows), width):
            return Table(data, lines)
    except ValueError:
        pass
    for n, text in rows:  # find the first bad cell, in the user's terms
        cells = _split(text, delimiter)
        if len(cells) != width:
            ref = f"the header has {width}" if names is not None else f"the first row has {width}"
            raise FcompError(f"{label}: cannot read as {what}: row {n} has {len(cells)} values, "
                             f"{ref}")
        for j, cell in enumerate(cells):
            try:
                float(cell)
                number = "_" not in cell  # Python reads 1_000; a data file must not
            except ValueError:
                number = False
            if not number:
                col = f"column {names[j]!r}" if names is not None else f"column {j + 1}"
                problem = (f"{cell!r} is not a number" if cell else "the value is missing") + (
                    " (digit separators are not read: write 1000, not 1_000)" if "_" in cell
                    else "")
                raise FcompError(f"{label}: cannot read as {what}: row {n}, {col}: "
                                 f"{problem}") from None
    raise FcompError(f"{label}: cannot read as {what}")  # pragma: no cover - loadtxt disagreed


def _split(text: str, delimiter: str | None) -> list[str]:
    return [c.strip() for c in (text.split(delimiter) if delimiter else text.split())]


def data_rows(text: str, start: int = 0) -> list[tuple[int, str]]:
    """Non-blank, non-comment lines of ``text`` from line index ``start`` on, with their
    1-based line numbers."""
    out = []
    for i, line in enumerate(text.splitlines()[start:], start=start + 1):
        s = _strip(line)
        if s:
            out.append((i, s))
    return out


def header_names(label: str, text: str) -> tuple[list[str], int]:
    """The column names of the first line that is neither blank nor a ``#`` comment
    (comma-separated, optionally quoted) and the index of the line after it."""
    lines = text.splitlines()
    idx = 0
    while idx < len(lines) and not _strip(lines[idx]):  # blank lines and # comments
        idx += 1
    header = lines[idx].strip() if idx < len(lines) else ""
    if not header:
        raise FcompError(f"{label}: the first line must be comma-separated column names "
                         "(the file is empty)")
    names = [_unquote(h.strip()) for h in header.split(",")]
    if len(names) == 1:
        for sep, word in ((";", "semicolons"), ("\t", "tabs")):
            if sep in header:
                raise FcompError(f"{label}: the header is separated by {word}; fcomp reads "
                                 "comma-separated values with a '.' decimal point "
                                 "(save the file as CSV with commas)")
    if any(not n for n in names):
        raise FcompError(f"{label}: the first line must be comma-separated column names "
                         "(one is empty)")
    seen: set[str] = set()
    for n in names:
        if n in seen:
            raise FcompError(f"{label}: duplicate column names in the header ({n!r} twice)")
        seen.add(n)
    return names, idx + 1


def _unquote(name: str) -> str:
    if len(name) >= 2 and name[0] == name[-1] and name[0] in "\"'":
        return name[1:-1].strip()
    return name


def first_bad(values: np.ndarray, limit: float = math.inf) -> int | None:
    """Index of the first non-finite value (or of magnitude above ``limit``), or ``None``."""
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(values) | (np.abs(values) > limit)
    return int(np.argmax(bad)) if bad.any() else None
