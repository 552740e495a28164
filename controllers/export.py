"""A controller's step as C code: CasADi code generation, a plain C interface, a closed-loop check.

:func:`export_controller` turns one sample of a controller of this package
into a CasADi function ::

    step(state, y, ref) -> (u, state_next)

with a *fixed-size* state vector (layout in :class:`StepExport`), writes its
C code (CasADi's code generator) behind a plain C interface
(``fcomp_ctrl.h``: ``fcomp_ctrl_init``, ``fcomp_ctrl_step``,
``fcomp_ctrl_step_ref``; every work array a fixed-size member of the
``fcomp_ctrl_t`` struct, no allocation anywhere), a ``Makefile`` and a small
``example.c``; then, with a C compiler, builds a shared library, runs the
compiled controller in closed loop against the Python plant of the harness
(:mod:`controllers.harness`: the same plant integration, sensors and
tasks) and checks, at every sample, that its command equals the command of
the *Python* controller (the classes of :mod:`controllers`, stepped in
lock step on the same measurements and references: an independent
implementation of the same law, not the same CasADi function); last it
times the compiled step in a C loop (``fcomp_ctrl_bench``).

What each controller's step holds
---------------------------------
Every exported controller but ``mpc`` is the PID of :mod:`controllers.pid` with its
friction estimate and the force-to-valve inversion of
:mod:`controllers.force_to_valve` (the grid of force rates, its running
maximum and the linear interpolation of ``numpy.interp``, written out as a
chain of ``if_else``); the state vector is ::

    [started, integral, v_f, x_prev, <compensation states>]

``started`` is 0 after ``fcomp_ctrl_init``: the first step then resets the
controller from its measurement, as :meth:`controllers.base.Controller.reset`
does from ``y0`` (the harness resets with the first sample's measurement).
The compensation states are

* ``pid``, ``pid-ff``: none (the feedforward map is static);
* ``lugre-observer``: the observer's friction states, then the side of motion;
* ``ekf``: the scaled state estimate (``nx``), its covariance (``nx*nx``,
  column-major) and the previous command.

The model functions a controller evaluates (force-rate grid, observer step,
steady-state map, EKF prediction and friction) are the controller's own
CasADi functions, called inside the exported step, so the C code computes
the same equations as the Python controller.

``mpc`` solves the quadratic programme of its real-time iteration with DAQP,
an active-set solver with a data-dependent number of iterations that CasADi's
code generator cannot express. It is exported in its *fixed-iteration* form,
:class:`controllers.mpc_fixed.FixedIterationMPC` (the same EKF, linearisation,
warm start, limits and fallback law; the QP by a fixed number of ADMM
iterations), and checked against that form in Python (numpy's ADMM); how far
its commands are from DAQP's is measured in ``docs/compensators.md``. Its
state is ``[ekf_x, ekf_P, u_prev, U (horizon), lam (2*horizon)]``, and
``fcomp_ctrl_init`` sets the state the Python ``reset`` gives at rest at
mid-stroke (the reset solves the plant's equilibrium, which is not
generated); ``fcomp_ctrl_set_state`` sets another. In the check both
compiled instances start from the Python controller's reset state.

Reference input
---------------
``ref = [r, dr, ddr]`` (m, m/s, m/s^2), for ``mpc`` followed by the
positions at the next ``horizon`` samples: ``fcomp_ctrl_step_ref`` takes
them (a trajectory, as the harness gives it); ``fcomp_ctrl_step(c, y, r)``
is the set-point form, ``dr = ddr = 0`` and ``r`` over the horizon (exact for
a held set point).

Compiler
--------
``$FCOMP_CC`` names the C compiler; when it is set and not found, there is
*no* compiler (the documented way to test that path). Otherwise ``$CC``,
``cc``, ``gcc``, ``clang``, the first found. Without one the code is still
written and the check is skipped (``equivalent`` is ``None``).
"""

from __future__ import annotations

import ctypes
import math
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from fcomp.compiled import casadi_c
from fcomp.errors import FcompError

#: Controllers :func:`export_controller` exports (``mpc`` as its fixed-iteration form).
EXPORTABLE = ("pid", "pid-ff", "lugre-observer", "ekf", "mpc")
#: Relative tolerance of the equivalence check.
RTOL = 1e-9
#: Name of the CasADi function (and of its C file).
CASADI_NAME = "fcomp_ctrl_casadi"
#: ``casadi_int`` of the generated code (also the type of ``iw`` in the struct).
CASADI_INT = "long long int"


