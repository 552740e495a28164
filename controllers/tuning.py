"""Default tuning that follows the plant: every compensator's tuning from the loop as it runs.

The controllers of :mod:`controllers` share one structure (:mod:`controllers.pid`):
a PID position loop whose force demand is met by the model-based force loop of
:mod:`controllers.force_to_valve`. Their default tuning is derived here from
the controller's own plant model (:class:`~controllers.plant_model.ControlModel`:
its plant, sensors, control rate, computation delay, and the plant file's
``[uncertainty]``), on the *loop as it runs* (:mod:`controllers.loop_analysis`:
the sampled plant linearised at rest over the stroke, the parameter box and the
friction regimes, the zero-order hold, the computation delay, the controller's
law exactly as coded). :func:`derive_tuning` gives a :class:`Tuning`: the values
and the margins of the loop at its worst point.

The requirement (Franklin, Powell & Emami-Naeini, *Feedback Control of Dynamic
Systems*, 7th ed., 2015, sec. 6.4; Skogestad & Postlethwaite, *Multivariable
Feedback Control*, 2nd ed., 2005, sec. 2.4.3): gain margin
:data:`MIN_GAIN_MARGIN` (2, 6 dB), phase margin :data:`MIN_PHASE_MARGIN`
(30 deg) and peak sensitivity :data:`MAX_SENSITIVITY` (2), broken at the valve
command and at the position sensor, at every point of the grid.

Rules (SI units; ``dt = 1/f_s`` the control period)
---------------------------------------------------
1. **What the valve allows** ``w_V``: the largest crossover of the force loop
   ``L_F(s) = w_F*G_v(s)/s`` alone (``G_v`` the valve's linearised dynamics, zero-order
   hold) with a :data:`FORCE_PHASE_MARGIN` (45 deg) phase margin -- for a second-order
   servo valve the root of ``atan(2 zeta_v r/(1 - r^2)) = 45 deg``, ``r = w_V/w_v``.
   It scales rule 2's search and bounds nothing: the force loop as it runs has the
   column, the delay and the position loop around it.
2. **The PID family's loop**: the PID's ``kp``, ``ki``, ``kd``, the force loop's
   ``w_F`` and the velocity compensation ``lambda`` (the share of the measured
   velocity in the force-to-valve inversion; the rest is the reference's:
   :mod:`controllers.force_to_valve`) maximise the loop's rejection of a load on the
   piston -- the integrated squared position error after a step load, alone and with
   the load fed forward exactly through the force demand, at nominal parameters
   along the stroke -- subject to the requirement at every grid point
   (:mod:`controllers.loop_analysis.design`; the robust-PID design of Astrom,
   Panagopoulos & Hagglund, Automatica 34(5), 1998, on a hydraulic servo's state
   feedback on position, velocity and load pressure: Merritt, *Hydraulic Control
   Systems*, 1967, sec. 8.4, Jelali & Kroll, *Hydraulic Servo-systems*, 2003, sec.
   7.3). ``pid_bandwidth`` is reported as ``w_P = (ki/m)^(1/3)`` (the triple pole
   whose ``ki = m w_P^3``). The force-to-valve inversion is the gain schedule over the
   stroke: it models the chambers at the measured position and pressures.
3. **Derivative filter** ``f_d`` (Hz). The filtered derivative of a position
   measured with noise ``sigma_x`` (noise and quantisation ``q/sqrt(12)``) has the
   variance ``sigma_x^2*w_d/dt`` (first-order filter, ``w_d*dt << 1``); its force
   ``kd*sigma_v`` is kept at the force noise the pressure sensors already put in
   the force loop, ``sigma_F = sigma_p*sqrt(A1^2 + A2^2)``::

       w_d = dt*(sigma_F/(kd*sigma_x))^2,    f_d = min(w_d/(2 pi), f_s/4).

   ``f_d`` depends on ``kd``: rule 2 is solved with ``f_d(kd)``.
4. **LuGre observer gain** ``k`` (1/s). The correction ``-k*e`` of the bristle
   state (:mod:`controllers.lugre_observer`) is a second controller beside the
   PID: at rest, where the bristle equation has no decay (``sigma0*|v|/g = 0``),
   the estimate ``F_hat = sigma0*z_hat + sigma1*dz_hat/dt`` adds an integral action
   of gain ``sigma0*k`` to the loop. ``k`` is the largest value up to ``w_P/2`` (the
   correction an octave slower than the loop it rides on), with its noise
   ``sigma1*k*sigma_x`` in the friction estimate below the pressure sensors' force
   noise (``k <= sigma_F/(sigma1*sigma_x)``), for which the ``lugre-observer``'s own
   loop -- linearised as coded, the observer's path included -- meets the requirement
   at the grid's points at rest in pre-sliding (:func:`resting_points`: where the
   observer is at rest too; sliding, its estimate follows the steady-state map). At
   rest the observer feeds its bristle stiffness forward against the seal's spring; it is
   built on the low end of the seal's stiffness range
   (:func:`controllers.lugre_observer.observer_friction`), so that it never
   over-cancels a softer seal into a negative stiffness. The passivity argument of Canudas de Wit et al. (1995), stability for
   every ``k > 0``, assumes a strictly positive real error dynamics that a sampled
   loop through a valve does not have.
5. **EKF** (:mod:`controllers.ekf`). The measurement noise is the sensors':
   ``R = diag(sigma_x^2, sigma_p^2, sigma_p^2)`` with noise and quantisation
   (``sigma^2 = noise^2 + q^2/12``); the process noise follows from the friction
   model's own uncertainty -- its standard errors, else a default share of its
   level -- by the rules of :mod:`controllers.estimator_tuning`.
6. **MPC** (:mod:`controllers.mpc`). The MPC drives the valve itself (no force
   loop, no PID): between its command and the position lie the valve and the
   oil (air) column. Its horizon spans half a period of the column,
   ``T_N = pi/w_h`` -- the time from a pressure change to the first peak of
   the piston's response, the slowest of the actuator's own dynamics the
   prediction must see (``N = ceil(T_N*f_mpc)`` steps); its velocity weight
   makes a position error ``e_x`` and a velocity error ``e_v`` equally costly
   an octave below the force bandwidth the valve allows (rule 1),
   ``e_v = e_x*w_V/2`` (faster errors weigh as velocity errors, slower ones as
   position errors; ``e_x`` only sets the scale of the cost).

Values given explicitly -- in a plant file's ``[control]`` table or as
controller options -- replace the derived ones (the others are derived around
them) and are checked the same way: a tuning that misses the requirement
anywhere on the grid is refused with one line (:class:`~fcomp.errors.FcompError`)
naming the worst point and what to change. So is a plant whose valve passes no
flow (:func:`dead_valve`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from controllers.loop_analysis.design import (
    Design,
    derivative_cutoff,
    design_pid_family,
    ratios,
)
from controllers.loop_analysis.grid import (
    PlantGrid,
    describe_at,
    mid_point,
    nominal_points,
    plant_grid,
    resting_points,
    worst_index,
)
from controllers.loop_analysis.margins import (
    MAX_SENSITIVITY,
    MIN_GAIN_MARGIN,
    MIN_PHASE_MARGIN,
    LoopMargins,
    loop_margins_from,
)
from controllers.loop_analysis.pid_family import PIDFamilyGains
from controllers.pid import PIDGains
from fcomp.errors import FcompError

if TYPE_CHECKING:
    from controllers.plant_model import ControlModel, Sensors

#: The margins of a tuning (:class:`controllers.loop_analysis.margins.LoopMargins`).
Margins = LoopMargins
#: Phase margin the force loop alone is designed for (deg), rule 1.
FORCE_PHASE_MARGIN = 45.0
#: Highest derivative filter cut-off, as a fraction of the control rate (Hz per Hz).
DERIVATIVE_CUTOFF_MAX_FRACTION = 0.25
#: Relative pad of rule 4's bisection on the requirement.
OBSERVER_PAD = 0.01
#: Bisection steps of rule 4.
OBSERVER_STEPS = 10
#: The tuning values a plant file or a caller may give.
GIVEN = ("force_bandwidth", "pid_bandwidth", "derivative_cutoff", "observer_gain",
         "velocity_compensation")


def _response(loop: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Magnitude, unwrapped phase (deg) and frequencies (rad/s) of a sampled loop."""
    dt = float(loop.dt)
    w = np.logspace(-1.0, math.log10(math.pi / dt) - 1e-4, 2000)
    resp = np.asarray(loop(np.exp(1j * w * dt)), dtype=complex).ravel()
    return np.abs(resp), np.degrees(np.unwrap(np.angle(resp))), w


