"""The ``motion`` plant: friction along a prescribed piston motion.

Input ``u`` is the piston velocity (m/s) as a function of time; the output is
a measurement with ``t`` (s), ``x`` (m, from 0), ``v`` (m/s), ``a`` (m/s^2,
the analytic-free central difference of ``v`` on the output grid) and the
friction force ``F`` (N). No mass, no pressures: it is the friction model
alone, evaluated with :func:`fcomp.trajectory.friction_along_motion`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from fcomp.errors import FcompError
from fcomp.measurement import Measurement
from fcomp.trajectory import friction_along_motion
from fcomp.version import __version__
from plants.base import InputFn, Plant, output_times


class MotionPlant(Plant):
    """Prescribed velocity in, friction force out (see the module docstring)."""

    name = "motion"
    input_names = ("v",)
    input_units = ("m/s",)

    def simulate(
        self, u: InputFn, duration: float, rate: float, *, x0: Any = None, **options: Any
    ) -> Measurement:
        unknown = set(options) - {"substeps"}
        if unknown:
            raise FcompError(f"plant {self.name}: unknown option(s) {', '.join(sorted(unknown))}")
        t = output_times(duration, rate)
        v = np.asarray(u(t), dtype=float) + 0.0 * t
        state0 = self.initial_state(x0) if isinstance(x0, Mapping) else x0
        run = friction_along_motion(self.friction, t, v, state0=state0,
                                    substeps=int(options.get("substeps", 1)))
        meta: dict[str, Any] = {
            "name": f"motion-{self.friction.name}",
            "kind": "friction-rig",
            "pressure": "gauge",
            "simulation": {
                "plant": self.name,
                "friction": self.friction.describe(),
                "params": self.paramset.name if self.paramset else "defaults",
                "duration": float(duration),
                "rate": float(rate),
                "fcomp_version": __version__,
            },
        }
        if self.paramset is not None:
            rig = {k: v for k, v in self.paramset.rig.items()
                   if k in ("bore", "rod", "stroke", "mass", "orientation")}
            if rig:
                meta["rig"] = rig
        return Measurement({"t": run.t, "x": run.x, "v": run.v, "a": run.a, "F": run.F}, meta)
