"""An effect is one class in one place: the diagnosis asks every effect through its hooks.

The diagnosis hooks of :class:`fcomp.effects.Effect` (``needs``, ``dynamic``,
``diagnosis_config``, ``diagnosis_forms``, ``unsuitable``, ``guess``, ``held``)
are all the diagnosis knows of an effect: a user's effect that declares them
gets them called, every catalogue effect's hooks run on a record, and the
diagnosis modules name no effect.
"""

from __future__ import annotations

import ast
import math
import uuid
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pytest

import fcomp.diagnosis.catalogue as catalogue
from fcomp.backend import Backend
from fcomp.conditioning import Scales
from fcomp.diagnosis import Diagnosis
from fcomp.effects import CATALOGUE, EFFECTS, Effect, register_effect
from fcomp.effects.record import DiagnosisForm, RecordView
from fcomp.errors import FcompError
from fcomp.models import make_model
from fcomp.models.base import Signals
from fcomp.parameters import ParamValues, make_params_class, spec
from fcomp.synthetic import generate

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def record():
    return generate([], duration=9.0, seed=11).measurement


@pytest.fixture(scope="module")
def fitted(record):
    return Diagnosis("lugre", search=False, n_jobs=1, check_baseline=False).fit(record)


def _user_effect(name: str, reason: str | None = None) -> type[Effect]:
    """A level scale with every diagnosis hook of its own."""

    class Hooked(Effect):
        """Test effect: all levels times ``1 + k + j``."""

        Params = make_params_class("HookedParams", [
            spec("k", "-", 0.0, -0.5, 1.0, "gain"),
            spec("j", "-", 0.0, -0.5, 1.0, "second gain (held by the 'plain' form)"),
            spec("q", "-", 0.0, -0.5, 1.0, "third gain (held by the record)"),
        ], owner=f"effect {name}")
        signature = "levels off by a constant factor"
        experiment = "none"
        needs = ("x",)
        calls: ClassVar[list[tuple[str, Any]]] = []

        def modify_levels(self, be: Backend, L: dict, w: list, sig: Signals,
                          P: ParamValues) -> dict:
            return {n: v * (1.0 + P("k") + P("j") + P("q")) for n, v in L.items()}

        @classmethod
        def diagnosis_config(cls, scales: Scales) -> dict[str, Any]:
            return {"speed": scales.speed}

        @classmethod
        def diagnosis_forms(cls) -> tuple[DiagnosisForm, ...]:
            return (DiagnosisForm("plain", held=("j",)), DiagnosisForm("both"))

        def unsuitable(self, view: RecordView) -> str | None:
            type(self).calls.append(("unsuitable", view))
            return reason

        def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
            type(self).calls.append(("guess", (form, dict(self.config))))
            return [{"k": 0.123, "j": 0.01 if form == "both" else 0.0}]

        def held(self, view: RecordView) -> list[str]:
            type(self).calls.append(("held", view))
            return ["q"]

    Hooked.name = name
    Hooked.calls = []
    return Hooked


def test_a_user_effects_hooks_make_its_proposals(fitted) -> None:
    name = f"test-hooked-{uuid.uuid4().hex[:8]}"
    cls = register_effect(_user_effect(name))
    ctx = fitted._search.context()
    assert catalogue.applicability(name, ctx) is None
    props = catalogue.propose_all(name, ctx)
    assert [p.form for p in props] == ["plain", "both"]
    speed = fitted.data_.scales.speed
    guessed = [c for c in cls.calls if c[0] == "guess"]  # type: ignore[attr-defined]
    assert guessed == [("guess", ("plain", {"speed": speed})),
                       ("guess", ("both", {"speed": speed}))]
    plain, both = props
    assert plain.model.effects[-1].config == {"speed": speed}
    assert plain.starts[0]["k"] == pytest.approx(0.123)
    assert both.starts[0]["j"] == pytest.approx(0.01)
    # the record holds q (its hook), the plain form holds j too: neither is refitted
    assert plain.free is not None and "k" in plain.free
    assert "q" not in plain.free and "j" not in plain.free
    assert both.free is not None and "j" in both.free and "q" not in both.free
    assert all(s["q"] == 0.0 and s["j"] == 0.0 for s in plain.starts)
    views = [c[1] for c in cls.calls if c[0] in ("unsuitable", "held")]  # type: ignore[attr-defined]
    assert views and all(isinstance(v, RecordView) for v in views)
    v = views[0]
    # the hooks read the tolerant residual: where structure is, not the scored error
    assert fitted.fit_.tolerant is not None
    np.testing.assert_array_equal(v.residual, fitted.fit_.tolerant)
    assert v.train is fitted.split_.train and v.scales is fitted.data_.scales


def test_a_user_effects_reasons_reach_the_diagnosis(record) -> None:
    name = f"test-unsuited-{uuid.uuid4().hex[:8]}"
    register_effect(_user_effect(name, reason="the test record cannot show it"))
    d = Diagnosis("lugre", candidates=[name], n_jobs=1, check_baseline=False).fit(record)
    assert d.skipped_[name] == "the test record cannot show it"
    with pytest.raises(FcompError, match="the test record cannot show it"):
        d.add_effect(name)


def test_a_user_effects_needs_and_dynamic_are_judged(fitted) -> None:
    import dataclasses

    name = f"test-needy-{uuid.uuid4().hex[:8]}"
    cls = register_effect(_user_effect(name))
    no_x = dataclasses.replace(fitted.data_, available={**fitted.data_.available, "x": False},
                               reasons={**fitted.data_.reasons, "x": "not measured"})
    ctx = catalogue.Context(no_x, fitted.segmentation_, fitted.split_.train, fitted.fit_)
    assert catalogue.applicability(name, ctx) == "needs x: not measured"
    cls.dynamic = True
    steady = dataclasses.replace(fitted.data_, steady_state=True)
    ctx = catalogue.Context(steady, fitted.segmentation_, fitted.split_.train, fitted.fit_)
    assert catalogue.applicability(name, ctx) == \
        "needs a motion (the data are steady-state points)"


