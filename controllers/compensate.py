"""What a better friction model buys in closed loop: every compensator built on each model.

:func:`compensate` runs, on one plant (a plant file or a built-in plant)
whose simulated friction is the *true* model, every controller built once
with each of the given friction models (e.g. a baseline fit and the model a
diagnosis found), on the standard tasks (:mod:`controllers.tasks`) or on a
user's reference (``t, x_ref`` samples), and reports

* ``runs``: per controller, model and task the errors of
  :mod:`controllers.metrics` (RMS, max, reversal, hunting, steady state), on
  the true position;
* ``ratios``: per controller and task, each model's errors divided by those
  of the first model (the baseline): below 1 the model helps;
* ``robustness``: a short Monte Carlo on one task (:data:`ROBUSTNESS_TASK`,
  or the task or reference given): in every draw the *true* plant differs
  from the identified one -- every parameter of the true friction and the
  moving mass times a factor uniform in ``1 +- spread`` (the seal warmer,
  worn or new; a heavier or lighter load) -- and every controller with every
  model runs on the same draws (common random numbers, the machinery of
  :mod:`controllers.robustness`); per controller the distribution of the RMS
  error per model and of its ratio to the baseline on the same draw.

The controllers' friction models are used as given (no mismatch factors:
the model *is* the identification being judged); their tuning is the
plant's (:class:`~controllers.plant_model.ControlModel`). The runs are
independent jobs (:func:`controllers.robustness.run_jobs`: local processes or
a Dask cluster). A run that fails (a loop gone unstable, an integration that
does not converge) is reported with its status and no errors, never dropped;
ratios involving it are ``None``.

Example
-------
>>> res = compensate("axis50.toml", "true.json", ["base.json", "diag.json"],
...                  controllers=("pid-ff", "mpc"), fast=True)          # doctest: +SKIP
>>> res.ratios["mpc"]["steps"]["diag"]["rms_error"]                     # doctest: +SKIP
0.19
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from controllers.harness import LoopConfig
from controllers.robustness import Job, distributions, median_interval, paired_ratios, run_jobs
from controllers.tasks import TASKS, Task, check_fits_stroke, reference_task
from fcomp.errors import FcompError
from fcomp.models import FrictionModel

#: The controllers run by default.
DEFAULT_CONTROLLERS: tuple[str, ...] = ("pid", "pid-ff", "lugre-observer", "ekf", "mpc")
#: Task of the robustness draws when no task or reference is given: position steps in
#: both directions (break-away, hunting), short runs.
ROBUSTNESS_TASK = "steps"
#: Errors of a run (keys of a run's entry; ``hunting`` is the hunting amplitude).
ERRORS: tuple[str, ...] = ("rms_error", "max_error", "reversal_error", "hunting",
                           "steady_state_error")
#: Errors whose ratios are reported.
RATIO_ERRORS: tuple[str, ...] = ("rms_error", "max_error", "reversal_error", "hunting")
#: Confidence of the interval of the median robustness ratio.
CONFIDENCE = 0.9


@dataclass
class CompensateResult:
    """The result of :func:`compensate` (SI units: errors in m).

    Attributes
    ----------
    plant
        The plant's name and kind (``{"name", "kind", "label"}``).
    friction
        Description of the true friction.
    models
        Model label -> description, in order (the first is the baseline).
    controllers, tasks
        What ran.
    fast
        Fast task durations.
    runs
        One entry per controller, model and task: ``controller``, ``model``,
        ``task``, ``status``, the :data:`ERRORS`, ``valve_activity``,
        ``fallbacks``.
    ratios
        ``ratios[controller][task][model][error]``: the model's error over the
        baseline's (``None`` where a run failed or the baseline's error is 0).
    robustness
        The Monte Carlo (module docstring): ``task``, ``samples``, ``spread``,
        ``seed``, ``draws`` and, per controller, ``rms_error`` per model and
        ``ratio`` per model (``median``, ``p10``, ``p90``, ``better`` -- the
        share of draws where the model beats the baseline --, ``interval``).
    warnings
        ``{"code", "parameter", "message"}`` of what was dropped or is doubtful.
    signals
        ``(controller, model, task) -> {"t", "r", "x", "u", "F_true", "F_hat"}`` of
        the nominal runs (not in :meth:`as_dict`; for figures).
    """

    plant: dict[str, str]
    friction: str
    models: dict[str, str]
    controllers: tuple[str, ...]
    tasks: tuple[str, ...]
    fast: bool
    runs: list[dict[str, Any]]
    ratios: dict[str, Any]
    robustness: dict[str, Any]
    warnings: list[dict[str, Any]] = field(default_factory=list)
    signals: dict[tuple[str, str, str], dict[str, np.ndarray]] = field(default_factory=dict,
                                                                      repr=False)

    @property
    def baseline(self) -> str:
        """The first model's label."""
        return next(iter(self.models))

    def as_dict(self) -> dict[str, Any]:
        """Every number as JSON-ready data (no signals)."""
        return {"plant": dict(self.plant), "friction": self.friction,
                "models": dict(self.models), "baseline": self.baseline,
                "controllers": list(self.controllers), "tasks": list(self.tasks),
                "fast": self.fast, "units": {"errors": "m"}, "runs": self.runs,
                "ratios": self.ratios, "robustness": self.robustness,
                "warnings": list(self.warnings)}


