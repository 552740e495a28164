"""The HTML report builder: one valid, self-contained HTML5 file."""

from __future__ import annotations

import base64
import re
from html.parser import HTMLParser
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

from fcomp import __version__  # noqa: E402
from fcomp.errors import FcompError  # noqa: E402
from fcomp.report import Comparison, Link, Report, format_value  # noqa: E402

VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source",
        "track", "wbr", "path", "rect", "circle", "line", "polyline", "polygon", "use", "stop",
        "ellipse"}


class _Checker(HTMLParser):
    """Tag balance, resource references and a few HTML5 essentials."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.errors: list[str] = []
        self.seen: dict[str, int] = {}
        self.refs: list[tuple[str, str, str]] = []
        self.decl: list[str] = []

    def handle_decl(self, decl: str) -> None:
        self.decl.append(decl)

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.seen[tag] = self.seen.get(tag, 0) + 1
        for k, v in attrs:
            if k in ("src", "href", "xlink:href", "data", "poster", "srcset") and v is not None:
                self.refs.append((tag, k, v))
        if tag not in VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.seen[tag] = self.seen.get(tag, 0) + 1
        for k, v in attrs:
            if k in ("src", "href", "xlink:href") and v is not None:
                self.refs.append((tag, k, v))

    def handle_endtag(self, tag: str) -> None:
        if tag in VOID:
            return
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"unexpected </{tag}> (open: {self.stack[-3:]})")
            return
        self.stack.pop()


def check_html(text: str) -> _Checker:
    """Parse ``text``; fail on unbalanced tags, missing essentials or external resources."""
    assert text.startswith("<!DOCTYPE html>")
    c = _Checker()
    c.feed(text)
    c.close()
    assert not c.errors, c.errors
    assert not c.stack, f"unclosed tags: {c.stack}"
    assert c.decl and c.decl[0].lower() == "doctype html"
    for tag in ("html", "head", "body", "title", "main"):
        assert c.seen.get(tag) == 1, tag
    assert re.search(r'<html lang="[a-z]+">', text)
    assert '<meta charset="utf-8">' in text
    assert 'name="viewport"' in text
    assert "<script" not in text.lower()
    assert "@import" not in text
    for ref in re.findall(r"url\(([^)]*)\)", text):  # only in-document references (SVG clips)
        assert ref.strip("'\" ").startswith("#"), ref
    for tag, attr, value in c.refs:
        assert not re.match(r"\s*(https?:)?//", value, re.I), f"external {tag} {attr}={value}"
        if attr == "src":
            assert value.startswith("data:"), f"{tag} src is not embedded: {value[:40]}"
    return c


def _figure() -> plt.Figure:
    fig, ax = plt.subplots(figsize=(3, 2))
    ax.plot([0, 1, 2], [0, 1, 4])
    ax.set_title("a <b> & c")
    return fig


def test_report_is_valid_self_contained_html(tmp_path: Path) -> None:
    rep = (Report("Seed <001> & friends", subtitle="a subtitle", command="fcomp study x --out d",
                  config={"out": "d", "fast": True})
           .section("First")
           .paragraph("Text with `code` and <script>alert(1)</script> & an unpaired ` tick.")
           .bullets(["one", Link("the other report", "other/report.html")])
           .note("careful", kind="warn")
           .table(["name", "value"], [["a", 1.23456], ["b", None], ["c", "text"]],
                  caption="A table", digits=[None, 2])
           .section("Second")
           .comparison([Comparison("x", 1.2254, 1.225, unit="N", digits=3),
                        Comparison("y", 1.2266, 1.225, unit="N", digits=3, note="why"),
                        Comparison("z", 2.0, None)], caption="beside the paper")
           .figure(_figure(), "PNG figure")
           .figure(_figure(), "SVG figure", fmt="svg")
           .section("Third")
           .parameters({"alpha": 0.05, "nested": {"k": [1, 2]}})
           .code("fcomp study coulomb-viscous --out out"))
    path = rep.write(tmp_path / "sub" / "report.html")
    text = path.read_text(encoding="utf-8")
    c = check_html(text)
    # text is escaped, markup only where the builder puts it
    assert "<script>alert(1)</script>" not in text
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in text
    assert "<code>code</code>" in text and "unpaired ` tick" in text
    assert "<title>Seed &lt;001&gt; &amp; friends</title>" in text
    # figures: one base64 PNG that decodes to a PNG, one inline SVG without a DOCTYPE
    pngs = re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', text)
    assert len(pngs) == 1
    assert base64.b64decode(pngs[0]).startswith(b"\x89PNG\r\n\x1a\n")
    assert c.seen.get("svg") == 1 and "<!DOCTYPE svg" not in text and "<?xml" not in text
    assert text.count("<figcaption>") == 2 and "Figure 2." in text
    # comparison: computed beside printed, status by the printed digits
    assert re.search(r'<tr class="match"><td>x</td><td>1.225</td><td>1.225</td>', text)
    assert re.search(r'<tr class="differs"><td>y</td><td>1.227</td><td>1.225</td>', text)
    assert '<tr class="na"><td>z</td>' in text
    # relative link, table numbering, tables scroll, responsive figures
    assert '<a href="other/report.html">the other report</a>' in text
    assert "Table 1. A table" in text and "Table 2. beside the paper" in text
    assert ".table-wrap { overflow-x: auto;" in text and "max-width: 100%" in text
    # provenance: version, command, configuration
    assert f"<dd>{__version__}</dd>" in text
    assert "fcomp study x --out d" in text and "&quot;fast&quot;: true" in text
    # table of contents for three or more sections
    assert '<nav class="toc"' in text and 'href="#second"' in text
    # no temporary file left behind
    assert [p.name for p in path.parent.iterdir()] == ["report.html"]


def test_labels_and_numbers() -> None:
    rep = Report("t", table_label="Report table", figure_label="Fig.")
    rep.table(["a"], [[1]], caption="c").figure(_figure(), "f")
    html = rep.to_html()
    assert "Report table 1. c" in html and "Fig. 1." in html
    assert format_value(None) == "\u2013" and format_value(float("nan")) == "\u2013"
    assert format_value(3) == "3" and format_value(2.0 / 3.0) == "0.6667"
    assert format_value(2.0 / 3.0, 2) == "0.67" and format_value(True) == "yes"


def test_comparison_status() -> None:
    assert Comparison("a", 95.7736, 95.774, digits=3).status == "match"
    assert Comparison("a", 95.7733, 95.774, digits=3).status == "differs"
    assert Comparison("a", 1.0, None).status == "n/a"
    assert Comparison("a", 5.0, 4.5).difference == pytest.approx(0.5)


@pytest.mark.parametrize("call", [
    lambda r: r.table(["a", "b"], [[1]]),
    lambda r: r.table([], []),
    lambda r: r.table(["a"], [[1]], digits=[1, 2]),
    lambda r: r.note("x", kind="loud"),
    lambda r: r.section("x", level=4),
    lambda r: r.figure(object(), "not a figure"),
    lambda r: r.figure(Path("/nonexistent/fig.png"), "missing"),
    lambda r: r.figure(_figure(), "x", fmt="gif"),
])
def test_bad_input_raises_fcomp_error(call) -> None:
    with pytest.raises(FcompError):
        call(Report("t"))


def test_write_refuses_a_directory_and_empty_title(tmp_path: Path) -> None:
    with pytest.raises(FcompError, match="is a directory"):
        Report("t").write(tmp_path)
    with pytest.raises(FcompError, match="title"):
        Report("  ")


def test_figure_from_files(tmp_path: Path) -> None:
    png = tmp_path / "f.png"
    _figure().savefig(png)
    svg = tmp_path / "f.svg"
    _figure().savefig(svg)
    html = Report("t").figure(png, "from png").figure(svg, "from svg").to_html()
    check_html(html)
    assert html.count("data:image/png;base64,") == 1 and html.count("<svg") == 1
