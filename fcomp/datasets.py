"""The real data sets shipped with the package (``fcomp/data/datasets/``).

Each data set is a folder with the files copied unchanged from their source and
a ``SOURCE.md`` giving the citation and licence (see docs/data.md):

* ``emps`` -- EMPS benchmark (``DATA_EMPS.mat``, ``DATA_EMPS_PULSES.mat``);
* ``zillen`` -- a subset of the TU Delft pneumatic seal-friction tests;
* ``mataveid`` -- MataveID hydraulic bench ``HangingLoad.csv``;
* ``seed001`` -- the measured friction tables of seed 001 (tables, not time series).

Files are found with :mod:`importlib.resources`, so this works from an
installed package as well as from the source tree -- and from any folder:
``fcomp import zillen O-ring_3bar -o run.csv`` takes the shipped file by name
(:func:`shipped`), ``fcomp list data`` lists them.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from fcomp.errors import FcompError, UnknownNameError
from fcomp.measurement import Measurement

#: Data set name -> the importer kind that converts its files (None: tables only).
IMPORT_KIND: dict[str, str | None] = {
    "emps": "emps", "zillen": "zillen", "mataveid": "mataveid", "seed001": None,
}


def root() -> Path:
    """The folder holding the data sets."""
    return Path(str(resources.files("fcomp.data").joinpath("datasets")))


def names() -> list[str]:
    """The shipped data sets."""
    return sorted(IMPORT_KIND)


def _folder(name: str) -> Path:
    if name not in IMPORT_KIND:
        raise UnknownNameError(f"unknown data set {name!r}; known: {', '.join(names())}")
    return root() / name


def files(name: str) -> list[str]:
    """The data files of data set ``name`` (without SOURCE.md, README and licences)."""
    skip = {"SOURCE.md", "README.txt"}
    return sorted(p.name for p in _folder(name).iterdir()
                  if p.is_file() and p.name not in skip and not p.name.startswith("LICENSE"))


def path(name: str, file: str) -> Path:
    """The path of ``file`` in data set ``name``; a clear error if it is not shipped."""
    p = _folder(name) / file
    if not p.is_file():
        raise FcompError(f"data set {name!r} has no file {file!r} (files: {', '.join(files(name))})")
    return p


def title(name: str) -> str:
    """The data set's title: the first heading of its ``SOURCE.md``."""
    for line in (_folder(name) / "SOURCE.md").read_text(encoding="utf-8").splitlines():
        if line.startswith("# "):
            return line[2:].strip()
    return name


def shipped(kind: str, name: str) -> Path | None:
    """The shipped file an importer ``kind`` takes by ``name`` -- its file name, or that
    name without its suffix (``fcomp import zillen O-ring_3bar``); ``None`` when no data
    set of that kind ships it."""
    for ds in names():
        if IMPORT_KIND[ds] != kind:
            continue
        for f in files(ds):
            if name in (f, Path(f).stem):
                return _folder(ds) / f
    return None


def shipped_names(kind: str) -> list[str]:
    """The names (file stems) of the shipped files importer ``kind`` takes."""
    return [Path(f).stem for ds in names() if IMPORT_KIND[ds] == kind for f in files(ds)]


def load(name: str, file: str) -> Measurement:
    """``file`` of data set ``name`` converted by its importer (SI, with provenance)."""
    from fcomp.importers import import_file

    kind = IMPORT_KIND.get(name, "")
    src = path(name, file)
    if kind is None:
        raise FcompError(f"data set {name!r} holds tables, not time series: read {src} "
                         "with numpy.genfromtxt(..., names=True, delimiter=',')")
    return import_file(kind, src)
