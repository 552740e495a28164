"""The ranges a friction model was fitted on, and the check of a use against them.

A fitted model is a description of the record it was fitted to: its laws were seen
at the record's positions, speeds and chamber pressures, nowhere else. Used far
outside them -- a ``position-dependence`` fitted on a 40 mm stroke run on a hydraulic
axis at 150 mm, a ``pressure-dependence`` fitted at 2-7 bar on a 65 bar supply -- its
force is an extrapolation, and for a polynomial law a meaningless one (the Legendre
polynomials of ``position-dependence`` grow without bound outside the stroke they are
written over: a factor of 140-434 at 150 mm on the README's chain).

A model carries the ranges of its record (:attr:`~fcomp.models.base.FrictionModel.fitted_range`,
set by a fit and a diagnosis, written into the model file as ``"fitted_range"``):

========= ==== =====================================================================
key       unit range
========= ==== =====================================================================
``x``     m    position, in the record's coordinates
``v``     m/s  speed (signed: the lowest and highest velocity)
``p``     Pa   chamber pressures ``p1`` and ``p2`` together, gauge (as the model reads
               them); absent when the record had none
========= ==== =====================================================================

:func:`check_range` compares a use with them -- ``x``, ``v``, ``p`` each as the values
the use will meet (an array, or a ``(low, high)`` pair); only the signals the model
reads are checked (``v`` always, ``x`` when an effect needs the position, ``p`` when one
needs the pressures). It returns one warning line per signal beyond its fitted range
(by more than :data:`MARGIN` of the range's width, at least the signal's
:data:`SIGNALS` tolerance) and raises :class:`OutOfRangeError` where the result would
be meaningless: the ``position-dependence`` law evaluated where its scale factor is more
than :data:`BLOW_UP` times the largest (or less than ``1/BLOW_UP`` times the smallest)
it takes over the stroke it was written for. The commands call it on what they will
run (``simulate``, ``compare``, ``sweep``, ``compensate``, ``export``); it is
``fcomp.modelfile.check_range`` as well.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from fcomp.errors import FcompError
from fcomp.parameters import finite_number

if TYPE_CHECKING:
    from fcomp.models.base import FrictionModel

#: Signal -> (SI unit, what it is, display factor, display unit, least tolerance in SI).
SIGNALS: dict[str, tuple[str, str, float, str, float]] = {
    "x": ("m", "positions", 1e3, "mm", 1e-3),
    "v": ("m/s", "speeds", 1e3, "mm/s", 1e-3),
    "p": ("Pa", "chamber pressures (gauge)", 1e-5, "bar", 2e4),
}
#: A use may pass the fitted range by this fraction of its width before a warning.
MARGIN = 0.1
#: Scale factor of a position law beyond which its result is refused (times the extreme
#: it takes over the stroke it was written for).
BLOW_UP = 2.0


class OutOfRangeError(FcompError):
    """A model used where its result is meaningless (a position polynomial far outside the
    stroke it was fitted on)."""


def checked_ranges(ranges: Mapping[str, Any], where: str = "fitted_range"
                   ) -> dict[str, tuple[float, float]]:
    """``ranges`` as ``{signal: (low, high)}``: each key one of :data:`SIGNALS`, each value
    two finite numbers, low not above high. Raises ``ValueError`` naming ``where``."""
    if not isinstance(ranges, Mapping):
        raise ValueError(f"{where} must be an object like {{\"x\": [low, high], ...}}")
    out: dict[str, tuple[float, float]] = {}
    for key, value in ranges.items():
        if key not in SIGNALS:
            raise ValueError(f"{where} has an unknown key {key!r} (known: {', '.join(SIGNALS)})")
        pair = _pair(value)
        if pair is None:
            raise ValueError(f"{where}.{key} must be two finite numbers [low, high] in "
                             f"{SIGNALS[key][0]}")
        if pair[0] > pair[1]:
            raise ValueError(f"{where}.{key} = [{pair[0]:g}, {pair[1]:g}]: low is above high")
        out[key] = pair
    return out


def _pair(value: Any) -> tuple[float, float] | None:
    if not isinstance(value, list | tuple) or len(value) != 2:
        return None
    low, high = finite_number(value[0]), finite_number(value[1])
    return None if low is None or high is None else (low, high)


def span(values: Any) -> tuple[float, float] | None:
    """The lowest and highest finite value of ``values`` (an array, or a ``(low, high)``
    pair); ``None`` when there is none."""
    if values is None:
        return None
    arr = np.asarray(values, dtype=float).ravel()
    arr = arr[np.isfinite(arr)]
    if arr.size == 0:
        return None
    return float(arr.min()), float(arr.max())


def signal_ranges(signals: Iterable[Mapping[str, Any]],
                  available: Mapping[str, bool] | None = None
                  ) -> dict[str, tuple[float, float]]:
    """The ranges of records' prepared signals (``x``, ``v``, ``p1``, ``p2``: a fit's
    :attr:`~fcomp.identification.target.FitData.sig`), over all of them. The pressures
    count only where measured: ``available["p1"]``/``["p2"]`` when given, else where they
    are not all zero (a record without pressures reads zero)."""
    found: dict[str, list[tuple[float, float]]] = {"x": [], "v": [], "p": []}
    for sig in signals:
        for key in ("x", "v"):
            s = span(sig.get(key))
            if s is not None:
                found[key].append(s)
        for key in ("p1", "p2"):
            values = sig.get(key)
            if values is None:
                continue
            measured = (available.get(key, False) if available is not None
                        else bool(np.any(np.asarray(values, dtype=float) != 0.0)))
            s = span(values) if measured else None
            if s is not None:
                found["p"].append(s)
    return {k: (min(a for a, _ in v), max(b for _, b in v)) for k, v in found.items() if v}


def _reads(model: FrictionModel) -> set[str]:
    """The signals of :data:`SIGNALS` the model's force depends on."""
    out = {"v"}
    for e in model.effects:
        needs = set(getattr(e, "needs", ()))
        if "x" in needs:
            out.add("x")
        if needs & {"p1", "p2"}:
            out.add("p")
    return out


