"""The report of study ``coulomb-viscous``: text, tables and figures from its results.

Every number in the text comes from the results of
:mod:`studies.coulomb_viscous_analysis`; the wording that depends on a test follows the
test's outcome. "Table N" in the text means the paper's table (seed 001);
the report's own tables carry their number in their caption.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from fcomp.figstyle import legend_above
from fcomp.report import Comparison, Report
from studies.base import StudyOutput
from studies.coulomb_viscous_analysis import (
    ALPHA,
    B_CONSISTENCY_TOL,
    CYLINDERS,
    DIRECTIONS,
    FIELDS,
    LEVEL,
    PAPER_TABLE8,
    PARAMETERS,
    T_TABLE_DECIMALS,
    Seed001Data,
    format_p,
    ols_line,
    significance,
)

EXT, RET = DIRECTIONS


def write_report(out: StudyOutput, data: Seed001Data, res: dict[str, Any],
                 B: Mapping[str, np.ndarray]) -> None:
    """Fill ``out.report`` (and write the figures) from the study's results."""
    rep = out.report
    rows = res["reproduction"]["comparisons"]
    c1 = [r for r in rows if r["cylinder"] == "C1"]
    n_match = sum(r["match"] for r in c1)
    rep.section("Findings")
    rep.paragraph(f"The paper's Table 8, cylinder C1: {n_match} of {len(c1)} numbers reproduced "
                  "to the printed digits from the single values of Tables 2-5.")
    rep.bullets(res["findings"])
    _method(rep)
    _table8(out, data, res)
    _cylinder2(rep, res)
    rep.section("The paper's assumptions, tested on its own data")
    _position(out, data, res)
    _independence(out, data, res)
    _sliding(out, data, res, B)
    _direction(rep, res)
    _uncertainty(rep, res)
    _conclusion(rep, data, res)
    rep.parameters({
        "confidence level": LEVEL,
        "significance level of the tests": ALPHA,
        "t quantile": f"{T_TABLE_DECIMALS}-decimal table value (the exact quantile in the "
                      "variants table)",
        "C1 B_i consistency tolerance [Ns/m]": B_CONSISTENCY_TOL,
        "data": "fcomp/data/datasets/seed001 (Tables 2-7 of seed 001)",
        "source": "Dağdelen, M., Sarıgeçili, M. İ. (2020), Estimation of the friction "
                  "parameters of linear pneumatic cylinders, J. Eng. Sci. Design 8(2) 397-406",
    })


def _label(par: str) -> str:
    kind, d = par.split("_")
    return f"{kind} ({d})"


def _unit(par: str) -> str:
    return "N" if par.startswith("Fc") else "Ns/m"


def _range(lo_hi: Any, digits: int = 3) -> str:
    lo, hi = lo_hi
    return f"{lo:.{digits}f} to {hi:.{digits}f}"


def _method(rep: Report) -> None:
    rep.section("Data and method")
    rep.paragraph(
        "Dağdelen & Sarıgeçili (2020) push the rod of a 25 mm bore double-acting cylinder by "
        "hand through a load cell, both chambers open to atmosphere, and fit the "
        "Coulomb-viscous model `F_ext = Fc + B v` (their Eqs. 4-5) in two steps: `Fc` is the "
        "force at which the rod starts to move, read at 12 positions along the stroke in 10 "
        "experiments per direction (Tables 2, 3); then, at constant speed, "
        "`B_i = (F_ext_i - mean Fc) / v_i` (Tables 4, 5). Their Table 8 gives 95 % Student-t "
        "intervals `mean +- t(0.975, n-1) s / sqrt(n)`. For cylinder C2 the paper prints only "
        "per-experiment averages (Tables 6, 7).")
    rep.paragraph(
        "This study reads the tables shipped in `fcomp/data/datasets/seed001` (transcribed "
        "from the paper; see SOURCE.md there). Forces in N, speeds in m/s, B in Ns/m. C1: Fc "
        "intervals from all 120 values (119 dof), B intervals from the 10 experiments (9 dof). "
        "The t quantile is read from a 3-decimal t table (2.262 for 9 dof, 1.980 for 119 dof), "
        "as the paper's digits show; the exact quantile is compared below.")


