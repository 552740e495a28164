"""Static laws of the truth friction: Stribeck humps, level factors, viscous terms, dwell excess.

Everything here is a function of the current motion and pressures (or, for
the dwell excess, of the rest time just ended); the laws with an internal
state are in :mod:`fcomp.synthetic.dynamics`. Notation: ``v`` velocity (m/s),
``s = sign(v)``, ``x`` position (m), ``L`` stroke (m), ``S = p1 + p2`` the
pressure sum (Pa, gauge), ``Fc`` the Coulomb level (N). A *level factor*
multiplies both friction levels ``Fc`` and ``Fs`` (the whole static map,
Stribeck hump included).

Sources
-------
* Armstrong-Helouvry, B. (1991). *Control of Machines with Friction*. Kluwer:
  the exponential Stribeck curve ``exp(-(|v|/vs)^delta)``, ``delta`` 0.5-2.
* Hess, D. P. & Soom, A. (1990). Friction at a lubricated line contact
  operating at oscillating sliding velocities. *J. Tribology* 112, 147-152:
  the Lorentzian curve ``1/(1 + (v/vs)^2)`` and the frictional lag.
* Kato, S., Sato, N. & Matsubayashi, T. (1972). Some considerations on
  characteristics of static friction of machine tool slideway. *J. Lubr.
  Technol.* 94, 234-247: ``Fs(t_d) = Fs_inf - (Fs_inf - Fc)*exp(-gamma*t_d^m)``.
* Dieterich, J. H. (1972). Time-dependent friction in rocks. *J. Geophys. Res.*
  77, 3690-3697: static friction growing with ``log(1 + t_d/tau)``.
* Harnoy, A., Friedland, B. & Cohn, S. (2008). Modeling and measuring friction
  effects. *IEEE Control Systems Magazine* 28(6), 82-91: friction set by a
  lubricant-film state with its own dynamics (the ``film`` lag).
* Power-law (Ostwald-de Waele) shear-thinning lubricant: the viscous force
  grows as ``|v|^n``, ``n < 1``.
* Seal friction growing with the pressure that energises the seal: Belforte,
  G. et al. (2003), Measurement of friction force in pneumatic cylinders,
  *Tribotest* 10, 33-48; Nikas, G. K. (2010), Eighty years of research on
  hydraulic reciprocating seals, *Proc. IMechE J* 224, 1-23.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fcomp.synthetic.catalogue import Law

G = 9.80665


# ------------------------------------------------------------------ Stribeck humps
def hump_fraction(speed: np.ndarray, law: Law | None, vs_base: float) -> np.ndarray:
    """The normalised Stribeck hump ``h(|v|)``: 1 at rest, falling to 0 with speed (-).

    ``law`` is the hidden ``stribeck`` law (None: the base curve, Gaussian
    ``exp(-(|v|/vs)^2)``).

    * ``armstrong``, ``low-exponent``: ``h = exp(-(|v|/vs)^delta)`` (Armstrong-Helouvry 1991).
    * ``lorentzian``: ``h = 1/(1 + (|v|/vs)^2)`` (Hess & Soom 1990).
    """
    if law is None:
        vs, delta = vs_base, 2.0
    elif law.shape.name == "lorentzian":
        return 1.0 / (1.0 + (speed / law["vs"]) ** 2)
    else:
        vs, delta = law["vs"], law["delta"]
    return np.exp(-((speed / vs) ** delta))


# ------------------------------------------------------------------ level factors
@dataclass(frozen=True)
class LevelContext:
    """What the level factors may depend on, at the fine-grid nodes (SI).

    Attributes
    ----------
    x, t, S : (n,) m, s, Pa
        Position, time, pressure sum.
    retracting : (n,) bool
        The side the friction acts on: last direction of motion was ``v < 0``.
    stroke, Fc : m, N
        Stroke and base Coulomb level.
    S_mid : Pa
        Reference pressure sum (the pressure laws are 1 there).
    chambers : (p1, p2, p1_mid, p2_mid) or None
        Chamber pressures (Pa) and their values at ``S_mid`` with no net force;
        only for the laws that need them.
    """

    x: np.ndarray
    t: np.ndarray
    S: np.ndarray
    retracting: np.ndarray
    stroke: float
    Fc: float
    S_mid: float
    chambers: tuple[np.ndarray, np.ndarray, float, float] | None = None


def _pressure(law: Law, c: LevelContext) -> np.ndarray:
    """Seal normal force energised by the chamber pressures (Belforte 2003; Nikas 2010).

    * ``lip-seal``: ``(1 + c_p*S)/(1 + c_p*S_mid)``: one lip seal on the pressure sum.
    * ``chamber-weighted``: ``(1 + c_piston*(p1 + p2) + c_rod*p2)/(same at mid)``: the
      piston seal is pressed by both chambers, the rod seal only by the rod chamber.
    * ``saturating``: ``(1 + c_p*p_sat*(1 - exp(-S/p_sat)))/(same at S_mid)``: the lip
      is fully energised above ~``p_sat``.
    """
    name = law.shape.name
    if name == "lip-seal":
        k = law["c_p"]
        return (1.0 + k * c.S) / (1.0 + k * c.S_mid)
    if name == "chamber-weighted":
        assert c.chambers is not None
        p1, p2, p1m, p2m = c.chambers
        cp, cr = law["c_piston"], law["c_rod"]
        return (1.0 + cp * (p1 + p2) + cr * p2) / (1.0 + cp * (p1m + p2m) + cr * p2m)
    k, ps = law["c_p"], law["p_sat"]
    return (1.0 + k * ps * (1.0 - np.exp(-c.S / ps))) / (1.0 + k * ps * (1.0 - math.exp(-c.S_mid / ps)))


def _direction(law: Law, c: LevelContext) -> np.ndarray | None:
    """``levels``: ``(Fc, Fs)*(1 + dF_neg/Fc)`` on the retracting side (the other shapes act
    on the whole friction or on the viscous term, see :func:`whole_factor`, :func:`viscous`)."""
    if law.shape.name != "levels":
        return None
    return np.where(c.retracting, 1.0 + law["dF_neg"] / c.Fc, 1.0)


def _position(law: Law, c: LevelContext) -> np.ndarray:
    """Friction along the stroke.

    * ``bump``: ``1 + a_g*exp(-((x - x_g)/w)^2) + a_l*(x - L/2)/L`` (a tighter bore
      section plus a taper).
    * ``tight-spot``: ``1 + a_t*(1 + cos(2*pi*(x - x_t)/w))/2`` for ``|x - x_t| < w/2``
      (a dent or a burr over ``w`` = 1-4 % of the stroke), exactly 1 elsewhere.
    * ``wear-gradient``: ``1 + a_w*(x - L/2)/L`` (a bore worn more at one end).
    * ``step``: ``1 + a_s*(1 + tanh((x - x_s)/w_edge))/2`` (a worn or damaged zone from
      ``x_s`` to the end of the bore).
    """
    x, L = c.x, c.stroke
    name = law.shape.name
    if name == "bump":
        xg, w = law["x_g_frac"] * L, law["w_frac"] * L
        return 1.0 + law["a_g"] * np.exp(-(((x - xg) / w) ** 2)) + law["a_l"] * (x - 0.5 * L) / L
    if name == "tight-spot":
        u = (x - law["x_t_frac"] * L) / (law["w_frac"] * L)
        return 1.0 + law["a_t"] * np.where(np.abs(u) < 0.5, 0.5 * (1.0 + np.cos(2 * np.pi * u)),
                                            0.0)
    if name == "wear-gradient":
        return 1.0 + law["a_w"] * (x - 0.5 * L) / L
    return 1.0 + law["a_s"] * 0.5 * (1.0 + np.tanh((x - law["x_s_frac"] * L) / law["w_edge"]))


def _ripple(law: Law, c: LevelContext) -> np.ndarray:
    """``1 + A*sin(2*pi*x/wavelength)``: a rod scratch of a few mm wavelength."""
    return 1.0 + law["A"] * np.sin(2 * np.pi * c.x / law["wavelength"])


def _drift(law: Law, c: LevelContext) -> np.ndarray:
    """``1 + beta*(t - t0)/(t_end - t0)``: slow thermal drift over the record."""
    t = c.t
    return 1.0 + law["beta"] * (t - t[0]) / max(t[-1] - t[0], 1e-9)


#: Level-factor laws, in the order they multiply (the original generator's order).
LEVEL_LAWS: dict[str, Callable[[Law, LevelContext], np.ndarray | None]] = {
    "pressure-dependence": _pressure,
    "direction-asymmetry": _direction,
    "position-dependence": _position,
    "ripple": _ripple,
    "drift": _drift,
}


def level_factor(laws: dict[str, Law], c: LevelContext) -> np.ndarray:
    """The product of the hidden effects' level factors at every node (-)."""
    scale = np.ones_like(c.x)
    for effect, fn in LEVEL_LAWS.items():
        if effect in laws:
            f = fn(laws[effect], c)
            if f is not None:
                scale *= f
    return scale