# ------------------------------------------------------------------ inputs
#: Longest user reference (s): every closed-loop run simulates all of it at the control
#: rate (an hour is 3.6 million steps at 1 kHz, per controller, model and draw).
MAX_REFERENCE_S = 3600.0


def resolve_plant(plant: Any) -> Any:
    """A :class:`~plants.planfile.PlantFile`: itself, a plant file read (a path), or the
    built-in plant of a kind (``hydraulic``, ``pneumatic``)."""
    from plants.planfile import KINDS, PlantFile, builtin_plant_file, read_plant_file

    if isinstance(plant, PlantFile):
        return plant
    text = str(plant)
    if isinstance(plant, str) and plant in KINDS:
        return builtin_plant_file(plant)
    if not text.lower().endswith(".toml"):
        raise FcompError(f"plant {text!r}: give a plant file (.toml) or a built-in plant "
                         f"({', '.join(KINDS)})")
    return read_plant_file(plant)


def resolve_friction(spec: Any, plant_file: Any, use: str,
                     warnings: list[dict[str, Any]] | None = None,
                     effects: str | None = None) -> FrictionModel:
    """A friction model: itself, a model file read (its measurement terms dropped, with a
    warning appended to ``warnings``), or a registered name with the values of the
    built-in plant of the plant file's kind."""
    from fcomp.modelfile import is_model_file, seal_friction
    from fcomp.models import make_model

    if isinstance(spec, FrictionModel):
        return spec
    if is_model_file(spec):
        model, dropped = seal_friction(spec, use, effects)
        if dropped and warnings is not None:
            _warn(warnings, "measurement-terms", dropped, str(spec))
        return model
    return make_model(str(spec), params=plant_file.friction_set)


def model_label(spec: Any) -> str:
    """How results name a model: a file's stem, a registered model's name."""
    if isinstance(spec, FrictionModel):
        return spec.describe()
    return Path(str(spec)).stem if str(spec).lower().endswith(".json") else str(spec)


