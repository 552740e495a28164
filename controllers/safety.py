"""The fail-safe layer every controller runs behind: input validation, a latched safe output,
recovery without re-initialisation, the valve's range and rate limit.

:func:`controllers.make_controller` returns every controller wrapped in a
:class:`FailSafe`; the exported C step (:mod:`controllers.export`) runs the
same layer. The rules are written **once**, as functions of a small
operations namespace (:data:`SCALAR` for Python floats, :data:`SYMBOLIC` for
CasADi expressions): :func:`admit` before the controller's step and
:func:`settle` after it. The Python controller evaluates them on floats, the
export generates them as C from the same functions, so the two cannot differ
in a rule -- the compiled step equals the Python step on hostile input as on
ordinary input, which the tests check.

Rules (one sample; ``N = fault_latch``, ``M = fault_recover``)
---------------------------------------------------------------
1. **Validation** (:func:`admit`). A sample is *faulty* when a measured
   channel or the reference is implausible:

   * position ``x`` non-finite or outside ``[-d, L + d]`` (``L`` the stroke,
     ``d = position_margin``, default 5 % of the stroke: an end stop yields far
     less, so a reading beyond it is the sensor's, not the piston's);
   * a chamber pressure non-finite or outside ``[-6 s_p, p_max]`` (absolute;
     ``s_p`` the pressure sensor's standard deviation, noise and quantisation,
     so that a true pressure near vacuum read through the noise is no fault;
     ``p_max = pressure_max``, default twice the supply pressure: above any
     pressure intensification of the load);
   * the reference ``r`` (and every future position an MPC takes) non-finite or
     outside ``[-d, L + d]``, or its velocity ``dr`` or acceleration ``ddr``
     non-finite.

   A faulty channel **holds its last good value** (the hold-last-good-value
   reaction of IEC 61508-7 / IEC 61511 to a detected sensor fault); a faulty
   reference holds the last good position with ``dr = ddr = 0`` (a set point,
   not a stale velocity). Every faulty sample counts one fault; its cause is
   kept as a bit mask (:data:`CAUSES`).
2. **Reference bounds (anti-windup).** A valid reference is clipped to the
   stroke ``[0, L]``, its velocity to ``+-L/dt`` and its acceleration to
   ``+-(F_max - F_min)/m`` (the actuator's whole force range on the moving
   mass): every term of the force demand stays finite and bounded, whatever
   the reference. With the integral's own bound (:func:`clamp_integral`:
   ``ki*I`` within ``[F_min, F_max]``; the back-calculation of Astrom &
   Hagglund, *Advanced PID Control*, 2006, sec. 3.5, stays in force inside it)
   a reference step of 1e300 never winds the integral up: it is a faulty
   sample, held, and the integral unwinds at once when the reference returns.
3. **Latch.** ``N`` faulty samples in a row **latch the safe output**
   (``safe_output`` of the plant file: ``"centre"``, the default, commands 0 --
   the closed centre of a servo or proportional valve, which blocks both
   chambers and holds the load on its oil or air column, the state a servo
   valve's spring centring or fail-safe spool takes on loss of command;
   ``"hold"`` keeps the last command; a number is a fixed command). While
   latched the controller is not stepped (its states stay as they were).
   Before the first good sample the controller has not started: the output is
   the safe output too.
4. **Recovery without re-init.** ``M`` good samples in a row unlatch. The
   controller then **re-enters** (:meth:`controllers.base.Controller.reenter`):
   its states re-seeded from the current measurement and the command the valve
   holds, bumplessly -- the PID's integral set so that its force demand equals
   the actuator force the measured pressures give (Astrom & Hagglund 2006,
   sec. 3.6, bumpless transfer), the estimators started from the measurement,
   the MPC's warm start at the held command. A controller whose own step
   returns a non-finite command (or raises ``FloatingPointError``) has a fault
   of cause ``controller``: the last command is held and the controller
   re-enters at its next good sample.
5. **Output** (:func:`settle`). Every command -- the controller's, the held
   one, the safe one -- is clipped to the valve's range ``+-u_max`` and then
   rate-limited to ``+-du_max*dt`` from the last command (``[valve] u_max``,
   ``du_max`` of the plant file), so the output is never NaN, never beyond the
   valve's range and never faster than the amplifier slews.

The fault state (:class:`FaultState`: faults so far, faulty samples in a
row, latched, the last fault's cause) is :attr:`FailSafe.fault_state`;
:mod:`controllers.harness` records it per sample and in the metrics, and the
exported C exposes it (``fcomp_ctrl_fault``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import casadi as ca
import numpy as np

from controllers.base import Controller, Reference
from fcomp.errors import FcompError
from plants.planfile import SAFE_OUTPUTS

#: Fault causes, the bits of the cause mask.
CAUSES: dict[int, str] = {1: "position", 2: "pressure p1", 4: "pressure p2", 8: "reference",
                          16: "controller"}
#: Defaults of the plant-file keys (``[control]``): faulty samples in a row that latch the
#: safe output, good samples in a row that unlatch it.
FAULT_LATCH = 5
FAULT_RECOVER = 50
#: Default position margin beyond the stroke, as a fraction of the stroke.
POSITION_MARGIN = 0.05
#: Default plausible pressure ceiling, as a multiple of the supply pressure.
PRESSURE_FACTOR = 2.0

#: The layer's state, in order: ``(name, size)`` (the exported C state's last blocks).
LAYOUT: list[tuple[str, int]] = [
    ("fs_seen", 1), ("fs_latched", 1), ("fs_consecutive", 1), ("fs_good_run", 1),
    ("fs_faults", 1), ("fs_cause", 1), ("fs_u", 1), ("fs_pending", 1), ("fs_y_hold", 3),
    ("fs_r_hold", 1),
]
SEEN, LATCHED, CONSEC, GOOD, FAULTS, CAUSE, U, PENDING, Y_HOLD, R_HOLD = (0, 1, 2, 3, 4, 5, 6, 7,
                                                                      8, 11)
#: Size of the layer's state.
N_STATE = sum(k for _, k in LAYOUT)


class Ops(NamedTuple):
    """The operations the rules are written with (module docstring): a selection, the
    minimum and maximum, the logical connectives, a finiteness test, a range test and a
    clip -- ``clip(a, lo, hi) = fmin(fmax(a, lo), hi)`` with C's ``fmin``/``fmax``, which
    take a NaN argument for missing (a NaN clips to ``lo``)."""

    if_else: Callable[[Any, Any, Any], Any]
    fmin: Callable[[Any, Any], Any]
    fmax: Callable[[Any, Any], Any]
    and_: Callable[[Any, Any], Any]
    or_: Callable[[Any, Any], Any]
    not_: Callable[[Any], Any]
    finite: Callable[[Any], Any]
    within: Callable[[Any, float, float], Any]
    clip: Callable[[Any, float, float], Any]


#: The rules on Python floats.
SCALAR = Ops(
    if_else=lambda c, a, b: a if c else b,
    fmin=lambda a, b: a if a < b else b,
    fmax=lambda a, b: a if a > b else b,
    and_=lambda a, b: a and b,
    or_=lambda a, b: a or b,
    not_=lambda a: not a,
    finite=math.isfinite,
    within=lambda a, lo, hi: lo <= a <= hi,
    clip=lambda a, lo, hi: lo if not a >= lo else (hi if a > hi else a),
)
#: The rules on CasADi expressions (generated as C by :mod:`controllers.export`).
SYMBOLIC = Ops(
    if_else=lambda c, a, b: ca.if_else(c, a, b),
    fmin=ca.fmin,
    fmax=ca.fmax,
    and_=ca.logic_and,
    or_=ca.logic_or,
    not_=ca.logic_not,
    finite=lambda a: ca.fabs(a) < ca.inf,
    within=lambda a, lo, hi: ca.logic_and(a >= lo, a <= hi),
    clip=lambda a, lo, hi: ca.fmin(ca.fmax(a, lo), hi),
)


@dataclass(frozen=True)
class Limits:
    """The numbers of the rules for one controller (SI; module docstring).

    Attributes
    ----------
    x_lo, x_hi
        Plausible positions and reference positions (m): the stroke widened by the margin.
    r_hi
        The stroke (m): a valid reference is clipped to ``[0, r_hi]``.
    p_lo, p_hi
        Plausible chamber pressures (Pa absolute).
    v_max, a_max
        Bounds of the reference velocity (m/s) and acceleration (m/s^2).
    u_max, du
        The valve's range and the largest command change per sample.
    n_latch, n_recover
        Faulty samples in a row that latch; good samples in a row that unlatch.
    hold
        Whether the safe output holds the last command (else :attr:`safe_value`).
    safe_value
        The safe command.
    """

    x_lo: float
    x_hi: float
    r_hi: float
    p_lo: float
    p_hi: float
    v_max: float
    a_max: float
    u_max: float
    du: float
    n_latch: float
    n_recover: float
    hold: bool
    safe_value: float

    @classmethod
    def of(cls, model: Any, dt: float) -> Limits:
        """The limits of a :class:`~controllers.plant_model.ControlModel` at sample time ``dt``."""
        s = model.settings
        stroke = float(model.stroke)
        margin = (POSITION_MARGIN * stroke if s.position_margin is None
                  else float(s.position_margin))
        p_max = (PRESSURE_FACTOR * float(model.params["ps"]) if s.pressure_max is None
                 else float(s.pressure_max))
        sp = float(model.sensors.std()[1])
        hold, value = safe_command(s.safe_output, model.u_max)
        return cls(x_lo=-margin, x_hi=stroke + margin, r_hi=stroke, p_lo=-6.0 * sp, p_hi=p_max,
                   v_max=stroke / dt, a_max=(model.force_max - model.force_min) / model.mass,
                   u_max=float(model.u_max), du=float(model.du_max) * dt,
                   n_latch=float(s.fault_latch), n_recover=float(s.fault_recover), hold=hold,
                   safe_value=value)


def safe_command(spec: str | float, u_max: float) -> tuple[bool, float]:
    """``(hold, value)`` of a ``safe_output`` setting (module docstring, rule 3)."""
    if spec == "hold":
        return True, 0.0
    if spec == "centre":
        return False, 0.0
    if isinstance(spec, bool) or not isinstance(spec, int | float) or not math.isfinite(spec):
        raise FcompError(f"safe_output must be {' or '.join(map(repr, SAFE_OUTPUTS))} or a "
                         f"command within +-u_max, got {spec!r}")
    if abs(spec) > u_max:
        raise FcompError(f"safe_output = {spec:g} is outside the valve's range +-{u_max:g}")
    return False, float(spec)


def initial_state() -> list[float]:
    """The layer's state before any sample (nothing seen, nothing latched, command 0)."""
    return [0.0] * N_STATE


