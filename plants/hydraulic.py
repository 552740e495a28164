"""The electrohydraulic servo of seed 002 (models.md 3.2), parameter set ``seed002-type1``.

A single-rod cylinder driven by a critical-centre four-way servo valve with
underlap, moving a load (seed 002: vertical, 118 kg). Input ``u``: valve
current (A).

Servo valve (second order, seed 002 Table 2)::

    d2xv/dt2 = omega_v^2*(kv*u - xv) - 2*zeta_v*omega_v*dxv/dt

Metering edges (turbulent orifice, opening ``U +- xv`` with underlap ``U``)::

    Q = cd*w*max(opening, 0)*sqrt(2/rho)*dp/(dp^2 + dp_lam^2)^(1/4)
    Q_PA: U + xv, ps - p1     Q_AT: U - xv, p1 - pt
    Q_PB: U - xv, ps - p2     Q_BT: U + xv, p2 - pt
    Q1 = Q_PA - Q_AT,  Q2 = Q_PB - Q_BT   (m^3/s into each chamber)

``dp/(dp^2 + dp_lam^2)^(1/4)`` is ``sign(dp)*sqrt(|dp|)`` with a laminar
transition below ``dp_lam`` (default 1e3 Pa): it keeps the Jacobian finite
at ``dp = 0`` (a stalled piston, an edge at balance) and changes the flow
by less than ``(dp_lam/dp)^2/4`` (2.5e-5 at 0.1 MPa).

Chambers (``V1 = V10 + A1*x``, ``V2 = V20 + A2*(stroke - x)``)::

    dp1/dt = beta/V1*(Q1 - A1*v),   dp2/dt = beta/V2*(Q2 + A2*v)

Cavitation floor: a chamber pressure does not fall below ``p_min``
(absolute, default 1 kPa): at ``p <= p_min`` its derivative is limited to
``>= 0`` and flows and forces use ``max(p, p_min)`` (vapour fills the
deficit; the pressure rises again as soon as the net inflow is positive).

The piston (models.md 3.1) is :class:`plants.mechanics.PistonPlant`.
States ``x, v, p1, p2, xv, vv`` (``vv = dxv/dt``) plus the friction
states; pressures are absolute states, written *gauge* in the results.

Default initial state: mid-stroke, at rest, valve centred (``xv = vv = 0``),
``p1 = p2 = (ps + pt)/2``, friction states zero. Under the seed's 118 kg
vertical load these pressures do not hold the load: the run starts with
the load settling onto the oil columns.
"""

from __future__ import annotations

import math
from typing import Any

from fcomp.backend import Backend
from fcomp.errors import FcompError
from fcomp.parameters import ParamValues, make_params_class
from fcomp.paramsets import ParameterSet
from plants.mechanics import PISTON_SPECS, Drive, PistonPlant, _s, areas, piston_values, volumes
from plants.mechanics import require_section as section

INF = math.inf

HydraulicParams = make_params_class("HydraulicParams", [
    *PISTON_SPECS,
    _s("kv", "m/A", 0.0227, 0.0, INF, "spool displacement per current (seed 002 Table 2)"),
    _s("omega_v", "rad/s", 440.0, 0.0, INF, "valve natural frequency", lower_open=True),
    _s("zeta_v", "-", 0.75, 0.0, INF, "valve damping ratio"),
    _s("cd", "-", 0.32, 0.0, INF, "discharge coefficient"),
    _s("w", "m", 0.0228, 0.0, INF, "area gradient (port width)"),
    _s("underlap", "m", 4e-5, 0.0, INF, "valve underlap U"),
    _s("beta", "Pa", 1e8, 0.0, INF, "effective bulk modulus", lower_open=True),
    _s("rho", "kg/m^3", 862.0, 0.0, INF, "oil density", lower_open=True),
    _s("p_min", "Pa", 1000.0, 0.0, INF, "cavitation floor (absolute)", lower_open=True),
    _s("V10", "m^3", 5e-6, 0.0, INF, "dead volume, cap side", lower_open=True),
    _s("V20", "m^3", 5e-6, 0.0, INF, "dead volume, rod side", lower_open=True),
    _s("ps", "Pa", 6.5e6, 0.0, INF, "supply pressure (absolute)", lower_open=True),
    _s("pt", "Pa", 1e5, 0.0, INF, "tank pressure (absolute)"),
    _s("dp_lam", "Pa", 1e3, 0.0, INF, "laminar transition of the orifice law",
       lower_open=True),
], owner="plant hydraulic")


