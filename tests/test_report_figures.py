"""The command reports' figures and pages in the shared style (issue 27, item 4): units an
engineer reads, categories inside the axes, no line across a gap, contents numbered once,
where the compared values came from, parameters with units, no 0.0000 for a non-zero number."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from fcomp.cli.main import main
from fcomp.report import Report
from fcomp.synthetic import generate


@pytest.fixture(scope="module")
def record(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("figs") / "rec.csv"
    generate(["pressure-dependence"], duration=12.0, seed=1).measurement.write(path)
    return path


@pytest.fixture(scope="module")
def comparison(record: Path):
    import fcomp
    from fcomp.measurement import Measurement

    return fcomp.compare(Measurement.read(record), "lugre")


def _drawn(fig):
    r = FigureCanvasAgg(fig).get_renderer()
    fig.draw(r)
    return r


def test_regime_bars_and_notes_inside_the_axes(comparison, monkeypatch) -> None:
    from fcomp.diagnosis import figures
    from fcomp.diagnosis.figures import fig_regimes

    # the first category (pre-sliding) counts as too few: no bar, a mark instead
    monkeypatch.setattr(figures, "MIN_REGIME_SAMPLES",
                        (comparison.regimes["pre-sliding"]["n"] or 0) + 1)
    fig = fig_regimes(comparison)
    r = _drawn(fig)
    ax = fig.axes[0]
    box = ax.get_window_extent(r)
    lo, hi = ax.get_xlim()
    bars = [p for p in ax.patches]
    assert bars and all(lo <= p.get_x() and p.get_x() + p.get_width() <= hi for p in bars)
    assert all(lo < x < hi for x in ax.get_xticks())  # every category inside the axes
    ticks_top = max(t.get_window_extent(r).y1 for t in ax.get_xticklabels() if t.get_text())
    notes = [t for t in ax.texts if "too few" in t.get_text()]
    assert notes
    for t in notes:
        e = t.get_window_extent(r)
        assert box.x0 <= e.x0 and e.x1 <= box.x1 and box.y0 <= e.y0 <= e.y1 <= box.y1
        assert e.y0 > ticks_top  # not over the tick labels
    legend = ax.get_legend().get_window_extent(r)
    assert legend.y0 >= box.y1 - 1  # the legend above the data


def test_positions_in_mm_and_binned_means_break_at_empty_bins(comparison) -> None:
    from fcomp.diagnosis.figures import fig_loops, fig_residuals

    loops = fig_loops(comparison)
    labels = [ax.get_xlabel() for ax in loops.axes]
    assert labels == ["velocity v (mm/s)", "position x (mm)"]
    x = comparison.data.signal("x")
    shown = loops.axes[1].lines[0].get_xdata()
    assert np.nanmax(shown) == pytest.approx(1e3 * x[comparison.judged].max())
    res = fig_residuals(comparison)
    xlabels = {ax.get_xlabel() for ax in res.axes if ax.get_visible()}
    assert {"x (mm)", "v (mm/s)", "p1+p2 (bar)", "displacement since reversal (mm)"} <= xlabels
    # the time axis has stretches without judged samples: its binned mean breaks there
    t_ax = next(ax for ax in res.axes if ax.get_xlabel() == "t (s)")
    mean_line = next(ln for ln in t_ax.lines if ln.get_label().endswith("(binned mean)"))
    assert np.isnan(mean_line.get_ydata()).any()


def test_time_series_break_at_gaps(record: Path) -> None:
    import fcomp
    from fcomp.measurement import Measurement

    rec = Measurement.read(record)
    fig = fcomp.fit(rec, "coulomb-viscous").plot()
    t = np.asarray(rec.t)
    jumps = np.diff(t) > 3 * np.median(np.diff(t))
    assert jumps.any(), "the record's experiments leave gaps in time"
    lines = [ln for ax in fig.axes if ax.get_xlabel() == "t (s)" for ln in ax.lines]
    assert lines
    for ln in lines:  # no segment of a drawn line is longer than a gap's threshold
        xs = np.asarray(ln.get_xdata(), dtype=float)
        steps = np.diff(xs)
        assert not (steps[np.isfinite(steps)] > 3 * np.median(np.diff(t))).any()


def test_contents_not_numbered_twice() -> None:
    rep = Report("t")
    for h in ("Summary", "1. Errors", "2. Where", "3. Which"):
        rep.section(h).paragraph("x")
    page = rep.to_html()
    toc = re.search(r'<nav class="toc".*?</nav>', page, re.S).group(0)
    assert "<ul>" in toc and "<ol>" not in toc
    plain = Report("t")
    for h in ("Summary", "Errors", "Where"):
        plain.section(h)
    assert "<ol>" in re.search(r'<nav class="toc".*?</nav>', plain.to_html(), re.S).group(0)


def test_no_zero_shown_for_a_non_zero_number_and_units_in_parameters() -> None:
    page = (Report("t").table(["a (N)"], [[0.00001], [0.0], [-1e-7], [0.25]], digits=3)
            .parameters({"Fc": 1.5, "n": 2.0}, units={"Fc": "N", "n": ""}).to_html())
    cells = re.findall(r'<td class="num">([^<]*)</td>', page)
    assert cells[:4] == ["&lt; 0.001", "0.000", "&gt; -0.001", "0.250"]
    assert "<th scope=\"col\">unit</th>" in page
    assert re.search(r"<td>Fc</td><td class=\"num\">1.5</td><td>N</td>", page)
    assert re.search(r"<td>n</td><td class=\"num\">2</td><td>-</td>", page)


def test_compare_report_says_where_the_values_came_from(record: Path, tmp_path: Path) -> None:
    fit = tmp_path / "fit.json"
    assert main(["fit", str(record), "--friction", "lugre", "--json", str(fit),
                 "--save-model", str(tmp_path / "m.json"), "--no-progress"]) == 0
    assert main(["compare", str(record), "--friction", "lugre", "--params", str(fit),
                 "--report", str(tmp_path / "c"), "--no-progress"]) == 0
    page = (tmp_path / "c" / "report.html").read_text()
    sub = re.search(r'<p class="subtitle">(.*?)</p>', page).group(1)
    assert "fit file" in sub and "fit.json" in sub and "own values" not in sub
    # the parameter table has a unit for every parameter
    params = page[page.index('id="parameters"'):]
    rows = re.findall(r"<tr><td>(\w+)</td><td class=\"num\">[^<]*</td><td>([^<]*)</td></tr>",
                      params)
    units = dict(rows)
    assert units["Fc"] == "N" and units["sigma0"] == "N/m" and units["vs"] == "m/s"
    assert all(units.values())
    assert main(["compare", str(record), "--friction", "lugre", "--params", "seed002-type1",
                 "--report", str(tmp_path / "s"), "--no-progress"]) == 0
    sub = re.search(r'<p class="subtitle">(.*?)</p>',
                    (tmp_path / "s" / "report.html").read_text()).group(1)
    assert "parameter set" in sub and "seed002-type1" in sub
    assert main(["compare", str(record), "--friction", "lugre", "--params",
                 str(tmp_path / "m.json"), "--report", str(tmp_path / "m"), "--no-progress"]) == 0
    sub = re.search(r'<p class="subtitle">(.*?)</p>',
                    (tmp_path / "m" / "report.html").read_text()).group(1)
    assert "model file" in sub and "m.json" in sub


def test_ratio_bars_green_when_better_red_when_worse_plain_ticks() -> None:
    from types import SimpleNamespace

    from matplotlib.colors import to_hex

    from controllers.compensate_report import figure_ratios
    from fcomp.figstyle import COLORS

    res = SimpleNamespace(models={"base": "lugre", "diag": "lugre + x"}, baseline="base",
                          tasks=("steps",), controllers=("pid", "pid-ff"),
                          ratios={"true": {"pid": {"steps": {"diag": {"rms_error": 0.5}}},
                                           "pid-ff": {"steps": {"diag": {"rms_error": 3.0}}}}})
    fig = figure_ratios(res)  # type: ignore[arg-type]
    fig.draw_without_rendering()
    ax = fig.axes[0]
    bars = sorted(ax.patches, key=lambda p: p.get_x())
    assert [to_hex(b.get_facecolor()) for b in bars] == [COLORS["good"], COLORS["bad"]]
    assert bars[0].get_y() == pytest.approx(1.0)  # drawn from the baseline's 1
    lo, hi = ax.get_ylim()
    labels = [t.get_text() for t in ax.get_yticklabels()
              if t.get_text() and lo <= t.get_position()[1] <= hi]
    assert "1" in labels and not any("10^" in s or "times" in s for s in labels)


def test_distribution_ticks_plain_over_a_narrow_range() -> None:
    from controllers.robustness import draw_distribution
    from fcomp import figstyle as fs

    fig, ax = fs.new_figure()
    dist = {"pid": {"rms_error": {"values": [46e-6, 51e-6]}},
            "pid-ff": {"rms_error": {"values": [47e-6, 49e-6]}}}
    draw_distribution(ax, dist, ["pid", "pid-ff"], scale=1e6)
    fig.draw_without_rendering()
    lo, hi = ax.get_ylim()
    labels = [t.get_text() for t in ax.get_yticklabels()
              if t.get_text() and lo <= t.get_position()[1] <= hi]
    assert len(labels) >= 2 and all(re.fullmatch(r"\d+(\.\d+)?", s) for s in labels), labels


def test_plant_domain_in_mm_and_bar(tmp_path: Path) -> None:
    import fcomp

    model = fcomp.make_model("lugre")
    run = fcomp.simulate("pneumatic", model, "sine:amplitude=0.3,frequency=0.5", duration=2.0,
                         rate=500.0)
    comp = fcomp.compare(run, model, plant="pneumatic")
    fig = comp.plot("plant")
    assert [ax.get_ylabel() for ax in fig.axes] == ["x (mm)", "p1 (bar)", "p2 (bar)"]
    x_line = fig.axes[0].lines[0].get_ydata()
    assert np.nanmax(np.abs(x_line)) == pytest.approx(1e3 * np.abs(comp.plant[0].measured["x"]).max())
    comp.write_report(tmp_path)
    page = (tmp_path / "report.html").read_text()
    plant_rows = re.findall(r"<td>(x|p1|p2)</td><td class=\"num\">[^<]*</td><td>([^<]*)</td>",
                            page)
    assert dict(plant_rows) == {"x": "mm", "p1": "bar", "p2": "bar"}
