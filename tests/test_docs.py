"""The code in the README and the docs runs: every example is executed here.

Fenced blocks are read from ``README.md`` and ``docs/*.md`` by their info
string:

* ``python`` -- executed, the blocks of one page in order in one namespace,
  in a fresh temporary folder (files a page writes are there for its later
  blocks);
* ``bash`` / ``sh`` -- every command (``\\`` continuations joined, ``#``
  comments dropped) is an ``fcomp`` command, run in-process in the same
  folder, and must exit 0;
* a block whose info string carries ``no-run`` (```` ```bash no-run ````) is
  illustrative -- it needs data the repository does not ship, a long run or
  another tool (pip) -- and is not executed; ``text``, ``toml`` and unlabelled
  blocks are not code.

Pages keep their examples small: short synthetic records
(:func:`fcomp.synthetic.generate`), small durations.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```([^\n`]*)\n(.*?)^```\s*$", re.S | re.M)
RUN = {"python", "bash", "sh"}


def blocks(page: Path) -> list[tuple[str, set[str], str, int]]:
    """``(language, flags, code, line)`` of every fenced block of ``page``."""
    text = page.read_text(encoding="utf-8")
    out = []
    for m in FENCE.finditer(text):
        words = m.group(1).split()
        lang = words[0] if words else ""
        out.append((lang, set(words[1:]), m.group(2), text[:m.start()].count("\n") + 1))
    return out


def commands(code: str) -> list[str]:
    """The commands of a shell block: continuations joined, comments dropped."""
    joined = re.sub(r"\\\n\s*", " ", code)
    out = []
    for line in joined.splitlines():
        words = shlex.split(line, comments=True)
        if words:
            out.append(shlex.join(words))
    return out


def test_every_code_block_is_runnable_or_marked() -> None:
    """A shell block either runs fcomp commands or says why not (``no-run``)."""
    bad = []
    for page in PAGES:
        for lang, flags, code, line in blocks(page):
            if lang in ("bash", "sh") and "no-run" not in flags:
                for cmd in commands(code):
                    if not cmd.startswith("fcomp "):
                        bad.append(f"{page.name}:{line}: {cmd}")
    assert not bad, "shell blocks with other commands must be marked no-run:\n" + "\n".join(bad)


def _runnable(page: Path) -> bool:
    return any(lang in RUN and "no-run" not in flags for lang, flags, _, _ in blocks(page))


@pytest.mark.parametrize("page", [p for p in PAGES if _runnable(p)],
                         ids=lambda p: p.relative_to(ROOT).as_posix())
def test_page_examples_run(page: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from fcomp.cli.main import main

    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": f"docs_{page.stem}"}
    for lang, flags, code, line in blocks(page):
        if lang not in RUN or "no-run" in flags:
            continue
        where = f"{page.relative_to(ROOT)} line {line}"
        if lang == "python":
            exec(compile(code, where, "exec"), namespace)
            continue
        for cmd in commands(code):
            code_ = main(shlex.split(cmd)[1:])
            assert code_ == 0, f"{where}: `{cmd}` exited {code_}"


@pytest.mark.slow
def test_the_compensators_tuning_tables_are_the_codes() -> None:
    """docs/compensators.md's tuning tables are what docs/make_tuning_tables.py derives now."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_tuning_tables",
                                                  ROOT / "docs" / "make_tuning_tables.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert mod.main(["--check"]) == 0
