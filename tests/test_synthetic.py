"""The synthetic rig generator: independence, physics of its truth, measurement realism."""

from __future__ import annotations

import ast
import hashlib
import math
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import fcomp.synthetic as syn
from fcomp.errors import FcompError
from fcomp.measurement import Measurement
from fcomp.synthetic import catalogue, dynamics, laws, sensors
from fcomp.synthetic.friction import node_average
from fcomp.synthetic.motion import Plan

FORBIDDEN = ("fcomp.models", "fcomp.effects", "fcomp.trajectory", "fcomp.identification",
             "fcomp.diagnosis", "fcomp.reconstruction")
#: Base on which each effect is judged: the Stribeck hump on a base without one, presliding
#: on a static base; the others on LuGre.
NATURAL_BASE = {"presliding": "stribeck", "stribeck": "coulomb-viscous"}


def _law(spec: str, scale: str = "pneumatic") -> catalogue.Law:
    return next(iter(catalogue.resolve([spec], syn.SCALES[scale].factors).values()))


# ------------------------------------------------------------------ independence
def test_generator_does_not_use_the_package_models() -> None:
    """Independence: the truth is integrated by the generator's own code (every module)."""
    files = sorted(Path(syn.__file__).parent.glob("*.py"))
    assert len(files) >= 8
    for path in files:
        imported = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                imported.add(node.module)
                imported |= {f"{node.module}.{a.name}" for a in node.names}
            elif isinstance(node, ast.Import):
                imported |= {a.name for a in node.names}
        fcomp_mods = {m for m in imported if m.startswith("fcomp")}
        assert not any(m.startswith(FORBIDDEN) for m in fcomp_mods), (path.name, fcomp_mods)
        allowed = ("fcomp.errors", "fcomp.measurement", "fcomp.synthetic")
        assert all(m.startswith(allowed) for m in fcomp_mods), (path.name, fcomp_mods)


# ------------------------------------------------------------------ bit-identity
#: sha256 (first 24 hex digits) of the columns and truth arrays of records made by the
#: generator before it became a package (fcomp/synthetic.py at ab73700), except the two
#: records with Maxwell-slip elements: their old law scaled the held force with the
#: Stribeck level at rest (the force jumped to Fs while nothing moved), now fixed.
OLD_DIGESTS = {
    "viscous-lugre": "6a939b4956a233a1ff261084",
    "stribeck-lugre": "33c4a6f0318ac6fe51d008a6",
    "nonlocal-memory-lugre": "8e2789e03d4c27902a18460c",  # slip forces now held at rest
    "frictional-lag-lugre": "9a7d67f81108597a787e04fe",
    "dwell-time-lugre": "43d22a3b7aa263078b33e22e",
    "direction-asymmetry-lugre": "032d11bd7073c408fc6ce4c1",
    "pressure-dependence-lugre": "02941875ca2cedd843da1b68",
    "position-dependence-lugre": "609fab40453bddf702578958",
    "viscous-lead-lugre": "79cfffa075251bb6f6f5a8e7",
    "inertia-error-lugre": "69ec4f5c5a093f50aebddc11",
    "force-offset-lugre": "8899f0cec654e2f9eda30d64",
    "ripple-lugre": "f2035972058545c8a7703998",
    "drift-lugre": "e83d70e84e0166ec7ec07d70",
    "presliding-stribeck": "1762e95e8f87d4570b0b6469",
    "stribeck-coulomb": "7d60c53fbaa2411587dabea8",
    "dwell-time-coulomb": "c56b8c3496ba0c7d95cf20c3",
    "base-coulomb": "eea3bfec402d0579bcbaa013",
    "base-coulomb-viscous": "9d6ab9b962c6c4d6373089f9",
    "base-stribeck": "92ccedefeca4292abd68d587",
    "base-lugre": "6e4e02b8e43990fdfbe472f9",
    "diag12": "c5547735cab9ad98bf87ef2d",
    "cli-fo": "1ab49f24bbea3c3d77f65189",
    "combo": "d1a6d2a95f0b09a0a09d3f73",
    "combo2": "8c483270d51595eff08362d9",  # Maxwell-slip: slip forces now held at rest
    "vel": "4ef5ee2f95a476278f500b2d",
    "params": "f68ba8bc1551127cbd00837d",
    "nonoise": "43c62cc895c2d4c3813dbe1e",
}


def _old_case(name: str) -> dict:
    special = {
        "diag12": {"hidden": ["pressure-dependence"], "duration": 12.0, "seed": 1},
        "cli-fo": {"hidden": ["force-offset"], "duration": 12.0, "experiments": 2, "seed": 1},
        "combo": {"hidden": ["pressure-dependence", "direction-asymmetry", "dwell-time"],
                  "duration": 6.0, "seed": 3, "experiments": 2},
        "combo2": {"hidden": {"nonlocal-memory": {"n_elements": 4},
                              "frictional-lag": {"tau_L": 0.02}},
                   "base": "stribeck", "duration": 4.0, "seed": 11, "rate": 1000.0},
        "vel": {"hidden": ["viscous"], "base": "coulomb", "include_velocity": True,
                "duration": 3.0, "seed": 2, "resolution": 5e-6, "pressure_noise": 1000.0,
                "noise_std": 1.0, "noise_tau": 0.01},
        "params": {"hidden": ["stribeck"], "base": "coulomb-viscous",
                   "params": syn.TruthParams(Fc=50.0, mass=3.0, bore=0.05), "duration": 3.0,
                   "seed": 4, "fine": 5, "pressures": (2e5, 6e5)},
        "nonoise": {"hidden": [], "duration": 4.0, "seed": 2, "pressure_noise": 0.0,
                    "noise_std": 0.0},
    }
    if name in special:
        return special[name]
    if name.startswith("base-"):
        return {"hidden": [], "base": name[5:], "duration": 3.0, "seed": 5}
    effect, base = name.rsplit("-", 1)
    return {"hidden": [effect], "base": base, "duration": 3.0, "seed": 7}


def _digest(rec: syn.SyntheticRecord) -> str:
    h = hashlib.sha256()
    tr = rec.truth
    arrays = list(rec.measurement.columns.items()) + [
        (k, getattr(tr, k)) for k in ("F", "friction", "v", "a", "noise")]
    for k, v in arrays:
        h.update(k.encode())
        h.update(np.ascontiguousarray(v, dtype=float).tobytes())
    return h.hexdigest()[:24]