def _table8(out: StudyOutput, data: Seed001Data, res: dict[str, Any]) -> None:
    rep = out.report
    t8 = res["table8"]
    rep.section("The paper's Table 8 reproduced")
    for cyl in CYLINDERS:
        items = [Comparison(f"{cyl} {_label(par)}, {field.replace('_', ' ')}",
                            t8[cyl][par][field], PAPER_TABLE8[cyl][par][i], unit=_unit(par),
                            digits=3, note=_note(cyl, par, res))
                 for par in PARAMETERS for i, field in enumerate(FIELDS)]
        rep.comparison(items, caption=f"Cylinder {cyl}: Table 8 computed here beside the paper "
                       "(3 decimals, as printed).")
    variants = res["reproduction"]["variants"]
    rep.table(
        ["t quantile", "C1 B values", "C1 numbers equal to the print", "largest |difference|",
         "differing"],
        [[v["t"], v["B_values"], f"{v['C1_matches']} / {v['C1_numbers']}",
          v["C1_max_abs_difference"], "; ".join(v["C1_differing"])] for v in variants],
        caption="How the last printed digits depend on the computation. B values: "
                "`printed` = Tables 4-5 as printed; `recomputed` = (F_ext - mean Fc)/v from the "
                "printed F_ext and v; `reconstructed` = recomputed where the printed v "
                "reproduces the printed B_i, else printed.",
        digits=[None, None, None, 4, None])
    sp = res["two_step_B"]
    moved = max(abs(a - b) for d in DIRECTIONS
                for a, b in zip(sp[d]["B_recomputed"], data.B_printed[d], strict=True))
    implied = ", ".join(f"{sp[d]['implied_speed'][i - 1]:.4f} m/s ({d} {i})"
                        for d in DIRECTIONS for i in sp[d]["inconsistent_experiments"])
    exact = _variant(variants, "exact", "printed")
    rep.paragraph(
        "The printed speeds have 3 decimals. In experiments "
        f"{_list(sp[EXT]['inconsistent_experiments'])} (extension) and "
        f"{_list(sp[RET]['inconsistent_experiments'])} (retraction) the printed v does not "
        f"reproduce the printed B_i: the paper divided by an unrounded speed (implied {implied}). "
        f"Recomputing those B_i from the printed speeds moves them by up to {moved:.2f} Ns/m "
        "and the B interval limits by up to "
        f"{_variant(variants, '3-decimal table', 'recomputed')['C1_max_abs_difference']:.2f} "
        "Ns/m. With the exact t quantile and the printed B_i, "
        f"{exact['C1_matches']} of {exact['C1_numbers']} C1 numbers equal the print"
        + (f"; the others differ in the last digit ({'; '.join(exact['C1_differing'])})"
           if exact["C1_differing"] else "")
        + ". Differences of this size are rounding, not method.")
    tr = res["reproduction"]["transcription"]
    check_rows = [[f"C1 Fc {d}: the 10 per-experiment means at the foot of the table",
                   "all equal" if tr[f"C1_Fc_{d}_experiment_means_match"] else "differ",
                   "printed"] for d in DIRECTIONS]
    check_rows += [[key.replace("_", " "), tr[key][0], tr[key][1]]
                   for key in sorted(tr) if not key.endswith("_match")]
    rep.table(["check", "computed", "paper"], check_rows,
              caption="The tables' printed means recomputed from their rows.",
              digits=[None, 4, 3])
    _fig_table8(out, res)


def _list(items: list[int]) -> str:
    return ", ".join(str(i) for i in items) if items else "none"


def _variant(variants: list[dict[str, Any]], t: str, b_values: str) -> dict[str, Any]:
    return next(v for v in variants if v["t"] == t and v["B_values"] == b_values)


def _note(cyl: str, par: str, res: dict[str, Any]) -> str:
    """How a computed Table 8 number was obtained, and why it differs where it does."""
    if cyl == "C1":
        if par.startswith("B"):
            return "10 two-step B_i, t(0.975, 9) = 2.262"
        return "120 break-away forces, t(0.975, 119) = 1.980"
    if par.startswith("Fc"):
        return ("from the 10 Table 6 averages (9 dof); the paper used the 120 single values, "
                "which it does not print")
    if res["c2_reconstruction"][par]["paper_std_is"].startswith("population"):
        return "the paper used the population std (divisor n) here, the sample std elsewhere"
    return "Table 7, t(0.975, 9) = 2.262"


