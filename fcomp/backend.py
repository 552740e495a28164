"""Math backends: the small namespace every model equation is written against.

Each friction model writes its equations *once* as Python functions that take
a backend ``be`` as first argument and only use ``be.exp``, ``be.abs``,
``be.if_else``, ... . Called with :data:`NUMPY` they evaluate numbers (fast
simulation, fitting); called with :data:`CASADI` they build CasADi ``SX``
expressions (exact Jacobians for the EKF, prediction models for MPC,
gradients for identification). Tests check that the two agree.

The two backends have the same attribute names and the same semantics:

========== ===========================================================
name        meaning
========== ===========================================================
exp, log    natural exponential / logarithm
sqrt        square root
abs, sign   absolute value; sign with ``sign(0) = 0``
fmin, fmax  element-wise minimum / maximum
power       ``power(a, b) = a**b``
tanh        hyperbolic tangent
if_else     ``if_else(c, a, b)``: ``a`` where ``c`` is true, else ``b``
========== ===========================================================
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np


def _np_if_else(cond: Any, a: Any, b: Any) -> Any:
    out = np.where(cond, a, b)
    return out if np.ndim(out) else float(out)


def _np_sign(a: Any) -> Any:
    out = np.sign(a)
    return out if np.ndim(out) else float(out)


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
)

BACKENDS: dict[str, Backend] = {"numpy": NUMPY, "casadi": CASADI}


def get_backend(name: str) -> Backend:
    """Return the backend called ``name`` (``"numpy"`` or ``"casadi"``)."""
    try:
        return BACKENDS[name]
    except KeyError:
        raise ValueError(f"unknown backend {name!r}; choose one of {sorted(BACKENDS)}") from None
