"""What a better friction model buys in closed loop -- under every friction the plant may have.

:func:`compensate` builds every controller once with each of the given
friction models (e.g. a baseline fit and the model a diagnosis found) and runs
them on one plant (a plant file or a built-in plant), on the standard tasks
(:mod:`controllers.tasks`) or on a user's reference (``t, x_ref`` samples).

**Which friction the plant runs.** Run on the diagnosed model, the
compensators built on the diagnosed model are exact and win by construction:
the comparison is circular. So, unless one true friction is given, the plant
runs each of several **candidate truths** (:mod:`controllers.truths`): the
compared models themselves, draws from each model's own uncertainty (its
file's standard errors), the rivals its diagnosis found, and truths the user
names. Every run says which friction the plant ran (``truth``). A true
friction that is one of the compared models -- given, or among the
candidates -- is said in the warnings (``truth-is-compared``), and a
recommendation is made only where it holds under every candidate truth.

Reported:

* ``runs``: per truth, controller, model and task the errors of
  :mod:`controllers.metrics` (RMS, max, reversal, hunting, steady state) on the
  true position, and the run's ``status``: ``ok`` (ranked); ``skipped: ...`` (a
  controller that cannot be built on that model, known before any run: a LuGre
  observer on a static map); ``failed: ...``; ``flagged: ...`` (a run that did
  not do the task -- never moved, saturated throughout, a limit cycle, a failed
  solver, :mod:`controllers.run_checks`): reported, never ranked;
* ``ratios[truth][controller][task][model][error]``: the model's error over
  the baseline's (the first model's) under the same truth, ``None`` where either
  run is not ranked; below 1 the model helps;
* ``across_truths[controller][model]``: the median-task ratio under each truth
  and whether the model is better under every one (``holds``);
* ``robustness``: a short Monte Carlo on one task (:data:`ROBUSTNESS_TASK`, or
  the task or reference given): draw ``i`` runs truth ``i mod n`` with every
  fitted parameter of it and the moving mass times a factor uniform in
  ``1 +- spread`` (the seal warmer, worn or new; a heavier load); every
  controller with every model on the same draws (common random numbers,
  :mod:`controllers.robustness`); per controller the distribution of each
  model's RMS error and of its ratio to the baseline on the same draw.

The controllers' friction models are used as given (no mismatch factors:
the model *is* the identification being judged); their tuning is the plant's
(:class:`~controllers.plant_model.ControlModel`: one PID per truth, whatever
model a controller is built on). A controller whose law uses no friction model
(``pid``) runs once per truth and task. The runs are independent jobs
(:func:`controllers.robustness.run_jobs`: local processes or a Dask cluster).

Example
-------
>>> res = compensate("axis50.toml", None, ["base.json", "diag.json"],
...                  controllers=("pid-ff", "mpc"), fast=True)          # doctest: +SKIP
>>> res.across["mpc"]["diag"]["holds"]                                   # doctest: +SKIP
'better'
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from statistics import median
from typing import Any

import numpy as np

from controllers.compensate_inputs import (
    model_label,
    read_reference,
    resolve_compared,
    resolve_friction,
    resolve_plant,
    warn_once,
)
from controllers.harness import LoopConfig
from controllers.robustness import (
    MAX_SAMPLES,
    Job,
    distributions,
    median_interval,
    paired_ratios,
    run_jobs,
)
from controllers.run_checks import run_status
from controllers.tasks import TASKS, Task, check_fits_stroke
from controllers.truths import Truth, candidate_truths, same_friction
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
#: A ratio this close to 1 is no difference (the same run to rounding).
SAME = 1e-9
#: The most uncertainty draws per compared model (each a truth every run is repeated on).
MAX_TRUTH_DRAWS = 50
#: Run facts copied from the metrics into a run's entry (besides the errors).
FACTS: tuple[str, ...] = ("valve_activity", "fallbacks", "travel", "reference_travel",
                          "saturated_share")


@dataclass
class CompensateResult:
    """The result of :func:`compensate` (SI units: errors in m).

    Attributes
    ----------
    plant
        The plant's name and kind (``{"name", "kind", "label"}``).
    friction
        The plant's friction in words: the true friction given, or the candidate truths.
    mode
        ``given`` (one true friction) or ``candidates`` (module docstring).
    truths
        Truth label -> :meth:`~controllers.truths.Truth.as_dict`, in order.
    models
        Model label -> description, in order (the first is the baseline).
    controllers, tasks
        What ran.
    uses_friction
        Controller -> whether its law uses the friction model.
    fast
        Fast task durations.
    runs
        One entry per truth, controller, model and task: ``truth``, ``controller``,
        ``model``, ``task``, ``status``, the :data:`ERRORS` and the :data:`FACTS`.
    ratios
        ``ratios[truth][controller][task][model][error]`` (module docstring).
    across
        ``across[controller][model]``: ``per_truth`` (truth -> median-task RMS ratio or
        ``None``), ``better_under``, ``worse_under``, ``ranked_truths``, ``truths``,
        ``best``, ``worst`` and ``holds`` (``better``, ``worse``, ``same``, ``partly
        ranked``, ``mixed``, ``not ranked``).
    robustness
        The Monte Carlo (module docstring): ``task``, ``samples``, ``spread``, ``seed``,
        ``draws`` (each with its ``truth``) and, per controller, ``rms_error`` per model
        and ``ratio`` per model (``median``, ``p10``, ``p90``, ``better`` -- the share
        of draws where the model beats the baseline --, ``interval``).
    warnings
        ``{"code", "parameter", "message"}`` of what was dropped or is doubtful.
    signals
        ``(truth, controller, model, task) -> {"t", "r", "x", "u", "F_true", "F_hat"}`` of
        the nominal runs (not in :meth:`as_dict`; for figures).
    """

    plant: dict[str, str]
    friction: str
    mode: str
    truths: dict[str, dict[str, Any]]
    models: dict[str, str]
    controllers: tuple[str, ...]
    tasks: tuple[str, ...]
    uses_friction: dict[str, bool]
    fast: bool
    runs: list[dict[str, Any]]
    ratios: dict[str, Any]
    across: dict[str, Any]
    robustness: dict[str, Any]
    warnings: list[dict[str, Any]] = field(default_factory=list)
    signals: dict[tuple[str, str, str, str], dict[str, np.ndarray]] = field(
        default_factory=dict, repr=False)

    @property
    def baseline(self) -> str:
        """The first model's label."""
        return next(iter(self.models))

    def as_dict(self) -> dict[str, Any]:
        """Every number as JSON-ready data (no signals)."""
        return {"plant": dict(self.plant), "friction": self.friction, "mode": self.mode,
                "truths": self.truths, "models": dict(self.models),
                "baseline": self.baseline, "controllers": list(self.controllers),
                "uses_friction": dict(self.uses_friction), "tasks": list(self.tasks),
                "fast": self.fast, "units": {"errors": "m"}, "runs": self.runs,
                "ratios": self.ratios, "across_truths": self.across,
                "robustness": self.robustness, "warnings": list(self.warnings)}


