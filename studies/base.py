"""What every study shares: configuration, output directory, figures, summary and report.

A study is an object with a ``name``, a ``title`` and a :meth:`Study.build`
method that computes its results and fills a report; :meth:`Study.main`
does the rest, always the same way::

    DIR/summary.json    the results (JSON; numbers in SI units) + "meta"
    DIR/fig-*.png       every figure of the report, also as a file
    DIR/report.html     the self-contained report (fcomp.report)

Every report opens with the study's conclusion (:meth:`Study.finding`, a
:class:`Finding`: what was found, how sure, what next, the numbers to check),
whatever order the study wrote its sections in; ``summary.json`` keeps it
under ``meta.finding``, with the report's key figure (:meth:`Study.key_figure`)
and the paper the study reproduces (:attr:`Study.paper`), for the index of
``study all``. Figures are made in the shared style (:meth:`StudyOutput.subplots`,
:mod:`fcomp.figstyle`).

Each study module exposes ``STUDY`` (its instance) and ``main(config) ->
results``; it is selected by name through ``studies.STUDIES``. The whole
folder is built in a temporary sibling folder and swapped into place only
when the study has finished (:func:`fcomp.outputs.staged_folder`): a failed
or interrupted run leaves the previous result whole, or nothing, never a
mixture of two runs or an empty folder. An existing ``DIR`` is replaced only
if it is empty or an earlier result (fcomp's marker file, or a
``summary.json``); any other folder is refused before the study starts. ``config.fast`` asks for the fast mode CI runs (fewer samples, shorter
runs); a study that is fast anyway says so and runs in full.
"""

from __future__ import annotations

import json
import math
import os
import shutil
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from fcomp.errors import FcompError
from fcomp.outputs import staged_folder, write_files, write_text
from fcomp.report import Report, render_png
from fcomp.version import __version__

__all__ = ["Finding", "Study", "StudyConfig", "StudyError", "StudyOutput", "StudyReport",
           "to_jsonable"]


#: :class:`StudyConfig` fields that only some studies take (:attr:`Study.options`), with
#: the command-line option of each.
STUDY_OPTIONS: dict[str, str] = {"plant_file": "--plant-params", "friction": "--friction",
                                 "effects": "--effects"}


def _option_label(value: Any) -> str:
    """How the record of a run names a plant file or a friction model given to it."""
    for attr in ("label", "describe"):  # a PlantFile's label, a FrictionModel's description
        got = getattr(value, attr, None)
        if got is not None:
            return str(got() if callable(got) else got)
    return str(value)


class StudyError(RuntimeError):
    """One or more studies raised an error (their output says which and why)."""


#: The colours of a finding (the report's note kinds): the claim holds, holds in part or
#: carries a number not to trust, fails.
LEVELS = ("ok", "warn", "bad")
#: A finding's level as the outcome of :func:`fcomp.conclusions.tone`.
OUTCOME = {"ok": "good", "warn": "mixed", "bad": "bad"}


