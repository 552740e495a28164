"""The rig file of ``fcomp design``: what the rig is and what it can do (SI units).

A small TOML file with two tables::

    [rig]       # what the programme files' sidecars carry (docs/data-format.md)
    bore = 0.032            # m
    rod = 0.012             # m (0 or absent: single-acting, p2 vented)
    mass = 1.2              # kg, the moving mass
    orientation = "horizontal"

    [limits]
    stroke = 0.2            # m, the position stays inside [0, stroke]
    speed_max = 0.2         # m/s
    accel_max = 4.0         # m/s^2
    pressure_min = 1.5e5    # Pa (gauge), the lowest level the rig holds
    pressure_max = 5.0e5    # Pa (gauge), the highest (equal to pressure_min: one level)
    pressure_levels = [..]  # or the levels it holds, instead of min/max
    duration_max = 30.0     # s, the longest experiment
    rate = 500.0            # Hz, the logger's sample rate
    noise = 0.4             # N (optional): the force noise; default the diagnosis's floor

:func:`read_rig` refuses anything else with one line (:class:`fcomp.errors.FcompError`).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fcomp.errors import FcompError

#: Orientations a sidecar may name (docs/data-format.md).
ORIENTATIONS = ("horizontal", "vertical-up", "vertical-down")
#: The shortest speed ramp of a programme (s): a rig's servo follows nothing faster.
RAMP_MIN = 0.2
#: Samples the logger must take in the shortest ramp (so the ramp is seen, not guessed).
SAMPLES_PER_RAMP = 10
#: The lowest logger rate a programme needs (Hz).
RATE_MIN = SAMPLES_PER_RAMP / RAMP_MIN

TEMPLATE = '''# The rig file of `fcomp design` (docs/design.md). SI units throughout.
# Every key of [limits] but `noise` is required; unknown keys are refused.

[rig]
bore = 0.032                  # m, piston diameter
rod = 0.012                   # m, rod diameter (0: single-acting, the other chamber vented)
mass = 1.2                    # kg, moving mass (piston, rod, load)
orientation = "horizontal"    # horizontal | vertical-up | vertical-down

[limits]
stroke = 0.2                  # m: the programme's position stays inside [0, stroke]
speed_max = 0.2               # m/s: the fastest the rig may move
accel_max = 4.0               # m/s^2: the largest acceleration it follows
pressure_min = 1.5e5          # Pa gauge: the lowest pressure level it holds
pressure_max = 5.0e5          # Pa gauge: the highest (= pressure_min: one level only)
# pressure_levels = [2e5, 4e5]  # instead of min/max: the only levels it holds
duration_max = 30.0           # s: the longest experiment (one file each)
rate = 500.0                  # Hz: the logger's sample rate
# noise = 0.4                 # N: force noise (default: the diagnosis's noise floor)
'''

#: The largest value each key may take (SI). Beyond it the file holds a slip (a unit, a
#: digit), not a rig: a 20 m stroke, 50 m/s, 1000 g, 10 kbar, an hour per experiment, a
#: 1 MHz logger, a 100 t moving mass, a force noise of 1 MN.
MAXIMA = {"bore": 2.0, "rod": 2.0, "mass": 1e5, "stroke": 20.0, "speed_max": 50.0,
          "accel_max": 1e4, "pressure_min": 1e9, "pressure_max": 1e9, "pressure_levels": 1e9,
          "duration_max": 3600.0, "rate": 1e6, "noise": 1e6}
#: The most samples one experiment may hold (``rate * duration_max``). The design evaluates
#: its rivals and their information at every sample the logger takes: 2e5 samples (10 kHz
#: for 20 s) take some 10 s and 0.5 GB on the 2-core reference machine, growing in
#: proportion; friction programmes need a few kHz at most.
SAMPLES_MAX = 5e5

_RIG_KEYS = {"bore", "rod", "mass", "orientation"}
_LIMIT_KEYS = {"stroke", "speed_max", "accel_max", "pressure_min", "pressure_max",
               "pressure_levels", "duration_max", "rate", "noise"}


@dataclass(frozen=True)
class Rig:
    """A rig and its limits (SI; :func:`read_rig`).

    ``levels`` are the pressure levels (Pa gauge) a programme may use: the
    file's list, or a spread over ``[pressure_min, pressure_max]``
    (:meth:`spread`); one level when the rig holds one.
    """

    bore: float
    rod: float
    mass: float
    orientation: str
    stroke: float
    speed_max: float
    accel_max: float
    pressure_min: float
    pressure_max: float
    duration_max: float
    rate: float
    levels_given: tuple[float, ...] = ()
    noise: float | None = None

    def levels(self, n: int = 4) -> tuple[float, ...]:
        """The pressure levels a programme may use: the given ones, or ``n`` spread
        evenly over the range (one when the range is a point)."""
        if self.levels_given:
            return self.levels_given
        if self.pressure_max <= self.pressure_min:
            return (self.pressure_min,)
        step = (self.pressure_max - self.pressure_min) / (n - 1)
        return tuple(self.pressure_min + k * step for k in range(n))

    @property
    def double_acting(self) -> bool:
        """Both chambers pressurised (a rod given): the programme holds ``p1 = p2``."""
        return self.rod > 0

    def sidecar(self) -> dict[str, Any]:
        """The ``[rig]`` table of a programme file's sidecar."""
        out: dict[str, Any] = {"bore": self.bore, "mass": self.mass,
                               "orientation": self.orientation, "stroke": self.stroke}
        if self.rod > 0:
            out["rod"] = self.rod
        return out

    def as_dict(self) -> dict[str, Any]:
        """The rig and limits as the design JSON's ``rig``."""
        return {"rig": self.sidecar(), "limits": {
            "stroke": self.stroke, "speed_max": self.speed_max, "accel_max": self.accel_max,
            "pressure_min": self.pressure_min, "pressure_max": self.pressure_max,
            "pressure_levels": list(self.levels()), "duration_max": self.duration_max,
            "rate": self.rate, "noise": self.noise}}

    def relaxed(self, **changes: Any) -> Rig:
        """A copy with some limits changed (what a wider limit would do)."""
        from dataclasses import replace

        return replace(self, **changes)


