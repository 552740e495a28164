"""Benchmark: friction force along a prescribed motion, 100 000 samples (issue 2).

For ``lugre`` and ``nmlgm`` (parameter set ``seed000-cylinder1``, direction
dependent) along a two-tone velocity with reversals (1 kHz, 100 s), it
times, in one run:

* ``fcomp``: :func:`fcomp.trajectory.friction_along_motion` -- signal
  preparation, the exponential Rosenbrock-Euler step compiled to C by
  CasADi and looped in C (:mod:`fcomp.compiled`), then the force at every
  sample, vectorised with numpy;
* ``plain Python``: a Python ``for`` loop over the same samples doing the
  same step -- interval-mean signals, ``x += dt*phi1(dt*J)*f`` with ``f``
  from the model's own equations on the NUMPY backend, one scalar sample at
  a time, the diagonal Jacobian ``J`` by a one-sided difference of ``f``
  (exact here: the friction equations are linear in each state between
  switches) -- and the force at every sample;
* ``hand-written C``: the same step and force written by hand in C (below),
  compiled with ``cc -O2`` and called through :mod:`ctypes` over the whole
  record -- the compiled loop a careful programmer would write;
* ``CasADi step loop``: :func:`fcomp.compiled.stepping_loop` of
  :func:`fcomp.trajectory.friction_step` alone (states only, no signal
  preparation, no force) -- the core of ``fcomp``.

Each alternative is checked against ``fcomp`` (largest force difference).
Times are medians of ``--repeat`` runs (the plain-Python loop
``--repeat-python`` runs); wall and CPU time of this process are both
reported, since the CPU time is the fairer figure on a loaded machine.
Goals: ``fcomp`` within 3x of the hand-written C loop and at least 5x faster
than plain Python.

Usage::

    python benchmarks/bench_friction.py [--repeat 7] [--repeat-python 3] [--samples 100000]
"""

from __future__ import annotations

import argparse
import ctypes
import math
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np

from fcomp.backend import NUMPY
from fcomp.compiled import compiler, stepping_loop
from fcomp.models import FrictionModel, Signals, make_model, side_of
from fcomp.trajectory import friction_along_motion, friction_step, midpoint_signals

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_plants import timed  # noqa: E402  (median wall and CPU time of repeated calls)

RATE = 1000.0  # Hz

C_SOURCE = r"""
#include <math.h>

/* Friction along a prescribed motion: LuGre family with optional film state h
   (models.md 1.3-1.5), the exponential Rosenbrock-Euler step of fcomp.trajectory
   at interval-mean signals, and the force at every sample.
   p: Fc+ Fc- Fs+ Fs- vs+ vs- n+ n- s2+ s2- sigma0 sigma1 vb+ vb- tau_hp tau_hn tau_h0 T v_eps
   film: 0 (LuGre) or 1 (film state h, NMLGM). */

enum {FC, FS = 2, VS = 4, N = 6, S2 = 8, SIGMA0 = 10, SIGMA1, VB, TAU_HP = 14, TAU_HN, TAU_H0,
      T, V_EPS};

static double side_par(const double *p, int k, double s) { return s > 0 ? p[k] : p[k + 1]; }

static double phi1(double y) { return fabs(y) < 1e-8 ? 1.0 + 0.5 * y : expm1(y) / y; }

static double h_ss(const double *p, double v, double s, int film) {
  if (!film) return 0.0;
  double r = fabs(v) / side_par(p, VB, s);
  r = r < 1.0 ? r : 1.0;
  r = r > 1e-30 ? r : 1e-30;
  return (1.0 - side_par(p, FC, s) / side_par(p, FS, s)) * pow(r, 2.0 / 3.0);
}

static double g_of(const double *p, double v, double h, double s) {
  double fc = side_par(p, FC, s), fs = side_par(p, FS, s);
  double r = fabs(v) / side_par(p, VS, s);
  r = r > 1e-30 ? r : 1e-30;
  return fc + ((1.0 - h) * fs - fc) * exp(-pow(r, side_par(p, N, s)));
}

void friction_loop(int n, const double *t, const double *v, const double *a, const double *p,
                   int film, double z, double h, double *Z, double *H, double *F) {
  double s = v[0] < 0 ? -1.0 : 1.0; /* side at the sample, held through v = 0 */
  for (int k = 0; k < n; ++k) {
    if (v[k] > 0) s = 1.0; else if (v[k] < 0) s = -1.0;
    Z[k] = z; H[k] = h;
    /* force at sample k */
    double g = g_of(p, v[k], h, s);
    double dz = v[k] - p[SIGMA0] * fabs(v[k]) * z / g;
    double lead = film ? p[T] * a[k] : 0.0;
    F[k] = p[SIGMA0] * z + p[SIGMA1] * dz + side_par(p, S2, s) * (v[k] + lead);
    if (k == n - 1) break;
    /* step to k + 1 with interval means */
    double dt = t[k + 1] - t[k], vm = 0.5 * (v[k] + v[k + 1]);
    double sm = vm > 0 ? 1.0 : (vm < 0 ? -1.0 : s);
    double gm = g_of(p, vm, h, sm);
    double jz = -p[SIGMA0] * fabs(vm) / gm;
    double fz = vm + jz * z;
    double z1 = z + dt * phi1(dt * jz) * fz;
    if (film) {
      double hs = h_ss(p, vm, sm, film);
      double tau = fabs(vm) < p[V_EPS] ? p[TAU_H0] : (h <= hs ? p[TAU_HP] : p[TAU_HN]);
      h = h + dt * phi1(-dt / tau) * (hs - h) / tau;
    }
    z = z1;
  }
}
"""

