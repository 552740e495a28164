"""Study ``presliding``: seed 000 reproduced on the ``presliding-rig``.

Seed 000 (Tran, Dao & Yanada, "Dynamic friction behavior in pre-sliding
regime of pneumatic actuators") pushes a free piston back and forth inside
its seals with two pressure-control valves and plots the friction force
(its Eq. 1, ``F = p1*A1 - p2*A2 - m*a``) against the displacement: an
elastic-plastic "nonlinear spring" (Figs. 4, 7, 8), clockwise loops (Fig. 9),
internal loops with nonlocal memory (Figs. 10, 11), loops growing with the
pressure (Fig. 12). The NMLGM cannot produce such loops (Fig. 14); the new
model, the NMLGM with a hysteresis function ``F(z)`` (``nmlgm-hysteresis``,
Eqs. 10-13), can (Figs. 19, 20).

How it is reproduced (SI units: m, N, Pa, s, J)
-----------------------------------------------
**Pressure programmes.** Each figure's pressure cycle is a sequence of
waypoints ``(duration, p1, p2)`` (gauge), joined by raised-cosine ramps and
sent to the two valves as commands ``u_i = p_i*u_full/p_rated`` (V). The
seed gives the peak pressures of Figs. 4, 7, 8 and 12; the durations, the
Fig. 9 and 10 peaks and the dips that make Fig. 10's internal loops are
assumed (:data:`~studies.presliding_runs.RAMP`, :data:`~studies.presliding_runs.HOLD`,
:func:`~studies.presliding_runs.programme`). For cylinders 2 and
3 the cylinder-1 pressures of Figs. 9, 10 and 12 are scaled by
``(Fs_i/A1_i)/(Fs_1/A1_1)`` so that every cylinder is pushed to the same
fraction of its break-away force (assumed: the seed shows only Fig. 11 for
them).

**The rig.** Plant ``presliding-rig`` (models.md 3.4) with the cylinder's
parameter set, the same plant for both models (:func:`~studies.presliding_runs.rig_run`). With the
NMLGM the plant engine (RODAS4) runs the whole rig. The new model has
discrete memory; the plant couples that memory to its engine
(:mod:`plants.discrete_memory`: the piston's equation of motion ``m*dv/dt =
p1*A1 - p2*A2 - F``, models.md 3.1, and the film state integrated by the
engine with the tangent of ``F(z)``, the memory driven exactly along the
deflection) in coupling intervals of :data:`~studies.presliding_runs.DT` = the seed's 1.1 ms
sampling. The coupling is checked against the plant engine: with the no-op
hysteresis function the new model *is* the NMLGM, and both runs must give
the same displacement.

**The new model is the reference.** Seed 000's measurements are not
available as data. The paper shows that the new model reproduces its
measured loops (Figs. 19, 20); here the rig run with the new model stands in
for the measurement, and, as the seed did for Figs. 14 and 19, each model is
then driven by the velocity of that run (``fcomp.trajectory.
friction_along_motion``) and its friction force compared with the
"measured" one. ``loop_area_error`` is the relative error of the friction
work over the pressure cycle, ``W = integral F dx`` (the area of the
force-displacement loop when the loop closes), against the reference's:
for ``nmlgm-hysteresis`` it is a self-consistency number (the reference is
the same model on the rig), for the NMLGM the size of its failure. An
independent check of the new model against the paper's numbers is reported
beside it: the area of the external loop that Table 3's curves (with
Table 2's boundaries) imply, integrated here in closed form, against the
model's loop over the same deflection cycle.

**Memory properties** are measured, not assumed: each model is driven by a
displacement with an external cycle and two internal loops (one on the
descending branch, one on the ascending one; :func:`~studies.presliding_analysis.memory_paths`), and by
the same displacement without the internal loops.
``minor_loops_closed``: when the displacement returns to an internal loop's
starting reversal point, the force is within :data:`~studies.presliding_analysis.MEMORY_TOL` (1 %) of
the external loop's force range of what it was there. ``wiping_out``: after
the loop closed, the force along the rest of the branch is within the same
tolerance of the force without the internal loop.

**Loop size against pressure** (Fig. 12): the displacement span (max - min)
of the reference run over the cycle, for each peak ``p1`` (Fig. 12a; Fig.
12b's ``p2`` series is reported beside it).

Modules (one concern each)
--------------------------
:mod:`studies.presliding_runs`
    the simulation: programmes, the rig with either model, the cases, replays;
:mod:`studies.presliding_analysis`
    the measures, the summary and the findings;
:mod:`studies.presliding_figures`, :mod:`studies.presliding_report`
    the figures and the report;
this module
    the study (``fcomp study presliding``).
"""

from __future__ import annotations

from typing import Any

from studies.base import Finding, Study, StudyConfig, StudyOutput
from studies.presliding_analysis import analyse, finding, findings
from studies.presliding_report import write_report
from studies.presliding_runs import run_cases


class PreslidingStudy(Study):
    """Seed 000 reproduced on the pre-sliding rig."""

    name = "presliding"
    cost = 10.0
    title = "Pre-sliding friction of pneumatic cylinders: Tran, Dao & Yanada reproduced"
    summary = ("Pressure cycles of seed 000 on the pre-sliding rig: force-displacement loops, "
               "the NMLGM's failure on nonlocal memory and the new model's success.")
    paper = ("Tran, Dao & Yanada, \"Dynamic friction behavior in pre-sliding regime of "
             "pneumatic actuators\"")
    figure_label = "Report figure"
    table_label = "Report table"

    def headline(self, results: dict[str, Any]) -> str:
        n, h = results["nmlgm"], results["nmlgm-hysteresis"]

        def yes(flag: bool) -> str:
            return "yes" if flag else "no"

        return (f"minor loops closed: NMLGM {yes(n['minor_loops_closed'])}, new model "
                f"{yes(h['minor_loops_closed'])}; wiping-out: NMLGM {yes(n['wiping_out'])}, "
                f"new model {yes(h['wiping_out'])}; NMLGM friction-work error "
                f"{100 * n['loop_area_error']:+.0f} %")

    def finding(self, results: dict[str, Any]) -> Finding:
        return finding(results)

    def key_figure(self, results: dict[str, Any]) -> str | None:
        return "memory"

    def build(self, out: StudyOutput, config: StudyConfig) -> dict[str, Any]:
        cases = run_cases(config.fast, progress=config.progress)
        res = analyse(cases, config.fast)
        res["findings"] = findings(res)
        write_report(out, cases, res, config.fast)
        for key in ("nmlgm", "nmlgm-hysteresis"):
            res[key] = dict(res[key])
        res.pop("_replays")
        mem = res.pop("_memory")
        del mem
        return res


STUDY = PreslidingStudy()
main = STUDY.main