# ------------------------------------------------------------------ the run
@dataclass(frozen=True)
class _Slot:
    """What a run is: nominal (``sample = None``) or a draw; truth, controller, model and
    task labels; the job it reads (``None``: skipped, ``why`` says why)."""

    truth: str
    controller: str
    model: str
    task: str
    job: int | None
    why: str = ""
    sample: int | None = None


def draws(true_friction: FrictionModel, samples: int, spread: float, seed: int
          ) -> list[dict[str, float]]:
    """The robustness draws of one truth: per draw, a factor uniform in ``1 +- spread`` on
    every fitted parameter of the true friction (:func:`controllers.truths.varied_names`:
    not the numerical thresholds and fixed reference values) and on the moving mass
    ``mass``. A draw that makes the friction model invalid (a static level below the
    Coulomb level, a bound crossed) is drawn again."""
    from controllers.plant_model import friction_with_mismatch
    from controllers.truths import varied_names

    names = varied_names(true_friction)
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


def default_truth_draws(fast: bool) -> int:
    """Uncertainty draws per compared model when not given: 4, or 2 with the fast tasks."""
    return 2 if fast else 4


def check_count(value: Any, name: str, most: int) -> int:
    """A whole number of draws in ``0..most`` (one line otherwise)."""
    if not (isinstance(value, int) and not isinstance(value, bool) and value >= 0):
        raise FcompError(f"{name} must be a whole number >= 0, got {value!r}")
    if value > most:
        raise FcompError(f"{name} {value}: at most {most} (each draw runs every controller "
                         "with every model; the interval of a median needs far fewer)")
    return value