def whole_factor(laws: dict[str, Law], F: np.ndarray) -> np.ndarray:
    """Direction asymmetry ``ratio``: the friction opposing extension (``F > 0``) times
    ``1 + dr_ext`` (continuous: the factor switches where the friction crosses zero)."""
    law = laws.get("direction-asymmetry")
    if law is None or law.shape.name != "ratio":
        return F
    return F * np.where(F > 0.0, 1.0 + law["dr_ext"], 1.0)


# ------------------------------------------------------------------ viscous terms
def viscous(laws: dict[str, Law], coefficient: float, vn: np.ndarray) -> np.ndarray:
    """Viscous friction at the node velocities ``vn`` (N).

    ``coefficient*v`` (the base's ``sigma2``) plus, when hidden,

    * ``viscous`` ``linear``: ``+ c_v*v``;
    * ``viscous`` ``power``: ``+ c_v*v_ref*(|v|/v_ref)^n*s``: a shear-thinning (power-law)
      film, equal to the linear law at ``v_ref`` (0.05 m/s, within the record's speeds);
    * ``direction-asymmetry`` ``viscous``: ``+ c_neg*v`` for ``v < 0`` only.
    """
    visc = linear_viscous(laws, coefficient)
    F = visc * vn
    law = laws.get("viscous")
    if law is not None and law.shape.name == "power":
        vr = law["v_ref"]
        F = F + law["c_v"] * vr * np.abs(vn / vr) ** law["n"] * np.sign(vn)
    law = laws.get("direction-asymmetry")
    if law is not None and law.shape.name == "viscous":
        F = F + law["c_neg"] * np.minimum(vn, 0.0)
    return F