def test_default_output_is_bit_identical_to_the_old_generator() -> None:
    """Old arguments give the old records bit for bit (other tests depend on them)."""
    wrong = {name: _digest(syn.generate(**_old_case(name))) for name in OLD_DIGESTS}
    wrong = {k: v for k, v in wrong.items() if v != OLD_DIGESTS[k]}
    assert not wrong
    rec = syn.generate(**_old_case("cli-fo"))
    assert rec.measurement.meta == {
        "name": "synthetic-force-offset", "kind": "pneumatic-cylinder", "pressure": "gauge",
        "rig": {"bore": 0.032, "rod": 0.012, "stroke": 0.2, "mass": 1.2,
                "orientation": "horizontal"},
        "synthetic": {"generator": "fcomp.synthetic", "seed": 1, "rate": 500.0,
                      "position_resolution": 1e-06}}


def test_catalogue_first_shapes_are_the_old_laws() -> None:
    assert syn.HIDDEN_DEFAULTS["nonlocal-memory"] == {"n_elements": 6.0, "d_max": 4e-4}
    assert syn.HIDDEN_DEFAULTS["dwell-time"] == {"dF_inf": 40.0, "tau_k": 0.5, "m": 1.0,
                                                 "d_c": 5e-4}
    pairs = syn.effect_shapes()
    assert len(pairs) == sum(len(s) for s in syn.SHAPES.values()) == len(set(pairs))
    for effect, shapes in syn.SHAPES.items():
        assert dict(catalogue.shape(effect).defaults) == syn.HIDDEN_DEFAULTS[effect]
        assert catalogue.shape(effect).name == shapes[0]
    assert {e for e, _ in syn.effect_shapes(include_outside=False)} == \
        set(syn.SHAPES) - set(syn.OUTSIDE)
    assert {"ripple", "drift", "ringing"} <= set(syn.OUTSIDE)
    for effect, n in [("stribeck", 3), ("presliding", 3), ("nonlocal-memory", 3),
                      ("frictional-lag", 4), ("dwell-time", 4), ("direction-asymmetry", 3),
                      ("pressure-dependence", 3), ("position-dependence", 4)]:
        assert len(syn.SHAPES[effect]) >= n, effect
    every_param = {k for shapes in syn.CATALOGUE.values() for s in shapes for k in s.defaults}
    assert set(catalogue.DIMENSIONS) <= every_param


# ------------------------------------------------------------------ independent integrations
def _sine_motion(t_end: float, V: float, f: float, dt: float) -> tuple:
    n = int(round(t_end / dt))
    t = np.arange(n) * dt
    w = 2 * math.pi * f
    tm = t + 0.5 * dt
    return t, V * np.sin(w * tm), V * w * np.cos(w * tm), V / w * (1 - np.cos(w * t))


@pytest.mark.parametrize("scale", list(syn.SCALES))
def test_truth_lugre_matches_an_independent_stiff_integration(scale: str) -> None:
    """LuGre along v = V*sin(w t) against solve_ivp (Radau, rtol 1e-10): models.md 1.3."""
    P = syn.SCALES[scale].params
    V, f, t_end, dt = 0.05, 1.5, 1.3, 2e-5
    vel = lambda t: V * math.sin(2 * math.pi * f * t)  # noqa: E731
    g = lambda v: P.Fc + (P.Fs - P.Fc) * math.exp(-((v / P.vs) ** 2))  # noqa: E731
    z_ss = P.Fc / P.sigma0
    sol = solve_ivp(lambda t, z: [vel(t) - P.sigma0 * abs(vel(t)) * z[0] / g(vel(t))],
                    (0.0, t_end), [0.0], method="Radau", rtol=1e-10, atol=1e-6 * z_ss,
                    dense_output=True, max_step=1e-3)
    t, v, a, x = _sine_motion(t_end, V, f, dt)
    F, _, _ = syn.truth_friction(P, "lugre", {}, t, v, a, x, np.zeros(t.size), dt, 0.0)
    idx = np.arange(0, t.size, 50)
    ref = np.empty(idx.size)
    for j, i in enumerate(idx):
        z, vi = sol.sol(t[i])[0], vel(t[i])
        dz = vi - P.sigma0 * abs(vi) * z / g(vi)
        ref[j] = P.sigma0 * z + P.sigma1 * dz + P.sigma2 * vi
    err = np.abs(F[idx] - ref)
    assert np.max(err) < 0.02 * P.Fc, np.max(err)
    assert np.sqrt(np.mean(err**2)) < 0.002 * P.Fc


def _alpha_ep(zeta: float, ba: float) -> float:
    """Dupont et al. 2002 alpha of the generator's transition (independent of its solver)."""
    if zeta <= ba:
        return 0.0
    if zeta < 1.0:
        return (zeta - ba) / ((1.0 - ba) * zeta)
    return 1.0


@pytest.mark.parametrize("scale", list(syn.SCALES))
@pytest.mark.parametrize("shape", ["bristle", "dahl", "elasto-plastic"])
def test_presliding_shapes_match_an_independent_integration(scale: str, shape: str) -> None:
    """Presliding on a Coulomb base (constant level) against solve_ivp on the ODE itself."""
    P = syn.SCALES[scale].params
    law = _law(f"presliding:{shape}", scale)
    k, Fc = law["k"], P.Fc
    z_ss = Fc / k
    A, f, dt = 3 * z_ss, 2.0, 5e-6  # loops of three presliding lengths
    V = A * 2 * math.pi * f
    t, v, a, x = _sine_motion(0.9, V, f, dt)

    def rhs(t_: float, y: np.ndarray) -> list:
        vi = V * math.sin(2 * math.pi * f * t_)
        s = math.copysign(1.0, vi)
        if shape == "bristle":
            return [vi - k * abs(vi) * y[0] / Fc]
        if shape == "dahl":  # state: the force
            u = 1.0 - y[0] * s / Fc
            return [k * abs(u) ** law["i"] * math.copysign(1.0, u) * vi]
        zeta = s * y[0] / z_ss  # z/z_ss(v), z_ss(v) = s*g/k (Dupont et al. 2002, Eq. 8)
        return [vi * (1.0 - _alpha_ep(zeta, law["ba"]) * zeta)]

    sol = solve_ivp(rhs, (0.0, t[-1]), [0.0], method="Radau", rtol=1e-9,
                    atol=1e-9 * (Fc if shape == "dahl" else z_ss), dense_output=True,
                    max_step=2e-4)
    F, _, _ = syn.truth_friction(P, "coulomb", {"presliding": law}, t, v, a, x,
                                 np.zeros(t.size), dt, 0.0)
    idx = np.arange(0, t.size, 200)
    ref = sol.sol(t[idx])[0] * (1.0 if shape == "dahl" else k)
    err = np.abs(F[idx] - ref)
    assert np.max(err) < 0.01 * Fc, np.max(err)
    assert np.max(np.abs(F)) == pytest.approx(Fc, rel=0.2)