def read_reference(path: str | Path, stroke: float | None = None) -> Task:
    """A user's reference file as a task (:func:`controllers.tasks.reference_task`).

    The file is a CSV with the columns ``t`` (s) and ``x_ref`` (m, absolute
    position; other columns ignored): times finite and strictly increasing,
    at least two samples over at least 0.1 s, positions finite and, given the
    ``stroke`` (m), inside it with the 5 mm margins of every task.

    Raises
    ------
    FcompError
        One line naming the file and the first bad row.
    """
    from fcomp.textdata import (
        check_path,
        data_rows,
        first_bad,
        header_names,
        parse_rows,
        read_text,
    )

    label = str(path)
    p = check_path(path, "reference file")
    text = read_text(p, label, what="a reference (CSV)")
    names, start = header_names(label, text)
    for col in ("t", "x_ref"):
        if col not in names:
            raise FcompError(f"{label}: a reference needs the columns t and x_ref (s, m); "
                             f"the header has {', '.join(names)}")
    table = parse_rows(label, data_rows(text, start), ",", names, what="a reference")
    t = table.data[:, names.index("t")]
    x = table.data[:, names.index("x_ref")]
    for col, values in (("t", t), ("x_ref", x)):
        bad = first_bad(values)
        if bad is not None:
            raise FcompError(f"{label}: row {table.lines[bad]}, column {col}: not a finite "
                             "number")
    if t.size < 2:
        raise FcompError(f"{label}: a reference needs at least two samples")
    steps = np.diff(t)
    if np.any(steps <= 0):
        bad = int(np.argmax(steps <= 0)) + 1
        raise FcompError(f"{label}: row {table.lines[bad]}: time {t[bad]:g} s does not "
                         f"follow {t[bad - 1]:g} s (times must increase)")
    if t[-1] - t[0] < 0.1:
        raise FcompError(f"{label}: the reference lasts {t[-1] - t[0]:g} s; give at least "
                         "0.1 s")
    if t[-1] - t[0] > MAX_REFERENCE_S:  # every run simulates all of it, at the control rate
        raise FcompError(f"{label}: the reference lasts {t[-1] - t[0]:.4g} s, longer than the "
                         f"{MAX_REFERENCE_S:g} s a closed-loop run takes (each run simulates "
                         "every controller step of it); give a shorter stretch (is column t "
                         "in seconds?)")
    task = reference_task(t, x, name=p.stem)
    if stroke is not None:
        lo, hi = 0.005, stroke - 0.005
        out = np.flatnonzero((x < lo) | (x > hi))
        if out.size:
            i = int(out[0])
            raise FcompError(f"{label}: row {table.lines[i]}: x_ref = {x[i]:g} m is outside "
                             f"the stroke 0..{stroke:g} m less 5 mm margins")
        check_fits_stroke(task, task.start_position(stroke), stroke)
    return task


# ------------------------------------------------------------------ the run
@dataclass(frozen=True)
class _Slot:
    """What a job is: nominal (``sample = None``) or a draw, its model and task labels."""

    kind: str
    controller: str
    model: str
    task: str
    sample: int | None = None


def draws(true_friction: FrictionModel, samples: int, spread: float, seed: int
          ) -> list[dict[str, float]]:
    """The robustness draws: per draw, a factor uniform in ``1 +- spread`` on every
    parameter of the true friction (flat names; those of value 0 or not finite are kept)
    and on the moving mass ``mass``. A draw that makes the friction model invalid (a
    static level below the Coulomb level, a bound crossed) is drawn again."""
    from controllers.plant_model import friction_with_mismatch

    flat = true_friction.flat_params()
    names = [k for k, v in flat.items() if math.isfinite(v) and v != 0.0]
    rng = np.random.default_rng(seed)
    out: list[dict[str, float]] = []
    while len(out) < samples:
        for _ in range(1000):
            f = rng.uniform(1.0 - spread, 1.0 + spread, len(names) + 1)
            factors = {k: float(v) for k, v in zip(names, f[:-1], strict=True)}
            try:
                friction_with_mismatch(true_friction, factors)
            except (FcompError, ValueError):
                continue
            out.append({**factors, "mass": float(f[-1])})
            break
        else:
            raise FcompError("robustness: no valid draw of the true friction in 1000 tries; "
                             "lower the spread")
    return out


def default_samples(fast: bool) -> int:
    """Robustness draws when not given: 8, or 4 with the fast tasks."""
    return 4 if fast else 8


