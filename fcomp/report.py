"""Self-contained HTML reports: one file, readable offline, to hand on.

A :class:`Report` is built by chaining calls and written once::

    from fcomp.report import Comparison, Report

    (Report("Seed 001 reproduced", command="fcomp study coulomb-viscous --out out")
     .section("Table 8")
     .paragraph("Student-t 95 % intervals, `n = 120` break-away forces.")
     .comparison([Comparison("Fc extension, std", 1.2252, 1.225, unit="N", digits=3)])
     .figure(fig, "Break-away force along the stroke.")
     .parameters({"t quantile": "3-decimal table value"})
     .write("out/report.html"))

Everything is embedded: figures as base64 PNG (or inline SVG), the style
sheet inline; there is no script and no external resource, so the file
opens the same way on any machine, offline. The page states the fcomp
version, the command and the configuration that produced it. Text is
HTML-escaped; in paragraphs, list items and table cells a pair of
backticks marks code (```Fc```).
"""

from __future__ import annotations

import base64
import html
import json
import math
import platform
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from fcomp.errors import FcompError
from fcomp.version import __version__

__all__ = ["Comparison", "Link", "Report", "atomic_write_text", "format_value",
           "notebook_html", "render_png"]

_CSS = """
:root { --fg:#1d2430; --muted:#5b6577; --line:#d9dee7; --bg:#ffffff; --soft:#f4f6fa;
  --ok:#1f7a3d; --okbg:#e6f4ea; --warn:#8a5a00; --warnbg:#fff4d6; --bad:#a1261b;
  --badbg:#fde8e6; --acc:#2356a8; }
* { box-sizing: border-box; }
html { -webkit-text-size-adjust: 100%; }
body { margin: 0; color: var(--fg); background: var(--bg);
  font: 16px/1.55 system-ui, -apple-system, "Segoe UI", Roboto, Helvetica, Arial, sans-serif; }
main { max-width: 64rem; margin: 0 auto; padding: 1.5rem 1rem 3rem; }
h1 { font-size: 1.7rem; line-height: 1.25; margin: 0 0 .3rem; }
h2 { font-size: 1.3rem; margin: 2.2rem 0 .6rem; padding-bottom: .25rem;
  border-bottom: 1px solid var(--line); }
h3 { font-size: 1.08rem; margin: 1.5rem 0 .5rem; }
p, ul, ol { margin: .55rem 0; }
.subtitle { color: var(--muted); margin: 0 0 1rem; }
code, pre { font-family: ui-monospace, SFMono-Regular, Menlo, Consolas, monospace;
  font-size: .9em; }
code { background: var(--soft); padding: .05em .3em; border-radius: 3px; }
pre { background: var(--soft); padding: .7rem .9rem; border-radius: 6px; overflow-x: auto;
  white-space: pre; }
pre code { background: none; padding: 0; }
nav.toc { background: var(--soft); border-radius: 6px; padding: .6rem 1rem; margin: 1rem 0; }
nav.toc ol { margin: .2rem 0; padding-left: 1.3rem; }
nav.toc ul { margin: .2rem 0; padding-left: 0; list-style: none; }
a { color: var(--acc); }
.table-wrap { overflow-x: auto; margin: .8rem 0; -webkit-overflow-scrolling: touch; }
table { border-collapse: collapse; font-size: .93rem; min-width: 50%; }
caption { caption-side: top; text-align: left; color: var(--muted); padding: 0 0 .35rem;
  font-size: .92rem; }
th, td { border-bottom: 1px solid var(--line); padding: .3rem .65rem; text-align: left;
  vertical-align: top; }
th { background: var(--soft); font-weight: 600; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
@media (min-width: 48rem) { th, td { padding: .3rem .45rem; }
  td { overflow-wrap: anywhere; } td.num { overflow-wrap: normal; } }
tr.match td.status { color: var(--ok); }
tr.differs td.status { color: var(--bad); }
tr.na td.status { color: var(--muted); }
figure { margin: 1.2rem 0; }
figure img, figure svg { max-width: 100%; height: auto; display: block;
  border: 1px solid var(--line); border-radius: 4px; }
figcaption { color: var(--muted); font-size: .92rem; margin-top: .35rem; }
.note { border-left: 4px solid var(--acc); background: var(--soft); padding: .5rem .8rem;
  margin: .8rem 0; border-radius: 0 4px 4px 0; }
.note.ok { border-color: var(--ok); background: var(--okbg); }
.note.warn { border-color: var(--warn); background: var(--warnbg); }
.note.bad { border-color: var(--bad); background: var(--badbg); }
footer { margin-top: 3rem; padding-top: .8rem; border-top: 1px solid var(--line);
  color: var(--muted); font-size: .88rem; }
dl.meta { display: grid; grid-template-columns: max-content 1fr; gap: .2rem 1rem; margin: .5rem 0; }
dl.meta dt { font-weight: 600; }
dl.meta dd { margin: 0; overflow-wrap: anywhere; }
@media (max-width: 40rem) { body { font-size: 15px; } main { padding: 1rem .6rem 2rem; } }
@media print { nav.toc { display: none; } a { color: inherit; } }
"""

