"""Friction-force reconstruction (seed 000 Eq. 1): filters, derivatives, known forces.

The reference values are computed here independently of the package: motions
are analytic multi-sines with analytic derivatives, the friction a plain
formula, and the pressures solved from Eq. 1 by hand before sensor noise and
quantisation are added.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.ndimage import minimum_filter1d

from fcomp.errors import FcompError
from fcomp.measurement import Measurement
from fcomp.reconstruction import (
    derivatives,
    differentiate,
    reconstruct_friction,
    zero_phase_lowpass,
)

G = 9.80665
P_ATM = 101325.0
COMPONENTS = ((0.04, 0.5), (0.01, 1.7))  # (amplitude m, frequency Hz)


def _motion(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    w = [(A, 2 * np.pi * f) for A, f in COMPONENTS]
    x = 0.1 + sum(A * np.sin(om * t) for A, om in w)
    v = sum(A * om * np.cos(om * t) for A, om in w)
    a = sum(-A * om**2 * np.sin(om * t) for A, om in w)
    return np.asarray(x), np.asarray(v), np.asarray(a)


def _friction(v: np.ndarray) -> np.ndarray:
    """Coulomb + Stribeck bump + viscous, smooth at v = 0 (N)."""
    return 300 * np.tanh(v / 0.002) + 150 * np.exp(-((v / 0.01) ** 2)) * np.tanh(v / 0.002) + 1500 * v


class _Rig:
    """A vertical hydraulic cylinder with a known friction force, measured with noise."""

    m, bore, rod = 25.0, 0.05, 0.025
    sp, sx, q, sf = 2000.0, 0.5e-6, 1e-6, 1.0  # Pa, m, m (encoder step), N

    def __init__(self, seed: int = 1, fs: float = 1000.0, duration: float = 6.0) -> None:
        rng = np.random.default_rng(seed)
        self.t = t = np.arange(0.0, duration, 1.0 / fs)
        self.x, self.v, self.a = _motion(t)
        self.A1 = math.pi / 4 * self.bore**2
        self.A2 = math.pi / 4 * (self.bore**2 - self.rod**2)
        self.F = _friction(self.v)
        self.F_ext = -400 - 200 * np.sin(2 * np.pi * 0.3 * t)
        p2 = 30e5 + 5e5 * np.sin(2 * np.pi * 0.8 * t)
        # Eq. 1 solved for p1 (vertical-up: s = +1)
        p1 = (self.F + self.m * self.a + self.m * G - self.F_ext + p2 * self.A2) / self.A1
        n1, n2 = self.sp * rng.standard_normal(t.size), self.sp * rng.standard_normal(t.size)
        nf = self.sf * rng.standard_normal(t.size)
        xm = np.round((self.x + self.sx * rng.standard_normal(t.size)) / self.q) * self.q
        self.noise_force = n1 * self.A1 - n2 * self.A2 + nf
        self.meas = Measurement(
            {"t": t, "x": xm, "p1": p1 + P_ATM + n1, "p2": p2 + P_ATM + n2, "F_ext": self.F_ext + nf},
            {"pressure": "absolute",
             "rig": {"bore": self.bore, "rod": self.rod, "mass": self.m,
                     "orientation": "vertical-up"}},
        )
        self.inner = (t > 0.5) & (t < t[-1] - 0.5)


@pytest.fixture(scope="module")
def rig() -> _Rig:
    return _Rig()


def _rms(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(e**2)))


def test_known_force_is_recovered_up_to_the_sensor_noise(rig: _Rig) -> None:
    out = reconstruct_friction(rig.meas)  # 10 Hz, order 2, pressures unfiltered
    err = out["F"] - rig.F
    noise = math.hypot(rig.sp * rig.A1, rig.sp * rig.A2, rig.sf)  # 5.0 N predicted
    assert _rms(err[rig.inner]) < 1.05 * noise
    # Take away the injected sensor noise: what is left is the inertia term m*(a_est - a),
    # which must be tiny for a 10 Hz filter on 0.5/1.7 Hz motion (stated: < 0.1 N rms).
    left = err - rig.noise_force
    assert _rms(left[rig.inner]) < 0.1
    assert np.max(np.abs(left[rig.inner])) < 0.2
    assert _rms(out["v"][rig.inner] - rig.v[rig.inner]) < 1e-4
    assert _rms(out["a"][rig.inner] - rig.a[rig.inner]) < 5e-3
    assert out.meta["reconstruction"]["mass"] == rig.m
    assert out.meta["reconstruction"]["resampled"] is False


def test_seed000_first_order_filter_is_slightly_worse_but_close(rig: _Rig) -> None:
    out = reconstruct_friction(rig.meas, order=1)
    left = out["F"] - rig.F - rig.noise_force
    # First order forward-backward: -40 dB/dec against +40 dB/dec of double differentiation.
    assert 0.1 < _rms(left[rig.inner]) < 2.0


def test_filtering_the_forces_removes_noise_away_from_reversals(rig: _Rig) -> None:
    out = reconstruct_friction(rig.meas, filter_forces=True)
    far = minimum_filter1d(np.abs(rig.v), size=201) > 0.05  # 0.1 s from any |v| < 0.05 m/s
    mask = rig.inner & far
    assert mask.sum() > 500
    assert _rms(out["F"][mask] - rig.F[mask]) < 1.0  # from 5 N of raw sensor noise
    assert out.meta["reconstruction"]["filter_forces"] is True


def test_gauge_horizontal_and_absolute_give_the_same_friction(rig: _Rig) -> None:
    cols = dict(rig.meas.columns)
    cols["p1"] = cols["p1"] - P_ATM
    cols["p2"] = cols["p2"] - P_ATM
    gauge = Measurement(cols, {"pressure": "gauge", "rig": dict(rig.meas.rig)})
    a = reconstruct_friction(gauge)["F"]
    b = reconstruct_friction(rig.meas)["F"]
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-6)
    horiz = Measurement(cols, {"rig": {**rig.meas.rig, "orientation": "horizontal"}})
    np.testing.assert_allclose(reconstruct_friction(horiz)["F"] - a, rig.m * G, atol=1e-6)
    down = Measurement(cols, {"rig": {**rig.meas.rig, "orientation": "vertical-down"}})
    np.testing.assert_allclose(reconstruct_friction(down)["F"] - a, 2 * rig.m * G, atol=1e-6)


def test_derivatives_of_a_sine_are_exact_in_the_interior() -> None:
    t = np.arange(0.0, 5.0, 1e-3)
    x, v, a = _motion(t)
    meas = Measurement({"t": t, "x": x}, {})
    ve, ae = derivatives(meas)
    inner = (t > 0.5) & (t < 4.5)
    # 2nd-order Butterworth twice at 10 Hz: gain 1 - (1.7/10)^4 ~ 0.9992 at 1.7 Hz
    assert np.max(np.abs(ve - v)[inner]) < 2e-3 * np.max(np.abs(v))
    assert np.max(np.abs(ae - a)[inner]) < 2e-3 * np.max(np.abs(a))


def test_non_uniform_time_is_resampled_and_mapped_back() -> None:
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.005, 0.015, 800))
    t -= t[0]
    x, v, a = _motion(t)
    xf, ve, ae = differentiate(t, x)
    assert xf.shape == ve.shape == ae.shape == t.shape
    inner = (t > 0.5) & (t < t[-1] - 0.5)
    assert np.max(np.abs(ve - v)[inner]) < 0.01 * np.max(np.abs(v))
    assert np.max(np.abs(ae - a)[inner]) < 0.03 * np.max(np.abs(a))
    meas = Measurement({"t": t, "x": x, "F_ext": np.zeros_like(t)}, {"rig": {"mass": 1.0}})
    assert reconstruct_friction(meas).meta["reconstruction"]["resampled"] is True


def test_the_filter_has_zero_phase_and_the_butterworth_gain() -> None:
    fs, fc = 1000.0, 10.0
    t = np.arange(0.0, 4.0, 1 / fs)
    for order in (1, 2, 3):
        y = zero_phase_lowpass(np.sin(2 * np.pi * fc * t), fs, fc, order)
        inner = (t > 1.0) & (t < 3.0)
        basis = np.column_stack([np.sin(2 * np.pi * fc * t), np.cos(2 * np.pi * fc * t)])[inner]
        (s, c), *_ = np.linalg.lstsq(basis, y[inner], rcond=None)
        assert abs(c) < 1e-3           # no phase shift
        assert abs(s - 0.5) < 2e-3     # |H(fc)|^2 = 1/2 for every Butterworth order


def test_emps_real_data_reproduce_the_published_rigid_model() -> None:
    """Least squares on the reconstructed EMPS motion vs the benchmark's own IDIM-LS.

    Reference (Janot et al. 2019; values in the benchmark's Simulation_EMPS.m, obtained
    with a 4th-order 100 Hz Butterworth filtfilt, central differences and decimation):
    M = 95.1089 kg, Fv = 203.5034 N s/m, Fc = 20.3935 N, offset = -3.1648 N.
    """
    from fcomp import datasets

    meas = datasets.load("emps", "DATA_EMPS.mat")
    v, a = derivatives(meas, cutoff_hz=80.0, order=2)
    X = np.column_stack([a, v, np.sign(v), np.ones_like(v)])
    (mass, viscous, coulomb, off), *_ = np.linalg.lstsq(X, meas["F_ext"], rcond=None)
    assert mass == pytest.approx(95.1089, rel=0.03)
    assert viscous == pytest.approx(203.5034, rel=0.03)
    assert coulomb == pytest.approx(20.3935, rel=0.03)
    assert off == pytest.approx(-3.1648, abs=0.3)


def test_zillen_friction_is_dissipative_and_grows_with_pressure() -> None:
    """Real seal friction: positive mean power F*v (the sign convention) and larger at 7 bar."""
    from fcomp import datasets

    levels = []
    for bar in (1, 7):
        out = reconstruct_friction(datasets.load("zillen", f"O-ring_{bar}bar.csv"), mass=0.0)
        F, v = out["F"], out["v"]
        assert np.mean(F * v) > 0
        moving = np.abs(v) > 0.003
        assert np.mean(np.sign(F[moving]) == np.sign(v[moving])) > 0.8
        levels.append(np.mean(np.abs(F[moving])))
    assert levels[1] > 1.5 * levels[0]


def _simple(**meta_rig: float) -> Measurement:
    t = np.linspace(0.0, 1.0, 200)
    return Measurement({"t": t, "x": 0.01 * np.sin(t), "p1": 2e5 + 0 * t, "p2": 1e5 + 0 * t},
                       {"name": "run", "rig": dict(meta_rig)})


@pytest.mark.parametrize(
    ("meas", "kwargs", "message"),
    [
        (_simple(bore=0.05, rod=0.02), {}, "rig.mass is missing"),
        (_simple(bore=0.05, mass=1.0), {}, "rig.rod is missing"),
        (_simple(rod=0.02, mass=1.0), {}, "rig.bore is missing"),
        (_simple(bore=0.05, rod=0.02, mass=1.0), {"cutoff_hz": 150.0}, "below half the sample rate"),
        (_simple(bore=0.05, rod=0.02, mass=1.0), {"order": 0}, "order must be a positive integer"),
        (_simple(bore=0.05, rod=0.02), {"mass": -1.0}, "mass must be a non-negative"),
        (Measurement({"t": [0.0, 1.0, 2.0], "p1": [1e5, 1e5, 1e5]}, {"name": "run"}), {"mass": 1.0},
         "needs the position column 'x'"),
        (Measurement({"t": [0.0, 1.0, 2.0], "x": [0.0, 0.1, 0.2]}, {"name": "run"}), {"mass": 1.0},
         "no force to reconstruct friction from"),
    ],
)
def test_bad_input_names_the_problem(meas: Measurement, kwargs: dict, message: str) -> None:
    with pytest.raises(FcompError, match=message) as info:
        reconstruct_friction(meas, **kwargs)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("order,stamps", [(1, "uniform"), (2, "irregular"), (3, "irregular")])
def test_band_limit_is_scipys_filter_on_the_interpolated_grid(order: int, stamps: str) -> None:
    """The column filter of a fit (its own odd extension, initial conditions computed once
    per design, sparse interpolation maps) against an independent computation: ``np.interp``
    onto the grid of the median interval, ``scipy.signal.sosfiltfilt`` per column, and
    ``np.interp`` back; one signal and several columns alike."""
    from scipy.signal import butter, sosfiltfilt

    from fcomp.reconstruction import band_limit

    rng = np.random.default_rng(order)
    dt = 1e-2 * (rng.choice([0.5, 1.0, 1.5], 3000) if stamps == "irregular" else np.ones(3000))
    t = np.concatenate([[0.0], np.cumsum(dt)])
    y = np.cumsum(rng.standard_normal((t.size, 4)), axis=0)
    h = float(np.median(np.diff(t)))
    grid = t[0] + h * np.arange(int(math.floor((t[-1] - t[0]) / h + 1e-9)) + 1)
    fs = (grid.size - 1) / (grid[-1] - grid[0])
    sos = butter(order, 7.0, fs=fs, output="sos")
    pad = min(grid.size - 1, int(math.ceil(3.0 * fs / 7.0)))
    want = np.column_stack([
        np.interp(t, grid, sosfiltfilt(sos, np.interp(grid, t, y[:, j]), padtype="odd",
                                       padlen=pad)) for j in range(y.shape[1])])
    got = band_limit(t, y, 7.0, order=order)
    assert got.shape == y.shape
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * np.abs(y).max())
    np.testing.assert_allclose(band_limit(t, y[:, 2].copy(), 7.0, order=order), want[:, 2],
                               rtol=0, atol=1e-9 * np.abs(y).max())


@pytest.mark.parametrize("path", ["default", "scipy"])
def test_zero_phase_filter_is_scipys_to_the_bit(path: str, monkeypatch: pytest.MonkeyPatch
                                                ) -> None:
    """The fits' zero-phase filter gives ``scipy.signal.sosfiltfilt``'s bits on both of its
    paths: the default one (the compiled C where a C compiler is at hand -- asserted to be
    taken then) and the one without a compiler (two ``sosfilt`` calls); orders 1-5, one
    signal or columns, padding from none to ``n - 1`` samples, a strided view, the shortest
    signal the filter takes."""
    from scipy.signal import sosfiltfilt

    from fcomp import reconstruction
    from fcomp.compiled import compiler

    if path == "scipy":
        monkeypatch.setattr(reconstruction, "_native_filtfilt", lambda: None)
    elif compiler() is not None:
        assert reconstruction._native_filtfilt() is not None, "a compiler, yet no C filter"
    rng = np.random.default_rng(5)
    for order in (1, 2, 3, 4, 5):
        sos = reconstruction._butterworth(order, 7.0, 100.0)
        for n, k, pad in [(4000, 13, 43), (3, 2, 2), (200, 3, 199), (500, 1, 0), (9, 1, 8)]:
            x = rng.standard_normal((n, 2 * k))[:, ::2]  # a strided view
            for arr in (x, x[:, 0]):
                want = sosfiltfilt(sos, arr, axis=0, padtype="odd", padlen=pad)
                got = reconstruction._filtfilt(order, 7.0, 100.0, arr, pad)
                assert got.shape == want.shape
                assert np.array_equal(got, want), (order, n, k, pad, arr.ndim)
