"""Exact parameter sensitivities of the friction force along a motion (forward sensitivities).

The simulation engine (:mod:`fcomp.trajectory`) advances the friction states
sample to sample with one CasADi step (:mod:`fcomp.models.stepping`) ``x_{k+1} = Phi(x_k, u_k, dt_k, p)``.
Differentiating that *same* step gives the exact derivative of the simulated
force with respect to the parameters (exact for the discrete scheme that
produces the simulated force, not a finite-difference approximation):

    S_{k+1} = Phi_x S_k + Phi_p,        S_0 = 0   (S = dx/dp, nx x np)
    dF_k/dp = F_x(x_k) S_k + F_p(x_k),

where ``F(x, sig, p)`` is the model's force at sample ``k``. The augmented
step ``[x, S, F, dF/dp] -> [x', S', F', dF'/dp]`` is built symbolically and
compiled to native code by :func:`fcomp.compiled.stepping_loop`; its input at
interval ``k`` is the interval-mean signal vector (what the simulation uses)
followed by the sample signals at ``k+1`` (what the force reads). Models
without states (static maps) use the same loop with ``S`` empty.

A fit evaluates one record many times: the loop keeps the prepared signals
of the record it was last given, and a loop compiled for more parameters of
the same model (at most :data:`WIDER` more) serves a narrower set -- the
trajectory stage probes all free parameters, then fits those the record
determines -- instead of compiling again. The last results (up to
:data:`KEEP_BYTES`, read-only) are reused when the same record is asked for at
the same parameters again: a fit asks for its start and its solution more
than once (the probe and the solve's start; the solve's end, the final
residuals and the prediction).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import casadi as ca
import numpy as np

from fcomp.backend import CASADI
from fcomp.compiled import Loop, stepping_loop
from fcomp.models.base import SIGNAL_NAMES, FrictionModel, Signals
from fcomp.models.stepping import friction_step, midpoint_signals, structure_key
from fcomp.parameters import ParamValues

#: The force at the initial state and its derivatives (:func:`_first`).
First = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[float, np.ndarray]]
_LOOPS: dict[tuple, tuple[Loop, First, tuple[str, ...]]] = {}

#: Extra parameters a compiled loop may carry to serve a narrower set (fraction of it, at
#: least one): each costs ~1/len(free) of an evaluation, a new compilation ~10 evaluations.
WIDER = 0.2


#: Bytes of results kept for reuse (the module docstring).
KEEP_BYTES = 64 * 2**20
#: (key, id of the record's first array) -> (record, F, G), oldest first (insertion order):
#: a dict, so a look-up is one hash, not a scan of every result kept (a scan with tuple
#: comparisons took 5 % of a diagnosis of the O-ring files)
_KEPT: dict[tuple, tuple[tuple, np.ndarray, np.ndarray]] = {}
_KEPT_BYTES = [0]  # their bytes (kept as a running sum: summing on every keep cost 3 %)


def _same(a: tuple, b: tuple) -> bool:
    """Whether two tuples hold the very same objects."""
    return len(a) == len(b) and all(x is y for x, y in zip(a, b, strict=True))


def _kept(key: tuple, record: tuple) -> tuple[np.ndarray, np.ndarray] | None:
    hit = _KEPT.get((key, id(record[0])))
    if hit is not None and _same(hit[0], record):
        return hit[1], hit[2]
    return None


def _keep(key: tuple, record: tuple, F: np.ndarray, G: np.ndarray) -> None:
    F.setflags(write=False)
    G.setflags(write=False)
    old = _KEPT.pop((key, id(record[0])), None)
    if old is not None:
        _KEPT_BYTES[0] -= old[1].nbytes + old[2].nbytes
    _KEPT[(key, id(record[0]))] = (record, F, G)
    _KEPT_BYTES[0] += F.nbytes + G.nbytes
    while _KEPT and _KEPT_BYTES[0] > KEEP_BYTES:
        _, F0, G0 = _KEPT.pop(next(iter(_KEPT)))
        _KEPT_BYTES[0] -= F0.nbytes + G0.nbytes


def _wider(key: tuple) -> tuple[Loop, First, tuple[str, ...]] | None:
    """A loop already built for the same model, substeps and mode whose parameters include
    ``key``'s, with at most :data:`WIDER` more; ``None`` if there is none."""
    structure, free, substeps, compiled = key
    room = max(1, int(WIDER * len(free)))
    for (s, f, n, c), entry in _LOOPS.items():
        if (s, n, c) == (structure, substeps, compiled) and set(free) <= set(f) \
                and len(f) <= len(free) + room:
            return entry
    return None


def _build(model: FrictionModel, free: tuple[str, ...], substeps: int, compiled: bool
           ) -> tuple[Loop, First]:
    names = list(model.flat_params())
    fi = [names.index(n) for n in free]
    nx, nf = model.n_states, len(free)
    p, P = ParamValues.symbolic(names)
    u = ca.SX.sym("u", 2 * len(SIGNAL_NAMES))
    dt = ca.SX.sym("dt")
    sig_next = Signals(*[u[len(SIGNAL_NAMES) + i] for i in range(len(SIGNAL_NAMES))])
    xs = ca.SX.sym("xs", nx)
    F = model.force(CASADI, [xs[i] for i in range(nx)], sig_next, P)
    F = ca.SX(F) if not isinstance(F, ca.SX) else F
    force = ca.Function("fcomp_force_sens", [xs, u, p],
                        [F, ca.jacobian(F, xs), ca.jacobian(F, p)[:, fi]])
    w = ca.SX.sym("w", nx + nx * nf + 1 + nf)
    if nx:
        x = w[:nx]
        S = ca.reshape(w[nx : nx + nx * nf], nx, nf)
        xn = friction_step(model, substeps)(x, u[: len(SIGNAL_NAMES)], dt, p)
        Sn = ca.jacobian(xn, x) @ S + ca.jacobian(xn, p)[:, fi]
        Fn, Fx, Fp = force(xn, u, p)
        out = ca.vertcat(xn, ca.vec(Sn), Fn, (Fx @ Sn + Fp).T)
    else:
        Fn, _, Fp = force(ca.SX(0, 1), u, p)
        out = ca.vertcat(Fn, Fp.T)
    step = ca.Function("fcomp_sens_step", [w, u, dt, p], [out])
    return stepping_loop(step, compiled=compiled), _first(force, nx, nf, len(SIGNAL_NAMES),
                                                          compiled)


