"""Laws with an internal state, integrated exactly interval by interval on the fine grid.

Convention: the motion is given per fine interval (velocity ``v[i]`` held
over ``[t_i, t_i + dt]``), a level ``g`` (N) at the nodes ``t_i``; every
state is advanced by the exact solution of its ODE for the held velocity
(with the interval's mean level), and the force is returned at the nodes,
computed from the state *before* the interval, so it lines up with the
sampled position. States do not change while ``v = 0`` (except the film and
the lag filters, which relax with time), so the loops skip the rest
intervals.

Sources
-------
* Canudas de Wit, C., Olsson, H., Astrom, K. J. & Lischinsky, P. (1995). A new
  model for control of systems with friction. *IEEE TAC* 40, 419-425 (bristle).
* Dahl, P. R. (1976). Solid friction damping of mechanical vibrations. *AIAA J.*
  14, 1675-1682 (``dF/dx = sigma0*|1 - F/Fc*s|^i*sign(1 - F/Fc*s)``).
* Dupont, P., Hayward, V., Armstrong, B. & Altpeter, F. (2002). Single state
  elastoplastic friction models. *IEEE TAC* 47, 787-792.
* Lampaert, V., Swevers, J. & Al-Bender, F. (2002). Modification of the Leuven
  integrated friction model structure. *IEEE TAC* 47, 683-687 (Maxwell slip).
* Hess, D. P. & Soom, A. (1990), *J. Tribology* 112, 147-152 (frictional lag).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.signal import lfilter

from fcomp.synthetic.catalogue import Law


def _interval_mean(g: np.ndarray) -> np.ndarray:
    """Mean of the two ends of every interval (the last interval holds its start value)."""
    out = np.empty_like(g)
    out[:-1] = 0.5 * (g[:-1] + g[1:])
    out[-1] = g[-1]
    return out


def _before(after: np.ndarray, moving: np.ndarray, n: int, initial: float = 0.0) -> np.ndarray:
    """State at every node from the states after the moving intervals (rest keeps the state)."""
    last = np.searchsorted(moving, np.arange(n), side="left") - 1
    out = np.full(n, initial)
    ok = last >= 0
    out[ok] = after[last[ok]]
    return out


def bristle(v: np.ndarray, vn: np.ndarray, g: np.ndarray, k: float, damp: float, dt: float
            ) -> np.ndarray:
    """LuGre bristle ``dz/dt = v - k*|v|*z/g``, ``F = k*z + damp*dz/dt`` (Canudas de Wit 1995).

    Exact for the velocity held over each fine interval:
    ``z(dt) = z_ss + (z0 - z_ss)*exp(-k*|v|*dt/g_m)``, ``z_ss = s*g_m/k``, ``g_m`` the
    interval's mean level. ``g`` at the nodes; returns the force at the nodes (N),
    with ``dz/dt`` evaluated at the node velocity ``vn``.
    """
    z = 0.0
    n = v.size
    out = np.empty_like(v)
    gl, vl, vnl = g.tolist(), v.tolist(), vn.tolist()
    for i in range(n):
        gi = gl[i]
        vni = vnl[i]
        dz = vni - k * abs(vni) * z / gi
        out[i] = k * z + damp * dz
        vi = vl[i]
        if vi != 0.0:
            gm = 0.5 * (gi + gl[min(i + 1, n - 1)])
            zss = gm / k * (1.0 if vi > 0 else -1.0)
            z = zss + (z - zss) * math.exp(-k * abs(vi) / gm * dt)
    return out


def dahl(v: np.ndarray, g: np.ndarray, k: float, exponent: float, dt: float) -> np.ndarray:
    """Dahl's model ``dF/dx = k*|y|^i*sign(y)``, ``y = 1 - F*s/g`` (Dahl 1976), at the nodes (N).

    With the displacement ``d = |v|*dt`` of an interval, ``dy/dd = -(k/g)*|y|^i*sign(y)``
    has the exact solution ``|y|^(1-i) = |y0|^(1-i) + (i - 1)*k*d/g`` (``i > 1``), or
    ``|y| = |y0|*exp(-k*d/g)`` (``i = 1``, the bristle); ``y`` keeps its sign.
    """
    moving = np.flatnonzero(v)
    gm = _interval_mean(g)[moving].tolist()
    after = np.empty(moving.size)
    F = 0.0
    one_minus_i = 1.0 - exponent
    for j, vi in enumerate(v[moving].tolist()):
        gi = gm[j]
        s = 1.0 if vi > 0.0 else -1.0
        y = 1.0 - s * F / gi
        if y != 0.0:
            kd = k * abs(vi) * dt / gi
            if one_minus_i == 0.0:
                ay = abs(y) * math.exp(-kd)
            else:
                ay = (abs(y) ** one_minus_i - one_minus_i * kd) ** (1.0 / one_minus_i)
            y = math.copysign(ay, y)
        F = s * gi * (1.0 - y)
        after[j] = F
    return _before(after, moving, v.size)


def elasto_plastic(v: np.ndarray, g: np.ndarray, k: float, ba: float, dt: float) -> np.ndarray:
    """Elasto-plastic presliding (Dupont et al. 2002), ``F = k*z`` at the nodes (N).

    ``dz/dt = v*(1 - alpha(z, v)*z/z_ss(v))``, ``z_ss(v) = s*g/k``. With ``zeta = z/z_ss(v)``:
    ``alpha = 0`` for ``zeta <= ba`` (pure elastic: no slip below the break-away
    displacement ``ba*z_ss``, nor when ``z`` and ``v`` have opposite signs),
    ``alpha = (zeta - ba)/((1 - ba)*zeta)`` for ``ba < zeta < 1`` (a smooth transition:
    ``dzeta/dxi = (1 - zeta)/(1 - ba)`` is continuous at ``ba`` and reaches 0 at 1) and
    ``alpha = 1`` beyond. In the slid distance ``xi = |x|/z_ss`` every phase is exact:
    ``zeta += dxi`` (elastic), ``1 - zeta`` times ``exp(-dxi/(1 - ba))`` (transition),
    ``zeta - 1`` times ``exp(-dxi)`` (above the steady state, after ``g`` fell).
    """
    moving = np.flatnonzero(v)
    gm = _interval_mean(g)[moving].tolist()
    after = np.empty(moving.size)
    z = 0.0
    soft = 1.0 - ba
    for j, vi in enumerate(v[moving].tolist()):
        zss = gm[j] / k
        s = 1.0 if vi > 0.0 else -1.0
        zeta = s * z / zss
        step = abs(vi) * dt / zss
        if zeta < ba:
            el = min(step, ba - zeta)
            zeta += el
            step -= el
        if step > 0.0:
            if zeta <= 1.0:
                zeta = 1.0 - (1.0 - zeta) * math.exp(-step / soft)
            else:
                zeta = 1.0 + (zeta - 1.0) * math.exp(-step)
        z = s * zeta * zss
        after[j] = k * z
    return _before(after, moving, v.size)


def play(dx: np.ndarray, d: float, state: float = 0.0) -> np.ndarray:
    """Play (backlash) operator: ``delta_k = clip(delta_{k-1} + dx_k, -d, d)`` from ``state``.

    Exactly the sequential floating-point recursion, without a Python loop per
    step: between clips the state is a running sum (``numpy.cumsum`` adds in
    order), and once clipped at ``+-d`` it stays there until ``dx`` changes sign.
    """
    n = dx.size
    out = np.empty(n)
    rising, falling = dx > 0.0, dx < 0.0
    k, s, win = 0, float(state), 256
    while k < n:
        if s == d or s == -d:  # saturated: held until the motion reverses
            rev = falling if s > 0 else rising
            j = k + int(np.argmax(rev[k:])) if rev[k:].any() else n
            out[k:j] = s
            k = j
            if k >= n:
                break
        m = min(n, k + win)
        c = np.cumsum(np.concatenate(([s], dx[k:m])))[1:]
        over = np.abs(c) > d
        if over.any():
            j = int(np.argmax(over))
            out[k:k + j] = c[:j]
            s = d if c[j] > 0 else -d
            out[k + j] = s
            k += j + 1
            win = 256
        else:
            out[k:m] = c
            s = float(c[-1])
            k = m
            win *= 2
    return out


def held_at_rest(g: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``g`` held at its last moving value wherever ``v == 0`` (its first value before any motion).

    The Maxwell-slip elements' slip forces ``w_i*g`` follow the Stribeck level while
    they slide; at rest nothing slides, so a rise of ``g`` towards ``Fs`` must not
    change the force the elements hold (their deflections and stiffnesses are
    frozen with the motion).
    """
    moving = v != 0.0
    idx = np.where(moving, np.arange(v.size), 0)
    return g[np.maximum.accumulate(idx)]


