"""One figure style for every report: sizes, fonts, units, gaps, ticks, colours, saving.

Every figure of a report (command reports and study reports) is made with
:func:`new_figure` and rendered with :func:`save` (which :class:`fcomp.report.Report`
and :func:`fcomp.report.render_png` call), so that it reads at the reports'
desktop width::

    from fcomp import figstyle as fs

    fig, ax = fs.new_figure(height=3.0)            # full column width, style applied
    fs.plot_gapped(ax, t, fs.scaled("x", x))        # position in mm, no line over gaps
    ax.set_ylabel(fs.label("position", "x"))        # "position (mm)"
    fs.legend_above(ax)
    png = fs.save(fig)                              # PNG bytes, font record in a tEXt chunk

Readable at 1400 px
-------------------
The report's column is :data:`COLUMN_PX` CSS px wide at desktop width (the page
is 1400 px; the column is ``64rem`` minus padding). A figure of
:data:`WIDTH` inches at :data:`DPI` is about as wide as the column, so it is
shown at (about) its natural size, and a text of ``s`` pt is then displayed at
``s * DPI / 72`` px, i.e. ``s * DPI / 96`` CSS pt. :data:`FONT_MIN` (the tick
labels, legends and annotations) is chosen so that this is at least 9 CSS pt.
Figures made elsewhere are measured all the same.

The record in the PNG
---------------------
:func:`save` writes two PNG tEXt entries, computed from the text the renderer
actually drew (every ``draw_text`` call of the Agg renderer that draws non-blank
text)::

    fcomp:min_font_pt   the smallest font size drawn, in points
    fcomp:dpi           the dots per inch of the PNG

so that a displayed font size can be computed from the PNG and the width a
browser shows it at: ``px = min_font_pt * dpi / 72 * shown_width / natural_width``.
:func:`read_record` reads them back.

Units
-----
Data stay SI; :data:`SCALES` says how a quantity is shown (position in mm,
pressure in bar, force in N, velocity in mm/s); :func:`scaled` and :func:`label`
apply it.
"""

from __future__ import annotations

import contextlib
import io
import math
import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import rc_context
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter

__all__ = [
    "COLORS", "COLUMN_PX", "DPI", "FONT", "FONT_MIN", "HALF_WIDTH", "RC", "SCALES", "WIDTH",
    "Scale", "apply_floor", "binned_means", "break_gaps", "check_readable", "displayed_pt",
    "good_bad_cmap", "label", "legend_above", "legend_top", "natural_px", "new_figure", "plain_log_ticks",
    "plot_gapped", "read_record", "save", "scale_of", "scaled", "style", "text_inside",
]

#: Width a figure is shown at, at most, at desktop width, CSS px (``main`` is 64rem minus
#: 2 x 1rem = 992 px; the image's 1 px border each side leaves 990).
COLUMN_PX = 990
#: Dots per inch of every PNG.
DPI = 100
#: Width of a full-column figure, inches (``WIDTH * DPI`` a little below :data:`COLUMN_PX`).
WIDTH = 9.5
#: Width of a figure meant to stand alone but need no full column (bar charts), inches.
HALF_WIDTH = 6.4
#: Smallest font size of any figure text (ticks, legends, annotations), pt.
FONT_MIN = 9.0
#: Font size of axis labels and titles, pt.
FONT = 10.0

#: Matplotlib settings of the style (applied by :func:`style`, :func:`new_figure`, :func:`save`).
RC: dict[str, Any] = {
    "font.size": FONT,
    "axes.labelsize": FONT,
    "axes.titlesize": FONT,
    "xtick.labelsize": FONT_MIN,
    "ytick.labelsize": FONT_MIN,
    "legend.fontsize": FONT_MIN,
    "legend.title_fontsize": FONT_MIN,
    "figure.titlesize": FONT + 1,
    "axes.formatter.useoffset": False,
    "axes.formatter.use_mathtext": True,
    "axes.grid": False,
    "lines.linewidth": 1.2,
    "savefig.dpi": DPI,
    "figure.dpi": DPI,
}

