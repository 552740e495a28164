"""Study ``coulomb-viscous``: seed 001 Table 8 reproduced, assumptions tested, report written.

The expected numbers are the paper's Table 8 as printed (typed here, not taken
from the module), and every statistic is checked against an independent
computation (numpy / scipy / least squares written out here).
"""

from __future__ import annotations

import io
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from fcomp import datasets
from studies import STUDIES
from studies import coulomb_viscous as cv_study
from studies import coulomb_viscous_analysis as cv
from studies.base import StudyConfig, StudyError

# seed 001 Table 8 as printed: std, lower limit, upper limit
TABLE8_C1 = {
    "Fc_extension": (1.225, 5.265, 5.708),
    "Fc_retraction": (1.275, 5.056, 5.516),
    "B_extension": (10.701, 95.774, 111.083),
    "B_retraction": (13.308, 75.395, 94.433),
}
TABLE8_C2 = {
    "Fc_extension": (1.605, 6.156, 6.736),
    "Fc_retraction": (2.216, 6.292, 7.093),
    "B_extension": (4.482, 44.475, 50.887),
    "B_retraction": (3.811, 42.662, 48.114),
}


def _cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "fcomp.cli.main", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300)


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict, str]:
    out = tmp_path_factory.mktemp("cv") / "out"
    proc = _cli("study", "coulomb-viscous", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    assert "summary.json" in proc.stdout
    summary = json.loads((out / "summary.json").read_text())
    return out, summary, (out / "report.html").read_text(encoding="utf-8")


def _table(name: str) -> np.ndarray:
    return np.genfromtxt(datasets.path("seed001", name), delimiter=",", names=True)


# ------------------------------------------------------------------ contract
def test_summary_contract_keys(run) -> None:
    _, s, _ = run
    assert set(s["table8"]) == {"C1", "C2"}
    for cyl in ("C1", "C2"):
        assert set(s["table8"][cyl]) == {"Fc_extension", "Fc_retraction", "B_extension",
                                         "B_retraction"}
        for entry in s["table8"][cyl].values():
            assert set(entry) == {"mean", "std", "ci_low", "ci_high"}
            assert all(isinstance(v, float) and math.isfinite(v) for v in entry.values())
            assert entry["ci_low"] < entry["mean"] < entry["ci_high"]
            assert entry["std"] > 0
            assert entry["mean"] - entry["ci_low"] == pytest.approx(
                entry["ci_high"] - entry["mean"], rel=1e-12)


def test_table8_c1_to_the_printed_digits(run) -> None:
    _, s, _ = run
    for par, printed in TABLE8_C1.items():
        got = s["table8"]["C1"][par]
        for field, value in zip(("std", "ci_low", "ci_high"), printed, strict=True):
            assert f"{got[field]:.3f}" == f"{value:.3f}", (par, field, got[field], value)
    assert s["reproduction"]["C1_matches_printed_digits"] is True


def test_c2_what_is_reproducible(run) -> None:
    _, s, _ = run
    # C2 B extension: Table 7 gives the printed numbers directly
    for field, value in zip(("std", "ci_low", "ci_high"), TABLE8_C2["B_extension"], strict=True):
        assert f"{s['table8']['C2']['B_extension'][field]:.3f}" == f"{value:.3f}"
    # C2 B retraction: the print used the population std; the study reports the sample std
    b = _table("c2_b.csv")["B_retraction"]
    assert s["table8"]["C2"]["B_retraction"]["std"] == pytest.approx(np.std(b, ddof=1), rel=1e-12)
    rec = s["c2_reconstruction"]["B_retraction"]
    assert rec["paper_std_is"] == "population (n)"
    assert f"{rec['population_std']:.3f}" == "3.811"
    assert [f"{x:.3f}" for x in rec["interval_with_that_std"]] == ["42.662", "48.114"]
    # C2 Fc: only averages are printed; the printed widths imply 120 single values
    for d in ("extension", "retraction"):
        n = s["c2_reconstruction"][f"Fc_{d}"]["implied_n"]
        assert n["n_min"] <= 120 <= n["n_max"] and abs(n["n"] - 120) < 0.5
        avg = _table("c2_fc.csv")[f"Fc_{d}"]
        assert s["table8"]["C2"][f"Fc_{d}"]["mean"] == pytest.approx(avg.mean(), rel=1e-12)


# ------------------------------------------------------ independent checks
def test_c1_statistics_against_an_independent_computation(run) -> None:
    """numpy mean/std and scipy's exact t interval: equal to the study up to the t rounding."""
    _, s, _ = run
    for d in ("extension", "retraction"):
        fc = _table(f"fc_{d}_c1.csv")["Fc"]
        assert fc.size == 120
        got = s["table8"]["C1"][f"Fc_{d}"]
        assert got["mean"] == pytest.approx(fc.mean(), rel=1e-13)
        assert got["std"] == pytest.approx(fc.std(ddof=1), rel=1e-13)
        lo, hi = stats.t.interval(0.95, fc.size - 1, loc=fc.mean(), scale=stats.sem(fc))
        # 1.980 instead of 1.98010 changes the half-width by 1e-4 * s / sqrt(n)
        assert got["ci_low"] == pytest.approx(lo, abs=2e-5)
        assert got["ci_high"] == pytest.approx(hi, abs=2e-5)
        b = _table(f"b_{d}_c1.csv")
        B = (b["F_ext"] - fc.mean()) / b["v"]
        keep = np.abs(B - b["B_reported"]) < 0.01
        assert keep.sum() >= 7  # most printed speeds reproduce the printed B_i
        B = np.where(keep, B, b["B_reported"])
        gotB = s["table8"]["C1"][f"B_{d}"]
        assert gotB["mean"] == pytest.approx(B.mean(), rel=1e-13)
        assert gotB["std"] == pytest.approx(B.std(ddof=1), rel=1e-13)
        lo, hi = stats.t.interval(0.95, 9, loc=B.mean(), scale=stats.sem(B))
        assert got["ci_low"] < got["mean"] < got["ci_high"]
        assert gotB["ci_low"] == pytest.approx(lo, abs=2e-3)
        assert gotB["ci_high"] == pytest.approx(hi, abs=2e-3)


def test_exact_t_differs_from_the_print_only_in_the_last_digit(run) -> None:
    _, s, _ = run
    exact = [v for v in s["reproduction"]["variants"]
             if v["t"] == "exact" and v["B_values"] == "printed"][0]
    assert exact["C1_max_abs_difference"] < 2e-3
    table = [v for v in s["reproduction"]["variants"]
             if v["t"] == "3-decimal table" and v["B_values"] == "reconstructed"][0]
    assert table["C1_matches"] == table["C1_numbers"] == 12


def test_t_interval_and_quantile() -> None:
    rng = np.random.default_rng(3)
    x = rng.normal(2.0, 0.5, 17)
    ti = cv.t_interval(x, decimals=None)
    lo, hi = stats.t.interval(0.95, 16, loc=x.mean(), scale=stats.sem(x))
    assert (ti["ci_low"], ti["ci_high"]) == pytest.approx((lo, hi), rel=1e-12)
    assert cv.t_quantile(9) == 2.262 and cv.t_quantile(119) == 1.980
    pop = cv.t_interval(x, decimals=None, ddof=0)
    assert pop["std"] == pytest.approx(x.std(), rel=1e-12)


def test_implied_sample_size_recovers_n() -> None:
    for n in (10, 37, 120):
        s = 1.3
        half = stats.t.ppf(0.975, n - 1) * s / math.sqrt(n)
        got = cv.implied_sample_size(s, 5.0 - half, 5.0 + half)
        assert got["n"] == pytest.approx(n, rel=1e-6)
        assert got["n_min"] < n < got["n_max"]


def test_two_way_anova_against_regression_f_test() -> None:
    """The closed-form two-way ANOVA equals nested least-squares models with dummies."""
    rng = np.random.default_rng(7)
    a, b = 6, 5
    M = rng.normal(size=(a, b)) + np.linspace(0, 1, a)[:, None]
    y = M.ravel()
    rows = np.repeat(np.arange(a), b)
    cols = np.tile(np.arange(b), a)
    R = (rows[:, None] == np.arange(1, a)).astype(float)
    C = (cols[:, None] == np.arange(1, b)).astype(float)
    one = np.ones((y.size, 1))

    def rss(X: np.ndarray) -> float:
        beta, *_ = np.linalg.lstsq(X, y, rcond=None)
        r = y - X @ beta
        return float(r @ r)

    full = rss(np.hstack([one, R, C]))
    df_e = (a - 1) * (b - 1)
    F_rows = (rss(np.hstack([one, C])) - full) / (a - 1) / (full / df_e)
    F_cols = (rss(np.hstack([one, R])) - full) / (b - 1) / (full / df_e)
    got = cv.two_way_anova(M)
    assert got["F_rows"] == pytest.approx(F_rows, rel=1e-10)
    assert got["F_cols"] == pytest.approx(F_cols, rel=1e-10)
    assert got["p_rows"] == pytest.approx(stats.f.sf(F_rows, a - 1, df_e), rel=1e-10)


def test_intraclass_correlation_limits() -> None:
    rng = np.random.default_rng(11)
    clustered = np.tile(rng.normal(size=10), (12, 1)) + 1e-6 * rng.normal(size=(12, 10))
    assert cv.intraclass_correlation(clustered) == pytest.approx(1.0, abs=1e-6)
    noise = rng.normal(size=(12, 400))
    assert abs(cv.intraclass_correlation(noise)) < 0.02


def test_linear_model_matches_linregress() -> None:
    rng = np.random.default_rng(5)
    x = rng.uniform(0.1, 0.2, 12)
    y = 12.0 + 30.0 * x + rng.normal(0, 0.5, 12)
    lm = cv.linear_model(np.column_stack([np.ones(12), x]), y, ("a", "b"))
    ref = stats.linregress(x, y)
    assert lm["b"]["coef"] == pytest.approx(ref.slope, rel=1e-10)
    assert lm["b"]["se"] == pytest.approx(ref.stderr, rel=1e-10)
    assert lm["b"]["p"] == pytest.approx(ref.pvalue, rel=1e-8)
    assert lm["a"]["se"] == pytest.approx(ref.intercept_stderr, rel=1e-10)


def test_assumption_results_against_independent_computations(run) -> None:
    _, s, _ = run
    A = s["assumptions"]
    for d in ("extension", "retraction"):
        t = _table(f"fc_{d}_c1.csv")
        M = np.zeros((12, 10))
        M[t["position_step"].astype(int) - 1, t["experiment"].astype(int) - 1] = t["Fc"]
        p = A["position_dependence"][d]
        assert p["anova_p"] == pytest.approx(stats.f_oneway(*M).pvalue, rel=1e-10)
        assert p["kruskal_p"] == pytest.approx(stats.kruskal(*M).pvalue, rel=1e-10)
        assert p["step1_excess"] == pytest.approx(M[0].mean() - M[1:].mean(), rel=1e-12)
        # Welch t-test written out
        a, r = M[0], M[1:].ravel()
        va, vr = a.var(ddof=1) / a.size, r.var(ddof=1) / r.size
        tw = (a.mean() - r.mean()) / math.sqrt(va + vr)
        dof = (va + vr) ** 2 / (va**2 / (a.size - 1) + vr**2 / (r.size - 1))
        assert p["step1_welch_p"] == pytest.approx(2 * stats.t.sf(abs(tw), dof), rel=1e-8)
        # the line through the constant-speed runs
        b = _table(f"b_{d}_c1.csv")
        slope, intercept = np.polyfit(b["v"], b["F_ext"], 1)
        line = A["sliding_force"][d]["line"]
        assert line["slope"] == pytest.approx(slope, rel=1e-9)
        assert line["intercept"] == pytest.approx(intercept, rel=1e-9)
        # uncertainty of mean B: Var = s_B^2/n + (mean 1/v)^2 s_Fc^2/N
        B = np.array(s["two_step_B"][d]["B_used"])
        se = math.sqrt(B.var(ddof=1) / 10 + np.mean(1 / b["v"]) ** 2 * M.var(ddof=1) / 120)
        assert A["uncertainty_of_B"][d]["se_total"] == pytest.approx(se, rel=1e-12)
        assert A["uncertainty_of_B"][d]["dB_dFc"] == pytest.approx(-np.mean(1 / b["v"]))


def test_uncertainty_propagation_by_monte_carlo(run) -> None:
    """Simulating the two steps (shared Fc estimate, scattered B_i) gives the propagated error."""
    _, s, _ = run
    rng = np.random.default_rng(2)
    d = "extension"
    b = _table(f"b_{d}_c1.csv")
    fc = _table(f"fc_{d}_c1.csv")["Fc"]
    s_B = np.std(s["two_step_B"][d]["B_used"], ddof=1)
    K = 20000
    fc_mean = rng.normal(fc.mean(), fc.std(ddof=1), (K, fc.size)).mean(axis=1)  # step 1, redone
    B_i = ((b["F_ext"][None, :] - fc_mean[:, None]) / b["v"][None, :]
           + rng.normal(0.0, s_B, (K, b["v"].size)))  # step 2 with the scatter of the B_i
    means = B_i.mean(axis=1)
    se = s["assumptions"]["uncertainty_of_B"][d]["se_total"]
    assert np.std(means) == pytest.approx(se, rel=0.03)


def test_findings_follow_the_tests(run) -> None:
    _, s, _ = run
    A = s["assumptions"]
    # the position effect sits in step 1
    for d in ("extension", "retraction"):
        assert A["position_dependence"][d]["anova_p"] < 0.05
        assert A["position_dependence"][d]["anova_p_without_step1"] > 0.05
        assert A["position_dependence"][d]["step1_excess"] > 1.0
    ret = A["sliding_force"]["retraction"]
    assert ret["line"]["intercept_ci"][0] > ret["breakaway_mean"]
    assert ret["B_vs_v_pearson_r"] < 0 and ret["B_vs_v_pearson_p"] < 0.05
    assert A["direction"]["F_ext"]["p"] > 0.05 and A["direction"]["B"]["p"] < 0.05
    text = " ".join(s["findings"])
    assert "not the Coulomb level" in text and "fall with speed" in text


# ------------------------------------------------------------------- report
def test_report_files_and_self_containment(run) -> None:
    out, s, html = run
    from test_report import check_html

    check_html(html)
    figures = sorted(p.name for p in out.glob("fig-*.png"))
    assert figures == sorted(s["meta"]["figures"]) and len(figures) >= 4
    for f in figures:
        assert (out / f).read_bytes().startswith(b"\x89PNG")
    assert html.count("data:image/png;base64,") == len(figures)
    assert not re.search(r"(src|href)\s*=\s*[\"']?\s*(https?:)?//", html, re.I)
    # every printed C1 number stands beside the computed one
    for par, printed in TABLE8_C1.items():
        for value in printed:
            assert re.search(rf"<td>{value:.3f}</td><td>{value:.3f}</td>", html), (par, value)
    assert "population std" in html and "fcomp study coulomb-viscous --out" in html
    assert s["meta"]["study"] == "coulomb-viscous" and not list(out.glob(".*.tmp"))


def test_fast_mode_and_config_mapping(run, tmp_path: Path) -> None:
    s = cv_study.main({"out": tmp_path / "fast", "fast": True})
    assert s["meta"]["fast"] is True and run[1]["meta"]["fast"] is False
    assert s["table8"] == run[1]["table8"]  # the study is small: fast mode runs it in full
    assert (tmp_path / "fast" / "report.html").is_file()
    with pytest.raises(ValueError, match="unknown key"):
        cv_study.main({"out": tmp_path, "speed": 1})
    with pytest.raises(ValueError, match="'out'"):
        StudyConfig.coerce({"fast": True})


# ---------------------------------------------------------------------- CLI
def test_unknown_study_is_one_line_exit_2(tmp_path: Path) -> None:
    proc = _cli("study", "no-such-study", "--out", str(tmp_path / "x"))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "no-such-study" in lines[0] and "coulomb-viscous" in lines[0]
    assert not (tmp_path / "x").exists()


def test_out_is_a_file_is_one_line_exit_2(tmp_path: Path) -> None:
    f = tmp_path / "file"
    f.write_text("x")
    proc = _cli("study", "coulomb-viscous", "--out", str(f))
    assert proc.returncode == 2
    assert len(proc.stderr.strip().splitlines()) == 1 and "not a directory" in proc.stderr


# ---------------------------------------------------------------------- all
class _Tiny(cv_study.Study):
    name = "tiny-test"
    title = "Tiny"
    summary = "a tiny study for the test"

    def build(self, out, config):
        out.report.section("Result").paragraph("ok")
        fig, ax = out.subplots()
        ax.plot([0, 1], [1, 0])
        out.figure(fig, "line", "a line")
        return {"value": 1.5, "fast": config.fast}


class _Broken(_Tiny):
    name = "broken-test"

    def build(self, out, config):
        raise RuntimeError("deliberate failure\nsecond line")


def test_all_runs_every_registered_study_and_writes_an_index(tmp_path: Path, monkeypatch) -> None:
    items = {"all": STUDIES.get("all"), "tiny-test": _Tiny()}
    monkeypatch.setattr(STUDIES, "_items", items)
    s = STUDIES.get("all").main(StudyConfig(out=tmp_path, fast=True, command="fcomp study all"))
    assert s["failed"] == [] and list(s["studies"]) == ["tiny-test"]
    sub = json.loads((tmp_path / "tiny-test" / "summary.json").read_text())
    assert sub["value"] == 1.5 and sub["fast"] is True
    index = (tmp_path / "index.html").read_text()
    from test_report import check_html

    check_html(index)
    assert '<a href="tiny-test/report.html">tiny-test</a>' in index
    assert (tmp_path / "tiny-test" / "fig-line.png").is_file()

    items["broken-test"] = _Broken()
    with pytest.raises(StudyError, match="broken-test"):
        STUDIES.get("all").main(StudyConfig(out=tmp_path / "again"))
    s = json.loads((tmp_path / "again" / "summary.json").read_text())
    assert s["failed"] == ["broken-test"]
    assert s["studies"]["broken-test"]["error"] == "RuntimeError: deliberate failure"
    assert s["studies"]["tiny-test"]["status"] == "ok"
    assert "failed: RuntimeError: deliberate failure" in (tmp_path / "again" / "index.html"
                                                         ).read_text()


def test_all_records_wall_and_cpu_time_in_turn_and_side_by_side(tmp_path: Path,
                                                                monkeypatch) -> None:
    items = {"all": STUDIES.get("all"), "tiny-test": _Tiny(), "tiny-b": _Tiny()}
    monkeypatch.setattr(STUDIES, "_items", items)
    for workers in (1, 2):
        out = tmp_path / f"w{workers}"
        s = STUDIES.get("all").main(StudyConfig(out=out, fast=True, workers=workers))
        assert s["workers"] == workers and s["failed"] == []
        for r in s["studies"].values():
            assert r["seconds"] >= 0 and r["cpu_seconds"] >= 0
        assert json.loads((out / "tiny-b" / "summary.json").read_text())["value"] == 1.5


class _TTY(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_of_a_worker_is_relayed_to_the_parent(monkeypatch) -> None:
    import queue

    from fcomp.progress import ProgressRelay, progress_bar, relay_progress, ticker

    q: queue.Queue = queue.Queue()
    relay_progress(q)
    try:
        bar = progress_bar("work", 3, unit="case")
        tick = ticker(bar)
        for done in (1, 2, 3):
            tick(done, 3)
        bar.set_postfix_str("last")
        bar.close()
        hidden = progress_bar("hidden", 2, enabled=False)
    finally:
        relay_progress(None)
    msgs = []
    while not q.empty():
        msgs.append(q.get())
    assert msgs[0][0] == "open" and msgs[0][2:] == ("work", 3, "case")
    assert [m[2] for m in msgs if m[0] == "update"] == [1, 1, 1]
    assert msgs[-2] == ("postfix", msgs[0][1], "last") and msgs[-1][0] == "close"
    assert hidden.disable                                   # a disabled bar is not relayed
    screen = _TTY()
    monkeypatch.setattr(sys, "stderr", screen)
    with ProgressRelay() as relay:                           # the parent draws what arrives
        for m in msgs:
            relay.queue.put(m)
    assert "work" in screen.getvalue() and "3/3" in screen.getvalue()
    with ProgressRelay(enabled=False) as off:
        assert off.queue is None


def test_registry_holds_the_contract_names() -> None:
    assert "coulomb-viscous" in STUDIES and "all" in STUDIES
    for name in STUDIES:
        assert STUDIES.get(name).name == name


def test_docs_quote_the_study(run) -> None:
    """docs/seed001.md quotes numbers the study computes (guards against stale docs)."""
    _, s, _ = run
    doc = (Path(__file__).resolve().parents[1] / "docs" / "seed001.md").read_text()
    t8, c2 = s["table8"], s["c2_reconstruction"]
    exact = [v for v in s["reproduction"]["variants"]
             if v["t"] == "exact" and v["B_values"] == "printed"][0]
    quoted = [
        f"{t8['C1']['B_retraction']['ci_low']:.3f}-{t8['C1']['B_retraction']['ci_high']:.3f}",
        *(f"{float(re.search(r': ([0-9.]+)', x).group(1)):.3f}" for x in exact["C1_differing"]),
        f"{t8['C2']['B_retraction']['std']:.3f}",
        f"{t8['C2']['B_retraction']['ci_low']:.3f}-{t8['C2']['B_retraction']['ci_high']:.3f}",
        f"n = {c2['Fc_extension']['implied_n']['n']:.1f} and "
        f"{c2['Fc_retraction']['implied_n']['n']:.1f}",
        f"{c2['Fc_extension']['table6_mean']:.3f} and {c2['Fc_retraction']['table6_mean']:.3f}",
        f"{s['assumptions']['sliding_force']['retraction']['line']['intercept']:.1f} N",
    ]
    for text in quoted:
        assert text in doc, text
