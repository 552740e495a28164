"""The effect catalogue of models.md section 1.8.

Each class docstring is the effect's physical explanation: what it is and
what it leaves in the residual of a model that lacks it. Defaults are
no-ops: adding an effect with default parameters does not change the force.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from fcomp.backend import Backend
from fcomp.effects.base import EFFECTS, Effect, scale_levels
from fcomp.effects.record import (
    DiagnosisForm,
    RecordView,
    distinct_columns,
    ls_slope,
    stribeck_hump_start,
)
from fcomp.models.hysteresis import (
    HYSTERESIS_CONSTRAINTS,
    NONLOCAL_MEMORY_DEFAULTS,
    hysteresis_specs,
    with_hysteresis,
)
from fcomp.models.lugre_family import FAMILY_SPECS, FEATURE_PARAMS
from fcomp.parameters import ParamValues, make_params_class, spec

if TYPE_CHECKING:
    from fcomp.conditioning import Scales
    from fcomp.models.base import FrictionModel, Signals

INF = math.inf


def _family(model: FrictionModel, effect: str) -> Any:
    """The model as a member of the LuGre family (its :meth:`feature_family`), else an error."""
    fam = model.feature_family()
    if fam is None:
        raise ValueError(
            f"effect {effect!r} is a term of the LuGre family and does not apply to "
            f"model {model.describe()!r}"
        )
    return fam


def _features(model: FrictionModel) -> frozenset[str] | None:
    """The feature set of a family model, ``None`` for models outside a feature family."""
    fam = model.feature_family()
    return None if fam is None else fam.features


class StructuralEffect(Effect):
    """An effect that is a term of the LuGre family: attaching it changes the model class.

    ``adds`` are the features attaching it switches on; a model that already has
    every feature of ``marks`` (default: ``adds``) already has the effect.
    """

    adds: ClassVar[frozenset[str]] = frozenset()
    marks: ClassVar[frozenset[str] | None] = None
    requires: ClassVar[frozenset[str]] = frozenset()

    def applies_to(self, model: FrictionModel) -> bool:
        features = _features(model)
        marks = self.adds if self.marks is None else self.marks
        return features is not None and not marks <= features

    def added_features(self) -> set[str]:
        """The features attaching this instance switches on (default :attr:`adds`)."""
        return set(self.adds)

    def new_values(self, model: FrictionModel) -> dict[str, float]:
        """Parameter values of the added terms (from this effect's parameters)."""
        return dict(self.params.flat())

    @classmethod
    def config_in(cls, model: FrictionModel) -> dict[str, Any]:
        """The configuration that attaches this effect as ``model`` has it (``model`` a
        model it was attached to): its ``form`` where it has several (default: none).

        The model keeps the effect as features, not as an instance
        (:meth:`attach`); a model file (:mod:`fcomp.modelfile`) writes this to
        rebuild it.
        """
        return {}

    def attach(self, model: FrictionModel) -> FrictionModel:
        fam = _family(model, self.name)
        if not self.applies_to(fam):
            raise ValueError(f"model {fam.describe()!r} already has effect {self.name!r}")
        missing = self.requires - fam.features
        if missing:
            raise ValueError(
                f"effect {self.name!r} needs {', '.join(sorted(missing))} in the model "
                f"{fam.describe()!r} first"
            )
        new = fam.with_features(self.added_features(), self.new_values(fam))
        new.lineage = (*(fam.lineage or (fam.name,)), self.name)
        return new


# ----------------------------------------------------------------- structural
ViscousParams = make_params_class("ViscousParams", [
    spec("sigma2", "Ns/m", 0.0, 0.0, INF, "viscous coefficient"),
    FAMILY_SPECS["p_visc"], FAMILY_SPECS["v_ref"]], owner="effect viscous")


class Viscous(StructuralEffect):
    """Viscous friction ``sigma2*v``: shear of the lubricant film between seal and bore.

    The force grows with sliding speed, linearly for a Newtonian film; a
    shear-thinning lubricant or a film that thickens with speed makes it a
    power of the speed, ``sigma2*v*(|v|/v_ref)^(p_visc - 1)`` (the
    ``viscous-power`` of :mod:`fcomp.models.lugre_family`; ``v_ref`` is
    configuration, the record's speed scale in a diagnosis). A model without
    it leaves a residual odd in ``v`` that grows with speed, unrelated to
    position or pressure.
    """

    name = "viscous"
    adds = frozenset({"viscous", "viscous-power"})
    marks = frozenset({"viscous"})
    Params = ViscousParams
    signature = "residual linear and odd in v, largest at high speed"
    experiment = "constant-speed runs at several speeds in both directions"

    @classmethod
    def diagnosis_config(cls, scales: Scales) -> dict[str, Any]:
        """The exponent's reference speed: the record's speed scale."""
        return {"v_ref": scales.speed}

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The slope of the residual against ``v`` while moving (Newtonian and thinning)."""
        m = view.moving
        c = ls_slope(view.residual[m], view.signal("v")[m])
        sc = view.scales
        c = c if c > 0 else 0.05 * sc.force / sc.speed
        return [{"sigma2": c}, {"sigma2": c, "p_visc": 0.6}]


    def new_values(self, model: FrictionModel) -> dict[str, float]:
        flat = self.params.flat()
        return {_family(model, self.name).viscous_name: flat["sigma2"], "p_visc": flat["p_visc"],
                "v_ref": float(self.config.get("v_ref", flat["v_ref"]))}


StribeckEffectParams = make_params_class("StribeckEffectParams", [
    spec("Fs_excess", "N", 0.0, 0.0, INF, "Fs - Fc, break-away excess over Coulomb"),
    spec("vs", "m/s", 0.01, 0.0, INF, "Stribeck velocity", lower_open=True),
    spec("n", "-", 2.0, 0.0, 10.0, "Stribeck exponent", lower_open=True),
    FAMILY_SPECS["kappa_s"],
], owner="effect stribeck")


class Stribeck(StructuralEffect):
    """Stribeck effect: friction falls from the break-away level ``Fs`` to ``Fc`` with speed.

    At low speed the seal rides on boundary contacts; as speed grows a
    hydrodynamic film carries part of the load and friction drops over a
    characteristic speed ``vs``. A model without it under-predicts the force
    at low speed and at break-away: the residual is a hump at small ``|v|``
    decaying over a few ``vs``, with peaks right after each start. The curve's
    exponent ``n`` and form ``kappa_s`` (exponential to rational, the
    ``stribeck-form`` of :mod:`fcomp.models.lugre_family`) cover the shapes
    reported for seals (Armstrong-Helouvry 1991; Hess & Soom 1990).
    """

    name = "stribeck"
    adds = frozenset({"stribeck", "stribeck-form"})
    marks = frozenset({"stribeck"})
    Params = StribeckEffectParams
    signature = "residual hump at low |v| decaying with speed; peaks after starts"
    experiment = "slow constant-speed runs (0.1-10 vs) in both directions"

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The low-speed hump of the force (:func:`~fcomp.effects.record.stribeck_hump_start`):
        its speed and a factor of four either side; the fat-tailed rational form too."""
        flat = view.params
        v = view.signal("v")
        m = view.train
        Fc = flat.get("Fc", flat.get("Fc_pos", view.level))
        B = flat.get("B", flat.get("sigma2", 0.0))
        Fs, vs = stribeck_hump_start(v[m], view.y[m], Fc, B, view.v_rest)
        exc = max(Fs - Fc, 0.1 * Fc)
        # the exponential form, and the fat-tailed rational one (its form has no gradient at 0)
        return [{"Fs_excess": exc, "vs": vs}, {"Fs_excess": exc, "vs": 4 * vs},
                {"Fs_excess": exc, "vs": vs / 4}, {"Fs_excess": exc, "vs": vs, "kappa_s": 0.7}]


    def new_values(self, model: FrictionModel) -> dict[str, float]:
        flat = model.params.flat()
        p = self.params
        exc = p.scalar("Fs_excess")
        out: dict[str, float] = {"vs": p.scalar("vs"), "n": p.scalar("n"),
                                 "kappa_s": p.scalar("kappa_s")}
        if "Fc" in flat:
            out["Fs"] = flat["Fc"] + exc
        else:
            out["Fs_pos"] = flat["Fc_pos"] + exc
            out["Fs_neg"] = flat["Fc_neg"] + exc
        return out


ViscousLeadParams = make_params_class("ViscousLeadParams", [
    spec("T", "s", 0.0, 0.0, INF, "time constant of the fluid-friction lead",
         directional=False)], owner="effect viscous-lead")


class ViscousLead(StructuralEffect):
    """Lead of fluid friction, ``sigma2*(v + T*dv/dt)`` (NMLGM, seed 000 Eq. 8).

    The film does not respond instantly: in the fluid-lubrication regime the
    viscous force leads the velocity, so the force-velocity plot shows a
    hysteresis loop at high speed whose width grows with acceleration. A
    model without it leaves a residual proportional to the acceleration ``a``
    during fast sliding.
    """

    name = "viscous-lead"
    #: a force proportional to the acceleration while sliding: a moving mass's, too
    confounded = ("inertia-error",)
    adds = frozenset({"lead"})
    requires = frozenset({"viscous"})
    Params = ViscousLeadParams
    signature = "residual proportional to acceleration while sliding fast"
    experiment = "sinusoidal velocity at two or more frequencies, same amplitude"
    needs = ("a",)
    dynamic = True

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """``T`` from the residual regressed on ``sigma2*a``."""
        flat = view.params
        visc = flat.get("sigma2", flat.get("B", flat.get("sigma2_pos", 0.0)))
        a = view.signal("a")
        m = view.train
        sc = view.scales
        T = ls_slope(view.residual[m], visc * a[m]) if visc > 0 else 0.0
        return [{"T": T if T > 0 else 0.05 * sc.speed / sc.accel}]


FrictionalLagParams = make_params_class("FrictionalLagParams", [
    dataclasses.replace(FAMILY_SPECS["vb"], default=INF),
    *(FAMILY_SPECS[n] for n in ("tau_hp", "tau_hn", "tau_h0", "tau_L", "w_L")),
], owner="effect frictional-lag")


class FrictionalLag(StructuralEffect):
    """Frictional lag: the Stribeck curve follows the velocity late.

    The lubricant film thickens while sliding and drains while decelerating
    or resting, so friction on the accelerating branch is higher than on the
    decelerating one, and break-away after a dwell is higher than after a
    short stop. A model without it leaves a residual that is a loop against
    ``v`` (sign depending on whether ``|v|`` rises or falls) and that grows with
    time since the last reversal. Two forms (configuration ``form``):

    ``"film"`` (default)
        the lubricant-film state ``h`` of the modified LuGre model (models.md
        1.4, seed 002 Eqs. 8-11), with different time constants for building,
        draining and dwell; defaults ``vb = inf`` make ``h`` identically zero.
    ``"speed-lag"``
        Hess & Soom (1990): the curve is evaluated at a lagged speed,
        ``dvL/dt = (|v| - vL)/tau_L``, blended by ``w_L`` (the ``speed-lag`` of
        :mod:`fcomp.models.lugre_family`); the steady-state map is unchanged;
        ``w_L = 0`` (the default) is no lag.
    """

    name = "frictional-lag"
    FORMS: ClassVar[tuple[str, ...]] = ("film", "speed-lag")
    adds = frozenset({"film", "film-lag"})
    marks = frozenset({"film-lag"})
    requires = frozenset({"stribeck"})
    Params = FrictionalLagParams
    signature = "residual loop against v: rising and falling |v| branches differ"
    experiment = "velocity sweeps up and down at several rates; dwell before restart"
    dynamic = True

    @classmethod
    def diagnosis_forms(cls) -> tuple[DiagnosisForm, ...]:
        """Both forms, the film and the lagged speed."""
        return tuple(DiagnosisForm(f, {"form": f}) for f in cls.FORMS)

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """A small grid of time constants: 10 and 50 ms (at least 5 and 25 samples); for the
        film, its speed ``vb`` at one and four Stribeck speeds; for the lagged speed, the
        whole lag and half of it."""
        flat = view.params
        vs = flat.get("vs", flat.get("vs_pos", 0.1 * view.scales.speed))
        dt = view.scales.dt
        taus = (max(5 * dt, 0.01), max(25 * dt, 0.05))
        if (form or "film") == "speed-lag":
            return [{"tau_L": tau, "w_L": w} for tau in (*taus, 0.2) for w in (1.0, 0.5)]
        out = []
        for vb in (vs, 4 * vs):
            for tau in taus:
                out.append({"vb": vb, "tau_hp": tau, "tau_hn": tau, "tau_h0": 1.0})
        return out

    @classmethod
    def config_in(cls, model: FrictionModel) -> dict[str, Any]:
        """``speed-lag`` when the model follows a lagged speed, else ``film``."""
        features = _features(model) or frozenset()
        return {"form": "speed-lag" if "speed-lag" in features else "film"}

    def applies_to(self, model: FrictionModel) -> bool:
        from fcomp.models.lugre_family import LuGreFamily

        return (isinstance(model, LuGreFamily) and "film-lag" not in model.features
                and "speed-lag" not in model.features)

    def attach(self, model: FrictionModel) -> FrictionModel:
        fam = _family(model, self.name)
        if not self.applies_to(fam):
            raise ValueError(f"model {fam.describe()!r} already has effect {self.name!r}")
        if "stribeck" not in fam.features:
            raise ValueError(
                f"effect 'frictional-lag' needs the Stribeck term: add 'stribeck' to "
                f"{fam.describe()!r} first"
            )
        values = dict(self.params.flat())
        lag = FEATURE_PARAMS["speed-lag"]
        if self.form == "speed-lag":
            new = fam.with_features({"speed-lag"}, {k: values[k] for k in lag})
        else:
            values = {k: v for k, v in values.items() if k not in lag}
            if "film" in fam.features:  # static film already present: keep its vb
                values = {k: v for k, v in values.items() if not k.startswith("vb")}
            new = fam.with_features({"film", "film-lag"}, values)
        new.lineage = (*(fam.lineage or (fam.name,)), self.name)
        return new


PreslidingParams = make_params_class("PreslidingParams", [
    spec("sigma0", "N/m", INF, 0.0, INF, "bristle stiffness (inf: rigid, no-op)",
         lower_open=True, directional=False),
    spec("sigma1", "Ns/m", 0.0, 0.0, INF, "bristle damping", directional=False),
    FAMILY_SPECS["i_pre"],
    FAMILY_SPECS["ba_pre"],
], owner="effect presliding")


class Presliding(StructuralEffect):
    """Pre-sliding: bristle compliance ``sigma0`` (the step from a static map to LuGre).

    Before gross sliding the seal deforms elastically: the force builds up
    over micrometres of displacement instead of jumping at ``v = 0``. A
    static model leaves residual spikes at every velocity reversal and a
    force-displacement loop (instead of a step) at small amplitude; the
    residual follows displacement since reversal, not velocity. The default
    ``sigma0 = inf`` is the rigid limit (the static map itself: a no-op).
    The bristle's approach to sliding is LuGre's exponential by default;
    Dahl's exponent ``i_pre`` (``bristle-exponent`` of
    :mod:`fcomp.models.lugre_family`) makes it softer or stiffer, and a
    break-away deflection ``ba_pre`` (``bristle-break``: the elasto-plastic
    bristle of Dupont et al. 2002) keeps it purely elastic up to that share of
    its steady deflection. Two forms (configuration ``form``):

    ``"bristle"`` (default)
        the exponent, no break;
    ``"elasto-plastic"``
        the break as well: below it, and whenever ``z`` and ``v`` have opposite
        signs, the bristle is a spring (it unloads elastically after a
        reversal, where LuGre's bristle relaxes faster than a spring can).
        ``ba_pre = 0`` is not LuGre: the unloading is elastic.

    A diagnosis fits both, the elasto-plastic one with LuGre's exponent.
    """

    name = "presliding"
    FORMS: ClassVar[tuple[str, ...]] = ("bristle", "elasto-plastic")
    adds = frozenset({"presliding", "damping", "bristle-exponent"})
    marks = frozenset({"presliding", "damping"})
    Params = PreslidingParams
    signature = "residual spikes at reversals that follow displacement since reversal"
    experiment = "small-amplitude displacement cycles (well below break-away)"
    dynamic = True

    @classmethod
    def diagnosis_forms(cls) -> tuple[DiagnosisForm, ...]:
        """Dahl's exponent without a break (``bristle``), and the elasto-plastic break with
        LuGre's exponent (``elasto-plastic``): two published laws of the approach to sliding."""
        return (DiagnosisForm("bristle", {"form": "bristle"}),
                DiagnosisForm("elasto-plastic", {"form": "elasto-plastic"}, held=("i_pre",)))

    @classmethod
    def forms_for(cls, model: FrictionModel) -> tuple[DiagnosisForm, ...]:
        """One form on a model with a bristle already (Dahl: only the damping is added)."""
        features = _features(model)
        has = features is not None and "presliding" in features
        return cls.diagnosis_forms()[:1] if has else cls.diagnosis_forms()

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The stiffness from the presliding length, a factor of four either side; the
        bristle exponent stiffer and softer than LuGre's, or the break at a fifth, half
        and four fifths of the steady deflection."""
        s0 = view.level / view.d_pre
        if form == "elasto-plastic":
            return [{"sigma0": s0, "ba_pre": 0.5}, {"sigma0": 4 * s0, "ba_pre": 0.5},
                    {"sigma0": s0 / 4, "ba_pre": 0.5}, {"sigma0": s0, "ba_pre": 0.2},
                    {"sigma0": s0, "ba_pre": 0.8}]
        return [{"sigma0": s0}, {"sigma0": 4 * s0}, {"sigma0": s0 / 4},
                {"sigma0": s0, "i_pre": 0.5}, {"sigma0": s0, "i_pre": 2.0}]


    def attach(self, model: FrictionModel) -> FrictionModel:
        fam = _family(model, self.name)
        if "presliding" in fam.features and "damping" not in fam.features:
            # Dahl: compliant bristles already, only the damping is missing; the model's
            # own sigma0 is kept and sigma1 = 0 (the default) is a no-op.
            new = fam.with_features({"damping"}, {"sigma1": self.params.scalar("sigma1")})
            new.lineage = (*(fam.lineage or (fam.name,)), self.name)
            return new
        if math.isinf(self.params.scalar("sigma0")):
            if "presliding" in fam.features:
                raise ValueError(f"model {fam.describe()!r} already has effect {self.name!r}")
            return Effect.attach(self, model)  # rigid bristles: the static map, unchanged
        return super().attach(model)

    @classmethod
    def config_in(cls, model: FrictionModel) -> dict[str, Any]:
        """``elasto-plastic`` when the bristle has its break-away deflection, else ``bristle``."""
        features = _features(model) or frozenset()
        return {"form": "elasto-plastic" if "bristle-break" in features else "bristle"}

    def added_features(self) -> set[str]:
        """The bristle, its damping and exponent; the break in the elasto-plastic form."""
        return set(self.adds) | ({"bristle-break"} if self.form == "elasto-plastic" else set())

    def new_values(self, model: FrictionModel) -> dict[str, float]:
        """The bristle's values (the break's only where the form has it)."""
        return {k: v for k, v in self.params.flat().items()
                if k != "ba_pre" or self.form == "elasto-plastic"}


# --------------------------------------------------------------------- add-ons
#: A chamber pressure whose 1st-99th percentile range over the samples weighed is at most
#: this share of that of ``p1 + p2`` (or 1 kPa) is constant for the laws below: a vented
#: chamber (``p2 = 0`` gauge) or one held by a regulator.
CONSTANT_PRESSURE_SHARE = 0.02


def constant_chambers(view: RecordView, mask: np.ndarray | None = None) -> list[str]:
    """The chambers (``"p1"``, ``"p2"``) whose pressure is constant over ``mask`` (default
    the training samples): identically zero (vented, or no column: 0 gauge) or varying by
    at most :data:`CONSTANT_PRESSURE_SHARE` of the range of ``p1 + p2`` (at least 1 kPa).
    A law's coefficient of such a pressure is a constant force or level: the record cannot
    tell it from the friction level or a force offset."""
    m = view.train if mask is None else mask
    if not m.any():
        return ["p1", "p2"]
    p1, p2 = view.signal("p1")[m], view.signal("p2")[m]

    def span(p: np.ndarray) -> float:
        lo, hi = np.percentile(p, [1.0, 99.0])
        return float(hi - lo)

    tol = max(1000.0, CONSTANT_PRESSURE_SHARE * span(p1 + p2))
    return [n for n, p in (("p1", p1), ("p2", p2))
            if not np.any(p != p[0]) or span(p) <= tol]


PressureDependenceParams = make_params_class("PressureDependenceParams", [
    spec("kp", "1/Pa", 0.0, -1e-3, 1e-3, "relative level change per pascal of p1 + p2"),
    spec("kd", "1/Pa", 0.0, -1e-3, 1e-3, "relative level change per pascal of p1 - p2",
         directional=False),
    spec("kq", "1/Pa^2", 0.0, -INF, INF, "curvature of the law in p1 + p2",
         directional=False),
    spec("p_ref", "Pa", 0.0, -INF, INF, "reference gauge pressure sum (fixed)",
         directional=False),
    spec("d_ref", "Pa", 0.0, -INF, INF, "reference pressure difference (fixed)",
         directional=False),
], owner="effect pressure-dependence")


class PressureDependence(Effect):
    """Pressure dependence: the levels scale with the chamber pressures (gauge).

    Chamber pressure energises lip seals: the normal force on the seal, and
    so the friction, grows with pressure (seed 000 Fig. 12, seed 001 Eq. 1).
    The piston seal sees both chambers and a rod seal only the rod side, so
    the chambers weigh differently; an energised lip saturates. With
    ``S = p1 + p2`` and ``D = p1 - p2``::

        (Fc, Fs) -> (Fc, Fs)*(1 + kp*(S - p_ref) + kd*(D - d_ref) + kq*(S - p_ref)^2)

    ``kd`` weighs the chambers apart (``kd = 0``: equally), ``kq`` bends the
    law (a saturating seal: ``kq < 0``). A model without it leaves a residual
    whose magnitude follows the pressures: runs at high pressure sit above the
    fit, runs at low pressure below, with the same sign as the friction.
    ``p_ref`` and ``d_ref`` are held fixed (not fitted). The factor is floored at
    1 % (:data:`~fcomp.effects.base.LEVEL_FLOOR`): a curvature fitted on a few
    pressure levels must not make the level negative at a pressure the fit
    never weighed.
    """

    name = "pressure-dependence"
    Params = PressureDependenceParams
    fixed: ClassVar[tuple[str, ...]] = ("p_ref", "d_ref")
    needs = ("p1", "p2")
    signature = "residual magnitude correlates with p1 + p2, sign follows friction"
    experiment = "identical motions at two or more chamber pressure levels"
    experiments: ClassVar[Mapping[str, str]] = MappingProxyType({
        "hydraulic-cylinder": "identical motions at two or more supply pressures (or loads, "
                              "which move both chamber pressures)",
        "friction-rig": "identical motions at two or more normal-force (contact pressure) "
                        "levels",
        "electromechanical-axis": "identical motions with two or more payloads or screw "
                                  "preloads (the normal force on guides and nut; the axis "
                                  "has no fluid pressure)",
    })

    def modify_levels(self, be: Backend, L: dict, w: list[Any], sig: Signals,
                      P: ParamValues) -> dict:
        dS = sig.p1 + sig.p2 - P("p_ref")
        dD = sig.p1 - sig.p2 - P("d_ref")
        return scale_levels(L, 1.0 + P("kp", sig.s) * dS + P("kd") * dD + P("kq") * dS * dS,
                            be=be)

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The level change per pascal of ``p1 + p2`` by least squares; then with the
        chambers weighed apart and a curvature too (the sign-corrected residual regressed
        on ``|F_hat|*(dS, dD, dS^2)``)."""
        m = view.moving
        s = np.sign(view.signal("v"))
        p1, p2 = view.signal("p1"), view.signal("p2")
        d_ref = float(np.mean(p1 - p2))
        dS = p1 + p2 - view.scales.p_mid
        dD = p1 - p2 - d_ref
        F = np.abs(view.F_hat)
        rs = (s * view.residual)[m]
        kp = ls_slope(rs, (F * dS)[m])
        bound = 0.9 / max(float(np.max(np.abs(dS))), 1.0)
        ref = {"p_ref": view.scales.p_mid, "d_ref": d_ref}
        cols = np.column_stack([F * dS, F * dD, F * dS * dS])[m]
        use = distinct_columns(cols)
        coef = np.zeros(3)
        coef[use], *_ = np.linalg.lstsq(cols[:, use], rs, rcond=None)
        bd = 0.9 / max(float(np.max(np.abs(dD))), 1.0)
        bq = 0.9 / max(float(np.max(dS * dS)), 1.0)
        full = {"kp": float(np.clip(coef[0], -bound, bound)),
                "kd": float(np.clip(coef[1], -bd, bd)),
                "kq": float(np.clip(coef[2], -bq, bq))}
        return [{"kp": float(np.clip(kp, -bound, bound)), **ref}, {**full, **ref}]

    def held(self, view: RecordView) -> list[str]:
        """The chamber weight ``kd`` and the curvature ``kq`` where the record cannot tell
        them from the level change ``kp``, at their no-op value 0.

        One chamber vented or held at a constant pressure (``p2 = 0`` on a
        single-acting cylinder; :func:`constant_chambers`): ``p1 - p2`` and
        ``p1 + p2`` then differ by a constant, only ``kp + kd`` is determined, and
        ``kd`` is held (the chambers weighed equally) rather than left to trade
        against ``kp`` up to a bound. Otherwise the columns the record cannot tell
        apart (:func:`~fcomp.effects.record.distinct_columns`; two pressure levels:
        the square is a line). Both chambers constant: all three (the level alone).
        """
        m = view.moving
        p1, p2 = view.signal("p1"), view.signal("p2")
        still = constant_chambers(view, m)
        if len(still) == 2:
            return ["kp", "kd", "kq"]
        dS = (p1 + p2 - view.scales.p_mid)[m]
        dD = (p1 - p2)[m] - float(np.mean((p1 - p2)[m]))
        use = distinct_columns(np.column_stack([dS, dD, dS * dS - np.mean(dS * dS)]))
        if still:
            use = [i for i in use if i != 1]
        return [n for i, n in enumerate(("kp", "kd", "kq")) if i not in use]


