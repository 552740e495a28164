"""The boxes and scales of a record's parameters, set by the record's own scales.

Each parameter's box is its :class:`~fcomp.parameters.ParamSpec` bounds
intersected with a box set by its unit and the record's
:class:`~fcomp.conditioning.Scales` (:func:`data_bounds`), so no fit can run
away to a value the record could not support (a stiffness softer than the
stroke allows, a time constant shorter than a sample...). A scale is an
estimate, so a box a fit is pinned against may widen (:meth:`DataBoxes.widen`);
the solver's typical magnitudes come from the same unit scales
(:meth:`DataBoxes.magnitudes`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from fcomp.conditioning import Scales
from fcomp.identification.records import EXTRA_SPECS
from fcomp.models.base import FrictionModel
from fcomp.parameters import ParamSpec

#: Softest stiffness allowed: its presliding range ``F/k`` is at most this many ``d_pre``.
PRESLIDING_SPAN = 20.0
#: Half-width, in unit scales, of the box of a pressure level-law coefficient.
LEVEL_LAW_SPAN = 2.0
#: A fit pinned at a data-box edge is retried with that edge this many times farther out
#: (:meth:`DataBoxes.widen`) ...
WIDEN_FACTOR = 10.0
#: ... at most this many times per parameter and side.
WIDEN_TRIES = 2
#: Units whose data boxes come from the record's scale alone, and widen.
WIDENED_UNITS = ("N", "Ns/m", "N/m", "m/s", "m", "s", "kg")
#: Parameters whose box is a physical rule (a Stribeck exponent's range, a passive bristle
#: damping): never widened.
UNWIDENED = ("n", "sigma1", "lag")


def unit_scale(unit: str, sc: Scales, d_pre: float) -> float:
    """The natural magnitude of a quantity of ``unit`` in this record (SI)."""
    table = {
        "N": sc.force,
        "Ns/m": sc.force / sc.speed,
        "N/m": sc.force / max(d_pre, sc.resolution),
        "m/s": sc.speed,
        "m/s^2": sc.accel,
        "m": sc.stroke,
        "s": max(sc.duration, 10 * sc.dt),
        "1/Pa": 1.0 / max(sc.p_span, abs(sc.p_mid), 1.0),
        "1/Pa^2": 1.0 / max(sc.p_span, abs(sc.p_mid), 1.0) ** 2,
        "kg": sc.force / sc.accel,
        "Pa": max(sc.p_span, abs(sc.p_mid), 1.0),
        "m^2": sc.force / max(sc.p_span, abs(sc.p_mid), 1.0),
    }
    return float(table.get(unit, 1.0))


def data_bounds(spec: ParamSpec, sc: Scales, d_pre: float) -> tuple[float, float]:
    """Box of a parameter: its spec bounds intersected with a data-derived box.

    Positive quantities (spec lower bound >= 0) are confined to
    ``[lo_u, hi_u]`` by unit: forces ``[0, 20 F]``; viscous coefficients
    ``[0, 50 F/V]``; stiffnesses ``[F/min(0.5*stroke, 20*d_pre), F/(0.2*resolution)]``
    (a bristle softer than that would make the presliding range twenty times
    the record's measured presliding length ``d_pre``: a soft spring then acts
    as a slow integrator that fits training segments and fails on others);
    the bristle damping ``sigma1 <= 4 F/V``, so that the model stays
    dissipative at the record's speeds (``sigma1*|v| <= 4*Fc``,
    :meth:`~fcomp.models.lugre_family.LuGreFamily.passivity`);
    speeds ``[1e-4 V, 100 V]``; lengths ``[0.2*resolution, stroke]``;
    time constants ``[dt/2, 10*duration]``; dimensionless numbers keep their
    spec box (an open lower bound becomes 1e-3). Signed quantities get
    ``+-20`` unit scales, but the coefficients of a level law in the pressures
    (``1/Pa``, ``1/Pa^2``) only ``+-2``: across the record's pressure span the
    law may change the friction level by twice its mid value, no more (a
    box twenty times wider let a refit wander where the law turns the level
    negative at a pressure of the record). ``F``, ``V`` are the force and speed
    scales.
    """
    u = spec.unit
    s = unit_scale(u, sc, d_pre)
    lo_s, hi_s = spec.lower, spec.upper
    if spec.lower >= 0:
        box = {
            "N": (0.0, 20.0 * s),
            "Ns/m": (0.0, 50.0 * s),
            "N/m": (sc.force / min(0.5 * sc.stroke, PRESLIDING_SPAN * max(d_pre, sc.resolution)),
                    sc.force / (0.2 * sc.resolution)),
            "m/s": (1e-4 * sc.speed, 100.0 * sc.speed),
            "m": (0.2 * sc.resolution, sc.stroke),
            "s": (0.5 * sc.dt, 10.0 * sc.duration),
            "kg": (0.0, 20.0 * s),
        }.get(u, (lo_s, hi_s))
        lo = max(lo_s, box[0])
        hi = min(hi_s, box[1])
        if spec.lower_open and lo <= spec.lower:
            lo = spec.lower + (1e-3 if u == "-" else 1e-9 * s)
    else:
        k = LEVEL_LAW_SPAN if u in ("1/Pa", "1/Pa^2") else 20.0
        lo, hi = max(lo_s, -k * s), min(hi_s, k * s)
    if spec.name == "n":
        lo = max(lo, 0.2)
        hi = min(hi, 6.0)
    if spec.name == "sigma1":  # dissipative bristle over the record's speeds
        hi = min(hi, 4.0 * sc.force / sc.speed)
    return float(lo), float(hi)


#: Widened boxes (name -> ``(lower, upper)``) and the widenings so far (``(name, side)`` -> count).
BoxState = tuple[dict[str, tuple[float, float]], dict[tuple[str, int], int]]


class DataBoxes:
    """The data boxes of one record's parameters, and those widened so far.

    Parameters
    ----------
    scales
        The record's scales.
    d_pre
        Presliding length (m) of the record (for the stiffness bounds).
    """

    def __init__(self, scales: Scales, d_pre: float) -> None:
        self.scales = scales
        self.d_pre = d_pre
        #: data boxes widened because a fit was pinned at their edge (:meth:`widen`)
        self.wide: dict[str, tuple[float, float]] = {}
        self._widened: dict[tuple[str, int], int] = {}

    def bounds(self, model: FrictionModel, names: Sequence[str]) -> dict[str, tuple[float, float]]:
        """The box of each of ``names``: the widened one, else :func:`data_bounds`."""
        specs = {**model.param_specs(), **EXTRA_SPECS}
        return {n: self.wide.get(n) or data_bounds(specs[n], self.scales, self.d_pre)
                for n in names}

    def widen(self, model: FrictionModel, name: str, side: int) -> bool:
        """Widen the data box of ``name`` on ``side`` (-1 lower, +1 upper); False if it cannot.

        The data boxes (:func:`data_bounds`) come from the record's scales, and a
        scale is an estimate: a soft pneumatic seal's bristle (1.5e4 N/m) lay below
        a stiffness box set by a presliding length read off a record of small
        loops. A fit pinned at a data-box edge is therefore retried in a box
        :data:`WIDEN_FACTOR` times wider on that side (within the spec's own
        bounds), at most :data:`WIDEN_TRIES` times per parameter. Only the boxes
        of positive quantities set by the record's scale widen; the boxes that
        encode a physical rule (``n``, the passive ``sigma1``, the level laws'
        coefficients, a channel lag) do not. The widened box holds for every later
        fit of the record, so models stay compared on the same boxes.
        """
        sp = {**model.param_specs(), **EXTRA_SPECS}.get(name)
        if sp is None or sp.lower < 0 or name in UNWIDENED or sp.unit not in WIDENED_UNITS:
            return False
        lo, hi = self.wide.get(name) or data_bounds(sp, self.scales, self.d_pre)
        count = self._widened.get((name, side), 0)
        if count >= WIDEN_TRIES:
            return False
        if side < 0:
            new_lo = max(sp.lower, lo / WIDEN_FACTOR) if lo > 0 else lo
            if not new_lo < lo:
                return False
            self.wide[name] = (new_lo, hi)
        else:
            new_hi = min(sp.upper, hi * WIDEN_FACTOR)
            if not new_hi > hi:
                return False
            self.wide[name] = (lo, new_hi)
        self._widened[(name, side)] = count + 1
        return True

    def state(self) -> BoxState:
        """The widened boxes and their counts (to restore with :meth:`set_state`)."""
        return dict(self.wide), dict(self._widened)

    def set_state(self, state: BoxState) -> None:
        self.wide, self._widened = dict(state[0]), dict(state[1])

    def adopt(self, boxes: Mapping[str, tuple[float, float]]) -> None:
        """Take over boxes widened elsewhere (a worker process): the union with each own box."""
        for name, box in boxes.items():
            lo, hi = self.wide.get(name, box)
            self.wide[name] = (min(lo, box[0]), max(hi, box[1]))

    def magnitudes(self, model: FrictionModel, names: Sequence[str],
                   start: Mapping[str, float]) -> dict[str, float]:
        """Typical magnitudes (the solver's ``x_scale``): ``|start|``, at least 1 % of the unit
        scale (:func:`unit_scale`; a lag: one sample interval)."""
        specs = {**model.param_specs(), **EXTRA_SPECS}
        out = {}
        for n in names:
            v = abs(float(start[n]))
            floor = self.scales.dt if n == "lag" else \
                0.01 * unit_scale(specs[n].unit, self.scales, self.d_pre)
            out[n] = max(v, floor) if math.isfinite(v) else 10.0 * floor
        return out
