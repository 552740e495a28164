"""Study ``compensators``: friction compensators against PID in closed loop, both fluid plants.

Every controller of :mod:`controllers` (``pid``, ``pid-ff``,
``lugre-observer``, ``ekf``, ``mpc``) runs every task of
:mod:`controllers.tasks` (``slow-sine``, ``steps``, ``low-velocity-ramp``,
``seed002-sine``) on both plants (``hydraulic``: seed 002's servo,
``pneumatic``: seed 000's cylinder with the assumed servo valve) -- or on
the one plant of a plant file (:attr:`StudyConfig.plant_file
<studies.base.StudyConfig>`, ``fcomp study compensators --plant-params
PLANT.toml``: its parameters, sensors, valve limits, control rate and
tuning; the results name it by the file's ``name``) -- in the
sampled-data harness of :mod:`controllers.harness`: sensor noise and
quantisation, and a controller whose friction model is *wrong* (the default
mismatch of :data:`controllers.harness.DEFAULT_MISMATCH`) -- the plant
integrates the true NMLGM friction, the controllers know a different one.
``StudyConfig.friction`` (``--friction NAME|MODEL.json``) replaces the true
friction: a model named takes its values from the parameter set of the
plant (of the built-in plant of a plant file's kind), a model file
(:mod:`fcomp.modelfile`) its own; the controllers are built with the same
model times the same mismatch factors (a factor on a parameter the model
lacks is ignored), and a model file's measurement terms are dropped with a
warning.

Outputs:

* ``summary.json``: ``{"results": [{"plant", "controller", "task",
  "rms_error", "max_error", "steady_state_error", "solve_time_median",
  "solve_time_max", ...}, ...]}`` (errors in m, times in s), plus the
  robustness distributions, how many draws and why (``robustness_draws``:
  the stopping rule's decisions), the EKF and MPC step times (wall clock and
  CPU, per closed loop) and the verdict; with a plant file or a friction
  given, also ``setup``: the plants run (name, kind, source, controller
  settings), the friction models and the mismatch factors, and the warnings;
* the report: ranked tables (RMS error, ratio to ``pid``), tracking-error
  plots, friction estimate against the true friction, the Monte Carlo
  robustness sweep (friction mismatch and sensor noise, per-compensator
  distributions), and the MPC step time beside do-mpc where do-mpc is
  installed (``pip install 'fcomp[bench]'``; ``benchmarks/bench_mpc.py``).

The runs go to a local process pool (2 workers by default; ``fcomp study
--jobs N``, or ``FCOMP_WORKERS``) or to a Dask cluster (``fcomp study
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
import re
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from controllers import CONTROLLERS
from controllers.harness import DEFAULT_MISMATCH, LoopConfig, control_model, friction_label
from controllers.plant_model import PlantSettings, friction_with_mismatch, plant_settings
from controllers.robustness import (
    Job,
    StoppingRule,
    Sweep,
    distributions,
    draw_distribution,
    run_jobs,
    run_sequential,
    with_tunings,
)
from controllers.tasks import TASKS
from fcomp.errors import FcompError
from fcomp.figstyle import legend_above
from fcomp.models.base import FrictionModel
from fcomp.progress import progress_bar, ticker
from studies.base import Finding, Study, StudyConfig, StudyOutput

#: The built-in plants the study runs on (without a plant file).
PLANTS = ("hydraulic", "pneumatic")
#: The plant's true friction model (the controllers': the same times the mismatch).
DEFAULT_FRICTION = "nmlgm"
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


@dataclass(frozen=True)
class StudyPlant:
    """A plant the study runs on.

    Attributes
    ----------
    label
        How the results name it: the built-in plant's name, or the plant file's ``name``.
    base
        The closed-loop set-up every run on it modifies (plant or plant file, the true and
        the controllers' friction).
    settings
        The controllers' settings on it (:func:`controllers.plant_model.plant_settings`).
    source
        ``"built-in"`` or the plant file as given.
    """

    label: str
    base: LoopConfig
    settings: PlantSettings
    source: str


def study_plants(config: StudyConfig, warnings: list[str] | None = None
                 ) -> list[StudyPlant]:
    """The plants a configuration runs the study on: the built-in :data:`PLANTS`, or the
    plant file of ``config.plant_file``; with the friction of ``config.friction``.

    Checks every input (the plant file reads, the friction model exists and takes the
    values of each plant's parameter set, the controllers' mismatched copy is valid); a
    model file's dropped measurement terms are appended to ``warnings``.

    Raises
    ------
    FcompError
        A plant file or model file that does not read, an unknown model.
    """
    friction = _true_friction(config.friction, warnings, config.effects)
    if config.plant_file is None:
        if config.friction is None:  # the study as it always ran (bit for bit)
            return [StudyPlant(p, LoopConfig(plant=p), plant_settings(p), "built-in")
                    for p in PLANTS]
        plants = [StudyPlant(p, LoopConfig(plant=p, friction=friction,
                                           controller_friction=friction),
                             plant_settings(p), "built-in") for p in PLANTS]
    else:
        from controllers.compensate import resolve_plant

        pf = resolve_plant(config.plant_file)
        plants = [StudyPlant(pf.name, LoopConfig(plant=pf.kind, plant_file=pf,
                                                 friction=friction,
                                                 controller_friction=friction),
                             plant_settings(pf), pf.label)]
    for sp in plants:
        _check_friction(sp.base)
    return plants


def _true_friction(spec: Any, warnings: list[str] | None,
                   effects: str | os.PathLike[str] | None = None) -> str | FrictionModel:
    """The plant's true friction: the default, a model, a model file's model (measurement
    terms dropped: a line in ``warnings``) or a registered name (checked). The user's
    effects module ``effects`` is loaded first, whatever the friction (an error in it is
    one line, as in ``compensate``)."""
    from fcomp.effects import load_effects_module
    from fcomp.modelfile import is_model_file, seal_friction
    from fcomp.models import MODELS

    if effects is not None:
        load_effects_module(effects)

    if spec is None:
        return DEFAULT_FRICTION
    if isinstance(spec, FrictionModel):
        return spec
    if not isinstance(spec, str | os.PathLike):
        raise FcompError(f"study friction: a model name, a model file or a friction model, "
                         f"not {type(spec).__name__}")
    text = str(spec)
    if is_model_file(text):
        model, dropped = seal_friction(text, "the plant's or the controllers' friction",
                                       effects)
        if dropped and warnings is not None:
            warnings.append(dropped)
        return model
    MODELS.get(text)
    return text


def _check_friction(base: LoopConfig) -> None:
    """The true friction of ``base`` builds on its plant's parameter set, and so does the
    controllers' copy with the mismatch factors."""
    from controllers.harness import _friction

    friction_with_mismatch(_friction(base.controller_friction, base), base.mismatch)
    _friction(base.friction, base)


def _slug(label: str) -> str:
    """A plant's label as a figure name may hold it (letters, digits, '-', '_')."""
    return re.sub(r"[^A-Za-z0-9_-]+", "-", label).strip("-") or "plant"


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
    options = ("plant_file", "friction", "effects")

    def check(self, config: StudyConfig) -> list[str]:
        warnings = super().check(config)
        study_plants(config, warnings)
        return warnings

    def subtitle(self, config: StudyConfig) -> str:
        if config.plant_file is None:
            return self.summary
        pf = study_plants(config)[0]
        return (f"PID, static feedforward, LuGre observer, EKF and MPC on the "
                f"{pf.base.plant} servo {pf.label} (plant file {pf.source}) whose friction "
                "the controllers know only approximately.")

    def build(self, out: StudyOutput, config: StudyConfig) -> dict[str, Any]:
        fast = config.fast
        warnings: list[str] = []
        plants = study_plants(config, warnings)
        names = [sp.label for sp in plants]
        jobs = [Job(c, t, replace(sp.base, fast=fast), keep_signals=True)
                for sp in plants for t in TASK_ORDER for c in CONTROLLER_ORDER]
        rule = (StoppingRule(min_draws=FAST_DRAWS, max_draws=FAST_DRAWS, batch=FAST_DRAWS)
                if fast else FULL_RULE)
        sweeps = {sp.label: Sweep(plant=sp.base.plant, samples=rule.max_draws, fast=True,
                                  controllers=CONTROLLER_ORDER, base=sp.base)
                  for sp in plants}
        bar = progress_bar("compensators",
                           len(jobs) + rule.max_draws * len(CONTROLLER_ORDER) * len(plants),
                           enabled=config.progress)
        tick = ticker(bar)

        def run(batch: list[Job]) -> list[dict[str, Any]]:
            # each configuration's tuning derived once, not by every worker that runs it
            tuned = with_tunings(batch, workers=config.local_workers(),
                                 scheduler=_scheduler(config))
            order = sorted(range(len(batch)), key=lambda i: -_cost(batch[i]))
            done = run_jobs([tuned[i] for i in order], workers=config.local_workers(),
                            scheduler=_scheduler(config), progress=tick)
            res: list[dict[str, Any]] = [{}] * len(batch)
            for i, r in zip(order, done, strict=True):
                pf = batch[i].config.plant_file  # a plant file's runs: named by its name
                res[i] = r if pf is None else {**r, "plant": pf.name}
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
        timing = self._timing(runs, names)
        bench = self._do_mpc(fast)
        verdict = self._verdict(results, names)
        self._report(out, config, plants, warnings, runs, results, robust, sweeps, draws,
                     timing, bench, verdict)
        doc = {"results": results, "robustness": robust, "robustness_draws": draws,
               "mpc_timing": timing, "benchmark": bench, "verdict": verdict}
        if config.plant_file is not None or config.friction is not None:
            doc["setup"] = self._setup(config, plants, warnings)
        return doc

    @staticmethod
    def _setup(config: StudyConfig, plants: list[StudyPlant], warnings: list[str]
               ) -> dict[str, Any]:
        """What the runs were set up with (summary.json ``setup``, when not the default)."""
        base = plants[0].base
        spec = config.friction
        return {
            "plants": [{"name": sp.label, "kind": sp.base.plant, "source": sp.source,
                        "settings": _settings_dict(sp.settings, control_model(sp.base).tuning)} for sp in plants],
            "friction": friction_label(base.friction),
            "friction_source": (None if spec is None or isinstance(spec, FrictionModel)
                                else str(spec)),
            "controller_friction": friction_label(base.controller_friction),
            "mismatch": dict(base.mismatch),
            "warnings": list(warnings),
        }

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
    def _timing(runs: list[dict[str, Any]], plants: list[str]) -> dict[str, Any]:
        """Step times of the EKF and the MPC: over each plant's runs, and per closed loop.

        Wall clock and the controller thread's CPU time (:mod:`controllers.harness`):
        ``p99`` and ``cpu_p99`` are the largest 99th percentile of the runs.
        """
        out: dict[str, Any] = {}
        for p in plants:
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
    def _verdict(results: list[dict[str, Any]], plants: list[str]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for p in plants:
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
        parts = [f"{k}: {d['best']} {100 * d['ratio']:.0f} % of PID's" for k, d in v.items()
                 if d["ratio"] is not None]
        return "RMS tracking error of the best compensator at low velocity -- " + "; ".join(parts)

    def finding(self, results: dict[str, Any]) -> Finding:
        v = {k: d for k, d in results["verdict"].items() if d["ratio"] is not None}
        halved = [k for k, d in v.items() if d["halved"]]
        plants = list(dict.fromkeys(r["plant"] for r in results["results"]))
        if v and len(halved) == len(results["verdict"]):
            status, level = "confirmed", "ok"
        elif halved:
            status, level = "partly confirmed", "warn"
        else:
            status, level = "not confirmed", "bad"
        best = ", ".join(f"{k} {d['best']} {100 * d['ratio']:.0f} %" for k, d in v.items())
        draws = results.get("robustness_draws", {})
        n = min((d["draws"] for d in draws.values()), default=0)
        return Finding(
            status, level,
            f"A friction compensator halves PID's RMS tracking error at low velocity in "
            f"{len(halved)} of {len(results['verdict'])} plant/task pairs (best compensator, "
            f"its error in % of PID's: {best}), with the controllers' friction model off by "
            "15-50 % per parameter.",
            sure=f"simulation only, one run per task on the shipped plants; the Monte Carlo "
                 f"check of friction mismatch and sensor noise ran {n} draws per plant"
                 + (" (fast mode: too few for intervals; run without --fast)." if
                    any(not d["decisions"] or all(not x.get("interval") for x in
                                                  d["decisions"].values())
                        for d in draws.values()) else "."),
            next="identify your cylinder's friction (fcomp fit), check what it buys on your "
                 "plant (fcomp compensate --plant-params PLANT.toml), then take the best "
                 "compensator to the rig as C code (fcomp export).",
            flags=worse_than_pid(results["results"], plants), confidence="medium")

    def key_figure(self, results: dict[str, Any]) -> str | None:
        return "robustness"

    # ---------------------------------------------------------------- report
    def _report(self, out: StudyOutput, config: StudyConfig, plants: list[StudyPlant],
                warnings: list[str], runs: list[dict[str, Any]],
                results: list[dict[str, Any]], robust: dict[str, Any],
                sweeps: dict[str, Sweep], draws: dict[str, Any], timing: dict[str, Any],
                bench: dict[str, Any], verdict: dict[str, Any]) -> None:
        rep = out.report
        rep.section("Settings")
        base = plants[0].base
        if config.friction is None:
            what = ("the plant integrates the true NMLGM friction (its parameter set), "
                    "the controller is built on its own plant model whose NMLGM parameters "
                    "are multiplied by the mismatch factors below")
        else:
            true = friction_label(base.friction)
            spec = config.friction
            given = (f" (model file `{spec}`)" if isinstance(spec, str | os.PathLike)
                     and str(spec).lower().endswith(".json") else "")
            what = (f"the plant integrates the true friction `{true}`{given}, "
                    f"the controller is built on its own plant model with the same friction "
                    f"model, its parameters multiplied by the mismatch factors below (a "
                    f"factor on a parameter the model lacks is ignored)")
        rep.paragraph(
            f"Each run: {what}; position and chamber pressures are "
            "measured with noise and quantisation. Errors are `r - x` on the true position. "
            + ("Fast mode: shortened tasks." if config.fast else "Full-length tasks."))
        for w in warnings:
            rep.note(w, kind="warn")
        rep.table(["parameter", "factor"], [[k, v] for k, v in DEFAULT_MISMATCH.items()],
                  caption="Mismatch of the controllers' friction model (factor on the "
                  "plant's value).", digits=[None, 2])
        for sp in plants:
            if sp.base.plant_file is not None:
                self._plant_file_table(out, sp)
        source = ("the built-in plants'" if all(sp.source == "built-in" for sp in plants)
                  else "the plant file's")
        rep.table(["setting", *(sp.label for sp in plants)], settings_rows(plants),
                  caption=f"Controller settings: {source} control rate, valve limits and "
                  "sensors; the tuning derived from the plant (controllers.tuning; values "
                  "the plant file gives explicitly win) with its margins; MPC at 500 Hz.")
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
        for flag in worse_than_pid(results, [sp.label for sp in plants]):
            rep.note(flag, kind="warn")

        rep.section("Ranked results")
        for p in (sp.label for sp in plants):
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
                                  ratio, r["valve_activity"]])
                for r in bad:
                    table.append([None, f"{r['controller']}: {r['status']}", None, None, None,
                                  None, None, None, None])
                rep.table(["rank", "controller", "RMS [um]", "max [um]", "steady [um]",
                           "hunting [um]", "reversal [um]", "RMS/pid", "valve act. [1/s]"],
                          table, caption=f"{p}, task `{t}`, ranked by RMS tracking error "
                          "(errors in micrometres; the step times of the EKF and the MPC are "
                          "in the last section).",
                          digits=[0, None, 1, 1, 1, 1, 1, 2, 2])
        self._tracking_figures(out, runs, plants)
        self._friction_figures(out, runs, plants)
        self._robustness(out, robust, sweeps, draws)
        self._benchmark(out, timing, bench)

    @staticmethod
    def _signals(runs: list[dict[str, Any]], plant: str, task: str) -> dict[str, Any]:
        return {r["controller"]: r["signals"] for r in runs
                if r["plant"] == plant and r["task"] == task and r.get("signals")}

    @staticmethod
    def _plant_file_table(out: StudyOutput, sp: StudyPlant) -> None:
        """The plant file's main values (geometry, supply, valve, lines) in the report."""
        pf = sp.base.plant_file
        assert pf is not None
        v = pf.values
        shown = {"bore": ("bore [mm]", 1e3), "rod": ("rod [mm]", 1e3),
                 "stroke": ("stroke [mm]", 1e3), "mass": ("moving mass [kg]", 1.0),
                 "ps": ("supply [MPa abs]", 1e-6), "pt": ("return [MPa abs]", 1e-6),
                 "omega_v": ("spool bandwidth [rad/s]", 1.0),
                 "tau_v": ("spool lag [ms]", 1e3), "V10": ("line volume cap side [cm^3]", 1e6),
                 "V20": ("line volume rod side [cm^3]", 1e6),
                 "beta": ("bulk modulus [MPa]", 1e-6)}
        rows = [[label, f"{float(v[k]) * f:.4g}"] for k, (label, f) in shown.items() if k in v]
        rows.insert(4, ["orientation", str(pf.rig.get("orientation", v.get("orient", "")))])
        out.report.table(["value", sp.label], rows,
                         caption=f"The plant of the plant file {sp.source} ({pf.kind}, name "
                         f"`{pf.name}`), instead of the built-in plants.")

    @staticmethod
    def _plants_of(runs: list[dict[str, Any]], plants: list[StudyPlant] | None) -> list[str]:
        return [sp.label for sp in plants] if plants is not None else \
            list(dict.fromkeys(r["plant"] for r in runs))

    def _tracking_figures(self, out: StudyOutput, runs: list[dict[str, Any]],
                          plants: list[StudyPlant] | None = None) -> None:
        rep = out.report
        rep.section("Tracking")
        for p in self._plants_of(runs, plants):
            fig, axes = out.subplots(len(TASK_ORDER), 1, figsize=(9, 2.6 * len(TASK_ORDER)))
            axes = np.atleast_1d(axes)
            for ax, t in zip(axes, TASK_ORDER, strict=True):
                for c, s in self._signals(runs, p, t).items():
                    ax.plot(s["t"], (s["r"] - s["x"]) * 1e6, lw=0.9, label=c)
                _panel(ax, f"{p}: {t}", "r - x [um]")
            _finish(out, fig, axes, 5, f"tracking-{_slug(p)}", f"Tracking error of every controller "
                    f"on every task, {p} plant (true position).")

    def _friction_figures(self, out: StudyOutput, runs: list[dict[str, Any]],
                          plants: list[StudyPlant] | None = None) -> None:
        rep = out.report
        rep.section("Friction estimate against the true friction")
        rep.paragraph("The force each compensator fed forward beside the plant's true "
                      "friction force in the same run (`pid` feeds none). `pid-ff` uses the static map at the "
                      "reference velocity; the observer and the EKF estimate the bristle (and "
                      "film) state on line; the MPC uses the EKF estimate.")
        for p in self._plants_of(runs, plants):
            if not LOW_VELOCITY:
                continue
            fig, axes = out.subplots(len(LOW_VELOCITY), 1,
                                     figsize=(9, 2.75 * len(LOW_VELOCITY)))
            axes = np.atleast_1d(axes)
            for ax, t in zip(axes, LOW_VELOCITY, strict=True):
                for c, s in self._signals(runs, p, t).items():
                    if c == "pid":
                        continue
                    line = ax.plot(s["t"], s["F_hat"], lw=0.9, label=f"{c} estimate")[0]
                    ax.plot(s["t"], s["F_true"], "--", lw=0.8, color=line.get_color(),
                            label=f"{c} true")
                _panel(ax, f"{p}: {t}", "F [N]")
            _finish(out, fig, axes, 4, f"friction-{_slug(p)}",
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
                rows.append([p, c, r["median"] * 1e6,
                             f"{r['p10'] * 1e6:.1f}-{r['p90'] * 1e6:.1f}",
                             d["max_error"]["median"] * 1e6, k.get("median_ratio"),
                             "-" if not k else (f"{ci[0]:.2f}-{ci[1]:.2f}" if ci else "too few"),
                             k.get("verdict", "reference"),
                             f"{d['runs']}" + (f" ({d['failed']} failed)" if d["failed"] else "")])
        rep.table(["plant", "controller", "RMS [um]", "p10-p90 [um]", "max [um]", "RMS/pid",
                   "interval", "vs pid", "runs"], rows,
                  caption="Distribution of the metrics over the draws: the median RMS error, "
                  "its 10-90 % range, the median max error; RMS/pid: the median of the "
                  "per-draw ratio to pid, with its confidence interval.",
                  digits=[None, None, 1, None, 1, 2, None, None, None])
        fig, axes = out.subplots(1, len(robust), figsize=(10, 3.8))
        axes = np.atleast_1d(axes)
        for ax, (p, dist) in zip(axes, robust.items(), strict=True):
            shown = draw_distribution(ax, dist, CONTROLLER_ORDER, scale=1e6)  # plain ticks
            ax.set_title(p, fontsize=9)
            ax.set_ylabel("RMS error [um]")
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
            rows.append([k, v["median_of_medians"] * 1e6, _pair(v["p99"], v["max"], 2),
                         _pair(v["cpu_p99"], v["cpu_max"], 2), v["descheduled"],
                         f"{'yes' if ok else 'NO'} ({period * 1e3:g} ms)", v["fallbacks"]])
            if not ok:
                late.append(f"`{k}` {v['cpu_max'] * 1e3:.3g} ms > {period * 1e3:g} ms")
        rep.table(["controller", "median [us]", "p99 / max [ms]", "CPU p99 / max [ms]",
                   "descheduled", "real-time (period)", "fallbacks"], rows,
                  caption="Controller step time in the closed-loop runs above (whole step: "
                  "EKF + law/QP; this machine; wall clock unless CPU) against the sampling "
                  "period of the loop; real-time: the largest CPU time of a step within the "
                  "period.",
                  digits=[None, 0, None, None, 0, None, 0])
        if late:
            rep.note("Worst step's CPU time longer than the sampling period -- not real-time on "
                     "this machine: " + "; ".join(late) + ".", kind="bad")
        loops = [[f"{k}/{task}", d["median"] * 1e6, _pair(d["p99"], d["max"], 2),
                  d["cpu_median"] * 1e6, _pair(d["cpu_p99"], d["cpu_max"], 2),
                  d["descheduled"]]
                 for k, v in timing.items() if k.endswith("/mpc")
                 for task, d in v["loops"].items()]
        rep.table(["closed loop", "median [us]", "p99 / max [ms]", "CPU median [us]",
                   "CPU p99 / max [ms]", "descheduled"], loops,
                  caption="MPC step (EKF + QP) in every closed loop: wall clock and CPU time.",
                  digits=[None, 0, None, 0, None, 0])
        if not bench.get("available"):  # an optional package: one line, not a warning box
            rep.paragraph("The comparison with do-mpc, an optional package "
                          "(`pip install 'fcomp[bench]'`, `benchmarks/bench_mpc.py`), was not "
                          "run: it is not installed here.")
            return
        rows = [[name, d["median"] * 1e3, d["max"] * 1e3, d["steps"]]
                for name, d in bench["solvers"].items()]
        rep.table(["solver", "median [ms]", "max [ms]", "steps"], rows,
                  caption=f"MPC step on the hydraulic servo with NMLGM in the prediction model, "
                  f"horizon {bench['horizon']} steps of {bench['dt'] * 1e3:g} ms, same problem "
                  f"for both ({bench['note']}).", digits=[None, 3, 3, 0])
        rep.paragraph(f"Speed-up of fcomp's RTI over do-mpc: median "
                      f"{bench['speedup_median']:.1f}x, max {bench['speedup_max']:.1f}x.")


def _pair(a: float, b: float, digits: int) -> str:
    """Two times (s) as ``"a / b"`` in ms."""
    return f"{a * 1e3:.{digits}f} / {b * 1e3:.{digits}f}"


def settings_rows(plants: list[StudyPlant]) -> list[list[Any]]:
    """The controller settings of each plant as rows ``[setting (unit), value, ...]``, one
    column per plant; the valve command in the plant's own unit (A, or normalised)."""
    from plants import PLANTS as PLANT_KINDS

    cols = []
    for sp in plants:
        s, tu = sp.settings, control_model(sp.base).tuning
        unit = PLANT_KINDS.get(sp.base.plant).input_units[0]
        cols.append([
            f"{s.control_rate:g}",
            f"{s.u_max:g} A" if unit == "A" else f"{s.u_max:g} (normalised: full opening)"
            if unit == "-" else f"{s.u_max:g} {unit}",
            f"{s.du_max:g}", f"{tu.pid_bandwidth:.1f}", f"{tu.force_bandwidth:.0f}",
            f"{tu.margins.gain_db:.1f}", f"{tu.margins.phase:.0f}",
            f"{tu.observer_gain:.1f}", f"{tu.mpc_horizon(500.0):.0f}",
            f"{s.sensors.x_quantum * 1e6:.2f}", f"{s.sensors.x_noise * 1e6:.2f}",
            f"{s.sensors.p_quantum:.0f}", f"{s.sensors.p_noise:.0f}"])
    names = ["control rate [Hz]", "valve command limit u_max", "valve rate limit du_max "
             "[1/s]", "PID bandwidth [rad/s]", "force-loop bandwidth [rad/s]",
             "gain margin [dB]", "phase margin [deg]", "observer gain [1/s]",
             "MPC horizon [steps]", "position quantum [um]", "position noise [um]",
             "pressure quantum [Pa]", "pressure noise [Pa]"]
    return [[n, *(c[i] for c in cols)] for i, n in enumerate(names)]


def worse_than_pid(results: list[dict[str, Any]], plants: list[str],
                   controller: str = "pid-ff") -> list[str]:
    """A sentence per plant where ``controller`` tracks worse than plain PID (RMS error), with
    the reason the friction-estimate figure shows; empty where it does not."""
    out = []
    for p in plants:
        pid = {r["task"]: r["rms_error"] for r in results
               if r["plant"] == p and r["controller"] == "pid" and r["status"] == "ok"}
        worse = {r["task"]: r["rms_error"] / pid[r["task"]] for r in results
                 if r["plant"] == p and r["controller"] == controller and r["status"] == "ok"
                 and r["task"] in pid and r["rms_error"] > pid[r["task"]]}
        if not worse:
            continue
        lo, hi = min(worse.values()), max(worse.values())
        span = f"{lo:.1f}x" if len(worse) == 1 else f"{lo:.1f}-{hi:.1f}x"
        out.append(
            f"`{controller}` tracks worse than plain `pid` on the {p} plant: {span} its RMS "
            f"error on {len(worse)} of {len(pid)} tasks ({', '.join(sorted(worse))}). Not a "
            "fault of the run: the static feed-forward adds the friction of the reference "
            "velocity, the full break-away level as soon as the reference moves, while the "
            "piston is still in pre-sliding; where that force is a large share of the drive "
            "(a compressible plant) the piston jumps ahead of the reference and then moves "
            "against it, and the feed-forward pushes with the wrong sign (friction estimate "
            "against the true friction, below). Use an observer-based compensator there, or "
            "fade the feed-forward in with the measured velocity.")
    return out


def _panel(ax: Any, title: str, ylabel: str) -> None:
    ax.set_title(title, fontsize=9)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)


def _finish(out: StudyOutput, fig: Any, axes: Any, ncol: int, name: str, caption: str) -> None:
    legend_above(axes[0], ncol=ncol)
    axes[-1].set_xlabel("t [s]")
    out.figure(fig, name, caption)


STUDY = CompensatorsStudy()
main = STUDY.main

def _settings_dict(s: PlantSettings, tuning: Any) -> dict[str, Any]:
    """Controller settings as summary.json holds them (SI units): the plant's, and the
    tuning the controllers ran with (derived, or given explicitly)."""
    return {"control_rate": s.control_rate, "u_max": s.u_max, "du_max": s.du_max,
            "pid_bandwidth": tuning.pid_bandwidth, "force_bandwidth": tuning.force_bandwidth,
            "observer_gain": tuning.observer_gain,
            "tuning": tuning.as_dict(),
            "sensors": {k: getattr(s.sensors, k) for k in ("x_noise", "x_quantum", "p_noise",
                                                           "p_quantum")}}


__all__ = ["CONTROLLERS", "DEFAULT_FRICTION", "PLANTS", "STUDY", "CompensatorsStudy",
           "StudyPlant", "main", "study_plants"]
