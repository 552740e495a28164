"""A plant beside a record in the plant domain: ``x``, ``p1``, ``p2`` simulated from ``u``.

For plant data (a valve command ``u`` and the responses ``x``, ``p1``,
``p2``), :func:`compare_plant` simulates a plant of :data:`plants.PLANTS` with
the measured input from the measured initial state and compares the simulated
``x``, ``p1``, ``p2`` with the measured ones (RMS errors in m and gauge Pa), as
a :class:`PlantComparison` with its own :meth:`PlantComparison.plot`.
``fcomp.compare(model, records, plant=NAME)`` attaches one per record to the
force-domain :class:`fcomp.diagnosis.Comparison`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from fcomp.errors import FcompError
from fcomp.figures import fig_plant
from fcomp.measurement import Measurement
from fcomp.models import FrictionModel
from fcomp.paramsets import ParameterSet
from fcomp.registry import PLANTS


@dataclass(frozen=True, repr=False)
class PlantComparison:
    """A plant simulated with a record's command beside the record (:func:`compare_plant`).

    Attributes
    ----------
    label, plant
        The record and the plant name.
    simulated
        The simulated run (a :class:`Measurement`).
    measured
        The compared signals as recorded (gauge pressures), on the record's time ``t``.
    predicted
        The same signals simulated, interpolated onto ``t``.
    t
        The record's time (s).
    rms
        RMS error of every compared signal (m, Pa).
    """

    label: str
    plant: str
    simulated: Measurement
    measured: dict[str, np.ndarray]
    predicted: dict[str, np.ndarray]
    t: np.ndarray
    rms: dict[str, float]

    def __getitem__(self, key: str) -> Any:
        """``result["rms"]``, ``result["simulated"]`` (the dictionary it once was)."""
        if key not in ("simulated", "rms", "measured", "predicted", "t", "plant", "label"):
            raise KeyError(key)
        return getattr(self, key)

    def plot(self) -> Figure:
        """Measured and simulated ``x``, ``p1``, ``p2`` over time, and their differences."""
        return fig_plant(self)

    def to_dict(self) -> dict[str, Any]:
        return {"label": self.label, "plant": self.plant, "rms": dict(self.rms)}

    def __repr__(self) -> str:
        errs = ", ".join(f"{k} {v:.3g} {'m' if k == 'x' else 'Pa'}" for k, v in self.rms.items())
        return f"<PlantComparison {self.plant} on {self.label}: RMS {errs}>"


def compare_plant(meas: Measurement, plant: str, friction: FrictionModel, *,
                  params: str | ParameterSet | None = None) -> PlantComparison:
    """Simulate ``plant`` with the measured command ``u`` and compare ``x``, ``p1``, ``p2``.

    The plant starts from the measured ``x``, ``p1``, ``p2`` at the first
    sample (gauge pressures, converted to the plant's states with the offset
    between each state and the recorded output of the same name, e.g. the
    atmospheric pressure of a pneumatic plant's absolute chamber pressures)
    and is driven by ``u`` interpolated linearly between samples. Returns
    the simulated measurement and the RMS error of every compared signal
    (m, gauge Pa) as a :class:`PlantComparison`. ``params``: a parameter set's name
    or object (a plant file's, :meth:`plants.planfile.PlantFile.parameter_set`).
    """
    if "u" not in meas:
        raise FcompError(f"{meas.label}: a plant-domain comparison needs the command column 'u'")
    cls = PLANTS.get(plant)
    p = cls(friction, params if params is not None else getattr(cls, "default_params", None))
    t, u = meas.t, meas["u"]

    def u_of(tt: Any) -> Any:
        return np.interp(tt, t - t[0], u)

    names = p.state_names
    measured = {k: (meas.gauge_pressure(k) if k in ("p1", "p2") else meas[k])
                for k in ("x", "p1", "p2") if k in meas}
    # the plant's states may be absolute pressures while its recorded outputs are gauge:
    # the offset between a state and the output of the same name maps one onto the other
    default = p.initial_state()
    outputs = getattr(p, "evaluate_outputs", None)  # ODE plants; others record their states
    y0 = outputs(default[None, :], np.array([[float(u[0])]])) if outputs is not None else {}
    x0: dict[str, float] = {}
    for k, col in measured.items():
        if k in names:
            offset = float(default[names.index(k)] - y0[k][0]) if k in y0 else 0.0
            x0[k] = float(col[0]) + offset
    rate = (t.size - 1) / float(t[-1] - t[0])
    sim = p.simulate(u_of, float(t[-1] - t[0]), rate, x0=p.initial_state(x0))
    errors, predicted = {}, {}
    for k, col in measured.items():
        if k in sim:
            ys = np.interp(t - t[0], sim.t, sim.gauge_pressure(k) if k in ("p1", "p2")
                           else sim[k])
            predicted[k] = ys
            errors[k] = float(np.sqrt(np.mean((ys - col) ** 2)))
    if not errors:
        raise FcompError(f"{meas.label}: no signal (x, p1, p2) to compare with plant {plant!r}")
    return PlantComparison(meas.label, plant, sim, {k: measured[k] for k in predicted},
                           predicted, t, errors)
