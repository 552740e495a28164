"""Segment parameters ``c_i, k_i`` of seed 000's hysteresis function from transition curves.

Seed 000 ("Identification of f(z)", Figs. 17-18, Table 3) identifies the
hysteresis function of its new model from measured friction
force-displacement curves in pre-sliding: every velocity reversal starts a
*transition curve*; the external loop's ascending curve is split into three
segments with boundaries from Table 2, the descending one mirrored
(``c_{4..6} = -c_{1..3}``, ``k_{4..6} = -k_{1..3}``), internal loops use one
segment (``c_7 = -c_8``, ``k_7 = -k_8``), and on each segment Eq. 13

    f_i(z) = f_i(z_i) + c_i*(1 - exp(-k_i*(z - z_i)))

is fitted, ``f_i(z_i)`` being the end of the previous segment. Here, in the
conventions of :mod:`fcomp.models.hysteresis` (segment widths relative to
the reversal point, Masing's rule):

1. **Reversals** are the turning points of the position ``x`` with a
   deadband ``tol`` (a reversal is declared once ``x`` has moved back by more
   than ``tol`` from its extreme), so sensor noise does not create spurious
   curves. The first monotone stretch from the start is the virgin curve.
2. **Transition curves**: from each reversal ``(x_r, F_r)`` in direction ``d``,
   the travel ``Delta = d*(x - x_r)`` and the force rise ``d*(F - F_r)``. As in
   the seed, the bristle deflection is taken equal to the displacement in
   pre-sliding.
3. **Classes** (rule 3 of :mod:`fcomp.models.hysteresis`): a curve starting at
   an extreme of the reversal points still in memory (or the first two
   curves) is *external* (ascending or descending by ``d``), any other is
   *internal*. A curve travelling farther than the external range
   ``z1 + z5`` has entered sliding: the memory is cleared after it.
4. **Least squares** of the raw curve shapes to the points with
   ``0 < Delta <= `` the identified range of their class (beyond it the model
   continues with the bristle stiffness ``sigma0``, not fitted here):
   ascending widths ``z1, z3, z5 - z3``, descending ``z5 - z4, z4 - z2, z2 + z1``
   with the same ``(c_i, k_i)``, internal ``zd - zc`` with ``(c8, k8)``.
   The Jacobian is analytic; the standard errors are the
   autocorrelation-robust ones of :mod:`.uncertainty` (points along a curve
   are strongly correlated).

The segment boundaries ``z1..z5``, ``internal_zc``, ``internal_zd`` are held at
the model's values (the seed fixes them from the loop's shape).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from fcomp.errors import FcompError
from fcomp.identification.problem import ParameterVector, Solution, solve
from fcomp.identification.uncertainty import Uncertainty, estimate
from fcomp.parameters import ParamSpec

EXTERNAL = ("c1", "k1", "c2", "k2", "c3", "k3")
INTERNAL = ("c8", "k8")


@dataclass(frozen=True)
class TransitionCurve:
    """Samples of one transition curve (see :func:`transition_curves`).

    Attributes
    ----------
    kind
        ``"ascending"``, ``"descending"`` (external shapes) or ``"internal"``.
    direction
        +1 ascending, -1 descending.
    start
        Sample index of the reversal point where the curve starts.
    delta, rise
        Travel ``d*(x - x_r)`` (m, >= 0) and force rise ``d*(F - F_r)`` (N) of
        the samples that lie on this curve.
    target
        ``(Delta_t, rise_t)`` of the memorised reversal point the curve heads
        for (it is scaled to pass through it), or ``None`` (raw shape).
    """

    kind: str
    direction: int
    start: int
    delta: np.ndarray
    rise: np.ndarray
    target: tuple[float, float] | None


def position_noise(x: np.ndarray) -> float:
    """Robust noise level of a position record (m) from its second differences."""
    if x.size < 4:
        return 0.0
    d2 = np.diff(x, 2)
    return float(np.median(np.abs(d2 - np.median(d2))) / 0.6745 / math.sqrt(6.0))


def turning_points(x: np.ndarray, tol: float) -> list[int]:
    """Indices where monotone stretches of ``x`` start: 0 (or the first extreme) and every
    reversal, detected with the deadband ``tol`` (m)."""
    n = x.size
    turns: list[int] = []
    imax = imin = 0
    d = 0
    ext = 0
    for i in range(1, n):
        xi = x[i]
        if d == 0:
            if xi > x[imax]:
                imax = i
            if xi < x[imin]:
                imin = i
            if x[imax] - xi > tol:
                turns += [imin] if imin < imax else []
                turns.append(imax)
                d, ext = -1, i
            elif xi - x[imin] > tol:
                turns += [imax] if imax < imin else []
                turns.append(imin)
                d, ext = 1, i
        elif d == 1:
            if xi >= x[ext]:
                ext = i
            elif x[ext] - xi > tol:
                turns.append(ext)
                d, ext = -1, i
        else:
            if xi <= x[ext]:
                ext = i
            elif xi - x[ext] > tol:
                turns.append(ext)
                d, ext = 1, i
    return sorted(set(turns))


def transition_curves(x: np.ndarray, F: np.ndarray, *, sliding_travel: float,
                      tol: float) -> list[TransitionCurve]:
    """The transition curves of a record, with the memory rules of the model.

    The turning-point memory of :class:`fcomp.models.hysteresis.HysteresisFunction`
    is replayed on the measured reversal points ``(x_r, F_r)``: the first two
    curves (after a virgin start) and a curve that follows the end of sliding
    are external; later curves are internal; a curve with a memorised target
    (the previous reversal point, from the third curve on) is scaled through
    it, and when the motion passes its target the loop closes and the
    samples beyond belong to the outer curve again (wiping-out). A curve
    travelling farther than ``sliding_travel`` has entered sliding: the memory
    is cleared and the next reversal point is a real root.
    """
    turns = turning_points(x, tol)
    if not turns:
        return []
    bounds = [*turns, x.size - 1]
    # a memorised reversal point: [x_r, F_r, direction, kind, target, sample index, samples]
    points: list[list] = []
    root_real = False
    curves: list[list] = []
    for j in range(len(turns)):
        a, b = bounds[j], bounds[j + 1]
        if b <= a:
            continue
        d = 1 if x[b] > x[a] else -1
        depth = len(points)
        external = depth <= 1 or (depth == 2 and not root_real)
        kind = ("ascending" if d > 0 else "descending") if external else "internal"
        target = None
        if depth >= 2 or (depth == 1 and root_real):
            target = (d * (points[-1][0] - x[a]), d * (points[-1][1] - F[a]))
        rec = [x[a], F[a], d, kind, target, a, []]
        points.append(rec)
        curves.append(rec)
        for i in range(a + 1, b + 1):
            # the loop closes when the motion reaches its target (wiping-out)
            while len(points) >= 2 and points[-1][4] is not None and \
                    d * (x[i] - points[-2][0]) >= 0.0:
                del points[-2:]
            if not points:  # back past a real root: sliding again
                break
            points[-1][6].append(i)
        if points and d * (x[b] - points[-1][0]) > sliding_travel:
            points = []  # entered sliding: the next reversal starts a real root
            root_real = True
    out = []
    for xr, Fr, d, kind, target, a, samples in curves:
        idx = np.asarray(samples, dtype=int)
        if idx.size:
            out.append(TransitionCurve(kind, d, a, d * (x[idx] - xr), d * (F[idx] - Fr), target))
    return out


def _chain(delta: np.ndarray, widths: Sequence[float], c: Sequence[float],
           k: Sequence[float], tail: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Raw shape ``Phi(Delta)`` (chained Eq. 13 segments, then slope ``tail`` = sigma0)
    and its derivatives in ``c`` and ``k``."""
    n, m = delta.size, len(widths)
    phi = np.zeros(n)
    dc = np.zeros((n, m))
    dk = np.zeros((n, m))
    start = 0.0
    for i, (w, ci, ki) in enumerate(zip(widths, c, k, strict=True)):
        u = np.clip(delta - start, 0.0, max(w, 0.0))
        e = np.exp(-ki * u)
        phi += ci * (1.0 - e)
        dc[:, i] = 1.0 - e
        dk[:, i] = ci * u * e
        start += max(w, 0.0)
    phi += tail * np.maximum(delta - start, 0.0)
    return phi, dc, dk


