"""Study ``all``: run every registered study, each in ``DIR/NAME/``, and write ``DIR/index.html``.

The index links each study's ``report.html`` and ``summary.json`` with its
status, run time and headline result. A study that raises is recorded as
failed (with the error line) and the others still run; the run then ends
with :class:`studies.base.StudyError` naming the failed studies. A tqdm
progress bar goes to stderr.
"""

from __future__ import annotations

import sys
import time
from typing import Any

from fcomp.report import Link
from studies.base import Study, StudyConfig, StudyError, StudyOutput


class AllStudies(Study):
    """Every registered study, with an index page."""

    name = "all"
    title = "fcomp studies"
    summary = "Every registered study, run in its own folder, with links to the reports."
    report_files = ("index.html", "report.html")

    def build(self, out: StudyOutput, config: StudyConfig) -> dict[str, Any]:
        from tqdm import tqdm

        from studies import STUDIES

        names = [n for n in STUDIES.names() if not isinstance(STUDIES.get(n), AllStudies)]
        runs: dict[str, dict[str, Any]] = {}
        bar = tqdm(names, desc="studies", unit="study", file=sys.stderr, dynamic_ncols=True)
        for name in bar:
            bar.set_postfix_str(name)
            study = STUDIES.get(name)
            sub = StudyConfig(out=config.out / name, workdir=out.directory / name,
                              fast=config.fast, scheduler=config.scheduler,
                              workers=config.workers, progress=config.progress,
                              command=f"(part of) {config.command}" if config.command else None)
            start = time.perf_counter()
            try:
                results = study.main(sub)
                runs[name] = {"status": "ok", "headline": study.headline(results), "error": None}
            except Exception as exc:  # record and go on: one failing study must not hide others
                line = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
                runs[name] = {"status": "failed", "headline": study.summary,
                              "error": f"{type(exc).__name__}: {line}"}
            runs[name].update({
                "seconds": round(time.perf_counter() - start, 3),
                "report": f"{name}/report.html",
                "summary": f"{name}/summary.json",
                "title": study.title,
            })
        bar.close()
        failed = [n for n, r in runs.items() if r["status"] != "ok"]

        rep = out.report
        rep.section("Studies")
        if not names:
            rep.note("No study is registered.", kind="warn")
        rep.paragraph(f"{len(names) - len(failed)} of {len(names)} studies ran "
                      f"{'in fast mode' if config.fast else 'in full'}; each folder holds the "
                      "study's `summary.json`, its figures and its `report.html`.")
        rows = []
        for n, r in runs.items():
            rows.append([
                Link(n, r["report"]) if r["status"] == "ok" else n,
                r["title"],
                r["status"] if r["status"] == "ok" else f"failed: {r['error']}",
                r["seconds"],
                r["headline"],
                Link("summary.json", r["summary"]) if r["status"] == "ok" else "",
            ])
        rep.table(["study", "title", "status", "time [s]", "result", "data"], rows,
                  caption="Registered studies (links are relative to this page).",
                  digits=[None, None, None, 1, None, None])
        if failed:
            rep.note(f"Failed: {', '.join(failed)}.", kind="bad")
        return {"studies": runs, "failed": failed}

    def main(self, config: Any) -> dict[str, Any]:
        summary = super().main(config)
        if summary["failed"]:
            cfg = StudyConfig.coerce(config)
            raise StudyError(f"studies failed: {', '.join(summary['failed'])} "
                              f"(see {cfg.out / 'index.html'})")
        return summary

    def headline(self, results: dict[str, Any]) -> str:
        return f"{len(results['studies']) - len(results['failed'])} studies ran"


STUDY = AllStudies()
main = STUDY.main
