"""The PID family's gains from the loop as it runs: the largest integral gain with the margins.

The PID family (:mod:`controllers.pid`: ``pid``, and ``pid-ff``, ``lugre-observer``,
``ekf`` on the same law) has five numbers that shape its loop at rest: the PID's
``kp``, ``ki``, ``kd``, the force loop's ``w_F`` and the velocity compensation
``lambda`` (:mod:`controllers.force_to_valve`); the derivative filter ``f_d``
follows ``kd`` (rule 3 of :mod:`controllers.tuning`: its noise no larger than the
pressure sensors'). They are chosen to

    maximise ki   subject to   GM >= 2, PM >= 30 deg, Ms <= 2 at both break points
                               and at every point of the grid,

the design of PID controllers for load-disturbance rejection under robustness
constraints (Astrom, Panagopoulos & Hagglund, "Design of PI controllers based on
non-convex optimization", Automatica 34(5), 1998; Astrom & Hagglund, *Advanced
PID Control*, 2006, sec. 7.4; Skogestad & Postlethwaite, *Multivariable Feedback
Control*, 2005, sec. 2.4.3 for the bounds): for a step load ``d`` on the piston
-- the disturbance friction is -- the integrated position error of the loop is
exactly ``d/ki`` (at rest the integral must end holding ``d``), so ``ki`` is the
figure of merit and the margins the constraint. On the grid
(:mod:`controllers.loop_analysis.grid`) the loop is the one the controller runs
(:mod:`controllers.loop_analysis.pid_family`, the computation delay and the
zero-order hold included), over the stroke, the parameter box and the friction
regimes; so the design *is* the gain scheduling the force-to-valve inversion
already does over the stroke (its model of the chambers at the measured position
and pressures), with gains that hold everywhere.

The optimisation is non-convex and non-smooth (a margin jumps between crossings),
so it is a derivative-free search (Nelder-Mead on the logarithms of ``kp``, ``ki``,
``kd``, ``w_F`` and on ``lambda``, the constraint as an exact penalty) from a few
physically placed starts, over an *active set* of grid points: it starts with the
nominal parameters at every position and friction regime, the full grid is
checked at the end of a search, the points that fail are added and the search
resumes from its best, until the full grid passes (at most :data:`ROUNDS` rounds).
Each search has two phases: first the nearest design that meets the active set
(maximise the least margin ratio ``min(GM/2, PM/30, 2/Ms)`` up to a little above
1), then the best performance among such designs. A design that still fails
somewhere after the rounds has the least ratio over the whole grid maximised; one
that cannot be brought to the requirement is returned with ``feasible = False``
and its worst point: :mod:`controllers.tuning` refuses it in one line naming that
point.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import minimize

from controllers.loop_analysis.grid import PlantGrid, worst_index
from controllers.loop_analysis.loop import unit_z
from controllers.loop_analysis.margins import (
    MAX_SENSITIVITY,
    MIN_GAIN_MARGIN,
    MIN_PHASE_MARGIN,
    frequency_grid,
)
from controllers.loop_analysis.pid_family import (
    PIDFamilyGains,
    pid_family_response,
    pid_family_ss,
)
from controllers.pid import VELOCITY_COMPENSATION

#: The design's margins above the requirement (relative): the search's interpolated
#: margins against the refined ones.
PAD = 0.02
#: Rounds of the active-set search (module docstring).
ROUNDS = 8
#: Points added to the active set per round (the worst failing ones).
ADDED = 12
#: Nelder-Mead iterations per search.
ITERATIONS = 500
#: The velocity compensation's range (below 0: velocity fed back to the valve).
LAMBDA_RANGE = VELOCITY_COMPENSATION
#: Frequencies of the search's responses (the final check uses the grid's own).
SEARCH_FREQUENCIES = 300


@dataclass(frozen=True)
class Design:
    """The outcome of :func:`design_pid_family`.

    Attributes
    ----------
    gains : PIDFamilyGains
        The design.
    feasible : bool
        Whether it meets the requirement at every grid point.
    worst : int
        Index of the grid point with the least margin (:func:`~controllers.loop_analysis.grid.worst_index`).
    worst_break : str
        ``"valve"`` or ``"position"``.
    ratio : float
        ``min(gain/2, phase/30, 2/Ms)`` there (below 1: the requirement is not met).
    evaluations : int
        Grid evaluations spent.
    """

    gains: PIDFamilyGains
    feasible: bool
    worst: int
    worst_break: str
    ratio: float
    evaluations: int


def derivative_cutoff(kd: float, sigma_x: float, sigma_F: float, dt: float) -> float:
    """Rule 3 of :mod:`controllers.tuning`: ``f_d = min(dt*(sigma_F/(kd*sigma_x))^2/(2 pi),
    f_s/4)`` (Hz)."""
    top = 0.25 / dt
    if kd <= 0:
        return top
    return max(min(dt * (sigma_F / (kd * sigma_x)) ** 2 / (2 * math.pi), top), 1e-3)


def _controller(grid: PlantGrid, gains: PIDFamilyGains
                ) -> Callable[[np.ndarray], tuple[np.ndarray, ...]]:
    """The PID family's linear law with ``gains`` at the grid's points (for
    :meth:`PlantGrid.margins`)."""
    s, Jy, Jv = grid.slopes
    z = unit_z(grid.w, grid.dt)
    A1, A2 = grid.areas

    def controller(idx: np.ndarray) -> tuple[np.ndarray, ...]:
        A, B, C, D = pid_family_ss(gains, s[idx], Jy[idx], Jv[idx], A1, A2, grid.dt)
        K = pid_family_response(gains, s[idx], Jy[idx], Jv[idx], A1, A2, grid.dt, z)
        return A, B, C, D, K

    return controller


def ratios(grid: PlantGrid, gains: PIDFamilyGains
           ) -> tuple[np.ndarray, dict[str, dict[str, np.ndarray]]]:
    """Per point, ``min(gain/2, phase/30, 2/Ms)`` over both breaks (an unstable point:
    minus its growth rate), and the margins."""
    m = grid.margins(_controller(grid, gains))
    r = np.full(len(grid), np.inf)
    for arr in m.values():
        ratio = np.minimum(np.minimum(arr["gain"] / MIN_GAIN_MARGIN,
                                      arr["phase"] / MIN_PHASE_MARGIN),
                           MAX_SENSITIVITY / arr["ms"])
        r = np.minimum(r, np.where(arr["radius"] < 1.0, ratio, -np.maximum(arr["growth"], 0)))
    return r, m


def performance(grid: PlantGrid, gains: PIDFamilyGains) -> float:
    """The design's figure of merit on ``grid`` (its sliding points at nominal parameters):
    the mean over them of the integrated squared position error (m^2 s) after a unit step
    load on the piston, once alone and once with the same load fed forward exactly
    through the force demand (a friction estimate that is right: what the force loop
    makes of it); ``inf`` where a closed loop is unstable.

    For a step ``b`` into the closed loop ``x[k+1] = A x[k] + b`` the error decays from
    ``x_ss = (I - A)^-1 b`` (the integral action takes the load), so ``sum_k e[k]^2 =
    x_ss' Q x_ss`` with ``A' Q A - Q + c c' = 0`` (discrete Lyapunov equation, ``c``
    the position's row), solved by Smith's doubling ``Q <- Q + A_j' Q A_j``, ``A_j <-
    A_j^2`` (Smith, SIAM J. Appl. Math. 16, 1968).
    """
    from controllers.loop_analysis.loop import closed_loop_matrix

    s, Jy, Jv = grid.slopes
    A1, A2 = grid.areas
    sel = [i for i, p in enumerate(grid.points)
           if p.presliding is None and all(v == 0 for _k, v in p.changes)]
    total = 0.0
    for i in sel:
        lp = grid.plants[i]
        A, B, C, D = pid_family_ss(gains, s[i:i + 1], Jy[i:i + 1], Jv[i:i + 1], A1, A2,
                                   grid.dt)
        M = closed_loop_matrix(lp.Ad, lp.Bd, lp.C, A[0], B[0], C[0], D[0], grid.delay)
        if not np.max(np.abs(np.linalg.eigvals(M))) < 1.0:
            return math.inf
        n, d = lp.Ad.shape[0], grid.delay
        N = M.shape[0]
        b_load = np.zeros(N)
        b_load[:n] = lp.Fd[:, 0]
        b_ff = np.zeros(N)  # -1 N through the force demand: u += s*w_F*(-1)
        if d == 0:
            b_ff[:n] = -s[i] * gains.force_bandwidth * lp.Bd[:, 0]
        else:
            b_ff[N - d] = -s[i] * gains.force_bandwidth
        c = np.zeros(N)
        c[:n] = lp.C[0]
        Q = _lyapunov(M, c)
        eye = np.eye(N)
        for b in (b_load, b_load + b_ff):
            x_ss = np.linalg.solve(eye - M, b)
            total += float(x_ss @ Q @ x_ss) * grid.dt
    return total / max(len(sel), 1)


def _lyapunov(M: np.ndarray, c: np.ndarray, sweeps: int = 60) -> np.ndarray:
    """``Q = sum_k (M')^k c c' M^k`` (``M`` stable) by doubling."""
    Q = np.outer(c, c)
    Aj = M.copy()
    for _ in range(sweeps):
        step = Aj.T @ Q @ Aj
        Q = Q + step
        if np.abs(step).max() <= 1e-15 * np.abs(Q).max():
            break
        Aj = Aj @ Aj
    return Q


#: The search's coordinates, in order (``q``: the logarithms of the first four, ``lambda``).
COORDINATES = ("kp", "ki", "kd", "force_bandwidth", "velocity_compensation")


def _gains(q: np.ndarray, sigma_x: float, sigma_F: float, dt: float,
           f_d: float | None = None) -> PIDFamilyGains:
    kp, ki, kd, wF = (float(math.exp(v)) for v in q[:4])
    lam = min(max(float(q[4]), LAMBDA_RANGE[0]), LAMBDA_RANGE[1])
    fd = derivative_cutoff(kd, sigma_x, sigma_F, dt) if f_d is None else f_d
    return PIDFamilyGains(kp, ki, kd, fd, wF, lam)


def design_pid_family(grid: PlantGrid, mass: float, force_bandwidth: float, sigma_x: float,
                      sigma_F: float, starts: list[np.ndarray] | None = None,
                      progress: Callable[[str], Any] | None = None,
                      hold: dict[str, float] | None = None) -> Design:
    """The design of the module docstring on ``grid``.

    Parameters
    ----------
    grid : PlantGrid
        The grid (:func:`~controllers.loop_analysis.grid.plant_grid`).
    mass : float
        Moving mass (kg): scales the starts.
    force_bandwidth : float
        A force-loop bandwidth (rad/s) the valve allows (rule 1 of
        :mod:`controllers.tuning`): scales the starts.
    sigma_x, sigma_F : float
        Position noise (m) and the pressure sensors' force noise (N): the derivative
        filter (rule 3).
    starts : list of numpy.ndarray, optional
        Starting points ``[log kp, log ki, log kd, log w_F, lambda]`` (default: placed).
    hold : dict, optional
        Values held (not searched): any of :data:`COORDINATES` and ``derivative_cutoff``
        (the values a plant file gives).
    """
    dt = grid.dt
    hold = dict(hold or {})
    f_d = hold.pop("derivative_cutoff", None)
    free = [i for i, c in enumerate(COORDINATES) if c not in hold]
    held = np.array([math.log(hold[c]) if i < 4 else hold[c]
                     for i, c in enumerate(COORDINATES) if c in hold])
    fixed = [i for i, c in enumerate(COORDINATES) if c in hold]

    def full(x: np.ndarray) -> np.ndarray:
        q = np.empty(len(COORDINATES))
        q[free], q[fixed] = x, held
        return q

    def gains_of(x: np.ndarray) -> PIDFamilyGains:
        return _gains(full(x), sigma_x, sigma_F, dt, f_d)

    w_search = frequency_grid(dt, SEARCH_FREQUENCIES)
    nominal = [i for i, p in enumerate(grid.points) if all(v == 0 for _k, v in p.changes)]
    active = list(nominal) or list(range(len(grid)))
    perf = grid.subset([i for i in nominal if grid.points[i].presliding is None])
    evaluations = 0

    def score(x: np.ndarray, sub: PlantGrid) -> float:
        nonlocal evaluations
        evaluations += 1
        return float(sub.requirement(_controller(sub, gains_of(x))).min())

    def objective(x: np.ndarray, sub: PlantGrid) -> float:
        if not np.all(np.abs(full(x)[:4]) < 40.0):  # gains beyond e^40: no loop
            return 1e6
        with np.errstate(all="ignore"):
            sc = score(x, sub)
            if not math.isfinite(sc):
                return 1e6
            short = (1.0 + PAD) - sc
            if short > 0:
                return 1e3 + 100.0 * short
            J = performance(perf, gains_of(x))
        return math.log(J) if 0 < J < math.inf else 1e3

    if starts is None:
        starts = []
        for frac_F, lam in ((1.0, 0.25), (0.25, 0.25), (1.0, 0.75)):
            wF = frac_F * force_bandwidth
            w = max(0.05 * wF, 1.0)  # a slow loop: feasible where anything is
            starts.append(np.array([math.log(3 * mass * w * w), math.log(mass * w ** 3),
                                    math.log(3 * mass * w), math.log(wF), lam]))
    starts = [q[free] for q in starts]
    def robustness(x: np.ndarray, sub: PlantGrid, target: float) -> float:
        if not np.all(np.abs(full(x)[:4]) < 40.0):
            return 1e6
        with np.errstate(all="ignore"):
            sc = score(x, sub)
        return -min(sc, target) if math.isfinite(sc) else 1e6

    def feasible_from(q0: np.ndarray, sub: PlantGrid) -> np.ndarray | None:
        """Phase 1: the nearest design with the active set's margins (maximise the least
        ratio up to a target a little above the requirement)."""
        target = 1.0 + 2 * PAD
        if -robustness(q0, sub, target) >= 1.0 + PAD:
            return q0
        res = minimize(robustness, q0, args=(sub, target), method="Nelder-Mead",
                       options={"maxiter": ITERATIONS, "xatol": 1e-4, "fatol": 1e-6,
                                "initial_simplex": _simplex(q0, free)})
        return res.x if -robustness(res.x, sub, target) >= 1.0 + PAD else None

    best: np.ndarray | None = None
    r_full = np.zeros(1)
    for round_ in range(ROUNDS if free else 0):
        sub = grid.subset(active, w_search)
        q = None
        for q0 in ([best] if best is not None else []) + starts:
            q = feasible_from(q0, sub)
            if q is not None:
                break
        if q is None:
            break  # nothing the search can reach meets the active set: refused below
        res = minimize(objective, q, args=(sub,), method="Nelder-Mead",  # phase 2
                       options={"maxiter": ITERATIONS, "xatol": 1e-3, "fatol": 1e-4,
                                "initial_simplex": _simplex(q, free)})
        best = res.x if objective(res.x, sub) <= objective(q, sub) else q
        r_full, _ = ratios(grid, gains_of(best))
        evaluations += 1
        if progress is not None:
            progress(f"round {round_ + 1}: ki {gains_of(best).ki:.4g}, worst ratio "
                     f"{r_full.min():.3f} on the full grid")
        if r_full.min() >= 1.0:
            break
        failing = [int(i) for i in np.argsort(r_full) if r_full[i] < 1.0 and i not in active]
        if not failing:  # the active set's optimum fails only where it already looked
            failing = [int(i) for i in np.argsort(r_full) if r_full[i] < 1.0]
        active = sorted(set(active) | set(failing[:ADDED]))
    if best is None:
        best = starts[0]
    gains = gains_of(best)
    r_full, m = ratios(grid, gains)
    if r_full.min() < 1.0 and free:  # the whole grid, its own frequencies: restore there
        q = feasible_from(best, grid)
        if q is not None:
            gains = gains_of(q)
            r_full, m = ratios(grid, gains)
    i, brk = worst_index(m)
    return Design(gains=gains, feasible=bool(r_full.min() >= 1.0), worst=i, worst_break=brk,
                  ratio=float(r_full.min()), evaluations=evaluations)


def _simplex(q0: np.ndarray, free: list[int] | None = None) -> np.ndarray:
    """The initial simplex: a factor e^0.7 (about 2) on each gain, 0.2 on lambda."""
    free = list(range(q0.size)) if free is None else free
    out = [q0.copy()]
    for k, c in enumerate(free):
        q = q0.copy()
        if c < 4:
            q[k] += 0.7
        else:
            q[k] += 0.2 if q0[k] + 0.2 <= LAMBDA_RANGE[1] else -0.2
        out.append(q)
    return np.array(out)


__all__ = ["COORDINATES", "PAD", "Design", "derivative_cutoff", "design_pid_family", "ratios"]