def test_elasto_plastic_has_no_slip_below_break_away() -> None:
    """Below the break-away displacement the force is exactly elastic and fully recovers."""
    law = _law("presliding:elasto-plastic")
    k, Fc, ba = law["k"], 30.0, law["ba"]
    dt = 1e-5
    d = 0.9 * ba * Fc / k  # a loop inside the elastic range
    t, v, a, x = _sine_motion(1.0, d / 2 * 2 * math.pi * 1.0, 1.0, dt)
    F = dynamics.elasto_plastic(v, np.full(t.size, Fc), k, ba, dt)
    assert np.allclose(F, k * x, atol=1e-9 * Fc)  # F = k*x: no plastic drift
    F = dynamics.dahl(v, np.full(t.size, Fc), k, 2.0, dt)
    assert np.max(np.abs(F - k * x)) > 0.01 * Fc  # Dahl slips at once


# ------------------------------------------------------------------ nonlocal memory
def _path(*points: float, n_per_m: float = 2e6) -> tuple[np.ndarray, list[int]]:
    """Piecewise-linear displacement through ``points``; indices of the turning points."""
    segs, marks = [np.array([points[0]])], [0]
    for p0, p1 in zip(points[:-1], points[1:], strict=True):
        n = max(2, int(abs(p1 - p0) * n_per_m))
        segs.append(np.linspace(p0, p1, n + 1)[1:])
        marks.append(marks[-1] + n)
    return np.concatenate(segs), marks


@pytest.mark.parametrize("shape", syn.SHAPES["nonlocal-memory"])
def test_maxwell_slip_has_return_point_memory_and_wipes_out(shape: str) -> None:
    law = _law(f"nonlocal-memory:{shape}")
    g0 = 30.0
    # return-point memory: the inner loop 1e-4 -> 2e-4 -> 1e-4 leaves no trace
    x, m = _path(0.0, 3e-4, 1e-4, 2e-4, 1e-4, -6e-4)
    F = dynamics.maxwell_slip(law, x, np.full(x.size, g0))
    assert x[m[2]] == pytest.approx(x[m[4]])
    assert F[m[2]] == pytest.approx(F[m[4]], abs=1e-9)
    assert abs(F[-1]) == pytest.approx(g0, rel=1e-9)  # full slip: every element slides
    # wiping out: once the input passes 2e-4 again, the inner pair (2e-4, 1.5e-4) is
    # forgotten: the force is that of the path without it
    xa, ma = _path(0.0, 3e-4, 1e-4, 2e-4, 1.5e-4, 3.5e-4)
    xb, mb = _path(0.0, 3e-4, 1e-4, 3.5e-4)
    Fa = dynamics.maxwell_slip(law, xa, np.full(xa.size, g0))
    Fb = dynamics.maxwell_slip(law, xb, np.full(xb.size, g0))
    probe = np.linspace(2.05e-4, 3.45e-4, 15)
    fa = np.interp(probe, xa[ma[4]:], Fa[ma[4]:])
    fb = np.interp(probe, xb[mb[2]:], Fb[mb[2]:])
    assert np.allclose(fa, fb, atol=1e-6 * g0)
    # ... while below 2e-4 the inner loop is still remembered (the branches differ)
    probe = np.linspace(1.6e-4, 1.9e-4, 4)
    fa = np.interp(probe, xa[ma[4]:], Fa[ma[4]:])
    fb = np.interp(probe, xb[mb[2]:], Fb[mb[2]:])
    assert np.max(np.abs(fa - fb)) > 1e-3 * g0


def test_play_operator_is_the_sequential_clip_recursion_bit_for_bit() -> None:
    rng = np.random.default_rng(0)
    dx = np.concatenate([rng.normal(0, 2e-6, 3000), np.full(500, 1e-6), np.zeros(200),
                         rng.normal(0, 5e-5, 2000)])
    for d in (1e-5, 1e-4):
        ref = np.empty(dx.size)
        s = 0.0
        for i, step in enumerate(dx):
            s = min(max(s + step, -d), d)
            ref[i] = s
        assert np.array_equal(dynamics.play(dx, d), ref)


# ------------------------------------------------------------------ no-op regions
def _test_motion(P: syn.TruthParams, levels: tuple[float, float], dt: float = 1e-4) -> dict:
    """Rest, a slide through mid-stroke, rest, a pressure change, a slow slide back."""
    L = P.stroke
    plan = Plan(dt=dt, x0=0.2 * L, stroke=L, level=levels[0])
    plan.dwell(0.5)
    plan.move(0.5 * L, 0.05, 0.1)
    plan.dwell(0.6)
    plan.pressure(levels[1])
    plan.move(-0.3 * L, 0.012, 0.1)
    plan.dwell(0.3)
    v, a, S = (np.concatenate(p) for p in (plan.v, plan.a, plan.S))
    x = 0.2 * L + np.concatenate([[0.0], np.cumsum(v[:-1] * dt)])
    t = np.arange(v.size) * dt
    vn, an = node_average(v), node_average(a)
    # time since the acceleration was last non-zero, distance since the last start/reversal
    moving_a = np.flatnonzero(an != 0.0)
    last_a = np.maximum.accumulate(np.where(an != 0.0, np.arange(an.size), 0))
    quiet = t - t[last_a] if moving_a.size else t
    turn = np.concatenate([[True], np.sign(vn[1:]) != np.sign(vn[:-1])])
    last_turn = np.maximum.accumulate(np.where(turn, np.arange(v.size), 0))
    slid = np.abs(x - x[last_turn])
    return {"t": t, "v": v, "a": a, "x": x, "S": S, "vn": vn, "an": an, "dt": dt,
            "quiet": quiet, "slid": slid, "L": L, "S_mid": levels[0]}


