"""The friction-model base class and the signals a model reads.

Implementer's contract
======================
A friction model is a subclass of :class:`FrictionModel` that defines

``name``
    its public name (class attribute), registered in :data:`fcomp.models.MODELS`;
``Params``
    a frozen :class:`~fcomp.parameters.ParamSet` dataclass of its parameters;
``base_states`` and :meth:`base_initial_state`
    the names and initial values of its own continuous states;
:meth:`base_rhs` ``(be, x, sig, P, L) -> list``
    the time derivatives of its states;
:meth:`base_force` ``(be, x, dx, sig, P, L) -> (F0, c_a)``
    the friction force split as ``F = F0 + c_a * a`` where ``a = dv/dt``;
    plants move ``c_a`` to the mass side so that terms like NMLGM's
    ``sigma2*T*dv/dt`` are solved exactly instead of lagged;
:meth:`base_steady_state` ``(be, sig, P, L) -> list``
    the states reached at constant velocity ``sig.v`` (used for the
    steady-state map and tests).

Each of these is written *once* against the backend ``be``
(:mod:`fcomp.backend`), so it evaluates numerically (numpy) and symbolically
(CasADi) from the same code. ``x`` is the list of the model's states,
``sig`` the :class:`Signals`, ``P`` the :class:`~fcomp.parameters.ParamValues`
view of all parameters (model and effects), ``L`` the *levels* (``Fc``,
``Fs`` and the other force levels after the effects modified them, see
:meth:`levels`).

Effects (:mod:`fcomp.effects`) add states, modify the levels and add force
terms; :meth:`FrictionModel.with_effects` composes them. Everything the
simulation engine, identification, EKF and MPC need is derived here:
:meth:`rhs`, :meth:`force`, :meth:`steady_state`, :meth:`casadi_functions`.

Capabilities, asked for, never switched on by type
==================================================
Every model can be put anywhere a model goes; what differs between models
is asked for, and the answer says which route to take:

:meth:`FrictionModel.discrete_memory`
    ``None`` for models whose memory is in their continuous states (every
    equation then has its symbolic form: :attr:`FrictionModel.symbolic` is
    true); otherwise the model's :class:`DiscreteMemory` (the turning-point
    stack of ``nmlgm-hysteresis``), which integrates a motion and couples to
    plants its own way, while :meth:`rhs` and :meth:`casadi_functions` raise
    :class:`NotSymbolicError`;
:meth:`FrictionModel.feature_family`
    ``None``, or the model as a member of a family of feature sets that
    structural effects extend (:class:`FeatureFamily`: the LuGre family);
:attr:`FrictionModel.static_map`
    whether the model is a memoryless map that plants hold with Karnopp's
    stick band;
``Params.UNIT_SUMS``
    parameter groups that sum to 1 (the fit keeps them so).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import casadi as ca
import numpy as np

from fcomp.backend import CASADI, NUMPY, Backend
from fcomp.errors import FcompError
from fcomp.parameters import ParamSet, ParamValues, PlainValue, adopt_params

if TYPE_CHECKING:
    from fcomp.effects.base import Effect
    from fcomp.models.lugre_family import Structure


class NotSymbolicError(FcompError):
    """A model without a symbolic (CasADi) form was asked for one."""


SIGNAL_NAMES: tuple[str, ...] = ("v", "a", "x", "p1", "p2", "s")


@dataclass(frozen=True)
class Signals:
    """The measured or simulated quantities a friction model may read (SI).

    Attributes
    ----------
    v : m/s
        Piston velocity, positive extending.
    a : m/s^2
        Piston acceleration ``dv/dt`` (only the ``c_a`` split of the force uses it).
    x : m
        Piston position from the cap end.
    p1, p2 : Pa
        Chamber pressures, *gauge* (effects such as ``pressure-dependence`` read them).
    s : -
        Side of the direction-dependent parameters: ``+1`` uses the ``v > 0``
        values, ``-1`` the ``v < 0`` ones. At ``v = 0`` the last side used is
        kept (models.md section 1); :func:`side_of` computes it.
    """

    v: Any
    a: Any = 0.0
    x: Any = 0.0
    p1: Any = 0.0
    p2: Any = 0.0
    s: Any = 1.0

    @classmethod
    def symbolic(cls) -> tuple[Signals, ca.SX]:
        """Signals made of CasADi symbols, and their stacked vector."""
        syms = [ca.SX.sym(n) for n in SIGNAL_NAMES]
        return cls(*syms), ca.vertcat(*syms)

    def as_list(self) -> list[Any]:
        return [self.v, self.a, self.x, self.p1, self.p2, self.s]


class DiscreteMemory(Protocol):
    """The capability of a model whose memory is discrete (:meth:`FrictionModel.discrete_memory`).

    The model's states are those of a *carrier* -- the model with continuous
    states it is built on -- plus :attr:`memory_state`, the value the memory
    gives (``Fz``, the force of the hysteresis function); the memory itself
    (the turning-point stack) is not a state vector and has no symbolic form.
    """

    #: name of the state the memory sets (among the model's ``state_names``)
    memory_state: str

    def carrier(self) -> FrictionModel:
        """The model with continuous states that integrates everything but the memory."""
        ...

    def hysteresis_function(self, values: Mapping[str, float] | None = None) -> Any:
        """A fresh memory (``reset``, ``step``, ``move_to``, ``snapshot``/``restore``)."""
        ...

    def bristle_inputs(self, x: Sequence[Any], sig: Signals, P: Any) -> tuple[Any, Any]:
        """What the memory reads at state ``x``: the sliding force ``g`` and threshold ``zs``."""
        ...

    def integrate_motion(self, sig: Mapping[str, np.ndarray], x0: np.ndarray,
                         flat: Mapping[str, float], substeps: int) -> np.ndarray:
        """The states ``(N, n_states)`` along sampled signals (``t, v, a, x, p1, p2, s``)."""
        ...


class FeatureFamily(Protocol):
    """The capability of a model that belongs to a family of feature sets
    (:meth:`FrictionModel.feature_family`): structural effects extend it, through
    :meth:`with_structure` alone."""

    params: ParamSet

    @property
    def features(self) -> frozenset[str]:
        """The family's features the model has (``viscous``, ``presliding``, ...)."""
        ...

    @property
    def viscous_name(self) -> str:
        """The name of its viscous coefficient (``sigma2``, ``B``)."""
        ...

    @property
    def lineage(self) -> tuple[str, ...]:
        """The model and the effects it was built from, in order (for :meth:`describe`)."""
        ...

    def with_structure(self, term: Structure) -> FrictionModel:
        """The family's model with a structural term (which features, their values) added
        (:meth:`fcomp.models.lugre_family.LuGreFamily.with_structure`)."""
        ...

    def describe(self) -> str: ...


