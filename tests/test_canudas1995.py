"""The classical LuGre experiments of Canudas de Wit et al. (1995), checked independently.

Parameter set ``canudas1995`` (Table I of the paper, unit mass): sigma0 = 1e5
N/m, sigma1 = sqrt(1e5) Ns/m, sigma2 = 0.4 Ns/m, Fc = 1 N, Fs = 1.5 N,
vs = 1e-3 m/s, n = 2.

Every experiment is computed twice:

* with the package: its friction model's symbolic form
  (:meth:`casadi_functions`) driving the mass, integrated by SUNDIALS CVODES,
  or :func:`friction_along_motion` for a prescribed velocity;
* with ``reference_lugre`` -- a plain implementation written from the
  equations that does not import ``fcomp`` -- in SciPy's Radau at
  ``rtol = 1e-10``;

and the two must agree to tolerances that a wrong term cannot meet. The
qualitative results of the paper are then checked on top, quantified, some
against closed-form quasi-static predictions derived in the test.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import casadi as ca
import numpy as np
import pytest
from helpers import reference_lugre as ref

from fcomp.models import FrictionModel, make_model
from fcomp.trajectory import friction_along_motion

P_REF = ref.CANUDAS
MASS = 1.0  # kg, unit mass of the paper


@pytest.fixture(scope="module")
def lugre() -> FrictionModel:
    return make_model("lugre", params="canudas1995")


class PackageMass:
    """``m*x'' = u(t, x) - F`` with the package's friction model, integrated by SUNDIALS.

    The equations are the model's symbolic form (:meth:`FrictionModel.casadi_functions`,
    ``F = F0 + c_a*a`` solved for ``a``), integrated by CasADi's CVODES (BDF,
    ``reltol = 1e-12``): a different implementation *and* a different
    integrator from the Radau reference. (That the symbolic form equals the
    numeric one is tested in ``test_models.py``.) State ``[x, v, z]``.
    """

    def __init__(self, model: FrictionModel, mass: float = MASS) -> None:
        self.model, self.mass = model, mass
        self.fns = model.casadi_functions()

    def simulate(
        self,
        u: Callable[[ca.SX, ca.SX], ca.SX],
        t_eval: np.ndarray,
        *,
        breaks: Sequence[float] = (),
    ) -> np.ndarray:
        """States at ``t_eval`` (columns); ``u(t, x)`` the applied force as a CasADi expression.

        The integration restarts at ``breaks`` (kinks of ``u``).
        """
        y, t = ca.SX.sym("y", 2 + self.model.n_states), ca.SX.sym("t")
        x, v, zs = y[0], y[1], y[2:]
        s = ca.if_else(v >= 0, 1.0, -1.0)
        parts = self.fns["force_parts"](zs, ca.vertcat(v, 0.0, x, 0.0, 0.0, s))
        a = (u(t, x) - parts[0]) / (self.mass + parts[1])
        dz = self.fns["rhs"](zs, ca.vertcat(v, a, x, 0.0, 0.0, s))
        dae = {"x": y, "t": t, "ode": ca.vertcat(v, a, dz)}
        opts = {"reltol": 1e-12, "abstol": 1e-19, "max_num_steps": 10**7}
        edges = sorted({t_eval[0], t_eval[-1], *[b for b in breaks if t_eval[0] < b < t_eval[-1]]})
        out = np.empty((2 + self.model.n_states, t_eval.size))
        out[:, 0] = yk = np.array([0.0, 0.0, *self.model.initial_state()])
        for lo, hi in zip(edges[:-1], edges[1:], strict=True):
            idx = np.flatnonzero((t_eval > lo) & (t_eval <= hi))
            grid = [*t_eval[idx], hi] if t_eval[idx[-1]] < hi else list(t_eval[idx])
            integ = ca.integrator("mass", "cvodes", dae, float(lo), grid, opts)
            Y = np.asarray(integ(x0=yk)["xf"])
            out[:, idx] = Y[:, : idx.size]
            yk = Y[:, -1]
        return out

    def friction(self, Y: np.ndarray) -> np.ndarray:
        """Friction force (N) at the states ``Y`` (columns ``[x, v, z]``)."""
        x, v = Y[0], Y[1]
        sig = np.vstack([v, 0 * v, x, 0 * v, 0 * v, np.where(v >= 0, 1.0, -1.0)])
        return np.asarray(self.fns["force"](Y[2:], sig)).ravel()


def ref_friction(Y: np.ndarray) -> np.ndarray:
    return np.array([P_REF.friction(z, v) for v, z in zip(Y[1], Y[2], strict=True)])


# ------------------------------------------------------------ (a) stick-slip
K_SPRING, V_PULL = 2.0, 0.1  # N/m, m/s (the paper's stick-slip experiment)


@pytest.fixture(scope="module")
def stick_slip(lugre: FrictionModel) -> dict[str, np.ndarray]:
    t = np.linspace(0.0, 21.0, 4201)
    mass = PackageMass(lugre)
    pkg = mass.simulate(lambda t, x: K_SPRING * (V_PULL * t - x), t)
    rf = ref.stick_slip(P_REF, t, k=K_SPRING, vy=V_PULL, mass=MASS)
    return {"t": t, "pkg": pkg, "ref": rf.y, "F_pkg": mass.friction(pkg),
            "F_ref": ref_friction(rf.y)}


def test_stick_slip_matches_independent_integration(stick_slip: dict) -> None:
    d = np.abs(stick_slip["pkg"] - stick_slip["ref"]).max(axis=1)
    assert d[0] < 1e-8, f"position differs by {d[0]:.3g} m"
    assert d[1] < 1e-8, f"velocity differs by {d[1]:.3g} m/s"
    assert d[2] < 1e-12, f"bristle deflection differs by {d[2]:.3g} m"
    assert np.abs(stick_slip["F_pkg"] - stick_slip["F_ref"]).max() < 1e-6


def test_stick_slip_is_a_regular_limit_cycle(stick_slip: dict) -> None:
    """Stick phases (mass nearly at rest while the spring loads) alternate with slips.

    Each slip starts when the friction has risen close to Fs (break-away) and
    the cycle repeats with a constant period; on average the mass follows the
    spring end at 0.1 m/s.
    """
    t, (x, v, _) = stick_slip["t"], stick_slip["ref"]
    F = stick_slip["F_ref"]
    slipping = v > 0.05
    starts = t[1:][np.diff(slipping.astype(int)) == 1]
    assert len(starts) >= 3, "expected at least three slips in 20 s"
    periods = np.diff(starts)
    assert np.ptp(periods) < 1e-3 * periods.mean(), periods
    # during stick the mass creeps far slower than the spring end moves
    sticking = v < 1e-3
    assert sticking.mean() > 0.5
    # friction peaks at break-away between Fc and Fs, near Fs
    for t0 in starts:
        window = (t > t0 - 1.0) & (t < t0)
        assert 1.4 < F[window].max() < P_REF.Fs
    # mean velocity over whole cycles equals the pulling speed
    i0, i1 = np.searchsorted(t, starts[0]), np.searchsorted(t, starts[-1])
    mean_v = (x[i1] - x[i0]) / (t[i1] - t[i0])
    assert mean_v == pytest.approx(V_PULL, rel=2e-3)
    # the peak slip velocity exceeds the pulling speed (the mass overshoots)
    assert v.max() > 2 * V_PULL


# --------------------------------------------------- (b) pre-sliding displacement
F_MAX = 0.95 * P_REF.Fs  # N


#: applied force (N): 0 -> 0.95*Fs in 10 s, down to -0.95*Fs at 30 s, back up at 50 s
PRESLIDING_T = [0.0, 10.0, 30.0, 50.0]
PRESLIDING_U = [0.0, F_MAX, -F_MAX, F_MAX]


@pytest.fixture(scope="module")
def presliding(lugre: FrictionModel) -> dict[str, np.ndarray]:
    t = np.linspace(0.0, 50.0, 5001)
    breaks = (10.0, 30.0)
    pkg = PackageMass(lugre).simulate(
        lambda t, x: ca.pw_lin(t, PRESLIDING_T, PRESLIDING_U), t, breaks=breaks)
    rf = ref.mass_with_force(P_REF, lambda t, x: float(np.interp(t, PRESLIDING_T, PRESLIDING_U)),
                             t, mass=MASS, breaks=breaks)
    return {"t": t, "pkg": pkg, "ref": rf.y}


def test_presliding_matches_independent_integration(presliding: dict) -> None:
    d = np.abs(presliding["pkg"] - presliding["ref"]).max(axis=1)
    assert d[0] < 1e-12, f"displacement differs by {d[0]:.3g} m"  # x is ~5e-5 m
    assert d[2] < 1e-14, f"bristle deflection differs by {d[2]:.3g} m"


def test_presliding_displacement_is_micrometres_with_partial_return(presliding: dict) -> None:
    """Below break-away the mass moves micrometres, like a nonlinear spring with hysteresis.

    Quasi-static prediction (``v`` tiny, so ``g = Fs``; ``sigma1*dz/dt``,
    ``sigma2*v`` and ``m*a`` negligible, so ``sigma0*z = u``): from
    ``dz/dx = 1 - sign(v)*sigma0*z/Fs``,

    * loading from rest to ``u``: ``x = -(Fs/sigma0)*ln(1 - u/Fs)`` (44.9 um at 0.95*Fs),
    * unloading from ``u0`` to ``u``: ``dx = -(Fs/sigma0)*ln((1 + u0/Fs)/(1 + u/Fs))``,

    so after unloading to zero the mass has returned only 10.0 um of 44.9 um.
    """
    t, (x, _, _) = presliding["t"], presliding["ref"]
    L = P_REF.Fs / P_REF.sigma0  # m
    r = F_MAX / P_REF.Fs

    def at(tq: float) -> float:
        return float(x[np.searchsorted(t, tq)])

    x_load = -L * math.log(1.0 - r)
    x_zero = x_load - L * math.log(1.0 + r)
    x_neg = x_load - L * math.log((1.0 + r) / (1.0 - r))
    assert np.abs(x).max() < 60e-6, "pre-sliding must stay at micrometres"
    assert at(10.0) == pytest.approx(x_load, abs=0.5e-6)
    assert at(20.0) == pytest.approx(x_zero, abs=0.5e-6)  # u back to 0
    assert at(30.0) == pytest.approx(x_neg, abs=0.5e-6)
    # partial return: unloading to zero force leaves most of the displacement
    assert 0.7 * at(10.0) < at(20.0) < 0.85 * at(10.0)
    # the displacement-force loop closes: same state after a full symmetric cycle
    assert at(50.0) == pytest.approx(at(10.0), abs=1e-10)


# ------------------------------------------------------------ (c) friction lag
OMEGAS = (1.0, 10.0, 25.0)  # rad/s, the paper's frequencies


def _lag_velocity(w: float) -> Callable[[float], float]:
    """``v = 1e-3*(1.5 + cos(w*t))`` m/s: sinusoidal around 1.5 mm/s, never reversing."""
    return lambda t: 1e-3 * (1.5 + math.cos(w * t))


@pytest.fixture(scope="module")
def friction_lag(lugre: FrictionModel) -> dict[float, dict[str, np.ndarray]]:
    out = {}
    for w in OMEGAS:
        period = 2 * math.pi / w
        t = np.linspace(0.0, 2 * period, int(round(2 * period * 10_000)) + 1)  # 10 kHz
        v = 1e-3 * (1.5 + np.cos(w * t))
        a = -1e-3 * w * np.sin(w * t)
        z0 = P_REF.g(v[0]) / P_REF.sigma0  # start on the steady state of the initial speed
        run = friction_along_motion(lugre, t, v, a=a, state0=np.array([z0]))
        rf = ref.along_velocity(P_REF, _lag_velocity(w), t, y0=(z0,))
        F_ref = np.array([P_REF.friction(z, vv) for z, vv in zip(rf.y[0], v, strict=True)])
        out[w] = {"t": t, "v": v, "F": run.F, "F_ref": F_ref, "last": t >= period}
    return out


def test_friction_lag_matches_independent_integration(friction_lag: dict) -> None:
    # friction_along_motion holds v at interval means: error O(dt^2), 4e-7 N at 10 kHz, 25 rad/s
    for w, r in friction_lag.items():
        err = np.abs(r["F"] - r["F_ref"]).max()
        assert err < 1e-6, f"{w} rad/s: friction differs by {err:.3g} N"


def test_friction_lag_loop_widens_with_frequency(friction_lag: dict) -> None:
    """Hysteresis in F-v (Hess & Soom; Canudas et al. 1995): the loop opens as frequency rises.

    Measured by the loop area ``|oint F dv|`` (W/m... N*m/s) over the last period
    and by the largest departure from the steady-state curve.
    """
    areas, departures = [], []
    for r in friction_lag.values():
        last = r["last"]
        areas.append(abs(np.trapezoid(r["F"][last], r["v"][last])))
        F_ss = np.array([P_REF.steady(v) for v in r["v"][last]])
        departures.append(np.abs(r["F"][last] - F_ss).max())
    assert areas[0] < areas[1] < areas[2]
    assert departures[0] < departures[1] < departures[2]
    assert departures[0] < 0.01  # 1 rad/s: close to the steady-state curve
    assert departures[2] > 0.05  # 25 rad/s: clearly off it (about 0.09 N)
    # the force is lower while accelerating than while decelerating at the same speed
    r = friction_lag[25.0]
    last, t, v, F = r["last"], r["t"], r["v"], r["F"]
    w = 25.0
    accelerating = last & (np.sin(w * t) < 0)
    decelerating = last & (np.sin(w * t) > 0)
    probe = 1.5e-3
    F_up = np.interp(probe, v[accelerating][np.argsort(v[accelerating])],
                     F[accelerating][np.argsort(v[accelerating])])
    F_down = np.interp(probe, v[decelerating][np.argsort(v[decelerating])],
                       F[decelerating][np.argsort(v[decelerating])])
    assert F_up > F_down


# ---------------------------------------------------- (d) break-away vs force rate
RATES = (0.3, 1.0, 3.0, 10.0, 30.0)  # N/s


def _break_away(t: np.ndarray, F: np.ndarray) -> float:
    """Friction force at its first maximum: the mass starts to slide (N).

    The paper determines break-away where the velocity rises sharply; the
    friction force then drops along the Stribeck curve, so its first maximum
    is the break-away force. Located on the sample grid and refined by the
    parabola through the three samples around it.
    """
    k = int(np.flatnonzero(np.diff(F) < 0)[0])
    f0, f1, f2 = F[k - 1], F[k], F[k + 1]
    return float(f1 + (f2 - f0) ** 2 / (8.0 * (2.0 * f1 - f0 - f2)))


def _ramp(rate: float, t: Any, x: Any) -> Any:
    """Applied force ``rate*t`` (N), for floats and CasADi symbols."""
    return rate * t


@pytest.fixture(scope="module")
def break_away(lugre: FrictionModel) -> dict[str, list[float]]:
    mass = PackageMass(lugre)
    out: dict[str, list[float]] = {"pkg": [], "ref": []}
    for rate in RATES:
        t = np.linspace(0.0, 1.6 * P_REF.Fs / rate, 3001)
        pkg = mass.simulate(partial(_ramp, rate), t)
        rf = ref.mass_with_force(P_REF, partial(_ramp, rate), t, mass=MASS)
        out["pkg"].append(_break_away(t, mass.friction(pkg)))
        out["ref"].append(_break_away(t, ref_friction(rf.y)))
    return out


def test_break_away_matches_independent_integration(break_away: dict) -> None:
    np.testing.assert_allclose(break_away["pkg"], break_away["ref"], rtol=0, atol=1e-7)


def test_break_away_force_falls_with_force_rate(break_away: dict) -> None:
    """The paper's result: the faster the applied force rises, the lower the break-away force.

    Quantified for the unit mass: from about Fs (1.47 N at 0.3 N/s) down to
    about Fc (1.02 N at 30 N/s), strictly decreasing in between.
    """
    F = np.asarray(break_away["ref"])
    assert np.all(np.diff(F) < 0), F
    assert F[0] == pytest.approx(1.469, abs=5e-3)
    assert F[-1] == pytest.approx(1.024, abs=5e-3)
    assert P_REF.Fc < F.min() and F.max() < P_REF.Fs
