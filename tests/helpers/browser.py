"""Render HTML files in headless Chromium and inspect them as a reader would (test helper).

Chromium (Debian package ``chromium``; ``.ci/run`` installs it) is driven
through the DevTools protocol over ``--remote-debugging-pipe``: JSON
messages separated by NUL bytes on file descriptors 3 (to the browser) and
4 (from it), so nothing but the standard library is needed and no port is
opened. The browser runs with a fresh profile and without network.

>>> with Browser() as b:                                # doctest: +SKIP
...     page = b.render(Path("report.html"), width=1280)
...     page["images"], page["overflow"]

:func:`validate_html` checks the markup with html5lib's strict parser
(WHATWG parsing rules: every parse error fails).
"""

from __future__ import annotations

import atexit
import contextlib
import functools
import json
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

#: The executable (Debian's ``chromium``).
CHROMIUM = os.environ.get("FCOMP_CHROMIUM", "/usr/bin/chromium")
FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-extensions", "--disable-default-apps", "--mute-audio", "--hide-scrollbars",
    "--remote-debugging-pipe",
)

#: What the page reports about itself once loaded (evaluated in the page).
PROBE = r"""
(() => {
  const vw = document.documentElement.clientWidth;
  const inScroller = el => !!el.closest('.table-wrap, pre');
  const images = Array.from(document.images).map(img => {
    const r = img.getBoundingClientRect();
    return {alt: img.alt, complete: img.complete, naturalWidth: img.naturalWidth,
            naturalHeight: img.naturalHeight, width: r.width, height: r.height,
            shownWidth: img.clientWidth,
            left: r.left, right: r.right};
  });
  const svgs = Array.from(document.querySelectorAll('figure svg')).map(s => {
    const r = s.getBoundingClientRect();
    return {width: r.width, height: r.height, left: r.left, right: r.right};
  });
  const cut = [];
  for (const el of document.querySelectorAll('body *')) {
    if (inScroller(el) || el.closest('svg')) continue;
    const r = el.getBoundingClientRect();
    if (r.width === 0 && r.height === 0) continue;
    if (r.left < -0.5 || r.right > vw + 0.5) {
      cut.push({tag: el.tagName.toLowerCase(), left: r.left, right: r.right,
                text: (el.textContent || '').trim().slice(0, 60)});
    }
  }
  const scrollers = Array.from(document.querySelectorAll('.table-wrap')).map(w => {
    const r = w.getBoundingClientRect();
    const cap = w.querySelector('caption');
    return {left: r.left, right: r.right, scrollable: w.scrollWidth > w.clientWidth,
            scrollWidth: w.scrollWidth, clientWidth: w.clientWidth,
            overflowX: getComputedStyle(w).overflowX,
            caption: ((cap && cap.textContent) || '').trim().slice(0, 60)};
  });
  const links = Array.from(document.querySelectorAll('a[href]')).map(a => a.getAttribute('href'));
  return {title: document.title, readyState: document.readyState, viewport: vw,
          scrollWidth: document.documentElement.scrollWidth,
          overflow: document.documentElement.scrollWidth > vw + 0.5,
          images, svgs, cut, scrollers, links,
          figures: document.querySelectorAll('figure').length,
          captions: Array.from(document.querySelectorAll('figcaption')).map(c => c.textContent),
          text: document.body.innerText.length};
})()
"""


class BrowserError(RuntimeError):
    """Chromium could not be started or did not answer."""


