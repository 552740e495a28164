"""Compare a model with measurements: force domain per regime, worst segments, plant domain.

Force domain
    The model is simulated along the measured motion and its force compared
    with the measured (or reconstructed, models.md 2) friction force:
    :func:`regime_errors` gives the RMS error (N) over the held-out samples of
    each regime of :mod:`.regimes`; :func:`worst_segments` finds the held-out
    windows where the model fails most; :func:`compare` does the whole thing
    for a model (fitted on the training samples first, by default).

Plant domain
    For plant data (a valve command ``u`` and the responses ``x``, ``p1``,
    ``p2``), :func:`compare_plant` simulates the plant (:mod:`plants`) with the
    measured input from the measured initial state and compares the simulated
    ``x``, ``p1``, ``p2`` with the measured ones (RMS errors in m and Pa).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fcomp.diagnosis.regimes import REGIMES, Segmentation
from fcomp.errors import FcompError
from fcomp.measurement import Measurement
from fcomp.models import FrictionModel


def regime_errors(residual: np.ndarray, seg: Segmentation, mask: np.ndarray
                  ) -> dict[str, dict[str, float | int | None]]:
    """Per regime and ``"all"``: RMS of ``residual`` (N) over ``mask`` and the sample count."""
    out: dict[str, dict[str, float | int | None]] = {}
    for i, name in enumerate(REGIMES):
        sel = mask & (seg.regime == i)
        n = int(sel.sum())
        out[name] = {"rms": float(np.sqrt(np.mean(residual[sel] ** 2))) if n else None, "n": n}
    n = int(mask.sum())
    out["all"] = {"rms": float(np.sqrt(np.mean(residual[mask] ** 2))) if n else None, "n": n}
    return out


@dataclass(frozen=True)
class Segment:
    """A window of samples ``[start, stop)`` and its RMS error (N)."""

    start: int
    stop: int
    rms: float


def worst_segments(residual: np.ndarray, mask: np.ndarray, width: int, count: int = 3,
                   boundaries: Sequence[int] = ()) -> list[Segment]:
    """The ``count`` non-overlapping windows of ``width`` samples with the largest RMS.

    Only windows lying entirely in ``mask`` (e.g. the held-out samples) and not
    crossing an experiment boundary are considered.
    """
    n = residual.size
    width = max(1, min(width, n))
    sq = np.where(mask, residual**2, 0.0)
    c = np.concatenate([[0.0], np.cumsum(sq)])
    cm = np.concatenate([[0], np.cumsum(mask.astype(int))])
    starts = np.arange(0, n - width + 1)
    full = (cm[starts + width] - cm[starts]) == width
    for b in boundaries:
        full &= ~((starts < b) & (starts + width > b))
    score = np.where(full, (c[starts + width] - c[starts]) / width, -1.0)
    out: list[Segment] = []
    taken = np.zeros(n, dtype=bool)
    for k in np.argsort(-score):
        if score[k] < 0 or len(out) >= count:
            break
        if taken[k:k + width].any():
            continue
        taken[k:k + width] = True
        out.append(Segment(int(k), int(k + width), float(math.sqrt(score[k]))))
    return out


@dataclass(frozen=True)
class Comparison:
    """A model compared with a record in the force domain (held-out errors, N)."""

    model: FrictionModel
    rms: float
    regimes: dict[str, dict[str, float | int | None]]
    worst: list[Segment]
    F_measured: np.ndarray
    F_model: np.ndarray
    split: str


def compare(model: str | FrictionModel, data: Measurement | Sequence[Measurement], *,
            fit: bool = True, split: str = "auto", cutoff_hz: float | None = None
            ) -> Comparison:
    """Compare ``model`` with ``data`` in the force domain, on held-out samples.

    With ``fit`` (default) the model is first fitted on the training samples
    (the baseline step of :class:`~fcomp.diagnosis.loop.Diagnosis`); without
    it the model's own parameter values are used as they are.
    """
    from fcomp.diagnosis.loop import Diagnosis

    diag = Diagnosis(model, search=False, split=split, cutoff_hz=cutoff_hz, n_jobs=1)
    if fit:
        diag.fit(data)
        res = diag.fit_
    else:
        diag.fit(data)
        mdl = diag.baseline_fit_.model if isinstance(model, str) else model
        res = diag._refit.result(mdl if isinstance(model, FrictionModel) else mdl, {}, 0)
    seg, sp = diag.segmentation_, diag.split_
    width = max(10, int(round(0.25 / diag.data_.scales.dt)))
    bounds = [e.start for e in diag.data_.experiments[1:]]
    return Comparison(res.model, res.rms_test, regime_errors(res.residual, seg, sp.test),
                      worst_segments(res.residual, sp.test, width, 3, bounds),
                      diag.data_.y, res.F_hat, sp.description)


def compare_plant(meas: Measurement, plant: str, friction: FrictionModel, *,
                  params: str | None = None) -> dict[str, Any]:
    """Simulate ``plant`` with the measured command ``u`` and compare ``x``, ``p1``, ``p2``.

    The plant starts from the measured ``x``, ``p1``, ``p2`` at the first
    sample (gauge pressures, converted to the plant's states with the offset
    between each state and the recorded output of the same name, e.g. the
    atmospheric pressure of a pneumatic plant's absolute chamber pressures)
    and is driven by ``u`` interpolated linearly between samples. Returns
    the simulated measurement and the RMS error of every compared signal
    (m, gauge Pa).
    """
    from plants import PLANTS

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
    errors = {}
    for k, col in measured.items():
        if k in sim:
            ys = np.interp(t - t[0], sim.t, sim.gauge_pressure(k) if k in ("p1", "p2")
                           else sim[k])
            errors[k] = float(np.sqrt(np.mean((ys - col) ** 2)))
    if not errors:
        raise FcompError(f"{meas.label}: no signal (x, p1, p2) to compare with plant {plant!r}")
    return {"simulated": sim, "rms": errors}
