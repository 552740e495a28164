"""Benchmark: fitting NMLGM to a 60 s record at 1 kHz, cold start, against a plain baseline.

What is timed
-------------
* **fcomp (cold)**: a *fresh Python process* with an *empty compile cache*
  (``FCOMP_CACHE`` pointed at a new temporary folder) runs
  ``FrictionFit("nmlgm").fit(record)``: imports, CasADi code generation, C
  compilation of the sensitivity step, the steady-state stage and the
  trajectory fit with exact sensitivities. Wall time from process start to
  the fitted result, and the CPU time of the process with the C compiler it
  runs (the fairer figure on a loaded machine). Repeated ``--repeats`` times;
  the median is reported.
* **fcomp (warm)**: the same fit again in an already warm process (compiled
  library loaded): the cost of the fit itself.
* **baseline**: :func:`scipy.optimize.least_squares` (``trf``, the same
  bounds and ``x_scale``) with ``jac="2-point"`` finite differences on a
  *plain Python* simulation of the same NMLGM with the same
  discretisation (interval-mean signals, exponential Rosenbrock-Euler step),
  from the *same start values* as fcomp's trajectory stage. One simulation is
  timed ``--repeats`` times (median); the baseline fit is run once to
  convergence (a few minutes) and its wall time measured. With
  ``--baseline-nfev N`` it is capped at ``N`` evaluations instead and its
  full cost *extrapolated* as (fcomp's evaluations) x (1 + p) simulations x
  (measured time per simulation), i.e. assuming the finite-difference fit
  needs as many iterations as fcomp's (a measured run needed about as many:
  see docs/identification.md).

The record: NMLGM (seed 000 cylinder-1 values, symmetric, ``T = 0.01 s``)
simulated by the package along a two-tone velocity, plus 0.05 N white noise.

Run ``python benchmarks/bench_fit.py`` (add ``--quick`` for a 10 s record).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

TRUTH = {"Fc": 5.5, "Fs": 22.5, "vs": 0.01, "n": 2.5, "sigma2": 25.0, "sigma0": 1.5e4,
         "sigma1": 0.1, "vb": 0.037, "tau_hp": 0.02, "tau_hn": 0.15, "tau_h0": 20.0,
         "T": 0.01, "v_eps": 1e-5}

COLD = r"""
import json, sys, time
t0 = time.perf_counter()
from fcomp.identification import FrictionFit
from fcomp.measurement import Measurement
meas = Measurement.read(sys.argv[1])
t1 = time.perf_counter()
fit = FrictionFit("nmlgm").fit(meas)
t2 = time.perf_counter()
print(json.dumps({"import_read": t1 - t0, "fit": t2 - t1, "total": t2 - t0,
                  "stages": fit.stages_, "rms": fit.rms_}))
"""


def make_record(path: Path, duration: float) -> None:
    from fcomp.measurement import Measurement
    from fcomp.models import make_model
    from fcomp.trajectory import friction_along_motion

    t = np.arange(int(round(duration * 1000)) + 1) / 1000.0
    v = 0.05 * np.sin(2 * np.pi * 0.5 * t) + 0.02 * np.sin(2 * np.pi * 1.3 * t)
    a = 0.05 * np.pi * np.cos(np.pi * t) + 0.02 * 2.6 * np.pi * np.cos(2.6 * np.pi * t)
    model = make_model("nmlgm", params=TRUTH)
    run = friction_along_motion(model, t, v, a=a)
    F = run.F + 0.05 * np.random.default_rng(1).standard_normal(t.size)
    Measurement({"t": t, "x": run.x, "v": v, "a": a, "F": F}, {"name": "bench-nmlgm"}).write(path)


# ------------------------------------------------------------- plain baseline
def plain_nmlgm(t: np.ndarray, v: np.ndarray, a: np.ndarray, p: dict[str, float]) -> np.ndarray:
    """NMLGM (models.md 1.5) in plain Python, the package's discretisation, symmetric params."""
    Fc, Fs, vs, n, s2 = p["Fc"], p["Fs"], p["vs"], p["n"], p["sigma2"]
    s0, s1, vb, T, veps = p["sigma0"], p["sigma1"], p["vb"], p["T"], p["v_eps"]
    thp, thn, th0 = p["tau_hp"], p["tau_hn"], p["tau_h0"]
    kf = 1.0 - Fc / Fs
    exp, expm1 = math.exp, math.expm1

    def hss(vv: float) -> float:
        r = min(abs(vv) / vb, 1.0)
        return kf * max(r, 1e-30) ** (2.0 / 3.0)

    def g(vv: float, h: float) -> float:
        return Fc + ((1.0 - h) * Fs - Fc) * exp(-max(abs(vv) / vs, 1e-30) ** n)

    def phi1(y: float) -> float:
        return 1.0 + 0.5 * y if abs(y) < 1e-8 else expm1(y) / y

    N = t.size
    F = np.empty(N)
    z = h = 0.0
    vl, al = v.tolist(), a.tolist()
    for k in range(N):
        vk = vl[k]
        gk = g(vk, h)
        dz = vk - s0 * abs(vk) * z / gk
        F[k] = s0 * z + s1 * dz + s2 * (vk + T * al[k])
        if k == N - 1:
            break
        dt = t[k + 1] - t[k]
        vm = 0.5 * (vk + vl[k + 1])
        gm = g(vm, h)
        jz = -s0 * abs(vm) / gm
        fz = vm - s0 * abs(vm) * z / gm
        hs = hss(vm)
        tau = th0 if abs(vm) < veps else (thp if h <= hs else thn)
        fh = (hs - h) / tau
        z = z + dt * phi1(dt * jz) * fz
        h = h + dt * phi1(-dt / tau) * fh
    return F


