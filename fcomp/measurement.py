"""Measurements and simulation results: one class, one file format (data-format.md).

A :class:`Measurement` is a time vector, named columns in SI units and the
sidecar metadata. It is written as ``NAME.csv`` (header line, one row per
sample, ``.`` decimal point, full ``repr`` precision so a round trip is
lossless) and ``NAME.toml`` (the rig and the conventions); unknown columns
and sidecar keys are carried through unchanged.

Validation (:meth:`Measurement.validate`, run on construction, before writing
and after reading) enforces data-format.md: a ``t`` column, strictly
increasing time, finite values, columns of equal length, and plausible SI
units. The unit checks are deliberately coarse, to catch the usual mistakes
without rejecting real data:

* ``rig.bore`` and ``rig.rod`` above 2 m, or ``rig.stroke`` above 20 m, are
  taken as millimetres and refused;
* a ``p1``/``p2`` column whose largest magnitude is above zero but below
  50 Pa is taken as bar or MPa and refused (a pressure transducer on a real
  chamber reads thousands of pascals; an all-zero column, a chamber vented
  to atmosphere in gauge pressure, is accepted); absolute pressures must not
  be negative;
* an ``x`` column spanning more than 20 m, or more than twice ``rig.stroke``
  plus 10 mm, is taken as millimetres and refused;
* ``signals.u_unit``, where given, must be ``"A"`` or ``"V"``.

Every error is one line naming the file (or measurement) and the problem.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fcomp.errors import FcompError
from fcomp.outputs import write_files
from fcomp.piston import piston_areas
from fcomp.textdata import data_rows, first_bad, header_names, parse_rows, read_text

#: Columns of data-format.md with their SI unit.
COLUMN_UNITS: dict[str, str] = {
    "t": "s", "x": "m", "v": "m/s", "a": "m/s^2", "p1": "Pa", "p2": "Pa",
    "u": "A or V", "F": "N", "F_ext": "N",
}
#: Units a column may be given in (import csv ``--units``, :meth:`Measurement.from_dataframe`):
#: unit -> (the SI unit, factor to SI). A column's unit must have its SI unit
#: (:data:`COLUMN_UNITS`; ``u`` in A or V).
UNITS: dict[str, tuple[str, float]] = {
    "s": ("s", 1.0), "ms": ("s", 1e-3), "us": ("s", 1e-6), "min": ("s", 60.0),
    "m": ("m", 1.0), "cm": ("m", 1e-2), "mm": ("m", 1e-3), "um": ("m", 1e-6),
    "in": ("m", 0.0254),
    "m/s": ("m/s", 1.0), "mm/s": ("m/s", 1e-3), "cm/s": ("m/s", 1e-2), "um/s": ("m/s", 1e-6),
    "m/s^2": ("m/s^2", 1.0), "mm/s^2": ("m/s^2", 1e-3), "g": ("m/s^2", 9.80665),
    "Pa": ("Pa", 1.0), "kPa": ("Pa", 1e3), "MPa": ("Pa", 1e6), "bar": ("Pa", 1e5),
    "mbar": ("Pa", 1e2), "psi": ("Pa", 6894.757293168361),
    "N": ("N", 1.0), "kN": ("N", 1e3), "lbf": ("N", 4.4482216152605),
    "A": ("A", 1.0), "mA": ("A", 1e-3), "V": ("V", 1.0), "mV": ("V", 1e-3),
}


def si_factor(column: str, unit: str, where: str = "units") -> float:
    """The factor that turns ``column`` given in ``unit`` into SI units (:data:`UNITS`).

    A column of the format must be given in a unit of its own kind (``x`` in
    ``mm``, not ``bar``); another column may be in any unit of the table (its
    values are scaled to the SI unit). Raises :class:`FcompError` naming ``where``.
    """
    unit = unit.strip()
    if unit in ("", "-", "1"):
        return 1.0
    if unit not in UNITS:
        raise FcompError(f"{where}: {column}={unit}: unknown unit (known: {', '.join(UNITS)})")
    si, factor = UNITS[unit]
    want = COLUMN_UNITS.get(column)
    if want is not None and si not in want.split(" or "):
        raise FcompError(f"{where}: {column}={unit}: column {column!r} is in {want}, and "
                         f"{unit} is a unit of {si}")
    return factor


#: Rig kinds of the sidecar's ``kind`` (data-format.md): they choose, e.g., which experiment
#: the diagnosis advises (:func:`fcomp.effects.experiment_for`).
KINDS = ("pneumatic-cylinder", "hydraulic-cylinder", "friction-rig", "electromechanical-axis")
ORIENTATIONS = {"horizontal": 0.0, "vertical-up": 1.0, "vertical-down": -1.0}
G = 9.80665
#: Largest plausible value of each length in ``[rig]`` (m); larger ones are taken as mm.
MAX_LENGTH = {"bore": 2.0, "rod": 2.0, "stroke": 20.0}
#: Largest plausible moving mass in ``[rig]`` (kg): beyond it the value is a unit mistake or
#: corrupted (and a force ``m*a`` of it overflows the computations).
MAX_MASS = 1.0e6
#: Shortest time step of a record (s): no rig logs faster than a gigahertz; shorter steps are
#: stamps in another unit or corrupted (and a rate of ``1/dt`` overflows the filters).
MIN_STEP = 1.0e-9
#: A non-zero pressure column whose largest magnitude is below this (Pa) is bar or MPa.
MIN_PRESSURE_SCALE = 50.0
U_UNITS = ("A", "V")
#: Range of a plausible sidecar ``p_atm`` (Pa): sea level down to high altitude, a
#: pressurised lab up to 2 bar; anything else is a unit mistake (bar, kPa).
P_ATM_RANGE = (1.0e4, 2.0e5)
#: The keys of the ``[rig]`` table; others are kept, with a warning (a typo?).
RIG_KEYS = ("bore", "rod", "stroke", "mass", "orientation")
#: Largest magnitude accepted in a column of the format (SI units): anything larger is
#: a unit mistake (nanoseconds, micrometres) or a corrupted value, and would overflow
#: the computations (squares, exponentials) with a misleading message later.
MAX_MAGNITUDE = 1e12


@dataclass
class Measurement:
    """A measurement or simulated run (SI units).

    Attributes
    ----------
    columns
        Column name -> 1-D float array, ``t`` first; all of one length.
    meta
        Sidecar content (``name``, ``kind``, ``pressure``, ``[rig]``, ``[signals]``,
        any other keys kept as they are).
    """

    columns: dict[str, np.ndarray]
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.columns = {k: np.asarray(v, dtype=float) for k, v in self.columns.items()}
        self.validate()

    def __repr__(self) -> str:
        t = self.columns.get("t")
        span = (f", t {float(t[0]):.4g}..{float(t[-1]):.4g} s" if t is not None and t.size
                else "")
        return (f"<Measurement {self.label!r}: {len(self)} samples{span}, columns "
                f"{', '.join(self.columns)}>")

    def _repr_html_(self) -> str:
        """Jupyter's view: every column with its unit and range, the sidecar's rig, and the
        position and force against time."""
        from matplotlib.figure import Figure

        from fcomp.report import notebook_html

        units = self.units()
        rows: list[list[str]] = [["column", "unit", "min", "max"]]
        rows += [[k, units.get(k, ""), f"{float(np.min(v)):.4g}", f"{float(np.max(v)):.4g}"]
                 for k, v in self.columns.items() if v.size]
        rig = self.meta.get("rig") if isinstance(self.meta.get("rig"), Mapping) else {}
        rows += [[f"rig.{k}", "", str(v), ""] for k, v in (rig or {}).items()]
        shown = [(k, f, u) for k, f, u in (("x", 1e3, "mm"), ("F", 1.0, "N"),
                                           ("F_ext", 1.0, "N")) if k in self.columns]
        fig = None
        if shown and len(self) > 1:
            fig = Figure(figsize=(7.0, 1.8 * len(shown)))
            for i, (k, f, u) in enumerate(shown):
                ax = fig.add_subplot(len(shown), 1, i + 1)
                ax.plot(self["t"], self[k] * f, lw=0.8)
                ax.set_ylabel(f"{k} ({u})")
            fig.axes[-1].set_xlabel("t (s)")
            fig.tight_layout()
        return notebook_html(f"Measurement {self.label}: {len(self)} samples", rows, fig)

    # ----------------------------------------------------------------- pandas
    def units(self) -> dict[str, str]:
        """The unit of every column: SI for the columns of the format (``u``: the sidecar's
        ``signals.u_unit`` where given), the sidecar's ``[units]`` or ``""`` for others."""
        extra = self.meta.get("units", {})
        u_unit = self.meta.get("signals", {}).get("u_unit", "A or V")
        return {k: (u_unit if k == "u" else COLUMN_UNITS[k]) if k in COLUMN_UNITS
                else str(extra.get(k, "")) if isinstance(extra, Mapping) else ""
                for k in self.columns}

    def to_dataframe(self) -> Any:
        """The measurement as a :class:`pandas.DataFrame` (pandas is optional: ``pip install
        'fcomp[pandas]'``).

        One column per measurement column (``t`` first, float64, unchanged);
        ``df.attrs["units"]`` gives each column's unit and ``df.attrs["meta"]``
        the sidecar, so :meth:`from_dataframe` gives back an equal measurement.
        """
        import copy

        pd = _pandas()
        df = pd.DataFrame({k: v.copy() for k, v in self.columns.items()})
        df.attrs["units"] = self.units()
        df.attrs["meta"] = copy.deepcopy({k: v for k, v in self.meta.items()
                                          if not k.startswith("_")})
        return df

    @classmethod
    def from_dataframe(cls, df: Any, meta: Mapping[str, Any] | None = None, *,
                       time: str | None = "t", units: Mapping[str, str] | None = None,
                       columns: Mapping[str, str] | None = None) -> Measurement:
        """A measurement from a :class:`pandas.DataFrame`.

        Parameters
        ----------
        df
            The frame: numeric columns, one row per sample.
        meta
            The sidecar content (default: ``df.attrs["meta"]``, as
            :meth:`to_dataframe` leaves it, else none).
        time
            The column holding the time (s); ``None`` takes the index (numbers in
            seconds, or datetimes/timedeltas, counted from the first sample).
        units
            Column -> unit (``{"x": "mm", "p1": "bar", "t": "ms"}``, :data:`UNITS`):
            the values are converted to SI. Default: ``df.attrs["units"]``
            where it holds units of the table, else SI.
        columns
            Measurement column -> frame column, to rename (``{"x": "position"}``).

        A round trip ``Measurement.from_dataframe(m.to_dataframe())`` gives an equal
        measurement (the same columns, values and sidecar).
        """
        pd = _pandas()
        if not isinstance(df, pd.DataFrame):
            raise FcompError(f"from_dataframe: expected a pandas DataFrame, got "
                             f"{type(df).__name__}")
        rename = {v: k for k, v in (columns or {}).items()}
        for src in rename:
            if src not in df.columns:
                raise FcompError(f"from_dataframe: no column {src!r} in the frame (columns: "
                                 f"{', '.join(map(str, df.columns))})")
        given = dict(units) if units is not None else {
            k: v for k, v in (df.attrs.get("units") or {}).items() if v in UNITS}
        cols: dict[str, np.ndarray] = {}
        if time is None:
            idx = df.index
            if isinstance(idx, pd.DatetimeIndex | pd.TimedeltaIndex):
                cols["t"] = np.asarray((idx - idx[0]) / pd.Timedelta(seconds=1), dtype=float)
            else:
                cols["t"] = np.asarray(idx, dtype=float)
        elif rename.get(time, time) not in [rename.get(str(c), str(c)) for c in df.columns]:
            raise FcompError(f"from_dataframe: no time column {time!r} (columns: "
                             f"{', '.join(map(str, df.columns))}); give time=None to take "
                             "the index")
        for c in df.columns:
            name = rename.get(str(c), str(c))
            if name == "t" and time is None:
                continue
            try:
                values = np.asarray(df[c].to_numpy(), dtype=float)
            except (TypeError, ValueError):
                raise FcompError(f"from_dataframe: column {c!r} is not numeric") from None
            cols["t" if time is not None and name == rename.get(time, time) else name] = values
        for k in list(cols):
            if k in given:
                cols[k] = cols[k] * si_factor(k, given[k], "from_dataframe units")
        doc = dict(meta) if meta is not None else dict(df.attrs.get("meta") or {})
        return cls({"t": cols.pop("t"), **cols}, doc)

    # ----------------------------------------------------------------- access
    @property
    def t(self) -> np.ndarray:
        return self.columns["t"]

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.columns[name]
        except KeyError:
            raise FcompError(
                f"{self.label}: column {name!r} is missing (have {', '.join(self.columns)})"
            ) from None

    def __contains__(self, name: object) -> bool:
        return name in self.columns

    def get(self, name: str, default: np.ndarray | None = None) -> np.ndarray | None:
        """Column ``name``, or ``default`` when the measurement does not have it."""
        return self.columns.get(name, default)

    def __len__(self) -> int:
        return self.t.size

    @property
    def label(self) -> str:
        return str(self.meta.get("name") or self.meta.get("_path") or "measurement")

    @property
    def rig(self) -> dict[str, Any]:
        return dict(self.meta.get("rig", {}))

    def rig_value(self, key: str) -> Any:
        """A ``[rig]`` value; a clear error naming the missing sidecar key otherwise."""
        rig = self.meta.get("rig", {})
        if key not in rig:
            raise FcompError(f"{self.label}: sidecar key rig.{key} is missing (add it to the .toml)")
        return rig[key]

    def areas(self) -> tuple[float, float]:
        """Piston areas ``A1``, ``A2`` (m^2) of ``rig.bore`` and ``rig.rod`` (0 if absent;
        :func:`fcomp.piston.piston_areas`)."""
        bore = float(self.rig_value("bore"))
        rod = float(self.meta.get("rig", {}).get("rod", 0.0))
        return piston_areas(bore, rod)

    def gauge_pressure(self, name: str) -> np.ndarray:
        """Column ``name`` (``p1`` or ``p2``) as gauge pressure (Pa).

        ``p_gauge = p - p_atm`` when the sidecar says ``pressure = "absolute"``
        (``p_atm`` from the sidecar, default 101325 Pa), else the column itself.
        """
        p_atm = float(self.meta.get("p_atm", 101325.0))
        shift = p_atm if self.meta.get("pressure", "gauge") == "absolute" else 0.0
        return self[name] - shift

    def gauge_pressures(self) -> tuple[np.ndarray, np.ndarray]:
        """``p1, p2`` as gauge pressures (Pa), converting from absolute if the sidecar says so."""
        return self.gauge_pressure("p1"), self.gauge_pressure("p2")

    def select(self, mask: np.ndarray) -> Measurement:
        """The samples where ``mask`` is true (a contiguous slice keeps time increasing)."""
        return Measurement({k: v[mask] for k, v in self.columns.items()}, dict(self.meta))

    def with_columns(self, **cols: np.ndarray) -> Measurement:
        new = dict(self.columns)
        new.update({k: np.asarray(v, dtype=float) for k, v in cols.items()})
        return Measurement(new, dict(self.meta))

    # ------------------------------------------------------------- validation
    def validate(self) -> None:
        """Check the data-format rules; raise :class:`FcompError` naming the problem."""
        if "t" not in self.columns:
            raise FcompError(f"{self.label}: column 't' (time, s) is required")
        n = self.columns["t"].size
        for k, v in self.columns.items():
            if v.ndim != 1 or v.size != n:
                raise FcompError(f"{self.label}: column {k!r} has {v.size} values, t has {n}")
        check_values(self.columns, self.label)
        if n < 2:
            raise FcompError(f"{self.label}: needs at least two samples")
        check_sidecar(self.meta, self.label)
        rig = self.meta.get("rig", {})
        self._check_units(self.meta.get("pressure", "gauge"), rig)

    def _check_units(self, pressure: str, rig: Mapping[str, Any]) -> None:
        """Coarse SI plausibility checks of the columns (see the module docstring)."""
        for name in ("p1", "p2"):
            if name not in self.columns:
                continue
            col = self.columns[name]
            peak = float(np.max(np.abs(col)))
            if 0.0 < peak < MIN_PRESSURE_SCALE:
                raise FcompError(
                    f"{self.label}: column {name!r} peaks at {peak:g}, which looks like bar or "
                    "MPa; pressures are in Pa (multiply bar by 1e5)"
                )
            if pressure == "absolute" and float(np.min(col)) < 0.0:
                raise FcompError(
                    f"{self.label}: column {name!r} has a negative absolute pressure "
                    f"({float(np.min(col)):g} Pa); is it gauge? set pressure = \"gauge\""
                )
        if "x" in self.columns:
            x = self.columns["x"]
            span = float(np.max(x) - np.min(x))
            limit = 20.0
            if isinstance(rig.get("stroke"), int | float) and rig["stroke"] > 0:
                limit = min(limit, 2.0 * float(rig["stroke"]) + 0.01)
            if span > limit:
                hint = ("the simulated piston left its plausible range; check the input and "
                        "the parameters" if "simulation" in self.meta
                        else "positions are in metres, not millimetres")
                raise FcompError(
                    f"{self.label}: column 'x' spans {span:g} m, more than is plausible "
                    f"({limit:g} m); {hint}"
                )
        signals = self.meta.get("signals", {})
        if not isinstance(signals, Mapping):
            raise FcompError(f"{self.label}: sidecar [signals] must be a table")
        if "u_unit" in signals and signals["u_unit"] not in U_UNITS:
            raise FcompError(
                f"{self.label}: sidecar signals.u_unit must be 'A' or 'V' (SI), got "
                f"{_plain(signals['u_unit'])}; convert the u column"
            )

    # -------------------------------------------------------------------- I/O
    def write(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``path`` (``.csv``) and its sidecar ``.toml`` atomically; return both paths."""
        csv, toml = sidecar_paths(path)
        self.validate()  # columns may have been changed in place since construction
        names = list(self.columns)
        data = np.column_stack([self.columns[k] for k in names])
        lines = [",".join(names)]
        lines += [",".join(map(repr, row)) for row in data.tolist()]
        meta = {k: v for k, v in self.meta.items() if not k.startswith("_")}
        write_files({csv: "\n".join(lines) + "\n", toml: dumps_toml(meta)})
        return csv, toml

    @classmethod
    def read(cls, path: str | Path, *, drop_nan: bool = False) -> Measurement:
        """Read ``NAME.csv`` and, if present, ``NAME.toml``.

        Errors name the file as given and count rows as lines of the file (the
        header is line 1), as an editor shows them. The CSV may start with a
        UTF-8 byte-order mark and its header names may be quoted.
        """
        csv, toml = measurement_paths(path)
        meta: dict[str, Any] = {}
        if toml.is_file():
            meta = read_sidecar(toml)
        elif toml.exists():
            raise FcompError(f"{toml}: the sidecar is not a regular file")
        meta.setdefault("name", csv.stem)
        meta["_path"] = str(csv)
        label = str(csv)
        text = read_text(csv, label, what="CSV numbers")
        names, start = header_names(label, text)
        table = parse_rows(label, data_rows(text, start), ",", names, what="CSV numbers")
        raw, lines = table.data, table.lines
        if drop_nan:
            keep = np.all(np.isfinite(raw), axis=1)
            raw, lines = raw[keep], lines[keep]
        cols = {n: raw[:, i] for i, n in enumerate(names)}
        check_values(cols, label, lines)
        return checked(cols, meta, csv)


def _pandas() -> Any:
    try:
        import pandas
    except ImportError:
        raise FcompError("pandas is not installed; pip install 'fcomp[pandas]' (or pandas) for "
                         "to_dataframe and from_dataframe") from None
    return pandas


def measurement_paths(path: str | Path) -> tuple[Path, Path]:
    """The CSV a user means by ``path`` and its sidecar, checked to exist.

    ``run.csv`` (any existing file) is read as it is; ``run`` with no suffix
    reads ``run.csv`` if there is no file ``run``; a ``.toml`` is the sidecar,
    not the data, and is refused with a hint.
    """
    text = str(path)
    if not text.strip():
        raise FcompError("no measurement file given (an empty argument)")
    p = Path(text)
    if p.suffix.lower() == ".toml":
        raise FcompError(f"{text}: is a sidecar; give the measurement's .csv file")
    if p.is_dir():
        raise FcompError(f"{text}: is a folder, not a measurement file")
    if not p.exists() and p.suffix == "" and p.with_suffix(".csv").is_file():
        p = p.with_suffix(".csv")
    if not p.exists():
        raise FcompError(f"{text}: file not found")
    if not p.is_file():
        raise FcompError(f"{text}: is not a regular file")
    return p, p.with_suffix(".toml")



def check_sidecar(meta: Mapping[str, Any], label: str) -> None:
    """Check a sidecar's entries against the data-format rules (``label`` names the file in
    the message: the measurement, or the sidecar file an importer was given).

    Raises
    ------
    FcompError
        One line naming the key and what is wrong with its value.
    """
    name = meta.get("name")
    if name is not None and not isinstance(name, str):
        raise FcompError(f"{label}: sidecar name = {_plain(name)} must be text (quote it: "
                         f"name = \"{_plain(name)}\")")
    kind = meta.get("kind")
    if kind is not None and kind not in KINDS:
        raise FcompError(f"{label}: sidecar kind = {_plain(kind)} is not one of "
                         f"{', '.join(KINDS)}")
    p_atm = meta.get("p_atm", 101325.0)
    if (not isinstance(p_atm, int | float) or isinstance(p_atm, bool)
            or not P_ATM_RANGE[0] <= p_atm <= P_ATM_RANGE[1]):
        raise FcompError(f"{label}: sidecar p_atm = {_plain(p_atm)} is not an "
                         f"atmospheric pressure in Pa ({P_ATM_RANGE[0]:g} to "
                         f"{P_ATM_RANGE[1]:g}; 1 bar = 1e5 Pa)")
    pr = meta.get("pressure", "gauge")
    if pr not in ("gauge", "absolute"):
        raise FcompError(f"{label}: sidecar 'pressure' must be 'gauge' or 'absolute', "
                         f"got {_plain(pr)}")
    rig = meta.get("rig", {})
    if not isinstance(rig, Mapping):
        raise FcompError(f"{label}: sidecar [rig] must be a table")
    for key in ("bore", "rod", "stroke", "mass"):
        if key in rig:
            val = rig[key]
            if (not isinstance(val, int | float) or isinstance(val, bool) or not val >= 0
                    or not math.isfinite(val)):
                raise FcompError(
                    f"{label}: sidecar rig.{key} must be a non-negative number in SI "
                    f"units, got {_plain(val)}"
                )
    if "mass" in rig and rig["mass"] > MAX_MASS:
        raise FcompError(f"{label}: sidecar rig.mass = {_plain(rig['mass'])} kg is "
                         f"implausible (more than {MAX_MASS:g} kg); the mass is in kg (SI)")
    for key, limit in MAX_LENGTH.items():
        if key in rig and rig[key] > limit:
            raise FcompError(
                f"{label}: sidecar rig.{key} = {_plain(rig[key])} m is implausible; "
                "lengths are in metres (SI), not millimetres"
            )
    if "bore" in rig and "rod" in rig and rig["rod"] >= rig["bore"]:
        raise FcompError(f"{label}: sidecar rig.rod ({_plain(rig['rod'])} m) must be "
                         f"smaller than rig.bore ({_plain(rig['bore'])} m)")
    orient = rig.get("orientation", "horizontal")
    if orient not in ORIENTATIONS:
        raise FcompError(
            f"{label}: sidecar rig.orientation must be one of {', '.join(ORIENTATIONS)}, "
            f"got {_plain(orient)}"
        )


def read_sidecar(toml: Path) -> dict[str, Any]:
    """A sidecar (or any TOML file the user gives) as a dict; one line on any problem."""
    text = read_text(toml, str(toml), what="TOML")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise FcompError(f"{toml}: not valid TOML ({exc})") from None


def sidecar_warnings(meas: Measurement) -> list[tuple[str, str]]:
    """``(key, one line)`` per suspicious sidecar entry: ``[rig]`` keys the format does not
    know (a typo such as ``mas`` leaves the mass unknown), and top-level keys that belong
    elsewhere: a ``[rig]`` key written above the ``[rig]`` header (``mass = 2`` at the
    top is not the moving mass) or a column's name (``experiment`` is a column)."""
    rig = meas.meta.get("rig", {})
    unknown = [k for k in rig if k not in RIG_KEYS] if isinstance(rig, Mapping) else []
    out = [(f"rig.{k}", f"{meas.label}: sidecar key rig.{k} is not one the format knows "
            f"({', '.join(RIG_KEYS)}); it is kept but not used") for k in unknown]
    for k in meas.meta:
        if k in RIG_KEYS:
            out.append((k, f"{meas.label}: sidecar key {k} is at the top level, where the "
                        f"format does not read it: put it under [rig] (rig.{k}); it is kept "
                        "but not used"))
        elif k in COLUMN_UNITS or k == "experiment":
            out.append((k, f"{meas.label}: sidecar key {k} names a column: {k} belongs in the "
                        "CSV, one value per row (data-format.md); it is kept but not used"))
    return out


