"""Pieces shared by the sub-commands: building models from options, output paths, JSON
results, warnings."""

from __future__ import annotations

import argparse
import json
import math
import sys
import threading
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fcomp.effects import load_effects_module
from fcomp.errors import FcompError, FcompWarning, render_terms
from fcomp.models import FrictionModel, make_model
from fcomp.outputs import InputSet, check_distinct, check_folder_target
from fcomp.registry import COMMANDS

#: Largest magnitude accepted for a number given on the command line (SI units).
MAX_VALUE = 1e15

#: Warnings of the running command (``{"code", "parameter", "message"}``), printed as
#: ``fcomp: warning: ...`` after a successful run and written into its outputs.
WARNINGS: list[dict[str, Any]] = []
#: The running command's arguments (after ``fcomp``), for reports.
ARGV: list[str] = []
#: Python warnings caught while the command runs (set by :func:`fcomp.cli.main.main`).
PYTHON_WARNINGS: list[warnings.WarningMessage] | None = None


#: Library parameter -> the command-line option that sets it: library messages name the
#: parameter (marked with :func:`fcomp.errors.term`), the command line shows its option.
OPTIONS: dict[str, str] = {
    "max_steps": "--max-steps", "rtol": "--rtol", "atol": "--atol", "duration": "--duration",
    "rate": "--rate", "coupling": "--coupling", "params": "--params", "fixed": "--fix",
    "out": "--out", "input": "--input", "mapping": "--map", "position_scale": "--position-scale",
    "effects_module": "--effects", "units": "--units", "drop": "--drop",
    "decimal": "--decimal", "delimiter": "--delimiter", "scheduler": "--scheduler",
    "mass": "--mass",
}


def in_cli_terms(message: str) -> str:
    """``message`` with every library parameter marked in it (:func:`fcomp.errors.term`)
    written as the command-line option that sets it (:data:`OPTIONS`)."""
    return render_terms(message, OPTIONS)


def warn(code: str, message: str, parameter: str | None = None) -> None:
    """Record a warning for a suspicious but legal input (one line, no duplicates); library
    parameters marked in it are written as their options (:func:`in_cli_terms`)."""
    message = in_cli_terms(message)
    item = {"code": code, "parameter": parameter, "message": " ".join(message.split())}
    if item not in WARNINGS:
        WARNINGS.append(item)


def python_warning(w: warnings.WarningMessage) -> tuple[str, str]:
    """A Python or numpy warning as ``(code, one-line message)``."""
    text = str(w.message).strip().splitlines()[0] if str(w.message).strip() else ""
    if isinstance(w.message, FcompWarning):
        return w.message.code, in_cli_terms(w.message.template.strip().splitlines()[0]
                                            if w.message.template.strip() else text)
    if issubclass(w.category, RuntimeWarning):
        return "numerical", (f"{text} (a computation left floating-point range; check the "
                             "inputs and the results)")
    return "library", f"{w.category.__name__}: {text}"


