"""Study ``presliding``, the simulation: seed 000's pressure programmes on the pre-sliding rig.

The programmes of the paper's figures (:func:`programme`), the rig with
either model (:func:`rig_plant`, :func:`rig_run`: the ``presliding-rig``
plant, the new model's memory coupled to its engine), every case of the study
(:func:`run_cases`) and a model driven by a run's velocity (:func:`replay`).
The study and its assumptions: :mod:`studies.presliding`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fcomp.backend import NUMPY
from fcomp.errors import FcompError
from fcomp.models import FrictionModel, make_model
from fcomp.piston import piston_areas
from fcomp.progress import progress_bar
from fcomp.trajectory import friction_along_motion
from plants.mechanics import end_stop_force
from plants.presliding_rig import PreslidingRig

CYLINDERS = (1, 2, 3)
#: Peak ``p1`` (Pa gauge) of Fig. 4 (cylinder 1), Fig. 7 (cylinder 2) and Fig. 8 (cylinder 3).
FIG4_P1MAX: dict[int, tuple[float, float, float]] = {
    1: (0.017e6, 0.025e6, 0.028e6), 2: (0.010e6, 0.024e6, 0.0286e6),
    3: (0.008e6, 0.011e6, 0.013e6)}
#: What Fig. 4 reports for cylinder 1 (displacement in m): peak, after release, sliding?
FIG4_PAPER = ({"x_peak": 0.07e-3, "x_final": 0.0, "slides": False},
              {"x_peak": None, "x_final": 0.025e-3, "slides": False},
              {"x_peak": None, "x_final": None, "slides": True})
#: Fig. 9 peaks (assumed: the seed prints none), cylinder 1, Pa gauge.
FIG9_PEAKS = (0.020e6, 0.020e6)
#: Fig. 10 peaks (assumed), cylinder 1.
FIG10_PEAKS = (0.020e6, 0.020e6)
#: Fig. 12a: peak p1 with p2 to 0.016 MPa; Fig. 12b: peak p2 with p1 to 0.014 MPa (seed 000).
FIG12A_P1 = (0.010e6, 0.014e6, 0.020e6)
FIG12A_P2 = 0.016e6
FIG12B_P2 = (0.0095e6, 0.016e6, 0.022e6)
FIG12B_P1 = 0.014e6
#: Ramp and hold durations of the pressure programmes (s, assumed).
RAMP = 1.0
HOLD = 0.3
#: Output interval and memory coupling interval (s): the seed's sampling interval; fast mode
#: doubles it.
DT = 1.1e-3


def paramset(cyl: int) -> str:
    """Parameter-set name of cylinder ``cyl`` (1, 2, 3)."""
    if cyl not in CYLINDERS:
        raise FcompError(f"seed 000 has cylinders 1, 2, 3, not {cyl!r}")
    return f"seed000-cylinder{cyl}"


def rig_plant(cyl: int, friction: FrictionModel | None = None) -> PreslidingRig:
    """The ``presliding-rig`` of cylinder ``cyl`` with ``friction`` (default its NMLGM, seed 000
    Table 4)."""
    pset = paramset(cyl)
    return PreslidingRig(friction or make_model("nmlgm", params=pset), pset)


def new_model(cyl: int, **changes: float) -> FrictionModel:
    """Seed 000's new model for cylinder ``cyl`` (Table 4 + Tables 2-3 of cylinder 1).

    ``changes``: flat parameters to change (e.g. the no-op hysteresis values).
    """
    model = make_model("nmlgm-hysteresis", params=paramset(cyl))
    return model.with_params(**changes) if changes else model


def cap_area(cyl: int) -> float:
    """Cap-side piston area ``A1`` (m^2) of cylinder ``cyl`` (:func:`fcomp.piston.piston_areas`)."""
    return piston_areas(rig_plant(cyl).plant_params.flat()["bore"])[0]


def pressure_scale(cyl: int) -> float:
    """``(Fs_i/A1_i)/(Fs_1/A1_1)``: cylinder-1 pressures scaled to cylinder ``cyl``."""

    def ratio(c: int) -> float:
        return rig_plant(c).friction.flat_params()["Fs_pos"] / cap_area(c)

    return ratio(cyl) / ratio(1)


# --------------------------------------------------------------- programmes
@dataclass(frozen=True)
class Programme:
    """A pressure programme: waypoints ``(duration s, p1 Pa, p2 Pa)`` from ``(0, 0)`` gauge."""

    name: str
    waypoints: tuple[tuple[float, float, float], ...]
    label: str = ""

    @property
    def duration(self) -> float:
        return float(sum(w[0] for w in self.waypoints)) + HOLD

    def pressures(self, t: np.ndarray) -> np.ndarray:
        """Set points ``(len(t), 2)`` (Pa gauge): raised-cosine ramps between waypoints."""
        out = np.zeros((t.size, 2))
        t0, prev = 0.0, np.zeros(2)
        for dur, p1, p2 in self.waypoints:
            nxt = np.array([p1, p2])
            s = np.clip((t - t0) / dur, 0.0, 1.0)[:, None]
            w = 0.5 - 0.5 * np.cos(np.pi * s)
            inside = (t >= t0)[:, None]
            out = np.where(inside, prev + (nxt - prev) * w, out)
            t0, prev = t0 + dur, nxt
        return out

    def scaled(self, k: float) -> Programme:
        """The programme with every pressure times ``k``."""
        if k == 1.0:
            return self
        return Programme(self.name, tuple((d, k * a, k * b) for d, a, b in self.waypoints),
                         f"{self.label}, scaled x{k:.3g}")


def programme(kind: str, p1: float, p2: float = 0.0, *, repeats: int = 1) -> Programme:
    """The pressure programme of a figure (module docstring; peaks in Pa gauge).

    ``fig4``: ``p1`` up and down (``p2 = 0``); ``fig9``/``fig12``: ``p1`` up and
    down, then ``p2``; ``fig10``: the same with dips that draw five internal
    loops (three in the ``p1`` half, two in the ``p2`` half).
    """
    if kind == "fig4":
        one = [(RAMP, p1, 0.0), (HOLD, p1, 0.0), (RAMP, 0.0, 0.0), (HOLD, 0.0, 0.0)]
        label = f"p1 to {p1 / 1e6:.4g} MPa"
    elif kind in ("fig9", "fig12"):
        one = [(RAMP, p1, 0.0), (HOLD, p1, 0.0), (RAMP, 0.0, 0.0), (HOLD, 0.0, 0.0),
               (RAMP, 0.0, p2), (HOLD, 0.0, p2), (RAMP, 0.0, 0.0), (HOLD, 0.0, 0.0)]
        label = f"p1 to {p1 / 1e6:.4g} MPa, p2 to {p2 / 1e6:.4g} MPa"
    elif kind == "fig10":
        h = 0.5 * RAMP
        one = [(RAMP, 0.5 * p1, 0.0), (h, 0.3 * p1, 0.0), (RAMP, 0.75 * p1, 0.0),
               (h, 0.55 * p1, 0.0), (RAMP, p1, 0.0), (HOLD, p1, 0.0), (RAMP, 0.4 * p1, 0.0),
               (h, 0.6 * p1, 0.0), (RAMP, 0.0, 0.0), (HOLD, 0.0, 0.0),
               (RAMP, 0.0, 0.6 * p2), (h, 0.0, 0.4 * p2), (RAMP, 0.0, p2), (HOLD, 0.0, p2),
               (RAMP, 0.0, 0.5 * p2), (h, 0.0, 0.7 * p2), (RAMP, 0.0, 0.0), (HOLD, 0.0, 0.0)]
        label = f"p1 to {p1 / 1e6:.4g} MPa, p2 to {p2 / 1e6:.4g} MPa, five internal loops"
    else:
        raise FcompError(f"unknown pressure programme {kind!r}")
    return Programme(kind, tuple(one * repeats), label)


# ------------------------------------------------------------ rig runs
@dataclass
class RigRun:
    """One run of the rig (SI): ``t, x`` (displacement from the start), ``v, a, p1, p2``
    (gauge), ``F`` (the friction force) and, in ``extra``, the model's states and
    ``F_eq1``, the friction as seed 000 computes it from the measured quantities (Eq. 1,
    ``p1*A1 - p2*A2 - m*a``, plus the end-stop force in contact): equal to ``F`` to
    rounding (the plant solves the acceleration from exactly that balance).
    """

    model: str
    programme: Programme
    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    p1: np.ndarray
    p2: np.ndarray
    F: np.ndarray
    extra: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def friction_work(self) -> float:
        """``W = integral F dx`` over the run (J): the loop area of a closed cycle."""
        return float(np.trapezoid(self.F * self.v, self.t))

    @property
    def span(self) -> float:
        """Displacement span ``max x - min x`` (m)."""
        return float(self.x.max() - self.x.min())


def rig_run(rig: PreslidingRig, prog: Programme, dt: float) -> RigRun:
    """The rig under programme ``prog`` from ambient chambers, output every ``dt`` s; friction
    with discrete memory coupled to the engine every ``dt`` (module docstring)."""
    p = rig.plant_params.flat()
    t = np.arange(int(round(prog.duration / dt)) + 1) * dt
    U = prog.pressures(t) * (p["u_full"] / p["p_rated"])
    coupling = dt if rig.friction.discrete_memory() is not None else None
    m = rig.simulate(U, float(t[-1]), 1.0 / dt, x0={"p1": p["p_atm"], "p2": p["p_atm"]},
                     coupling=coupling)
    c = m.columns
    A1, A2 = piston_areas(p["bore"], p["rod"])
    stop = end_stop_force(NUMPY, c["x"], c["v"], rig.param_values(NUMPY))
    extra = {n: c[n] for n in rig.friction.state_names}
    extra["F_eq1"] = c["p1"] * A1 - c["p2"] * A2 + stop - p["mass"] * c["a"]
    return RigRun(rig.friction.name, prog, c["t"], c["x"] - c["x"][0], c["v"], c["a"], c["p1"],
                  c["p2"], c["F"], extra)


def replay(model: FrictionModel, ref: RigRun, substeps: int = 4) -> np.ndarray:
    """Friction force (N) of ``model`` driven by the velocity of ``ref`` (the seed's Figs. 14, 19)."""
    run = friction_along_motion(model, ref.t, ref.v, a=ref.a, x=ref.x, p1=ref.p1, p2=ref.p2,
                                substeps=substeps)
    return run.F


# -------------------------------------------------------------------- cases
@dataclass
class Case:
    """One pressure programme on one cylinder, with both models."""

    cylinder: int
    figure: str
    programme: Programme
    nmlgm: RigRun
    new: RigRun


def run_cases(fast: bool, progress: bool = True) -> list[Case]:
    """Every pressure programme on the rig (both models); ``progress``: a bar on a terminal."""
    dt = 2 * DT if fast else DT
    plan: list[tuple[int, str, Programme]] = []
    for cyl in ((1,) if fast else CYLINDERS):
        for p in FIG4_P1MAX[cyl]:
            plan.append((cyl, "fig4", programme("fig4", p, repeats=1 if fast else 2)))
        k = pressure_scale(cyl)
        if not fast:
            plan.append((cyl, "fig9", programme("fig9", *FIG9_PEAKS).scaled(k)))
        plan.append((cyl, "fig10", programme("fig10", *FIG10_PEAKS).scaled(k)))
        for p in FIG12A_P1:
            plan.append((cyl, "fig12a", programme("fig12", p, FIG12A_P2).scaled(k)))
        if not fast:
            for p in FIG12B_P2:
                plan.append((cyl, "fig12b", programme("fig12", FIG12B_P1, p).scaled(k)))
    bar = progress_bar("presliding", len(plan), enabled=progress)
    cases = []
    cyls = sorted({p[0] for p in plan})
    rigs = {c: (rig_plant(c), rig_plant(c, new_model(c))) for c in cyls}
    for cyl, fig, prog in plan:
        bar.set_postfix_str(f"cylinder {cyl} {fig}")
        nmlgm_rig, new_rig = rigs[cyl]
        cases.append(Case(cyl, fig, prog, rig_run(nmlgm_rig, prog, dt),
                          rig_run(new_rig, prog, dt)))
        bar.update()
    bar.close()
    return cases