#: Colours with a meaning: ``good`` green, ``bad`` red; models as in the diagnosis figures.
COLORS: dict[str, str] = {
    "good": "#1f7a3d",
    "bad": "#a1261b",
    "warn": "#b7791f",
    "neutral": "0.6",
    "measured": "0.25",
    "baseline": "#c0392b",
    "final": "#2356a8",
    "reference": "0.4",
}

#: Keys of the tEXt entries :func:`save` writes.
KEY_MIN_FONT = "fcomp:min_font_pt"
KEY_DPI = "fcomp:dpi"


@dataclass(frozen=True)
class Scale:
    """How an SI quantity is shown: ``shown = factor * value`` in ``unit``."""

    factor: float
    unit: str


#: How quantities are shown, by signal name or kind (data stay SI).
SCALES: dict[str, Scale] = {
    "x": Scale(1e3, "mm"), "position": Scale(1e3, "mm"), "displacement": Scale(1e3, "mm"),
    "displacement_since_reversal": Scale(1e3, "mm"),
    "v": Scale(1e3, "mm/s"), "velocity": Scale(1e3, "mm/s"),
    "a": Scale(1.0, "m/s²"), "acceleration": Scale(1.0, "m/s²"),
    "p": Scale(1e-5, "bar"), "p1": Scale(1e-5, "bar"), "p2": Scale(1e-5, "bar"),
    "p1+p2": Scale(1e-5, "bar"), "pressure": Scale(1e-5, "bar"),
    "F": Scale(1.0, "N"), "force": Scale(1.0, "N"), "y": Scale(1.0, "N"),
    "t": Scale(1.0, "s"), "time": Scale(1.0, "s"), "time_since_reversal": Scale(1.0, "s"),
    "dwell_time": Scale(1.0, "s"),
}


def scale_of(name: str) -> Scale:
    """The :class:`Scale` of ``name`` (a key of :data:`SCALES`; unknown names: SI as is)."""
    return SCALES.get(name, Scale(1.0, ""))


def scaled(name: str, values: Any) -> Any:
    """``values`` (SI) in the unit a reader expects for ``name`` (``x`` in mm, ``p1`` in bar)."""
    f = scale_of(name).factor
    return values * f if f != 1.0 else values


def label(text: str, name: str | None = None) -> str:
    """An axis label with the shown unit: ``label("position", "x")`` -> ``"position (mm)"``."""
    unit = scale_of(name or text).unit
    return f"{text} ({unit})" if unit else text


# ------------------------------------------------------------------ figures
@contextlib.contextmanager
def style() -> Iterator[None]:
    """The style's matplotlib settings for the ``with`` block (figures built inside take them)."""
    with rc_context(RC):  # type: ignore[arg-type]
        yield


def new_figure(height: float = 3.2, width: float = WIDTH, *, nrows: int = 1, ncols: int = 1,
               squeeze: bool = True, **subplot_kw: Any) -> tuple[Figure, Any]:
    """A figure of the style and its axes (like ``plt.subplots``, without pyplot state).

    Parameters
    ----------
    height, width
        Size in inches; ``width`` defaults to the full column (:data:`WIDTH`), never
        wider (a wider figure would be shown smaller and its text below 9 pt).
    nrows, ncols, squeeze
        The grid of axes, as ``Figure.subplots``.
    **subplot_kw
        Passed on to ``Figure.subplots`` (``sharex=True`` ...).

    Returns
    -------
    (Figure, axes)
        The figure uses the constrained layout (worked out when drawn, so labels,
        legends above the axes and titles get their room).
    """
    with style():
        fig = Figure(figsize=(min(float(width), WIDTH), float(height)), dpi=DPI,
                     layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=squeeze, **subplot_kw)
    for ax in np.atleast_1d(axes).ravel():
        ax.tick_params(labelsize=FONT_MIN)
    return fig, axes