def _cylinder2(rep: Report, res: dict[str, Any]) -> None:
    c2 = res["c2_reconstruction"]
    rep.section("Cylinder C2: what can and cannot be reproduced")
    rep.paragraph(
        "For C2 the paper prints only the 10 per-experiment averages of Fc (each of 12 "
        "values) and the 10 B_i. The C2 table above therefore gives, for Fc, an interval over "
        "the 10 experiment averages (9 dof): another statistic than the paper's, whose "
        "standard deviation is that of the single values (and, with repeated runs as the "
        "unit, the more defensible one). What the printed C2 numbers imply:")
    rows = []
    for d in DIRECTIONS:
        f, b = c2[f"Fc_{d}"], c2[f"B_{d}"]
        nlo, nhi = math.ceil(f["implied_n"]["n_min"]), math.floor(f["implied_n"]["n_max"])
        paper = PAPER_TABLE8["C2"]
        rows += [
            [f"Fc {d}: sample size behind the printed std and interval",
             f"{f['implied_n']['n']:.2f} (integers the rounding allows: "
             f"{nlo if nlo == nhi else f'{nlo}-{nhi}'})", "12 positions x 10 experiments"],
            [f"Fc {d}: mean of the Table 6 averages; printed mean; interval centre",
             f"{f['table6_mean']:.4f}", f"{f['paper_mean']:.3f}; {f['paper_ci_centre']:.4f}"],
            [f"Fc {d}: interval with the paper's std, n = 120 and the Table 6 mean",
             _range(f["interval_paper_std_table6_mean"]), _range(paper[f"Fc_{d}"][1:])],
            [f"B {d}: sample / population std of Table 7",
             f"{b['sample_std']:.3f} / {b['population_std']:.3f}",
             f"{b['paper_std']:.3f} ({b['paper_std_is']})"],
            [f"B {d}: interval with the std the paper used", _range(b["interval_with_that_std"]),
             _range(paper[f"B_{d}"][1:])],
        ]
    rep.table(["what", "computed here", "paper"], rows,
              caption="Cylinder C2: what the printed numbers imply.")
    fe, fr = c2["Fc_extension"], c2["Fc_retraction"]
    rep.paragraph(
        f"The C2 Fc standard deviations ({PAPER_TABLE8['C2']['Fc_extension'][0]:.3f} and "
        f"{PAPER_TABLE8['C2']['Fc_retraction'][0]:.3f} N) are those of single values that are "
        "not printed, so they cannot be recomputed; with them the printed interval widths "
        f"imply n = {fe['implied_n']['n']:.0f} and {fr['implied_n']['n']:.0f}, the 12 x 10 "
        f"values. The Table 6 averages do not average to the printed means "
        f"({fe['table6_mean']:.4f} against {fe['paper_mean']:.3f} N, {fr['table6_mean']:.4f} "
        f"against {fr['paper_mean']:.3f} N; the interval centres agree with the printed means): "
        "a printed average or a mean carries a slip, or the experiments had unequal numbers "
        "of values. Either way the C2 Fc row of Table 8 cannot be reproduced from the paper.")
    for d in DIRECTIONS:
        b = c2[f"B_{d}"]
        if b["paper_std_is"].startswith("population"):
            ti = res["table8"]["C2"][f"B_{d}"]
            rep.paragraph(
                f"The C2 B {d} standard deviation is the population value (divisor n), unlike "
                f"every other entry; with it the printed interval is reproduced exactly. With "
                f"the sample value it is {b['sample_std']:.3f} Ns/m and the interval "
                f"{ti['ci_low']:.3f} to {ti['ci_high']:.3f} Ns/m (the C2 table above).")


def _position(out: StudyOutput, data: Seed001Data, res: dict[str, Any]) -> None:
    rep = out.report
    pos = res["assumptions"]["position_dependence"]
    rep.section("Is Fc independent of the position along the stroke?", level=3)
    rep.table(
        ["test", "extension", "retraction"],
        [[label, pos[EXT][key], pos[RET][key]] for label, key in (
            ("one-way ANOVA over 12 steps, p", "anova_p"),
            ("Kruskal-Wallis, p", "kruskal_p"),
            ("Friedman (experiments as blocks), p", "friedman_p"),
            ("ANOVA without step 1, p", "anova_p_without_step1"),
            ("Friedman without step 1, p", "friedman_p_without_step1"),
            ("mean Fc at step 1 [N]", "step1_mean"),
            ("mean Fc at steps 2-12 [N]", "other_steps_mean"),
            ("step 1 vs steps 2-12, Welch p", "step1_welch_p"),
            ("step 1 vs steps 2-12, Mann-Whitney p", "step1_mannwhitney_p"),
            ("experiments where step 1 is the highest (of 10)", "step1_highest_in_experiments"),
        )],
        caption="Break-away force against the position step.")
    flat = all(pos[d]["anova_p_without_step1"] >= ALPHA for d in DIRECTIONS)
    high = all(pos[d]["step1_welch_p"] < ALPHA and pos[d]["step1_excess"] > 0
               for d in DIRECTIONS)
    text = (f"The position effect is {significance(pos[EXT]['anova_p'])} in extension and "
            f"{significance(pos[RET]['anova_p'])} in retraction (one-way ANOVA). Without step 1 "
            f"the ANOVA gives p = {format_p(pos[EXT]['anova_p_without_step1'])} and "
            f"{format_p(pos[RET]['anova_p_without_step1'])}: "
            + ("the effect is carried by step 1 alone. " if flat
               else "a position effect remains beyond step 1. "))
    if high:
        text += ("Step 1 is the first break-away after the rod has rested at the end of the "
                 "stroke; the later steps follow a short stop. A higher first break-away is the "
                 "dwell-time effect (static friction growing with the time at rest): that force "
                 "is the static level Fs of a Stribeck or LuGre model, not the Coulomb level. ")
    text += (f"Averaging it into Fc raises mean Fc by "
             f"{(pos[EXT]['step1_mean'] - pos[EXT]['other_steps_mean']) / 12:.2f} N (extension) "
             f"and {(pos[RET]['step1_mean'] - pos[RET]['other_steps_mean']) / 12:.2f} N "
             "(retraction).")
    rep.paragraph(text)
    _fig_position(out, data, res)