class Admitted(NamedTuple):
    """What :func:`admit` decides for one sample.

    Attributes
    ----------
    y, ref
        What the controller steps on (held and clipped): ``[x, p1, p2]``,
        ``[r, dr, ddr, *future]``.
    mid
        The layer's state after the validation (the command not yet updated).
    run
        Whether the controller steps this sample.
    start
        Whether this is its first good sample (a start).
    reenter
        Whether it re-enters (after a latch, a fault of its own, or its states gone
        non-finite) before stepping.
    counted
        Whether this sample counted a fault already.
    """

    y: list[Any]
    ref: list[Any]
    mid: list[Any]
    run: Any
    start: Any
    reenter: Any
    counted: Any


def admit(ops: Ops, lim: Limits, fs: Sequence[Any], y: Sequence[Any], ref: Sequence[Any],
          healthy: Any = True) -> Admitted:
    """Rules 1-4 before the controller's step (module docstring).

    Parameters
    ----------
    ops
        :data:`SCALAR` or :data:`SYMBOLIC`.
    lim
        The rules' numbers.
    fs
        The layer's state (:data:`LAYOUT`).
    y
        The measurement ``[x, p1, p2]``.
    ref
        ``[r, dr, ddr, *future]``.
    healthy
        Whether the controller's own states are all finite (else it re-enters now, a
        fault of cause ``controller``).

    Returns
    -------
    Admitted
    """
    ie, _fmin, _fmax, and_, or_, not_, finite, within, clip = ops
    x_lo, x_hi, r_hi = lim.x_lo, lim.x_hi, lim.r_hi
    x_ok = within(y[0], x_lo, x_hi)
    p1_ok = within(y[1], lim.p_lo, lim.p_hi)
    p2_ok = within(y[2], lim.p_lo, lim.p_hi)
    r_ok = and_(within(ref[0], x_lo, x_hi), and_(finite(ref[1]), finite(ref[2])))
    future = ref[3:]
    for f in future:
        r_ok = and_(r_ok, within(f, x_lo, x_hi))
    bad = ie(x_ok, 0.0, 1.0) + ie(p1_ok, 0.0, 2.0) + ie(p2_ok, 0.0, 4.0) + ie(r_ok, 0.0, 8.0)
    fault = bad > 0.5
    y_used = [ie(x_ok, y[0], fs[Y_HOLD]), ie(p1_ok, y[1], fs[Y_HOLD + 1]),
              ie(p2_ok, y[2], fs[Y_HOLD + 2])]
    held = fs[R_HOLD]
    ref_used = [ie(r_ok, clip(ref[0], 0.0, r_hi), held),
                ie(r_ok, clip(ref[1], -lim.v_max, lim.v_max), 0.0),
                ie(r_ok, clip(ref[2], -lim.a_max, lim.a_max), 0.0)]
    ref_used += [ie(r_ok, clip(f, 0.0, r_hi), held) for f in future]
    was_seen = fs[SEEN] > 0.5
    was_latched = fs[LATCHED] > 0.5
    seen = or_(was_seen, not_(fault))
    consec = ie(fault, fs[CONSEC] + 1.0, 0.0)
    good = ie(fault, 0.0, fs[GOOD] + 1.0)
    latched = ie(was_latched, good < lim.n_recover, consec >= lim.n_latch)
    run = and_(seen, not_(latched))
    broken = and_(run, not_(healthy))
    reenter = and_(run, or_(or_(was_latched, fs[PENDING] > 0.5), broken))
    start = and_(run, not_(was_seen))
    any_fault = or_(fault, broken)
    mid = [ie(seen, 1.0, 0.0), ie(latched, 1.0, 0.0), consec, good,
           fs[FAULTS] + ie(any_fault, 1.0, 0.0),
           ie(any_fault, bad + ie(broken, 16.0, 0.0), fs[CAUSE]),
           fs[U], fs[PENDING], *y_used, ref_used[0]]
    return Admitted(y_used, ref_used, mid, run, start, reenter, any_fault)