class Browser:
    """A headless Chromium driven over the DevTools pipe (module docstring)."""

    def __init__(self, executable: str = CHROMIUM, timeout: float = 60.0) -> None:
        self.executable = executable
        self.timeout = timeout
        self._id = 0
        self._buf = b""
        self.proc: subprocess.Popen[bytes] | None = None

    # ---------------------------------------------------------- lifecycle
    def __enter__(self) -> Browser:
        if not (Path(self.executable).exists() or shutil.which(self.executable)):
            raise BrowserError(f"{self.executable} not found (Debian package 'chromium')")
        self.profile = tempfile.mkdtemp(prefix="fcomp-chromium-")
        to_r, to_w = os.pipe()      # we write commands, the browser reads fd 3
        from_r, from_w = os.pipe()  # the browser writes fd 4, we read

        def child() -> None:
            # move both ends clear of 3 and 4 first, then put them there (inheritable);
            # every other descriptor of ours is non-inheritable and closes on exec
            import fcntl

            a = fcntl.fcntl(to_r, fcntl.F_DUPFD, 10)
            b = fcntl.fcntl(from_w, fcntl.F_DUPFD, 10)
            os.dup2(a, 3)
            os.dup2(b, 4)

        self.stderr = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(
            [self.executable, *FLAGS, f"--user-data-dir={self.profile}", "about:blank"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=self.stderr,
            preexec_fn=child, close_fds=False,
        )
        os.close(to_r)
        os.close(from_w)
        self._w, self._r = to_w, from_r
        self.call("Target.setDiscoverTargets", {"discover": False})
        return self

    def __exit__(self, *exc: Any) -> None:
        try:
            if self.proc and self.proc.poll() is None:
                with contextlib.suppress(BrowserError):
                    self.call("Browser.close", timeout=5.0)
                try:
                    self.proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    self.proc.kill()
                    self.proc.wait(timeout=10)
        finally:
            for fd in (getattr(self, "_w", None), getattr(self, "_r", None)):
                if fd is not None:
                    with contextlib.suppress(OSError):
                        os.close(fd)
            self.stderr.close()
            shutil.rmtree(self.profile, ignore_errors=True)

    # ----------------------------------------------------------- protocol
    def call(self, method: str, params: dict[str, Any] | None = None,
             session: str | None = None, timeout: float | None = None) -> dict[str, Any]:
        """Send one command and return its ``result`` (raise on a protocol error)."""
        self._id += 1
        msg: dict[str, Any] = {"id": self._id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self._w, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + (timeout or self.timeout)
        while True:
            for reply in self._messages(deadline, method):
                if reply.get("id") == self._id:
                    if "error" in reply:
                        raise BrowserError(f"{method}: {reply['error']}")
                    return reply.get("result", {})

    def _messages(self, deadline: float, method: str) -> list[dict[str, Any]]:
        while b"\0" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0:
                raise BrowserError(f"{method}: no answer from Chromium")
            ready, _, _ = select.select([self._r], [], [], left)
            if not ready:
                continue
            chunk = os.read(self._r, 1 << 20)
            if not chunk:
                self.stderr.seek(0)
                err = self.stderr.read().decode(errors="replace")[-2000:]
                raise BrowserError(f"{method}: Chromium closed the pipe\n{err}")
            self._buf += chunk
        *done, self._buf = self._buf.split(b"\0")
        return [json.loads(m) for m in done if m]

    # --------------------------------------------------------------- pages
    def render(self, path: Path, *, width: int = 1280, height: int = 900,
               screenshot: Path | None = None) -> dict[str, Any]:
        """Open ``path`` at a viewport of ``width`` x ``height`` CSS px; return :data:`PROBE`'s report."""
        url = Path(path).resolve().as_uri()
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.call("Target.attachToTarget",
                            {"targetId": target, "flatten": True})["sessionId"]
        try:
            self.call("Emulation.setDeviceMetricsOverride",
                      {"width": width, "height": height, "deviceScaleFactor": 1,
                       "mobile": False}, session)
            self.call("Page.enable", {}, session)
            self.call("Page.navigate", {"url": url}, session)
            deadline = time.monotonic() + self.timeout
            state = ""
            while time.monotonic() < deadline:
                state = self.evaluate("document.readyState + ':' + "
                                      "Array.from(document.images).every(i => i.complete)",
                                      session)
                if state == "complete:true":
                    break
                time.sleep(0.05)
            if state != "complete:true":
                raise BrowserError(f"{path}: the page did not finish loading ({state})")
            report = self.evaluate(PROBE, session)
            if screenshot is not None:
                import base64

                shot = self.call("Page.captureScreenshot", {"format": "png"}, session)
                screenshot.write_bytes(base64.b64decode(shot["data"]))
            return report
        finally:
            self.call("Target.closeTarget", {"targetId": target})

    def evaluate(self, expression: str, session: str) -> Any:
        res = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True},
                        session)
        if "exceptionDetails" in res:
            raise BrowserError(f"script error: {res['exceptionDetails']}")
        return res["result"].get("value")


def page_problems(report: dict[str, Any]) -> list[str]:
    """What a reader would see go wrong on a rendered page (empty when it reads well)."""
    out = []
    if report["overflow"]:
        out.append(f"page wider than the viewport ({report['scrollWidth']} > "
                   f"{report['viewport']} px): horizontal scrolling")
    for img in report["images"]:
        if not img["complete"] or img["naturalWidth"] == 0:
            out.append(f"image did not load: {img['alt'][:60]!r}")
        elif img["width"] < 1 or img["height"] < 1:
            out.append(f"image not displayed: {img['alt'][:60]!r}")
        elif img["left"] < -0.5 or img["right"] > report["viewport"] + 0.5:
            out.append(f"image cut off ({img['left']:.0f}..{img['right']:.0f} px): "
                       f"{img['alt'][:60]!r}")
    for svg in report["svgs"]:
        if svg["width"] < 1 or svg["right"] > report["viewport"] + 0.5:
            out.append("inline SVG figure not displayed or cut off")
    for el in report["cut"]:
        out.append(f"<{el['tag']}> outside the viewport ({el['left']:.0f}..{el['right']:.0f} "
                   f"px): {el['text']!r}")
    for w in report["scrollers"]:
        if w["scrollable"] and w["overflowX"] not in ("auto", "scroll"):
            out.append("a wide table is clipped without a scroll bar")
    if report["figures"] != len(report["captions"]):
        out.append("a figure without a caption")
    return out


def validate_html(text: str) -> list[str]:
    """HTML5 parse errors of ``text`` (html5lib, strict WHATWG parsing); empty when valid."""
    import html5lib

    parser = html5lib.HTMLParser(strict=False, namespaceHTMLElements=False)
    parser.parse(text)
    return [f"line {pos[0]} col {pos[1]}: {code} {data or ''}".strip()
            for pos, code, data in parser.errors]