def _number(table: Mapping[str, Any], key: str, where: str, *, positive: bool = True,
            required: bool = True, default: float | None = None) -> float | None:
    if key not in table:
        if required:
            raise FcompError(f"{where}: [{where.split('[')[-1].rstrip(']')}] {key} is missing "
                             f"(fcomp design --template writes a rig file with every key)")
        return default
    return _checked(table[key], key, where, positive)


def _checked(v: Any, key: str, where: str, positive: bool) -> float:
    """``v`` as the finite float ``key`` needs: a number (an integer too long for a float
    is none), positive (or not negative), at most :data:`MAXIMA`."""
    try:
        f = float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else math.nan
    except OverflowError:  # an integer of hundreds of digits
        raise FcompError(f"{where}: {key} must be a finite number, got an integer of "
                         f"{len(str(abs(v)))} digits") from None
    if not math.isfinite(f):
        raise FcompError(f"{where}: {key} must be a finite number, got {v!r}")
    if positive and not f > 0:
        raise FcompError(f"{where}: {key} must be positive, got {v!r}")
    if not positive and f < 0:
        raise FcompError(f"{where}: {key} must not be negative, got {v!r}")
    top = MAXIMA.get(key, math.inf)
    if f > top:
        raise FcompError(f"{where}: {key} = {f:g} is beyond any rig (at most {top:g}, SI "
                         "units: m, m/s, m/s^2, Pa, s, Hz, kg, N); check its unit")
    return f