def settle(ops: Ops, lim: Limits, mid: Sequence[Any], run: Any, u_in: Any, counted: Any
           ) -> tuple[Any, list[Any]]:
    """Rules 3-5 after the controller's step (module docstring): ``(u, state_next)``.

    ``mid``, ``run`` and ``counted`` are :func:`admit`'s (the state after the validation,
    whether the controller stepped, whether this sample counted a fault already); ``u_in``
    is the controller's command (ignored unless ``run``): a non-finite one is a fault of
    cause ``controller``.
    """
    ie, _fmin, _fmax, and_, or_, not_, finite, _within, clip = ops
    ok = finite(u_in)
    used = and_(run, ok)
    broke = and_(run, not_(ok))
    new = and_(broke, not_(counted))  # a faulty sample counts once
    consec = ie(new, mid[CONSEC] + 1.0, mid[CONSEC])
    latched = or_(mid[LATCHED] > 0.5, consec >= lim.n_latch)
    u_prev = mid[U]
    safe = u_prev if lim.hold else lim.safe_value
    target = ie(used, u_in, ie(or_(latched, mid[SEEN] < 0.5), safe, u_prev))
    u = clip(clip(target, -lim.u_max, lim.u_max), u_prev - lim.du, u_prev + lim.du)
    nxt = list(mid)
    nxt[LATCHED] = ie(latched, 1.0, 0.0)
    nxt[CONSEC] = consec
    nxt[GOOD] = ie(broke, 0.0, mid[GOOD])
    nxt[FAULTS] = mid[FAULTS] + ie(new, 1.0, 0.0)
    cause = mid[CAUSE]
    nxt[CAUSE] = ie(broke, ie(counted, ie(cause >= 16.0, cause, cause + 16.0), 16.0), cause)
    nxt[U] = u
    nxt[PENDING] = ie(run, ie(ok, 0.0, 1.0), mid[PENDING])
    return u, nxt


