"""Every report, checked as a reader would: rendered in headless Chromium, validated as HTML.

``fcomp study all --fast`` builds the site once (:func:`helpers.browser.build_site`);
every page (the index, each study's report and the diagnosis reports it
links) is opened in Chromium at desktop widths (1400 px, 1280 px) and a phone
width: every figure must load and show, nothing may stick out of the page
(wide tables scroll inside their frame), the page must not scroll sideways;
the markup must parse without a single HTML5 parse error and reference
nothing outside itself except sibling pages.

The command reports (``fit``, ``compare``, ``diagnose``, ``sweep``,
``compensate``) are built once from a short synthetic record. Every report,
site and command, is measured at 1400 px (100 % zoom on a desktop): no table
wider than its column, and no figure text below 9 pt as displayed (each PNG
records its smallest drawn font and dpi; the page gives the displayed width).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from helpers.browser import (
    CHROMIUM,
    Browser,
    figure_text_problems,
    page_problems,
    table_problems,
    validate_html,
)

from studies import STUDIES

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("site")]  # builds the study site or runs long diagnoses

#: A desktop at 100 % zoom (the width the figures and tables are measured at), a laptop, a phone.
DESKTOP = 1400
WIDTHS = (DESKTOP, 1280, 390)
#: The commands that write a report (built by :func:`command_reports`).
COMMANDS = ("fit", "compare", "diagnose", "sweep", "compensate")
ROOT = Path(__file__).resolve().parents[1]


def _studies() -> list[str]:
    return [n for n in STUDIES.names() if n != "all"]


def _pages(out: Path) -> list[Path]:
    pages = [out / "index.html"]
    for name in _studies():
        pages.append(out / name / "report.html")
        pages.extend(sorted((out / name).glob("*/report.html")))  # linked sub-reports
    return pages


def _render_all(pages: list[Path], root: Path) -> dict[tuple[str, int], dict]:
    assert Path(CHROMIUM).exists(), (
        f"{CHROMIUM} is missing: install Debian's chromium package (.ci/run does)")
    out = {}
    with Browser() as b:
        for page in pages:
            for w in WIDTHS:
                out[(str(page.relative_to(root)), w)] = b.render(page, width=w)
    return out


@pytest.fixture(scope="module")
def rendered(site: Path) -> dict[tuple[str, int], dict]:
    return _render_all(_pages(site), site)


@pytest.fixture(scope="module")
def command_reports(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``DIR/COMMAND/report.html`` of every command in :data:`COMMANDS`, from a 12 s synthetic
    record (pressure-dependent friction) and short closed-loop runs."""
    from fcomp.cli.main import main
    from fcomp.models import make_model
    from fcomp.synthetic import generate

    out = tmp_path_factory.mktemp("command-reports")
    rec = out / "rec.csv"
    generate(["pressure-dependence"], duration=12.0, seed=1).measurement.write(rec)
    lugre = make_model("lugre", params="seed002-type1")
    lugre.with_effects("direction-asymmetry").with_params(r_neg=1.5).save(out / "true.json")
    lugre.save(out / "base.json")
    runs = {
        "fit": ["fit", str(rec), "--friction", "lugre", "--json", str(out / "fit.json")],
        "compare": ["compare", str(rec), "--friction", "lugre", "--params",
                    str(out / "fit.json")],
        "diagnose": ["diagnose", str(rec), "--friction", "lugre", "--jobs", "1",
                     "--candidates", "pressure-dependence,force-offset,stribeck"],
        "sweep": ["sweep", "--controllers", "pid,pid-ff", "--samples", "2", "--jobs", "1"],
        "compensate": ["compensate", "--plant-params", str(ROOT / "docs/examples/axis50.toml"),
                       "--friction", str(out / "true.json"), "--controller-friction",
                       f"{out / 'base.json'},{out / 'true.json'}", "--controllers", "pid-ff",
                       "--task", "steps", "--fast", "--samples", "1", "--jobs", "1"],
    }
    for name in COMMANDS:
        code = main([*runs[name], "--report", str(out / name), "--no-progress"])
        assert code == 0, f"fcomp {name} exited {code}"
    return out


