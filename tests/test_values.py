"""Models, effects and parameters are plain values: they pickle, also across processes.

For every registered model, with every catalogue effect that applies to it
(each alone with non-trivial values, and all add-on effects together), the
force along a motion is the same after ``pickle.loads(pickle.dumps(model))``;
classes made on the fly for a feature combination pickle by their recipe,
and a fresh interpreter (the ``spawn`` start method) rebuilds the same model.
"""

from __future__ import annotations

import multiprocessing
import pickle

import numpy as np
import pytest

from fcomp.effects import CATALOGUE, EFFECTS, make_effect
from fcomp.effects.structural import StructuralEffect
from fcomp.models import MODELS, FrictionModel, make_model
from fcomp.models.gms import gms_class
from fcomp.models.lugre_family import family_class, params_class
from fcomp.parameters import Directional
from fcomp.trajectory import friction_along_motion

T = np.linspace(0.0, 1.0, 401)
V = 0.02 * np.sin(2 * np.pi * 2 * T) + 0.004 * np.sin(2 * np.pi * 13 * T)
SIG = {"x": 0.1 + 0.01 * np.sin(2 * np.pi * 2 * T), "p1": 2e5 + 1e5 * np.sin(T),
       "p2": 5e4 * np.cos(T)}

#: Effect values that change the force (the defaults are no-ops).
VALUES: dict[str, dict[str, float]] = {
    "viscous": {"sigma2": 30.0, "p_visc": 0.8},
    "stribeck": {"Fs_excess": 0.6, "vs": 0.005, "kappa_s": 0.3},
    "presliding": {"sigma0": 5e4, "sigma1": 50.0, "i_pre": 1.5},
    "frictional-lag": {"vb": 0.02},
    "dwell-time": {"dFs": 0.5, "tau_dwell": 0.2},
    "direction-asymmetry": {"r_neg": 1.2, "rv_neg": 1.4},
    "pressure-dependence": {"kp": 1e-6, "kd": -4e-7, "kq": 1e-13, "p_ref": 2e5, "d_ref": 1e5},
    "position-dependence": {"kx1": 0.1, "kb": 0.3, "xb": 0.1},
    "viscous-lead": {"T": 0.01},
    "inertia-error": {"dm": 0.3},
    "force-offset": {"offset": 0.2},
    "area-error": {"dA1": 5e-6, "dA2": -3e-6},
    "nonlocal-memory": {"c1": 0.2, "k1": 3e5, "z1": 5e-5, "z3": 6e-5, "z5": 8e-5, "z2": 3e-5,
                        "z4": 7e-5},
}


def _force(model: FrictionModel) -> np.ndarray:
    return friction_along_motion(model, T, V, **SIG).F


def _roundtrip(model: FrictionModel) -> FrictionModel:
    return pickle.loads(pickle.dumps(model))


def _with(model: FrictionModel, effect: str, **config: object) -> FrictionModel | None:
    """``model`` with ``effect`` (non-trivial values), or None where it cannot be added."""
    eff = make_effect(effect, VALUES[effect], **config)
    if not eff.applies_to(model):
        return None
    missing = getattr(eff, "requires", frozenset()) - getattr(model, "features", frozenset())
    if missing:
        return None
    return model.with_effects(eff)


#: Every model alone and with every effect that applies to it.
CASES = [(name, effect) for name in MODELS.names() for effect in [None, *EFFECTS.names()]
         if effect is None or _with(make_model(name), effect) is not None]


@pytest.mark.parametrize(("name", "effect"), CASES)
def test_model_with_effect_pickles_to_equal_forces(name: str, effect: str | None) -> None:
    model = make_model(name)
    if effect is not None:
        model = _with(model, effect)
    back = _roundtrip(model)
    assert type(back) is type(model)
    assert back.describe() == model.describe()
    assert back.flat_params() == model.flat_params()
    np.testing.assert_array_equal(_force(back), _force(model))