@pytest.mark.parametrize("baseline", ["lugre", "coulomb"])
def test_every_catalogue_effects_hooks_run_on_a_record(record, baseline) -> None:
    d = Diagnosis(baseline, search=False, n_jobs=1, check_baseline=False).fit(record)
    ctx = d._search.context()
    view = ctx.view
    for cls in CATALOGUE:
        config = cls.diagnosis_config(view.scales)
        assert isinstance(config, dict)
        forms = cls.diagnosis_forms()
        assert forms and all(isinstance(f, DiagnosisForm) for f in forms)
        own = set(cls.Params().flat())
        for form in forms:
            effect = cls(None, **{**config, **form.config})
            reason = effect.unsuitable(view)
            assert reason is None or isinstance(reason, str)
            assert set(effect.held(view)) <= own
            assert set(form.held) <= own
            starts = effect.guess(view, form.name)
            assert starts and all(isinstance(s, dict) for s in starts)
            for s in starts:
                assert all(isinstance(v, float) and math.isfinite(v) for v in s.values()), \
                    (cls.name, s)
        if catalogue.applicability(cls.name, ctx) is None:
            for prop in catalogue.propose_all(cls.name, ctx):
                assert prop.effect == cls.name
                assert not cls().applies_to(prop.model)  # the effect is part of it now
                assert prop.starts


#: What every catalogue effect declares: the signals it reads besides v, and whether it
#: needs a motion (memory or acceleration).
DECLARED = {
    "viscous": ((), False),
    "stribeck": ((), False),
    "presliding": ((), True),
    "frictional-lag": ((), True),
    "dwell-time": ((), True),
    "direction-asymmetry": ((), False),
    "pressure-dependence": (("p1", "p2"), False),
    "position-dependence": (("x",), False),
    "viscous-lead": (("a",), True),
    "inertia-error": (("a",), True),
    "force-offset": ((), False),
    "area-error": (("p1", "p2"), False),
    "nonlocal-memory": ((), True),
}


def test_every_catalogue_effect_declares_needs_and_dynamic() -> None:
    assert {cls.name for cls in CATALOGUE} == set(DECLARED)
    for cls in CATALOGUE:
        assert (cls.needs, cls.dynamic) == DECLARED[cls.name], cls.name
        assert EFFECTS.get(cls.name) is cls
        if cls.states:
            assert cls.dynamic, cls.name


def test_an_effect_is_one_module_and_structure_reaches_models_one_way(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Every catalogue effect lives in a module of its own, and a structural one hands
    the LuGre family its term (``with_structure``): no effect module builds a model class
    or sets a model's lineage."""
    from fcomp.effects.structural import StructuralEffect
    from fcomp.models.lugre_family import LuGreFamily, Structure

    modules = [cls.__module__ for cls in CATALOGUE]
    assert len(set(modules)) == len(modules)
    for cls in CATALOGUE:
        text = Path(__import__(cls.__module__, fromlist=["_"]).__file__).read_text()
        for internal in ("_with_features", "with_hysteresis", "family_class",
                         "hysteresis_class", ".lineage"):
            assert internal not in text, (cls.name, internal)
    calls: list[Structure] = []
    original = LuGreFamily.with_structure

    def spy(self: LuGreFamily, term: Structure) -> LuGreFamily:
        calls.append(term)
        return original(self, term)

    monkeypatch.setattr(LuGreFamily, "with_structure", spy)
    model = make_model("coulomb").with_effects(
        "viscous", EFFECTS.get("presliding")({"sigma0": 1e5}), "stribeck",
        "frictional-lag", "viscous-lead", "nonlocal-memory")
    assert [t.effect for t in calls] == ["viscous", "presliding", "stribeck",
                                         "frictional-lag", "viscous-lead", "nonlocal-memory"]
    assert all(issubclass(EFFECTS.get(t.effect), StructuralEffect) for t in calls)
    assert model.describe() == ("coulomb + viscous + presliding + stribeck + frictional-lag"
                                " + viscous-lead + nonlocal-memory")


def _named_effects(text: str, names: set[str]) -> list[tuple[int, str]]:
    """``(line, name)`` of every string of ``text`` (a Python module) that is one of
    ``names`` -- a literal, a piece of an f-string, or a quoted word in a docstring."""
    found = [(node.lineno, node.value) for node in ast.walk(ast.parse(text))
             if isinstance(node, ast.Constant) and node.value in names]
    for i, line in enumerate(text.splitlines(), 1):
        found += [(i, n) for n in names if f'"{n}"' in line or f"'{n}'" in line]
    return sorted(set(found))


def test_the_diagnosis_names_no_effect() -> None:
    """Effect-specific logic lives on the effects (their modules and attributes), not in
    the diagnosis: no module of ``fcomp/diagnosis/`` names a registered effect (``stribeck``
    is also a model, the static baseline, and may be named as that outside the
    catalogue's view)."""
    from fcomp.models import MODELS

    sources = sorted((ROOT / "fcomp" / "diagnosis").glob("*.py"))
    assert len(sources) >= 12
    named = []
    for path in sources:
        names = set(EFFECTS.names())
        if path.name != "catalogue.py":
            names -= set(MODELS.names())
        named += [f"{path.name}:{line}: {name}"
                  for line, name in _named_effects(path.read_text(), names)]
    assert not named, named