def force_loop(force_bandwidth: float, valve: Any, dt: float) -> Any:
    """The force loop alone, ``w_F*G_v(s)/s`` sampled with a zero-order hold (rule 1)."""
    import control as ct

    s = ct.tf("s")
    return ct.tf(ct.c2d(ct.ss(force_bandwidth * valve / s), dt, "zoh"))


def _phase_margin(loop: Any) -> float:
    """The phase margin (deg) of the first gain crossover of a sampled loop."""
    mag, ph, _w = _response(loop)
    lm = np.log(mag)
    ig = np.nonzero(np.sign(lm[:-1]) != np.sign(lm[1:]))[0]
    if ig.size == 0:
        return math.inf
    i = int(ig[0])
    f = lm[i] / (lm[i] - lm[i + 1])
    return 180.0 + ph[i] + f * (ph[i + 1] - ph[i])


def force_bandwidth_rule(valve: Any, dt: float) -> float:
    """Rule 1: the largest ``w_V`` whose force loop alone keeps :data:`FORCE_PHASE_MARGIN`."""
    def ok(w: float) -> bool:
        return _phase_margin(force_loop(w, valve, dt)) >= FORCE_PHASE_MARGIN

    low, high = 1.0, 0.5 * math.pi / dt
    if not ok(low):
        raise FcompError(f"no force-loop bandwidth keeps a {FORCE_PHASE_MARGIN:g} deg phase "
                         f"margin through this valve at {1 / dt:g} Hz; raise the control rate")
    if ok(high):
        return high
    while high - low > 5e-3 * low:
        mid = math.sqrt(low * high)
        low, high = (mid, high) if ok(mid) else (low, mid)
    return low


