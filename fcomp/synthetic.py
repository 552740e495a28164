"""Synthetic rig measurements with hidden effects: the test bench of the diagnosis.

The generator is *independent* of the code it tests: it never imports
:mod:`fcomp.models` or :mod:`fcomp.effects` and integrates its own truth
friction on a fine time grid, driven by an analytic motion. Where an effect
admits several laws it deliberately uses a *different* functional form from
the package's (the column "truth law" below), so a diagnosis that finds the
effect is finding the physics, not its own equations.

Truth friction (SI units; ``s = sign(v)``, levels ``Fc``, ``Fs`` in N)
------------------------------------------------------------------------
``base = "coulomb"``
    ``F = Fc*s`` (``s = tanh(v/1e-5)``: a smooth sign, ``F = 0`` at rest).
``base = "coulomb-viscous"``
    ``F = Fc*s + sigma2*v`` (seed 001 Eq. 4).
``base = "stribeck"``
    ``F = s*(Fc + (Fs - Fc)*exp(-(|v|/vs)^2)) + sigma2*v`` (models.md 1.1).
``base = "lugre"``
    bristle state ``dz/dt = v - sigma0*|v|*z/g``, ``F = sigma0*z + sigma1*dz/dt
    + sigma2*v`` with ``g`` the Stribeck curve above (Canudas de Wit et al.
    1995, models.md 1.3).

Hidden effects (names of models.md 1.8, plus two that are outside it):

=======================  ====================================================
effect                   truth law used here
=======================  ====================================================
``viscous``              ``+ c_v*v``
``stribeck``             hump ``(Fs - Fc)*exp(-(|v|/vs)^1.4)`` (Armstrong's exponent
                         form with ``delta = 1.4``, not the package's default 2)
``presliding``           bristle compliance ``dz/dt = v - k*|v|*z/g``, ``F = k*z``
                         on a static map
``nonlocal-memory``      classical Maxwell-slip: ``N`` elasto-slide elements of
                         stiffness ``k_i`` and slip force ``f_i`` (Lampaert et al. 2002)
                         replacing the bristle
``frictional-lag``       Hess-Soom time lag: the Stribeck hump is evaluated at a
                         lagged speed ``dv_L/dt = (|v| - v_L)/tau_L``
``dwell-time``           Kato law on the *measured* dwell time ``t_d``:
                         ``dFs(t_d) = dF_inf*(1 - exp(-(t_d/tau_k)^m))`` added to the
                         static level ``Fs``, erased over the distance slid since the
                         start, ``exp(-s/d_c)`` (not an ageing state)
``direction-asymmetry``  for ``v < 0`` the levels ``Fc, Fs`` are ``dF_neg`` newtons higher
                         and the hump scales with them: ``(Fc, Fs)*(1 + dF_neg/Fc)``
``pressure-dependence``  seal friction proportional to the normal force of a lip seal
                         energised by pressure: ``(Fc, Fs)*(1 + c_p*(p1 + p2))/(1 +
                         c_p*p_mid)`` (referenced to zero gauge pressure)
``position-dependence``  levels times ``1 + a_g*exp(-((x - x_g)/w)^2) + a_l*(x - x_mid)/L``
``viscous-lead``         ``+ sigma2*T*a`` (NMLGM lead, seed 000 Eq. 8)
``inertia-error``        the recorded force carries ``dm*a`` (the sidecar mass is wrong)
``force-offset``         a constant ``+ offset`` on the recorded force
``ripple`` (outside)     levels times ``1 + A*sin(2*pi*x/lambda)``: a rod scratch of
                         wavelength a few mm that no catalogue entry explains
``drift`` (outside)      levels times ``1 + beta*t/t_end``: slow thermal drift
=======================  ====================================================

Measurement: ``t`` (s), ``x`` quantised to the encoder resolution (m), gauge
``p1``, ``p2`` (Pa) from the force balance ``p1*A1 - p2*A2 = F + m*a`` at the
pressure-sum level of each experiment (plus sensor noise), the recorded
friction force ``F`` (N) with coloured AR(1) noise, an ``experiment`` column;
``v`` only with ``include_velocity=True``. The truth is returned separately
(:class:`SyntheticTruth`) and never written to the sidecar.

Motions (per experiment, seeded): smooth slides at speeds spread over two
decades, reversals with and without a stop, dwells from 0.05 s to 3 s,
small displacement loops (presliding), sinusoidal sweeps, and a pressure
change in the middle of each experiment.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fcomp.errors import FcompError
from fcomp.measurement import Measurement

#: Bases the generator can simulate.
BASES = ("coulomb", "coulomb-viscous", "stribeck", "lugre")

#: Default law parameters of each hidden effect (SI units).
HIDDEN_DEFAULTS: dict[str, dict[str, float]] = {
    "viscous": {"c_v": 80.0},
    "stribeck": {"dF": 15.0, "vs": 0.012, "delta": 1.4},
    "presliding": {"k": 1.5e5},
    "nonlocal-memory": {"n_elements": 6.0, "d_max": 4e-4},
    "frictional-lag": {"tau_L": 0.06},
    "dwell-time": {"dF_inf": 40.0, "tau_k": 0.5, "m": 1.0, "d_c": 5e-4},
    "direction-asymmetry": {"dF_neg": 8.0},
    "pressure-dependence": {"c_p": 4e-6},
    "position-dependence": {"a_g": 0.25, "x_g_frac": 0.3, "w_frac": 0.15, "a_l": 0.12},
    "viscous-lead": {"T": 0.06},
    "inertia-error": {"dm": -2.5},
    "force-offset": {"offset": 6.0},
    "ripple": {"A": 0.12, "wavelength": 3e-3},
    "drift": {"beta": 0.25},
}
#: Hidden effects that are outside the catalogue of models.md 1.8.
OUTSIDE = ("ripple", "drift")


@dataclass(frozen=True)
class TruthParams:
    """Base friction and rig of the synthetic truth (SI).

    Attributes
    ----------
    Fc, Fs : N
        Coulomb and static levels (``Fs`` used by the ``stribeck`` and ``lugre`` bases).
    vs : m/s
        Stribeck velocity of the base curve (exponential, ``n = 2``).
    sigma0 : N/m
        Bristle stiffness (``lugre`` base).
    sigma1 : Ns/m
        Bristle damping (``lugre`` base).
    sigma2 : Ns/m
        Viscous coefficient (bases with a viscous term).
    mass : kg
        True moving mass.
    bore, rod, stroke : m
        Cylinder geometry (``A1 = pi/4*bore^2``, ``A2 = pi/4*(bore^2 - rod^2)``).
    """

    Fc: float = 30.0
    Fs: float = 45.0
    vs: float = 0.012
    sigma0: float = 2.0e5
    sigma1: float = 250.0
    sigma2: float = 60.0
    mass: float = 1.2
    bore: float = 0.032
    rod: float = 0.012
    stroke: float = 0.2


@dataclass(frozen=True)
class SyntheticTruth:
    """What the measurement hides: the clean friction and the laws that made it.

    Attributes
    ----------
    F : (N,) N
        Recorded force without noise (friction plus recording errors).
    friction : (N,) N
        The friction force alone.
    v, a : (N,) m/s, m/s^2
        Exact velocity and acceleration at the samples.
    noise : (N,) N
        The coloured noise added to ``F``.
    base : str
        The base friction law.
    hidden : dict
        Hidden effect name -> its law parameters.
    params : TruthParams
        Base parameters.
    noise_std : N
        Standard deviation of the force noise (the true noise floor).
    """

    F: np.ndarray
    friction: np.ndarray
    v: np.ndarray
    a: np.ndarray
    noise: np.ndarray
    base: str
    hidden: dict[str, dict[str, float]]
    params: TruthParams
    noise_std: float


@dataclass(frozen=True)
class SyntheticRecord:
    """A synthetic measurement and, separately, its truth."""

    measurement: Measurement
    truth: SyntheticTruth

    def experiments(self) -> list[Measurement]:
        """The measurement split into one :class:`Measurement` per experiment."""
        ids = self.measurement["experiment"]
        out = []
        for e in np.unique(ids):
            sub = self.measurement.select(ids == e)
            sub.meta["name"] = f"{self.measurement.label}-exp{int(e)}"
            out.append(sub)
        return out


# ---------------------------------------------------------------- motion plan
@dataclass
class _Plan:
    """Piecewise motion on the fine grid: velocity, acceleration, pressure sum."""

    dt: float
    x0: float
    stroke: float
    v: list[np.ndarray] = field(default_factory=list)
    a: list[np.ndarray] = field(default_factory=list)
    S: list[np.ndarray] = field(default_factory=list)
    x: float = 0.0
    level: float = 3e5

    def __post_init__(self) -> None:
        self.x = self.x0

    @property
    def duration(self) -> float:
        return sum(seg.size for seg in self.v) * self.dt

    def _push(self, v: np.ndarray, a: np.ndarray) -> None:
        self.v.append(v)
        self.a.append(a)
        self.S.append(np.full(v.size, self.level))
        self.x += float(np.sum(v) * self.dt)

    def dwell(self, T: float) -> None:
        n = max(1, int(round(T / self.dt)))
        self._push(np.zeros(n), np.zeros(n))

    def move(self, d: float, V: float, t_ramp: float) -> None:
        """A smooth move of signed distance ``d`` at cruise speed ``V`` (raised-cosine ramps)."""
        d = float(np.clip(self.x + d, 0.03 * self.stroke, 0.97 * self.stroke) - self.x)
        dist = abs(d)
        if dist < 1e-6:
            return
        V = min(V, dist / t_ramp)  # short moves: triangular-ish profile
        T = dist / V + t_ramp
        n = max(4, int(round(T / self.dt)))
        t = (np.arange(n) + 0.5) * self.dt
        T = n * self.dt
        u_up = np.clip(t / t_ramp, 0.0, 1.0)
        u_dn = np.clip((T - t) / t_ramp, 0.0, 1.0)
        shape = np.minimum(0.5 * (1 - np.cos(np.pi * u_up)), 0.5 * (1 - np.cos(np.pi * u_dn)))
        dshape = np.where(
            u_up < u_dn,
            np.where(t < t_ramp, 0.5 * np.pi / t_ramp * np.sin(np.pi * u_up), 0.0),
            np.where(T - t < t_ramp, -0.5 * np.pi / t_ramp * np.sin(np.pi * u_dn), 0.0),
        )
        scale = dist / (np.sum(shape) * self.dt)  # hit the distance exactly
        s = math.copysign(1.0, d)
        self._push(s * scale * shape, s * scale * dshape)

    def loops(self, A: float, f: float, cycles: int) -> None:
        """``x = x0 + s*A*(1 - cos(2*pi*f*t))``: closed displacement cycles starting at rest."""
        s = 1.0 if self.x < 0.5 * self.stroke else -1.0
        n = max(8, int(round(cycles / f / self.dt)))
        t = (np.arange(n) + 0.5) * self.dt
        w = 2 * np.pi * cycles / (n * self.dt)
        self._push(s * A * w * np.sin(w * t), s * A * w * w * np.cos(w * t))

    def pressure(self, level: float, tau: float = 0.15) -> None:
        """Change the pressure sum during a 1 s dwell (first-order transition, ``tau`` s)."""
        n = max(1, int(round(1.0 / self.dt)))
        t = (np.arange(n) + 0.5) * self.dt
        S = level + (self.level - level) * np.exp(-t / tau)
        self.v.append(np.zeros(n))
        self.a.append(np.zeros(n))
        self.S.append(S)
        self.level = level


#: Speed classes (m/s) the slides cycle through, so every record spans two decades.
SPEED_CLASSES = ((0.003, 0.015), (0.015, 0.06), (0.06, 0.25))
#: Dwell classes (s) before the dwell-slides, alternating short and long.
DWELL_CLASSES = ((0.1, 0.4), (0.8, 3.0))
MOTION_KINDS = ("slide", "reverse", "dwell-slide", "loops", "sweep")


def _schedule(plan: _Plan, rng: np.random.Generator, duration: float, levels: Sequence[float],
              a_max: float) -> None:
    """Fill ``plan`` with a realistic motion of about ``duration`` seconds.

    The motion kinds (:data:`MOTION_KINDS`) are drawn from a shuffled deck, so
    every kind comes before any repeats; slide speeds cycle through
    :data:`SPEED_CLASSES` and dwells through :data:`DWELL_CLASSES` (values
    log-uniform within a class). The pressure level changes once, half way.
    """
    L = plan.stroke
    plan.level = float(levels[0])
    plan.dwell(0.3)
    changed = len(levels) < 2
    deck: list[str] = []
    n_slide = n_dwell = int(rng.integers(3))

    def log_uniform(lo: float, hi: float) -> float:
        return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))

    while plan.duration < duration:
        if not changed and plan.duration > 0.5 * duration:
            plan.pressure(float(levels[1]))
            changed = True
        if not deck:
            deck = [MOTION_KINDS[i] for i in rng.permutation(len(MOTION_KINDS))]
        kind = deck.pop()
        V = log_uniform(*SPEED_CLASSES[n_slide % len(SPEED_CLASSES)])
        n_slide += 1
        t_ramp = max(0.01, V / a_max * rng.uniform(1.0, 2.5))
        towards = 1.0 if plan.x < 0.5 * L else -1.0
        d = towards * min(V * rng.uniform(0.4, 1.2) + V * t_ramp, 0.35 * L)
        if kind == "slide":
            plan.move(d, V, t_ramp)
            plan.dwell(log_uniform(0.05, 0.4))
        elif kind == "reverse":  # out and straight back: a reversal without a stop
            plan.move(d, V, t_ramp)
            plan.move(-0.6 * d, V, t_ramp)
        elif kind == "dwell-slide":
            plan.dwell(log_uniform(*DWELL_CLASSES[n_dwell % len(DWELL_CLASSES)]))
            n_dwell += 1
            plan.move(d, V, t_ramp)
        elif kind == "loops":  # small displacement cycles (presliding), at most 1 s
            plan.loops(log_uniform(2e-5, 3e-4), float(rng.uniform(2.0, 5.0)), 2)
            plan.dwell(0.1)
        else:  # one sinusoidal sweep, at most 1 s
            f = float(rng.uniform(1.0, 2.5))
            A = min(0.12 * L, 0.15 / (2 * np.pi * f))
            plan.loops(A, f, 1)
            plan.dwell(0.1)


# ---------------------------------------------------------------- truth friction
def _stribeck_hump(speed: np.ndarray | float, dF: float, vs: float, delta: float) -> Any:
    """``dF*exp(-(|v|/vs)^delta)`` (N)."""
    return dF * np.exp(-((np.asarray(speed) / vs) ** delta))


def _level_scale(P: TruthParams, hidden: Mapping[str, Mapping[str, float]], x: np.ndarray,
                 S: np.ndarray, t: np.ndarray, neg: np.ndarray, S_mid: float) -> np.ndarray:
    """Factor multiplying both levels ``Fc`` and ``Fs`` at every fine step (-)."""
    scale = np.ones_like(x)
    L = P.stroke
    if "pressure-dependence" in hidden:
        c = hidden["pressure-dependence"]["c_p"]
        scale *= (1.0 + c * S) / (1.0 + c * S_mid)
    if "direction-asymmetry" in hidden:
        scale *= np.where(neg, 1.0 + hidden["direction-asymmetry"]["dF_neg"] / P.Fc, 1.0)
    if "position-dependence" in hidden:
        h = hidden["position-dependence"]
        xg, w = h["x_g_frac"] * L, h["w_frac"] * L
        scale *= 1.0 + h["a_g"] * np.exp(-(((x - xg) / w) ** 2)) + h["a_l"] * (x - 0.5 * L) / L
    if "ripple" in hidden:
        h = hidden["ripple"]
        scale *= 1.0 + h["A"] * np.sin(2 * np.pi * x / h["wavelength"])
    if "drift" in hidden:
        scale *= 1.0 + hidden["drift"]["beta"] * (t - t[0]) / max(t[-1] - t[0], 1e-9)
    return scale


def _node_average(mid: np.ndarray) -> np.ndarray:
    """Values at the nodes (interval ends) from interval values: the mean of the two neighbours."""
    out = np.empty_like(mid)
    out[0] = 0.5 * mid[0]
    out[1:] = 0.5 * (mid[1:] + mid[:-1])
    return out


def truth_friction(P: TruthParams, base: str, hidden: Mapping[str, Mapping[str, float]],
                   t: np.ndarray, v: np.ndarray, a: np.ndarray, x: np.ndarray, S: np.ndarray,
                   dt: float, S_mid: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The truth friction along a fine-grid motion; returns ``(F, v_node, a_node)`` (SI).

    Parameters
    ----------
    P, base, hidden
        Base parameters, base law (:data:`BASES`) and hidden laws (name -> law
        parameters, complete; see :data:`HIDDEN_DEFAULTS`).
    t, x : (n,) s, m
        Time and position at the nodes where the fine intervals start.
    v, a : (n,) m/s, m/s^2
        Velocity and acceleration of each fine interval (midpoint values).
    S : (n,) Pa
        Pressure sum ``p1 + p2`` (gauge) at the nodes.
    dt : s
        Fine step.
    S_mid : Pa
        Reference pressure sum of the pressure law.

    States (bristle, lagged speed, dwell age, Maxwell-slip deflections)
    advance interval by interval; the force is evaluated at the nodes with
    the node velocity (mean of the two neighbouring intervals) so that it
    lines up with the sampled ``x``.
    """
    n = v.size
    vn = _node_average(v)
    an = _node_average(a)
    neg_side = np.empty(n, dtype=bool)  # side held at rest (last direction)
    last = False
    for i, vi in enumerate(vn):
        if vi != 0.0:
            last = vi < 0.0
        neg_side[i] = last
    scale = _level_scale(P, hidden, x, S, t, neg_side, S_mid)
    has_hump = base in ("stribeck", "lugre") or "stribeck" in hidden
    if "stribeck" in hidden:
        h = hidden["stribeck"]
        hump_dF, hump_vs, delta = h["dF"], h["vs"], h["delta"]
    else:
        hump_dF, hump_vs, delta = P.Fs - P.Fc, P.vs, 2.0
    hump_speed = np.abs(vn)
    if "frictional-lag" in hidden and has_hump:  # Hess-Soom lagged speed, at the nodes
        c = 1.0 - math.exp(-dt / hidden["frictional-lag"]["tau_L"])
        hump_speed = np.empty(n)
        cur = 0.0
        for i, sp in enumerate(np.abs(v)):
            hump_speed[i] = cur
            cur += (sp - cur) * c
    dwell = _dwell_bump(hidden["dwell-time"], v, dt) if "dwell-time" in hidden else 0.0
    if has_hump:
        hump = _stribeck_hump(hump_speed, 1.0, hump_vs, delta) * (hump_dF + dwell) * scale
    else:  # without a Stribeck curve the dwell excess decays with the sliding distance only
        hump = dwell * scale
    g = P.Fc * scale + hump
    visc = P.sigma2 if base in ("coulomb-viscous", "stribeck", "lugre") else 0.0
    if "viscous" in hidden:
        visc += hidden["viscous"]["c_v"]
    F_visc = visc * vn
    if "viscous-lead" in hidden:
        F_visc = F_visc + visc * hidden["viscous-lead"]["T"] * an
    if "nonlocal-memory" in hidden:
        F_dry = _maxwell_slip(hidden["nonlocal-memory"], x, g)
    elif base == "lugre" or "presliding" in hidden:
        k = P.sigma0 if base == "lugre" else hidden["presliding"]["k"]
        damp = P.sigma1 if base == "lugre" else 0.0
        F_dry = _bristle(v, vn, g, k, damp, dt)
    else:
        F_dry = np.tanh(vn / 1e-5) * g
    return F_dry + F_visc, vn, an