def _independence(out: StudyOutput, data: Seed001Data, res: dict[str, Any]) -> None:
    rep = out.report
    ind, nor = res["assumptions"]["independence"], res["assumptions"]["normality"]
    rep.section("Are the 120 values independent and normal?", level=3)
    rep.table(
        ["quantity", "extension", "retraction"],
        [["two-way ANOVA: experiment effect, p", ind[EXT]["two_way_anova"]["p_cols"],
          ind[RET]["two_way_anova"]["p_cols"]],
         ["two-way ANOVA: position effect, p", ind[EXT]["two_way_anova"]["p_rows"],
          ind[RET]["two_way_anova"]["p_rows"]],
         ["intraclass correlation within an experiment", ind[EXT]["icc"], ind[RET]["icc"]],
         ["design effect / effective n (of 120)",
          f"{ind[EXT]['design_effect']:.2f} / {ind[EXT]['effective_n']:.0f}",
          f"{ind[RET]['design_effect']:.2f} / {ind[RET]['effective_n']:.0f}"],
         ["95 % interval over the 10 experiment means [N]",
          _range(ind[EXT]["interval_experiment_means"]),
          _range(ind[RET]["interval_experiment_means"])],
         ["Shapiro-Wilk p, all 120 Fc", nor[EXT]["Fc_shapiro_p"], nor[RET]["Fc_shapiro_p"]],
         ["skewness, all 120 Fc", nor[EXT]["Fc_skewness"], nor[RET]["Fc_skewness"]],
         ["Shapiro-Wilk p, Fc without step 1", nor[EXT]["Fc_without_step1_shapiro_p"],
          nor[RET]["Fc_without_step1_shapiro_p"]],
         ["skewness, Fc without step 1", nor[EXT]["Fc_without_step1_skewness"],
          nor[RET]["Fc_without_step1_skewness"]],
         ["Shapiro-Wilk p, 10 B_i", nor[EXT]["B_shapiro_p"], nor[RET]["B_shapiro_p"]]],
        caption="Independence and normality behind Table 8.")
    clustered = [d for d in DIRECTIONS if ind[d]["two_way_anova"]["p_cols"] < ALPHA]
    normal_all = [d for d in DIRECTIONS if nor[d]["Fc_shapiro_p"] >= ALPHA]
    normal_wo = [d for d in DIRECTIONS if nor[d]["Fc_without_step1_shapiro_p"] >= ALPHA]
    rep.paragraph(
        ("The experiments do not differ significantly from one another (two-way ANOVA) and "
         "the intraclass correlation is small, so treating the 120 values as independent "
         "(119 dof) narrows the Fc interval only a little; the interval over the 10 "
         "experiment means is the conservative alternative. " if not clustered else
         f"The experiments differ significantly ({', '.join(clustered)}): the 120 values are "
         "not independent and the 119-dof interval is too narrow; the interval over the 10 "
         "experiment means is the honest one. ")
        + ("The break-away forces are not normal (Shapiro-Wilk rejects; right skew)"
           if len(normal_all) < len(DIRECTIONS) else "The break-away forces look normal")
        + "; without step 1 the test "
        + (f"no longer rejects in {', '.join(normal_wo)}" if normal_wo else "still rejects")
        + (f" but still rejects in {', '.join(d for d in DIRECTIONS if d not in normal_wo)}"
           if normal_wo and len(normal_wo) < len(DIRECTIONS) else "")
        + ". The t interval of a mean of 120 values is still adequate (central limit "
        "theorem), but the standard deviation mixes the static break-away at step 1 with the "
        "others, and B_i computed from it inherit the mix.")
    _fig_normal(out, data, res)


