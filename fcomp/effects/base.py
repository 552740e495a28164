"""The effect base class: a named, switchable physical effect added to any model.

Implementer's contract
======================
An effect is a subclass of :class:`Effect` with

``name``
    its public name (the catalogue of models.md 1.8, or the user's own);
``Params``
    a frozen :class:`~fcomp.parameters.ParamSet` whose *defaults make the
    effect a no-op* (the model's force is unchanged);
``states`` / ``initial``
    names and rest values of any states it adds (e.g. the dwell state);
``signature``
    one line: the residual signature it explains (used by diagnosis);
``experiment``
    one line: the experiment that isolates it (used for confounded ties),
    worded for any rig;
``confounded``
    optional, names of effects that give the same force over the motions most
    records hold (an offset and a direction asymmetry of the levels, while
    sliding): the diagnosis puts each in this effect's place at the end and
    reports a tie when it fits as well;
``experiments``
    optional, rig kind (the sidecar's ``kind``: ``pneumatic-cylinder``,
    ``hydraulic-cylinder``, ``friction-rig``, ``electromechanical-axis``) ->
    that experiment worded for such a rig, where it differs (no chambers to
    vent on a motor-driven axis); :meth:`Effect.experiment_for` picks it (a
    plain ``dict`` in the class body, made read-only when the class is made);
``of_measurement``
    optional, ``True`` for an effect of the measurement, not of the seal (a force
    offset, an inertia error): a model file keeps it among its measurement terms;
``fit_extra``
    optional, the name of an extra term of a fit (``offset``: the constant
    force ``fcomp fit --offset`` estimates beside the model) that this effect
    holds as its own parameter of that name: a fit's value of it becomes this
    effect (:func:`fcomp.effects.effect_holding`);

and overrides whichever hooks it needs, each written once against the
backend ``be`` (so it works numerically and symbolically):

:meth:`modify_levels` ``(be, L, w, sig, P) -> L``
    scale or shift the force levels ``L = {"Fc": .., "Fs": ..}``;
:meth:`rhs` ``(be, w, sig, P) -> list``
    derivatives of its own states ``w``;
:meth:`extra_force` ``(be, sig, P) -> (F0, c_a)``
    an additive force ``F0 + c_a*a``;
:meth:`steady_state` ``(be, sig, P) -> list``
    its states at constant velocity.

Diagnosis hooks
---------------
A diagnosis (:class:`fcomp.diagnosis.Diagnosis`) takes every registered effect
as a candidate and treats each the same way, through these class attributes
and methods. Each has a neutral default, so an effect that overrides none of
them is still a candidate (started from its defaults). The methods receive a
:class:`~fcomp.effects.record.RecordView`: the record's signals, the force to
match, the current model's prediction and residual, the training mask, the
current parameter values, the record's scales
(:class:`~fcomp.conditioning.Scales`), rest speed, presliding length, the
starts after a dwell, whether the mass is fitted.

``needs`` (class attribute, default ``()``)
    signals the effect reads besides ``v`` (``"x"``, ``"p1"``, ``"p2"``,
    ``"a"``): a record without one measured and informative cannot show it;
``dynamic`` (class attribute, default ``False``)
    whether the effect needs a motion (a memory or the acceleration);
    effects with ``states`` are dynamic anyway. Not a candidate for
    steady-state points;
``factors`` (class attribute, default ``()``)
    the operating factors the effect's law acts through (``speed``,
    ``direction``, ``pressure``, ``position``, ``distance-since-reversal``): where the
    record varies two factors together (one speed per direction, a speed that
    falls with the pressure), effects acting through them are reported as a tie
    with the experiment that separates them (:mod:`fcomp.diagnosis.design`);
``acts_in`` (class attribute, default ``()``: anywhere)
    the motion regimes its signature lives in, named as
    :data:`fcomp.diagnosis.regimes.REGIMES` names them (``"pre-sliding"``,
    ``"reversal"``, ``"sliding"``, ``"dwell/break-away"``). A flexible effect that
    declares them is accepted only when most of its held-out fall lies there
    (:data:`fcomp.diagnosis.loop.SIGNATURE_SHARE`): its freedom must not win on a
    misfit elsewhere (the Maxwell-slip elements of ``nonlocal-memory``, spread over
    a long slip, can bend any transient after a reversal);
:meth:`diagnosis_config` ``(scales) -> dict``
    class method (default ``{}``): the configuration of an instance fitted to a
    record with these :class:`~fcomp.conditioning.Scales` (a reference speed,
    the stroke's ends);
:meth:`diagnosis_forms` ``() -> tuple[DiagnosisForm, ...]``
    class method (default one form, ``DiagnosisForm()``): the forms the
    diagnosis refits side by side, of which it keeps the one the information
    criterion prefers; each a label, a configuration and the parameters it
    holds at their no-op values (:class:`~fcomp.effects.record.DiagnosisForm`);
:meth:`refined_forms` ``() -> tuple[DiagnosisForm, ...]``
    class method (default none): richer forms tried once the effect is
    accepted, each kept only when the acceptance rule accepts it against the
    form it would replace, on held-out data (the saturating and power laws of
    ``pressure-dependence``);
:meth:`forms_for` ``(model) -> tuple[DiagnosisForm, ...]``
    class method (default :meth:`diagnosis_forms`): those of the forms that are
    different laws on ``model`` (two forms can coincide on a simpler model);
:meth:`unsuitable` ``(view) -> str | None`` (default ``None``)
    why this record cannot show the effect (no start after a dwell; the mass
    already fitted), ``None`` if it can;
:meth:`guess` ``(view, form) -> list[dict]`` (default ``[{}]``: the defaults)
    data-driven starts of the refit, flat values of the effect's own
    parameters (a guess may also move parameters of the model, e.g. a
    stiffer bristle), read off the current residual and the motion; one
    dict per alternative start. ``form`` is the label of the form tried
    (``None`` for an effect with one form);
:meth:`held` ``(view) -> list[str]`` (default ``[]``)
    parameters the record cannot determine (columns it cannot tell apart),
    held at their no-op values in the refit.

The diagnosis judges a candidate in this order: it must change the model
(:meth:`applies_to`), the signals of ``needs`` but ``"a"`` must be there, a
``dynamic`` effect needs a motion, then the acceleration (``"a"`` in
``needs``), then :meth:`unsuitable`, then attaching it must work. The
methods are called on an instance with default parameters configured for the
record: ``diagnosis_config`` (and, for :meth:`guess` and :meth:`held`, the
form's ``config``; :meth:`unsuitable` is asked before a form is chosen).
Guesses only start the refit: every parameter of the model is refitted, but
the held ones.

*Structural* effects (terms of the LuGre family itself: ``stribeck``,
``viscous``, ``viscous-lead``, ``presliding``, ``frictional-lag``,
``nonlocal-memory``) derive from
:class:`~fcomp.effects.structural.StructuralEffect`: attaching one returns the
richer model of the family, built by the family's
:meth:`~fcomp.models.lugre_family.LuGreFamily.with_structure`, instead of
riding along.

Each effect of the catalogue is one module of :mod:`fcomp.effects` (its law,
its diagnosis hooks, its wording), listed in :mod:`fcomp.effects.catalogue`.

The class docstring of each effect is its physical explanation: what it is
and what it leaves in a residual when a model lacks it.

This module imports nothing of :mod:`fcomp.models` (the models' ``with_effects``
takes names and resolves them through :data:`EFFECTS` here), so models and
effects form no import circle: the effects build on the models, the models
only on this base.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, ClassVar

from fcomp.backend import Backend
from fcomp.parameters import ParamSet, ParamValues, PlainValue, adopt_params
from fcomp.registry import Registry

if TYPE_CHECKING:
    from fcomp.conditioning import Scales
    from fcomp.effects.record import DiagnosisForm, RecordView
    from fcomp.models.base import FrictionModel, Signals


class Effect(PlainValue):
    """Base class of effects (see the module docstring for the contract).

    Effects are plain values: they pickle with their parameters and configuration.

    Parameters
    ----------
    params
        Effect parameters (instance of ``Params`` or mapping of flat names);
        defaults (a no-op) where omitted.
    """

    name: ClassVar[str] = ""
    Params: ClassVar[type[ParamSet]]
    states: ClassVar[tuple[str, ...]] = ()
    initial: ClassVar[tuple[float, ...]] = ()
    signature: ClassVar[str] = ""
    experiment: ClassVar[str] = ""
    #: rig kind -> the experiment for such a rig, where it differs from ``experiment``
    experiments: ClassVar[Mapping[str, str]] = MappingProxyType({})
    #: effects that give the same force over most motions (tried in its place: a tie)
    confounded: ClassVar[tuple[str, ...]] = ()
    #: the extra term of a fit this effect holds as its own parameter of that name ("": none)
    fit_extra: ClassVar[str] = ""
    #: it describes the measurement, not the seal (a model file keeps it in
    #: ``measurement_terms``; plant friction and compensators drop it)
    of_measurement: ClassVar[bool] = False
    #: signals the effect reads besides v (diagnosis checks the data has them)
    needs: ClassVar[tuple[str, ...]] = ()
    #: needs a motion (memory, acceleration): not a candidate for steady-state points
    dynamic: ClassVar[bool] = False
    #: the operating factors its law acts through (``speed``, ``direction``, ``pressure``,
    #: ``position``, ``distance-since-reversal``; :mod:`fcomp.diagnosis.design`): a record
    #: that varies two factors together cannot tell the laws in them apart
    factors: ClassVar[tuple[str, ...]] = ()
    #: the motion regimes its signature lives in (empty: anywhere; module docstring)
    acts_in: ClassVar[tuple[str, ...]] = ()
    #: the laws the effect can take, chosen by the configuration ``form=``; the first is
    #: the default (empty: one law, no ``form``)
    FORMS: ClassVar[tuple[str, ...]] = ()
    #: its configuration keys besides ``form`` (``x_min``, ...): any other is refused (a
    #: typo would be dropped silently) for fcomp's own effects and for an effect that
    #: declares them; an effect of the user's that declares none is not checked
    CONFIG: ClassVar[tuple[str, ...]] = ()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        adopt_params(cls)
        own = cls.__dict__.get("experiments")
        if isinstance(own, dict):  # wording is data: read-only once the class is made
            cls.experiments = MappingProxyType(dict(own))

    def __init__(self, params: ParamSet | Mapping[str, Any] | None = None, **config: Any) -> None:
        if params is None:
            params = self.Params()
        elif isinstance(params, Mapping):
            params = self.Params.from_flat(params)
        elif not isinstance(params, self.Params):
            raise ValueError(f"effect {self.name}: expected {self.Params.__name__}")
        self.params: ParamSet = params
        self.config: dict[str, Any] = dict(config)
        known = ("form", *self.CONFIG)
        unknown = [k for k in self.config if k not in known]
        if unknown and _checks_config(type(self)):
            raise ValueError(f"effect {self.name}: unknown configuration key {unknown[0]!r} "
                             f"(known: {', '.join(known)})")
        if self.FORMS and self.form not in self.FORMS:
            raise ValueError(f"effect {self.name}: form must be one of "
                             f"{', '.join(self.FORMS)}, got {self.form!r}")

    @property
    def form(self) -> str:
        """The law chosen from :attr:`FORMS` (``config["form"]``, default the first)."""
        return str(self.config.get("form", self.FORMS[0] if self.FORMS else ""))

    @classmethod
    def experiment_for(cls, kind: str) -> str:
        """The experiment that isolates this effect on a rig of ``kind`` (the sidecar's
        ``kind``; ``""`` or a kind without its own wording: the general ``experiment``)."""
        return cls.experiments.get(kind, cls.experiment)

    def with_params(self, **flat: float) -> Effect:
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new.params = self.Params.from_flat(flat, base=self.params)
        return new

    # ------------------------------------------------------------------ hooks
    def attach(self, model: FrictionModel) -> FrictionModel:
        """Return ``model`` with this effect (add-on effects ride along)."""
        if any(e.name == self.name for e in model.effects):
            raise ValueError(f"model {model.describe()!r} already has effect {self.name!r}")
        return model._rebuild(model.params, (*model.effects, self))

    def applies_to(self, model: FrictionModel) -> bool:
        """Whether adding this effect to ``model`` changes its structure."""
        return all(e.name != self.name for e in model.effects)

    def modify_levels(
        self, be: Backend, L: dict, w: list[Any], sig: Signals, P: ParamValues
    ) -> dict:
        return L

    def rhs(self, be: Backend, w: list[Any], sig: Signals, P: ParamValues) -> list:
        return []

    def extra_force(self, be: Backend, sig: Signals, P: ParamValues) -> tuple[Any, Any]:
        return 0.0, 0.0

    def steady_state(self, be: Backend, sig: Signals, P: ParamValues) -> list:
        return list(self.initial)

    # ------------------------------------------------------- diagnosis hooks
    @classmethod
    def diagnosis_config(cls, scales: Scales) -> dict[str, Any]:
        """Configuration of an instance fitted to a record of these ``scales`` (default none)."""
        return {}

    @classmethod
    def diagnosis_forms(cls) -> tuple[DiagnosisForm, ...]:
        """The forms a diagnosis refits side by side (default: one, unconfigured)."""
        from fcomp.effects.record import DiagnosisForm

        return (DiagnosisForm(),)

    @classmethod
    def refined_forms(cls) -> tuple[DiagnosisForm, ...]:
        """Richer forms a diagnosis tries once the effect is accepted (default none): each
        is refitted in place of the form accepted and kept only when the acceptance rule
        accepts it against that form on the held-out data (a saturating pressure law)."""
        return ()

    @classmethod
    def forms_for(cls, model: FrictionModel) -> tuple[DiagnosisForm, ...]:
        """The forms that are different laws on ``model`` (default: all of
        :meth:`diagnosis_forms`); a form that coincides with an earlier one there
        is left out rather than refitted twice."""
        return cls.diagnosis_forms()

    def unsuitable(self, view: RecordView) -> str | None:
        """Why the record cannot show this effect, ``None`` if it can (default: it can)."""
        return None

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """Data-driven starts of the refit (default: the parameters' defaults)."""
        return [{}]

    def held(self, view: RecordView) -> list[str]:
        """Parameters the record cannot determine, held at their no-op values (default none)."""
        return []

    def __repr__(self) -> str:
        return f"<effect {self.name} {self.params}>"


#: The least share of its reference level a level law may scale a friction level to
#: (:func:`scale_levels` with a backend): a seal's friction stays positive whatever a
#: fitted polynomial does outside the range where the record fixes it.
LEVEL_FLOOR = 0.01


def scale_levels(L: dict, factor: Any, names: tuple[str, ...] = ("Fc", "Fs"),
                 be: Backend | None = None) -> dict:
    """``L`` with the named levels multiplied by ``factor``.

    With a backend ``be`` the factor is first floored at :data:`LEVEL_FLOOR`,
    ``max(factor, 0.01)``: level laws that are polynomials (pressure, position)
    can turn negative far from the data that fixed them, and a negative level
    is no friction at all (a LuGre state divides by it). Where the factor is
    above the floor the law is unchanged.
    """
    if be is not None:
        factor = be.fmax(factor, LEVEL_FLOOR)
    out = dict(L)
    for n in names:
        if n in out:
            out[n] = out[n] * factor
    return out


#: Effects by public name: the catalogue (:mod:`fcomp.effects.catalogue`, one module per
#: effect) registers itself when imported (importing any module of :mod:`fcomp.effects`
#: imports it), users with :func:`register_effect`.
EFFECTS: Registry[type[Effect]] = Registry("effect")


def register_effect(cls: type[Effect], *, replace: bool = False) -> type[Effect]:
    """Register a user effect class under ``cls.name`` (usable as a decorator)."""
    if not (isinstance(cls, type) and issubclass(cls, Effect)):
        raise ValueError(f"{cls!r} is not an Effect subclass")
    if not cls.name:
        raise ValueError(f"effect class {cls.__name__} has no name")
    for attr in ("Params",):
        if not hasattr(cls, attr):
            raise ValueError(f"effect {cls.name!r} must define {attr}")
    EFFECTS.register(cls.name, cls, replace=replace)
    return cls


def _checks_config(cls: type[Effect]) -> bool:
    """Whether ``cls`` has its configuration keys checked: fcomp's own effects, and one of
    the user's that declares :attr:`Effect.CONFIG`."""
    return cls.__module__.startswith("fcomp.") or any(
        "CONFIG" in k.__dict__ for k in cls.__mro__ if k is not Effect)


def make_effect(name: str, params: Any = None, **config: Any) -> Effect:
    """An effect instance by name, with parameters (defaults: a no-op)."""
    return EFFECTS.get(name)(params, **config)


def as_effect(effect: Effect | str) -> Effect:
    """``effect`` itself, or the registered effect of that name with default parameters."""
    return make_effect(effect) if isinstance(effect, str) else effect
