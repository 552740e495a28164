"""Study ``presliding``, the report: summary, method, tables and figures from the results."""

from __future__ import annotations

from typing import Any

from studies.base import StudyOutput
from studies.presliding_analysis import (
    FIG4_QUANTITIES,
    MODELS,
    PAPER_FACTOR,
    findings,
    mismatch,
)
from studies.presliding_figures import fig_case, fig_fig4, fig_memory, fig_replay, fig_size
from studies.presliding_runs import Case


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


def _three(e: dict[str, Any], paper: dict[str, Any], q: str) -> str:
    """New model / NMLGM / paper values of ``q`` in mm (the paper's only where it gives one)."""
    vals = [e["nmlgm-hysteresis"][q], e["nmlgm"][q]]
    if paper:
        vals.append(paper.get(q))
    return " / ".join("-" if v is None else f"{v * 1e3:.3f}" for v in vals)


def _against_paper(e: dict[str, Any], paper: dict[str, Any]) -> str:
    """The flag of a row: each quantity where a model is :data:`PAPER_FACTOR` x off the paper."""
    if not paper:
        return "-"
    flags = []
    for q in FIG4_QUANTITIES:
        ratios = [r for key in MODELS if (r := mismatch(e[key][q], paper.get(q))) is not None]
        if ratios:
            lo, hi = f"{min(ratios):.0f}", f"{max(ratios):.0f}"
            flags.append(f"{FIG4_QUANTITIES[q]} {lo if lo == hi else f'{lo}-{hi}'}x off: check")
    return "; ".join(flags) or f"within {PAPER_FACTOR:g}x"


def write_report(out: StudyOutput, cases: list[Case], res: dict[str, Any], fast: bool) -> None:
    rep = out.report
    n, h = res["nmlgm"], res["nmlgm-hysteresis"]
    rep.section("Findings")
    rep.bullets(findings(res))
    if fast:
        rep.note("Fast mode (CI): cylinder 1 only, Fig. 9 and Fig. 12b left out, a 2.2 ms "
                 "step; run without `--fast` for all three cylinders.", kind="info")
    rep.section("Method")
    rep.paragraph(
        "Plant `presliding-rig` (horizontal free piston, two pressure-control valves of 1 MPa "
        "rated pressure, first-order response) with the cylinders of seed 000 Table 1 and the "
        "friction of its Table 4; the new model adds the hysteresis function of Tables 2-3 "
        "(cylinder 1; the seed gives no other, so cylinders 2 and 3 use it too). Chambers start "
        "at ambient pressure, the seal in its virgin state.")
    rep.paragraph(
        "Both models run in the same plant. The NMLGM runs in the plant engine whole; the new "
        "model has discrete memory, which the plant couples to its engine at the seed's 1.1 ms "
        "sampling: the engine integrates the piston, the chambers and the film with the "
        "tangent of the hysteresis function, the memory follows the deflection exactly. The "
        "coupling reproduces the plant engine when the hysteresis function is switched off "
        "(last finding).")
    rep.paragraph(
        "Seed 000's measurements are not available as data. The new model on the rig is the "
        "reference (the paper shows it matches its measurements, Figs. 19-20); each model is "
        "then driven by the reference's velocity as the seed did. `loop_area_error` is the "
        "relative error of the friction work `W = integral F dx` over the Fig. 10 programme "
        "(the loop area of a closed cycle). The memory properties are measured on a prescribed "
        "displacement with and without two internal loops.")
    rep.section("Nonlocal memory and loop areas")
    rep.table(["quantity", "NMLGM", "new model"], [
        ["minor loops closed", _yes(n["minor_loops_closed"]), _yes(h["minor_loops_closed"])],
        ["closing gaps [N]", ", ".join(f"{g:.3g}" for g in n["closing_gaps"]),
         ", ".join(f"{g:.3g}" for g in h["closing_gaps"])],
        ["wiping-out", _yes(n["wiping_out"]), _yes(h["wiping_out"])],
        ["wiping deviation [N]", ", ".join(f"{g:.3g}" for g in n["wiping_deviation"]),
         ", ".join(f"{g:.3g}" for g in h["wiping_deviation"])],
        ["tolerance [N]", n["memory_tolerance"], h["memory_tolerance"]],
        ["loop_area_error (friction work)", n["loop_area_error"], h["loop_area_error"]],
        ["force RMS error against the reference [N]", n["force_rms_error"],
         h["force_rms_error"]],
    ], caption="summary.json `nmlgm` and `nmlgm-hysteresis`.")
    fig_memory(out, res)
    fig_replay(out, cases, res)
    tc = h["table3_check"]
    rep.paragraph(
        f"Check against the paper's Table 3: the external loop its curves imply over "
        f"[-z1, z5] encloses {tc['table3_loop_area'] * 1e3:.4f} mJ (closed-form integral of "
        f"Eq. 13); the model's F(z) loop over the same deflection cycle "
        f"{tc['model_loop_area'] * 1e3:.4f} mJ ({100 * tc['relative_error']:+.2f} %).")
    rep.section("Pressure cycles of Figs. 4, 9, 10 and 12")
    for cyl in sorted({c.cylinder for c in cases}):
        rep.section(f"Cylinder {cyl}", level=3)
        f4 = res["fig4"][str(cyl)]
        rows = []
        for e in f4:
            paper = e.get("paper", {})
            rows.append([e["p1_max"] / 1e6, _three(e, paper, "x_peak"),
                         _three(e, paper, "x_final"),
                         f"{'yes' if e['nmlgm-hysteresis']['slides'] else 'no'} / "
                         f"{'yes' if e['nmlgm']['slides'] else 'no'}"
                         + (f" / {'yes' if paper['slides'] else 'no'}" if paper else ""),
                         _against_paper(e, paper)])
        rep.table(["p1 max [MPa]", "peak x [mm]", "x after release [mm]", "slides",
                   "against the paper"], rows,
                  caption=f"Fig. {dict([(1, 4), (2, 7), (3, 8)])[cyl]} quantities, cylinder "
                  f"{cyl}: new model / NMLGM / paper (the paper's value where it gives one); "
                  f"a model {PAPER_FACTOR:g}x or more off the paper is flagged.",
                  digits=[4, None, None, None, None])
        fig_fig4(out, cases, cyl)
        for c in cases:
            if c.cylinder == cyl and c.figure in ("fig9", "fig10"):
                fig_case(out, c, f"{c.figure}-cylinder{cyl}",
                          f"Seed 000 Fig. {c.figure[3:]} programme, cylinder {cyl} "
                          f"({c.programme.label}): pressures, displacement, friction force "
                          "against displacement.")
    rep.section("Loop size against pressure (Fig. 12)")
    rep.table(["peak p1 [MPa]", "loop span, new model [mm]"],
              [[p / 1e6, s * 1e3] for p, s in res["loop_size_vs_pressure"]],
              caption="summary.json `loop_size_vs_pressure` (p in Pa, size in m there).",
              digits=[4, 4])
    fig_size(out, cases, res)
    rep.section("Parameters")
    names = sorted(set(res["parameters"]["nmlgm"]) | set(res["parameters"]["nmlgm-hysteresis"]))
    rep.table(["parameter", "NMLGM", "new model"],
              [[k, res["parameters"]["nmlgm"].get(k), res["parameters"]["nmlgm-hysteresis"].get(k)]
               for k in names], caption="Friction parameters of cylinder 1 (SI; seed 000 "
              "Tables 2-4, Table 2 read as metres, see `fcomp.paramsets`).")
    rep.table(["setting", "value"], [[k, str(v)] for k, v in res["settings"].items()],
              caption="Study settings.")
