"""Default tuning that follows the plant: every compensator's tuning from the linearised plant.

The controllers of :mod:`controllers` share one structure (:mod:`controllers.pid`):
a PID position loop whose force demand is met by the model-based force loop of
:mod:`controllers.force_to_valve`. Their default tuning is derived here from
the controller's own plant model (:class:`~controllers.plant_model.ControlModel`:
its linearised valve, mass, friction slope, sensors and control rate), not from
the plant's name. :func:`derive_tuning` gives a :class:`Tuning`: the values and
the margins python-control computes for them (``control.stability_margins``).

Rules (SI units; ``dt = 1/f_s`` the control period)
---------------------------------------------------
1. **Force loop** ``w_F``. The force loop closes ``dF_a/dt = w_F*(F_d - F_a)``
   through the valve, so its loop transfer function is
   ``L_F(s) = w_F*G_v(s)/s`` (``G_v`` the valve's linearised dynamics, unit DC
   gain), sampled with a zero-order hold at ``dt``. ``w_F`` is the largest
   crossover for which ``L_F`` keeps the phase margin
   :data:`FORCE_PHASE_MARGIN` (45 deg: the valve's and the hold's lag at
   ``w_F`` at most 45 deg; an inner loop with a 45 deg margin has its closed-loop
   damping ratio near 0.45, Franklin, Powell & Emami-Naeini, *Feedback Control of
   Dynamic Systems*, 7th ed., 2015, sec. 6.4, ``zeta ~ PM/100``). For a
   first-order spool ``1/(tau_v s + 1)`` and a negligible hold this is
   ``w_F = 1/tau_v``; for the second-order servo valve
   (``w_v``, ``zeta_v``) the root of ``atan(2 zeta_v r/(1 - r^2)) = 45 deg``,
   ``r = w_F/w_v``. Where the force loop is slower than the oil (air) column
   (``w_F < w_h``) it cannot damp the column actively, and the classical limit
   of a valve-controlled axis applies to the position loop below.
2. **Position loop** ``w_P`` and the PID's pole pattern. The PID's gains are
   the triple-pole placement of :mod:`controllers.pid` with ``kp`` and ``kd``
   scaled, ``kp = a_p*3 m w_P^2``, ``ki = m w_P^3``, ``kd = a_d*3 m w_P``
   (``a_p`` in :data:`KP_FACTORS`, ``a_d`` in :data:`KD_FACTORS`; ``a_p = a_d = 1``
   is the triple pole at ``-w_P``). For each pattern, ``w_P`` is the largest
   bandwidth for which the nominal sampled loop of
   :func:`controllers.pid.position_loop` (mass and friction slope, the force
   loop of rule 1 through the valve, zero-order hold, the PID's derivative
   filter) keeps the margins :data:`MIN_GAIN_MARGIN` (2, 6 dB) and
   :data:`MIN_PHASE_MARGIN` (30 deg) -- the usual minimum margins (Franklin
   et al. sec. 6.4; Skogestad & Postlethwaite, *Multivariable Feedback
   Control*, 2nd ed., 2005, sec. 2.4.3: ``GM > 2``, ``PM > 30 deg``); of these,
   the pattern whose loop has the least integrated absolute error (IAE) after
   a step force on the piston (the load disturbance a friction force is;
   :func:`controllers.pid.disturbance_response`) is taken -- the design of PID
   controllers for load-disturbance rejection under robustness constraints
   (Astrom & Hagglund, *Advanced PID Control*, 2006, sec. 7.2-7.4: minimise
   IAE, or maximise ``ki``, subject to a robustness constraint). When the
   force loop is slower than the column (``w_F < w_h``), ``w_P`` is also kept
   below ``w_h/3``, the rule for a lightly damped hydraulic axis (Merritt,
   *Hydraulic Control Systems*, 1967, sec. 8.3; Jelali & Kroll, *Hydraulic
   Servo-systems*, 2003, sec. 7.2: position bandwidth below a third of
   ``w_h``).
3. **Derivative filter** ``f_d`` (Hz). The filtered derivative of a position
   measured with noise ``sigma_x`` (noise and quantisation ``q/sqrt(12)``) has the
   variance ``sigma_x^2*w_d/dt`` (first-order filter, ``w_d*dt << 1``); its force
   ``kd*sigma_v`` is kept at the force noise the pressure sensors already put in
   the force loop, ``sigma_F = sigma_p*sqrt(A1^2 + A2^2)``::

       w_d = dt*(sigma_F/(kd*sigma_x))^2,    f_d = min(w_d/(2 pi), f_s/4).

   ``f_d`` depends on ``kd`` (on ``w_P``), and the margins of rule 2 on ``f_d``:
   rule 2 is solved with ``f_d(kd)``.
4. **LuGre observer gain** ``k`` (1/s). The correction ``-k*e`` of the bristle
   state (:mod:`controllers.lugre_observer`) is a second controller beside the
   PID: at rest, where the bristle equation has no decay (``sigma0*|v|/g = 0``),
   the estimate ``F_hat = sigma0*z_hat + sigma1*dz_hat/dt`` adds
   ``sigma1*k + sigma0*k*dt/(z - 1)`` to the PID's ``C(z)`` -- an integral gain
   ``sigma0*k`` that on a stiff seal is several times the PID's own ``ki``
   (``sigma0`` = 1e6 N/m, ``k`` = 20 1/s: 2e7 N/(m s) against 7e6). ``k`` is
   the largest value up to ``w_P/2`` (the correction an octave slower than the
   loop it rides on) for which the loop *with* this path keeps the margins of
   rule 2 (:func:`observer_loop`), and its noise ``sigma1*k*sigma_x`` in the
   friction estimate stays below the pressure sensors' force noise ``sigma_F``
   (``k <= sigma_F/(sigma1*sigma_x)``, ``sigma0``, ``sigma1`` the bristle
   stiffness and damping of the controller's friction model). The passivity
   argument of Canudas de Wit et al. (1995), stability for every ``k > 0``,
   assumes a strictly positive real error dynamics that a sampled loop through a
   valve does not have: with ``k = w_P/2`` the hydraulic servo's loop at rest
   has no phase margin (-2 deg) and the observer built on the plant's true
   friction tracks worse than one built on a third of it.
5. **EKF** (:mod:`controllers.ekf`). The measurement noise is the sensors':
   ``R = diag(sigma_x^2, sigma_p^2, sigma_p^2)`` with noise and quantisation
   (``sigma^2 = noise^2 + q^2/12``); the process noise is the model's
   (:meth:`~controllers.plant_model.ControlModel.process_noise`: a thousandth of
   each state's scale, the bristle free to absorb the friction mismatch).
6. **MPC** (:mod:`controllers.mpc`). The MPC drives the valve itself (no force
   loop, no PID): between its command and the position lie the valve and the
   oil (air) column. Its horizon spans half a period of the column,
   ``T_N = pi/w_h`` -- the time from a pressure change to the first peak of
   the piston's response, the slowest of the actuator's own dynamics the
   prediction must see (``N = ceil(T_N*f_mpc)`` steps); its velocity weight
   makes a position error ``e_x`` and a velocity error ``e_v`` equally costly
   an octave below the force bandwidth the valve allows (rule 1),
   ``e_v = e_x*w_F/2`` (faster errors weigh as velocity errors, slower ones as
   position errors; ``e_x`` only sets the scale of the cost).

Values given explicitly -- in a plant file's ``[control]`` table or as
controller options -- replace the derived ones, and are checked the same way:
a tuning whose nominal loop is unstable or whose margins are below
:data:`MIN_GAIN_MARGIN` / :data:`MIN_PHASE_MARGIN` is refused with one line
(:class:`~fcomp.errors.FcompError`) naming the margin and what to change.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from controllers.pid import (
    PIDGains,
    disturbance_response,
    nominal_plant,
    pid_transfer,
    position_loop,
    spectral_radius,
)
from fcomp.errors import FcompError

if TYPE_CHECKING:
    from controllers.plant_model import ControlModel, Sensors

#: Minimum gain margin (factor, either way) of the position loop: 2 (6 dB).
MIN_GAIN_MARGIN = 2.0
#: Minimum phase margin of the position loop (deg).
MIN_PHASE_MARGIN = 30.0
#: Phase margin the force loop is designed for (deg), rule 1.
FORCE_PHASE_MARGIN = 45.0
#: Ratio of the position-loop bandwidth to the column's frequency where the force
#: loop does not damp the column (Merritt; Jelali & Kroll), rule 2.
COLUMN_FRACTION = 1.0 / 3.0
#: Highest derivative filter cut-off, as a fraction of the control rate (Hz per Hz).
DERIVATIVE_CUTOFF_MAX_FRACTION = 0.25
#: Pole patterns of rule 2: factors on the triple-pole ``kd`` and ``kp`` (``ki = m w^3``).
KD_FACTORS = (0.4, 0.6, 0.8, 1.0)
KP_FACTORS = (0.5, 0.7, 1.0)
#: Duration (s) of the step-disturbance response whose IAE rule 2 minimises.
IAE_DURATION = 1.0
#: Relative pad of rule 4's bisection on the margins (rule 2 leaves the PID at its
#: margins plus :data:`PAD`: the observer may take the rest).
OBSERVER_PAD = 1e-3
#: The derivation's margins above the minimum: 1 % on the gain, 1 deg on the phase
#: (the bisection's interpolated margins against python-control's).
PAD = 0.01
#: Frequencies of the loops' responses (margins).
N_FREQUENCIES = 2000


@dataclass(frozen=True)
class Margins:
    """Stability margins of a sampled loop (python-control).

    Attributes
    ----------
    gain : float
        Gain margin: the factor by which the loop gain may grow (or, for a
        conditionally stable loop, shrink) before the closed loop is unstable
        (``inf`` if no phase crossover).
    phase : float
        Phase margin (deg; ``inf`` if no gain crossover).
    crossover : float
        Gain crossover frequency (rad/s) of the phase margin.
    radius : float
        Largest closed-loop pole magnitude ``|z|`` (stable below 1).
    """

    gain: float
    phase: float
    crossover: float
    radius: float

    @property
    def gain_db(self) -> float:
        """The gain margin in dB."""
        return 20 * math.log10(self.gain) if self.gain > 0 else -math.inf

    def shortfall(self, min_gain: float = MIN_GAIN_MARGIN,
                  min_phase: float = MIN_PHASE_MARGIN) -> str | None:
        """What is insufficient (one phrase), or None."""
        if not self.radius < 1.0:
            return f"the closed loop is unstable (largest pole |z| = {self.radius:.4f} >= 1)"
        if self.gain < min_gain:
            return (f"gain margin {self.gain:.3g} ({self.gain_db:.1f} dB) < {min_gain:g} "
                    f"({20 * math.log10(min_gain):.0f} dB)")
        if self.phase < min_phase:
            return f"phase margin {self.phase:.1f} deg < {min_phase:g} deg"
        return None

    def describe(self) -> str:
        return (f"gain margin {self.gain:.3g} ({self.gain_db:.1f} dB), phase margin "
                f"{self.phase:.1f} deg at {self.crossover:.4g} rad/s, closed-loop |z| "
                f"{self.radius:.4f}")


def _response(loop: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Magnitude, unwrapped phase (deg) and frequencies (rad/s) of a sampled loop, 0.1 rad/s
    to just below Nyquist (:data:`N_FREQUENCIES` points, logarithmic)."""
    dt = float(loop.dt)
    w = np.logspace(-1.0, math.log10(math.pi / dt) - 1e-4, N_FREQUENCIES)
    resp = np.asarray(loop(np.exp(1j * w * dt)), dtype=complex).ravel()
    return np.abs(resp), np.degrees(np.unwrap(np.angle(resp))), w