def compensate(plant: Any, true_friction: Any, models: Sequence[Any] | Mapping[str, Any], *,
               controllers: Sequence[str] = DEFAULT_CONTROLLERS, task: str | None = None,
               reference: str | Path | Task | None = None, fast: bool = False,
               samples: int | None = None, spread: float = 0.2, seed: int = 2026,
               workers: int | None = None, scheduler: str | None = None,
               progress: Callable[[int, int], None] | None = None,
               keep_signals: bool = False, effects: str | None = None) -> CompensateResult:
    """Every controller built with each friction model, in closed loop on the plant with the
    true friction (module docstring).

    Parameters
    ----------
    plant
        A plant file (path or :class:`~plants.planfile.PlantFile`) or a built-in plant
        (``hydraulic``, ``pneumatic``).
    true_friction
        The plant's simulated friction: a model file, a model, or a registered name
        (the values of the built-in plant of the plant's kind).
    models
        The controllers' friction models, the first the baseline: model files (named by
        their stems), registered names, or a mapping label -> model (or file).
    controllers
        Controllers to run (default :data:`DEFAULT_CONTROLLERS`).
    task
        One standard task (default: all of :data:`controllers.tasks.TASKS`).
    reference
        A user's reference instead (a CSV file, :func:`read_reference`, or a task).
    fast
        Fast durations of the standard tasks (a reference keeps its own).
    samples
        Robustness draws (default 8, 4 with ``fast``; 0: none).
    spread
        Half width of the uniform factors of the draws (0.2: +-20 %).
    seed
        Seed of the draws and of the sensor noise.
    workers, scheduler
        Local processes, or the Dask scheduler's address
        (:func:`controllers.robustness.run_jobs`).
    progress
        Called with ``(done, total)`` as runs finish.
    keep_signals
        Keep the nominal runs' signals (:attr:`CompensateResult.signals`).
    effects
        The user's effects module (``--effects``) the model files may name.

    Raises
    ------
    FcompError
        Bad input (unknown controller or task, a missing or bad file, a task and a
        reference together, fewer than two models, two models of one name).
    """
    from controllers import CONTROLLERS

    warns: list[dict[str, Any]] = []
    if task is not None and reference is not None:
        raise FcompError("give a task or a reference, not both")
    controllers = tuple(controllers)
    if not controllers:
        raise FcompError("give at least one controller")
    for c in controllers:
        CONTROLLERS.get(c)
    if task is not None:
        TASKS.get(task)
    samples = default_samples(fast) if samples is None else samples
    if not (isinstance(samples, int) and samples >= 0):
        raise FcompError(f"samples must be a whole number >= 0, got {samples!r}")
    if not (math.isfinite(spread) and 0 <= spread < 1):
        raise FcompError(f"spread must lie in [0, 1), got {spread}")
    pf = resolve_plant(plant)
    stroke = float(pf.values["stroke"])
    ref_task: Task | None = None
    if isinstance(reference, Task):
        ref_task = reference
        check_fits_stroke(ref_task, ref_task.start_position(stroke), stroke, fast)
    elif reference is not None:
        ref_task = read_reference(reference, stroke)
    true = resolve_friction(true_friction, pf, "plant friction", warns, effects)
    items = list(models.items()) if isinstance(models, Mapping) else [
        (model_label(m), m) for m in models]
    if len(items) < 2:
        raise FcompError("give at least two models: a baseline and one to compare with it")
    labels = [k for k, _ in items]
    for i, k in enumerate(labels):
        if k in labels[:i]:
            raise FcompError(f"two models are named {k!r} (model files are named by their "
                             "stems): rename one")
    built = {k: resolve_friction(m, pf, "controller friction", warns, effects)
             for k, m in items}
    tasks: list[str | Task] = ([ref_task] if ref_task is not None
                               else [task] if task is not None else list(TASKS.names()))
    task_names = tuple(t if isinstance(t, str) else t.name for t in tasks)
    mc_task: str | Task = ref_task if ref_task is not None else task or ROBUSTNESS_TASK
    mc_name = mc_task if isinstance(mc_task, str) else mc_task.name

    nominal = LoopConfig(plant_file=pf, friction=true, mismatch={}, noise=1.0, seed=seed,
                         fast=fast)
    jobs: list[Job] = []
    slots: list[_Slot] = []
    for tk, name in zip(tasks, task_names, strict=True):
        for c in controllers:
            for label, model in built.items():
                cfg = LoopConfig(**{**_fields(nominal), "controller_friction": model})
                jobs.append(Job(c, tk, cfg, keep_signals=keep_signals))
                slots.append(_Slot("nominal", c, label, name))
    drawn = draws(true, samples, spread, seed) if samples else []
    for i, factors in enumerate(drawn):
        for c in controllers:
            for label, model in built.items():
                cfg = LoopConfig(**{**_fields(nominal), "controller_friction": model,
                                    "plant_factors": factors, "seed": seed + 1 + i})
                jobs.append(Job(c, mc_task, cfg, sample=i))
                slots.append(_Slot("draw", c, label, mc_name, i))
    results = run_jobs(jobs, workers=workers, scheduler=scheduler, progress=progress)

    runs: list[dict[str, Any]] = []
    signals: dict[tuple[str, str, str], dict[str, np.ndarray]] = {}
    mc: list[dict[str, Any]] = []
    for slot, res in zip(slots, results, strict=True):
        if slot.kind == "nominal":
            runs.append(_run_entry(slot, res))
            if keep_signals and "signals" in res:
                signals[(slot.controller, slot.model, slot.task)] = res["signals"]
        else:
            mc.append({**res, "model": slot.model})
    for r in runs:
        if r["status"] != "ok":
            _warn(warns, "run-failed", f"{r['controller']} with model {r['model']} on "
                  f"{r['task']}: {r['status']}", r["controller"])
    return CompensateResult(
        plant={"name": pf.name, "kind": pf.kind, "label": pf.label},
        friction=true.describe(), models={k: m.describe() for k, m in built.items()},
        controllers=controllers, tasks=task_names, fast=fast, runs=runs,
        ratios=ratios(runs, labels), warnings=warns, signals=signals,
        robustness=robustness(mc, controllers, labels, mc_name, drawn, spread, seed))


