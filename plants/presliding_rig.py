"""Seed 000's pneumatic pre-sliding rig (Fig. 1; models.md 3.4), default set ``seed000-cylinder1``.

A horizontal cylinder whose piston, joined to an iron sensing object, moves
freely (no guide) under the chamber pressures and the friction; two
proportional pressure-control valves (rated 1 MPa, amplifier input 0..5 V)
set ``p1`` and ``p2``. Inputs ``u1``, ``u2``: the two valve commands (V).

Pressure valves (first-order response, time constant ``tau_p``, assumed
0.05 s), gauge set point proportional to the command and limited by the
supply::

    p_set_i = p_atm + min(p_rated*clip(u_i/u_full, 0, 1), ps_g)
    dp_i/dt = (p_set_i - p_i)/tau_p

The piston (models.md 3.1) is :class:`plants.mechanics.PistonPlant`:
``m*dv/dt = p1*A1 - p2*A2 - p_atm*(A1 - A2) - F`` (+ end stops). States
``x, v, p1, p2`` (absolute) plus the friction states.

Default initial state: mid-stroke, at rest, friction states zero, and the
piston *balanced*: ``p2 = (ps + p_atm)/2`` (``ps = p_atm + ps_g``) and ``p1``
such that ``p1*A1 - p2*A2 - p_atm*(A1 - A2) = 0`` (gauge ``p1 = p2*A2/A1``).
This deliberately departs from the ``(ps + p_atm)/2`` in both chambers of
the pneumatic servo: on this free, unguided piston equal pressures push
with ``(p - p_atm)*(A1 - A2)`` (15.7 N for cylinder 1), close to the
break-away force, before any command is given.

One input signal ``u`` (the ``fcomp simulate`` SPEC, V) is a differential
command about the commands that hold the default pressures:
``u1 = u1_0 + u/2``, ``u2 = u2_0 - u/2``, ``u_i0 = u_full*p_i0/p_rated``
(gauge ``p_i0``), so ``u = 0`` keeps the piston balanced and ``u > 0``
pushes it outward. Commands beyond 0..u_full saturate in the valves.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from fcomp.backend import Backend
from fcomp.parameters import ParamValues, make_params_class
from fcomp.paramsets import ParameterSet
from fcomp.piston import piston_areas
from plants.mechanics import PISTON_SPECS, Drive, PistonPlant, _s, areas, piston_values
from plants.mechanics import require_section as section

INF = math.inf

PreslidingRigParams = make_params_class("PreslidingRigParams", [
    *PISTON_SPECS,
    _s("p_rated", "Pa", 1e6, 0.0, INF, "rated pressure of the valves (at u_full)",
       lower_open=True),
    _s("u_full", "V", 5.0, 0.0, INF, "command of the rated pressure", lower_open=True),
    _s("tau_p", "s", 0.05, 0.0, INF, "pressure response time constant", lower_open=True),
    _s("ps_g", "Pa", 0.4e6, 0.0, INF, "supply pressure (gauge)", lower_open=True),
], owner="plant presliding-rig")


class PreslidingRig(PistonPlant):
    """Seed 000's pre-sliding rig (see the module docstring)."""

    name = "presliding-rig"
    default_params = "seed000-cylinder1"
    kind = "pneumatic-cylinder"
    input_names = ("u1", "u2")
    input_units = ("V", "V")
    Params = PreslidingRigParams
    plant_states = ("x", "v", "p1", "p2")
    state_units = {"x": "m", "v": "m/s", "p1": "Pa (absolute)", "p2": "Pa (absolute)"}

    @classmethod
    def params_from_set(cls, pset: ParameterSet | None) -> dict[str, Any]:
        rig = section(pset, cls.name, "presliding_rig")
        out = piston_values(pset)
        names = {"valve_rated_pressure": "p_rated", "valve_input_max": "u_full",
                 "tau_p": "tau_p", "ps": "ps_g"}
        out.update({new: rig[old] for old, new in names.items() if old in rig})
        return out

    def balanced_pressures(self) -> tuple[float, float]:
        """Gauge ``(p1, p2)`` of the default state: ``p2 = ps_g/2``, ``p1*A1 = p2*A2``."""
        p = self.plant_params.flat()
        p2 = 0.5 * p["ps_g"]
        A1, A2 = piston_areas(p["bore"], p["rod"])
        return p2 * A2 / A1, p2

    def commands_at_rest(self) -> tuple[float, float]:
        """Valve commands (V) that hold the default pressures."""
        p = self.plant_params.flat()
        return tuple(p["u_full"] * pg / p["p_rated"] for pg in self.balanced_pressures())  # type: ignore[return-value]

    def scalar_input(self, u: np.ndarray) -> np.ndarray:
        """``u1 = u1_0 + u/2``, ``u2 = u2_0 - u/2`` (module docstring)."""
        u1, u2 = self.commands_at_rest()
        return np.column_stack([u1 + 0.5 * u, u2 - 0.5 * u])

    def drive(self, be: Backend, x: dict[str, Any], u: dict[str, Any],
              P: ParamValues) -> Drive:
        A1, A2 = areas(be, P)
        pa = P("p_atm")

        def setpoint(cmd: Any) -> Any:
            frac = be.fmin(be.fmax(cmd / P("u_full"), 0.0), 1.0)
            return pa + be.fmin(P("p_rated") * frac, P("ps_g"))

        p1, p2 = x["p1"], x["p2"]
        tau = P("tau_p")
        force = p1 * A1 - p2 * A2 - pa * (A1 - A2)
        return Drive(force, p1, p2, rates={"p1": (setpoint(u["u1"]) - p1) / tau,
                                           "p2": (setpoint(u["u2"]) - p2) / tau})

    def default_state(self) -> dict[str, float]:
        pa = self.plant_params.flat()["p_atm"]
        p1, p2 = self.balanced_pressures()
        return {**super().default_state(), "p1": pa + p1, "p2": pa + p2}

    def state_scales(self) -> dict[str, float]:
        p = self.plant_params.flat()
        ps = p["p_atm"] + p["ps_g"]
        return {**super().state_scales(), "p1": ps, "p2": ps}