def maxwell_slip(law: Law, x: np.ndarray, g: np.ndarray, block: int = 65536) -> np.ndarray:
    """Maxwell-slip model: elasto-slide elements in parallel (Lampaert et al. 2002), N.

    Element ``i`` (``1..N``) has break displacement ``d_i = d_max*(i/N)^p_d`` and slip
    force ``w_i*g`` (shares ``w_i ~ (N + 1 - i)^p_w``, summing to 1), so stiffness
    ``w_i*g/d_i``; its deflection follows the displacement and is clipped to
    ``+-d_i`` (:func:`play`): ``F = sum(w_i*g*delta_i/d_i)``. The result has
    nonlocal memory: return-point memory and wiping out of inner loops.
    """
    n = int(law["n_elements"])
    d = law["d_max"] * (np.arange(1, n + 1) / n) ** law["p_d"]
    w = (n + 1.0 - np.arange(1, n + 1)) ** law["p_w"]
    w = w / np.sum(w)
    dx = np.empty_like(x)
    dx[0] = 0.0
    dx[1:] = x[1:] - x[:-1]
    out = np.empty_like(x)
    state = np.zeros(n)
    for b in range(0, x.size, block):
        sl = slice(b, min(b + block, x.size))
        D = np.empty((sl.stop - sl.start, n))
        for e in range(n):
            D[:, e] = play(dx[sl], float(d[e]), float(state[e]))
        state = D[-1].copy()
        out[sl] = np.sum(w * g[sl, None] * D / d, axis=1)
    return out


