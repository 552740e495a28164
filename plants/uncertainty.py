"""What an engineer is unsure of in a plant file, and the controller's computation delay.

Two optional parts of a plant file (docs/plants.md, "Margins of the loop as it runs")
feed the loop analysis of :mod:`controllers.loop_analysis`:

``[uncertainty]``
    relative ranges of the parameters the margins must hold over, each a number ``r``
    (``-r .. +r``, ``0 <= r < 1``) or a pair ``[low, high]`` (``-1 < low <= 0 <= high``):

    ============== ======================================== ==================== =========
    key            parameter scaled                         hydraulic            pneumatic
    ============== ======================================== ==================== =========
    ``valve_gain`` flow gain: ``w`` (``cd*w``) / ``A_valve`` +-10 %                +-10 %
    ``beta``       bulk modulus ``beta`` (hydraulic)        +-20 %                --
    ``kappa``      polytropic exponent (pneumatic; the gas  --                   +-10 %
                   stiffness ``kappa*p*A^2/V``), within 1-2
    ``mass``       moving mass                              +-10 %                +-10 %
    ``ps``         supply pressure above return (``ps -      +-5 %                 +-5 %
                   pt``, pneumatic ``ps - p_atm``)
    ============== ======================================== ==================== =========

    The defaults are the tolerances of an axis characterised as the plant file
    describes it: a servo valve's rated flow to +-10 %, the effective bulk modulus
    (oil, hoses, entrained air) or the polytropic exponent to +-20 % / +-10 %, the
    moving mass to +-10 %, a regulated supply to +-5 %. Wider ranges cost
    bandwidth: the tuning must then meet the requirement on a larger box.

    and ``presliding``, the range of the seal's pre-sliding stiffness ``sigma0`` relative
    to the controller's friction model (default ``[-0.5, 1.0]``: half to twice; the
    piston at rest is held by that spring, :mod:`controllers.loop_analysis.grid`), and
    ``positions``, the fractions of the stroke the margins are checked at (default
    :data:`POSITIONS`: 5 % and 10 % from each end, the quarters: the last 5 % of a stroke
    is, on most axes, the end cushion's, with its own damping; give ``[0.02, ...]`` to
    check closer). A key left out takes the default; ``0`` removes that parameter from the
    grid.
``[control] delay``
    the computation delay in whole control samples (default 1: the command computed
    from the measurement at ``t[k]`` acts from ``t[k+1]``; 0 for a controller whose
    output leaves within a negligible part of the period), 0 to :data:`MAX_DELAY`.

The defaults are stated in the template (``fcomp plant template``), in docs/plants.md
and in the output of ``fcomp plant check``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

#: The uncertain parameters by plant kind: key -> (plant parameter, meaning, default range).
PARAMETERS: dict[str, dict[str, tuple[str, str, tuple[float, float]]]] = {
    "hydraulic": {
        "valve_gain": ("w", "valve flow gain cd*w", (-0.1, 0.1)),
        "beta": ("beta", "bulk modulus", (-0.2, 0.2)),
        "mass": ("mass", "moving mass", (-0.1, 0.1)),
        "ps": ("ps", "supply pressure above return", (-0.05, 0.05)),
    },
    "pneumatic": {
        "valve_gain": ("A_valve", "valve edge area (flow gain)", (-0.1, 0.1)),
        "kappa": ("k_poly", "polytropic exponent", (-0.1, 0.1)),
        "mass": ("mass", "moving mass", (-0.1, 0.1)),
        "ps": ("ps", "supply pressure above exhaust", (-0.05, 0.05)),
    },
}
#: Default range of the pre-sliding stiffness (relative to the controller's friction model).
PRESLIDING = (-0.5, 1.0)
#: Default positions of the margin grid, fractions of the stroke.
POSITIONS = (0.05, 0.1, 0.25, 0.5, 0.75, 0.9, 0.95)
#: Default computation delay (control samples).
DELAY = 1
#: Largest computation delay accepted (samples).
MAX_DELAY = 10


@dataclass(frozen=True)
class Uncertainty:
    """The ``[uncertainty]`` table read (module docstring).

    Attributes
    ----------
    kind : str
        The plant kind.
    table : tuple of (str, float, float)
        Relative range ``(key, low, high)`` per key of :data:`PARAMETERS` (defaults filled
        in; a tuple, so that the settings holding it hash).
    positions : tuple of float
        Fractions of the stroke of the grid.
    presliding : tuple of float
        Relative range of the pre-sliding stiffness.
    given : tuple of str
        The keys the file gave.
    """

    kind: str
    table: tuple[tuple[str, float, float], ...] = ()
    positions: tuple[float, ...] = POSITIONS
    presliding: tuple[float, float] = PRESLIDING
    given: tuple[str, ...] = ()

    @classmethod
    def default(cls, kind: str) -> Uncertainty:
        """The default ranges of a plant kind."""
        return cls(kind, tuple((k, *d) for k, (_p, _m, d) in PARAMETERS[kind].items()))

    @property
    def ranges(self) -> dict[str, tuple[float, float]]:
        """``key -> (low, high)``."""
        return {k: (lo, hi) for k, lo, hi in self.table}

    def levels(self, key: str) -> tuple[float, ...]:
        """The relative changes of ``key`` on the grid: low, 0 and high (0 alone when the
        range is empty)."""
        low, high = self.ranges[key]
        return tuple(sorted({low, 0.0, high}))

    def scaled(self, values: Mapping[str, float], changes: Mapping[str, float]
               ) -> dict[str, float]:
        """Plant parameter values with the relative ``changes`` (key -> change) applied:
        ``p*(1 + change)``; the supply pressure's part above the return pressure; the
        polytropic exponent kept within 1 and 2."""
        out = dict(values)
        for key, change in changes.items():
            name = PARAMETERS[self.kind][key][0]
            if key == "ps":
                low = out.get("pt", out["p_atm"])
                out[name] = low + (out[name] - low) * (1.0 + change)
            elif key == "kappa":
                out[name] = min(max(out[name] * (1.0 + change), 1.0), 2.0)
            else:
                out[name] = out[name] * (1.0 + change)
        return out

    def describe(self) -> str:
        """One line: each range in percent, the positions, and which are defaults."""
        parts = []
        for key, (low, high) in self.ranges.items():
            rng = (f"+-{100 * high:.3g} %" if math.isclose(-low, high)
                   else f"{100 * low:+.3g}..{100 * high:+.3g} %")
            parts.append(f"{key} {rng}{'' if key in self.given else ' (default)'}")
        low, high = self.presliding
        parts.append(f"pre-sliding stiffness x{1 + low:.3g}..x{1 + high:.3g}"
                     f"{'' if 'presliding' in self.given else ' (default)'}")
        pos = ", ".join(f"{100 * p:.3g}" for p in self.positions)
        where = "" if "positions" in self.given else " (default)"
        return f"{'; '.join(parts)}; positions {pos} % of the stroke{where}"

    def as_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {"ranges": {k: [lo, hi] for k, lo, hi in self.table},
                "presliding": list(self.presliding), "positions": list(self.positions),
                "given": list(self.given)}


def _range(value: Any) -> tuple[float, float] | str:
    """A range from a number ``r`` or a pair ``[low, high]``, or why not."""
    def num(v: Any) -> bool:
        return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)

    if num(value):
        r = float(value)
        if not 0.0 <= r < 1.0:
            return f"= {value!r} must be a relative range 0 <= r < 1 (-r .. +r)"
        return (-r, r)
    if isinstance(value, list | tuple) and len(value) == 2 and all(num(v) for v in value):
        low, high = float(value[0]), float(value[1])
        if not -1.0 < low <= 0.0 <= high:
            return f"= {list(value)!r} must be [low, high] with -1 < low <= 0 <= high"
        return (low, high)
    return f"= {value!r} must be a number r (-r .. +r) or a pair [low, high]"


def parse_uncertainty(table: Any, kind: str, label: str) -> tuple[Uncertainty, list[str]]:
    """The ``[uncertainty]`` table of a plant file of ``kind`` (``None``: the defaults), and
    one problem line per bad key."""
    base = Uncertainty.default(kind)
    if table is None:
        return base, []
    if not isinstance(table, Mapping):
        return base, [f"{label}: uncertainty must be a table [uncertainty]"]
    known = PARAMETERS[kind]
    problems: list[str] = []
    ranges = dict(base.ranges)
    positions = POSITIONS
    presliding = PRESLIDING
    for key, value in table.items():
        if key == "presliding":
            r = _range(value)
            if isinstance(r, str):
                problems.append(f"{label}: [uncertainty] presliding {r} (the seal's "
                                "pre-sliding stiffness)")
            else:
                presliding = r
        elif key == "positions":
            ok = (isinstance(value, list) and len(value) > 0
                  and all(isinstance(v, int | float) and not isinstance(v, bool)
                          and math.isfinite(v) and 0.0 < v < 1.0 for v in value))
            if ok:
                positions = tuple(sorted({float(v) for v in value}))
            else:
                problems.append(f"{label}: [uncertainty] positions = {value!r} must be a "
                                "non-empty list of fractions of the stroke, each 0 < f < 1")
        elif key not in known:
            problems.append(f"{label}: unknown key [uncertainty] {key} (known for a {kind} "
                            f"plant: {', '.join([*known, 'presliding', 'positions'])})")
        else:
            r = _range(value)
            if isinstance(r, str):
                problems.append(f"{label}: [uncertainty] {key} {r} ({known[key][1]})")
            else:
                ranges[key] = r
    return Uncertainty(kind, tuple((k, *v) for k, v in ranges.items()), positions, presliding,
                       tuple(table)), problems


def parse_delay(value: Any, label: str) -> tuple[int, list[str]]:
    """``[control] delay`` (``None``: the default :data:`DELAY`) and its problem, if any."""
    if value is None:
        return DELAY, []
    if (isinstance(value, bool) or not isinstance(value, int | float)
            or not math.isfinite(value) or value != int(value) or not 0 <= value <= MAX_DELAY):
        return DELAY, [f"{label}: [control] delay = {value!r} must be a whole number of "
                       f"control samples, 0 to {MAX_DELAY} (the computation delay)"]
    return int(value), []


def split_loop_keys(doc: Mapping[str, Any], kind: str, label: str
                    ) -> tuple[dict[str, Any], Uncertainty, int, list[str]]:
    """A plant file's document without the keys of this module (``[uncertainty]`` and
    ``[control] delay``), those keys read, and their problems."""
    rest = {k: v for k, v in doc.items() if k != "uncertainty"}
    unc, problems = parse_uncertainty(doc.get("uncertainty"), kind, label)
    control = rest.get("control")
    delay_value = None
    if isinstance(control, Mapping) and "delay" in control:
        delay_value = control["delay"]
        rest["control"] = {k: v for k, v in control.items() if k != "delay"}
    delay, more = parse_delay(delay_value, label)
    return rest, unc, delay, problems + more


__all__ = ["DELAY", "MAX_DELAY", "PARAMETERS", "POSITIONS", "PRESLIDING", "Uncertainty", "parse_delay",
           "parse_uncertainty", "split_loop_keys"]