@pytest.fixture(scope="module")
def rendered_commands(command_reports: Path) -> dict[tuple[str, int], dict]:
    return _render_all([command_reports / c / "report.html" for c in COMMANDS],
                       command_reports)


def _groups() -> list[str]:
    """What the 1400 px checks are parametrized by: the site's index, each study (its report
    and the reports it links) and each command's report."""
    return ["index", *_studies(), *(f"fcomp-{c}" for c in COMMANDS)]


def _group_pages(group: str, request: pytest.FixtureRequest) -> list[tuple[Path, dict]]:
    """The pages of ``group`` and their rendering at :data:`DESKTOP` px."""
    if group.startswith("fcomp-"):
        root = request.getfixturevalue("command_reports")
        rendered = request.getfixturevalue("rendered_commands")
        pages = [root / group.removeprefix("fcomp-") / "report.html"]
    else:
        root = request.getfixturevalue("site")
        rendered = request.getfixturevalue("rendered")
        pages = ([root / "index.html"] if group == "index" else
                 [root / group / "report.html", *sorted((root / group).glob("*/report.html"))])
    return [(p, rendered[(str(p.relative_to(root)), DESKTOP)]) for p in pages]


@pytest.mark.parametrize("group", _groups())
def test_tables_fit_the_column_at_1400px(group: str, request: pytest.FixtureRequest) -> None:
    """At a 1400 px desktop no table needs its scroll bar, and nothing sticks out."""
    problems = []
    for page, rep in _group_pages(group, request):
        problems += [f"{page.name} ({page.parent.name}): {p}"
                     for p in table_problems(rep) + page_problems(rep)]
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("group", _groups())
def test_figure_text_at_least_9pt_at_1400px(group: str, request: pytest.FixtureRequest) -> None:
    """Every figure's smallest text, as displayed at 1400 px and 100 % zoom, is 9 pt or more."""
    problems = []
    for page, rep in _group_pages(group, request):
        problems += [f"{page.parent.name}/{page.name}: {p}"
                     for p in figure_text_problems(page, rep)]
    assert not problems, "\n".join(problems)


def test_command_reports_read_at_every_width(command_reports: Path,
                                              rendered_commands: dict) -> None:
    """The command reports load, show every figure and validate, at every width."""
    problems = []
    for (page, width), rep in rendered_commands.items():
        assert rep["readyState"] == "complete"
        assert rep["images"], f"{page}: no figure"
        problems += [f"{page} @ {width}px: {p}" for p in page_problems(rep)]
    for name in COMMANDS:
        problems += [f"{name}: {e}" for e in
                     validate_html((command_reports / name / "report.html").read_text())]
    assert not problems, "\n".join(problems)


def test_site_has_every_study(site: Path) -> None:
    index = (site / "index.html").read_text(encoding="utf-8")
    for name in _studies():
        folder = site / name
        assert (folder / "summary.json").is_file(), name
        assert (folder / "report.html").is_file(), name
        assert f'href="{name}/report.html"' in index, name
        assert list(folder.glob("fig-*.png")), f"{name}: no figure file"


def test_every_figure_loads_and_nothing_is_cut_off(site: Path, rendered: dict) -> None:
    problems = []
    for (page, width), rep in rendered.items():
        assert rep["readyState"] == "complete"
        assert rep["text"] > 200, f"{page}: almost no text"
        problems += [f"{page} @ {width}px: {p}" for p in page_problems(rep)]
    assert not problems, "\n".join(problems)


def test_each_figure_file_is_in_its_report(site: Path, rendered: dict) -> None:
    for name in _studies():
        n_files = len(list((site / name).glob("fig-*.png")))
        rep = rendered[(f"{name}/report.html", WIDTHS[0])]
        assert len(rep["images"]) + len(rep["svgs"]) >= n_files > 0, name
        assert all(img["naturalWidth"] > 100 and img["naturalHeight"] > 100
                   for img in rep["images"]), name


def test_reports_state_version_and_parameters(site: Path) -> None:
    from fcomp import __version__

    for page in _pages(site):
        text = page.read_text(encoding="utf-8")
        assert f"fcomp {__version__}" in text or __version__ in text, page
        assert "<footer>" in text, page
    for name in _studies():
        text = (site / name / "report.html").read_text(encoding="utf-8")
        assert re.search(r">\s*Parameters\s*<|>\s*Settings\s*<", text), name