#: Effects in their other forms (the diagnosis fits these): lugre with each.
FORM_CASES = [("frictional-lag", {"form": "speed-lag"}, {"tau_L": 0.05, "w_L": 0.8}),
              ("nonlocal-memory", {"form": "maxwell-slip"},
               {"ms_share": 0.8, "ms_dmax": 2e-4, "ms_spread": 20.0, "ms_scaling": 0.5})]


@pytest.mark.parametrize(("effect", "config", "values"), FORM_CASES,
                         ids=[c[0] for c in FORM_CASES])
def test_effect_forms_pickle_to_equal_forces(effect: str, config: dict, values: dict) -> None:
    model = make_model("lugre").with_effects(make_effect(effect, values, **config))
    back = _roundtrip(model)
    assert back.describe() == model.describe() and back.state_names == model.state_names
    np.testing.assert_array_equal(_force(back), _force(model))
    assert np.abs(_force(model) - _force(make_model("lugre"))).max() > 1e-3


@pytest.mark.parametrize("name", MODELS.names())
def test_every_add_on_effect_at_once(name: str) -> None:
    model = make_model(name)
    for cls in CATALOGUE:
        if not issubclass(cls, StructuralEffect):
            model = _with(model, cls.name) or model
    assert len(model.effects) >= 6
    back = _roundtrip(model)
    assert [type(e) for e in back.effects] == [type(e) for e in model.effects]
    np.testing.assert_array_equal(_force(back), _force(model))


def test_classes_made_on_the_fly_pickle_by_recipe() -> None:
    made = [
        make_model("coulomb").with_effects(make_effect("presliding", {"sigma0": 1e5}),
                                           make_effect("stribeck", VALUES["stribeck"])),
        _with(make_model("lugre"), "nonlocal-memory", form="maxwell-slip"),
        _with(make_model("dahl"), "nonlocal-memory"),  # hysteresis on a custom feature set
        gms_class(2)({"k1": 5e4, "k2": 5e4, "alpha1": 0.25, "alpha2": 0.75}),
        make_model("lugre", params={"Fc_pos": 1.0, "Fc_neg": 1.3}),
    ]
    for model in made:
        assert model is not None
        back = _roundtrip(model)
        assert type(back) is type(model) and back.params == model.params
        np.testing.assert_array_equal(_force(back), _force(model))
    cls = family_class(frozenset({"presliding", "elements", "viscous"}))
    assert pickle.loads(pickle.dumps(cls())).params == cls().params
    P = params_class(frozenset({"stribeck", "viscous"}))
    p = P(Fc=Directional(1.0, 1.2))
    assert pickle.loads(pickle.dumps(p)) == p


def test_parameter_classes_are_importable_and_typed() -> None:
    import sys

    from fcomp.models import lugre_family

    assert lugre_family.LuGreParams is make_model("lugre").Params
    assert lugre_family.LuGreParams.__module__ == "fcomp.models.lugre_family"
    for cls in CATALOGUE:  # each in the effect's own module, beside its class
        assert cls.Params.__module__ == cls.__module__
        assert getattr(sys.modules[cls.__module__], cls.Params.__qualname__) is cls.Params
    fields = lugre_family.LuGreParams.__dataclass_fields__
    assert fields["Fc"].type == float | Directional   # direction-capable
    assert fields["sigma0"].type is float              # not direction-capable


def test_a_fresh_interpreter_rebuilds_the_model() -> None:
    """The ``spawn`` start method (macOS, Windows): the child imports fcomp afresh."""
    models = [make_model("nmlgm", effects=["dwell-time"]).with_params(dFs=0.4),
              _with(make_model("lugre"), "nonlocal-memory", form="maxwell-slip"),
              make_model("nmlgm-hysteresis", params="seed000-cylinder1"),
              gms_class(3)()]
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(1) as pool:
        runs = pool.starmap(friction_along_motion, [(m, T, V) for m in models])
    for model, run in zip(models, runs, strict=True):
        np.testing.assert_array_equal(run.F, friction_along_motion(model, T, V).F)