def force_noise(model: ControlModel) -> float:
    """``sigma_F = sigma_p*sqrt(A1^2 + A2^2)`` (N): the pressure sensors' force noise."""
    return float(model.sensors.std()[1]) * math.hypot(model.A1, model.A2)


def derivative_cutoff_rule(kd: float, sensors: Sensors, sigma_F: float, dt: float) -> float:
    """Rule 3: the derivative filter cut-off (Hz) whose force noise is ``sigma_F``."""
    return derivative_cutoff(kd, float(sensors.std()[0]), sigma_F, dt)


def valve_bandwidth(valve: Any) -> float:
    """The -3 dB bandwidth (rad/s) of the valve's linear dynamics (``control.bandwidth``)."""
    import control as ct

    return float(ct.bandwidth(valve))


def pid_gains(mass: float, bandwidth: float, sensors: Sensors, sigma_F: float,
              dt: float, kp_factor: float = 1.0, kd_factor: float = 1.0) -> PIDGains:
    """The triple-pole gains of a bandwidth (:meth:`controllers.pid.PIDGains.placed`) with
    the derivative filter of rule 3."""
    placed = PIDGains.placed(mass, bandwidth, kp_factor, kd_factor)
    return PIDGains.placed(mass, bandwidth, kp_factor, kd_factor,
                           derivative_cutoff=derivative_cutoff_rule(placed.kd, sensors,
                                                                    sigma_F, dt))