def loop_margins(loop: Any) -> Margins:
    """Gain and phase margins of a sampled loop transfer function (``control.stability_margins``).

    python-control is given the loop's frequency response (:func:`_response`; its
    polynomial method is unreliable on these high-order sampled loops). Every
    crossing is considered (``returnall=True``): the gain margin is the smallest
    factor, up (``gm > 1``) or down (``1/gm`` for ``gm < 1``: a PID on a double
    integrator is conditionally stable), the phase margin the smallest over the
    gain crossovers, wrapped to ``(-180, 180]`` deg.
    """
    import control as ct

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gm, pm, _sm, _wpc, wgc, _wms = ct.stability_margins(_response(loop), returnall=True)
    return _margins(np.atleast_1d(gm), np.atleast_1d(pm), np.atleast_1d(wgc),
                    spectral_radius(loop))


def _margins(gm: np.ndarray, pm: np.ndarray, wgc: np.ndarray, radius: float) -> Margins:
    gms = [float(g) for g in gm if np.isfinite(g) and g > 0]
    gain = min((g if g >= 1 else 1 / g for g in gms), default=math.inf)
    pms = [((float(p) + 180.0) % 360.0) - 180.0 for p in pm]
    if pms:
        i = int(np.argmin(pms))
        return Margins(gain=gain, phase=pms[i], crossover=float(wgc[i]), radius=radius)
    return Margins(gain=gain, phase=math.inf, crossover=math.nan, radius=radius)


