"""Pneumatic position servo with a proportional 5/3 flow valve (models.md 3.3).

Parameter set ``seed000-servo``: cylinder 1 of seed 000 (25/10 mm, 300 mm
stroke) plus the valve, supply and tubing assumed in
``pneumatic-seed000.toml`` ``[servo]`` (none of it is in the seeds). Input
``u``: valve command, normalised -1..1 (``u_max`` = full opening), positive
connecting the cap side to supply.

Valve: the spool follows the saturated command with a first-order lag,
``dxs/dt = (sat(u/u_max) - xs)/tau_v``, ``xs`` in -1..1. Edge areas with
underlap ``lap`` (a fraction of full opening)::

    A_PA = A_BT = A_v*clip(lap + xs, 0, 1),   A_AT = A_PB = A_v*clip(lap - xs, 0, 1)

Mass flow through an edge from ``p_up`` to ``p_dn`` -- **ISO 6358** form
(ISO 6358-1:2013, Pneumatic fluid power -- flow-rate characteristics of
components; sonic conductance ``C``, critical pressure ratio ``b``)::

    mdot = C*rho0*p_up*sqrt(T0/T)*phi(r),   r = p_dn/p_up
    phi = 1                                   r <= b       (choked)
    phi = sqrt(1 - ((r - b)/(1 - b))^2)       b < r < r_lam (subsonic)
    phi = phi(r_lam)*(1 - r)/(1 - r_lam)      r >= r_lam   (laminar, linear to 0)

The sonic conductance is that of an ideal nozzle of the edge area ``A``:
``C*rho0*sqrt(T0) = A*psi_c/sqrt(R)``, ``psi_c = sqrt(gamma*(2/(gamma +
1))^((gamma + 1)/(gamma - 1)))`` (0.685 for air), i.e. ``mdot =
A*psi_c*p_up/sqrt(R*T)*phi(r)`` -- the choked flow of isentropic nozzle
theory, with ``b`` = 0.528 as in the parameter set. The linear laminar end
above ``r_lam`` (default 0.999, the laminar-flow region of the Simscape
"Orifice ISO 6358" block) keeps the Jacobian finite at ``r = 1``. Flow
reverses with the pressure difference. Air temperature ``T_air`` is that
of the supply throughout.

Chambers (polytropic exponent ``k_poly``; ``V1 = V10 + A1*x``,
``V2 = V20 + A2*(stroke - x)``)::

    dp1/dt = k_poly/V1*(R*T*mdot1 - p1*A1*v),   mdot1 = mdot_PA - mdot_AT
    dp2/dt = k_poly/V2*(R*T*mdot2 + p2*A2*v),   mdot2 = mdot_PB - mdot_BT

With ``k_poly = 1`` (isothermal) the chamber air mass ``p*V/(R*T)``
changes exactly by the valve flows; with the valve shut, ``p*V^k_poly`` is
constant. The piston (models.md 3.1) is :class:`plants.mechanics.PistonPlant`.

States ``x, v, p1, p2, xs`` plus the friction states; pressures absolute
states, written gauge. Default initial state: mid-stroke, at rest, valve
centred, ``p1 = p2 = (ps + p_atm)/2``, friction states zero.
"""

from __future__ import annotations

import math
from typing import Any

from fcomp.backend import Backend
from fcomp.errors import FcompError
from fcomp.parameters import ParamValues, make_params_class
from fcomp.paramsets import ParameterSet
from plants.mechanics import (
    PISTON_SPECS,
    Drive,
    PistonPlant,
    _s,
    areas,
    orient_value,
    piston_values,
    volumes,
)
from plants.mechanics import require_section as section

INF = math.inf

PneumaticParams = make_params_class("PneumaticParams", [
    *PISTON_SPECS,
    _s("ps", "Pa", 0.6e6, 0.0, INF, "supply pressure (absolute)", lower_open=True),
    _s("R_air", "J/(kg K)", 287.05, 0.0, INF, "gas constant of air", lower_open=True),
    _s("T_air", "K", 293.15, 0.0, INF, "air (supply) temperature", lower_open=True),
    _s("gamma_air", "-", 1.4, 1.0, 2.0, "ratio of specific heats (choked-flow constant)",
       lower_open=True),
    _s("b_crit", "-", 0.528, 0.0, 1.0, "critical pressure ratio b (ISO 6358)", lower_open=True),
    _s("r_lam", "-", 0.999, 0.0, 1.0, "pressure ratio above which the flow is laminar",
       lower_open=True),
    _s("k_poly", "-", 1.2, 1.0, 2.0, "polytropic exponent of the chambers"),
    _s("A_valve", "m^2", 6e-6, 0.0, INF, "effective edge area at full opening"),
    _s("lap", "-", 0.01, 0.0, 1.0, "valve underlap, fraction of full opening"),
    _s("tau_v", "s", 0.005, 0.0, INF, "spool time constant", lower_open=True),
    _s("u_max", "-", 1.0, 0.0, INF, "command of full opening", lower_open=True),
    _s("V10", "m^3", 1e-5, 0.0, INF, "dead volume incl. tubing, cap side", lower_open=True),
    _s("V20", "m^3", 1e-5, 0.0, INF, "dead volume incl. tubing, rod side", lower_open=True),
], owner="plant pneumatic")


