"""Conditions of the synthetic rig: pink force noise, vertical rigs, presliding-dominated
motions on soft seals, and the matrix's ``conditions`` dimension with its judge.

The physics is checked on the generator's own truth arrays (never through
:mod:`fcomp.reconstruction`); the matrix through its public functions only.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.signal import welch

import fcomp.synthetic as syn
from fcomp.errors import FcompError
from fcomp.synthetic import matrix, motion, sensors

G = 9.80665
#: ``s`` of the weight ``m*g*s`` as docs/data-format.md defines ``rig.orientation``
#: (+1 extending upward: the weight opposes extension).
SIGN = {"horizontal": 0.0, "vertical-up": 1.0, "vertical-down": -1.0}


def _slope(y: np.ndarray, fs: float, lo: float, hi: float, nperseg: int) -> float:
    """Least-squares slope of the log-log Welch PSD of ``y`` between ``lo`` and ``hi`` Hz."""
    f, p = welch(y, fs=fs, nperseg=nperseg)
    band = (f >= lo) & (f <= hi)
    return float(np.polyfit(np.log10(f[band]), np.log10(p[band]), 1)[0])


# ------------------------------------------------------------------ pink noise
def test_pink_noise_has_the_std_and_a_one_over_f_spectrum() -> None:
    y = sensors.pink(np.random.default_rng(0), 2**17, 0.4)
    assert np.std(y) == pytest.approx(0.4, rel=1e-9)
    assert abs(np.mean(y)) < 1e-9
    assert -1.3 < _slope(y, 1000.0, 0.5, 50.0, 2**14) < -0.7  # two decades
    white = np.random.default_rng(0).normal(0.0, 0.4, 2**17)
    assert abs(_slope(white, 1000.0, 0.5, 50.0, 2**14)) < 0.2  # the fit tells them apart


@pytest.mark.parametrize("style", ["load-cell", "drive-force", "pressures"])
def test_pink_force_noise_of_a_record(style: str) -> None:
    """``noise_color="pink"``: the force channel's noise is 1/f (two decades, 1-100 Hz) with
    the standard deviation of the AR(1) it replaces; the motion and the truth are unchanged."""
    ar = syn.generate(["dwell-time"], duration=40.0, rate=1000.0, seed=3, style=style)
    rec = syn.generate(["dwell-time"], duration=40.0, rate=1000.0, seed=3, style=style,
                       noise_color="pink")
    tr = rec.truth
    assert tr.sensors is not None and tr.sensors.noise_color == "pink"
    assert ar.truth.sensors is not None and ar.truth.sensors.noise_color == "ar1"
    assert np.array_equal(tr.F, ar.truth.F) and np.array_equal(rec.measurement["x"],
                                                              ar.measurement["x"])
    assert tr.noise_std == ar.truth.noise_std
    assert np.std(tr.noise) == pytest.approx(tr.noise_std, rel=0.15)
    assert -1.3 < _slope(tr.noise, 1000.0, 1.0, 100.0, 8192) < -0.7
    assert _slope(ar.truth.noise, 1000.0, 0.5, 8.0, 8192) > -0.4  # AR(1): flat below ~30 Hz
    assert _slope(tr.noise, 1000.0, 0.5, 8.0, 8192) < -0.7
    if style == "load-cell":
        assert np.allclose(rec.measurement["F"] - tr.noise, tr.F)
        assert np.std(tr.noise) == pytest.approx(tr.noise_std, rel=1e-9)
    if style == "pressures":  # both transducers pink
        A1, A2 = tr.params.areas
        exact = syn.generate(["dwell-time"], duration=40.0, rate=1000.0, seed=3, style=style,
                             noise_color="pink", pressure_noise=0.0)
        n1 = rec.measurement["p1"] - exact.measurement["p1"]
        assert -1.3 < _slope(n1, 1000.0, 1.0, 100.0, 8192) < -0.7
        assert np.allclose(n1 * A1 - (rec.measurement["p2"] - exact.measurement["p2"]) * A2,
                           tr.noise)


def test_noise_color_on_the_sensors_and_bad_values() -> None:
    sens = replace(syn.SCALES["pneumatic"].sensors, noise_color="pink")
    rec = syn.generate([], duration=4.0, seed=2, sensors=sens)
    assert rec.truth.describe()["sensors.noise_color"] == "pink"
    assert np.array_equal(rec.truth.noise,
                          syn.generate([], duration=4.0, seed=2, noise_color="pink").truth.noise)
    with pytest.raises(FcompError, match="noise colour"):
        syn.generate([], duration=1.0, noise_color="blue")
    with pytest.raises(FcompError, match="noise colour"):
        syn.generate([], duration=1.0, sensors=replace(sens, noise_color="brown"))


# ------------------------------------------------------------------ vertical rigs
def _area(meta: dict) -> tuple[float, float]:
    D, d = meta["rig"]["bore"], meta["rig"]["rod"]
    return math.pi / 4 * D * D, math.pi / 4 * (D * D - d * d)


@pytest.mark.parametrize("scale", ["pneumatic", "hydraulic"])
@pytest.mark.parametrize("orientation", ["vertical-up", "vertical-down"])
def test_vertical_pressures_balance_friction_inertia_and_weight(scale: str,
                                                                orientation: str) -> None:
    """``p1*A1 - p2*A2 - m*a - m*g*s`` (sidecar mass and orientation, true ``a``) is the
    recorded force ``truth.F``: exactly without sensor noise and lag, within the noise
    and the transducer lag with them."""
    hidden = ["stribeck:lorentzian", "force-offset"]
    quiet = replace(syn.SCALES[scale].sensors, pressure_noise=0.0, pressure_lag=0.0)
    exact = syn.generate(hidden, base="coulomb-viscous", duration=8.0, seed=5, scale=scale,
                         style="pressures", sensors=quiet, orientation=orientation)
    m, tr = exact.measurement, exact.truth
    assert m.meta["rig"]["orientation"] == orientation and tr.orientation == orientation
    A1, A2 = _area(m.meta)
    mass, s = m.meta["rig"]["mass"], SIGN[m.meta["rig"]["orientation"]]
    F = m["p1"] * A1 - m["p2"] * A2 - mass * tr.a - mass * G * s
    assert np.allclose(F, tr.F, rtol=0, atol=1e-9 * np.max(np.abs(tr.F)))
    flat = syn.generate(hidden, base="coulomb-viscous", duration=8.0, seed=5, scale=scale,
                        style="pressures", sensors=quiet)
    assert np.array_equal(flat.truth.F, tr.F)  # the friction does not change
    net = (m["p1"] * A1 - m["p2"] * A2) - (flat.measurement["p1"] * A1
                                            - flat.measurement["p2"] * A2)
    assert np.allclose(net, mass * G * s, rtol=1e-9)  # the chambers carry the weight
    # with the noise and the lag of the transducers: the error is the horizontal rig's
    # (the weight is constant, the lag passes it unchanged), noise and lag only
    rec = syn.generate(hidden, base="coulomb-viscous", duration=8.0, seed=5, scale=scale,
                       style="pressures", orientation=orientation)
    m, tr = rec.measurement, rec.truth
    F = m["p1"] * A1 - m["p2"] * A2 - mass * tr.a - mass * G * s
    flat = syn.generate(hidden, base="coulomb-viscous", duration=8.0, seed=5, scale=scale,
                        style="pressures")
    fm = flat.measurement
    F0 = fm["p1"] * A1 - fm["p2"] * A2 - mass * flat.truth.a
    assert np.allclose(F - tr.F, F0 - flat.truth.F, rtol=0, atol=1e-6 * tr.params.Fc)
    assert np.median(np.abs(F - tr.F)) < 2 * tr.noise_std  # the lag acts at transients only
    assert np.median(np.abs(F - tr.F - tr.noise)) < 0.2 * tr.noise_std
    assert abs(np.mean(F - tr.F)) < 0.2 * tr.noise_std  # no weight left over


def test_vertical_drive_force_load_cell_and_a_wrong_mass() -> None:
    rec = syn.generate(["stribeck"], base="coulomb-viscous", duration=6.0, seed=4,
                       style="drive-force", orientation="vertical")
    m, tr = rec.measurement, rec.truth
    assert m.meta["rig"]["orientation"] == "vertical-up"
    mass = m.meta["rig"]["mass"]
    assert np.allclose(m["F_ext"] - mass * tr.a - mass * G, tr.F + tr.noise)
    # a load cell measures the friction: its column is that of the horizontal rig ...
    lc = syn.generate(["stribeck"], base="coulomb-viscous", duration=6.0, seed=4,
                      orientation="vertical-down")
    flat = syn.generate(["stribeck"], base="coulomb-viscous", duration=6.0, seed=4)
    assert np.array_equal(lc.measurement["F"], flat.measurement["F"])
    # ... while its chambers carry the weight
    A1, A2 = lc.truth.params.areas
    net = lambda r: r.measurement["p1"] * A1 - r.measurement["p2"] * A2  # noqa: E731
    assert np.mean(net(lc) - net(flat)) == pytest.approx(-lc.truth.params.mass * G, rel=0.02)
    # a wrong sidecar mass on a vertical rig subtracts a wrong weight: dm*(a + g*s)
    quiet = replace(syn.SCALES["pneumatic"].sensors, pressure_noise=0.0, pressure_lag=0.0)
    rec = syn.generate(["inertia-error"], duration=4.0, seed=4, style="pressures",
                       sensors=quiet, orientation="vertical-up")
    tr, m = rec.truth, rec.measurement
    dm = tr.hidden["inertia-error"]["dm"]
    assert np.allclose(tr.F - tr.friction, dm * (tr.a + G))
    A1, A2 = _area(m.meta)
    mass = m.meta["rig"]["mass"]
    assert np.allclose(m["p1"] * A1 - m["p2"] * A2,
                       tr.friction + tr.params.mass * (tr.a + G), atol=1e-9)
    with pytest.raises(FcompError, match="orientation"):
        syn.generate([], duration=1.0, orientation="sideways")


def test_chamber_weighted_pressure_law_on_a_vertical_rig() -> None:
    """The pressure law sees the chambers that carry the weight (and is referred to the
    chambers at rest at the reference pressure, weight included)."""
    law = "pressure-dependence:chamber-weighted"
    flat = syn.generate([law], duration=6.0, seed=2, scale="hydraulic")
    up = syn.generate([law], duration=6.0, seed=2, scale="hydraulic", orientation="vertical-up")
    rel = np.abs(up.truth.friction - flat.truth.friction) / up.truth.params.Fc
    assert 1e-4 < np.max(rel) < 0.1
    assert np.array_equal(syn.generate(["dwell-time"], duration=3.0, seed=2,
                                       orientation="vertical-up").truth.friction,
                          syn.generate(["dwell-time"], duration=3.0, seed=2).truth.friction)


# ------------------------------------------------------------------ presliding motion
def _since_start(v: np.ndarray, x: np.ndarray, F: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Displacement and force change since the last start or reversal; the starts."""
    s = np.sign(v)
    start = (s != 0) & (s != np.concatenate([[0.0], s[:-1]]))
    last = np.maximum.accumulate(np.where(start, np.arange(v.size), 0))
    return x - x[last], F - F[last], start