@dataclass
class StepExport:
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
    """

    fn: ca.Function
    state0: np.ndarray
    layout: list[tuple[str, int]]
    note: str
    n_ref: int = 3

    @property
    def n_state(self) -> int:
        return int(self.state0.size)


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


def _mpc_step(ctrl: Any) -> StepExport:
    """The step of :class:`controllers.mpc_fixed.FixedIterationMPC` (module docstring)."""
    m = ctrl.model
    ekf = ctrl.ekf
    sol = ctrl.solver
    pb = ctrl.problem
    N = pb.horizon
    nx = ekf.model.nx
    dt = float(ctrl.dt)
    layout = [("ekf_x", nx), ("ekf_P", nx * nx), ("u_prev", 1), ("U", N), ("lam", 2 * N)]
    ns = sum(k for _, k in layout)
    s = ca.MX.sym("state", ns)
    y = ca.MX.sym("y", 3)
    ref = ca.MX.sym("ref", 3 + N)
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
    xi_new, P_new, F_hat = _ekf_update(ekf, xi, P, u_prev, y)
    x_hat = xi_new * ca.DM(ekf.scale)
    R = ref[3:3 + N]
    V = (R - ca.vertcat(r, R[:N - 1])) / dt
    U_s = ca.vertcat(U[1:], U[N - 1])
    H, g, _cost, _X = sol._lin.fn(x_hat, U_s, u_prev, R, V, ca.DM(sol.p), ca.DM(sol.scales))
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
    s_next = ca.vertcat(xi_new, ca.reshape(P_new, nx * nx, 1), u, U_next, lam_next)
    fn = ca.Function(CASADI_NAME, [s, y, ref], [u, s_next], ["state", "y", "ref"],
                     ["u", "state_next"])
    return StepExport(fn=fn, state0=np.zeros(ns), layout=layout, n_ref=3 + N,
                      note=f"MPC real-time iteration (EKF, condensed Gauss-Newton, QP by "
                      f"{sol.qp_iterations} ADMM iterations, not DAQP) with its fallback law")


def step_function(ctrl: Any) -> StepExport:
    """The step of the Python controller ``ctrl`` (built, not yet reset) as a CasADi function.

    Raises
    ------
    FcompError
        For a controller that is not exported (``mpc`` with DAQP; module docstring).
    """
    from controllers.ekf import EKFController
    from controllers.feedforward import PIDFeedforwardController
    from controllers.lugre_observer import LuGreObserverController
    from controllers.mpc import MPCController
    from controllers.mpc_fixed import FixedIterationMPC
    from controllers.pid import PIDController

    name = getattr(ctrl, "name", type(ctrl).__name__)
    if isinstance(ctrl, FixedIterationMPC):
        return _mpc_step(ctrl)
    if isinstance(ctrl, MPCController):
        raise FcompError("export: this mpc solves its QP with DAQP, an active-set solver CasADi "
                         "cannot generate as C; export controllers.mpc_fixed.FixedIterationMPC "
                         "(the same MPC with a fixed-iteration QP)")
    if not isinstance(ctrl, PIDController) or name not in EXPORTABLE:
        raise FcompError(f"export: controller {name} is not exported (exported: "
                         f"{', '.join(EXPORTABLE)})")
    m = ctrl.model
    law = ctrl.law
    g = ctrl.gains
    dt = float(ctrl.dt)
    if isinstance(ctrl, LuGreObserverController):
        nc = m.friction.n_states + 1
    elif isinstance(ctrl, EKFController):
        nx = ctrl.ekf.model.nx
        nc = nx + nx * nx + 1
    else:
        nc = 0
    ns = 4 + nc
    s = ca.MX.sym("state", ns)
    y = ca.MX.sym("y", 3)
    ref = ca.MX.sym("ref", 3)
    r, dr, ddr = ref[0], ref[1], ref[2]
    started = s[0] != 0
    x = y[0]
    # reset on the first step (Controller.reset from y0)
    integral = ca.if_else(started, s[1], 0.0)
    v_f_prev = ca.if_else(started, s[2], 0.0)
    x_prev = ca.if_else(started, s[3], x)
    e = r - x
    v_f = (law.Tf * v_f_prev + x - x_prev) / (law.Tf + dt)
    p1g = y[1] - m.p_atm
    p2g = y[2] - m.p_atm
    comp_next: list[Any] = []
    v_inv = v_f
    layout = [("started", 1), ("integral", 1), ("v_f", 1), ("x_prev", 1)]
    state0 = np.zeros(ns)
    if isinstance(ctrl, LuGreObserverController):
        nf = m.friction.n_states
        xh0 = np.asarray(m.friction.initial_state(), dtype=float).ravel()
        xh = ca.if_else(started, s[4:4 + nf], ca.DM(xh0))
        side_prev = ca.if_else(started, s[4 + nf], 1.0)
        side = ca.if_else(v_f != 0, ca.if_else(v_f > 0, 1.0, -1.0), side_prev)
        sig = ca.vertcat(v_f, ddr, x, p1g, p2g, side)
        c = -ctrl.k * (x - r)
        xh_next, F_hat = ctrl._step(xh, sig, c, dt)
        comp_next = [xh_next, side]
        layout += [("observer", nf), ("side", 1)]
        state0[4:4 + nf] = xh0
        state0[4 + nf] = 1.0
        note = "PID + LuGre observer (Canudas de Wit et al. 1995) + force-to-valve inversion"
    elif isinstance(ctrl, EKFController):
        ekf = ctrl.ekf
        sc = np.asarray(ekf.scale, dtype=float)
        meas = list(ekf.model.measured)
        # EKF.reset: x0 = the model at rest with the measured states set, P0 (model units)
        x0 = np.asarray(m.initial_state(np.zeros(3)), dtype=float)
        _, P0 = m.estimator_initial(np.zeros(3))
        sel = np.zeros((nx, 3))
        keep = np.ones(nx)
        for row, i in enumerate(meas):
            sel[i, row] = 1.0 / sc[i]
            keep[i] = 0.0
        xi0 = ca.DM(keep * x0 / sc) + ca.mtimes(ca.DM(sel), y)
        Pi0 = ca.DM(np.asarray(P0, dtype=float) / np.outer(sc, sc))
        xi = ca.if_else(started, s[4:4 + nx], xi0)
        P = ca.if_else(started, ca.reshape(s[4 + nx:4 + nx + nx * nx], nx, nx), Pi0)
        u_prev = ca.if_else(started, s[4 + nx + nx * nx], 0.0)
        xi_new, P_new, F_hat = _ekf_update(ekf, xi, P, u_prev, y)
        v_inv = xi_new[ctrl.iv] * float(sc[ctrl.iv])
        comp_next = [xi_new, ca.reshape(P_new, nx * nx, 1)]  # u_prev appended below
        layout += [("ekf_x", nx), ("ekf_P", nx * nx), ("u_prev", 1)]
        note = "PID + EKF friction estimate (filterpy's EKF equations) + force-to-valve inversion"
    elif isinstance(ctrl, PIDFeedforwardController):
        F_map = ctrl._map(dr, x, p1g, p2g)
        F_hat = ca.if_else(dr == 0, 0.0, F_map * ca.fmin(ca.fabs(dr) / ctrl.band, 1.0))
        note = "PID + static friction feedforward + force-to-valve inversion"
    else:
        F_hat = ca.MX(0.0)
        note = "PID + force-to-valve inversion"
    demand = (m.mass * ddr + m.weight + (g.kp * e + g.ki * (integral + dt * e) + g.kd * (dr - v_f))
              + F_hat)  # the backward-Euler integral of PIDLaw.force
    applied = ca.fmin(ca.fmax(demand, m.force_min), m.force_max)
    lam = ctrl.velocity_compensation  # PIDController.step's velocity mix
    u, sat = _valve_command(ctrl.valve, applied, y, lam * v_inv + (1.0 - lam) * dr)
    if g.ki == 0:
        integral_next = integral
    else:
        integral_next = ca.if_else(sat * e > 0, integral,
                                   integral + dt * (e + g.kt * (applied - demand) / g.ki))
    if isinstance(ctrl, EKFController):
        comp_next.append(u)
    s_next = ca.vertcat(1.0, integral_next, v_f, x, *comp_next)
    fn = ca.Function(CASADI_NAME, [s, y, ref], [u, s_next], ["state", "y", "ref"],
                     ["u", "state_next"])
    return StepExport(fn=fn, state0=state0, layout=layout, note=note)


# ----------------------------------------------------------------------- C files
_HEADER = r"""/* fcomp_ctrl.h -- one sample of the controller @CONTROLLER@, generated by fcomp @VERSION@.
 *
 * @NOTE@
 * Plant: @PLANT@. Sample time @DT@ s (call fcomp_ctrl_step once per sample).
 *
 * Interface (fixed memory: every work array is a member of fcomp_ctrl_t; nothing is
 * allocated, no library call but libm):
 *   fcomp_ctrl_init(c)           -> 0; the next step resets the controller from its
 *                                   measurement (as the Python controller's reset(y0)).
 *   fcomp_ctrl_step(c, y, r)     -> valve command u for the measurement
 *                                   y = {x [m], p1 [Pa abs], p2 [Pa abs]} and a held
 *                                   set point r [m] (reference velocity and acceleration 0).
 *   fcomp_ctrl_step_ref(c, y, ref) -> the same with ref = {r [m], dr [m/s], ddr [m/s^2]}
 *                                   then, for the MPC, the positions r [m] at the next
 *                                   FCOMP_CTRL_NREF - 3 samples (the horizon).
 *   fcomp_ctrl_set_state(c, s)   -> sets the state (FCOMP_CTRL_NSTATE values, layout below).
 *   Both return NAN if the evaluation failed. Units of u: @UNIT@, within +-@UMAX@.
 */
