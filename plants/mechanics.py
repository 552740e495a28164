"""The piston: equation of motion, end stops and the Karnopp stick of static maps.

Every cylinder plant shares this mechanics (models.md 3.1); a plant only
supplies the force that drives the piston (its chambers and valves,
:meth:`PistonPlant.drive`).

Equation of motion
------------------
``m*dv/dt = F_p - F - F_load - m*g*s + F_stop`` with ``F_p = p1*A1 - p2*A2 -
p_atm*(A1 - A2)`` for a cylinder (absolute pressures), ``A1 = pi/4*D^2``,
``A2 = pi/4*(D^2 - d^2)``, ``s = orient`` (+1 vertical extending upward, -1
downward, 0 horizontal), ``g = 9.80665 m/s^2``.

The friction model gives its force split ``F = F0 + c_a*a``
(:meth:`~fcomp.models.base.FrictionModel.force_parts`); the ``c_a*a`` part
(NMLGM's ``sigma2*T*dv/dt``, an inertia error ``dm*a``) is moved to the mass
side and the acceleration solved *exactly*: ``a = (F_app - F0)/(m + c_a)``,
``F_app`` being every force but friction. Friction reads *gauge* chamber
pressures and the side ``s_f = -1`` for ``v < 0``, ``+1`` otherwise.

End stops
---------
At ``x = 0`` and ``x = stroke`` the piston meets a stiff spring-damper
contact (never a silent clip): with penetration ``d`` (m) and its rate,
``F_stop = max(0, k_stop*d + c_stop*dd/dt)`` pushing back, ``c_stop =
2*zeta_stop*sqrt(k_stop*m)``, and no force out of contact (the ``max``
stops the damper from pulling the piston onto the stop). Defaults
``k_stop = 1e8 N/m`` (a steel stop: 46 um penetration under the hydraulic
servo's full 4.6 kN) and ``zeta_stop = 0.7``.

Static friction maps: Karnopp stick
-----------------------------------
Static maps (``coulomb``, ``coulomb-viscous``, ``stribeck``: no bristle
state) are regularised near ``v = 0`` by the models for use along a
prescribed motion; in a plant they would turn into a huge viscous damper.
Plants use Karnopp's stick band instead (D. Karnopp, ASME J. Dyn. Syst.
Meas. Control 107, 1985): with ``v_eps`` the model's ``v_eps`` (default
1e-5 m/s) and ``F_brk+ = F0(+v_eps)``, ``F_brk- = F0(-v_eps)`` the map's
force just outside the band (the break-away levels, effects included),

* ``|v| < v_eps`` and ``F_brk- <= F_app <= F_brk+``: **stuck**, the friction
  balances the applied force and removes the residual velocity inside the
  band: ``F = clip(F_app + m*v/tau_stick, F_brk-, F_brk+)``, so ``a = -v/tau_stick``
  (``tau_stick`` = 1 ms by default: without it Karnopp's band lets a stuck
  piston creep at up to ``v_eps``; with it the creep after a stop is below
  ``v_eps*tau_stick`` = 1e-8 m, and the extra force ``m*v/tau_stick`` is
  below ``m*v_eps/tau_stick``, 0.01 N per kg);
* ``|v| < v_eps`` and ``F_app`` beyond a break-away level: the piston breaks
  away with ``F = F_brk``;
* ``|v| >= v_eps``: sliding, ``F`` is the map.

Dynamic models (LuGre family with a bristle state) need no band.
"""

from __future__ import annotations

import math
from abc import abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from fcomp.backend import NUMPY, Backend
from fcomp.errors import FcompError, term
from fcomp.measurement import ORIENTATIONS, G
from fcomp.models.base import FrictionModel, Signals
from fcomp.parameters import ParamSpec, ParamValues, spec
from fcomp.paramsets import ParameterSet
from fcomp.piston import chamber_volumes, piston_areas
from plants.base import OdePlant

INF = math.inf


def _s(name: str, unit: str, default: float, lower: float, upper: float, doc: str,
       lower_open: bool = False) -> ParamSpec:
    return spec(name, unit, default, lower, upper, doc, directional=False, lower_open=lower_open)


#: Parameters every piston plant has (SI units).
PISTON_SPECS: tuple[ParamSpec, ...] = (
    _s("mass", "kg", 1.0, 0.0, INF, "moving mass (piston, rod, load)", lower_open=True),
    _s("bore", "m", 0.025, 0.0, 2.0, "cylinder bore D", lower_open=True),
    _s("rod", "m", 0.010, 0.0, 2.0, "rod diameter d (d < D)"),
    _s("stroke", "m", 0.3, 0.0, 20.0, "stroke (end stops at 0 and stroke)", lower_open=True),
    _s("orient", "-", 0.0, -1.0, 1.0, "orientation: +1 vertical extending up, -1 down, 0 "
       "horizontal"),
    _s("F_load", "N", 0.0, -INF, INF, "constant external load opposing extension"),
    _s("p_atm", "Pa", 101325.0, 0.0, INF, "atmospheric pressure", lower_open=True),
    _s("k_stop", "N/m", 1e8, 0.0, INF, "end-stop contact stiffness", lower_open=True),
    _s("zeta_stop", "-", 0.7, 0.0, INF, "end-stop damping ratio"),
    _s("tau_stick", "s", 1e-3, 0.0, INF, "Karnopp band: decay time of the residual velocity "
       "while stuck (static maps only)", lower_open=True),
)