def _cruise(m: dict, distance: float) -> np.ndarray:
    """Steady sliding: constant speed for 50 ms, more than ``distance`` since the start."""
    return (m["slid"] > distance) & (m["quiet"] > 0.05) & (m["vn"] != 0)


Mask = Callable[[dict, catalogue.Law, np.ndarray], np.ndarray]
NOOP_CASES: list[tuple[str, str, Mask, float]] = [
    ("position-dependence:tight-spot", "coulomb-viscous",
     lambda m, h, F0: np.abs(m["x"] - h["x_t_frac"] * m["L"]) >= 0.5 * h["w_frac"] * m["L"], 0),
    ("position-dependence:step", "coulomb-viscous",
     lambda m, h, F0: m["x"] < h["x_s_frac"] * m["L"] - 25 * h["w_edge"], 0),
    ("direction-asymmetry:levels", "coulomb-viscous",
     lambda m, h, F0: np.cumsum(m["vn"] < 0) == 0, 0),
    ("direction-asymmetry:viscous", "coulomb-viscous", lambda m, h, F0: m["vn"] >= 0, 0),
    ("direction-asymmetry:ratio", "coulomb-viscous", lambda m, h, F0: F0 <= 0, 0),
    ("viscous:linear", "coulomb", lambda m, h, F0: m["vn"] == 0, 0),
    ("viscous:power", "coulomb", lambda m, h, F0: m["vn"] == 0, 0),
    ("viscous-lead:lead", "coulomb-viscous", lambda m, h, F0: m["an"] == 0, 0),
    ("viscous-lead:lead-lag", "coulomb-viscous",
     lambda m, h, F0: m["quiet"] > 30 * h["T_f"], 1e-9),
    ("pressure-dependence:lip-seal", "stribeck", lambda m, h, F0: m["S"] == m["S_mid"], 0),
    ("pressure-dependence:saturating", "stribeck",
     lambda m, h, F0: m["S"] == m["S_mid"], 1e-12),
    ("dwell-time:kato", "coulomb-viscous", lambda m, h, F0: m["slid"] > 40 * h["d_c"], 1e-9),
    ("dwell-time:dieterich", "coulomb-viscous",
     lambda m, h, F0: m["slid"] > 40 * h["d_c"], 1e-9),
    *[(f"frictional-lag:{s}", "stribeck",  # tau_L, or the film's building time
       lambda m, h, F0: m["quiet"] > 20 * h.params.get("tau_L", h.params.get("tau_rise")),
       1e-6) for s in syn.SHAPES["frictional-lag"]],
    *[(f"presliding:{s}", "stribeck", lambda m, h, F0: _cruise(m, 50 * 45.0 / h["k"]), 1e-9)
      for s in ("bristle", "elasto-plastic")],
    *[(f"nonlocal-memory:{s}", "stribeck", lambda m, h, F0: _cruise(m, h["d_max"]), 1e-9)
      for s in syn.SHAPES["nonlocal-memory"]],
]


@pytest.mark.parametrize("spec, base, mask, tol", NOOP_CASES, ids=[c[0] for c in NOOP_CASES])
def test_each_shape_is_a_no_op_where_it_should_be(spec: str, base: str, mask: Mask,
                                                   tol: float) -> None:
    """Away from a tight spot, at rest for a viscous law, in steady sliding for a lag, ...
    the friction equals the base's (exactly, where the law multiplies by 1 or adds 0)."""
    P = syn.TruthParams()
    m = _test_motion(P, (3e5, 5e5))
    law = _law(spec)
    args = (P, base)
    rest = (m["t"], m["v"], m["a"], m["x"], m["S"], m["dt"], m["S_mid"])
    F0, _, _ = syn.truth_friction(*args, {}, *rest)
    F1, _, _ = syn.truth_friction(*args, {law.effect: law}, *rest)
    where = mask(m, law, F0)
    assert 0.02 < np.mean(where) < 0.995, np.mean(where)  # the test exercises both regions
    if tol == 0:
        assert np.array_equal(F1[where], F0[where])
    else:
        assert np.allclose(F1[where], F0[where], rtol=tol, atol=tol * P.Fc)
    assert np.max(np.abs(F1 - F0)[~where]) > 1e-3 * P.Fc  # and acts elsewhere


def test_dahl_approaches_the_level_algebraically() -> None:
    """Dahl with i = 2 reaches the level as 1/x (not exponentially): |g - F| ~ g^2/(k*x)."""
    law = _law("presliding:dahl")
    k, g0, dt = law["k"], 30.0, 1e-5
    v = np.full(20000, 0.01)
    F = dynamics.dahl(v, np.full(v.size, g0), k, law["i"], dt)
    xs = np.arange(v.size) * 0.01 * dt
    late = xs > 1e-3
    assert np.allclose(g0 - F[late], g0 / (1.0 + k * xs[late] / g0), rtol=1e-6)


def test_chamber_weighted_pressure_law_is_one_at_the_reference_chambers() -> None:
    law = _law("pressure-dependence:chamber-weighted")
    p1m, p2m = 1.2e5, 1.8e5
    ones = np.ones(4)
    ctx = laws.LevelContext(x=ones, t=np.arange(4.0), S=ones * 3e5, retracting=ones < 0,
                            stroke=0.2, Fc=30.0, S_mid=3e5,
                            chambers=(ones * p1m, ones * p2m, p1m, p2m))
    assert np.allclose(laws.level_factor({law.effect: law}, ctx), 1.0, rtol=1e-14)
    ctx = replace(ctx, chambers=(ones * p1m, ones * (p2m + 1e5), p1m, p2m))
    assert np.all(laws.level_factor({law.effect: law}, ctx) > 1.2)  # the rod seal sees p2


def test_dwell_time_acts_on_every_base_including_alone() -> None:
    for base in syn.BASES:
        b = syn.generate([], base=base, duration=6.0, seed=4).truth
        for shape in syn.SHAPES["dwell-time"]:
            r = syn.generate([f"dwell-time:{shape}"], base=base, duration=6.0, seed=4).truth
            assert np.max(np.abs(r.F - b.F)) > 5 * r.noise_std, (base, shape)


