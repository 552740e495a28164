"""The LuGre family: Coulomb, Coulomb-viscous, Stribeck, Dahl, LuGre, modified LuGre, NMLGM.

All seven models are one set of equations (models.md sections 1.1-1.5) with
*features* switched on or off, written once here:

==============  ==========================================================
feature          term
==============  ==========================================================
``viscous``      ``sigma2*v`` (``B*v`` for ``coulomb-viscous``, seed 001 Eq. 4)
``stribeck``     ``g = Fc + ((1 - h)*Fs - Fc)*exp(-(|v|/vs)^n)`` (seed 002 Eq. 7)
``presliding``   bristle state ``z``: ``dz/dt = v - sigma0*|v|*z/g`` (LuGre, Dahl)
``damping``      ``sigma1*dz/dt`` (LuGre; absent in Dahl)
``film``         film term ``h`` with ``h_ss = (1 - Fc/Fs)*min(|v|/vb, 1)^(2/3)``
                 (seed 002 Eqs. 10-11, ``Kf*min(|v|, vb)^(2/3)`` rewritten)
``film-lag``     ``h`` is a state: ``dh/dt = (h_ss - h)/tau_h`` (seed 002 Eqs. 8-9);
                 without it ``h = h_ss`` (the steady-state model, seed 002 Eq. 12)
``lead``         ``sigma2*(v + T*dv/dt)`` (NMLGM, seed 000 Eq. 8, seed 002 Eq. 6)
``elements``     the bristle split into :data:`ELEMENTS` Maxwell-slip elements
                 (nonlocal memory, models.md 1.7-1.8; below)
``stribeck-      the curve's form: ``exp(-r^n)`` becomes the q-exponential
form``           ``(1 + kappa_s*r^n)^(-1/kappa_s)``, ``r = |v|/vs``: ``kappa_s -> 0``
                 the exponential, ``kappa_s = 1`` the rational ``1/(1 + r^n)``
                 (Hess & Soom 1990's Lorentzian for ``n = 2``), a fatter tail between
``speed-lag``    state ``vL``: ``dvL/dt = (|v| - vL)/tau_L``; the Stribeck curve is
                 evaluated at ``|v| + w_L*(vL - |v|)`` (Hess & Soom 1990's frictional
                 lag: the curve follows the speed late; ``w_L = 0`` no lag, 1 the
                 lagged speed alone). The steady-state map is unchanged.
``viscous-       ``sigma2*v*(|v|/v_ref)^(p_visc - 1)``: a power law of the speed
power``          (a shear-thinning or -thickening film), ``sigma2`` its slope at
                 ``v_ref`` (fixed); ``p_visc = 1`` is the linear term
``bristle-       Dahl's exponent ``i_pre``: ``dz/dt = v*|1 - u|^i*sign(1 - u)``,
exponent``       ``u = sigma0*sign(v)*z/g`` (Dahl 1976; ``i = 1`` is LuGre's bristle,
                 ``i > 1`` a softer approach to sliding, ``i < 1`` stiffer until
                 close to it, towards the elasto-plastic bristle of Dupont et al. 2002)
``bristle-       the elasto-plastic bristle (Dupont, Hayward, Armstrong & Altpeter
break``          2002): below a break-away deflection ``u <= ba_pre`` (and whenever
                 ``z`` and ``v`` have opposite signs) the bristle is purely elastic,
                 ``dz/dt = v``; above, the bristle law acts on ``w = (u - ba)/(1 - ba)``
                 in place of ``u``. Even at ``ba_pre = 0`` it unloads as a spring
                 after a reversal (LuGre's bristle unloads faster).
==============  ==========================================================

Maxwell-slip elements (``elements``, nonlocal memory). A share ``s =
ms_share`` of the level is carried by ``N`` (:data:`ELEMENTS`) elasto-slide
elements in parallel with the bristle (classical Maxwell-slip, Lampaert,
Al-Bender & Swevers 2002; models.md 1.7-1.8). Element ``i`` is a spring of
stiffness ``k_i = s*alpha_i*Fc/d_i`` whose deflection ``delta_i`` follows the
displacement until its force reaches its slip force ``s*alpha_i*g`` (deflection
``d_i*g/Fc``), and slides there::

    delta_i <- clip(delta_i + dx, -d_i*g/Fc, d_i*g/Fc)          (each step: exact)
    F = (1 - s)*(sigma0*z + sigma1*dz/dt) + sum(k_i*delta_i) + sigma2*(v + T*a)

with the bristle ``z`` as in LuGre (it carries ``(1 - s)*g``). Slip
displacements ``d_i = ms_dmax*rho^(u_i - 1)``, ``u_i = (i - 1)/(N - 1)``,
spread over ``rho = ms_spread`` up to ``ms_dmax``; level shares ``alpha_i``
proportional to ``rho^(beta*u_i)`` (``beta = ms_shape``), summing to 1. After
a reversal the stiff elements slip first and the force-displacement curve
softens element by element; a minor loop rewrites only the elements it made
slip, so the force returns exactly to its value at the earlier reversal
point (return-point memory, wiping-out) -- the nonlocal memory the single
bristle lacks. ``ms_share = 0`` (the default) is the bristle alone: a no-op.

The clip is the model's *projection* (:meth:`LuGreFamily.base_project`),
applied after every step of the sampled engine, where the deflection rate
is ``v`` inside the band, so each step is exact for a held velocity; in the
continuous right-hand side (plants) a deflection outside the band relaxes
onto it over ``d_i`` of travel.

Structural effects (:mod:`fcomp.effects.structural`: ``stribeck``,
``presliding``, ...) switch features on through one public method,
:meth:`LuGreFamily.with_structure`, given a :class:`Structure` (the
features, the values of their parameters); the family makes the class.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from typing import Any, ClassVar

from fcomp.backend import Backend
from fcomp.models.base import FrictionModel, Signals
from fcomp.parameters import ParamSet, ParamSpec, ParamValues, make_params_class, spec, with_recipe

INF = math.inf
_TINY = 1e-30

#: Every parameter of the family, once (models.md names, SI units).
FAMILY_SPECS: dict[str, ParamSpec] = {
    s.name: s
    for s in (
        spec("Fc", "N", 1.0, 0.0, INF, "Coulomb friction level"),
        spec("B", "Ns/m", 0.0, 0.0, INF, "viscous coefficient (coulomb-viscous, seed 001)"),
        spec("Fs", "N", 1.5, 0.0, INF, "static (break-away) friction level, Fs >= Fc"),
        spec("vs", "m/s", 1e-3, 0.0, INF, "Stribeck velocity", lower_open=True),
        spec("n", "-", 2.0, 0.0, 10.0, "Stribeck exponent", lower_open=True),
        spec("sigma2", "Ns/m", 0.4, 0.0, INF, "viscous (fluid) friction coefficient"),
        spec("sigma0", "N/m", 1e5, 0.0, INF, "bristle stiffness", lower_open=True,
             directional=False),
        spec("sigma1", "Ns/m", 316.2277660, 0.0, INF, "bristle damping", directional=False),
        spec("vb", "m/s", 0.03, 0.0, INF, "velocity up to which the film thickens "
             "(inf: no film effect)", lower_open=True),
        spec("tau_hp", "s", 0.02, 0.0, INF, "film time constant, acceleration",
             lower_open=True, directional=False),
        spec("tau_hn", "s", 0.12, 0.0, INF, "film time constant, deceleration",
             lower_open=True, directional=False),
        spec("tau_h0", "s", 10.0, 0.0, INF, "film time constant, dwell",
             lower_open=True, directional=False),
        spec("T", "s", 0.0, 0.0, INF, "time constant of the fluid-friction lead",
             directional=False),
        spec("v_eps", "m/s", 1e-5, 0.0, INF, "velocity treated as zero (dwell detection, "
             "static-map regularisation)", lower_open=True, directional=False),
        spec("p_visc", "-", 1.0, 0.2, 2.0, "viscous exponent: the term is "
             "visc*v*(|v|/v_ref)^(p_visc - 1) (1: linear, < 1 a shear-thinning film)",
             directional=False),
        spec("v_ref", "m/s", 0.05, 0.0, INF, "reference speed of the viscous exponent "
             "(fixed: visc is the slope there)", lower_open=True, directional=False),
        spec("tau_L", "s", 0.05, 0.0, INF, "time constant of the lagged speed the Stribeck "
             "curve follows (Hess-Soom frictional lag)", lower_open=True, directional=False),
        spec("w_L", "-", 0.0, 0.0, 1.0, "share of the lag in the speed the curve follows "
             "(0: none, 1: the lagged speed alone)", directional=False),
        spec("kappa_s", "-", 0.0, 0.0, 1.0, "Stribeck curve form: 0 the exponential "
             "exp(-r^n), 1 the rational 1/(1 + r^n), between the q-exponential",
             directional=False),
        spec("i_pre", "-", 1.0, 0.2, 4.0, "bristle exponent: 1 LuGre, > 1 softer (Dahl i), "
             "< 1 stiffer until near slip (elasto-plastic)", directional=False),
        spec("ba_pre", "-", 0.0, 0.0, 0.95, "break-away deflection of the bristle as a share "
             "of its steady one: purely elastic below (elasto-plastic, Dupont 2002; 0: none)",
             directional=False),
        spec("ms_share", "-", 0.0, 0.0, 1.0, "Maxwell-slip elements: share of the level they "
             "carry (0: the bristle alone)", directional=False),
        spec("ms_dmax", "m", 1e-4, 0.0, INF, "Maxwell-slip elements: largest slip "
             "displacement (at the Coulomb level)", lower_open=True, directional=False),
        spec("ms_spread", "-", 10.0, 1.0, 1e4, "Maxwell-slip elements: ratio of the largest "
             "to the smallest slip displacement", directional=False),
        spec("ms_shape", "-", 0.0, -3.0, 3.0, "Maxwell-slip elements: exponent of the level "
             "shares (0: equal shares)", directional=False),
        spec("ms_scaling", "-", 0.0, 0.0, 1.0, "Maxwell-slip elements: how the stiffness "
             "follows the slip level (0: constant stiffness, 1: constant slip displacement)",
             directional=False),
    )
}
#: Number of Maxwell-slip elements of the ``elements`` feature.
ELEMENTS = 8

FEATURE_PARAMS: dict[str, tuple[str, ...]] = {
    "viscous": ("sigma2",),
    "stribeck": ("Fs", "vs", "n"),
    "presliding": ("sigma0",),
    "damping": ("sigma1",),
    "film": ("vb",),
    "film-lag": ("tau_hp", "tau_hn", "tau_h0"),
    "lead": ("T",),
    "elements": ("ms_share", "ms_dmax", "ms_spread", "ms_shape", "ms_scaling"),
    "stribeck-form": ("kappa_s",),
    "viscous-power": ("p_visc", "v_ref"),
    "speed-lag": ("tau_L", "w_L"),
    "bristle-exponent": ("i_pre",),
    "bristle-break": ("ba_pre",),
}
FEATURE_ORDER = ("stribeck", "viscous", "presliding", "damping", "film", "film-lag", "lead",
                 "elements", "stribeck-form", "bristle-exponent", "viscous-power", "speed-lag",
                 "bristle-break")


#: Feature -> (the feature it builds on, the message when that is missing).
FEATURE_NEEDS: dict[str, tuple[str, str]] = {
    "film": ("stribeck", "the film term needs the Stribeck term (Fs) to act on"),
    "film-lag": ("film", "film-lag needs the film term"),
    "damping": ("presliding", "bristle damping needs the bristle state (presliding)"),
    "elements": ("presliding", "Maxwell-slip elements split the bristle: they need presliding"),
    "stribeck-form": ("stribeck", "the Stribeck curve form needs the Stribeck term"),
    "viscous-power": ("viscous", "the viscous exponent needs the viscous term"),
    "bristle-exponent": ("presliding", "the bristle exponent needs the bristle (presliding)"),
    "bristle-break": ("presliding", "the bristle's break-away deflection needs the bristle "
                      "(presliding)"),
    "speed-lag": ("stribeck", "the lagged speed needs the Stribeck term it acts on"),
}


def _check_features(features: frozenset[str]) -> None:
    unknown = features - set(FEATURE_PARAMS)
    if unknown:
        raise ValueError(f"unknown model feature(s): {sorted(unknown)}")
    for feature, (needed, why) in FEATURE_NEEDS.items():
        if feature in features and needed not in features:
            raise ValueError(why)


def _param_names(features: frozenset[str], viscous_name: str) -> tuple[str, ...]:
    names = ["Fc"]
    for f in FEATURE_ORDER:
        if f in features:
            names += [viscous_name if p == "sigma2" else p for p in FEATURE_PARAMS[f]]
    if "presliding" not in features or "film" in features:
        names.append("v_eps")
    return tuple(names)


def params_class(
    features: frozenset[str], viscous_name: str = "sigma2", cls_name: str = "", owner: str = ""
) -> type[ParamSet]:
    """The frozen parameter dataclass of a feature set (cached; pickles by its recipe)."""
    return _params_class(frozenset(features), viscous_name, cls_name, owner)


@cache
def _params_class(features: frozenset[str], viscous_name: str, cls_name: str,
                  owner: str) -> type[ParamSet]:
    _check_features(features)
    names = _param_names(features, viscous_name)
    cls = make_params_class(
        cls_name or "Params_" + "_".join(sorted(f.replace("-", "_") for f in features)),
        [FAMILY_SPECS[n] for n in names],
        owner=owner or "model",
        constraints=[("Fc", "Fs")],
        module=__name__,
    )
    return with_recipe(cls, _params_class, features, viscous_name, cls_name, owner)


@dataclass(frozen=True)
class Structure:
    """A term of the family as a structural effect adds it (:meth:`LuGreFamily.with_structure`).

    Attributes
    ----------
    effect
        The name of the effect that adds it (the model's :attr:`~LuGreFamily.lineage`).
    features
        The features it switches on (the table of the module docstring).
    values
        Values of their parameters by flat name; parameters not given keep the
        model's value, new ones their default.
    """

    effect: str
    features: frozenset[str]
    values: Mapping[str, float]

    def apply(self, model: LuGreFamily) -> LuGreFamily:
        """``model`` with :attr:`features` switched on (a term that replaces one of the
        family's terms instead, the hysteresis function of :mod:`fcomp.models.hysteresis`,
        overrides this)."""
        return model._with_features(self.features, self.values)


class LuGreFamily(FrictionModel):
    """One model of the LuGre family, defined by its ``features`` (see module docstring)."""

    features: ClassVar[frozenset[str]] = frozenset()
    viscous_name: ClassVar[str] = "sigma2"

    # ------------------------------------------------------------ structure
    @property
    def base_states(self) -> tuple[str, ...]:  # type: ignore[override]
        st = []
        if "presliding" in self.features:
            st.append("z")
        if "elements" in self.features:
            st += [f"delta{i}" for i in range(1, ELEMENTS + 1)]
        if "film-lag" in self.features:
            st.append("h")
        if "elements" in self.features:
            st.append("eps_g")
        if "speed-lag" in self.features:
            st.append("vL")
        return tuple(st)

    def with_structure(self, term: Structure) -> LuGreFamily:
        """The model with the structural ``term`` an effect adds (:class:`Structure`).

        The one way a term of the family reaches a model: a structural effect
        (:mod:`fcomp.effects.structural`) says which features it switches on
        and the values of their parameters, the family builds the model. The
        result is an instance of the registered model class whose feature set
        matches, so ``lugre`` + ``frictional-lag`` *is* ``modified-lugre``; its
        :attr:`lineage` records the effect after the model it was built from.
        """
        new = term.apply(self)
        new.lineage = (*(self.lineage or (self.name,)), term.effect)
        return new

    def _with_features(self, add: frozenset[str], values: Mapping[str, float]) -> LuGreFamily:
        """The model with more features, new parameters from ``values`` (else defaults)."""
        features = frozenset(self.features | add)
        cls = family_class(features, self.viscous_name)
        flat = dict(self.params.flat())
        flat.update(values)
        keep = set(cls.Params.names())
        flat = {k: v for k, v in flat.items() if k.removesuffix("_pos").removesuffix("_neg") in keep}
        return cls(cls.Params.from_flat(flat), effects=self.effects)

    #: the model and the effects it was built from, in order (:meth:`describe`)
    lineage: tuple[str, ...] = ()

    def feature_family(self) -> LuGreFamily:
        """The model itself: structural effects extend it (:meth:`with_structure`)."""
        return self

    @property
    def static_map(self) -> bool:
        """Without the bristle state (``presliding``) the model is a memoryless map."""
        return "presliding" not in self.features

    def describe(self) -> str:
        base = self.name if not self.lineage else self.lineage[0]
        parts = [base, *self.lineage[1:]] if self.lineage else [self.name]
        return " + ".join(parts + [e.name for e in self.effects])

    # ------------------------------------------------------------- equations
    def _stribeck_decay(self, be: Backend, v: Any, P: ParamValues, s: Any) -> Any:
        """``exp(-r^n)``, ``r = |v|/vs``; with ``stribeck-form`` the q-exponential
        ``(1 + kappa*r^n)^(-1/kappa)`` (``kappa -> 0``: the exponential, 1: rational)."""
        vs, n = P("vs", s), P("n", s)
        rn = be.power(be.fmax(be.abs(v) / vs, _TINY), n)
        if "stribeck-form" not in self.features:
            return be.exp(-rn)
        kappa = P("kappa_s")
        q = be.power(1.0 + be.fmax(kappa, 1e-6) * rn, -1.0 / be.fmax(kappa, 1e-6))
        return be.if_else(kappa < 1e-6, be.exp(-rn), q)

    def _curve_speed(self, be: Backend, x: list[Any], v: Any, P: ParamValues) -> Any:
        """The speed the Stribeck curve follows: ``|v|``, or with ``speed-lag`` the blend
        ``|v| + w_L*(vL - |v|)`` of the lagged speed."""
        if "speed-lag" not in self.features:
            return v
        vL = x[self.base_states.index("vL")]
        return be.abs(v) + P("w_L") * (vL - be.abs(v))

    def g(self, be: Backend, v: Any, h: Any, P: ParamValues, L: dict, s: Any) -> Any:
        """Stribeck function ``g(v, h) = Fc + ((1 - h)*Fs - Fc)*exp(-(|v|/vs)^n)`` (N)."""
        Fc = L["Fc"]
        if "stribeck" not in self.features:
            return Fc
        Fs = L["Fs"]
        return Fc + ((1.0 - h) * Fs - Fc) * self._stribeck_decay(be, v, P, s)

    def h_ss(self, be: Backend, v: Any, P: ParamValues, L: dict, s: Any) -> Any:
        """Steady film ``h_ss = Kf*min(|v|, vb)^(2/3)``, ``Kf = (1 - Fc/Fs)*vb^(-2/3)`` (-)."""
        if "film" not in self.features:
            return 0.0
        r = be.fmin(be.abs(v) / P("vb", s), 1.0)
        return (1.0 - L["Fc"] / L["Fs"]) * be.power(be.fmax(r, _TINY), 2.0 / 3.0)

    def _h(self, x: list[Any], be: Backend, sig: Signals, P: ParamValues, L: dict) -> Any:
        if "film-lag" in self.features:
            return x[self.base_states.index("h")]
        return self.h_ss(be, sig.v, P, L, sig.s)

    def tau_h(self, be: Backend, v: Any, h: Any, hss: Any, P: ParamValues) -> Any:
        """Film time constant (seed 002 Eq. 9): dwell, building or thinning."""
        moving = be.if_else(h <= hss, P("tau_hp"), P("tau_hn"))
        return be.if_else(be.abs(v) < P("v_eps"), P("tau_h0"), moving)

    def _slip_level(self, x: list[Any], L: dict) -> Any:
        """The held slip level ``g_h = Fc*(1 + eps_g)`` of the elements (N)."""
        return L["Fc"] * (1.0 + x[self.base_states.index("eps_g")])

    def _element_law(self, be: Backend, x: list[Any], P: ParamValues, L: dict
                     ) -> list[tuple[Any, Any]]:
        """``(k_i, limit_i)``: stiffness (N/m) and slip deflection (m) of each element.

        ``k_i = s*alpha_i*Fc*(g_h/Fc)^lambda/d_i`` and ``limit_i = d_i*(g_h/Fc)^(1-lambda)``,
        ``lambda = ms_scaling``: the slip force ``k_i*limit_i = s*alpha_i*g_h`` either way.
        """
        ratio = be.fmax(self._slip_level(x, L) / L["Fc"], 1e-9)
        lam, share = P("ms_scaling"), P("ms_share")
        return [(share * al * L["Fc"] * be.power(ratio, lam) / di, di * be.power(ratio, 1.0 - lam))
                for al, di in self._elements(be, P)]

    def _elements(self, be: Backend, P: ParamValues) -> list[tuple[Any, Any]]:
        """``(alpha_i, d_i)`` of the Maxwell-slip elements (module docstring)."""
        rho, beta, dmax = P("ms_spread"), P("ms_shape"), P("ms_dmax")
        u = [i / (ELEMENTS - 1) for i in range(ELEMENTS)]
        a_raw = [be.power(rho, beta * ui) for ui in u]
        a_sum = sum(a_raw[1:], a_raw[0])
        return [(a / a_sum, dmax * be.power(rho, ui - 1.0))
                for a, ui in zip(a_raw, u, strict=True)]

    def _split(self, x: list[Any]) -> tuple[list[Any], list[Any], list[Any]]:
        """States ``(bristle, elements, film)`` as lists (empty where absent)."""
        nz = 1 if "presliding" in self.features else 0
        ne = ELEMENTS if "elements" in self.features else 0
        return x[:nz], x[nz:nz + ne], x[nz + ne:nz + ne + (1 if "film-lag" in self.features else 0)]

    def base_rhs(self, be: Backend, x: list[Any], sig: Signals, P: ParamValues, L: dict) -> list:
        out = []
        v = sig.v
        h = self._h(x, be, sig, P, L)
        z, deltas, _ = self._split(x)
        if z:
            g = self.g(be, self._curve_speed(be, x, v, P), h, P, L, sig.s)
            if self.features & {"bristle-exponent", "bristle-break"}:
                u = 1.0 - self._bristle_w(be, z[0], sig, P, g)
                if "bristle-exponent" in self.features:  # Dahl's exponent (Dahl 1976)
                    out.append(v * be.sign(u) * be.power(be.fmax(be.abs(u), 1e-12), P("i_pre")))
                else:
                    out.append(v * u)
            else:
                out.append(v - P("sigma0") * be.abs(v) * z[0] / g)
            if deltas:
                law = self._element_law(be, x, P, L)
                for d, (_, lim), (_, di) in zip(deltas, law, self._elements(be, P), strict=True):
                    outside = be.abs(d) >= lim
                    outward = d * v > 0
                    relax = -be.abs(v) * (d - be.sign(d) * lim) / di
                    out.append(be.if_else(outside, be.if_else(outward, relax, v), v))
        if "film-lag" in self.features:
            hss = self.h_ss(be, v, P, L, sig.s)
            out.append((hss - h) / self.tau_h(be, v, h, hss, P))
        if "elements" in self.features:  # the slip level follows g over the shortest slip
            eps = x[self.base_states.index("eps_g")]
            d_min = P("ms_dmax") / P("ms_spread")
            out.append((g / L["Fc"] - 1.0 - eps) * be.abs(v) / d_min)
        if "speed-lag" in self.features:
            out.append((be.abs(v) - x[self.base_states.index("vL")]) / P("tau_L"))
        return out

    def _bristle_w(self, be: Backend, z: Any, sig: Signals, P: ParamValues, g: Any) -> Any:
        """``w``, what the bristle law acts on: ``u = sigma0*sign(v)*z/g``, or with a break-away
        deflection ``(u - ba)/(1 - ba)`` above it and 0 below (purely elastic)."""
        u = P("sigma0") * be.sign(sig.v) * z / g
        if "bristle-break" not in self.features:
            return u
        ba = P("ba_pre")
        return be.fmax(u - ba, 0.0) / (1.0 - ba)

    def base_exact_steps(self, be: Backend, x: list[Any], sig: Signals, P: ParamValues,
                         L: dict, h: Any) -> list[Any | None]:
        """The bristle's closed-form step at held velocity (Dahl's exponent, a break-away).

        With ``u = sigma0*s*z/g`` (``s = sign(v)``) and the slid distance ``xi = |v|*t``,
        ``du/dxi = k*(1 - w)^i`` (signed power), ``k = sigma0/g``. Without a break
        ``w = u``; with one, ``du/dxi = k`` (purely elastic) until ``u = ba`` -- a slid
        distance ``(ba - u_0)/k`` -- and then ``w = (u - ba)/(1 - ba)`` with
        ``dw/dxi = k/(1 - ba)*(1 - w)^i``. On the bristle law ``|1 - w|^(1-i)``
        changes linearly in ``xi`` (``1 - w`` keeps its sign): after a slid distance
        ``e``, ``|1 - w_1| = |1 - w_0|*q^(1/(1-i))``, ``q = 1 - (1 - i)*k'*e*|1 - w_0|^(i-1)``,
        ``q <= 0`` (``i < 1``: the steady deflection is reached in finite slip)
        giving ``w_1 = 1``, and ``exp(-k'*e)`` at ``i = 1`` (LuGre). The tangent step
        overshot the steady deflection on a stiff step (hydraulic bristles at 1 kHz:
        by ``1/i - 1`` of the gap, without bound below ``i = 1/2``; past the break
        in one step, by the whole elastic stretch).
        """
        out: list[Any | None] = [None] * len(x)
        z, _, _ = self._split(x)
        if not (z and self.features & {"bristle-exponent", "bristle-break"}):
            return out
        film = self._h(x, be, sig, P, L)
        g = self.g(be, self._curve_speed(be, x, sig.v, P), film, P, L, sig.s)
        s = be.sign(sig.v)
        k = P("sigma0") / g
        xi = be.abs(sig.v) * h
        u0 = k * s * z[0]
        i = P("i_pre") if "bristle-exponent" in self.features else 1.0
        if "bristle-break" in self.features:
            ba = P("ba_pre")
            elastic = be.fmin(be.fmax((ba - u0) / k, 0.0), xi)
            u_e = u0 + k * elastic
            rest = xi - elastic
            w0 = be.fmax(u_e - ba, 0.0) / (1.0 - ba)
            kw = k / (1.0 - ba)
        else:
            ba, u_e, rest, w0, kw = 0.0, u0, xi, u0, k
        r0 = 1.0 - w0
        ar0 = be.fmax(be.abs(r0), 1e-12)
        one = be.abs(1.0 - i) < 1e-6
        safe = be.if_else(one, 1.0, 1.0 - i)
        q = be.fmax(1.0 - safe * kw * rest * be.power(ar0, i - 1.0), 0.0)
        ratio = be.if_else(one, be.exp(-kw * rest), be.power(q, 1.0 / safe))
        w1 = 1.0 - r0 * ratio
        u1 = ba + (1.0 - ba) * w1
        if "bristle-break" in self.features:
            u1 = be.if_else(u_e < ba, u_e, u1)
        out[0] = z[0] + s * (u1 - u0) / k  # at rest (xi = 0) u1 = u0: z is held
        return out

    def base_project(self, be: Backend, x: list[Any], sig: Signals, P: ParamValues,
                     L: dict) -> list:
        """Element deflections clipped to their slip band (:meth:`_element_law`)."""
        if "elements" not in self.features:
            return x
        z, deltas, _ = self._split(x)
        clipped = [be.fmax(-lim, be.fmin(lim, d))
                   for d, (_, lim) in zip(deltas, self._element_law(be, x, P, L), strict=True)]
        return [*z, *clipped, *x[len(z) + len(deltas):]]  # the film and lag states as they are

    def _viscous(self, P: ParamValues, s: Any) -> Any:
        if "viscous" not in self.features:
            return 0.0
        return P(self.viscous_name, s)

    def _viscous_force(self, be: Backend, v: Any, visc: Any, P: ParamValues) -> Any:
        """``visc*v``; with ``viscous-power`` ``visc*v*(|v|/v_ref)^(p_visc - 1)``."""
        if "viscous-power" not in self.features:
            return visc * v
        r = be.fmax(be.abs(v) / P("v_ref"), _TINY)
        return visc * v * be.power(r, P("p_visc") - 1.0)

    def base_force(
        self, be: Backend, x: list[Any], dx: list[Any], sig: Signals, P: ParamValues, L: dict
    ) -> tuple[Any, Any]:
        v = sig.v
        visc = self._viscous(P, sig.s)
        c_a = visc * P("T") if "lead" in self.features else 0.0
        if "presliding" in self.features:
            F0 = P("sigma0") * x[0]
            if "damping" in self.features:
                F0 = F0 + P("sigma1") * dx[0]
            _, deltas, _ = self._split(x)
            if deltas:
                F0 = (1.0 - P("ms_share")) * F0
                for d, (k, _) in zip(deltas, self._element_law(be, x, P, L), strict=True):
                    F0 = F0 + k * d
            return F0 + self._viscous_force(be, v, visc, P), c_a
        h = self._h(x, be, sig, P, L)
        sat = be.fmax(-1.0, be.fmin(1.0, v / P("v_eps")))
        g = self.g(be, self._curve_speed(be, x, v, P), h, P, L, sig.s)
        return sat * g + self._viscous_force(be, v, visc, P), c_a

    def base_steady_state(self, be: Backend, sig: Signals, P: ParamValues, L: dict) -> list:
        v = sig.v
        hss = self.h_ss(be, v, P, L, sig.s)
        out = []
        g_ss = self.g(be, v, hss, P, L, sig.s) if "presliding" in self.features else 0.0
        if "presliding" in self.features:
            out.append(be.sign(v) * g_ss / P("sigma0"))
            if "elements" in self.features:
                ratio = g_ss / L["Fc"]
                lam = P("ms_scaling")
                out += [be.sign(v) * di * be.power(ratio, 1.0 - lam)
                        for _, di in self._elements(be, P)]
        if "film-lag" in self.features:
            out.append(hss)
        if "elements" in self.features:
            out.append(g_ss / L["Fc"] - 1.0)
        if "speed-lag" in self.features:
            out.append(be.abs(v))
        return out

    def base_initial_state(self) -> list[float]:
        return [0.0] * len(self.base_states)

    # ------------------------------------------------------------ passivity
    def passivity(self) -> dict[str, Any]:
        """Dissipativity of the bristle map ``v -> sigma0*z + sigma1*dz/dt`` (LuGre type).

        With the storage ``V = sigma0*z^2/2`` and ``alpha = sigma0*|v|/g(v)``,
        ``v*(sigma0*z + sigma1*dz/dt) - dV/dt = sigma1*dz^2 + sigma1*alpha*z*dz
        + sigma0*alpha*z^2``: a quadratic form in ``(z, dz/dt)`` that is
        non-negative for every state iff ``sigma1*alpha <= 4*sigma0``, i.e.
        ``sigma1*|v| <= 4*g(v)``. Since ``g >= Fc`` the map is dissipative for
        every motion with ``|v| <= v_max = 4*Fc/sigma1``; beyond that speed the
        bristle damping can return energy and the result is flagged
        (``passive: None``). ``sigma2*v`` is dissipative; the NMLGM lead
        ``sigma2*T*dv/dt`` is a mass-like term that stores, not dissipates.
        """
        if "presliding" not in self.features:
            return {"applies": False, "passive": True, "reason": "memoryless monotone map"}
        p = self.params
        sigma1 = p.scalar("sigma1") if "damping" in self.features else 0.0
        gmin = min(p.side_values("Fc"))
        if sigma1 == 0.0:
            return {"applies": True, "passive": True, "v_max": INF,
                    "reason": "no bristle damping: dissipative for every velocity"}
        vmax = 4.0 * gmin / sigma1
        return {
            "applies": True,
            "passive": None,
            "v_max": vmax,
            "reason": f"dissipative for |v| <= 4*Fc/sigma1 = {vmax:.3g} m/s; beyond that "
            "the bristle damping can return energy (flagged)",
        }


def family_class(features: frozenset[str], viscous_name: str = "sigma2") -> type[LuGreFamily]:
    """The model class of a feature set: a registered preset if one matches, else a class
    made here (named after its features; cached, its instances pickle by its recipe)."""
    return _family_class(frozenset(features), viscous_name)


@cache
def _family_class(features: frozenset[str], viscous_name: str) -> type[LuGreFamily]:
    for cls in PRESETS.values():
        if cls.features == features and cls.viscous_name == viscous_name:
            return cls
    name = "+".join(sorted(features))
    made = type(
        "LuGreFamily_" + name.replace("-", "_").replace("+", "__"),
        (LuGreFamily,),
        {
            "name": "custom",
            "features": features,
            "viscous_name": viscous_name,
            "Params": params_class(features, viscous_name, owner="model " + name),
            "__module__": __name__,
        },
    )
    return with_recipe(made, _family_class, features, viscous_name)


# ------------------------------------------------------------------ the presets
class Coulomb(LuGreFamily):
    """Coulomb friction ``F = Fc*sign(v)`` (models.md 1.1)."""

    name = "coulomb"
    features = frozenset()
    Params = params_class(features, "sigma2", "CoulombParams", "coulomb")


class CoulombViscous(LuGreFamily):
    """Coulomb-viscous friction ``F = Fc*sign(v) + B*v`` (seed 001 Eq. 4)."""

    name = "coulomb-viscous"
    features = frozenset({"viscous"})
    viscous_name = "B"
    Params = params_class(features, "B", "CoulombViscousParams", "coulomb-viscous")


class Stribeck(LuGreFamily):
    """Stribeck steady-state map with film term, seed 002 Eq. 12 / seed 000 Eq. 9:
    ``F = sign(v)*(Fc + ((1 - h_ss)*Fs - Fc)*exp(-(|v|/vs)^n)) + sigma2*v``;
    ``vb = inf`` gives the classical Stribeck curve."""

    name = "stribeck"
    features = frozenset({"stribeck", "viscous", "film"})
    Params = params_class(features, "sigma2", "StribeckParams", "stribeck")


class Dahl(LuGreFamily):
    """Dahl model ``dz/dt = v - sigma0*|v|*z/Fc``, ``F = sigma0*z + sigma2*v`` (models.md 1.2)."""

    name = "dahl"
    features = frozenset({"presliding", "viscous"})
    Params = params_class(features, "sigma2", "DahlParams", "dahl")


class LuGre(LuGreFamily):
    """LuGre model (Canudas de Wit et al. 1995, models.md 1.3)."""

    name = "lugre"
    features = frozenset({"stribeck", "viscous", "presliding", "damping"})
    Params = params_class(features, "sigma2", "LuGreParams", "lugre")


class ModifiedLuGre(LuGreFamily):
    """Modified LuGre with lubricant-film state h (Yanada & Sekikawa; seed 000 Eqs. 2-8,
    T = 0; models.md 1.4)."""

    name = "modified-lugre"
    features = frozenset({"stribeck", "viscous", "presliding", "damping", "film", "film-lag"})
    Params = params_class(features, "sigma2", "ModifiedLuGreParams", "modified-lugre")


class NMLGM(LuGreFamily):
    """New modified LuGre model (Tran et al.; seed 002 Eqs. 5-11, seed 000 Eq. 8):
    ``F = sigma0*z + sigma1*dz/dt + sigma2*(v + T*dv/dt)`` (models.md 1.5)."""

    name = "nmlgm"
    features = frozenset({"stribeck", "viscous", "presliding", "damping", "film", "film-lag",
                          "lead"})
    Params = params_class(features, "sigma2", "NMLGMParams", "nmlgm")


PRESETS: dict[str, type[LuGreFamily]] = {
    cls.name: cls for cls in (Coulomb, CoulombViscous, Stribeck, Dahl, LuGre, ModifiedLuGre, NMLGM)
}

CoulombParams = Coulomb.Params
CoulombViscousParams = CoulombViscous.Params
StribeckParams = Stribeck.Params
DahlParams = Dahl.Params
LuGreParams = LuGre.Params
ModifiedLuGreParams = ModifiedLuGre.Params
NMLGMParams = NMLGM.Params
