"""Independent plain implementations of the plants, for tests and the benchmark.

Written straight from models.md (sections 1.3-1.5, 3.1-3.5) and the choices
the plant modules document (orifice regularisation ``dp_lam``, ISO 6358
form with laminar end ``r_lam``, cavitation floor, end stops), in plain
Python floats, without importing any equation of the package: only the
parameter *numbers* are read from the TOML copies carried in the package.
Integrated with :func:`scipy.integrate.solve_ivp` (Radau) at tight
tolerance they are the reference the engine is checked against; the
benchmark times the same right-hand sides as the "plain solve_ivp" baseline.

State vectors (SI, pressures absolute):

* hydraulic: ``[x, v, p1, p2, xv, vv, z, h]`` with NMLGM friction
  (``[..., z]`` with LuGre);
* pneumatic: ``[x, v, p1, p2, xs, z, h]`` with NMLGM friction;
* presliding-rig: ``[x, v, p1, p2, z, h]`` with NMLGM friction;
* force-rig: ``[x, v, z]`` with LuGre friction.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from fcomp.paramsets import get as get_paramset

G = 9.80665
P_ATM = 101325.0
ORIENT = {"horizontal": 0.0, "vertical-up": 1.0, "vertical-down": -1.0}


# ------------------------------------------------------------------ friction
@dataclass
class Friction:
    """LuGre-family parameters (magnitudes; ``pos``/``neg`` pairs as tuples)."""

    Fc: tuple[float, float]
    Fs: tuple[float, float]
    vs: tuple[float, float]
    n: tuple[float, float]
    sigma2: tuple[float, float]
    sigma0: float
    sigma1: float
    vb: tuple[float, float] = (math.inf, math.inf)
    tau_hp: float = 0.02
    tau_hn: float = 0.12
    tau_h0: float = 10.0
    T: float = 0.0
    v_eps: float = 1e-5
    film: bool = True  # film-lag state h present (NMLGM / modified LuGre)

    @classmethod
    def from_toml(cls, sec: dict, film: bool = True) -> Friction:
        def pair(key: str, default: float | None = None) -> tuple[float, float]:
            val = sec.get(key, default)
            if isinstance(val, dict):
                return (abs(val["pos"]), abs(val["neg"]))
            return (float(val), float(val))  # type: ignore[arg-type]

        return cls(Fc=pair("Fc"), Fs=pair("Fs"), vs=pair("vs"), n=pair("n"),
                   sigma2=pair("sigma2"), sigma0=float(sec["sigma0"]),
                   sigma1=float(sec["sigma1"]), vb=pair("vb", math.inf) if film else
                   (math.inf, math.inf), tau_hp=float(sec.get("tau_hp", 0.02)),
                   tau_hn=float(sec.get("tau_hn", 0.12)), tau_h0=float(sec.get("tau_h0", 10.0)),
                   T=float(sec.get("T", 0.0)) if film else 0.0,
                   v_eps=float(sec.get("v_eps", 1e-5)), film=film)

    @property
    def n_states(self) -> int:
        return 2 if self.film else 1

    def parts(self, v: float, zs: list[float]) -> tuple[list[float], float, float]:
        """``(dz/dt, dh/dt)``, ``F0`` and ``c_a`` of models.md 1.3-1.5 (``F = F0 + c_a*a``)."""
        i = 1 if v < 0 else 0
        Fc, Fs, vs, n, s2 = self.Fc[i], self.Fs[i], self.vs[i], self.n[i], self.sigma2[i]
        z = zs[0]
        av = abs(v)
        if self.film:
            h = zs[1]
            r = min(av / self.vb[i], 1.0)
            hss = (1.0 - Fc / Fs) * r ** (2.0 / 3.0)
        else:
            h = hss = 0.0
        g = Fc + ((1.0 - h) * Fs - Fc) * math.exp(-((av / vs) ** n))
        dz = v - self.sigma0 * av * z / g
        F0 = self.sigma0 * z + self.sigma1 * dz + s2 * v
        out = [dz]
        if self.film:
            if av < self.v_eps:
                tau = self.tau_h0
            elif h <= hss:
                tau = self.tau_hp
            else:
                tau = self.tau_hn
            out.append((hss - h) / tau)
        return out, F0, s2 * self.T


def stop_force(x: float, v: float, m: float, stroke: float, k: float = 1e8,
               zeta: float = 0.7) -> float:
    """Spring-damper end stops that only push (plants/mechanics.py docstring)."""
    c = 2.0 * zeta * math.sqrt(k * m)
    if x < 0.0:
        return max(0.0, -k * x - c * v)
    if x > stroke:
        return min(0.0, -k * (x - stroke) - c * v)
    return 0.0


# ----------------------------------------------------------------- hydraulic
@dataclass
class Hydraulic:
    """Seed 002 servo (models.md 3.2) from ``hydraulic-seed002.toml``."""

    fr: Friction
    m: float
    D: float
    d: float
    L: float
    s: float
    kv: float
    wv: float
    zv: float
    cd: float
    w: float
    U: float
    beta: float
    rho: float
    pmin: float
    V10: float
    V20: float
    ps: float
    pt: float
    dp_lam: float = 1e3

    @classmethod
    def seed002(cls, model: str = "nmlgm") -> Hydraulic:
        raw = get_paramset("seed002-type1").raw
        sv, fl, cy, su, lo = (raw[k] for k in ("servo_valve", "fluid", "cylinder", "supply",
                                                "load"))
        fr = Friction.from_toml(raw["friction"][model], film=(model == "nmlgm"))
        return cls(fr, lo["mass"], cy["bore"], cy["rod"], cy["stroke"], ORIENT[lo["orientation"]],
                   sv["kv"], sv["omega_v"], sv["zeta_v"], sv["cd"], sv["w"], sv["underlap"],
                   fl["beta"], fl["rho"], fl["p_min"], cy["V10"], cy["V20"], su["ps"], su["pt"])

    def x0(self) -> list[float]:
        pm = 0.5 * (self.ps + self.pt)
        return [self.L / 2, 0.0, pm, pm, 0.0, 0.0] + [0.0] * self.fr.n_states

    def q(self, opening: float, dp: float) -> float:
        """Orifice flow (m^3/s) with the documented laminar transition."""
        return (self.cd * self.w * max(opening, 0.0) * math.sqrt(2.0 / self.rho) * dp
                / (dp * dp + self.dp_lam ** 2) ** 0.25)

    def flows(self, y: list[float]) -> tuple[float, float, list[float]]:
        xv = y[4]
        p1, p2 = max(y[2], self.pmin), max(y[3], self.pmin)
        e = [self.q(self.U + xv, self.ps - p1), self.q(self.U - xv, p1 - self.pt),
             self.q(self.U - xv, self.ps - p2), self.q(self.U + xv, p2 - self.pt)]
        return e[0] - e[1], e[2] - e[3], e

    def rhs(self, t: float, y: list[float], u: Callable[[float], float]) -> list[float]:
        x, v, _, _, xv, vv = y[:6]
        A1 = math.pi / 4 * self.D ** 2
        A2 = math.pi / 4 * (self.D ** 2 - self.d ** 2)
        p1, p2 = max(y[2], self.pmin), max(y[3], self.pmin)
        Q1, Q2, _ = self.flows(y)
        V1 = self.V10 + A1 * x
        V2 = self.V20 + A2 * (self.L - x)
        dp1 = self.beta / V1 * (Q1 - A1 * v)
        dp2 = self.beta / V2 * (Q2 + A2 * v)
        if y[2] <= self.pmin:
            dp1 = max(dp1, 0.0)
        if y[3] <= self.pmin:
            dp2 = max(dp2, 0.0)
        dvv = self.wv ** 2 * (self.kv * u(t) - xv) - 2 * self.zv * self.wv * vv
        dfr, F0, ca = self.fr.parts(v, y[6:])
        Fp = p1 * A1 - p2 * A2 - P_ATM * (A1 - A2)
        Fa = Fp - self.m * G * self.s + stop_force(x, v, self.m, self.L)
        a = (Fa - F0) / (self.m + ca)
        return [v, a, dp1, dp2, vv, dvv, *dfr]


# ----------------------------------------------------------------- pneumatic
@dataclass
class Pneumatic:
    """Pneumatic servo (models.md 3.3) from ``pneumatic-seed000.toml`` ``[servo]``."""

    fr: Friction
    m: float
    D: float
    d: float
    L: float
    ps: float
    V10: float
    V20: float
    k: float
    Av: float
    lap: float
    tau: float
    umax: float
    R: float
    T: float
    gam: float
    b: float
    r_lam: float = 0.999

    @classmethod
    def seed000(cls) -> Pneumatic:
        raw = get_paramset("seed000-servo").raw
        sv, air = raw["servo"], raw["air"]
        cyl = raw["cylinder"][str(sv["cylinder"])]
        fr = Friction.from_toml(raw["friction"][str(sv["cylinder"])])
        return cls(fr, cyl["mass"] + sv["load_mass"], cyl["bore"], cyl["rod"], cyl["stroke"],
                   sv["ps"], sv["V10"], sv["V20"], sv["polytropic"], sv["valve_area_max"],
                   sv["valve_underlap"], sv["valve_tau"], sv["u_max"], air["R"], air["T"],
                   air["gamma"], air["critical_ratio"])

    def x0(self) -> list[float]:
        pm = 0.5 * (self.ps + P_ATM)
        return [self.L / 2, 0.0, pm, pm, 0.0] + [0.0] * self.fr.n_states

    def mdot(self, pa: float, pb: float, area: float) -> float:
        """ISO 6358 mass flow from ``pa`` to ``pb`` with the ideal-nozzle conductance."""
        up, dn = max(pa, pb), min(pa, pb)
        r = dn / up
        psi = math.sqrt(self.gam * (2 / (self.gam + 1)) ** ((self.gam + 1) / (self.gam - 1)))

        def ell(q: float) -> float:
            return math.sqrt(max(1 - ((q - self.b) / (1 - self.b)) ** 2, 0.0))

        if r <= self.b:
            phi = 1.0
        elif r < self.r_lam:
            phi = ell(r)
        else:
            phi = ell(self.r_lam) * (1 - r) / (1 - self.r_lam)
        q = area * psi * up / math.sqrt(self.R * self.T) * phi
        return q if pa >= pb else -q

    def flows(self, y: list[float]) -> tuple[float, float]:
        p1, p2, xs = y[2], y[3], y[4]
        oa = self.Av * min(max(self.lap + xs, 0.0), 1.0)
        ob = self.Av * min(max(self.lap - xs, 0.0), 1.0)
        m1 = self.mdot(self.ps, p1, oa) - self.mdot(p1, P_ATM, ob)
        m2 = self.mdot(self.ps, p2, ob) - self.mdot(p2, P_ATM, oa)
        return m1, m2

    def rhs(self, t: float, y: list[float], u: Callable[[float], float]) -> list[float]:
        x, v, p1, p2, xs = y[:5]
        A1 = math.pi / 4 * self.D ** 2
        A2 = math.pi / 4 * (self.D ** 2 - self.d ** 2)
        m1, m2 = self.flows(y)
        V1 = self.V10 + A1 * x
        V2 = self.V20 + A2 * (self.L - x)
        RT = self.R * self.T
        dp1 = self.k / V1 * (RT * m1 - p1 * A1 * v)
        dp2 = self.k / V2 * (RT * m2 + p2 * A2 * v)
        dxs = (min(max(u(t) / self.umax, -1.0), 1.0) - xs) / self.tau
        dfr, F0, ca = self.fr.parts(v, y[5:])
        Fa = p1 * A1 - p2 * A2 - P_ATM * (A1 - A2) + stop_force(x, v, self.m, self.L)
        a = (Fa - F0) / (self.m + ca)
        return [v, a, dp1, dp2, dxs, *dfr]


# ------------------------------------------------------------ presliding rig
@dataclass
class PreslidingRig:
    """Seed 000 pre-sliding rig (models.md 3.4), cylinder 1."""

    fr: Friction
    m: float
    D: float
    d: float
    L: float
    p_rated: float
    u_full: float
    tau_p: float
    ps_g: float

    @classmethod
    def seed000(cls) -> PreslidingRig:
        raw = get_paramset("seed000-cylinder1").raw
        cyl, rig = raw["cylinder"]["1"], raw["presliding_rig"]
        return cls(Friction.from_toml(raw["friction"]["1"]), cyl["mass"], cyl["bore"],
                   cyl["rod"], cyl["stroke"], rig["valve_rated_pressure"],
                   rig["valve_input_max"], rig["tau_p"], rig["ps"])

    def x0(self) -> list[float]:
        """Balanced piston: p2 at half the supply, p1*A1 = p2*A2 in gauge."""
        p2 = 0.5 * self.ps_g
        p1 = p2 * (self.D ** 2 - self.d ** 2) / self.D ** 2
        return [self.L / 2, 0.0, P_ATM + p1, P_ATM + p2] + [0.0] * self.fr.n_states

    def rhs(self, t: float, y: list[float], u: Callable[[float], tuple[float, float]]
            ) -> list[float]:
        x, v, p1, p2 = y[:4]
        A1 = math.pi / 4 * self.D ** 2
        A2 = math.pi / 4 * (self.D ** 2 - self.d ** 2)
        u1, u2 = u(t)

        def pset(c: float) -> float:
            return P_ATM + min(self.p_rated * min(max(c / self.u_full, 0.0), 1.0), self.ps_g)

        dfr, F0, ca = self.fr.parts(v, y[4:])
        Fa = p1 * A1 - p2 * A2 - P_ATM * (A1 - A2) + stop_force(x, v, self.m, self.L)
        a = (Fa - F0) / (self.m + ca)
        return [v, a, (pset(u1) - p1) / self.tau_p, (pset(u2) - p2) / self.tau_p, *dfr]


# ----------------------------------------------------------------- force rig
@dataclass
class ForceRig:
    """Seed 001 rig (models.md 3.5): ``m*dv/dt = F_ext - F``."""

    fr: Friction
    m: float
    L: float

    def x0(self) -> list[float]:
        return [self.L / 2, 0.0] + [0.0] * self.fr.n_states

    def rhs(self, t: float, y: list[float], u: Callable[[float], float]) -> list[float]:
        x, v = y[:2]
        dfr, F0, ca = self.fr.parts(v, y[2:])
        a = (u(t) - F0 + stop_force(x, v, self.m, self.L)) / (self.m + ca)
        return [v, a, *dfr]


# -------------------------------------------------------------------- solver
def held_input(t: np.ndarray, U: np.ndarray) -> Callable[[float], float]:
    """The input linearly interpolated between samples (the engine's ``hold="linear"``)."""
    return lambda tq: float(np.interp(tq, t, U))


def reference(rhs: Callable, y0: list[float], t: np.ndarray, *, rtol: float = 1e-10,
              atol: np.ndarray | float = 1e-12, method: str = "Radau") -> np.ndarray:
    """``solve_ivp`` of a plain right-hand side ``rhs(t, y)`` on the grid ``t``: ``(len(t), n)``."""
    sol = solve_ivp(rhs, (t[0], t[-1]), y0, method=method, t_eval=t, rtol=rtol, atol=atol)
    if sol.status != 0:
        raise RuntimeError(f"reference integration failed: {sol.message}")
    return sol.y.T