# ------------------------------------------------------------------ the records
def test_measurement_format_and_hidden_truth_kept_apart(tmp_path: Path) -> None:
    rec = syn.generate(["force-offset"], duration=4.0, experiments=2, seed=1)
    m = rec.measurement
    assert list(m.columns) == ["t", "x", "p1", "p2", "F", "experiment"]
    assert "v" not in m  # the tool must derive the velocity
    assert np.all(np.diff(m.t) > 0)
    assert set(np.unique(m["experiment"])) == {1.0, 2.0}
    text = str(m.meta)
    assert "force-offset" in m.meta["name"] and "offset" not in text.replace("force-offset", "")
    csv, _ = m.write(tmp_path / "s.csv")
    back = Measurement.read(csv)
    assert np.array_equal(back["F"], m["F"])
    # the recorded force is the truth plus noise; the offset is in the truth
    assert np.allclose(m["F"] - rec.truth.noise, rec.truth.F)
    assert np.allclose(rec.truth.F - rec.truth.friction, 6.0)


#: What a real rig of each style writes.
STYLE_COLUMNS = {
    "load-cell": ["t", "x", "p1", "p2", "F", "experiment"],
    "tacho": ["t", "x", "v", "p1", "p2", "F", "experiment"],
    "encoder-velocity": ["t", "x", "v", "p1", "p2", "F", "experiment"],
    "pressures": ["t", "x", "p1", "p2", "experiment"],
    "pressures-tacho": ["t", "x", "v", "p1", "p2", "experiment"],
    "coarse-encoder": ["t", "x", "p1", "p2", "F", "experiment"],
    "drive-force": ["t", "x", "F_ext", "experiment"],
    "potentiometer": ["t", "x", "p1", "p2", "F", "experiment"],
    "potentiometer-pressures": ["t", "x", "p1", "p2", "experiment"],
}


@pytest.mark.parametrize("scale", list(syn.SCALES))
@pytest.mark.parametrize("style", list(STYLE_COLUMNS))
def test_each_style_writes_what_a_real_rig_would(tmp_path: Path, style: str, scale: str
                                                 ) -> None:
    assert set(STYLE_COLUMNS) == set(syn.STYLES)
    hidden = ["pressure-dependence:chamber-weighted", "inertia-error", "force-offset:tilt"]
    rec = syn.generate(hidden, duration=2.0, seed=3, scale=scale, style=style, name="run-7")
    m = rec.measurement
    assert list(m.columns) == STYLE_COLUMNS[style] == list(syn.STYLES[style].columns)
    cylinder = "hydraulic-cylinder" if scale.endswith("hydraulic") else "pneumatic-cylinder"
    assert m.meta["kind"] == ("friction-rig" if style == "drive-force" else cylinder)
    rig = m.meta["rig"]
    assert rig["mass"] == pytest.approx(rec.truth.params.mass - rec.truth.hidden[
        "inertia-error"]["dm"])
    assert ("bore" in rig) == (style != "drive-force")
    csv, toml = m.write(tmp_path / "run.csv")
    text = toml.read_text()
    for word in ["inertia", "tilt", "chamber", "angle", "dm", "c_rod", "hidden", "truth"]:
        assert word not in text, word
    assert Measurement.read(csv).columns.keys() == m.columns.keys()


@pytest.mark.parametrize("scale", list(syn.SCALES))
@pytest.mark.parametrize("style", ["pressures", "pressures-tacho", "drive-force"])
def test_force_balance_gives_the_recorded_force(style: str, scale: str) -> None:
    """Without sensor noise and lag, ``p1*A1 - p2*A2 - m*a`` (or ``F_ext - m*a``) with the
    sidecar mass is the truth's recorded force, recording errors included."""
    sens = replace(syn.SCALES[scale].sensors, pressure_noise=0.0, pressure_lag=0.0,
                   noise_std=0.0)
    hidden = ["inertia-error:understated", "force-offset", "ringing", "stribeck:lorentzian"]
    rec = syn.generate(hidden, base="coulomb-viscous", duration=4.0, seed=5, scale=scale,
                       style=style, sensors=sens)
    m, tr = rec.measurement, rec.truth
    mass = m.meta["rig"]["mass"]
    if style == "drive-force":
        F = m["F_ext"] - mass * tr.a
    else:
        A1, A2 = math.pi / 4 * m.meta["rig"]["bore"] ** 2, math.pi / 4 * (
            m.meta["rig"]["bore"] ** 2 - m.meta["rig"]["rod"] ** 2)
        F = m["p1"] * A1 - m["p2"] * A2 - mass * tr.a
        S = m["p1"] + m["p2"]  # the pressure sum steps between and within experiments
        assert len(np.unique(np.round(S / 1e3))) >= 3
    assert np.allclose(F, tr.F, atol=1e-9 * np.max(np.abs(tr.F)))


@pytest.mark.parametrize("scale", list(syn.SCALES))
def test_pressure_sensor_noise_and_lag(scale: str) -> None:
    sc = syn.SCALES[scale]
    rec = syn.generate([], duration=6.0, seed=6, scale=scale, style="pressures")
    m, tr = rec.measurement, rec.truth
    exact = syn.generate([], duration=6.0, seed=6, scale=scale, style="pressures",
                         sensors=replace(sc.sensors, pressure_noise=0.0, pressure_lag=0.0))
    lagged = syn.generate([], duration=6.0, seed=6, scale=scale, style="pressures",
                          sensors=replace(sc.sensors, pressure_noise=0.0))
    for p in ("p1", "p2"):
        assert np.std(m[p] - lagged.measurement[p]) == pytest.approx(sc.sensors.pressure_noise,
                                                                     rel=0.05)
        lag_err = lagged.measurement[p] - exact.measurement[p]
        assert 0 < np.max(np.abs(lag_err)) < 0.05 * np.max(exact.measurement[p])
    A1, A2 = tr.params.areas
    assert tr.noise_std == pytest.approx(sc.sensors.pressure_noise * math.hypot(A1, A2))
    assert np.std(tr.noise) == pytest.approx(tr.noise_std, rel=0.05)


def test_first_order_lag_is_exact_for_a_step() -> None:
    dt, tau = 1e-4, 1e-3
    u = np.concatenate([np.zeros(10), np.ones(200)])
    y = dynamics.lowpass(u, tau, dt)
    k = np.arange(1, 200)
    assert np.allclose(y[10 + k - 1], 1 - np.exp(-k * dt / tau), rtol=1e-12)


