"""Parameters as data: specifications, direction-dependent values, frozen sets.

Every model and effect declares its parameters as :class:`ParamSpec` entries
(name, SI unit, default, bounds, meaning). :func:`make_params_class` turns a
tuple of specs into a *frozen dataclass* whose construction validates every
value against its bounds and raises a ``ValueError`` naming the offending
parameter.

Direction-dependent parameters (seed 000 Table 4, models.md section 1) are
:class:`Directional` values holding the magnitude used for ``v > 0`` and for
``v < 0``. The seed writes the negative-side value with a minus sign; the
magnitude is stored, so ``Directional(22.5, -25.0)`` and
``Directional(22.5, 25.0)`` are the same value.

For fitting and for symbolic evaluation a parameter set is *flattened* into a
mapping of scalar names: a scalar ``Fc`` stays ``Fc``, a directional ``Fc``
becomes ``Fc_pos`` and ``Fc_neg``. :class:`ParamValues` is the view the model
equations read: ``P("Fc", s)`` returns the value for the side ``s`` (+1/-1).

Values that travel
------------------
Parameter sets, models and effects are plain values: they pickle, so they can
be cached, sent to worker processes (``spawn`` start method, Dask) and saved.
A class defined in a module pickles by reference, as any class. A class a
*factory* makes on demand (the parameter class of a feature set, the model
class of a feature combination) carries a :class:`ClassRecipe` -- the
factory and its arguments -- and its instances pickle by that recipe
(:class:`PlainValue`); the factories are cached, so the recipe gives back the
very same class in the same process and an equal one in another.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple, TypeVar

from fcomp.backend import Backend


@dataclass(frozen=True)
class Directional:
    """A parameter with separate magnitudes for ``v > 0`` (``pos``) and ``v < 0`` (``neg``).

    A negative ``neg`` (the seed tables' way of writing the retracting side)
    is stored as its magnitude.
    """

    pos: float
    neg: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "pos", float(self.pos))
        object.__setattr__(self, "neg", abs(float(self.neg)))

    def values(self) -> tuple[float, float]:
        return (self.pos, self.neg)

    def __str__(self) -> str:
        return f"{{pos={self.pos:g}, neg={self.neg:g}}}"


@dataclass(frozen=True)
class ParamSpec:
    """Specification of one parameter.

    Attributes
    ----------
    name
        Symbol used in models.md (``Fc``, ``sigma0``, ...).
    unit
        SI unit (``"N"``, ``"N/m"``, ``"Ns/m"``, ``"m/s"``, ``"s"``, ``"-"``).
    default
        Default value.
    lower, upper
        Inclusive bounds (``lower_open`` makes the lower bound exclusive).
    doc
        One line of meaning.
    directional
        Whether a :class:`Directional` value is allowed.
    """

    name: str
    unit: str
    default: float
    lower: float = -math.inf
    upper: float = math.inf
    doc: str = ""
    directional: bool = True
    lower_open: bool = False

    def check(self, value: float, owner: str) -> None:
        """Raise ``ValueError`` naming this parameter if ``value`` is out of bounds."""
        if not isinstance(value, int | float) or isinstance(value, bool):
            raise ValueError(f"{owner}: parameter {self.name} must be a number, got {value!r}")
        if math.isnan(value):
            raise ValueError(f"{owner}: parameter {self.name} is NaN")
        low_bad = value <= self.lower if self.lower_open else value < self.lower
        if low_bad or value > self.upper:
            lo = "(" if self.lower_open else "["
            raise ValueError(
                f"{owner}: parameter {self.name} = {value:g} {self.unit} is outside its bounds "
                f"{lo}{self.lower:g}, {self.upper:g}] ({self.doc})"
            )


def spec(
    name: str,
    unit: str,
    default: float,
    lower: float = -math.inf,
    upper: float = math.inf,
    doc: str = "",
    *,
    directional: bool = True,
    lower_open: bool = False,
) -> ParamSpec:
    """Shorthand constructor of :class:`ParamSpec`."""
    return ParamSpec(name, unit, default, lower, upper, doc, directional, lower_open)


P = TypeVar("P", bound="ParamSet")
C = TypeVar("C", bound=type)


class ClassRecipe(NamedTuple):
    """How a class made by a factory is made again: ``factory(*args)`` (see the module docstring)."""

    factory: Callable[..., type]
    args: tuple[Any, ...]

    def make(self) -> type:
        return self.factory(*self.args)


#: Largest magnitude of a number the user gives in SI units (the command line's values,
#: a model file's): beyond it no rig has a value, whatever the unit.
MAX_VALUE = 1e15

def finite_number(value: Any) -> float | None:
    """A value read from a file (JSON, TOML) as a finite float; ``None`` for anything else:
    text, a bool, a list, infinity or NaN, an integer too large for a float."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


#: Class attribute holding a factory-made class's :class:`ClassRecipe`.
RECIPE = "__recipe__"


def with_recipe(cls: C, factory: Callable[..., type], *args: Any) -> C:
    """Mark ``cls`` as made by ``factory(*args)`` (an importable, cached factory); returns ``cls``."""
    setattr(cls, RECIPE, ClassRecipe(factory, tuple(args)))
    return cls


def class_reference(cls: type) -> type | ClassRecipe:
    """What a pickle stores for ``cls``: its recipe if a factory made it, else the class."""
    recipe = cls.__dict__.get(RECIPE)
    return recipe if isinstance(recipe, ClassRecipe) else cls


def restore(ref: type | ClassRecipe, state: Mapping[str, Any]) -> Any:
    """An instance of the class ``ref`` names (class or recipe) with attributes ``state``."""
    cls = ref.make() if isinstance(ref, ClassRecipe) else ref
    obj: Any = object.__new__(cls)
    obj.__dict__.update(state)
    return obj


class PlainValue:
    """Mixin: instances pickle as their class reference (:func:`class_reference`) and
    their attributes; nothing else is needed to rebuild them."""

    def __reduce__(self) -> tuple[Any, ...]:
        return restore, (class_reference(type(self)), dict(self.__dict__))


def adopt_params(owner: type) -> None:
    """Home the ``Params`` class made in the body of ``owner`` as ``owner.Params``.

    :func:`make_params_class` names a class after its ``cls_name`` in the
    module that made it, which is right for a module-level
    ``FooParams = make_params_class("FooParams", ...)``; made inside a class
    body (effects, user models) it is importable as ``Owner.Params`` instead,
    and this gives it that qualified name. Model, effect and plant classes call
    it when they are created (``__init_subclass__``).
    """
    params = owner.__dict__.get("Params")
    if not isinstance(params, type) or RECIPE in params.__dict__:
        return
    module = sys.modules.get(params.__module__)
    if module is not None and getattr(module, params.__qualname__, None) is params:
        return
    if params.__module__ == owner.__module__:
        params.__qualname__ = f"{owner.__qualname__}.Params"


class ParamSet(PlainValue):
    """Base of every parameter dataclass (made by :func:`make_params_class`).

    Subclasses are frozen dataclasses whose fields are the parameters; the
    class attribute ``SPECS`` holds their :class:`ParamSpec`. Construction
    validates bounds, the cross-constraints in ``CONSTRAINTS`` (pairs
    ``(small, large)`` meaning ``small <= large`` on each side) and the
    equalities in ``UNIT_SUMS`` (groups whose values sum to 1, within
    :data:`UNIT_SUM_TOL`).
    """

    SPECS: ClassVar[tuple[ParamSpec, ...]] = ()
    CONSTRAINTS: ClassVar[tuple[tuple[str, str], ...]] = ()
    #: groups of parameters that must sum to 1 (e.g. the slip fractions of GMS), and why
    UNIT_SUMS: ClassVar[tuple[tuple[tuple[str, ...], str], ...]] = ()
    OWNER: ClassVar[str] = "parameters"

    def __post_init__(self) -> None:
        for s in self.SPECS:
            raw = getattr(self, s.name)
            if isinstance(raw, Mapping):
                raw = Directional(raw["pos"], raw["neg"])
                object.__setattr__(self, s.name, raw)
            elif isinstance(raw, tuple | list) and len(raw) == 2:
                raw = Directional(raw[0], raw[1])
                object.__setattr__(self, s.name, raw)
            if isinstance(raw, Directional):
                if not s.directional:
                    raise ValueError(
                        f"{self.OWNER}: parameter {s.name} cannot be direction-dependent"
                    )
                s.check(raw.pos, self.OWNER)
                s.check(raw.neg, self.OWNER)
            else:
                if isinstance(raw, int) and not isinstance(raw, bool):
                    raw = float(raw)
                    object.__setattr__(self, s.name, raw)
                s.check(raw, self.OWNER)
        for small, large in self.CONSTRAINTS:
            a, b = self.side_values(small), self.side_values(large)
            for side, va, vb in zip(("v > 0", "v < 0"), a, b, strict=True):
                if va > vb:
                    raise ValueError(
                        f"{self.OWNER}: parameter {small} = {va:g} must not exceed "
                        f"{large} = {vb:g} ({side})"
                    )
        for group, why in self.UNIT_SUMS:
            total = sum(float(getattr(self, n)) for n in group)
            if abs(total - 1.0) > UNIT_SUM_TOL:
                raise ValueError(
                    f"{self.OWNER}: parameters {group[0]}..{group[-1]} must sum to 1 (they sum "
                    f"to {total:.12g})" + (f"; {why}" if why else "")
                )

    # ------------------------------------------------------------------ access
    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(s.name for s in cls.SPECS)

    @classmethod
    def spec_of(cls, name: str) -> ParamSpec:
        for s in cls.SPECS:
            if s.name == name:
                return s
        raise ValueError(f"{cls.OWNER}: no parameter {name!r}; known: {', '.join(cls.names())}")

    def scalar(self, name: str) -> float:
        """The value of parameter ``name``, which must not be direction-dependent."""
        raw = getattr(self, name)
        if isinstance(raw, Directional):
            raise ValueError(f"{self.OWNER}: parameter {name} must be one value for both "
                             f"directions here, got {raw}")
        return float(raw)

    def side_values(self, name: str) -> tuple[float, float]:
        """``(value for v > 0, value for v < 0)`` of parameter ``name``."""
        raw = getattr(self, name)
        return raw.values() if isinstance(raw, Directional) else (raw, raw)

    def flat(self) -> dict[str, float]:
        """Flatten to scalar names (``Fc`` or ``Fc_pos``/``Fc_neg``)."""
        out: dict[str, float] = {}
        for s in self.SPECS:
            raw = getattr(self, s.name)
            if isinstance(raw, Directional):
                out[s.name + "_pos"] = raw.pos
                out[s.name + "_neg"] = raw.neg
            else:
                out[s.name] = float(raw)
        return out

    @classmethod
    def from_flat(cls: type[P], values: Mapping[str, float], base: P | None = None) -> P:
        """Inverse of :meth:`flat`; missing names are taken from ``base`` (or defaults)."""
        base = base if base is not None else cls()
        kwargs: dict[str, Any] = {}
        for s in cls.SPECS:
            if s.name + "_pos" in values or s.name + "_neg" in values:
                pos, neg = base.side_values(s.name)
                kwargs[s.name] = Directional(
                    float(values.get(s.name + "_pos", pos)), float(values.get(s.name + "_neg", neg))
                )
            elif s.name in values:
                kwargs[s.name] = float(values[s.name])
            else:
                kwargs[s.name] = getattr(base, s.name)
        unknown = set(values) - {
            k for s in cls.SPECS for k in (s.name, s.name + "_pos", s.name + "_neg")
        }
        if unknown:
            raise ValueError(
                f"{cls.OWNER}: unknown parameter(s) {', '.join(sorted(unknown))}; "
                f"known: {', '.join(cls.names())}"
            )
        return cls(**kwargs)

    def replace(self: P, **changes: Any) -> P:
        """A copy with some parameters changed (validated)."""
        return dataclasses.replace(self, **changes)  # type: ignore[type-var]

    def is_directional(self) -> bool:
        return any(isinstance(getattr(self, s.name), Directional) for s in self.SPECS)

    def describe(self) -> list[tuple[str, str, str, str]]:
        """Rows ``(name, value, unit, meaning)`` for reports."""
        return [(s.name, str(getattr(self, s.name)), s.unit, s.doc) for s in self.SPECS]


#: Tolerance of the ``UNIT_SUMS`` check.
UNIT_SUM_TOL = 1e-9


def make_params_class(
    cls_name: str,
    specs: Iterable[ParamSpec],
    *,
    owner: str,
    constraints: Iterable[tuple[str, str]] = (),
    unit_sums: Iterable[tuple[tuple[str, ...], str]] = (),
    doc: str = "",
    module: str | None = None,
) -> type[ParamSet]:
    """Build a frozen dataclass (subclass of :class:`ParamSet`) from ``specs``.

    Fields default to each spec's default and are typed ``float``, or
    ``float | Directional`` where the spec allows direction-dependent values.
    Constraints name pairs ``(small, large)`` that must satisfy ``small <=
    large`` (e.g. ``("Fc", "Fs")``); pairs naming a parameter the class does not
    have are ignored. ``unit_sums``: groups of names whose values must sum to
    1, each with the reason (``ParamSet.UNIT_SUMS``).

    The class belongs to ``module`` (default: the calling module) under the
    name ``cls_name``: bind it to that name there (or make it in a class body,
    :func:`adopt_params`), or give it a recipe (:func:`with_recipe`) when a
    factory makes it.
    """
    specs = tuple(specs)
    names = {s.name for s in specs}
    fields = [(s.name, float | Directional if s.directional else float,
               dataclasses.field(default=s.default)) for s in specs]
    ns = {
        "SPECS": specs,
        "CONSTRAINTS": tuple((a, b) for a, b in constraints if a in names and b in names),
        "UNIT_SUMS": tuple((tuple(g), why) for g, why in unit_sums),
        "OWNER": owner,
        "__doc__": doc
        or f"Parameters of {owner} (SI units).\n\n"
        + "\n".join(f"{s.name} [{s.unit}]: {s.doc} (default {s.default:g})" for s in specs),
    }
    cls = dataclasses.make_dataclass(cls_name, fields, bases=(ParamSet,), frozen=True, namespace=ns)
    cls.__module__ = module or sys._getframe(1).f_globals.get("__name__", __name__)
    cls.__qualname__ = cls_name
    return cls


class ParamValues:
    """The view of a flat parameter mapping that model equations read.

    ``P("Fc", s)`` is the value of ``Fc`` for side ``s`` (``s > 0``: the
    ``v > 0`` value). Values may be floats, numpy arrays or CasADi symbols.
    """

    def __init__(self, values: Mapping[str, Any], be: Backend) -> None:
        self.values = values
        self.be = be

    def __call__(self, name: str, side: Any = 1.0) -> Any:
        if name in self.values:
            return self.values[name]
        try:
            pos, neg = self.values[name + "_pos"], self.values[name + "_neg"]
        except KeyError:
            raise ValueError(f"parameter {name!r} is not defined") from None
        return self.be.if_else(side > 0, pos, neg)

    def has(self, name: str) -> bool:
        return name in self.values or name + "_pos" in self.values

    @classmethod
    def symbolic(cls, names: Iterable[str], label: str = "p") -> tuple[Any, ParamValues]:
        """A CasADi symbol vector for the flat parameters ``names`` and its view.

        Used wherever parameters are function *inputs* (compiled loops,
        sensitivities, symbolic plant and model functions).
        """
        import casadi as ca

        from fcomp.backend import CASADI

        names = list(names)
        p = ca.SX.sym(label, len(names))
        return p, cls({n: p[i] for i, n in enumerate(names)}, CASADI)