#ifndef FCOMP_CTRL_H
#define FCOMP_CTRL_H

#ifdef __cplusplus
extern "C" {
#endif

#define FCOMP_CTRL_NSTATE @NSTATE@
#define FCOMP_CTRL_NY 3
#define FCOMP_CTRL_NREF @NREF@
#define FCOMP_CTRL_DT @DT@
#define FCOMP_CTRL_U_MAX @UMAX@
#define FCOMP_CTRL_SZ_ARG @SZARG@
#define FCOMP_CTRL_SZ_RES @SZRES@
#define FCOMP_CTRL_SZ_IW @SZIW@
#define FCOMP_CTRL_SZ_W @SZW@

typedef struct {
  double state[FCOMP_CTRL_NSTATE];      /* @LAYOUT@ */
  double state_next[FCOMP_CTRL_NSTATE];
  double u;                             /* the last command */
  const double* arg[FCOMP_CTRL_SZ_ARG];
  double* res[FCOMP_CTRL_SZ_RES];
  @CASADI_INT@ iw[FCOMP_CTRL_SZ_IW + 1];
  double w[FCOMP_CTRL_SZ_W + 1];
} fcomp_ctrl_t;

int fcomp_ctrl_init(fcomp_ctrl_t* c);
double fcomp_ctrl_step(fcomp_ctrl_t* c, const double* y, double r);
double fcomp_ctrl_step_ref(fcomp_ctrl_t* c, const double* y, const double* ref);
void fcomp_ctrl_set_state(fcomp_ctrl_t* c, const double* state);
/* Timing (fcomp_ctrl_bench.c, POSIX clock_gettime): n steps on the m recorded samples
 * Y (m x FCOMP_CTRL_NY) and REF (m x FCOMP_CTRL_NREF), cycled (init before every cycle); times[i] the duration (s)
 * of step i. Returns 0. */
int fcomp_ctrl_bench(fcomp_ctrl_t* c, long n, long m, const double* Y, const double* REF,
                     double* times);

#ifdef __cplusplus
}
#endif
#endif
"""

_SOURCE = r"""/* fcomp_ctrl.c -- the plain C interface of fcomp_ctrl.h around CasADi's generated step. */
#include <math.h>
#include <string.h>
#include "fcomp_ctrl.h"
#include "@CASADI_NAME@.h"

