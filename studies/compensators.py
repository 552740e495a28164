"""Study ``compensators``: friction compensators against PID in closed loop, both fluid plants.

Every controller of :mod:`controllers` (``pid``, ``pid-ff``,
``lugre-observer``, ``ekf``, ``mpc``) runs every task of
:mod:`controllers.tasks` (``slow-sine``, ``steps``, ``low-velocity-ramp``,
``seed002-sine``) on both plants (``hydraulic``: seed 002's servo,
``pneumatic``: seed 000's cylinder with the assumed servo valve), in the
sampled-data harness of :mod:`controllers.harness`: sensor noise and
quantisation, and a controller whose friction model is *wrong* (the default
mismatch of :data:`controllers.harness.DEFAULT_MISMATCH`) -- the plant
integrates the true NMLGM friction, the controllers know a different one.

Outputs:

* ``summary.json``: ``{"results": [{"plant", "controller", "task",
  "rms_error", "max_error", "steady_state_error", "solve_time_median",
  "solve_time_max", ...}, ...]}`` (errors in m, times in s), plus the
  robustness distributions, how many draws and why (``robustness_draws``:
  the stopping rule's decisions), the EKF and MPC step times (wall clock and
  CPU, per closed loop) and the verdict;
* the report: ranked tables (RMS error, ratio to ``pid``), tracking-error
  plots, friction estimate against the true friction, the Monte Carlo
  robustness sweep (friction mismatch and sensor noise, per-compensator
  distributions), and the MPC step time beside do-mpc where do-mpc is
  installed (``pip install 'fcomp[bench]'``; ``benchmarks/bench_mpc.py``).

The runs go to a local process pool (2 workers by default; ``fcomp study
--workers N``, or ``FCOMP_WORKERS``) or to a Dask cluster (``fcomp study
--scheduler ADDRESS``, or ``FCOMP_DASK_SCHEDULER``), with a progress bar on a
terminal; the longest runs are handed out first, so that no worker is left
alone with a long run at the end. The Monte Carlo sweep draws in batches
until :data:`FULL_RULE` is met (:func:`controllers.robustness.run_sequential`:
each compensator until the confidence interval of its median error ratio to
``pid`` excludes 1, at most ``max_draws``); fast mode runs :data:`FAST_DRAWS`
draws, drawn as points rather than box plots.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from controllers import CONTROLLERS
from controllers.harness import DEFAULT_MISMATCH, LoopConfig, control_model
from controllers.robustness import (
    Job,
    StoppingRule,
    Sweep,
    distributions,
    draw_distribution,
    run_jobs,
    run_sequential,
)
from controllers.tasks import TASKS
from fcomp.parallel import progress_bar, ticker
from studies.base import Study, StudyConfig, StudyOutput

PLANTS = ("hydraulic", "pneumatic")
CONTROLLER_ORDER = ("pid", "pid-ff", "lugre-observer", "ekf", "mpc")
TASK_ORDER = ("slow-sine", "steps", "low-velocity-ramp", "seed002-sine")
#: Tasks at low velocity (the verdict: best compensator vs pid).
LOW_VELOCITY = ("slow-sine", "low-velocity-ramp")
SUMMARY_FIELDS = ("rms_error", "max_error", "steady_state_error", "solve_time_median",
                  "solve_time_max")


#: Monte Carlo draws per plant, full mode: from 8, 4 more at a time, at most 20 (the former
#: fixed count), until every compensator's effect on the RMS error is decided at 95 %.
FULL_RULE = StoppingRule(confidence=0.95, min_draws=8, max_draws=20, batch=4,
                         reference="pid", metric="rms_error")
#: Monte Carlo draws per plant in fast mode (too few for an interval: shown as points).
FAST_DRAWS = 3
#: Relative cost of a controller's sample (plant step included), to hand out long runs first.
COST = {"pid": 1.0, "pid-ff": 1.2, "lugre-observer": 1.5, "ekf": 2.0, "mpc": 3.0}


def _scheduler(config: StudyConfig) -> str | None:
    return config.scheduler or os.environ.get("FCOMP_DASK_SCHEDULER") or None


def _cost(job: Job) -> float:
    """Expected run time of a job, in arbitrary units (:data:`COST` times the duration)."""
    return COST.get(job.controller, 1.0) * TASKS.get(job.task).run_duration(job.config.fast)


class CompensatorsStudy(Study):
    """Every controller on every task on both plants (see the module docstring)."""

    name = "compensators"
    cost = 80.0
    title = "Friction compensation in closed loop"
    summary = ("PID, static feedforward, LuGre observer, EKF and MPC on a hydraulic and a "
               "pneumatic servo whose friction the controllers know only approximately.")

    def build(self, out: StudyOutput, config: StudyConfig) -> dict[str, Any]:
        fast = config.fast
        jobs = [Job(c, t, LoopConfig(plant=p, fast=fast), keep_signals=True)
                for p in PLANTS for t in TASK_ORDER for c in CONTROLLER_ORDER]
        rule = (StoppingRule(min_draws=FAST_DRAWS, max_draws=FAST_DRAWS, batch=FAST_DRAWS)
                if fast else FULL_RULE)
        sweeps = {p: Sweep(plant=p, samples=rule.max_draws, fast=True,
                           controllers=CONTROLLER_ORDER) for p in PLANTS}
        bar = progress_bar("compensators",
                           len(jobs) + rule.max_draws * len(CONTROLLER_ORDER) * len(PLANTS),
                           enabled=config.progress)
        tick = ticker(bar)

        def run(batch: list[Job]) -> list[dict[str, Any]]:
            order = sorted(range(len(batch)), key=lambda i: -_cost(batch[i]))
            done = run_jobs([batch[i] for i in order], workers=config.local_workers(),
                            scheduler=_scheduler(config), progress=tick)
            res: list[dict[str, Any]] = [{}] * len(batch)
            for i, r in zip(order, done, strict=True):
                res[i] = r
            return res

        try:
            runs = run(jobs)
            sequential = run_sequential(sweeps, rule, run)
        finally:
            bar.close()
        robust = {p: distributions(s["results"]) for p, s in sequential.items()}
        draws = {p: {"draws": s["draws"], "stopped": s["stopped"], "decisions": s["decisions"],
                     "rule": {"confidence": rule.confidence, "level": rule.level,
                              "min_draws": rule.min_draws, "max_draws": rule.max_draws,
                              "batch": rule.batch, "reference": rule.reference,
                              "metric": rule.metric}}
                 for p, s in sequential.items()}
        results = [self._row(r) for r in runs]
        timing = self._timing(runs)
        bench = self._do_mpc(fast)
        verdict = self._verdict(results)
        self._report(out, config, runs, results, robust, sweeps, draws, timing, bench, verdict)
        return {"results": results, "robustness": robust, "robustness_draws": draws,
                "mpc_timing": timing, "benchmark": bench, "verdict": verdict}

    # --------------------------------------------------------------- results
    @staticmethod
    def _row(run: dict[str, Any]) -> dict[str, Any]:
        m = run["metrics"] or {}
        row = {"plant": run["plant"], "controller": run["controller"], "task": run["task"]}
        for k in SUMMARY_FIELDS:
            row[k] = m.get(k, math.nan)
        for k in ("hunting_amplitude", "reversal_error", "valve_activity", "fallbacks"):
            row[k] = m.get(k)
        row["status"] = run["status"]
        return row

    @staticmethod
    def _timing(runs: list[dict[str, Any]]) -> dict[str, Any]:
        """Step times of the EKF and the MPC: over each plant's runs, and per closed loop.

        Wall clock and the controller thread's CPU time (:mod:`controllers.harness`):
        ``p99`` and ``cpu_p99`` are the largest 99th percentile of the runs.
        """
        out: dict[str, Any] = {}
        for p in PLANTS:
            for c in ("ekf", "mpc"):
                mine = [r for r in runs
                        if r["plant"] == p and r["controller"] == c and r["metrics"]]
                if not mine:
                    continue
                ms = [r["metrics"] for r in mine]
                out[f"{p}/{c}"] = {
                    "median_of_medians": float(np.median([m["solve_time_median"] for m in ms])),
                    "p99": float(max(m["solve_time_p99"] for m in ms)),
                    "max": float(max(m["solve_time_max"] for m in ms)),
                    "cpu_p99": float(max(m["solve_time_cpu_p99"] for m in ms)),
                    "cpu_max": float(max(m["solve_time_cpu_max"] for m in ms)),
                    "descheduled": int(sum(m["solve_time_descheduled"] for m in ms)),
                    "steps": int(sum(m["steps"] for m in ms)),
                    "fallbacks": int(sum(m["fallbacks"] for m in ms)),
                    "period": float(np.diff(mine[0]["signals"]["t"][:2])[0]),
                    "loops": {r["task"]: {k: r["metrics"][f"solve_time_{k}"] for k in
                                          ("median", "p99", "max", "cpu_median", "cpu_p99",
                                           "cpu_max", "descheduled")} for r in mine},
                }
        return out

    @staticmethod
    def _do_mpc(fast: bool) -> dict[str, Any]:
        from controllers.mpc_benchmark import compare, do_mpc_available

        if not do_mpc_available():
            return {"available": False,
                    "note": "do-mpc is not installed (pip install 'fcomp[bench]'); "
                            "run benchmarks/bench_mpc.py for the comparison"}
        return {"available": True, **compare(steps=40 if fast else 300)}

    @staticmethod
    def _verdict(results: list[dict[str, Any]]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for p in PLANTS:
            for t in LOW_VELOCITY:
                rows = {r["controller"]: r for r in results
                        if r["plant"] == p and r["task"] == t and r["status"] == "ok"}
                if "pid" not in rows:
                    out[f"{p}/{t}"] = {"best": None, "ratio": None, "halved": False}
                    continue
                comp = {c: r for c, r in rows.items() if c != "pid"}
                best = min(comp, key=lambda c: comp[c]["rms_error"]) if comp else None
                ratio = comp[best]["rms_error"] / rows["pid"]["rms_error"] if best else None
                out[f"{p}/{t}"] = {"best": best, "ratio": ratio,
                                   "halved": bool(ratio is not None and ratio <= 0.5)}
        return out

    def headline(self, results: dict[str, Any]) -> str:
        v = results["verdict"]
        parts = [f"{k}: {d['best']} {d['ratio']:.2f}x pid" for k, d in v.items()
                 if d["ratio"] is not None]
        return "best compensator RMS error vs PID at low velocity -- " + "; ".join(parts)

    # ---------------------------------------------------------------- report
    def _report(self, out: StudyOutput, config: StudyConfig, runs: list[dict[str, Any]],
                results: list[dict[str, Any]], robust: dict[str, Any],
                sweeps: dict[str, Sweep], draws: dict[str, Any], timing: dict[str, Any],
                bench: dict[str, Any], verdict: dict[str, Any]) -> None:
        rep = out.report
        rep.section("Settings")
        rep.paragraph(
            "Each run: the plant integrates the *true* NMLGM friction (its parameter set), "
            "the controller is built on its own plant model whose NMLGM parameters are "
            "multiplied by the mismatch factors below; position and chamber pressures are "
            "measured with noise and quantisation. Errors are `r - x` on the true position. "
            + ("Fast mode: shortened tasks." if config.fast else "Full-length tasks."))
        rep.table(["parameter", "factor"], [[k, v] for k, v in DEFAULT_MISMATCH.items()],
                  caption="Mismatch of the controllers' friction model (factor on the "
                  "plant's value).", digits=[None, 2])
        rows = []
        for p in PLANTS:
            model = control_model(LoopConfig(plant=p))
            s, tu = model.settings, model.tuning
            rows.append([p, s.control_rate, s.u_max, tu.pid_bandwidth, tu.force_bandwidth,
                         tu.margins.gain_db, tu.margins.phase, tu.observer_gain,
                         tu.mpc_horizon(500.0), s.sensors.x_quantum * 1e6, s.sensors.p_quantum])
        rep.table(["plant", "rate [Hz]", "u_max", "PID bw [rad/s]", "force bw [rad/s]",
                   "GM [dB]", "PM [deg]", "observer k [1/s]", "MPC horizon", "x quantum [um]",
                   "p quantum [Pa]"], rows,
                  caption="Controller settings: the tuning derived from each plant "
                  "(controllers.tuning; MPC at 500 Hz).",
                  digits=[None, 0, 3, 1, 0, 1, 0, 1, 0, 1, 0])
        rep.table(["task", "what it exercises", "duration [s]"],
                  [[t, TASKS.get(t).description, TASKS.get(t).run_duration(config.fast)]
                   for t in TASK_ORDER], caption="Tasks.", digits=[None, None, 1])

        rep.section("Verdict: low-velocity tasks")
        for key, d in verdict.items():
            if d["ratio"] is None:
                rep.note(f"{key}: no comparison (pid or every compensator failed).", kind="bad")
                continue
            kind = "ok" if d["halved"] else "warn"
            rep.note(f"{key}: best compensator `{d['best']}` has {d['ratio']:.2f} times the "
                     f"RMS error of `pid` ({'halved or better' if d['halved'] else 'NOT halved'}).",
                     kind=kind)

        rep.section("Ranked results")
        for p in PLANTS:
            rep.section(f"{p}", level=3)
            for t in TASK_ORDER:
                rows_t = [r for r in results if r["plant"] == p and r["task"] == t]
                pid = next((r for r in rows_t if r["controller"] == "pid"
                            and r["status"] == "ok"), None)
                ok = sorted((r for r in rows_t if r["status"] == "ok"),
                            key=lambda r: r["rms_error"])
                bad = [r for r in rows_t if r["status"] != "ok"]
                table = []
                for rank, r in enumerate(ok, start=1):
                    ratio = r["rms_error"] / pid["rms_error"] if pid else None
                    table.append([rank, r["controller"], r["rms_error"] * 1e6,
                                  r["max_error"] * 1e6, r["steady_state_error"] * 1e6,
                                  None if r["hunting_amplitude"] is None
                                  else r["hunting_amplitude"] * 1e6,
                                  None if r["reversal_error"] is None
                                  else r["reversal_error"] * 1e6,
                                  ratio, r["valve_activity"], r["solve_time_median"] * 1e6,
                                  r["solve_time_max"] * 1e3, r["fallbacks"], "ok"])
                for r in bad:
                    table.append([None, r["controller"], None, None, None, None, None, None,
                                  None, None, None, None, r["status"]])
                rep.table(["rank", "controller", "RMS [um]", "max [um]", "steady [um]",
                           "hunting [um]", "reversal [um]", "RMS/pid", "valve act. [1/s]",
                           "step median [us]", "step max [ms]", "fallbacks", "status"],
                          table, caption=f"{p}, task `{t}`, ranked by RMS tracking error.",
                          digits=[0, None, 1, 1, 1, 1, 1, 2, 2, 0, 2, 0, None])
        self._tracking_figures(out, runs)
        self._friction_figures(out, runs)
        self._robustness(out, robust, sweeps, draws)
        self._benchmark(out, timing, bench)

    @staticmethod
    def _signals(runs: list[dict[str, Any]], plant: str, task: str) -> dict[str, Any]:
        return {r["controller"]: r["signals"] for r in runs
                if r["plant"] == plant and r["task"] == task and r.get("signals")}

    def _tracking_figures(self, out: StudyOutput, runs: list[dict[str, Any]]) -> None:
        rep = out.report
        rep.section("Tracking")
        for p in PLANTS:
            fig, axes = out.subplots(len(TASK_ORDER), 1, figsize=(9, 2.6 * len(TASK_ORDER)))
            for ax, t in zip(axes, TASK_ORDER, strict=True):
                for c, s in self._signals(runs, p, t).items():
                    ax.plot(s["t"], (s["r"] - s["x"]) * 1e6, lw=0.9, label=c)
                _panel(ax, f"{p}: {t}", "r - x [um]")
            _finish(out, fig, axes, 5, f"tracking-{p}", f"Tracking error of every controller "
                    f"on every task, {p} plant (true position).")

    def _friction_figures(self, out: StudyOutput, runs: list[dict[str, Any]]) -> None:
        rep = out.report
        rep.section("Friction estimate against the true friction")
        rep.paragraph("The force each compensator fed forward beside the plant's true NMLGM "
                      "friction force in the same run (`pid` feeds none). `pid-ff` uses the static map at the "
                      "reference velocity; the observer and the EKF estimate the bristle (and "
                      "film) state on line; the MPC uses the EKF estimate.")
        for p in PLANTS:
            fig, axes = out.subplots(2, 1, figsize=(9, 5.5))
            for ax, t in zip(axes, LOW_VELOCITY, strict=True):
                for c, s in self._signals(runs, p, t).items():
                    if c == "pid":
                        continue
                    line = ax.plot(s["t"], s["F_hat"], lw=0.9, label=f"{c} estimate")[0]
                    ax.plot(s["t"], s["F_true"], "--", lw=0.8, color=line.get_color(),
                            label=f"{c} true")
                _panel(ax, f"{p}: {t}", "F [N]")
            _finish(out, fig, axes, 4, f"friction-{p}",
                    f"Friction estimate (solid) vs the true friction of the same run (dashed), "
                    f"{p} plant.")

    def _robustness(self, out: StudyOutput, robust: dict[str, Any],
                    sweeps: dict[str, Sweep], draws: dict[str, Any]) -> None:
        rep = out.report
        rep.section("Robustness: friction mismatch and sensor noise (Monte Carlo)")
        sw = next(iter(sweeps.values()))
        rule = next(iter(draws.values()))["rule"]
        counts = ", ".join(f"{p} {d['draws']}" for p, d in draws.items())
        rep.paragraph(
            f"Draws on task `{sw.task}` (fast): every friction parameter of the controllers' "
            f"model multiplied by `exp(N(0, {sw.spread}^2))`, sensor noise scaled by a factor "
            f"uniform in {list(sw.noise)}; every controller sees the same draws. How many: "
            f"{rule['min_draws']} draws, then {rule['batch']} more at a time, at most "
            f"{rule['max_draws']}; a compensator stops being drawn once the confidence interval "
            f"of its median RMS-error ratio to `{rule['reference']}` on the same draws excludes "
            f"1 (distribution-free, order statistics; {100 * rule['level']:.2f} % at each look, "
            f"{100 * rule['confidence']:g} % over all looks). Draws per plant: {counts}. Runs on a "
            "process pool, or a Dask cluster (`fcomp study compensators --scheduler ADDRESS`); "
            "`fcomp sweep` runs such sweeps and grids on their own.")
        rows = []
        for p, dist in robust.items():
            dec = draws[p]["decisions"]
            for c in CONTROLLER_ORDER:
                d = dist.get(c)
                if d is None:
                    continue
                r = d["rms_error"]
                k = dec.get(c, {})
                ci = k.get("interval")
                rows.append([p, c, r["median"] * 1e6, r["p10"] * 1e6, r["p90"] * 1e6,
                             d["max_error"]["median"] * 1e6, k.get("median_ratio"),
                             "-" if not k else (f"{ci[0]:.2f}-{ci[1]:.2f}" if ci else "too few"),
                             k.get("verdict", "reference"), d["runs"], d["failed"]])
        rep.table(["plant", "controller", "RMS median [um]", "RMS p10 [um]", "RMS p90 [um]",
                   "max-error median [um]", "RMS / pid (median)", "interval",
                   "vs pid", "runs", "failed"], rows,
                  caption="Distribution of the metrics over the draws; the median of the "
                  "per-draw ratio to pid with its confidence interval.",
                  digits=[None, None, 1, 1, 1, 1, 2, None, None, 0, 0])
        fig, axes = out.subplots(1, len(robust), figsize=(10, 3.8))
        axes = np.atleast_1d(axes)
        for ax, (p, dist) in zip(axes, robust.items(), strict=True):
            shown = draw_distribution(ax, dist, CONTROLLER_ORDER, scale=1e6)
            ax.set_title(p, fontsize=9)
            ax.set_ylabel("RMS error [um]")
        fig.tight_layout()
        how = ("box: quartiles, whiskers: 10-90 %" if shown == "box" else
               "every draw as a point: too few draws for quantiles")
        out.figure(fig, "robustness", f"RMS tracking error over the Monte Carlo draws, per "
                   f"compensator (log scale; {how}).")

    @staticmethod
    def _benchmark(out: StudyOutput, timing: dict[str, Any], bench: dict[str, Any]) -> None:
        rep = out.report
        rep.section("Compute time: EKF and MPC steps")
        rep.paragraph(
            "Every controller step is timed twice: wall clock, and the CPU time of the "
            "controller's thread -- what the step costs on a processor of its own. Where the "
            "wall clock exceeds the CPU time by more than 0.5 ms the operating system gave the "
            "processor to another process during the step (`descheduled`: on this shared "
            "machine whole scheduler ticks of 4 ms); those steps, not the controller, make the "
            "wall-clock maxima. Python's garbage collector is held off during the loops, as in "
            "a real-time control thread.")
        rows, late = [], []
        for k, v in timing.items():
            period = v["period"]
            ok = v["cpu_max"] <= period
            rows.append([k, v["median_of_medians"] * 1e6, v["p99"] * 1e3, v["max"] * 1e3,
                         v["cpu_p99"] * 1e3, v["cpu_max"] * 1e3, v["descheduled"],
                         period * 1e3, "yes" if ok else "NO", v["fallbacks"]])
            if not ok:
                late.append(f"`{k}` {v['cpu_max'] * 1e3:.3g} ms > {period * 1e3:g} ms")
        rep.table(["plant/controller", "median step [us]", "p99 [ms]", "max [ms]",
                   "CPU p99 [ms]", "CPU max [ms]", "descheduled", "period [ms]", "real-time",
                   "fallbacks"], rows,
                  caption="Controller step time in the closed-loop runs above (whole step: "
                  "EKF + law/QP; this machine) against the sampling period of the loop; "
                  "real-time: the largest CPU time of a step within the period.",
                  digits=[None, 0, 2, 2, 2, 2, 0, 2, None, 0])
        if late:
            rep.note("Worst step's CPU time longer than the sampling period -- not real-time on "
                     "this machine: " + "; ".join(late) + ".", kind="bad")
        loops = [[f"{k}/{task}", d["median"] * 1e6, d["p99"] * 1e3, d["max"] * 1e3,
                  d["cpu_median"] * 1e6, d["cpu_p99"] * 1e3, d["cpu_max"] * 1e3,
                  d["descheduled"]]
                 for k, v in timing.items() if k.endswith("/mpc")
                 for task, d in v["loops"].items()]
        rep.table(["closed loop", "p50 [us]", "p99 [ms]", "max [ms]", "CPU p50 [us]",
                   "CPU p99 [ms]", "CPU max [ms]", "descheduled"], loops,
                  caption="MPC step (EKF + QP) in every closed loop: wall clock and CPU time.",
                  digits=[None, 0, 3, 2, 0, 3, 3, 0])
        if not bench.get("available"):
            rep.note(bench.get("note", "do-mpc comparison not run"), kind="warn")
            return
        rows = [[name, d["median"] * 1e3, d["max"] * 1e3, d["steps"]]
                for name, d in bench["solvers"].items()]
        rep.table(["solver", "median [ms]", "max [ms]", "steps"], rows,
                  caption=f"MPC step on the hydraulic servo with NMLGM in the prediction model, "
                  f"horizon {bench['horizon']} steps of {bench['dt'] * 1e3:g} ms, same problem "
                  f"for both ({bench['note']}).", digits=[None, 3, 3, 0])
        rep.paragraph(f"Speed-up of fcomp's RTI over do-mpc: median "
                      f"{bench['speedup_median']:.1f}x, max {bench['speedup_max']:.1f}x.")


def _panel(ax: Any, title: str, ylabel: str) -> None:
    ax.set_title(title, fontsize=9)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)


def _finish(out: StudyOutput, fig: Any, axes: Any, ncol: int, name: str, caption: str) -> None:
    axes[0].legend(fontsize=7, ncol=ncol)
    axes[-1].set_xlabel("t [s]")
    fig.tight_layout()
    out.figure(fig, name, caption)


STUDY = CompensatorsStudy()
main = STUDY.main

__all__ = ["CONTROLLERS", "STUDY", "CompensatorsStudy", "main"]