def _shown(key: str, pair: tuple[float, float]) -> str:
    _unit, _what, factor, unit, _tol = SIGNALS[key]
    return f"{pair[0] * factor:.4g} to {pair[1] * factor:.4g} {unit}"


def check_range(model: FrictionModel, *, x: Any = None, v: Any = None, p: Any = None,
                label: str | None = None) -> list[str]:
    """Check a use of ``model`` against the ranges it was fitted on (module docstring).

    Parameters
    ----------
    model : FrictionModel
        The model (its :attr:`~fcomp.models.base.FrictionModel.fitted_range` and effects).
    x, v, p : array_like or (low, high), optional
        The positions (m), velocities (m/s) and gauge chamber pressures (Pa) the use
        meets; ``None``: not known, not checked.
    label : str, optional
        How to name the model in the lines (default its description).

    Returns
    -------
    list of str
        One warning line naming every signal used beyond its fitted range (empty: all
        within).

    Raises
    ------
    OutOfRangeError
        A ``position-dependence`` law evaluated where it is meaningless.
    """
    name = label or model.describe()
    used = {"x": span(x), "v": span(v), "p": span(p)}
    _check_position_law(model, used["x"], name)
    fitted = model.fitted_range
    reads = _reads(model)
    beyond = []
    for key in ("x", "v", "p"):
        have, want = fitted.get(key), used[key]
        if key not in reads or have is None or want is None:
            continue
        tol = max(MARGIN * (have[1] - have[0]), SIGNALS[key][4])
        if want[0] >= have[0] - tol and want[1] <= have[1] + tol:
            continue
        beyond.append((f"{SIGNALS[key][1]} {_shown(key, have)}",
                       f"{SIGNALS[key][1].split(' (')[0]} {_shown(key, want)}"))
    if not beyond:
        return []
    return [f"{name} was fitted on {'; '.join(h for h, _ in beyond)}, and this use reaches "
            f"{'; '.join(w for _, w in beyond)}: its friction there is an extrapolation, not "
            "a measurement (fit it on a record that covers them)"]


def _check_position_law(model: FrictionModel, used: tuple[float, float] | None,
                        name: str) -> None:
    """Refuse a ``position-dependence`` law evaluated where its scale factor has left
    everything it takes over its own stroke by more than :data:`BLOW_UP`."""
    if used is None:
        return
    for e in model.effects:
        ends = getattr(e, "x_range", None)
        if e.name != "position-dependence" or ends is None:
            continue
        x_min, x_max = ends
        if used[0] >= x_min and used[1] <= x_max:
            continue
        inside = _position_scale(e, np.linspace(x_min, x_max, 401))
        xs = np.linspace(min(used[0], x_min), max(used[1], x_max), 2001)
        outside = xs[(xs < x_min) | (xs > x_max)]
        scale = _position_scale(e, outside)
        high, low = float(inside.max()), float(inside.min())
        worst = int(np.argmax(np.maximum(scale / high, low / np.maximum(scale, 1e-300))))
        ratio = max(scale[worst] / high, low / max(scale[worst], 1e-300))
        if ratio > BLOW_UP:
            raise OutOfRangeError(
                f"{name}: its position-dependence law is a polynomial written over x = "
                f"{x_min * 1e3:.4g} to {x_max * 1e3:.4g} mm; at x = {outside[worst] * 1e3:.4g} mm "
                f"it scales the friction by {scale[worst]:.3g} (between {low:.3g} and "
                f"{high:.3g} on that stroke): meaningless there. Use the model on the positions "
                "it was fitted on, or without position-dependence")


def _position_scale(effect: Any, x: np.ndarray) -> np.ndarray:
    """The smooth part of ``position-dependence``'s scale factor at positions ``x``
    (``1 + kx1*P1 + kx2*P2 + kx3*P3`` of ``xi``, floored at 1 %, as the law does)."""
    from fcomp.effects.base import LEVEL_FLOOR

    flat = effect.params.flat()
    x_min, x_max = effect.x_range
    xi = 2.0 * (np.asarray(x, dtype=float) - x_min) / (x_max - x_min) - 1.0
    p2 = 0.5 * (3.0 * xi * xi - 1.0)
    p3 = 0.5 * (5.0 * xi**3 - 3.0 * xi)
    scale = 1.0 + flat["kx1"] * xi + flat["kx2"] * p2 + flat["kx3"] * p3
    return np.maximum(scale, LEVEL_FLOOR)


def as_document(ranges: Mapping[str, Sequence[float]]) -> dict[str, list[float]]:
    """``ranges`` as a model file's ``"fitted_range"`` (lists of two floats)."""
    return {k: [float(ranges[k][0]), float(ranges[k][1])] for k in SIGNALS if k in ranges}


__all__ = ["BLOW_UP", "MARGIN", "SIGNALS", "OutOfRangeError", "as_document", "check_range",
           "checked_ranges", "signal_ranges", "span"]
