"""Signal conditioning: the velocity that drives the friction states, rest, and the force band.

A friction model is simulated along the *measured* motion, so whatever is
wrong with the motion signals goes straight into its states. Real rigs record
the motion in several ways -- an encoder position ``x`` (quantised), a
tachometer or a drive's differentiated encoder velocity ``v`` (noisy, with a
bias, a gain error and a lag), sometimes no position at all -- and the force
as a load-cell friction ``F``, or as chamber pressures from which the friction
is reconstructed, ``p1*A1 - p2*A2 + F_ext - m*a``. The same physical record
written in any of these styles must drive the model with the same motion.
This module decides, per record and visibly (:class:`Conditioning`, the
``signals`` field of ``fcomp diagnose --json``):

**Which velocity.** ``dx/dt`` is the zero-phase low-pass derivative of the
position at the cut-off :func:`default_cutoff` (set by the position noise).
A ``v`` column is first *calibrated* against it (:func:`calibrate_velocity`):
its bias is its median at rest (rest read off the position, where the true
velocity is zero), its noise the robust spread there, its lag and gain the
shift and slope that best map it onto ``dx/dt`` while moving. Then

* ``"x"`` -- ``dx/dt`` alone, when there is no ``v`` column, when the column
  disagrees with the position (gain off by more than :data:`GAIN_TOL`, or it
  explains less than :data:`MIN_R2` of ``dx/dt``'s variance while moving), or
  when it is noisier than ``dx/dt`` over the whole band used;
* ``"fused"`` -- a complementary filter: ``dx/dt`` below the cross-over
  frequency ``f* = sigma_v/(2*pi*sigma_x)`` where the two noise densities
  are equal (white position noise ``sigma_x`` differentiated rises as ``f``;
  the column's white noise ``sigma_v`` is flat), the calibrated
  column (bias removed, lag and gain corrected) above it;
* ``"v"`` -- the calibrated column, when the record has no position. Its bias
  is then its median over quiet stretches (:func:`velocity_rest`).

A measured velocity is never trusted at rest: a tachometer's noise of
1e-4 m/s drives a bristle state through every dwell (LuGre's held force creeps
by newtons), and a bias drives it to one side. **Rest** is read off the
position where there is one (it stays within six position-noise standard
deviations, one encoder step, for 8 ms or more: :func:`position_rest`), else off the
calibrated velocity (quiet for at least :data:`MIN_QUIET` s); velocity and
acceleration are held at zero there.

**The force band.** A friction reconstructed from pressures subtracts
``m*a``, and ``a`` is a second derivative of a quantised position: its noise
grows as ``fc^2.5``. Where the target is reconstructed (or the mass is fitted
to the driving force) the whole driving force and the model's prediction are
passed through the same zero-phase low-pass ("parallel filtering", Gautier &
Janot), at the highest cut-off at which the inertia noise ``m*sigma_a`` stays
below :data:`INERTIA_NOISE_SHARE` of the force noise in that band
(:func:`force_cutoff`). Target and prediction then have the same bandwidth,
so the residual is the model error in that band and the noise floor,
estimated from the same filtered force at rest, is its noise.
"""


from __future__ import annotations

from fcomp.conditioning.ensemble import (
    ENSEMBLE,
    TURN_BANDS,
    count_timing,
    motion_ensemble,
    through_turns,
)
from fcomp.conditioning.force_band import (
    INERTIA_NOISE_SHARE,
    force_cutoff,
    rest_noise,
)
from fcomp.conditioning.motion import (
    Conditioning,
    Motion,
    condition_motion,
)
from fcomp.conditioning.position import (
    CUTOFF_FRACTIONS,
    MIN_REST,
    REST_HALF_WINDOW,
    REST_NOISE_BAND,
    analog_noise,
    band,
    bristle_stiffness,
    default_cutoff,
    derived_acceleration_noise,
    derived_velocity_noise,
    position_noise,
    position_rest,
    quiet_runs,
    resolution,
    sample_rate,
    speed_scale,
)
from fcomp.conditioning.scales import (
    Scales,
)
from fcomp.conditioning.velocity import (
    GAIN_TOL,
    MAX_LAG,
    MIN_QUIET,
    MIN_R2,
    REST_EDGE,
    VELOCITY_SOURCES,
    VelocityCalibration,
    calibrate_velocity,
    velocity_rest,
)

__all__ = [
    "CUTOFF_FRACTIONS",
    "Conditioning",
    "ENSEMBLE",
    "GAIN_TOL",
    "INERTIA_NOISE_SHARE",
    "MAX_LAG",
    "MIN_QUIET",
    "MIN_R2",
    "MIN_REST",
    "Motion",
    "REST_EDGE",
    "REST_HALF_WINDOW",
    "REST_NOISE_BAND",
    "Scales",
    "TURN_BANDS",
    "VELOCITY_SOURCES",
    "VelocityCalibration",
    "analog_noise",
    "band",
    "bristle_stiffness",
    "calibrate_velocity",
    "condition_motion",
    "count_timing",
    "default_cutoff",
    "derived_acceleration_noise",
    "derived_velocity_noise",
    "force_cutoff",
    "motion_ensemble",
    "position_noise",
    "position_rest",
    "quiet_runs",
    "resolution",
    "rest_noise",
    "sample_rate",
    "speed_scale",
    "through_turns",
    "velocity_rest",
]
