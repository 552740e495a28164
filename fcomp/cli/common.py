"""Pieces shared by the sub-commands: building models from options, output paths, JSON
results, warnings."""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import threading
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from fcomp.effects import load_effects_module
from fcomp.errors import FcompError, FcompWarning, deprecation_message, render_terms
from fcomp.models import FrictionModel, make_model
from fcomp.outputs import InputSet, check_distinct, check_folder_target
from fcomp.registry import COMMANDS

#: Largest magnitude accepted for a number given on the command line (SI units).
MAX_VALUE = 1e15

#: Warnings of the running command (``{"code", "parameter", "message"}``), printed as
#: ``fcomp: warning: ...`` after a successful run and written into its outputs.
WARNINGS: list[dict[str, Any]] = []
#: Files and reports written before the summary is printed: announced after it
#: (:func:`wrote`, :func:`emit_result`), so that the conclusion comes first.
WRITTEN: list[Path] = []
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


# ---------------------------------------------------------------- one vocabulary
#: The wording of ``--set`` on every command (docs/cli.md).
SET_HELP = ("set a friction parameter (flat name, SI units); in fit: its start value; "
            "repeatable")


class _Spellings:
    """Mixin of an argparse action whose option has deprecated spellings besides its own.

    The action holds every spelling (``option_strings``; the first is the canonical one)
    and stores into the canonical destination whichever is given. A deprecated spelling
    is noted in ``args._deprecated`` and :func:`say_deprecated` prints it after a run that
    succeeded: one line ``fcomp: warning: OLD is deprecated, use NEW ...`` on stderr
    (once per run, however often it is given); the old and the new spelling given together
    are one error (exit 2, no warning). The help lists only the canonical spelling
    (:class:`HelpFormatter`).
    """

    deprecated: tuple[str, ...] = ()
    dest: str
    option_strings: Sequence[str]

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:
        seen = namespace.__dict__.setdefault("_spellings", {}).setdefault(self.dest, set())
        seen.add(option_string)
        canonical = self.option_strings[0]
        old = sorted(s for s in seen if s in self.deprecated)
        if old and len(seen) > 1:
            parser.error(f"{old[0]} and {canonical} are the same option ({old[0]} is the "
                         f"deprecated spelling): give only {canonical}")
        said = namespace.__dict__.setdefault("_deprecated", [])
        if option_string in self.deprecated:
            line = deprecation_message(option_string, canonical)
            if line not in said:
                said.append(line)
        super().__call__(parser, namespace, values, option_string)  # type: ignore[misc]


def say_deprecated(args: argparse.Namespace) -> None:
    """Print the deprecated spellings the command line used, one line each, on stderr (after
    a successful run, before its other warnings: a failed one says only its error)."""
    for line in getattr(args, "_deprecated", ()):
        sys.stderr.write(f"fcomp: warning: {line}\n")


class _StoreSpellings(_Spellings, argparse._StoreAction):
    pass


class _AppendSpellings(_Spellings, argparse._AppendAction):
    pass


def add_option(p: argparse.ArgumentParser | Any, flag: str, *deprecated: str,
               **kwargs: Any) -> argparse.Action:
    """``p.add_argument(flag, ...)`` with the ``deprecated`` old spellings of the option
    still accepted for one release (:class:`_Spellings`): the one mechanism of every
    renamed option of the command line (docs/cli.md, "Deprecated spellings")."""
    if not deprecated:
        return p.add_argument(flag, **kwargs)
    kind = kwargs.pop("action", "store")
    cls = {"store": _StoreSpellings, "append": _AppendSpellings}[kind]
    action = type(cls.__name__, (cls,), {"deprecated": tuple(deprecated)})
    kwargs.setdefault("dest", flag.lstrip("-").replace("-", "_"))
    return p.add_argument(flag, *deprecated, action=action, **kwargs)


def add_friction_option(p: argparse.ArgumentParser, *deprecated: str, required: bool = True,
                        default: str | None = None, help: str | None = None) -> None:
    """``--friction NAME|MODEL.json``: the friction model, a registered name (fcomp list
    models) or a model file (fcomp fit --save-model)."""
    add_option(p, "--friction", *deprecated, required=required, default=default,
               metavar="NAME|MODEL.json",
               help=help or "the friction model: a name (fcomp list models) or a model file "
               "(fcomp fit --save-model)")