@dataclass(frozen=True)
class Finding:
    """What a study found, in an engineer's words: the top of its report, its entry on the index.

    Attributes
    ----------
    status
        The finding in a few words: ``"reproduced"``, ``"partly reproduced"``, ``"not
        reproduced"`` (a paper's claim), ``"confirmed"``, ... (the study's own claim).
    level
        Its colour, one of :data:`LEVELS`: ``"ok"`` the claim holds, ``"warn"`` it holds in
        part, ``"bad"`` it fails.
    found
        What was found: one or two sentences, with units.
    sure
        How sure: what the result rests on, what is assumed.
    next
        What to do next.
    flags
        Numbers not to trust, one sentence each (what, and why not).
    confidence
        How sure, in a word (:data:`fcomp.conclusions.LEVELS`: ``"high"``, ``"medium"``,
        ``"low"``), as every command's conclusion says it; a flag makes it ``"medium"`` at
        best.
    """

    status: str
    level: str
    found: str
    sure: str = ""
    next: str = ""
    flags: Sequence[str] = field(default_factory=tuple)
    confidence: str = "medium"

    def __post_init__(self) -> None:
        from fcomp.conclusions import LEVELS as CONFIDENCE

        if self.level not in LEVELS:
            raise FcompError(f"finding level must be one of {', '.join(LEVELS)}, "
                             f"got {self.level!r}")
        if self.confidence not in CONFIDENCE:
            raise FcompError(f"finding confidence must be one of {', '.join(CONFIDENCE)}, "
                             f"got {self.confidence!r}")
        if not self.status.strip() or not self.found.strip():
            raise FcompError("a finding needs a status and what was found")
        object.__setattr__(self, "flags", tuple(self.flags))
        if self.flags and self.confidence == "high":
            object.__setattr__(self, "confidence", "medium")

    def conclusion(self) -> Any:
        """The finding as every command states its result (:class:`fcomp.conclusions.Conclusion`:
        what was found, how sure and why -- the flags first --, what next)."""
        from fcomp.conclusions import Conclusion

        status = self.status[:1].upper() + self.status[1:]
        return Conclusion(f"{status}. {self.found}", self.confidence,
                          (*self.flags, *([self.sure] if self.sure else [])),
                          (self.next,) if self.next else (),
                          outcome=OUTCOME[self.level])

    @property
    def shown_level(self) -> str:
        """The colour shown, by the one rule of every report (:func:`fcomp.conclusions.tone`:
        the worse of what the claim does and how sure the study is): a claim that holds but
        carries a flag is amber, not green; one not reproduced is red however sure."""
        from fcomp.conclusions import tone

        level = "warn" if self.level == "ok" and self.flags else self.level
        return tone(OUTCOME[level], self.confidence)

    def as_dict(self) -> dict[str, Any]:
        """The finding as ``summary.json`` holds it (``meta.finding``)."""
        return {**asdict(self), "flags": list(self.flags), "shown_level": self.shown_level}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Finding:
        """The finding of :meth:`as_dict` (``shown_level`` is derived, not read)."""
        return cls(status=str(data["status"]), level=str(data["level"]),
                   found=str(data["found"]), sure=str(data.get("sure", "")),
                   next=str(data.get("next", "")), flags=tuple(data.get("flags", ())),
                   confidence=str(data.get("confidence", "medium")))


class StudyReport(Report):
    """A study's report: a :class:`fcomp.report.Report` that opens with the study's conclusion."""

    def lead(self, finding: Finding) -> StudyReport:
        """Open the report with ``finding``, before every section added so far, in the form
        every command's report opens with (:meth:`fcomp.report.Report.conclusion`)."""
        self.conclusion(finding.conclusion(), first=True)
        return self


@dataclass(frozen=True)
class StudyConfig:
    """How to run a study.

    Attributes
    ----------
    out
        Output directory (created if missing).
    fast
        Fast mode (what CI runs).
    command
        The command line that asked for the run, recorded in the report.
    workdir
        Where the files are actually written while the study runs (set by
        :meth:`Study.main`: a staging folder that becomes ``out`` at the end;
        a study run inside another's staging folder writes there directly).
    out_label
        How messages name ``out`` (the command line gives its option, ``--out``).
    scheduler
        Address of a Dask distributed scheduler: the study's independent jobs
        (closed-loop runs, candidate refits) run on its workers
        (:mod:`fcomp.parallel`); the results are those of a local run.
    workers
        Local worker processes (default: the study's own choice).
    progress
        Show progress bars on a terminal.
    plant_file
        A plant file (a path to a ``.toml``, or a :class:`plants.planfile.PlantFile`)
        to run the study on instead of its built-in plants (studies whose
        :attr:`Study.options` name it: ``compensators``).
    friction
        The simulated plant's friction model: a registered name, a model file
        (``MODEL.json``, :mod:`fcomp.modelfile`) or a
        :class:`~fcomp.models.base.FrictionModel` (default: the study's own;
        studies whose :attr:`Study.options` name it).
    effects
        The user's effects module (a ``.py`` file, :func:`fcomp.effects.load_effects_module`)
        that registers the effects a model file of ``friction`` names (the same studies).
    """

    out: Path
    fast: bool = False
    command: str | None = None
    workdir: Path | None = None
    out_label: str = "out"
    scheduler: str | None = None
    workers: int | None = None
    progress: bool = True
    plant_file: Any = None
    friction: Any = None
    effects: str | os.PathLike[str] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "out", Path(self.out))
        if not isinstance(self.fast, bool):
            raise FcompError(f"study config: fast must be true or false, got {self.fast!r}")

    @classmethod
    def coerce(cls, config: StudyConfig | Mapping[str, Any]) -> StudyConfig:
        """A :class:`StudyConfig` from itself or a mapping with keys ``out``, ``fast``, ``command``."""
        if isinstance(config, StudyConfig):
            return config
        if not isinstance(config, Mapping):
            raise FcompError(f"study config must be a mapping, got {type(config).__name__}")
        unknown = set(config) - {"out", "fast", "command", "scheduler", "workers",
                                 "plant_file", "friction", "effects"}
        if unknown:
            raise FcompError(f"study config: unknown key(s) {', '.join(sorted(unknown))}")
        if "out" not in config:
            raise FcompError("study config: 'out' (output directory) is required")
        return cls(out=Path(config["out"]), fast=bool(config.get("fast", False)),
                   command=config.get("command"), scheduler=config.get("scheduler"),
                   workers=config.get("workers"), plant_file=config.get("plant_file"),
                   friction=config.get("friction"), effects=config.get("effects"))

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"out": str(self.out), "fast": self.fast, "command": self.command}
        for key in STUDY_OPTIONS:  # only when given: a default run's record stays as it was
            value = getattr(self, key)
            if value is not None:
                out[key] = _option_label(value)
        return out

    def local_workers(self) -> int:
        """Local worker processes: :attr:`workers`, else ``FCOMP_WORKERS``, else up to 2
        (the CPU count, at most 2)."""
        if self.workers is not None:
            return self.workers
        raw = os.environ.get("FCOMP_WORKERS", "")
        return int(raw) if raw.isdigit() and int(raw) > 0 else min(2, os.cpu_count() or 1)