@pytest.mark.parametrize("scale", ["pneumatic", "hydraulic"])
def test_presliding_motion_is_mostly_small_loops(scale: str) -> None:
    rec = syn.generate([], duration=40.0, seed=3, scale=scale, motion="presliding")
    assert rec.truth.motion == "presliding"
    v, x = rec.truth.v, rec.measurement["x"]
    lo, hi = syn.SCALES[scale].presliding_amplitude
    if scale == "pneumatic":
        assert (lo, hi) == (1e-5, 2.5e-4)
    d, _, start = _since_start(v, x, rec.truth.F)
    moving = v != 0
    loop = moving & (np.abs(d) < 2.4 * hi)
    assert np.sum(loop) / np.sum(moving) > 0.7  # most of the motion: small loops
    assert np.mean(loop | ~moving) > 0.75
    assert np.sum(start) > 50  # many cycles
    # a few slides of about 20 mm: the largest displacement of each move
    starts = np.flatnonzero(start)
    swing = np.array([np.max(np.abs(d[a:b])) for a, b in
                      zip(starts, [*starts[1:], v.size], strict=True)])
    slides = swing > 1e-2
    assert 3 <= np.sum(slides) <= 10
    assert np.all(swing[slides] < 0.03)
    small = swing[swing < 3 * hi]
    assert np.min(small) < 4 * lo and np.max(small) > 1.2 * hi  # swings 2*A over the range
    # several frequencies: half periods of the loops from 1/16 s to 1 s
    half = np.diff(rec.measurement.t[starts])[swing[:-1] < 3 * hi]
    assert np.min(half) < 0.1 and np.max(half) > 0.8


