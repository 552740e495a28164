"""Study ``all``: run every registered study, each in ``DIR/NAME/``, and write ``DIR/index.html``.

The index links each study's ``report.html`` and ``summary.json`` with its
status, run time (wall clock and CPU time of its processes) and headline
result. A study that raises is recorded as failed (with the error line) and
the others still run; the run then ends with :class:`studies.base.StudyError`
naming the failed studies.

The studies are independent: they run side by side on a local process pool
(:meth:`studies.base.StudyConfig.local_workers` processes, 2 by default), the
longest first (:attr:`studies.base.Study.cost`), each with its own parallel
jobs inside; one worker runs them here in turn. Progress, on a terminal only: a
bar of finished studies naming those running now, and each running study's own bar
beneath it (:class:`fcomp.progress.ProgressRelay`, :func:`fcomp.progress.running`).
"""

from __future__ import annotations

import resource
import time
from dataclasses import dataclass
from typing import Any

from fcomp.parallel import run_tasks
from fcomp.progress import ProgressRelay, progress_bar, relay_progress, running, ticker
from fcomp.report import Link
from studies.base import Study, StudyConfig, StudyError, StudyOutput


@dataclass(frozen=True)
class StudyJob:
    """One study of ``all`` as a picklable job (:func:`run_study`).

    Attributes
    ----------
    name
        The study's registered name.
    study
        The study.
    config
        Its configuration (output inside the staging folder of ``all``).
    progress
        Queue of the parent's :class:`fcomp.progress.ProgressRelay`, or ``None``.
    """

    name: str
    study: Study
    config: StudyConfig
    progress: Any = None


def _cpu() -> float:
    """CPU time (s) of this process and of its children that have finished."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def run_study(job: StudyJob) -> dict[str, Any]:
    """Run one study; its status, headline or error, wall-clock and CPU seconds."""
    relay_progress(job.progress)
    start, cpu = time.perf_counter(), _cpu()
    try:
        with running(job.name):
            results = job.study.main(job.config)
        run: dict[str, Any] = {"status": "ok", "headline": job.study.headline(results),
                               "error": None}
    except Exception as exc:  # record and go on: one failing study must not hide others
        line = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        run = {"status": "failed", "headline": job.study.summary,
               "error": f"{type(exc).__name__}: {line}"}
    finally:
        relay_progress(None)
    run.update({
        "seconds": round(time.perf_counter() - start, 3),
        "cpu_seconds": round(_cpu() - cpu, 3),
        "report": f"{job.name}/report.html",
        "summary": f"{job.name}/summary.json",
        "title": job.study.title,
    })
    return run


class AllStudies(Study):
    """Every registered study, with an index page."""

    name = "all"
    title = "fcomp studies"
    summary = "Every registered study, run in its own folder, with links to the reports."
    report_files = ("index.html", "report.html")

    def build(self, out: StudyOutput, config: StudyConfig) -> dict[str, Any]:
        from studies import STUDIES

        names = [n for n in STUDIES.names() if not isinstance(STUDIES.get(n), AllStudies)]
        order = sorted(names, key=lambda n: -STUDIES.get(n).cost)
        workers = min(config.local_workers(), max(len(names), 1))
        start = time.perf_counter()
        bar = progress_bar("studies", len(names), unit="study", enabled=config.progress)
        # on a terminal the studies' own bars are drawn below, and the running ones named
        with ProgressRelay(enabled=config.progress, head=bar) as relay:
            jobs = [StudyJob(n, STUDIES.get(n), StudyConfig(
                out=config.out / n, workdir=out.directory / n, fast=config.fast,
                scheduler=config.scheduler, workers=config.workers, progress=config.progress,
                command=f"(part of) {config.command}" if config.command else None),
                relay.queue) for n in order]
            try:
                done = run_tasks(run_study, jobs, workers=workers, progress=ticker(bar))
            finally:
                bar.close()
        wall = time.perf_counter() - start
        runs = {j.name: r for j, r in zip(jobs, done, strict=True)}
        runs = {n: runs[n] for n in names}
        failed = [n for n, r in runs.items() if r["status"] != "ok"]

        rep = out.report
        rep.section("Studies")
        if not names:
            rep.note("No study is registered.", kind="warn")
        rep.paragraph(f"{len(names) - len(failed)} of {len(names)} studies ran "
                      f"{'in fast mode' if config.fast else 'in full'}, {workers} at a time, in "
                      f"{wall:.0f} s; each folder holds the study's `summary.json`, its figures "
                      "and its `report.html`. Time: wall clock of each study (they overlap); "
                      "CPU: the CPU time of its processes.")
        rows = []
        for n, r in runs.items():
            rows.append([
                Link(n, r["report"]) if r["status"] == "ok" else n,
                r["title"],
                r["status"] if r["status"] == "ok" else f"failed: {r['error']}",
                r["seconds"],
                r["cpu_seconds"],
                r["headline"],
                Link("summary.json", r["summary"]) if r["status"] == "ok" else "",
            ])
        rep.table(["study", "title", "status", "time [s]", "CPU [s]", "result", "data"], rows,
                  caption="Registered studies (links are relative to this page).",
                  digits=[None, None, None, 1, 1, None, None])
        if failed:
            rep.note(f"Failed: {', '.join(failed)}.", kind="bad")
        return {"studies": runs, "failed": failed, "workers": workers,
                "seconds": round(wall, 3)}

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
