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
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar

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


class ParamSet:
    """Base of every parameter dataclass (made by :func:`make_params_class`).

    Subclasses are frozen dataclasses whose fields are the parameters; the
    class attribute ``SPECS`` holds their :class:`ParamSpec`. Construction
    validates bounds and the cross-constraints in ``CONSTRAINTS``
    (pairs ``(small, large)`` meaning ``small <= large`` on each side).
    """

    SPECS: ClassVar[tuple[ParamSpec, ...]] = ()
    CONSTRAINTS: ClassVar[tuple[tuple[str, str], ...]] = ()
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


def make_params_class(
    cls_name: str,
    specs: Iterable[ParamSpec],
    *,
    owner: str,
    constraints: Iterable[tuple[str, str]] = (),
    doc: str = "",
) -> type[ParamSet]:
    """Build a frozen dataclass (subclass of :class:`ParamSet`) from ``specs``.

    Fields default to each spec's default. Constraints name pairs
    ``(small, large)`` that must satisfy ``small <= large`` (e.g. ``("Fc", "Fs")``);
    pairs naming a parameter the class does not have are ignored.
    """
    specs = tuple(specs)
    names = {s.name for s in specs}
    fields = [(s.name, Any, dataclasses.field(default=s.default)) for s in specs]
    ns = {
        "SPECS": specs,
        "CONSTRAINTS": tuple((a, b) for a, b in constraints if a in names and b in names),
        "OWNER": owner,
        "__doc__": doc
        or f"Parameters of {owner} (SI units).\n\n"
        + "\n".join(f"{s.name} [{s.unit}]: {s.doc} (default {s.default:g})" for s in specs),
    }
    cls = dataclasses.make_dataclass(cls_name, fields, bases=(ParamSet,), frozen=True, namespace=ns)
    cls.__module__ = "fcomp.parameters"
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