def _fields(config: LoopConfig) -> dict[str, Any]:
    return {k: getattr(config, k) for k in config.__dataclass_fields__}


def _warn(warns: list[dict[str, Any]], code: str, message: str, parameter: str | None) -> None:
    item = {"code": code, "parameter": parameter, "message": " ".join(message.split())}
    if item not in warns:
        warns.append(item)


def _run_entry(slot: _Slot, res: Mapping[str, Any]) -> dict[str, Any]:
    m = res.get("metrics") or {}
    errors = {e: m.get("hunting_amplitude" if e == "hunting" else e) for e in ERRORS}
    return {"controller": slot.controller, "model": slot.model, "task": slot.task,
            "status": res["status"], **errors,
            "valve_activity": m.get("valve_activity"), "fallbacks": m.get("fallbacks")}


def _finite(d: Mapping[str, Any]) -> dict[str, Any]:
    """``d`` with NaN numbers (no run succeeded) as ``None``."""
    return {k: None if isinstance(v, float) and not math.isfinite(v) else v
            for k, v in d.items()}


def ratio(value: float | None, base: float | None) -> float | None:
    """``value / base``, or ``None`` when either is missing or the base is not positive."""
    if value is None or base is None or not base > 0:
        return None
    return float(value) / float(base)


def ratios(runs: Sequence[Mapping[str, Any]], models: Sequence[str]) -> dict[str, Any]:
    """``[controller][task][model][error]``: each model's error over the first model's, on
    the same controller and task (:data:`RATIO_ERRORS`)."""
    by = {(r["controller"], r["task"], r["model"]): r for r in runs}
    out: dict[str, Any] = {}
    for (c, t, m), r in by.items():
        if m == models[0]:
            continue
        base = by.get((c, t, models[0]))
        out.setdefault(c, {}).setdefault(t, {})[m] = {
            e: ratio(r[e], base[e] if base else None) for e in RATIO_ERRORS}
    return out


def robustness(results: Sequence[Mapping[str, Any]], controllers: Sequence[str],
               models: Sequence[str], task: str, drawn: Sequence[Mapping[str, float]],
               spread: float, seed: int) -> dict[str, Any]:
    """The Monte Carlo's summary (module docstring) from the draws' runs (each with its
    ``model`` label)."""
    per: dict[str, Any] = {}
    for c in controllers:
        mine = [{**r, "controller": r["model"]} for r in results if r["controller"] == c]
        dist = distributions(mine, ("rms_error",))
        entry: dict[str, Any] = {"rms_error": {m: {**_finite(dist[m]["rms_error"]),
                                                    "runs": dist[m]["runs"],
                                                    "failed": dist[m]["failed"]}
                                                for m in models if m in dist},
                                 "ratio": {}}
        for m, values in paired_ratios(mine, models[0]).items():
            ci = median_interval(values, CONFIDENCE) if values.size else None
            entry["ratio"][m] = {
                "values": values.tolist(), "paired_draws": int(values.size),
                "median": float(np.median(values)) if values.size else None,
                "p10": float(np.quantile(values, 0.1)) if values.size else None,
                "p90": float(np.quantile(values, 0.9)) if values.size else None,
                "better": float(np.mean(values < 1.0)) if values.size else None,
                "interval": list(ci) if ci is not None else None,
                "confidence": CONFIDENCE}
        per[c] = entry
    return {"task": task, "samples": len(drawn), "spread": spread, "seed": seed,
            "draws": [dict(d) for d in drawn], "controllers": per}