@dataclass(frozen=True)
class Tuning:
    """A compensator tuning derived from the plant (module docstring), with its margins.

    Attributes
    ----------
    column_frequency : float
        ``w_h`` (rad/s): the oil (air) column at mid stroke (linearised).
    valve_bandwidth : float
        The valve's -3 dB bandwidth (rad/s), from its linearised dynamics.
    control_rate : float
        ``f_s`` (Hz).
    force_bandwidth : float
        ``w_F`` (rad/s), rule 2.
    pid_bandwidth : float
        ``w_P = (ki/m)^(1/3)`` (rad/s).
    pid_gains : PIDGains
        The PID's gains (rule 2) and filter (rule 3).
    derivative_cutoff : float
        ``f_d`` (Hz), rule 3.
    observer_gain : float
        ``k`` (1/s), rule 4.
    ekf_measurement_std : tuple of float
        Standard deviations of ``[x, p1, p2]`` (m, Pa, Pa), rule 5.
    mpc_horizon_time : float
        ``T_N = pi/w_h`` (s), rule 6.
    mpc_velocity_ratio : float
        ``e_v/e_x = w_V/2`` (1/s), rule 6 (``w_V``: rule 1).
    margins : LoopMargins
        The PID loop's at its worst point over the grid (both breaks).
    worst : str
        That point, its break and what is short there (or its margins), one phrase.
    mid : dict of str to LoopMargins
        The PID loop's at mid stroke, nominal, sliding, per break.
    given : tuple of str
        The values given explicitly (not derived).
    observer_margins : LoopMargins or None
        The ``lugre-observer`` loop's at its worst point (None for a friction model
        without a bristle state).
    observer_stiffness : float
        The observer's bristle stiffness ``sigma0`` (N/m), rule 4 (NaN: the model's own).
    velocity_compensation : float
        ``lambda``, rule 2.
    valve_allows : float
        ``w_V`` (rad/s), rule 1.
    delay : int
        The computation delay (control samples) the loop was analysed with.
    """

    column_frequency: float
    valve_bandwidth: float
    control_rate: float
    force_bandwidth: float
    pid_bandwidth: float
    pid_gains: PIDGains
    derivative_cutoff: float
    observer_gain: float
    ekf_measurement_std: tuple[float, float, float]
    mpc_horizon_time: float
    mpc_velocity_ratio: float
    margins: LoopMargins
    worst: str = ""
    mid: dict[str, LoopMargins] = field(default_factory=dict)
    given: tuple[str, ...] = field(default=())
    observer_margins: LoopMargins | None = None
    velocity_compensation: float = 1.0
    valve_allows: float = math.nan
    delay: int = 1
    observer_worst: str = ""
    observer_stiffness: float = math.nan

    def mpc_horizon(self, rate: float) -> int:
        """Horizon in steps at an MPC rate (Hz): ``ceil(T_N*rate)``, at least 2."""
        return max(2, math.ceil(self.mpc_horizon_time * rate - 1e-9))

    def family(self) -> PIDFamilyGains:
        """The five numbers of the PID family's loop (:mod:`controllers.loop_analysis.pid_family`)."""
        g = self.pid_gains
        return PIDFamilyGains(g.kp, g.ki, g.kd, g.derivative_cutoff, self.force_bandwidth,
                              self.velocity_compensation)

    def lines(self) -> list[str]:
        """The tuning as printed by ``fcomp plant check``."""
        def src(name: str) -> str:
            return "given" if name in self.given else "derived"

        g = self.pid_gains
        mid = self.mid
        return [
            f"tuning: PID kp {g.kp:.4g} N/m, ki {g.ki:.4g} N/(m s), kd {g.kd:.4g} N s/m "
            f"(w_P = (ki/m)^(1/3) = {self.pid_bandwidth:.4g} rad/s, {src('pid_bandwidth')}), "
            f"derivative filter {self.derivative_cutoff:.4g} Hz, force loop "
            f"{self.force_bandwidth:.4g} rad/s ({src('force_bandwidth')}; the valve alone allows "
            f"{self.valve_allows:.4g}, valve bandwidth {self.valve_bandwidth:.4g} rad/s, column "
            f"{self.column_frequency:.4g} rad/s), velocity compensation "
            f"{self.velocity_compensation:.3g} ({src('velocity_compensation')}), observer gain "
            f"{self.observer_gain:.4g} 1/s ({src('observer_gain')})"
            + (f", observer stiffness {self.observer_stiffness:.4g} N/m (derived)"
               if math.isfinite(self.observer_stiffness) else ""),
            *([f"  PID loop at mid stroke (nominal, sliding): at the valve "
               f"{mid['valve'].describe()}; at the position sensor {mid['position'].describe()}"]
              if mid else []),
            f"  PID loop, worst point of the grid: {self.worst}",
            *([f"  with the LuGre observer, worst point: {self.observer_worst}"]
              if self.observer_margins is not None else []),
            f"  MPC horizon {self.mpc_horizon_time * 1e3:.3g} ms, velocity weight e_v/e_x = "
            f"{self.mpc_velocity_ratio:.4g} 1/s; EKF sensor std x {self.ekf_measurement_std[0]:.3g}"
            f" m, p {self.ekf_measurement_std[1]:.4g} Pa",
        ]

    def as_dict(self) -> dict[str, Any]:
        """JSON form (SI units)."""
        def marg(m: LoopMargins | None) -> dict[str, Any] | None:
            if m is None:
                return None
            d = m.as_dict()
            d["phase"] = d["phase_deg"]
            d["crossover"] = d["gain_crossover"]
            return d

        return {
            "column_frequency": self.column_frequency, "valve_bandwidth": self.valve_bandwidth,
            "control_rate": self.control_rate, "force_bandwidth": self.force_bandwidth,
            "valve_allows": self.valve_allows, "pid_bandwidth": self.pid_bandwidth,
            "derivative_cutoff": self.derivative_cutoff,
            "pid_gains": {"kp": self.pid_gains.kp, "ki": self.pid_gains.ki,
                          "kd": self.pid_gains.kd},
            "velocity_compensation": self.velocity_compensation,
            "observer_gain": self.observer_gain,
            "observer_stiffness": (self.observer_stiffness
                                   if math.isfinite(self.observer_stiffness) else None),
            "ekf_measurement_std": list(self.ekf_measurement_std),
            "mpc_horizon_time": self.mpc_horizon_time,
            "mpc_velocity_ratio": self.mpc_velocity_ratio,
            "margins": marg(self.margins), "worst": self.worst,
            "mid": {k: marg(v) for k, v in self.mid.items()},
            "observer_margins": marg(self.observer_margins),
            "observer_worst": self.observer_worst or None,
            "delay": self.delay, "given": list(self.given),
        }