def side_of(v: np.ndarray, initial: float = 1.0) -> np.ndarray:
    """Side ``s`` (+1/-1) for a velocity record: ``sign(v)``, holding the last side at ``v = 0``."""
    v = np.asarray(v, dtype=float)
    s = np.sign(v)
    if s.size and s[0] == 0:
        s[0] = initial
    # forward-fill zeros with the last non-zero side
    idx = np.where(s != 0, np.arange(s.size), 0)
    np.maximum.accumulate(idx, out=idx)
    return s[idx]


class FrictionModel(PlainValue, ABC):
    """Base class of every friction model (see the module docstring for the contract).

    Models are plain values: they pickle (:class:`~fcomp.parameters.PlainValue`),
    with their parameters and effects, also when their class was made for a
    feature combination (it pickles by its recipe).

    Parameters
    ----------
    params
        The model's parameters (a ``Params`` instance or a mapping of flat
        names); defaults where omitted.
    effects
        Effect instances composed onto the model (:meth:`with_effects` adds them by
        name too).
    """

    name: ClassVar[str] = ""
    Params: ClassVar[type[ParamSet]]
    base_states: ClassVar[tuple[str, ...]] = ()
    #: level parameters that effects may scale (present ones only)
    level_names: ClassVar[tuple[str, ...]] = ("Fc", "Fs")

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        adopt_params(cls)

    def __init__(
        self,
        params: ParamSet | Mapping[str, Any] | None = None,
        effects: Sequence[Effect] = (),
    ) -> None:
        if params is None:
            params = self.Params()
        elif isinstance(params, Mapping):
            params = self.Params.from_flat(params)
        elif not isinstance(params, self.Params):
            raise ValueError(
                f"{self.name}: expected {self.Params.__name__}, got {type(params).__name__}"
            )
        self.params: ParamSet = params
        if any(isinstance(e, str) for e in effects):
            raise ValueError(f"{self.name}: effects are given as instances here; "
                             "add them by name with with_effects")
        self.effects: tuple[Effect, ...] = tuple(effects)
        names = list(self.params.flat())
        for e in self.effects:
            for n in e.params.flat():
                if n in names:
                    raise ValueError(
                        f"{self.name}: parameter {n!r} of effect {e.name!r} clashes with another"
                    )
                names.append(n)

    # -------------------------------------------------------- capabilities
    def discrete_memory(self) -> DiscreteMemory | None:
        """The model's discrete memory, or ``None`` when its memory is its continuous
        states (module docstring, "Capabilities")."""
        return None

    @property
    def symbolic(self) -> bool:
        """Whether every equation has its symbolic (CasADi) form: no discrete memory."""
        return self.discrete_memory() is None

    def feature_family(self) -> FeatureFamily | None:
        """The model as a member of a feature family that structural effects extend, or
        ``None`` (module docstring, "Capabilities")."""
        return None

    @property
    def static_map(self) -> bool:
        """Whether the model is a memoryless map (plants hold it with Karnopp's stick band,
        :mod:`plants.mechanics`); models with a bristle or element states are not."""
        return False

    # ------------------------------------------------------------ contract
    def base_initial_state(self) -> list[float]:
        """Initial values of :attr:`base_states` (friction states zero)."""
        return [0.0] * len(self.base_states)

    def base_rhs(self, be: Backend, x: list[Any], sig: Signals, P: ParamValues, L: dict) -> list:
        """Time derivatives of the model's own states (none for static maps)."""
        return []

    def base_exact_steps(self, be: Backend, x: list[Any], sig: Signals, P: ParamValues,
                         L: dict, h: Any) -> list[Any | None]:
        """The model's own states after a sampled step of ``h`` s, where known in closed form.

        The sampled step (:func:`fcomp.models.stepping.exponential_euler`) is
        ``x_1 = x_0 + h*phi1(h*J)*f(x_0)`` with ``J`` the diagonal of the exact
        Jacobian: exact where a state's equation is linear in it at held signals
        (LuGre's bristle). A state whose equation is not, but whose value after
        the step at held signals has a closed form, gives it here; None (the
        default) keeps the exponential Euler step. (Dahl's exponent ``i < 1``: the
        tangent step overshot the steady deflection by ``1/i - 1`` of the gap,
        without bound below ``1/2``.)
        """
        return [None] * len(self.base_states)

    @abstractmethod
    def base_force(
        self, be: Backend, x: list[Any], dx: list[Any], sig: Signals, P: ParamValues, L: dict
    ) -> tuple[Any, Any]:
        """Friction force ``(F0, c_a)`` with ``F = F0 + c_a*a`` (N, kg)."""

    def base_steady_state(self, be: Backend, sig: Signals, P: ParamValues, L: dict) -> list:
        """States reached at constant velocity ``sig.v``."""
        return []

    # ------------------------------------------------------------- composition
    @property
    def state_names(self) -> tuple[str, ...]:
        names = list(self.base_states)
        for e in self.effects:
            names += list(e.states)
        return tuple(names)

    @property
    def n_states(self) -> int:
        return len(self.state_names)

    @property
    def dynamic(self) -> bool:
        """Whether the model has continuous states."""
        return self.n_states > 0

    def initial_state(self) -> np.ndarray:
        """Initial state vector (friction states zero, effect states at their rest values)."""
        x0 = list(self.base_initial_state())
        for e in self.effects:
            x0 += list(e.initial)
        return np.asarray(x0, dtype=float)

    def with_effects(self, *effects: Effect | str) -> FrictionModel:
        """A new model with ``effects`` added (names or :class:`~fcomp.effects.Effect` objects).

        Each effect attaches itself (:meth:`~fcomp.effects.Effect.attach`): a
        structural one (a term of the LuGre family) returns the richer model of
        the family (:meth:`FeatureFamily.with_structure`), the others ride along.
        A name is the registered effect of that name with its defaults: the names
        are the effects' (:data:`fcomp.effects.EFFECTS`), resolved there, in the
        one place this module meets the registry (imported here, not at the top:
        importing it registers the catalogue, which is built on the model modules).
        """
        from fcomp.effects.base import as_effect

        model: FrictionModel = self
        for e in effects:
            model = as_effect(e).attach(model)
        if self.measurement and not model.measurement:  # a structural term builds anew
            model = model.with_measurement(self.measurement)
        if self.fitted_range and not model.fitted_range:
            model = model.with_fitted_range(self.fitted_range)
        return model

    def with_params(self, **flat: float) -> FrictionModel:
        """A copy with parameters changed by flat name (model or effect parameters)."""
        own = {k: v for k, v in flat.items() if k in self.params.flat()}
        new_params = self.Params.from_flat(own, base=self.params) if own else self.params
        rest = {k: v for k, v in flat.items() if k not in own}
        effects = []
        for e in self.effects:
            mine = {k: v for k, v in rest.items() if k in e.params.flat()}
            effects.append(e.with_params(**mine) if mine else e)
            for k in mine:
                rest.pop(k)
        if rest:
            raise ValueError(
                f"{self.describe()}: unknown parameter(s) {', '.join(sorted(rest))}; "
                f"known: {', '.join(self.flat_params())}"
            )
        return self._rebuild(new_params, tuple(effects))

    def _rebuild(self, params: ParamSet, effects: tuple[Effect, ...]) -> FrictionModel:
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new.params = params
        new.effects = effects
        return new

    # ------------------------------------------------------ measurement
    @property
    def measurement(self) -> dict[str, float]:
        """The terms of the *measurement* a fit found beside the friction (a copy):
        ``mass`` (kg, the moving mass of a driving force), ``offset`` (N, a constant
        force offset), ``lag`` (s, the lag of the force channel) -- those estimated;
        empty for a model not fitted.

        They are the model file's ``measurement_terms.params``
        (:data:`fcomp.models.document.MEASUREMENT_PARAMS`): a comparison with a
        record puts them back (:func:`fcomp.modelfile.split_measurement`), so a fitted
        model is compared as it was fitted; the friction itself -- what a plant or a
        compensator uses -- never reads them. A plant has its own moving mass.
        """
        return dict(self.__dict__.get("_measurement") or {})

    def with_measurement(self, terms: Mapping[str, float] | None = None) -> FrictionModel:
        """A copy carrying the measurement terms ``terms`` (:attr:`measurement`), replacing
        any it had; ``None`` or empty: none (the seal's friction alone).

        Raises
        ------
        ValueError
            For a name that is not a measurement term or a value that is not finite.
        """
        from fcomp.models.document import MEASUREMENT_PARAMS

        clean: dict[str, float] = {}
        for k, v in (terms or {}).items():
            if k not in MEASUREMENT_PARAMS:
                raise ValueError(f"{k!r} is not a measurement term (known: "
                                 f"{', '.join(MEASUREMENT_PARAMS)})")
            if not math.isfinite(float(v)):
                raise ValueError(f"measurement term {k} = {v} is not a finite number")
            clean[k] = float(v)
        new = self._rebuild(self.params, self.effects)
        new.__dict__.pop("_measurement", None)
        if clean:
            new.__dict__["_measurement"] = clean
        return new

    @property
    def stderr(self) -> dict[str, float]:
        """Standard errors of the values by flat name, where an identification gave them (a
        model file's ``stderr``, read by :func:`fcomp.modelfile.read_model`); empty for a
        model whose values nobody estimated. A copy. The estimators of
        :mod:`controllers` tune their process noise from it
        (:mod:`controllers.estimator_tuning`)."""
        return dict(self.__dict__.get("_stderr") or {})

    def with_stderr(self, stderr: Mapping[str, float] | None) -> FrictionModel:
        """A copy carrying the standard errors ``stderr`` (:attr:`stderr`; finite, >= 0; names
        the model lacks are left out), replacing any it had; ``None``: none."""
        flat = self.flat_params()
        clean = {k: float(v) for k, v in (stderr or {}).items()
                 if k in flat and math.isfinite(float(v)) and float(v) >= 0}
        new = self._rebuild(self.params, self.effects)
        new.__dict__.pop("_stderr", None)
        if clean:
            new.__dict__["_stderr"] = clean
        return new

    @property
    def fitted_range(self) -> dict[str, tuple[float, float]]:
        """The ranges of the record the model was fitted on (a copy): ``x`` (m), ``v``
        (m/s), ``p`` (Pa, gauge chamber pressures), those known; empty for a model not
        fitted. A fit and a diagnosis set them, the model file carries them
        (``"fitted_range"``), and :func:`fcomp.modelfile.check_range` checks a use against
        them (:mod:`fcomp.models.fitted_range`)."""
        return dict(self.__dict__.get("_fitted_range") or {})

    def with_fitted_range(self, ranges: Mapping[str, Any] | None = None) -> FrictionModel:
        """A copy carrying the fitted ranges ``ranges`` (:attr:`fitted_range`), replacing any
        it had; ``None`` or empty: none.

        Raises
        ------
        ValueError
            For an unknown signal, or a range that is not two finite numbers, low first.
        """
        from fcomp.models.fitted_range import checked_ranges

        clean = checked_ranges(ranges or {})
        new = self._rebuild(self.params, self.effects)
        new.__dict__.pop("_fitted_range", None)
        if clean:
            new.__dict__["_fitted_range"] = clean
        return new

    def flat_params(self) -> dict[str, float]:
        """All parameters, model and effects, by flat name."""
        out = dict(self.params.flat())
        for e in self.effects:
            out.update(e.params.flat())
        return out

    def param_specs(self) -> dict[str, Any]:
        """Flat name -> :class:`~fcomp.parameters.ParamSpec` of every parameter."""
        out = {}
        for owner in (self.params, *[e.params for e in self.effects]):
            for n in owner.flat():
                own = type(owner).names()  # a parameter may itself end in _neg (r_neg)
                base = n[:-4] if n not in own and n.endswith(("_pos", "_neg")) else n
                out[n] = type(owner).spec_of(base)
        return out

    def describe(self) -> str:
        """``"lugre + pressure-dependence"`` style label."""
        return " + ".join([self.name, *[e.name for e in self.effects]])

    # ------------------------------------------------------------ evaluation
    def param_values(self, be: Backend, values: Mapping[str, Any] | None = None) -> ParamValues:
        return ParamValues(values if values is not None else self.flat_params(), be)

    def levels(self, be: Backend, x: list[Any], sig: Signals, P: ParamValues) -> dict:
        """Force levels after every effect modified them (``Fc``, ``Fs``, ...)."""
        L = {n: P(n, sig.s) for n in self.level_names if P.has(n)}
        offset = len(self.base_states)
        for e in self.effects:
            k = len(e.states)
            L = e.modify_levels(be, L, x[offset : offset + k], sig, P)
            offset += k
        return L

    def rhs(self, be: Backend, x: Sequence[Any], sig: Signals, P: ParamValues) -> list:
        """Time derivatives of all states (model then effects)."""
        x = list(x)
        L = self.levels(be, x, sig, P)
        nb = len(self.base_states)
        dx = list(self.base_rhs(be, x[:nb], sig, P, L))
        offset = nb
        for e in self.effects:
            k = len(e.states)
            dx += list(e.rhs(be, x[offset : offset + k], sig, P))
            offset += k
        return dx

    def exact_steps(self, be: Backend, x: Sequence[Any], sig: Signals, P: ParamValues,
                    h: Any) -> list[Any | None]:
        """:meth:`base_exact_steps` of all states (the effects' states: None)."""
        x = list(x)
        nb = len(self.base_states)
        out = list(self.base_exact_steps(be, x[:nb], sig, P, self.levels(be, x, sig, P), h))
        return out + [None] * (len(x) - nb)

    def base_project(self, be: Backend, x: list[Any], sig: Signals, P: ParamValues,
                     L: dict) -> list:
        """The base states after a step, mapped back onto their admissible set (default: as is).

        A model whose states have hard limits (Maxwell-slip element deflections
        within their slip band) clips them here; the sampled engine applies it
        after every step (:func:`fcomp.models.stepping.friction_step`).
        """
        return x

    def project(self, be: Backend, x: Sequence[Any], sig: Signals, P: ParamValues) -> list:
        """All states after a step, base states projected (:meth:`base_project`)."""
        x = list(x)
        nb = len(self.base_states)
        return list(self.base_project(be, x[:nb], sig, P, self.levels(be, x, sig, P))) + x[nb:]

    def force_parts(
        self, be: Backend, x: Sequence[Any], sig: Signals, P: ParamValues
    ) -> tuple[Any, Any]:
        """Friction force split ``(F0, c_a)``, ``F = F0 + c_a*a`` (effects included)."""
        x = list(x)
        L = self.levels(be, x, sig, P)
        nb = len(self.base_states)
        dx = self.base_rhs(be, x[:nb], sig, P, L)
        F0, ca_ = self.base_force(be, x[:nb], dx, sig, P, L)
        for e in self.effects:
            f0, c = e.extra_force(be, sig, P)
            F0 = F0 + f0
            ca_ = ca_ + c
        return F0, ca_

    def force(self, be: Backend, x: Sequence[Any], sig: Signals, P: ParamValues) -> Any:
        """Friction force ``F`` (N), positive opposing extension."""
        F0, c = self.force_parts(be, x, sig, P)
        return F0 + c * sig.a

    def steady_state_states(self, be: Backend, sig: Signals, P: ParamValues) -> list:
        """All states at constant velocity ``sig.v``."""
        xs: list[Any] = []
        for e in self.effects:
            xs += list(e.steady_state(be, sig, P))
        # levels may depend on effect states: evaluate them with the effect states first
        nb = len(self.base_states)
        placeholder = [0.0] * nb + xs
        L = self.levels(be, placeholder, sig, P)
        return list(self.base_steady_state(be, sig, P, L)) + xs

    def steady_state(
        self,
        v: Any,
        *,
        x: Any = 0.0,
        p1: Any = 0.0,
        p2: Any = 0.0,
        values: Mapping[str, Any] | None = None,
    ) -> np.ndarray:
        """Steady-state friction force ``F_ss(v)`` (N) at constant velocity ``v`` (m/s).

        For static maps this is the map itself; for dynamic models it is the
        force their states settle to when ``v`` is held constant (e.g. for
        LuGre ``F_ss = sign(v)*g(v) + sigma2*v``, models.md 1.3).
        """
        v = np.asarray(v, dtype=float)
        s = np.where(v >= 0, 1.0, -1.0)
        sig = Signals(v=v, a=0.0, x=x, p1=p1, p2=p2, s=s)
        P = self.param_values(NUMPY, values)
        xs = self.steady_state_states(NUMPY, sig, P)
        xs = [np.broadcast_to(np.asarray(c, dtype=float), v.shape) for c in xs]
        return np.asarray(self.force(NUMPY, xs, sig, P), dtype=float)

    # -------------------------------------------------------------- symbolic
    def require_symbolic(self) -> None:
        """Raise :class:`NotSymbolicError` unless the model has its symbolic form."""
        if self.discrete_memory() is not None:
            raise NotSymbolicError(
                f"model {self.describe()!r} has discrete (turning-point) memory and no "
                "symbolic CasADi form; use its numeric simulation, or 'nmlgm'/'gms' for "
                "EKF/MPC/gradient-based work"
            )

    def casadi_functions(self, *, symbolic_params: bool = False) -> dict[str, ca.Function]:
        """CasADi functions of the model, built from the same equations.

        Returns
        -------
        dict
            ``"rhs"``: ``(x, sig[, p]) -> dx/dt``; ``"force"``: ``(x, sig[, p]) -> F``;
            ``"force_parts"``: ``(x, sig[, p]) -> [F0, c_a]``. ``sig`` is the vector
            ``[v, a, x, p1, p2, s]``; ``p`` (only with ``symbolic_params``) the
            flat parameters in the order of :meth:`flat_params`.
        """
        self.require_symbolic()
        xs = ca.SX.sym("x", self.n_states)
        sig, sigv = Signals.symbolic()
        names = list(self.flat_params())
        if symbolic_params:
            pv, P = ParamValues.symbolic(names)
            args, argn = [xs, sigv, pv], ["x", "sig", "p"]
        else:
            P = self.param_values(CASADI)
            args, argn = [xs, sigv], ["x", "sig"]
        xl = [xs[i] for i in range(self.n_states)]
        dx = self.rhs(CASADI, xl, sig, P)
        F0, c = self.force_parts(CASADI, xl, sig, P)
        dxv = ca.vertcat(*dx) if dx else ca.SX(0, 1)
        return {
            "rhs": ca.Function("rhs", args, [dxv], argn, ["dx"]),
            "force": ca.Function("force", args, [F0 + c * sig.a], argn, ["F"]),
            "force_parts": ca.Function("force_parts", args, [ca.vertcat(F0, c)], argn, ["Fc_a"]),
        }

    # ----------------------------------------------------------------- file
    def save(self, path: str | Path, **document: Any) -> Path:
        """Write the model as a model file (``docs/model-file.md``); ``fcomp.load_model``
        reads it back with the same forces, bit for bit.

        Parameters
        ----------
        path : str or Path
            The JSON file written (atomically).
        **document
            ``stderr``, ``measurement``, ``source`` of
            :func:`fcomp.models.document.model_document`.

        Returns
        -------
        Path
            The file written.
        """
        from fcomp.models.document import save_model

        return save_model(self, path, **document)

    # ----------------------------------------------------------------- misc
    def __repr__(self) -> str:
        from fcomp.models.document import MEASUREMENT_PARAMS

        terms = self.measurement
        extra = ("; measurement " + ", ".join(f"{k} {v:.4g} {MEASUREMENT_PARAMS[k]}"
                                              for k, v in terms.items()) if terms else "")
        return f"<{type(self).__name__} {self.describe()}{extra}>"

    def passivity(self) -> dict[str, Any]:
        """Passivity (dissipativity) of the map ``v -> F``.

        Models without a bristle state are memoryless monotone maps and are
        passive when every level is non-negative; dynamic models override this.
        """
        return {"applies": False, "passive": None, "reason": "no bristle state"}


def isfinite_param(value: float) -> bool:
    return math.isfinite(value)