def finite_float(text: str) -> float:
    """argparse ``type=``: a finite number within :data:`MAX_VALUE`."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    if abs(value) > MAX_VALUE:
        raise argparse.ArgumentTypeError(f"{text!r} is beyond any plausible value in SI units")
    return value


def add_model_options(p: argparse.ArgumentParser, *, flag: str = "--friction") -> None:
    p.add_argument("--add-effect", action="append", default=[], metavar="EFFECT",
                   help="add a catalogue (or registered) effect to the model; repeatable")
    add_effects_option(p, "registers the user's own effects")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="override a friction parameter (flat name, SI units); repeatable")


def add_effects_option(p: argparse.ArgumentParser,
                       what: str = "registers the user's own effects the model files name"
                       ) -> None:
    """``--effects MODULE.py``: a Python file that ``what`` (executed: SECURITY, README)."""
    p.add_argument("--effects", metavar="MODULE.py", default=None,
                   help=f"a Python file that {what} (it is executed: see SECURITY in the "
                   "README)")


def parse_assignments(items: list[str], option: str = "--set") -> dict[str, float]:
    """``NAME=VALUE`` items as a dict: finite numbers, each name once."""
    out: dict[str, float] = {}
    for item in items:
        if "=" not in item:
            raise FcompError(f"{option} {item!r}: expected NAME=VALUE")
        k, v = (s.strip() for s in item.split("=", 1))
        if not k:
            raise FcompError(f"{option} {item!r}: the name before '=' is missing")
        try:
            value = float(v)
        except ValueError:
            hint = f"; give one NAME=VALUE per {option}" if "=" in v else ""
            raise FcompError(f"{option} {item!r}: {v!r} is not a number{hint}") from None
        if not math.isfinite(value):
            raise FcompError(f"{option} {item!r}: the value must be a finite number")
        if abs(value) > MAX_VALUE:
            raise FcompError(f"{option} {item!r}: {v} is beyond any plausible value in SI units")
        if k in out:
            raise FcompError(f"{option} {k}: given twice ({out[k]:g} and {value:g})")
        out[k] = value
    return out


def name_list(text: str | None, option: str) -> list[str] | None:
    """``A,B,C`` as a list (``None`` if the option was not given); refuses an empty list
    and repeated names."""
    if text is None:
        return None
    names = [s.strip() for s in text.split(",") if s.strip()]
    if not names:
        raise FcompError(f"{option}: give at least one name (got {text!r})")
    for i, n in enumerate(names):
        if n in names[:i]:
            raise FcompError(f"{option}: {n} is given twice")
    return names


def build_model(name: str, params: str | None, args: argparse.Namespace) -> FrictionModel:
    """The friction model of the options (model, parameter set, effects, overrides)."""
    if args.effects is not None:
        load_effects_module(args.effects)
    model = make_model(name, params=params)
    if args.add_effect:
        model = model.with_effects(*args.add_effect)
    overrides = parse_assignments(args.set)
    return model.with_params(**overrides) if overrides else model


def add_save_model_option(p: argparse.ArgumentParser, what: str) -> None:
    """``--save-model MODEL.json``: write ``what`` as a model file (docs/model-file.md)."""
    p.add_argument("--save-model", metavar="MODEL.json", default=None,
                   help=f"write {what} as a model file (versioned JSON, docs/model-file.md) "
                   "that every friction option reads (simulate --friction, compare --model, "
                   "...)")


def model_target(path: str | None) -> Path | None:
    """The file ``--save-model PATH`` writes (``None`` without the option); checked before
    any work: a ``.json`` name in an existing folder."""
    if path is None:
        return None
    if not path.strip():
        raise FcompError("--save-model: no file name given (an empty argument)")
    out = Path(path)
    if out.suffix.lower() != ".json" or not out.stem:
        raise FcompError(f"--save-model {path}: a model file ends in .json")
    if out.is_dir():
        raise FcompError(f"--save-model {path}: is a directory")
    if not out.parent.is_dir():
        raise FcompError(f"--save-model {path}: folder {out.parent} does not exist")
    return out


def save_model_file(doc: dict[str, Any], out: Path | None, json_arg: str | None) -> None:
    """Write the model file ``doc`` to ``out`` (atomically; nothing without ``--save-model``);
    says so unless the JSON result goes to standard output."""
    from fcomp.models.document import document_text
    from fcomp.outputs import write_text

    if out is None:
        return
    write_text(out, document_text(doc))
    if json_arg != "-":
        print(f"wrote {out}")


def model_source(data: list[str]) -> dict[str, Any]:
    """A model file's ``source`` for a command run on the records ``data``."""
    import shlex

    return {"command": "fcomp " + shlex.join(ARGV) if ARGV else None, "data": list(data)}


def friction_model(spec: str, params: str | None, args: argparse.Namespace, *,
                   use: str = "plant friction") -> FrictionModel:
    """The friction model a friction option names: a model file (``.json``, its
    measurement terms dropped with a warning) or a registered model (:func:`build_model`).

    A file takes no parameter set; ``--add-effect`` and ``--set`` apply to it as to a name.
    """
    from fcomp.modelfile import is_model_file, seal_friction

    if not is_model_file(spec):
        return build_model(spec, params, args)
    model, dropped = seal_friction(spec, use, args.effects)
    if dropped:
        warn("measurement-terms", dropped, "friction")
    if args.add_effect:
        model = model.with_effects(*args.add_effect)
    overrides = parse_assignments(args.set)
    return model.with_params(**overrides) if overrides else model


def output_path(path: str, suffix: str = ".csv", option: str = "-o") -> Path:
    """The measurement file an ``-o OUT.csv`` option names (its sidecar goes next to it)."""
    if not path.strip():
        raise FcompError(f"{option}: no file name given (an empty argument)")
    p = Path(path)
    if p.suffix != suffix or p.stem == "":
        raise FcompError(f"{option} {path}: the output must end in {suffix}")
    for q in (p, p.with_suffix(".toml")):
        if q.is_dir():
            raise FcompError(f"{option} {path}: {q} is a directory")
    return p


#: Suffixes a ``--json`` output may not have: they name the package's inputs and outputs.
_NOT_JSON = (".csv", ".toml", ".py", ".mat", ".html", ".png")


