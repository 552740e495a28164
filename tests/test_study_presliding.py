"""Study ``presliding`` (seed 000 on the pre-sliding rig): programmes, measures, physics, summary.

Independent references: the Dahl model's minor-loop drift in closed form,
the area of seed 000's Table 3 loop by brute-force quadrature of Eq. 13,
and (in the summary) the rig with the memory coupled to its engine against the plant engine.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers.browser import study_summary

from fcomp.models import make_model
from studies import presliding_analysis as analysis
from studies import presliding_runs as runs

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("site")]  # builds the study site or runs long diagnoses


@pytest.fixture(scope="module")
def summary() -> dict:
    return study_summary("presliding")


def test_programme_reaches_its_waypoints() -> None:
    prog = runs.programme("fig9", 0.02e6, 0.016e6)
    t = np.concatenate([[0.0], np.cumsum([w[0] for w in prog.waypoints])])
    P = prog.pressures(t)
    assert np.allclose(P[1:], [[w[1], w[2]] for w in prog.waypoints])
    fine = prog.pressures(np.linspace(0, prog.duration, 20001))
    assert fine.min() >= 0 and fine[:, 0].max() == pytest.approx(0.02e6)
    assert np.max(np.abs(np.diff(fine, axis=0))) < 0.02e6 * 0.01  # continuous ramps
    with pytest.raises(Exception, match="programme"):
        runs.programme("fig99", 1.0)


def _dahl_gaps(Fc: float, s0: float) -> list[float]:
    """Closing gaps of the memory protocol for the Dahl model, in closed form.

    On a monotone move in direction s, dz/dx = 1 - s*sigma0*z/Fc, so
    z(x) = s*Fc/sigma0 + (z0 - s*Fc/sigma0)*exp(-sigma0*|x - x0|/Fc).
    """
    pts, _ = analysis.memory_paths()
    z, zs = 0.0, [0.0]
    for a, b in zip(pts[:-1], pts[1:], strict=True):
        s = math.copysign(1.0, b - a)
        zinf = s * Fc / s0
        z = zinf + (z - zinf) * math.exp(-s0 * abs(b - a) / Fc)
        zs.append(z)
    return [s0 * abs(zs[6] - zs[4]), s0 * abs(zs[10] - zs[8])]


def test_memory_measure_against_closed_form_dahl() -> None:
    Fc, s0 = 5.0, 1.5e4
    dahl = make_model("dahl", params={"Fc": Fc, "sigma0": s0, "sigma2": 0.0})
    got = analysis.memory_properties(dahl)
    want = _dahl_gaps(Fc, s0)
    assert got["closing_gaps"] == pytest.approx(want, rel=2e-3, abs=1e-5)
    assert min(want) > 0.01  # Dahl's minor loops do not close ...
    assert not got["minor_loops_closed"]  # ... and the measure says so


def test_table3_area_against_quadrature() -> None:
    v = runs.new_model(1).flat_params()
    c = [v["c1"], v["c2"], v["c3"]]
    k = [v["k1"], v["k2"], v["k3"]]
    z1, z2, z3, z4, z5 = (v[f"z{i}"] for i in range(1, 6))

    def chain(u: np.ndarray, bounds: list[float]) -> np.ndarray:
        """Eq. 13 segments one after the other, each from where the last ended."""
        out = np.zeros_like(u)
        level = 0.0
        for ci, ki, lo, hi in zip(c, k, bounds[:-1], bounds[1:], strict=True):
            inside = (u >= lo) & (u <= hi)
            out[inside] = level + ci * (1 - np.exp(-ki * (u[inside] - lo)))
            level += ci * (1 - math.exp(-ki * (hi - lo)))
        return out

    z = np.linspace(-z1, z5, 400001)
    up = chain(z + z1, [0.0, z1, z1 + z3, z1 + z5])                    # from (-z1, 0)
    top = up[-1]
    down = top - chain(z5 - z, [0.0, z5 - z4, z5 - z2, z5 + z1])       # from (z5, top)
    area = np.trapezoid(up - down, z)
    assert analysis.table3_loop_area(v) == pytest.approx(area, rel=1e-6)
    assert area > 0


def test_summary_contract(summary: dict) -> None:
    for key in ("nmlgm", "nmlgm-hysteresis"):
        e = summary[key]
        assert isinstance(e["minor_loops_closed"], bool)
        assert isinstance(e["wiping_out"], bool)
        assert isinstance(e["loop_area_error"], float) and math.isfinite(e["loop_area_error"])
    ls = summary["loop_size_vs_pressure"]
    assert len(ls) >= 3 and all(len(row) == 2 for row in ls)
    assert [row[0] for row in ls] == sorted(row[0] for row in ls)


def test_cosimulation_reproduces_the_plant_engine(summary: dict) -> None:
    """No-op hysteresis function = NMLGM: the coupled memory and the RODAS4 plant run agree."""
    assert summary["engine_check"]["relative"] < 1e-3


def test_nonlocal_memory_findings(summary: dict) -> None:
    n, h = summary["nmlgm"], summary["nmlgm-hysteresis"]
    assert h["minor_loops_closed"] and not n["minor_loops_closed"]
    assert max(h["closing_gaps_relative"]) < 0.1 * min(n["closing_gaps_relative"])
    # the NMLGM, driven by the reference's velocity, misses the friction work clearly
    assert abs(n["loop_area_error"]) > 0.05 > abs(h["loop_area_error"])


def test_loop_grows_with_pressure(summary: dict) -> None:
    """Seed 000 conclusion iii (Fig. 12): the loop is larger at higher pressure."""
    sizes = [row[1] for row in summary["loop_size_vs_pressure"]]
    assert all(b > a > 0 for a, b in zip(sizes[:-1], sizes[1:], strict=True))
