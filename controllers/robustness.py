"""Monte Carlo robustness of the compensators: friction mismatch and sensor noise, run in parallel.

A sweep (:class:`Sweep`) draws ``samples`` plant/controller mismatches: for
each sample ``i`` every friction parameter the controller's model has is
multiplied by a factor ``exp(N(0, spread^2))`` (log-normal, median 1: the
controller's model is wrong by about ``spread`` in either direction), and the
sensor noise is scaled by a factor drawn uniformly from ``noise``. Every
controller is run on the *same* draws (common random numbers), so the
per-compensator distributions of the metrics compare like with like.

The closed-loop runs are independent jobs (:class:`Job`, picklable),
executed by :func:`run_jobs`

* on a local **process pool** (:class:`concurrent.futures.ProcessPoolExecutor`,
  ``workers`` processes, default the number of CPUs), or
* on a **Dask distributed** cluster when given a scheduler address
  (``tcp://host:8786``; ``distributed.Client(address).map``), e.g. a
  :class:`distributed.LocalCluster` or a cluster started with
  ``dask scheduler`` / ``dask worker`` on other machines.

How many draws: :func:`run_sequential` draws in batches and stops by a
:class:`StoppingRule` instead of a fixed count -- each compensator is run
until the confidence interval of its median effect (its metric divided by
the reference controller's on the same draw, ``pid``'s by default) excludes
1, i.e. until the draws show whether it helps or harms, or until the most
draws allowed (then reported as undecided). The interval is distribution-free
(order statistics of the paired ratios, binomial coverage; Conover,
*Practical Nonparametric Statistics*, 3rd ed., 1999, sec. 3.2), at the level
``1 - (1 - confidence)/looks`` for the ``looks`` the rule may take
(Bonferroni), so that stopping at the first decisive look keeps the stated
confidence.

A grid (:class:`Grid`) runs every combination of given mismatch factors and
of the friction models the controllers are built with instead (``fcomp
sweep --grid``). A run that fails (a plant integration that does not converge, a loop gone
unstable) is returned with ``status = "failed: ..."`` and no metrics: it is
counted, never dropped.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from controllers.harness import LoopConfig, control_model, friction_label, run_closed_loop
from controllers.plant_model import ControlModel
from controllers.tasks import Task
from controllers.tuning import Tuning
from fcomp.errors import FcompError, term
from fcomp.figstyle import plain_log_ticks
from fcomp.models import FrictionModel
from fcomp.parallel import run_tasks

#: Friction parameters perturbed by the sweep (those a model lacks are ignored).
MISMATCH_PARAMS: tuple[str, ...] = ("Fc", "Fs", "vs", "sigma0", "sigma1", "sigma2", "vb",
                                    "tau_hp", "tau_hn", "T")


@dataclass(frozen=True)
class Job:
    """One closed-loop run: controller, task (a name or a :class:`~controllers.tasks.Task`),
    configuration, options, and a label."""

    controller: str
    task: str | Task
    config: LoopConfig
    options: Mapping[str, Any] = field(default_factory=dict)
    sample: int = 0
    keep_signals: bool = False


def run_job(job: Job) -> dict[str, Any]:
    """Run one job; a dict with the metrics (or the failure) and the sample's draw."""
    out: dict[str, Any] = {
        "controller": job.controller,
        "task": job.task if isinstance(job.task, str) else job.task.name,
        "plant": job.config.plant,
        "sample": job.sample, "noise": job.config.noise, "mismatch": dict(job.config.mismatch),
        "friction": friction_label(job.config.friction),
        "controller_friction": friction_label(job.config.controller_friction),
    }
    try:
        res = run_closed_loop(job.controller, job.task, job.config, job.options)
    except (FcompError, ValueError, ArithmeticError) as exc:  # ConvergenceError included: an
        # unstable or failed run, or a controller model the factors made invalid (Fc > Fs)
        out.update(status=f"failed: {str(exc).splitlines()[0]}", metrics=None)
        return out
    out.update(status="ok", metrics=res.metrics.as_dict(), description=res.description)
    if job.keep_signals:
        out["signals"] = {k: getattr(res, k) for k in ("t", "r", "x", "u", "F_true", "F_hat")}
    return out


def run_jobs(jobs: Sequence[Job], *, workers: int | None = None, scheduler: str | None = None,
             progress: Callable[[int, int], None] | None = None) -> list[dict[str, Any]]:
    """Run ``jobs`` in parallel; results in the order of ``jobs``.

    Parameters
    ----------
    jobs
        The runs.
    workers
        Local processes (default: CPU count; 1 runs in this process).
    scheduler
        Address of a Dask distributed scheduler: run there instead.
    progress
        Called with ``(done, total)`` as results arrive.
    """
    return run_tasks(run_job, list(jobs), workers=workers, scheduler=scheduler,
                     progress=progress)