def legend_above(ax: Any, ncol: int = 3, *, handles: Any = None, **kw: Any) -> Any:
    """A legend above the axes, never over the data (only if something is labelled:
    ``handles``, or else the axes' labelled artists). The axes' title, if any, becomes the
    legend's title: above the axes the two would be drawn over each other."""
    if handles is None:
        handles = ax.get_legend_handles_labels()[0]
    if not handles:
        return None
    title = ax.get_title()
    if title and "title" not in kw:
        ax.set_title("")
        kw.update(title=title, alignment="left", title_fontsize=FONT)
    kw.setdefault("fontsize", FONT_MIN)
    return ax.legend(handles=handles, loc="lower left", bbox_to_anchor=(0.0, 1.01), ncol=ncol,
                     frameon=False, borderaxespad=0.0, **kw)


def legend_top(fig: Figure, ax: Any = None, ncol: int = 3, **kw: Any) -> Any:
    """One legend for a figure of several axes, above all of them (never over data or
    titles; the constrained layout makes room): the labelled artists of ``ax`` (default:
    the first axes that has any)."""
    for a in [ax] if ax is not None else fig.axes:
        handles, labels = a.get_legend_handles_labels()
        if handles:
            kw.setdefault("fontsize", FONT_MIN)
            return fig.legend(handles, labels, loc="outside upper left", ncol=ncol,
                              frameon=False, **kw)
    return None


def text_inside(ax: Any, x: float, text: str, *, frac: float = 0.04, **kw: Any) -> Any:
    """A note placed inside the axes at data ``x``, ``frac`` of the height above the bottom
    (a category's "too few samples" mark: inside the axes, never over the tick labels)."""
    kw.setdefault("fontsize", FONT_MIN)
    kw.setdefault("color", "0.35")
    kw.setdefault("ha", "center")
    kw.setdefault("va", "bottom")
    return ax.text(x, frac, text, transform=ax.get_xaxis_transform(), clip_on=True, **kw)


def plain_log_ticks(ax: Any, axis: str = "y") -> None:
    """Log-axis ticks as plain numbers (1, 10, 100, 0.01; never ``10^2`` or ``6x10^1``),
    minor ticks unlabelled. Call it after the data are drawn: over less than a decade the
    ticks are evenly spaced plain numbers (46, 48, 50), over less than three decades
    1-2-5 steps (0.5, 1, 2, 5), else powers of ten."""

    def fmt(v: float, _pos: int) -> str:
        if v <= 0 or not math.isfinite(v):
            return ""
        return np.format_float_positional(float(f"{v:.6g}"), trim="-")

    for name in ("x", "y") if axis == "both" else (axis,):
        ax_ = ax.xaxis if name == "x" else ax.yaxis
        lo, hi = sorted(ax.get_xlim() if name == "x" else ax.get_ylim())
        span = hi / lo if lo > 0 and math.isfinite(hi / lo) else math.inf
        if span < 10.0:
            ax_.set_major_locator(MaxNLocator(nbins=5, steps=[1, 2, 2.5, 5, 10]))
        elif span < 1000.0:
            ax_.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        else:
            ax_.set_major_locator(LogLocator(base=10.0))
        ax_.set_major_formatter(FuncFormatter(fmt))
        ax_.set_minor_formatter(NullFormatter())


def good_bad_cmap(higher_is_better: bool = True) -> str:
    """A colour map where good is green and bad red: ``RdYlGn`` when a higher value is
    better, ``RdYlGn_r`` when a lower one is (an error, a ratio to the best)."""
    return "RdYlGn" if higher_is_better else "RdYlGn_r"


# ------------------------------------------------------------------ gaps
def break_gaps(x: Any, *ys: Any, max_step: float | None = None, factor: float = 3.0,
               starts: Any = ()) -> tuple[np.ndarray, ...]:
    """``x`` and ``ys`` with a NaN inserted wherever ``x`` jumps and before every index of
    ``starts`` (where an experiment begins), so a line is not drawn over the gap.

    Parameters
    ----------
    x
        Increasing abscissa (time).
    *ys
        Series of the same length.
    max_step
        Largest step that is not a gap; default ``factor`` times the median step.
    starts
        Indices where a new experiment begins: a break there whatever the step.
    """
    xa = np.asarray(x, dtype=float)
    yas = [np.asarray(y, dtype=float) for y in ys]
    cut = np.unique([int(i) for i in starts if 0 < int(i) < xa.size]).astype(int)
    d = np.diff(xa)
    pos = d[np.isfinite(d) & (d > 0)]
    if max_step is None and xa.size >= 3 and pos.size:
        max_step = factor * float(np.median(pos))
    if max_step is not None:
        cut = np.union1d(cut, np.flatnonzero(~(np.abs(d) <= max_step)) + 1).astype(int)
    if not cut.size:
        return (xa, *yas)
    return (np.insert(xa, cut, np.nan), *(np.insert(y, cut, np.nan) for y in yas))


