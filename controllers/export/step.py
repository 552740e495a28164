"""The exported step, symbolic: one sample of a controller as a CasADi function
``step(state, y, ref) -> (u, state_next)`` (:mod:`controllers.export`, "What each
controller's step holds")."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from fcomp.errors import FcompError

#: Controllers :func:`export_controller` exports (``mpc`` as its fixed-iteration form).
EXPORTABLE = ("pid", "pid-ff", "lugre-observer", "ekf", "mpc")
#: Name of the CasADi function (and of its C file).
CASADI_NAME = "fcomp_ctrl_casadi"
#: ``casadi_int`` of the generated code (also the type of ``iw`` in the struct).
CASADI_INT = "long long int"


@dataclass
class _Shape:
    """The state and reference of an exported step."""

    state0: np.ndarray
    layout: list[tuple[str, int]]
    note: str
    n_ref: int = 3

    @property
    def n_state(self) -> int:
        return int(self.state0.size)


@dataclass(kw_only=True)
class StepExport(_Shape):
    """One controller step as a CasADi function (module docstring).

    Attributes
    ----------
    fn
        ``(state, y, ref) -> (u, state_next)``.
    state0
        The state after ``fcomp_ctrl_init`` (``started = 0``).
    layout
        ``(name, size)`` of the state's blocks, in order.
    note
        What the exported step does, one line.
    n_ref
        Size of the reference (3, the MPC's ``3 + horizon``).
    """

    fn: ca.Function


# ----------------------------------------------------------------- symbolic step
def _cummax(v: list[Any]) -> list[Any]:
    out = [v[0]]
    for e in v[1:]:
        out.append(ca.fmax(out[-1], e))
    return out


def _valve_command(valve: Any, F_d: Any, y: Any, v: Any) -> tuple[Any, Any]:
    """:meth:`controllers.force_to_valve.ForceToValve.command`, symbolic: ``(u, sat)``."""
    model = valve.model
    grid = [float(g) for g in valve.grid]
    F_a = (y[1] - model.p_atm) * model.A1 - (y[2] - model.p_atm) * model.A2
    target = valve.bandwidth * (F_d - F_a)
    meas = ca.vertcat(y[0], v, y[1], y[2])
    raw = valve._rates.fn(meas, ca.DM(valve.grid), ca.DM(valve.p))
    rates = _cummax([raw[k] for k in range(len(grid))])
    n = len(grid)

    def seg(j: int) -> Any:  # numpy.interp's slope*(x - xp[j]) + fp[j]
        slope = (grid[j + 1] - grid[j]) / (rates[j + 1] - rates[j])
        return slope * (target - rates[j]) + grid[j]

    inner = seg(n - 2)
    for j in range(n - 3, -1, -1):
        inner = ca.if_else(target < rates[j + 1], seg(j), inner)
    u = ca.if_else(target >= rates[-1], grid[-1], ca.if_else(target <= rates[0], grid[0], inner))
    sat = ca.if_else(target >= rates[-1], 1.0, ca.if_else(target <= rates[0], -1.0, 0.0))
    return u, sat


def _ekf_update(ekf: Any, xi: Any, P: Any, u_prev: Any, y: Any) -> tuple[Any, Any, Any]:
    """:meth:`controllers.ekf.FrictionEKF.step` and ``friction``, symbolic (filterpy's
    equations): ``(xi_next, P_next, F_hat)`` on the scaled state."""
    nx = ekf.model.nx
    pv, scv = ca.DM(ekf.p), ca.DM(ekf.scale)
    xn, A = ekf._predict.fn(xi, u_prev, pv, scv)
    P = ca.mtimes(ca.mtimes(A, P), A.T) + ca.DM(ekf.Q)
    H = ca.DM(ekf.H)
    R = ca.DM(ekf.R)
    PHT = ca.mtimes(P, H.T)
    S = ca.mtimes(H, PHT) + R
    K = ca.mtimes(PHT, ca.inv(S))
    z = y / ca.DM(ekf.r)
    xi_new = xn + ca.mtimes(K, z - ca.mtimes(H, xn))
    I_KH = ca.DM.eye(nx) - ca.mtimes(K, H)
    P_new = ca.mtimes(ca.mtimes(I_KH, P), I_KH.T) + ca.mtimes(ca.mtimes(K, R), K.T)
    F_hat = ekf._friction.fn(xi_new, u_prev, pv, scv)
    return xi_new, P_new, F_hat


def _all_finite(*ms: Any) -> Any:
    """1 if every entry of the matrices is finite (NaN and inf give 0)."""
    bad = 0
    for m in ms:
        bad = bad + ca.sum1(ca.vec(ca.fabs(m) < np.inf) == 0)
    return bad == 0


@dataclass(kw_only=True)
class _Law(_Shape):
    """A controller's law as a graph builder: ``graph(s, y, ref, reenter, u_hold) -> (u,
    s_next)`` on the state ``s`` of ``layout`` (``reenter`` None: the plain step; else the
    fail-safe layer's re-entry flag and held command, :mod:`controllers.safety`)."""

    graph: Callable[[Any, Any, Any, Any, Any], tuple[Any, Any]]


def _mpc_law(ctrl: Any) -> _Law:
    """The law of :class:`controllers.mpc_fixed.FixedIterationMPC` (module docstring)."""
    m = ctrl.model
    ekf = ctrl.ekf
    sol = ctrl.solver
    pb = ctrl.problem
    N = pb.horizon
    nx = ekf.model.nx
    dt = float(ctrl.dt)
    layout = [("ekf_x", nx), ("ekf_P", nx * nx), ("u_prev", 1), ("U", N), ("lam", 2 * N)]
    ns = sum(k for _, k in layout)
    # re-entry (MPCController.reenter): the EKF from the measurement, the warm start at u
    sc = np.asarray(ekf.scale, dtype=float)
    xi0, Pi0 = _ekf_start(m, ekf, sc)

    def graph(s: Any, y: Any, ref: Any, reenter: Any, u_hold: Any) -> tuple[Any, Any]:
        r, dr, ddr = ref[0], ref[1], ref[2]
        i = 0
        xi = s[i:i + nx]
        i += nx
        P = ca.reshape(s[i:i + nx * nx], nx, nx)
        i += nx * nx
        u_prev = s[i]
        i += 1
        U = s[i:i + N]
        i += N
        lam = s[i:i + 2 * N]
        if reenter is not None:
            xi = ca.if_else(reenter, xi0(y), xi)
            P = ca.if_else(reenter, Pi0, P)
            u_prev = ca.if_else(reenter, u_hold, u_prev)
            U = ca.if_else(reenter, ca.repmat(u_hold, N, 1), U)
            lam = ca.if_else(reenter, ca.DM.zeros(2 * N), lam)
        xi_new, P_new, F_hat = _ekf_update(ekf, xi, P, u_prev, y)
        x_hat = xi_new * ca.DM(ekf.scale)
        R = ref[3:3 + N]
        V = (R - ca.vertcat(r, R[:N - 1])) / dt
        U_s = ca.vertcat(U[1:], U[N - 1])
        H, g, _cost, _X = sol._lin.fn(x_hat, U_s, u_prev, R, V, ca.DM(sol.p),
                                      ca.DM(sol.scales))
        ok_lin = _all_finite(H, g)
        eye = ca.DM.eye(N)
        H = H + (sol.reg * ca.fmax(ca.trace(H) / N, 1.0)) * eye
        D = ca.DM(sol.D)
        du = pb.du_max * pb.dt
        diff = ca.mtimes(D, U_s) - ca.vertcat(u_prev, ca.DM.zeros(N - 1))
        upper = ca.vertcat(pb.u_max - U_s, du - diff)
        lower = ca.vertcat(-pb.u_max - U_s, -du - diff)
        A = ca.DM(sol.A)
        rho = sol.rho_rel * ca.trace(H) / N
        sigma = 1e-6 * rho
        Kinv = ca.inv(H + sigma * eye + rho * ca.DM(sol.A.T @ sol.A))
        x = ca.DM.zeros(N)
        z = ca.fmin(ca.fmax(ca.DM.zeros(2 * N), lower), upper)
        for _ in range(sol.qp_iterations):
            x = ca.mtimes(Kinv, sigma * x - g + ca.mtimes(A.T, rho * z - lam))
            Ax = ca.mtimes(A, x)
            z = ca.fmin(ca.fmax(Ax + lam / rho, lower), upper)
            lam = lam + rho * (Ax - z)
        ok = ca.logic_and(ok_lin, _all_finite(x, lam))
        U_new = ca.fmin(ca.fmax(U_s + x, -pb.u_max), pb.u_max)
        # the fallback law (MPCController._fallback)
        fg = ctrl.fallback_gains
        v = x_hat[ctrl.iv]
        demand = m.mass * ddr + m.weight + fg.kp * (r - y[0]) + fg.kd * (dr - v) + F_hat
        demand = ca.fmin(ca.fmax(demand, m.force_min), m.force_max)
        u_fb, _sat = _valve_command(ctrl.valve, demand, y, v)
        u_fb = ca.fmin(ca.fmax(u_fb, u_prev - pb.du_max * dt), u_prev + pb.du_max * dt)
        u = ca.if_else(ok, U_new[0], u_fb)
        U_next = ca.if_else(ok, U_new, ca.repmat(u_fb, N, 1))
        lam_next = ca.if_else(ok, lam, ca.DM.zeros(2 * N))
        return u, ca.vertcat(xi_new, ca.reshape(P_new, nx * nx, 1), u, U_next, lam_next)

    return _Law(graph=graph, state0=np.zeros(ns), layout=layout, n_ref=3 + N,
                note=f"MPC real-time iteration (EKF, condensed Gauss-Newton, QP by "
                f"{sol.qp_iterations} ADMM iterations, not DAQP) with its fallback law")


def _ekf_start(m: Any, ekf: Any, sc: np.ndarray) -> tuple[Callable[[Any], Any], Any]:
    """The EKF's start from a measurement (:meth:`controllers.ekf.FrictionEKF.reset` with
    :meth:`~controllers.plant_model.ControlModel.estimator_initial`), scaled: ``(xi0(y), P0)``:
    the model at rest with the measured states set."""
    nx = ekf.model.nx
    x0 = np.asarray(m.initial_state(np.zeros(3)), dtype=float)
    _, P0 = m.estimator_initial(np.zeros(3))
    sel = np.zeros((nx, 3))
    keep = np.ones(nx)
    for row, i in enumerate(ekf.model.measured):
        sel[i, row] = 1.0 / sc[i]
        keep[i] = 0.0
    Pi0 = ca.DM(np.asarray(P0, dtype=float) / np.outer(sc, sc))
    return (lambda y: ca.DM(keep * x0 / sc) + ca.mtimes(ca.DM(sel), y)), Pi0


def _pid_law(ctrl: Any) -> _Law:
    """The law of a PID-based controller (module docstring)."""
    from controllers.ekf import EKFController
    from controllers.feedforward import PIDFeedforwardController
    from controllers.lugre_observer import LuGreObserverController
    from controllers.safety import SYMBOLIC, bumpless_integral, clamp_integral

    m = ctrl.model
    law = ctrl.law
    g = ctrl.gains
    dt = float(ctrl.dt)
    layout = [("started", 1), ("integral", 1), ("v_f", 1), ("x_prev", 1)]
    dynamic_ff = isinstance(ctrl, PIDFeedforwardController) and ctrl.dynamic
    if isinstance(ctrl, LuGreObserverController):
        nf = m.friction.n_states
        xh0 = np.asarray(m.friction.initial_state(), dtype=float).ravel()
        layout += [("observer", nf), ("side", 1)]
        note = "PID + LuGre observer (Canudas de Wit et al. 1995) + force-to-valve inversion"
    elif isinstance(ctrl, EKFController):
        ekf = ctrl.ekf
        nx = ekf.model.nx
        sc = np.asarray(ekf.scale, dtype=float)
        xi0, Pi0 = _ekf_start(m, ekf, sc)
        layout += [("ekf_x", nx), ("ekf_P", nx * nx), ("u_prev", 1)]
        note = "PID + EKF friction estimate (filterpy's EKF equations) + force-to-valve inversion"
    elif dynamic_ff:
        nf = m.friction.n_states
        xh0 = np.asarray(m.friction.initial_state(), dtype=float).ravel()
        layout += [("feedforward", nf), ("side", 1)]
        note = "PID + friction feedforward along the reference + force-to-valve inversion"
    elif isinstance(ctrl, PIDFeedforwardController):
        note = "PID + static friction feedforward + force-to-valve inversion"
    else:
        note = "PID + force-to-valve inversion"
    lead = bool(ctrl.uses_friction and ctrl.friction_lead)
    if lead:  # PIDController.friction_demand: the previous estimate, last
        layout += [("F_prev", 1)]
    state0 = np.zeros(sum(k for _, k in layout))
    if isinstance(ctrl, LuGreObserverController) or dynamic_ff:
        state0[4:4 + nf] = xh0
        state0[4 + nf] = 1.0
    bounds = ctrl.integral_bounds

    def graph(s: Any, y: Any, ref: Any, reenter: Any, u_hold: Any) -> tuple[Any, Any]:
        r, dr, ddr = ref[0], ref[1], ref[2]
        started = s[0] != 0
        if reenter is not None:  # re-entry resets as the first step does (PIDController.reenter)
            started = ca.logic_and(started, ca.logic_not(reenter))
        x = y[0]
        # reset on the first step (Controller.reset from y0)
        v_f_prev = ca.if_else(started, s[2], 0.0)
        x_prev = ca.if_else(started, s[3], x)
        e = r - x
        v_f = (law.Tf * v_f_prev + x - x_prev) / (law.Tf + dt)
        p1g = y[1] - m.p_atm
        p2g = y[2] - m.p_atm
        comp_next: list[Any] = []
        v_inv = v_f
        if isinstance(ctrl, LuGreObserverController):
            xh = ca.if_else(started, s[4:4 + nf], ca.DM(xh0))
            side_prev = ca.if_else(started, s[4 + nf], 1.0)
            side = ca.if_else(v_f != 0, ca.if_else(v_f > 0, 1.0, -1.0), side_prev)
            sig = ca.vertcat(v_f, ddr, x, p1g, p2g, side)
            c = -ctrl.k * (x - r)
            xh_next, F_hat = ctrl._step(xh, sig, c, dt)
            comp_next = [xh_next, side]
        elif isinstance(ctrl, EKFController):
            xi = ca.if_else(started, s[4:4 + nx], xi0(y))
            P = ca.if_else(started, ca.reshape(s[4 + nx:4 + nx + nx * nx], nx, nx), Pi0)
            u_start = 0.0 if reenter is None else ca.if_else(reenter, u_hold, 0.0)
            u_prev = ca.if_else(started, s[4 + nx + nx * nx], u_start)
            xi_new, P_new, F_hat = _ekf_update(ekf, xi, P, u_prev, y)
            v_inv = xi_new[ctrl.iv] * float(sc[ctrl.iv])
            comp_next = [xi_new, ca.reshape(P_new, nx * nx, 1)]  # u_prev appended below
        elif dynamic_ff:  # PIDFeedforwardController.compensation: along the reference
            xf = ca.if_else(started, s[4:4 + nf], ca.DM(xh0))
            side_prev = ca.if_else(started, s[4 + nf], 1.0)
            side = ca.if_else(dr != 0, ca.if_else(dr > 0, 1.0, -1.0), side_prev)
            xf_next, F_hat = ctrl._step(xf, ca.vertcat(dr, ddr, r, p1g, p2g, side), 0.0, dt)
            comp_next = [xf_next, side]
        elif isinstance(ctrl, PIDFeedforwardController):
            F_map = ctrl._map(dr, r, p1g, p2g)
            F_hat = ca.if_else(dr == 0, 0.0, F_map * ca.fmin(ca.fabs(dr) / ctrl.band, 1.0))
        else:
            F_hat = ca.MX(0.0)
        F_dem = F_hat
        if lead:  # the estimate's lead through the force loop (none on the first step)
            F_prev = ca.if_else(started, s[-1], F_hat)
            F_dem = F_hat + (F_hat - F_prev) / (dt * ctrl.valve.bandwidth)
        if reenter is None:
            integral0: Any = 0.0
        else:  # bumpless: the demand equals the measured actuator force
            other = (m.mass * ddr + m.weight
                     + (g.kp * e + g.ki * dt * e + g.kd * (dr - v_f)) + F_dem)
            F_a = p1g * m.A1 - p2g * m.A2
            integral0 = ca.if_else(reenter, bumpless_integral(SYMBOLIC, F_a, other, g.ki, bounds),
                                   0.0)
        integral = ca.if_else(started, s[1], integral0)
        demand = (m.mass * ddr + m.weight
                  + (g.kp * e + g.ki * (integral + dt * e) + g.kd * (dr - v_f))
                  + F_dem)  # the backward-Euler integral of PIDLaw.force
        applied = ca.fmin(ca.fmax(demand, m.force_min), m.force_max)
        lam = ctrl.velocity_compensation  # PIDController.step's velocity mix
        u, sat = _valve_command(ctrl.valve, applied, y, lam * v_inv + (1.0 - lam) * dr)
        if g.ki == 0:
            integral_next = integral
        else:
            integral_next = ca.if_else(sat * e > 0, integral,
                                       integral + dt * (e + g.kt * (applied - demand) / g.ki))
        integral_next = clamp_integral(SYMBOLIC, integral_next, bounds)
        if isinstance(ctrl, EKFController):
            comp_next.append(u)
        if lead:
            comp_next.append(F_hat)
        return u, ca.vertcat(1.0, integral_next, v_f, x, *comp_next)

    return _Law(graph=graph, state0=state0, layout=layout, note=note)


def _law(ctrl: Any) -> _Law:
    """The law of the Python controller ``ctrl`` (behind its fail-safe layer or not)."""
    from controllers.mpc import MPCController
    from controllers.mpc_fixed import FixedIterationMPC
    from controllers.pid import PIDController
    from controllers.safety import unwrap

    ctrl = unwrap(ctrl)
    name = getattr(ctrl, "name", type(ctrl).__name__)
    if isinstance(ctrl, FixedIterationMPC):
        return _mpc_law(ctrl)
    if isinstance(ctrl, MPCController):
        raise FcompError("export: this mpc solves its QP with DAQP, an active-set solver CasADi "
                         "cannot generate as C; export controllers.mpc_fixed.FixedIterationMPC "
                         "(the same MPC with a fixed-iteration QP)")
    if not isinstance(ctrl, PIDController) or name not in EXPORTABLE:
        raise FcompError(f"export: controller {name} is not exported (exported: "
                         f"{', '.join(EXPORTABLE)})")
    return _pid_law(ctrl)


def step_function(ctrl: Any) -> StepExport:
    """The step of the Python controller ``ctrl`` (built, not yet reset) as a CasADi function:
    the controller's law alone, without the fail-safe layer (a controller behind the layer
    is unwrapped: :func:`controllers.safety.unwrap`).

    Raises
    ------
    FcompError
        For a controller that is not exported (``mpc`` with DAQP; module docstring).
    """
    law = _law(ctrl)
    s = ca.MX.sym("state", law.n_state)
    y = ca.MX.sym("y", 3)
    ref = ca.MX.sym("ref", law.n_ref)
    u, s_next = law.graph(s, y, ref, None, None)
    fn = ca.Function(CASADI_NAME, [s, y, ref], [u, s_next], ["state", "y", "ref"],
                     ["u", "state_next"])
    return StepExport(fn=fn, state0=law.state0, layout=law.layout, note=law.note,
                      n_ref=law.n_ref)


def guarded_step_function(ctrl: Any) -> StepExport:
    """The step of ``ctrl`` behind the fail-safe layer (:mod:`controllers.safety`, its rules
    generated from the same functions the Python layer runs) as a CasADi function: the law's
    state, then the layer's (:data:`controllers.safety.LAYOUT`).

    The law steps on the held and clipped inputs; while the layer does not run it (latched,
    not started) its state is kept; its ``u_prev`` block (EKF, MPC) takes the command the
    layer gave, as :meth:`controllers.base.Controller.applied` does in Python.
    """
    from controllers.safety import LAYOUT, N_STATE, SYMBOLIC, FailSafe, Limits, U, admit, settle
    from controllers.safety import initial_state as fs_initial

    law = _law(ctrl)
    lim = ctrl.limits if isinstance(ctrl, FailSafe) else Limits.of(ctrl.model, ctrl.dt)
    nl = law.n_state
    s = ca.MX.sym("state", nl + N_STATE)
    y = ca.MX.sym("y", 3)
    ref = ca.MX.sym("ref", law.n_ref)
    s_law = s[:nl]
    fs = [s[nl + k] for k in range(N_STATE)]
    a = admit(SYMBOLIC, lim, fs, [y[k] for k in range(3)], [ref[k] for k in range(law.n_ref)],
              _all_finite(s_law))
    u_law, s_law_next = law.graph(s_law, ca.vertcat(*a.y), ca.vertcat(*a.ref), a.reenter,
                                  a.mid[U])
    u, fs_next = settle(SYMBOLIC, lim, a.mid, a.run, u_law, a.counted)
    names = [n for n, _ in law.layout]
    if "u_prev" in names:  # Controller.applied: the estimator predicts with the given command
        i = sum(k for n, k in law.layout[:names.index("u_prev")])
        s_law_next = ca.vertcat(s_law_next[:i], u, s_law_next[i + 1:])
    s_next = ca.vertcat(ca.if_else(a.run, s_law_next, s_law), *fs_next)
    fn = ca.Function(CASADI_NAME, [s, y, ref], [u, s_next], ["state", "y", "ref"],
                     ["u", "state_next"])
    return StepExport(fn=fn, state0=np.concatenate([law.state0, fs_initial()]),
                      layout=law.layout + LAYOUT, n_ref=law.n_ref,
                      note=law.note + ", behind the fail-safe layer")
