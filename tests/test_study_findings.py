"""What the studies conclude and how the site says it (issue 27, items 3-4), without rerunning
the studies: the findings and flags are built from constructed summaries, the index from
constructed runs, the report's lead from a small report."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from studies import STUDIES, compensators, friction_models, missing_physics
from studies import presliding_analysis as pa
from studies import presliding_report as pr
from studies.all import finding_words, study_card, write_index
from studies.base import Finding, Study, StudyConfig, StudyReport


# ------------------------------------------------------------ constructed summaries
def _friction_models_summary(claim: bool) -> dict:
    ratio = {"velocity": 2.6 if claim else 1.2, "force": 2.9 if claim else 1.31,
             "pressure": 2.4 if claim else 1.18}
    return {"claim_reproduced": claim,
            "paper_case": {"ratio_lugre_to_nmlgm": ratio},
            "sweep": [{"sigma1": 3e2, "claim_holds": False}, {"sigma1": 1e5, "claim_holds": True}]}


def _run(finding: Finding | None, *, status: str = "ok", paper: str | None = "A & B (2020)",
         key_figure: str | None = None) -> dict:
    return {"status": status, "finding": None if finding is None else finding.as_dict(),
            "error": None if status == "ok" else "RuntimeError: broke", "seconds": 3.2,
            "cpu_seconds": 1.1, "report": "x/report.html", "summary": "x/summary.json",
            "title": "A study", "paper": paper, "key_figure": key_figure,
            "key_caption": "What it shows, `code`."}


def _diagnosis(final: float, floor: float, verdict: str = "explained") -> dict:
    return {"rms_baseline": 3.3, "rms_final": final, "noise_floor": floor, "verdict": verdict,
            "added": ["force-offset"], "ties": [], "baseline": "coulomb-viscous"}


# ------------------------------------------------------------------ the index
def test_index_says_not_reproduced_in_words_and_red_for_a_failed_claim() -> None:
    f = friction_models.finding(_friction_models_summary(claim=False))
    assert (f.status, f.shown_level) == ("not reproduced", "bad")
    run = _run(f)
    assert finding_words(run) == ("not reproduced", "bad")
    card = study_card("friction-models", run)
    assert card.startswith('<div class="note bad">')
    assert "<strong>Not reproduced.</strong>" in card
    assert "1.20x the NMLGM's in velocity" in card  # the numbers in words, not raw values
    assert "False" not in card and "True" not in card


def test_index_says_reproduced_in_green_and_a_flag_turns_it_amber() -> None:
    from fcomp.conclusions import tone

    ok = friction_models.finding(_friction_models_summary(claim=True))
    # the one colour rule (issue 42): green only when the claim holds *and* the study is sure
    shown = tone("good", ok.confidence)
    assert finding_words(_run(ok)) == ("reproduced", shown)
    assert study_card("friction-models", _run(ok)).startswith(f'<div class="note {shown}">')
    sure = Finding("reproduced", "ok", "It holds.", confidence="high")
    assert finding_words(_run(sure)) == ("reproduced", "ok")
    flagged = Finding("reproduced", "ok", "It holds.", flags=["a number is 10x off"])
    words, level = finding_words(_run(flagged))
    assert level == "warn" and words == "reproduced (1 number to check)"
    card = study_card("x", _run(flagged))
    assert "<strong>Check:</strong> a number is 10x off" in card


def test_index_names_the_paper_links_the_report_and_shows_the_key_figure() -> None:
    f = Finding("partly reproduced", "warn", "Half of it.")
    card = study_card("x", _run(f, paper="Tran, Dao & Yanada (2014), \"Effect\"",
                                key_figure="iVBORw0KGgo="))
    assert "Reproduces Tran, Dao &amp; Yanada (2014)" in card
    assert '<figure><a href="x/report.html"><img src="data:image/png;base64,iVBORw0KGgo="' in card
    assert "<figcaption><strong>Key figure.</strong> What it shows, <code>code</code>." in card
    own = study_card("x", _run(f, paper=None))
    assert "A claim of fcomp's own." in own and "<img" not in own


def test_index_shows_a_study_that_did_not_run_as_failed() -> None:
    run = _run(None, status="failed")
    assert finding_words(run) == ("failed: RuntimeError: broke", "bad")
    rep = StudyReport("index")
    write_index(rep, {"broken": run, "fine": _run(Finding("confirmed", "ok", "Yes."))})
    page = rep.to_html()
    assert "failed: RuntimeError: broke" in page
    assert '<a href="x/report.html">fine</a>' in page and "confirmed" in page
    assert page.count('<div class="note ') == 2


def test_finding_round_trips_and_refuses_an_unknown_colour() -> None:
    f = Finding("not confirmed", "bad", "No.", sure="one seed", next="more", flags=["x"],
                confidence="low")
    assert Finding.from_dict(json.loads(json.dumps(f.as_dict()))) == f
    with pytest.raises(Exception, match="level"):
        Finding("fine", "green", "Yes.")


# ------------------------------------------------------- the report's lead
def test_the_conclusion_opens_the_report_before_the_sections_written_first() -> None:
    rep = StudyReport("t")
    rep.section("Method").paragraph("how").section("Results").paragraph("what")
    rep.section("Parameters").paragraph("values")
    rep.lead(Finding("partly reproduced", "warn", "Two of three claims hold.",
                     sure="assumed parameters", next="measure", flags=["x is 10x off"],
                     confidence="high"))
    page = rep.to_html()
    body = page[page.index("</nav>"):]
    assert body.index("Two of three claims hold") < body.index("Method") < body.index("Results")
    # the form every command's report opens with (fcomp.report.Report.conclusion); a flag
    # makes a high confidence medium
    assert ('<div class="note warn conclusion"><p><strong>Conclusion:</strong> Partly '
            "reproduced. Two of three claims hold.</p><p><strong>How sure:</strong> medium, "
            "because</p><ul><li>x is 10x off</li><li>assumed parameters</li></ul>") in page
    assert "<p><strong>Next:</strong></p><ul><li>measure</li></ul>" in page


def test_a_finding_reads_as_a_command_conclusion() -> None:
    c = Finding("not reproduced", "bad", "It fails.", sure="one seed", next="rerun",
                confidence="low").conclusion()
    assert c.lines() == ["Conclusion: Not reproduced. It fails.", "How sure: low, because",
                         "  - one seed", "Next:", "  - rerun"]
    with pytest.raises(Exception, match="confidence"):
        Finding("fine", "ok", "Yes.", confidence="certain")


class _Claimed(Study):
    name = "claimed-test"
    title = "Claimed"
    summary = "a study with a failed claim"
    paper = "Someone (1999), \"A claim\""

    def build(self, out, config):
        out.report.section("Details").paragraph("the details")
        fig, ax = out.subplots()
        ax.plot([0, 1], [1, 0])
        out.figure(fig, "key", "the key figure")
        return {"claim": False}

    def finding(self, results):
        return Finding("not reproduced", "bad", "The claim fails here.")

    def key_figure(self, results):
        return "key"


def test_study_all_index_shows_the_finding_the_paper_and_the_key_figure(
        tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(STUDIES, "_items", {"all": STUDIES.get("all"),
                                            "claimed-test": _Claimed()})
    s = STUDIES.get("all").main(StudyConfig(out=tmp_path, fast=True))
    sub = json.loads((tmp_path / "claimed-test" / "summary.json").read_text())
    assert sub["meta"]["finding"]["status"] == "not reproduced"
    assert sub["meta"]["key_figure"] == "fig-key.png" and sub["meta"]["paper"].startswith("Some")
    report = (tmp_path / "claimed-test" / "report.html").read_text()
    assert report.index("The claim fails here.") < report.index("Details")
    index = (tmp_path / "index.html").read_text()
    assert '<div class="note bad"><p><strong>Not reproduced.</strong>' in index
    assert "Reproduces Someone (1999)" in index
    assert '<a href="claimed-test/report.html"><img src="data:image/png;base64,' in index
    assert "key_figure" not in s["studies"]["claimed-test"]  # the page holds it, not the JSON
    png = (tmp_path / "claimed-test" / "fig-key.png").read_bytes()
    import base64

    assert base64.b64encode(png).decode() in index  # the figure itself, its font record kept
    assert "<strong>Key figure.</strong> the key figure" in index


# ------------------------------------------------------------ presliding
def _fig4(x_peak_new: float, x_peak_nmlgm: float) -> dict:
    def run(x):
        return {"x_peak": x, "x_final": 0.0, "slides": False}

    return {"1": [{"p1_max": 0.017e6, "nmlgm-hysteresis": run(x_peak_new),
                   "nmlgm": run(x_peak_nmlgm),
                   "paper": {"x_peak": 0.07e-3, "x_final": 0.0, "slides": False}}]}


def test_presliding_flags_a_tenfold_mismatch_with_the_paper_and_not_less() -> None:
    flags = pa.paper_mismatches(_fig4(0.713e-3, 0.5e-3))
    assert [(m["model"], m["quantity"]) for m in flags] == [("nmlgm-hysteresis", "x_peak")]
    assert flags[0]["ratio"] == pytest.approx(10.19, abs=0.01)
    text = pa.mismatch_flags(flags)
    assert text[0] == ("Fig. 4 (cylinder 1, p1 = 0.017 MPa): peak displacement 0.713 mm (new "
                       "model) against the paper's 0.070 mm, 10.2x")
    assert len(text) == 2 and "10-fold or larger mismatch" in text[1]
    both = pa.mismatch_flags(pa.paper_mismatches(_fig4(0.713e-3, 0.95e-3)))
    assert len(both) == 2 and "0.950 mm (NMLGM) and 0.713 mm (new model)" in both[0]
    assert pa.mismatch_flags([]) == []
    assert pa.paper_mismatches(_fig4(0.69e-3, 0.5e-3)) == []  # 9.9x: not flagged
    assert pa.paper_mismatches(_fig4(0.006e-3, 0.07e-3))[0]["ratio"] < 0.1  # 10x too small
    # the paper's zero (back to 0 after release) has no ratio: never a flag
    assert pa.mismatch(0.3e-3, 0.0) is None and pa.mismatch(0.3e-3, None) is None


def test_presliding_table_and_conclusion_carry_the_flag() -> None:
    f4 = _fig4(0.713e-3, 0.95e-3)["1"][0]
    assert pr._against_paper(f4, f4["paper"]) == "peak displacement 10-14x off: check"
    assert pr._against_paper(f4, {}) == "-"
    ok = _fig4(0.1e-3, 0.2e-3)["1"][0]
    assert pr._against_paper(ok, ok["paper"]) == "within 10x"
    res = {"nmlgm": {"minor_loops_closed": False, "wiping_out": False, "loop_area_error": -0.19,
                     "force_rms_error": 0.8},
           "nmlgm-hysteresis": {"minor_loops_closed": True, "wiping_out": False,
                                "loop_area_error": -0.004},
           "loop_size_vs_pressure": [[1e4, 0.8e-3], [2e4, 1.0e-3]],
           "paper_mismatches": pa.paper_mismatches(_fig4(0.713e-3, 0.5e-3))}
    f = pa.finding(res)
    assert (f.status, f.shown_level) == ("partly reproduced", "warn")
    assert "not shown: it wipes out internal loops" in f.found
    assert len(f.flags) == 2 and "10.2x" in f.flags[0]


# ------------------------------------------------------ missing physics
def test_missing_physics_flags_a_held_out_error_below_the_noise_floor() -> None:
    low = {"case": "zillen-o-ring", "file": "O-ring_3bar.csv",
           "diagnosis": _diagnosis(0.23, 0.417)}
    flag = missing_physics.below_floor(low)
    assert flag is not None and "0.230 N" in flag and "0.417 N" in flag and "45 %" in flag
    assert "over-fits" in flag and "not confirmed" in flag
    assert missing_physics._verdict(low) == "explained (below the noise floor: check)"
    # the threshold of every command's conclusion (fcomp.conclusions): 0.8 x the floor
    assert missing_physics.below_floor({"case": "c", "diagnosis": _diagnosis(0.32, 0.417)})
    at_floor = {"case": "c", "diagnosis": _diagnosis(0.35, 0.417)}
    assert missing_physics.below_floor(at_floor) is None  # within the floor's own scatter
    assert missing_physics._verdict(at_floor) == "explained"
    gen = {"case": "generated-x", "hidden": "x", "recovered": True, "true_noise_std": 0.4,
           "diagnosis": _diagnosis(0.49, 0.398)}
    f = missing_physics.finding({"generated": [gen], "real": [low]})
    assert (f.status, f.shown_level) == ("confirmed", "warn")  # recovered, but a flag
    assert f.flags == (flag,) and f.confidence == "medium"
    clean = missing_physics.finding({"generated": [gen], "real": []})
    assert not clean.flags  # no flag: its colour is what it says and how sure (issue 42)
    assert clean.shown_level == {"high": "ok", "medium": "warn"}[clean.confidence]


def test_the_stretch_figure_breaks_its_lines_at_gaps_and_experiment_boundaries() -> None:
    from fcomp import figstyle

    t = np.array([0.0, 0.01, 0.02, 0.03, 0.5, 0.51, 0.52, 0.53])
    tt, y = figstyle.break_gaps(t, t * 2.0, starts=[2])
    pieces = [p for p in np.split(tt, np.flatnonzero(np.isnan(tt))) if np.isfinite(p).any()]
    assert [p[np.isfinite(p)].tolist() for p in pieces] == [[0.0, 0.01], [0.02, 0.03],
                                                           [0.5, 0.51, 0.52, 0.53]]
    assert np.array_equal(np.isnan(tt), np.isnan(y))


# --------------------------------------------------------- compensators
def _row(plant: str, controller: str, task: str, rms: float) -> dict:
    return {"plant": plant, "controller": controller, "task": task, "rms_error": rms,
            "status": "ok"}


def test_compensators_explain_a_feed_forward_worse_than_pid() -> None:
    rows = [_row("pneumatic", "pid", t, 1e-4) for t in ("a", "b", "c")]
    rows += [_row("pneumatic", "pid-ff", "a", 3.4e-4), _row("pneumatic", "pid-ff", "b", 1.8e-4),
             _row("pneumatic", "pid-ff", "c", 0.5e-4),
             _row("hydraulic", "pid", "a", 1e-4), _row("hydraulic", "pid-ff", "a", 0.5e-4)]
    flags = compensators.worse_than_pid(rows, ["hydraulic", "pneumatic"])
    assert len(flags) == 1
    assert "pneumatic plant: 1.8-3.4x its RMS error on 2 of 3 tasks (a, b)" in flags[0]
    assert "*" not in flags[0] and "wrong sign" in flags[0]
    assert compensators.worse_than_pid(rows, ["hydraulic"]) == []


def test_compensators_finding_counts_the_halved_pairs() -> None:
    verdict = {"h/slow": {"best": "ekf", "ratio": 0.22, "halved": True},
               "p/slow": {"best": "mpc", "ratio": 0.7, "halved": False}}
    res = {"verdict": verdict, "results": [_row("p", "pid", "slow", 1.0)],
           "robustness_draws": {"p": {"draws": 12, "decisions": {"ekf": {"interval": [0.1, 0.3]}}}}}
    f = compensators.CompensatorsStudy().finding(res)
    assert (f.status, f.level) == ("partly confirmed", "warn")
    assert "1 of 2 plant/task pairs" in f.found and "ekf 22 %" in f.found


def test_compensators_settings_give_the_valve_command_its_unit() -> None:
    plants = compensators.study_plants(StudyConfig(out=Path("unused")))
    rows = {r[0]: r[1:] for r in compensators.settings_rows(plants)}
    assert rows["valve command limit u_max"] == ["0.01 A", "1 (normalised: full opening)"]
    assert all(name.endswith("]") for name in rows if name != "valve command limit u_max")


# ------------------------------------------------------- friction models
def test_spectrum_axis_stops_at_the_useful_range() -> None:
    P = np.concatenate([np.logspace(-2, -7, 200), np.full(20, 1e-23)])
    low, top = friction_models.psd_limits(P)
    assert top == pytest.approx(1e-2) and low >= 1e-2 * 10 ** -friction_models.PSD_DECADES
    assert low <= 1e-7  # the curves themselves stay inside
    assert friction_models.psd_limits(np.logspace(-3, -5, 50)) == (pytest.approx(1e-5),
                                                                   pytest.approx(1e-3))


def test_sweep_map_is_green_where_the_claim_holds(tmp_path: Path) -> None:
    from studies.base import StudyOutput

    sweep = [{"sigma0": 2e6, "sigma1": s1, "ratio_to_nmlgm": {"velocity": r, "force": r,
                                                              "pressure": r}}
             for s1, r in ((3e2, 0.8), (3e4, 1.3), (1e5, 2.6))]
    out = StudyOutput(tmp_path, StudyReport("t"))
    captured = {}
    out.figure = lambda fig, name, caption: captured.update(fig=fig)  # type: ignore[method-assign]
    friction_models._fig_sweep(out, {"sweep": sweep})
    ax = captured["fig"].axes[0]
    im = ax.images[0]
    rgba = im.cmap(im.norm(np.array([0.8, 1.3, 2.6])))
    green = tuple(int(friction_models.CLAIM_COLORS["ok"][i:i + 2], 16) / 255 for i in (1, 3, 5))
    red = tuple(int(friction_models.CLAIM_COLORS["bad"][i:i + 2], 16) / 255 for i in (1, 3, 5))
    assert tuple(rgba[2][:3]) == pytest.approx(green) and tuple(rgba[0][:3]) == pytest.approx(red)
    words = [t.get_text() for t in ax.texts]
    assert words == ["0.80\nfails", "1.30\nfails", "2.60\nholds"]


def test_study_figures_are_column_wide_at_most_and_their_text_9pt_or_more(tmp_path: Path) -> None:
    from fcomp import figstyle
    from fcomp.figstyle import legend_above
    from studies.base import StudyOutput

    out = StudyOutput(tmp_path, StudyReport("t"))
    fig, axes = out.subplots(1, 2, figsize=(12.0, 4.0), sharey=True)
    assert tuple(fig.get_size_inches()) == pytest.approx((figstyle.WIDTH, 4.0 * 9.5 / 12.0))
    axes[0].plot([0, 1], [0, 1], label="a line")
    axes[0].set_title("a title")
    axes[0].text(0.5, 0.5, "small", fontsize=6)
    legend = legend_above(axes[0], ncol=1)
    assert axes[0].get_title() == "" and legend.get_title().get_text() == "a title"
    path = out.figure(fig, "wide", "a wide figure")
    rec = figstyle.read_record(path.read_bytes())
    assert float(rec[figstyle.KEY_MIN_FONT]) >= figstyle.FONT_MIN
    assert figstyle.check_readable(path.read_bytes()) is None


def test_the_study_command_prints_its_finding_first(tmp_path, capsys) -> None:
    from fcomp.cli.main import main

    assert main(["study", "coulomb-viscous", "--fast", "--out", str(tmp_path / "cv"),
                 "--no-progress"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("Conclusion: Partly reproduced. Table 8 (cylinder C1): 12 of 12 ")
    assert out[1].startswith("How sure: high")
    assert out[-1].startswith("wrote ")
