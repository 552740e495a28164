"""Importers: real data sets -> the measurement format of data-format.md.

One function per KIND, registered in :data:`IMPORTERS` by the name used on the
command line (``fcomp import KIND SRC -o OUT.csv``). Every importer returns a
validated :class:`~fcomp.measurement.Measurement` in SI units whose sidecar
carries the provenance in a ``[source]`` table (original file name and SHA-256,
repository, licence, citation, the importer and the fcomp version) and the
conversion notes in ``[source].notes``. Sign conventions are those of
data-format.md: ``x`` positive = extending, ``F_ext`` positive when it pushes
in the extending direction, so that (seed 000, Eq. 1, models.md section 2)

    F = p1*A1 - p2*A2 - m*a - m*g*s + F_ext

is the friction force, positive opposing extension.

Kinds
-----
``emps``
    EMPS benchmark ``.mat`` (Janot, Gautier & Brunot 2019): ``t``; ``x = qm``;
    ``F_ext = gtau*vir`` (motor force on the carriage, N); user columns
    ``x_ref = qg`` (m), ``u = vir`` (V) and ``pulses_N`` where present.
``zillen``
    TU Delft pneumatic seal-friction text files (Zillen, Vallery & Smit 2021).
``mataveid``
    MataveID hydraulic bench CSV (raw volts, no calibration).
``mat``
    Any ``.mat`` file through a column mapping (:mod:`fcomp.matfile`) and an
    optional sidecar TOML giving the rig.
``csv``
    Any CSV file (comma, semicolon or tab separated; ``.`` or ``,`` decimal
    point) through the same mapping, with units and an optional sidecar TOML:
    :func:`import_csv`.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fcomp.errors import FcompError, term
from fcomp.matfile import from_variables, load_mat, parse_mapping
from fcomp.measurement import Measurement, check_sidecar, checked, read_sidecar
from fcomp.registry import Registry
from fcomp.textdata import check_path, data_rows, parse_rows, read_text
from fcomp.version import __version__

#: Where each known data set comes from (written into the ``[source]`` table).
ORIGINS: dict[str, dict[str, str]] = {
    "emps": {
        "dataset": "EMPS (Electro-Mechanical Positioning System) benchmark",
        "repository": "https://github.com/forgi86/sysid-neural-continuous "
                      "(examples/EMPS/data), redistributing the benchmark files",
        "licence": "none stated by the benchmark; cite the paper",
        "citation": "A. Janot, M. Gautier, M. Brunot, Data Set and Reference Models of EMPS, "
                    "2019 Workshop on Nonlinear System Identification Benchmarks, Eindhoven",
    },
    "zillen": {
        "dataset": "Pneumatic cylinder seal-friction tests (3D-printed pneumatic actuators)",
        "repository": "https://github.com/EvaZillen/3D-printed-pneumatic-actuator "
                      "(results_pneumatic-actuator/data, HEAD 6e0bcb4)",
        "licence": "CC0-1.0",
        "citation": "E. Zillen, H. Vallery, G. Smit, MSc thesis, TU Delft BioMechanical Design, "
                    "2021",
    },
    "mataveid": {
        "dataset": "MataveID electro-hydraulic bench recording (HangingLoad)",
        "repository": "https://github.com/DanielMartensson/MataveID (data/HangingLoad.csv, "
                      "commit 4a12ff2)",
        "licence": "MIT (Copyright (c) 2017 Daniel Mårtensson)",
        "citation": "D. Mårtensson, MataveID, GitHub repository",
    },
}


@dataclass(frozen=True)
class Importer:
    """A registered importer.

    Attributes
    ----------
    function
        ``function(src, **options) -> Measurement``.
    options
        The keyword options it accepts (the CLI refuses the others).
    summary
        One line for help texts.
    """

    function: Callable[..., Measurement]
    options: tuple[str, ...]
    summary: str


IMPORTERS: Registry[Importer] = Registry("import kind")


def import_file(kind: str, src: str | Path, **options: Any) -> Measurement:
    """Convert ``src`` with the importer registered as ``kind``.

    Raises
    ------
    UnknownNameError
        For an unknown kind.
    FcompError
        For an option the importer does not take, or any problem with the file.
    """
    imp = IMPORTERS.get(kind)
    bad = sorted(set(options) - set(imp.options))
    if bad:
        allowed = ", ".join(imp.options) or "none"
        raise FcompError(f"import {kind}: option(s) {', '.join(bad)} do not apply "
                         f"(options of {kind}: {allowed})")
    return imp.function(Path(src), **options)


def provenance(src: Path, kind: str, notes: str = "", **extra: Any) -> dict[str, Any]:
    """The ``[source]`` sidecar table for a file converted by importer ``kind``."""
    out: dict[str, Any] = {"file": src.name, "sha256": _sha256(src),
                           "importer": f"fcomp import {kind}", "fcomp_version": __version__}
    out.update(ORIGINS.get(kind, {}))
    out.update(extra)
    if notes:
        out["notes"] = notes
    return out


def _sha256(src: Path) -> str:
    try:
        return hashlib.sha256(src.read_bytes()).hexdigest()
    except OSError as exc:
        raise FcompError(f"{src}: cannot read ({exc.strerror or exc})") from None


def _require_file(src: Path) -> None:
    check_path(src)


# ---------------------------------------------------------------------- EMPS
EMPS_NOTES = (
    "x = qm (carriage position, m); F_ext = gtau*vir, the motor force on the carriage (N, "
    "positive in +x); x_ref = qg (reference position, m); u = vir (drive input, V); "
    "pulses_N (validation file) kept unchanged and not added to F_ext: the pulses are "
    "already in vir (F_ext jumps within one sample by about gtau*5 V = 176 N when pulses_N "
    "steps from 0 to 5; the benchmark calls them force pulses in newtons, the data show them "
    "added to the drive input). Closed-loop data "
    "(position loop gains kp, kv). No moving mass is given: rigid model "
    "M*qdd + Fv*qd + Fc*sign(qd) + offset = F_ext, M to be estimated."
)


def import_emps(src: Path) -> Measurement:
    """EMPS benchmark ``.mat`` -> measurement (kind ``electromechanical-axis``, no mass).

    Columns: ``t`` (s), ``x = qm`` (m), ``F_ext = gtau*vir`` (N), ``x_ref = qg`` (m),
    ``u = vir`` (V), ``pulses_N`` (N, validation file only, carried unchanged).
    """
    variables = load_mat(src)
    required = ("t", "qm", "qg", "vir", "gtau")
    missing = [k for k in required if k not in variables]
    if missing:
        raise FcompError(f"{src}: not an EMPS file, variable(s) {', '.join(missing)} missing "
                         "(use 'fcomp import mat' with --map for other .mat files)")
    mapping = {"t": "t", "x": "qm", "F_ext": "gtau*vir", "x_ref": "qg", "u": "vir"}
    if "pulses_N" in variables:
        mapping["pulses_N"] = "pulses_N"
    gains = {k: float(np.squeeze(variables[k])) for k in ("gtau", "kp", "kv") if k in variables}
    meta = {
        "name": src.stem,
        "kind": "electromechanical-axis",  # a DC motor and ball screw: no chambers
        "rig": {"orientation": "horizontal"},
        "signals": {"u_unit": "V"},
        "source": provenance(src, "emps", EMPS_NOTES, mapping=mapping, **gains),
    }
    return from_variables(variables, mapping, meta, source=src)


# -------------------------------------------------------------------- Zillen
ZILLEN_BORE = 0.025         # m, the standard cylinder of the set-up
ZILLEN_BORE_257 = 0.0257    # m, files with "257" in the name (authors' script)
ZILLEN_NOTES = (
    "Axis: x = -(laser position)*1e-3, positive = extension = the direction in which the "
    "chamber pressure pushes the piston (the laser reading grows as the piston retracts: "
    "the authors' friction Force - p*A is positive while the laser reading grows). "
    "p1 = chamber pressure (bar -> Pa, gauge), acting on A1 = pi/4*bore^2; the other side "
    "of the piston is open to atmosphere, so there is no p2 column (p2 = 0 gauge) and "
    "rig.rod is not needed. F_ext = -(load-cell force), N: the load cell holds the piston "
    "against the pressure. Hence F = p1*A1 + F_ext - m*a = -(Force - p*A) - m*a, the "
    "authors' friction with the sign of this package. Moving mass and mounting orientation "
    "are not given (a vertical mounting would show as a constant offset m*g). Raw sensor "
    "volts kept as laser_V, pressure_V, force_V. Rows with a repeated time stamp are "
    "dropped (the first is kept): counts in duplicate_rows_dropped (identical rows) and "
    "repeated_times_dropped (same time, different values)."
)


def import_zillen(src: Path, *, bore: float | None = None) -> Measurement:
    """TU Delft pneumatic seal-friction file -> measurement (kind ``pneumatic-cylinder``).

    The 7 whitespace-separated columns are time (ms), laser (V), pressure (V),
    force (V), laser position (mm), chamber pressure (bar, gauge), force (N).
    Output: ``t`` (s), ``x`` (m), ``p1`` (Pa gauge), ``F_ext`` (N) and the raw volts;
    see :data:`ZILLEN_NOTES` for the axis and sign conventions. ``bore`` (m)
    defaults to 25.7 mm for file names containing ``257``, else 25 mm.
    """
    _require_file(src)
    table = parse_rows(str(src), data_rows(read_text(src, what="whitespace-separated numbers")),
                       None, what="whitespace-separated numbers")
    raw, lines = table.data, table.lines
    if raw.shape[1] != 7 or raw.shape[0] < 2:
        raise FcompError(f"{src}: expected 7 whitespace-separated columns and at least two rows "
                         f"(got {raw.shape[0]} rows of {raw.shape[1]})")
    bad = ~np.isfinite(raw)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise FcompError(f"{src}: non-finite value ({raw[row, col]}) at line {lines[row]}, "
                         f"column {col + 1}")
    dt = np.diff(raw[:, 0])
    if np.any(dt < 0):
        i = int(np.argmax(dt < 0))
        raise FcompError(f"{src}: time goes backwards at line {lines[i + 1]} "
                         f"({raw[i, 0]} ms -> {raw[i + 1, 0]} ms)")
    repeat = np.concatenate([[False], dt == 0])
    identical = repeat & np.concatenate([[False], np.all(raw[1:] == raw[:-1], axis=1)])
    raw = raw[~repeat]
    if bore is None:
        bore = ZILLEN_BORE_257 if "257" in src.name else ZILLEN_BORE
    cols = {
        "t": raw[:, 0] * 1e-3,
        "x": -raw[:, 4] * 1e-3 + 0.0,  # + 0.0: no negative zeros in the file
        "p1": raw[:, 5] * 1e5,
        "F_ext": -raw[:, 6],
        "laser_V": raw[:, 1],
        "pressure_V": raw[:, 2],
        "force_V": raw[:, 3],
    }
    meta = {
        "name": src.stem,
        "kind": "pneumatic-cylinder",
        "pressure": "gauge",
        "rig": {"bore": float(bore)},
        "source": provenance(src, "zillen", ZILLEN_NOTES,
                             duplicate_rows_dropped=int(identical.sum()),
                             repeated_times_dropped=int(repeat.sum() - identical.sum())),
    }
    return checked(cols, meta, src)


# ------------------------------------------------------------------ MataveID
MATAVEID_NOTES = (
    "Raw instrument volts, no calibration given: u = P-controller output (V, the valve "
    "command); r_raw = reference and y_raw = cylinder position, both in volts. Without a "
    "calibration there is no x in metres, no pressure and no force, so friction in newtons "
    "cannot be reconstructed; the file still shows the valve deadband / stiction (|u| up to "
    "~0.4 V with no motion) in the volt domain. With --position-scale K (m/V) the columns "
    "x = K*y_raw and x_ref = K*r_raw are added (a user-given calibration, not from the "
    "source)."
)


def import_mataveid(src: Path, *, position_scale: float | None = None) -> Measurement:
    """MataveID ``HangingLoad.csv`` (t, r, y, u; volts) -> measurement.

    Output: ``t`` (s), ``u`` (V), ``r_raw``, ``y_raw`` (V); with ``position_scale``
    (m/V, user calibration) also ``x`` and ``x_ref`` (m).
    """
    _require_file(src)
    table = parse_rows(str(src), data_rows(read_text(src, what="comma-separated numbers")),
                       ",", what="comma-separated numbers")
    raw = table.data
    if raw.shape[1] != 4:
        raise FcompError(f"{src}: expected 4 columns t, r, y, u (got {raw.shape[1]})")
    cols = {"t": raw[:, 0], "u": raw[:, 3], "r_raw": raw[:, 1], "y_raw": raw[:, 2]}
    extra: dict[str, Any] = {}
    if position_scale is not None:
        k = float(position_scale)
        if not np.isfinite(k) or k == 0.0:
            raise FcompError(f"{term('position_scale')} {position_scale}: must be a non-zero "
                             "number (m/V)")
        cols["x"] = k * raw[:, 2]
        cols["x_ref"] = k * raw[:, 1]
        extra["position_scale_m_per_V"] = k
    meta = {
        "name": src.stem,
        "kind": "hydraulic-cylinder",
        "signals": {"u_unit": "V"},
        "source": provenance(src, "mataveid", MATAVEID_NOTES, **extra),
    }
    return checked(cols, meta, src)


# ------------------------------------------------------------------- generic
def import_mat(src: Path, *, mapping: str | Mapping[str, str],
               sidecar: str | Path | None = None) -> Measurement:
    """Any MATLAB ``.mat`` file through a column mapping (see :mod:`fcomp.matfile`).

    ``sidecar`` is a TOML file with the rig and conventions of data-format.md
    (``kind``, ``pressure``, ``[rig]``, ``[signals]``); its content is copied into
    the output sidecar, with the ``[source]`` provenance added.
    """
    _require_file(src)
    meta = _sidecar(sidecar)
    cmap = parse_mapping(mapping) if isinstance(mapping, str) else dict(mapping)
    meta.setdefault("name", src.stem)
    meta["source"] = provenance(src, "mat", mapping=cmap,
                                **({"sidecar": Path(sidecar).name} if sidecar else {}))
    return from_variables(load_mat(src), cmap, meta, source=src)


def _sidecar(sidecar: str | Path | None) -> dict[str, Any]:
    """The content of an importer's ``sidecar`` file (``{}`` without one), checked: a bad
    value is named with that file, not with the data file."""
    if sidecar is None:
        return {}
    meta = read_sidecar(check_path(sidecar, "sidecar file"))
    check_sidecar(meta, str(sidecar))
    return meta


def _csv_table(src: Path, delimiter: str | None, decimal: str) -> dict[str, np.ndarray]:
    """The named columns of a CSV file: the first non-comment line is the header."""
    text = read_text(src, str(src), what="CSV numbers")
    lines = text.splitlines()
    idx = next((i for i, line in enumerate(lines) if line.strip() and
                not line.lstrip().startswith("#")), None)
    if idx is None:
        raise FcompError(f"{src}: the file is empty (a header line of column names is needed)")
    header = lines[idx]
    if delimiter is None:
        counts = {d: header.count(d) for d in (",", ";", "\t")}
        delimiter = max(counts, key=lambda d: counts[d]) if any(counts.values()) else ","
    if decimal not in (".", ","):
        raise FcompError(f"decimal: {decimal!r} must be '.' or ','")
    if decimal == delimiter:
        raise FcompError(f"{src}: the decimal mark and the delimiter are both {decimal!r}")
    from fcomp.matfile import split_outside_quotes

    names = [n.strip().strip("\"'").strip() for n in split_outside_quotes(header, delimiter)]
    if any(not n for n in names):
        raise FcompError(f"{src}: line {idx + 1}: a column name of the header is empty")
    dup = next((n for i, n in enumerate(names) if n in names[:i]), None)
    if dup is not None:
        raise FcompError(f"{src}: line {idx + 1}: column {dup!r} appears twice in the header")
    rows = data_rows(text, idx + 1)
    if decimal == ",":
        rows = [(n, r.replace(",", ".")) for n, r in rows]
    table = parse_rows(str(src), rows, delimiter, names, what="CSV numbers")
    return {n: table.data[:, i] for i, n in enumerate(names)}


def import_csv(src: Path, *, mapping: str | Mapping[str, str],
               units: str | Mapping[str, str] | None = None,
               sidecar: str | Path | None = None, drop: str | Sequence[str] | None = None,
               delimiter: str | None = None, decimal: str = ".") -> Measurement:
    """Any CSV file through a column mapping (the language of :mod:`fcomp.matfile`).

    ``mapping`` gives each measurement column as a product of CSV columns and
    numbers (``t=time_ms*1e-3,x='Position [mm]'*1e-3,F=-force``; a leading
    ``-`` flips the sign); ``units`` the unit of mapped columns, converted to SI
    (``x=mm,p1=bar,t=ms``; :data:`fcomp.measurement.UNITS`). Every CSV column
    must be used by the mapping or named in ``drop`` (``"*"``: every other one):
    a column left over is an error, so no signal is lost unnoticed.
    ``sidecar`` is a TOML file with the rig (as for ``mat``); ``delimiter``
    (default: the one of ``,``, ``;``, tab the header uses) and ``decimal``
    (``.`` or ``,``) describe the file.
    """
    from fcomp.matfile import split_outside_quotes

    _require_file(src)
    cmap = parse_mapping(mapping) if isinstance(mapping, str) else dict(mapping)
    umap = _pairs(units, "units") if isinstance(units, str) else dict(units or {})
    cols = _csv_table(src, delimiter, decimal)
    dropped = ([s.strip() for s in split_outside_quotes(drop, ",") if s.strip()]
               if isinstance(drop, str) else list(drop or []))
    dropped = [d.strip("\"'") for d in dropped]
    for d in dropped:
        if d != "*" and d not in cols:
            raise FcompError(f"{src}: drop: no column {d!r} in the file (columns: "
                             f"{', '.join(cols)})")
    meta = _sidecar(sidecar)
    meta.setdefault("name", src.stem)
    meta["source"] = provenance(src, "csv", mapping=cmap, units=umap,
                                **({"sidecar": Path(sidecar).name} if sidecar else {}))
    meas = from_variables(cols, cmap, meta, source=src, noun="column", units=umap)
    used = {tok.strip().lstrip("-").strip().strip("\"'") for e in cmap.values()
            for tok in split_outside_quotes(e.strip().lstrip("-"), "*")}
    both = [d for d in dropped if d in used]
    if both:
        raise FcompError(f"{src}: {term('drop')} {both[0]}: the column is mapped too "
                         f"({term('mapping')}); drop only columns the mapping does not use")
    left = [c for c in cols if c not in used and c not in dropped]
    if left and "*" not in dropped:
        names = ",".join(c if c.isidentifier() else f"'{c}'" for c in left)
        raise FcompError(f"{src}: column(s) {', '.join(repr(c) for c in left)} of the file "
                         f"are not mapped: map them ({term('mapping')} NAME=COLUMN) or leave "
                         f"them out ({term('drop')} {names})")
    return meas


def _pairs(spec: str, what: str) -> dict[str, str]:
    """``"x=mm,t=ms"`` -> ``{"x": "mm", "t": "ms"}``."""
    out: dict[str, str] = {}
    for item in (s.strip() for s in spec.split(",") if s.strip()):
        if "=" not in item:
            raise FcompError(f"{term(what)} {item!r}: expected COLUMN=UNIT")
        k, v = (x.strip() for x in item.split("=", 1))
        if k in out:
            raise FcompError(f"{term(what)}: column {k!r} is given twice")
        out[k] = v
    return out


IMPORTERS.register("emps", Importer(import_emps, (), "EMPS benchmark .mat (Janot et al. 2019)"))
IMPORTERS.register("zillen", Importer(import_zillen, ("bore",),
                                      "TU Delft pneumatic seal-friction text file (Zillen 2021)"))
IMPORTERS.register("mataveid", Importer(import_mataveid, ("position_scale",),
                                        "MataveID hydraulic bench CSV (raw volts)"))
IMPORTERS.register("mat", Importer(import_mat, ("mapping", "sidecar"),
                                   "any MATLAB .mat file with --map COLUMN=VARIABLE,..."))
IMPORTERS.register("csv", Importer(import_csv, ("mapping", "units", "sidecar", "drop",
                                                "delimiter", "decimal"),
                                   "any CSV file with --map COLUMN=EXPR,... and --units"))
