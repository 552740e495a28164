"""Study ``friction-models`` (seed 002 on the hydraulic plant): measures, physics, summary.

The high-frequency measure is checked against signals whose answer is known
analytically; the summary (from the shared ``fcomp study all --fast`` run)
against its contract and against the physics it reports.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers.browser import study_summary

from studies import friction_models as fm

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("site")]  # builds the study site or runs long diagnoses

FIELDS = ("hf_velocity_rms", "hf_force_rms", "hf_pressure_rms")


@pytest.fixture(scope="module")
def summary() -> dict:
    return study_summary("friction-models")


def test_hf_rms_keeps_the_high_and_rejects_the_low() -> None:
    rate = 4000.0
    t = np.arange(0, 4.0, 1 / rate)
    low = 3.0 * np.sin(2 * np.pi * 1.0 * t) + 0.7  # the input frequency and an offset
    high = 0.05 * np.sin(2 * np.pi * 40.0 * t)     # 40 Hz, well above the 10 Hz cutoff
    got = fm.hf_rms(low + high, rate)
    assert got == pytest.approx(0.05 / math.sqrt(2), rel=0.01)   # RMS of a sine: A/sqrt(2)
    assert fm.hf_rms(low, rate) < 0.003 * 3.0                    # 4th order at a decade: -80 dB
    assert fm.dominant_frequency(low + high, rate) == pytest.approx(40.0, abs=1.0)


def test_hf_rms_refuses_a_cutoff_above_nyquist() -> None:
    from fcomp.errors import FcompError

    with pytest.raises(FcompError, match="Nyquist"):
        fm.hf_rms(np.zeros(100), 10.0, cutoff=20.0)


def test_claim_rule() -> None:
    a = {"hf_velocity_rms": 2.0, "hf_force_rms": 4.0, "hf_pressure_rms": 2.0}
    b = {"hf_velocity_rms": 1.0, "hf_force_rms": 1.0, "hf_pressure_rms": 1.0}
    assert fm.claim_holds(a, b)
    assert not fm.claim_holds({**a, "hf_pressure_rms": 1.9}, b)  # every signal must show it
    assert fm.ratios(a, b) == {"velocity": 2.0, "force": 4.0, "pressure": 2.0}


def test_oil_column_stiffness_from_the_parameter_set() -> None:
    """k_h = beta*(A1^2/V1 + A2^2/V2) at mid-stroke, from the TOML numbers written out here."""
    plant = fm.hydraulic_plant("lugre")
    beta, V0, D, d, L, m = 1e8, 5e-6, 0.030, 0.016, 0.3, 118.0  # seed002-type1
    A1, A2 = math.pi / 4 * D**2, math.pi / 4 * (D**2 - d**2)
    kh = beta * (A1**2 / (V0 + A1 * L / 2) + A2**2 / (V0 + A2 * L / 2))
    assert fm.oil_column_stiffness(plant) == pytest.approx(kh, rel=1e-12)
    modes = fm.modes(plant)
    assert modes["oil_column_hz"] == pytest.approx(math.sqrt(kh / m) / (2 * math.pi), rel=1e-12)
    assert modes["dissipative_below"] == pytest.approx(4 * 120.0 / 300.0)  # 4 Fc/sigma1


def test_summary_contract(summary: dict) -> None:
    assert set(summary["models"]) == {"steady-state", "lugre", "nmlgm"}
    for entry in summary["models"].values():
        assert set(entry) == set(FIELDS)
        assert all(isinstance(entry[f], float) and entry[f] > 0 for f in FIELDS)
    assert isinstance(summary["claim_reproduced"], bool)
    assert isinstance(summary["sweep"], list) and summary["sweep"]
    for row in summary["sweep"]:
        assert {"sigma0", "sigma1", "claim_holds", "ratio_to_nmlgm", *FIELDS} <= set(row)


def test_claim_verdict_follows_from_the_numbers(summary: dict) -> None:
    m = summary["models"]
    assert summary["claim_reproduced"] == fm.claim_holds(m["lugre"], m["nmlgm"])
    for row in summary["sweep"]:
        assert row["claim_holds"] == fm.claim_holds(row, m["nmlgm"])


def test_paper_case_resembles_the_measurement(summary: dict) -> None:
    """Seed 002 Fig. 5: velocity between about -0.14 and +0.14 m/s (geometry assumed for it)."""
    lo, hi = summary["paper_case"]["velocity_range"]
    assert -0.18 < lo < -0.10 and 0.10 < hi < 0.18


def test_ringing_is_the_oil_column_mode(summary: dict) -> None:
    f_h = summary["physics"]["oil_column_hz"]
    for key in ("steady-state", "lugre", "nmlgm"):
        f = summary["paper_case"]["details"][key]["dominant_hz"]
        assert f == pytest.approx(f_h, rel=0.2), key


def test_large_bristle_damping_spikes_the_friction(summary: dict) -> None:
    """Where the claim holds, LuGre's friction peaks above Fs (the sigma1*dz/dt spike)."""
    fs = summary["parameters"]["lugre"]["Fs"]
    holds = [r for r in summary["sweep"] if r["claim_holds"]]
    calm = [r for r in summary["sweep"] if not r["claim_holds"]]
    assert holds and calm, "the fast sweep spans both outcomes"
    assert min(r["peak_force"] for r in holds) > 1.3 * fs
    assert max(r["sigma1"] for r in calm) < min(r["sigma1"] for r in holds)
