"""Candidate truths: the frictions a plant may really have, when nobody knows which.

``fcomp compensate`` builds every compensator on each of several friction
models (a baseline fit, a diagnosed model) and runs them on a plant. Which
friction the *plant* runs decides the answer: run on the diagnosed model, the
compensators built on the diagnosed model are exact and win by construction --
a comparison that proves nothing. When the true friction is not known, the
honest question is what each model buys under *every* friction the evidence
leaves plausible, and a recommendation is one that holds across them.

:func:`candidate_truths` builds that set from what the compared models carry:

* **the compared models themselves** (the baseline is as plausible a truth
  as the diagnosed model until a record says otherwise);
* **draws from each model's own uncertainty**: a model file's ``stderr``
  (:mod:`fcomp.modelfile`; ``fcomp fit`` and ``fcomp diagnose`` write it),
  each fitted parameter drawn from ``N(value, stderr^2)`` truncated to its
  bounds and to the model's constraints (``Fc <= Fs``; a draw that breaks one
  is drawn again). The files carry no covariance, so the draws are
  independent: a pair of parameters that trade off (``Fc`` against ``Fs``)
  is drawn wider than the record allows, never narrower;
* **rivals**: the models a diagnosis found nearly as good (the tied effects
  of a step, the other baseline's answer), which ``fcomp diagnose`` writes
  into its model file (``source.diagnosis.rivals``);
* **truths the user names** (``--truths``).

A truth equal to one of the compared models (:func:`same_friction`) is
marked as such (:attr:`Truth.equals`): against it, that model is exact.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fcomp.errors import FcompError
from fcomp.models import FrictionModel

#: Rivals taken from one model file (the best ones, in the diagnosis's order).
MAX_RIVALS = 2
#: Tries for one valid uncertainty draw before giving up on that model.
TRIES = 1000


@dataclass(frozen=True)
class Compared:
    """A compared model (a controller friction) and what its file says about it.

    Attributes
    ----------
    model
        The seal's friction (measurement terms dropped).
    stderr
        Standard errors by flat name (a model file's ``stderr``; empty: none).
    rivals
        ``(name, model, why)`` of the rival models its diagnosis wrote.
    source
        Where it comes from, in words (a file, a name).
    """

    model: FrictionModel
    stderr: Mapping[str, float] = field(default_factory=dict)
    rivals: tuple[tuple[str, FrictionModel, str], ...] = ()
    source: str = ""


@dataclass(frozen=True)
class Truth:
    """One candidate truth: the friction a plant runs.

    Attributes
    ----------
    label
        Its name in the results (a compared model's label, ``LABEL~2`` for the second
        draw of ``LABEL``'s uncertainty, ``LABEL:rival1``, a given file's stem).
    model
        The friction.
    origin
        ``given``, ``compared``, ``uncertainty``, ``rival`` or ``named``.
    note
        What it is, in words.
    equals
        The label of the compared model it equals (``None``: none).
    """

    label: str
    model: FrictionModel
    origin: str
    note: str
    equals: str | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON form (the friction's description and values)."""
        return {"description": self.model.describe(), "origin": self.origin,
                "note": self.note, "equals": self.equals,
                "params": {k: (v if math.isfinite(v) else str(v))
                           for k, v in self.model.flat_params().items()}}


def same_friction(a: FrictionModel, b: FrictionModel, rel: float = 1e-9) -> bool:
    """Whether two models are the same friction: the same structure (model, effects and
    their configuration) and the same values to ``rel``."""
    if a.describe() != b.describe():
        return False
    if [dict(e.config) for e in a.effects] != [dict(e.config) for e in b.effects]:
        return False
    fa, fb = a.flat_params(), b.flat_params()
    if set(fa) != set(fb):
        return False
    return all(fa[k] == fb[k] or (math.isfinite(fa[k]) and math.isfinite(fb[k])
                                  and abs(fa[k] - fb[k]) <= rel * max(abs(fa[k]), abs(fb[k])))
               for k in fa)


def varied_names(model: FrictionModel) -> list[str]:
    """The parameters a draw may vary: the finite, non-zero ones a fit estimates (not the
    numerical thresholds, reference values and effects' fixed values,
    :func:`fcomp.diagnosis.refit.fixed_names`)."""
    from fcomp.diagnosis.refit import fixed_names

    fixed = fixed_names(model)
    return [k for k, v in model.flat_params().items()
            if k not in fixed and math.isfinite(v) and v != 0.0]


def _truncated(rng: np.random.Generator, mean: float, sd: float, spec: Any) -> float | None:
    """A draw of ``N(mean, sd^2)`` within ``spec``'s bounds (drawn again while outside;
    ``None`` if :data:`TRIES` draws all fall outside)."""
    for _ in range(TRIES):
        v = mean + sd * float(rng.standard_normal())
        if spec.lower <= v <= spec.upper and not (spec.lower_open and v <= spec.lower):
            return v
    return None


def uncertainty_draws(model: FrictionModel, stderr: Mapping[str, float], n: int,
                      rng: np.random.Generator) -> list[FrictionModel]:
    """``n`` draws of ``model`` from its standard errors (module docstring): each varied
    parameter with a positive finite standard error from ``N(value, stderr^2)`` truncated to
    its bounds (drawn again while outside), the whole draw again while the model refuses it
    (``Fc > Fs``). Empty without standard errors.

    Raises
    ------
    FcompError
        No valid draw in :data:`TRIES` tries.
    """
    specs = model.param_specs()
    flat = model.flat_params()
    names = [k for k in varied_names(model)
             if k in stderr and math.isfinite(stderr[k]) and stderr[k] > 0]
    if not names or n <= 0:
        return []
    out: list[FrictionModel] = []
    for _ in range(n):
        for _try in range(TRIES):
            values = {k: _truncated(rng, flat[k], stderr[k], specs[k]) for k in names}
            if any(v is None for v in values.values()):
                break
            try:
                out.append(model.with_params(**values))  # type: ignore[arg-type]
            except (ValueError, FcompError):
                continue
            break
        if len(out) < _ + 1:
            raise FcompError(f"no valid draw of {model.describe()} from its standard errors "
                             f"in {TRIES} tries (its values sit at a bound, or its errors "
                             "are far larger than its values)")
    return out


def rivals_of(document: Mapping[str, Any], effects: str | None = None
              ) -> tuple[tuple[str, FrictionModel, str], ...]:
    """The rival models a diagnosis wrote into its model file (``source.diagnosis.rivals``:
    ``[{"model_file": {...}, "why": "..."}]``), the first :data:`MAX_RIVALS`, each as
    ``(description, friction, why)`` (measurement terms dropped)."""
    from fcomp.errors import FileFormatError
    from fcomp.modelfile import read_model

    diag = ((document.get("source") or {}).get("diagnosis") or {})
    out = []
    for entry in (diag.get("rivals") or [])[:MAX_RIVALS]:
        if not isinstance(entry, Mapping) or not isinstance(entry.get("model_file"), Mapping):
            continue
        try:
            mf = read_model(entry["model_file"], effects)
        except FileFormatError:
            continue
        out.append((mf.model.describe(), mf.model, str(entry.get("why", "a rival"))))
    return tuple(out)


def candidate_truths(compared: Mapping[str, Compared], draws: int, seed: int,
                     named: Mapping[str, FrictionModel] | None = None,
                     not_drawn: list[str] | None = None) -> list[Truth]:
    """The candidate truths (module docstring), in order: each compared model, its
    uncertainty draws and rivals, then the ``named`` ones; a candidate equal to an earlier
    one is left out.

    Parameters
    ----------
    compared
        Label -> :class:`Compared`, the first the baseline.
    draws
        Uncertainty draws per compared model that carries standard errors.
    seed
        Seed of the draws.
    named
        Label -> friction: truths the user names.
    not_drawn
        Appended to: why a model's uncertainty could not be drawn (its draws are left out).
    """
    rng = np.random.default_rng(seed)
    out: list[Truth] = []
    skipped = not_drawn if not_drawn is not None else []

    def add(truth: Truth) -> None:
        if any(same_friction(truth.model, t.model) for t in out):
            return
        eq = next((k for k, c in compared.items() if same_friction(truth.model, c.model)),
                  None)
        out.append(Truth(truth.label, truth.model, truth.origin, truth.note, eq))

    for label, c in compared.items():
        add(Truth(label, c.model, "compared", f"the compared model {label} ({c.source})"))
    for label, c in compared.items():
        try:
            drawn = uncertainty_draws(c.model, c.stderr, draws, rng)
        except FcompError as exc:  # said, and the comparison goes on without them
            skipped.append(f"{label}: {exc}")
            drawn = []
        for i, m in enumerate(drawn, start=1):
            add(Truth(f"{label}~{i}", m, "uncertainty",
                      f"draw {i} of {label}'s values from its standard errors"))
        for i, (name, m, why) in enumerate(c.rivals, start=1):
            add(Truth(f"{label}:rival{i}", m, "rival", f"{name}, a rival of {label}: {why}"))
    for label, m in (named or {}).items():
        add(Truth(label, m, "named", f"{m.describe()}, named as a candidate truth"))
    return out


def circular(truths: Sequence[Truth]) -> list[Truth]:
    """The truths that are one of the compared models."""
    return [t for t in truths if t.equals is not None]


__all__ = ["MAX_RIVALS", "Compared", "Truth", "candidate_truths", "circular", "rivals_of",
           "same_friction", "uncertainty_draws", "varied_names"]
