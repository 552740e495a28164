"""Your plant as a file: a TOML description of a hydraulic or pneumatic servo.

A plant file (``docs/plants.md``, "Plant files") gives the geometry in
``[rig]`` (the keys of a record's sidecar: ``bore``, ``rod``, ``stroke``,
``mass``, ``orientation``), the supply, the valve with its command and rate
limits, the line volumes, the fluid (bulk modulus) or the gas, the sensors and
the control rate. :func:`read_plant_file` reads it into a :class:`PlantFile`:
the plant's parameters (:attr:`PlantFile.values`, the names of
:class:`~plants.hydraulic.HydraulicParams` / :class:`~plants.pneumatic.PneumaticParams`)
and the controller's settings (:attr:`PlantFile.sensors`, :attr:`PlantFile.control`:
the fields of :class:`controllers.plant_model.Sensors` and
:class:`controllers.plant_model.PlantSettings`). :meth:`PlantFile.make_plant`
builds the plant with a friction model.

The two built-in plants are such files, shipped in ``plants/data/``
(:func:`builtin_plant_file`; ``fcomp plant template KIND`` prints them).

Every bad value is one line naming the file, the table and the key (a rod
not thinner than the bore, a volume or mass not positive, a control rate
below the valve bandwidth, an unknown key, ...); all of them are collected
and raised together as one :class:`~fcomp.errors.FileFormatError`
(:class:`PlantFileError`, its :attr:`~PlantFileError.problems` one per line).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fcomp.errors import FileFormatError
from fcomp.measurement import ORIENTATIONS
from fcomp.parameters import ParamSpec
from fcomp.paramsets import ParameterSet
from plants.base import OdePlant
from plants.hydraulic import HydraulicPlant
from plants.pneumatic import PneumaticPlant

if TYPE_CHECKING:
    from fcomp.models.base import FrictionModel

#: Plant kind -> its class.
KINDS: dict[str, type[OdePlant]] = {"hydraulic": HydraulicPlant, "pneumatic": PneumaticPlant}

#: ISO 6358 reference state of the sonic conductance: density (kg/m^3) and temperature (K).
RHO0, T0 = 1.185, 293.15


@dataclass(frozen=True)
class Key:
    """One key of a plant file.

    Attributes
    ----------
    target : str
        Where the value goes: a plant parameter name (``"plant:bore"``), a sensor
        (``"sensors:x_noise"``), a controller setting (``"control:u_max"``), or a
        value converted by the reader (``"rated:..."``).
    unit : str
        SI unit, for messages.
    doc : str
        Meaning, for messages.
    required : bool
        Whether the file must give it (else the plant's default).
    """

    target: str
    unit: str
    doc: str
    required: bool = True


def _k(target: str, unit: str, doc: str, required: bool = True) -> Key:
    return Key(target, unit, doc, required)


_RIG = {
    "bore": _k("plant:bore", "m", "piston diameter"),
    "rod": _k("plant:rod", "m", "rod diameter"),
    "stroke": _k("plant:stroke", "m", "stroke"),
    "mass": _k("plant:mass", "kg", "moving mass"),
    "orientation": _k("rig:orientation", "-", "horizontal, vertical-up or vertical-down"),
}
_MECHANICS = {
    "F_load": _k("plant:F_load", "N", "constant load opposing extension", False),
    "k_stop": _k("plant:k_stop", "N/m", "end-stop stiffness", False),
    "zeta_stop": _k("plant:zeta_stop", "-", "end-stop damping ratio", False),
}
_SENSORS = {
    "x_resolution": _k("sensors:x_quantum", "m", "position quantum"),
    "x_noise": _k("sensors:x_noise", "m", "position noise"),
    "p_resolution": _k("sensors:p_quantum", "Pa", "pressure quantum"),
    "p_noise": _k("sensors:p_noise", "Pa", "pressure noise"),
}
_CONTROL = {
    "rate": _k("control:control_rate", "Hz", "controller sample rate"),
    "pid_bandwidth": _k("control:pid_bandwidth", "rad/s", "PID bandwidth", False),
    "force_bandwidth": _k("control:force_bandwidth", "rad/s", "force-loop bandwidth", False),
    "observer_gain": _k("control:observer_gain", "1/s", "LuGre observer gain", False),
    # the fail-safe layer (controllers.safety; docs/plants.md, "Plant files")
    "safe_output": _k("control:safe_output", "command unit", 'command after repeated input '
                      'faults: "centre", "hold" or a command within +-u_max', False),
    "fault_latch": _k("control:fault_latch", "samples", "faulty samples in a row that latch "
                      "the safe output", False),
    "fault_recover": _k("control:fault_recover", "samples", "good samples in a row that end "
                        "the latch", False),
    "position_margin": _k("control:position_margin", "m", "plausible position reading beyond "
                          "the stroke", False),
    "pressure_max": _k("control:pressure_max", "Pa", "highest plausible pressure reading "
                       "(absolute)", False),
}
#: Named safe outputs of ``[control] safe_output`` (besides a number).
SAFE_OUTPUTS = ("centre", "hold")
_LINES = {
    "V10": _k("plant:V10", "m^3", "dead volume, cap side"),
    "V20": _k("plant:V20", "m^3", "dead volume, rod side"),
}

#: Tables and keys of each kind.
SCHEMA: dict[str, dict[str, dict[str, Key]]] = {
    "hydraulic": {
        "rig": _RIG, "mechanics": _MECHANICS,
        "supply": {"ps": _k("plant:ps", "Pa", "supply pressure (absolute)"),
                   "pt": _k("plant:pt", "Pa", "return pressure (absolute)"),
                   "p_atm": _k("plant:p_atm", "Pa", "ambient pressure", False)},
        "valve": {"kv": _k("plant:kv", "m/A", "spool displacement per command"),
                  "cd": _k("plant:cd", "-", "discharge coefficient", False),
                  "w": _k("plant:w", "m", "area gradient", False),
                  "rated_flow": _k("rated:flow", "m^3/s", "rated flow at full command", False),
                  "rated_dp": _k("rated:dp", "Pa", "valve drop of the rating", False),
                  "underlap": _k("plant:underlap", "m", "underlap", False),
                  "omega_v": _k("plant:omega_v", "rad/s", "spool natural frequency"),
                  "zeta_v": _k("plant:zeta_v", "-", "spool damping ratio"),
                  "u_max": _k("control:u_max", "A", "command limit"),
                  "du_max": _k("control:du_max", "A/s", "command rate limit")},
        "lines": _LINES,
        "fluid": {"beta": _k("plant:beta", "Pa", "bulk modulus"),
                  "rho": _k("plant:rho", "kg/m^3", "oil density"),
                  "p_min": _k("plant:p_min", "Pa", "cavitation floor", False),
                  "dp_lam": _k("plant:dp_lam", "Pa", "laminar transition", False)},
        "sensors": _SENSORS, "control": _CONTROL,
    },
    "pneumatic": {
        "rig": _RIG, "mechanics": _MECHANICS,
        "supply": {"ps": _k("plant:ps", "Pa", "supply pressure (absolute)"),
                   "p_atm": _k("plant:p_atm", "Pa", "ambient pressure", False)},
        "valve": {"A_valve": _k("plant:A_valve", "m^2", "edge area at full opening", False),
                  "sonic_conductance": _k("rated:C", "m^3/(s Pa)",
                                          "ISO 6358 sonic conductance at full opening", False),
                  "lap": _k("plant:lap", "-", "underlap", False),
                  "tau_v": _k("plant:tau_v", "s", "spool time constant"),
                  "u_open": _k("plant:u_max", "-", "command of full opening", False),
                  "u_max": _k("control:u_max", "-", "command limit"),
                  "du_max": _k("control:du_max", "1/s", "command rate limit")},
        "lines": _LINES,
        "gas": {"kappa": _k("plant:k_poly", "-", "polytropic exponent"),
                "R": _k("plant:R_air", "J/(kg K)", "gas constant"),
                "T": _k("plant:T_air", "K", "supply temperature"),
                "gamma": _k("plant:gamma_air", "-", "ratio of specific heats", False),
                "b_crit": _k("plant:b_crit", "-", "critical pressure ratio", False),
                "r_lam": _k("plant:r_lam", "-", "laminar pressure ratio", False)},
        "sensors": _SENSORS, "control": _CONTROL,
    },
}
#: Top-level keys (besides the tables).
TOP = ("kind", "name")


class PlantFileError(FileFormatError):
    """A plant file with bad values: :attr:`problems` holds one line per bad value; the
    message is all of them, ``"; "``-separated."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("; ".join(problems))
        self.problems = list(problems)


@dataclass(frozen=True)
class PlantFile:
    """A plant file read (:func:`read_plant_file`).

    Attributes
    ----------
    kind : str
        ``"hydraulic"`` or ``"pneumatic"``.
    name : str
        The plant's name (the file's ``name``, else its stem).
    label : str
        The file as given, for messages.
    values : dict of str to float
        Every plant parameter by flat name (SI), defaults included.
    sensors : dict of str to float
        ``x_noise``, ``x_quantum`` (m), ``p_noise``, ``p_quantum`` (Pa).
    control : dict of str to float
        ``control_rate`` (Hz), ``u_max``, ``du_max``, the tuning given
        (``pid_bandwidth``, ``force_bandwidth``, ``observer_gain``) and the fail-safe
        layer's settings given (``safe_output``, a name or a number; ``fault_latch``,
        ``fault_recover``, whole numbers; ``position_margin``, ``pressure_max``).
    rig : dict
        The ``[rig]`` table as a sidecar writes it.
    """

    kind: str
    name: str
    label: str
    values: dict[str, float] = field(default_factory=dict)
    sensors: dict[str, float] = field(default_factory=dict)
    control: dict[str, float] = field(default_factory=dict)
    rig: dict[str, Any] = field(default_factory=dict)

    @property
    def plant_class(self) -> type[OdePlant]:
        """The plant class of :attr:`kind`."""
        return KINDS[self.kind]

    @property
    def friction_set(self) -> str | None:
        """The parameter set whose friction values a friction model named (not a model
        file) takes on this plant: the built-in plant's of the same kind."""
        return self.plant_class.default_params

    def parameter_set(self) -> ParameterSet:
        """The file as a :class:`~fcomp.paramsets.ParameterSet` a plant takes (its
        parameters given directly, no friction sections)."""
        return ParameterSet(self.name, self.label, {}, rig=dict(self.rig),
                            plant=dict(self.values))

    def make_plant(self, friction: FrictionModel) -> OdePlant:
        """The plant with the friction model ``friction``."""
        return self.plant_class(friction, self.parameter_set())

    @property
    def valve_bandwidth(self) -> float:
        """The valve's bandwidth (Hz): ``omega_v/(2 pi)``, or ``1/(2 pi tau_v)``."""
        v = self.values
        return (v["omega_v"] if self.kind == "hydraulic" else 1.0 / v["tau_v"]) / (2 * math.pi)


def builtin_plant_file(kind: str) -> PlantFile:
    """The built-in plant ``kind`` (``hydraulic``, ``pneumatic``) as its shipped file."""
    return read_plant_file(builtin_path(kind))


def builtin_path(kind: str) -> Path:
    """The shipped plant file of ``kind`` (``plants/data/KIND.toml``)."""
    from fcomp.errors import UnknownNameError

    if kind not in KINDS:
        raise UnknownNameError(f"unknown plant kind {kind!r}; known: {', '.join(KINDS)}")
    return Path(str(resources.files("plants").joinpath("data", f"{kind}.toml")))


def template(kind: str) -> str:
    """The commented plant file of ``kind`` to start from (the built-in plant's)."""
    return builtin_path(kind).read_text(encoding="utf-8")


def read_plant_file(path: str | Path) -> PlantFile:
    """Read and check a plant file.

    Parameters
    ----------
    path : str or Path
        The TOML file.

    Returns
    -------
    PlantFile

    Raises
    ------
    FileFormatError
        The file cannot be read or is not TOML (one line).
    PlantFileError
        Bad values: one line each, all of them.
    """
    from fcomp.textdata import check_path, read_text

    label = str(path)
    p = check_path(path, "plant file")
    try:
        doc = tomllib.loads(read_text(p, label, what="TOML"))
    except tomllib.TOMLDecodeError as exc:
        raise FileFormatError(f"{label}: not valid TOML ({exc})") from None
    return parse_plant(doc, label, default_name=p.stem)


def parse_plant(doc: Mapping[str, Any], label: str, default_name: str = "plant") -> PlantFile:
    """A plant file's document (parsed TOML) as a :class:`PlantFile`; ``label`` names it
    in messages. Raises :class:`PlantFileError` listing every bad value."""
    kind = doc.get("kind")
    if kind not in SCHEMA:
        raise PlantFileError([f"{label}: kind must be one of {', '.join(SCHEMA)} "
                              f"(got {kind!r})"])
    schema = SCHEMA[kind]
    problems: list[str] = []
    given: dict[str, tuple[str, str, Key, Any]] = {}  # target -> (table, key, Key, value)
    for k, v in doc.items():
        if k in TOP:
            continue
        if k not in schema:
            problems.append(f"{label}: unknown key {k!r} (known: "
                            f"{', '.join([*TOP, *(f'[{t}]' for t in schema)])})")
        elif not isinstance(v, Mapping):
            problems.append(f"{label}: {k} must be a table [{k}]")
        else:
            for key, value in v.items():
                spec = schema[k].get(key)
                if spec is None:
                    problems.append(f"{label}: unknown key [{k}] {key} (known in [{k}]: "
                                    f"{', '.join(schema[k])})")
                else:
                    given[spec.target] = (k, key, spec, value)
    for table, keys in schema.items():
        for key, spec in keys.items():
            if spec.required and spec.target not in given:
                problems.append(f"{label}: [{table}] {key} is missing ({spec.doc}, {spec.unit})")
    numbers: dict[str, float] = {}
    for target, (table, key, spec, value) in given.items():
        if target == "rig:orientation":
            if value not in ORIENTATIONS:
                problems.append(f"{label}: [rig] orientation must be one of "
                                f"{', '.join(ORIENTATIONS)}, got {value!r}")
            continue
        if target == "control:safe_output" and isinstance(value, str):
            continue  # a name: _fail_safe_keys
        if isinstance(value, bool) or not isinstance(value, int | float) \
                or not math.isfinite(value):
            problems.append(f"{label}: [{table}] {key} = {value!r} is not a finite number "
                            f"({spec.unit})")
        else:
            numbers[target] = float(value)
    cls = KINDS[kind]
    values = _plant_values(cls, numbers, given, label, problems)
    sensors = {t.split(":", 1)[1]: v for t, v in numbers.items() if t.startswith("sensors:")}
    control = {t.split(":", 1)[1]: v for t, v in numbers.items() if t.startswith("control:")}
    for target, v in numbers.items():
        if target.startswith(("sensors:", "control:")) and target != "control:safe_output":
            table, key, spec, _ = given[target]
            low_ok = v >= 0 if target.startswith("sensors:") else v > 0
            if not low_ok:
                bound = ">= 0" if target.startswith("sensors:") else "> 0"
                problems.append(f"{label}: [{table}] {key} = {v:g} {spec.unit} must be {bound} "
                                f"({spec.doc})")
    _fail_safe_keys(given, control, label, problems)
    orientation = given["rig:orientation"][3] if "rig:orientation" in given else "horizontal"
    values["orient"] = ORIENTATIONS.get(orientation, 0.0)
    pf = PlantFile(kind=kind, name=str(doc.get("name", default_name)), label=label,
                   values=values, sensors=sensors, control=control,
                   rig={"bore": values["bore"], "rod": values["rod"],
                        "stroke": values["stroke"], "mass": values["mass"],
                        "orientation": orientation})
    problems += _cross_checks(pf, given)
    if problems:
        raise PlantFileError(problems)
    return pf


def _fail_safe_keys(given: dict[str, tuple[str, str, Key, Any]], control: dict[str, Any],
                    label: str, problems: list[str]) -> None:
    """The ``[control]`` keys of the fail-safe layer (:mod:`controllers.safety`):
    ``safe_output`` one of :data:`SAFE_OUTPUTS` or a command within ``+-u_max`` (the
    number itself is checked with the others), the counts whole numbers of samples."""
    if "control:safe_output" in given:
        value = given["control:safe_output"][3]
        if isinstance(value, str):
            if value not in SAFE_OUTPUTS:
                problems.append(f"{label}: [control] safe_output = {value!r} must be one of "
                                f"{', '.join(map(repr, SAFE_OUTPUTS))} or a command (a number)")
            else:
                control["safe_output"] = value
        elif "safe_output" in control:
            u_max = control.get("u_max")
            if u_max is not None and abs(control["safe_output"]) > u_max:
                problems.append(f"{label}: [control] safe_output = {control['safe_output']:g} "
                                f"is outside the valve's range +-{u_max:g} ([valve] u_max)")
    for key in ("fault_latch", "fault_recover"):
        v = control.get(key)
        if v is not None and v > 0:
            if not float(v).is_integer() or v > 1e9:
                problems.append(f"{label}: [control] {key} = {v:g} must be a whole number of "
                                "samples (1 to 1e9)")
            else:
                control[key] = int(v)


def _plant_values(cls: type[OdePlant], numbers: dict[str, float],
                  given: dict[str, tuple[str, str, Key, Any]], label: str,
                  problems: list[str]) -> dict[str, float]:
    """The plant's parameters: its defaults, the file's values, the rated valve converted;
    each out of its bounds is a problem."""
    specs = {s.name: s for s in cls.Params.SPECS}
    values = {s.name: float(s.default) for s in cls.Params.SPECS}
    values.update({t.split(":", 1)[1]: v for t, v in numbers.items() if t.startswith("plant:")})
    rated = {t.split(":", 1)[1]: (given[t][0], given[t][1]) for t in numbers
             if t.startswith("rated:")}
    if rated:
        _rated_valve(cls, numbers, values, given, rated, label, problems)
    elif cls is HydraulicPlant and not {"plant:cd", "plant:w"} <= set(numbers):
        problems.append(f"{label}: [valve] give the flow gain (cd and w) or the rating "
                        "(rated_flow and rated_dp)")
    elif cls is PneumaticPlant and "plant:A_valve" not in numbers:
        problems.append(f"{label}: [valve] give A_valve (edge area at full opening) or "
                        "sonic_conductance")
    where = {t.split(":", 1)[1]: (g[0], g[1]) for t, g in given.items() if t.startswith("plant:")}
    for name, value in values.items():
        problem = _out_of_bounds(specs[name], value)
        if problem:
            table, key = where.get(name, ("defaults", name))
            problems.append(f"{label}: [{table}] {key} = {value:g} {specs[name].unit} "
                            f"{problem}")
    return values


def _out_of_bounds(spec: ParamSpec, value: float) -> str | None:
    """Why ``value`` is outside the bounds of ``spec`` (``None`` if within)."""
    low_bad = value <= spec.lower if spec.lower_open else value < spec.lower
    if low_bad or value > spec.upper:
        lo = "(" if spec.lower_open else "["
        return f"is outside {lo}{spec.lower:g}, {spec.upper:g}] ({spec.doc})"
    return None


def _rated_valve(cls: type[OdePlant], numbers: dict[str, float], values: dict[str, float],
                 given: dict[str, tuple[str, str, Key, Any]],
                 rated: dict[str, tuple[str, str]], label: str, problems: list[str]) -> None:
    """The valve's flow gain from its rating (docs/plants.md, "Plant files").

    Hydraulic: a rated flow ``Q_n`` at full command ``u_max`` and total valve drop
    ``dp_n`` (two edges, ``dp_n/2`` each) gives ``cd*w = Q_n/(kv*u_max*sqrt(dp_n/rho))``
    (``w`` for the file's ``cd`` or its default). Pneumatic: the sonic conductance
    ``C`` gives the edge area ``A = C*rho0*sqrt(R*T0)/psi_c`` (ISO 6358, ``rho0`` =
    1.185 kg/m^3, ``T0`` = 293.15 K).
    """
    if cls is HydraulicPlant:
        if "plant:w" in numbers:
            problems.append(f"{label}: [valve] give either the flow gain (cd and w) or the "
                            "rating (rated_flow and rated_dp), not both")
            return
        if set(rated) != {"flow", "dp"}:
            problems.append(f"{label}: [valve] the rating needs both rated_flow and rated_dp")
            return
        u_max = numbers.get("control:u_max", 0.0)
        q, dp = numbers["rated:flow"], numbers["rated:dp"]
        if not (q > 0 and dp > 0 and u_max > 0 and values["kv"] > 0 and values["rho"] > 0):
            problems.append(f"{label}: [valve] rated_flow, rated_dp, u_max, kv and rho must be "
                            "positive to convert the rating")
            return
        values["w"] = q / (values["kv"] * u_max * math.sqrt(dp / values["rho"])) / values["cd"]
    else:
        if "plant:A_valve" in numbers:
            problems.append(f"{label}: [valve] give either A_valve or sonic_conductance, "
                            "not both")
            return
        gam = values["gamma_air"]
        psi_c = math.sqrt(gam * (2.0 / (gam + 1.0)) ** ((gam + 1.0) / (gam - 1.0)))
        values["A_valve"] = numbers["rated:C"] * RHO0 * math.sqrt(values["R_air"] * T0) / psi_c


def _cross_checks(pf: PlantFile, given: dict[str, tuple[str, str, Key, Any]]) -> list[str]:
    """Values that are each fine but impossible together, one line each."""
    v, label = pf.values, pf.label
    out = []
    if v["rod"] >= v["bore"]:
        out.append(f"{label}: [rig] rod = {v['rod']:g} m must be smaller than bore = "
                   f"{v['bore']:g} m")
    if pf.kind == "hydraulic" and not v["p_min"] <= v["pt"] < v["ps"]:
        out.append(f"{label}: [supply] pressures must satisfy p_min <= pt < ps (absolute; got "
                   f"p_min {v['p_min']:g}, pt {v['pt']:g}, ps {v['ps']:g} Pa)")
    if pf.kind == "pneumatic":
        if not v["ps"] > v["p_atm"]:
            out.append(f"{label}: [supply] ps = {v['ps']:g} Pa (absolute) must exceed p_atm "
                       f"= {v['p_atm']:g} Pa")
        if not v["b_crit"] < v["r_lam"]:
            out.append(f"{label}: [gas] r_lam = {v['r_lam']:g} must exceed b_crit = "
                       f"{v['b_crit']:g}")
    rate = pf.control.get("control_rate")
    if rate is not None and rate < pf.valve_bandwidth:
        key = "omega_v/(2 pi)" if pf.kind == "hydraulic" else "1/(2 pi tau_v)"
        out.append(f"{label}: [control] rate = {rate:g} Hz is below the valve bandwidth "
                   f"{pf.valve_bandwidth:.3g} Hz ({key}): the controller cannot act on the "
                   "valve's time scale")
    return out


__all__ = ["KINDS", "SAFE_OUTPUTS", "PlantFile", "PlantFileError", "builtin_path", "builtin_plant_file",
           "parse_plant", "read_plant_file", "template"]