def quick_margins(loop: Any) -> Margins:
    """:func:`loop_margins` by linear interpolation of the same response (no python-control
    search): the rules' bisections, the final values from :func:`loop_margins`."""
    mag, ph, w = _response(loop)
    lm = np.log(mag)
    ig = np.nonzero(np.sign(lm[:-1]) != np.sign(lm[1:]))[0]
    fg = lm[ig] / (lm[ig] - lm[ig + 1])
    pm = 180.0 + ph[ig] + fg * (ph[ig + 1] - ph[ig])
    wgc = w[ig] * (w[ig + 1] / w[ig]) ** fg
    k = np.floor((ph + 180.0) / 360.0)
    ip = np.nonzero(k[:-1] != k[1:])[0]
    ref = -180.0 + 360.0 * np.maximum(k[ip], k[ip + 1])
    fp = (ref - ph[ip]) / (ph[ip + 1] - ph[ip])
    gm = 1.0 / np.exp(lm[ip] + fp * (lm[ip + 1] - lm[ip]))
    keep = w[ip] > 1.0  # the integrators' phase at the bottom of the grid is no crossing
    return _margins(gm[keep], pm, wgc, spectral_radius(loop))


def force_loop(force_bandwidth: float, valve: Any, dt: float) -> Any:
    """The force loop's sampled loop transfer function ``w_F*G_v(s)/s`` (zero-order hold)."""
    import control as ct

    s = ct.tf("s")
    return ct.tf(ct.c2d(ct.ss(force_bandwidth * valve / s), dt, "zoh"))


