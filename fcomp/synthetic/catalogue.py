"""The hidden effects the generator can put into a record, each with several shapes (laws).

An *effect* is a physical mechanism (a name of models.md 1.8, or one of
:data:`OUTSIDE`); a *shape* is one law for it. The first shape of every
effect is the law of the original generator, with the same parameters
(:data:`HIDDEN_DEFAULTS`), so the default output is unchanged. The laws
themselves are written in :mod:`fcomp.synthetic.laws` and
:mod:`fcomp.synthetic.dynamics`; this module holds their names, their
default parameters (pneumatic scale, SI units), which parameters set the
effect's *magnitude* (jittered by ``vary``), and the physical dimension of
every parameter (how it is carried to the hydraulic scale,
:mod:`fcomp.synthetic.scales`).

A hidden effect is written ``"effect"`` (its first shape) or
``"effect:shape"``, e.g. ``"stribeck:lorentzian"``.

Effects outside the catalogue (:data:`OUTSIDE`) and why no catalogue entry
explains them:

``ripple``
    friction levels modulated periodically *in position* with a wavelength of
    a few mm (a rod scratch): position dependence in the catalogue is smooth
    over the stroke, so a residual periodic in ``x`` remains.
``drift``
    levels growing slowly *in time* over the record (warming seals): no
    catalogue entry depends on the absolute time.
``ringing``
    a lightly damped rig mode (load-cell fixture, oil or air column) rung by
    every break-away: a decaying oscillation at ``f_r`` (30 Hz pneumatic,
    75 Hz hydraulic) with zero mean. Every catalogue entry is a function of
    the motion (``v``, ``a``, ``x``), the pressures, the rest time or the
    displacement history; the motion has no content at ``f_r`` (raised-cosine
    ramps, slides, loops below 5 Hz) and the ring is the same after every start
    whatever follows, so no static map, lag, memory or mass term can produce it.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from fcomp.errors import FcompError


@dataclass(frozen=True)
class Shape:
    """One law of a hidden effect.

    Attributes
    ----------
    effect, name
        The effect and the shape's name.
    law
        One line: the law (documentation and :meth:`SyntheticTruth.describe`).
    defaults
        Overridable law parameters and their defaults at the pneumatic scale (SI).
    magnitude
        The parameters that set how strong the effect is (multiplied by 0.6-1.5 with ``vary``).
    constants
        Fixed structure constants of the law (not overridable; used where the
        original law had no parameter for them, so its defaults stay as they were).
    """

    effect: str
    name: str
    law: str
    defaults: Mapping[str, float]
    magnitude: tuple[str, ...]
    constants: Mapping[str, float] = field(default_factory=dict)


def _shapes(effect: str, *rows: tuple[str, str, dict[str, float], tuple[str, ...]]
            ) -> tuple[Shape, ...]:
    return tuple(Shape(effect, name, law, defaults, mag) for name, law, defaults, mag in rows)


_MAXWELL = Shape(
    "nonlocal-memory", "maxwell-slip",
    "N equal elasto-slide elements, break displacements d_max*(i/N)^1.5 (Lampaert 2002)",
    {"n_elements": 6.0, "d_max": 4e-4}, ("d_max",), {"p_d": 1.5, "p_w": 0.0})

#: Every effect's shapes, the first being the original generator's law.
CATALOGUE: dict[str, tuple[Shape, ...]] = {
    "viscous": _shapes(
        "viscous",
        ("linear", "+ c_v*v", {"c_v": 80.0}, ("c_v",)),
        ("power", "+ c_v*v_ref*(|v|/v_ref)^n*sign(v), n = 0.6 (shear-thinning film)",
         {"c_v": 80.0, "v_ref": 0.05, "n": 0.6}, ("c_v",)),
    ),
    "stribeck": _shapes(
        "stribeck",
        ("armstrong", "hump dF*exp(-(|v|/vs)^delta), delta = 1.4 (Armstrong-Helouvry 1991)",
         {"dF": 15.0, "vs": 0.012, "delta": 1.4}, ("dF",)),
        ("lorentzian", "hump dF/(1 + (v/vs)^2) (Hess & Soom 1990)",
         {"dF": 15.0, "vs": 0.012}, ("dF",)),
        ("low-exponent", "hump dF*exp(-(|v|/vs)^delta), delta = 0.6 (long tail)",
         {"dF": 15.0, "vs": 0.008, "delta": 0.6}, ("dF",)),
    ),
    "presliding": _shapes(
        "presliding",
        ("bristle", "dz/dt = v - k*|v|*z/g, F = k*z (Canudas de Wit 1995 without damping)",
         {"k": 1.5e5}, ("k",)),
        ("dahl", "dF/dx = k*|1 - F/g*sign(v)|^i*sign(1 - F/g*sign(v)), i = 2 (Dahl 1976)",
         {"k": 1.5e5, "i": 2.0}, ("k",)),
        ("elasto-plastic", "dz/dt = v*(1 - alpha(z, v)*z/z_ss), no slip for |z| < ba*z_ss "
         "(Dupont et al. 2002)", {"k": 1.5e5, "ba": 0.5}, ("k",)),
    ),
    "nonlocal-memory": (
        _MAXWELL,
        Shape("nonlocal-memory", "graded",
              "N = 12 elements, d_i = d_max*(i/N)^p_d, slip-force shares ~ (N + 1 - i)^p_w "
              "(stiff elements carry more)",
              {"n_elements": 12.0, "d_max": 4e-4, "p_d": 1.0, "p_w": 1.0}, ("d_max",)),
        Shape("nonlocal-memory", "few",
              "N = 3 elements, d_i = d_max*(i/N)^2, shares ~ (N + 1 - i)^-1 (soft ones carry more)",
              {"n_elements": 3.0, "d_max": 3e-4, "p_d": 2.0, "p_w": -1.0}, ("d_max",)),
    ),
    "frictional-lag": _shapes(
        "frictional-lag",
        ("hess-soom", "hump at the lagged speed dv_L/dt = (|v| - v_L)/tau_L (Hess & Soom 1990)",
         {"tau_L": 0.06}, ("tau_L",)),
        ("hess-soom-short", "the same, tau_L = 10 ms", {"tau_L": 0.01}, ("tau_L",)),
        ("hess-soom-long", "the same, tau_L = 0.2 s", {"tau_L": 0.2}, ("tau_L",)),
        ("film", "film fraction l -> 1 - hump(|v|) with tau_rise (building) or tau_fall "
         "(draining); hump force scaled by 1 - l", {"tau_rise": 0.03, "tau_fall": 0.15},
         ("tau_rise", "tau_fall")),
    ),
    "dwell-time": _shapes(
        "dwell-time",
        ("kato", "dF_inf*(1 - exp(-(t_d/tau_k)^m)) added to Fs, erased as exp(-s/d_c) "
         "(Kato et al. 1972)", {"dF_inf": 40.0, "tau_k": 0.5, "m": 1.0, "d_c": 5e-4},
         ("dF_inf",)),
        ("kato-short", "the same, tau_k = 0.1 s",
         {"dF_inf": 40.0, "tau_k": 0.1, "m": 1.0, "d_c": 5e-4}, ("dF_inf",)),
        ("kato-long", "the same, tau_k = 3 s",
         {"dF_inf": 40.0, "tau_k": 3.0, "m": 1.0, "d_c": 5e-4}, ("dF_inf",)),
        ("dieterich", "min(dF_log*ln(1 + t_d/tau_d), dF_max), erased as exp(-s/d_c) "
         "(Dieterich 1972)", {"dF_log": 8.0, "tau_d": 0.05, "dF_max": 40.0, "d_c": 5e-4},
         ("dF_log", "dF_max")),
    ),
    "direction-asymmetry": _shapes(
        "direction-asymmetry",
        ("levels", "levels (Fc, Fs)*(1 + dF_neg/Fc) on the retracting side",
         {"dF_neg": 8.0}, ("dF_neg",)),
        ("ratio", "the whole friction times 1 + dr_ext where it opposes extension (F > 0)",
         {"dr_ext": 0.3}, ("dr_ext",)),
        ("viscous", "+ c_neg*v for v < 0 only (asymmetric viscous coefficient)",
         {"c_neg": 100.0}, ("c_neg",)),
    ),
    "pressure-dependence": _shapes(
        "pressure-dependence",
        ("lip-seal", "levels*(1 + c_p*(p1 + p2))/(1 + c_p*S_mid)", {"c_p": 4e-6}, ("c_p",)),
        ("chamber-weighted", "levels*(1 + c_piston*(p1 + p2) + c_rod*p2)/(the same at S_mid): "
         "the piston seal sees both chambers, the rod seal only p2",
         {"c_piston": 1.5e-6, "c_rod": 6e-6}, ("c_piston", "c_rod")),
        ("saturating", "levels*(1 + c_p*p_sat*(1 - exp(-S/p_sat)))/(the same at S_mid)",
         {"c_p": 4e-6, "p_sat": 2e5}, ("c_p",)),
    ),
    "position-dependence": _shapes(
        "position-dependence",
        ("bump", "levels*(1 + a_g*exp(-((x - x_g)/w)^2) + a_l*(x - L/2)/L)",
         {"a_g": 0.25, "x_g_frac": 0.3, "w_frac": 0.15, "a_l": 0.12}, ("a_g", "a_l")),
        ("tight-spot", "levels*(1 + a_t*(1 + cos(2*pi*(x - x_t)/w))/2) for |x - x_t| < w/2, "
         "w = 2.5 % of the stroke", {"a_t": 0.5, "x_t_frac": 0.45, "w_frac": 0.025}, ("a_t",)),
        ("wear-gradient", "levels*(1 + a_w*(x - L/2)/L)", {"a_w": 0.5}, ("a_w",)),
        ("step", "levels*(1 + a_s*(1 + tanh((x - x_s)/w_edge))/2): a worn zone of the bore",
         {"a_s": -0.3, "x_s_frac": 0.47, "w_edge": 1e-3}, ("a_s",)),
    ),
    "viscous-lead": _shapes(
        "viscous-lead",
        ("lead", "+ sigma2*T*a (NMLGM lead, seed 000 Eq. 8)", {"T": 0.06}, ("T",)),
        ("lead-lag", "viscous force through (1 + T*s)/(1 + T_f*s): + sigma2*(T - T_f)*"
         "lowpass_T_f(a)", {"T": 0.08, "T_f": 0.02}, ("T",)),
    ),
    "inertia-error": _shapes(
        "inertia-error",
        ("overstated", "recorded force carries dm*a; the sidecar mass is m - dm (dm < 0)",
         {"dm": -2.5}, ("dm",)),
        ("understated", "the same with dm > 0: the sidecar mass is too small",
         {"dm": 0.6}, ("dm",)),
    ),
    "force-offset": _shapes(
        "force-offset",
        ("constant", "+ offset on the recorded force (a sensor zero error)",
         {"offset": 6.0}, ("offset",)),
        ("tilt", "+ m*g*sin(angle): an inclination the sidecar does not declare",
         {"angle": -0.25}, ("angle",)),
    ),
    "ripple": _shapes(
        "ripple",
        ("scratch", "levels*(1 + A*sin(2*pi*x/wavelength)): a rod scratch",
         {"A": 0.12, "wavelength": 3e-3}, ("A",)),
    ),
    "drift": _shapes(
        "drift",
        ("thermal", "levels*(1 + beta*t/t_end): slow thermal drift", {"beta": 0.25}, ("beta",)),
    ),
    "ringing": _shapes(
        "ringing",
        ("break-away", "+ F_r*exp(-zeta*w*tau)*sin(w_d*tau) after every start from rest: a "
         "lightly damped rig mode (fixture, oil or air column) rung by the break-away",
         {"F_r": 5.0, "f_r": 30.0, "zeta": 0.06}, ("F_r",)),
    ),
}

#: Effect -> its shape names; the first is the original generator's law.
SHAPES: dict[str, tuple[str, ...]] = {e: tuple(s.name for s in v) for e, v in CATALOGUE.items()}
#: Default law parameters of each hidden effect's first shape (pneumatic scale, SI units).
HIDDEN_DEFAULTS: dict[str, dict[str, float]] = {
    e: dict(v[0].defaults) for e, v in CATALOGUE.items()
}
#: Hidden effects outside the catalogue of models.md 1.8 (no catalogue entry explains them).
OUTSIDE = ("ripple", "drift", "ringing")

#: Physical dimension of every law parameter: how it is carried to another rig scale
#: (:attr:`fcomp.synthetic.scales.Scale.factors`); parameters not listed keep their value.
DIMENSIONS: dict[str, str] = {
    "c_v": "damping", "c_neg": "damping",
    "dF": "force", "dF_inf": "force", "dF_log": "force", "dF_max": "force", "dF_neg": "force",
    "offset": "force", "F_r": "force",
    "k": "stiffness",
    "d_max": "presliding-length",
    "d_c": "slide-length",
    "c_p": "per-pressure", "c_piston": "per-pressure", "c_rod": "per-pressure",
    "p_sat": "pressure",
    "dm": "mass-error",
    "f_r": "frequency",
}


def shape(effect: str, name: str | None = None) -> Shape:
    """The :class:`Shape` ``name`` of ``effect`` (its first shape if ``name`` is None)."""
    if effect not in CATALOGUE:
        raise FcompError(f"unknown hidden effect {effect!r}; known: {', '.join(CATALOGUE)}")
    shapes = CATALOGUE[effect]
    if name is None:
        return shapes[0]
    for s in shapes:
        if s.name == name:
            return s
    raise FcompError(f"hidden effect {effect!r}: unknown shape {name!r}; known: "
                     f"{', '.join(SHAPES[effect])}")


def effect_shapes(include_outside: bool = True) -> list[tuple[str, str]]:
    """Every ``(effect, shape)`` pair of the catalogue, in catalogue order."""
    return [(e, s) for e, names in SHAPES.items() for s in names
            if include_outside or e not in OUTSIDE]


def parse(spec: str) -> tuple[str, str]:
    """``"effect"`` or ``"effect:shape"`` -> ``(effect, shape)`` (checked)."""
    effect, _, name = spec.partition(":")
    return effect, shape(effect, name or None).name


@dataclass(frozen=True)
class Law:
    """A resolved hidden effect: its shape and complete parameters (at the record's scale)."""

    shape: Shape
    params: dict[str, float]

    @property
    def effect(self) -> str:
        return self.shape.effect

    def __getitem__(self, key: str) -> float:
        """A law parameter, or one of the shape's fixed constants."""
        if key in self.params:
            return self.params[key]
        return float(self.shape.constants[key])


def resolve(hidden: Sequence[str] | Mapping[str, Mapping[str, float]],
            factors: Mapping[str, float]) -> dict[str, Law]:
    """Hidden-effect specification -> ``{effect: Law}`` with complete, scaled parameters.

    Parameters
    ----------
    hidden
        ``"effect"`` / ``"effect:shape"`` names, or a mapping of them to parameter overrides.
    factors
        Dimension -> factor applied to the *defaults* (not to overrides), see :data:`DIMENSIONS`.
    """
    items: Iterable[tuple[str, Mapping[str, float]]] = (
        hidden.items() if isinstance(hidden, Mapping) else ((h, {}) for h in hidden))
    out: dict[str, Law] = {}
    for spec, over in items:
        effect, name = parse(spec)
        if effect in out:
            raise FcompError(f"hidden effect {effect!r} given twice (one shape per effect)")
        sh = shape(effect, name)
        params = {k: v * factors.get(DIMENSIONS.get(k, ""), 1.0) for k, v in sh.defaults.items()}
        unknown = set(over) - set(params)
        if unknown:
            raise FcompError(f"hidden effect {spec!r}: unknown law parameter(s) "
                             f"{', '.join(sorted(unknown))}; known: {', '.join(params)}")
        params.update({k: float(v) for k, v in over.items()})
        out[effect] = Law(sh, params)
    return out