def test_soft_bristle_shows_in_the_presliding_loops() -> None:
    """The issue's seal: 25 mm pneumatic, bristle 1.5e4 N/m (presliding range 2 mm). In
    loops well inside it the friction changes with the displacement since the reversal
    at about that stiffness: a spring, not a sign."""
    k = 1.5e4
    rec = syn.generate([], duration=40.0, seed=2, motion="presliding", bristle=k,
                       resolution=1e-8)
    P = rec.truth.params
    nominal = syn.SCALES["pneumatic"].params
    assert P.sigma0 == k
    assert P.sigma1 == pytest.approx(nominal.sigma1 * math.sqrt(k / nominal.sigma0))
    d, dF, _ = _since_start(rec.truth.v, rec.measurement["x"], rec.truth.friction)
    small = (rec.truth.v != 0) & (np.abs(d) > 0) & (np.abs(d) < 0.1 * P.Fc / k)
    assert np.sum(small) > 2000
    slope = np.sum(dF[small] * d[small]) / np.sum(d[small] ** 2)
    assert slope == pytest.approx(k, rel=0.15)
    # no jump to the other sliding level (2*Fc): the elastic change is at most 0.1*Fc here,
    # the bristle damping adds a little at the starts of the slides
    assert np.percentile(np.abs(dF[small]), 99) < 0.2 * P.Fc
    # the stiff default seal on the same motion: a stiffness ten times larger
    stiff = syn.generate([], duration=40.0, seed=2, motion="presliding", resolution=1e-8)
    d2, dF2, _ = _since_start(stiff.truth.v, stiff.measurement["x"], stiff.truth.friction)
    tiny = (stiff.truth.v != 0) & (np.abs(d2) > 0) & (np.abs(d2) < 0.1 * P.Fc / nominal.sigma0)
    assert np.sum(dF2[tiny] * d2[tiny]) / np.sum(d2[tiny] ** 2) > 8 * k