def linear_viscous(laws: dict[str, Law], coefficient: float) -> float:
    """The linear viscous coefficient: the base's plus a hidden ``linear`` one (Ns/m)."""
    law = laws.get("viscous")
    if law is not None and law.shape.name == "linear":
        return coefficient + law["c_v"]
    return coefficient


# ------------------------------------------------------------------ dwell excess
def dwell_law(law: Law) -> Callable[[float], float]:
    """Excess of the static level after a rest of ``t_d`` seconds (N), by shape.

    * ``kato*``: ``dF_inf*(1 - exp(-(t_d/tau_k)^m))`` (Kato et al. 1972).
    * ``dieterich``: ``min(dF_log*ln(1 + t_d/tau_d), dF_max)`` (Dieterich 1972), capped
      where the contact is fully aged.
    """
    if law.shape.name == "dieterich":
        a, tau, cap = law["dF_log"], law["tau_d"], law["dF_max"]
        return lambda t_d: min(a * math.log1p(t_d / tau), cap)
    dF, tau, m = law["dF_inf"], law["tau_k"], law["m"]
    return lambda t_d: dF * (1.0 - math.exp(-((t_d / tau) ** m)))


# ------------------------------------------------------------------ recording errors
def ringing(law: Law, t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """A lightly damped rig mode rung by every start from rest (N), at the nodes ``t``.

    ``F_r*exp(-zeta*w*tau)*sin(w_d*tau)``, ``w = 2*pi*f_r``, ``w_d = w*sqrt(1 - zeta^2)``,
    ``tau`` the time since the start (the impulse response of a second-order mode).
    ``v`` per fine interval: a start is an interval that moves after one that did not.
    """
    w = 2 * np.pi * law["f_r"]
    zeta = law["zeta"]
    wd = w * math.sqrt(1.0 - zeta * zeta)
    moving = v != 0.0
    starts = np.flatnonzero(moving & ~np.concatenate([[False], moving[:-1]]))
    span = 12.0 / (zeta * w)  # the ring has decayed to 6e-6 of its amplitude
    out = np.zeros_like(t)
    for i in starts:
        j = int(np.searchsorted(t, t[i] + span))
        tau = t[i:j] - t[i]
        out[i:j] += law["F_r"] * np.exp(-zeta * w * tau) * np.sin(wd * tau)
    return out


def recording_errors(laws: dict[str, Law], t: np.ndarray, v: np.ndarray, an: np.ndarray,
                     mass: float) -> tuple[list[np.ndarray | float], list[np.ndarray]]:
    """Terms the recorded force carries besides the friction (N), split by where they act.

    Returns ``(channel, physical)``:

    * ``channel``: errors of the force channel, absent from the piston's force balance:
      ``inertia-error`` ``dm*a`` (the sidecar mass is ``m - dm``) and ``force-offset``
      ``constant`` (a sensor zero error);
    * ``physical``: forces that really act on the piston but are not friction:
      ``force-offset`` ``tilt`` (``m*g*sin(angle)``, gravity along an undeclared
      inclination) and ``ringing``.
    """
    channel: list[np.ndarray | float] = []
    physical: list[np.ndarray] = []
    if "inertia-error" in laws:
        channel.append(laws["inertia-error"]["dm"] * an)
    law = laws.get("force-offset")
    if law is not None:
        if law.shape.name == "constant":
            channel.append(law["offset"])
        else:
            physical.append(np.full(t.size, mass * G * math.sin(law["angle"])))
    if "ringing" in laws:
        physical.append(ringing(laws["ringing"], t, v))
    return channel, physical