# ------------------------------------------------------------------ figures and report
def figure_tracking(result: CompensateResult, task: str) -> Any:
    """Tracking error ``r - x`` (um) over time on ``task``, one panel per controller, every
    model's run overlaid (the nominal runs; needs ``keep_signals``)."""
    from fcomp import figstyle as fs

    shown = [c for c in result.controllers
             if any((c, m, task) in result.signals for m in result.models)]
    fig, axes2 = fs.new_figure(height=1.4 + 1.6 * max(len(shown), 1), nrows=max(len(shown), 1),
                               squeeze=False, sharex=True)
    axes = axes2[:, 0]
    for ax, c in zip(axes, shown, strict=False):
        for i, m in enumerate(result.models):
            sig = result.signals.get((c, m, task))
            if sig is None:
                continue
            fs.plot_gapped(ax, sig["t"], (sig["r"] - sig["x"]) * 1e6, lw=1.0, color=f"C{i}",
                           label=f"{m} ({result.models[m]})")
        ax.set_ylabel(f"{c}\nerror (\u00b5m)")
        ax.axhline(0.0, color="0.6", lw=0.5)
        ax.grid(alpha=0.3)
    fs.legend_above(axes[0], ncol=2)
    axes[-1].set_xlabel("time (s)")
    return fig


def figure_ratios(result: CompensateResult, error: str = "rms_error") -> Any:
    """Bar chart of the ratios of ``error`` (log scale): per controller, one bar per task
    and compared model, drawn from 1 (the baseline) down in green where the model beats the
    baseline, up in red where it does worse; tasks and models told apart by hatching."""
    from matplotlib.patches import Patch

    from fcomp import figstyle as fs

    fig, ax = fs.new_figure(height=3.6, width=fs.HALF_WIDTH + 1.6)
    others = [m for m in result.models if m != result.baseline]
    groups = [(t, m) for t in result.tasks for m in others]
    width = 0.8 / max(len(groups), 1)
    x = np.arange(len(result.controllers))
    hatches = ["", "//", "..", "xx", "\\\\", "++", "oo"]
    shown: list[float] = []
    handles = []
    for j, (t, m) in enumerate(groups):
        vals = [((result.ratios.get(c, {}).get(t, {}).get(m) or {}).get(error)) for c in
                result.controllers]
        ratio = np.array([np.nan if v is None else float(v) for v in vals])
        ok = np.isfinite(ratio) & (ratio > 0)
        colours = [fs.COLORS["good"] if r < 1.0 else fs.COLORS["bad"] for r in ratio[ok]]
        hatch = hatches[j % len(hatches)]
        ax.bar((x - 0.4 + (j + 0.5) * width)[ok], ratio[ok] - 1.0, width, bottom=1.0,
               color=colours, hatch=hatch, edgecolor="white", linewidth=0.5)
        shown += list(ratio[ok])
        handles.append(Patch(facecolor="0.75", hatch=hatch, edgecolor="white",
                             label=f"{m} on {t}" if len(others) > 1 else t))
    handles += [Patch(color=fs.COLORS["good"], label="better than the baseline"),
                Patch(color=fs.COLORS["bad"], label="worse")]
    ax.axhline(1.0, color="0.2", lw=1.0)
    ax.set_yscale("log")
    reach = max([1.25, *(max(r, 1.0 / r) for r in shown)]) * 1.15
    ax.set_ylim(1.0 / reach, reach)
    fs.plain_log_ticks(ax)
    ax.set_xticks(x, list(result.controllers))
    ax.set_xlim(-0.6, len(result.controllers) - 0.4)
    ax.set_ylabel(f"{error.replace('_', ' ')} / baseline's")
    ax.grid(alpha=0.3, axis="y")
    fs.legend_above(ax, handles=handles)
    return fig