def plot_gapped(ax: Any, x: Any, y: Any, *args: Any, max_step: float | None = None,
                starts: Any = (), **kw: Any) -> list[Any]:
    """``ax.plot(x, y, ...)`` with the line broken where ``x`` jumps and where an experiment
    starts (:func:`break_gaps`)."""
    xs, ys = break_gaps(x, y, max_step=max_step, starts=starts)
    return ax.plot(xs, ys, *args, **kw)  # type: ignore[no-any-return]


def binned_means(f: Any, r: Any, bins: int | None = None, *, min_count: int = 5
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Means of ``r`` in equal-width bins of ``f``: bin centres and means, NaN where a bin
    holds fewer than ``min_count`` samples (a line drawn through them breaks there,
    instead of jumping across an empty stretch).

    ``bins`` defaults to ``clip(n / 50, 8, 40)``.
    """
    fa, ra = np.asarray(f, dtype=float), np.asarray(r, dtype=float)
    ok = np.isfinite(fa) & np.isfinite(ra)
    fa, ra = fa[ok], ra[ok]
    if fa.size == 0:
        return np.array([]), np.array([])
    nb = int(bins) if bins else int(np.clip(fa.size // 50, 8, 40))
    lo, hi = float(fa.min()), float(fa.max())
    if hi <= lo:
        return np.array([lo]), np.array([float(ra.mean())])
    edges = np.linspace(lo, hi, nb + 1)
    idx = np.clip(np.searchsorted(edges, fa, side="right") - 1, 0, nb - 1)
    count = np.bincount(idx, minlength=nb)
    total = np.bincount(idx, weights=ra, minlength=nb)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(count >= min_count, total / np.maximum(count, 1), np.nan)
    return 0.5 * (edges[:-1] + edges[1:]), mean


# ------------------------------------------------------------------ saving
def _drawn_font_sizes(fig: Figure) -> list[float]:
    """Font sizes (pt) of every non-blank text the Agg renderer draws for ``fig``."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    renderer = canvas.get_renderer()
    sizes: list[float] = []
    draw_text = renderer.draw_text

    def recording(gc: Any, x: float, y: float, s: str, prop: Any, angle: float,
                  ismath: Any = False, mtext: Any = None) -> Any:
        if str(s).strip():
            sizes.append(float(prop.get_size_in_points()))
        return draw_text(gc, x, y, s, prop, angle, ismath=ismath, mtext=mtext)

    renderer.draw_text = recording  # type: ignore[method-assign]
    try:
        fig.draw(renderer)
    finally:
        del renderer.draw_text
    return sizes


def save(fig: Any, path: str | Path | None = None, *, fmt: str = "png", dpi: int = DPI,
         close: bool = True) -> bytes:
    """Render ``fig`` (PNG or SVG) in the style, record its smallest font and dpi, return the
    bytes (and write them whole to ``path`` if given).

    Parameters
    ----------
    fig
        A matplotlib figure.
    path
        Where to write the file (through a temporary file and a rename); ``None``:
        only return the bytes.
    fmt
        ``"png"`` or ``"svg"``.
    dpi
        Dots per inch of a PNG (:data:`DPI`; a report shows a figure at its natural size
        up to the column width, so a higher dpi makes the figure and its text smaller).
    close
        Close the figure afterwards (frees a pyplot figure; harmless otherwise).

    Returns
    -------
    bytes
        The file; a PNG carries the tEXt entries ``fcomp:min_font_pt`` and ``fcomp:dpi``
        (module docstring).
    """
    if fmt not in ("png", "svg"):
        raise ValueError(f"figure format must be png or svg, got {fmt!r}")
    buf = io.BytesIO()
    with style():
        if fmt == "png":
            fig.set_dpi(dpi)
            sizes = _drawn_font_sizes(fig)
            meta: dict[str, Any] = {"Software": None, KEY_DPI: f"{dpi:g}"}
            if sizes:
                meta[KEY_MIN_FONT] = f"{min(sizes):.2f}"
            fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight", metadata=meta)
        else:
            fig.savefig(buf, format="svg", bbox_inches="tight", metadata={"Date": None})
    if close:
        with contextlib.suppress(ImportError):
            import matplotlib.pyplot as plt

            plt.close(fig)
    data = buf.getvalue()
    if path is not None:
        from fcomp.outputs import write_files

        write_files({Path(path): data})
    return data


def read_record(png: bytes) -> dict[str, str]:
    """The tEXt entries of a PNG (``fcomp:min_font_pt``, ``fcomp:dpi`` among them)."""
    if png[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    out: dict[str, str] = {}
    pos = 8
    while pos + 8 <= len(png):
        (length,) = struct.unpack(">I", png[pos:pos + 4])
        kind = png[pos + 4:pos + 8]
        body = png[pos + 8:pos + 8 + length]
        if kind == b"tEXt":
            key, _, value = body.partition(b"\0")
            out[key.decode("latin-1")] = value.decode("latin-1")
        elif kind == b"zTXt":
            key, _, rest = body.partition(b"\0")
            out[key.decode("latin-1")] = zlib.decompress(rest[1:]).decode("latin-1")
        elif kind == b"IEND":
            break
        pos += 12 + length
    return out


def displayed_pt(min_font_pt: float, dpi: float, natural_px: float,
                 shown_px: float | None = None) -> float:
    """CSS pt at which a figure's smallest text is shown: natural size if ``shown_px`` is
    ``None``, else scaled by ``shown_px / natural_px`` (1 CSS px = 0.75 pt)."""
    scale = 1.0 if shown_px is None else shown_px / natural_px
    return min_font_pt * dpi / 72.0 * scale * 0.75


def natural_px(png: bytes) -> tuple[int, int]:
    """Width and height of a PNG in pixels (its IHDR chunk)."""
    w, h = struct.unpack(">II", png[16:24])
    return int(w), int(h)


def check_readable(png: bytes, column_px: float = COLUMN_PX, min_pt: float = 9.0) -> str | None:
    """Why a PNG's smallest text would be below ``min_pt`` CSS pt in the report column
    (``None`` when it reads; a PNG without the record fails)."""
    rec = read_record(png)
    if KEY_MIN_FONT not in rec or KEY_DPI not in rec:
        return "no font record"
    w, _ = natural_px(png)
    shown = min(float(w), column_px)
    pt = displayed_pt(float(rec[KEY_MIN_FONT]), float(rec[KEY_DPI]), w, shown)
    return None if pt >= min_pt - 1e-6 else f"smallest text {pt:.1f} pt at {shown:.0f} px"


def apply_floor(fig: Figure, floor: float = FONT_MIN) -> None:
    """Raise every text of ``fig`` (tick labels included) below ``floor`` pt to ``floor``.

    For figures drawn before the style (a plugin's): their layout should be worked out
    at draw time (constrained layout) or redone after this.
    """
    from matplotlib.text import Text

    def small(texts: Any) -> bool:
        return any(float(t.get_fontsize()) < floor for t in texts)

    for ax in fig.axes:
        for name in ("x", "y"):
            axis = ax.xaxis if name == "x" else ax.yaxis
            ticks = axis.get_ticklabels() + axis.get_ticklabels(minor=True)
            if not ticks or small(ticks):
                ax.tick_params(axis="x" if name == "x" else "y", which="both", labelsize=floor)
    for t in fig.findobj(Text):
        if float(t.get_fontsize()) < floor:
            t.set_fontsize(floor)