def rig_from(doc: Mapping[str, Any], label: str = "rig") -> Rig:
    """A :class:`Rig` from the rig file's tables (checked: every limit finite, positive)."""
    unknown = set(doc) - {"rig", "limits"}
    if unknown:
        raise FcompError(f"{label}: unknown table(s) {', '.join(sorted(unknown))}; a rig file "
                         "has [rig] and [limits]")
    for name in ("rig", "limits"):
        if not isinstance(doc.get(name), Mapping):
            raise FcompError(f"{label}: the [{name}] table is missing "
                             "(fcomp design --template writes one)")
    rig, lim = doc["rig"], doc["limits"]
    for table, keys, name in ((rig, _RIG_KEYS, "rig"), (lim, _LIMIT_KEYS, "limits")):
        extra = set(table) - keys
        if extra:
            raise FcompError(f"{label}: unknown key(s) in [{name}]: {', '.join(sorted(extra))}; "
                             f"known: {', '.join(sorted(keys))}")
    w_rig, w_lim = f"{label} [rig]", f"{label} [limits]"
    orientation = rig.get("orientation", "horizontal")
    if orientation not in ORIENTATIONS:
        raise FcompError(f"{w_rig}: orientation must be one of {', '.join(ORIENTATIONS)}, "
                         f"got {orientation!r}")
    bore = _number(rig, "bore", w_rig)
    rod = _number(rig, "rod", w_rig, positive=False, required=False, default=0.0)
    mass = _number(rig, "mass", w_rig)
    assert bore is not None and rod is not None and mass is not None
    if rod >= bore:
        raise FcompError(f"{w_rig}: rod ({rod:g} m) must be smaller than the bore ({bore:g} m)")
    levels: tuple[float, ...] = ()
    if "pressure_levels" in lim:
        raw = lim["pressure_levels"]
        if not isinstance(raw, list) or not raw:
            raise FcompError(f"{w_lim}: pressure_levels must be a non-empty list of pressures "
                             f"(Pa gauge), got {raw!r}")
        levels = tuple(sorted({_checked(v, "pressure_levels", w_lim, False) for v in raw}))
        if "pressure_min" in lim or "pressure_max" in lim:
            raise FcompError(f"{w_lim}: give pressure_levels or pressure_min/pressure_max, "
                             "not both")
        p_min, p_max = levels[0], levels[-1]
    else:
        p_min = _number(lim, "pressure_min", w_lim, positive=False) or 0.0
        p_max = _number(lim, "pressure_max", w_lim, positive=False) or 0.0
        if p_max < p_min:
            raise FcompError(f"{w_lim}: pressure_max ({p_max:g} Pa) is below pressure_min "
                             f"({p_min:g} Pa)")
    vals = {k: _number(lim, k, w_lim) for k in ("stroke", "speed_max", "accel_max",
                                                "duration_max", "rate")}
    noise = _number(lim, "noise", w_lim, required=False)
    r = Rig(bore=bore, rod=rod, mass=mass, orientation=str(orientation),
            stroke=vals["stroke"] or 0.0, speed_max=vals["speed_max"] or 0.0,
            accel_max=vals["accel_max"] or 0.0, pressure_min=p_min, pressure_max=p_max,
            duration_max=vals["duration_max"] or 0.0, rate=vals["rate"] or 0.0,
            levels_given=levels, noise=noise)
    if r.rate < RATE_MIN:
        raise FcompError(f"{w_lim}: rate {r.rate:g} Hz is below the {RATE_MIN:g} Hz a "
                         f"programme needs ({SAMPLES_PER_RAMP} samples in its shortest "
                         f"speed ramp of {RAMP_MIN:g} s)")
    if r.rate * r.duration_max > SAMPLES_MAX:
        raise FcompError(f"{w_lim}: rate x duration_max = {r.rate * r.duration_max:.3g} samples "
                         f"in one experiment, more than the {SAMPLES_MAX:.0e} a design evaluates; "
                         "lower rate (a few kHz is plenty for friction) or duration_max")
    if r.duration_max < 10 * RAMP_MIN:
        raise FcompError(f"{w_lim}: duration_max {r.duration_max:g} s is too short for one "
                         f"move and back (at least {10 * RAMP_MIN:g} s)")
    return r


def read_rig(path: str | Path) -> Rig:
    """Read and check a rig file (:data:`TEMPLATE`); one clear line on anything wrong."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise FcompError(f"--rig {path}: cannot read it ({getattr(exc, 'strerror', None) or exc})"
                         ) from None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise FcompError(f"--rig {path}: not a valid TOML file ({exc})") from None
    return rig_from(doc, f"--rig {path}")
