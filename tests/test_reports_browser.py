"""The report site, checked as a reader would: rendered in headless Chromium, validated as HTML.

``fcomp study all --fast`` builds the site once (:func:`helpers.browser.build_site`);
every page (the index, each study's report and the diagnosis reports it
links) is opened in Chromium at a desktop and a phone width: every figure
must load and show, nothing may stick out of the page (wide tables scroll
inside their frame), the page must not scroll sideways; the markup must
parse without a single HTML5 parse error and reference nothing outside
itself except sibling pages.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from helpers.browser import CHROMIUM, Browser, page_problems, validate_html

from studies import STUDIES

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("site")]  # builds the study site or runs long diagnoses

WIDTHS = (1280, 390)


def _studies() -> list[str]:
    return [n for n in STUDIES.names() if n != "all"]


def _pages(out: Path) -> list[Path]:
    pages = [out / "index.html"]
    for name in _studies():
        pages.append(out / name / "report.html")
        pages.extend(sorted((out / name).glob("*/report.html")))  # linked sub-reports
    return pages


@pytest.fixture(scope="module")
def rendered(site: Path) -> dict[tuple[str, int], dict]:
    assert Path(CHROMIUM).exists(), (
        f"{CHROMIUM} is missing: install Debian's chromium package (.ci/run does)")
    out = {}
    with Browser() as b:
        for page in _pages(site):
            for w in WIDTHS:
                out[(str(page.relative_to(site)), w)] = b.render(page, width=w)
    return out


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
    assert not validate_html("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
                             "<title>t</title></head><body><p>a</p></body></html>")
