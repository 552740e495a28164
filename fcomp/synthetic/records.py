"""A synthetic record: the measurement, and apart from it the truth that made it."""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from fcomp.measurement import Measurement
from fcomp.synthetic.scales import Sensors, TruthParams


@dataclass(frozen=True)
class SyntheticTruth:
    """What the measurement hides: the clean friction and the laws that made it.

    Attributes
    ----------
    F : (N,) N
        Recorded force without noise (friction plus recording errors): what the
        tool should reconstruct, whatever the style.
    friction : (N,) N
        The friction force alone.
    v, a : (N,) m/s, m/s^2
        Exact velocity and acceleration at the samples.
    noise : (N,) N
        The noise the force channel adds to ``F`` (for the ``pressures`` styles the
        pressure noise in force units, ``n1*A1 - n2*A2``).
    base : str
        The base friction law.
    hidden : dict
        Hidden effect name -> its law parameters (at the record's scale, after ``vary``).
    params : TruthParams
        Base parameters (after ``vary``).
    noise_std : N
        Standard deviation of the force-channel noise (the true noise floor).
    shapes : dict
        Hidden effect name -> its shape.
    scale, style : str
        Rig scale and measurement style.
    rate : Hz
        Sample rate.
    sensors : Sensors or None
        Sensor characteristics used.
    nuisance : dict
        Values drawn by ``vary`` (empty without it).
    orientation : str
        How the cylinder is mounted (``horizontal``, ``vertical-up``, ``vertical-down``).
    motion : str
        The motion plan (``standard``, ``presliding``).
    """

    F: np.ndarray
    friction: np.ndarray
    v: np.ndarray
    a: np.ndarray
    noise: np.ndarray
    base: str
    hidden: dict[str, dict[str, float]]
    params: TruthParams
    noise_std: float
    shapes: dict[str, str] = field(default_factory=dict)
    scale: str = "pneumatic"
    style: str = "load-cell"
    rate: float = 500.0
    sensors: Sensors | None = None
    nuisance: dict[str, float] = field(default_factory=dict)
    orientation: str = "horizontal"
    motion: str = "standard"

    @property
    def effects(self) -> list[str]:
        """The hidden effects as ``"effect:shape"``."""
        return [f"{e}:{self.shapes.get(e, '')}".rstrip(":") for e in self.hidden]

    def describe(self) -> dict[str, Any]:
        """A flat summary for benchmark tables.

        Keys: ``scale``, ``style``, ``base``, ``rate``, ``noise_std``, ``hidden`` (the
        ``effect:shape`` list joined by ``", "``), ``orientation``, ``motion``,
        ``law.EFFECT.PARAM`` for every law parameter, ``base.NAME`` for the base
        parameters, ``sensors.NAME`` (numbers, and ``sensors.noise_color``), and every
        value drawn by ``vary`` under its own key.
        """
        out: dict[str, Any] = {
            "scale": self.scale, "style": self.style, "base": self.base,
            "orientation": self.orientation, "motion": self.motion,
            "rate": float(self.rate), "noise_std": float(self.noise_std),
            "hidden": ", ".join(self.effects) or "-",
        }
        for effect, law in self.hidden.items():
            out.update({f"law.{effect}.{k}": float(v) for k, v in law.items()})
        out.update({f"base.{f.name}": float(getattr(self.params, f.name))
                    for f in fields(self.params)})
        if self.sensors is not None:
            out.update({f"sensors.{f.name}": (value if isinstance(value, str) else float(value))
                        for f in fields(self.sensors)
                        for value in [getattr(self.sensors, f.name)]})
        out.update(self.nuisance)
        return out


@dataclass(frozen=True)
class SyntheticRecord:
    """A synthetic measurement and, separately, its truth."""

    measurement: Measurement
    truth: SyntheticTruth

    def __repr__(self) -> str:  # a summary, never the arrays
        hidden = ", ".join(self.truth.hidden) or "nothing"
        return (f"<SyntheticRecord {self.measurement.label!r}: {len(self.measurement)} "
                f"samples, base {self.truth.base}, hidden {hidden}, noise "
                f"{self.truth.noise_std:.3g} N>")

    def experiments(self) -> list[Measurement]:
        """The measurement split into one :class:`Measurement` per experiment."""
        ids = self.measurement["experiment"]
        out = []
        for e in np.unique(ids):
            sub = self.measurement.select(ids == e)
            sub.meta["name"] = f"{self.measurement.label}-exp{int(e)}"
            out.append(sub)
        return out