def lagged_speed(speed: np.ndarray, tau: float, dt: float) -> np.ndarray:
    """Hess-Soom lagged speed ``dv_L/dt = (|v| - v_L)/tau`` at the nodes (m/s).

    ``speed`` per interval; exact first-order step ``v_L += (|v| - v_L)*(1 - exp(-dt/tau))``.
    """
    c = 1.0 - math.exp(-dt / tau)
    out = np.empty(speed.size)
    cur = 0.0
    for i, sp in enumerate(speed.tolist()):
        out[i] = cur
        cur += (sp - cur) * c
    return out


def film(target: np.ndarray, tau_rise: float, tau_fall: float, dt: float) -> np.ndarray:
    """Lubricant-film fraction ``l`` at the nodes (-), ``dl/dt = (l_ss - l)/tau``.

    ``tau = tau_rise`` while the film builds (``l_ss > l``) and ``tau_fall`` while it
    drains (squeeze film: slower); ``target`` (``l_ss``) per interval, exact for the
    held target. Starts dry. A film-state model in the spirit of Harnoy, Friedland &
    Cohn (2008); unlike the Hess-Soom lag, the lag acts *after* the Stribeck map,
    with different time constants up and down.
    """
    c_up, c_down = math.exp(-dt / tau_rise), math.exp(-dt / tau_fall)
    out = np.empty(target.size)
    lam = 0.0
    for i, tgt in enumerate(target.tolist()):
        out[i] = lam
        lam = tgt + (lam - tgt) * (c_up if tgt > lam else c_down)
    return out


def lowpass(u: np.ndarray, tau: float, dt: float) -> np.ndarray:
    """First-order lag ``dy/dt = (u - y)/tau`` of a sampled signal, exact for a held input,
    starting in steady state at ``u[0]``."""
    if tau <= 0.0:
        return u.copy()
    c = math.exp(-dt / tau)
    y, _ = lfilter([1.0 - c], [1.0, -c], u, zi=[c * float(u[0])])
    return np.asarray(y)


def dwell_excess(v: np.ndarray, dt: float, law: Law,
                 excess_of_rest: Callable[[float], float]) -> np.ndarray:
    """Excess of the static level after each rest, erased as ``exp(-s/d_c)`` (N), at the nodes.

    ``excess_of_rest(t_d)`` gives the excess after a rest of ``t_d`` seconds
    (:func:`fcomp.synthetic.laws.dwell_law`); ``s`` is the distance slid since
    the start. The rig rested 5 s before the record.
    """
    fn = excess_of_rest
    d_c = law["d_c"]
    out = np.zeros_like(v)
    t_rest = 5.0
    bump = 0.0
    s = 0.0
    for i, vi in enumerate(v.tolist()):
        out[i] = bump * math.exp(-s / d_c) if bump else 0.0
        if vi == 0.0:
            t_rest += dt
            continue
        if t_rest > 0.0:  # a start: the excess is set by the dwell just ended
            bump = fn(t_rest)
            s = 0.0
            t_rest = 0.0
            out[i] = bump
        s += abs(vi) * dt
    return out