def to_jsonable(obj: Any) -> Any:
    """``obj`` with numpy scalars/arrays as Python numbers/lists and NaN/inf as ``None``."""
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return [to_jsonable(v) for v in obj.tolist()]
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, Path):
        return str(obj)
    if obj is None or isinstance(obj, bool | int | float | str):
        return obj
    raise TypeError(f"cannot write a {type(obj).__name__} to summary.json")


def _takers(key: str) -> str:
    """The studies (subclasses of :class:`Study` defined so far) whose :attr:`Study.options`
    hold ``key``, for a message."""
    names: list[str] = []
    todo: list[type[Study]] = list(Study.__subclasses__())
    while todo:
        cls = todo.pop()
        todo += cls.__subclasses__()
        name = getattr(cls, "name", None)
        if key in cls.options and isinstance(name, str) and name not in names:
            names.append(name)
    return " and ".join(sorted(names)) or "no"


class StudyOutput:
    """The output directory and the report of one run, handed to :meth:`Study.build`.

    Attributes
    ----------
    directory
        Where the files go.
    report
        The :class:`StudyReport` being built.
    figures
        Paths of the figure files written so far.
    """

    def __init__(self, directory: Path, report: StudyReport) -> None:
        self.directory = directory
        self.report = report
        self.figures: list[Path] = []
        self.captions: dict[str, str] = {}

    @staticmethod
    def subplots(nrows: int = 1, ncols: int = 1, *, figsize: tuple[float, float] | None = None,
                 **kwargs: Any) -> tuple[Any, Any]:
        """A figure in the report style and its axes, like ``matplotlib.pyplot.subplots``
        (:func:`fcomp.figstyle.new_figure`: fonts readable at 1400 px, constrained layout).
        A ``figsize`` wider than the column (:data:`fcomp.figstyle.WIDTH`) is scaled down
        to it, aspect kept: a wider figure would be shown smaller, its text below 9 pt."""
        from fcomp import figstyle

        width, height = figsize or (figstyle.WIDTH, 3.2)
        if width > figstyle.WIDTH:
            width, height = figstyle.WIDTH, height * figstyle.WIDTH / width
        return figstyle.new_figure(height=height, width=width, nrows=nrows, ncols=ncols,
                                   **kwargs)

    def figure(self, fig: Any, name: str, caption: str, *, dpi: int | None = None) -> Path:
        """Write ``fig`` (a matplotlib figure, or PNG bytes rendered elsewhere) to
        ``DIR/fig-NAME.png`` and embed the same image in the report. A matplotlib figure's
        texts below :data:`fcomp.figstyle.FONT_MIN` are raised to it first."""
        from fcomp import figstyle

        if not name.replace("-", "").replace("_", "").isalnum():
            raise FcompError(f"figure name {name!r}: use letters, digits, '-' and '_'")
        if not isinstance(fig, bytes):
            figstyle.apply_floor(fig)
        png = fig if isinstance(fig, bytes) else render_png(fig, dpi=dpi)
        path = self.directory / f"fig-{name}.png"
        write_files({path: png})
        self.figures.append(path)
        self.captions[path.name] = caption
        self.report.figure(png, caption, alt=f"{name}: {caption}")
        return path