def _largest(ok: Any, low: float, high: float, rel: float = 5e-3) -> float:
    """The largest ``w`` in ``[low, high]`` with ``ok(w)`` (``ok(low)`` true, monotone)."""
    if ok(high):
        return high
    while high - low > rel * low:
        mid = math.sqrt(low * high)
        low, high = (mid, high) if ok(mid) else (low, mid)
    return low


def force_bandwidth_rule(valve: Any, dt: float) -> float:
    """Rule 1: the largest ``w_F`` whose force loop keeps :data:`FORCE_PHASE_MARGIN`."""
    def ok(w: float) -> bool:
        return quick_margins(force_loop(w, valve, dt)).phase >= FORCE_PHASE_MARGIN

    low = 1.0
    if not ok(low):
        raise FcompError(f"no force-loop bandwidth keeps a {FORCE_PHASE_MARGIN:g} deg phase "
                         f"margin through this valve at {1 / dt:g} Hz; raise the control rate")
    return _largest(ok, low, 0.5 * math.pi / dt)


def force_noise(model: ControlModel) -> float:
    """``sigma_F = sigma_p*sqrt(A1^2 + A2^2)`` (N): the pressure sensors' force noise."""
    return float(model.sensors.std()[1]) * math.hypot(model.A1, model.A2)


