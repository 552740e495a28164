"""The diagnosis matrix: cases of hidden effects x styles x scales x baselines x seeds, and their judge.

A *case* is one synthetic record (:func:`fcomp.synthetic.generate`) and the
baseline a user would diagnose it with. The *judge* reads only the public
JSON of ``fcomp diagnose`` (``added``, ``ties``, ``verdict``, ``rms_baseline``,
``rms_final``), so it tests the contract, not the implementation, and this
module imports nothing of :mod:`fcomp.diagnosis`.

Rows (what is hidden) and what a right answer is:

* one catalogue effect: it is added (or named in a reported tie with the
  effect added, a confounded group), nothing else is added, the verdict is
  ``explained`` and the held-out error falls to at most
  :data:`MAX_ERROR_RATIO` of the baseline's -- the RMS, or its excess over
  the record's true noise (:func:`judge`);
* two catalogue effects: both are added (a structural one first where the
  other needs it), nothing else, ``explained``, the same fall;
* nothing: nothing is added, ``explained``;
* an effect outside the catalogue: nothing is added,
  ``unexplained-structure``.

Baseline kinds: ``static`` (a static generator law and the matching static
baseline) and ``dynamic`` (the LuGre law and the ``lugre`` baseline); rows
whose effect is already part of a kind's baseline (a viscous term in LuGre)
or needs another effect first have only the other kind. Shapes rotate with
the case so that every shape of every effect is met; nuisance parameters are
drawn per seed (``vary=True``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

from fcomp.synthetic import OUTSIDE, SHAPES, STYLES, generate

#: Largest held-out error, as a share of the baseline's, of a right answer.
MAX_ERROR_RATIO = 0.6
#: The default scales and styles (the generator has more: ``small-pneumatic``,
#: ``heavy-hydraulic``, the ``potentiometer`` styles -- magnitudes and a sensor the
#: matrix's figures were not tuned on, run with ``--scales`` and ``--styles``).
SCALES = ("pneumatic", "hydraulic")
MATRIX_STYLES = ("load-cell", "tacho", "encoder-velocity", "pressures", "pressures-tacho",
                 "coarse-encoder", "drive-force")
KINDS = ("static", "dynamic")

#: kind -> (generator base law, baseline model name), and per-row exceptions.
KIND_BASES: dict[str, tuple[str, str]] = {"static": ("stribeck", "stribeck"),
                                          "dynamic": ("lugre", "lugre")}


@dataclass(frozen=True)
class Row:
    """One row of the matrix: what is hidden and which baseline kinds apply.

    ``static_base`` overrides the static kind's ``(generator base, baseline)``.
    ``ordered`` pairs ``(a, b)``: ``a`` must be added before ``b``.
    """

    name: str
    hidden: tuple[str, ...]
    kinds: tuple[str, ...] = KINDS
    static_base: tuple[str, str] | None = None
    ordered: tuple[tuple[str, str], ...] = ()
    needs: tuple[str, ...] = ()  # signals the row needs in the record (style filter)

    @property
    def outside(self) -> bool:
        return any(h in OUTSIDE for h in self.hidden)

    @property
    def expected(self) -> tuple[str, ...]:
        return () if self.outside else self.hidden


ROWS: tuple[Row, ...] = (
    Row("viscous", ("viscous",), ("static",), ("coulomb", "coulomb")),
    Row("stribeck", ("stribeck",), ("static",), ("coulomb-viscous", "coulomb-viscous")),
    Row("presliding", ("presliding",), ("static",)),
    Row("nonlocal-memory", ("nonlocal-memory",), ("dynamic",)),
    Row("frictional-lag", ("frictional-lag",)),
    Row("dwell-time", ("dwell-time",), KINDS, ("coulomb-viscous", "coulomb-viscous")),
    Row("direction-asymmetry", ("direction-asymmetry",)),
    Row("pressure-dependence", ("pressure-dependence",), needs=("p1", "p2")),
    Row("position-dependence", ("position-dependence",), needs=("x",)),
    Row("viscous-lead", ("viscous-lead",)),
    Row("inertia-error", ("inertia-error",)),
    Row("force-offset", ("force-offset",)),
    Row("presliding+direction-asymmetry", ("presliding", "direction-asymmetry"), ("static",)),
    Row("pressure+direction-asymmetry", ("pressure-dependence", "direction-asymmetry"),
        needs=("p1", "p2")),
    Row("nothing", ()),
    *(Row(o, (o,)) for o in OUTSIDE),
)

CASE_FIELDS = ("row", "kind", "style", "scale", "seed", "shape", "baseline", "base")


@dataclass(frozen=True)
class Case:
    """One record of the matrix and the baseline it is diagnosed with."""

    row: str
    kind: str
    style: str
    scale: str
    seed: int
    shape: str
    baseline: str
    base: str
    duration: float
    rate: float

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    @property
    def spec(self) -> Row:
        return next(r for r in ROWS if r.name == self.row)


def _style_signals(style: str) -> set[str]:
    """Signals a style records (from the generator's style registry)."""
    return set(STYLES[style].columns)


def cases(*, seeds: Iterable[int] = (1, 2, 3), rows: Sequence[str] | None = None,
          styles: Sequence[str] | None = None, scales: Sequence[str] | None = None,
          kinds: Sequence[str] | None = None, duration: float = 40.0,
          rate: float = 1000.0) -> list[Case]:
    """Every case of the matrix (or of the named subsets)."""
    out = []
    style_list = list(styles or MATRIX_STYLES)
    scale_list = list(scales or SCALES)
    seed_list = list(seeds)
    for row in ROWS:
        if rows and row.name not in rows:
            continue
        for kind in row.kinds:
            if kinds and kind not in kinds:
                continue
            base, baseline = (row.static_base or KIND_BASES["static"]) if kind == "static" \
                else KIND_BASES["dynamic"]
            for si, style in enumerate(style_list):
                if not set(row.needs) <= _style_signals(style):
                    continue
                for ci, scale in enumerate(scale_list):
                    for seed in seed_list:
                        shapes = [":".join(_shape_of(h, seed + si + 2 * ci + k))
                                  for k, h in enumerate(row.hidden)]
                        out.append(Case(row.name, kind, style, scale, int(seed),
                                        ",".join(shapes), baseline, base, duration, rate))
    return out


def _shape_of(effect: str, k: int) -> tuple[str, str]:
    names = SHAPES[effect]
    return effect, names[k % len(names)]


def record(case: Case):
    """The synthetic record of ``case``."""
    hidden = [s for s in case.shape.split(",") if s]
    return generate(hidden, base=case.base, scale=case.scale, style=case.style,
                    duration=case.duration, rate=case.rate, seed=case.seed, vary=True,
                    name=f"case-{case.seed}")


def _named(effect: str, added: Sequence[str], ties: Sequence[Sequence[str]]) -> bool:
    if effect in added:
        return True
    return any(effect in t and set(t) & set(added) for t in ties)


def judge(case: Case, doc: Mapping[str, Any], noise_std: float = 0.0) -> tuple[bool, str]:
    """``(right, why)`` of one diagnosis JSON (``fcomp diagnose --json``) for ``case``.

    ``noise_std`` is the record's true force noise (the generator's truth): the
    held-out error that can fall is the excess over it, ``sqrt(rms^2 - noise^2)``,
    and the fall is judged on that excess (an effect that acts only at
    break-aways cannot take 40 % off an RMS the noise dominates).
    """
    if "error" in doc:
        return False, f"failed: {doc['error']}"
    row = case.spec
    added = list(doc.get("added") or [])
    ties = [list(t) for t in doc.get("ties") or []]
    verdict = doc.get("verdict")
    expected = row.expected
    problems = []
    for e in expected:
        if not _named(e, added, ties):
            problems.append(f"{e} not found")
    tied_ok = {x for t in ties for x in t if set(t) & set(expected)}
    extra = [a for a in added if a not in expected and a not in tied_ok]
    if extra:
        problems.append(f"wrongly added {', '.join(extra)}")
    for a, b in row.ordered:
        if a in added and b in added and added.index(a) > added.index(b):
            problems.append(f"{b} added before {a}")
    want = "unexplained-structure" if row.outside else "explained"
    if verdict != want:
        problems.append(f"verdict {verdict} (want {want}: {doc.get('reason', '')})")
    if expected:
        rb, rf = doc.get("rms_baseline"), doc.get("rms_final")
        if rb is None or rf is None or not (math.isfinite(rb) and math.isfinite(rf)):
            problems.append("no held-out error")
        else:
            eb = math.sqrt(max(rb * rb - noise_std**2, 0.0))
            ef = math.sqrt(max(rf * rf - noise_std**2, 0.0))
            if rf > MAX_ERROR_RATIO * rb and ef > MAX_ERROR_RATIO * eb:
                problems.append(f"held-out error {rb:.3g} -> {rf:.3g} N, excess over the noise "
                                f"{eb:.3g} -> {ef:.3g} N (> {MAX_ERROR_RATIO} x)")
    return (not problems), ("; ".join(problems) if problems else
                            f"{'+'.join(added) or 'nothing'} / {verdict}")
