"""One parameter vector fitted to the masked samples of several records: the fitting engine's core.

A fit adjusts the flat parameters ``theta`` (model names, plus the extras
``mass``, ``offset`` and ``lag``) to minimise

    sum over records r, over its masked samples k:  w_rk*(y_rk - F_hat_rk(theta))^2,

where ``F_hat_r`` is the model simulated from rest along record ``r``'s
measured motion (:class:`~fcomp.identification.dynamic.TrajectoryProblem`:
the gradient strategy the model's capabilities allow), ``y_r`` its target
(:class:`~fcomp.identification.target.FitData`) and ``w_rk`` the weight of
the sample (1 by default). Residuals and Jacobians of the records, scaled by
``sqrt(w_rk)``, are stacked (:class:`RecordsProblem`) and handed to the
bounded trust-region solve of :func:`~fcomp.identification.problem.solve`.
A record may carry extras held at known values (:meth:`Record.holding`: the
target carries the held term) and may be averaged over blocks of samples
(:meth:`Record.averaged`) to fit a long record on a shorter copy.

:func:`fit_records` is the entry point for several records: given the
parameter list, the starts, the bounds and the scales, it probes the starts
(:func:`best_start`: short solves, raced by successive halving), continues
from the best, optionally in two stages (shape exponents held first), and
returns the values reached and the solution.
:class:`~fcomp.identification.estimator.FrictionFit` runs its trajectory
stages through :class:`RecordsProblem` with one record; the diagnosis
(:class:`fcomp.diagnosis.refit.Refit`) refits every candidate model through
:func:`fit_records` on the training samples of several experiments, weighted.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fcomp.errors import FcompError
from fcomp.identification.dynamic import EXTRAS, Dependent, TrajectoryProblem
from fcomp.identification.problem import ParameterVector, Solution, solve
from fcomp.identification.target import FitData, block_mean
from fcomp.models.base import FrictionModel
from fcomp.parameters import ParamSpec, spec

#: Specifications of the identification extras (not model parameters).
EXTRA_SPECS: dict[str, ParamSpec] = {
    "mass": spec("mass", "kg", 0.0, 0.0, np.inf, "moving mass", directional=False),
    "offset": spec("offset", "N", 0.0, -np.inf, np.inf, "constant force offset",
                   directional=False),
    "lag": spec("lag", "s", 0.0, -0.02, 0.02, "first-order lag of the driving force's "
                "channel (pressure transducers and lines; negative: it leads)",
                directional=False),
}


@dataclass(frozen=True)
class Record:
    """One record of a fit: its data, the samples that enter the residual and their weights.

    Attributes
    ----------
    data
        Signals and target (:func:`~fcomp.identification.target.fit_data`).
    mask
        Boolean, one per sample: the samples in the residual (default all).
        The model is always simulated over the whole record.
    weights
        One per sample (default all 1): the weight ``w_k`` of the sample's
        squared residual (:class:`RecordsProblem`); read at the masked samples.
    """

    data: FitData
    mask: np.ndarray | None = None
    weights: np.ndarray | None = None

    def holding(self, held: Mapping[str, float]) -> Record:
        """This record with the extras ``held`` (name -> value) held: the target carries
        each held term, ``y - value*column``, and none is left to fit
        (:meth:`~fcomp.identification.target.FitData.holding`)."""
        d = self.data
        for name, value in held.items():
            d = d.holding(name, value)
        return dataclasses.replace(self, data=d)

    def averaged(self, q: int) -> Record:
        """This record averaged over blocks of ``q`` samples
        (:meth:`~fcomp.identification.target.FitData.averaged`): a block is in the
        mask when all its samples are, and weighs the mean of their weights."""
        if q <= 1:
            return self
        mask = None if self.mask is None else block_mean(self.mask.astype(float), q) > 0.999
        weights = None if self.weights is None else block_mean(self.weights, q)
        return Record(self.data.averaged(q), mask, weights)


class RecordsProblem:
    """Stacked residuals and Jacobians ``dF_hat/dtheta`` of several records, weighted.

    The residual of record ``r`` at its masked sample ``k`` is
    ``sqrt(w_rk)*(y_rk - F_hat_rk(theta))`` and its Jacobian row
    ``sqrt(w_rk)*dF_hat_rk/dtheta`` (``w_rk = 1`` for a record without weights),
    so the sum of squares is ``sum w_rk*(y_rk - F_hat_rk)^2``.

    Parameters
    ----------
    model
        The friction model (with effects).
    records
        The records, their masks and weights.
    pv
        The fitted parameters.
    substeps
        Integration steps per sample interval.
    dependent
        Model parameters tied to the fitted ones by equalities.
    """

    def __init__(self, model: FrictionModel, records: Sequence[Record], pv: ParameterVector, *,
                 substeps: int = 1, dependent: Sequence[Dependent] = ()) -> None:
        if not records:
            raise FcompError(f"fitting {model.describe()}: no record to fit")
        self.model = model
        self.pv = pv
        self.problems = [TrajectoryProblem(model, r.data, pv, mask=r.mask, substeps=substeps,
                                           dependent=dependent) for r in records]
        #: ``sqrt(w)`` of each record's masked samples (None: unweighted)
        self.roots = [None if r.weights is None else np.sqrt(r.weights[p.mask])
                      for r, p in zip(records, self.problems, strict=True)]

    def __call__(self, theta: np.ndarray,
                 need_jac: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
        if len(self.problems) == 1 and self.roots[0] is None:
            return self.problems[0](theta, need_jac)
        rs: list[np.ndarray] = []
        Gs: list[np.ndarray] = []
        for p, w in zip(self.problems, self.roots, strict=True):
            r, G = p(theta, need_jac)
            if w is not None:
                r = r * w
                G = None if G is None else G * w[:, None]
            rs.append(r)
            if G is not None:
                Gs.append(G)
        if len(Gs) < len(self.problems):
            return np.concatenate(rs), None
        return np.concatenate(rs), np.vstack(Gs)

    def predict(self, theta: Sequence[float] | np.ndarray) -> np.ndarray:
        """``F_hat`` at every sample of every record, concatenated (N)."""
        return np.concatenate([p.predict(theta) for p in self.problems])

    @property
    def jacobian_is_free(self) -> bool:
        """Whether the Jacobian comes with every evaluation (exact sensitivities)."""
        return all(p.jacobian_is_free for p in self.problems)

    @property
    def evaluations(self) -> int:
        """Model evaluations per record so far."""
        return sum(p.evaluations for p in self.problems) // len(self.problems)


def fit_specs(model: FrictionModel, names: Sequence[str],
              bounds: Mapping[str, tuple[float, float]] | None = None) -> dict[str, ParamSpec]:
    """The specs of ``names`` (model parameters and :data:`EXTRA_SPECS`), ``bounds`` (name ->
    ``(lower, upper)``, closed) replacing their own boxes."""
    all_specs = {**model.param_specs(), **EXTRA_SPECS}
    specs = {n: all_specs[n] for n in names}
    for n, (lo, hi) in (bounds or {}).items():
        if n in specs:
            specs[n] = dataclasses.replace(specs[n], lower=float(lo), upper=float(hi),
                                           lower_open=False)
    return specs


def solve_records(model: FrictionModel, records: Sequence[Record], pv: ParameterVector, *,
                  max_nfev: int, substeps: int = 1, dependent: Sequence[Dependent] = (),
                  what: str = "", compress: bool | None = None
                  ) -> tuple[Solution, RecordsProblem]:
    """The bounded least-squares solve of :class:`RecordsProblem` from ``pv.start``.

    ``compress`` reduces every evaluation to ``p + 1`` rows
    (:func:`~fcomp.identification.problem.compressed`); ``None``: where the
    Jacobian comes with every evaluation at no extra cost.
    """
    prob = RecordsProblem(model, records, pv, substeps=substeps, dependent=dependent)
    sol = solve(pv, prob, max_nfev=max_nfev, what=what or f"fit of {model.describe()}",
                compress=prob.jacobian_is_free if compress is None else compress)
    return sol, prob


@dataclass
class RecordsFit:
    """The result of :func:`fit_records`.

    Attributes
    ----------
    model
        The model with the fitted values (the extras excluded).
    values
        Fitted name -> value (the extras included).
    start
        The start the final solve began from (name -> value).
    cost
        Weighted sum of squared residuals over the masked samples (N^2).
    converged, message
        The solver's verdict.
    nfev
        Model evaluations of every solve (probes included).
    solution
        The final :class:`~fcomp.identification.problem.Solution` (``theta``,
        stacked residuals, Jacobian ``dF_hat/dtheta``, active bounds).
    probed_only
        True when the fit stopped after its probes (``keep_going`` said no).
    """

    model: FrictionModel
    values: dict[str, float]
    start: dict[str, float]
    cost: float
    converged: bool
    message: str
    nfev: int
    solution: Solution
    probed_only: bool = False


def fit_records(
    model: FrictionModel,
    records: Sequence[Record],
    names: Sequence[str],
    *,
    starts: Sequence[Mapping[str, float]] = (),
    bounds: Mapping[str, tuple[float, float]] | None = None,
    scales: Mapping[str, float] | Callable[[Mapping[str, float]], Mapping[str, float]]
    | None = None,
    max_nfev: int = 200,
    probe_nfev: int | None = None,
    probe_records: Sequence[Record] | None = None,
    keep_going: Callable[[float], bool] | None = None,
    staged: Collection[str] = (),
    substeps: int = 1,
    compress: bool | None = None,
) -> RecordsFit:
    """Fit the parameters ``names`` of ``model`` to the masked samples of several records.

    Minimises the stacked, weighted squared force error of the module docstring
    over one parameter vector, by bounded trust-region least squares with the
    gradient strategy the model's capabilities allow. With several starts and
    ``probe_nfev`` every start is probed first (:func:`best_start`, raced by
    successive halving) and the best continues; names in ``staged`` are held
    at their start values until a last solve frees them.

    Parameters
    ----------
    model
        The friction model (any effects); its values are the start of every
        name a start does not give, and the values of everything not fitted.
    records
        The records (:class:`Record`: data, mask of the samples in the
        residual, weights). Extras held at known values are taken out of the
        records beforehand (:meth:`Record.holding`).
    names
        Flat names to fit: model parameters and the extras ``mass`` (every
        record must then carry a driving force, ``FitData.inertia``),
        ``offset`` and ``lag`` (a driving force's rate). A model parameter
        named like an extra is fitted as the extra: set the model's own to 0
        first.
    starts
        Start points, each a mapping of names to values (missing names: the
        model's values; extras: 0). With several starts and ``probe_nfev``
        every start gets a short solve of ``probe_nfev`` evaluations and the
        best continues; without ``probe_nfev`` the first start is used.
    bounds
        Name -> ``(lower, upper)`` replacing the box of the parameter's
        :class:`~fcomp.parameters.ParamSpec` (closed bounds).
    scales
        Name -> typical magnitude (the solver's ``x_scale``), or a function of
        the start giving them; default ``|start|``.
    max_nfev
        Evaluation budget of each full solve.
    probe_nfev
        Budget of each probe (several starts).
    probe_records
        The records the probes run on (default ``records``), e.g. copies
        averaged over blocks (:meth:`Record.averaged`): the probes only rank
        the starts.
    keep_going
        Called with the best probe's cost; ``False`` stops there (the result
        then has ``probed_only`` set and ``converged`` false).
    staged
        Names held at their start values in a first stage and fitted with the
        others in a second (shape exponents, whose flat valleys a first stage
        keeps the fit out of). Unused when every name is staged.
    substeps
        Integration steps per sample interval.
    compress
        Reduce every evaluation to ``p + 1`` rows (:func:`solve_records`);
        default: where the Jacobian comes free.

    Returns
    -------
    RecordsFit

    Raises
    ------
    FcompError
        When no start gives finite forces, or a name is unknown.
    """
    names = list(names)
    flat = model.flat_params()
    unknown = [n for n in names if n not in flat and n not in EXTRAS]
    if unknown:
        raise FcompError(f"{model.describe()}: no parameter(s) {', '.join(unknown)} to fit; "
                         f"known: {', '.join(flat)}")
    base = {**flat, **{n: 0.0 for n in EXTRAS if n in names}}
    start_list = [dict(base, **s) for s in starts] or [dict(base)]
    specs = fit_specs(model, names, bounds)
    first = [n for n in names if n not in staged] or names

    def run(fitted: list[str], st: Mapping[str, float], budget: int,
            recs: Sequence[Record]) -> tuple[Solution, int]:
        sc = scales(st) if callable(scales) else scales
        pv = ParameterVector.build(fitted, st, specs, sc)
        sol, prob = solve_records(model, recs, pv, max_nfev=budget, substeps=substeps,
                                  compress=compress)
        return sol, prob.evaluations

    def resume(st: dict[str, float], sol: Solution) -> dict[str, float]:
        return dict(st, **dict(zip(first, map(float, sol.theta), strict=True)))

    probing = len(start_list) > 1 and bool(probe_nfev)
    budget = probe_nfev if probe_nfev and probing else max_nfev
    tried = start_list if probing else start_list[:1]
    on = (probe_records or records) if probing else records
    cost, sol, st, nfev = best_start(tried, lambda s, k: run(first, s, k, on), budget,
                                     model.describe(), resume=resume)
    chosen = resume(st, sol)
    if probing:
        if keep_going is not None and not keep_going(cost):
            return _result(model, names, chosen, st, sol, nfev, probed_only=True)
        sol, k = run(first, chosen, max_nfev, records)
        nfev += k
        chosen = resume(chosen, sol)
    if first != names:
        sol, k = run(names, chosen, max_nfev, records)
        nfev += k
    return _result(model, names, dict(zip(names, map(float, sol.theta), strict=True)), chosen,
                   sol, nfev)


def best_start(starts: Sequence[dict[str, float]],
               solve: Callable[[dict[str, float], int], tuple[Solution, int]],
               budget: int, what: str, *,
               resume: Callable[[dict[str, float], Solution], dict[str, float]] | None = None,
               ) -> tuple[float, Solution, dict[str, float], int]:
    """The start whose (short) solve ends with the least sum of squares.

    ``solve(start, evaluations)`` returns the solution and its evaluation count, or
    raises :class:`~fcomp.errors.FcompError` for a start where the model gives
    non-finite forces (that start is skipped); each start gets ``budget``
    evaluations. Returns ``(cost, solution, start, evaluations)``, the evaluations
    summed over every start tried.

    With ``resume`` and more than two starts, the probes are raced by successive
    halving (Jamieson and Talwalkar, "Non-stochastic best arm identification and
    hyperparameter optimization", AISTATS 2016): every start gets a third of
    ``budget``; the better half (by cost, at least two) continue from where they
    stopped (``resume(start, solution)``) with the rest. A start that has not found
    its valley after a third of the budget rarely wins; the evaluations of the
    others are saved (a third of the probing with six starts). The start returned
    is then where the winner resumed.

    Raises
    ------
    FcompError
        When no start gives finite forces.
    """
    if resume is None or len(starts) <= 2:
        ranked, nfev = _ranked(starts, lambda st: solve(st, budget), what)
        return (*ranked[0], nfev)
    short = max(budget // 3, 1)
    ranked, nfev = _ranked(starts, lambda st: solve(st, short), what)
    keep = ranked[: max(2, (len(ranked) + 1) // 2)]
    out, more = _ranked([resume(st, sol) for _, sol, st in keep],
                        lambda st: solve(st, budget - short), what)
    return (*out[0], nfev + more)


def _ranked(starts: Sequence[dict[str, float]],
            solve_one: Callable[[dict[str, float]], tuple[Solution, int]],
            what: str) -> tuple[list[tuple[float, Solution, dict[str, float]]], int]:
    """Every start's ``(cost, solution, start)``, least cost first, and the evaluations."""
    out: list[tuple[float, Solution, dict[str, float]]] = []
    nfev = 0
    for st in starts:
        try:
            sol, k = solve_one(st)
        except FcompError:
            continue
        nfev += k
        out.append((float(sol.residuals @ sol.residuals), sol, st))
    if not out:
        raise FcompError(f"fitting {what}: the model gives non-finite forces at every start")
    out.sort(key=lambda e: e[0])
    return out, nfev


def _result(model: FrictionModel, names: Sequence[str], values: Mapping[str, float],
            start: Mapping[str, float], sol: Solution, nfev: int, *,
            probed_only: bool = False) -> RecordsFit:
    vals = {n: float(values[n]) for n in names}
    own = {k: v for k, v in vals.items() if k not in EXTRAS}
    return RecordsFit(model.with_params(**own) if own else model, vals, dict(start),
                      float(sol.residuals @ sol.residuals), sol.converged and not probed_only,
                      sol.message, nfev, sol, probed_only)
