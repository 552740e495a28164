"""The ``position-dependence`` effect: friction levels varying along the stroke.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`PositionDependence`; its docstring is the physics).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from fcomp.backend import Backend
from fcomp.effects.base import Effect, scale_levels
from fcomp.effects.record import RecordView
from fcomp.parameters import ParamValues, make_params_class, spec

if TYPE_CHECKING:
    from fcomp.conditioning import Scales
    from fcomp.models.base import Signals


#: The shortest stretch of the bore over which seal friction can change (m): a seal's
#: contact band is a millimetre or more and averages the bore over its width, so a
#: local box is at least this wide (``wb >= SEAL_BAND/2``) and its edges at least a
#: fifth of it (``eb``). A narrower box would not be a property of the bore but of
#: the samples at one position -- a rest point, where break-aways happen.
SEAL_BAND = 1e-3

#: The stroke's ends of the configuration by default (m).
X_MIN, X_MAX = 0.0, 0.3

PositionDependenceParams = make_params_class("PositionDependenceParams", [
    spec("kx1", "-", 0.0, -1.0, 1.0, "linear Legendre coefficient", directional=False),
    spec("kx2", "-", 0.0, -1.0, 1.0, "quadratic Legendre coefficient", directional=False),
    spec("kx3", "-", 0.0, -1.0, 1.0, "cubic Legendre coefficient", directional=False),
    spec("kb", "-", 0.0, -1.0, 3.0, "relative level change inside the local box (0: none)",
         directional=False),
    spec("xb", "m", 0.15, -math.inf, math.inf, "centre of the local box", directional=False),
    spec("wb", "m", 0.01, 0.5 * SEAL_BAND, math.inf, "half-width of the local box (at least "
         "half a seal's contact band)", directional=False),
    spec("eb", "m", 0.002, 0.2 * SEAL_BAND, math.inf, "edge width of the local box (at least a "
         "fifth of a seal's contact band)", directional=False),
], owner="effect position-dependence")


class PositionDependence(Effect):
    """Position dependence: levels scaled by a function of the stroke position ``x``.

    Bore tolerance, wear, rod bending and seal squeeze vary along the stroke,
    so friction does too (seed 001 measured break-away at 12 positions); a
    scored or worn stretch of the bore, or a tight spot, changes it over a
    short stretch only. The scale is

    ``1 + kx1*P1(xi) + kx2*P2(xi) + kx3*P3(xi) + kb*box(x)``

    with Legendre polynomials of ``xi = 2*(x - x_min)/(x_max - x_min) - 1``
    (``x_min``, ``x_max`` are configuration, default 0..0.3 m) for the smooth
    variation along the stroke, and a soft box for a local one,
    ``box(x) = (tanh((x - xb + wb)/eb) - tanh((x - xb - wb)/eb))/2``: centre
    ``xb``, half-width ``wb``, edge width ``eb`` (a narrow box with soft edges
    is a bump, a wide one reaching past the end of the stroke a step; the box is
    never narrower than a seal's contact band, :data:`SEAL_BAND`). A model
    without it leaves a residual that is a function of ``x``, repeated on every
    stroke, of the friction's sign. The scale is floored at 1 %
    (:data:`~fcomp.effects.base.LEVEL_FLOOR`).
    """

    name = "position-dependence"
    Params = PositionDependenceParams
    CONFIG = ("x_min", "x_max")
    factors = ("position",)
    needs = ("x",)
    signature = "residual a function of x, repeated stroke after stroke (smooth or local)"
    experiment = "the same slow stroke repeated, break-away measured along the stroke"
    experiments = {
        "electromechanical-axis": "the same slow travel over the whole axis repeated, "
                                  "break-away measured along it (screw and guides)",
    }

    def __init__(self, params: Any = None, **config: Any) -> None:
        super().__init__(params, **config)
        ends = []
        for key, default in (("x_min", X_MIN), ("x_max", X_MAX)):
            value = self.config.get(key, default)
            try:
                number = float(value)
            except (TypeError, ValueError, OverflowError):
                number = math.nan
            if isinstance(value, bool) or not math.isfinite(number):
                raise ValueError(f"effect {self.name}: {key} = {value!r} is not a finite "
                                 "position in m")
            ends.append(number)
        if not ends[0] < ends[1]:
            raise ValueError(f"effect {self.name}: x_min = {ends[0]:g} m must be below x_max "
                             f"= {ends[1]:g} m (the stroke's ends the law is written over)")

    @property
    def x_range(self) -> tuple[float, float]:
        """The stroke's ends ``(x_min, x_max)`` (m) the Legendre polynomials are written
        over; outside them the polynomials grow without bound."""
        return (float(self.config.get("x_min", X_MIN)), float(self.config.get("x_max", X_MAX)))

    def modify_levels(self, be: Backend, L: dict, w: list[Any], sig: Signals,
                      P: ParamValues) -> dict:
        x_min, x_max = self.x_range
        xi = 2.0 * (sig.x - x_min) / (x_max - x_min) - 1.0
        p2 = 0.5 * (3.0 * xi * xi - 1.0)
        p3 = 0.5 * (5.0 * xi * xi * xi - 3.0 * xi)
        xb, wb, eb = P("xb"), P("wb"), P("eb")
        box = 0.5 * (be.tanh((sig.x - xb + wb) / eb) - be.tanh((sig.x - xb - wb) / eb))
        return scale_levels(L, 1.0 + P("kx1") * xi + P("kx2") * p2 + P("kx3") * p3
                            + P("kb") * box, be=be)

    @classmethod
    def diagnosis_config(cls, scales: Scales) -> dict[str, Any]:
        """The stroke's ends: the record's position range, padded by 2 % of the stroke."""
        pad = 0.02 * scales.stroke
        return {"x_min": scales.x_min - pad, "x_max": scales.x_max + pad}

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """Legendre coefficients by least squares, and a local box where the rest peaks.

        The sign-corrected training residual of the moving samples is regressed on
        ``|F_hat|*P_k(xi)`` (the smooth part); what remains, relative to
        ``|F_hat|``, is averaged in bins of 0.5 % of the stroke and its largest
        excursion (three bins smoothed) gives the box: centre, half-width (where it
        stays above half the peak), amplitude. Starts: the smooth part alone, the
        smooth part with the box, the box alone, and a step (:func:`_step_start`).
        """
        m = view.moving
        cfg = self.diagnosis_config(view.scales)
        x = view.signal("x")
        xi = 2.0 * (x - cfg["x_min"]) / (cfg["x_max"] - cfg["x_min"]) - 1.0
        F = np.abs(view.F_hat)
        cols = np.column_stack([F * xi, F * 0.5 * (3 * xi**2 - 1),
                                F * 0.5 * (5 * xi**3 - 3 * xi)])
        rs = np.sign(view.signal("v")) * view.residual
        coef, *_ = np.linalg.lstsq(cols[m], rs[m], rcond=None)
        coef = np.clip(coef, -0.9, 0.9)
        smooth_part = {"kx1": float(coef[0]), "kx2": float(coef[1]), "kx3": float(coef[2]),
                       "kb": 0.0}
        sc = view.scales
        level = np.maximum(F[m], 1e-3 * sc.force)
        rel = (rs - cols @ coef)[m] / level
        width = max(0.005 * sc.stroke, 2.0 * sc.resolution)
        edges = np.arange(sc.x_min, sc.x_max + width, width)
        k = np.clip(np.digitize(x[m], edges) - 1, 0, max(edges.size - 2, 0))
        count = np.bincount(k, minlength=edges.size - 1)
        if edges.size < 4 or (count >= 5).sum() < 4:
            return [smooth_part]
        mean = np.where(count >= 5, np.bincount(k, rel, minlength=edges.size - 1)
                        / np.maximum(count, 1), 0.0)
        sm = np.convolve(mean, np.ones(3) / 3.0, mode="same")
        j = int(np.argmax(np.abs(sm)))
        peak = float(sm[j])
        lo = hi = j
        while (lo > 0 and abs(sm[lo - 1]) > 0.5 * abs(peak)
               and np.sign(sm[lo - 1]) == np.sign(peak)):
            lo -= 1
        while (hi < sm.size - 1 and abs(sm[hi + 1]) > 0.5 * abs(peak)
               and np.sign(sm[hi + 1]) == np.sign(peak)):
            hi += 1
        eb = float(max(0.25 * width, sc.resolution, 0.2 * SEAL_BAND))
        box = {"kb": float(np.clip(peak, -0.9, 2.9)),
               "xb": float(0.5 * (edges[lo] + edges[hi + 1])),
               "wb": float(max(0.5 * (edges[hi + 1] - edges[lo]), 0.5 * SEAL_BAND)),
               "eb": eb}
        none = {"kx1": 0.0, "kx2": 0.0, "kx3": 0.0}
        step = _step_start(rs[m] / level, k, count, edges)
        return [smooth_part, {**smooth_part, **box}, {**none, **box}, {**none, **step, "eb": eb}]


def _step_start(rel: np.ndarray, k: np.ndarray, count: np.ndarray, edges: np.ndarray
                ) -> dict[str, float]:
    """A step along the stroke (a worn or scored zone from ``x_s`` to the end): the box
    of :class:`PositionDependence` reaching past the far end of the stroke, from the
    split that best separates two levels of the relative residual ``rel`` (binned by
    ``k``), without the smooth part -- the Legendre cubic absorbs most of a step and
    leaves the box start of :meth:`PositionDependence.guess` at a ripple of its own.

    The split maximises the between-level sum of squares ``n_l*n_r/n*(m_l - m_r)^2``
    over the bins with samples; ``kb`` is the far side's level relative to the near
    side's, ``(m_r - m_l)/(1 + m_l)``. The bins used are those of at least five samples
    (the caller has four or more).
    """
    used = count >= 5
    sums = np.bincount(k, rel, minlength=count.size)[used]
    n = count[used].astype(float)
    right_edges = edges[1:][used]
    cn, cs = np.cumsum(n)[:-1], np.cumsum(sums)[:-1]
    ml, mr = cs / cn, (sums.sum() - cs) / (n.sum() - cn)
    j = int(np.argmax(cn * (n.sum() - cn) / n.sum() * (ml - mr) ** 2))
    kb = float(np.clip((mr[j] - ml[j]) / max(1.0 + ml[j], 0.1), -0.9, 2.9))
    span = float(edges[-1] - edges[0])
    x_s = float(right_edges[j])
    return {"kb": kb, "xb": x_s + span, "wb": span}
