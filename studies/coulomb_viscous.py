"""Study ``coulomb-viscous``: seed 001 reproduced, then its assumptions tested on its own data.

Seed 001 (Dağdelen & Sarıgeçili 2020) identifies the Coulomb-viscous model
``F_ext = Fc + B*v`` (seed 001 Eqs. 4-5) of a pneumatic cylinder pushed by
hand. The study runs the analysis of :mod:`studies.coulomb_viscous_analysis`
(Table 8 recomputed, the paper's assumptions tested on its own data) and
writes the report of :mod:`studies.coulomb_viscous_report`; docs/seed001.md
summarises the results.
"""

from __future__ import annotations

from typing import Any

import studies.coulomb_viscous_analysis as cva
from studies.base import Finding, Study, StudyConfig, StudyOutput
from studies.coulomb_viscous_report import write_report


class CoulombViscousStudy(Study):
    """Seed 001 Table 8 reproduced, and the Coulomb-viscous assumptions tested."""

    name = "coulomb-viscous"
    title = ("Coulomb-viscous friction of two pneumatic cylinders: Dağdelen & Sarıgeçili "
             "(2020) reproduced")
    summary = ("Dağdelen & Sarıgeçili (2020): the two-step estimates and Table 8 recomputed "
               "from the paper's tables, and the paper's assumptions tested on its own data.")
    paper = ("Dağdelen & Sarıgeçili (2020), \"Estimation of the friction parameters of linear "
             "pneumatic cylinders\", J. Eng. Sci. Design 8(2)")
    # "Table N" in the text is the paper's; the report's own tables say so
    table_label = "Report table"

    def headline(self, results: dict[str, Any]) -> str:
        rows = [r for r in results["reproduction"]["comparisons"] if r["cylinder"] == "C1"]
        return (f"Table 8, C1: {sum(r['match'] for r in rows)} of {len(rows)} numbers equal "
                "to the printed digits")

    def finding(self, results: dict[str, Any]) -> Finding:
        rows = [r for r in results["reproduction"]["comparisons"] if r["cylinder"] == "C1"]
        n_match = sum(r["match"] for r in rows)
        sliding = results["assumptions"]["sliding_force"]
        off = {d: s for d, s in sliding.items() if s["intercept_vs_breakaway_p"] < cva.ALPHA}
        numbers = (f"Table 8 (cylinder C1): {n_match} of {len(rows)} numbers recomputed to the "
                   "printed digits from the paper's own tables")
        if off:
            model = ("; but the model behind them does not describe the paper's runs: in "
                     + " and ".join(off) + " the constant-speed forces extrapolate to "
                     + " and ".join(f"{s['line']['intercept']:.1f} N" for s in off.values())
                     + " at v = 0, against a break-away force of "
                     + " and ".join(f"{s['breakaway_mean']:.1f} N" for s in off.values())
                     + ": the break-away force is not the Coulomb level of the sliding force")
        else:
            model = "; the paper's Coulomb-viscous assumptions are not contradicted by its data"
        whole = n_match == len(rows)
        status, level = (("reproduced", "ok") if whole and not off else
                         ("partly reproduced", "warn") if n_match else ("not reproduced", "bad"))
        return Finding(
            status, level, numbers + model + ".",
            sure=f"the arithmetic is exact (the paper's printed single values); the tests of its "
                 f"assumptions use {100 * cva.LEVEL:g} % intervals and a significance level of "
                 f"{cva.ALPHA:g} on 10 constant-speed runs per direction -- few runs, but the "
                 "retraction result is significant.",
            next="for a compensator or a simulation take the break-away force as the static "
                 "level and the sliding force from the constant-speed runs (section \"What it "
                 "means for a control engineer\"); on a time series, fcomp diagnose tells "
                 "which law the seal follows.",
            confidence="high")

    def key_figure(self, results: dict[str, Any]) -> str | None:
        return "force-speed"

    def build(self, out: StudyOutput, config: StudyConfig) -> dict[str, Any]:
        # the study is small: the fast mode runs it in full
        data = cva.load_seed001()
        t8 = cva.table8(data)
        B = {d: cva.two_step_B(data.F_ext[d], data.v[d], data.fc[d].mean(), data.B_printed[d])[0]
             for d in cva.DIRECTIONS}
        variants = []
        for dec in (cva.T_TABLE_DECIMALS, None):
            for bv in ("reconstructed", "printed", "recomputed"):
                rows = cva.reproduction(cva.table8(data, decimals=dec, b_values=bv))
                c1 = [r for r in rows if r["cylinder"] == "C1"]
                variants.append({
                    "t": "3-decimal table" if dec is not None else "exact",
                    "B_values": bv, "C1_matches": sum(r["match"] for r in c1),
                    "C1_numbers": len(c1),
                    "C1_max_abs_difference": max(abs(r["computed"] - r["paper"]) for r in c1),
                    "C1_differing": [f"{r['parameter']} {r['field']}: {r['computed']:.4f} "
                                     f"(paper {r['paper']:.3f})" for r in c1 if not r["match"]],
                })
        comparisons = cva.reproduction(t8)
        results: dict[str, Any] = {
            "table8": {cyl: {p: cva.summary_fields(t8[cyl][p]) for p in cva.PARAMETERS} for cyl in cva.CYLINDERS},
            "paper": {
                "table8": {cyl: {p: dict(zip(cva.FIELDS, cva.PAPER_TABLE8[cyl][p], strict=True))
                                 for p in cva.PARAMETERS} for cyl in cva.CYLINDERS},
                "means": cva.PAPER_MEANS,
            },
            "table8_details": {cyl: {p: {k: v for k, v in t8[cyl][p].items()}
                                     for p in cva.PARAMETERS} for cyl in cva.CYLINDERS},
            "reproduction": {
                "C1_matches_printed_digits": all(r["match"] for r in comparisons
                                                 if r["cylinder"] == "C1"),
                "comparisons": comparisons,
                "variants": variants,
                "transcription": cva.transcription_checks(data),
            },
            "two_step_B": cva.printed_speeds(data),
            "c2_reconstruction": cva.c2_reconstruction(data),
            "assumptions": {
                "position_dependence": {d: cva.position_dependence(data.fc[d]) for d in cva.DIRECTIONS},
                "independence": {d: cva.independence(data.fc[d]) for d in cva.DIRECTIONS},
                "normality": cva.normality(data, B),
                "sliding_force": cva.sliding_force(data, B),
                "direction": cva.direction_difference(data, B),
                "uncertainty_of_B": cva.uncertainty_of_B(data, B),
            },
            "settings": {"level": cva.LEVEL, "alpha": cva.ALPHA, "t_table_decimals": cva.T_TABLE_DECIMALS,
                         "B_consistency_tol": cva.B_CONSISTENCY_TOL, "units": {
                             "Fc": "N", "B": "Ns/m", "F_ext": "N", "v": "m/s"}},
        }
        results["findings"] = cva.findings(results)
        write_report(out, data, results, B)
        return results


STUDY = CoulombViscousStudy()
main = STUDY.main