def _sliding(out: StudyOutput, data: Seed001Data, res: dict[str, Any],
             B: Mapping[str, np.ndarray]) -> None:
    rep = out.report
    sl = res["assumptions"]["sliding_force"]
    rep.section("Is the break-away force the Coulomb level, and is B constant?", level=3)
    rows = []
    for d in DIRECTIONS:
        s, line = sl[d], sl[d]["line"]
        rows += [
            [f"{d}: speeds [m/s]", _range(s["speed_range"])],
            [f"{d}: line F_ext = a + b v: a [N] (95 %)",
             f"{line['intercept']:.2f} ({_range(line['intercept_ci'], 2)})"],
            [f"{d}: mean break-away force [N]", f"{s['breakaway_mean']:.3f}"],
            [f"{d}: a - mean Fc [N]; p", f"{s['intercept_minus_breakaway']:.2f}; "
             f"{format_p(s['intercept_vs_breakaway_p'])}"],
            [f"{d}: slope b [Ns/m] (95 %)", f"{line['slope']:.1f} ({_range(line['slope_ci'], 1)})"],
            [f"{d}: two-step mean B [Ns/m]", f"{s['two_step_B_mean']:.3f}"],
            [f"{d}: B_i against v_i: Pearson r (p); Spearman rho (p)",
             f"{s['B_vs_v_pearson_r']:.2f} ({format_p(s['B_vs_v_pearson_p'])}); "
             f"{s['B_vs_v_spearman_rho']:.2f} ({format_p(s['B_vs_v_spearman_p'])})"],
        ]
    rep.table(["quantity", "value"], rows,
              caption="The constant-speed runs against the Coulomb-viscous line.")
    r, e = sl[RET], sl[EXT]
    lo_v = r["speed_range"][0]
    at_lo = r["line"]["intercept"] + r["line"]["slope"] * lo_v
    at_hi = r["line"]["intercept"] + r["line"]["slope"] * r["speed_range"][1]
    b_out = not (r["line"]["slope_ci"][0] <= r["two_step_B_mean"] <= r["line"]["slope_ci"][1])
    rep.paragraph(
        "If the model held, a straight line through the constant-speed points would cut v = 0 "
        "at the Coulomb level, i.e. at mean Fc, and the B_i would scatter around one value. "
        f"In retraction (speeds {_range(r['speed_range'])} m/s) the line cuts v = 0 at "
        f"{r['line']['intercept']:.1f} N, {r['intercept_minus_breakaway']:.1f} N above mean Fc "
        f"(p = {format_p(r['intercept_vs_breakaway_p'])}); its slope, "
        f"{r['line']['slope']:.0f} Ns/m, is "
        + ("well below" if b_out else "compatible with")
        + f" the two-step mean B ({r['two_step_B_mean']:.0f} Ns/m), and the B_i "
        + ("fall with speed. " if r["B_vs_v_pearson_p"] < ALPHA and r["B_vs_v_pearson_r"] < 0
           else "show no clear trend. ")
        + f"From the break-away level ({r['breakaway_mean']:.1f} N) to the slowest run "
        f"({lo_v:.3f} m/s) the force must rise by about {at_lo - r['breakaway_mean']:.0f} N, "
        f"then by only {at_hi - at_lo:.1f} N more up to {r['speed_range'][1]:.3f} m/s. The "
        "two-step B puts the whole gap between sliding force and break-away force, divided by "
        "the speed, into a viscous term, which is why it falls with speed. In extension the "
        f"ten runs span only {1e3 * (e['speed_range'][1] - e['speed_range'][0]):.0f} mm/s and "
        "cannot separate a and b (the intervals are wide); their force level "
        f"({e['F_mean']:.1f} N at {np.mean(data.v[EXT]):.3f} m/s) sits on the retraction line. "
        "A hand-pushed rod is not at constant speed either: any acceleration adds M a to "
        "F_ext, which the method ignores.")
    _fig_force_speed(out, data, res)
    _fig_b_speed(out, data, res, B)


def _direction(rep: Report, res: dict[str, Any]) -> None:
    dr = res["assumptions"]["direction"]
    rep.section("Do extension and retraction differ?", level=3)
    rep.table(
        ["quantity", "extension - retraction", "p"],
        [["Fc (120 vs 120) [N], Welch", dr["Fc"]["difference"], dr["Fc"]["p"]],
         ["B (10 vs 10) [Ns/m], Welch", dr["B"]["difference"], dr["B"]["p"]],
         ["speed v [m/s], Welch", dr["v"]["difference"], dr["v"]["p"]],
         ["applied force F_ext [N], Welch", dr["F_ext"]["difference"], dr["F_ext"]["p"]],
         ["B at equal speed (B ~ 1 + v + direction) [Ns/m]",
          dr["B_given_speed"]["extension"]["coef"], dr["B_given_speed"]["extension"]["p"]],
         ["F_ext at equal speed (F ~ 1 + v + direction) [N]",
          dr["F_given_speed"]["extension"]["coef"], dr["F_given_speed"]["extension"]["p"]]],
        caption="Extension against retraction (last two rows: t-test of the direction "
                "coefficient of a least-squares fit over all 20 runs).")
    b_eq = dr["B_given_speed"]["extension"]
    rep.paragraph(
        f"Fc: the difference between directions is {significance(dr['Fc']['p'])} "
        f"(p = {format_p(dr['Fc']['p'])}), as the paper says. B: the paper's lower retraction "
        f"coefficient is a {significance(dr['B']['p'])} difference (p = "
        f"{format_p(dr['B']['p'])}), but the applied forces are "
        + ("the same" if dr["F_ext"]["p"] >= ALPHA else "different")
        + f" (p = {format_p(dr['F_ext']['p'])}) while the retraction runs were "
        + ("faster" if dr["v"]["difference"] < 0 else "slower")
        + f" (p = {format_p(dr['v']['p'])}): dividing the same force by a larger speed gives a "
        f"smaller B. At equal speed the direction effect on B is {b_eq['coef']:.1f} Ns/m "
        f"({significance(b_eq['p'])}, p = {format_p(b_eq['p'])}).")