def orifice_flow(be: Backend, coeff: Any, opening: Any, dp: Any, rho: Any, dp_lam: Any) -> Any:
    """Turbulent orifice ``cd*w*max(opening, 0)*sqrt(2/rho)*dp/(dp^2 + dp_lam^2)^(1/4)`` (m^3/s)."""
    return (coeff * be.fmax(opening, 0.0) * be.sqrt(2.0 / rho) * dp
            / be.power(dp * dp + dp_lam * dp_lam, 0.25))


class HydraulicPlant(PistonPlant):
    """Electrohydraulic servo of seed 002 (see the module docstring)."""

    name = "hydraulic"
    default_params = "seed002-type1"
    kind = "hydraulic-cylinder"
    input_names = ("u",)
    input_units = ("A",)
    Params = HydraulicParams
    plant_states = ("x", "v", "p1", "p2", "xv", "vv")
    state_units = {"x": "m", "v": "m/s", "p1": "Pa (absolute)", "p2": "Pa (absolute)",
                   "xv": "m", "vv": "m/s"}
    output_names = ("x", "v", "a", "p1", "p2", "F", "xv", "Q1", "Q2")
    output_units = {**PistonPlant.output_units, "xv": "m", "Q1": "m^3/s", "Q2": "m^3/s"}

    @classmethod
    def params_from_set(cls, pset: ParameterSet | None) -> dict[str, Any]:
        valve = section(pset, cls.name, "servo_valve")
        fluid = section(pset, cls.name, "fluid")
        cyl = section(pset, cls.name, "cylinder")
        supply = section(pset, cls.name, "supply")
        out = piston_values(pset)
        out.update({k: valve[k] for k in ("kv", "omega_v", "zeta_v", "cd", "w", "underlap")
                    if k in valve})
        out.update({k: fluid[k] for k in ("beta", "rho", "p_min") if k in fluid})
        out.update({k: cyl[k] for k in ("V10", "V20") if k in cyl})
        out.update({k: supply[k] for k in ("ps", "pt") if k in supply})
        return out

    def check_params(self) -> None:
        super().check_params()
        p = self.plant_params.flat()
        if not p["p_min"] <= p["pt"] < p["ps"]:
            raise FcompError(f"plant {self.name}: pressures must satisfy p_min <= pt < ps "
                             f"(got {p['p_min']:g}, {p['pt']:g}, {p['ps']:g} Pa)")

    def drive(self, be: Backend, x: dict[str, Any], u: dict[str, Any],
              P: ParamValues) -> Drive:
        A1, A2 = areas(be, P)
        pos, vel = x["x"], x["v"]
        p_min = P("p_min")
        p1, p2 = be.fmax(x["p1"], p_min), be.fmax(x["p2"], p_min)
        xv, vv = x["xv"], x["vv"]
        U, ps, pt = P("underlap"), P("ps"), P("pt")
        k, rho, lam = P("cd") * P("w"), P("rho"), P("dp_lam")
        Q1 = (orifice_flow(be, k, U + xv, ps - p1, rho, lam)
              - orifice_flow(be, k, U - xv, p1 - pt, rho, lam))
        Q2 = (orifice_flow(be, k, U - xv, ps - p2, rho, lam)
              - orifice_flow(be, k, U + xv, p2 - pt, rho, lam))
        V1, V2 = volumes(pos, P, A1, A2)
        beta = P("beta")
        dp1 = beta / V1 * (Q1 - A1 * vel)
        dp2 = beta / V2 * (Q2 + A2 * vel)
        dp1 = be.if_else(x["p1"] <= p_min, be.fmax(dp1, 0.0), dp1)
        dp2 = be.if_else(x["p2"] <= p_min, be.fmax(dp2, 0.0), dp2)
        wv, zv = P("omega_v"), P("zeta_v")
        dvv = wv * wv * (P("kv") * u["u"] - xv) - 2.0 * zv * wv * vv
        force = p1 * A1 - p2 * A2 - P("p_atm") * (A1 - A2)
        return Drive(force, p1, p2, rates={"p1": dp1, "p2": dp2, "xv": vv, "vv": dvv},
                     extras={"xv": xv, "Q1": Q1, "Q2": Q2})

    def default_state(self) -> dict[str, float]:
        p = self.plant_params.flat()
        pm = 0.5 * (p["ps"] + p["pt"])
        return {**super().default_state(), "p1": pm, "p2": pm, "xv": 0.0, "vv": 0.0}

    def state_scales(self) -> dict[str, float]:
        p = self.plant_params.flat()
        xv = max(p["underlap"], p["kv"] * 0.01, 1e-6)
        return {**super().state_scales(), "p1": p["ps"], "p2": p["ps"], "xv": xv,
                "vv": xv * p["omega_v"]}