def integral_bounds(ki: float, force_min: float, force_max: float) -> tuple[float, float]:
    """Bounds of a PID integral ``I`` whose force ``ki*I`` stays within the actuator's range
    ``[force_min, force_max]`` (rule 2; no bound for ``ki = 0``)."""
    if ki == 0:
        return -math.inf, math.inf
    return force_min / ki, force_max / ki


def clamp_integral(ops: Ops, integral: Any, bounds: tuple[float, float]) -> Any:
    """The integral within its :func:`integral_bounds`."""
    lo, hi = bounds
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return integral
    return ops.clip(integral, lo, hi)


def bumpless_integral(ops: Ops, force: Any, other: Any, ki: float,
                      bounds: tuple[float, float]) -> Any:
    """The integral at re-entry (rule 4): ``(F_a - F_other)/ki`` within its bounds, so that
    the force demand ``F_other + ki*I`` equals the actuator force ``F_a`` the measured
    pressures give (Astrom & Hagglund 2006, sec. 3.6); 0 without integral action."""
    if ki == 0:
        return 0.0
    return clamp_integral(ops, (force - other) / ki, bounds)


@dataclass(frozen=True)
class FaultState:
    """The fail-safe layer's fault state (module docstring).

    Attributes
    ----------
    faults
        Faulty samples so far (input and controller faults).
    consecutive
        Faulty samples in a row up to now.
    latched
        Whether the safe output is latched.
    cause
        The last fault's cause (names of :data:`CAUSES`, comma-separated), None before any.
    good_run
        Good samples in a row up to now.
    """

    faults: int
    consecutive: int
    latched: bool
    cause: str | None
    good_run: int

    @classmethod
    def of(cls, fs: Sequence[float]) -> FaultState:
        """The fault state of a layer's state vector (:data:`LAYOUT`)."""
        return cls(faults=int(fs[FAULTS]), consecutive=int(fs[CONSEC]),
                   latched=bool(fs[LATCHED] > 0.5), cause=cause_names(int(fs[CAUSE])),
                   good_run=int(fs[GOOD]))

    def as_dict(self) -> dict[str, Any]:
        return {"faults": self.faults, "consecutive": self.consecutive,
                "latched": self.latched, "cause": self.cause, "good_run": self.good_run}


