"""Plausibility of a fit's estimates: what a careful engineer would question before using them.

A least-squares fit always returns numbers; whether they mean anything is a
separate question. :func:`check_fit` answers it from the numbers alone -- the
estimates, their standard errors, confidence intervals and correlations, the
box the solver searched, whether it converged -- and what the sidecar says
about the rig (:class:`RigContext`). It needs no fit object, so every fit
(``fcomp fit``, the diagnosis's refits, a user's own) can be checked the same
way. Each finding is a :class:`FitWarning` (docs/identification.md, "Warnings"):

``at-bound``
    An estimate at, or within :data:`BOUND_HAIR` of, a bound of its box: the
    data push it beyond the allowed range, its standard error means nothing.
``interval-crosses-zero``
    A quantity that must be positive (its box starts at 0) whose interval
    reaches zero or below: the record does not establish the term.
``mass-implausible``
    A fitted moving mass off by more than :data:`MASS_RATIO` from the
    sidecar's ``rig.mass`` (outside ``[0.5, 2]`` times it), or, without it,
    outside what the piston geometry allows (:func:`mass_range`: below half an
    aluminium piston ``0.2*D`` long, 3.3 g for a 25 mm bore, "the record does
    not determine the moving mass"), or above :data:`LOAD_FACTOR` (10) times
    a solid steel piston and rod (:func:`steel_piston_mass`: 7850 kg/m^3, a
    piston of the bore's area one bore long plus a rod of ``rig.rod`` over
    ``rig.stroke``; 0.096 kg for a bare 25 mm bore, so a flag above 0.96 kg):
    a load that heavy must be stated (``rig.mass``, ``--mass``), a fitted one
    is usually a mass trading off with other terms.
``not-identified``
    An infinite standard error (a parameter the record does not determine,
    held), a standard error above :data:`HUGE_RELATIVE_ERROR` times a positive
    value, or two parameters that trade off (``|correlation| >``
    :data:`MAX_CORRELATION`). The message names the experiment that would
    determine it (:func:`fcomp.effects.experiment_for`, worded for the rig).
``not-converged``
    The solver stopped before converging.

A parameter gets at most one of ``at-bound``, ``not-identified`` (by its own
standard error) and ``interval-crosses-zero``, in that order: a value at a
bound has no meaningful error, and a huge error implies the interval.

Rig terms a fit estimated once and then held for the fits that follow (the
diagnosis's driving-force channel ``lag``, :meth:`fcomp.diagnosis.refit.Refit.hold`)
have no standard error of their own; :func:`check_held` checks their values
(:data:`HELD_CODES`):

``at-bound``
    As above: the held value is at a bound of its box (``lag``: +-20 ms).
``lag-negative``
    A channel lag below ``-LEAD_SAMPLES`` sample intervals: the force leads the
    motion, which no sensor or line lag does -- a timing offset between the
    channels (separate clocks, a delayed motion signal) or a wrong sign.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fcomp.effects import effect_of_parameter, experiment_for
from fcomp.piston import piston_areas

#: Codes of :class:`FitWarning`, in the order the checks run.
CODES = ("not-converged", "at-bound", "not-identified", "interval-crosses-zero",
         "mass-implausible")
#: An estimate within this fraction of ``max(|bound|, |value|, stderr)`` of a bound is at it.
BOUND_HAIR = 1e-6
#: A positive quantity whose standard error exceeds this many times its value is not
#: identified (its 95 % interval spans about 40 times the value).
HUGE_RELATIVE_ERROR = 10.0
#: Two estimates with a larger absolute correlation trade off: the record fixes a
#: combination of them, not each.
MAX_CORRELATION = 0.99
#: A fitted mass further than this factor from the sidecar's ``rig.mass`` is implausible.
MASS_RATIO = 2.0
#: Densities (kg/m^3) of the lightest and heaviest usual piston and rod materials.
RHO_ALUMINIUM = 2700.0
RHO_STEEL = 7850.0
#: Piston length as a fraction of the bore: the thinnest plausible piston (lower limit of
#: the mass) and a long one (upper limit).
PISTON_LENGTH_MIN = 0.2
PISTON_LENGTH_MAX = 1.0
#: The lower limit is this fraction of the aluminium piston and rod (hollow or plastic parts:
#: a 3D-printed piston has about half the density of aluminium).
FLOOR_FRACTION = 0.5
#: The upper limit is this many times the steel piston and rod: the load a cylinder
#: positions is at most a few hundred times its piston and rod (seed 002's hydraulic
#: servo: 118 kg on a 30 mm bore with a 16 mm rod, about 170 times).
CEILING_FACTOR = 1000.0
#: Without a bore: no moving part weighs less than a gram, and no servo positions 100 t.
MIN_MASS = 1e-3
MAX_MASS = 1e5
#: Without a stated ``rig.mass``, a fitted mass above this many times a solid steel piston
#: and rod (:func:`steel_piston_mass`) is flagged: a bare cylinder's piston, rod and carriage
#: weigh less; a heavier load is possible (seed 002's servo: 118 kg on a 30/16 mm cylinder)
#: but must be stated, a fitted one is usually a mass trading off with other terms (the
#: 34, 3.9 and 1.87 kg fitted on the 25 mm Zillen piston, limit 0.96 kg).
LOAD_FACTOR = 10.0
#: Codes of :func:`check_held`.
HELD_CODES = ("at-bound", "lag-negative")
#: A held channel lag below minus this many sample intervals is a lead, not rounding.
LEAD_SAMPLES = 1.0


@dataclass(frozen=True)
class FitWarning:
    """One plausibility finding of a fit (the JSON ``warnings`` items).

    Attributes
    ----------
    code
        One of :data:`CODES`.
    parameter
        The flat parameter name (``Fc``, ``sigma0_pos``, ``mass``), ``A,B`` for a
        pair that trades off, ``None`` for the fit as a whole.
    message
        One line: what was found, and what to do about it.
    """

    code: str
    parameter: str | None
    message: str

    def to_dict(self) -> dict[str, str | None]:
        """``{"code", "parameter", "message"}`` (the contract's warning item)."""
        return {"code": self.code, "parameter": self.parameter, "message": self.message}


@dataclass(frozen=True)
class RigContext:
    """What the sidecar says about the rig, for the checks (SI units).

    Attributes
    ----------
    kind
        The sidecar's ``kind`` (``pneumatic-cylinder``, ``hydraulic-cylinder``,
        ``friction-rig``, ``electromechanical-axis``; ``""`` if not given).
    mass
        The known moving mass (kg): ``rig.mass`` or one given with the fit.
    bore, rod, stroke
        Piston and rod diameters and the stroke (m), where given.
    """

    kind: str = ""
    mass: float | None = None
    bore: float | None = None
    rod: float | None = None
    stroke: float | None = None

    @classmethod
    def from_meta(cls, meta: Mapping[str, Any], mass: float | None = None) -> RigContext:
        """The context of a measurement's sidecar ``meta``; ``mass`` overrides ``rig.mass``."""
        rig = meta.get("rig") or {}

        def length(key: str) -> float | None:
            value = rig.get(key)
            return float(value) if isinstance(value, int | float) and value > 0 else None

        known = mass if mass is not None else rig.get("mass")
        return cls(str(meta.get("kind") or ""),
                   float(known) if isinstance(known, int | float) else None,
                   length("bore"), length("rod"), length("stroke"))


def mass_range(context: RigContext) -> tuple[float, float, str]:
    """``(low, high, basis)``: the moving masses (kg) the rig makes plausible, and why.

    With a bore ``D`` (rod ``d`` and stroke ``L`` where given): at least
    :data:`FLOOR_FRACTION` of an aluminium piston ``PISTON_LENGTH_MIN*D`` long
    plus an aluminium rod of length ``L``; at most :data:`CEILING_FACTOR` times
    a steel piston ``PISTON_LENGTH_MAX*D`` long plus a steel rod of length
    ``L + D``. Without a bore: :data:`MIN_MASS` to :data:`MAX_MASS`. This is
    what a rig can carry at all; :func:`check_fit` also flags a fitted mass above
    :data:`LOAD_FACTOR` times :func:`steel_piston_mass` that ``rig.mass`` does not state.
    """
    if context.bore is None:
        return MIN_MASS, MAX_MASS, "any moving part of a rig"
    D = context.bore
    d = context.rod or 0.0
    L = context.stroke or 0.0

    A1, A2 = piston_areas(D, d)

    def parts(piston_length: float, rod_length: float) -> float:  # volume, m^3
        return A1 * piston_length + (A1 - A2) * rod_length

    low = FLOOR_FRACTION * RHO_ALUMINIUM * parts(PISTON_LENGTH_MIN * D, L)
    high = CEILING_FACTOR * RHO_STEEL * parts(PISTON_LENGTH_MAX * D, L + D)
    rod = f", rod {1e3 * d:.3g} mm, stroke {1e3 * L:.3g} mm" if d and L else ""
    return low, high, f"the piston of the {1e3 * D:.3g} mm bore{rod}"


def steel_piston_mass(context: RigContext) -> float | None:
    """Mass (kg) of a solid steel piston and rod of the rig's geometry, ``None`` without a bore.

    Density :data:`RHO_STEEL` (7850 kg/m^3); a piston of the bore's area
    ``PISTON_LENGTH_MAX*D`` (one bore) long plus a rod of diameter ``rig.rod``
    and length ``rig.stroke`` (none where not given): 0.096 kg for a bare
    25 mm bore. :data:`LOAD_FACTOR` times it is the largest fitted mass
    believed without a stated ``rig.mass``.
    """
    if context.bore is None:
        return None
    D = context.bore
    A1, A2 = piston_areas(D, context.rod or 0.0)
    return RHO_STEEL * (A1 * PISTON_LENGTH_MAX * D + (A1 - A2) * (context.stroke or 0.0))


def correlations(names: Sequence[str], cov: np.ndarray) -> dict[tuple[str, str], float]:
    """Correlation of every pair ``(names[i], names[j])``, ``i < j``, from a covariance
    matrix in the order of ``names`` (pairs with a non-finite variance are left out)."""
    cov = np.asarray(cov, dtype=float)
    se = np.sqrt(np.abs(np.diag(cov))) if cov.size else np.zeros(0)
    out: dict[tuple[str, str], float] = {}
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            if se[i] > 0 and se[j] > 0 and np.isfinite(cov[i, j]) and np.isfinite(se[[i, j]]).all():
                out[(names[i], names[j])] = float(cov[i, j] / (se[i] * se[j]))
    return out


def check_fit(
    values: Mapping[str, float],
    stderr: Mapping[str, float],
    ci: Mapping[str, tuple[float, float]],
    bounds: Mapping[str, tuple[float, float]],
    corr: Mapping[tuple[str, str], float] | None = None,
    converged: bool = True,
    context: RigContext | None = None,
    *,
    units: Mapping[str, str] | None = None,
    confidence: float = 0.95,
    message: str = "",
) -> list[FitWarning]:
    """The plausibility warnings of a fit (see the module docstring for the rules).

    Parameters
    ----------
    values
        Flat name -> estimate (SI), parameters held because the record does
        not determine them included (with an infinite ``stderr``).
    stderr
        Flat name -> standard error (``inf``: not determined); names missing
        here are not checked for their errors.
    ci
        Flat name -> ``(low, high)`` confidence interval at ``confidence``.
    bounds
        Flat name -> ``(lower, upper)`` of the box the solver searched
        (``-inf``/``inf`` for none); a lower bound ``>= 0`` marks a quantity that
        must be positive.
    corr
        ``(name_a, name_b)`` -> correlation of the two estimates
        (:func:`correlations` builds it from a covariance matrix).
    converged
        Whether the solver converged.
    context
        The rig (kind for the experiments advised, known mass, geometry).
    units
        Flat name -> unit, for the messages.
    confidence
        Level of ``ci``, for the messages.
    message
        The solver's stopping message, quoted by ``not-converged``.

    Returns
    -------
    list of FitWarning
        In the order: ``not-converged``, then per parameter (order of
        ``values``) ``at-bound`` / ``not-identified`` / ``interval-crosses-zero``
        and ``mass-implausible``, then the pairs that trade off.
    """
    ctx = context or RigContext()
    unit = dict(units or {})
    out: list[FitWarning] = []
    if not converged:
        why = f" ({message})" if message else ""
        out.append(FitWarning("not-converged", None, (
            f"the fit did not converge{why}: the values are where the solver stopped, not a "
            "least-squares optimum; fix the parameters the record does not determine "
            "(--fix) or give a richer record")))
    judged: set[str] = set()  # at a bound or not determined: no meaningful correlation
    for name, value in values.items():
        item = _parameter_warning(name, value, stderr.get(name), ci.get(name),
                                  bounds.get(name), unit.get(name, ""), ctx, confidence)
        if item is not None:
            out.append(item)
            if item.code != "interval-crosses-zero":
                judged.add(name)
        mass = _mass_warning(name, value, stderr.get(name), ctx)
        if mass is not None:
            out.append(mass)
    for (a, b), r in (corr or {}).items():
        if abs(r) > MAX_CORRELATION and a not in judged and b not in judged:
            out.append(FitWarning("not-identified", f"{a},{b}", (
                f"{a} and {b} trade off (correlation {r:+.4f}): the record fixes mainly a "
                f"combination of them, a change of one largely made up by the other"
                f"{_advice(ctx.kind, a, b)}")))
    return out


def check_held(
    values: Mapping[str, float],
    bounds: Mapping[str, tuple[float, float]],
    *,
    units: Mapping[str, str] | None = None,
    dt: float = 0.0,
    context: RigContext | None = None,
) -> list[FitWarning]:
    """The warnings of rig terms estimated once and held for the fits that follow.

    Parameters
    ----------
    values
        Flat name -> held value (SI), e.g. the driving-force channel ``lag`` (s).
    bounds
        Flat name -> ``(lower, upper)`` of the box it was estimated in.
    units
        Flat name -> unit, for the messages.
    dt
        Sample interval (s) of the record it was estimated on: a ``lag`` above
        ``-LEAD_SAMPLES*dt`` is zero within the timing of the samples.
    context
        The rig, to judge a held ``mass`` as a fitted one is judged
        (``mass-implausible``: a mass that went to zero is as wrong held as fitted).

    Returns
    -------
    list of FitWarning
        Per name (order of ``values``): ``at-bound`` (within :data:`BOUND_HAIR`
        of a bound), then for ``mass`` ``mass-implausible`` and for ``lag``
        ``lag-negative`` (see the module docstring).
    """
    ctx = context or RigContext()
    unit = dict(units or {})
    out: list[FitWarning] = []
    for name, value in values.items():
        u = unit.get(name, "")
        box = bounds.get(name)
        if box is not None:
            for side, bound in (("lower", box[0]), ("upper", box[1])):
                if math.isfinite(bound) and \
                        abs(value - bound) <= BOUND_HAIR * max(abs(bound), abs(value)):
                    out.append(FitWarning("at-bound", name, (
                        f"{name} = {_q(value, u)}, estimated once and held for the fits that "
                        f"follow, is at its {side} bound {_q(bound, u)}: the data push it "
                        "beyond the allowed range (a missing effect, or a record that does "
                        "not determine it), and every later fit carries that value")))
                    break
        mass = _mass_warning(name, value, None, ctx)
        if mass is not None:
            out.append(mass)
        if name == "lag" and value < -LEAD_SAMPLES * max(dt, 0.0) and value < 0.0:
            out.append(FitWarning("lag-negative", name, (
                f"lag = {_q(value, u or 's')}: the driving force leads the motion by "
                f"{_q(-value, u or 's')}, which no sensor or line lag does; it is a timing "
                "offset between the channels (separate clocks or a delayed motion signal) "
                "or a wrong sign of the force, not a transducer lag; align the channels' "
                "time stamps (or check the force's sign) before trusting the friction "
                "values")))
    return out


def _q(value: float, unit: str) -> str:
    """A value with its unit, for messages."""
    return f"{value:.4g} {unit}".rstrip() if unit not in ("", "-") else f"{value:.4g}"


def _advice(kind: str, *names: str) -> str:
    """``"; to determine it: <experiment>"`` for the effects the names belong to, or ``""``."""
    seen: list[str] = []
    for n in names:
        effect = effect_of_parameter(n)
        if effect is not None:
            text = experiment_for(effect, kind)
            if text not in seen:
                seen.append(text)
    return f"; to determine {'them' if len(names) > 1 else 'it'}: {'; or '.join(seen)}" \
        if seen else ""


def _parameter_warning(name: str, value: float, se: float | None,
                       interval: tuple[float, float] | None, box: tuple[float, float] | None,
                       unit: str, ctx: RigContext, confidence: float) -> FitWarning | None:
    """``at-bound``, ``not-identified`` or ``interval-crosses-zero`` of one estimate, or None."""
    if se is not None and not math.isfinite(se):
        return FitWarning("not-identified", name, (
            f"{name} is not determined by this record: held at {_q(value, unit)}, a value "
            f"the data neither support nor contradict{_advice(ctx.kind, name)}"))
    spread = abs(se) if se is not None else 0.0
    if box is not None:
        for side, bound in (("lower", box[0]), ("upper", box[1])):
            hair = BOUND_HAIR * max(abs(bound), abs(value), spread)
            if math.isfinite(bound) and abs(value - bound) <= hair:
                return FitWarning("at-bound", name, (
                    f"{name} = {_q(value, unit)} is at its {side} bound {_q(bound, unit)}: "
                    "the data push it beyond the allowed range (a missing effect, or a record "
                    "that does not determine it); its standard error and interval mean "
                    f"nothing{_advice(ctx.kind, name)}"))
    positive = box is not None and box[0] >= 0.0
    if positive and se is not None and spread > HUGE_RELATIVE_ERROR * abs(value):
        return FitWarning("not-identified", name, (
            f"{name} = {_q(value, unit)} has a standard error of {_q(spread, unit)}, "
            f"{spread / abs(value) if value else math.inf:.3g} times its value: the record "
            f"hardly determines it{_advice(ctx.kind, name)}"))
    if positive and interval is not None and interval[0] <= 0.0:
        pct = f"{100 * confidence:.3g} %"
        return FitWarning("interval-crosses-zero", name, (
            f"{name} = {_q(value, unit)} must be positive, but its {pct} interval "
            f"[{interval[0]:.4g}, {interval[1]:.4g}] reaches zero or below: the record does not "
            f"establish it (the term may be absent){_advice(ctx.kind, name)}"))
    return None


def _mass_warning(name: str, value: float, se: float | None,
                  ctx: RigContext) -> FitWarning | None:
    """``mass-implausible`` for a fitted ``mass`` (or a mass error ``dm``), or None."""
    if name == "dm" and ctx.mass is not None:
        total = ctx.mass + value
        what = f"the moving mass rig.mass + dm = {total:.4g} kg"
    elif name == "mass":
        total, what = value, f"the fitted mass {value:.4g} kg"
    else:
        return None
    spread = f" (standard error {se:.3g} kg)" if se is not None and math.isfinite(se) else ""
    if ctx.mass is not None and ctx.mass > 0:
        if ctx.mass / MASS_RATIO <= total <= ctx.mass * MASS_RATIO:
            return None
        return FitWarning("mass-implausible", name, (
            f"{what}{spread} is {total / ctx.mass:.3g} times the sidecar's rig.mass "
            f"{ctx.mass:.4g} kg: check the sidecar (a load not counted?) and the fit"))
    low, high, basis = mass_range(ctx)
    if total < low:
        return FitWarning("mass-implausible", name, (
            f"{what}{spread} is below {low:.3g} kg, the least that {basis} can weigh: the "
            "record does not determine the moving mass (too little acceleration); give "
            "rig.mass in the sidecar or --mass"))
    if total > high:
        return FitWarning("mass-implausible", name, (
            f"{what}{spread} is above {high:.3g} kg, more than {basis} can plausibly carry: "
            "the mass trades off with other terms; give rig.mass in the sidecar or --mass"))
    steel = steel_piston_mass(ctx)
    if steel is None or total <= LOAD_FACTOR * steel:
        return None
    return FitWarning("mass-implausible", name, (
        f"{what}{spread} is {total / steel:.3g} times the {steel:.3g} kg of a solid steel "
        f"piston one bore long and rod over the stroke ({basis}), above the "
        f"{LOAD_FACTOR * steel:.3g} kg ({LOAD_FACTOR:g} times) a piston, rod and carriage "
        "weigh: a load that heavy is not stated, and a fitted one usually trades off with "
        "other terms (a record with little acceleration does not weigh it); give rig.mass in "
        "the sidecar or --mass"))