def test_bristle_sets_the_presliding_laws_and_survives_vary() -> None:
    k = 2e4
    rec = syn.generate(["presliding:dahl"], base="stribeck", duration=2.0, seed=1,
                       bristle=k, vary=True)
    assert rec.truth.hidden["presliding"]["k"] == k
    mem = syn.generate(["nonlocal-memory"], duration=2.0, seed=1, bristle=k)
    P = syn.SCALES["pneumatic"].params
    assert mem.truth.hidden["nonlocal-memory"]["d_max"] == pytest.approx(
        syn.HIDDEN_DEFAULTS["nonlocal-memory"]["d_max"] * P.sigma0 / k)
    assert syn.generate([], duration=1.0, seed=1, vary=True, bristle=k).truth.params.sigma0 == k
    with pytest.raises(FcompError, match="bristle"):
        syn.generate([], duration=1.0, bristle=-1.0)
    with pytest.raises(FcompError, match="unknown motion"):
        syn.generate([], duration=1.0, motion="zigzag")
    assert set(motion.MOTIONS) == {"standard", "presliding"}


# ------------------------------------------------------------------ the matrix
#: sha256 (24 hex digits) and length of the default selections before the conditions
#: were added (``Case.as_dict()`` without ``condition``, JSON with sorted keys).
OLD_CASES = {
    "default": ("8020d07e0554e18e72ccae0d", 1278),
    "seeds-4-5": ("175a3c851c296ca0dc1a4288", 852),
    "every-style-scale": ("ee59c0536483cef4da0fae2a", 2200),
}


def _digest(cs: list[matrix.Case]) -> tuple[str, int]:
    dicts = [c.as_dict() for c in cs]
    assert all(d.pop("condition") == "plain" for d in dicts)
    return hashlib.sha256(json.dumps(dicts, sort_keys=True).encode()).hexdigest()[:24], len(cs)