@dataclass(frozen=True)
class GivenTuning:
    """A tuning derived beforehand (:func:`with_tunings`), in the form
    :attr:`controllers.harness.LoopConfig.tuning` takes: the model's own derived tuning,
    carried by the job instead of derived again where the job runs."""

    tuning: Tuning

    def __call__(self, model: ControlModel) -> Tuning:
        return self.tuning


def derived_tuning(config: LoopConfig) -> Tuning | None:
    """The derived tuning of a configuration's controller model (``None`` if it cannot be
    derived: the run itself then fails and says why)."""
    try:
        return control_model(config).tuning
    except (FcompError, ValueError, ArithmeticError):
        return None


def with_tunings(jobs: Sequence[Job], *, workers: int | None = None,
                 scheduler: str | None = None) -> list[Job]:
    """``jobs``, each carrying the derived tuning of its configuration (:class:`GivenTuning`).

    Deriving a tuning takes seconds (:mod:`controllers.tuning`), and every controller on a
    configuration needs the same one: derived where each job runs, a pool's workers would
    each derive it again (a fast ``compensators`` study spent most of its time there). Here
    each distinct configuration's is derived once, in parallel (``workers``, ``scheduler``:
    as :func:`run_jobs`); the runs and their results are the same. Jobs with a tuning of
    their own keep it.
    """
    configs: list[LoopConfig] = []
    index: list[int | None] = []
    for job in jobs:
        if job.config.tuning is not None:
            index.append(None)
            continue
        k = next((i for i, c in enumerate(configs) if c == job.config), len(configs))
        if k == len(configs):
            configs.append(job.config)
        index.append(k)
    tunings = run_tasks(derived_tuning, configs, workers=workers, scheduler=scheduler)
    return [job if k is None or tunings[k] is None
            else replace(job, config=replace(job.config, tuning=GivenTuning(tunings[k])))
            for job, k in zip(jobs, index, strict=True)]


#: Most Monte Carlo draws a sweep or a comparison takes: each is one closed-loop run per
#: controller (and model), seconds each -- 1000 draws of five controllers on the fast ramp
#: are hours on two cores, and the interval of a median needs far fewer; 1e8 draws ran
#: unbounded, for years (issue 42 item 10).
MAX_SAMPLES = 1000


@dataclass(frozen=True)
class Sweep:
    """A Monte Carlo sweep (see the module docstring).

    Attributes
    ----------
    plant, task
        Plant and task names.
    controllers
        Controller names.
    samples
        Number of draws.
    spread
        Log-normal standard deviation of the mismatch factors.
    noise
        Range ``(lo, hi)`` of the sensor-noise factor.
    seed
        Seed of the draws.
    fast
        Fast task durations.
    base
        Configuration the draws modify (plant, friction models, tolerances).
    """

    plant: str = "hydraulic"
    task: str = "low-velocity-ramp"
    controllers: tuple[str, ...] = ("pid", "pid-ff", "lugre-observer", "ekf", "mpc")
    samples: int = 20
    spread: float = 0.3
    noise: tuple[float, float] = (0.5, 3.0)
    seed: int = 2026
    fast: bool = True
    base: LoopConfig = field(default_factory=LoopConfig)

    def __post_init__(self) -> None:
        if not (isinstance(self.samples, int) and self.samples >= 1):
            raise FcompError(f"robustness sweep: {term('samples')} must be a positive integer, "
                             f"got {self.samples!r}")
        if self.samples > MAX_SAMPLES:
            raise FcompError(f"robustness sweep: {term('samples')} {self.samples}: at most "
                             f"{MAX_SAMPLES} draws (each one closed-loop run per controller)")
        if not (math.isfinite(self.spread) and self.spread >= 0):
            raise FcompError(f"robustness sweep: {term('spread')} must be >= 0, got {self.spread}")
        lo, hi = self.noise
        if not (0 <= lo <= hi and math.isfinite(hi)):
            raise FcompError(f"robustness sweep: {term('noise')} range must be 0 <= lo <= hi, "
                             f"got {self.noise}")

    def draws(self) -> list[tuple[dict[str, float], float]]:
        """``(mismatch factors, noise factor)`` of every sample (reproducible).

        The draws lie within the controller model's constraints: a draw that makes its
        friction invalid (a static level below the Coulomb level, ``Fc > Fs``; a value
        beyond its bound) is drawn again -- the log-normal truncated to the valid models,
        not a failed run counted against the controllers.
        """
        from controllers.harness import _friction
        from controllers.plant_model import friction_with_mismatch

        model = _friction(self.base.controller_friction, self.base)
        rng = np.random.default_rng(self.seed)
        out = []
        for _ in range(self.samples):
            for _try in range(1000):
                f = np.exp(self.spread * rng.standard_normal(len(MISMATCH_PARAMS)))
                noise = float(rng.uniform(*self.noise))
                factors = {k: float(v) for k, v in zip(MISMATCH_PARAMS, f, strict=True)}
                try:
                    friction_with_mismatch(model, factors)
                except (FcompError, ValueError):
                    continue
                out.append((factors, noise))
                break
            else:
                raise FcompError(f"robustness sweep: no valid draw of {model.describe()} in "
                                 "1000 tries; lower the spread")
        return out

    def jobs(self, samples: range | None = None,
             controllers: Sequence[str] | None = None) -> list[Job]:
        """One job per (sample, controller): every sample and controller, or those given
        (sample ``i`` is the same draw whichever others are run)."""
        draws = self.draws()
        out = []
        for i in samples if samples is not None else range(self.samples):
            mismatch, noise = draws[i]
            cfg = replace(self.base, plant=self.plant, mismatch=mismatch, noise=noise,
                          seed=self.seed + i, fast=self.fast)
            for c in controllers if controllers is not None else self.controllers:
                out.append(Job(c, self.task, cfg, sample=i))
        return out


