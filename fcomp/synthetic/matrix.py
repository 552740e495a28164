"""The diagnosis matrix: cases of hidden effects x styles x scales x baselines x conditions x
seeds, and their judge.

A *case* is one synthetic record (:func:`fcomp.synthetic.generate`) and the
baseline a user would diagnose it with. The *judge* reads only the public
JSON of ``fcomp diagnose`` (``added``, ``ties``, ``verdict``, ``rms_baseline``,
``rms_final``, ``disturbances``), so it tests the contract, not the
implementation, and this module imports nothing of :mod:`fcomp.diagnosis`.

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

Rows not in the default selection (:data:`DEFAULT_ROWS`; name them, or
``"all"``, in :func:`cases`'s ``rows``): two effects hidden on a base that
the dynamic baseline must carry too -- ``dwell-time+direction-asymmetry``
(stiction after rest on a seal that rubs harder one way) and
``pressure-dependence+dwell-time`` (a pneumatic lip seal: pressed harder at
higher pressure, and sticking after rest), both kinds.

Conditions (:data:`CONDITIONS`, :func:`condition_args`): how the logger,
the sensors or the rig differ from the records the diagnosis was built on.
``plain`` is the original record (the default, so the default cases are the
old ones); ``irregular-stamps`` and ``gapped-stamps`` a logger's stamps
(``stamps=``); ``pink-noise`` 1/f force noise of the same standard deviation
(``noise_color="pink"``); ``vertical`` a vertical rig, the weight in the
force balance (``orientation="vertical-up"`` for odd seeds,
``"vertical-down"`` for even ones; not for ``inertia-error`` rows whose force
comes from a balance: a wrong mass there is also a constant weight error
``dm*g*s`` that the catalogue's ``inertia-error`` does not carry, so the
right answer would be another row's); ``pulsation`` a periodic force
disturbance at :data:`PULSATION_HZ` (drawn per seed) of
:data:`PULSATION_NOISE_RATIO` times the record's force-noise standard
deviation (``pulsation=``); ``soft-presliding`` a presliding-dominated motion
(``motion="presliding"``) on a soft seal (``bristle=`` the scale's
``sigma0`` times :data:`SOFT_BRISTLE`, 1-2.5e4 N/m on the pneumatic rig). The
last is sensible only where the answer's model can show presliding, and the
hidden effect still acts in small loops (:data:`SOFT_PRESLIDING_ROWS`): with
the dynamic (LuGre) baseline, nothing hidden, a force offset, a mass error
or a direction asymmetry; with a static baseline only the rows that hide
presliding itself (which must then be found). Effects that act only through
the sliding level (dwell, lag, pressure, position, the Stribeck hump) are
barely exercised by a few slides, and Maxwell-slip elements on a soft seal
stay elastic in loops of a tenth of their break displacement, where they
cannot be told from a bristle: those rows are left out.

Judging a condition: for ``pulsation`` a right answer also lists the
pulsation in ``disturbances`` (a line within :data:`PULSATION_TOLERANCE_HZ` of
its frequency) and then has the verdict ``unexplained-structure`` (a record
with a disturbance in it is not explained), the added set judged as for the
row; in every other case a non-empty ``disturbances`` is wrong (a false
disturbance).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from fcomp.synthetic import OUTSIDE, SHAPES, STYLES, generate
from fcomp.synthetic import SCALES as SCALE_PRESETS

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
    default: bool = True  # in the default selection of :func:`cases`

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
    # two effects hidden with the dynamic baseline too (not in the default selection)
    Row("dwell-time+direction-asymmetry", ("dwell-time", "direction-asymmetry"), KINDS,
        ("coulomb-viscous", "coulomb-viscous"), default=False),
    Row("pressure-dependence+dwell-time", ("pressure-dependence", "dwell-time"), KINDS,
        ("coulomb-viscous", "coulomb-viscous"), needs=("p1", "p2"), default=False),
)
#: The rows :func:`cases` takes when none are named (the matrix before conditions).
DEFAULT_ROWS = tuple(r.name for r in ROWS if r.default)

#: The conditions (see the module docstring); ``plain`` is the original record.
CONDITIONS = ("plain", "irregular-stamps", "gapped-stamps", "pink-noise", "vertical",
              "pulsation", "soft-presliding")
#: Frequency range (Hz) of the pulsation, drawn uniformly per seed.
PULSATION_HZ = (23.0, 47.0)
#: Pulsation amplitude over the record's force-noise standard deviation, drawn per seed.
PULSATION_NOISE_RATIO = (1.6, 2.4)
#: Largest distance (Hz) of a reported disturbance from the pulsation it finds.
PULSATION_TOLERANCE_HZ = 0.1
#: The soft seal's bristle stiffness over the scale's nominal ``sigma0``, drawn log-uniformly
#: per seed (pneumatic: 1.0e4-2.5e4 N/m, a presliding range of 1.2-3 mm).
SOFT_BRISTLE = (0.05, 0.125)
#: Rows (and their kinds) the ``soft-presliding`` condition applies to.
SOFT_PRESLIDING_ROWS: dict[str, tuple[str, ...]] = {
    "nothing": ("dynamic",),
    "force-offset": ("dynamic",),
    "inertia-error": ("dynamic",),
    "direction-asymmetry": ("dynamic",),
    "presliding": ("static",),
    "presliding+direction-asymmetry": ("static",),
}

CASE_FIELDS = ("row", "kind", "style", "scale", "seed", "shape", "baseline", "base",
               "condition")


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
    condition: str = "plain"

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    @property
    def spec(self) -> Row:
        return next(r for r in ROWS if r.name == self.row)


def _style_signals(style: str) -> set[str]:
    """Signals a style records (from the generator's style registry)."""
    return set(STYLES[style].columns)


def condition_applies(condition: str, row: Row, kind: str, style: str) -> bool:
    """Whether ``condition`` is sensible for a case of ``row``, ``kind`` and ``style``
    (module docstring)."""
    if condition == "vertical":
        return not ("inertia-error" in row.hidden and STYLES[style].force != "load-cell")
    if condition == "soft-presliding":
        return kind in SOFT_PRESLIDING_ROWS.get(row.name, ())
    return True


def cases(*, seeds: Iterable[int] = (1, 2, 3), rows: Sequence[str] | None = None,
          styles: Sequence[str] | None = None, scales: Sequence[str] | None = None,
          kinds: Sequence[str] | None = None, duration: float = 40.0,
          rate: float = 1000.0, conditions: Sequence[str] | None = None) -> list[Case]:
    """Every case of the matrix (or of the named subsets).

    ``rows`` defaults to :data:`DEFAULT_ROWS` (``"all"`` among them: every row of
    :data:`ROWS`); ``conditions`` to ``("plain",)``, the original records. A
    condition is crossed with the cases it applies to (:func:`condition_applies`).
    """
    out = []
    style_list = list(styles or MATRIX_STYLES)
    scale_list = list(scales or SCALES)
    seed_list = list(seeds)
    cond_list = list(conditions or ("plain",))
    unknown = set(cond_list) - set(CONDITIONS)
    if unknown:
        raise ValueError(f"unknown condition(s) {', '.join(sorted(unknown))}; known: "
                         f"{', '.join(CONDITIONS)}")
    if not rows:
        row_names = set(DEFAULT_ROWS)
    elif "all" in rows:
        row_names = {r.name for r in ROWS}
    else:
        row_names = set(rows)
    for row in ROWS:
        if row.name not in row_names:
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
                        for cond in cond_list:
                            if not condition_applies(cond, row, kind, style):
                                continue
                            out.append(Case(row.name, kind, style, scale, int(seed),
                                            ",".join(shapes), baseline, base, duration, rate,
                                            cond))
    return out


def _shape_of(effect: str, k: int) -> tuple[str, str]:
    names = SHAPES[effect]
    return effect, names[k % len(names)]


def pulsation_of(case: Case) -> tuple[float, float]:
    """``(frequency Hz, amplitude / force-noise std)`` of a ``pulsation`` case's disturbance
    (drawn from the seed alone: the same for every row, style and scale)."""
    rng = np.random.default_rng([case.seed, 23])
    return float(rng.uniform(*PULSATION_HZ)), float(rng.uniform(*PULSATION_NOISE_RATIO))


def soft_bristle(case: Case) -> float:
    """The soft seal's bristle stiffness (N/m) of a ``soft-presliding`` case."""
    rng = np.random.default_rng([case.seed, 29])
    lo, hi = SOFT_BRISTLE
    ratio = float(np.exp(rng.uniform(math.log(lo), math.log(hi))))
    return SCALE_PRESETS[case.scale].params.sigma0 * ratio


def condition_args(case: Case, noise_std: float | None = None) -> dict[str, Any]:
    """The generator arguments (:func:`fcomp.synthetic.generate`) of ``case``'s condition.

    ``pulsation`` needs the record's force-noise standard deviation ``noise_std``
    (the truth of the same record without it: the pulsation has its own random
    stream, so the rest of the record is the same).
    """
    c = case.condition
    if c == "plain":
        return {}
    if c in ("irregular-stamps", "gapped-stamps"):
        return {"stamps": c.split("-")[0]}
    if c == "pink-noise":
        return {"noise_color": "pink"}
    if c == "vertical":
        return {"orientation": "vertical-up" if case.seed % 2 else "vertical-down"}
    if c == "pulsation":
        if noise_std is None:
            raise ValueError("the pulsation condition needs the record's noise_std")
        freq, ratio = pulsation_of(case)
        return {"pulsation": (freq, ratio * noise_std)}
    if c == "soft-presliding":
        return {"motion": "presliding", "bristle": soft_bristle(case)}
    raise ValueError(f"unknown condition {c!r}; known: {', '.join(CONDITIONS)}")


def record(case: Case):
    """The synthetic record of ``case`` (its condition mapped by :func:`condition_args`)."""
    hidden = [s for s in case.shape.split(",") if s]
    common: dict[str, Any] = dict(base=case.base, scale=case.scale, style=case.style,
                                  duration=case.duration, rate=case.rate, seed=case.seed,
                                  vary=True, name=f"case-{case.seed}")
    noise_std = None
    if case.condition == "pulsation":
        noise_std = generate(hidden, **common).truth.noise_std
    return generate(hidden, **common, **condition_args(case, noise_std))


def _named(effect: str, added: Sequence[str], ties: Sequence[Sequence[str]]) -> bool:
    if effect in added:
        return True
    return any(effect in t and set(t) & set(added) for t in ties)


def _falls(rb: float | None, rf: float | None, noise_std: float) -> bool:
    """Whether a held-out error falls to :data:`MAX_ERROR_RATIO` of the baseline's, in RMS or
    in its excess over the record's true noise."""
    if rb is None or rf is None or not (math.isfinite(rb) and math.isfinite(rf)):
        return False
    eb = math.sqrt(max(rb * rb - noise_std**2, 0.0))
    ef = math.sqrt(max(rf * rf - noise_std**2, 0.0))
    return rf <= MAX_ERROR_RATIO * rb or ef <= MAX_ERROR_RATIO * eb


def judge(case: Case, doc: Mapping[str, Any], noise_std: float = 0.0) -> tuple[bool, str]:
    """``(right, why)`` of one diagnosis JSON (``fcomp diagnose --json``) for ``case``.

    ``noise_std`` is the record's true force noise (the generator's truth): the
    held-out error that can fall is the excess over it, ``sqrt(rms^2 - noise^2)``,
    and the fall is judged on that excess (an effect that acts only at
    break-aways cannot take 40 % off an RMS the noise dominates). The errors are
    the deciding (scored) ones, or the plain ``y - F_hat`` ones of ``rms_plain``:
    the scored error of the right model keeps what it scores within the timing
    windows of events, which no effect removes.

    Disturbances (``disturbances``, each with ``frequency_hz``): a ``pulsation`` case
    needs its pulsation among them (within :data:`PULSATION_TOLERANCE_HZ`) and the
    verdict ``unexplained-structure``; any other case must report none.
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
    lines = [d for d in doc.get("disturbances") or [] if isinstance(d, Mapping)]
    freqs = [float(d.get("frequency_hz", math.nan)) for d in lines]
    if case.condition == "pulsation":
        f0 = pulsation_of(case)[0]
        if not any(abs(f - f0) <= PULSATION_TOLERANCE_HZ for f in freqs):
            found = ", ".join(f"{f:.2f}" for f in freqs) or "none"
            problems.append(f"pulsation at {f0:.2f} Hz not found (disturbances: {found} Hz)")
        want = "unexplained-structure"
    elif freqs or doc.get("disturbances"):
        problems.append("false disturbance at " + (", ".join(f"{f:.2f}" for f in freqs)
                                                   or "?") + " Hz")
    if verdict != want:
        problems.append(f"verdict {verdict} (want {want}: {doc.get('reason', '')})")
    if expected:
        rb, rf = doc.get("rms_baseline"), doc.get("rms_final")
        plain = doc.get("rms_plain") or {}
        if rb is None or rf is None or not (math.isfinite(rb) and math.isfinite(rf)):
            problems.append("no held-out error")
        elif not (_falls(rb, rf, noise_std)
                  or _falls(plain.get("baseline"), plain.get("final"), noise_std)):
            eb = math.sqrt(max(rb * rb - noise_std**2, 0.0))
            ef = math.sqrt(max(rf * rf - noise_std**2, 0.0))
            problems.append(f"held-out error {rb:.3g} -> {rf:.3g} N, excess over the noise "
                            f"{eb:.3g} -> {ef:.3g} N (> {MAX_ERROR_RATIO} x)")
    return (not problems), ("; ".join(problems) if problems else
                            f"{'+'.join(added) or 'nothing'} / {verdict}")
