"""Trajectory fit: the simulated model force along the measured motion against the measured force.

The prediction at sample ``k`` is

    F_hat_k = F_model_k(theta) + mass*(a_k + g*s_o) + offset - lag*dD/dt_k,

where ``F_model`` is the friction model integrated along the measured
velocity exactly as :func:`fcomp.trajectory.friction_along_motion` does
(interval-mean signals, exponential Rosenbrock-Euler step, states starting
at rest), and the ``mass``, ``offset`` and ``lag`` terms are present only
when fitted. ``lag`` is the first-order lag (s) of the force channel of a
driving force ``D`` (pressure transducers and their lines): the target
``D_meas - m*a`` then misses ``lag*dD/dt`` wherever ``D`` changes fast, and
the prediction carries it instead.
The residual is ``r = y - F_hat`` (target ``y`` from :mod:`.target`), over
all samples or a ``mask``. Where the target was low-passed (parallel
filtering, :attr:`~.target.FitData.band_hz`) the model force and its
sensitivities pass through the same filter before the extras are added.

Jacobian: a *gradient strategy*, chosen by what the model can do (its
:meth:`~fcomp.models.base.FrictionModel.discrete_memory` capability), never by
its type: :class:`ExactSensitivities` for models whose memory is their
continuous states (the forward sensitivities of
:class:`~fcomp.identification.sensitivity.SensitivityLoop`: one compiled pass
gives the force and all its derivatives), :class:`FiniteDifferences` for
models with discrete memory (forward differences of the numeric simulation,
step ``1e-6`` of each parameter's scale, one extra simulation per parameter).
Everything else of the fit is the same path for every model. The ``mass``,
``offset`` and ``lag`` columns are ``a + g*s_o``, ``1`` and ``-dD/dt``
(:meth:`~.target.FitData.extra_column`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from fcomp.identification.problem import ParameterVector
from fcomp.identification.sensitivity import SensitivityLoop
from fcomp.identification.target import FitData
from fcomp.models.base import FrictionModel
from fcomp.trajectory import friction_along_motion

EXTRAS = ("mass", "offset", "lag")


@dataclass(frozen=True)
class Dependent:
    """A model parameter set by an affine equality, ``name = constant + sum(coef_k*theta_k)``.

    E.g. the last slip fraction of the generalized Maxwell-slip model,
    ``alpha_N = 1 - alpha_1 - ... - alpha_{N-1}``. Its sensitivity is folded
    into the free parameters': ``dF/dtheta_k += coef_k*dF/d(name)``.
    """

    name: str
    constant: float
    coef: Mapping[str, float]

    def value(self, values: Mapping[str, float]) -> float:
        return self.constant + sum(c * values[k] for k, c in self.coef.items())


class GradientStrategy(ABC):
    """The model force along a record and its derivatives with respect to ``names``.

    Parameters
    ----------
    model
        The friction model.
    data
        The record's signals.
    names
        Flat parameter names to differentiate with respect to.
    substeps
        Integration steps per sample interval.
    """

    #: whether the derivatives come with every evaluation at no extra cost
    free_jacobian: ClassVar[bool] = False

    def __init__(self, model: FrictionModel, data: FitData, names: Sequence[str],
                 substeps: int = 1) -> None:
        self.model = model
        self.data = data
        self.names = tuple(names)
        self.substeps = substeps

    @abstractmethod
    def __call__(self, values: Mapping[str, float], jac: bool
                 ) -> tuple[np.ndarray, np.ndarray]:
        """``(F, dF/d names)`` at the flat ``values`` (``dF`` zeros when not ``jac`` and not free)."""

    def simulate(self, values: Mapping[str, float]) -> np.ndarray:
        """The model force (N) along the record with the flat ``values``."""
        s = self.data.sig
        return friction_along_motion(self.model, s["t"], s["v"], a=s["a"], x=s["x"],
                                     p1=s["p1"], p2=s["p2"], values=values,
                                     substeps=self.substeps).F


class ExactSensitivities(GradientStrategy):
    """Exact derivatives: the forward sensitivities of the simulation step (models whose
    memory is their continuous states; :class:`~fcomp.identification.sensitivity.SensitivityLoop`)."""

    free_jacobian = True

    def __init__(self, model: FrictionModel, data: FitData, names: Sequence[str],
                 substeps: int = 1) -> None:
        super().__init__(model, data, names, substeps)
        self.loop = SensitivityLoop(model, self.names, substeps=substeps)

    def __call__(self, values: Mapping[str, float], jac: bool
                 ) -> tuple[np.ndarray, np.ndarray]:
        return self.loop(self.data.sig, values)


class FiniteDifferences(GradientStrategy):
    """Forward differences of the numeric simulation, one extra run per name (models with
    discrete memory). ``steps`` gives the step of each name (default ``1e-6`` of its
    magnitude); a step that would cross ``upper`` is taken backwards."""

    def __init__(self, model: FrictionModel, data: FitData, names: Sequence[str],
                 substeps: int = 1, steps: Mapping[str, float] | None = None,
                 upper: Mapping[str, float] | None = None) -> None:
        super().__init__(model, data, names, substeps)
        self.steps = dict(steps or {})
        self.upper = dict(upper or {})

    def __call__(self, values: Mapping[str, float], jac: bool
                 ) -> tuple[np.ndarray, np.ndarray]:
        F = self.simulate(values)
        G = np.zeros((F.size, len(self.names)))
        if jac:
            for j, name in enumerate(self.names):
                h = self.steps.get(name) or 1e-6 * max(abs(values[name]), 1e-12)
                if values[name] + h > self.upper.get(name, np.inf):
                    h = -h
                G[:, j] = (self.simulate({**values, name: values[name] + h}) - F) / h
        return F, G


def gradient_strategy(model: FrictionModel, data: FitData, names: Sequence[str], *,
                      substeps: int = 1, steps: Mapping[str, float] | None = None,
                      upper: Mapping[str, float] | None = None) -> GradientStrategy:
    """The gradient strategy the model's capabilities allow: exact sensitivities unless its
    memory is discrete (then finite differences); a plain simulation where there is
    nothing to differentiate and no state to integrate."""
    if model.discrete_memory() is None and model.n_states + len(names) > 0:
        return ExactSensitivities(model, data, names, substeps)
    return FiniteDifferences(model, data, names, substeps, steps, upper)


class TrajectoryProblem:
    """Residuals ``y - F_hat`` and ``dF_hat/dtheta`` along a record (see the module docstring).

    Parameters
    ----------
    model
        The friction model (with effects).
    data
        Signals and target of the record.
    pv
        The fitted parameters: model flat names plus optionally ``mass``, ``offset``.
    mask
        Samples that enter the residual (default all). The model is always
        simulated over the whole record.
    substeps
        Integration steps per sample interval.
    dependent
        Model parameters tied to the fitted ones by :class:`Dependent` equalities.
    gradient
        The gradient strategy (default :func:`gradient_strategy`: by the model's capability).
    """

    def __init__(self, model: FrictionModel, data: FitData, pv: ParameterVector, *,
                 mask: np.ndarray | None = None, substeps: int = 1,
                 dependent: Sequence[Dependent] = (),
                 gradient: GradientStrategy | None = None) -> None:
        self.model = model
        self.data = data
        self.pv = pv
        self.model_free = [n for n in pv.names if n not in EXTRAS]
        for name in EXTRAS:
            if name in pv.names and data.extra_column(name) is None:
                raise ValueError(f"the {name} can only be fitted to driving-force data")
        self.mask = np.ones(data.n, dtype=bool) if mask is None else np.asarray(mask, bool)
        self.all_samples = bool(self.mask.all())
        self.substeps = substeps
        self.dependent = tuple(dependent)
        diff = [*self.model_free, *(dep.name for dep in self.dependent)]
        self.gradient = gradient or gradient_strategy(
            model, data, diff, substeps=substeps,
            steps={n: 1e-6 * pv.scale[pv.index(n)] for n in self.model_free},
            upper={n: pv.upper[pv.index(n)] for n in self.model_free})
        self.evaluations = 0

    # ------------------------------------------------------------------ model
    def _with_dependent(self, values: dict[str, float]) -> dict[str, float]:
        out = dict(values)
        for dep in self.dependent:
            out[dep.name] = dep.value(out)
        return out

    def _model_force(self, values: dict[str, float], jac: bool) -> tuple[np.ndarray, np.ndarray]:
        nf = len(self.model_free)
        F, Gall = self.gradient(self._with_dependent(values), jac)
        G = Gall[:, :nf].copy() if self.dependent else Gall
        for k, dep in enumerate(self.dependent):  # dF/dtheta_k += coef_k*dF/d(dependent)
            for name, c in dep.coef.items():
                if name in self.model_free:
                    G[:, self.model_free.index(name)] += c * Gall[:, nf + k]
        return F, G

    def values(self, theta: Sequence[float] | np.ndarray) -> dict[str, float]:
        return dict(zip(self.pv.names, map(float, theta), strict=True))

    def predict(self, theta: Sequence[float] | np.ndarray) -> np.ndarray:
        """``F_hat`` at every sample (N)."""
        return self._predict(theta, jac=False)[0]

    def _predict(self, theta: Sequence[float] | np.ndarray,
                 jac: bool) -> tuple[np.ndarray, np.ndarray]:
        vals = self.values(theta)
        model_vals = {k: v for k, v in vals.items() if k not in EXTRAS}
        F, Gm = self._model_force(model_vals, jac)
        self.evaluations += 1
        if Gm.size and (jac or self.jacobian_is_free):  # one pass of the filter for all
            both = self.data.band_limited(np.column_stack([F, Gm]))
            F, Gm = both[:, 0].copy(), both[:, 1:]
        else:
            F = self.data.band_limited(F.copy())
        G = np.empty((F.size, len(self.pv.names)))
        pos = [self.pv.index(n) for n in self.model_free]
        if pos == list(range(len(pos))):
            G[:, : len(pos)] = Gm
        else:
            G[:, pos] = Gm
        for name in EXTRAS:
            if name not in vals:
                continue
            col = self.data.extra_column(name)
            F += vals[name] * col  # type: ignore[operator]
            G[:, self.pv.index(name)] = col  # type: ignore[call-overload]
        return F, G

    def __call__(self, theta: np.ndarray,
                 need_jac: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
        F, G = self._predict(theta, jac=need_jac)
        give = need_jac or self.jacobian_is_free
        if self.all_samples:
            return self.data.y - F, (G if give else None)
        m = self.mask
        return self.data.y[m] - F[m], (G[m] if give else None)

    @property
    def jacobian_is_free(self) -> bool:
        """Whether the Jacobian comes with every evaluation (exact sensitivities)."""
        return self.gradient.free_jacobian or not self.model_free