@dataclass(frozen=True)
class Grid:
    """A parameter grid: every combination of mismatch factors and controller friction models.

    Attributes
    ----------
    plant, task, controllers
        As for :class:`Sweep`.
    factors
        Friction parameter -> the factors on the controller model's value to try
        (:data:`MISMATCH_PARAMS`); every combination is a grid point.
    controller_frictions
        The friction models the controllers are built with (friction-model
        mismatch: the plant keeps ``base.friction``).
    noise, seed, fast, base
        Sensor-noise factor, seed of the sensor noise, fast task durations, the
        configuration the points modify.
    """

    plant: str = "hydraulic"
    task: str = "low-velocity-ramp"
    controllers: tuple[str, ...] = ("pid", "pid-ff", "lugre-observer", "ekf", "mpc")
    factors: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    controller_frictions: tuple[str | FrictionModel, ...] = ()
    noise: float = 1.0
    seed: int = 2026
    fast: bool = True
    base: LoopConfig = field(default_factory=LoopConfig)

    def __post_init__(self) -> None:
        for k, vals in self.factors.items():
            if k not in MISMATCH_PARAMS:
                raise FcompError(f"{term('grid')}: {k!r} is not a friction parameter the "
                                 "controllers' "
                                 f"model is perturbed in ({', '.join(MISMATCH_PARAMS)})")
            if not vals or any(not (math.isfinite(v) and v > 0) for v in vals):
                raise FcompError(f"{term('grid')} {k}: factors must be positive numbers, got "
                                 f"{list(vals)}")
        if not self.factors and not self.controller_frictions:
            raise FcompError("grid: give mismatch factors or controller friction models")

    def points(self) -> list[tuple[dict[str, float], str | FrictionModel]]:
        """``(mismatch factors, controller friction)`` of every grid point, in order."""
        import itertools

        names = list(self.factors)
        combos = list(itertools.product(*(self.factors[n] for n in names))) or [()]
        frictions = self.controller_frictions or (self.base.controller_friction,)
        return [({**dict(self.base.mismatch), **dict(zip(names, c, strict=True))}, f)
                for f in frictions for c in combos]

    def jobs(self) -> list[Job]:
        """One job per (grid point, controller)."""
        out: list[Job] = []
        for i, (mismatch, friction) in enumerate(self.points()):
            cfg = replace(self.base, plant=self.plant, mismatch=mismatch, noise=self.noise,
                          seed=self.seed, fast=self.fast, controller_friction=friction)
            out.extend(Job(c, self.task, cfg, sample=i) for c in self.controllers)
        return out