def check_values(columns: Mapping[str, np.ndarray], label: str,
                 lines: np.ndarray | None = None) -> None:
    """Finite values everywhere, plausible magnitudes in the columns of the format,
    strictly increasing time; ``lines``: the file line of every row (default: the
    row as written, header first)."""
    def row(i: int) -> int:
        return int(lines[i]) if lines is not None else i + 2

    for k, v in columns.items():
        i = first_bad(v, MAX_MAGNITUDE if k in COLUMN_UNITS else math.inf)
        if i is None:
            continue
        if not math.isfinite(v[i]):
            raise FcompError(f"{label}: column {k!r} has a non-finite value ({v[i]}) "
                             f"at row {row(i)}")
        raise FcompError(f"{label}: column {k!r} has {float(v[i]):g} at row {row(i)}, beyond "
                         f"any plausible value in SI units ({COLUMN_UNITS[k]}); check the "
                         "units of the column")
    t = columns.get("t")
    if t is not None and t.size > 1:
        dt = np.diff(t)
        if np.any(dt <= 0):
            i = int(np.argmax(dt <= 0))
            raise FcompError(f"{label}: time is not strictly increasing at row {row(i + 1)} "
                             f"(t = {float(t[i + 1])!r} s)")
        if np.any(dt < MIN_STEP):
            i = int(np.argmax(dt < MIN_STEP))
            raise FcompError(f"{label}: the time step at row {row(i + 1)} is "
                             f"{float(dt[i]):g} s, shorter than {MIN_STEP:g} s: no rig logs "
                             "that fast; check that column 't' is in seconds")