def _rest_signals(v: np.ndarray, dt: float, every: int) -> sensors.FineSignals:
    z = np.zeros(v.size)
    return sensors.FineSignals(t=np.arange(v.size) * dt, x=z, v=v, a=z, S=z, experiment=z,
                               friction=z, recorded=z, physical=None, dt=dt,
                               idx=np.arange(0, v.size, every))


def test_tacho_bias_noise_gain_and_lag_are_as_asked() -> None:
    sens = syn.SCALES["pneumatic"].sensors
    sens = replace(sens, tacho_bias=1.2e-4, tacho_gain=0.012, tacho_lag=2e-3)
    rng = np.random.default_rng(1)
    at_rest = sensors.tacho(_rest_signals(np.zeros(4_000_000), 1e-4, 10), sens, rng)
    assert np.mean(at_rest) == pytest.approx(sens.tacho_bias, abs=5e-6)
    assert np.std(at_rest) == pytest.approx(math.hypot(sens.tacho_white, sens.tacho_coloured),
                                            rel=0.03)
    # the coloured part: neighbours correlate by c^2*exp(-dt/tau)/(w^2 + c^2)
    rho = np.corrcoef(at_rest[1:], at_rest[:-1])[0, 1]
    w2, c2 = sens.tacho_white**2, sens.tacho_coloured**2
    assert rho == pytest.approx(c2 * math.exp(-1e-3 / sens.tacho_tau) / (w2 + c2), abs=0.01)
    quiet = replace(sens, tacho_white=0.0, tacho_coloured=0.0)
    step = np.concatenate([np.zeros(100), np.full(1000, 0.1)])
    y = sensors.tacho(_rest_signals(step, 1e-4, 1), quiet, rng)
    assert y[-1] == pytest.approx(1.012 * 0.1 + 1.2e-4, rel=1e-9)  # gain and bias
    k63 = int(np.argmax(y - 1.2e-4 > (1 - math.exp(-1)) * 0.1 * 1.012))
    assert (k63 - 100) * 1e-4 == pytest.approx(2e-3, abs=2e-4)  # lag


@pytest.mark.parametrize("style", ["tacho", "pressures-tacho"])
def test_tacho_column_of_a_record(style: str) -> None:
    rec = syn.generate([], duration=12.0, seed=2, style=style)
    s, v = rec.truth.sensors, rec.measurement["v"]
    assert s is not None
    still = np.convolve(np.abs(rec.truth.v) > 0, np.ones(101), "same") == 0  # 0.1 s at rest
    assert np.mean(v[still]) == pytest.approx(s.tacho_bias, abs=3e-5)
    moving = np.abs(rec.truth.v) > 0.02
    assert np.corrcoef(v[moving], rec.truth.v[moving])[0, 1] > 0.99


@pytest.mark.parametrize("window", [1, 4])
def test_encoder_velocity_is_the_difference_of_the_quantised_position(window: int) -> None:
    sens = replace(syn.SCALES["pneumatic"].sensors, encoder_window=window)
    rec = syn.generate([], duration=6.0, seed=8, style="encoder-velocity", sensors=sens)
    m = rec.measurement
    x, t, v = m["x"], m["t"], m["v"]
    q = x / sens.resolution
    assert np.allclose(q, np.round(q), atol=1e-6)
    k = np.arange(window, x.size)
    assert np.allclose(v[k], (x[k] - x[k - window]) / (t[k] - t[k - window]), rtol=1e-12,
                       atol=1e-15)
    rest = rec.truth.v == 0
    assert 0 < np.mean(v[rest] != 0) < 0.2  # counts flicker at rest: the velocity jumps
    uniform = np.concatenate([np.zeros(window, bool), np.isclose(
        t[window:] - t[:-window], window / 500.0)])
    jumps = np.abs(v[rest & uniform & (v != 0)]) * window / (500 * sens.resolution)
    assert jumps.size and np.allclose(jumps, np.round(jumps), atol=1e-6)  # whole counts


def test_coarse_encoder_and_drive_force() -> None:
    rec = syn.generate(["inertia-error"], duration=4.0, seed=2, style="coarse-encoder")
    s = rec.truth.sensors
    assert s is not None and 10 <= s.coarse <= 20
    q = rec.measurement["x"] / (s.resolution * s.coarse)
    assert np.allclose(q, np.round(q), atol=1e-6)
    assert rec.measurement.meta["synthetic"]["position_resolution"] == s.resolution * s.coarse
    rec = syn.generate(["inertia-error"], duration=4.0, seed=2, style="drive-force")
    m, tr = rec.measurement, rec.truth
    F = m["F_ext"] - m.meta["rig"]["mass"] * tr.a
    assert np.allclose(F, tr.F + tr.noise)
    assert np.std(tr.noise) == pytest.approx(0.4, rel=0.1)


def test_an_analog_position_is_noisy_and_read_by_a_16_bit_converter() -> None:
    """The potentiometer styles: white noise of ``analog_noise`` on the position, then a
    converter step of stroke/2^16 (3 um on 200 mm); the sidecar gives that step."""
    exact = replace(syn.SCALES["pneumatic"].sensors, analog_noise=0.0)
    clean = syn.generate([], duration=4.0, seed=2, style="potentiometer", sensors=exact)
    rec = syn.generate([], duration=4.0, seed=2, style="potentiometer")
    q = 0.2 / 2**16
    assert np.allclose(clean.measurement["x"] / q, np.round(clean.measurement["x"] / q))
    assert rec.measurement.meta["synthetic"]["position_resolution"] == q
    d = rec.measurement["x"] - clean.measurement["x"]  # noise, and two roundings
    assert np.std(d) == pytest.approx(math.sqrt(2e-6**2 + q * q / 6), rel=0.1)
    assert np.all(np.isfinite(syn.generate([], duration=2.0, seed=2,
                                           style="potentiometer-pressures").measurement["x"]))
    drawn = syn.generate([], duration=1.0, seed=4, style="potentiometer", vary=True).truth
    assert drawn.sensors is not None and 1e-6 <= drawn.sensors.analog_noise <= 4e-6