def figure_robustness(result: CompensateResult) -> Any:
    """The robustness draws: per controller, each compared model's RMS-error ratio to the
    baseline on the same draw (:func:`controllers.robustness.draw_distribution`)."""
    from controllers.robustness import draw_distribution
    from fcomp import figstyle as fs

    fig, ax = fs.new_figure(height=3.4, width=fs.HALF_WIDTH + 1.6)
    per = result.robustness["controllers"]
    others = [m for m in result.models if m != result.baseline]
    dist = {f"{c}: {m}" if len(others) > 1 else c: {"ratio": {"values":
            per[c]["ratio"].get(m, {}).get("values", [])}} for c in result.controllers
            for m in others}
    draw_distribution(ax, dist, list(dist), metric="ratio")
    ax.axhline(1.0, color="0.2", lw=1.0)
    lo, hi = ax.get_ylim()
    reach = max(1.25, hi, 1.0 / lo)
    ax.set_ylim(1.0 / reach, reach)
    fs.plain_log_ticks(ax)
    ax.set_ylabel("RMS error / baseline's (same draw)")
    return fig


def report(result: CompensateResult, command: str | None = None) -> Any:
    """The result as a :class:`~fcomp.report.Report` (figures, ratios, runs, draws)."""
    from fcomp.report import Report

    others = [m for m in result.models if m != result.baseline]
    rep = Report(f"Compensation on {result.plant['name']}: what the friction model buys",
                 subtitle=f"{len(result.controllers)} controllers x {len(result.models)} "
                 f"models x {len(result.tasks)} task(s); true friction {result.friction}",
                 command=command,
                 config={"plant": result.plant["label"], "true friction": result.friction,
                         **{f"model {k}": v for k, v in result.models.items()},
                         "tasks": ", ".join(result.tasks), "fast": result.fast})
    from controllers.conclusions import of_compensation

    rep.conclusion(of_compensation(result.as_dict()))
    for w in result.warnings:
        rep.note(w["message"], kind="warn")
    rep.section("Ratios to the baseline")
    rep.paragraph(f"Each model's error divided by the baseline's (`{result.baseline}`) for "
                  "the same controller and task; below 1 the model helps.")
    rep.figure(figure_ratios(result), "RMS tracking-error ratio per controller and task "
               "(log scale).")
    rows = [[c, t, m, *[(result.ratios.get(c, {}).get(t, {}).get(m) or {}).get(e)
                        for e in RATIO_ERRORS]]
            for c in result.controllers for t in result.tasks for m in others]
    rep.table(["controller", "task", "model", *RATIO_ERRORS], rows,
              digits=[None, None, None, 3, 3, 3, 3])
    if result.signals:
        rep.section("Tracking errors")
        for t in result.tasks:
            rep.figure(figure_tracking(result, t), f"Tracking error on {t}, every model.")
    rep.section("Robustness")
    rob = result.robustness
    if rob["samples"]:
        rep.paragraph(f"{rob['samples']} draws on `{rob['task']}`: every parameter of the "
                      f"true friction and the moving mass times a factor uniform in "
                      f"1 +- {rob['spread']:g}; every controller and model on the same draws.")
        rep.figure(figure_robustness(result), "RMS-error ratio to the baseline on every "
                   "draw (line: median).")
        rep.table(["controller", "model", "median ratio", "p10", "p90", "draws better",
                   "paired draws"],
                  [[c, m, r.get("median"), r.get("p10"), r.get("p90"), r.get("better"),
                    r.get("paired_draws")]
                   for c in result.controllers
                   for m, r in rob["controllers"][c]["ratio"].items()],
                  digits=[None, None, 3, 3, 3, 2, 0])
    else:
        rep.paragraph("No robustness draws (samples 0).")
    rep.section("Runs")
    rep.table(["controller", "model", "task", "status", "RMS (µm)", "max (µm)",
               "reversal (µm)", "hunting (µm)"],
              [[r["controller"], r["model"], r["task"], r["status"],
                *[None if r[e] is None else r[e] * 1e6 for e in RATIO_ERRORS]]
               for r in result.runs], digits=[None, None, None, None, 3, 3, 3, 3])
    return rep


__all__ = ["CONFIDENCE", "DEFAULT_CONTROLLERS", "ERRORS", "RATIO_ERRORS", "ROBUSTNESS_TASK",
           "CompensateResult", "compensate", "default_samples", "draws", "figure_ratios",
           "figure_robustness", "figure_tracking", "model_label", "ratio", "ratios",
           "read_reference", "report", "resolve_friction", "resolve_plant",
           "robustness"]