_NOTE_KINDS = ("info", "ok", "warn", "bad")
#: A heading that carries its own number ("2. ", "3.1 ", "A. ").
_NUMBERED = re.compile(r"^\s*(\d+\.(\d+\.?)*|[A-Z]\.)\s")


def format_value(value: Any, digits: int | None = None) -> str:
    """A number as text: ``digits`` decimals if given, else 4 significant digits.

    ``None`` and NaN print as an en dash; non-numbers print with ``str``.
    """
    if value is None:
        return "\u2013"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if not isinstance(value, int | float):
        try:
            value = float(value)  # numpy scalars
        except (TypeError, ValueError):
            return str(value)
    if math.isnan(value):
        return "\u2013"
    if math.isinf(value):
        return "\u221e" if value > 0 else "-\u221e"
    if digits is not None:
        return f"{value:.{digits}f}"
    if isinstance(value, int):
        return str(value)
    return f"{value:.4g}"


@dataclass(frozen=True)
class Link:
    """A hyperlink in a table cell or list item (relative links for sibling reports)."""

    text: str
    href: str


@dataclass(frozen=True)
class Comparison:
    """A computed number beside the number the source prints.

    Attributes
    ----------
    name
        What the number is.
    value
        The value computed here.
    paper
        The value the source prints (``None`` where it prints none).
    unit
        SI unit, shown in its own column.
    digits
        Decimals the source prints; ``value`` is rounded to as many for the
        comparison ("reproduced to the printed digits").
    note
        Where and why the two differ (or how the value was obtained).
    """

    name: str
    value: float | None
    paper: float | None
    unit: str = ""
    digits: int = 3
    note: str = ""

    @property
    def status(self) -> str:
        """``"match"`` (equal to the printed digits), ``"differs"`` or ``"n/a"``."""
        if self.value is None or self.paper is None:
            return "n/a"
        same = format_value(self.value, self.digits) == format_value(self.paper, self.digits)
        return "match" if same else "differs"

    @property
    def difference(self) -> float | None:
        if self.value is None or self.paper is None:
            return None
        return float(self.value) - float(self.paper)


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file and a rename (no half-written file;
    :func:`fcomp.outputs.write_text`)."""
    from fcomp.outputs import write_text

    return write_text(path, text)


def inline(text: str) -> str:
    """Escape ``text``; ```code``` spans become ``<code>``."""
    parts = str(text).split("`")
    out = []
    for i, part in enumerate(parts):
        esc = html.escape(part, quote=False)
        out.append(f"<code>{esc}</code>" if i % 2 == 1 and i < len(parts) - 1 else esc)
    if len(parts) % 2 == 0:  # an unpaired backtick: keep it literally
        out[-1] = "`" + out[-1]
    return "".join(out)


def _cell(value: Any, digits: int | None = None) -> tuple[str, bool]:
    """HTML of a table cell and whether it is numeric."""
    if isinstance(value, Link):
        return f'<a href="{html.escape(value.href)}">{inline(value.text)}</a>', False
    numeric = isinstance(value, int | float) and not isinstance(value, bool)
    if not numeric:
        try:
            import numpy as np

            numeric = isinstance(value, np.number)
        except ImportError:  # pragma: no cover - numpy is a dependency
            numeric = False
    if numeric:
        return html.escape(_tiny(value, digits) or format_value(value, digits)), True
    return inline("" if value is None else str(value)), False


def _tiny(value: Any, digits: int | None) -> str | None:
    """``"< 0.001"`` for a non-zero number that ``digits`` decimals would show as zero
    (never a bare ``0.000`` for something that is not zero); ``None`` otherwise."""
    if digits is None or digits < 1:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    step = 10.0 ** -digits
    if v == 0.0 or not math.isfinite(v) or abs(v) >= step / 2:
        return None
    return f"< {step:.{digits}f}" if v > 0 else f"> -{step:.{digits}f}"


def _slug(text: str, taken: set[str]) -> str:
    base = re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-") or "section"
    slug, i = base, 2
    while slug in taken:
        slug, i = f"{base}-{i}", i + 1
    taken.add(slug)
    return slug


def _svg_inline(svg: str) -> str:
    """An SVG document made embeddable: no XML prolog, no DOCTYPE (it names a remote DTD)."""
    svg = re.sub(r"<\?xml[^>]*\?>", "", svg)
    svg = re.sub(r"<!DOCTYPE[^>]*>", "", svg, flags=re.S)
    return svg.strip()


class Report:
    """A single-file HTML report, built by chaining.

    Parameters
    ----------
    title
        Page title and top heading.
    subtitle
        One line under the title.
    command
        The command line that produced the report (shown in the footer).
    config
        The configuration (JSON-serialisable mapping) that produced it.
    table_label, figure_label
        Words before the numbers of table and figure captions (a report about
        a paper may say ``"Report table"`` so as not to clash with the paper's
        own table numbers).
    """

    def __init__(
        self,
        title: str,
        *,
        subtitle: str | None = None,
        command: str | None = None,
        config: Mapping[str, Any] | None = None,
        table_label: str = "Table",
        figure_label: str = "Figure",
    ) -> None:
        if not title or not str(title).strip():
            raise FcompError("a report needs a non-empty title")
        self.title = str(title)
        self.subtitle = subtitle
        self.command = command
        self.config = dict(config) if config else {}
        self.table_label = table_label
        self.figure_label = figure_label
        self._blocks: list[str] = []
        self._toc: list[tuple[int, str, str]] = []
        self._slugs: set[str] = set()
        self._figures = 0
        self._tables = 0

    # ------------------------------------------------------------------ blocks
    def section(self, heading: str, *, level: int = 2) -> Report:
        """Start a section (``level`` 2) or sub-section (``level`` 3)."""
        if level not in (2, 3):
            raise FcompError(f"section level must be 2 or 3, got {level}")
        slug = _slug(heading, self._slugs)
        self._toc.append((level, slug, heading))
        self._blocks.append(f'<h{level} id="{slug}">{inline(heading)}</h{level}>')
        return self

    def paragraph(self, text: str) -> Report:
        """A paragraph of plain text (escaped; ```code``` spans allowed)."""
        self._blocks.append(f"<p>{inline(text)}</p>")
        return self

    def bullets(self, items: Iterable[Any], *, ordered: bool = False) -> Report:
        """A bulleted (or numbered) list; items may be :class:`Link`."""
        tag = "ol" if ordered else "ul"
        lis = "".join(f"<li>{_cell(item)[0]}</li>" for item in items)
        self._blocks.append(f"<{tag}>{lis}</{tag}>")
        return self

    def note(self, text: str, *, kind: str = "info") -> Report:
        """A highlighted remark: ``kind`` is ``info``, ``ok``, ``warn`` or ``bad``."""
        if kind not in _NOTE_KINDS:
            raise FcompError(f"note kind must be one of {', '.join(_NOTE_KINDS)}, got {kind!r}")
        self._blocks.append(f'<div class="note {kind}"><p>{inline(text)}</p></div>')
        return self

    def markup(self, html_text: str) -> Report:
        """A block of markup the caller built and escaped (e.g. the study index's cards)."""
        self._blocks.append(html_text)
        return self

    def conclusion(self, found: Any, *, first: bool = False) -> Report:
        """The report's opening: what was found, how sure, what next.

        ``found`` is a :class:`fcomp.conclusions.Conclusion` (or any object with its
        ``finding``, ``confidence``, ``reasons`` and ``next_steps``); shown as a note in
        the one colour rule of every report (:func:`fcomp.conclusions.tone`: the worse of
        what it says and how sure it is), every reason listed; ``first``: before every
        block added so far (the report opens with it).
        """
        from fcomp.conclusions import tone

        kind = tone(getattr(found, "outcome", None), found.confidence)
        reasons = "".join(f"<li>{inline(r)}</li>" for r in found.reasons)
        steps = "".join(f"<li>{inline(s)}</li>" for s in found.next_steps)
        self._blocks.insert(
            0 if first else len(self._blocks),
            f'<div class="note {kind} conclusion"><p><strong>Conclusion:</strong> '
            f"{inline(found.finding)}</p><p><strong>How sure:</strong> "
            f"{inline(found.confidence)}" + (", because" if reasons else "") + "</p>"
            + (f"<ul>{reasons}</ul>" if reasons else "")
            + (f"<p><strong>Next:</strong></p><ul>{steps}</ul>" if steps else "") + "</div>")
        return self

    def code(self, text: str) -> Report:
        """A preformatted block (commands, configuration)."""
        self._blocks.append(f"<pre><code>{html.escape(text)}</code></pre>")
        return self

    def table(
        self,
        header: Sequence[str],
        rows: Iterable[Sequence[Any]],
        *,
        caption: str | None = None,
        digits: int | Sequence[int | None] | None = None,
        row_classes: Sequence[str] | None = None,
    ) -> Report:
        """A table; numbers right-aligned and formatted (``digits`` decimals, per column or all).

        Cells may be numbers, text (```code``` allowed), ``None`` or :class:`Link`.
        """
        ncol = len(header)
        if ncol == 0:
            raise FcompError("a table needs at least one column")
        col_digits = list(digits) if isinstance(digits, Sequence) else [digits] * ncol
        if len(col_digits) != ncol:
            raise FcompError(f"digits has {len(col_digits)} entries for {ncol} columns")
        self._tables += 1
        parts = ['<div class="table-wrap"><table>']
        if caption:
            parts.append(f"<caption>{html.escape(self.table_label)} {self._tables}. "
                         f"{inline(caption)}</caption>")
        parts.append("<thead><tr>" + "".join(f'<th scope="col">{inline(h)}</th>'
                                             for h in header) + "</tr></thead><tbody>")
        for i, row in enumerate(rows):
            row = list(row)
            if len(row) != ncol:
                raise FcompError(f"table row {i + 1} has {len(row)} cells for {ncol} columns")
            cls = f' class="{html.escape(row_classes[i])}"' if row_classes else ""
            tds = []
            for j, value in enumerate(row):
                text, numeric = _cell(value, col_digits[j])
                klass = ["num"] if numeric else []
                if header[j].lower() == "status":
                    klass.append("status")
                attr = f' class="{" ".join(klass)}"' if klass else ""
                tds.append(f"<td{attr}>{text}</td>")
            parts.append(f"<tr{cls}>" + "".join(tds) + "</tr>")
        parts.append("</tbody></table></div>")
        self._blocks.append("".join(parts))
        return self

    def comparison(self, items: Sequence[Comparison], *, caption: str | None = None) -> Report:
        """Computed values beside the source's printed values, with match status and notes."""
        rows = []
        for c in items:
            diff = c.difference
            rows.append([
                c.name,
                format_value(c.value, c.digits),
                format_value(c.paper, c.digits),
                c.unit,
                "" if diff is None else f"{diff:+.{c.digits + 1}f}",
                c.status,
                c.note,
            ])
        return self.table(
            ["quantity", "computed here", "paper", "unit", "difference", "status", "note"],
            rows, caption=caption, row_classes=[c.status.replace("/", "") for c in items],
        )

    def parameters(self, values: Mapping[str, Any], *, heading: str = "Parameters",
                   caption: str | None = None, units: Mapping[str, str] | None = None
                   ) -> Report:
        """A parameters section: name / value table (nested mappings shown as JSON); with
        ``units`` (name -> unit, ``"-"`` for a pure number) a unit column."""
        self.section(heading)
        rows = [[k, json.dumps(v) if isinstance(v, Mapping | list | tuple) else v]
                for k, v in values.items()]
        if units is None:
            return self.table(["parameter", "value"], rows, caption=caption)
        return self.table(["parameter", "value", "unit"],
                          [[*r, units.get(str(r[0]), "") or "-"] for r in rows],
                          caption=caption)

    def figure(self, fig: Any, caption: str, *, alt: str | None = None, dpi: int | None = None,
               fmt: str = "png") -> Report:
        """Embed a figure with a numbered caption.

        Parameters
        ----------
        fig
            A matplotlib ``Figure`` (rendered here and closed), PNG bytes, SVG
            text, or the path of a ``.png``/``.svg`` file.
        caption
            What the figure shows and how to read it.
        dpi
            Dots per inch of a matplotlib figure's PNG (default
            :data:`fcomp.figstyle.DPI`: shown at its natural size in the column).
        fmt
            ``"png"`` (base64) or ``"svg"`` (inline) for a matplotlib figure.
        """
        if fmt not in ("png", "svg"):
            raise FcompError(f"figure format must be png or svg, got {fmt!r}")
        self._figures += 1
        label = f"{html.escape(self.figure_label)} {self._figures}."
        alt_text = html.escape(alt or caption)
        if isinstance(fig, str | Path) and not str(fig).lstrip().startswith("<"):
            path = Path(fig)
            if not path.is_file():
                raise FcompError(f"figure file {path} does not exist")
            fmt = "svg" if path.suffix.lower() == ".svg" else "png"
            fig = path.read_text() if fmt == "svg" else path.read_bytes()
        elif isinstance(fig, str):
            fmt = "svg"
        elif not isinstance(fig, bytes | bytearray):
            fig = _render(fig, fmt, dpi)
        if fmt == "svg":
            body = _svg_inline(fig.decode() if isinstance(fig, bytes | bytearray) else fig)
            body = body.replace("<svg", f'<svg role="img" aria-label="{alt_text}"', 1)
        else:
            data = base64.b64encode(bytes(fig)).decode("ascii")
            body = f'<img src="data:image/png;base64,{data}" alt="{alt_text}">'
        self._blocks.append(
            f"<figure>{body}<figcaption><strong>{label}</strong> {inline(caption)}"
            "</figcaption></figure>"
        )
        return self

    # ------------------------------------------------------------------ output
    def to_html(self) -> str:
        """The complete HTML5 document."""
        now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
        head = (
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
            f"<meta name=\"generator\" content=\"fcomp {html.escape(__version__)}\">\n"
            f"<title>{html.escape(self.title)}</title>\n<style>{_CSS}</style>\n</head>\n"
        )
        parts = [head, "<body>\n<main>\n<header>", f"<h1>{inline(self.title)}</h1>"]
        if self.subtitle:
            parts.append(f'<p class="subtitle">{inline(self.subtitle)}</p>')
        parts.append("</header>")
        if sum(1 for lvl, _, _ in self._toc if lvl == 2) >= 3:
            items = "".join(f'<li><a href="#{slug}">{inline(h)}</a></li>'
                            for lvl, slug, h in self._toc if lvl == 2)
            # headings that carry their own numbers ("2. Where the model fails") are listed
            # as written, not numbered again ("2. 2. Where ...")
            numbered = any(_NUMBERED.match(h) for lvl, _, h in self._toc if lvl == 2)
            tag = "ul" if numbered else "ol"
            parts.append(f'<nav class="toc" aria-label="Contents"><strong>Contents</strong>'
                         f"<{tag}>{items}</{tag}></nav>")
        parts.extend(self._blocks)
        meta = [("fcomp version", __version__),
                ("Python", platform.python_version()),
                ("generated", now)]
        if self.command:
            meta.insert(1, ("command", self.command))
        dl = "".join(f"<dt>{html.escape(k)}</dt><dd>{inline(f'`{v}`' if k == 'command' else v)}"
                     "</dd>" for k, v in meta)
        parts.append(f'<footer><dl class="meta">{dl}</dl>')
        if self.config:
            cfg = json.dumps(self.config, indent=2, sort_keys=True, default=str)
            parts.append(f"<p>Configuration:</p><pre><code>{html.escape(cfg)}</code></pre>")
        parts.append("</footer>\n</main>\n</body>\n</html>\n")
        return "\n".join(parts)

    def write(self, path: str | Path) -> Path:
        """Write the report to ``path`` (atomically) and return the path."""
        path = Path(path)
        if path.exists() and path.is_dir():
            raise FcompError(f"{path}: is a directory, cannot write the report there")
        return atomic_write_text(path, self.to_html())


def _render(fig: Any, fmt: str, dpi: int | None) -> bytes:
    """Render a matplotlib figure to PNG or SVG bytes in the report style and close it
    (:func:`fcomp.figstyle.save`: a PNG records its smallest font and its dpi)."""
    from fcomp.figstyle import DPI, save

    if not hasattr(fig, "savefig"):
        raise FcompError(f"cannot embed a {type(fig).__name__} as a figure")
    return save(fig, fmt=fmt, dpi=dpi or DPI)


def render_png(fig: Any, *, dpi: int | None = None) -> bytes:
    """PNG bytes of a matplotlib figure in the report style (the figure is closed; ``dpi``
    defaults to :data:`fcomp.figstyle.DPI`)."""
    return _render(fig, "png", dpi)


def notebook_html(title: str, rows: Iterable[Sequence[Any]], fig: Any = None) -> str:
    """A small HTML block for Jupyter's ``_repr_html_``: a title, a table of ``rows`` (cells
    as text) and a figure (a matplotlib figure, embedded as PNG; closed)."""
    cells = "".join("<tr>" + "".join(
        f"<td style='text-align:{'right' if i else 'left'}'>{html.escape(str(c))}</td>"
        for i, c in enumerate(row)) + "</tr>" for row in rows)
    img = ""
    if fig is not None:
        data = base64.b64encode(render_png(fig, dpi=80)).decode("ascii")
        img = (f'<img src="data:image/png;base64,{data}" style="max-width:100%" '
               f'alt="{html.escape(title)}">')
    return (f"<div class='fcomp'><strong>{html.escape(title)}</strong>"
            f"<table>{cells}</table>{img}</div>")