def _first(force: ca.Function, nx: int, nf: int, ns: int, compiled: bool) -> First:
    """``first(x0, u, p) -> (F0, dF0/dp)``: the force at the initial state and its derivatives
    (the state's sensitivities start at zero), as a compiled one-sample loop: CasADi's own
    call from Python cost 6 % of a diagnosis, once per evaluation."""
    w = ca.SX.sym("w", nx + nx * nf + 1 + nf)
    u = ca.SX.sym("u", 2 * ns)
    dt = ca.SX.sym("dt")
    p = ca.SX.sym("p", force.size1_in(2))
    Fn, _, Fp = force(w[:nx], u, p)
    out = ca.densify(ca.vertcat(w[:nx + nx * nf], Fn, Fp.T))  # every entry written
    loop = stepping_loop(ca.Function("fcomp_sens_first", [w, u, dt, p], [out]),
                         compiled=compiled)
    zero_dt = np.zeros(1)

    def first(x0: np.ndarray, u0: np.ndarray, pvec: np.ndarray) -> tuple[float, np.ndarray]:
        w0 = np.zeros(nx + nx * nf + 1 + nf)
        w0[:nx] = x0
        W = loop(w0, u0.reshape(1, -1), zero_dt, pvec)
        return float(W[1, nx + nx * nf]), W[1, nx + nx * nf + 1:]

    return first


class SensitivityLoop:
    """Friction force and its exact derivatives along a sampled motion.

    Parameters
    ----------
    model
        A symbolic friction model (any effects).
    free
        Flat names of the parameters to differentiate with respect to.
    substeps
        Integration steps per sample interval (as :func:`fcomp.trajectory.friction_along_motion`).
    compiled
        Native-compiled loop (default) or CasADi's virtual machine.

    Calling the object with the prepared signals (:func:`fcomp.trajectory.prepare_signals`)
    and the flat parameter values returns ``(F, G)``: the force (N,) in N and
    ``G[k, j] = dF_k/dp_j`` (N, len(free)).
    """

    def __init__(self, model: FrictionModel, free: Sequence[str], *, substeps: int = 1,
                 compiled: bool = True) -> None:
        model.require_symbolic()
        names = list(model.flat_params())
        unknown = [n for n in free if n not in names]
        if unknown:
            raise ValueError(f"{model.describe()}: no parameter(s) {', '.join(unknown)}")
        self.model = model
        self.free = tuple(free)
        self.names = names
        key = (structure_key(model), self.free, int(substeps), bool(compiled))
        if key not in _LOOPS:
            _LOOPS[key] = _wider(key) or (*_build(model, self.free, int(substeps),
                                                  bool(compiled)), self.free)
        self._loop, self._force, self._loop_free = _LOOPS[key]
        self._cols = [self._loop_free.index(n) for n in self.free]
        self._prep_refs: tuple = ()
        self._prep: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def _prepared(self, sig: Mapping[str, np.ndarray]
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(U, dt, signals at sample 0)`` of ``sig``, kept for the signals last given (the
        same mapping holding the same arrays: a fit's record, which it does not change)."""
        refs = (sig, *(sig[k] for k in ("t", *SIGNAL_NAMES)))
        if self._prep is None or not _same(refs, self._prep_refs):
            M, dt = midpoint_signals(sig)
            S = np.vstack([np.asarray(sig[k], dtype=float) for k in SIGNAL_NAMES])
            U = np.ascontiguousarray(np.vstack([M, S[:, 1:]]).T)
            self._prep, self._prep_refs = (U, dt, S[:, 0].copy()), refs
        return self._prep

    def __call__(
        self,
        sig: Mapping[str, np.ndarray],
        values: Mapping[str, float],
        state0: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        model = self.model
        nx, nf = model.n_states, len(self._loop_free)
        flat = dict(model.flat_params())
        flat.update(values)
        pvec = np.array([flat[n] for n in self.names], dtype=float)
        U, dt, s0 = self._prepared(sig)
        x0 = model.initial_state() if state0 is None else np.asarray(state0, dtype=float)
        key = (id(self._loop), pvec.tobytes(), x0.tobytes())
        known = _kept(key, self._prep_refs)
        if known is None:
            w0 = np.zeros(nx + nx * nf + 1 + nf)
            w0[:nx] = x0
            W = self._loop(w0, U, dt, pvec)
            F0, G0 = self._force(x0, np.concatenate([s0, s0]), pvec)
            F = W[:, nx + nx * nf].copy()  # compact copies: W (with the states) is let go
            G = np.ascontiguousarray(W[:, nx + nx * nf + 1 :])
            F[0] = float(F0)
            G[0] = np.asarray(G0, dtype=float).ravel()
            _keep(key, self._prep_refs, F, G)
        else:
            F, G = known
        if self._cols != list(range(nf)):  # a wider loop: the columns asked for
            G = G[:, self._cols]
        return F, G