def test_default_cases_are_unchanged() -> None:
    assert _digest(matrix.cases()) == OLD_CASES["default"]
    assert _digest(matrix.cases(seeds=[4, 5])) == OLD_CASES["seeds-4-5"]
    assert _digest(matrix.cases(seeds=[1, 2], styles=list(syn.STYLES), scales=list(syn.SCALES),
                                duration=20.0, rate=500.0)) == OLD_CASES["every-style-scale"]
    assert matrix.cases() == matrix.cases(conditions=["plain"])
    assert all(c.condition == "plain" for c in matrix.cases(rows=["all"]))


def test_cases_cross_the_conditions() -> None:
    plain = matrix.cases(seeds=[1])
    conds = [c for c in matrix.CONDITIONS if c != "plain"]
    assert {"irregular-stamps", "gapped-stamps", "pink-noise", "vertical", "pulsation",
            "soft-presliding"} <= set(conds)
    every = matrix.cases(seeds=[1], conditions=matrix.CONDITIONS)
    assert [c for c in every if c.condition == "plain"] == plain
    for cond in ("irregular-stamps", "gapped-stamps", "pink-noise", "pulsation"):
        got = [c for c in every if c.condition == cond]
        assert [replace(c, condition="plain") for c in got] == plain
    vertical = [c for c in every if c.condition == "vertical"]
    assert 0 < len(plain) - len(vertical) == len(
        [c for c in plain if c.row == "inertia-error" and syn.STYLES[c.style].force != "load-cell"])
    soft = [c for c in every if c.condition == "soft-presliding"]
    assert {(c.row, c.kind) for c in soft} == {
        (r, k) for r, ks in matrix.SOFT_PRESLIDING_ROWS.items() for k in ks}
    assert all(c.kind == "dynamic" or "presliding" in c.row for c in soft)
    with pytest.raises(ValueError, match="unknown condition"):
        matrix.cases(conditions=["underwater"])


def test_two_effect_rows_from_a_dynamic_baseline() -> None:
    new = ("dwell-time+direction-asymmetry", "pressure-dependence+dwell-time")
    assert not set(new) & {c.row for c in matrix.cases(seeds=[1])}  # opt-in
    got = matrix.cases(seeds=[1], rows=list(new))
    assert got and {c.row for c in got} == set(new)
    assert {c.kind for c in got} == {"static", "dynamic"}
    for c in got:
        assert len(c.shape.split(",")) == 2
        if c.kind == "dynamic":
            assert c.base == c.baseline == "lugre"
        if c.row == "pressure-dependence+dwell-time":
            assert c.style != "drive-force"
    assert {c.row for c in matrix.cases(seeds=[1], rows=["all"])} == {r.name for r in matrix.ROWS}


def test_conditions_map_to_generator_arguments() -> None:
    base = matrix.cases(seeds=[3], rows=["nothing"], kinds=["dynamic"], styles=["pressures"],
                        scales=["pneumatic"], duration=8.0)[0]
    case = lambda cond: replace(base, condition=cond)  # noqa: E731
    plain = matrix.record(base)
    assert matrix.condition_args(base) == {}
    rec = matrix.record(case("irregular-stamps"))
    assert len(np.unique(np.round(np.diff(rec.measurement.t) * rec.truth.rate, 6))) >= 3
    rec = matrix.record(case("gapped-stamps"))
    assert np.max(np.diff(rec.measurement.t)) > 0.15
    rec = matrix.record(case("pink-noise"))
    assert rec.truth.sensors is not None and rec.truth.sensors.noise_color == "pink"
    rec = matrix.record(case("vertical"))
    assert rec.measurement.meta["rig"]["orientation"] == "vertical-up"  # odd seed
    assert matrix.condition_args(replace(case("vertical"), seed=4)) == {
        "orientation": "vertical-down"}
    # pulsation: a line on p1 of the drawn frequency, about twice the force noise
    rec = matrix.record(case("pulsation"))
    freq, ratio = matrix.pulsation_of(case("pulsation"))
    assert 23.0 <= freq <= 47.0 and 1.5 <= ratio <= 2.5
    wave = (rec.measurement["p1"] - plain.measurement["p1"]) * rec.truth.params.areas[0]
    assert np.max(np.abs(wave)) == pytest.approx(ratio * plain.truth.noise_std, rel=1e-3)
    spec = np.abs(np.fft.rfft(wave))
    fr = np.fft.rfftfreq(wave.size, 1.0 / rec.truth.rate)
    assert fr[np.argmax(spec)] == pytest.approx(freq, abs=0.2)
    assert np.array_equal(rec.truth.F, plain.truth.F)
    # soft presliding: the motion and a bristle of 1.0-2.5e4 N/m on the pneumatic rig
    rec = matrix.record(case("soft-presliding"))
    assert rec.truth.motion == "presliding"
    assert 1.0e4 <= rec.truth.params.sigma0 <= 2.5e4
    assert rec.truth.params.sigma0 == matrix.soft_bristle(case("soft-presliding"))