PARAM_ORDER = ("Fc", "Fs", "vs", "n", "sigma2", "sigma0", "sigma1", "vb", "tau_hp", "tau_hn",
               "tau_h0", "T", "v_eps")


def motion(samples: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``t`` (s), ``v`` (m/s), ``a`` (m/s^2): two tones with reversals, at 1 kHz."""
    t = np.arange(samples) / RATE
    w1, w2 = 2 * math.pi * 0.5, 2 * math.pi * 3.1
    v = 0.05 * np.sin(w1 * t) + 0.02 * np.sin(w2 * t)
    a = 0.05 * w1 * np.cos(w1 * t) + 0.02 * w2 * np.cos(w2 * t)
    return t, v, a


# ------------------------------------------------------------------ plain Python
def plain_python(model: FrictionModel, t: np.ndarray, v: np.ndarray,
                 a: np.ndarray) -> np.ndarray:
    """The same scheme as ``friction_along_motion``, one scalar sample at a time."""
    P = model.param_values(NUMPY)
    s_all = side_of(v)
    M, dts = midpoint_signals({"t": t, "v": v, "a": a, "x": np.zeros_like(t),
                               "p1": np.zeros_like(t), "p2": np.zeros_like(t), "s": s_all})
    nx = model.n_states
    x = [float(c) for c in model.initial_state()]
    F = np.empty(t.size)
    for k in range(t.size):
        sig = Signals(v=float(v[k]), a=float(a[k]), s=float(s_all[k]))
        F[k] = model.force(NUMPY, x, sig, P)
        if k == t.size - 1:
            break
        mid = Signals(*(float(c) for c in M[:, k]))
        f = model.rhs(NUMPY, x, mid, P)
        dt = float(dts[k])
        new = []
        for i in range(nx):
            delta = 1e-6 * max(abs(x[i]), 1e-3)
            xp = list(x)
            xp[i] += delta
            J = (model.rhs(NUMPY, xp, mid, P)[i] - f[i]) / delta
            y = dt * J
            phi = 1.0 + 0.5 * y if abs(y) < 1e-8 else math.expm1(y) / y
            new.append(x[i] + dt * phi * f[i])
        x = new
    return F


# --------------------------------------------------------------- hand-written C
def hand_c_loop(workdir: Path) -> Callable[..., np.ndarray] | None:
    """The C loop above, compiled; ``None`` without a C compiler."""
    cc = compiler() or shutil.which("cc")
    if cc is None:
        return None
    src, lib = workdir / "friction_loop.c", workdir / "friction_loop.so"
    src.write_text(C_SOURCE)
    subprocess.run([cc, "-O2", "-fPIC", "-shared", str(src), "-o", str(lib), "-lm"], check=True)
    fn = ctypes.CDLL(str(lib)).friction_loop
    dp = ctypes.POINTER(ctypes.c_double)
    fn.argtypes = [ctypes.c_int, dp, dp, dp, dp, ctypes.c_int, ctypes.c_double, ctypes.c_double,
                   dp, dp, dp]
    fn.restype = None

    def run(model: FrictionModel, t: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        flat = model.flat_params()
        p = []
        for name in PARAM_ORDER:
            if name in flat:
                p += [flat[name]] if name in ("sigma0", "sigma1", "tau_hp", "tau_hn", "tau_h0",
                                              "T", "v_eps") else [flat[name], flat[name]]
            elif name + "_pos" in flat:
                p += [flat[name + "_pos"], flat[name + "_neg"]]
            else:  # LuGre: no film, no lead
                p += [math.inf, math.inf] if name == "vb" else [1.0]
        pa = np.array(p, dtype=float)
        n = t.size
        Z, H, F = np.empty(n), np.empty(n), np.empty(n)
        film = int("h" in model.state_names)
        fn(n, *(np.ascontiguousarray(q).ctypes.data_as(dp) for q in (t, v, a, pa)), film, 0.0,
           0.0, *(q.ctypes.data_as(dp) for q in (Z, H, F)))
        return F

    return run


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=7, help="runs of the fast methods (>= 5)")
    ap.add_argument("--repeat-python", type=int, default=3, help="runs of the plain loop")
    ap.add_argument("--samples", type=int, default=100_000)
    args = ap.parse_args()
    t, v, a = motion(args.samples)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        hand = hand_c_loop(Path(tmp))
        for name in ("lugre", "nmlgm"):
            model = make_model(name, params="seed000-cylinder1")
            ours = friction_along_motion(model, t, v, a=a)  # warm-up: compiles once
            w_f, c_f, run = timed(partial(friction_along_motion, model, t, v, a=a), args.repeat)
            results = {"fcomp": (w_f, c_f, 0.0)}
            w, c, F = timed(partial(plain_python, model, t, v, a), args.repeat_python)
            results["plain Python"] = (w, c, float(np.abs(F - run.F).max()))
            if hand is not None:
                w, c, F = timed(partial(hand, model, t, v, a), args.repeat)
                results["hand-written C"] = (w, c, float(np.abs(F - run.F).max()))
            step = stepping_loop(friction_step(model))
            M, dts = midpoint_signals({"t": t, "v": v, "a": a, "x": 0 * t, "p1": 0 * t,
                                       "p2": 0 * t, "s": side_of(v)})
            U = np.ascontiguousarray(M.T)
            pvec = np.array(list(model.flat_params().values()))
            x0 = model.initial_state()
            w, c, X = timed(partial(step, x0, U, dts, pvec), args.repeat)
            results["CasADi step loop"] = (w, c, float(np.abs(X - ours.states).max()))
            rows.append((name, results))

    n = args.samples
    print(f"friction along a prescribed motion, {n} samples, median of {args.repeat} runs "
          f"({args.repeat_python} for plain Python)\n")
    head = (f"{'model':7s} {'method':17s} {'wall ms':>9s} {'CPU ms':>9s} {'ns/sample':>10s} "
            f"{'CPU / fcomp':>12s} {'max diff':>10s}")
    print(head)
    print("-" * len(head))
    for name, results in rows:
        c_ref = results["fcomp"][1]
        for method, (w, c, diff) in results.items():
            unit = "m" if method == "CasADi step loop" else "N"
            print(f"{name:7s} {method:17s} {w * 1e3:9.2f} {c * 1e3:9.2f} {c / n * 1e9:10.1f} "
                  f"{c / c_ref:12.3g} {diff:9.2g}{unit}")
        print()
    for name, results in rows:
        c_ref = results["fcomp"][1]
        speedup = results["plain Python"][1] / c_ref
        msg = f"{name}: fcomp is {speedup:.0f}x faster than plain Python (goal >= 5x)"
        if "hand-written C" in results:
            ratio = c_ref / results["hand-written C"][1]
            msg += f"; {ratio:.2f}x the hand-written C loop (goal <= 3x)"
        print(msg)


if __name__ == "__main__":
    main()
