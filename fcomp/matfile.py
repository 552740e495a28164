"""MATLAB ``.mat`` files -> :class:`~fcomp.measurement.Measurement` with a column mapping.

A mapping says which measurement column (data-format.md) comes from which
variable of the file, e.g. ``t=time,x=qm,F_ext=gtau*vir``. The right-hand side
of each entry is a product of factors separated by ``*``, each factor a
variable name (``qm``; a field of a MATLAB struct as ``data.qm``) or a number
(``1e-3`` to convert mm to m), optionally preceded by one ``-`` for a sign
change. Vector variables (``N``, ``N x 1`` or ``1 x N``) give the samples;
scalar variables (``1 x 1``, e.g. a gain) multiply every sample. A name
that is not an identifier (a CSV header such as ``Position [mm]``) is quoted:
``x='Position [mm]'*1e-3``. The same language maps the columns of any CSV
file (``fcomp import csv``, :func:`fcomp.importers.import_csv`).

MATLAB v4, v6 and v7 files are read with :func:`scipy.io.loadmat`; v7.3 files
(HDF5) are refused with a one-line error telling the user to save with ``-v7``.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from fcomp.errors import FcompError, term
from fcomp.measurement import Measurement, checked, si_factor
from fcomp.textdata import check_path

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")
_COLUMN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*$")


def load_mat(path: str | Path) -> dict[str, Any]:
    """The variables of a ``.mat`` file (structs as nested dicts, arrays squeezed).

    Raises
    ------
    FcompError
        The file is missing, is MATLAB v7.3/HDF5, or cannot be read as a ``.mat`` file.
    """
    p = check_path(path)
    try:
        with p.open("rb") as fh:
            head = fh.read(128)
    except OSError as exc:
        raise FcompError(f"{p}: cannot read ({exc.strerror or exc})") from None
    if b"MATLAB 7.3" in head or head[:8] == b"\x89HDF\r\n\x1a\n":
        raise FcompError(
            f"{p}: MATLAB v7.3 (HDF5) files are not supported; save it with save(..., '-v7')"
        )
    import scipy.io  # here: keeps the command line's start-up light

    try:
        raw = scipy.io.loadmat(p, simplify_cells=True)
    except Exception as exc:  # scipy raises several types for corrupt files
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise FcompError(f"{p}: cannot read as a MATLAB .mat file ({msg})") from None
    return {k: v for k, v in raw.items() if not k.startswith("__")}


def _bad(message: str) -> FcompError:
    """The error of a malformed column mapping (the CLI's ``--map``)."""
    return FcompError(message.replace("mapping", term("mapping"), 1))


def split_outside_quotes(text: str, sep: str) -> list[str]:
    """``text`` split at ``sep`` where it is not inside single or double quotes."""
    parts: list[str] = []
    buf: list[str] = []
    quote = ""
    for ch in text:
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == sep:
            parts.append("".join(buf))
            buf = []
            continue
        buf.append(ch)
    parts.append("".join(buf))
    return parts


def parse_mapping(spec: str) -> dict[str, str]:
    """``"t=time,x=qm,F_ext=gtau*vir"`` -> ``{"t": "time", "x": "qm", "F_ext": "gtau*vir"}``."""
    out: dict[str, str] = {}
    for item in (s.strip() for s in split_outside_quotes(spec, ",")):
        if not item:
            continue
        if "=" not in item:
            raise _bad(f"mapping {item!r}: expected COLUMN=VARIABLE")
        col, expr = (s.strip() for s in item.split("=", 1))
        if not _COLUMN.match(col):
            raise _bad(f"mapping {item!r}: {col!r} is not a valid column name")
        if col in out:
            raise _bad(f"mapping: column {col!r} is mapped twice")
        if not expr:
            raise _bad(f"mapping {item!r}: no variable given for column {col!r}")
        out[col] = expr
    if "t" not in out:
        raise _bad("mapping: the time column 't' must be mapped (e.g. t=time)")
    return out


def _lookup(variables: Mapping[str, Any], name: str, path: Path, quoted: bool = False,
            noun: str = "variable") -> Any:
    obj: Any = variables
    for part in [name] if quoted or noun != "variable" else name.split("."):
        if not isinstance(obj, Mapping) or part not in obj:
            have = ", ".join(sorted(k for k in variables)) or "none"
            raise FcompError(f"{path}: no {noun} {name!r} in the file ({noun}s: {have})")
        obj = obj[part]
    return obj


def _factor(variables: Mapping[str, Any], token: str, path: Path, column: str,
            noun: str = "variable") -> np.ndarray:
    try:
        number = float(token)
    except ValueError:
        pass
    else:
        if not math.isfinite(number):
            shown = token if len(token) <= 30 else f"{token[:12]}... ({len(token)} characters)"
            raise FcompError(f"{path}: column {column!r}: the number {shown} in the mapping is "
                             "not a finite number (beyond about 1.8e308, or nan/inf)")
        return np.asarray(number)
    quoted = len(token) >= 2 and token[0] == token[-1] and token[0] in "'\""
    if quoted:
        token = token[1:-1]
    elif not _NAME.match(token):
        raise FcompError(f"{path}: column {column!r}: {token!r} is neither a variable nor a "
                         "number (quote a name that is not an identifier: 'Position [mm]')")
    value = _lookup(variables, token, path, quoted, noun)
    try:
        arr = np.asarray(value)
        if np.iscomplexobj(arr) or arr.dtype.kind not in "biuf":
            raise TypeError
        arr = arr.astype(float)
    except (TypeError, ValueError):
        raise FcompError(
            f"{path}: variable {token!r} (for column {column!r}) is not a real numeric array"
        ) from None
    arr = np.squeeze(arr)
    if arr.ndim > 1:
        raise FcompError(
            f"{path}: variable {token!r} (for column {column!r}) has shape {arr.shape}; "
            "a vector or a scalar is needed"
        )
    return arr


def evaluate(variables: Mapping[str, Any], expr: str, *, path: str | Path, column: str,
             noun: str = "variable") -> np.ndarray:
    """Evaluate one mapping expression (product of variables / numbers, optional leading ``-``)."""
    p = Path(path)
    text = expr.strip()
    sign = 1.0
    if text.startswith("-"):
        sign, text = -1.0, text[1:].strip()
    tokens = [s.strip() for s in split_outside_quotes(text, "*")]
    if any(not s for s in tokens):
        raise FcompError(f"{p}: column {column!r}: cannot parse {expr!r}")
    factors = [_factor(variables, token, p, column, noun) for token in tokens]  # looked up once
    value: np.ndarray = np.asarray(sign)
    with np.errstate(over="ignore", invalid="ignore"):
        for f in factors:
            value = value * f
    out = np.asarray(value, dtype=float)
    if all(np.isfinite(f).all() for f in factors) and not np.all(np.isfinite(out)):
        raise FcompError(f"{p}: column {column!r}: {expr!r} overflows (the product is beyond "
                         "floating-point range); check the factors")
    return out


def read_mat(path: str | Path, mapping: Mapping[str, str] | str,
             meta: Mapping[str, Any] | None = None) -> Measurement:
    """Read a ``.mat`` file into a :class:`Measurement` through a column mapping.

    Parameters
    ----------
    path
        The ``.mat`` file.
    mapping
        ``{column: expression}`` or the ``"col=expr,..."`` text (see the module doc).
    meta
        The sidecar content to attach (rig, kind, provenance).

    Raises
    ------
    FcompError
        Naming the file and the problem (missing variable, wrong shape, lengths that
        differ, non-finite values, time not strictly increasing).
    """
    p = Path(path)
    cmap = parse_mapping(mapping) if isinstance(mapping, str) else dict(mapping)
    return from_variables(load_mat(p), cmap, meta, source=p)


def from_variables(variables: Mapping[str, Any], mapping: Mapping[str, str],
                   meta: Mapping[str, Any] | None, *, source: str | Path,
                   noun: str = "variable", units: Mapping[str, str] | None = None
                   ) -> Measurement:
    """:func:`read_mat` on variables already loaded with :func:`load_mat` (or the columns of
    a CSV file, ``noun="column"``); ``units`` gives the unit of mapped columns, converted
    to SI (:func:`fcomp.measurement.si_factor`)."""
    p = Path(source)
    cmap = dict(mapping)
    if "t" not in cmap:
        raise FcompError(f"{p}: the mapping must give the time column 't'")
    cols = {c: evaluate(variables, e, path=p, column=c, noun=noun) for c, e in cmap.items()}
    for c, unit in (units or {}).items():
        if c not in cols:
            raise FcompError(f"{p}: units: column {c!r} is not mapped (mapped: "
                             f"{', '.join(cols)})")
        cols[c] = cols[c] * si_factor(c, unit, "units")
    n = max((v.size for v in cols.values() if v.ndim == 1), default=0)
    if cols["t"].ndim != 1:
        raise FcompError(f"{p}: time {cmap['t']!r} is a scalar, not a vector of sample times")
    lengths = {c: v.size for c, v in cols.items() if v.ndim == 1}
    if len(set(lengths.values())) > 1:
        desc = ", ".join(f"{c}: {k}" for c, k in lengths.items())
        raise FcompError(f"{p}: the mapped variables have different lengths ({desc})")
    cols = {c: (np.full(n, float(v)) if v.ndim == 0 else v) for c, v in cols.items()}
    cols = {"t": cols.pop("t"), **cols}
    doc = dict(meta or {})
    doc.setdefault("name", p.stem)
    return checked(cols, doc, p)