def derivative_cutoff_rule(kd: float, sensors: Sensors, sigma_F: float, dt: float) -> float:
    """Rule 3: the derivative filter cut-off (Hz) whose force noise is ``sigma_F``."""
    sigma_x = float(sensors.std()[0])
    top = DERIVATIVE_CUTOFF_MAX_FRACTION / dt
    if kd <= 0:
        return top
    w_d = dt * (sigma_F / (kd * sigma_x)) ** 2
    return min(w_d / (2 * math.pi), top)


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
    force_bandwidth, pid_bandwidth : float
        ``w_F``, ``w_P`` (rad/s), rules 1 and 2 (``w_P``: ``ki = m w_P^3``).
    pid_gains : PIDGains
        The PID's gains (rule 2's pole pattern, rule 3's filter).
    derivative_cutoff : float
        ``f_d`` (Hz), rule 3.
    observer_gain : float
        ``k`` (1/s), rule 4.
    ekf_measurement_std : tuple of float
        Standard deviations of ``[x, p1, p2]`` (m, Pa, Pa), rule 5.
    mpc_horizon_time : float
        ``T_N = pi/w_h`` (s), rule 6.
    mpc_velocity_ratio : float
        ``e_v/e_x = w_F/2`` (1/s), rule 6.
    margins : Margins
        The position loop's.
    force_margins : Margins
        The force loop's.
    observer_margins : Margins or None
        The position loop's with the LuGre observer's path at rest (rule 4); None for a
        friction model without a bristle state.
    given : tuple of str
        The values given explicitly (not derived).
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
    margins: Margins
    force_margins: Margins
    given: tuple[str, ...] = field(default=())
    observer_margins: Margins | None = None
    velocity_compensation: float = 1.0

    def mpc_horizon(self, rate: float) -> int:
        """Horizon in steps at an MPC rate (Hz): ``ceil(T_N*rate)``, at least 2."""
        return max(2, math.ceil(self.mpc_horizon_time * rate - 1e-9))

    def lines(self) -> list[str]:
        """The tuning as printed by ``fcomp plant check``."""
        def src(name: str) -> str:
            return "given" if name in self.given else "derived"

        return [
            f"tuning: force loop {self.force_bandwidth:.4g} rad/s ({src('force_bandwidth')}; "
            f"valve bandwidth {self.valve_bandwidth:.4g} rad/s, column {self.column_frequency:.4g}"
            f" rad/s), PID {self.pid_bandwidth:.4g} rad/s ({src('pid_bandwidth')}), "
            f"kp {self.pid_gains.kp:.4g} N/m, ki {self.pid_gains.ki:.4g} N/(m s), kd "
            f"{self.pid_gains.kd:.4g} N s/m, derivative filter {self.derivative_cutoff:.4g} Hz, "
            f"observer gain "
            f"{self.observer_gain:.4g} 1/s ({src('observer_gain')})",
            f"  position loop: {self.margins.describe()}",
            f"  force loop: {self.force_margins.describe()}",
            *([f"  with the LuGre observer at rest: {self.observer_margins.describe()}"]
              if self.observer_margins is not None else []),
            f"  MPC horizon {self.mpc_horizon_time * 1e3:.3g} ms, velocity weight e_v/e_x = "
            f"{self.mpc_velocity_ratio:.4g} 1/s; EKF sensor std x {self.ekf_measurement_std[0]:.3g}"
            f" m, p {self.ekf_measurement_std[1]:.4g} Pa",
        ]

    def as_dict(self) -> dict[str, Any]:
        """JSON form (SI units)."""
        def marg(m: Margins) -> dict[str, float | None]:
            return {k: (v if math.isfinite(v) else None) for k, v in
                    (("gain", m.gain), ("gain_db", m.gain_db), ("phase", m.phase),
                     ("crossover", m.crossover), ("radius", m.radius))}

        return {
            "column_frequency": self.column_frequency, "valve_bandwidth": self.valve_bandwidth,
            "control_rate": self.control_rate, "force_bandwidth": self.force_bandwidth,
            "pid_bandwidth": self.pid_bandwidth, "derivative_cutoff": self.derivative_cutoff,
            "pid_gains": {"kp": self.pid_gains.kp, "ki": self.pid_gains.ki,
                          "kd": self.pid_gains.kd},
            "observer_gain": self.observer_gain,
            "ekf_measurement_std": list(self.ekf_measurement_std),
            "mpc_horizon_time": self.mpc_horizon_time,
            "mpc_velocity_ratio": self.mpc_velocity_ratio,
            "margins": marg(self.margins), "force_margins": marg(self.force_margins),
            "observer_margins": (None if self.observer_margins is None
                                 else marg(self.observer_margins)),
            "given": list(self.given),
        }


