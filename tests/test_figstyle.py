"""The shared figure style (:mod:`fcomp.figstyle`): font record, units, gaps, ticks, placement."""

from __future__ import annotations

import base64
import re
import struct

import numpy as np
import pytest
from matplotlib.figure import Figure

from fcomp import figstyle as fs
from fcomp.report import Report, render_png


def _text_chunks(png: bytes) -> dict[str, str]:
    """tEXt entries parsed here, independently of :func:`fcomp.figstyle.read_record`."""
    out, pos = {}, 8
    while pos < len(png):
        (n,) = struct.unpack(">I", png[pos:pos + 4])
        if png[pos + 4:pos + 8] == b"tEXt":
            k, _, v = png[pos + 8:pos + 8 + n].partition(b"\0")
            out[k.decode()] = v.decode()
        pos += 12 + n
    return out


def test_save_records_the_smallest_drawn_font_and_the_dpi() -> None:
    fig, ax = fs.new_figure(height=2.5)
    ax.plot([0, 1], [0, 1])
    ax.annotate("small", (0.5, 0.5), fontsize=6.5)
    hidden = ax.text(0.2, 0.2, "hidden", fontsize=3)
    hidden.set_visible(False)
    ax.text(0.3, 0.3, "   ", fontsize=2)  # blank: nothing drawn
    rec = _text_chunks(fs.save(fig))
    assert rec == {"fcomp:dpi": "100", "fcomp:min_font_pt": "6.50"}


def test_style_figures_read_at_9pt_in_the_column_and_old_ones_do_not() -> None:
    fig, ax = fs.new_figure(height=2.5, width=20.0)  # capped at the column width
    ax.plot([1, 2, 3], label="a")
    ax.set_xlabel("t (s)")
    fs.legend_above(ax)
    png = fs.save(fig)
    assert fs.natural_px(png)[0] <= fs.COLUMN_PX
    assert fs.check_readable(png) is None
    assert float(fs.read_record(png)["fcomp:min_font_pt"]) >= fs.FONT_MIN
    old = Figure(figsize=(12.0, 3.0))
    a = old.add_subplot()
    a.plot([1, 2])
    a.tick_params(labelsize=7)
    assert "smallest text" in (fs.check_readable(fs.save(old)) or "")
    assert fs.check_readable(fs.save(Figure())) == "no font record"  # nothing drawn


def test_report_and_render_png_embed_the_record() -> None:
    fig, ax = fs.new_figure(height=2.0)
    ax.plot([0, 1])
    assert "fcomp:min_font_pt" in _text_chunks(render_png(fig))
    fig, ax = fs.new_figure(height=2.0)
    ax.plot([0, 1])
    page = Report("t").figure(fig, "a line").to_html()
    data = base64.b64decode(re.search(r'base64,([^"]+)"', page).group(1))
    assert _text_chunks(data)["fcomp:dpi"] == str(fs.DPI)


def test_units_shown_where_an_engineer_reads_them() -> None:
    assert fs.scaled("x", np.array([0.012]))[0] == pytest.approx(12.0)
    assert fs.scaled("p1", 3e5) == pytest.approx(3.0)
    assert fs.scaled("v", 0.05) == pytest.approx(50.0)
    assert fs.label("position", "x") == "position (mm)"
    assert fs.label("p1+p2") == "p1+p2 (bar)"
    assert fs.label("force", "F") == "force (N)"
    assert fs.label("velocity", "v") == "velocity (mm/s)"
    assert fs.label("strength") == "strength"


def test_break_gaps_inserts_nan_at_a_jump_only() -> None:
    t = np.r_[np.arange(0.0, 1.0, 0.1), np.arange(5.0, 6.0, 0.1)]
    y = np.arange(t.size, dtype=float)
    tt, yy = fs.break_gaps(t, y)
    assert tt.size == t.size + 1 and np.isnan(tt[10]) and np.isnan(yy[10])
    assert np.array_equal(tt[~np.isnan(tt)], t)
    t2 = np.arange(0.0, 1.0, 0.1)
    assert not np.isnan(fs.break_gaps(t2, t2)[1]).any()
    fig, ax = fs.new_figure()
    (line,) = fs.plot_gapped(ax, t, y)
    assert np.isnan(line.get_xdata()).sum() == 1


