"""Named parameter sets carried in the package (models.md section 4).

The TOML files in ``fcomp/data/paramsets/`` are copies of the project's
``params/`` files: every number with its source (a seed table, or
``assumed`` with the reason). A set is selected by name:

==================== ==================================================================
name                 content
==================== ==================================================================
``canudas1995``      LuGre test vector, Canudas de Wit et al. 1995 Table I, unit mass
``seed000-cylinder1`` seed 000 Table 1 cylinder 1, Table 4 NMLGM friction, Tables 2-3
                     hysteresis function
``seed000-cylinder2`` cylinder 2 (Table 4; hysteresis of cylinder 1, the seed gives no other)
``seed000-cylinder3`` cylinder 3 (idem)
``seed000-servo``    pneumatic position servo: cylinder 1 + the assumed 5/3 valve
``seed002-type1``    electrohydraulic servo of seed 002 with Type 1 cylinder friction
==================== ==================================================================

**Unit of seed 000 Table 2.** The table prints the segment boundaries
``z1..z5`` (and the internal-loop ``zc``, ``zd``) in "mm" with values around
``1e-4``. Read as millimetres they would be 0.1-0.3 *micrometres*: with the
Table 3 rates ``k_i`` (3e4-3.4e5 1/m) every segment would then be a straight
line (``k_i*width`` ~ 0.004-0.04) rising by hundredths of a newton, whereas
the paper's loops (Figs. 4, 17) span several newtons over a few tenths of a
millimetre. Read as *metres* they are 0.08-0.27 mm: ``k_i*width`` is 2.8-38
(curved, saturating segments as in Fig. 17), ``zc, zd = 0.246, 0.265 mm``
match the displacement points 0.292 and 0.311 mm the text quotes for the
internal loop (an internal loop 0.019 mm wide), and all lie below the
sliding threshold ``Fs/sigma0 = 1.5 mm``. The package therefore reads the
Table 2 values as metres (the "mm" heading is taken to be a misprint).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any

from fcomp.errors import UnknownNameError
from fcomp.parameters import Directional

_FILES = {
    "canudas1995": "lugre-canudas1995.toml",
    "seed000-cylinder1": "pneumatic-seed000.toml",
    "seed000-cylinder2": "pneumatic-seed000.toml",
    "seed000-cylinder3": "pneumatic-seed000.toml",
    "seed000-servo": "pneumatic-seed000.toml",
    "seed002-type1": "hydraulic-seed002.toml",
}

SOURCES = {
    "canudas1995": "Canudas de Wit, Olsson, Astrom, Lischinsky, IEEE TAC 40(3) 1995, Table I",
    "seed000-cylinder1": "seed 000 Tables 1-4 (cylinder 1); mass assumed",
    "seed000-cylinder2": "seed 000 Tables 1 and 4 (cylinder 2); mass assumed; hysteresis "
    "segments of cylinder 1 (assumed: the seed gives them for cylinder 1 only)",
    "seed000-cylinder3": "seed 000 Tables 1 and 4 (cylinder 3); mass assumed; hysteresis "
    "segments of cylinder 1 (assumed)",
    "seed000-servo": "seed 000 cylinder 1 + assumed proportional 5/3 valve (params file)",
    "seed002-type1": "seed 002 Table 2 + assumed geometry and friction (params file)",
}


@cache
def _load(filename: str) -> dict[str, Any]:
    text = resources.files("fcomp.data.paramsets").joinpath(filename).read_text()
    return tomllib.loads(text)


def names() -> list[str]:
    """Names of the parameter sets carried in the package."""
    return sorted(_FILES)


@dataclass(frozen=True)
class ParameterSet:
    """A named parameter set: friction sections, rig geometry and plant data (SI).

    Attributes
    ----------
    name, source
        Set name and where its numbers come from.
    friction
        Model-section name -> flat parameter mapping (directional values as
        :class:`~fcomp.parameters.Directional`).
    hysteresis
        Flat hysteresis-function parameters (seed 000 Tables 2-3, metres).
    rig
        ``bore``, ``rod``, ``stroke`` (m), ``mass`` (kg), ``orientation``.
    raw
        The whole TOML document (plant sections: valve, fluid, supply, ...).
    plant
        The plant's parameters by flat name (SI), when the set gives them
        directly (a plant file, :mod:`plants.planfile`); empty for the sets
        here, whose plants read their sections from ``raw``.
    """

    name: str
    source: str
    friction: dict[str, dict[str, Any]]
    hysteresis: dict[str, float] = field(default_factory=dict)
    rig: dict[str, Any] = field(default_factory=dict)
    raw: dict[str, Any] = field(default_factory=dict)
    plant: dict[str, float] = field(default_factory=dict)

    def friction_section(self, model_name: str) -> dict[str, Any]:
        """The friction parameters for ``model_name``.

        The section whose ``model`` key equals the name is used; otherwise the
        fullest section (most parameters), of which the model keeps the
        parameters it has (others take the model's defaults).
        """
        for sec in self.friction.values():
            if sec.get("model") == model_name:
                return {k: v for k, v in sec.items() if k != "model"}
        best = max(self.friction.values(), key=len)
        return {k: v for k, v in best.items() if k != "model"}


def _friction_values(section: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in section.items():
        if isinstance(v, dict) and set(v) == {"pos", "neg"}:
            out[k] = Directional(v["pos"], v["neg"])
        else:
            out[k] = v
    return out


def _hysteresis(doc: dict[str, Any], key: str) -> dict[str, float]:
    h = doc.get("hysteresis", {}).get(key)
    if not h:
        return {}
    out: dict[str, float] = {}
    # Table 2 values are read as metres (see the module docstring).
    for k, v in h["boundaries_mm"].items():
        out[k] = float(v)
    for k, v in h["segments"].items():
        out[k] = float(v)
    return out


@cache
def get(name: str) -> ParameterSet:
    """The parameter set called ``name``."""
    if name not in _FILES:
        raise UnknownNameError(f"unknown parameter set {name!r}; known: {', '.join(names())}")
    doc = _load(_FILES[name])
    if name == "canudas1995":
        sec = {k: v for k, v in doc.items() if k not in ("name", "mass")}
        return ParameterSet(name, SOURCES[name], {"lugre": _friction_values(sec)},
                            rig={"mass": doc["mass"], "orientation": "horizontal"}, raw=doc)
    if name.startswith("seed000-"):
        idx = "1" if name == "seed000-servo" else name[-1]
        cyl = dict(doc["cylinder"][idx])
        rig = {**cyl, "orientation": "horizontal"}
        return ParameterSet(
            name, SOURCES[name], {"nmlgm": _friction_values(doc["friction"][idx])},
            hysteresis=_hysteresis(doc, idx) or _hysteresis(doc, "1"), rig=rig, raw=doc,
        )
    # seed002-type1
    fr = {k: _friction_values(v) for k, v in doc["friction"].items()}
    cyl = doc["cylinder"]
    rig = {"bore": cyl["bore"], "rod": cyl["rod"], "stroke": cyl["stroke"],
           "mass": doc["load"]["mass"], "orientation": doc["load"]["orientation"]}
    return ParameterSet(name, SOURCES[name], fr, rig=rig, raw=doc)


def friction_values(set_name: str, model_name: str) -> dict[str, Any]:
    """The friction values set ``set_name`` gives model ``model_name`` (flat names, SI).

    The model's friction section (:meth:`ParameterSet.friction_section`) with
    the hysteresis-function values of the set; ``B`` of ``coulomb-viscous``
    is the set's ``sigma2`` where the set gives no ``B``. Which of them a
    model takes is the model's business (:func:`fcomp.models.model_params`).
    """
    pset = get(set_name)
    values = dict(pset.friction_section(model_name))
    values.update(pset.hysteresis)
    if model_name == "coulomb-viscous" and "B" not in values and "sigma2" in values:
        values["B"] = values["sigma2"]
    return values