def _bristle(v: np.ndarray, vn: np.ndarray, g: np.ndarray, k: float, damp: float, dt: float
             ) -> np.ndarray:
    """``dz/dt = v - k*|v|*z/g``, exact for the velocity held over each fine interval.

    ``g`` is at the nodes (its interval value is the mean of the two ends);
    returns ``k*z + damp*dz/dt`` at the nodes (N).
    """
    z = 0.0
    out = np.empty_like(v)
    n = v.size
    for i in range(n):
        gi = float(g[i])
        dz = float(vn[i]) - k * abs(float(vn[i])) * z / gi
        out[i] = k * z + damp * dz
        vi = float(v[i])
        if vi != 0.0:
            gm = 0.5 * (gi + float(g[min(i + 1, n - 1)]))
            zss = gm / k * (1.0 if vi > 0 else -1.0)
            z = zss + (z - zss) * math.exp(-k * abs(vi) / gm * dt)
    return out


def _maxwell_slip(h: Mapping[str, float], x: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Classical Maxwell-slip model: elasto-slide elements in parallel (nonlocal memory).

    Element ``i`` has slip force ``f_i = w_i*g`` (weights summing to 1) and
    stiffness ``k_i = f_i/d_i`` with break displacements ``d_i`` spread up to
    ``d_max``; its deflection follows the displacement and is clipped to
    ``+-d_i``: ``F = sum(k_i*delta_i)``.
    """
    n = int(h["n_elements"])
    d = h["d_max"] * (np.arange(1, n + 1) / n) ** 1.5
    w = np.full(n, 1.0 / n)
    delta = np.zeros(n)
    out = np.empty_like(x)
    x_prev = float(x[0])
    for i in range(x.size):
        delta = np.clip(delta + (float(x[i]) - x_prev), -d, d)
        x_prev = float(x[i])
        out[i] = float(np.sum(w * g[i] * delta / d))
    return out


def _dwell_bump(h: Mapping[str, float], v: np.ndarray, dt: float) -> np.ndarray:
    """Kato-law excess of the static level after a dwell, erased over the sliding distance.

    ``v`` per fine interval; returns the excess at the nodes (interval starts).
    """
    out = np.zeros_like(v)
    t_rest = 5.0  # the rig rested before the record
    bump = 0.0
    s = 0.0
    for i, vi in enumerate(v):
        out[i] = bump * math.exp(-s / h["d_c"]) if bump else 0.0
        if vi == 0.0:
            t_rest += dt
            continue
        if t_rest > 0.0:  # a start: the excess is set by the dwell just ended
            bump = h["dF_inf"] * (1.0 - math.exp(-((t_rest / h["tau_k"]) ** h["m"])))
            s = 0.0
            t_rest = 0.0
            out[i] = bump
        s += abs(vi) * dt
    return out


def _ar1(rng: np.random.Generator, n: int, std: float, tau: float, dt: float) -> np.ndarray:
    """Stationary AR(1) noise of standard deviation ``std`` and correlation time ``tau``."""
    phi = math.exp(-dt / tau)
    e = rng.normal(0.0, std * math.sqrt(1 - phi * phi), n)
    out = np.empty(n)
    prev = rng.normal(0.0, std)
    for i in range(n):
        prev = phi * prev + e[i]
        out[i] = prev
    return out


# ---------------------------------------------------------------------- API
def _resolve_hidden(hidden: Sequence[str] | Mapping[str, Mapping[str, float]]
                    ) -> dict[str, dict[str, float]]:
    items = hidden.items() if isinstance(hidden, Mapping) else ((h, {}) for h in hidden)
    out: dict[str, dict[str, float]] = {}
    for name, over in items:
        if name not in HIDDEN_DEFAULTS:
            raise FcompError(f"unknown hidden effect {name!r}; known: "
                             f"{', '.join(HIDDEN_DEFAULTS)}")
        law = dict(HIDDEN_DEFAULTS[name])
        unknown = set(over) - set(law)
        if unknown:
            raise FcompError(f"hidden effect {name!r}: unknown law parameter(s) "
                             f"{', '.join(sorted(unknown))}; known: {', '.join(law)}")
        law.update({k: float(v) for k, v in over.items()})
        out[name] = law
    return out


def generate(
    hidden: Sequence[str] | Mapping[str, Mapping[str, float]] = (),
    *,
    base: str = "lugre",
    params: TruthParams | None = None,
    experiments: int = 3,
    duration: float = 12.0,
    rate: float = 500.0,
    pressures: Sequence[float] = (1.5e5, 3.0e5, 5.0e5),
    noise_std: float = 0.4,
    noise_tau: float = 0.005,
    resolution: float = 1e-6,
    pressure_noise: float = 300.0,
    include_velocity: bool = False,
    seed: int = 0,
    fine: int = 10,
) -> SyntheticRecord:
    """A synthetic rig measurement with ``hidden`` effects (see the module docstring).

    Parameters
    ----------
    hidden
        Effect names, or a mapping name -> law-parameter overrides
        (:data:`HIDDEN_DEFAULTS` lists the laws' parameters and defaults).
    base
        Base friction law: one of :data:`BASES`.
    params
        Base friction and rig parameters.
    experiments
        Number of experiments (each at its own pressure levels).
    duration
        Total recorded duration (s), shared among the experiments.
    rate
        Sample rate (Hz).
    pressures
        Pressure-sum levels ``p1 + p2`` (gauge, Pa) the experiments cycle through.
    noise_std, noise_tau
        Standard deviation (N) and correlation time (s) of the AR(1) force noise.
    resolution
        Position quantisation (encoder resolution, m).
    pressure_noise
        White noise on each pressure sensor (Pa, standard deviation).
    include_velocity
        Also write the exact velocity column ``v`` (otherwise the tool must derive it from ``x``).
    seed
        Random seed (motions and noise).
    fine
        Integration sub-steps per sample interval.
    """
    if base not in BASES:
        raise FcompError(f"unknown base {base!r}; known: {', '.join(BASES)}")
    if experiments < 1 or duration <= 0 or rate <= 0 or fine < 1:
        raise FcompError("experiments, duration, rate and fine must be positive")
    P = params or TruthParams()
    laws = _resolve_hidden(hidden)
    rng = np.random.default_rng(seed)
    dt_s = 1.0 / rate
    dt = dt_s / fine
    levels = list(pressures)
    A1 = math.pi / 4 * P.bore**2
    A2 = math.pi / 4 * (P.bore**2 - P.rod**2)
    a_max = 4.0
    t_parts, v_parts, a_parts, x_parts, S_parts, e_parts = [], [], [], [], [], []
    t_start = 0.0
    x0 = 0.5 * P.stroke
    for e in range(experiments):
        plan = _Plan(dt=dt, x0=x0, stroke=P.stroke)
        lv = [levels[(e + k) % len(levels)] for k in range(2)]
        _schedule(plan, rng, duration / experiments, lv, a_max)
        n_keep = int(round(duration / experiments / dt))  # the record ends where it ends
        v = np.concatenate(plan.v)[:n_keep]
        a = np.concatenate(plan.a)[:n_keep]
        S = np.concatenate(plan.S)[:n_keep]
        x = x0 + np.concatenate([[0.0], np.cumsum(v[:-1] * dt)])
        t = t_start + np.arange(v.size) * dt
        t_parts.append(t)
        v_parts.append(v)
        a_parts.append(a)
        x_parts.append(x)
        S_parts.append(S)
        e_parts.append(np.full(v.size, e + 1.0))
        t_start = t[-1] + 1.0  # a one-second gap between experiments
        x0 = float(x[-1])
    S_mid = float(np.mean(levels))
    # friction: the state is carried from experiment to experiment (same rig, same seal)
    t_f = np.concatenate(t_parts)
    v_f = np.concatenate(v_parts)
    a_f = np.concatenate(a_parts)
    x_f = np.concatenate(x_parts)
    S_f = np.concatenate(S_parts)
    e_f = np.concatenate(e_parts)
    fric_f, vn_f, an_f = truth_friction(P, base, laws, t_f, v_f, a_f, x_f, S_f, dt, S_mid)
    idx = np.arange(0, t_f.size, fine)  # samples at nodes: the start of every fine interval
    t_s, v_s, a_s, x_s, S_s, e_s = (arr[idx] for arr in (t_f, vn_f, an_f, x_f, S_f, e_f))
    fric = fric_f[idx]
    recorded = fric.copy()
    if "inertia-error" in laws:
        recorded += laws["inertia-error"]["dm"] * a_s
    if "force-offset" in laws:
        recorded += laws["force-offset"]["offset"]
    noise = _ar1(rng, t_s.size, noise_std, noise_tau, dt_s) if noise_std > 0 else np.zeros(
        t_s.size)
    F_meas = recorded + noise
    # chamber pressures from the force balance at the pressure-sum level S
    F_net = fric + P.mass * a_s
    p1 = (F_net + S_s * A2) / (A1 + A2)
    p2 = S_s - p1
    p1 = p1 + rng.normal(0.0, pressure_noise, p1.size)
    p2 = p2 + rng.normal(0.0, pressure_noise, p2.size)
    xq = np.round(x_s / resolution) * resolution if resolution > 0 else x_s
    cols: dict[str, np.ndarray] = {"t": t_s - t_s[0], "x": xq}
    if include_velocity:
        cols["v"] = v_s
    cols.update({"p1": p1, "p2": p2, "F": F_meas, "experiment": e_s})
    mass_assumed = P.mass - (laws["inertia-error"]["dm"] if "inertia-error" in laws else 0.0)
    meta: dict[str, Any] = {
        "name": "synthetic-" + ("-".join(laws) if laws else "none"),
        "kind": "pneumatic-cylinder",
        "pressure": "gauge",
        "rig": {"bore": P.bore, "rod": P.rod, "stroke": P.stroke,
                "mass": float(max(mass_assumed, 0.0)), "orientation": "horizontal"},
        "synthetic": {"generator": "fcomp.synthetic", "seed": int(seed), "rate": float(rate),
                      "position_resolution": float(resolution)},
    }
    truth = SyntheticTruth(F=recorded, friction=fric, v=v_s, a=a_s, noise=noise, base=base,
                           hidden=laws, params=P, noise_std=float(noise_std))
    return SyntheticRecord(Measurement(cols, meta), truth)