def test_binned_means_leave_empty_bins_empty() -> None:
    f = np.r_[np.linspace(0, 1, 300), np.linspace(9, 10, 300)]
    c, m = fs.binned_means(f, 2 * f, bins=10)
    assert c.size == 10 and np.isnan(m[2:8]).all()
    assert np.isfinite(m[0]) and np.isfinite(m[-1])
    assert m[-1] == pytest.approx(2 * 9.5, abs=0.2)


def test_log_ticks_are_plain_numbers() -> None:
    fig, ax = fs.new_figure(height=2.5)
    ax.plot([1, 2, 3], [0.5, 60, 900])
    ax.set_yscale("log")
    fs.plain_log_ticks(ax)
    fig.draw_without_rendering()
    lo, hi = ax.get_ylim()
    shown = [t.get_text() for t in ax.get_yticklabels()
             if t.get_text() and lo <= t.get_position()[1] <= hi]
    assert shown == ["1", "10", "100", "1000"]
    assert not [t for t in ax.yaxis.get_minorticklabels() if t.get_text()]
    for data, want in (([46, 51], {"46", "48", "50"}),
                       ([0.6, 3.0], {"1", "2"})):
        fig, ax = fs.new_figure(height=2.5)
        ax.plot([0, 1], data)
        ax.set_yscale("log")
        fs.plain_log_ticks(ax)
        fig.draw_without_rendering()
        lo, hi = ax.get_ylim()
        got = {t.get_text() for t in ax.get_yticklabels()
               if t.get_text() and lo <= t.get_position()[1] <= hi}
        assert want <= got and not any("10^" in g or "times" in g or "e" in g for g in got), got


def test_legend_above_and_notes_inside_the_axes() -> None:
    fig, ax = fs.new_figure(height=3.0)
    ax.bar([0, 1, 2], [1, 2, 3], label="bars")
    leg = fs.legend_above(ax)
    note = fs.text_inside(ax, 2.0, "too few\nsamples")
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    r = FigureCanvasAgg(fig).get_renderer()
    fig.draw(r)
    box = ax.get_window_extent(r)
    assert leg.get_window_extent(r).y0 >= box.y1 - 1
    nb = note.get_window_extent(r)
    assert box.x0 <= nb.x0 and nb.x1 <= box.x1 and box.y0 <= nb.y0 and nb.y1 <= box.y1
    assert fs.legend_above(fs.new_figure()[1]) is None  # nothing labelled: no empty legend
    fig, (a1, a2) = fs.new_figure(height=3.0, ncols=2)
    a1.plot([0, 1], label="one")
    a1.set_title("a title")
    a2.set_title("another")
    leg = fs.legend_top(fig)
    r = FigureCanvasAgg(fig).get_renderer()
    fig.draw(r)
    lb = leg.get_window_extent(r)
    for a in (a1, a2):
        assert lb.y0 >= a.title.get_window_extent(r).y1 - 1  # above the titles


def test_good_is_green() -> None:
    from matplotlib import colormaps

    def green(c: tuple) -> bool:
        return c[1] > c[0]

    assert green(colormaps[fs.good_bad_cmap(higher_is_better=True)](1.0))
    assert green(colormaps[fs.good_bad_cmap(higher_is_better=False)](0.0))
    assert not green(colormaps[fs.good_bad_cmap(higher_is_better=False)](1.0))


def test_apply_floor_raises_small_text() -> None:
    fig = Figure(figsize=(6, 3), layout="constrained")
    ax = fig.add_subplot()
    ax.plot([1, 2])
    ax.tick_params(labelsize=6)
    ax.set_title("t", fontsize=5)
    fs.apply_floor(fig)
    assert float(fs.read_record(fs.save(fig))["fcomp:min_font_pt"]) >= fs.FONT_MIN