def add_add_effect_option(p: argparse.ArgumentParser, *deprecated: str,
                          help: str | None = None) -> None:
    """``--add-effect EFFECT`` (repeatable): an effect added to the friction model."""
    add_option(p, "--add-effect", *deprecated, action="append", default=[], metavar="EFFECT",
               help=help or "add a catalogue (or registered) effect to the model; repeatable")


def add_parallel_options(p: argparse.ArgumentParser, *deprecated: str, what: str,
                         default: str = "CPU count") -> None:
    """``--jobs N`` and ``--scheduler ADDRESS``: where the independent jobs ``what`` run
    (local processes, or a Dask distributed cluster); the results are the same."""
    add_option(p, "--jobs", *deprecated, type=int, default=None, metavar="N",
               help=f"local processes running {what} (default: {default})")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help=f"run {what} on the Dask distributed scheduler at ADDRESS "
                   "(tcp://host:8786) instead of local processes; the same results")


def check_jobs(jobs: int | None) -> None:
    """Refuse ``--jobs`` below 1."""
    if jobs is not None and jobs < 1:
        raise FcompError(f"--jobs must be a positive integer, got {jobs}")


def add_length_options(p: argparse.ArgumentParser, default: str, fast: str, full: str) -> None:
    """``--fast`` / ``--full``, a mutually exclusive pair storing ``args.fast``; ``default``
    (``"fast"`` or ``"full"``) is the command's own default, and the help says so."""
    g = p.add_mutually_exclusive_group()
    mark = {"fast": " (default)" if default == "fast" else "",
            "full": " (default)" if default == "full" else ""}
    g.add_argument("--fast", dest="fast", action="store_const", const=True,
                   help=f"{fast}{mark['fast']}")
    g.add_argument("--full", dest="fast", action="store_const", const=False,
                   help=f"{full}{mark['full']}")
    p.set_defaults(fast=default == "fast")


def add_progress_option(p: argparse.ArgumentParser) -> None:
    """``--no-progress``: no progress display (shown only on a terminal anyway)."""
    p.add_argument("--no-progress", action="store_true",
                   help="no progress display on stderr (it is shown only on a terminal)")


def add_set_option(p: argparse.ArgumentParser) -> None:
    """``--set NAME=VALUE``, worded alike on every command (:data:`SET_HELP`)."""
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help=SET_HELP)


#: The wording of ``--params`` on every command that takes it.
PARAMS_HELP = ("parameter values: a parameter set (fcomp list params), a fit's JSON (fcomp fit "
               "--json) or a model file (fcomp fit --save-model)")


def add_params_option(p: argparse.ArgumentParser, default: str) -> None:
    """``--params SET|FIT.json|MODEL.json`` (:func:`friction_values`)."""
    p.add_argument("--params", default=None, metavar="SET|FIT.json|MODEL.json",
                   help=f"{PARAMS_HELP} (default: {default})")


# ---------------------------------------------------------------- plain-text help
_REST = [
    (re.compile(r":(?:class|func|meth|mod|data|attr|exc|obj|ref|doc):`~?([^`<]*?)(?:\s*<[^>]*>)?`"),
     lambda m: m.group(1).rsplit(".", 1)[-1] if "." in m.group(1) and "(" not in m.group(1)
     else m.group(1)),
    (re.compile(r"``(.+?)``", re.S), lambda m: m.group(1)),
    (re.compile(r"(?<![\w`])`([^`\n]+)`_{0,2}(?![\w`])"), lambda m: m.group(1)),
    (re.compile(r"(?<![\w*])\*\*(?=\S)([^*\n]+?)(?<=\S)\*\*(?![\w*])"), lambda m: m.group(1)),
    (re.compile(r"(?<![\w*'\\])\*(?=[A-Za-z])([A-Za-z][^*\n]*?)(?<=[A-Za-z.])\*(?![\w*])"),
     lambda m: m.group(1)),
    (re.compile(r"(\S)::$", re.M), lambda m: m.group(1) + ":"),
    (re.compile(r"^(\s*)::$", re.M), lambda m: ""),
    (re.compile(r"\\\\"), lambda m: "\\"),
]