def compensate(plant: Any, true_friction: Any, models: Sequence[Any] | Mapping[str, Any], *,
               controllers: Sequence[str] = DEFAULT_CONTROLLERS, task: str | None = None,
               reference: str | Path | Task | None = None, fast: bool = False,
               samples: int | None = None, spread: float = 0.2, seed: int = 2026,
               truth_draws: int | None = None, truths: Sequence[Any] = (),
               workers: int | None = None, scheduler: str | None = None,
               progress: Callable[[int, int], None] | None = None,
               keep_signals: bool = False, effects: str | None = None) -> CompensateResult:
    """Every controller built with each friction model, in closed loop on the plant under
    each candidate truth or the one true friction given (module docstring).

    Parameters
    ----------
    plant
        A plant file (path or :class:`~plants.planfile.PlantFile`) or a built-in plant
        (``hydraulic``, ``pneumatic``).
    true_friction
        The plant's simulated friction -- a model file, a model, or a registered name
        (the values of the built-in plant of the plant's kind) --, or ``None``: the
        candidate truths (:func:`controllers.truths.candidate_truths`).
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
        Robustness draws (default 8, 4 with ``fast``; 0: none; at most
        :data:`MAX_SAMPLES`).
    spread
        Half width of the uniform factors of the draws (0.2: +-20 %).
    seed
        Seed of the draws (truths and robustness) and of the sensor noise.
    truth_draws
        Candidate truths drawn from each compared model's standard errors (default 4, 2
        with ``fast``; at most :data:`MAX_TRUTH_DRAWS`); not with ``true_friction``.
    truths
        More candidate truths (model files, names or models); not with ``true_friction``.
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
        reference together, fewer than two models, two models of one name, too many
        draws), a comparison that cannot be made (no controller that uses a friction
        model, every pair refused), a plant that cannot hold its load, a tuning without
        margins.
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
    samples = check_count(default_samples(fast) if samples is None else samples, "samples",
                          MAX_SAMPLES)
    given = true_friction is not None
    if given and (truth_draws or truths):
        raise FcompError("a true friction given is the plant's one truth: no candidate truths "
                         "(truth draws, named truths) with it")
    truth_draws = check_count(default_truth_draws(fast) if truth_draws is None
                              else truth_draws, "truth draws", MAX_TRUTH_DRAWS)
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
    items = list(models.items()) if isinstance(models, Mapping) else [
        (model_label(m), m) for m in models]
    if len(items) < 2:
        raise FcompError("give at least two models: a baseline and one to compare with it")
    labels = [k for k, _ in items]
    for i, k in enumerate(labels):
        if k in labels[:i]:
            raise FcompError(f"two models are named {k!r} (model files are named by their "
                             "stems): rename one")
    if given:
        truth_model = resolve_friction(true_friction, pf, "plant friction", warns, effects)
    compared = {k: resolve_compared(m, pf, warns, effects) for k, m in items}
    built = {k: c.model for k, c in compared.items()}
    if given:
        eq = next((k for k, m in built.items() if same_friction(truth_model, m)), None)
        cast = [Truth(model_label(true_friction), truth_model, "given",
                      f"the true friction given ({true_friction if isinstance(true_friction, str) else truth_model.describe()})",
                      eq)]
    else:
        named = {model_label(t): resolve_friction(t, pf, "plant friction", warns, effects)
                 for t in truths}
        not_drawn: list[str] = []
        cast = candidate_truths(compared, truth_draws, seed, named, not_drawn)
        for why in not_drawn:
            warn_once(warns, "truth-left-out", f"uncertainty draws left out: {why}", None)
    _say_circular(warns, cast, given)
    tasks: list[str | Task] = ([ref_task] if ref_task is not None
                               else [task] if task is not None else list(TASKS.names()))
    task_names = tuple(t if isinstance(t, str) else t.name for t in tasks)
    mc_task: str | Task = ref_task if ref_task is not None else task or ROBUSTNESS_TASK
    mc_name = mc_task if isinstance(mc_task, str) else mc_task.name
    classes = {c: CONTROLLERS.get(c) for c in controllers}
    refused = {(c, k): classes[c].refuses(m) for c in controllers for k, m in built.items()}
    _check_comparable(controllers, classes, refused, labels)
    free_force = _check_plant(pf, cast, built, refused, controllers, fast)
    if not given:
        cast = _plausible(warns, cast, free_force, stroke)
    _range_warnings(warns, pf, cast, built, tasks, fast, free_force)

    jobs: list[Job] = []
    slots: list[_Slot] = []

    def plan(truth: Truth, tk: str | Task, name: str, c: str, sample: int | None,
             factors: Mapping[str, float] | None) -> None:
        shared: int | None = None
        for label, model in built.items():
            why = refused[(c, label)]
            if why is not None:
                slots.append(_Slot(truth.label, c, label, name, None, f"skipped: {why}",
                                   sample))
                continue
            if shared is None or classes[c].uses_friction:
                cfg = LoopConfig(plant_file=pf, friction=truth.model, mismatch={}, noise=1.0,
                                 seed=seed if sample is None else seed + 1 + sample,
                                 fast=fast, controller_friction=model,
                                 plant_factors=dict(factors or {}))
                jobs.append(Job(c, tk, cfg, keep_signals=keep_signals and sample is None,
                                sample=sample or 0))
                shared = len(jobs) - 1
            slots.append(_Slot(truth.label, c, label, name, shared, sample=sample))

    for truth in cast:
        for tk, name in zip(tasks, task_names, strict=True):
            for c in controllers:
                plan(truth, tk, name, c, None, None)
    drawn: list[dict[str, Any]] = []
    for i in range(samples):
        truth = cast[i % len(cast)]
        factors = draws(truth.model, 1, spread, seed + 7919 * i)[0]
        drawn.append({"truth": truth.label, **factors})
        for c in controllers:
            plan(truth, mc_task, mc_name, c, i, factors)
    results = run_jobs(_with_tunings(jobs, workers, scheduler), workers=workers,
                       scheduler=scheduler, progress=progress)

    runs: list[dict[str, Any]] = []
    signals: dict[tuple[str, str, str, str], dict[str, np.ndarray]] = {}
    mc: list[dict[str, Any]] = []
    for slot in slots:
        res: Mapping[str, Any] = (results[slot.job] if slot.job is not None
                                  else {"status": slot.why, "metrics": None})
        entry = _run_entry(slot, res)
        if slot.sample is None:
            runs.append(entry)
            if keep_signals and "signals" in res:
                signals[(slot.truth, slot.controller, slot.model, slot.task)] = res["signals"]
        else:
            mc.append({"controller": slot.controller, "model": slot.model,
                       "sample": slot.sample, "status": entry["status"],
                       "metrics": res.get("metrics")})
    per_truth = {t.label: ratios([r for r in runs if r["truth"] == t.label], labels)
                 for t in cast}
    blind = {c: not classes[c].uses_friction for c in controllers}
    return CompensateResult(
        plant={"name": pf.name, "kind": pf.kind, "label": pf.label},
        friction=(cast[0].model.describe() if given else
                  f"candidate truths: {', '.join(t.label for t in cast)}"),
        mode="given" if given else "candidates",
        truths={t.label: t.as_dict() for t in cast},
        models={k: m.describe() for k, m in built.items()},
        controllers=controllers, tasks=task_names,
        uses_friction={c: not b for c, b in blind.items()}, fast=fast, runs=runs,
        ratios=per_truth, across=across_truths(per_truth, controllers, labels, task_names),
        warnings=warns, signals=signals,
        robustness=robustness(mc, controllers, labels, mc_name, drawn, spread, seed))


def _say_circular(warns: list[dict[str, Any]], cast: Sequence[Truth], given: bool) -> None:
    """The warning that a true friction is one of the compared models (contract)."""
    same = [t for t in cast if t.equals is not None]
    if not same:
        return
    if given:
        t = same[0]
        warn_once(warns, "truth-is-compared",
              f"the plant's true friction {t.label} is the compared model {t.equals}: the "
              f"controllers built on {t.equals} are exact here and win by construction -- "
              "a circular comparison that says how well each model tracks if "
              f"{t.equals} were right, not which model is; leave out the true friction "
              "(--friction) to compare under every candidate truth", t.equals)
        return
    warn_once(warns, "truth-is-compared",
          f"the candidate truths include the compared models themselves "
          f"({', '.join(str(t.equals) for t in same)}): under its own truth a model wins by "
          "construction, so a model is recommended only where it wins under every "
          "candidate truth", None)


def _plausible(warns: list[dict[str, Any]], cast: Sequence[Truth], free: float,
               stroke: float) -> list[Truth]:
    """The candidate truths a plant can move: a draw or a rival whose steady friction at mid
    stroke reaches the whole force ``free`` (N) the actuator has left after holding its
    load (a draw of values its record does not determine: ``Fs`` +- 4e6 N) is left out
    with a warning; the compared models are kept (warned later if they come near)."""
    from controllers.model_range import SPEEDS, steady_level

    out = []
    for t in cast:
        level = (steady_level(t.model, np.array([0.5 * stroke]), np.array(SPEEDS), 0.0)
                 if t.origin in ("uncertainty", "rival") else 0.0)
        if level >= free:
            warn_once(warns, "truth-left-out",
                      f"candidate truth {t.label} ({t.note}) left out: its friction reaches "
                      f"{level:.4g} N, beyond the {free:.4g} N the actuator has left after "
                      "holding its load (values the record does not determine)", t.label)
            continue
        out.append(t)
    return out


def _check_comparable(controllers: Sequence[str], classes: Mapping[str, Any],
                      refused: Mapping[tuple[str, str], str | None],
                      labels: Sequence[str]) -> None:
    """Refuse a comparison that cannot compare (one line): no controller that uses a
    friction model, or none that can be built on two of the models."""
    users = [c for c in controllers if classes[c].uses_friction]
    if not users:
        raise FcompError(f"controllers {', '.join(controllers)}: none uses a friction model, "
                         "so the models cannot make a difference; add pid-ff, "
                         "lugre-observer, ekf or mpc (--controllers)")
    if not any(sum(refused[(c, k)] is None for k in labels) >= 2 for c in users):
        reasons = sorted({str(v) for v in refused.values() if v is not None})
        raise FcompError("no controller can be built on two of the models: "
                         + "; ".join(reasons))


def _check_plant(pf: Any, cast: Sequence[Truth], built: Mapping[str, FrictionModel],
                 refused: Mapping[tuple[str, str], str | None], controllers: Sequence[str],
                 fast: bool) -> float:
    """Refuse, before any run, a plant that cannot hold its load and a tuning without
    margins (one line each); the force (N) the actuator has left after holding the load."""
    from controllers.harness import control_model

    label = next(k for k in built if any(refused[(c, k)] is None for c in controllers))
    cfg = LoopConfig(plant_file=pf, friction=cast[0].model, mismatch={}, fast=fast,
                     controller_friction=built[label])
    model = control_model(cfg)
    lo, hi, w = model.force_min, model.force_max, model.weight
    if not lo < w < hi:
        raise FcompError(f"{pf.label}: the load's weight {w:.4g} N is outside the force "
                         f"range {lo:.4g}..{hi:.4g} N the supply gives the piston: the plant "
                         "cannot hold its load; raise [supply] ps, or lower [rig] mass")
    _ = model.tuning  # a tuning without margins: refused here (one line), not in every run
    return float(min(hi - w, w - lo))


def _range_warnings(warns: list[dict[str, Any]], pf: Any, cast: Sequence[Truth],
                    built: Mapping[str, FrictionModel], tasks: Sequence[str | Task],
                    fast: bool, free_force: float) -> None:
    """Models run outside their fitted position window; true frictions the plant can hardly
    move (:func:`controllers.model_range.range_warnings`)."""
    from controllers.model_range import range_warnings, task_span

    span = task_span(pf, tasks, fast)
    for truth in cast:
        for code, msg in range_warnings(truth.label, truth.model, span, truth=True,
                                        free_force=free_force):
            warn_once(warns, code, msg, truth.label)
    for k, m in built.items():
        if not any(truth.label == k for truth in cast):
            for code, msg in range_warnings(k, m, span, truth=False):
                warn_once(warns, code, msg, k)


def _with_tunings(jobs: Sequence[Job], workers: int | None, scheduler: str | None
                  ) -> list[Job]:
    """``jobs`` carrying their derived tunings, each derived once per (truth, model) --
    a robustness draw's plant factors do not change the controller's model
    (:func:`controllers.robustness.with_tunings`)."""
    from controllers.robustness import GivenTuning, derived_tuning
    from fcomp.parallel import run_tasks

    def key(job: Job) -> LoopConfig:
        return replace(job.config, plant_factors={}, seed=0)

    configs: list[LoopConfig] = []
    for job in jobs:
        if key(job) not in configs:
            configs.append(key(job))
    tunings = run_tasks(derived_tuning, configs, workers=workers, scheduler=scheduler)
    out = []
    for job in jobs:
        tu = tunings[configs.index(key(job))]
        out.append(job if tu is None else
                   replace(job, config=replace(job.config, tuning=GivenTuning(tu))))
    return out


def _run_entry(slot: _Slot, res: Mapping[str, Any]) -> dict[str, Any]:
    m = res.get("metrics") or {}
    errors = {e: m.get("hunting_amplitude" if e == "hunting" else e) for e in ERRORS}
    return {"truth": slot.truth, "controller": slot.controller, "model": slot.model,
            "task": slot.task, "status": run_status(res["status"], res.get("metrics")),
            **errors, **{k: m.get(k) for k in FACTS}}


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
    """``[controller][task][model][error]`` of one truth's runs: each model's error over the
    first model's, on the same controller and task (:data:`RATIO_ERRORS`); ``None`` where
    either run is not ranked (a status other than ``ok``)."""
    by = {(r["controller"], r["task"], r["model"]): r for r in runs}
    out: dict[str, Any] = {}
    for (c, t, m), r in by.items():
        if m == models[0]:
            continue
        base = by.get((c, t, models[0]))
        ok = base is not None and base["status"] == "ok" and r["status"] == "ok"
        out.setdefault(c, {}).setdefault(t, {})[m] = {
            e: ratio(r[e], base[e]) if ok and base is not None else None
            for e in RATIO_ERRORS}
    return out


def across_truths(per_truth: Mapping[str, Any], controllers: Sequence[str],
                  models: Sequence[str], tasks: Sequence[str]) -> dict[str, Any]:
    """Per controller and compared model, the median-task RMS ratio under each truth and
    whether the model is better (``holds = "better"``), worse or the same (``"same"``, a
    ratio of 1 to :data:`SAME`) under every truth -- its runs ranked under all of them --;
    ``"partly ranked"`` where the ranked truths agree but some truth ranked none of its
    runs; ``"mixed"`` where the truths disagree (module docstring)."""
    out: dict[str, Any] = {}
    for c in controllers:
        for m in models[1:]:
            per: dict[str, float | None] = {}
            for truth, rat in per_truth.items():
                vals = [v for t in tasks if (v := ((rat.get(c, {}).get(t, {}).get(m) or {})
                                                   .get("rms_error"))) is not None]
                per[truth] = float(median(vals)) if vals else None
            ranked = [v for v in per.values() if v is not None]
            better = sum(v < 1.0 - SAME for v in ranked)
            worse = sum(v > 1.0 + SAME for v in ranked)
            same = len(ranked) - better - worse
            holds = ("not ranked" if not ranked else
                     "mixed" if better and (worse or same) or worse and same else
                     "partly ranked" if len(ranked) < len(per) else
                     "better" if better else "worse" if worse else "same")
            out.setdefault(c, {})[m] = {
                "per_truth": per, "better_under": better, "worse_under": worse,
                "ranked_truths": len(ranked), "truths": len(per),
                "best": min(ranked) if ranked else None,
                "worst": max(ranked) if ranked else None, "holds": holds}
    return out


def robustness(results: Sequence[Mapping[str, Any]], controllers: Sequence[str],
               models: Sequence[str], task: str, drawn: Sequence[Mapping[str, Any]],
               spread: float, seed: int) -> dict[str, Any]:
    """The Monte Carlo's summary (module docstring) from the draws' runs (each with its
    ``model`` label); a run not ranked (failed, skipped, flagged) is counted, not paired."""
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


__all__ = ["CONFIDENCE", "DEFAULT_CONTROLLERS", "ERRORS", "MAX_SAMPLES", "MAX_TRUTH_DRAWS",
           "RATIO_ERRORS", "ROBUSTNESS_TASK", "CompensateResult", "across_truths",
           "compensate", "default_samples", "default_truth_draws", "draws", "model_label",
           "ratio", "ratios", "read_reference", "resolve_compared", "resolve_friction",
           "resolve_plant", "robustness"]