def refuse(what: str, problem: str, advice: str) -> FcompError:
    """The one-line refusal of a tuning."""
    return FcompError(f"{what} refused: {problem}; {advice}")


# ------------------------------------------------------------------ the grid
#: Grids by what they depend on (plant, settings, friction regimes, rate, delay).
_GRIDS: dict[tuple[Any, ...], PlantGrid] = {}


def model_grid(model: ControlModel, dt: float | None = None) -> PlantGrid:
    """The grid of a controller model (:func:`controllers.loop_analysis.grid.plant_grid`),
    built once per plant, settings, friction regimes and rate."""
    dt = 1.0 / model.control_rate if dt is None else float(dt)
    key = (model.plant_key(), dt)
    if key not in _GRIDS:
        dead = dead_valve(model)
        if dead is not None:
            raise FcompError(dead)
        _GRIDS[key] = plant_grid(model, dt=dt)
    return _GRIDS[key]


def dead_valve(model: ControlModel) -> str | None:
    """Why the model's valve passes no flow (:func:`plants.check.dead_valve`), or None."""
    from plants.check import dead_valve as why

    return why(model.plant_name, model.params)


# -------------------------------------------------------------------- rules
def _design(model: ControlModel, grid: PlantGrid, given: dict[str, float], sigma_F: float,
            w_V: float, dt: float) -> Design:
    """Rule 2 with the given values held (a ``pid_bandwidth`` given holds the triple pole
    ``kp = 3 m w^2``, ``ki = m w^3``, ``kd = 3 m w``)."""
    sigma_x = float(model.sensors.std()[0])
    m = model.mass
    hold = {k: float(v) for k, v in given.items()
            if k in ("force_bandwidth", "velocity_compensation", "derivative_cutoff")}
    if "pid_bandwidth" in given:
        w = float(given["pid_bandwidth"])
        hold.update(kp=3 * m * w * w, ki=m * w ** 3, kd=3 * m * w)
    return design_pid_family(grid, m, w_V, sigma_x, sigma_F, hold=hold)


def bristles(model: ControlModel) -> tuple[float, float] | None:
    """``(sigma0, sigma1)`` of the controller's friction model (N/m, N s/m), or None for a
    model without a bristle state (no LuGre observer to tune: it refuses such a model)."""
    p = model.friction.flat_params()
    if "sigma0" not in p or "z" not in model.friction.state_names:
        return None
    return float(p["sigma0"]), float(p.get("sigma1", 0.0))


#: The observer's linearised path per grid (:class:`~controllers.loop_analysis.observer.ObserverPath`).
_OBSERVER_JACOBIANS: dict[tuple[Any, ...], tuple[np.ndarray, np.ndarray]] = {}


def observer_margins(model: ControlModel, grid: PlantGrid, k: float, family: PIDFamilyGains,
                     points: list[int] | None = None, stiffness: float | None = None) -> Any:
    """The ``lugre-observer`` loop's margins with the PID family's ``family``, the observer
    gain ``k`` (1/s) and bristle stiffness ``stiffness`` (N/m, default the highest allowed,
    :func:`controllers.lugre_observer.stiffness_ceiling`) at the grid's resting ``points`` (:func:`~controllers.loop_analysis.grid.resting_points`;
    the observer's path in closed form, :mod:`controllers.loop_analysis.observer`)."""
    from controllers.loop_analysis.loop import controller_response, unit_z
    from controllers.loop_analysis.observer import ObserverPath, observer_ss
    from controllers.lugre_observer import stiffness_ceiling

    pts = resting_points(grid, points)
    stiffness = stiffness_ceiling(model) if stiffness is None else float(stiffness)
    key = (id(grid), model._tuning_key(), stiffness)
    if key not in _OBSERVER_JACOBIANS:
        path = ObserverPath(model, grid.dt, stiffness)
        jac = [path.at(lp.measurement) for lp in grid.plants]
        _OBSERVER_JACOBIANS[key] = (np.array([j[0] for j in jac]), np.array([j[1] for j in jac]))
    phi, fh = _OBSERVER_JACOBIANS[key]
    s, Jy, Jv = grid.slopes
    sub = grid.subset(pts)
    z = unit_z(sub.w, sub.dt)
    sel = np.array(pts)

    def controller(idx: np.ndarray) -> tuple[np.ndarray, ...]:
        j = sel[idx]
        A, B, C, D = observer_ss(family, k, s[j], Jy[j], Jv[j], phi[j], fh[j], *grid.areas,
                                 grid.dt)
        return A, B, C, D, controller_response(A, B, C, D, z)

    return _Margins(pts, sub.margins(controller))


