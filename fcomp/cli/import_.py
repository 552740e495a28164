r"""``fcomp import KIND SRC -o OUT.csv`` -- convert a real data file to the measurement format.

KIND is ``emps`` (EMPS benchmark .mat), ``zillen`` (TU Delft pneumatic
seal-friction text file), ``mataveid`` (MataveID hydraulic bench CSV), ``mat``
(any MATLAB .mat file with ``--map COLUMN=VARIABLE,...`` and an optional
``--sidecar RIG.toml``) or ``csv`` (any CSV file from another tool, with the
same ``--map`` language over its column names, ``--units COLUMN=UNIT,...``
converting to SI, ``--drop`` for columns left out, and ``--sidecar``).

The mapping: ``COLUMN=EXPR`` items separated by commas; ``EXPR`` a product of
names and numbers (``*``), a leading ``-`` flips the sign, a name that is not
an identifier is quoted (``x='Position [mm]'*1e-3``). Example::

    fcomp import csv log.csv --map "t=time_ms,x='pos [mm]',F=-force" \
          --units t=ms,x=mm --drop comment -o run.csv

Units (``--units``): s ms us min, m cm mm um in, m/s mm/s, m/s^2 g, Pa kPa MPa
bar mbar psi, N kN lbf, A mA V mV. The measurement format is described in
docs/data-format.md. Writes OUT.csv and OUT.toml (SI units, provenance in
the ``[source]`` table of the sidecar) atomically: on any error nothing is
written and the command exits with status 2.
"""

from __future__ import annotations

import argparse

from fcomp.cli.common import (
    check_outputs,
    finite_float,
    output_path,
    warn,
    warn_sidecar,
    write_measurement,
)


def add_parser(sub: argparse._SubParsersAction) -> None:
    from fcomp.importers import IMPORTERS

    kinds = ", ".join(f"{n} ({IMPORTERS.get(n).summary})" for n in IMPORTERS.names())
    p = sub.add_parser("import", help="convert a real data file to the measurement format",
                       description=__doc__)
    p.add_argument("kind", metavar="KIND", help=f"the file's kind: {kinds}")
    p.add_argument("src", metavar="SRC", help="the file to convert, or a data set shipped "
                   "with fcomp by name (fcomp list data: O-ring_3bar, DATA_EMPS, ...)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.csv",
                   help="the measurement written (OUT.csv and its sidecar OUT.toml)")
    p.add_argument("--map", dest="mapping", default=None, metavar="COL=EXPR,...",
                   help="mat, csv: column mapping, e.g. t=time,x=qm,F_ext=gtau*vir "
                   "(products of variables or CSV columns and numbers; a leading - flips the "
                   "sign; quote other names: x='pos [mm]')")
    p.add_argument("--units", default=None, metavar="COL=UNIT,...",
                   help="csv: the unit of mapped columns, converted to SI (e.g. t=ms,x=mm,"
                   "p1=bar)")
    p.add_argument("--drop", default=None, metavar="COLUMN,...",
                   help="csv: columns of the file left out ('*': every column not mapped); "
                   "any other unmapped column is an error")
    p.add_argument("--delimiter", default=None, type=_delimiter, metavar="comma|semicolon|tab",
                   help="csv: the field separator, comma (','), semicolon (';') or tab "
                   "(default: the one the header uses)")
    p.add_argument("--decimal", default=".", type=_decimal, metavar="point|comma",
                   help="csv: the decimal mark, point ('.', the default) or comma (',')")
    p.add_argument("--sidecar", default=None, metavar="RIG.toml",
                   help="mat, csv: a TOML file with kind, pressure, [rig], [signals] "
                   "(docs/data-format.md)")
    p.add_argument("--bore", type=finite_float, default=None, metavar="M",
                   help="zillen: piston bore in m (default from the file name: 0.0257 if it "
                   "contains 257, else 0.025)")
    p.add_argument("--position-scale", type=finite_float, default=None, metavar="M_PER_V",
                   help="mataveid: a calibration of the position signal in m/V, adds x and x_ref")
    p.set_defaults(func=run)


#: ``--delimiter`` and ``--decimal``: the words (and the characters) each accepts.
_DELIMITERS = {"comma": ",", ",": ",", "semicolon": ";", ";": ";", "tab": "tab", "\t": "tab"}
_DECIMALS = {"point": ".", ".": ".", "comma": ",", ",": ","}


def _delimiter(text: str) -> str:
    """argparse ``type=`` of ``--delimiter``: ``,``, ``;`` or ``tab``."""
    try:
        return _DELIMITERS[text.strip().lower()]
    except KeyError:
        raise argparse.ArgumentTypeError(f"{text!r} is not comma, semicolon or tab") from None


def _decimal(text: str) -> str:
    """argparse ``type=`` of ``--decimal``: ``.`` or ``,``."""
    try:
        return _DECIMALS[text.strip().lower()]
    except KeyError:
        raise argparse.ArgumentTypeError(f"{text!r} is not point or comma") from None


def _source(kind: str, src: str) -> str:
    """``src``: a file, else the shipped data set file of that name for importer ``kind``
    (``fcomp import zillen O-ring_3bar``, from any folder; ``fcomp list data``)."""
    from pathlib import Path

    from fcomp import datasets
    from fcomp.errors import FcompError

    if not src.strip() or Path(src).exists():
        return src
    found = datasets.shipped(kind, src)
    if found is not None:
        return str(found)
    known = datasets.shipped_names(kind)
    if known and "/" not in src and "\\" not in src:
        raise FcompError(f"{src}: file not found, and no data set shipped for import {kind} "
                         f"has that name (shipped: {', '.join(known)}; fcomp list data)")
    return src


def run(args: argparse.Namespace) -> int:
    from fcomp.errors import FcompError
    from fcomp.importers import IMPORTERS, import_file
    from fcomp.outputs import InputSet
    from fcomp.textdata import check_path

    out = output_path(args.output)
    if args.delimiter == "tab":
        args.delimiter = "\t"
    if args.decimal == ".":
        args.decimal = None  # the default: an option only csv takes
    options = {k: getattr(args, k) for k in ("mapping", "sidecar", "bore", "position_scale",
                                             "units", "drop", "delimiter", "decimal")
               if getattr(args, k) is not None}
    IMPORTERS.get(args.kind)  # an unknown kind first: it decides which options apply
    if args.kind in ("mat", "csv") and "mapping" not in options:
        raise FcompError(f"import {args.kind}: --map COLUMN=EXPR,... is required (t at least)")
    if args.bore is not None and not 0 < args.bore <= 2.0:
        raise FcompError(f"--bore {args.bore:g}: must be a positive length in metres "
                         "(e.g. 0.025 for 25 mm)")
    args.src = _source(args.kind, args.src)
    inputs = InputSet()
    inputs.file(check_path(args.src), "SRC")
    if args.sidecar is not None:
        inputs.file(check_path(args.sidecar, "sidecar file"), "--sidecar")
    check_outputs(inputs, [("-o", out)])
    meas = import_file(args.kind, args.src, **options)
    source = meas.meta.get("source", {})
    dropped = int(source.get("duplicate_rows_dropped", 0)) + int(
        source.get("repeated_times_dropped", 0))
    if dropped:
        warn("rows-dropped", f"{args.src}: {dropped} row(s) with a repeated time stamp dropped "
             "(the first of each kept; counts in the sidecar's [source])")
    warn_sidecar(meas)
    csv, toml = write_measurement(meas, out)
    print(f"wrote {csv} and {toml} ({len(meas)} samples, columns {', '.join(meas.columns)})")
    return 0
