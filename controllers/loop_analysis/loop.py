"""The sampled loop as it runs: plant, zero-order hold, computation delay, controller.

At one operating point (:mod:`controllers.loop_analysis.grid`) the loop is

* the plant sampled with a zero-order hold (:class:`plants.linearise.LinearPlant`:
  ``x[k+1] = Ad x[k] + Bd w[k]``, ``y[k] = C x[k]``, ``y = [x, p1, p2]``; the
  sensors measure the states, their noise and quantisation have no linear part);
* the controller (:class:`~controllers.loop_analysis.controller.LinearController`
  or :mod:`controllers.loop_analysis.pid_family`): ``u[k] = K(z) y[k]``;
* the computation delay of ``d`` samples: ``w[k] = u[k - d]`` (``z^-d``).

With the plant's response ``P(z) = C (zI - Ad)^-1 Bd`` (3 x 1) and the
controller's ``K(z)`` (1 x 3), both at ``z = e^{jwT}``, the loop broken

* **at the valve command** (between the delay and the valve) returns
  ``L_u(z) = -z^-d K(z) P(z)``;
* **at the position sensor** (the measured position cut, the pressures still
  fed back) returns ``L_x(z) = -z^-d P_x(z) K_x(z) / (1 - z^-d K_p(z) P_p(z))``,
  ``K_x``, ``K_p`` the controller's position and pressure columns, ``P_x``,
  ``P_p`` the plant's rows;

in the convention of negative feedback (the closed loop is ``1 + L = 0``).
Whether the closed loop is stable comes from the eigenvalues of its state
matrix (:func:`closed_loop_matrix`; states: the plant's, the controller's and
the ``d`` commands in the delay line), not from the Nyquist curve: the open loops
have poles on the unit circle (the piston's and the controller's integrators).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: The points where the loop is broken (:func:`loop_responses`).
BREAKS = ("valve", "position")


#: Largest condition number of an eigenvector basis used for a frequency response (beyond
#: it, the resolvent is solved frequency by frequency).
MAX_EIGENVECTOR_CONDITION = 1e8


def ss_response(A: np.ndarray, B: np.ndarray, C: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``C (zI - A)^-1 B`` at the points ``z``: ``A`` ``(..., n, n)``, ``B`` ``(..., n, m)``,
    ``C`` ``(..., p, n)``; returns ``(..., F, p, m)`` for ``F`` values of ``z``.

    By the eigen-decomposition ``A = V diag(l) V^-1``: ``C V diag(1/(z - l)) V^-1 B``, where
    the eigenvectors are well conditioned (:data:`MAX_EIGENVECTOR_CONDITION`); else (a
    nearly defective matrix: repeated poles such as the delay line's) by solving
    ``(zI - A) X = B`` at each frequency.
    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    C = np.asarray(C, dtype=float)
    n = A.shape[-1]
    lead = np.broadcast_shapes(A.shape[:-2], B.shape[:-2], C.shape[:-2])
    if n == 0:
        return np.zeros((*lead, z.size, C.shape[-2], B.shape[-1]), dtype=complex)
    A = np.broadcast_to(A, (*lead, n, n))
    B = np.broadcast_to(B, (*lead, *B.shape[-2:]))
    C = np.broadcast_to(C, (*lead, *C.shape[-2:]))
    d = balancing(A)  # A -> D^-1 A D, B -> D^-1 B, C -> C D: the same transfer function
    A = A / d[..., :, None] * d[..., None, :]
    B = B / d[..., :, None]
    C = C * d[..., None, :]
    lam, V = np.linalg.eig(A)
    good = np.linalg.cond(V) < MAX_EIGENVECTOR_CONDITION
    out = np.empty((*lead, z.size, C.shape[-2], B.shape[-1]), dtype=complex)
    if np.any(good):
        Vg = V[good]
        CV = C[good] @ Vg
        VB = np.linalg.solve(Vg, B[good].astype(complex))
        R = 1.0 / (z[None, :, None] - lam[good][:, None, :])  # (G, F, n)
        out[good] = np.einsum("gpn,gfn,gnm->gfpm", CV, R, VB)
    if not np.all(good):
        Ab, Bb, Cb = A[~good], B[~good], C[~good]
        M = z[None, :, None, None] * np.eye(n) - Ab[:, None, :, :]
        X = np.linalg.solve(M, np.broadcast_to(Bb.astype(complex)[:, None], M.shape[:-1]
                                               + (Bb.shape[-1],)))
        out[~good] = Cb[:, None] @ X
    return out


def balancing(A: np.ndarray, sweeps: int = 8) -> np.ndarray:
    """Diagonal scalings ``d`` (powers of 2) that balance the rows and columns of each ``A``
    (batched; Parlett & Reinsch, Numer. Math. 13, 1969): ``D^-1 A D`` has comparable row and
    column norms, so that its eigenvectors are not ill-conditioned by the units of the
    states (metres beside pascals)."""
    n = A.shape[-1]
    d = np.ones(A.shape[:-1])
    off = 1.0 - np.eye(n)
    M = np.abs(A) * off
    for _ in range(sweeps):
        B = M / d[..., :, None] * d[..., None, :]
        c = B.sum(axis=-2)
        r = B.sum(axis=-1)
        ok = (c > 0) & (r > 0)
        f = np.where(ok, np.exp2(np.round(0.5 * np.log2(np.where(ok, r / np.where(c > 0, c, 1),
                                                                    1.0)))), 1.0)
        if np.all(f == 1.0):
            break
        d = d * f
    return d


def plant_response(Ad: np.ndarray, Bd: np.ndarray, C: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``P(z) = C (zI - Ad)^-1 Bd`` as ``(..., F, 3)`` (the plant has one input)."""
    return ss_response(Ad, Bd, C, z)[..., 0]