def plain_text(text: str) -> str:
    """``text`` (a module docstring in reST) as plain text for ``--help``: roles
    (``:class:`~a.B``` -> ``B``), literals (````x```` -> ``x``), emphasis and ``Example::``
    written plainly."""
    for pattern, repl in _REST:
        text = pattern.sub(repl, text)
    return text


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """The help of every command: descriptions as written (line breaks kept), in plain
    text (:func:`plain_text`), an option listed by its canonical spelling only (the
    deprecated ones of :func:`add_option` stay out of the help)."""

    def _format_action_invocation(self, action: argparse.Action) -> str:
        hidden = getattr(action, "deprecated", ())
        if not hidden:
            return super()._format_action_invocation(action)
        shown = argparse.Action([s for s in action.option_strings if s not in hidden],
                                action.dest, nargs=action.nargs, metavar=action.metavar)
        return super()._format_action_invocation(shown)

    def _expand_help(self, action: argparse.Action) -> str:
        return plain_text(super()._expand_help(action))

    def _format_text(self, text: str) -> str:
        return super()._format_text(plain_text(text))


def add_model_options(p: argparse.ArgumentParser, *, add_deprecated: tuple[str, ...] = ()
                      ) -> None:
    """``--add-effect EFFECT`` (repeatable), ``--effects MODULE.py`` and ``--set
    NAME=VALUE``: the options that change a friction model on every command."""
    add_add_effect_option(p, *add_deprecated)
    add_effects_option(p, "registers the user's own effects")
    add_set_option(p)


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
                   "that every friction option reads (simulate --friction, compare --friction, "
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
    _writable_folder("--save-model", path)
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
    measurement terms dropped with a warning) or a registered model with the values of
    ``params`` (a parameter set, a fit's JSON or a model file: :func:`model_with_params`).

    A file takes no ``params``; ``--add-effect`` and ``--set`` apply to it as to a name.
    """
    return _friction(spec, params, args, use, measured=False)[0]


def model_with_params(args: argparse.Namespace, *, use: str = "plant friction",
                      measured: bool = False, document: dict[str, Any] | None = None
                      ) -> tuple[FrictionModel, float | None]:
    """The model of ``--friction`` with the values of ``--params`` (``SET``, ``FIT.json``
    or ``MODEL.json``), ``--add-effect`` and ``--set``; and the moving mass (kg) a fit's
    JSON or a model file gives (``None`` otherwise).

    ``measured``: the model as fitted to its records (a model file's or a fit's offset
    kept as an effect; ``compare``); otherwise the seal's friction (measurement terms
    dropped with a warning). ``document``: the ``--params`` file already read
    (:func:`params_document`), not read again.
    """
    from fcomp.modelfile import is_model_file

    if args.params is not None and is_model_file(args.friction):
        raise FcompError(f"--params {args.params}: the model file {args.friction} gives the "
                         "values; change one with --set NAME=VALUE")
    return _friction(args.friction, args.params, args, use, measured=measured,
                     document=document)


def _friction(spec: str, params: str | None, args: argparse.Namespace, use: str, *,
              measured: bool, document: dict[str, Any] | None = None
              ) -> tuple[FrictionModel, float | None]:
    from fcomp.modelfile import is_model_file, read_model, seal_friction

    mass: float | None = None
    if is_model_file(spec):
        if params is not None and is_model_file(params):  # a set gives a plant's values
            raise FcompError(f"--params {params}: the model file {spec} gives the values; "
                             "change one with --set NAME=VALUE")
        if measured:
            mf = read_model(spec, args.effects)
            model, mass = mf.measured_model(), mf.mass
        else:
            model, dropped = seal_friction(spec, use, args.effects)
            if dropped:
                warn("measurement-terms", dropped, "friction")
    elif params is not None and is_model_file(params):
        model, mass = _values_file(spec, params, args.effects, use, measured, document)
    else:
        return build_model(spec, params, args), None
    if args.add_effect:
        model = model.with_effects(*args.add_effect)
    overrides = parse_assignments(args.set)
    return (model.with_params(**overrides) if overrides else model), mass


def params_document(path: str) -> dict[str, Any]:
    """The JSON object of ``--params FILE.json`` (a fit's JSON or a model file), read once;
    one line naming the file on any problem."""
    from fcomp.textdata import check_path, read_text

    try:
        doc = json.loads(read_text(check_path(path, "parameter file"), path, what="JSON"))
    except json.JSONDecodeError as exc:
        raise FcompError(f"--params {path}: not valid JSON ({exc.msg}, line {exc.lineno})") \
            from None
    if not isinstance(doc, dict):
        raise FcompError(f"--params {path}: neither a fit's JSON nor a model file (a JSON "
                         "object is expected)")
    return doc


def _values_file(name: str, path: str, effects: str | None, use: str, measured: bool,
                 doc: dict[str, Any] | None = None) -> tuple[FrictionModel, float | None]:
    """The model ``name`` with the values of ``--params FILE.json``: a fit's JSON (``fcomp
    fit --json``) or a model file (``fcomp fit --save-model``) of that model (``doc``: the
    file already read)."""
    from fcomp.diagnosis.compare import model_from_fit
    from fcomp.modelfile import read_model

    source = f"--params {path}"
    doc = params_document(path) if doc is None else doc
    if isinstance(doc.get("records"), list):
        raise FcompError(f"{source}: the JSON of a fit of several records; give the fit of "
                         "one record")
    if doc.get("model") not in (None, name):
        raise FcompError(f"{source}: gives the values of {doc['model']}, not of {name}; "
                         f"give --friction {doc['model']}")
    if effects is not None:
        load_effects_module(effects)
    if "format" in doc or (not measured and isinstance(doc.get("model_file"), dict)):
        mf = read_model(doc, effects)
        if measured:
            return mf.measured_model(), mf.mass
        if mf.measurement_terms:
            warn("measurement-terms", mf.dropped_note(use).replace("model document", source),
                 "params")
        return mf.model, None
    return model_from_fit(doc, make_model(name), source=source)


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
        If ``path`` is empty, a directory, or under a file (checked before any work, so a
        failure never leaves a half-written result). Missing folders are created, as for
        every output (and removed again if the run fails).
    """
    if path is None or path == "-":
        return None
    if not path.strip():
        raise FcompError("--json: no file name given (an empty argument; '-' is standard output)")
    out = Path(path)
    if out.is_dir():
        raise FcompError(f"--json {path}: is a directory")
    _writable_folder("--json", path)
    return out


