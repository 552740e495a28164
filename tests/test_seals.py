"""Real seals read as an expert reads them (issue 43): the parts, fast.

* answers invariant to file names, file order and a near-duplicate record: the data a
  diagnosis works on and its held-out split are the same to the bit;
* the record's design: which factors the TU Delft records vary together;
* the band the motion is derived in keeps the force's transitions at the reversals;
* measurement terms apart from the friction (``area-error``), values the record does not
  determine flagged in the model file, standard errors written;
* the pressure law's forms, their values against an independent computation, and their
  round trip through the model file;
* the advice: no experiment the record already holds, no option the command lacks;
* the seal structures named (creep over strokes, an end zone, a ripple along the bore)
  on a residual whose structures are known;
* the pair search's choice of candidates, and held parameters that stay held.

The long diagnoses of the shipped records are in ``tests/test_seals_records.py``.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from fcomp import datasets
from fcomp.conditioning.events import event_band, transition_times
from fcomp.diagnosis.advice import reword
from fcomp.diagnosis.data import DiagnosisData, prepare
from fcomp.diagnosis.design import record_design
from fcomp.diagnosis.pairs import pairs_of, promising
from fcomp.diagnosis.regimes import segment
from fcomp.diagnosis.rule import AcceptanceRule, Failure, Judgement
from fcomp.diagnosis.seal_structures import seal_structures
from fcomp.diagnosis.split import make_split
from fcomp.effects import make_effect
from fcomp.errors import FcompWarning
from fcomp.identification.plausibility import FitWarning
from fcomp.measurement import Measurement
from fcomp.modelfile import load_model, read_model
from fcomp.models import make_model
from fcomp.reconstruction import zero_phase_lowpass

ORING = [f"O-ring_{k}bar.csv" for k in (1, 3, 5, 7)]


def _records(names: list[str]) -> list[Measurement]:
    return [datasets.load("zillen", n) for n in names]


def _renamed(meas: Measurement, name: str) -> Measurement:
    """The same record under another name (its sidecar's name and source file too)."""
    out = meas.with_columns()
    out.meta["name"] = name
    if isinstance(out.meta.get("source"), dict):
        out.meta["source"] = {**out.meta["source"], "file": f"{name}.csv"}
    return out


def _split(data: DiagnosisData) -> tuple[np.ndarray, np.ndarray]:
    sp = make_split(data, segment(data).valid)
    return sp.train, sp.test


# ------------------------------------------------------------------- invariance
def test_renamed_and_reordered_records_give_the_same_data_and_split() -> None:
    """The order files are named in and their names are no information: every signal,
    the force to match and the held-out split are the same to the bit."""
    recs = _records(ORING)
    one = prepare(recs)
    names = ["zz", "a", "m7", "b1"]  # sorts the files in another order than their names did
    two = prepare([_renamed(r, n) for r, n in zip(recs[::-1], names, strict=True)])
    for k in ("t", "x", "v", "a", "p1", "p2"):
        np.testing.assert_array_equal(one.signal(k), two.signal(k))
    np.testing.assert_array_equal(one.y, two.y)
    for a, b in zip(_split(one), _split(two), strict=True):
        np.testing.assert_array_equal(a, b)


def test_an_added_record_leaves_every_other_experiments_split_alone() -> None:
    """Each experiment's held-out blocks are its own (its duration and content): adding a
    near-duplicate of one file (the same record, its force 0.1 % higher) changes no block
    of the others."""
    recs = _records(ORING)
    near = recs[2].with_columns(F_ext=recs[2]["F_ext"] * 1.001)
    near.meta["name"] = "O-ring_5bar_again"
    base = prepare(recs)
    more = prepare([*recs, near])
    tb, sb = _split(base)
    tm, sm = _split(more)
    for e in base.experiments:
        f = next(x for x in more.experiments if x.digest == e.digest)
        np.testing.assert_array_equal(sb[e.start:e.stop], sm[f.start:f.stop])
        np.testing.assert_array_equal(tb[e.start:e.stop], tm[f.start:f.stop])


def test_an_irrelevant_sidecar_mass_keeps_the_band() -> None:
    """``rig.mass = 0.1`` kg on a record moving at 10 mm/s changes the force by milligrams:
    the band the force and motion are filtered in stays that of the events."""
    recs = _records(ORING[:2])
    heavy = []
    for r in recs:
        h = r.with_columns()
        h.meta["rig"] = {**h.meta.get("rig", {}), "mass": 0.1}
        heavy.append(h)
    a, b = prepare(recs), prepare(heavy)
    for sa, sb in zip(a.signals, b.signals, strict=True):
        assert sa.cutoff_hz == sb.cutoff_hz
        assert sa.force_cutoff_hz == pytest.approx(sb.force_cutoff_hz)
    assert np.max(np.abs(a.y - b.y)) < 0.05  # N: 0.1 kg times the acceleration


# ------------------------------------------------------------------------ design
def test_the_oring_design_confounds_speed_with_direction_and_pressure() -> None:
    data = prepare(_records(ORING))
    d = record_design(data, segment(data))
    assert d.one_speed and d.fixed_stroke
    assert [round(p / 1e5) for p in d.pressure_levels] == [1, 3, 5, 7]
    assert d.confounds("speed", "direction") is not None
    c = d.confounds("speed", "pressure")
    assert c is not None and "retracting speed falls" in c.why
    lo, hi = c.over["retracting speed"]
    assert 0.005 < lo < 0.006 and 0.0095 < hi < 0.0105  # m/s: 5.5 and 10.0 mm/s
    assert d.confounds("position", "distance-since-reversal") is not None
    doc = json.loads(json.dumps(d.to_dict()))  # plain JSON for the experiment designer
    assert {tuple(c["factors"]) for c in doc["confounded"]} >= {("speed", "direction"),
                                                               ("speed", "pressure")}


# ----------------------------------------------------------------- events' band
def test_transition_times_of_a_known_ramp_and_the_band_that_keeps_it() -> None:
    """Reversals of a triangle stroke whose force swings by 10 N as a 10-90 % ramp of
    0.12 s: the time is read back, and the band chosen keeps it within 15 %."""
    fs = 100.0
    t = np.arange(0.0, 60.0, 1.0 / fs)
    v = 0.01 * np.sign(np.sin(2 * np.pi * t / 8.0))
    width = 0.12
    force = 5.0 * np.tanh(np.sin(2 * np.pi * t / 8.0) / 1e-9)  # a step at each reversal
    kernel = np.clip(np.arange(-30, 31) / fs / (width / 0.8) + 0.5, 0, 1)  # a linear ramp
    force = np.convolve(force, np.diff(kernel, prepend=0.0), mode="same")
    times = transition_times(t, v, force)
    assert len(times) >= 10
    assert np.median(times) == pytest.approx(width, abs=0.011)
    fc = event_band(fs, 1.0, float(np.percentile(times, 25)), 0.01, lambda f: 0.0)
    kept = zero_phase_lowpass(force, fs, fc, 2, label="F")
    assert np.median(transition_times(t, v, kept)) < 1.15 * np.median(times)
    # a noisy position keeps its noise-limited band, and a band above the events is kept
    assert event_band(fs, 1.0, width, 0.01, lambda f: 1.0) == 1.0
    assert event_band(1000.0, 200.0, 0.3, 0.1, lambda f: 0.0) == 200.0


def test_the_oring_records_are_derived_in_the_band_of_their_transitions() -> None:
    for rec in _records(ORING):
        cond = prepare([rec]).signals[0]
        assert cond.event_time_s is not None and 0.05 < cond.event_time_s < 0.2
        assert cond.cutoff_hz >= 0.75 / cond.event_time_s  # was 1-2 Hz
        assert cond.force_cutoff_hz == cond.cutoff_hz  # the force follows (mass fitted)


# ----------------------------------------------------- measurement terms, model file
def test_area_error_is_a_measurement_term_of_the_model_file(tmp_path: Path) -> None:
    """The friction loaded from a diagnosed model carries no ``dA*p``: at 5 bar in the
    rod chamber it is the seal's ~10 N, not 100 N."""
    model = make_model("lugre", params="canudas1995").with_effects(
        make_effect("area-error", {"dA1": -5e-6, "dA2": 2e-4}))
    path = tmp_path / "m.json"
    model.save(path)
    doc = json.loads(path.read_text())
    assert [e["name"] for e in doc["measurement_terms"]["effects"]] == ["area-error"]
    assert "dA2" not in doc["params"]
    with pytest.warns(FcompWarning, match="measurement terms area-error"):
        friction = load_model(path)
    v = np.array([-0.01, 0.01])
    np.testing.assert_array_equal(friction.steady_state(v, p2=5e5),
                                  make_model("lugre", params="canudas1995").steady_state(v))
    # a file written when area-error was a friction effect reads it as a measurement term
    old = {**doc, "effects": [{"name": "area-error", "config": {}}],
           "params": {**doc["params"], "dA1": -5e-6, "dA2": 2e-4}}
    old.pop("measurement_terms")
    mf = read_model(old)
    assert [e.name for e in mf.measurement_effects] == ["area-error"]
    assert not mf.model.effects


def test_undetermined_values_are_flagged_in_the_file_and_on_loading(tmp_path: Path) -> None:
    from fcomp.models.document import model_document

    model = make_model("lugre", params="canudas1995")
    doc = model_document(model, stderr={"Fc": 0.1, "n": float("nan")},
                         undetermined={"n": "at-bound: n = 10 is at its upper bound"})
    assert doc["stderr"] == {"Fc": 0.1, "n": None}
    path = tmp_path / "m.json"
    path.write_text(json.dumps(doc))
    with pytest.warns(FcompWarning, match="n not determined by the record"):
        load_model(path)
    assert read_model(path).undetermined == {"n": "at-bound: n = 10 is at its upper bound"}


# ---------------------------------------------------------------- pressure forms
@pytest.mark.parametrize("form", ["linear", "saturating", "power"])
def test_pressure_forms_scale_the_levels_as_their_equations(form: str) -> None:
    """The factor of each form against its equation written out here (models.md), on a
    Coulomb map (the force is the level times the factor)."""
    kp, p_ref, p_sat, m = 8e-7, 4e5, 3e5, 0.6
    base = make_model("coulomb", params="seed000-cylinder1")
    eff = make_effect("pressure-dependence", {"kp": kp, "p_ref": p_ref, "p_sat": p_sat,
                                              "p_exp": m}, form=form)
    model = base.with_effects(eff)
    v = np.array([-0.02, 0.02])
    for p1 in (0.5e5, 2e5, 4e5, 6e5, 9e5):
        dS = p1 - p_ref
        g = {"linear": 1 + kp * dS,
             "saturating": 1 + kp * p_sat * (1 - math.exp(-dS / p_sat)),
             "power": 1 + kp * p_ref / m * ((p1 / p_ref) ** m - 1)}[form]
        np.testing.assert_allclose(model.steady_state(v, p1=p1),
                                   max(g, 0.01) * base.steady_state(v), rtol=1e-12)


def test_pressure_forms_round_trip_through_the_model_file(tmp_path: Path) -> None:
    model = make_model("lugre", params="canudas1995").with_effects(
        make_effect("pressure-dependence", {"kp": 9e-7, "p_ref": 4e5, "p_sat": 2.5e5,
                                            "kpv": 4e-7}, form="saturating"))
    path = tmp_path / "m.json"
    model.save(path)
    same = load_model(path)
    v = np.linspace(-0.05, 0.05, 11)
    for p1 in (1e5, 7e5):
        np.testing.assert_array_equal(same.steady_state(v, p1=p1),
                                      model.steady_state(v, p1=p1))
    assert same.effects[0].form == "saturating"


def test_a_file_of_the_former_pressure_law_gives_the_same_forces(tmp_path: Path) -> None:
    """Written before the forms (no form, kq fitted): the linear form, bit for bit."""
    doc = {"format": "fcomp-model", "version": 1, "model": "lugre",
           "effects": [{"name": "pressure-dependence", "config": {}}],
           "params": {"kp": 1.2e-6, "kq": -9e-13, "p_ref": 4e5}}
    path = tmp_path / "old.json"
    path.write_text(json.dumps(doc))
    model = load_model(path)
    v = np.array([-0.01, 0.01])
    base = make_model("lugre")
    for p1 in (1e5, 7e5):
        dS = p1 - 4e5
        g = 1 + 1.2e-6 * dS - 9e-13 * dS**2
        got = model.steady_state(v, p1=p1) - 0.4 * v  # the default sigma2 is not scaled
        np.testing.assert_allclose(got, g * (base.steady_state(v) - 0.4 * v), rtol=1e-12)


# -------------------------------------------------------------------- advice
def test_advice_does_not_ask_for_what_the_record_holds_or_for_missing_options() -> None:
    data = prepare(_records(ORING))
    design = record_design(data, segment(data))
    ws = [FitWarning("at-bound", "kp", "kp = 1e-06 1/Pa is at its upper bound: ...; to "
                     "determine it: identical motions at two or more chamber pressure levels"),
          FitWarning("mass-implausible", "mass", "the fitted mass 0 kg is below 0.0033 kg: "
                     "...; give rig.mass in the sidecar or --mass")]
    out = reword(ws, design, "pneumatic-cylinder")
    assert "two or more chamber pressure levels" not in out[0].message
    assert "already holds identical motions at 4 pressure levels" in out[0].message
    assert "the same retracting speed at every pressure level" in out[0].message
    assert "--mass" not in out[1].message and "rig.mass in the sidecar" in out[1].message


# ----------------------------------------------------------------- structures
def test_seal_structures_are_named_with_their_sizes() -> None:
    """A residual built from an end zone, a creep and a ripple of known sizes on the O-ring
    3 bar record's motion: each is named, with its size."""
    data = prepare(_records(ORING[1:2]))
    seg = segment(data)
    x, v = data.signal("x"), data.signal("v")
    s = np.sign(v)
    sc = data.scales
    t = data.signal("t")
    end = np.where((x > sc.x_max - 3e-3) & (v > 0), 2.0, 0.0)  # +2 N, last 3 mm extending
    creep = np.zeros(x.size)  # the level up by 0.8 N over each experiment
    for e in data.experiments:
        te = t[e.start:e.stop]
        creep[e.start:e.stop] = 0.8 * (te - te[0]) / np.ptp(te)
    ripple = 0.25 * np.sin(2 * np.pi * x / 3.5e-3)  # 0.5 N peak to peak, 3.5 mm period
    rng = np.random.default_rng(1)
    r = s * (end + creep + ripple) + 0.05 * rng.standard_normal(x.size)
    F_hat = s * 6.0
    found = {st.name: st for st in seal_structures(r, F_hat, data, seg, least=0.2)}
    assert set(found) == {"end-zone", "creep", "ripple"}
    assert found["end-zone"].figures["end"] == "extended"
    assert found["end-zone"].size == pytest.approx(2.0, rel=0.25)
    assert found["creep"].size == pytest.approx(0.8, rel=0.35)
    assert found["ripple"].figures["period"] == pytest.approx(3.5e-3, rel=0.1)
    assert found["ripple"].size == pytest.approx(0.25, rel=0.25)
    assert seal_structures(0.05 * rng.standard_normal(x.size), F_hat, data, seg, 0.2) == []


# --------------------------------------------------------------------- pairs
@dataclasses.dataclass(frozen=True)
class _Cand:
    effect: str
    judgement: Judgement | None
    rms_heldout: float
    fit: object = True
    form: str | None = None


def _judged(fall: float, p: float, *codes: str) -> Judgement:
    return Judgement(fall, 3.0, p, -1.0, tuple(Failure(c) for c in codes), AcceptanceRule())


def test_pairs_are_drawn_from_significant_falls_short_only_of_their_size() -> None:
    rule = AcceptanceRule()
    cands = [_Cand("area-error", _judged(0.3, 1e-9, "small-share"), 1.0),
             _Cand("direction-asymmetry", _judged(0.25, 1e-12, "small-share"), 1.05),
             _Cand("stribeck", _judged(0.2, 0.3, "small-share", "not-significant"), 1.1),
             _Cand("viscous", _judged(0.2, 1e-6, "bic"), 1.1),
             _Cand("presliding", None, math.nan, fit=None),
             _Cand("pressure-dependence", _judged(0.1, 1e-4, "small-fall"), 1.2),
             _Cand("position-dependence", _judged(0.05, 1e-4, "small-share"), 1.3)]
    got = promising(cands, rule)
    assert [c.effect for c in got] == ["area-error", "direction-asymmetry",
                                       "pressure-dependence", "position-dependence"]
    # never two effects declared confounded (an area error and a direction asymmetry take the
    # same excess twice): the pressure law is paired with each, the best singles first
    pairs = [(got[i].effect, got[j].effect) for i, j in pairs_of(got)]
    assert pairs == [("area-error", "pressure-dependence"),
                     ("direction-asymmetry", "pressure-dependence"),
                     ("area-error", "position-dependence")]


# ----------------------------------------------------------------- the conclusion
def test_the_conclusion_names_the_design_tie_the_structures_and_one_feature() -> None:
    from fcomp.conclusions import of_diagnosis

    doc = {"baseline": "coulomb-viscous", "model": "coulomb-viscous + area-error",
           "added": ["area-error"], "rms_baseline": 3.0, "rms_final": 0.66,
           "noise_floor": 0.21, "verdict": "unexplained-structure",
           "residual_features": [{"feature": "x", "strength": 0.4,
                                  "same_as": ["displacement_since_reversal"]}],
           "structures": [{"name": "end-zone", "text": "..."}, {"name": "creep", "text": ""}],
           "ties": [["area-error", "stribeck"]],
           "tie_experiments": {"area-error": {"area-error": "a", "stribeck": "b"}},
           "confounding": [{"effects": ["area-error", "stribeck"],
                            "factors": ["speed", "pressure"],
                            "separates": "the same retracting speed at every pressure level"}],
           "warnings": []}
    c = of_diagnosis(doc)
    assert "follows x (one with displacement_since_reversal on this record's fixed stroke)" \
        in c.finding
    assert c.finding.endswith("named: end-zone, creep")
    assert any("varies speed and pressure together): record the same retracting speed"
               in s for s in c.next_steps)
    assert not any("area-error: a" in s for s in c.next_steps)  # the design's experiment


def test_a_value_at_its_bound_has_no_standard_error(tmp_path: Path) -> None:
    """An O-ring's Fs at its bound came out with a standard error of 1.3e38 N (the Jacobian's
    column there says nothing of the data): it is null in the JSON and the model file, "-"
    in the report, and flagged; the other values keep theirs."""
    from fcomp.diagnosis.refit import FitUncertainty
    from fcomp.diagnosis.report import final_parameters
    from fcomp.diagnosis.result import _stderr
    from fcomp.models.document import model_document
    from fcomp.report import Report

    class AtBound:
        def uncertainty(self, fit: object) -> FitUncertainty:
            return FitUncertainty({"Fc": 0.23, "Fs": 1.3e38, "sigma2": 14.0}, {}, {}, {})

    flags = [FitWarning("at-bound", "Fs", "final model lugre: Fs = 4 N is at its upper bound"),
             FitWarning("interval-crosses-zero", "sigma2", "final model lugre: through zero")]
    stderr = _stderr(AtBound(), None, flags)  # type: ignore[arg-type]
    assert stderr["Fc"] == 0.23 and stderr["sigma2"] == 14.0 and math.isnan(stderr["Fs"])
    doc = model_document(make_model("lugre", params="canudas1995"), stderr=stderr,
                         undetermined={"Fs": "at-bound: Fs = 4 N is at its upper bound"})
    assert doc["stderr"] == {"Fc": 0.23, "Fs": None, "sigma2": 14.0}
    assert "1.3e+38" not in json.dumps(doc)
    rep = final_parameters(Report("d"), {"params": {"Fc": 1.66, "Fs": 4.0},
                                         "stderr": doc["stderr"], "model_file": doc}, {})
    assert "1.3e" not in rep.to_html() and "at-bound" in rep.to_html()


def test_a_bridged_or_cut_pause_holds_out_the_same_samples(monkeypatch: pytest.MonkeyPatch
                                                            ) -> None:
    """The O-ring 3 bar file pauses 0.3 s mid-slide (12 mm/s both sides): bridged, it is one
    experiment; cut, two pieces. The held-out blocks are the file's (the experiment of its
    design), counted over its measured samples: the same samples are held out either way,
    and the same as for the file alone (a split by piece moved every block of the file and
    turned the pair found on 1, 3, 5 bar into nothing added)."""
    import fcomp.diagnosis.pauses as pauses
    from fcomp.diagnosis.split import _segment_split

    recs = [datasets.load("zillen", f"O-ring_{k}bar.csv") for k in (1, 3)]

    def held(data: DiagnosisData) -> tuple[np.ndarray, np.ndarray]:
        measured = ~data.bridged
        split = _segment_split(data, measured)
        t = data.signal("t")
        return t[split.test], t[split.train]

    bridged = prepare(recs)
    assert bridged.bridged.sum() == 29 and len(bridged.experiments) == 2
    monkeypatch.setattr(pauses, "kind", lambda *a, **k: None)
    cut = prepare(recs)
    assert len(cut.experiments) == 3 and cut.experiments[1].design == cut.experiments[2].design
    one, two = held(bridged), held(cut)
    for a, b in zip(one, two, strict=True):
        np.testing.assert_array_equal(a, b)
    e = bridged.experiments[1]  # the 3 bar file, with the 1 bar one and bridged, or alone and cut
    with_other = _segment_split(bridged, ~bridged.bridged).test[e.start:e.stop]
    with_other = with_other[~bridged.bridged[e.start:e.stop]]
    by_itself = prepare(recs[1:])  # alone and cut
    np.testing.assert_array_equal(with_other, _segment_split(by_itself,
                                                             ~by_itself.bridged).test)
    assert 0.3 < len(one[0]) / (len(one[0]) + len(one[1])) < 0.36