def piston_values(pset: ParameterSet | None) -> dict[str, Any]:
    """``mass``, ``bore``, ``rod``, ``stroke``, ``orient`` from a set's ``[rig]``, where given."""
    out: dict[str, Any] = {}
    if pset is None:
        return out
    for k in ("mass", "bore", "rod", "stroke"):
        if k in pset.rig:
            out[k] = pset.rig[k]
    if "orientation" in pset.rig:
        out["orient"] = orient_value(pset.rig["orientation"], pset.name)
    return out


def orient_value(orientation: Any, where: str) -> float:
    """``orient`` (+1, -1, 0) of an orientation name (``vertical-up``, ...)."""
    if orientation not in ORIENTATIONS:
        raise FcompError(f"parameter set {where}: orientation must be one of "
                         f"{', '.join(ORIENTATIONS)}, got {orientation!r}")
    return ORIENTATIONS[orientation]


def require_section(pset: ParameterSet | None, plant: str, *keys: str) -> dict[str, Any]:
    """The nested section ``keys`` of the set's TOML, or a one-line error naming it."""
    if pset is None:
        raise FcompError(f"plant {plant} needs a parameter set ({term('params')})")
    node: Any = pset.raw
    for i, k in enumerate(keys):
        if not isinstance(node, dict) or k not in node:
            path = ".".join(keys[: i + 1])
            raise FcompError(f"parameter set {pset.name} has no [{path}] section, which plant "
                             f"{plant} needs")
        node = node[k]
    return dict(node)


def areas(be: Backend, P: ParamValues) -> tuple[Any, Any]:
    """Piston areas ``A1``, ``A2`` (m^2) of the plant's ``bore`` and ``rod``
    (:func:`fcomp.piston.piston_areas`)."""
    return piston_areas(P("bore"), P("rod"))


def force_range(p: Mapping[str, float]) -> tuple[float, float]:
    """The piston force ``F_p`` the chamber pressures can give, lowest to highest (N):

    ``(p_low - p_atm)*A1 - (ps - p_atm)*A2`` to ``(ps - p_atm)*A1 - (p_low - p_atm)*A2``,

    each chamber between the supply ``ps`` and the return ``p_low`` -- the tank ``pt`` of
    a hydraulic valve, the atmosphere where a pneumatic valve exhausts (``p``: a plant's
    flat parameters; ``pt`` absent means the atmosphere)."""
    A1, A2 = piston_areas(p["bore"], p["rod"])
    pa = p["p_atm"]
    low = p.get("pt", pa)
    return ((low - pa) * A1 - (p["ps"] - pa) * A2, (p["ps"] - pa) * A1 - (low - pa) * A2)


def hold_force(p: Mapping[str, float]) -> float:
    """The piston force that holds the load at rest (N): ``F_load + m*g*orient``
    (the equation of motion with ``v = a = 0``, friction and end stops aside)."""
    return p["F_load"] + p["mass"] * G * p["orient"]


def volumes(pos: Any, P: ParamValues, A1: Any, A2: Any) -> tuple[Any, Any]:
    """Chamber volumes ``V1``, ``V2`` (m^3) at position ``pos`` (:func:`fcomp.piston.chamber_volumes`)."""
    return chamber_volumes(pos, P("stroke"), P("V10"), P("V20"), A1, A2)


def end_stop_force(be: Backend, x: Any, v: Any, P: ParamValues) -> Any:
    """Contact force of the end stops (N, positive extending; module docstring)."""
    k = P("k_stop")
    c = 2.0 * P("zeta_stop") * be.sqrt(k * P("mass"))
    low = be.if_else(x < 0.0, be.fmax(0.0, -k * x - c * v), 0.0)
    over = x - P("stroke")
    high = be.if_else(over > 0.0, be.fmin(0.0, -k * over - c * v), 0.0)
    return low + high


def is_static_map(model: FrictionModel) -> bool:
    """Whether ``model`` is a memoryless map needing the Karnopp band in a plant (the model's
    :attr:`~fcomp.models.base.FrictionModel.static_map`: in the LuGre family every model
    without the bristle state ``presliding``)."""
    return model.static_map