static const double fcomp_ctrl_state0[FCOMP_CTRL_NSTATE] = {@STATE0@};

int fcomp_ctrl_init(fcomp_ctrl_t* c) {
  memcpy(c->state, fcomp_ctrl_state0, sizeof(c->state));
  c->u = 0.0;
  return 0;
}

double fcomp_ctrl_step_ref(fcomp_ctrl_t* c, const double* y, const double* ref) {
  c->arg[0] = c->state;
  c->arg[1] = y;
  c->arg[2] = ref;
  c->res[0] = &c->u;
  c->res[1] = c->state_next;
  if (@CASADI_NAME@(c->arg, c->res, c->iw, c->w, 0)) return NAN;
  memcpy(c->state, c->state_next, sizeof(c->state));
  return c->u;
}

double fcomp_ctrl_step(fcomp_ctrl_t* c, const double* y, double r) {
  double ref[FCOMP_CTRL_NREF];
  ref[0] = r;
  ref[1] = 0.0;
  ref[2] = 0.0;
  for (int i = 3; i < FCOMP_CTRL_NREF; ++i) ref[i] = r;
  return fcomp_ctrl_step_ref(c, y, ref);
}

void fcomp_ctrl_set_state(fcomp_ctrl_t* c, const double* state) {
  memcpy(c->state, state, sizeof(c->state));
}
"""

_BENCH = r"""/* fcomp_ctrl_bench.c -- times fcomp_ctrl_step_ref in a C loop (POSIX clock_gettime). */
#define _POSIX_C_SOURCE 199309L
#include <time.h>
#include "fcomp_ctrl.h"

int fcomp_ctrl_bench(fcomp_ctrl_t* c, long n, long m, const double* Y, const double* REF,
                     double* times) {
  volatile double sink = 0.0;
  struct timespec t0, t1;
  for (long i = 0; i < n; ++i) {
    long k = i % m;
    if (k == 0) fcomp_ctrl_init(c);
    clock_gettime(CLOCK_MONOTONIC, &t0);
    double u = fcomp_ctrl_step_ref(c, Y + FCOMP_CTRL_NY * k, REF + FCOMP_CTRL_NREF * k);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    sink += u;
    times[i] = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
  }
  (void)sink;
  return 0;
}
"""

_EXAMPLE = r"""/* example.c -- run the exported controller: `make && ./example`.
 * A real target calls fcomp_ctrl_step once per sample (every FCOMP_CTRL_DT s) with its
 * sensors' readings; here the measurement is held at a fixed value, so the command is
 * only shown, not a closed loop. Then 100000 steps are timed (fcomp_ctrl_bench). */
#include <stdio.h>
#include <stdlib.h>
#include "fcomp_ctrl.h"

