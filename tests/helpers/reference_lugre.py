"""An independent plain-Python implementation of the LuGre family, for the tests only.

Written directly from the equations (design/models.md sections 1.1-1.5;
Canudas de Wit, Olsson, Astrom, Lischinsky, "A new model for control of
systems with friction", IEEE TAC 40(3), 1995, Eqs. (1)-(4)) with ``math``
scalars, and integrated with SciPy's Radau at ``rtol = 1e-10``. It imports
nothing from ``fcomp``: the tests compare the package against it, so an
error in the package's equations or in its integration scheme shows up as
a disagreement instead of being reproduced.

SI units throughout: m, m/s, N, N/m, Ns/m, s, kg.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

RTOL = 1e-10


def sign(v: float) -> float:
    """``sign(v)`` with ``sign(0) = 0``."""
    return 1.0 if v > 0 else (-1.0 if v < 0 else 0.0)


# ----------------------------------------------------------------- static maps
def coulomb(v: float, Fc: float) -> float:
    """``F = Fc*sign(v)`` (models.md 1.1)."""
    return Fc * sign(v)


def coulomb_viscous(v: float, Fc: float, B: float) -> float:
    """``F = Fc*sign(v) + B*v`` (seed 001 Eq. 4)."""
    return Fc * sign(v) + B * v


def film_ss(v: float, Fc: float, Fs: float, vb: float) -> float:
    """``h_ss = Kf*min(|v|, vb)^(2/3)``, ``Kf = (1 - Fc/Fs)*vb^(-2/3)`` (seed 002 Eqs. 10-11)."""
    if math.isinf(vb):
        return 0.0
    Kf = (1.0 - Fc / Fs) * vb ** (-2.0 / 3.0)
    return Kf * min(abs(v), vb) ** (2.0 / 3.0)


def stribeck_map(
    v: float, Fc: float, Fs: float, vs: float, n: float, sigma2: float, vb: float = math.inf
) -> float:
    """Stribeck steady state (seed 002 Eq. 12, seed 000 Eq. 9).

    ``F = sign(v)*(Fc + ((1 - h_ss)*Fs - Fc)*exp(-(|v|/vs)^n)) + sigma2*v``.
    """
    h = film_ss(v, Fc, Fs, vb)
    return sign(v) * (Fc + ((1.0 - h) * Fs - Fc) * math.exp(-((abs(v) / vs) ** n))) + sigma2 * v


# ---------------------------------------------------------------------- LuGre
@dataclass(frozen=True)
class LuGreRef:
    """LuGre (Canudas de Wit et al. 1995; models.md 1.3), symmetric parameters."""

    Fc: float
    Fs: float
    vs: float
    n: float
    sigma0: float
    sigma1: float
    sigma2: float

    def g(self, v: float) -> float:
        """``g(v) = Fc + (Fs - Fc)*exp(-(|v|/vs)^n)`` (N)."""
        return self.Fc + (self.Fs - self.Fc) * math.exp(-((abs(v) / self.vs) ** self.n))

    def zdot(self, z: float, v: float) -> float:
        """``dz/dt = v - sigma0*|v|*z/g(v)`` (m/s)."""
        return v - self.sigma0 * abs(v) * z / self.g(v)

    def friction(self, z: float, v: float) -> float:
        """``F = sigma0*z + sigma1*dz/dt + sigma2*v`` (N)."""
        return self.sigma0 * z + self.sigma1 * self.zdot(z, v) + self.sigma2 * v

    def steady(self, v: float) -> float:
        """Constant-velocity force ``sign(v)*g(v) + sigma2*v`` (N)."""
        return sign(v) * self.g(v) + self.sigma2 * v

    def zdot_partials(self, z: float, v: float) -> tuple[float, float]:
        """``(d(dz/dt)/dz, d(dz/dt)/dv)`` by hand (for the integrator's Newton iterations).

        ``|v|`` has a kink at ``v = 0``; within ``|v| < 1e-12`` m/s the mean of
        the two one-sided slopes is returned so that Newton's method does not
        flip between them while the mass rests (accuracy is unaffected: the
        Jacobian only steers the iterations).
        """
        if abs(v) < 1e-12:
            v = 0.0
        g = self.g(v)
        r = abs(v) / self.vs
        slope = self.n * r ** (self.n - 1) / self.vs if r > 0 else 0.0
        dg = -(self.Fs - self.Fc) * math.exp(-(r**self.n)) * slope  # dg/d|v|
        dz_dz = -self.sigma0 * abs(v) / g
        dz_dv = 1.0 - self.sigma0 * z * sign(v) * (g - abs(v) * dg) / g**2
        return dz_dz, dz_dv


#: Table I of Canudas de Wit et al. (1995), unit mass.
CANUDAS = LuGreRef(Fc=1.0, Fs=1.5, vs=1e-3, n=2.0, sigma0=1e5, sigma1=math.sqrt(1e5), sigma2=0.4)


# ------------------------------------------------------- modified LuGre / NMLGM
@dataclass(frozen=True)
class FilmLuGreRef:
    """Modified LuGre / NMLGM with the film state ``h`` (models.md 1.4-1.5).

    ``params`` maps each name to a number or to ``(value for v > 0, value
    for v < 0)`` (magnitudes). ``T = 0`` is the modified LuGre model.
    """

    params: dict[str, float | tuple[float, float]] = field(default_factory=dict)

    def p(self, name: str, s: float) -> float:
        val = self.params[name]
        if isinstance(val, tuple):
            return abs(val[0]) if s > 0 else abs(val[1])
        return float(val)

    def h_ss(self, v: float, s: float) -> float:
        return film_ss(v, self.p("Fc", s), self.p("Fs", s), self.p("vb", s))

    def g(self, v: float, h: float, s: float) -> float:
        """``g(v, h) = Fc + ((1 - h)*Fs - Fc)*exp(-(|v|/vs)^n)``."""
        Fc, Fs = self.p("Fc", s), self.p("Fs", s)
        return Fc + ((1.0 - h) * Fs - Fc) * math.exp(-((abs(v) / self.p("vs", s)) ** self.p("n", s)))

    def tau_h(self, v: float, h: float, s: float) -> float:
        """``tau_h0`` if ``|v| < v_eps``, else ``tau_hp`` if ``h <= h_ss`` else ``tau_hn``."""
        if abs(v) < self.p("v_eps", s):
            return self.p("tau_h0", s)
        return self.p("tau_hp", s) if h <= self.h_ss(v, s) else self.p("tau_hn", s)

    def rates(self, z: float, h: float, v: float, s: float) -> tuple[float, float]:
        """``(dz/dt, dh/dt)``."""
        dz = v - self.p("sigma0", s) * abs(v) * z / self.g(v, h, s)
        dh = (self.h_ss(v, s) - h) / self.tau_h(v, h, s)
        return dz, dh

    def friction(self, z: float, h: float, v: float, a: float, s: float) -> float:
        """``F = sigma0*z + sigma1*dz/dt + sigma2*(v + T*a)``."""
        dz, _ = self.rates(z, h, v, s)
        T = self.p("T", s) if "T" in self.params else 0.0
        return (self.p("sigma0", s) * z + self.p("sigma1", s) * dz
                + self.p("sigma2", s) * (v + T * a))

    def steady(self, v: float) -> float:
        """Constant-velocity force ``sign(v)*g(v, h_ss(v)) + sigma2*v``."""
        s = 1.0 if v >= 0 else -1.0
        return sign(v) * self.g(v, self.h_ss(v, s), s) + self.p("sigma2", s) * v


# ---------------------------------------------------------------- integration
@dataclass
class Trajectory:
    """A reference solution: ``y[:, k]`` is the state at ``t[k]``; ``sol`` its dense output."""

    t: np.ndarray
    y: np.ndarray
    sol: Callable[[np.ndarray], np.ndarray]


Rhs = Callable[[float, np.ndarray], Sequence[float]]
Jac = Callable[[float, np.ndarray], np.ndarray]


def solve_radau(
    fun: Rhs | Sequence[Rhs],
    t_span: tuple[float, float],
    y0: Sequence[float],
    t_eval: np.ndarray,
    atol: Sequence[float],
    breaks: Sequence[float] = (),
    max_step: float = math.inf,
    jac: Jac | Sequence[Jac | None] | None = None,
) -> Trajectory:
    """Radau at ``rtol = 1e-10``, restarted at every break point.

    ``breaks`` are the kinks or jumps of the input. ``fun`` (and ``jac``) is
    one right-hand side, or one per piece between consecutive break points:
    an input that *jumps* at a break must use the latter, since the
    integrator evaluates each piece at both of its ends.
    """
    edges = sorted({t_span[0], t_span[1], *[b for b in breaks if t_span[0] < b < t_span[1]]})
    n = len(edges) - 1
    funs = list(fun) if isinstance(fun, Sequence) else [fun] * n
    jacs = list(jac) if isinstance(jac, Sequence) else [jac] * n
    if len(funs) != n or len(jacs) != n:
        raise ValueError(f"{n} pieces but {len(funs)} right-hand sides / {len(jacs)} Jacobians")
    y = np.asarray(y0, dtype=float)
    pieces = []
    t_eval = np.asarray(t_eval, dtype=float)
    out = np.empty((y.size, t_eval.size))
    for a, b, f, J in zip(edges[:-1], edges[1:], funs, jacs, strict=True):
        sol = solve_ivp(f, (a, b), y, method="Radau", rtol=RTOL, atol=np.asarray(atol),
                        dense_output=True, max_step=max_step, jac=J)
        if not sol.success:
            raise RuntimeError(f"reference integration failed on [{a}, {b}]: {sol.message}")
        mask = (t_eval >= a) & (t_eval <= b)
        out[:, mask] = sol.sol(t_eval[mask])
        pieces.append((a, b, sol.sol))
        y = sol.y[:, -1]

    def dense(tq: np.ndarray) -> np.ndarray:
        tq = np.atleast_1d(np.asarray(tq, dtype=float))
        res = np.empty((y.size, tq.size))
        for a, b, f in pieces:
            m = (tq >= a) & (tq <= b)
            res[:, m] = f(tq[m])
        return res

    return Trajectory(t_eval, out, dense)


def mass_with_force(
    p: LuGreRef,
    u: Callable[[float, float], float],
    t_eval: np.ndarray,
    *,
    du_dx: float = 0.0,
    mass: float = 1.0,
    y0: Sequence[float] = (0.0, 0.0, 0.0),
    breaks: Sequence[float] = (),
    max_step: float = math.inf,
) -> Trajectory:
    """A mass under an applied force and LuGre friction: ``m*x'' = u(t, x) - F``.

    State ``[x, v, z]``; ``u(t, x)`` is the applied force (N), ``du_dx`` its
    (constant) slope in ``x``, for the hand-written Jacobian.
    """

    def fun(t: float, y: np.ndarray) -> list[float]:
        x, v, z = y
        dz = p.zdot(z, v)
        F = p.sigma0 * z + p.sigma1 * dz + p.sigma2 * v
        return [v, (u(t, x) - F) / mass, dz]

    def jac(t: float, y: np.ndarray) -> np.ndarray:
        _, v, z = y
        dz_dz, dz_dv = p.zdot_partials(z, v)
        dF_dv = p.sigma1 * dz_dv + p.sigma2
        dF_dz = p.sigma0 + p.sigma1 * dz_dz
        return np.array([[0.0, 1.0, 0.0],
                         [du_dx / mass, -dF_dv / mass, -dF_dz / mass],
                         [0.0, dz_dv, dz_dz]])

    return solve_radau(fun, (float(t_eval[0]), float(t_eval[-1])), y0, t_eval,
                       atol=(1e-14, 1e-14, 1e-19), breaks=breaks, max_step=max_step, jac=jac)


def stick_slip(
    p: LuGreRef, t_eval: np.ndarray, *, k: float = 2.0, vy: float = 0.1, mass: float = 1.0
) -> Trajectory:
    """Canudas et al. (1995) stick-slip: ``m*x'' = k*(y - x) - F``, ``y = vy*t``."""
    return mass_with_force(p, lambda t, x: k * (vy * t - x), t_eval, du_dx=-k, mass=mass)


def along_velocity(
    p: LuGreRef | FilmLuGreRef,
    v: Callable[[float], float],
    t_eval: np.ndarray,
    *,
    y0: Sequence[float] | None = None,
    side: Callable[[float], float] | None = None,
    breaks: Sequence[float] = (),
    max_step: float = math.inf,
) -> Trajectory:
    """The friction states along a prescribed velocity ``v(t)``.

    LuGre: state ``[z]``; film models: ``[z, h]`` with the side ``side(t)``
    (default ``+1`` for ``v >= 0``, else ``-1``).
    """
    if isinstance(p, LuGreRef):
        def fun(t: float, y: np.ndarray) -> list[float]:
            return [p.zdot(y[0], v(t))]

        def jac(t: float, y: np.ndarray) -> np.ndarray:
            return np.array([[p.zdot_partials(y[0], v(t))[0]]])

        return solve_radau(fun, (float(t_eval[0]), float(t_eval[-1])), y0 or (0.0,), t_eval,
                           atol=(1e-19,), breaks=breaks, max_step=max_step, jac=jac)

    sfun = side or (lambda t: 1.0 if v(t) >= 0 else -1.0)

    def fun2(t: float, y: np.ndarray) -> list[float]:
        return list(p.rates(y[0], y[1], v(t), sfun(t)))

    return solve_radau(fun2, (float(t_eval[0]), float(t_eval[-1])), y0 or (0.0, 0.0), t_eval,
                       atol=(1e-19, 1e-14), breaks=breaks, max_step=max_step)
