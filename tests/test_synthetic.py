"""The synthetic rig generator: independence, physics of its truth, measurement realism."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import fcomp.synthetic as syn
from fcomp.errors import FcompError
from fcomp.measurement import Measurement


def test_generator_does_not_use_the_package_models() -> None:
    """Independence: the truth is integrated by the generator's own code."""
    tree = ast.parse(Path(syn.__file__).read_text())
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            imported.add(node.module)
        elif isinstance(node, ast.Import):
            imported |= {a.name for a in node.names}
    assert not any(m.startswith(("fcomp.models", "fcomp.effects", "fcomp.trajectory",
                                 "fcomp.identification", "fcomp.diagnosis")) for m in imported)


def _lugre_reference(t_end: float, P: syn.TruthParams) -> tuple:
    """LuGre along v(t) = V*sin(w t) by solve_ivp (Radau, rtol 1e-10): models.md 1.3."""
    V, w = 0.05, 2 * math.pi * 1.5

    def vel(t: float) -> float:
        return V * math.sin(w * t)

    def g(v: float) -> float:
        return P.Fc + (P.Fs - P.Fc) * math.exp(-((v / P.vs) ** 2))

    def rhs(t: float, z: np.ndarray) -> list:
        v = vel(t)
        return [v - P.sigma0 * abs(v) * z[0] / g(v)]

    sol = solve_ivp(rhs, (0.0, t_end), [0.0], method="Radau", rtol=1e-10, atol=1e-14,
                    dense_output=True, max_step=1e-3)
    return sol, vel, g, V, w


def test_truth_lugre_matches_an_independent_stiff_integration() -> None:
    P = syn.TruthParams()
    t_end = 1.3
    sol, vel, g, V, w = _lugre_reference(t_end, P)
    dt = 2e-5
    n = int(round(t_end / dt))
    t = np.arange(n) * dt
    tm = t + 0.5 * dt
    v = V * np.sin(w * tm)
    a = V * w * np.cos(w * tm)
    x = V / w * (1 - np.cos(w * t))
    F, vn, _ = syn.truth_friction(P, "lugre", {}, t, v, a, x, np.zeros(n), dt, 0.0)
    ref = np.empty(n)
    for i in range(0, n, 50):
        z = sol.sol(t[i])[0]
        vi = vel(t[i])
        dz = vi - P.sigma0 * abs(vi) * z / g(vi)
        ref[i] = P.sigma0 * z + P.sigma1 * dz + P.sigma2 * vi
    idx = np.arange(0, n, 50)
    err = np.abs(F[idx] - ref[idx])
    assert np.max(err) < 0.02 * P.Fc, np.max(err)  # N, on a force of 30-45 N
    assert np.sqrt(np.mean(err**2)) < 0.002 * P.Fc


def test_maxwell_slip_truth_has_return_point_memory() -> None:
    """A closed displacement cycle inside a larger one leaves no trace (nonlocal memory)."""
    h = syn.HIDDEN_DEFAULTS["nonlocal-memory"]
    x = np.concatenate([np.linspace(0, 3e-4, 300), np.linspace(3e-4, 1e-4, 200),
                        np.linspace(1e-4, 2e-4, 100), np.linspace(2e-4, 1e-4, 100),
                        np.linspace(1e-4, -6e-4, 700)])
    g = np.full(x.size, 30.0)
    F = syn._maxwell_slip(h, x, g)
    # after the inner loop 1e-4 -> 2e-4 -> 1e-4 the force at x = 1e-4 is the same again
    i1, i2 = 499, 699
    assert x[i1] == pytest.approx(x[i2])
    assert F[i1] == pytest.approx(F[i2], abs=1e-9)
    assert abs(F[-1]) == pytest.approx(30.0, rel=1e-9)  # full slip: every element slides


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


def test_position_quantised_and_pressures_balance_the_force() -> None:
    rec = syn.generate([], duration=4.0, seed=2, pressure_noise=0.0, noise_std=0.0)
    m, tr, P = rec.measurement, rec.truth, rec.truth.params
    q = m["x"] / 1e-6
    assert np.allclose(q, np.round(q), atol=1e-6)
    A1 = math.pi / 4 * P.bore**2
    A2 = math.pi / 4 * (P.bore**2 - P.rod**2)
    net = m["p1"] * A1 - m["p2"] * A2
    assert np.allclose(net, tr.friction + P.mass * tr.a, atol=1e-6)
    assert np.allclose(m["F"], tr.F)


def test_coloured_noise_statistics() -> None:
    rng = np.random.default_rng(0)
    e = syn._ar1(rng, 200_000, 0.5, 0.005, 0.002)
    assert np.std(e) == pytest.approx(0.5, rel=0.03)
    rho = np.corrcoef(e[1:], e[:-1])[0, 1]
    assert rho == pytest.approx(math.exp(-0.002 / 0.005), abs=0.01)


def test_motion_is_realistic() -> None:
    """Slides at many speeds, reversals with and without stops, dwells, small loops."""
    rec = syn.generate([], duration=12.0, seed=3)
    v = rec.truth.v
    speed = np.abs(v)
    moving = speed > 1e-6
    assert 0.2 < np.mean(~moving) < 0.7  # dwells
    top = speed[moving]
    assert np.percentile(top, 95) / np.percentile(top, 20) > 5  # speeds over a decade
    s = np.sign(v[moving])
    assert np.sum(s[1:] != s[:-1]) >= 10  # reversals
    x = rec.measurement["x"]
    # small displacement loops (presliding): excursions below 0.5 mm between reversals
    rev = np.flatnonzero(np.diff(np.sign(v)) != 0)
    swings = np.abs(np.diff(x[rev]))
    assert np.sum((swings > 1e-5) & (swings < 5e-4)) >= 3
    S = rec.measurement["p1"] + rec.measurement["p2"]
    assert np.ptp(S) > 2e5  # pressure changes


@pytest.mark.parametrize("name", ["direction-asymmetry", "pressure-dependence",
                                  "position-dependence", "ripple", "viscous-lead"])
def test_each_hidden_law_changes_the_truth(name: str) -> None:
    a = syn.generate([name], duration=8.0, seed=4).truth
    b = syn.generate([], duration=8.0, seed=4).truth
    assert np.sqrt(np.mean((a.F - b.F) ** 2)) > 0.3  # N, against 0.4 N of noise: present


def test_inertia_error_is_a_mass_error_in_the_recorded_force() -> None:
    rec = syn.generate(["inertia-error"], duration=3.0, seed=4)
    dm = syn.HIDDEN_DEFAULTS["inertia-error"]["dm"]
    assert np.allclose(rec.truth.F - rec.truth.friction, dm * rec.truth.a)
    assert rec.measurement.meta["rig"]["mass"] == pytest.approx(rec.truth.params.mass - dm)


def test_same_seed_same_record() -> None:
    a = syn.generate(["dwell-time"], duration=2.0, seed=9).measurement
    b = syn.generate(["dwell-time"], duration=2.0, seed=9).measurement
    assert all(np.array_equal(a[k], b[k]) for k in a.columns)


@pytest.mark.parametrize("kwargs, match", [
    ({"hidden": ["no-such-effect"]}, "unknown hidden effect"),
    ({"hidden": {"dwell-time": {"nope": 1.0}}}, "unknown law parameter"),
    ({"base": "gms"}, "unknown base"),
    ({"duration": -1.0}, "positive"),
])
def test_bad_arguments(kwargs: dict, match: str) -> None:
    with pytest.raises(FcompError, match=match):
        syn.generate(**kwargs)