def test_position_quantised_and_pressures_balance_the_force() -> None:
    rec = syn.generate([], duration=4.0, seed=2, pressure_noise=0.0, noise_std=0.0)
    m, tr, P = rec.measurement, rec.truth, rec.truth.params
    q = m["x"] / 1e-6
    assert np.allclose(q, np.round(q), atol=1e-6)
    A1, A2 = P.areas
    net = m["p1"] * A1 - m["p2"] * A2
    assert np.allclose(net, tr.friction + P.mass * tr.a, atol=1e-6)
    assert np.allclose(m["F"], tr.F)


def test_coloured_noise_statistics() -> None:
    rng = np.random.default_rng(0)
    e = sensors.ar1(rng, 200_000, 0.5, 0.005, 0.002)
    assert np.std(e) == pytest.approx(0.5, rel=0.03)
    rho = np.corrcoef(e[1:], e[:-1])[0, 1]
    assert rho == pytest.approx(math.exp(-0.002 / 0.005), abs=0.01)


@pytest.mark.parametrize("scale", list(syn.SCALES))
def test_motion_is_realistic(scale: str) -> None:
    """Slides at many speeds, reversals with and without stops, dwells, small loops."""
    rec = syn.generate([], duration=12.0, seed=3, scale=scale)
    v = rec.truth.v
    speed = np.abs(v)
    moving = speed > 1e-6
    assert 0.2 < np.mean(~moving) < 0.7  # dwells
    top = speed[moving]
    assert np.percentile(top, 95) / np.percentile(top, 20) > 5  # speeds over a decade
    s = np.sign(v[moving])
    assert np.sum(s[1:] != s[:-1]) >= 10  # reversals
    x = rec.measurement["x"]
    lo, hi = syn.SCALES[scale].loop_amplitude
    rev = np.flatnonzero(np.diff(np.sign(v)) != 0)
    swings = np.abs(np.diff(x[rev]))
    assert np.sum((swings > 0.5 * lo) & (swings < 2 * hi)) >= 3  # presliding loops
    S = rec.measurement["p1"] + rec.measurement["p2"]
    assert np.ptp(S) > 0.4 * np.mean(S)  # pressure changes


def test_hydraulic_scale_is_in_range() -> None:
    sc = syn.SCALES["hydraulic"]
    P, s = sc.params, sc.sensors
    assert 200 <= P.Fc <= 500 and P.Fs > P.Fc
    assert 1e7 <= P.sigma0 <= 1e8 and 1e-6 <= P.Fc / P.sigma0 <= 2e-5  # a few micrometres
    assert 10 <= P.mass <= 40 and 0.04 <= P.bore <= 0.08 and P.rod < P.bore
    assert 1 <= s.noise_std <= 10 and 5e3 <= s.pressure_noise <= 2e4
    hyd = syn.generate([], duration=8.0, seed=1, scale="hydraulic", style="pressures")
    pne = syn.generate([], duration=8.0, seed=1)
    p = np.concatenate([hyd.measurement["p1"], hyd.measurement["p2"]])
    assert np.min(p) > 1.5e6 and np.max(p) < 2.0e7  # chamber pressures 2-20 MPa gauge
    assert np.max(np.abs(hyd.truth.a)) > 2 * np.max(np.abs(pne.truth.a))
    assert 250 < np.median(np.abs(hyd.truth.friction[np.abs(hyd.truth.v) > 1e-3])) < 600
    # effect sizes follow the rig: forces x10, presliding lengths / 20
    assert _law("stribeck", "hydraulic")["dF"] == 10 * syn.HIDDEN_DEFAULTS["stribeck"]["dF"]
    assert _law("nonlocal-memory", "hydraulic")["d_max"] == pytest.approx(2e-5)
    assert _law("pressure-dependence", "hydraulic")["c_p"] * 1.2e7 == pytest.approx(
        syn.HIDDEN_DEFAULTS["pressure-dependence"]["c_p"] * 3e5)


@pytest.mark.parametrize("scale", list(syn.SCALES))
def test_every_hidden_effect_is_visible_above_the_noise(scale: str) -> None:
    """At least 4 noise standard deviations where it acts, for the load cell and for the
    (larger, at the hydraulic scale) pressure-reconstructed force; not dominant: the
    effect's RMS within 1.6 times the base force's. (Presliding on a static base comes
    nearest: the base force is zero at rest where presliding holds its force, and the
    short stroke of ``small-pneumatic`` rests 67 % of the time: 1.51.)"""
    P = syn.SCALES[scale].params
    A1, A2 = P.areas
    sigma = max(syn.SCALES[scale].sensors.noise_std,
                syn.SCALES[scale].sensors.pressure_noise * math.hypot(A1, A2))
    bases: dict[str, syn.SyntheticTruth] = {}
    for effect, shape in syn.effect_shapes():
        base = NATURAL_BASE.get(effect, "lugre")
        if base not in bases:
            bases[base] = syn.generate([], base=base, duration=12.0, seed=1, scale=scale).truth
        b = bases[base]
        d = syn.generate([f"{effect}:{shape}"], base=base, duration=12.0, seed=1,
                         scale=scale).truth.F - b.F
        assert np.sum(np.abs(d) > 4 * sigma) >= 10, (effect, shape, np.max(np.abs(d)) / sigma)
        assert np.sqrt(np.mean(d**2)) < 1.6 * np.sqrt(np.mean(b.F**2)), (effect, shape)


def test_ringing_is_outside_any_law_of_the_motion() -> None:
    """The ring is a decaying oscillation at f_r after each start: zero mean, a spectral
    line far above the motion's bandwidth, the same after every start whatever follows."""
    law = _law("ringing")
    rec = syn.generate(["ringing"], duration=8.0, seed=2, rate=1000.0)
    ring = rec.truth.F - rec.truth.friction
    assert abs(np.mean(ring)) < 0.01 * law["F_r"]
    spec = np.abs(np.fft.rfft(ring)) ** 2
    freq = np.fft.rfftfreq(ring.size, 1e-3)
    assert freq[np.argmax(spec)] == pytest.approx(law["f_r"], rel=0.05)
    band = np.abs(freq - law["f_r"]) < 0.3 * law["f_r"]
    assert np.sum(spec[band]) > 0.8 * np.sum(spec)
    motion = np.abs(np.fft.rfft(rec.truth.a)) ** 2  # the motion has (almost) nothing there
    assert np.sum(motion[band]) < 0.05 * np.sum(motion)


