"""Generalized Maxwell-slip (GMS) friction, continuous-state form (models.md 1.7).

Al-Bender, Lampaert and Swevers (IEEE TAC 50(11), 2005, "The generalized
Maxwell-slip model: a novel model for friction simulation and compensation")
model friction as ``N`` elasto-slide elements in parallel, all driven by the
same displacement: element ``i`` is a spring of stiffness ``k_i`` that sticks
until its force reaches its slip force ``alpha_i*g(v)`` and then slides. The
parallel connection gives *nonlocal memory*: after a reversal the elements
with small slip displacement ``alpha_i*g/k_i`` slip first and the stiff
initial slope softens element by element, and a minor loop only rewrites the
elements it made slip, so the force returns (approximately) to its value at
the earlier reversal point (return-point memory).

The original switches each element between stick (``dF_i/dt = k_i*v``) and
slip (a LuGre-like relaxation towards ``sign(v)*alpha_i*s(v)``), a hybrid
model. Here each element instead obeys one continuous LuGre-type (Dahl)
state equation for its deflection ``z_i`` (the "multi-state LuGre" reading of
GMS), so the model is smooth, symbolic (one set of equations for numpy and
CasADi) and exactly integrated by :mod:`fcomp.trajectory` (linear in ``z_i``
at fixed ``v``)::

    dz_i/dt = v - |v| * k_i*z_i / (alpha_i*g(v))          i = 1..N
    F = sum_i k_i*z_i + sigma1*sum_i dz_i/dt + sigma2*v
    g(v) = Fc + (Fs - Fc)*exp(-(|v|/vs)^n)                (Stribeck curve, models.md 1.3)

Each element is a Dahl/LuGre bristle with stiffness ``k_i`` and level
``alpha_i*g``: it behaves elastically (``dF_i/dx = k_i``) while
``|k_i*z_i| << alpha_i*g`` and saturates at ``sign(v)*alpha_i*g``. At constant
velocity ``k_i*z_i = sign(v)*alpha_i*g(v)``, so with ``sum(alpha_i) = 1``
(validated) the steady-state map is the Stribeck curve
``F_ss = sign(v)*g(v) + sigma2*v``. Return-point memory is approximate: a
Dahl element is stiffer after a reversal from saturation (``k_i*(1 + r)``,
``r = k_i*z_i/(alpha_i*g)``) than before it, so small loops near saturation
do not close. On nested loops with ``Fs = 1`` N the default GMS stays within
about 0.17 N rms of the ideal Maxwell-slip model (elasto-plastic elements,
exact return-point memory), against 0.28 N for a one-state LuGre of the
same stiffness (``tests/test_gms.py``).

Defaults (``N = 4``): ``alpha_i = i/10`` (0.1 .. 0.4) and
``k_i = 1e5*(N + 1 - i)/10`` N/m (4e4 .. 1e4), i.e. the total initial
stiffness ``sum k_i = 1e5`` N/m of the default LuGre bristle and slip
displacements ``alpha_i*Fs/k_i`` from 3.75 um to 60 um, spread over a decade
so that the virgin curve is smooth. :func:`gms_class` builds other ``N``.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any, ClassVar

from fcomp.backend import Backend
from fcomp.models.base import FrictionModel, Signals
from fcomp.models.lugre_family import FAMILY_SPECS, PRESETS, LuGreFamily
from fcomp.parameters import (
    ParamSet,
    ParamValues,
    make_params_class,
    spec,
    with_recipe,
)

INF = math.inf



@cache
def _stribeck_model() -> LuGreFamily:
    """The family's ``stribeck`` model, whose ``g(v, h)`` GMS evaluates with ``h = 0``."""
    return PRESETS["stribeck"]()


def gms_params_class(n: int) -> type[ParamSet]:
    """The frozen parameter class of a GMS model with ``n`` elements (``k1..kn``,
    ``alpha1..alphan``, which sum to 1); cached, pickles by its recipe."""
    return _gms_params_class(n)


@cache
def _gms_params_class(n: int) -> type[ParamSet]:
    if not (isinstance(n, int) and n >= 1):
        raise ValueError(f"gms: the number of elements must be an integer >= 1, got {n!r}")
    total = n * (n + 1) / 2
    owner = "gms" if n == 4 else f"gms (N={n})"
    specs = [FAMILY_SPECS[name] for name in ("Fc", "Fs", "vs", "n", "sigma1", "sigma2")]
    specs += [spec(f"k{i}", "N/m", 1e5 * (n + 1 - i) / total, 0.0, INF,
                   f"stiffness of element {i}", lower_open=True, directional=False)
              for i in range(1, n + 1)]
    specs += [spec(f"alpha{i}", "-", i / total, 0.0, 1.0,
                   f"slip-force fraction of element {i} (sum of all alpha = 1)",
                   lower_open=True, directional=False)
              for i in range(1, n + 1)]
    alphas = tuple(f"alpha{i}" for i in range(1, n + 1))
    cls = make_params_class(
        "GMSParams" if n == 4 else f"GMS{n}Params", specs, owner=owner,
        constraints=[("Fc", "Fs")], module=__name__,
        unit_sums=[(alphas, "the slip forces alpha_i*g(v) add up to the Stribeck curve g(v)")])
    return with_recipe(cls, _gms_params_class, n)