def baseline(record: dict[str, np.ndarray], start: dict[str, float], free: list[str],
             bounds: tuple[np.ndarray, np.ndarray], scale: np.ndarray, max_nfev: int | None
             ) -> dict[str, float]:
    t, v, a, y = record["t"], record["v"], record["a"], record["F"]
    sims = 0

    def res(q: np.ndarray) -> np.ndarray:
        nonlocal sims
        sims += 1
        return y - plain_nmlgm(t, v, a, {**start, **dict(zip(free, q, strict=True))})

    x0 = np.array([start[k] for k in free])
    t0, c0 = time.perf_counter(), time.process_time()
    out = least_squares(res, x0, jac="2-point", bounds=bounds, x_scale=scale, method="trf",
                        max_nfev=max_nfev)
    return {"seconds": time.perf_counter() - t0, "cpu_seconds": time.process_time() - c0,
            "simulations": sims, "nfev": int(out.nfev),
            "njev": int(out.njev or 0), "status": int(out.status),
            "rms": float(np.sqrt(np.mean(out.fun**2)))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="10 s record instead of 60 s")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--baseline-nfev", type=int, default=None,
                    help="cap the baseline fit at N evaluations and extrapolate (default: "
                    "run it to convergence)")
    ap.add_argument("--json", default=None, help="write the figures to this JSON file")
    args = ap.parse_args()
    duration = 10.0 if args.quick else 60.0

    with tempfile.TemporaryDirectory() as tmp:
        rec = Path(tmp) / "nmlgm.csv"
        make_record(rec, duration)
        print(f"record: NMLGM, {duration:g} s at 1 kHz ({int(duration * 1000) + 1} samples)")

        colds = []
        for i in range(args.repeats):
            env = dict(os.environ, FCOMP_CACHE=str(Path(tmp) / f"cache{i}"))
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            proc = subprocess.run([sys.executable, "-c", COLD, str(rec)], capture_output=True,
                                  text=True, env=env, check=True)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            colds.append(json.loads(proc.stdout.strip().splitlines()[-1]))
            colds[-1]["cpu"] = (after.ru_utime + after.ru_stime
                                - before.ru_utime - before.ru_stime)  # with the C compiler
        cold = statistics.median(c["total"] for c in colds)
        cold_cpu = statistics.median(c["cpu"] for c in colds)
        runs = ", ".join(f"{c['total']:.2f}" for c in colds)
        print(f"fcomp cold (fresh process, empty compile cache), median of {args.repeats}: "
              f"{cold:.2f} s wall, {cold_cpu:.2f} s CPU (compiler included)  [runs: {runs}; "
              f"imports and reading {statistics.median(c['import_read'] for c in colds):.2f} s, "
              f"fit {statistics.median(c['fit'] for c in colds):.2f} s]")

        from fcomp.identification import FrictionFit
        from fcomp.identification.dynamic import EXTRAS
        from fcomp.identification.engine import FitJob
        from fcomp.identification.target import fit_data
        from fcomp.measurement import Measurement

        meas = Measurement.read(rec)
        FrictionFit("nmlgm").fit(meas)  # warm up
        warms, warm_cpus = [], []
        for _ in range(args.repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            fit = FrictionFit("nmlgm").fit(meas)
            warms.append(time.perf_counter() - t0)
            warm_cpus.append(time.process_time() - c0)
        warm = statistics.median(warms)
        warm_cpu = statistics.median(warm_cpus)
        traj = fit.stages_[-1]
        print(f"fcomp warm fit, median of {args.repeats}: {warm:.2f} s wall, {warm_cpu:.2f} s CPU "
              f"(trajectory stage: {traj['evaluations']} evaluations, rms {fit.rms_:.4f} N)")

        # the baseline starts where fcomp's trajectory stage starts
        est = FrictionFit("nmlgm")
        model = est._base_model()
        job = FitJob(est.settings(), model, fit_data(meas))
        free0, _, start = job.prepare()
        job.static_stage(model, free0, start, required=False, final=False)  # updates start
        free = [n for n in traj["parameters"] if n not in EXTRAS]
        specs = model.param_specs()
        lo = np.array([specs[n].lower + (1e-12 if specs[n].lower_open else 0.0) for n in free])
        hi = np.array([specs[n].upper for n in free])
        scale = np.array([abs(start[n]) or 0.01 for n in free])
        record = {k: meas[k] for k in ("t", "v", "a", "F")}
        base_start = {k: float(v) for k, v in start.items() if k not in EXTRAS}
        sim_times = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            plain_nmlgm(record["t"], record["v"], record["a"], base_start)
            sim_times.append(time.perf_counter() - t0)
        sim = statistics.median(sim_times)
        print(f"baseline: one plain-Python simulation, median of {args.repeats}: {sim:.3f} s")
        cap = args.baseline_nfev
        b = baseline(record, base_start, free, (lo, hi), scale, cap)
        per_sim = b["seconds"] / b["simulations"]
        print(f"baseline least_squares (2-point, {len(free)} parameters, "
              f"{'to convergence' if cap is None else f'capped at {cap} evaluations'}): "
              f"{b['seconds']:.1f} s wall, {b['cpu_seconds']:.1f} s CPU for {b['simulations']} "
              "simulations "
              f"({b['nfev']} residual + {b['njev']} Jacobian evaluations, status {b['status']})")
        base_cpu = b["cpu_seconds"] * (1.0 if cap is None else (
            traj["evaluations"] * (1 + len(free)) / b["simulations"]))
        if cap is None:
            base_total = b["seconds"]
            label = "measured"
        else:
            # fcomp's trajectory stage: each evaluation = residual and exact Jacobian;
            # the finite-difference baseline needs 1 + p simulations per Jacobian
            base_total = traj["evaluations"] * (1 + len(free)) * per_sim
            label = (f"extrapolated: {traj['evaluations']} evaluations x "
                     f"{1 + len(free)} simulations x {per_sim:.3f} s")
        print(f"baseline full fit: {base_total:.0f} s ({label})")
        print(f"ratio baseline / fcomp cold = {base_total / cold:.0f}x wall, "
              f"{base_cpu / cold_cpu:.0f}x CPU; baseline / fcomp warm = {base_total / warm:.0f}x "
              f"wall, {base_cpu / warm_cpu:.0f}x CPU")
        print(f"goal (issue 15): cold <= 4 s -> {'met' if cold <= 4 else 'NOT met'}; the goal "
              f"was set against a 168 s baseline, i.e. baseline / cold >= 42x -> "
              f"{'met' if base_cpu / cold_cpu >= 42 else 'NOT met'} "
              f"({base_cpu / cold_cpu:.0f}x CPU)")
        if args.json:
            Path(args.json).write_text(json.dumps({
                "duration_s": duration, "cold_runs": colds, "cold_median_s": cold,
                "cold_cpu_median_s": cold_cpu,
                "warm_runs_s": warms, "warm_median_s": warm, "warm_cpu_median_s": warm_cpu,
                "baseline_cpu_s": base_cpu, "baseline_sim_s": sim_times,
                "baseline_run": b, "baseline_total_s": base_total, "baseline_label": label,
                "ratio_cold": base_total / cold, "ratio_warm": base_total / warm,
            }, indent=2))


if __name__ == "__main__":
    main()