def _writable_folder(option: str, path: str) -> None:
    """Refuse an output file under a file; a missing folder is fine (every output creates
    its missing folders, :func:`fcomp.outputs.write_files`)."""
    parent = Path(path).parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise FcompError(f"{option} {path}: {parent} is a file, not a folder")


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
    """``doc`` with one ``"warnings"`` list (the contract's ``[{"code", "parameter",
    "message"}, ...]``, present even when empty): its own warnings, recorded as the
    command's so that they are printed too (on stderr, grouped, by :func:`fcomp.cli.main.main`),
    and every other warning of the command."""
    for w in doc.get("warnings") or []:
        warn(w["code"], w["message"], w.get("parameter"))
    return {**doc, "warnings": current_warnings()}


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
    ``--jobs`` (old spelling ``--workers``), ``--scheduler``, ``--json``, ``--report``,
    ``--no-progress``."""
    add_parallel_options(p, "--workers", what="the closed-loop runs")
    p.add_argument("--json", metavar="OUT", default=None,
                   help="write the result as JSON to OUT ('-' for standard output)")
    p.add_argument("--report", metavar="DIR", default=None,
                   help="write a self-contained HTML report to DIR/report.html")
    add_progress_option(p)


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


def wrote(path: Path) -> None:
    """Announce ``path`` (a report written before the result) after the summary."""
    WRITTEN.append(path)


def emit_result(text: str, json_arg: str | None, out: Path | None, summary: str) -> None:
    """Write a command's result: the JSON ``text`` alone to standard output for
    ``--json -``; otherwise the human ``summary``, then ``text`` to ``out``
    (atomically, so no half-written file is left) when ``--json OUT`` was given."""
    from fcomp.outputs import write_text

    if json_arg == "-":
        sys.stdout.write(text)
        return
    print(summary)
    for path in WRITTEN:
        print(f"wrote {path}")
    WRITTEN.clear()
    if out is not None:
        write_text(out, text)
        print(f"wrote {out}")