@pytest.mark.parametrize("width", WIDTHS)
def test_no_horizontal_scroll(rendered: dict, width: int) -> None:
    wide = [p for (p, w), r in rendered.items() if w == width and r["overflow"]]
    assert not wide, wide


def test_html_validates(site: Path) -> None:
    errors = []
    for page in _pages(site):
        errors += [f"{page.relative_to(site)}: {e}" for e in
                   validate_html(page.read_text(encoding="utf-8"))]
    assert not errors, "\n".join(errors[:20])


def test_self_contained_and_links_resolve(site: Path) -> None:
    for page in _pages(site):
        text = page.read_text(encoding="utf-8")
        assert "<script" not in text.lower(), page
        for _attr, ref in re.findall(r'\b(src|href)="([^"]*)"', text):
            if ref.startswith(("data:", "#")):
                continue
            assert "://" not in ref and not ref.startswith("//"), f"{page}: external {ref}"
            assert (page.parent / ref).exists(), f"{page}: broken link {ref}"


def test_validator_and_probe_catch_faults(tmp_path: Path) -> None:
    """The checks can fail: a broken image, a too-wide element and bad markup are caught."""
    bad = tmp_path / "bad.html"
    bad.write_text(
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>x</title>"
        "</head><body><main><p>" + "some text " * 40 + "</p>"
        "<figure><img src=\"data:image/png;base64,AAAA\" alt=\"broken\">"
        "<figcaption>c</figcaption></figure>"
        "<div style=\"width:3000px\">wide</div></main></body></html>", encoding="utf-8")
    with Browser() as b:
        rep = b.render(bad, width=800)
    probs = page_problems(rep)
    assert any("did not load" in p for p in probs)
    assert any("wider than the viewport" in p for p in probs)
    assert validate_html("<!DOCTYPE html><html><body><p>a</div></body></html>")


def _png(fontsize: float, width: float = 6.0, record: bool = True) -> bytes:
    """A PNG drawn here at 100 dpi (not by fcomp), ``width`` inches wide, with or without the
    font record."""
    import io

    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, 2.0))
    ax = fig.add_subplot()
    ax.plot([0, 1], [0, 1])
    ax.tick_params(labelsize=fontsize)
    buf = io.BytesIO()
    meta = {"fcomp:min_font_pt": str(fontsize), "fcomp:dpi": "100"} if record else {}
    fig.savefig(buf, format="png", dpi=100, metadata=meta)
    return buf.getvalue()


def test_table_and_figure_text_checks_catch_faults(tmp_path: Path) -> None:
    """A table wider than the column, small figure text (drawn small, or a wide PNG shown
    scaled down to the column) and a PNG without the record are caught; a readable figure
    passes."""
    import base64

    def img(png: bytes, alt: str) -> str:
        return (f'<figure><img src="data:image/png;base64,{base64.b64encode(png).decode()}" '
                f'alt="{alt}" style="max-width:100%"><figcaption>{alt}</figcaption></figure>')

    cells = "".join(f"<th>a long column header {i}</th>" for i in range(20))
    bad = tmp_path / "bad.html"
    bad.write_text(
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>x</title>"
        "</head><body><main style=\"max-width:60rem\"><div class=\"table-wrap\" "
        "style=\"overflow-x:auto\"><table><caption>wide</caption><tr>" + cells +
        "</tr></table></div>" + img(_png(7), "small") + img(_png(9, width=20.0), "scaled") +
        img(_png(9, record=False), "bare") + img(_png(9), "fine") +
        "</main></body></html>", encoding="utf-8")
    with Browser() as b:
        rep = b.render(bad, width=DESKTOP)
    tables = table_problems(rep)
    assert len(tables) == 1 and "'wide'" in tables[0]
    figs = figure_text_problems(bad, rep)
    assert [p.split(":")[0] for p in figs] == ["image 1 'small'", "image 2 'scaled'",
                                              "image 3 'bare'"], figs
    assert "no font record" in figs[2]
    assert not validate_html("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
                             "<title>t</title></head><body><p>a</p></body></html>")