def _uncertainty(rep: Report, res: dict[str, Any]) -> None:
    un = res["assumptions"]["uncertainty_of_B"]
    rep.section("How uncertain is B?", level=3)
    rep.table(
        ["quantity", "extension", "retraction"],
        [["mean B [Ns/m]", un[EXT]["mean_B"], un[RET]["mean_B"]],
         ["standard error from the scatter of the B_i", un[EXT]["se_from_scatter"],
          un[RET]["se_from_scatter"]],
         ["standard error carried from mean Fc", un[EXT]["se_from_Fc"], un[RET]["se_from_Fc"]],
         ["combined standard error (Welch-Satterthwaite dof)",
          f"{un[EXT]['se_total']:.3f} ({un[EXT]['dof']:.1f})",
          f"{un[RET]['se_total']:.3f} ({un[RET]['dof']:.1f})"],
         ["95 % interval with both [Ns/m]", _range(un[EXT]["interval"], 2),
          _range(un[RET]["interval"], 2)],
         ["the paper's interval [Ns/m]", _range(un[EXT]["paper_interval"]),
          _range(un[RET]["paper_interval"])],
         ["d(mean B)/d(Fc) [Ns/m per N]", un[EXT]["dB_dFc"], un[RET]["dB_dFc"]],
         ["mean B with Fc = mean break-away without step 1",
          un[EXT]["mean_B_if_Fc_is_breakaway_without_step1"],
          un[RET]["mean_B_if_Fc_is_breakaway_without_step1"]],
         ["mean B with Fc = intercept of the sliding line",
          un[EXT]["mean_B_if_Fc_is_sliding_intercept"],
          un[RET]["mean_B_if_Fc_is_sliding_intercept"]],
         ["mean bound on |B_i error| from 3-decimal speeds", un[EXT]["speed_rounding_bound_mean"],
          un[RET]["speed_rounding_bound_mean"]]],
        caption="Uncertainty of the two-step B (Ns/m unless stated).")
    widen = max(un[d]["se_total"] / un[d]["se_from_scatter"] - 1 for d in DIRECTIONS)
    rep.paragraph(
        "Table 8 treats mean Fc as exact when it computes the B interval. Carried through, its "
        f"standard error widens the standard error of mean B by at most {100 * widen:.0f} %. "
        "What dominates is the model: every newton by which the Coulomb level differs from "
        f"mean Fc moves mean B by about {abs(un[EXT]['dB_dFc']):.0f} Ns/m, and with the "
        "intercept of the sliding runs as the Coulomb level mean B drops to "
        f"{un[EXT]['mean_B_if_Fc_is_sliding_intercept']:.0f} and "
        f"{un[RET]['mean_B_if_Fc_is_sliding_intercept']:.0f} Ns/m.")


def _conclusion(rep: Report, data: Seed001Data, res: dict[str, Any]) -> None:
    A = res["assumptions"]
    pos, sl = A["position_dependence"], A["sliding_force"]
    t8 = res["table8"]["C1"]
    allF = np.concatenate([data.F_ext[d] for d in DIRECTIONS])
    allv = np.concatenate([data.v[d] for d in DIRECTIONS])
    r = sl[RET]
    ends = r["speed_range"]
    two_step = [t8["Fc_retraction"]["mean"] + t8["B_retraction"]["mean"] * x for x in ends]
    fitted = [r["line"]["intercept"] + r["line"]["slope"] * x for x in ends]
    rep.section("What it means for a control engineer")
    rep.paragraph(
        "The two-step numbers reproduce, but they do not describe one friction law. For a "
        "compensator or a simulation of this cylinder, take the break-away force as the static "
        f"level (mean {pos[EXT]['other_steps_mean']:.1f} N / {pos[RET]['other_steps_mean']:.1f} "
        f"N in extension / retraction, {pos[EXT]['step1_mean']:.1f} N / "
        f"{pos[RET]['step1_mean']:.1f} N after a rest at the stroke end), and take the sliding "
        f"force from the constant-speed runs (mean {allF.mean():.1f} N, standard deviation "
        f"{allF.std(ddof=1):.1f} N, between {allv.min():.3f} and {allv.max():.3f} m/s in both "
        f"directions). In retraction the two-step line Fc + B v gives {two_step[0]:.1f} N at "
        f"{ends[0]:.3f} m/s and {two_step[1]:.1f} N at {ends[1]:.3f} m/s, where the runs "
        f"themselves give {fitted[0]:.1f} N and {fitted[1]:.1f} N"
        + (": it under-predicts the force at the slow end and over-predicts it at the fast "
           "end, and more so beyond them." if two_step[0] < fitted[0] and two_step[1] > fitted[1]
           else ".")
        + " The usual Stribeck picture (break-away above the sliding level) is the opposite of "
        "what these data show: the sliding force lies well above the break-away force, as a "
        "velocity-strengthening seal, or an air-flow (throttling) force through the open ports "
        "and speed-control valves, would make it. Time series, not printed tables, are needed "
        "to tell which; `fcomp diagnose` does that on a measurement.")