static int cmp(const void* a, const void* b) {
  double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

int main(void) {
  static fcomp_ctrl_t ctrl;            /* fixed memory, no allocation in the step */
  const double y[3] = {@Y0@};            /* x [m], p1 [Pa abs], p2 [Pa abs] */
  const double r = @R0@;                 /* set point [m] */
  fcomp_ctrl_init(&ctrl);
  for (int k = 0; k < 5; ++k) {
    double u = fcomp_ctrl_step(&ctrl, y, r);
    printf("step %d: u = %.9g\n", k, u);
  }
  enum { N = 100000 };
  static double times[N];
  double ref[FCOMP_CTRL_NREF] = {r, 0.0, 0.0};
  for (int i = 3; i < FCOMP_CTRL_NREF; ++i) ref[i] = r;
  fcomp_ctrl_bench(&ctrl, N, 1, y, ref, times);
  qsort(times, N, sizeof(double), cmp);
  printf("step time over %d steps: median %.3g us, max %.3g us\n", N,
         1e6 * times[N / 2], 1e6 * times[N - 1]);
  return 0;
}
"""

_MAKEFILE = """# Builds the exported controller: `make` -> example and libfcomp_ctrl.a (and .so).
CC ?= cc
CFLAGS ?= -O2 -ffp-contract=off
OBJS = fcomp_ctrl.o fcomp_ctrl_bench.o @CASADI_NAME@.o

all: example libfcomp_ctrl.a

libfcomp_ctrl.a: $(OBJS)
\t$(AR) rcs $@ $(OBJS)

libfcomp_ctrl.so: fcomp_ctrl.c fcomp_ctrl_bench.c @CASADI_NAME@.c
\t$(CC) $(CFLAGS) -fPIC -shared $^ -o $@ -lm

example: example.o libfcomp_ctrl.a
\t$(CC) $(CFLAGS) example.o libfcomp_ctrl.a -o $@ -lm

%.o: %.c fcomp_ctrl.h @CASADI_NAME@.h
\t$(CC) $(CFLAGS) -c $< -o $@

clean:
\trm -f *.o libfcomp_ctrl.a libfcomp_ctrl.so example

.PHONY: all clean
"""

#: C flags of fcomp's own build (no fused multiply-add contraction: the same rounding as
#: the Python controller's kernels on every architecture).
CFLAGS = ("-O2", "-ffp-contract=off")


def _fill(text: str, values: Mapping[str, str]) -> str:
    for k, v in values.items():
        text = text.replace(k, v)
    return text


def write_c(step: StepExport, folder: Path, *, controller: str, plant: str, unit: str,
            u_max: float, dt: float, y_example: np.ndarray, r_example: float) -> list[Path]:
    """Write the C files of ``step`` into ``folder`` (created); return their paths."""
    from fcomp.version import __version__

    folder.mkdir(parents=True, exist_ok=True)
    fn = step.fn
    gen = casadi_c([fn], CASADI_NAME, {"with_header": True, "casadi_real": "double",
                                        "casadi_int": CASADI_INT})
    layout = ", ".join(f"{n}[{k}]" if k > 1 else n for n, k in step.layout)
    vals = {f"@{k}@": v for k, v in {
        "CASADI_NAME": CASADI_NAME, "CASADI_INT": CASADI_INT, "CONTROLLER": controller,
        "VERSION": __version__, "NOTE": step.note, "PLANT": plant, "NSTATE": str(step.n_state),
        "DT": repr(float(dt)), "UMAX": repr(float(u_max)), "UNIT": unit,
        "NREF": str(step.n_ref), "SZARG": str(fn.sz_arg()), "SZRES": str(fn.sz_res()), "SZIW": str(fn.sz_iw()),
        "SZW": str(fn.sz_w()), "LAYOUT": layout,
        "STATE0": ", ".join(repr(float(v)) for v in step.state0),
        "Y0": ", ".join(repr(float(v)) for v in y_example), "R0": repr(float(r_example)),
    }.items()}
    files = {
        "fcomp_ctrl.h": _fill(_HEADER, vals),
        "fcomp_ctrl.c": _fill(_SOURCE, vals),
        "fcomp_ctrl_bench.c": _BENCH,
        "example.c": _fill(_EXAMPLE, vals),
        "Makefile": _fill(_MAKEFILE, {"@CASADI_NAME@": CASADI_NAME}),
        **gen,
    }
    out = []
    for name, text in files.items():
        path = folder / name
        path.write_text(text)
        out.append(path)
    return out


# -------------------------------------------------------------------- compiling
def find_compiler() -> str | None:
    """The C compiler (module docstring: ``$FCOMP_CC``, else ``$CC``, cc, gcc, clang)."""
    forced = os.environ.get("FCOMP_CC")
    if forced is not None:
        return shutil.which(forced) if forced.strip() else None
    for cand in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if cand and shutil.which(cand):
            return cand
    return None


class CompiledController:
    """The exported C controller, built as a shared library and called through ctypes."""

    def __init__(self, folder: Path, cc: str, n_state: int, build: Path, n_ref: int = 3) -> None:
        srcs = [folder / "fcomp_ctrl.c", folder / "fcomp_ctrl_bench.c",
                folder / f"{CASADI_NAME}.c"]
        lib = build / "libfcomp_ctrl.so"
        proc = subprocess.run([cc, *CFLAGS, "-fPIC", "-shared", *map(str, srcs), "-o", str(lib),
                               "-lm"], capture_output=True, text=True)
        if proc.returncode != 0:
            first = (proc.stderr.strip().splitlines() or ["(no message)"])[0]
            raise FcompError(f"export: the C compiler {cc} failed on the generated code: {first}")
        self.dll = ctypes.CDLL(str(lib))
        size = self._struct_size(folder, cc, build)
        self.size = size
        self.mem = ctypes.create_string_buffer(size + 64)
        dp = ctypes.POINTER(ctypes.c_double)
        self.dll.fcomp_ctrl_init.argtypes = [ctypes.c_void_p]
        self.dll.fcomp_ctrl_step_ref.argtypes = [ctypes.c_void_p, dp, dp]
        self.dll.fcomp_ctrl_step_ref.restype = ctypes.c_double
        self.dll.fcomp_ctrl_bench.argtypes = [ctypes.c_void_p, ctypes.c_long, ctypes.c_long,
                                              dp, dp, dp]
        self.dll.fcomp_ctrl_bench.restype = ctypes.c_int
        self._y = np.zeros(3)
        self._ref = np.zeros(n_ref)
        self._yp = self._y.ctypes.data_as(dp)
        self._refp = self._ref.ctypes.data_as(dp)
        self._dp = dp
        self.n_state = n_state

    @staticmethod
    def _struct_size(folder: Path, cc: str, build: Path) -> int:
        """``sizeof(fcomp_ctrl_t)``, asked of the compiler (a tiny program run once)."""
        src = build / "size.c"
        src.write_text('#include <stdio.h>\n#include "fcomp_ctrl.h"\n'
                       'int main(void) { printf("%zu\\n", sizeof(fcomp_ctrl_t)); return 0; }\n')
        exe = build / "size"
        proc = subprocess.run([cc, f"-I{folder}", str(src), "-o", str(exe)],
                              capture_output=True, text=True)
        if proc.returncode != 0:
            raise FcompError(f"export: the C compiler {cc} failed on fcomp_ctrl.h")
        return int(subprocess.run([str(exe)], capture_output=True, text=True,
                                  check=True).stdout)

    def instance(self) -> Any:
        """Memory of one more controller (an ``fcomp_ctrl_t``)."""
        return ctypes.create_string_buffer(self.size + 64)

    def init(self, mem: Any = None) -> None:
        self.dll.fcomp_ctrl_init(self.mem if mem is None else mem)

    def set_state(self, state: np.ndarray, mem: Any = None) -> None:
        """Overwrite the controller's state (``state`` is the struct's first member)."""
        buf = np.ascontiguousarray(state, dtype=float)
        if buf.size != self.n_state:
            raise ValueError(f"state of {buf.size} values, the controller has {self.n_state}")
        ctypes.memmove(self.mem if mem is None else mem, buf.ctypes.data, buf.nbytes)

    def state(self, mem: Any = None) -> np.ndarray:
        """A copy of the controller's state."""
        raw = ctypes.string_at(self.mem if mem is None else mem, 8 * self.n_state)
        return np.frombuffer(raw, dtype=float).copy()

    def step(self, y: np.ndarray, ref: Any, mem: Any = None) -> float:
        self._y[:] = y
        self._ref[:] = ref
        return float(self.dll.fcomp_ctrl_step_ref(self.mem if mem is None else mem, self._yp,
                                                  self._refp))

    def bench(self, n: int, Y: np.ndarray, REF: np.ndarray) -> np.ndarray:
        Y = np.ascontiguousarray(Y, dtype=float)
        REF = np.ascontiguousarray(REF, dtype=float)
        times = np.zeros(n)
        self.dll.fcomp_ctrl_bench(self.mem, n, len(Y), Y.ctypes.data_as(self._dp),
                                  REF.ctypes.data_as(self._dp), times.ctypes.data_as(self._dp))
        return times