def valve_bandwidth(valve: Any) -> float:
    """The -3 dB bandwidth (rad/s) of the valve's linear dynamics (``control.bandwidth``)."""
    import control as ct

    return float(ct.bandwidth(valve))


def pid_gains(mass: float, bandwidth: float, sensors: Sensors, sigma_F: float,
              dt: float, kp_factor: float = 1.0, kd_factor: float = 1.0) -> PIDGains:
    """The placed PID gains of a bandwidth and pole pattern with the derivative filter of
    rule 3."""
    placed = PIDGains.placed(mass, bandwidth, kp_factor, kd_factor)
    return PIDGains.placed(mass, bandwidth, kp_factor, kd_factor,
                           derivative_cutoff=derivative_cutoff_rule(placed.kd, sensors,
                                                                    sigma_F, dt))


def refuse(what: str, problem: str, advice: str) -> FcompError:
    """The one-line refusal of a tuning."""
    return FcompError(f"{what} refused: {problem} on the nominal loop; {advice}")


#: Rules 1-3 by plant (their results do not depend on the friction model's levels).
_PID_PARTS: dict[tuple[Any, ...], tuple[Any, ...]] = {}


def _pid_part(model: ControlModel, dt: float, given: dict[str, float], sigma_F: float
              ) -> tuple[Any, ...]:
    """Rules 1-3: ``(w_h, valve, w_F, force margins, w_P, gains, margins, nominal plant)``."""
    valve = model.valve_transfer()
    damping = model.viscous_damping()
    w_h = model.column_frequency
    w_F = float(given.get("force_bandwidth") or force_bandwidth_rule(valve, dt))
    f_margins = loop_margins(force_loop(w_F, valve, dt))
    if "force_bandwidth" in given and (why := f_margins.shortfall(1.0, 0.0)) is not None:
        raise refuse(f"force_bandwidth {w_F:.4g} rad/s", f"the force loop: {why}",
                     "lower force_bandwidth")

    def gains_of(w_P: float, shape: tuple[float, float]) -> PIDGains:
        if "derivative_cutoff" in given:
            return PIDGains.placed(model.mass, w_P, *shape,
                                   derivative_cutoff=float(given["derivative_cutoff"]))
        return pid_gains(model.mass, w_P, model.sensors, sigma_F, dt, *shape)

    plant = nominal_plant(model.mass, damping, w_F, valve, dt)  # position_loop's, once

    def margins_of(gains: PIDGains, quick: bool = True) -> Margins:
        loop = pid_transfer(gains, dt) * plant
        return quick_margins(loop) if quick else loop_margins(loop)

    def iae(gains: PIDGains) -> float:
        e = disturbance_response(gains, model.mass, damping, w_F, valve, dt, IAE_DURATION)
        return float(np.sum(np.abs(e)) * dt)

    if "pid_bandwidth" in given:
        w_P = float(given["pid_bandwidth"])
        gains = gains_of(w_P, (1.0, 1.0))
    else:
        cap = COLUMN_FRACTION * w_h if w_F < w_h else w_F
        low = min(1.0, cap)
        candidates = []
        for shape in ((kp, kd) for kd in KD_FACTORS for kp in KP_FACTORS):
            def ok(w: float, shape: tuple[float, float] = shape) -> bool:
                return margins_of(gains_of(w, shape)).shortfall(
                    MIN_GAIN_MARGIN * (1 + PAD), MIN_PHASE_MARGIN + PAD * 100) is None

            if ok(low):
                w = _largest(ok, low, cap)
                candidates.append((iae(gains_of(w, shape)), w, shape))
        if not candidates:
            why = margins_of(gains_of(low, (1.0, 1.0))).shortfall()
            raise refuse("the derived tuning", f"even a PID bandwidth of {low:g} rad/s gives "
                         f"{why}", "check the plant file's valve, mass and control rate")
        _, w_P, shape = min(candidates)
        gains = gains_of(w_P, shape)
    margins = margins_of(gains, quick=False)
    if (why := margins.shortfall()) is not None:
        raise refuse(f"pid_bandwidth {w_P:.4g} rad/s with force_bandwidth {w_F:.4g} rad/s", why,
                     "lower pid_bandwidth or raise force_bandwidth")
    return w_h, valve, w_F, f_margins, w_P, gains, margins, plant


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
        ``observer_gain`` (1/s).

    Raises
    ------
    FcompError
        The explicit (or the derived) tuning's loop is unstable or lacks margin (one line).
    """
    given = dict(given or {})
    bad = sorted(set(given) - {"force_bandwidth", "pid_bandwidth", "derivative_cutoff",
                               "observer_gain"})
    if bad:
        raise FcompError(f"unknown tuning value(s) {', '.join(bad)}")
    dt = 1.0 / model.control_rate if dt is None else dt
    sigma_F = force_noise(model)
    key = (model.plant_key(), dt, tuple(sorted((k, v) for k, v in given.items()
                                                if k != "observer_gain")))
    if key not in _PID_PARTS:
        _PID_PARTS[key] = _pid_part(model, dt, given, sigma_F)
    w_h, valve, w_F, f_margins, w_P, gains, margins, plant = _PID_PARTS[key]
    o_margins = None
    if "observer_gain" in given:
        k = float(given["observer_gain"])
        if bristles(model) is not None:
            o_margins = check_observer(gains, model, k, w_F, dt, f"observer_gain {k:.4g} 1/s",
                                       plant)
    else:
        k, o_margins = observer_gain_rule(model, gains, w_P, w_F, sigma_F, dt, plant)
    return Tuning(
        column_frequency=w_h, valve_bandwidth=valve_bandwidth(valve),
        control_rate=1.0 / dt, force_bandwidth=w_F, pid_bandwidth=w_P, pid_gains=gains,
        derivative_cutoff=gains.derivative_cutoff, observer_gain=float(k),
        ekf_measurement_std=tuple(float(s) for s in model.sensors.std()),  # type: ignore[arg-type]
        mpc_horizon_time=math.pi / w_h, mpc_velocity_ratio=0.5 * w_F,
        margins=margins, force_margins=f_margins, given=tuple(sorted(given)),
        observer_margins=o_margins,
    )


def bristles(model: ControlModel) -> tuple[float, float] | None:
    """``(sigma0, sigma1)`` of the controller's friction model (N/m, N s/m), or None for a
    model without a bristle state (no LuGre observer to tune: it refuses such a model)."""
    p = model.friction.flat_params()
    if "sigma0" not in p:
        return None
    return float(p["sigma0"]), float(p.get("sigma1", 0.0))


def observer_loop(gains: PIDGains, model: ControlModel, observer_gain: float,
                  force_bandwidth: float, dt: float, plant: Any = None) -> Any:
    """The position loop with the LuGre observer's path at rest (rule 4)::

        L(z) = (C(z) + sigma1*k + sigma0*k*dt/(z - 1)) * P(z)

    ``C`` the PID and the path over one denominator (:func:`controllers.pid.pid_transfer`:
    no hidden pole at ``z = 1``), ``P`` the nominal plant (:func:`controllers.pid.nominal_plant`,
    or ``plant`` if given)."""
    sigma0, sigma1 = bristles(model) or (0.0, 0.0)
    if plant is None:
        plant = nominal_plant(model.mass, model.viscous_damping(), force_bandwidth,
                              model.valve_transfer(), dt)
    return pid_transfer(gains, dt, extra_p=sigma1 * observer_gain,
                        extra_i=sigma0 * observer_gain) * plant


def observer_gain_rule(model: ControlModel, gains: PIDGains, pid_bandwidth: float,
                       force_bandwidth: float, sigma_F: float, dt: float, plant: Any
                       ) -> tuple[float, Margins | None]:
    """Rule 4: the largest ``k <= min(w_P/2, sigma_F/(sigma1*sigma_x))`` (1/s) whose
    :func:`observer_loop` (on the nominal ``plant``) keeps the margins of rule 2, with those
    margins (None for a model without a bristle state)."""
    k = 0.5 * pid_bandwidth
    if (b := bristles(model)) is None:
        return k, None  # no bristle state: no observer to tune
    sigma1 = b[1]
    sigma_x = float(model.sensors.std()[0])
    if sigma1 > 0 and math.isfinite(sigma1):
        k = min(k, sigma_F / (sigma1 * sigma_x))

    def ok(kk: float) -> bool:
        return quick_margins(observer_loop(gains, model, kk, force_bandwidth, dt,
                                           plant)).shortfall(
            MIN_GAIN_MARGIN * (1 + OBSERVER_PAD), MIN_PHASE_MARGIN + OBSERVER_PAD * 100) is None

    def margins(kk: float) -> Margins:
        return loop_margins(observer_loop(gains, model, kk, force_bandwidth, dt, plant))

    low = 1e-3 * k
    if not ok(low):
        return low, margins(low)
    k = _largest(ok, low, k)
    # the bisection's interpolated margins against python-control's: shrink until it agrees
    m = margins(k)
    while k > low and m.shortfall() is not None:
        k = max(low, 0.9 * k)
        m = margins(k)
    return k, m


def fixed_tuning(model: ControlModel, force_bandwidth: float, pid_bandwidth: float,
                 derivative_cutoff: float, observer_gain: float, mpc_horizon_time: float,
                 mpc_velocity_ratio: float) -> Tuning:
    """A tuning of given numbers with its margins, *not* checked (comparisons, reports:
    ``benchmarks/bench_tuning.py`` runs the former fixed tuning with it)."""
    dt = 1.0 / model.control_rate
    valve = model.valve_transfer()
    gains = PIDGains.placed(model.mass, pid_bandwidth, derivative_cutoff=derivative_cutoff)
    return Tuning(
        column_frequency=model.column_frequency, valve_bandwidth=valve_bandwidth(valve),
        control_rate=model.control_rate, force_bandwidth=force_bandwidth,
        pid_bandwidth=pid_bandwidth, pid_gains=gains, derivative_cutoff=derivative_cutoff,
        observer_gain=observer_gain,
        ekf_measurement_std=tuple(float(s) for s in model.sensors.std()),  # type: ignore[arg-type]
        mpc_horizon_time=mpc_horizon_time, mpc_velocity_ratio=mpc_velocity_ratio,
        margins=loop_margins(position_loop(gains, model.mass, model.viscous_damping(),
                                           force_bandwidth, valve, dt)),
        force_margins=loop_margins(force_loop(force_bandwidth, valve, dt)),
        given=("force_bandwidth", "pid_bandwidth", "derivative_cutoff", "observer_gain"),
        observer_margins=(loop_margins(observer_loop(gains, model, observer_gain,
                                                     force_bandwidth, dt))
                          if bristles(model) is not None else None),
    )


def check_observer(gains: PIDGains, model: ControlModel, observer_gain: float,
                   force_bandwidth: float, dt: float, what: str, plant: Any = None) -> Margins:
    """Margins of the loop with the LuGre observer (:func:`observer_loop`) for explicit values;
    refused (one line) if insufficient."""
    m = loop_margins(observer_loop(gains, model, observer_gain, force_bandwidth, dt, plant))
    if (why := m.shortfall()) is not None:
        raise refuse(what, f"the loop with the LuGre observer at rest: {why}",
                     "lower observer_gain (or the PID's gains)")
    return m


def check_gains(gains: PIDGains, model: ControlModel, force_bandwidth: float, dt: float,
                what: str) -> Margins:
    """Margins of explicit gains on the nominal loop; refused (one line) if insufficient."""
    m = loop_margins(position_loop(gains, model.mass, model.viscous_damping(), force_bandwidth,
                                   model.valve_transfer(), dt))
    if (why := m.shortfall()) is not None:
        raise refuse(what, why, "lower the gains (bandwidth) or raise force_bandwidth")
    return m


__all__ = ["FORCE_PHASE_MARGIN", "MIN_GAIN_MARGIN", "MIN_PHASE_MARGIN", "Margins", "Tuning",
           "bristles", "check_gains", "check_observer", "derive_tuning", "fixed_tuning", "force_bandwidth_rule", "force_loop",
           "loop_margins", "observer_loop", "quick_margins"]