class _Margins:
    """Margins at some grid points: ``points`` and per-break ``arrays``."""

    def __init__(self, points: list[int], arrays: dict[str, dict[str, np.ndarray]]) -> None:
        self.points = points
        self.arrays = arrays
        self.structural = False

    def worst(self) -> tuple[int, str]:
        i, brk = worst_index(self.arrays)
        return self.points[i], brk

    def at(self, point: int, brk: str) -> LoopMargins:
        return loop_margins_from(self.arrays[brk], (self.points.index(point),))

    def describe(self, grid: PlantGrid) -> str:
        i, brk = worst_index(self.arrays)
        return describe_at(grid.subset(self.points), self.arrays, i, brk)


def _ratio(cm: Any) -> float:
    r = np.inf
    for arr in cm.arrays.values():
        ratio = np.minimum(np.minimum(arr["gain"] / MIN_GAIN_MARGIN,
                                      arr["phase"] / MIN_PHASE_MARGIN),
                           MAX_SENSITIVITY / arr["ms"])
        r = min(r, float(np.min(np.where(arr["radius"] < 1.0, ratio, -arr["growth"]))))
    return r


#: Fractions of the observer's stiffness ceiling tried by rule 4, in order.
STIFFNESS_FRACTIONS = (1.0, 0.7, 0.5, 0.35, 0.25, 0.18, 0.125, 0.09, 0.0625)


def observer_gain_rule(model: ControlModel, grid: PlantGrid, family: PIDFamilyGains,
                       w_P: float, sigma_F: float) -> tuple[float, Any, float]:
    """Rule 4: the observer's bristle stiffness, the largest of :data:`STIFFNESS_FRACTIONS`
    of its ceiling (:func:`controllers.lugre_observer.stiffness_ceiling`) whose loop at rest
    meets the requirement on the whole grid with a correction a decade below its cap; then the largest ``k <= min(w_P/2, sigma_F/(sigma1*sigma_x))`` (1/s) whose
    ``lugre-observer`` loop meets the requirement on the grid. Returns ``k``, its margins
    and the stiffness (N/m) (the nominal points searched, the whole grid checked; margins
    None without a bristle state)."""
    from controllers.lugre_observer import stiffness_ceiling

    k = 0.5 * w_P
    b = bristles(model)
    if b is None:
        return k, None, math.nan
    sigma1 = b[1]
    sigma_x = float(model.sensors.std()[0])
    if sigma1 > 0 and math.isfinite(sigma1):
        k = min(k, sigma_F / (sigma1 * sigma_x))
    nominal = nominal_points(grid)
    ceiling = stiffness_ceiling(model)
    stiff = ceiling

    def ok(kk: float, points: list[int] | None) -> bool:
        return _ratio(observer_margins(model, grid, kk, family, points, stiff)) \
            >= 1.0 + OBSERVER_PAD

    low = 1e-3 * k
    hi = k
    for frac in STIFFNESS_FRACTIONS:  # room for a correction a decade below its cap
        stiff = frac * ceiling
        if ok(0.1 * k, None):
            break
    if not ok(hi, nominal):
        if not ok(low, nominal):
            # no gain meets it: what fails is the observer's path at rest itself (its
            # bristle integrates the velocity, sigma0*x fed forward: a seal softer than the
            # model by more than the loop's stiffness is over-cancelled), not k
            cm = observer_margins(model, grid, hi, family, None, stiff)
            cm.structural = True
            return hi, cm, stiff
        for _ in range(OBSERVER_STEPS):
            mid = math.sqrt(low * hi)
            low, hi = (mid, hi) if ok(mid, nominal) else (low, mid)
        k = low
    cm = observer_margins(model, grid, k, family, None, stiff)
    while _ratio(cm) < 1.0 and k > 1e-2 * hi:  # the whole grid: shrink until it holds
        k *= 0.7
        cm = observer_margins(model, grid, k, family, None, stiff)
    return k, cm, stiff


