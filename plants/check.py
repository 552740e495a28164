"""What an engineer checks first on a plant file (``fcomp plant check FILE``).

At mid stroke, holding its load at rest (:func:`plants.equilibrium.equilibrium`),
the plant is linearised with python-control (``plant.to_iosys().linearize``);
the piston and its two chambers -- the block of the states ``v``, ``p1``,
``p2`` of that linear system, valve held -- give the natural frequency
``w_n`` and damping ratio of the oil (or air) column (``control.damp``).
For a hydraulic cylinder it is the textbook

    w_n^2 = beta*A1^2/(m*V1) + beta*A2^2/(m*V2),

and for a pneumatic one, at the equilibrium pressures,

    w_n^2 = kappa*p1*A1^2/(m*V1) + kappa*p2*A2^2/(m*V2)

(both printed beside it); the damping comes from the valve's flow-pressure
coefficient (underlap). The valve-limited speed is that of steady motion
through mid stroke at the command limit ``+-u_max`` (the piston free of
friction and external load, its weight included:
:func:`plants.equilibrium.steady_motion`), the force range what the supply
and return pressures can push and pull, ``(ps - p_atm)*A1 - (pt - p_atm)*A2``
to ``(pt - p_atm)*A1 - (ps - p_atm)*A2`` (``pt = p_atm`` for a pneumatic
servo exhausting to atmosphere).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from fcomp.measurement import G
from fcomp.piston import chamber_volumes, piston_areas
from plants.base import OdePlant
from plants.equilibrium import equilibrium, steady_motion

if TYPE_CHECKING:
    from fcomp.models.base import FrictionModel
    from plants.planfile import PlantFile


def dead_valve(kind: str, values: dict[str, float], label: str = "") -> str | None:
    """Why a plant's valve passes no flow (one line), or None: a hydraulic valve whose spool
    gain ``kv``, discharge coefficient ``cd`` or area gradient ``w`` (a rated flow of 0) is
    0, a pneumatic one whose edge area ``A_valve`` (sonic conductance) is 0 -- no command
    moves the piston, so there is nothing to check or to tune."""
    if kind == "hydraulic":
        names = {"kv": "kv (spool displacement per command)", "cd": "cd (discharge "
                 "coefficient)", "w": "w (area gradient; or its rated_flow)"}
    else:
        names = {"A_valve": "A_valve (edge area; or its sonic_conductance)"}
    bad = [k for k in names if not values.get(k, 1.0) > 0]
    if not bad:
        return None
    where = f"{label}: " if label else ""
    return (f"{where}[valve] {', '.join(names[k] for k in bad)} is 0: the valve passes no "
            "flow, no command moves the piston; give the valve's flow gain")


def frictionless() -> FrictionModel:
    """A friction model that adds no force: Coulomb with ``Fc = 0``."""
    from fcomp.models import make_model

    return make_model("coulomb", {"Fc": 0.0})


@dataclass(frozen=True)
class ColumnMode:
    """The oil (air) column's mode at a position, holding the load at rest.

    Attributes
    ----------
    frequency : float
        Natural frequency ``w_n`` (rad/s).
    damping : float
        Damping ratio.
    state : numpy.ndarray
        The equilibrium state linearised about.
    command : float
        The valve command holding it.
    """

    frequency: float
    damping: float
    state: np.ndarray
    command: float


def column_mode(plant: OdePlant, x_pos: float) -> ColumnMode:
    """Natural frequency and damping of the oil (air) column at ``x_pos`` (m).

    The plant is linearised with python-control (``plant.to_iosys().linearize``) at
    rest holding its load (:func:`plants.equilibrium.equilibrium`); the block of the
    states ``v``, ``p1``, ``p2`` (valve held) gives the mode (``control.damp``): the
    fastest oscillating pair, or the fastest real pole when the damping leaves none.
    """
    import control as ct

    names = list(plant.state_names)
    x0, u0 = equilibrium(plant, x_pos)
    lin = plant.to_iosys().linearize(x0, [u0])
    idx = [names.index(n) for n in ("v", "p1", "p2")]
    A = np.asarray(lin.A, dtype=float)[np.ix_(idx, idx)]
    wn, zeta, poles = ct.damp(ct.ss(A, np.zeros((3, 1)), np.eye(3), np.zeros((3, 1))),
                              doprint=False)
    pair = [i for i, p in enumerate(poles) if abs(np.imag(p)) > 0]
    k = max(pair, key=lambda i: wn[i]) if pair else int(np.argmax(wn))
    return ColumnMode(float(wn[k]), float(zeta[k]), np.asarray(x0, dtype=float), float(u0))


def check_plant(pf: PlantFile, friction: FrictionModel | None = None) -> dict[str, Any]:
    """The figures of ``fcomp plant check`` (module docstring), SI units.

    Parameters
    ----------
    pf : PlantFile
        The plant.
    friction : FrictionModel, optional
        Friction of the piston for the linearisation (default none, as the hand
        formulas). A static map's viscous slope adds damping; a model with states
        (a bristle) is outside the block analysed, and a damping that leaves no
        oscillating pair reports the fastest real pole.

    Returns
    -------
    dict
        ``kind``, ``name``, ``natural_frequency`` (rad/s), ``natural_frequency_hz``,
        ``damping``, ``hand_formula`` (rad/s), ``equilibrium`` (``u``, ``p1``, ``p2``
        absolute Pa, ``V1``, ``V2`` m^3), ``valve_limited_speed`` (``extend``,
        ``retract`` m/s), ``force_range`` (``max``, ``min`` N), ``weight`` (N),
        ``valve_bandwidth_hz``, ``control_rate`` (Hz).
    """
    plant = pf.make_plant(friction or frictionless())
    v = pf.values
    names = list(plant.state_names)
    mid = 0.5 * v["stroke"]
    mode = column_mode(plant, mid)
    x0, u0 = mode.state, mode.command
    A1, A2 = piston_areas(v["bore"], v["rod"])
    V1, V2 = chamber_volumes(mid, v["stroke"], v["V10"], v["V20"], A1, A2)
    p1, p2 = float(x0[names.index("p1")]), float(x0[names.index("p2")])
    m = v["mass"]
    if pf.kind == "hydraulic":
        hand = math.sqrt(v["beta"] * (A1**2 / V1 + A2**2 / V2) / m)
        p_low = v["pt"]
    else:
        hand = math.sqrt(v["k_poly"] * (p1 * A1**2 / V1 + p2 * A2**2 / V2) / m)
        p_low = v["p_atm"]
    pa = v["p_atm"]
    u_max = pf.control["u_max"]
    return {
        "kind": pf.kind, "name": pf.name, "file": pf.label,
        "natural_frequency": mode.frequency, "natural_frequency_hz": mode.frequency / (2 * math.pi),
        "damping": mode.damping, "hand_formula": hand,
        "equilibrium": {"x": mid, "u": u0, "p1": p1, "p2": p2, "V1": float(V1), "V2": float(V2)},
        "valve_limited_speed": {"extend": _speed(plant, mid, u_max, pf, A1),
                                "retract": _speed(plant, mid, -u_max, pf, A1)},
        "force_range": {"max": (v["ps"] - pa) * A1 - (p_low - pa) * A2,
                        "min": (p_low - pa) * A1 - (v["ps"] - pa) * A2},
        "weight": m * G * v["orient"],
        "valve_bandwidth_hz": pf.valve_bandwidth, "control_rate": pf.control["control_rate"],
    }


def _speed(plant: Any, x_pos: float, u: float, pf: PlantFile, A1: float) -> float:
    """Speed of steady motion through ``x_pos`` under the command ``u`` (m/s)."""
    v = pf.values
    if pf.kind == "hydraulic":  # the no-load estimate Q/A1 as the start
        opening = v["kv"] * abs(u) + v["underlap"]
        guess = v["cd"] * v["w"] * opening * math.sqrt((v["ps"] - v["pt"]) / v["rho"]) / A1
    else:
        guess = 0.1 * v["A_valve"] * 340.0 / A1  # a tenth of the sonic volume flow
    state = steady_motion(plant, x_pos, u, math.copysign(guess, u))
    return float(state[list(plant.state_names).index("v")])


__all__ = ["ColumnMode", "check_plant", "column_mode", "dead_valve", "frictionless"]
