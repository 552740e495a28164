"""Study ``all``: run every registered study, each in ``DIR/NAME/``, and write ``DIR/index.html``.

The index names each study by the paper it reproduces and states what it
found (:class:`studies.base.Finding`: "reproduced", "partly reproduced", "not
reproduced", ..., in words and in colour, with the numbers to check), links
its ``report.html`` and ``summary.json``, shows its key figure (linking to the
report, at the column's width as in the report) and its run time (wall clock
and CPU time of its processes); :func:`write_index` builds it from the runs'
records. A study that raises is recorded as failed (with the error line) and
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

import base64
import html
import resource
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from fcomp.parallel import run_tasks
from fcomp.progress import ProgressRelay, progress_bar, relay_progress, running, ticker
from fcomp.report import Link, inline
from studies.base import Finding, Study, StudyConfig, StudyError, StudyOutput, StudyReport


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
    """Run one study; its status, headline and finding or error, its key figure (PNG,
    base64) and that figure's caption, wall-clock and CPU seconds."""
    relay_progress(job.progress)
    start, cpu = time.perf_counter(), _cpu()
    key = caption = None
    try:
        with running(job.name):
            results = job.study.main(job.config)
        meta = results["meta"]
        run: dict[str, Any] = {"status": "ok", "headline": job.study.headline(results),
                               "finding": meta["finding"], "error": None}
        if meta.get("key_figure"):
            key = (job.config.workdir or job.config.out).joinpath(
                meta["key_figure"]).read_bytes()
            caption = meta.get("key_caption")
    except Exception as exc:  # record and go on: one failing study must not hide others
        line = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        run = {"status": "failed", "headline": job.study.summary, "finding": None,
               "error": f"{type(exc).__name__}: {line}"}
    finally:
        relay_progress(None)
    run.update({
        "seconds": round(time.perf_counter() - start, 3),
        "cpu_seconds": round(_cpu() - cpu, 3),
        "report": f"{job.name}/report.html",
        "summary": f"{job.name}/summary.json",
        "title": job.study.title,
        "paper": job.study.paper,
        "key_figure": None if key is None else base64.b64encode(key).decode("ascii"),
        "key_caption": caption,
    })
    return run


def _esc(text: str) -> str:
    """``text`` for the page: escaped, with ```code``` spans (as the report's own text)."""
    return inline(str(text))


def finding_words(run: Mapping[str, Any]) -> tuple[str, str]:
    """How the index states a study's outcome: ``(words, level)``, the level one of
    :data:`studies.base.LEVELS` (a study that failed to run is ``bad``)."""
    if run["status"] != "ok" or not run.get("finding"):
        return f"failed: {run.get('error') or 'no result'}", "bad"
    f = Finding.from_dict(run["finding"])
    return f.status + (f" ({len(f.flags)} number{'s' * (len(f.flags) > 1)} to check)"
                       if f.flags else ""), f.shown_level


def study_card(name: str, run: Mapping[str, Any]) -> str:
    """The index's card of one study: the finding in its colour and words, the paper, the
    flags, the links and the key figure (linking to the report)."""
    words, level = finding_words(run)
    report = html.escape(run["report"])
    parts = [f'<div class="note {level}">']
    if run["status"] == "ok" and run.get("finding"):
        f = Finding.from_dict(run["finding"])
        parts.append(f"<p><strong>{_esc(f.status[:1].upper() + f.status[1:])}.</strong> "
                     f"{_esc(f.found)}</p>")
        parts += [f"<p><strong>Check:</strong> {_esc(flag)}</p>" for flag in f.flags]
        if f.next:
            parts.append(f"<p><strong>Next:</strong> {_esc(f.next)}</p>")
    else:
        parts.append(f"<p><strong>{_esc(words[:1].upper() + words[1:])}.</strong></p>")
    parts.append("<p>" + (f"Reproduces {_esc(run['paper'])}. " if run.get("paper") else
                          "A claim of fcomp's own. ")
                 + (f'<a href="{report}">Report</a>, ' if run["status"] == "ok" else "")
                 + (f'<a href="{html.escape(run["summary"])}">summary.json</a>; '
                    if run["status"] == "ok" else "")
                 + f"{run['seconds']:.0f} s.</p>")
    parts.append("</div>")
    if run.get("key_figure"):  # at the column's width, as in the report: its text readable
        caption = run.get("key_caption") or ""
        parts.append(f'<figure><a href="{report}"><img src="data:image/png;base64,'
                     f'{run["key_figure"]}" alt="{html.escape(name)}: the key figure of its '
                     f'report"></a><figcaption><strong>Key figure.</strong> {_esc(caption)} '
                     f'(<a href="{report}">the report</a>)</figcaption></figure>')
    return "".join(parts)


def write_index(rep: StudyReport, runs: Mapping[str, Mapping[str, Any]]) -> None:
    """The index's table (each study with its finding in words) and a card per study
    (:func:`study_card`)."""
    rows = []
    for n, r in runs.items():
        words, _ = finding_words(r)
        rows.append([Link(n, r["report"]) if r["status"] == "ok" else n,
                     r["title"], words, r["seconds"], r["cpu_seconds"]])
    rep.table(["study", "title", "finding", "time [s]", "CPU [s]"], rows,
              caption="Registered studies and what each found (links are relative to this "
              "page; time: wall clock, CPU: the CPU time of its processes).",
              digits=[None, None, None, 0, 0])
    for n, r in runs.items():
        rep.section(r["title"], level=3)
        rep.markup(study_card(n, r))


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
                      "and its `report.html`. Green: the claim holds; amber: it holds in part, "
                      "or a number needs checking; red: the claim fails.")
        if failed:
            rep.note(f"Failed: {', '.join(failed)}.", kind="bad")
        write_index(rep, runs)
        for r in runs.values():  # the key figures live in the page, not in summary.json
            r.pop("key_figure", None)
        return {"studies": runs, "failed": failed, "workers": workers,
                "seconds": round(wall, 3)}

    def finding(self, results: dict[str, Any]) -> Finding:
        runs = results["studies"]
        counts: dict[str, int] = {}
        for r in runs.values():
            level = finding_words(r)[1]
            counts[level] = counts.get(level, 0) + 1
        said = {"ok": "hold", "warn": "hold in part or carry a number to check",
                "bad": "fail or did not run"}
        found = "; ".join(f"{said[k]}: {counts[k]}" for k in ("ok", "warn", "bad") if k in counts)
        level = ("bad" if results["failed"] else
                 "warn" if any(k != "ok" for k in counts) else "ok")
        return Finding(f"{len(runs) - len(results['failed'])} of {len(runs)} studies ran", level,
                       f"The studies' claims that {found or 'none'} (each study below, in "
                       "its colour).", confidence="low" if results["failed"] else "high")

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