def iso6358_flow(be: Backend, p_a: Any, p_b: Any, area: Any, P: ParamValues) -> Any:
    """Mass flow (kg/s) through an edge of ``area`` from ``p_a`` to ``p_b`` (negative if back).

    ISO 6358 form with the ideal-nozzle sonic conductance (module docstring).
    """
    gam = P("gamma_air")
    psi_c = be.sqrt(gam * be.power(2.0 / (gam + 1.0), (gam + 1.0) / (gam - 1.0)))
    b, rl = P("b_crit"), P("r_lam")
    p_up = be.fmax(be.fmax(p_a, p_b), 1.0)
    r = be.fmin(p_a, p_b) / p_up

    def ellipse(q: Any) -> Any:
        e = (q - b) / (1.0 - b)
        return be.sqrt(be.fmax(1.0 - e * e, 0.0))

    phi = be.if_else(r <= b, 1.0,
                     be.if_else(r < rl, ellipse(r), ellipse(rl) * (1.0 - r) / (1.0 - rl)))
    mdot = area * psi_c * p_up / be.sqrt(P("R_air") * P("T_air")) * phi
    return be.if_else(p_a >= p_b, mdot, -mdot)


class PneumaticPlant(PistonPlant):
    """Pneumatic position servo (see the module docstring)."""

    name = "pneumatic"
    default_params = "seed000-servo"
    kind = "pneumatic-cylinder"
    input_names = ("u",)
    input_units = ("-",)
    Params = PneumaticParams
    plant_states = ("x", "v", "p1", "p2", "xs")
    state_units = {"x": "m", "v": "m/s", "p1": "Pa (absolute)", "p2": "Pa (absolute)",
                   "xs": "-"}
    output_names = ("x", "v", "a", "p1", "p2", "F", "xs", "mdot1", "mdot2")
    output_units = {**PistonPlant.output_units, "xs": "-", "mdot1": "kg/s", "mdot2": "kg/s"}

    @classmethod
    def params_from_set(cls, pset: ParameterSet | None) -> dict[str, Any]:
        servo = section(pset, cls.name, "servo")
        air = section(pset, cls.name, "air")
        out = piston_values(pset)
        cyl = str(int(servo.get("cylinder", 1)))
        out.update({k: v for k, v in section(pset, cls.name, "cylinder", cyl).items()
                    if k in ("bore", "rod", "stroke", "mass")})
        out["mass"] = out.get("mass", 0.0) + servo.get("load_mass", 0.0)
        names = {"R": "R_air", "T": "T_air", "gamma": "gamma_air", "p_atm": "p_atm",
                 "critical_ratio": "b_crit"}
        out.update({new: air[old] for old, new in names.items() if old in air})
        names = {"ps": "ps", "V10": "V10", "V20": "V20", "polytropic": "k_poly",
                 "valve_area_max": "A_valve", "valve_underlap": "lap", "valve_tau": "tau_v",
                 "u_max": "u_max"}
        out.update({new: servo[old] for old, new in names.items() if old in servo})
        if "orientation" in servo:
            out["orient"] = orient_value(servo["orientation"], f"{pset.name} [servo]")  # type: ignore[union-attr]
        return out

    def check_params(self) -> None:
        super().check_params()
        p = self.plant_params.flat()
        if not p["ps"] > p["p_atm"]:
            raise FcompError(f"plant {self.name}: supply pressure ps = {p['ps']:g} Pa (absolute) "
                             f"must exceed p_atm = {p['p_atm']:g} Pa")
        if not p["b_crit"] < p["r_lam"]:
            raise FcompError(f"plant {self.name}: r_lam ({p['r_lam']:g}) must exceed b_crit "
                             f"({p['b_crit']:g})")

    def drive(self, be: Backend, x: dict[str, Any], u: dict[str, Any],
              P: ParamValues) -> Drive:
        A1, A2 = areas(be, P)
        pos, vel = x["x"], x["v"]
        p1, p2, xs = x["p1"], x["p2"], x["xs"]
        ps, pa = P("ps"), P("p_atm")
        Av, lap = P("A_valve"), P("lap")
        open_a = Av * be.fmin(be.fmax(lap + xs, 0.0), 1.0)
        open_b = Av * be.fmin(be.fmax(lap - xs, 0.0), 1.0)
        mdot1 = iso6358_flow(be, ps, p1, open_a, P) - iso6358_flow(be, p1, pa, open_b, P)
        mdot2 = iso6358_flow(be, ps, p2, open_b, P) - iso6358_flow(be, p2, pa, open_a, P)
        V1, V2 = volumes(pos, P, A1, A2)
        k, RT = P("k_poly"), P("R_air") * P("T_air")
        dp1 = k / V1 * (RT * mdot1 - p1 * A1 * vel)
        dp2 = k / V2 * (RT * mdot2 + p2 * A2 * vel)
        cmd = be.fmin(be.fmax(u["u"] / P("u_max"), -1.0), 1.0)
        dxs = (cmd - xs) / P("tau_v")
        force = p1 * A1 - p2 * A2 - pa * (A1 - A2)
        return Drive(force, p1, p2, rates={"p1": dp1, "p2": dp2, "xs": dxs},
                     extras={"xs": xs, "mdot1": mdot1, "mdot2": mdot2})

    def default_state(self) -> dict[str, float]:
        p = self.plant_params.flat()
        pm = 0.5 * (p["ps"] + p["p_atm"])
        return {**super().default_state(), "p1": pm, "p2": pm, "xs": 0.0}

    def state_scales(self) -> dict[str, float]:
        p = self.plant_params.flat()
        return {**super().state_scales(), "p1": p["ps"], "p2": p["ps"], "xs": 1.0}
