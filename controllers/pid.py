"""``pid``: PID position control with a derivative filter and anti-windup.

The PID acts on the position error ``e = r - x`` (m) and produces a *force
demand* (N); :mod:`controllers.force_to_valve` turns the force demand into
the valve command. Every force-based controller of the package
(``pid-ff``, ``lugre-observer``, ``ekf``) is this PID plus a friction
estimate added to the demand, so they differ only in the compensation::

    F_d = m*d2r/dt2 + F_g + kp*e + ki*I + kd*(dr/dt - v_f) + F_hat

with ``F_g`` the weight the actuator carries (``m*g`` for a vertical
cylinder extending upward, 0 for a horizontal one), ``v_f`` the velocity
from the measured position through the derivative filter (first order,
cut-off ``derivative_cutoff`` Hz; backward Euler)::

    v_f[k] = (Tf*v_f[k-1] + x[k] - x[k-1]) / (Tf + dt),   Tf = 1/(2*pi*f_d)

and ``F_hat`` the friction estimate (0 for ``pid``), *with its lead through the
force loop* where :attr:`PIDController.friction_lead` (off by default: the tuning's
closed forms do not include it; :meth:`PIDController.friction_demand`): the force loop of
:mod:`controllers.force_to_valve` follows its demand with the first-order lag
``1/(1 + s/w_F)``, so an estimate added as it is arrives ``1/w_F`` late (5 ms on
the hydraulic servo) -- at a reversal, where the friction turns over in tens of
milliseconds, late enough that an exact estimate compensates worse than a
crude one that turns early. The estimate's rate is fed forward with it,
``F_hat + (F_hat[k] - F_hat[k-1])/(dt*w_F)``, the demand whose lagged force is
the estimate (backstepping: the desired force's derivative fed forward). The
integral is the
backward-Euler sum of ``e`` with *anti-windup* by back-calculation (gain
``kt``, 1/s; Astrom & Hagglund, *Advanced PID Control*, 2006, sec. 3.5): when
the force demand exceeds what the actuator can produce
(``[F_min, F_max]``, from the supply pressure and the piston areas) the
integral is bled by ``kt*(F_sat - F_d)/ki`` per second, and it is frozen
while the valve command itself saturates in the direction of the error. The integral is
bounded besides: its force ``ki*I`` stays within ``[F_min, F_max]``
(:func:`controllers.safety.clamp_integral`), so that nothing winds it beyond what the
actuator can push, and after the fail-safe layer held the valve it restarts bumplessly
(:meth:`PIDController.reenter`).

The gains (``kp``, ``ki``, ``kd``), the force-loop bandwidth, the velocity
compensation and the derivative cut-off are derived from the plant by
:mod:`controllers.tuning` on the loop as it runs (:mod:`controllers.loop_analysis`);
:meth:`PIDGains.placed` is the triple pole at ``-w`` of the ideal
mass-plus-force-loop, ``kp = 3*m*w^2``, ``ki = m*w^3``, ``kd = 3*m*w``, the
pattern a ``bandwidth`` option places.

**Gains without margins are refused**: explicit options are checked on the loop as
it runs (:meth:`~controllers.plant_model.ControlModel.checked_margins`: the sampled
plant over the stroke and the plant file's parameter box, the delay, this law as
coded) and refused in one line naming the worst point where it misses GM >= 2, PM
>= 30 deg or Ms <= 2 -- an unstable loop first. :func:`pid_transfer` is this PID's
discrete transfer function (its integral the backward-Euler sum ``PIDLaw.force``
runs).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from controllers.base import Controller, Reference
from controllers.safety import SCALAR, bumpless_integral, clamp_integral, integral_bounds
from fcomp.errors import FcompError


@dataclass(frozen=True)
class PIDGains:
    """PID gains (SI): ``kp`` N/m, ``ki`` N/(m s), ``kd`` N s/m, cut-off Hz, ``kt`` 1/s."""

    kp: float
    ki: float
    kd: float
    derivative_cutoff: float = 60.0
    kt: float = 20.0

    def __post_init__(self) -> None:
        for name in ("kp", "ki", "kd", "derivative_cutoff", "kt"):
            val = getattr(self, name)
            if not (isinstance(val, int | float) and math.isfinite(val) and val >= 0):
                raise FcompError(f"pid gain {name} must be a finite number >= 0, got {val!r}")
        if self.kp == 0:
            raise FcompError("pid gain kp must be positive (a position loop needs it)")
        if self.derivative_cutoff == 0:
            raise FcompError("pid derivative_cutoff must be positive (Hz)")

    @classmethod
    def placed(cls, mass: float, bandwidth: float, kp_factor: float = 1.0,
               kd_factor: float = 1.0, **extra: float) -> PIDGains:
        """Gains placing the nominal closed-loop poles at ``-bandwidth`` (rad/s):
        ``kp = 3 m w^2``, ``ki = m w^3``, ``kd = 3 m w``; ``kp_factor`` and ``kd_factor``
        scale ``kp`` and ``kd`` (another pole pattern with the same ``ki``)."""
        if not (math.isfinite(bandwidth) and bandwidth > 0):
            raise FcompError(f"pid bandwidth must be a positive number (rad/s), got {bandwidth}")
        w = bandwidth
        return cls(kp=kp_factor * 3 * mass * w**2, ki=mass * w**3,
                   kd=kd_factor * 3 * mass * w, **extra)


def pid_transfer(gains: PIDGains, dt: float, extra_p: float = 0.0,
                 extra_i: float = 0.0) -> Any:
    """The discrete PID of this module, error -> force (backward-Euler integral, derivative
    through the first-order filter), with an optional parallel path ``extra_p +
    extra_i*dt/(z - 1)`` (a forward-Euler integrator: the LuGre observer at rest,
    at rest) over the same denominator::

        C(z) = kp + extra_p + (ki*dt*z + extra_i*dt)/(z - 1) + kd*(z - 1)/((Tf + dt)*z - Tf)
    """
    import control as ct

    z = ct.tf([1.0, 0.0], [1.0], dt)
    Tf = 1.0 / (2 * math.pi * gains.derivative_cutoff)
    return ct.tf(gains.kp + extra_p + (gains.ki * dt * z + extra_i * dt) / (z - 1)
                 + gains.kd * (z - 1) / ((Tf + dt) * z - Tf))


def unstable(gains: PIDGains, rho: float, dt: float) -> FcompError:
    """The refusal of gains whose nominal closed loop has a pole ``|z| = rho >= 1``."""
    return FcompError(
        f"pid gains kp={gains.kp:.4g}, ki={gains.ki:.4g}, kd={gains.kd:.4g} give an unstable "
        f"closed loop on the nominal model (largest pole |z| = {rho:.4f} >= 1 at "
        f"{1 / dt:.0f} Hz); lower the gains or the bandwidth"
    )


#: The velocity compensation's range: 1 the measured velocity alone, 0 the reference's,
#: below 0 the measured velocity fed back to the valve (:mod:`controllers.force_to_valve`).
VELOCITY_COMPENSATION = (-3.0, 1.0)


class PIDLaw:
    """The discrete PID of the module docstring (state: integral, filtered velocity)."""

    def __init__(self, gains: PIDGains, dt: float) -> None:
        self.gains = gains
        self.dt = dt
        self.Tf = 1.0 / (2 * math.pi * gains.derivative_cutoff)
        self.reset(0.0)

    def reset(self, x0: float) -> None:
        self.integral = 0.0
        self.v_f = 0.0
        self.x_prev = x0

    def velocity(self, x: float) -> float:
        """Update and return the filtered velocity ``v_f`` (m/s) from the measured position."""
        self.v_f = (self.Tf * self.v_f + x - self.x_prev) / (self.Tf + self.dt)
        self.x_prev = x
        return self.v_f

    def force(self, e: float, dr: float) -> float:
        """``kp*e + ki*(I + dt*e) + kd*(dr - v_f)``: the backward-Euler integral, this
        sample's error included (``I[k] = I[k-1] + dt*e[k]``; :func:`pid_transfer`'s
        ``ki*dt*z/(z - 1)``); :meth:`integrate` then stores it, or keeps ``I[k-1]``."""
        g = self.gains
        return g.kp * e + g.ki * (self.integral + self.dt * e) + g.kd * (dr - self.v_f)

    def integrate(self, e: float, demand: float, applied: float, valve_saturated: int) -> None:
        """Advance the integral to ``I[k] = I[k-1] + dt*e[k]`` (the value :meth:`force` used)
        plus the back-calculation ``dt*kt*(applied - demand)/ki`` (zero unless the demand
        was clipped); frozen at ``I[k-1]`` while the valve saturates with ``e``.

        ``valve_saturated`` is +1 / -1 when the valve command hit its upper /
        lower limit, 0 otherwise.
        """
        g = self.gains
        if g.ki == 0:
            return
        if valve_saturated * e > 0:
            return
        self.integral += self.dt * (e + g.kt * (applied - demand) / g.ki)


class PIDController(Controller):
    """PID position control, force demand through the valve model (see the module docstring).

    Parameters
    ----------
    model
        The controller's own view of the plant (:class:`controllers.base.ControlModel`).
    rate
        Sample rate (Hz); default the plant's control rate.
    bandwidth
        Closed-loop bandwidth (rad/s) placing the gains; default the plant's derived one
        (:attr:`~controllers.plant_model.ControlModel.tuning`). Any explicit tuning option
        is checked for margins (:meth:`~controllers.plant_model.ControlModel.checked_margins`).
    kp, ki, kd
        Gains (N/m, N/(m s), N s/m) overriding the placed ones.
    derivative_cutoff
        Derivative filter cut-off (Hz); default the tuning's (rule 3 of
        :mod:`controllers.tuning`).
    kt
        Anti-windup back-calculation gain (1/s).
    force_bandwidth
        Bandwidth of the force loop (rad/s) of :mod:`controllers.force_to_valve`.
    """

    name: ClassVar[str] = "pid"
    uses_friction: ClassVar[bool] = False
    #: Whether the friction estimate is fed with its lead through the force loop
    #: (:meth:`friction_demand`). Off: the tuning's closed forms of the compensators'
    #: paths (:mod:`controllers.loop_analysis.observer`) do not include the lead's state,
    #: so with it on the loop as it runs would differ from the loop the tuning derived
    #: (``fcomp plant check`` analyses the step as coded either way).
    friction_lead: ClassVar[bool] = False
    options: ClassVar[tuple[str, ...]] = (
        "rate", "bandwidth", "kp", "ki", "kd", "derivative_cutoff", "kt", "force_bandwidth",
        "velocity_compensation",
    )
    #: The options that replace the derived tuning (checked for margins when given).
    tuning_options: ClassVar[tuple[str, ...]] = (
        "rate", "bandwidth", "kp", "ki", "kd", "derivative_cutoff", "force_bandwidth",
        "velocity_compensation",
    )

    def __init__(self, model: Any, **options: Any) -> None:
        super().__init__(model, **options)
        o = self.opts
        from controllers.force_to_valve import ForceToValve

        tu = model.tuning
        explicit = sorted(set(o) & set(self.tuning_options))
        placed = (model.placed_gains(float(o["bandwidth"]), self.dt) if "bandwidth" in o
                  else tu.pid_gains)
        self.gains = PIDGains(
            kp=float(o.get("kp", placed.kp)), ki=float(o.get("ki", placed.ki)),
            kd=float(o.get("kd", placed.kd)),
            derivative_cutoff=float(o.get("derivative_cutoff", placed.derivative_cutoff)),
            kt=float(o.get("kt", 20.0)),
        )
        self.valve = ForceToValve(model, float(o.get("force_bandwidth", tu.force_bandwidth)))
        lam = float(o.get("velocity_compensation", tu.velocity_compensation))
        if not (math.isfinite(lam) and VELOCITY_COMPENSATION[0] <= lam
                <= VELOCITY_COMPENSATION[1]):
            raise FcompError(f"{self.name}: velocity_compensation must be a number from "
                             f"{VELOCITY_COMPENSATION[0]:g} to {VELOCITY_COMPENSATION[1]:g}, "
                             f"got {lam}")
        #: ``lambda``: the inversion's velocity is ``lambda*v_hat + (1 - lambda)*dr``
        #: (:mod:`controllers.force_to_valve`).
        self.velocity_compensation = lam
        #: Margins of the loop as it runs at its worst point over the grid
        #: (:class:`controllers.loop_analysis.margins.LoopMargins`); explicit values are
        #: checked (refused without margins), the derived ones are the tuning's.
        self.margins = (model.checked_margins(self.family(), self.dt,
                                              f"{self.name} tuning ({', '.join(explicit)} given)")
                        if explicit else tu.margins)
        #: Largest closed-loop pole magnitude of the nominal loop at mid stroke (sliding):
        #: a tuning set unchecked (:meth:`~controllers.plant_model.ControlModel.use_tuning`,
        #: a comparison's former numbers) is still refused when that loop is unstable.
        mid = tu.mid.get("valve") if not explicit and tu.mid else None
        self.stability_radius = (mid or self.margins).radius
        if not self.stability_radius < 1.0:
            raise unstable(self.gains, self.stability_radius, self.dt)
        self.law = PIDLaw(self.gains, self.dt)
        #: Bounds of the integral (:func:`controllers.safety.integral_bounds`).
        self.integral_bounds = integral_bounds(self.gains.ki, model.force_min, model.force_max)
        self._bumpless = False
        self.F_demand = 0.0
        self._F_prev: float | None = None

    def family(self) -> Any:
        """The five numbers of the loop at rest (:class:`controllers.loop_analysis.pid_family.PIDFamilyGains`)."""
        from controllers.loop_analysis.pid_family import PIDFamilyGains

        g = self.gains
        return PIDFamilyGains(g.kp, g.ki, g.kd, g.derivative_cutoff, self.valve.bandwidth,
                              self.velocity_compensation)

    # hooks for the compensators ------------------------------------------------
    def reset_compensation(self, y0: np.ndarray, ref: Reference) -> None:
        """Reset the friction estimator (none for plain PID)."""

    def compensation(self, t: float, y: np.ndarray, ref: Reference, v: float) -> float:
        """Friction force estimate ``F_hat`` (N) to add to the demand (0 for plain PID)."""
        return 0.0

    def velocity_estimate(self, v_f: float) -> float:
        """Velocity (m/s) the force-to-valve inversion uses (the filtered one here)."""
        return v_f

    def friction_demand(self, F_hat: float) -> float:
        """The friction estimate as force demand: ``F_hat`` and, where :attr:`friction_lead`,
        its lead through the force loop, ``(F_hat - F_hat_prev)/(dt*w_F)`` (module
        docstring; no lead on the first sample after a reset)."""
        prev = F_hat if self._F_prev is None else self._F_prev
        self._F_prev = F_hat  # also marks the controller as stepped since its reset
        if not self.friction_lead:
            return F_hat
        return F_hat + (F_hat - prev) / (self.dt * self.valve.bandwidth)

    # contract ---------------------------------------------------------------------
    def reset(self, t0: float, y0: np.ndarray, ref: Reference) -> None:
        self.law.reset(float(y0[0]))
        self.valve.reset()
        self._bumpless = False
        self.friction_estimate = 0.0
        self._F_prev = None
        self.fallbacks = 0
        self.fallback_active = False
        self.reset_compensation(y0, ref)

    def healthy(self) -> bool:
        law = self.law
        return all(math.isfinite(v) for v in (law.integral, law.v_f, law.x_prev))

    def reenter(self, t: float, y: np.ndarray, ref: Reference, u: float) -> None:
        """Reset from ``y``; the next step sets the integral so that the force demand equals
        the measured actuator force (bumpless: :func:`controllers.safety.bumpless_integral`)."""
        super().reenter(t, y, ref, u)
        self._bumpless = True

    def step(self, t: float, y: np.ndarray, ref: Reference) -> float:
        x = float(y[0])
        e = ref.r - x
        v_f = self.law.velocity(x)
        F_hat = self.compensation(t, y, ref, v_f)
        self.friction_estimate = F_hat
        m = self.model
        g = self.gains
        F_dem = self.friction_demand(F_hat)
        if self._bumpless:
            other = (m.mass * ref.ddr + m.weight
                     + (g.kp * e + g.ki * self.law.dt * e + g.kd * (ref.dr - v_f)) + F_dem)
            self.law.integral = bumpless_integral(SCALAR, m.actuator_force(y), other, g.ki,
                                                  self.integral_bounds)
            self._bumpless = False
        demand = m.mass * ref.ddr + m.weight + self.law.force(e, ref.dr) + F_dem
        applied = min(max(demand, m.force_min), m.force_max)
        lam = self.velocity_compensation
        v_inv = lam * self.velocity_estimate(v_f) + (1.0 - lam) * ref.dr
        u, sat = self.valve.command(applied, y, v_inv)
        self.law.integrate(e, demand, applied, sat)
        self.law.integral = clamp_integral(SCALAR, self.law.integral, self.integral_bounds)
        self.F_demand = applied
        self.last_u = u
        return u
