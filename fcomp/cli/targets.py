"""The outputs of a command, checked before any work: never onto an input, never two onto
one place, folders fcomp may replace (the rules of :mod:`fcomp.outputs`)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from fcomp.errors import FcompError
from fcomp.outputs import (
    InputSet,
    check_distinct,
    check_folder_target,
    check_name_length,
    check_writable,
)


def model_target(path: str | None) -> Path | None:
    """The file ``--save-model PATH`` writes (``None`` without the option); checked before
    any work: a ``.json`` name in an existing folder."""
    if path is None:
        return None
    if not path.strip():
        raise FcompError("--save-model: no file name given (an empty argument)")
    out = Path(path)
    check_name_length("--save-model", out)
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


def output_path(path: str, suffix: str = ".csv", option: str = "-o") -> Path:
    """The measurement file an ``-o OUT.csv`` option names (its sidecar goes next to it)."""
    if not path.strip():
        raise FcompError(f"{option}: no file name given (an empty argument)")
    p = Path(path)
    check_name_length(option, p)
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
    check_name_length("--json", out)
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
    check_name_length(option, Path(path))
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
    for option, path, _ in listed:  # writable, before the work: not found after a long run
        check_writable(option, path)


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