def median_interval(values: Sequence[float] | np.ndarray, confidence: float
                    ) -> tuple[float, float] | None:
    """Distribution-free confidence interval of the median of ``values``.

    The order statistics ``(x_(k), x_(n+1-k))`` with the largest ``k`` whose
    coverage ``P(k <= B <= n - k)``, ``B ~ Binomial(n, 1/2)``, is at least
    ``confidence`` (exact for any continuous distribution); ``None`` when even
    the extremes do not reach it (fewer than 6 values at 95 %).
    """
    from scipy.stats import binom

    v = np.sort(np.asarray(values, dtype=float))
    n = v.size
    best = 0
    for k in range(1, n // 2 + 1):
        if binom.cdf(n - k, n, 0.5) - binom.cdf(k - 1, n, 0.5) >= confidence:
            best = k
    return (float(v[best - 1]), float(v[n - best])) if best else None


def paired_ratios(results: Sequence[Mapping[str, Any]], reference: str,
                  metric: str = "rms_error") -> dict[str, np.ndarray]:
    """Per controller, its ``metric`` divided by ``reference``'s on the same draw (the draws
    where both ran and neither failed)."""
    ref = {r["sample"]: float(r["metrics"][metric]) for r in results
           if r["controller"] == reference and r["status"] == "ok"}
    out: dict[str, list[float]] = {}
    for r in results:
        c = r["controller"]
        if c == reference:
            continue
        out.setdefault(c, [])
        if r["status"] == "ok" and r["sample"] in ref and ref[r["sample"]] > 0:
            out[c].append(float(r["metrics"][metric]) / ref[r["sample"]])
    return {c: np.asarray(v) for c, v in out.items()}


@dataclass(frozen=True)
class StoppingRule:
    """When a Monte Carlo sweep has drawn enough (module docstring, "How many draws").

    Attributes
    ----------
    confidence
        Overall confidence of the decisions (each look uses ``1 - (1 - confidence)/looks``).
    min_draws, max_draws, batch
        Draws before the first look, the most draws, draws added per look.
    reference
        The controller the others are compared with (run as long as any is undecided).
    metric
        The metric compared (a key of :class:`controllers.metrics.Metrics`).
    """

    confidence: float = 0.95
    min_draws: int = 8
    max_draws: int = 20
    batch: int = 4
    reference: str = "pid"
    metric: str = "rms_error"

    def __post_init__(self) -> None:
        if not 0 < self.confidence < 1:
            raise FcompError(f"stopping rule: confidence must lie in (0, 1), "
                             f"got {self.confidence}")
        if not 1 <= self.min_draws <= self.max_draws or self.batch < 1:
            raise FcompError("stopping rule: need 1 <= min_draws <= max_draws and batch >= 1")

    @property
    def looks(self) -> int:
        """How many times the rule may look at the draws."""
        return 1 + math.ceil((self.max_draws - self.min_draws) / self.batch)

    @property
    def level(self) -> float:
        """Confidence level of each look's intervals (Bonferroni over :attr:`looks`)."""
        return 1.0 - (1.0 - self.confidence) / self.looks

    def decisions(self, results: Sequence[Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
        """Per compared controller: paired draws, median ratio, its interval, ``decided``
        (the interval excludes 1) and ``verdict`` (``better``, ``worse``, ``undecided``)."""
        out: dict[str, dict[str, Any]] = {}
        for c, ratios in paired_ratios(results, self.reference, self.metric).items():
            ci = median_interval(ratios, self.level)
            decided = ci is not None and (ci[1] < 1.0 or ci[0] > 1.0)
            verdict = "undecided" if not decided or ci is None else (
                "better" if ci[1] < 1.0 else "worse")
            out[c] = {"paired_draws": int(ratios.size),
                      "median_ratio": float(np.median(ratios)) if ratios.size else math.nan,
                      "interval": list(ci) if ci is not None else None,
                      "level": self.level, "decided": decided, "verdict": verdict}
        return out


def run_sequential(sweeps: Mapping[str, Sweep], rule: StoppingRule,
                   run: Callable[[list[Job]], list[dict[str, Any]]]
                   ) -> dict[str, dict[str, Any]]:
    """Run every sweep in batches of draws until ``rule`` is met (module docstring).

    Each look runs the next batch of draws of every undecided controller (and
    of the reference) of every sweep in one call of ``run`` (a list of jobs ->
    their results, e.g. :func:`run_jobs` on a pool). A sweep's ``samples`` is
    ignored; it draws at most ``rule.max_draws``.

    Returns, per sweep key: ``results`` (every run), ``draws`` (how many were
    drawn), ``decisions`` (:meth:`StoppingRule.decisions`) and ``stopped``
    (``decided`` or ``max-draws``).
    """
    state: dict[str, dict[str, Any]] = {}
    for key, sw in sweeps.items():
        if rule.reference not in sw.controllers:
            raise FcompError(f"stopping rule: the reference controller {rule.reference!r} is "
                             f"not in the sweep ({', '.join(sw.controllers)})")
        state[key] = {"sweep": replace(sw, samples=rule.max_draws), "results": [],
                      "draws": 0, "open": list(sw.controllers)}
    while True:
        batch: list[Job] = []
        parts: list[tuple[dict[str, Any], int, int]] = []  # whose jobs are batch[a:b]
        for st in state.values():
            if not st["open"]:
                continue
            stop = min(rule.max_draws, st["draws"] + (rule.batch if st["draws"]
                                                      else rule.min_draws))
            jobs = st["sweep"].jobs(range(st["draws"], stop), st["open"])
            parts.append((st, len(batch), len(batch) + len(jobs)))
            batch += jobs
            st["draws"] = stop
        if not batch:
            break
        results = run(batch)
        for st, a, b in parts:
            st["results"] += results[a:b]
            dec = rule.decisions(st["results"])
            undecided = [c for c in st["open"] if c != rule.reference
                         and not dec.get(c, {}).get("decided", False)]
            st["open"] = ([rule.reference, *undecided]
                          if undecided and st["draws"] < rule.max_draws else [])
    out = {}
    for key, st in state.items():
        dec = rule.decisions(st["results"])
        out[key] = {"results": st["results"], "draws": st["draws"], "decisions": dec,
                    "stopped": "decided" if all(d["decided"] for d in dec.values())
                    else "max-draws"}
    return out


def distributions(results: Sequence[Mapping[str, Any]],
                  metrics: Sequence[str] = ("rms_error", "max_error", "steady_state_error")
                  ) -> dict[str, dict[str, Any]]:
    """Per-controller distribution of each metric: values, median, 10/90 % quantiles, failures."""
    out: dict[str, dict[str, Any]] = {}
    for r in results:
        d = out.setdefault(r["controller"], {"runs": 0, "failed": 0,
                                             **{m: [] for m in metrics}})
        d["runs"] += 1
        if r["status"] != "ok":
            d["failed"] += 1
            continue
        for m in metrics:
            d[m].append(float(r["metrics"][m]))
    for d in out.values():
        for m in metrics:
            vals = np.asarray(d[m], dtype=float)
            d[m] = {
                "values": vals.tolist(),
                "median": float(np.median(vals)) if vals.size else math.nan,
                "p10": float(np.quantile(vals, 0.1)) if vals.size else math.nan,
                "p90": float(np.quantile(vals, 0.9)) if vals.size else math.nan,
            }
    return out


#: Fewest draws a box plot (quartiles, 10-90 % whiskers) is drawn from; fewer: the points.
MIN_BOX_DRAWS = 20


def draw_distribution(ax: Any, dist: Mapping[str, Any], order: Sequence[str],
                      metric: str = "rms_error", scale: float = 1.0) -> str:
    """Draw each controller's ``metric`` over the draws on ``ax`` (log scale): box plots when
    every controller has at least :data:`MIN_BOX_DRAWS` values, else every value as a point
    (a box of three draws would invent quartiles). Returns ``"box"`` or ``"points"``."""
    names = [c for c in order if c in dist and dist[c][metric]["values"]]
    values = [np.asarray(dist[c][metric]["values"]) * scale for c in names]
    pos = np.arange(1, len(names) + 1)
    box = bool(values) and min(v.size for v in values) >= MIN_BOX_DRAWS
    if box:
        ax.boxplot(values, positions=pos, whis=(10, 90), showfliers=True)
    else:
        rng = np.random.default_rng(0)  # a fixed jitter: the figure is reproducible
        for x, v in zip(pos, values, strict=True):
            ax.plot(x + rng.uniform(-0.12, 0.12, v.size), v, "o", ms=4, alpha=0.75,
                    color="#2356a8")
            if v.size:
                ax.plot([x - 0.25, x + 0.25], [np.median(v)] * 2, "-", color="0.2", lw=1.2)
    ax.set_xticks(pos, names, rotation=30 if len(names) > 4 else 0,
                  ha="right" if len(names) > 4 else "center")
    ax.set_xlim(0.4, len(names) + 0.6)
    ax.set_yscale("log")
    ax.grid(alpha=0.3)
    plain_log_ticks(ax)
    return "box" if box else "points"


__all__ = ["MAX_SAMPLES", "MIN_BOX_DRAWS", "MISMATCH_PARAMS", "Grid", "Job", "StoppingRule", "Sweep",
           "distributions", "draw_distribution", "median_interval", "paired_ratios", "run_job",
           "run_jobs", "run_sequential"]
