"""The truth friction along a fine-grid motion: a base law with hidden effects.

Bases (SI units; ``s = sign(v)``, levels ``Fc``, ``Fs`` in N; the levels are
multiplied by the hidden effects' level factors, :mod:`fcomp.synthetic.laws`):

``coulomb``
    ``F = Fc*s`` (``s = tanh(v/1e-5)``: a smooth sign, ``F = 0`` at rest).
``coulomb-viscous``
    ``F = Fc*s + sigma2*v`` (seed 001 Eq. 4).
``stribeck``
    ``F = s*(Fc + (Fs - Fc)*exp(-(|v|/vs)^2)) + sigma2*v`` (models.md 1.1).
``lugre``
    bristle state ``dz/dt = v - sigma0*|v|*z/g``, ``F = sigma0*z + sigma1*dz/dt
    + sigma2*v`` with ``g`` the Stribeck curve above (Canudas de Wit et al.
    1995, models.md 1.3).

Assembly: ``g = Fc*f + (hump + dwell)*f`` (``f`` the product of the level
factors, ``hump`` the Stribeck hump at the possibly lagged speed, ``dwell``
the excess after a rest); the dry friction is ``g`` through the presliding
law (a smooth sign on the static bases, the LuGre bristle, a hidden
presliding or Maxwell-slip law); plus the viscous terms; times the
direction ratio where hidden.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

import fcomp.synthetic.dynamics as dyn
import fcomp.synthetic.laws as lw
from fcomp.errors import FcompError
from fcomp.synthetic.catalogue import Law, shape
from fcomp.synthetic.scales import TruthParams

#: Bases the generator can simulate.
BASES = ("coulomb", "coulomb-viscous", "stribeck", "lugre")
#: Bases with a Stribeck hump and with a viscous term.
_HUMP_BASES = ("stribeck", "lugre")
_VISCOUS_BASES = ("coulomb-viscous", "stribeck", "lugre")
#: Fixed-point iterations of the chamber pressures for laws that depend on them.
CHAMBER_ITERATIONS = 3


def as_laws(hidden: Mapping[str, Law | Mapping[str, float]]) -> dict[str, Law]:
    """Effect -> :class:`Law`; a plain parameter mapping means the effect's first shape."""
    return {e: h if isinstance(h, Law) else Law(shape(e), dict(h)) for e, h in hidden.items()}


def check_compatible(base: str, laws: Mapping[str, Law]) -> None:
    """Refuse hidden effects that would leave no trace on ``base`` (``FcompError``)."""
    if base not in BASES:
        raise FcompError(f"unknown base {base!r}; known: {', '.join(BASES)}")
    if "frictional-lag" in laws and base not in _HUMP_BASES and "stribeck" not in laws:
        raise FcompError(f"frictional-lag acts on the Stribeck hump, which the {base!r} base "
                         "lacks: use base 'stribeck' or 'lugre', or hide 'stribeck' too")
    if "presliding" in laws and base == "lugre":
        raise FcompError("the 'lugre' base has presliding already (its bristle): hide "
                         "presliding on a static base (coulomb, coulomb-viscous, stribeck)")
    if "presliding" in laws and "nonlocal-memory" in laws:
        raise FcompError("presliding and nonlocal-memory are two presliding laws: hide one")


def node_average(mid: np.ndarray) -> np.ndarray:
    """Values at the nodes (interval ends) from interval values: the mean of the two neighbours."""
    out = np.empty_like(mid)
    out[0] = 0.5 * mid[0]
    out[1:] = 0.5 * (mid[1:] + mid[:-1])
    return out


def retracting_side(vn: np.ndarray) -> np.ndarray:
    """At every node, whether the last non-zero velocity was negative (False before any)."""
    idx = np.maximum.accumulate(np.where(vn != 0.0, np.arange(vn.size), -1))
    return np.where(idx >= 0, vn[np.maximum(idx, 0)] < 0.0, False)