# ------------------------------------------------------------------ variation, API
def test_vary_draws_plausible_rigs_and_records_them() -> None:
    seen_rates = set()
    for seed in range(6):
        rec = syn.generate(["stribeck:lorentzian", "dwell-time"], base="coulomb-viscous",
                           duration=2.0, seed=seed, vary=True, scale="hydraulic")
        tr = rec.truth
        sc = syn.SCALES["hydraulic"]
        assert tr.rate in (500.0, 1000.0, 2000.0)
        seen_rates.add(tr.rate)
        assert np.median(np.diff(rec.measurement.t)) == pytest.approx(1 / tr.rate)
        assert 0.69 * sc.params.Fc <= tr.params.Fc <= 1.31 * sc.params.Fc
        assert sc.mass_range[0] <= tr.params.mass <= sc.mass_range[1]
        assert tr.sensors is not None and tr.sensors.resolution in sc.resolutions
        k = tr.nuisance["magnitude.stribeck"]
        assert 0.6 <= k <= 1.5
        assert tr.hidden["stribeck"]["dF"] == pytest.approx(k * 150.0)
        assert tr.hidden["stribeck"]["vs"] == syn.HIDDEN_DEFAULTS["stribeck"]["vs"]
        assert 2e-5 <= abs(tr.sensors.tacho_bias) <= 4e-4
        row = tr.describe()
        assert row["hidden"] == "stribeck:lorentzian, dwell-time:kato"
        assert row["scale"] == "hydraulic" and row["style"] == "load-cell"
        assert row["rate"] == tr.rate and row["magnitude.dwell-time"] > 0
        assert row["base.mass"] == tr.params.mass and "sensors.noise_std" in row
        assert row["law.stribeck.dF"] == tr.hidden["stribeck"]["dF"]
    assert len(seen_rates) >= 2
    a = syn.generate(["viscous"], duration=2.0, seed=3, vary=True).measurement
    b = syn.generate(["viscous"], duration=2.0, seed=3, vary=True).measurement
    assert all(np.array_equal(a[k], b[k]) for k in a.columns)
    # explicit arguments are kept
    tr = syn.generate([], duration=1.0, seed=3, vary=True, rate=800.0, noise_std=0.7).truth
    assert tr.rate == 800.0 and tr.noise_std == 0.7


def test_every_effect_shape_style_and_scale_generates() -> None:
    n = 0
    for scale in syn.SCALES:
        for style in syn.STYLES:
            for effect, shape in syn.effect_shapes():
                rec = syn.generate([f"{effect}:{shape}"], base=NATURAL_BASE.get(effect, "lugre"),
                                   duration=0.6, experiments=1, seed=n, scale=scale,
                                   style=style, vary=n % 3 == 0)
                assert np.all(np.isfinite(rec.truth.F))
                assert rec.truth.shapes == {effect: shape}
                n += 1
    assert n == len(syn.SCALES) * len(syn.STYLES) * len(syn.effect_shapes())


def test_a_minute_at_one_kilohertz_generates_in_seconds() -> None:
    start = time.perf_counter()
    syn.generate(["nonlocal-memory:graded", "dwell-time", "frictional-lag:film"],
                 duration=60.0, rate=1000.0, style="pressures-tacho")
    assert time.perf_counter() - start < 10.0  # ~0.5 s on one core


@pytest.mark.parametrize("name", ["direction-asymmetry", "pressure-dependence",
                                  "position-dependence", "ripple", "viscous-lead"])
def test_each_hidden_law_changes_the_truth(name: str) -> None:
    a = syn.generate([name], duration=8.0, seed=4).truth
    b = syn.generate([], duration=8.0, seed=4).truth
    assert np.sqrt(np.mean((a.F - b.F) ** 2)) > 0.3  # N, against 0.4 N of noise: present


def test_inertia_error_is_a_mass_error_in_the_recorded_force() -> None:
    for shape in syn.SHAPES["inertia-error"]:
        rec = syn.generate([f"inertia-error:{shape}"], duration=3.0, seed=4)
        dm = rec.truth.hidden["inertia-error"]["dm"]
        assert np.allclose(rec.truth.F - rec.truth.friction, dm * rec.truth.a)
        assert rec.measurement.meta["rig"]["mass"] == pytest.approx(rec.truth.params.mass - dm)
    assert catalogue.shape("inertia-error", "understated").defaults["dm"] > 0


def test_same_seed_same_record() -> None:
    a = syn.generate(["dwell-time"], duration=2.0, seed=9).measurement
    b = syn.generate(["dwell-time"], duration=2.0, seed=9).measurement
    assert all(np.array_equal(a[k], b[k]) for k in a.columns)


@pytest.mark.parametrize("kwargs, match", [
    ({"hidden": ["no-such-effect"]}, "unknown hidden effect"),
    ({"hidden": {"dwell-time": {"nope": 1.0}}}, "unknown law parameter"),
    ({"hidden": ["stribeck:gaussian"]}, "unknown shape"),
    ({"hidden": ["stribeck", "stribeck:lorentzian"]}, "given twice"),
    ({"base": "gms"}, "unknown base"),
    ({"duration": -1.0}, "positive"),
    ({"scale": "electric"}, "unknown scale"),
    ({"style": "laser"}, "unknown style"),
    ({"hidden": ["frictional-lag"], "base": "coulomb"}, "Stribeck hump"),
    ({"hidden": ["presliding"], "base": "lugre"}, "presliding already"),
    ({"style": "tacho", "include_velocity": True}, "velocity of its own"),
])
def test_bad_arguments(kwargs: dict, match: str) -> None:
    with pytest.raises(FcompError, match=match):
        syn.generate(**kwargs)


@pytest.mark.parametrize("shape", syn.SHAPES["nonlocal-memory"])
def test_maxwell_slip_holds_its_force_at_rest(shape: str) -> None:
    """At rest nothing slides: the elements' force stays what it was when the motion stopped,
    though the Stribeck level the slip forces follow rises towards Fs."""
    rec = syn.generate([f"nonlocal-memory:{shape}"], base="lugre", duration=8.0, seed=3)
    v, F = rec.truth.v, rec.truth.friction
    still = np.flatnonzero((v[1:] == 0.0) & (v[:-1] == 0.0)) + 1
    assert still.size > 100
    np.testing.assert_allclose(F[still], F[still - 1], rtol=0, atol=1e-9)
