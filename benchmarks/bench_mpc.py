"""Benchmark: MPC step on the hydraulic servo with NMLGM in the prediction model, beside do-mpc.

Runs, in one process and one closed loop each (controllers/mpc_benchmark.py):

* fcomp's real-time-iteration MPC (CasADi, compiled condensing, DAQP), horizon >= 20 steps
  of 2 ms (500 Hz), and do-mpc (collocation + IPOPT) on the same problem;
* the EKF step (filterpy, exact CasADi Jacobians) at 1 kHz.

Goals (issue 6): MPC median < 2 ms and max < 10 ms, faster than do-mpc; EKF median < 0.2 ms.

    pip install -e ".[bench]"         # do-mpc, for the comparison
    python benchmarks/bench_mpc.py [--steps 300] [--horizon 20] [--json OUT.json]
"""

from __future__ import annotations

import argparse
import json
import platform
import sys


def main(argv: list[str] | None = None) -> int:
    from controllers.mpc_benchmark import benchmark_ekf, compare, do_mpc_available

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=300, help="closed-loop MPC steps (default 300)")
    p.add_argument("--horizon", type=int, default=20, help="MPC horizon in steps (>= 20)")
    p.add_argument("--json", default=None, metavar="OUT.json", help="also write the results")
    args = p.parse_args(argv)
    if args.horizon < 20 or args.steps < 10:
        p.error("--horizon must be >= 20 and --steps >= 10")
    if not do_mpc_available():
        print("note: do-mpc is not installed (pip install -e '.[bench]'): fcomp only",
              file=sys.stderr)
    res = compare(steps=args.steps, horizon=args.horizon)
    res["ekf"] = benchmark_ekf()
    res["machine"] = {"python": platform.python_version(), "machine": platform.machine(),
                      "processor": platform.processor()}
    print(f"MPC step, hydraulic servo + NMLGM, horizon {res['horizon']} x "
          f"{res['dt'] * 1e3:g} ms, {args.steps} closed-loop steps")
    for name, d in res["solvers"].items():
        print(f"  {name:32s} median {d['median'] * 1e3:8.3f} ms   max {d['max'] * 1e3:8.3f} ms"
              f"   p99 {d['p99'] * 1e3:8.3f} ms   tracking RMS {d['rms_error'] * 1e6:7.1f} um"
              f"   failed {d['failed']}")
    if "speedup_median" in res:
        print(f"  speed-up over do-mpc: median {res['speedup_median']:.0f}x, "
              f"max {res['speedup_max']:.0f}x")
    e = res["ekf"]
    print(f"EKF step (1 kHz, 8 states): median {e['median'] * 1e3:.3f} ms, "
          f"max {e['max'] * 1e3:.3f} ms")
    fc = next(iter(res["solvers"].values()))
    ok = fc["median"] < 2e-3 and fc["max"] < 10e-3 and e["median"] < 0.2e-3
    print("goals met" if ok else "goals NOT met (median MPC < 2 ms, max < 10 ms, EKF < 0.2 ms)")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(res, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
