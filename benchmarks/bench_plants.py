"""Benchmark: the plant engine against plain solve_ivp and python-control (issue 3).

For each case -- ``hydraulic`` with ``nmlgm`` under seed 002's input (4.5 mA,
1 Hz) and ``pneumatic`` with ``nmlgm`` (``seed000-servo``, 0.1 at 1 Hz, clear of the end stops),
3 s each, output at 1 kHz -- it times, in one run:

* ``fcomp``: :meth:`plants.base.OdePlant.simulate` (compiled RODAS4, default
  tolerances ``rtol = atol = 1e-6``; the one-time C compilation is reported
  apart);
* ``solve_ivp``: :func:`scipy.integrate.solve_ivp` (Radau) on the plain
  Python right-hand side of the same equations (``tests/independent_plants.py``)
  at ``rtol = 1e-6``, absolute tolerances ``1e-6`` times the same state scales;
* ``python-control``: ``control.input_output_response`` on the exported
  system (:meth:`~plants.base.OdePlant.to_iosys`), its default solver
  (RK45) with ``rtol = 1e-6``;

and the accuracy of each against a tight reference (LSODA on the plain
right-hand side at ``rtol = 1e-10``): the largest error in ``v`` and ``p1``
relative to their range over the run. Times are medians of ``--repeat``
runs (the slow baselines once unless ``--repeat-slow``).

Usage::

    python benchmarks/bench_plants.py [--repeat 5] [--repeat-slow 1] [--json OUT.json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the independent plain implementations

from helpers import independent_plants as ip  # noqa: E402

from fcomp.models import make_model  # noqa: E402
from plants import PLANTS  # noqa: E402

P_ATM = 101325.0
DURATION = 3.0
RATE = 1000.0


def timed(fn: Callable[[], Any], repeat: int) -> tuple[float, float, Any]:
    """Median wall time and median CPU time (s) of ``repeat`` calls, and the last result.

    CPU time (this process) is the fairer figure on a shared, loaded machine."""
    wall, cpu, out = [], [], None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu), out


def rel_err(got: np.ndarray, ref: np.ndarray) -> float:
    return float(np.max(np.abs(got - ref)) / np.ptp(ref))


def case(name: str, plant_name: str, params: str, amp: float, freq: float, plain: Any,
         scale: np.ndarray, args: argparse.Namespace) -> dict[str, Any]:
    plant = PLANTS.get(plant_name)(make_model("nmlgm", params=params))
    t = np.arange(int(DURATION * RATE) + 1) / RATE
    U = amp * np.sin(2 * np.pi * freq * t)

    def u_fn(tq: float) -> float:
        return amp * np.sin(2 * np.pi * freq * tq)

    def rhs(tq: float, y: np.ndarray) -> list[float]:
        return plain.rhs(tq, y, u_fn)

    y0 = plain.x0()
    t0 = time.perf_counter()
    plant.simulate(U[:11], 0.01, RATE)  # builds and compiles the model once
    compile_s = time.perf_counter() - t0

    ref = ip.reference(rhs, y0, t, rtol=1e-10, atol=1e-12 * scale, method="LSODA")
    ref_v, ref_p1 = ref[:, 1], ref[:, 2]

    t_fc, c_fc, run = timed(lambda: plant.simulate(U, DURATION, RATE), args.repeat)
    fc_err = max(rel_err(run["v"], ref_v), rel_err(run["p1"] + P_ATM, ref_p1))

    def radau() -> Any:
        return solve_ivp(rhs, (0.0, DURATION), y0, method="Radau", t_eval=t, rtol=1e-6,
                         atol=1e-6 * scale)

    t_ra, c_ra, sol = timed(radau, args.repeat_slow)
    ra_err = max(rel_err(sol.y[1], ref_v), rel_err(sol.y[2], ref_p1))

    import control as ct

    sys_ = plant.to_iosys()

    def pyctrl() -> Any:
        return ct.input_output_response(sys_, t, U, plant.initial_state(),
                                        solve_ivp_kwargs={"rtol": 1e-6})

    t_ct, c_ct, resp = timed(pyctrl, args.repeat_slow)
    iv, ip1 = list(plant.output_names).index("v"), list(plant.output_names).index("p1")
    ct_err = max(rel_err(resp.outputs[iv], ref_v), rel_err(resp.outputs[ip1] + P_ATM, ref_p1))

    return {
        "case": name, "simulated_s": DURATION, "output_rate_hz": RATE,
        "fcomp_s": t_fc, "fcomp_cpu_s": c_fc, "fcomp_error": fc_err,
        "fcomp_steps": run.meta["simulation"]["steps"], "fcomp_compile_s": compile_s,
        "solve_ivp_radau_s": t_ra, "solve_ivp_radau_cpu_s": c_ra, "solve_ivp_radau_error": ra_err,
        "python_control_s": t_ct, "python_control_cpu_s": c_ct, "python_control_error": ct_err,
        "speedup_vs_radau": t_ra / t_fc, "speedup_vs_radau_cpu": c_ra / c_fc,
        "speedup_vs_python_control": t_ct / t_fc,
        "speedup_vs_python_control_cpu": c_ct / c_fc,
        "realtime_factor": DURATION / t_fc, "realtime_factor_cpu": DURATION / c_fc,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="runs of the fcomp engine")
    ap.add_argument("--repeat-slow", type=int, default=1, dest="repeat_slow",
                    help="runs of each baseline")
    ap.add_argument("--json", default=None, help="write the results here")
    args = ap.parse_args()
    hyd = ip.Hydraulic.seed002()
    pne = ip.Pneumatic.seed000()
    results = [
        case("hydraulic + nmlgm (seed 002, 4.5 mA, 1 Hz)", "hydraulic", "seed002-type1",
             0.0045, 1.0, hyd, np.array([0.3, 1, 6.5e6, 6.5e6, 2e-4, 0.1, 1e-4, 0.5]), args),
        case("pneumatic + nmlgm (seed000-servo, 0.1, 1 Hz)", "pneumatic", "seed000-servo",
             0.1, 1.0, pne, np.array([0.3, 1, 6e5, 6e5, 1, 1e-3, 0.5]), args),
    ]
    for r in results:
        print(f"\n{r['case']}: {r['simulated_s']:g} s simulated, output {r['output_rate_hz']:g} Hz"
              "   [median wall ms / CPU ms, error = max |e|/range of v, p1]")
        rows = [("fcomp (rodas4, compiled)", "fcomp", ""),
                ("solve_ivp Radau (plain)", "solve_ivp_radau", "radau"),
                ("python-control (RK45)", "python_control", "python_control")]
        for label, key, ratio in rows:
            line = (f"  {label:26s} {r[key + '_s'] * 1e3:9.1f} / {r[key + '_cpu_s'] * 1e3:9.1f}"
                    f"  error {r[key + '_error']:.1e}")
            if ratio:
                line += (f"  x{r['speedup_vs_' + ratio]:.0f} (wall) x{r['speedup_vs_' + ratio + '_cpu']:.0f}"
                         " (CPU) slower than fcomp")
            print(line)
        print(f"  fcomp: {r['fcomp_steps']} steps, one-time model build {r['fcomp_compile_s']:.1f} s"
              f" (cached), {r['realtime_factor']:.0f}x (wall) / {r['realtime_factor_cpu']:.0f}x (CPU)"
              " faster than real time")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