# ------------------------------------------------------------------ the judge
def _doc(added=(), verdict="explained", disturbances=(), rb=2.0, rf=0.5) -> dict:
    return {"added": list(added), "ties": [], "verdict": verdict, "reason": "",
            "rms_baseline": rb, "rms_final": rf,
            "disturbances": [{"frequency_hz": f, "amplitude": 0.8} for f in disturbances]}


def _case(row: str, condition: str) -> matrix.Case:
    c = matrix.cases(seeds=[2], rows=[row], styles=["load-cell"], scales=["pneumatic"],
                     conditions=[condition])
    return c[0]


def test_judge_wants_the_pulsation_and_an_unexplained_verdict() -> None:
    case = _case("dwell-time", "pulsation")
    f0 = matrix.pulsation_of(case)[0]
    ok, why = matrix.judge(case, _doc(["dwell-time"], "unexplained-structure", [f0 + 0.05]),
                           0.4)
    assert ok, why
    ok, why = matrix.judge(case, _doc(["dwell-time"], "explained", [f0]), 0.4)
    assert not ok and "verdict explained" in why
    ok, why = matrix.judge(case, _doc(["dwell-time"], "unexplained-structure", []), 0.4)
    assert not ok and "pulsation" in why and "not found" in why
    ok, why = matrix.judge(case, _doc(["dwell-time"], "unexplained-structure", [f0 + 0.3]), 0.4)
    assert not ok and "not found" in why
    ok, why = matrix.judge(case, _doc(["dwell-time", "viscous"], "unexplained-structure", [f0]),
                           0.4)
    assert not ok and "wrongly added viscous" in why  # the added set as for the row
    ok, why = matrix.judge(case, _doc([], "unexplained-structure", [f0]), 0.4)
    assert not ok and "dwell-time not found" in why
    ok, why = matrix.judge(case, _doc(["dwell-time"], "unexplained-structure", [f0], rf=1.9),
                           0.4)
    assert not ok and "held-out error" in why
    nothing = _case("nothing", "pulsation")
    f1 = matrix.pulsation_of(nothing)[0]
    assert matrix.judge(nothing, _doc([], "unexplained-structure", [f1]), 0.4)[0]
    drift = _case("drift", "pulsation")
    assert matrix.judge(drift, _doc([], "unexplained-structure", [f1]), 0.4)[0]


@pytest.mark.parametrize("condition", ["plain", "vertical", "pink-noise", "irregular-stamps"])
def test_judge_calls_any_disturbance_elsewhere_false(condition: str) -> None:
    case = _case("dwell-time", condition)
    assert matrix.judge(case, _doc(["dwell-time"]), 0.4)[0]
    ok, why = matrix.judge(case, _doc(["dwell-time"], disturbances=[31.7]), 0.4)
    assert not ok and "false disturbance at 31.70 Hz" in why
    ok, why = matrix.judge(case, _doc(["dwell-time"], "unexplained-structure", [31.7]), 0.4)
    assert not ok and "false disturbance" in why and "verdict" in why
    outside = _case("ripple", condition)
    assert matrix.judge(outside, _doc([], "unexplained-structure"), 0.4)[0]
    assert not matrix.judge(outside, _doc([], "unexplained-structure", [40.0]), 0.4)[0]