def json_target(path: str | None) -> Path | None:
    """The file ``--json PATH`` writes to; ``None`` for standard output (``-``) or no ``--json``.

    Raises
    ------
    FcompError
        If ``path`` is empty, a directory, or its folder does not exist (checked before any work, so a failure never leaves a
        half-written result).
    """
    if path is None or path == "-":
        return None
    if not path.strip():
        raise FcompError("--json: no file name given (an empty argument; '-' is standard output)")
    out = Path(path)
    if out.is_dir():
        raise FcompError(f"--json {path}: is a directory")
    if not out.parent.exists():
        raise FcompError(f"--json {path}: folder {out.parent} does not exist")
    if not out.parent.is_dir():
        raise FcompError(f"--json {path}: {out.parent} is not a folder")
    return out


def report_dir(path: str | None, option: str = "--report") -> Path | None:
    """The folder ``--report DIR`` names (``None`` without the option)."""
    if path is None:
        return None
    if not path.strip():
        raise FcompError(f"{option}: no folder name given (an empty argument)")
    return Path(path)


def check_outputs(inputs: InputSet, files: list[tuple[str, Path | None]],
                  folders: list[tuple[str, Path | None, str]] | None = None) -> None:
    """Refuse outputs that would overwrite an input (or its sidecar, or a folder holding
    one), that overlap each other, or folders fcomp may not replace (before any work)."""
    listed: list[tuple[str, Path, bool]] = []
    for option, path in files:
        if path is None:
            continue
        inputs.check_file(option, path)
        if path.suffix == ".csv" and option != "--json":  # a measurement: and its sidecar
            inputs.check_file(option, path.with_suffix(".toml"))
        if option == "--json" and path.suffix.lower() in _NOT_JSON:
            raise FcompError(f"--json {path}: a JSON result should not be written to a "
                             f"{path.suffix} file; name it .json")
        listed.append((option, path, False))
    for option, folder, kind in folders or []:
        if folder is None:
            continue
        inputs.check_folder(option, folder)
        check_folder_target(option, folder, kind)
        listed.append((option, folder, True))
    check_distinct(listed)


def plant_inputs(args: argparse.Namespace) -> InputSet:
    """The files a plant command reads besides its records: ``--plant-params`` and
    ``--friction`` when they name a ``.toml``/``.json`` file, and the ``--effects`` module."""
    inputs = InputSet()
    for option, spec in (("--plant-params", args.plant_params), ("--friction", args.friction)):
        if spec is not None and spec.lower().endswith((".toml", ".json")):
            inputs.file(spec, option)
    if args.effects is not None:
        inputs.file(args.effects, "--effects")
    return inputs


def measurement_inputs(paths: list[str], option: str = "DATA") -> InputSet:
    """The input set of measurement files; refuses the same file given twice."""
    from fcomp.measurement import measurement_paths
    from fcomp.outputs import same_file

    inputs = InputSet()
    seen: list[tuple[str, Path]] = []
    for p in paths:
        csv, _ = measurement_paths(p)
        for q, other in seen:
            if same_file(csv, other):
                raise FcompError(f"{p}: the same file is given twice (also as {q})")
        seen.append((p, csv))
        inputs.measurement(csv, option)
    return inputs


def warn_sidecar(meas: Any) -> None:
    """Warnings for suspicious sidecar entries of a measurement read (code ``unknown-key``)."""
    from fcomp.measurement import sidecar_warnings

    for key, message in sidecar_warnings(meas):
        warn("unknown-key", message, key)


def guard_outputs(data: list[str], effects: str | None, files: list[tuple[str, Path | None]],
                  folders: list[tuple[str, Path | None, str]] | None = None,
                  models: list[tuple[str, str]] | None = None) -> None:
    """:func:`check_outputs` for a command reading the measurements ``data`` (each once),
    the ``--effects`` module ``effects`` and the model files of ``models`` (``(option,
    spec)`` pairs; a spec that is a name, not a ``.json`` file, is no input)."""
    inputs = measurement_inputs(data)
    if effects is not None:
        inputs.file(effects, "--effects")
    for option, spec in models or []:
        if spec.lower().endswith(".json"):
            inputs.file(spec, option)
    check_outputs(inputs, files, folders)


def with_warnings(doc: dict[str, Any]) -> dict[str, Any]:
    """``doc`` with the command's warnings added to its ``"warnings"`` list (the contract's
    ``[{"code", "parameter", "message"}, ...]``, present even when empty)."""
    items = list(doc.get("warnings") or [])
    for w in current_warnings():
        if w not in items:
            items.append(w)
    return {**doc, "warnings": items}


def write_measurement(meas: Any, out: Path) -> tuple[Path, Path]:
    """Write ``meas`` to ``out`` (CSV and sidecar), the command's warnings so far in the
    sidecar; the two paths written."""
    ws = current_warnings()
    if ws:
        meas.meta["warnings"] = ws
    return meas.write(out)


