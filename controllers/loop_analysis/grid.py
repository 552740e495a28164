"""Where the margins must hold: the stroke, the parameters an engineer is unsure of, friction.

A :class:`PlantGrid` holds the sampled linear plant (:mod:`plants.linearise`) at
every point of

* the **stroke**: the fractions of :attr:`plants.uncertainty.Uncertainty.positions`
  (default 2 %, 5 %, 25 %, 50 %, 75 %, 95 %, 98 %): the oil (air) column's stiffness
  ``beta*A1^2/V1 + beta*A2^2/V2`` grows without bound towards the ends, where the
  chambers' dead volumes alone remain;
* the **parameter box** of the plant file's ``[uncertainty]`` (valve flow gain, bulk
  modulus or polytropic exponent, moving mass, supply pressure): the nominal values,
  each parameter alone at its low and at its high end, and every corner of the box
  (``1 + 2k + 2^k`` combinations of ``k`` parameters: the worst case of a margin that
  changes monotonically with each parameter lies on a corner; the one-at-a-time
  points are what an engineer tries first);
* the **friction regime** of the piston at rest: sliding (the friction's sliding
  slope, no pre-sliding) and held by the seal's pre-sliding spring (the controller's
  friction model's bristle stiffness ``sigma0`` at the low end, nominal and high end of
  its range, with its damping), when that model has a bristle state.

The plant is linearised where it holds its load at rest (the equilibrium of each
parameter set; the pre-sliding regimes share the sliding one's: the bristle is
unstrained there). Each point keeps the plant's frequency response ``P(e^{jwT})``
on the analysis's frequency grid, so that a controller's margins over the whole
grid cost one vectorised evaluation (:meth:`PlantGrid.margins`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from controllers.loop_analysis.loop import (
    closed_loop_matrix,
    dominant_pole,
    loop_responses,
    plant_response,
    unit_z,
)
from controllers.loop_analysis.margins import frequency_grid, margins_of_responses
from plants.linearise import Linearisation, LinearPlant
from plants.uncertainty import PARAMETERS, Uncertainty


@dataclass(frozen=True)
class GridPoint:
    """One point of the grid.

    Attributes
    ----------
    fraction : float
        Piston position as a fraction of the stroke.
    position : float
        Piston position (m).
    changes : tuple of (str, float)
        Relative change of each uncertain parameter (key of :data:`plants.uncertainty.PARAMETERS`).
    presliding : float or None
        Factor on the pre-sliding stiffness ``sigma0`` (None: the sliding piston).
    """

    fraction: float
    position: float
    changes: tuple[tuple[str, float], ...]
    presliding: float | None

    def describe(self) -> str:
        """One phrase: where, which parameter values, which friction regime."""
        ch = [f"{k} {100 * v:+.3g} %" for k, v in self.changes if v]
        fr = ("sliding" if self.presliding is None
              else f"at rest in pre-sliding (sigma0 x{self.presliding:.3g})")
        return (f"{100 * self.fraction:.3g} % of the stroke ({1e3 * self.position:.4g} mm), "
                f"{', '.join(ch) if ch else 'nominal parameters'}, {fr}")

    def as_dict(self) -> dict[str, Any]:
        return {"position": self.position, "fraction": self.fraction,
                "parameters": {k: v for k, v in self.changes},
                "friction": "sliding" if self.presliding is None else "presliding",
                "presliding_factor": self.presliding}


def parameter_combinations(unc: Uncertainty) -> list[tuple[tuple[str, float], ...]]:
    """Nominal, each parameter alone at each end, every corner (module docstring)."""
    keys = [k for k, lo, hi in unc.table if lo != 0 or hi != 0]
    nominal = tuple((k, 0.0) for k, _lo, _hi in unc.table)
    rng = unc.ranges
    out = [nominal]

    def combo(values: dict[str, float]) -> tuple[tuple[str, float], ...]:
        return tuple((k, values.get(k, 0.0)) for k, _lo, _hi in unc.table)

    for k in keys:
        for end in rng[k]:
            if end != 0:
                out.append(combo({k: end}))
    for ends in itertools.product(*[[e for e in rng[k] if e != 0] for k in keys]):
        if len(keys) > 1:
            out.append(combo(dict(zip(keys, ends, strict=True))))
    seen: set[tuple[tuple[str, float], ...]] = set()
    return [c for c in out if not (c in seen or seen.add(c))]  # type: ignore[func-returns-value]


@dataclass
class PlantGrid:
    """The linear plants of a controller model's grid (module docstring).

    Build it with :func:`plant_grid`.

    Attributes
    ----------
    points : list of GridPoint
    plants : list of LinearPlant
    slopes : tuple of numpy.ndarray
        The force-to-valve inversion's ``(s, J_y, J_v)`` at each point's measurement and
        holding command (:meth:`controllers.force_to_valve.ForceToValve.slopes`).
    delay : int
        Computation delay (samples).
    dt : float
        Sample period (s).
    w : numpy.ndarray
        The frequency grid (rad/s).
    areas : tuple of float
        ``(A1, A2)`` (m^2).
    """

    points: list[GridPoint]
    plants: list[LinearPlant]
    slopes: tuple[np.ndarray, np.ndarray, np.ndarray]
    delay: int
    dt: float
    w: np.ndarray
    areas: tuple[float, float]
    _blocks: list[tuple[np.ndarray, dict[str, np.ndarray]]] = field(default_factory=list,
                                                                    repr=False)

    def __post_init__(self) -> None:
        # one block: plants with fewer states padded by decoupled states at z = 0 (no
        # effect on P(z) or on the closed loop's other poles)
        z = unit_z(self.w, self.dt)
        n = max(lp.Ad.shape[0] for lp in self.plants)
        P = len(self.plants)
        Ad, Bd, C = np.zeros((P, n, n)), np.zeros((P, n, 1)), np.zeros((P, 3, n))
        for i, lp in enumerate(self.plants):
            k = lp.Ad.shape[0]
            Ad[i, :k, :k], Bd[i, :k], C[i, :, :k] = lp.Ad, lp.Bd, lp.C
        self._blocks.append((np.arange(P), {"Ad": Ad, "Bd": Bd, "C": C,
                                            "P": plant_response(Ad, Bd, C, z)}))

    def __len__(self) -> int:
        return len(self.points)

    def margins(self, controller: Callable[[np.ndarray], tuple[np.ndarray, ...]],
                delay: int | None = None) -> dict[str, dict[str, np.ndarray]]:
        """The margins of a controller at every point, both breaks.

        Parameters
        ----------
        controller : callable
            ``controller(idx)`` -> ``(A, B, C, D, K)``: the controller's discrete state
            space at the points ``idx`` (batched: ``(P, nc, nc)``, ``(P, nc, 3)``, ``(P, 1,
            nc)``, ``(P, 1, 3)``) and its response ``K`` ``(P, F, 3)`` on :attr:`w`.
        delay : int, optional
            Computation delay (default :attr:`delay`).

        Returns
        -------
        dict
            ``{"valve": arrays, "position": arrays}`` of
            :func:`~controllers.loop_analysis.margins.margins_of_responses`, one entry per
            point.
        """
        d = self.delay if delay is None else int(delay)
        z = unit_z(self.w, self.dt)
        out: dict[str, dict[str, np.ndarray]] = {}
        for idx, blk in self._blocks:
            Ac, Bc, Cc, Dc, K = controller(idx)
            L = loop_responses(blk["P"], K, z, d)
            M = closed_loop_matrix(blk["Ad"], blk["Bd"], blk["C"], Ac, Bc, Cc, Dc, d)
            pole = dominant_pole(M)
            for brk, resp in L.items():
                m = margins_of_responses(resp, self.w, pole, self.dt)
                dst = out.setdefault(brk, {k: np.empty(len(self.points)) for k in m})
                for k, v in m.items():
                    dst[k][idx] = v
        return out

    def requirement(self, controller: Callable[[np.ndarray], tuple[np.ndarray, ...]]
                    ) -> np.ndarray:
        """Per point, the smaller over both breaks of
        :func:`~controllers.loop_analysis.margins.requirement_ratio` (a search's figure)."""
        from controllers.loop_analysis.margins import requirement_ratio

        z = unit_z(self.w, self.dt)
        out = np.empty(len(self.points))
        for idx, blk in self._blocks:
            Ac, Bc, Cc, Dc, K = controller(idx)
            L = loop_responses(blk["P"], K, z, self.delay)
            pole = dominant_pole(closed_loop_matrix(blk["Ad"], blk["Bd"], blk["C"], Ac, Bc, Cc,
                                                    Dc, self.delay))
            out[idx] = np.minimum(requirement_ratio(L["valve"], pole, self.dt),
                                  requirement_ratio(L["position"], pole, self.dt))
        return out

    def subset(self, keep: list[int], w: np.ndarray | None = None) -> PlantGrid:
        """The grid at the points ``keep`` only (on the frequencies ``w``, default the
        same)."""
        s, Jy, Jv = self.slopes
        return PlantGrid([self.points[i] for i in keep], [self.plants[i] for i in keep],
                         (s[keep], Jy[keep], Jv[keep]), self.delay, self.dt,
                         self.w if w is None else w, self.areas)


def plant_grid(model: Any, uncertainty: Uncertainty | None = None,
               delay: int | None = None, n_frequencies: int | None = None,
               dt: float | None = None) -> PlantGrid:
    """The grid of a controller model (:class:`controllers.plant_model.ControlModel`): its
    plant's parameters, friction (sliding slope :meth:`~controllers.plant_model.ControlModel.viscous_damping`,
    pre-sliding bristle :attr:`~controllers.plant_model.ControlModel.bristle`), control rate
    (or ``dt``), delay and uncertainty (module docstring)."""
    from controllers.force_to_valve import ForceToValve
    from fcomp.parallel import one_blas_thread

    unc = uncertainty or model.uncertainty
    dt = 1.0 / model.control_rate if dt is None else float(dt)
    d = model.delay if delay is None else int(delay)
    bare = model._bare()
    flat = bare.plant_params.flat()
    stroke = float(flat["stroke"])
    damping = model.viscous_damping()
    kinds = PARAMETERS[model.plant_name]
    points: list[GridPoint] = []
    plants: list[LinearPlant] = []
    meas_u: list[tuple[np.ndarray, float]] = []
    with one_blas_thread():
        sliding = Linearisation(bare, dt)
        resting = None
        factors: list[float] = []
        seal = model.presliding_plant()
        if seal is not None:
            resting = Linearisation(seal, dt)
            lo, hi = unc.presliding
            factors = sorted({1.0 + lo, 1.0, 1.0 + hi})
            sigma0 = float(seal.friction.flat_params()["sigma0"])
        for combo in parameter_combinations(unc):
            values = unc.scaled(flat, dict(combo))
            changed = {kinds[k][0]: values[kinds[k][0]] for k, _v in combo}
            p_slide = bare.param_vector(**changed)
            for frac in unc.positions:
                pos = frac * stroke
                lp = sliding.at(pos, p_slide, damping=damping)
                points.append(GridPoint(frac, pos, combo, None))
                plants.append(lp)
                meas_u.append((lp.measurement, lp.command))
                if resting is not None:
                    n = len(lp.state)
                    for f in factors:
                        p_rest = seal.param_vector(**changed, sigma0=sigma0 * f)
                        plants.append(resting.at(pos, p_rest,
                                                 equilibrium=(lp.state[:n], lp.command)))
                        points.append(GridPoint(frac, pos, combo, f))
                        meas_u.append((lp.measurement, lp.command))
        valve = ForceToValve(model, 1.0)
        sl = [valve.slopes(y, u) for y, u in meas_u]
    slopes = (np.array([x[0] for x in sl]), np.array([x[1] for x in sl]),
              np.array([x[2] for x in sl]))
    w = frequency_grid(dt) if n_frequencies is None else frequency_grid(dt, n_frequencies)
    with one_blas_thread():
        return PlantGrid(points, plants, slopes, d, dt, w, (model.A1, model.A2))


def nominal_points(grid: PlantGrid) -> list[int]:
    """The grid points with every uncertain parameter nominal (all positions, all friction
    regimes)."""
    return [i for i, p in enumerate(grid.points) if all(v == 0 for _k, v in p.changes)]


def resting_points(grid: PlantGrid, points: list[int] | None = None) -> list[int]:
    """The points (of ``points``, default all) with the piston at rest in pre-sliding:
    where a friction model with a bristle is linear at rest as the plant's seal is (with the
    plant sliding, such a model slides as well, its bristle saturated, its estimate the
    steady-state map; linearised at rest -- ``dz/dt = v``, its stiffness ``sigma0`` fed
    forward -- it would meet a piston the seal does not hold)."""
    pts = range(len(grid)) if points is None else points
    return [i for i in pts if grid.points[i].presliding is not None]


def mid_point(grid: PlantGrid) -> int:
    """The nominal sliding point nearest mid stroke."""
    cand = [i for i in nominal_points(grid) if grid.points[i].presliding is None]
    return min(cand, key=lambda i: abs(grid.points[i].fraction - 0.5))


def describe_at(grid: PlantGrid, arrays: dict[str, dict[str, np.ndarray]], i: int, brk: str
                ) -> str:
    """One phrase: what is short at a point and break (or its margins), and where."""
    from controllers.loop_analysis.margins import loop_margins_from

    m = loop_margins_from(arrays[brk], (i,))
    where = "the valve command" if brk == "valve" else "the position sensor"
    return f"{m.shortfall() or m.describe()}, broken at {where}, at {grid.points[i].describe()}"


def worst_index(arrays: dict[str, dict[str, np.ndarray]]) -> tuple[int, str]:
    """The point and break with the smallest ``min(gain/2, phase/30, 2/Ms)`` (an unstable
    point first, the fastest-growing)."""
    from controllers.loop_analysis.margins import (
        MAX_SENSITIVITY,
        MIN_GAIN_MARGIN,
        MIN_PHASE_MARGIN,
    )

    best: tuple[float, int, str] = (math.inf, -1, "")
    for brk, m in arrays.items():
        ratio = np.minimum(np.minimum(m["gain"] / MIN_GAIN_MARGIN,
                                      m["phase"] / MIN_PHASE_MARGIN),
                           MAX_SENSITIVITY / m["ms"])
        ratio = np.where(m["radius"] < 1.0, ratio, -m["growth"])
        i = int(np.argmin(ratio))
        if ratio[i] < best[0]:
            best = (float(ratio[i]), i, brk)
    return best[1], best[2]


__all__ = ["GridPoint", "PlantGrid", "describe_at", "mid_point", "nominal_points",
           "parameter_combinations", "plant_grid", "resting_points", "worst_index"]