# ------------------------------------------------------------------ the check
def python_state(ctrl: Any) -> np.ndarray:
    """The Python controller's state in the exported layout (:class:`StepExport`; after its
    ``reset``, so ``started = 1``)."""
    from controllers.ekf import EKFController
    from controllers.lugre_observer import LuGreObserverController
    from controllers.mpc_fixed import FixedIterationMPC

    if isinstance(ctrl, FixedIterationMPC):
        kf = ctrl.ekf.kf
        lam = ctrl.solver._lam
        N = ctrl.problem.horizon
        return np.concatenate([np.asarray(kf.x, dtype=float)[:, 0],
                               np.asarray(kf.P, dtype=float).ravel(order="F"),
                               [ctrl._u_prev], np.asarray(ctrl.solver.U, dtype=float),
                               np.zeros(2 * N) if lam is None else np.asarray(lam, dtype=float)])
    law = ctrl.law
    parts = [np.array([1.0, law.integral, law.v_f, law.x_prev], dtype=float)]
    if isinstance(ctrl, LuGreObserverController):
        parts += [np.asarray(ctrl.x_hat, dtype=float).ravel(), np.array([ctrl._side])]
    elif isinstance(ctrl, EKFController):
        kf = ctrl.ekf.kf
        parts += [np.asarray(kf.x, dtype=float)[:, 0],
                  np.asarray(kf.P, dtype=float).ravel(order="F"), np.array([ctrl._u_prev])]
    return np.concatenate(parts)


@dataclass
class CheckResult:
    """The lock-step closed loop of :func:`check_equivalence` (SI units).

    Attributes
    ----------
    u_python
        The Python controller's commands.
    u_step
        The compiled step's commands from the Python controller's state at every sample
        (the step, compared step for step).
    u_free
        The commands of the compiled controller running on its own state (these drive
        the plant).
    state_rel_diff
        Per sample, the largest difference of the compiled step's next state from the
        Python controller's, relative per block (:func:`block_difference`).
    Y, REF
        Measurements and references of the run (for the timing loop).
    u_max
        The valve range (floor of the relative differences).
    """

    u_python: np.ndarray
    u_step: np.ndarray
    u_free: np.ndarray
    state_rel_diff: np.ndarray
    Y: np.ndarray
    REF: np.ndarray
    u_max: float

    @property
    def max_rel_diff(self) -> float:
        return float(np.max(relative_difference(self.u_step, self.u_python, self.u_max)))

    @property
    def free_max_rel_diff(self) -> float:
        return float(np.max(relative_difference(self.u_free, self.u_python, self.u_max)))

    @property
    def free_max_abs_diff(self) -> float:
        return float(np.max(np.abs(self.u_free - self.u_python)))

    @property
    def max_state_rel_diff(self) -> float:
        return float(np.max(self.state_rel_diff))


def relative_difference(u_c: np.ndarray, u_py: np.ndarray, u_max: float) -> np.ndarray:
    """``|u_c - u_py| / max(|u_py|, 1e-6*u_max)``: relative, with a floor a millionth of the
    valve range (a command of exactly zero has no relative error of its own)."""
    return np.abs(u_c - u_py) / np.maximum(np.abs(u_py), 1e-6 * u_max)