# ------------------------------------------------------------------ the site
SITE_TIMEOUT = 1500.0


@functools.cache
def build_site() -> tuple[Path, int, str]:
    """``fcomp study all --fast`` once per test process: ``(DIR, exit status, stderr)``.

    The study tests and the browser test share this one run (``functools.cache``);
    the folder is removed when the process ends.
    """
    out = Path(tempfile.mkdtemp(prefix="fcomp-site-"))
    atexit.register(shutil.rmtree, out, ignore_errors=True)
    proc = subprocess.run(
        [sys.executable, "-m", "fcomp.cli.main", "study", "all", "--fast", "--out", str(out)],
        capture_output=True, text=True, timeout=SITE_TIMEOUT,
    )
    return out, proc.returncode, proc.stderr


def study_summary(name: str) -> dict[str, Any]:
    """``summary.json`` of study ``name`` in the shared site (fails clearly if it did not run)."""
    out, code, err = build_site()
    path = out / name / "summary.json"
    if not path.is_file():
        tail = "\n".join(err.strip().splitlines()[-5:])
        raise AssertionError(f"study {name} wrote no summary.json (fcomp study all exited "
                             f"{code}):\n{tail}")
    return json.loads(path.read_text(encoding="utf-8"))


# ------------------------------------------------------- figures and tables
#: Smallest figure text a reader should get at 100 % zoom, CSS pt.
MIN_FIGURE_PT = 9.0


def png_text(png: bytes) -> dict[str, str]:
    """The tEXt entries of a PNG, read here from the bytes (standard library only)."""
    import struct

    if png[:8] != b"\x89PNG\r\n\x1a\n":
        return {}
    out, pos = {}, 8
    while pos + 8 <= len(png):
        (length,) = struct.unpack(">I", png[pos:pos + 4])
        kind, body = png[pos + 4:pos + 8], png[pos + 8:pos + 8 + length]
        if kind == b"tEXt":
            key, _, value = body.partition(b"\0")
            out[key.decode("latin-1")] = value.decode("latin-1")
        elif kind == b"IEND":
            break
        pos += 12 + length
    return out


def image_sources(page: Path) -> list[bytes | None]:
    """The bytes of every ``<img>`` of ``page`` in document order (``document.images``
    order): data URIs decoded, relative files read; ``None`` for what cannot be read."""
    import base64
    from html.parser import HTMLParser

    srcs: list[str] = []

    class Images(HTMLParser):
        def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
            if tag == "img":
                srcs.append(dict(attrs).get("src") or "")

    Images().feed(page.read_text(encoding="utf-8"))
    out: list[bytes | None] = []
    for src in srcs:
        if src.startswith("data:"):
            head, _, data = src.partition(",")
            out.append(base64.b64decode(data) if head.endswith(";base64") else None)
        else:
            path = page.parent / src
            out.append(path.read_bytes() if src and path.is_file() else None)
    return out


def figure_text_problems(page: Path, report: dict[str, Any],
                         min_pt: float = MIN_FIGURE_PT) -> list[str]:
    """Figures of a rendered page whose smallest text is shown below ``min_pt`` CSS pt.

    Each PNG records the smallest font it drew (``fcomp:min_font_pt``, pt) and its
    ``fcomp:dpi``; shown at ``shownWidth`` CSS px (the content box, without the border) of
    ``naturalWidth`` px, a text of ``s`` pt is ``s * dpi / 72 * shownWidth / naturalWidth``
    CSS px, i.e. 0.75 times as many CSS pt.
    A PNG without the record fails.
    """
    out = []
    pngs = image_sources(page)
    if len(pngs) != len(report["images"]):
        return [f"{len(pngs)} <img> in the file, {len(report['images'])} in the page"]
    for i, (img, png) in enumerate(zip(report["images"], pngs, strict=True)):
        name = f"image {i + 1} {img['alt'][:50]!r}"
        rec = png_text(png or b"")
        if "fcomp:min_font_pt" not in rec or "fcomp:dpi" not in rec:
            out.append(f"{name}: no font record (fcomp:min_font_pt, fcomp:dpi) in the PNG")
            continue
        if not img["naturalWidth"]:
            continue  # reported as not loaded by page_problems
        px = (float(rec["fcomp:min_font_pt"]) * float(rec["fcomp:dpi"]) / 72.0
              * img["shownWidth"] / img["naturalWidth"])
        if px * 0.75 < min_pt - 1e-6:
            out.append(f"{name}: smallest text {px * 0.75:.1f} pt (drawn at "
                       f"{rec['fcomp:min_font_pt']} pt, {rec['fcomp:dpi']} dpi, shown at "
                       f"{img['shownWidth']} of {img['naturalWidth']} px)")
    return out


def table_problems(report: dict[str, Any]) -> list[str]:
    """Tables wider than their column (the ``.table-wrap`` scrolls)."""
    return [f"table {w['caption']!r} is {w['scrollWidth']} px wide in a {w['clientWidth']} px "
            "column" for w in report["scrollers"] if w["scrollWidth"] > w["clientWidth"]]