class GMSModel(FrictionModel):
    """Generalized Maxwell-slip friction with LuGre-type elements (module docstring).

    Class attribute ``n_elements`` fixes ``N``; use :func:`gms_class` for other ``N``.
    """

    n_elements: ClassVar[int] = 4

    def g(self, be: Backend, v: Any, P: ParamValues, L: dict, s: Any) -> Any:
        """Stribeck curve ``g(v) = Fc + (Fs - Fc)*exp(-(|v|/vs)^n)`` (N), the family's."""
        return _stribeck_model().g(be, v, 0.0, P, L, s)

    def _k_alpha(self, P: ParamValues) -> list[tuple[Any, Any]]:
        return [(P(f"k{i}"), P(f"alpha{i}")) for i in range(1, self.n_elements + 1)]

    def base_rhs(self, be: Backend, x: list[Any], sig: Signals, P: ParamValues, L: dict) -> list:
        """``dz_i/dt = v - |v|*k_i*z_i/(alpha_i*g(v))``."""
        v = sig.v
        g = self.g(be, v, P, L, sig.s)
        return [v - be.abs(v) * k * zi / (al * g)
                for zi, (k, al) in zip(x, self._k_alpha(P), strict=True)]

    def base_force(
        self, be: Backend, x: list[Any], dx: list[Any], sig: Signals, P: ParamValues, L: dict
    ) -> tuple[Any, Any]:
        """``F = sum k_i*z_i + sigma1*sum dz_i/dt + sigma2*v`` (``c_a = 0``)."""
        F = P("sigma2", sig.s) * sig.v
        for zi, dzi, (k, _) in zip(x, dx, self._k_alpha(P), strict=True):
            F = F + k * zi + P("sigma1") * dzi
        return F, 0.0

    def base_steady_state(self, be: Backend, sig: Signals, P: ParamValues, L: dict) -> list:
        """``z_i = sign(v)*alpha_i*g(v)/k_i``."""
        sg = be.sign(sig.v) * self.g(be, sig.v, P, L, sig.s)
        return [sg * al / k for k, al in self._k_alpha(P)]

    def passivity(self) -> dict[str, Any]:
        """Dissipativity of ``v -> sum(k_i*z_i + sigma1*dz_i/dt)``.

        Per element, with storage ``k_i*z_i^2/2`` and ``a_i = k_i*|v|/(alpha_i*g)``,
        the supply minus storage rate is ``k_i*a_i*z_i^2 + sigma1*dz_i^2 +
        sigma1*a_i*z_i*dz_i``, non-negative for every state iff
        ``sigma1*a_i <= 4*k_i``, i.e. ``|v| <= 4*alpha_i*g/sigma1``. Since
        ``g >= Fc`` the map is dissipative for ``|v| <= 4*min(alpha_i)*Fc/sigma1``
        (as for LuGre, passivity above that speed is not guaranteed: flagged).
        """
        p = self.params
        sigma1 = p.scalar("sigma1")
        if sigma1 == 0.0:
            return {"applies": True, "passive": True, "v_max": INF,
                    "reason": "no bristle damping: dissipative for every velocity"}
        amin = min(getattr(p, f"alpha{i}") for i in range(1, self.n_elements + 1))
        vmax = 4.0 * amin * min(p.side_values("Fc")) / sigma1
        return {"applies": True, "passive": None, "v_max": vmax,
                "reason": f"dissipative for |v| <= 4*min(alpha)*Fc/sigma1 = {vmax:.3g} m/s; "
                "beyond that the damping can return energy (flagged)"}


def _element_states(n: int) -> tuple[str, ...]:
    return tuple(f"z{i}" for i in range(1, n + 1))


class GMS(GMSModel):
    """Generalized Maxwell-slip friction with 4 elements (models.md 1.7; Al-Bender,
    Lampaert, Swevers 2005): the registered ``gms``."""

    name = "gms"
    n_elements = 4
    Params = gms_params_class(4)
    base_states = _element_states(4)


GMSParams = GMS.Params


def gms_class(n: int) -> type[GMSModel]:
    """The GMS model class with ``n`` elements (``n = 4`` is the registered :class:`GMS`;
    others are made here, cached, and pickle by their recipe)."""
    return _gms_class(n)


@cache
def _gms_class(n: int) -> type[GMSModel]:
    params = gms_params_class(n)
    if n == 4:
        return GMS
    made = type(f"GMS{n}", (GMSModel,), {
        "name": f"gms{n}",
        "n_elements": n,
        "Params": params,
        "base_states": _element_states(n),
        "__doc__": f"Generalized Maxwell-slip friction with {n} elements (models.md 1.7; "
                   "Al-Bender, Lampaert, Swevers 2005).",
        "__module__": __name__,
    })
    return with_recipe(made, _gms_class, n)
