"""One parameter vector fitted to the masked samples of several records: the fitting engine's core.

A fit adjusts the flat parameters ``theta`` (model names, plus the extras
``mass`` and ``offset``) to minimise

    sum over records r, over its masked samples k:  (y_rk - F_hat_rk(theta))^2,

where ``F_hat_r`` is the model simulated from rest along record ``r``'s
measured motion (:class:`~fcomp.identification.dynamic.TrajectoryProblem`:
the gradient strategy the model's capabilities allow) and ``y_r`` its target
(:class:`~fcomp.identification.target.FitData`). Residuals and Jacobians of
the records are stacked (:class:`RecordsProblem`) and handed to the bounded
trust-region solve of :func:`~fcomp.identification.problem.solve`.

:class:`~fcomp.identification.estimator.FrictionFit` runs its trajectory
stages through :class:`RecordsProblem` with one record; :func:`fit_records` is
the public entry point for several (the diagnosis refits candidate models on
the training samples of several experiments with it): given the parameter
list, the starts, the bounds and the scales, it returns the values reached
and the solution.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fcomp.errors import FcompError
from fcomp.identification.dynamic import EXTRAS, Dependent, TrajectoryProblem
from fcomp.identification.problem import ParameterVector, Solution, solve
from fcomp.identification.target import FitData
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
    """One record of a fit: its data and the samples that enter the residual.

    Attributes
    ----------
    data
        Signals and target (:func:`~fcomp.identification.target.fit_data`).
    mask
        Boolean, one per sample: the samples in the residual (default all).
        The model is always simulated over the whole record, from rest.
    """

    data: FitData
    mask: np.ndarray | None = None


class RecordsProblem:
    """Stacked residuals ``y - F_hat`` and Jacobians ``dF_hat/dtheta`` of several records.

    Parameters
    ----------
    model
        The friction model (with effects).
    records
        The records and their masks.
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

    def __call__(self, theta: np.ndarray,
                 need_jac: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
        if len(self.problems) == 1:
            return self.problems[0](theta, need_jac)
        rs: list[np.ndarray] = []
        Gs: list[np.ndarray] = []
        for p in self.problems:
            r, G = p(theta, need_jac)
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


def solve_records(model: FrictionModel, records: Sequence[Record], pv: ParameterVector, *,
                  max_nfev: int, substeps: int = 1, dependent: Sequence[Dependent] = (),
                  what: str = "") -> tuple[Solution, RecordsProblem]:
    """The bounded least-squares solve of :class:`RecordsProblem` from ``pv.start``."""
    prob = RecordsProblem(model, records, pv, substeps=substeps, dependent=dependent)
    sol = solve(pv, prob, max_nfev=max_nfev, what=what or f"fit of {model.describe()}",
                compress=prob.jacobian_is_free)
    return sol, prob


@dataclass
class RecordsFit:
    """The result of :func:`fit_records`.

    Attributes
    ----------
    model
        The model with the fitted values (``mass``/``offset`` excluded).
    values
        Fitted name -> value (the extras included).
    start
        The start the final solve began from (name -> value).
    cost
        Sum of squared residuals over the masked samples (N^2).
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
    keep_going: Callable[[float], bool] | None = None,
    substeps: int = 1,
) -> RecordsFit:
    """Fit the parameters ``names`` of ``model`` to the masked samples of several records.

    Minimises the stacked squared force error of the module docstring over one
    parameter vector, by bounded trust-region least squares with the gradient
    strategy the model's capabilities allow.

    Parameters
    ----------
    model
        The friction model (any effects); its values are the start of every
        name a start does not give, and the values of everything not fitted.
    records
        The records (:class:`Record`: data and mask of the samples in the residual).
    names
        Flat names to fit: model parameters and the extras ``mass`` (every
        record must then carry a driving force, ``FitData.inertia``) and
        ``offset``. A model parameter named like an extra is fitted as the
        extra: set the model's own to 0 first.
    starts
        Start points, each a mapping of names to values (missing names: the
        model's values; ``mass``, ``offset``: 0). With several starts and
        ``probe_nfev`` every start gets a short solve of ``probe_nfev``
        evaluations and the best continues; without ``probe_nfev`` the first
        start is used.
    bounds
        Name -> ``(lower, upper)`` replacing the box of the parameter's
        :class:`~fcomp.parameters.ParamSpec` (closed bounds).
    scales
        Name -> typical magnitude (the solver's ``x_scale``), or a function of
        the start giving them; default ``|start|``.
    max_nfev
        Evaluation budget of the final solve.
    probe_nfev
        Budget of each probe (several starts).
    keep_going
        Called with the best probe's cost; ``False`` stops there (the result
        then has ``probed_only`` set and ``converged`` false).
    substeps
        Integration steps per sample interval.

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
    all_specs = {**model.param_specs(), **EXTRA_SPECS}
    specs = {n: all_specs[n] for n in names}
    for n, (lo, hi) in (bounds or {}).items():
        if n in specs:
            specs[n] = dataclasses.replace(specs[n], lower=float(lo), upper=float(hi),
                                           lower_open=False)

    def vector(start: Mapping[str, float]) -> ParameterVector:
        sc = scales(start) if callable(scales) else scales
        return ParameterVector.build(names, start, specs, sc)

    nfev = 0
    chosen = start_list[0]
    if len(start_list) > 1 and probe_nfev:
        def probe(st: dict[str, float], k: int) -> tuple[Solution, int]:
            sol, prob = solve_records(model, records, vector(st), max_nfev=k,
                                      substeps=substeps)
            return sol, prob.evaluations

        cost, sol, st, k = best_start(start_list, probe, probe_nfev, model.describe())
        nfev += k
        chosen = dict(st, **dict(zip(names, map(float, sol.theta), strict=True)))
        if keep_going is not None and not keep_going(cost):
            return _result(model, names, chosen, st, sol, nfev, probed_only=True)
    sol, prob = solve_records(model, records, vector(chosen), max_nfev=max_nfev,
                              substeps=substeps)
    nfev += prob.evaluations
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