def shape_widths(values: Mapping[str, float]) -> dict[str, list[float]]:
    """Segment widths (m) of the three curve classes from the boundaries (Masing's rule)."""
    v = values
    return {
        "ascending": [v["z1"], v["z3"], v["z5"] - v["z3"]],
        "descending": [v["z5"] - v["z4"], v["z4"] - v["z2"], v["z2"] + v["z1"]],
        "internal": [v["internal_zd"] - v["internal_zc"]],
    }


@dataclass
class HysteresisFit:
    """Result of :func:`fit_hysteresis`."""

    values: dict[str, float]
    names: list[str]
    solution: Solution
    uncertainty: Uncertainty
    rms: float
    curves: dict[str, int] = field(default_factory=dict)
    not_identifiable: list[str] = field(default_factory=list)

    @property
    def stderr(self) -> dict[str, float]:
        return {n: float(s) for n, s in zip(self.names, self.uncertainty.stderr, strict=True)}


def fit_hysteresis(
    x: np.ndarray,
    F: np.ndarray,
    values: Mapping[str, float],
    specs: Mapping[str, ParamSpec],
    *,
    free: Sequence[str] = (*EXTERNAL, *INTERNAL),
    tol: float | None = None,
    max_nfev: int = 200,
    level: float = 0.95,
    label: str = "record",
) -> HysteresisFit:
    """Fit ``c_i, k_i`` to the transition curves of ``(x, F)`` (see the module docstring).

    Parameters
    ----------
    x, F
        Position (m) and friction force (N) samples.
    values
        The model's flat values: boundaries ``z1..z5``, ``internal_zc/zd`` and
        start values of the ``c_i, k_i``.
    specs
        Parameter specs (bounds) of the ``c_i, k_i``.
    free
        Which of ``c1..k3, c8, k8`` to fit.
    tol
        Reversal deadband (m); default ``max(5*noise, 1 %`` of ``z1 + z5)``.
    """
    widths = shape_widths(values)
    ext_range = float(sum(widths["ascending"]))
    int_range = float(sum(widths["internal"]))
    if not ext_range > 0:
        raise FcompError(f"{label}: the external loop has zero width (z1 + z5 = 0)")
    if tol is None:
        tol = max(5.0 * position_noise(x), 0.01 * ext_range)
    sigma0 = float(values["sigma0"])
    zs = max(values.get(k, 0.0) for k in ("Fs", "Fs_pos", "Fs_neg", "Fc", "Fc_pos", "Fc_neg"))
    curves = transition_curves(x, F, sliding_travel=2.0 * zs / sigma0, tol=tol)
    counts = {k: sum(c.kind == k for c in curves) for k in ("ascending", "descending", "internal")}
    groups = []
    for c in curves:
        limit = int_range if c.kind == "internal" else ext_range
        m = (c.delta > 0) & (c.delta <= limit)
        if m.any():
            groups.append((c.kind, c.delta[m], c.rise[m], c.target))
    n_ext = sum(g[1].size for g in groups if g[0] != "internal")
    n_int = sum(g[1].size for g in groups if g[0] == "internal")
    unknown = [n for n in free if n not in (*EXTERNAL, *INTERNAL)]
    if unknown:
        raise FcompError(f"fit_hysteresis: no segment parameter(s) {', '.join(unknown)}")
    dropped = [n for n in free if (n in EXTERNAL and n_ext < 8) or (n in INTERNAL and n_int < 4)]
    names = [n for n in free if n not in dropped]
    if not names:
        raise FcompError(f"{label}: no transition curves within the identified deflection range "
                         f"({ext_range * 1e3:.3g} mm) to fit the hysteresis segments to")
    start = {n: float(values[n]) for n in (*EXTERNAL, *INTERNAL)}
    start.update(_data_start(groups, widths, names))

    def fun(theta: np.ndarray, need_jac: bool) -> tuple[np.ndarray, np.ndarray]:
        vals = {**start, **dict(zip(names, theta, strict=True))}
        rs, gs = [], []
        for kind, delta, rise, target in groups:
            params = INTERNAL if kind == "internal" else EXTERNAL
            cn, kn = params[0::2], params[1::2]
            cv, kv = [vals[c] for c in cn], [vals[k] for k in kn]
            phi, dc, dk = _chain(delta, widths[kind], cv, kv, sigma0)
            if target is not None and target[0] > 0:
                pt, dct, dkt = _chain(np.array([target[0]]), widths[kind], cv, kv, sigma0)
                lam = max(target[1], 0.0) / pt[0] if pt[0] > 0 else 1.0
                # d(lam*phi) = lam*(dphi - phi*dphi_t/phi_t)
                dc = lam * (dc - np.outer(phi, dct[0]) / pt[0])
                dk = lam * (dk - np.outer(phi, dkt[0]) / pt[0])
                phi = lam * phi
            G = np.zeros((delta.size, len(names)))
            for i, (c, k) in enumerate(zip(cn, kn, strict=True)):
                if c in names:
                    G[:, names.index(c)] = dc[:, i]
                if k in names:
                    G[:, names.index(k)] = dk[:, i]
            rs.append(rise - phi)
            gs.append(G)
        return np.concatenate(rs), np.vstack(gs)

    pv = ParameterVector.build(names, start, {n: specs[n] for n in names})
    sol = solve(pv, fun, max_nfev=max_nfev, what=f"{label}: hysteresis segment fit",
                compress=True)
    unc = estimate(sol.jacobian, sol.residuals, sol.theta, level=level)
    out = {n: float(v) for n, v in zip(names, sol.theta, strict=True)}
    rms = float(np.sqrt(np.mean(sol.residuals**2)))
    return HysteresisFit(out, names, sol, unc, rms, counts, dropped)


def _data_start(groups: list, widths: Mapping[str, list[float]],
                names: Sequence[str]) -> dict[str, float]:
    """Start values from the raw (unscaled) curves: ``c_i`` the mean rise over segment ``i``
    divided by ``1 - exp(-3)``, ``k_i = 3/width_i`` (95 % of the rise within the segment)."""
    out: dict[str, float] = {}
    for kinds, params in ((("ascending", "descending"), EXTERNAL), (("internal",), INTERNAL)):
        for i in range(len(params) // 2):
            cn, kn = params[2 * i], params[2 * i + 1]
            rises = []
            for kind, delta, rise, target in groups:
                if kind not in kinds or target is not None:
                    continue
                w = widths[kind]
                lo, hi = sum(w[:i]), sum(w[: i + 1])
                inside = (delta > lo) & (delta <= hi)
                if inside.sum() >= 2:
                    rises.append(float(rise[inside][-1] - rise[inside][0]))
            wi = widths[kinds[0]][i]
            if cn in names and rises:
                out[cn] = max(float(np.mean(rises)), 1e-6) / (1.0 - math.exp(-3.0))
            if kn in names and wi > 0:
                out[kn] = 3.0 / wi
    return out