# ------------------------------------------------------------------- figures
def _decorate(ax: Any, title: str, xlabel: str, *, legend: bool = False) -> None:
    ax.set_title(title)
    ax.set_xlabel(xlabel)
    ax.grid(alpha=0.3)
    if legend:
        legend_above(ax, ncol=1)


def _fig_table8(out: StudyOutput, res: dict[str, Any]) -> None:
    fig, axes = out.subplots(1, 2, figsize=(11, 3.8))
    for ax, kind, unit in ((axes[0], "Fc", "N"), (axes[1], "B", "Ns/m")):
        labels = []
        for i, (cyl, d) in enumerate([(c, d) for c in CYLINDERS for d in DIRECTIONS]):
            ours = res["table8"][cyl][f"{kind}_{d}"]
            _, lo, hi = PAPER_TABLE8[cyl][f"{kind}_{d}"]
            ax.errorbar(i - 0.12, ours["mean"], yerr=[[ours["mean"] - ours["ci_low"]],
                        [ours["ci_high"] - ours["mean"]]], fmt="o", color="tab:blue",
                        capsize=4, label="computed here" if i == 0 else None)
            ax.errorbar(i + 0.12, (lo + hi) / 2, yerr=(hi - lo) / 2, fmt="s", color="tab:red",
                        capsize=4, label="paper, Table 8" if i == 0 else None)
            labels.append(f"{cyl}\n{d}")
        ax.set_xticks(range(len(labels)), labels)
        ax.set_ylabel(f"{kind} [{unit}] (95 % interval)")
        ax.grid(alpha=0.3)
        legend_above(ax)
    out.figure(fig, "table8",
               "The paper's Table 8: 95 % intervals computed here (blue) and printed (red). C1 "
               "coincide. C2 Fc differs because only the experiment averages are printed (the "
               "interval here is over the 10 averages); C2 B retraction because the paper used "
               "a population standard deviation there.")


def _fig_position(out: StudyOutput, data: Seed001Data, res: dict[str, Any]) -> None:
    pos = res["assumptions"]["position_dependence"]
    steps = np.arange(1, 13)
    fig, axes = out.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, d in zip(axes, DIRECTIONS, strict=True):
        M = data.fc[d]
        ax.boxplot(M.T, positions=steps, widths=0.55, showfliers=False)
        jitter = np.linspace(-0.18, 0.18, M.shape[1])
        for i in range(M.shape[0]):
            ax.plot(steps[i] + jitter, M[i], "o", ms=3.2, alpha=0.6,
                    color="tab:red" if i == 0 else "tab:blue")
        ti = res["table8"]["C1"][f"Fc_{d}"]
        ax.axhspan(ti["ci_low"], ti["ci_high"], color="tab:green", alpha=0.25,
                   label="95 % interval of the mean (Table 8)")
        ax.axhline(ti["mean"], color="tab:green", lw=1.2, label=f"mean {ti['mean']:.3f} N")
        ax.axhline(pos[d]["other_steps_mean"], color="k", ls="--", lw=1,
                   label="mean of steps 2-12")
        _decorate(ax, f"{d} (C1), ANOVA p = {format_p(pos[d]['anova_p'])}",
                  "position step (1 = first break-away from rest at the stroke end)")
    axes[0].set_ylabel("break-away force Fc [N]")
    legend_above(axes[0], ncol=1)
    out.figure(fig, "fc-position",
               "Break-away force of C1 at the 12 positions along the stroke (Tables 2-3; each "
               "dot one experiment, step 1 in red). Green: the mean and its 95 % interval. "
               "Step 1, the first break-away after rest at the stroke end, stands out.")


def _fig_normal(out: StudyOutput, data: Seed001Data, res: dict[str, Any]) -> None:
    from scipy import stats

    nor = res["assumptions"]["normality"]
    fig, axes = out.subplots(1, 2, figsize=(11, 4.0), sharey=True)
    for ax, d in zip(axes, DIRECTIONS, strict=True):
        M = data.fc[d]
        (osm, _osr), _ = stats.probplot(M.ravel(), dist="norm")  # against the sorted values
        values = np.sort(M.ravel(), kind="stable")
        first = np.argsort(M.ravel(), kind="stable") < M.shape[1]  # row 0 = step 1
        ax.plot(osm[~first], values[~first], "o", ms=3.5, label="steps 2-12")
        ax.plot(osm[first], values[first], "^", color="tab:red", ms=4.5, label="step 1")
        ax.plot(osm, M.mean() + M.std(ddof=1) * osm, "k--", lw=1,
                label="normal with the sample mean and std")
        _decorate(ax, f"{d}: Shapiro-Wilk p = {format_p(nor[d]['Fc_shapiro_p'])}",
                  "normal quantile", legend=True)
    axes[0].set_ylabel("break-away force Fc [N]")
    out.figure(fig, "fc-normal",
               "Normal probability plots of the 120 break-away forces per direction (C1). The "
               "upper tail is heavier than normal; step-1 values (red) populate it.")