def _plain(value: Any) -> str:
    """A sidecar value for a message: numbers as plain numbers, text quoted."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float | np.number):
        return repr(float(value)) if isinstance(value, float | np.floating) else str(int(value))
    return repr(value)


def checked(columns: Mapping[str, np.ndarray], meta: Mapping[str, Any],
            source: str | Path) -> Measurement:
    """A validated :class:`Measurement` whose validation errors name ``source``.

    For readers and importers: the message becomes ``"SOURCE: problem"`` (the file
    the user gave) rather than the measurement's own name.
    """
    try:
        return Measurement(dict(columns), dict(meta))
    except FcompError as exc:
        msg = str(exc)
        if not msg.startswith(str(source)):
            msg = f"{source}: {msg.split(': ', 1)[-1]}"
        raise FcompError(msg) from None


def sidecar_paths(path: str | Path) -> tuple[Path, Path]:
    p = Path(path)
    csv = p if p.suffix == ".csv" else p.with_suffix(".csv")
    return csv, csv.with_suffix(".toml")


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        f = float(v)
        if math.isinf(f):
            return "inf" if f > 0 else "-inf"
        if math.isnan(f):
            return "nan"
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, Mapping):  # None (no value) has no TOML form: the key is left out
        return "{" + ", ".join(f"{_key(k)} = {_toml_value(x)}" for k, x in v.items()
                               if x is not None) + "}"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def _key(k: str) -> str:
    return k if k.replace("_", "").replace("-", "").isalnum() else _toml_value(k)


def dumps_toml(doc: Mapping[str, Any], _prefix: str = "") -> str:
    """A minimal TOML writer for sidecars (scalars, arrays, nested tables)."""
    lines: list[str] = []
    tables: list[tuple[str, Mapping[str, Any]]] = []
    for k, v in doc.items():
        if v is None:
            continue
        if isinstance(v, Mapping):
            tables.append((k, v))
        else:
            lines.append(f"{_key(k)} = {_toml_value(v)}")
    out = "\n".join(lines) + ("\n" if lines else "")
    for k, v in tables:
        name = f"{_prefix}{_key(k)}"
        out += f"\n[{name}]\n" + dumps_toml(v, name + ".")
    return out


def from_arrays(meta: Mapping[str, Any] | None = None, **columns: Iterable[float]) -> Measurement:
    """A :class:`Measurement` from keyword arrays (``t`` required)."""
    return Measurement({k: np.asarray(list(v) if not isinstance(v, np.ndarray) else v)
                        for k, v in columns.items()}, dict(meta or {}))
