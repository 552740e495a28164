"""Math backends: the small namespace every model equation is written against.

Each friction model writes its equations *once* as Python functions that take
a backend ``be`` as first argument and only use ``be.exp``, ``be.abs``,
``be.if_else``, ... . Called with :data:`NUMPY` they evaluate numbers (fast
simulation, fitting); called with :data:`CASADI` they build CasADi ``SX``
expressions (exact Jacobians for the EKF, prediction models for MPC,
gradients for identification). Tests check that the two agree.

The two backends have the same attribute names and the same semantics:

=================== ==================================================
name                 meaning
=================== ==================================================
exp, log             natural exponential / logarithm
log10, log1p, expm1  ``log10(a)``, ``log(1 + a)``, ``exp(a) - 1``
sqrt                 square root
abs, sign            absolute value; sign with ``sign(0) = 0``
copysign             ``copysign(a, b)``: ``|a|`` with the sign of ``b``
fmin, fmax           element-wise minimum / maximum
power                ``power(a, b) = a**b``
hypot                ``sqrt(a**2 + b**2)`` without overflow
sin, cos, tan        trigonometric functions (radians)
asin, acos, atan     their inverses
atan2                ``atan2(y, x)``, the angle of the point ``(x, y)``
sinh, cosh, tanh     hyperbolic functions
asinh, acosh, atanh  their inverses
erf                  the error function
floor, ceil          rounding down / up (derivative zero almost everywhere)
fmod                 ``fmod(a, b)``: remainder of ``a/b`` with the sign of ``a``
if_else              ``if_else(c, a, b)``: ``a`` where ``c`` is true, else ``b``
pi                   the number pi (a constant)
=================== ==================================================

A user's own effect (docs/effects.md) uses exactly these: a cogging force
``A*sin(2*pi*x/period)`` is ``P.A * be.sin(2 * be.pi * sig.x / P.period)``.
:data:`FUNCTIONS` lists the function names.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from scipy import special


def _np_if_else(cond: Any, a: Any, b: Any) -> Any:
    out = np.where(cond, a, b)
    return out if np.ndim(out) else float(out)


def _np_sign(a: Any) -> Any:
    out = np.sign(a)
    return out if np.ndim(out) else float(out)


#: The elementary functions every backend has (the module docstring's table, less
#: ``if_else`` and the constant ``pi``).
FUNCTIONS: tuple[str, ...] = (
    "exp", "log", "log10", "log1p", "expm1", "sqrt", "abs", "sign", "copysign", "fmin", "fmax",
    "power", "hypot", "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh",
    "tanh", "asinh", "acosh", "atanh", "erf", "floor", "ceil", "fmod",
)


@dataclass(frozen=True)
class Backend:
    """A namespace of elementary functions (see the module docstring)."""

    name: str
    symbolic: bool
    exp: Callable[[Any], Any]
    log: Callable[[Any], Any]
    sqrt: Callable[[Any], Any]
    abs: Callable[[Any], Any]
    sign: Callable[[Any], Any]
    fmin: Callable[[Any, Any], Any]
    fmax: Callable[[Any, Any], Any]
    power: Callable[[Any, Any], Any]
    tanh: Callable[[Any], Any]
    if_else: Callable[[Any, Any, Any], Any]
    log10: Callable[[Any], Any]
    log1p: Callable[[Any], Any]
    expm1: Callable[[Any], Any]
    copysign: Callable[[Any, Any], Any]
    hypot: Callable[[Any, Any], Any]
    sin: Callable[[Any], Any]
    cos: Callable[[Any], Any]
    tan: Callable[[Any], Any]
    asin: Callable[[Any], Any]
    acos: Callable[[Any], Any]
    atan: Callable[[Any], Any]
    atan2: Callable[[Any, Any], Any]
    sinh: Callable[[Any], Any]
    cosh: Callable[[Any], Any]
    asinh: Callable[[Any], Any]
    acosh: Callable[[Any], Any]
    atanh: Callable[[Any], Any]
    erf: Callable[[Any], Any]
    floor: Callable[[Any], Any]
    ceil: Callable[[Any], Any]
    fmod: Callable[[Any, Any], Any]
    pi: float = float(np.pi)

    def __getattr__(self, name: str) -> Any:  # only for names it does not have
        if name.startswith("__"):
            raise AttributeError(name)
        raise AttributeError(f"the backend has no function {name!r}; equations may use "
                             f"{', '.join(FUNCTIONS)}, if_else and the constant pi "
                             "(fcomp.backend)")


NUMPY = Backend(
    name="numpy",
    symbolic=False,
    exp=np.exp,
    log=np.log,
    sqrt=np.sqrt,
    abs=np.abs,
    sign=_np_sign,
    fmin=np.minimum,
    fmax=np.maximum,
    power=np.power,
    tanh=np.tanh,
    if_else=_np_if_else,
    log10=np.log10,
    log1p=np.log1p,
    expm1=np.expm1,
    copysign=np.copysign,
    hypot=np.hypot,
    sin=np.sin,
    cos=np.cos,
    tan=np.tan,
    asin=np.arcsin,
    acos=np.arccos,
    atan=np.arctan,
    atan2=np.arctan2,
    sinh=np.sinh,
    cosh=np.cosh,
    asinh=np.arcsinh,
    acosh=np.arccosh,
    atanh=np.arctanh,
    erf=special.erf,
    floor=np.floor,
    ceil=np.ceil,
    fmod=np.fmod,
)

CASADI = Backend(
    name="casadi",
    symbolic=True,
    exp=ca.exp,
    log=ca.log,
    sqrt=ca.sqrt,
    abs=ca.fabs,
    sign=ca.sign,
    fmin=ca.fmin,
    fmax=ca.fmax,
    power=ca.power,
    tanh=ca.tanh,
    if_else=lambda c, a, b: ca.if_else(c, a, b),
    log10=ca.log10,
    log1p=ca.log1p,
    expm1=ca.expm1,
    copysign=ca.copysign,
    hypot=ca.hypot,
    sin=ca.sin,
    cos=ca.cos,
    tan=ca.tan,
    asin=ca.asin,
    acos=ca.acos,
    atan=ca.atan,
    atan2=ca.atan2,
    sinh=ca.sinh,
    cosh=ca.cosh,
    asinh=ca.asinh,
    acosh=ca.acosh,
    atanh=ca.atanh,
    erf=ca.erf,
    floor=ca.floor,
    ceil=ca.ceil,
    fmod=ca.fmod,
)

BACKENDS: dict[str, Backend] = {"numpy": NUMPY, "casadi": CASADI}


def get_backend(name: str) -> Backend:
    """Return the backend called ``name`` (``"numpy"`` or ``"casadi"``)."""
    try:
        return BACKENDS[name]
    except KeyError:
        raise ValueError(f"unknown backend {name!r}; choose one of {sorted(BACKENDS)}") from None