def _fig_force_speed(out: StudyOutput, data: Seed001Data, res: dict[str, Any]) -> None:
    from scipy import stats

    from fcomp.models import make_model

    sl = res["assumptions"]["sliding_force"]
    t8 = res["table8"]["C1"]
    fig, ax = out.subplots(figsize=(8.5, 5.2))
    model = make_model("coulomb-viscous", params={
        "Fc_pos": t8["Fc_extension"]["mean"], "Fc_neg": t8["Fc_retraction"]["mean"],
        "B_pos": t8["B_extension"]["mean"], "B_neg": t8["B_retraction"]["mean"]})
    vv = np.linspace(0.002, 0.22, 200)
    for sgn in (1.0, -1.0):
        ax.plot(sgn * vv, model.steady_state(sgn * vv), color="tab:green", lw=1.6,
                label="fcomp coulomb-viscous, two-step means" if sgn > 0 else None)
    for d, sgn, col in ((EXT, 1.0, "tab:blue"), (RET, -1.0, "tab:orange")):
        v, F, M = data.v[d], data.F_ext[d], data.fc[d]
        ax.plot(sgn * v, sgn * F, "o", color=col, label=f"{d}: constant-speed runs")
        ax.plot(np.full(M.shape[1], sgn * 0.004), sgn * M[0], "^", color="tab:red", ms=4,
                alpha=0.7, label="break-away, step 1" if d == EXT else None)
        ax.plot(np.full(M[1:].size, sgn * 0.008), sgn * M[1:].ravel(), "_", color=col, ms=6,
                alpha=0.6, label=f"{d}: break-away, steps 2-12")
        line = sl[d]["line"]
        xs = np.linspace(0.0, 0.21, 60)
        X = np.column_stack([np.ones_like(v), v])
        cov = np.linalg.inv(X.T @ X)
        resid = F - (line["intercept"] + line["slope"] * v)
        s2 = float(resid @ resid) / (len(v) - 2)
        band = stats.t.ppf(0.975, len(v) - 2) * np.sqrt(
            s2 * (cov[0, 0] + 2 * cov[0, 1] * xs + cov[1, 1] * xs**2))
        fit = line["intercept"] + line["slope"] * xs
        ax.plot(sgn * xs, sgn * fit, "--", color=col, lw=1.2,
                label=f"{d}: least-squares line through the runs, 95 % band")
        ax.fill_between(sgn * xs, sgn * (fit - band), sgn * (fit + band), color=col, alpha=0.12)
    ax.axhline(0, color="k", lw=0.6)
    ax.axvline(0, color="k", lw=0.6)
    ax.set_xlabel("velocity v [m/s] (extension > 0)")
    ax.set_ylabel("friction force F [N] (opposing extension > 0)")
    ax.set_ylim(-40, 40)
    ax.grid(alpha=0.3)
    legend_above(ax, ncol=2)
    out.figure(fig, "force-speed",
               "C1 friction force against velocity. Green: the Coulomb-viscous model with the "
               "two-step means of Table 8 (fcomp model `coulomb-viscous`). Dots: the "
               "constant-speed runs the B values come from; near v = 0 the break-away forces. "
               "The dashed lines fitted through the runs meet v = 0 far above the break-away "
               "level in retraction.")


def _fig_b_speed(out: StudyOutput, data: Seed001Data, res: dict[str, Any],
                 B: Mapping[str, np.ndarray]) -> None:
    sl = res["assumptions"]["sliding_force"]
    fig, axes = out.subplots(1, 2, figsize=(11, 4.0))
    for ax, d in zip(axes, DIRECTIONS, strict=True):
        s = sl[d]
        ax.plot(data.v[d], B[d], "o", label="two-step B_i")
        trend = ols_line(data.v[d], B[d])
        xs = np.linspace(data.v[d].min(), data.v[d].max(), 20)
        ax.plot(xs, trend["intercept"] + trend["slope"] * xs, "--", color="tab:gray",
                label=f"trend (Pearson r = {s['B_vs_v_pearson_r']:.2f}, "
                      f"p = {format_p(s['B_vs_v_pearson_p'])})")
        ax.axhline(B[d].mean(), color="tab:green", label=f"mean B = {B[d].mean():.1f} Ns/m")
        ax.axhline(s["line"]["slope"], color="tab:purple", ls=":",
                   label=f"slope of F_ext(v) = {s['line']['slope']:.0f} Ns/m")
        _decorate(ax, f"{d} (C1)", "speed v [m/s]", legend=True)
    axes[0].set_ylabel("B [Ns/m]")
    out.figure(fig, "b-speed",
               "Two-step viscous coefficients against the speed of their run (C1). A constant "
               "B would show no trend. Purple: the slope of the force-speed line through the "
               "same runs.")