DirectionAsymmetryParams = make_params_class("DirectionAsymmetryParams", [
    spec("r_neg", "-", 1.0, 0.0, 10.0, "ratio of the v < 0 levels to the v > 0 levels",
         lower_open=True, directional=False),
    spec("rv_neg", "-", 1.0, 0.0, 10.0, "ratio of the viscous slope for v < 0 to that "
         "for v > 0 (models with a viscous term)", directional=False),
], owner="effect direction-asymmetry")


class DirectionAsymmetry(Effect):
    """Direction asymmetry: a separate friction level, and viscous slope, for ``v < 0``.

    Rod and piston seals are not symmetric (lip direction, rod seal only on
    one side, seed 002 Fig. 4): extending and retracting friction differ. The
    levels of ``v < 0`` are ``r_neg`` times those of ``v > 0``, and the viscous
    slope ``rv_neg`` times (the rod seal's film is sheared only one way; a
    model with a viscous term). A
    symmetric model leaves a residual even in ``v``: a step at every reversal,
    growing with speed on one side when the slopes differ.
    """

    name = "direction-asymmetry"
    Params = DirectionAsymmetryParams
    confounded = ("force-offset", "area-error")
    signature = "residual even in v: same-sign offset in both directions, step at reversals"
    experiment = "the same speed profile in both directions of travel, with the force zero " \
        "known (see force-offset)"
    experiments: ClassVar[Mapping[str, str]] = MappingProxyType({
        kind: "the same speed profile extending and retracting, with the force zero known "
              "(see force-offset)" for kind in ("pneumatic-cylinder", "hydraulic-cylinder")
    })

    def modify_levels(self, be: Backend, L: dict, w: list[Any], sig: Signals,
                      P: ParamValues) -> dict:
        return scale_levels(L, be.if_else(sig.s > 0, 1.0, P("r_neg")))

    def extra_force(self, be: Backend, sig: Signals, P: ParamValues) -> tuple[Any, Any]:
        visc = next((P(n) for n in ("sigma2", "B") if P.has(n)), None)
        if visc is None:  # no viscous term to differ between the directions
            return 0.0, 0.0
        return (P("rv_neg") - 1.0) * visc * be.fmin(sig.v, 0.0), 0.0

    @classmethod
    def diagnosis_forms(cls) -> tuple[DiagnosisForm, ...]:
        """The levels alone (the viscous ratio held at 1), and levels with the viscous ratio."""
        return (DiagnosisForm("levels", held=("rv_neg",)), DiagnosisForm("levels-viscous"))

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The ratio of the median retracting to extending force; with the viscous ratio,
        the slope of the residual while retracting relative to the viscous one."""
        form = form or "levels-viscous"
        m = view.moving
        v, y = view.signal("v"), view.y
        pos, neg = m & (v > 0), m & (v < 0)
        if pos.sum() < 3 or neg.sum() < 3:
            return [{"r_neg": 1.0}]
        a, b = float(np.median(y[pos])), float(np.median(-y[neg]))
        ratio = b / a if a > 0 and b > 0 else 1.0
        starts = [{"r_neg": float(np.clip(ratio, 0.2, 5.0))}]
        flat = view.params
        visc = flat.get("sigma2", flat.get("B", 0.0))
        if visc > 0 and form != "levels":
            c = ls_slope(view.residual[neg], v[neg])
            starts.append({"r_neg": 1.0, "rv_neg": float(np.clip(1.0 + c / visc, 0.1, 9.0))})
        return starts


#: The shortest stretch of the bore over which seal friction can change (m): a seal's
#: contact band is a millimetre or more and averages the bore over its width, so a
#: local box is at least this wide (``wb >= SEAL_BAND/2``) and its edges at least a
#: fifth of it (``eb``). A narrower box would not be a property of the bore but of
#: the samples at one position -- a rest point, where break-aways happen.
SEAL_BAND = 1e-3

PositionDependenceParams = make_params_class("PositionDependenceParams", [
    spec("kx1", "-", 0.0, -1.0, 1.0, "linear Legendre coefficient", directional=False),
    spec("kx2", "-", 0.0, -1.0, 1.0, "quadratic Legendre coefficient", directional=False),
    spec("kx3", "-", 0.0, -1.0, 1.0, "cubic Legendre coefficient", directional=False),
    spec("kb", "-", 0.0, -1.0, 3.0, "relative level change inside the local box (0: none)",
         directional=False),
    spec("xb", "m", 0.15, -INF, INF, "centre of the local box", directional=False),
    spec("wb", "m", 0.01, 0.5 * SEAL_BAND, INF, "half-width of the local box (at least "
         "half a seal's contact band)", directional=False),
    spec("eb", "m", 0.002, 0.2 * SEAL_BAND, INF, "edge width of the local box (at least a "
         "fifth of a seal's contact band)", directional=False),
], owner="effect position-dependence")


class PositionDependence(Effect):
    """Position dependence: levels scaled by a function of the stroke position ``x``.

    Bore tolerance, wear, rod bending and seal squeeze vary along the stroke,
    so friction does too (seed 001 measured break-away at 12 positions); a
    scored or worn stretch of the bore, or a tight spot, changes it over a
    short stretch only. The scale is

    ``1 + kx1*P1(xi) + kx2*P2(xi) + kx3*P3(xi) + kb*box(x)``

    with Legendre polynomials of ``xi = 2*(x - x_min)/(x_max - x_min) - 1``
    (``x_min``, ``x_max`` are configuration, default 0..0.3 m) for the smooth
    variation along the stroke, and a soft box for a local one,
    ``box(x) = (tanh((x - xb + wb)/eb) - tanh((x - xb - wb)/eb))/2``: centre
    ``xb``, half-width ``wb``, edge width ``eb`` (a narrow box with soft edges
    is a bump, a wide one reaching past the end of the stroke a step; the box is
    never narrower than a seal's contact band, :data:`SEAL_BAND`). A model
    without it leaves a residual that is a function of ``x``, repeated on every
    stroke, of the friction's sign. The scale is floored at 1 %
    (:data:`~fcomp.effects.base.LEVEL_FLOOR`).
    """

    name = "position-dependence"
    Params = PositionDependenceParams
    needs = ("x",)
    signature = "residual a function of x, repeated stroke after stroke (smooth or local)"
    experiment = "the same slow stroke repeated, break-away measured along the stroke"
    experiments: ClassVar[Mapping[str, str]] = MappingProxyType({
        "electromechanical-axis": "the same slow travel over the whole axis repeated, "
                                  "break-away measured along it (screw and guides)",
    })

    def modify_levels(self, be: Backend, L: dict, w: list[Any], sig: Signals,
                      P: ParamValues) -> dict:
        x_min = float(self.config.get("x_min", 0.0))
        x_max = float(self.config.get("x_max", 0.3))
        xi = 2.0 * (sig.x - x_min) / (x_max - x_min) - 1.0
        p2 = 0.5 * (3.0 * xi * xi - 1.0)
        p3 = 0.5 * (5.0 * xi * xi * xi - 3.0 * xi)
        xb, wb, eb = P("xb"), P("wb"), P("eb")
        box = 0.5 * (be.tanh((sig.x - xb + wb) / eb) - be.tanh((sig.x - xb - wb) / eb))
        return scale_levels(L, 1.0 + P("kx1") * xi + P("kx2") * p2 + P("kx3") * p3
                            + P("kb") * box, be=be)

    @classmethod
    def diagnosis_config(cls, scales: Scales) -> dict[str, Any]:
        """The stroke's ends: the record's position range, padded by 2 % of the stroke."""
        pad = 0.02 * scales.stroke
        return {"x_min": scales.x_min - pad, "x_max": scales.x_max + pad}

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """Legendre coefficients by least squares, and a local box where the rest peaks.

        The sign-corrected training residual of the moving samples is regressed on
        ``|F_hat|*P_k(xi)`` (the smooth part); what remains, relative to
        ``|F_hat|``, is averaged in bins of 0.5 % of the stroke and its largest
        excursion (three bins smoothed) gives the box: centre, half-width (where it
        stays above half the peak), amplitude. Starts: the smooth part alone, the
        smooth part with the box, the box alone, and a step (:func:`_step_start`).
        """
        m = view.moving
        cfg = self.diagnosis_config(view.scales)
        x = view.signal("x")
        xi = 2.0 * (x - cfg["x_min"]) / (cfg["x_max"] - cfg["x_min"]) - 1.0
        F = np.abs(view.F_hat)
        cols = np.column_stack([F * xi, F * 0.5 * (3 * xi**2 - 1),
                                F * 0.5 * (5 * xi**3 - 3 * xi)])
        rs = np.sign(view.signal("v")) * view.residual
        coef, *_ = np.linalg.lstsq(cols[m], rs[m], rcond=None)
        coef = np.clip(coef, -0.9, 0.9)
        smooth_part = {"kx1": float(coef[0]), "kx2": float(coef[1]), "kx3": float(coef[2]),
                       "kb": 0.0}
        sc = view.scales
        level = np.maximum(F[m], 1e-3 * sc.force)
        rel = (rs - cols @ coef)[m] / level
        width = max(0.005 * sc.stroke, 2.0 * sc.resolution)
        edges = np.arange(sc.x_min, sc.x_max + width, width)
        k = np.clip(np.digitize(x[m], edges) - 1, 0, max(edges.size - 2, 0))
        count = np.bincount(k, minlength=edges.size - 1)
        if edges.size < 4 or (count >= 5).sum() < 4:
            return [smooth_part]
        mean = np.where(count >= 5, np.bincount(k, rel, minlength=edges.size - 1)
                        / np.maximum(count, 1), 0.0)
        sm = np.convolve(mean, np.ones(3) / 3.0, mode="same")
        j = int(np.argmax(np.abs(sm)))
        peak = float(sm[j])
        lo = hi = j
        while (lo > 0 and abs(sm[lo - 1]) > 0.5 * abs(peak)
               and np.sign(sm[lo - 1]) == np.sign(peak)):
            lo -= 1
        while (hi < sm.size - 1 and abs(sm[hi + 1]) > 0.5 * abs(peak)
               and np.sign(sm[hi + 1]) == np.sign(peak)):
            hi += 1
        eb = float(max(0.25 * width, sc.resolution, 0.2 * SEAL_BAND))
        box = {"kb": float(np.clip(peak, -0.9, 2.9)),
               "xb": float(0.5 * (edges[lo] + edges[hi + 1])),
               "wb": float(max(0.5 * (edges[hi + 1] - edges[lo]), 0.5 * SEAL_BAND)),
               "eb": eb}
        none = {"kx1": 0.0, "kx2": 0.0, "kx3": 0.0}
        step = _step_start(rs[m] / level, k, count, edges)
        return [smooth_part, {**smooth_part, **box}, {**none, **box}, {**none, **step, "eb": eb}]


def _step_start(rel: np.ndarray, k: np.ndarray, count: np.ndarray, edges: np.ndarray
                ) -> dict[str, float]:
    """A step along the stroke (a worn or scored zone from ``x_s`` to the end): the box
    of :class:`PositionDependence` reaching past the far end of the stroke, from the
    split that best separates two levels of the relative residual ``rel`` (binned by
    ``k``), without the smooth part -- the Legendre cubic absorbs most of a step and
    leaves the box start of :meth:`PositionDependence.guess` at a ripple of its own.

    The split maximises the between-level sum of squares ``n_l*n_r/n*(m_l - m_r)^2``
    over the bins with samples; ``kb`` is the far side's level relative to the near
    side's, ``(m_r - m_l)/(1 + m_l)``. The bins used are those of at least five samples
    (the caller has four or more).
    """
    used = count >= 5
    sums = np.bincount(k, rel, minlength=count.size)[used]
    n = count[used].astype(float)
    right_edges = edges[1:][used]
    cn, cs = np.cumsum(n)[:-1], np.cumsum(sums)[:-1]
    ml, mr = cs / cn, (sums.sum() - cs) / (n.sum() - cn)
    j = int(np.argmax(cn * (n.sum() - cn) / n.sum() * (ml - mr) ** 2))
    kb = float(np.clip((mr[j] - ml[j]) / max(1.0 + ml[j], 0.1), -0.9, 2.9))
    span = float(edges[-1] - edges[0])
    x_s = float(right_edges[j])
    return {"kb": kb, "xb": x_s + span, "wb": span}


DwellTimeParams = make_params_class("DwellTimeParams", [
    spec("dFs", "N", 0.0, 0.0, INF, "break-away increase after a long dwell"),
    spec("tau_dwell", "s", 1.0, 0.0, INF, "ageing time constant", lower_open=True,
         directional=False),
    spec("L_dwell", "m", 1e-4, 0.0, INF, "sliding distance that erases the age",
         lower_open=True, directional=False),
    spec("k_dwell", "-", 0.0, 0.0, 5.0, "ageing shape: 0 exponential (Kato), > 0 "
         "towards logarithmic (Dieterich)", directional=False),
    spec("v_rest", "m/s", 1e-5, 0.0, INF, "speed scale of rest (fixed): ageing "
         "weighted by exp(-|v|/v_rest)", lower_open=True, directional=False),
], owner="effect dwell-time")


class DwellTime(Effect):
    """Dwell-time dependence: static friction rising with time at rest.

    At rest, seal asperities creep and the rubber settles into the surface
    texture; the longer the stop the higher the next break-away force. The
    contact "age" ``w`` in [0, 1] grows while the piston rests and is erased
    by sliding (Rabinowicz; Kato et al.; the ageing term of Dieterich-Ruina
    rate-and-state friction restricted to rest)::

        dw/dt = r(v)*(1 - w)^(1 + k)/tau_dwell - w*|v|/L_dwell,   r(v) = exp(-|v|/v_rest)

    and raises the friction level by ``dFs*w`` in one of two forms (``form=``):

    ``"static"`` (the default)
        the static level, ``Fs -> Fs + dFs*w``: the Stribeck hump grows and,
        like it, fades above the Stribeck speed (the dwell-dependent static
        friction of Armstrong-Helouvry's seven-parameter model);
    ``"level"``
        the whole curve, ``Fc -> Fc + dFs*w`` and ``Fs -> Fs + dFs*w``: the
        excess is erased by the sliding distance alone, at any speed (the
        state of rate-and-state friction).

    The two are one law for models without ``Fs`` (``Fc -> Fc + dFs*w``).
    After a dwell ``t_d`` from ``w = 0`` the age is
    ``1 - exp(-t_d/tau_dwell)`` for ``k = 0`` (Kato's exponential law) and
    ``1 - (1 + k*t_d/tau_dwell)^(-1/k)`` for ``k > 0``, which grows about
    logarithmically over the middle decades (Dieterich's log ageing); it is
    erased over a sliding distance ``L_dwell``. ``r(v)`` limits the ageing to
    rest (``v_rest``, fixed, far below any sliding speed), so the effect adds no
    force while sliding. A model without it leaves positive spikes at
    break-away whose height grows with the dwell time before the start.
    """

    name = "dwell-time"
    FORMS: ClassVar[tuple[str, ...]] = ("static", "level")
    states = ("w",)
    initial = (0.0,)
    Params = DwellTimeParams
    fixed: ClassVar[tuple[str, ...]] = ("v_rest",)
    signature = "break-away spikes growing with the dwell time before the start"
    experiment = "starts after dwells of different lengths (0.1 s to 10 s)"
    dynamic = True

    def modify_levels(self, be: Backend, L: dict, w: list[Any], sig: Signals,
                      P: ParamValues) -> dict:
        out = dict(L)
        keys = ("Fs",) if "Fs" in out and self.form == "static" else ("Fc", "Fs")
        for key in keys:
            if key in out:
                out[key] = out[key] + P("dFs", sig.s) * w[0]
        return out

    @classmethod
    def diagnosis_forms(cls) -> tuple[DiagnosisForm, ...]:
        """Both forms: the hump grows, or the whole curve."""
        return tuple(DiagnosisForm(f, {"form": f}) for f in cls.FORMS)

    @classmethod
    def forms_for(cls, model: FrictionModel) -> tuple[DiagnosisForm, ...]:
        """Both forms where the model has a static level ``Fs``; one law without it."""
        forms = cls.diagnosis_forms()
        flat = model.flat_params()
        return forms if any(n == "Fs" or n.startswith("Fs_") for n in flat) else forms[:1]

    def rhs(self, be: Backend, w: list[Any], sig: Signals, P: ParamValues) -> list:
        rest = be.exp(-be.abs(sig.v) / P("v_rest"))
        young = be.power(be.fmax(1.0 - w[0], 1e-30), 1.0 + P("k_dwell"))
        return [rest * young / P("tau_dwell") - w[0] * be.abs(sig.v) / P("L_dwell")]

    def steady_state(self, be: Backend, sig: Signals, P: ParamValues) -> list:
        # exact for k = 0; at any sliding speed r(v) ~ 0 and the age is ~0
        L, tau = P("L_dwell"), P("tau_dwell")
        rest = be.exp(-be.abs(sig.v) / P("v_rest"))
        return [L * rest / (L * rest + be.abs(sig.v) * tau)]

    def unsuitable(self, view: RecordView) -> str | None:
        """A record without a start after a dwell cannot show it."""
        return None if view.dwell_starts else "the record has no start after a dwell"

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """Break-away peaks of the residual against the dwell time before each start."""
        x, v = view.signal("x"), view.signal("v")
        r = view.residual
        zone = 3.0 * view.d_pre
        dwells, peaks = [], []
        for k, dw in view.dwell_starts:
            j = k
            s = math.copysign(1.0, v[k]) if v[k] != 0 else 1.0
            while j < view.n and abs(x[j] - x[k]) < zone and j - k < 10_000:
                j += 1
            win = slice(k, max(j, k + 1))
            sel = view.train[win]
            if sel.any():
                dwells.append(dw)
                peaks.append(float(np.max(s * r[win][sel])))
        level = view.level
        if len(dwells) < 2:
            return [{"dFs": 0.2 * level, "tau_dwell": 1.0, "L_dwell": 2 * view.d_pre}]
        d, p = np.array(dwells), np.array(peaks)
        best = None
        for tau in np.geomspace(max(d.min(), 0.01), max(d.max(), 0.02), 5):
            A = np.column_stack([np.ones_like(d), 1.0 - np.exp(-d / tau)])
            coef, *_ = np.linalg.lstsq(A, p, rcond=None)
            cost = float(np.sum((p - A @ coef) ** 2))
            if best is None or cost < best[0]:
                best = (cost, max(float(coef[1]), 0.05 * level), float(tau))
        _, dFs, tau = best  # type: ignore[misc]
        L = max(2 * view.d_pre, 20 * view.scales.resolution)
        return [{"dFs": dFs, "tau_dwell": tau, "L_dwell": L},
                {"dFs": dFs, "tau_dwell": tau, "L_dwell": 8 * L},
                {"dFs": 1.5 * dFs, "tau_dwell": 0.3 * tau, "L_dwell": 2 * L, "k_dwell": 1.0}]


InertiaErrorParams = make_params_class("InertiaErrorParams", [
    spec("dm", "kg", 0.0, -INF, INF, "mass error (true minus assumed)", directional=False),
], owner="effect inertia-error")


class InertiaError(Effect):
    """Inertia error: a mass correction ``dm*a`` in the reconstructed force.

    The friction force reconstructed as ``p1*A1 - p2*A2 - m*a`` carries
    ``-(m_true - m)*a`` when the moving mass is wrong (forgotten fittings,
    oil in the rod, a load). A model without it leaves a residual
    proportional to the acceleration at every speed, largest at reversals of
    a fast sine, independent of the friction's sign.
    """

    name = "inertia-error"
    Params = InertiaErrorParams
    # sigma2*T*a while sliding is dm*a there; a force reconstructed from the pressures is
    # F + m*a, so an area error carries a share of m*a too
    confounded = ("viscous-lead", "area-error")
    signature = "residual proportional to acceleration at all speeds"
    experiment = "the same motion with a known added mass"
    needs = ("a",)
    dynamic = True

    def extra_force(self, be: Backend, sig: Signals, P: ParamValues) -> tuple[Any, Any]:
        return 0.0, P("dm")

    def unsuitable(self, view: RecordView) -> str | None:
        """A fitted mass already holds any mass error."""
        return ("the mass is already fitted (no rig.mass): a mass error is part of it"
                if view.fits_mass else None)

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The residual regressed on the acceleration."""
        m = view.train
        return [{"dm": ls_slope(view.residual[m], view.signal("a")[m])}]


ForceOffsetParams = make_params_class("ForceOffsetParams", [
    spec("offset", "N", 0.0, -INF, INF, "constant force offset", directional=False),
], owner="effect force-offset")


class ForceOffset(Effect):
    """Force offset: a constant bias of the force sensor or pressure transducers.

    Load-cell zero drift or a pressure-sensor offset adds a constant to the
    measured force. A model without it leaves a residual with a non-zero
    mean of the same sign in both directions, unrelated to ``v``, ``x`` or
    the pressures.
    """

    name = "force-offset"
    Params = ForceOffsetParams
    # the same force while sliding: only rest tells; at one pressure level an area error
    # is a constant too
    confounded = ("direction-asymmetry", "area-error")
    signature = "residual with a constant non-zero mean in both directions"
    experiment = "a zero reading of the force measurement at rest with nothing driving or " \
        "loading the actuator"
    experiments: ClassVar[Mapping[str, str]] = MappingProxyType({
        "pneumatic-cylinder": "a zero-force reading at rest with the chambers vented",
        "hydraulic-cylinder": "a zero-force reading at rest with the pump off and both "
                              "chambers relieved to tank",
        "friction-rig": "a zero reading of the load cell at rest with the drive disconnected",
        "electromechanical-axis": "a zero reading of the motor force with the drive disabled "
                                  "(current-sensor offset) and a level check of the axis (a "
                                  "tilt adds a constant m*g*sin(angle))",
    })

    def extra_force(self, be: Backend, sig: Signals, P: ParamValues) -> tuple[Any, Any]:
        return P("offset"), 0.0

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The mean training residual."""
        return [{"offset": float(np.mean(view.residual[view.train]))}]


#: Largest area error the diagnosis fits (m^2): 5 % of the piston area of a 100 mm bore.
#: The fit's box is this (``m^2`` has no data scale in
#: :func:`fcomp.diagnosis.refit.data_bounds`: its +-20 unit scales are +-20 m^2).
AREA_ERROR_BOUND = 0.05 * math.pi / 4 * 0.1**2

AreaErrorParams = make_params_class("AreaErrorParams", [
    spec("dA1", "m^2", 0.0, -AREA_ERROR_BOUND, AREA_ERROR_BOUND,
         "area error of chamber 1: nominal A1 minus the effective pressurised area",
         directional=False),
    spec("dA2", "m^2", 0.0, -AREA_ERROR_BOUND, AREA_ERROR_BOUND,
         "area error of chamber 2: nominal A2 minus the effective pressurised area",
         directional=False),
], owner="effect area-error")


class AreaError(Effect):
    """Area error: the pressure force reconstructed with areas the pressure does not act on.

    The friction force is reconstructed as ``p1*A1 - p2*A2 + F_ext - m*a`` with
    the nominal areas ``A1 = pi/4*bore^2`` and ``A2 = pi/4*(bore^2 - rod^2)``
    (models.md 3). The area the pressure actually acts on differs: a seal lip
    or an O-ring in its groove is pressurised on part of its own face, so the
    effective diameter lies between bore and groove bottom (about 1 % of the
    area); bore and rod tolerances, a cushioning spigot or a wrong rod
    diameter add to it. With ``dA1``, ``dA2`` the nominal minus the effective
    areas, the reconstructed force carries::

        F_add = dA1*p1 - dA2*p2

    (gauge pressures). A model without it leaves a residual proportional to
    the pressures that does not change sign with the direction of travel: at
    a constant pressure a constant offset, so ``|F|`` is larger in one
    direction than in the other by ``2*F_add`` -- the same force as a
    direction asymmetry of the levels or a force offset while sliding
    (confounded with both); across pressure levels it grows with the
    pressure, in both directions alike, and at rest against a stop it is all
    the force left. A chamber whose pressure is constant over the record
    (vented: ``p2 = 0``) leaves its coefficient a constant force the record
    cannot tell from an offset: it is held at 0 (:meth:`held`).
    """

    name = "area-error"
    Params = AreaErrorParams
    needs = ("p1", "p2")
    # the pressure force of a reconstructed record is F + m*a: an area error scales the
    # inertia term as a mass error does (at rest, with a = 0, only the area error is left)
    confounded = ("direction-asymmetry", "force-offset", "inertia-error")
    signature = ("residual proportional to the pressures, the same sign in both directions "
                 "(|F| larger one way)")
    experiment = ("the force held at rest at several driving pressures, or the same motion "
                  "at several pressure levels in both directions of travel")
    experiments: ClassVar[Mapping[str, str]] = MappingProxyType({
        "pneumatic-cylinder": "the force at rest against a stop at several chamber pressures "
                              "(each chamber alone), or the same motion at several pressures "
                              "extending and retracting",
        "hydraulic-cylinder": "the force at rest against a stop (or a load cell) at several "
                              "pressures in each chamber, or the same motion at several "
                              "supply pressures extending and retracting",
        "friction-rig": "a calibration of the force reading at rest against known loads at "
                        "several normal-force levels (a gain error of the force channel)",
        "electromechanical-axis": "the motor force held against a load cell at rest at "
                                  "several force levels (a force-constant error; the axis "
                                  "has no fluid pressure)",
    })

    def extra_force(self, be: Backend, sig: Signals, P: ParamValues) -> tuple[Any, Any]:
        return P("dA1") * sig.p1 - P("dA2") * sig.p2, 0.0

    def unsuitable(self, view: RecordView) -> str | None:
        """An area error is seen only where the pressures and an *independent* force
        channel make up the force (a load cell on the rod, ``F_ext``, and the chamber
        pressures: ``F = F_ext + p1*A1 - p2*A2 - m*a``).

        A force column measured on the friction (``F``) holds no pressure force, so no
        area can be wrong in it. Where the pressures *are* the force sensor
        (``p1*A1 - p2*A2 - m*a`` alone), ``dA1*p1 - dA2*p2`` is a gain on the measured
        force itself plus a term in the pressure sum: the "prediction" would carry the
        measurement, noise and every unexplained structure included, and take a share
        of any residual (a ripple, a drift) -- a gain error of the only force channel
        cannot be told from the friction's level without a second force reading.
        """
        if view.source == "F" or "F" in view.force_channels:
            return ("the force is measured directly (an F column), not reconstructed from "
                    "the pressures: no area enters it")
        if view.force_channels and "F_ext" not in view.force_channels:
            return ("the pressures are the only force sensor: an area error is a gain of "
                    "the measured force itself, not separable from the friction level "
                    "without a second force reading (a load cell, F_ext)")
        return None

    def held(self, view: RecordView) -> list[str]:
        """The area error of a chamber whose pressure is constant over the training samples
        (:func:`constant_chambers`: vented, ``p2 = 0``), and ``dA2`` where the two pressures
        move together (centred, one a multiple of the other: only one combination is
        determined): held at 0."""
        still = constant_chambers(view)
        out = [n for n, p in (("dA1", "p1"), ("dA2", "p2")) if p in still]
        if not out:
            m = view.train
            cols = np.column_stack([view.signal("p1")[m], -view.signal("p2")[m]])
            use = distinct_columns(cols - cols.mean(axis=0))
            out = [n for i, n in enumerate(("dA1", "dA2")) if i not in use]
        return out

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The training residual regressed on ``p1`` and ``-p2`` by least squares (the
        chambers :meth:`held` leaves out at 0): through the origin, and with an intercept
        (the slopes alone, where the residual also holds an offset)."""
        m = view.train
        held = set(self.held(view))
        names = [n for n in ("dA1", "dA2") if n not in held]
        out: dict[str, float] = {"dA1": 0.0, "dA2": 0.0}
        if not names or not m.any():
            return [out]
        p = {"dA1": view.signal("p1")[m], "dA2": -view.signal("p2")[m]}
        cols = np.column_stack([p[n] for n in names])
        r = view.residual[m]
        starts = []
        for design in (cols, np.column_stack([cols, np.ones(cols.shape[0])])):
            coef, *_ = np.linalg.lstsq(design, r, rcond=None)
            start = dict(out)
            for n, c in zip(names, coef, strict=False):
                value = float(c) if math.isfinite(c) else 0.0
                start[n] = float(np.clip(value, -AREA_ERROR_BOUND, AREA_ERROR_BOUND))
            starts.append(start)
        return starts


NonlocalMemoryParams = make_params_class(
    "NonlocalMemoryParams",
    [*hysteresis_specs(NONLOCAL_MEMORY_DEFAULTS),
     *(FAMILY_SPECS[n] for n in FEATURE_PARAMS["elements"])],
    owner="effect nonlocal-memory", constraints=HYSTERESIS_CONSTRAINTS,
)


class NonlocalMemory(StructuralEffect):
    """Nonlocal memory: pre-sliding friction that remembers earlier reversal points.

    In pre-sliding the asperity junctions of the seal deform elastically and
    plastically: the force-displacement curve after each reversal starts
    stiff and softens, and its course depends on the earlier reversal points,
    not only on the current state (seed 000 Figs. 10-11): minor loops close,
    and once the displacement passes an earlier reversal point the curve goes
    on as if the minor loop had never happened (wiping-out). The LuGre bristle
    is one spring with local memory (stiffness ``sigma0`` after every reversal,
    lens-shaped loops). A model without this effect leaves residuals at small
    displacements that follow the displacement since the last reversal: the
    model is too soft just after a reversal and the loop shape is wrong, and
    after a minor loop an offset remains that the data erase once the earlier
    reversal point is passed.

    Two forms (configuration ``form``; models.md 1.8: "the hysteresis function
    of 1.6 (or GMS elements)"):

    ``"hysteresis"`` (default)
        seed 000's hysteresis function ``F(z)`` in place of ``sigma0*z``
        (:mod:`fcomp.models.hysteresis`, Tables 2-3; discrete turning-point
        memory, numeric only). Its defaults -- zero segment widths and
        amplitudes -- make every transition curve the continuation with slope
        ``sigma0``: a no-op.
    ``"maxwell-slip"``
        the bristle split into parallel Maxwell-slip elements (the ``elements``
        feature of :mod:`fcomp.models.lugre_family`: ``ms_spread``, ``ms_shape``;
        continuous states, exact sensitivities). ``ms_spread = 1`` is the
        bristle itself: a no-op. The diagnosis fits this form.

    Needs a bristle state (``presliding``).
    """

    name = "nonlocal-memory"
    FORMS: ClassVar[tuple[str, ...]] = ("hysteresis", "maxwell-slip")
    Params = NonlocalMemoryParams
    signature = ("small-displacement residual following travel since reversal; minor-loop "
                 "offsets erased past earlier reversal points")
    experiment = "small displacement cycles with nested minor loops (seed 000 Figs. 10, 16)"
    dynamic = True
    #: within the presliding travel after a reversal or a start; in steady sliding every
    #: element slips and the force is the bristle's (matrix seeds 131/149: 99-100 % of
    #: the held-out fall of true nonlocal-memory records lies there, 47 % where
    #: nonlocal-memory absorbed a pressure law's misfit)
    acts_in = ("pre-sliding", "reversal", "dwell/break-away")

    @classmethod
    def diagnosis_config(cls, scales: Scales) -> dict[str, Any]:
        """The form with continuous states and exact sensitivities."""
        return {"form": "maxwell-slip"}

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """Maxwell-slip elements carrying most of the level, spread over one and two decades.

        The slip displacement of the softest element starts at three presliding
        lengths (the fitted bristle's ``Fc/sigma0``, else the record's); the
        elements' stiffness either constant (GMS) or scaling with the slip level
        (constant slip displacements), their shares equal. The bristle keeps its
        fitted stiffness for the share it still carries.
        """
        flat = view.params
        level = flat.get("Fc", flat.get("Fc_pos", view.level))
        s0 = flat.get("sigma0", level / view.d_pre)
        d_pre = level / s0 if s0 > 0 else view.d_pre
        out = []
        for spread, scaling in ((10.0, 0.0), (100.0, 0.0), (10.0, 1.0), (100.0, 1.0)):
            out.append({"ms_share": 0.9, "ms_dmax": 3.0 * d_pre, "ms_spread": spread,
                        "ms_shape": 0.0, "ms_scaling": scaling})
        return out

    @classmethod
    def config_in(cls, model: FrictionModel) -> dict[str, Any]:
        """``hysteresis`` for a model with the turning-point memory, else ``maxwell-slip``."""
        return {"form": "hysteresis" if model.discrete_memory() is not None else "maxwell-slip"}

    def applies_to(self, model: FrictionModel) -> bool:
        features = _features(model)
        return (features is not None and "presliding" in features
                and "elements" not in features and model.discrete_memory() is None)

    def attach(self, model: FrictionModel) -> FrictionModel:
        fam = _family(model, self.name)
        if model.discrete_memory() is not None or "elements" in fam.features:
            raise ValueError(f"model {fam.describe()!r} already has effect {self.name!r}")
        if "presliding" not in fam.features:
            raise ValueError(
                f"effect 'nonlocal-memory' replaces the bristle force sigma0*z: add "
                f"'presliding' to {fam.describe()!r} first"
            )
        flat = self.params.flat()
        shape = FEATURE_PARAMS["elements"]
        if self.form == "maxwell-slip":
            new = fam.with_features({"elements"}, {k: flat[k] for k in shape})
        else:
            new = with_hysteresis(fam, {k: v for k, v in flat.items() if k not in shape})
        new.lineage = (*(fam.lineage or (fam.name,)), self.name)
        return new


CATALOGUE: tuple[type[Effect], ...] = (
    Viscous, Stribeck, Presliding, FrictionalLag, DwellTime, DirectionAsymmetry,
    PressureDependence, PositionDependence, ViscousLead, InertiaError, ForceOffset,
    AreaError, NonlocalMemory,
)
for _cls in CATALOGUE:
    EFFECTS.register(_cls.name, _cls)
