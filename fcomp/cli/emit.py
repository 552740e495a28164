"""What a command says: its warnings (``fcomp: warning: ...``, recorded while it runs and
printed after a successful run), the files it wrote, and its result (JSON and summary)."""

from __future__ import annotations

import json
import math
import sys
import warnings
from pathlib import Path
from typing import Any

from fcomp.errors import FcompWarning, render_terms

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
    "mass": "--mass", "samples": "--samples", "spread": "--spread", "noise": "--noise",
    "grid": "--grid", "seed": "--seed",
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


def warn_sidecar(meas: Any) -> None:
    """Warnings for suspicious sidecar entries of a measurement read (code ``unknown-key``)."""
    from fcomp.measurement import sidecar_warnings

    for key, message in sidecar_warnings(meas):
        warn("unknown-key", message, key)


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


def write_stdout(text: str, what: str) -> None:
    """Write ``text`` (the command's product: ``what``) to standard output; one line if
    standard output is closed (``>&-``: Python then has no ``sys.stdout`` at all)."""
    from fcomp.errors import FcompError

    if sys.stdout is None:
        raise FcompError(f"standard output is closed: nowhere to write {what}; redirect it "
                         "to a file (> FILE)")
    try:
        sys.stdout.write(text)
        sys.stdout.flush()
    except BrokenPipeError:
        raise
    except OSError as exc:
        raise FcompError(f"standard output: cannot write {what} ({exc.strerror or exc})") \
            from None


def emit_result(text: str, json_arg: str | None, out: Path | None, summary: str) -> None:
    """Write a command's result: the JSON ``text`` alone to standard output for
    ``--json -``; otherwise the human ``summary``, then ``text`` to ``out``
    (atomically, so no half-written file is left) when ``--json OUT`` was given."""
    from fcomp.outputs import write_text

    if json_arg == "-":
        write_stdout(text, "the JSON result (--json -)")
        return
    print(summary)
    for path in WRITTEN:
        print(f"wrote {path}")
    WRITTEN.clear()
    if out is not None:
        write_text(out, text)
        print(f"wrote {out}")