def cause_names(mask: int) -> str | None:
    """The names of a cause mask's bits (:data:`CAUSES`), comma-separated; None for 0."""
    names = [n for bit, n in CAUSES.items() if mask & bit]
    return ", ".join(names) if names else None


#: What a controller's own step may raise on numbers gone bad (a fault of cause
#: ``controller``, rule 4); anything else is a programming or set-up error and propagates.
NUMERIC_ERRORS = (FloatingPointError, ZeroDivisionError, OverflowError, np.linalg.LinAlgError)


class FailSafe(Controller):
    """A controller behind the fail-safe layer (module docstring).

    Parameters
    ----------
    inner
        The controller (its law); its model's settings give the rules' numbers
        (:class:`Limits`).

    Everything the inner controller has (gains, estimators, options) is read through
    this object; :attr:`fault_state` is the layer's.
    """

    def __init__(self, inner: Controller) -> None:  # noqa: D107 (no Controller options)
        if isinstance(inner, FailSafe):
            raise FcompError("a controller is wrapped in the fail-safe layer once")
        self.inner = inner
        self.limits = Limits.of(inner.model, inner.dt)
        self._fs = initial_state()
        self._started = False

    # the inner controller's attributes ------------------------------------------------
    def __getattr__(self, name: str) -> Any:
        if name == "inner":  # not set yet (unpickling, copying)
            raise AttributeError(name)
        return getattr(self.inner, name)

    name = property(lambda self: self.inner.name)  # type: ignore[assignment]
    preview = property(lambda self: self.inner.preview)  # type: ignore[assignment]
    model = property(lambda self: self.inner.model)
    dt = property(lambda self: self.inner.dt)
    rate = property(lambda self: self.inner.rate)
    opts = property(lambda self: self.inner.opts)
    friction_estimate = property(lambda self: self.inner.friction_estimate)
    fallback_active = property(lambda self: self.inner.fallback_active)
    fallbacks = property(lambda self: self.inner.fallbacks)

    # the layer ----------------------------------------------------------------------
    @property
    def state(self) -> list[float]:
        """The layer's state (:data:`LAYOUT`), a copy."""
        return list(self._fs)

    @property
    def started(self) -> bool:
        """Whether the controller has been reset (started) on a good sample."""
        return self._started

    @property
    def fault_state(self) -> FaultState:
        """The fault state now (:class:`FaultState`)."""
        return FaultState.of(self._fs)

    faults = property(lambda self: int(self._fs[FAULTS]), doc="faulty samples so far")
    consecutive_faults = property(lambda self: int(self._fs[CONSEC]),
                                  doc="faulty samples in a row")
    latched = property(lambda self: bool(self._fs[LATCHED] > 0.5),
                       doc="whether the safe output is latched")
    last_fault = property(lambda self: cause_names(int(self._fs[CAUSE])),
                          doc="the last fault's cause")

    def _reference(self, ref: Reference) -> list[float]:
        """``[r, dr, ddr, *future]`` with the future padded to the preview as the MPC pads it."""
        n = self.inner.preview
        out = [float(ref.r), float(ref.dr), float(ref.ddr)]
        if n:
            fut = [float(f) for f in ref.future[:n]]
            fut += [fut[-1] if fut else float(ref.r)] * (n - len(fut))
            out += fut
        return out

    def reset(self, t0: float, y0: np.ndarray, ref: Reference) -> None:
        """Forget everything; reset the controller from ``y0`` if it is a good sample (else
        at the first good one: rule 3)."""
        self._fs = initial_state()
        yv = [float(v) for v in np.asarray(y0, dtype=float).ravel()[:3]]
        a = admit(SCALAR, self.limits, self._fs, yv, self._reference(ref))
        self._started = bool(a.run)
        if a.run:
            self.inner.reset(t0, np.asarray(y0, dtype=float), _as_reference(a.ref))
            self._fs[SEEN] = 1.0
            self._fs[Y_HOLD:Y_HOLD + 3] = a.y
            self._fs[R_HOLD] = a.ref[0]

    def step(self, t: float, y: np.ndarray, ref: Reference) -> float:
        """One sample through the layer (module docstring): never NaN, within ``+-u_max``,
        rate-limited."""
        lim = self.limits
        inner = self.inner
        yv = [float(y[0]), float(y[1]), float(y[2])]
        rv = self._reference(ref)
        a = admit(SCALAR, lim, self._fs, yv, rv, not self._started or inner.healthy())
        u_in = math.nan
        if a.run:
            ya = y if a.y == yv else np.array(a.y)  # nothing held: the caller's arrays
            rf = ref if a.ref == rv and len(ref.future) == self.inner.preview else \
                _as_reference(a.ref)
            if a.reenter:
                inner.reenter(t, ya, rf, a.mid[U])
            elif a.start:
                inner.reset(t, ya, rf)
            self._started = True
            try:
                u_in = float(inner.step(t, ya, rf))
            except NUMERIC_ERRORS:
                u_in = math.nan
        u, self._fs = settle(SCALAR, lim, a.mid, a.run, u_in, a.counted)
        if a.run:
            inner.applied(u)
        return u

    def describe(self) -> str:
        return self.inner.describe()


def _as_reference(r: Sequence[float]) -> Reference:
    return Reference(r[0], r[1], r[2], tuple(r[3:]))


def unwrap(ctrl: Any) -> Any:
    """The controller behind the fail-safe layer (``ctrl`` itself if it has none)."""
    return ctrl.inner if isinstance(ctrl, FailSafe) else ctrl


__all__ = ["CAUSES", "FAULT_LATCH", "FAULT_RECOVER", "LAYOUT", "N_STATE", "SAFE_OUTPUTS",
           "SCALAR", "SYMBOLIC", "Admitted", "FailSafe", "FaultState", "Limits", "Ops", "admit",
           "bumpless_integral", "cause_names", "clamp_integral", "initial_state",
           "integral_bounds", "safe_command", "settle", "unwrap"]
