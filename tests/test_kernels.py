"""The native kernels of issue 15 give what the paths they replace give.

* the friction along a motion in one C loop
  (:func:`fcomp.models.stepping.motion_kernel`) against the numpy path
  (``compiled=False``): the same states and signals bit for bit, the same
  force to rounding, for every symbolic model, with effects, substeps, an
  initial state, given or derived position and acceleration, held or
  sampled pressures; invalid signals are named as before;
* the sensitivity loop (:class:`fcomp.identification.sensitivity.SensitivityLoop`):
  a loop compiled for more parameters serves a narrower set with the same
  columns, and a pass asked for again (same record, same parameters) is the
  kept, read-only result.

No timing here: ``benchmarks/bench_friction.py`` and ``benchmarks/bench_fit.py``
measure the speed beside their baselines.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from fcomp.errors import FcompError
from fcomp.identification.sensitivity import SensitivityLoop
from fcomp.models import MODELS, FrictionModel, make_model
from fcomp.trajectory import friction_along_motion, prepare_signals

RATE = 1000.0  # Hz


def motion(seconds: float = 4.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``t``, ``v``, ``a``: two tones with reversals and a rest (``v = 0`` exactly)."""
    t = np.arange(int(seconds * RATE)) / RATE
    w1, w2 = 2 * np.pi * 0.5, 2 * np.pi * 3.1
    v = 0.05 * np.sin(w1 * t) + 0.02 * np.sin(w2 * t)
    a = 0.05 * w1 * np.cos(w1 * t) + 0.02 * w2 * np.cos(w2 * t)
    rest = (t > 1.0) & (t < 1.2)
    v[rest], a[rest] = 0.0, 0.0
    return t, v, a


def agree(model: FrictionModel, t: np.ndarray, v: Any, **kw: Any) -> None:
    native = friction_along_motion(model, t, v, **kw)
    plain = friction_along_motion(model, t, v, compiled=False, **kw)
    for name in ("t", "v", "a", "x", "p1", "p2", "s", "states"):
        np.testing.assert_array_equal(getattr(native, name), getattr(plain, name), err_msg=name)
    scale = float(np.max(np.abs(plain.F))) or 1.0
    np.testing.assert_allclose(native.F, plain.F, rtol=0, atol=1e-12 * scale)
    assert native.state_names == plain.state_names


SYMBOLIC = [n for n in MODELS if make_model(n).symbolic]


@pytest.mark.parametrize("name", SYMBOLIC)
def test_native_motion_equals_numpy_path(name: str) -> None:
    t, v, a = motion()
    model = make_model(name)
    agree(model, t, v)
    agree(model, t, v, a=a, x=0.01 * np.sin(t), p1=2e5 + 1e4 * np.cos(t), p2=1e5)


@pytest.mark.parametrize("effects", [("pressure-dependence",), ("frictional-lag", "dwell-time"),
                                     ("position-dependence", "direction-asymmetry")])
def test_native_motion_with_effects_and_substeps(effects: tuple[str, ...]) -> None:
    t, v, a = motion()
    model = make_model("lugre", params="seed000-cylinder1").with_effects(*effects)
    rng = np.random.default_rng(3)
    p1 = 3e5 + 2e4 * rng.standard_normal(t.size)
    agree(model, t, v, a=a, p1=p1, p2=[1.5e5], substeps=3)
    state0 = model.initial_state() + 1e-5
    agree(model, t, v, a=a, p1=p1, state0=state0)


def test_native_motion_held_velocity() -> None:
    t = np.arange(200) / RATE
    agree(make_model("nmlgm"), t, 0.01)
    agree(make_model("nmlgm"), t, 0.0)


@pytest.mark.parametrize(("change", "message"), [
    ({"v": "nan"}, "signal v has non-finite values"),
    ({"a": "inf"}, "signal a has non-finite values"),
    ({"p1": "nan"}, "signal p1 has non-finite values"),
    ({"t": "repeat"}, "time must be finite and strictly increasing"),
    ({"t": "inf"}, "time must be finite and strictly increasing"),
])
def test_native_motion_names_invalid_signals(change: dict[str, str], message: str) -> None:
    t, v, a = motion(1.0)
    sig = {"t": t.copy(), "v": v.copy(), "a": a.copy(), "p1": np.zeros_like(t)}
    (name, how), = change.items()
    if how == "repeat":
        sig[name][500] = sig[name][499]
    else:
        sig[name][-1] = float(how)
    with pytest.raises(FcompError, match=message):
        friction_along_motion(make_model("lugre"), sig["t"], sig["v"], a=sig["a"], p1=sig["p1"])


def test_wider_sensitivity_loop_serves_a_narrower_set() -> None:
    t, v, a = motion(2.0)
    model = make_model("nmlgm").with_effects("force-offset")  # a structure of this test alone
    wide = ("Fc", "Fs", "vs", "n", "sigma2", "sigma0", "sigma1", "vb", "tau_hp", "tau_hn", "T")
    narrow = tuple(n for n in wide if n != "vb")
    sig = prepare_signals(t, v, a)
    F_wide, G_wide = SensitivityLoop(model, wide)(sig, {})
    loop = SensitivityLoop(model, narrow)
    assert loop._loop_free == wide  # served by the wider loop: no second compilation
    F, G = loop(prepare_signals(t, v, a), {})  # another record object: computed afresh
    np.testing.assert_array_equal(F, F_wide)
    np.testing.assert_array_equal(G, G_wide[:, [wide.index(n) for n in narrow]])


def test_sensitivity_pass_asked_again_is_kept() -> None:
    t, v, a = motion(2.0)
    model = make_model("lugre")
    free = ("Fc", "Fs", "sigma0")
    sig = prepare_signals(t, v, a)
    loop = SensitivityLoop(model, free)
    F1, G1 = loop(sig, {"Fc": 1.1})
    F2, G2 = SensitivityLoop(model, free)(sig, {"Fc": 1.1})
    assert F2 is F1 and G2 is G1  # the same record at the same parameters
    assert not F1.flags.writeable and not G1.flags.writeable
    F3, _ = loop(sig, {"Fc": 1.2})
    assert F3 is not F1 and not np.array_equal(F3, F1)
