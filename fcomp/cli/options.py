"""The one vocabulary of the command line (docs/cli.md): the options every command shares,
their deprecated spellings, and the parsing of their values."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Sequence
from typing import Any

from fcomp.errors import FcompError, deprecation_message
from fcomp.parameters import MAX_VALUE  # noqa: F401 (the one limit of numbers given)
from fcomp.registry import COMMANDS


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


def add_save_model_option(p: argparse.ArgumentParser, what: str) -> None:
    """``--save-model MODEL.json``: write ``what`` as a model file (docs/model-file.md)."""
    p.add_argument("--save-model", metavar="MODEL.json", default=None,
                   help=f"write {what} as a model file (versioned JSON, docs/model-file.md) "
                   "that every friction option reads (simulate --friction, compare --friction, "
                   "...)")


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