@dataclass
class Drive:
    """What a plant's chambers and valves give the piston.

    Attributes
    ----------
    force
        Driving force on the piston (N, positive extending), friction, load,
        gravity and end stops excluded.
    p1, p2
        Absolute chamber pressures (Pa) the friction model reads (as gauge).
    rates
        Derivatives of the plant's states other than ``x`` and ``v``.
    extras
        Outputs worth writing (valve position, flows, ...).
    """

    force: Any
    p1: Any
    p2: Any
    rates: dict[str, Any] = field(default_factory=dict)
    extras: dict[str, Any] = field(default_factory=dict)


class PistonPlant(OdePlant):
    """A piston with friction and end stops, driven by :meth:`drive` (module docstring)."""

    plant_states: ClassVar[tuple[str, ...]] = ("x", "v")
    state_units: ClassVar[dict[str, str]] = {"x": "m", "v": "m/s"}
    output_names: ClassVar[tuple[str, ...]] = ("x", "v", "a", "p1", "p2", "F")
    output_units: ClassVar[dict[str, str]] = {"x": "m", "v": "m/s", "a": "m/s^2", "p1": "Pa (gauge)", "p2": "Pa (gauge)",
                    "F": "N"}

    @abstractmethod
    def drive(self, be: Backend, x: dict[str, Any], u: dict[str, Any],
              P: ParamValues) -> Drive:
        """The driving force, chamber pressures and other state derivatives."""

    # --------------------------------------------------------------- checks
    def check_params(self) -> None:
        p = self.plant_params.flat()
        if p["rod"] >= p["bore"]:
            raise FcompError(f"plant {self.name}: rod diameter {p['rod']:g} m must be smaller "
                             f"than the bore {p['bore']:g} m")
        if p["orient"] not in ORIENTATIONS.values():
            raise FcompError(f"plant {self.name}: orient must be +1, -1 or 0, got {p['orient']:g}")
        self._check_mass_side()

    def _check_mass_side(self) -> None:
        """``m + c_a > 0`` on both sides: the acceleration can be solved."""
        P = self.friction.param_values(NUMPY)
        m = self.plant_params.flat()["mass"]
        x = list(self.friction.initial_state())
        for s in (1.0, -1.0):
            _, c_a = self.friction.force_parts(NUMPY, x, Signals(v=0.1 * s, s=s), P)
            if not m + float(np.asarray(c_a)) > 0:
                raise FcompError(f"plant {self.name}: moving mass {m:g} kg plus the friction's "
                                 f"acceleration term {float(c_a):g} kg must be positive")

    def rig_meta(self) -> dict[str, Any]:
        p = self.plant_params.flat()
        orient = {v: k for k, v in ORIENTATIONS.items()}[p["orient"]]
        return {"bore": p["bore"], "rod": p["rod"], "stroke": p["stroke"], "mass": p["mass"],
                "orientation": orient}

    # ------------------------------------------------------------ equations
    def equations(self, be: Backend, x: dict[str, Any], u: dict[str, Any],
                  P: ParamValues) -> tuple[dict[str, Any], dict[str, Any]]:
        pos, vel = x["x"], x["v"]
        d = self.drive(be, x, u, P)
        m = P("mass")
        F_app = (d.force - P("F_load") - m * G * P("orient")
                 + end_stop_force(be, pos, vel, P))
        p_atm = P("p_atm")
        fr = self.friction
        zf = [x[n] for n in fr.state_names]

        def signals(v: Any, s: Any) -> Signals:
            return Signals(v=v, a=0.0, x=pos, p1=d.p1 - p_atm, p2=d.p2 - p_atm, s=s)

        sig = signals(vel, be.if_else(vel < 0.0, -1.0, 1.0))
        dz = fr.rhs(be, zf, sig, P)
        F0, c_a = fr.force_parts(be, zf, sig, P)
        if is_static_map(fr):
            v_eps = P("v_eps")
            Fp, cp = fr.force_parts(be, zf, signals(v_eps, 1.0), P)
            Fn, cn = fr.force_parts(be, zf, signals(-v_eps, -1.0), P)
            band = be.abs(vel) < v_eps
            stuck = F_app + m * vel / P("tau_stick")
            F0 = be.if_else(band, be.fmin(be.fmax(stuck, Fn), Fp), F0)
            c_band = be.if_else(F_app > Fp, cp, be.if_else(F_app < Fn, cn, 0.0))
            c_a = be.if_else(band, c_band, c_a)
        a = (F_app - F0) / (m + c_a)
        dx = {"x": vel, "v": a, **d.rates, **dict(zip(fr.state_names, dz, strict=True))}
        y = {"x": pos, "v": vel, "a": a, "p1": d.p1 - p_atm, "p2": d.p2 - p_atm,
             "F": F0 + c_a * a, **d.extras}
        return dx, y

    def default_state(self) -> dict[str, float]:
        """Mid-stroke, at rest (plants add their chambers and valves)."""
        return {"x": 0.5 * self.plant_params.flat()["stroke"], "v": 0.0}

    def state_scales(self) -> dict[str, float]:
        return {"x": self.plant_params.flat()["stroke"], "v": 1.0}