class Study(ABC):
    """Base of every study: subclasses set ``name``, ``title``, ``summary`` and write ``build``."""

    #: Public name (``fcomp study NAME``).
    name: ClassVar[str]
    #: Report title.
    title: ClassVar[str]
    #: One line: what the study shows.
    summary: ClassVar[str]
    #: Caption labels of the report's tables and figures.
    table_label: ClassVar[str] = "Table"
    figure_label: ClassVar[str] = "Figure"
    #: File names the report is written to inside the output directory.
    report_files: ClassVar[tuple[str, ...]] = ("report.html",)
    #: Relative run time of a full run (about its CPU seconds): ``all`` starts the longest first.
    cost: ClassVar[float] = 1.0
    #: The optional :class:`StudyConfig` fields (:data:`STUDY_OPTIONS`) this study takes.
    options: ClassVar[tuple[str, ...]] = ()
    #: The paper the study reproduces (authors, year, title; the index names the study by
    #: it), or ``None`` for a study of the package's own claims.
    paper: ClassVar[str | None] = None

    def check(self, config: StudyConfig) -> list[str]:
        """Check the configuration's inputs before anything is written (:meth:`main` calls
        it first; the command line too): options this study does not take, files that do
        not read. Returns warnings (one line each); raises :class:`FcompError`."""
        for key, option in STUDY_OPTIONS.items():
            if getattr(config, key) is not None and key not in self.options:
                raise FcompError(f"{option} applies to the {_takers(key)} study, not to "
                                 f"{self.name}")
        return []

    def subtitle(self, config: StudyConfig) -> str:
        """The report's subtitle for a run of ``config`` (default: the summary)."""
        return self.summary

    def headline(self, results: dict[str, Any]) -> str:
        """One line of result for the index of ``fcomp study all`` (default: the summary)."""
        return self.summary

    def finding(self, results: dict[str, Any]) -> Finding:
        """What the run found (:class:`Finding`): the conclusion the report opens with and
        the study's entry on the index. The default judges nothing: the headline."""
        return Finding("ran", "ok", self.headline(results))

    def key_figure(self, results: dict[str, Any]) -> str | None:
        """The name of the report's most telling figure (``fig-NAME.png``): the index shows
        it. ``None``: no figure."""
        return None

    @abstractmethod
    def build(self, out: StudyOutput, config: StudyConfig) -> dict[str, Any]:
        """Compute the results, add sections and figures to ``out.report``; return the results.

        The results become ``summary.json`` (a key ``"meta"`` is added there).
        """

    def main(self, config: StudyConfig | Mapping[str, Any]) -> dict[str, Any]:
        """Run the study: write ``summary.json``, figures and the report; return the results."""
        cfg = StudyConfig.coerce(config)
        self.check(cfg)
        if cfg.workdir is not None:  # inside the staging folder of an enclosing run
            try:
                return self._run(cfg, cfg.workdir)
            except BaseException:  # a failed part leaves no half-written folder either
                shutil.rmtree(cfg.workdir, ignore_errors=True)
                raise
        note = cfg.command or f"study {self.name}"
        with staged_folder(cfg.out, cfg.out_label, "study", note=note) as staging:
            return self._run(cfg, staging)

    def _run(self, cfg: StudyConfig, directory: Path) -> dict[str, Any]:
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise FcompError(f"{cfg.out_label} {cfg.out}: cannot create it ({exc.strerror})") \
                from None
        report = StudyReport(self.title, subtitle=self.subtitle(cfg), command=cfg.command,
                        config={"study": self.name, **cfg.as_dict()},
                        table_label=self.table_label, figure_label=self.figure_label)
        out = StudyOutput(directory, report)
        results = self.build(out, replace(cfg, workdir=directory))
        if "meta" in results:
            raise RuntimeError(f"study {self.name}: 'meta' is reserved in summary.json")
        finding = self.finding(results)
        report.lead(finding)
        key = self.key_figure(results)
        key_file = f"fig-{key}.png" if key else None
        if key_file is not None and directory / key_file not in out.figures:
            raise RuntimeError(f"study {self.name}: key figure {key_file} was not written")
        summary = to_jsonable({
            **results,
            "meta": {
                "study": self.name,
                "title": self.title,
                "fcomp_version": __version__,
                "fast": cfg.fast,
                "command": cfg.command,
                "figures": [p.name for p in out.figures],
                "finding": finding.as_dict(),
                "key_figure": key_file,
                "key_caption": out.captions.get(key_file) if key_file else None,
                "paper": self.paper,
                "reports": list(self.report_files),
            },
        })
        write_text(directory / "summary.json",
                   json.dumps(summary, indent=2, allow_nan=False) + "\n")
        page = report.to_html()
        for filename in self.report_files:
            write_text(directory / filename, page)
        return summary
