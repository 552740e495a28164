"""``fcomp list [WHAT]`` -- the registered names, one a line with what each is.

WHAT is models, effects, plants, params, controllers, studies or data (default:
all). ``data`` lists the real data sets shipped with fcomp, each file by the name
``fcomp import KIND NAME -o OUT.csv`` takes from any folder.
The description of a name is its object's own: a ``description`` attribute, else
the first paragraph of its docstring (a parameter set: where its numbers come
from), so that a model, effect, plant, controller or study you register yourself
is described as well.
"""

from __future__ import annotations

import argparse
from typing import Any

#: What ``fcomp list`` shows, in order.
GROUPS = ("models", "effects", "plants", "params", "controllers", "studies", "data")

#: Longest description kept whole; a longer one is cut after its first clause.
_SHORT = 90

#: The pointer some docstrings end their first line with: not a description.
_POINTER = " (see the module docstring)"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("list", help="list the registered names with a short description",
                       description=__doc__)
    p.add_argument("what", nargs="?", default="all", metavar="WHAT",
                   choices=["all", *GROUPS],
                   help=f"what to list: {', '.join(GROUPS)} or all (default)")
    p.set_defaults(func=run)


def description(obj: Any) -> str:
    """One line saying what a registered object is: its ``description`` attribute, else the
    first paragraph of its own docstring in plain text (empty when it has neither)."""
    from fcomp.cli.common import plain_text

    text = getattr(obj, "description", None)
    if not isinstance(text, str) or not text.strip():
        doc = obj.__dict__.get("__doc__") if isinstance(obj, type) else type(obj).__doc__
        text = (doc or "").strip().split("\n\n")[0]
    line = " ".join(plain_text(text).split()).replace(_POINTER, "")
    if len(line) > _SHORT:  # a long paragraph: its first clause or sentence
        line = _first_clause(line)
    return line.rstrip(":")


def _first_clause(line: str) -> str:
    """``line`` up to its first ``: `` or sentence end outside parentheses."""
    depth = 0
    for i, c in enumerate(line[:-2]):
        depth += (c == "(") - (c == ")")
        if depth == 0 and i > 20 and (line[i:i + 2] == ": " or (
                c == "." and line[i + 1] == " " and line[i + 2].isupper())):
            return line[:i + (c == ".")]
    return line


def entries(group: str) -> list[tuple[str, str]]:
    """``(name, description)`` of every name of ``group`` (:data:`GROUPS`); empty for a
    group whose package this build leaves out."""
    import fcomp.paramsets as paramsets
    from fcomp.effects import EFFECTS
    from fcomp.models import MODELS
    from fcomp.registry import CONTROLLERS, PLANTS, STUDIES

    if group == "params":
        return [(n, paramsets.SOURCES[n]) for n in paramsets.names()]  # no file parsed
    if group == "data":
        return _data_entries()
    if group == "effects":
        return [(n, f"{description(e)} [{e.signature}]")
                for n in EFFECTS.names() for e in [EFFECTS.get(n)]]
    registry: Any = {"models": MODELS, "plants": PLANTS, "controllers": CONTROLLERS,
                     "studies": STUDIES}[group]
    return [(n, description(registry.get(n))) for n in registry.names()]


def _data_entries() -> list[tuple[str, str]]:
    """The shipped data files: ``(name, "fcomp import KIND NAME ...: the set's title")``;
    a set of tables (not records) names its folder."""
    from fcomp import datasets

    out = []
    for ds in datasets.names():
        kind = datasets.IMPORT_KIND[ds]
        for f in datasets.files(ds):
            stem = f.rsplit(".", 1)[0]
            how = (f"fcomp import {kind} {stem} -o OUT.csv" if kind is not None
                   else f"a table in {datasets.root() / ds}")
            out.append((stem, f"{how} ({datasets.title(ds)})"))
    return out


def run(args: argparse.Namespace) -> int:
    for group in GROUPS:
        if args.what not in ("all", group):
            continue
        items = entries(group)
        if not items:  # a build without that package
            continue
        print(f"{group}:")
        width = max(len(n) for n, _ in items)
        for name, text in items:
            print(f"  {name:{width}s}  {text or '(no description)'}")
    return 0