def controller_response(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                        z: np.ndarray) -> np.ndarray:
    """``K(z) = C (zI - A)^-1 B + D`` as ``(..., F, 3)`` (the controller has one output)."""
    return ss_response(A, B, C, z)[..., 0, :] + np.asarray(D)[..., None, 0, :]


def loop_responses(P: np.ndarray, K: np.ndarray, z: np.ndarray, delay: int
                   ) -> dict[str, np.ndarray]:
    """``L_u`` and ``L_x`` (module docstring) from ``P`` and ``K`` ``(..., F, 3)``."""
    zd = z ** (-delay)
    Lu = -zd * np.sum(K * P, axis=-1)
    inner = 1.0 - zd * np.sum(K[..., 1:] * P[..., 1:], axis=-1)
    Lx = -zd * P[..., 0] * K[..., 0] / inner
    return {"valve": Lu, "position": Lx}


def closed_loop_matrix(Ad: np.ndarray, Bd: np.ndarray, C: np.ndarray, Ac: np.ndarray,
                       Bc: np.ndarray, Cc: np.ndarray, Dc: np.ndarray, delay: int
                       ) -> np.ndarray:
    """The closed loop's state matrix (batched over leading axes); states ``[plant,
    controller, delay line]`` (module docstring)."""
    Ad, Bd, Ac, Bc, Cc, Dc = (np.asarray(m, dtype=float) for m in (Ad, Bd, Ac, Bc, Cc, Dc))
    lead = np.broadcast_shapes(Ad.shape[:-2], Ac.shape[:-2])
    n, nc, d = Ad.shape[-1], Ac.shape[-1], int(delay)
    N = n + nc + d
    M = np.zeros((*lead, N, N))
    ip, ic = slice(0, n), slice(n, n + nc)
    M[..., ip, ip] = Ad
    M[..., ic, ic] = Ac
    M[..., ic, ip] = Bc @ C
    if d == 0:
        M[..., ip, ip] += Bd @ (Dc @ C)
        M[..., ip, ic] = Bd @ Cc
    else:
        M[..., n + nc, ip] = (Dc @ C)[..., 0, :]
        M[..., n + nc, ic] = Cc[..., 0, :]
        for j in range(1, d):
            M[..., n + nc + j, n + nc + j - 1] = 1.0
        M[..., ip, n + nc + d - 1] = Bd[..., :, 0]
    return M


#: Closed-loop poles this close to z = 1 are conserved quantities, not modes (two integral
#: actions on the same error -- the PID's and a LuGre observer's bristle correction -- share
#: a load in any proportion: their weighted difference never changes).
INVARIANT = 1e-8


def dominant_pole(M: np.ndarray) -> np.ndarray:
    """The largest-magnitude eigenvalue of each matrix (batched), conserved quantities
    (:data:`INVARIANT`) left out."""
    ev = np.linalg.eigvals(M)
    mag = np.where(np.abs(ev - 1.0) < INVARIANT, 0.0, np.abs(ev))
    i = np.argmax(mag, axis=-1)
    return np.take_along_axis(ev, i[..., None], -1)[..., 0]


def unit_z(w: np.ndarray, dt: float) -> np.ndarray:
    """``z = e^{jwT}``."""
    return np.exp(1j * np.asarray(w) * dt)


def iosystems(Ad: np.ndarray, Bd: np.ndarray, C: np.ndarray, Ac: np.ndarray, Bc: np.ndarray,
              Cc: np.ndarray, Dc: np.ndarray, delay: int, dt: float) -> dict[str, Any]:
    """The two open loops as python-control state-space systems (``L_u``, ``L_x`` of the
    module docstring; for plots and :func:`control.stability_margins`)."""
    import control as ct

    n, nc, d = Ad.shape[0], Ac.shape[0], int(delay)
    N = n + nc + d
    ip, ic = slice(0, n), slice(n, n + nc)
    # at the valve: input w (the applied command), output -u
    A = np.zeros((N, N))
    B = np.zeros((N, 1))
    A[ip, ip], A[ic, ic], A[ic, ip] = Ad, Ac, Bc @ C
    Cv = np.zeros((1, N))
    Cv[0, ip], Cv[0, ic] = (Dc @ C)[0], Cc[0]
    if d == 0:
        B[ip, 0] = Bd[:, 0]
    else:
        B[n + nc, 0] = 1.0
        for j in range(1, d):
            A[n + nc + j, n + nc + j - 1] = 1.0
        A[ip, n + nc + d - 1] = Bd[:, 0]
        # the delay line's head takes w; its tail drives the plant
    valve = ct.ss(A, B, -Cv, np.zeros((1, 1)), dt)
    # at the position sensor: input the measured position, output -x
    A2 = closed_loop_matrix(Ad, Bd, C[1:], Ac, Bc[:, 1:], Cc, Dc[:, 1:], d)
    B2 = np.zeros((N, 1))
    B2[ic, 0] = Bc[:, 0]
    if d == 0:
        B2[ip, 0] = Bd[:, 0] * Dc[0, 0]
    else:
        B2[n + nc, 0] = Dc[0, 0]
    C2 = np.zeros((1, N))
    C2[0, ip] = -C[0]
    position = ct.ss(A2, B2, C2, np.zeros((1, 1)), dt)
    return {"valve": valve, "position": position}


def nyquist_frequency(dt: float) -> float:
    """``pi/T`` (rad/s)."""
    return math.pi / dt


__all__ = ["BREAKS", "closed_loop_matrix", "controller_response", "dominant_pole",
           "iosystems", "loop_responses", "nyquist_frequency", "plant_response",
           "ss_response", "unit_z"]
