"""The magnitudes of a record, the reference of every data-derived threshold
(:class:`Scales`)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Scales:
    """Magnitudes of a record, the reference of every data-derived threshold (SI).

    Attributes
    ----------
    force : N
        Typical friction magnitude: median ``|y|`` over moving samples.
    speed : m/s
        95th percentile of ``|v|``.
    accel : m/s^2
        95th percentile of ``|a|``.
    x_min, x_max : m
        1st and 99th percentiles of the position.
    resolution : m
        Position resolution: the smallest clearly non-zero step of ``x``.
    p_mid, p_span : Pa
        Mean and range (1st to 99th percentile) of ``p1 + p2``.
    dt : s
        Median sample interval.
    duration : s
        Total duration of all experiments.
    """

    force: float
    speed: float
    accel: float
    x_min: float
    x_max: float
    resolution: float
    p_mid: float
    p_span: float
    dt: float
    duration: float

    @property
    def stroke(self) -> float:
        """Position range covered (m), at least 100 resolutions."""
        return max(self.x_max - self.x_min, 100.0 * self.resolution)