# -------------------------------------------------------------- derivation
def derive_tuning(model: ControlModel, dt: float | None = None,
                  given: dict[str, float] | None = None) -> Tuning:
    """Derive the tuning of ``model`` (module docstring), explicit values in ``given`` winning.

    Parameters
    ----------
    model : ControlModel
        The controller's plant model.
    dt : float, optional
        Control period (s); default ``1/model.control_rate``.
    given : dict, optional
        Explicit ``force_bandwidth``, ``pid_bandwidth`` (rad/s), ``derivative_cutoff`` (Hz),
        ``observer_gain`` (1/s), ``velocity_compensation``.

    Raises
    ------
    FcompError
        The tuning misses the requirement somewhere on the grid, or the valve passes no
        flow (one line naming the worst point).
    """
    given = dict(given or {})
    bad = sorted(set(given) - set(GIVEN))
    if bad:
        raise FcompError(f"unknown tuning value(s) {', '.join(bad)}")
    dead = dead_valve(model)
    if dead is not None:
        raise FcompError(f"no tuning: {dead}")
    dt = 1.0 / model.control_rate if dt is None else dt
    sigma_F = force_noise(model)
    key = (model.plant_key(), dt, tuple(sorted((k, v) for k, v in given.items()
                                                if k != "observer_gain")))
    if key not in _PID_PARTS:
        _PID_PARTS[key] = _pid_part(model, dt, given, sigma_F)
    base = _PID_PARTS[key]
    grid = model_grid(model, dt)
    provisional = replace(base, observer_margins=None, given=tuple(sorted(given)))
    if bristles(model) is None:
        return replace(provisional, observer_gain=0.5 * provisional.pid_bandwidth)
    fam = provisional.family()
    # the stiffness is derived with the rule's own search; a gain given is checked with it
    k_rule, cm, stiff = observer_gain_rule(model, grid, fam, provisional.pid_bandwidth,
                                           sigma_F)
    k = k_rule
    if "observer_gain" in given:
        k = float(given["observer_gain"])
        cm = observer_margins(model, grid, k, fam, None, stiff)
        if _ratio(cm) < 1.0:
            raise refuse(f"observer_gain {k:.4g} 1/s", "the loop with the LuGre observer: "
                         + cm.describe(grid), "lower observer_gain")
    i, brk = cm.worst()
    m = cm.at(i, brk)
    text = cm.describe(grid)
    if cm.structural:
        text += (" -- for every observer gain: at rest the observer's bristle integrates the "
                 "velocity and feeds its pre-sliding stiffness forward (the low end of the "
                 "seal's range, controllers.lugre_observer.observer_friction), and the loop "
                 "with that path does not meet the requirement; check the plant file's "
                 "[uncertainty] presliding range and the friction model's sigma0, sigma1")
    return replace(provisional, observer_gain=float(k), observer_margins=m,
                   observer_worst=text, observer_stiffness=float(stiff))


#: Rules 1-3 by plant (their results do not depend on the friction model's levels).
_PID_PARTS: dict[tuple[Any, ...], Tuning] = {}


def _pid_part(model: ControlModel, dt: float, given: dict[str, float], sigma_F: float
              ) -> Tuning:
    """Rules 1-3, 5 and 6 (the observer's gain provisional)."""
    valve = model.valve_transfer()
    w_V = force_bandwidth_rule(valve, dt)
    grid = model_grid(model, dt)
    d = _design(model, grid, given, sigma_F, w_V, dt)
    g = d.gains
    what = ("the derived tuning" if not given else
            "the tuning given (" + ", ".join(f"{k} {v:g}" for k, v in sorted(given.items())
                                             if k != "observer_gain") + ")")
    if not d.feasible:
        r, mm = ratios(grid, g)
        m = loop_margins_from(mm[d.worst_break], (d.worst,))
        where = "the valve command" if d.worst_break == "valve" else "the position sensor"
        raise refuse(what, f"{m.shortfall()} broken at {where} at "
                     f"{grid.points[d.worst].describe()}",
                     "widen nothing: check the plant file's valve, volumes, mass and control "
                     "rate, or narrow its [uncertainty]" if not given else
                     "lower the gains given (or give fewer of them)")
    r, mm = ratios(grid, g)
    i, brk = worst_index(mm)
    worst = loop_margins_from(mm[brk], (i,))
    where = "the valve command" if brk == "valve" else "the position sensor"
    j = mid_point(grid)
    mid = {b: loop_margins_from(mm[b], (j,)) for b in mm}
    gains = PIDGains(kp=g.kp, ki=g.ki, kd=g.kd, derivative_cutoff=g.derivative_cutoff)
    w_P = (g.ki / model.mass) ** (1.0 / 3.0)
    w_h = model.column_frequency
    return Tuning(
        column_frequency=w_h, valve_bandwidth=valve_bandwidth(valve),
        control_rate=1.0 / dt, force_bandwidth=g.force_bandwidth, pid_bandwidth=w_P,
        pid_gains=gains, derivative_cutoff=g.derivative_cutoff, observer_gain=0.5 * w_P,
        ekf_measurement_std=tuple(float(s) for s in model.sensors.std()),  # type: ignore[arg-type]
        mpc_horizon_time=math.pi / w_h, mpc_velocity_ratio=0.5 * w_V,
        margins=worst, worst=f"{worst.describe()}, broken at {where}, at "
        f"{grid.points[i].describe()}", mid=mid, given=tuple(sorted(given)),
        velocity_compensation=g.velocity_compensation, valve_allows=w_V, delay=grid.delay,
    )