def block_difference(s_c: np.ndarray, s_py: np.ndarray, layout: list[tuple[str, int]]) -> float:
    """Largest over the state's blocks of ``max|s_c - s_py| / max(max|s_py|, 1e-300)``."""
    worst = 0.0
    i = 0
    for _name, k in layout:
        a, b = s_c[i:i + k], s_py[i:i + k]
        d = float(np.max(np.abs(a - b)))
        if d > 0:
            worst = max(worst, d / max(float(np.max(np.abs(b))), 1e-300))
        i += k
    return worst


def check_equivalence(ctrl: Any, compiled: CompiledController, plant: Any, *,
                      layout: list[tuple[str, int]] | None = None, start_from_init: bool = True,
                      task: str = "seed002-sine", duration: float = 0.6, noise: float = 1.0,
                      seed: int = 0) -> CheckResult:
    """Run the compiled controller in closed loop against ``plant`` (the harness's plant
    integration and sensors) with the Python controller ``ctrl`` stepped on the same
    measurements and references.

    Two compiled instances run: one on its own state from ``fcomp_ctrl_init`` (its
    commands drive the plant: ``u_free``; without ``start_from_init``, from the Python
    controller's state after its reset, as the MPC needs), and one whose state is set to the Python
    controller's before every sample (``u_step``: the step itself, compared step for
    step, and its next state against the Python controller's).
    """
    from controllers.base import Reference
    from controllers.harness import SensorModel
    from controllers.plant_model import equilibrium
    from controllers.tasks import get_task

    model = ctrl.model
    tk = get_task(task)
    x_mid = 0.5 * model.stroke
    dt = ctrl.dt
    n = max(1, int(round(duration / dt)))
    t = np.arange(n + 1) * dt
    r, dr, ddr = tk.sample(t)
    r = r + x_mid
    if r.min() < 0.005 or r.max() > model.stroke - 0.005:
        raise FcompError(f"export: task {task} leaves the stroke within {duration} s")
    x0, _ = equilibrium(plant, x_mid)
    stepper = plant.stepper(dt, x0=x0, rtol=1e-5, atol=1e-5)
    sensors = SensorModel(model.sensors, noise, seed)
    names = plant.state_names
    meas = [names.index(k) for k in ("x", "p1", "p2")]
    state = stepper.reset()
    u_py, u_step, u_free, s_diff = (np.zeros(n + 1) for _ in range(4))
    Y = np.zeros((n + 1, 3))
    preview = int(getattr(ctrl, "preview", 0))
    r_pad = np.concatenate([r, np.full(preview, r[-1])])
    REF = np.zeros((n + 1, 3 + preview))
    synced = compiled.instance()
    compiled.init()
    compiled.init(synced)
    lay = layout or [("state", compiled.n_state)]
    u_max = model.u_max
    for k in range(n + 1):
        y = sensors.measure(state[meas])
        Y[k] = y
        fut = tuple(float(v) for v in r_pad[k + 1:k + 1 + preview])
        ref = Reference(float(r[k]), float(dr[k]), float(ddr[k]), fut)
        REF[k] = (ref.r, ref.dr, ref.ddr, *fut)
        if k == 0:
            ctrl.reset(0.0, y, ref)
            if not start_from_init:  # the MPC's start needs the plant's equilibrium (Python)
                compiled.set_state(python_state(ctrl))
        compiled.set_state(python_state(ctrl), synced)
        u_step[k] = compiled.step(y, REF[k], synced)
        u_py[k] = ctrl.step(float(t[k]), y, ref)
        s_diff[k] = block_difference(compiled.state(synced), python_state(ctrl), lay)
        u_free[k] = compiled.step(y, REF[k])
        if not math.isfinite(u_free[k]):
            raise FcompError(f"export: the compiled controller returned {u_free[k]} at "
                             f"t = {t[k]:.4f} s")
        if k < n:
            state = stepper.step(min(max(u_free[k], -u_max), u_max))
    return CheckResult(u_python=u_py, u_step=u_step, u_free=u_free, state_rel_diff=s_diff,
                       Y=Y, REF=REF, u_max=u_max)


# ------------------------------------------------------------------ the whole
@dataclass
class ExportResult:
    """What :func:`export_controller` did (SI units; times in s)."""

    controller: str
    files: list[Path]
    equivalent: bool | None
    max_rel_diff: float | None
    max_state_rel_diff: float | None
    free_run_max_rel_diff: float | None
    free_run_max_abs_diff: float | None
    steps_checked: int
    step_time_median: float | None
    step_time_max: float | None
    timed_steps: int
    compiler: str | None
    note: str
    layout: list[tuple[str, int]]
    reference: str = ""
    warnings: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return {
            "controller": self.controller, "files": [str(f) for f in self.files],
            "equivalent": self.equivalent, "max_rel_diff": self.max_rel_diff,
            "max_state_rel_diff": self.max_state_rel_diff, "rtol": RTOL,
            "free_run_max_rel_diff": self.free_run_max_rel_diff,
            "free_run_max_abs_diff": self.free_run_max_abs_diff,
            "free_run_equivalent": (None if self.free_run_max_rel_diff is None
                                    else self.free_run_max_rel_diff <= RTOL),
            "steps_checked": self.steps_checked, "step_time_median": self.step_time_median,
            "step_time_max": self.step_time_max, "timed_steps": self.timed_steps,
            "compiler": self.compiler, "step": self.note, "python_reference": self.reference,
            "state_layout": [{"name": n, "size": k} for n, k in self.layout],
        }