def current_warnings() -> list[dict[str, Any]]:
    """The warnings so far, Python warnings caught on the way included."""
    for w in PYTHON_WARNINGS or []:
        code, message = python_warning(w)
        warn(code, message)
    if PYTHON_WARNINGS is not None:
        PYTHON_WARNINGS.clear()
    return list(WARNINGS)


class Progress:
    """A one-line progress display of a long simulation, on a terminal only.

    Shown once the run has taken ``delay`` s, updated at most twice a second,
    erased at the end: nothing is left on the screen, nothing goes to a
    redirected stderr.
    """

    def __init__(self, label: str, total: float, *, enabled: bool = True,
                 delay: float = 2.0) -> None:
        self.label, self.total, self.delay = label, total, delay
        self.enabled = enabled and sys.stderr.isatty()
        self.shown = False
        self._cm: Any = None

    def __enter__(self) -> Progress:
        from fcomp.progress import reporting

        self.start = self.last = time.monotonic()
        if self.enabled:
            self._cm = reporting(lambda done, total: self.update(done / total, done))
            self._cm.__enter__()
        return self

    def update(self, fraction: float, t: float) -> None:
        now = time.monotonic()
        if now - self.start < self.delay or now - self.last < 0.5 or fraction <= 0:
            return
        self.last = now
        spent = now - self.start
        left = spent * (1.0 - fraction) / fraction
        sys.stderr.write(f"\r{self.label}: {100 * fraction:.0f} % (t = {t:.4g} of "
                         f"{self.total:g} s, {_clock(spent)} spent, about {_clock(left)} left; "
                         "Ctrl-C stops)\x1b[K")
        sys.stderr.flush()
        self.shown = True

    def __exit__(self, *exc: Any) -> None:
        if self._cm is not None:
            self._cm.__exit__(*exc)
        if self.shown:
            sys.stderr.write("\r\x1b[K")
            sys.stderr.flush()


class Activity:
    """A one-line "still working" display for a step of unknown length (a fit), terminal only.

    Shown once the step has taken ``delay`` s: the label and the time spent,
    refreshed every half second by a background thread, erased at the end.
    """

    def __init__(self, label: str, *, enabled: bool = True, delay: float = 2.0) -> None:
        self.label, self.delay = label, delay
        self.enabled = enabled and sys.stderr.isatty()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.shown = False

    def _run(self) -> None:
        start = time.monotonic()
        while not self._stop.wait(0.5):
            spent = time.monotonic() - start
            if spent >= self.delay:
                sys.stderr.write(f"\r{self.label}: {_clock(spent)} spent (Ctrl-C stops)\x1b[K")
                sys.stderr.flush()
                self.shown = True

    def __enter__(self) -> Activity:
        if self.enabled:
            self._thread = threading.Thread(target=self._run, daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._thread is not None:
            self._stop.set()
            self._thread.join()
        if self.shown:
            sys.stderr.write("\r\x1b[K")
            sys.stderr.flush()


def _clock(seconds: float) -> str:
    m, s = divmod(int(seconds), 60)
    h, m = divmod(m, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


def provided(command: str) -> Callable[[argparse.Namespace], int]:
    """The run of ``command``, which a package above fcomp provides
    (:data:`fcomp.registry.COMMANDS`), looked up when the command runs: the options and help
    of a command need no package above fcomp."""

    def run(args: argparse.Namespace) -> int:
        return COMMANDS.get(command)(args)

    return run


def add_closed_loop_run_options(p: argparse.ArgumentParser) -> None:
    """The options of a command that runs many closed loops (``sweep``, ``compensate``):
    ``--workers``, ``--scheduler``, ``--json``, ``--report``, ``--no-progress``."""
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="local worker processes (default: CPU count)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on the Dask distributed scheduler at ADDRESS (tcp://host:8786)")
    p.add_argument("--json", metavar="OUT", default=None,
                   help="write the result as JSON to OUT ('-' for standard output)")
    p.add_argument("--report", metavar="DIR", default=None,
                   help="write a self-contained HTML report to DIR/report.html")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")


def result_text(doc: dict) -> str:
    """A command's JSON result as text: strict JSON, a non-finite number (the error of a
    run that failed, a bound at infinity) written as ``null``."""
    return json.dumps(_finite(doc), indent=2, allow_nan=False) + "\n"


def _finite(value: Any) -> Any:
    """``value`` with every non-finite float, at any depth, replaced by None."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    return value


def emit_result(text: str, json_arg: str | None, out: Path | None, summary: str) -> None:
    """Write a command's result: the JSON ``text`` alone to standard output for
    ``--json -``; otherwise the human ``summary``, then ``text`` to ``out``
    (atomically, so no half-written file is left) when ``--json OUT`` was given."""
    from fcomp.outputs import write_text

    if json_arg == "-":
        sys.stdout.write(text)
        return
    print(summary)
    if out is not None:
        write_text(out, text)
        print(f"wrote {out}")