def chamber_pressures(P: TruthParams, S: np.ndarray, F_net: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Gauge ``p1, p2`` (Pa) with ``p1 + p2 = S`` and ``p1*A1 - p2*A2 = F_net``."""
    A1, A2 = P.areas
    p1 = (F_net + S * A2) / (A1 + A2)
    return p1, S - p1


def truth_friction(P: TruthParams, base: str, hidden: Mapping[str, Law | Mapping[str, float]],
                   t: np.ndarray, v: np.ndarray, a: np.ndarray, x: np.ndarray, S: np.ndarray,
                   dt: float, S_mid: float, weight: float = 0.0
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The truth friction along a fine-grid motion; returns ``(F, v_node, a_node)`` (SI).

    Parameters
    ----------
    P, base, hidden
        Base parameters, base law (:data:`BASES`) and hidden laws (effect ->
        :class:`Law`, or effect -> complete parameters of its first shape).
    t, x : (n,) s, m
        Time and position at the nodes where the fine intervals start.
    v, a : (n,) m/s, m/s^2
        Velocity and acceleration of each fine interval (midpoint values).
    S : (n,) Pa
        Pressure sum ``p1 + p2`` (gauge) at the nodes.
    dt : s
        Fine step.
    S_mid : Pa
        Reference pressure sum of the pressure laws.
    weight : N
        ``m*g*s`` of a vertical rig (``s = +1`` extending upward): the chambers carry it
        (the reference chambers at ``S_mid`` too, so the pressure laws' factor is one there
        at rest); 0 horizontal.

    States (bristle, lagged speed, film, dwell age, Maxwell-slip deflections)
    advance interval by interval; the force is evaluated at the nodes with
    the node velocity (mean of the two neighbouring intervals) so that it
    lines up with the sampled ``x``. Laws on the chamber pressures use the
    force balance ``p1*A1 - p2*A2 = F + m*a`` at the pressure sum ``S``,
    iterated to a fixed point (:data:`CHAMBER_ITERATIONS`; the friction moves
    the pressures by ~0.1 % of their level).
    """
    laws = as_laws(hidden)
    check_compatible(base, laws)
    vn = node_average(v)
    an = node_average(a)
    ctx = lw.LevelContext(x=x, t=t, S=S, retracting=retracting_side(vn), stroke=P.stroke,
                          Fc=P.Fc, S_mid=S_mid)
    pressure = laws.get("pressure-dependence")
    if pressure is None or pressure.shape.name != "chamber-weighted":
        return _friction(P, base, laws, ctx, v, vn, an, dt), vn, an
    p1m, p2m = chamber_pressures(P, np.array([S_mid]), np.full(1, weight))
    inertial = P.mass * an
    if weight != 0.0:
        inertial = inertial + weight
    p1, p2 = chamber_pressures(P, S, inertial)
    for _ in range(CHAMBER_ITERATIONS):
        c = replace(ctx, chambers=(p1, p2, float(p1m[0]), float(p2m[0])))
        F = _friction(P, base, laws, c, v, vn, an, dt)
        p1, p2 = chamber_pressures(P, S, F + inertial)
    return F, vn, an


def _hump(P: TruthParams, base: str, laws: dict[str, Law], v: np.ndarray, vn: np.ndarray,
          dt: float) -> tuple[np.ndarray | None, float]:
    """Normalised hump at the nodes (lagged or filtered if hidden) and its size (N)."""
    stribeck = laws.get("stribeck")
    if base not in _HUMP_BASES and stribeck is None:
        return None, 0.0
    dF = stribeck["dF"] if stribeck is not None else P.Fs - P.Fc
    lag = laws.get("frictional-lag")
    if lag is None:
        return lw.hump_fraction(np.abs(vn), stribeck, P.vs), dF
    if lag.shape.name == "film":
        dry = 1.0 - lw.hump_fraction(np.abs(v), stribeck, P.vs)
        return 1.0 - dyn.film(dry, lag["tau_rise"], lag["tau_fall"], dt), dF
    speed = dyn.lagged_speed(np.abs(v), lag["tau_L"], dt)
    return lw.hump_fraction(speed, stribeck, P.vs), dF


def _dry(P: TruthParams, base: str, laws: dict[str, Law], g: np.ndarray, x: np.ndarray,
         v: np.ndarray, vn: np.ndarray, dt: float) -> np.ndarray:
    """The dry friction: the level ``g`` through the presliding law (N)."""
    memory = laws.get("nonlocal-memory")
    if memory is not None:  # the slip forces follow g while sliding; at rest they hold
        return dyn.maxwell_slip(memory, x, dyn.held_at_rest(g, vn))
    if base == "lugre":
        return dyn.bristle(v, vn, g, P.sigma0, P.sigma1, dt)
    pre = laws.get("presliding")
    if pre is None:
        return np.tanh(vn / 1e-5) * g
    if pre.shape.name == "dahl":
        return dyn.dahl(v, g, pre["k"], pre["i"], dt)
    if pre.shape.name == "elasto-plastic":
        return dyn.elasto_plastic(v, g, pre["k"], pre["ba"], dt)
    return dyn.bristle(v, vn, g, pre["k"], 0.0, dt)


def _friction(P: TruthParams, base: str, laws: dict[str, Law], ctx: lw.LevelContext,
              v: np.ndarray, vn: np.ndarray, an: np.ndarray, dt: float) -> np.ndarray:
    """Friction at the nodes for given level-factor inputs (N)."""
    scale = lw.level_factor(laws, ctx)
    hump, dF = _hump(P, base, laws, v, vn, dt)
    dwell_law = laws.get("dwell-time")
    dwell: np.ndarray | float = 0.0
    if dwell_law is not None:
        dwell = dyn.dwell_excess(v, dt, dwell_law, lw.dwell_law(dwell_law))
    # without a Stribeck curve the dwell excess decays with the sliding distance only
    bump = dwell * scale if hump is None else hump * (dF + dwell) * scale
    g = P.Fc * scale + bump
    coefficient = P.sigma2 if base in _VISCOUS_BASES else 0.0
    F_visc = lw.viscous(laws, coefficient, vn)
    lead = laws.get("viscous-lead")
    if lead is not None:
        visc = lw.linear_viscous(laws, coefficient)
        if lead.shape.name == "lead":
            F_visc = F_visc + visc * lead["T"] * an
        else:
            F_visc = F_visc + visc * (lead["T"] - lead["T_f"]) * dyn.lowpass(an, lead["T_f"], dt)
    return lw.whole_factor(laws, _dry(P, base, laws, g, ctx.x, v, vn, dt) + F_visc)