def export_controller(name: str, model: Any, folder: Path, *,
                      options: Mapping[str, Any] | None = None, plant: Any = None,
                      task: str = "seed002-sine", duration: float = 0.6,
                      timing_steps: int = 100_000, seed: int = 0,
                      on_stage: Callable[[str], None] | None = None) -> ExportResult:
    """Export controller ``name`` built on ``model`` (a
    :class:`~controllers.plant_model.ControlModel`: plant and friction) as C into ``folder``;
    compile, check in closed loop against ``plant`` (default: the model's own plant, the
    controller's friction as the true one) and time it (module docstring)."""
    from controllers import CONTROLLERS, make_controller
    from controllers.base import Reference
    from controllers.mpc_fixed import FixedIterationMPC
    from controllers.plant_model import MEASURED, equilibrium

    CONTROLLERS.get(name)
    if name not in EXPORTABLE:
        raise FcompError(f"export: controller {name} is not exported (exported: "
                         f"{', '.join(EXPORTABLE)})")
    if timing_steps < 100_000:
        raise FcompError(f"export: time at least 100000 steps, got {timing_steps}")
    if not (math.isfinite(duration) and duration > 0):
        raise FcompError(f"export: the check's duration must be positive, got {duration}")
    say = on_stage or (lambda _s: None)
    ctrl = (FixedIterationMPC(model, **dict(options or {})) if name == "mpc"
            else make_controller(name, model, **dict(options or {})))
    step = step_function(ctrl)
    unit = "A (servo-valve current)" if model.plant_name == "hydraulic" else \
        "normalised valve command (-1..1)"
    # the example's measurement: at rest at mid-stroke, holding the load
    x_eq, _ = equilibrium(model.plant, 0.5 * model.stroke)
    names = model.plant.state_names
    y_ex = np.array([x_eq[names.index(k)] for k in MEASURED])
    if name == "mpc":  # fcomp_ctrl_init: the Python reset there (it solves the equilibrium)
        ctrl.reset(0.0, y_ex, Reference(float(y_ex[0]), 0.0, 0.0))
        step.state0 = python_state(ctrl)
    files = write_c(step, folder, controller=name, plant=model.describe(), unit=unit,
                    u_max=model.u_max, dt=ctrl.dt, y_example=y_ex,
                    r_example=0.5 * model.stroke + 0.001)
    cc = find_compiler()
    res = ExportResult(controller=name, files=files, equivalent=None, max_rel_diff=None,
                       max_state_rel_diff=None, free_run_max_rel_diff=None,
                       free_run_max_abs_diff=None, steps_checked=0, step_time_median=None,
                       step_time_max=None, timed_steps=0, compiler=cc, note=step.note,
                       layout=step.layout,
                       reference=f"{type(ctrl).__module__}.{type(ctrl).__qualname__}")
    if cc is None:
        forced = os.environ.get("FCOMP_CC")
        where = (f"FCOMP_CC={forced} is not found" if forced is not None
                 else "none of $CC, cc, gcc, clang is on the PATH")
        res.warnings.append(f"no C compiler found ({where}): the C code is written to {folder} "
                            "but not compiled, checked or timed")
        return res
    with tempfile.TemporaryDirectory() as tmp:
        say("compiling")
        try:
            lib = CompiledController(folder, cc, step.n_state, Path(tmp), n_ref=step.n_ref)
        except FcompError as exc:  # a broken toolchain: the code stays written
            res.warnings.append(f"{exc}; the C code is written to {folder} but not checked "
                                "or timed")
            return res
        say("checking")
        chk = check_equivalence(ctrl, lib, plant if plant is not None else model.plant,
                                layout=step.layout, start_from_init=name != "mpc", task=task,
                                duration=duration, seed=seed)
        say("timing")
        times = lib.bench(timing_steps, chk.Y, chk.REF)
    res.equivalent = bool(chk.max_rel_diff <= RTOL and chk.max_state_rel_diff <= RTOL)
    res.max_rel_diff = chk.max_rel_diff
    res.max_state_rel_diff = chk.max_state_rel_diff
    res.free_run_max_rel_diff = chk.free_max_rel_diff
    res.free_run_max_abs_diff = chk.free_max_abs_diff
    res.steps_checked = int(chk.u_free.size)
    res.step_time_median = float(np.median(times))
    res.step_time_max = float(np.max(times))
    res.timed_steps = int(times.size)
    if not res.equivalent:
        res.warnings.append(f"the compiled step differs from the Python controller's: relative "
                            f"{chk.max_rel_diff:.3g} on the command, {chk.max_state_rel_diff:.3g} "
                            f"on the state (tolerance {RTOL:g})")
    return res


__all__ = ["EXPORTABLE", "RTOL", "CheckResult", "CompiledController", "ExportResult",
           "StepExport", "check_equivalence", "export_controller", "find_compiler",
           "python_state", "step_function", "write_c"]