def family_margins(model: ControlModel, family: PIDFamilyGains, dt: float | None = None
                   ) -> tuple[LoopMargins, str, dict[str, LoopMargins]]:
    """The PID family's loop with ``family`` on the model's grid: the margins at the worst
    point, that point described, and the mid-stroke margins per break."""
    grid = model_grid(model, dt)
    r, mm = ratios(grid, family)
    i, brk = worst_index(mm)
    where = "the valve command" if brk == "valve" else "the position sensor"
    worst = loop_margins_from(mm[brk], (i,))
    j = mid_point(grid)
    return (worst, f"{worst.shortfall() or worst.describe()}, broken at {where}, at "
            f"{grid.points[i].describe()}", {b: loop_margins_from(mm[b], (j,)) for b in mm})


def fixed_tuning(model: ControlModel, force_bandwidth: float, pid_bandwidth: float,
                 derivative_cutoff: float, observer_gain: float, mpc_horizon_time: float,
                 mpc_velocity_ratio: float, velocity_compensation: float = 1.0) -> Tuning:
    """A tuning of given numbers with its margins, *not* checked (comparisons, reports:
    ``benchmarks/bench_tuning.py`` runs the former fixed tuning with it)."""
    dt = 1.0 / model.control_rate
    valve = model.valve_transfer()
    gains = PIDGains.placed(model.mass, pid_bandwidth, derivative_cutoff=derivative_cutoff)
    fam = PIDFamilyGains(gains.kp, gains.ki, gains.kd, derivative_cutoff, force_bandwidth,
                         velocity_compensation)
    worst, text, mid = family_margins(model, fam, dt)
    return Tuning(
        column_frequency=model.column_frequency, valve_bandwidth=valve_bandwidth(valve),
        control_rate=model.control_rate, force_bandwidth=force_bandwidth,
        pid_bandwidth=pid_bandwidth, pid_gains=gains, derivative_cutoff=derivative_cutoff,
        observer_gain=observer_gain,
        ekf_measurement_std=tuple(float(s) for s in model.sensors.std()),  # type: ignore[arg-type]
        mpc_horizon_time=mpc_horizon_time, mpc_velocity_ratio=mpc_velocity_ratio,
        margins=worst, worst=text, mid=mid,
        given=("force_bandwidth", "pid_bandwidth", "derivative_cutoff", "observer_gain",
               "velocity_compensation"),
        velocity_compensation=velocity_compensation,
        valve_allows=force_bandwidth_rule(valve, dt), delay=model.delay,
    )


def check_gains(model: ControlModel, family: PIDFamilyGains, dt: float, what: str
                ) -> LoopMargins:
    """The margins of explicit PID-family values on the grid at their worst point; refused
    (one line naming that point) where the requirement is not met."""
    worst, text, _mid = family_margins(model, family, dt)
    if worst.shortfall() is not None:
        raise refuse(what, text, "lower the gains (bandwidth), or give fewer values")
    return worst


def check_observer(ctrl: Any, what: str) -> LoopMargins:
    """Margins of an explicitly tuned ``lugre-observer`` on the grid's resting points; refused
    (one line) if insufficient."""
    grid = model_grid(ctrl.model, ctrl.dt)
    cm = observer_margins(ctrl.model, grid, ctrl.k, ctrl.family(), None,
                          ctrl.observer_stiffness)
    if _ratio(cm) < 1.0:
        raise refuse(what, f"the loop with the LuGre observer at rest: {cm.describe(grid)}",
                     "lower observer_gain (or the PID's gains)")
    i, brk = cm.worst()
    return cm.at(i, brk)


__all__ = ["FORCE_PHASE_MARGIN", "GIVEN", "MAX_SENSITIVITY", "MIN_GAIN_MARGIN",
           "MIN_PHASE_MARGIN", "Margins", "Tuning", "bristles", "check_gains",
           "check_observer", "dead_valve", "derive_tuning", "family_margins", "fixed_tuning",
           "force_bandwidth_rule", "force_loop", "model_grid", "observer_margins"]
