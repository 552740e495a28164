"""Study ``friction-models``: seed 002 reproduced on the ``hydraulic`` plant with ``seed002-type1``.

Seed 002 (Tran, Dao & Yanada, "Effect of friction model on simulation of
hydraulic actuator") simulates an electrohydraulic servo (its Table 2; the
plant of :mod:`plants.hydraulic`, models.md 3.2) driven by a sinusoidal
valve current, with three friction models sharing the same static
parameters:

* the **steady-state** model, seed 002 Eq. 12 (``stribeck`` with the film
  term ``h_ss(v)``; in the plant a Karnopp stick band, :mod:`plants.mechanics`);
* **LuGre** (Canudas de Wit et al. 1995; models.md 1.3);
* the **new modified LuGre model** (NMLGM, seed 002 Eqs. 5-11: lubricant film
  ``h`` and the fluid-friction lead ``sigma2*(v + T*dv/dt)``).

Its claim: "the LuGre model may cause high-frequency oscillations in
velocity, friction force, and pressures, which are not observed in
experiments", while the NMLGM predicts the measured behaviour. The seed's
friction parameters (its Table 3) are not in the text: the numbers used are
the *assumed* ones of ``seed002-type1`` (see its TOML), the same ``sigma0``,
``sigma1`` for LuGre and the NMLGM.

What is computed (SI units: m/s, N, Pa, Hz)
-------------------------------------------
**High-frequency content.** A signal's high-frequency content is the RMS of
its zero-phase high-pass part (4th-order Butterworth, ``scipy.signal.
sosfiltfilt``) above :data:`HF_CUTOFF` = 10 Hz, ten times the paper's 1 Hz
input, over whole cycles after the first (the first cycle holds the start
from rest: the 118 kg load settling onto the oil columns, the break-away).
``hf_pressure_rms`` is the RMS over both chambers, ``sqrt((rms1^2 + rms2^2)/2)``.

**The claim** is taken to reproduce when, at the paper's input (4.5 mA,
1 Hz), LuGre's high-frequency content is at least :data:`CLAIM_RATIO` (2)
times the NMLGM's in velocity, friction force and pressure alike.

**Sweep.** The parameters the seed does not give that decide the dynamics of
a LuGre bristle are ``sigma0`` (bristle stiffness) and ``sigma1`` (bristle
damping): LuGre's are swept over a grid with the NMLGM held at the assumed
values (the seed identified each model's dynamic parameters separately), and,
wherever the claim holds, the NMLGM is run with the *same* ``sigma0``,
``sigma1`` (control run: does the difference come from the model structure
or from the parameters?).

**Physics reported beside it:** the oil-column natural frequency
``f_h = sqrt(beta*(A1^2/V1 + A2^2/V2)/m)/(2*pi)`` at mid-stroke (linearised
chambers, valve closed), the bristle-mass mode ``sqrt((sigma0 + k_h)/m)``,
its damping ratio ``(sigma1 + sigma2)/(2*sqrt((sigma0 + k_h)*m))``, and the
speed above which LuGre's bristle damping stops being dissipative,
``v_max = 4*Fc/sigma1`` (:meth:`fcomp.models.LuGreFamily.passivity`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fcomp.errors import FcompError
from fcomp.figstyle import legend_above
from fcomp.measurement import Measurement
from fcomp.models import FrictionModel, make_model
from fcomp.paramsets import get as get_paramset
from fcomp.piston import chamber_volumes, piston_areas
from fcomp.progress import progress_bar
from studies.base import Finding, Study, StudyConfig, StudyOutput

#: The paper (seed 002).
PAPER = ("Tran, Dao & Yanada (2014), \"Effect of friction model on simulation of hydraulic "
         "actuator\", Proc. IMechE Part I")

#: Parameter set of the study.
PARAMSET = "seed002-type1"
#: Model names of the study (the friction sections of ``seed002-type1``), in plotting order.
MODEL_KEYS = ("steady-state", "lugre", "nmlgm")
#: High-pass cutoff of the high-frequency content (Hz): ten times the paper's 1 Hz input.
HF_CUTOFF = 10.0
#: Order of the Butterworth high-pass.
HF_ORDER = 4
#: LuGre/NMLGM ratio of high-frequency content that counts as "LuGre oscillates, NMLGM does not".
CLAIM_RATIO = 2.0
#: Cycles simulated per run (the first is excluded from the measures).
CYCLES = 3
#: Output rate of the runs (Hz).
RATE = 4000.0
#: Samples per line in the time-series figures.
PLOT_POINTS = 3000
#: Upper frequency (Hz) of the spectrum figure, and the decades of PSD it shows.
SPECTRUM_MAX_HZ = 120.0
PSD_DECADES = 8.0

#: LuGre bristle parameters swept (N/m, Ns/m): full run and fast mode.
SWEEP_SIGMA0 = (2e5, 6e5, 2e6, 6e6, 2e7)
SWEEP_SIGMA1 = (3e2, 3e3, 3e4, 1e5, 3e5)
FAST_SIGMA0 = (2e6,)
FAST_SIGMA1 = (3e2, 3e4, 1e5)
#: Valve-current amplitudes (A) and frequencies (Hz) of the input grid (full run; fast: paper case).
GRID_AMPLITUDES = (1.5e-3, 3.0e-3, 4.5e-3, 6.0e-3)
GRID_FREQUENCIES = (0.5, 1.0, 2.0)
SIGNALS = ("velocity", "force", "pressure")


# --------------------------------------------------------------------- models
def friction_model(key: str, **changes: float) -> FrictionModel:
    """The friction model ``key`` (``steady-state``, ``lugre``, ``nmlgm``) of ``seed002-type1``."""
    pset = get_paramset(PARAMSET)
    if key not in pset.friction:
        raise FcompError(f"parameter set {PARAMSET} has no friction section {key!r}")
    model = make_model(pset.friction[key]["model"], params=PARAMSET)
    return model.with_params(**changes) if changes else model


def hydraulic_plant(key: str, **changes: float) -> Any:
    """The ``hydraulic`` plant of ``seed002-type1`` with friction model ``key`` (params changed)."""
    from plants import PLANTS

    return PLANTS.get("hydraulic")(friction_model(key, **changes), PARAMSET)


def paper_input() -> tuple[float, float]:
    """The paper's input (seed 002 Fig. 5): amplitude (A) and frequency (Hz) of the valve current."""
    exp = get_paramset(PARAMSET).raw["experiment"]
    return float(exp["u_amplitude"]), float(exp["u_frequency"])


def run_sine(plant: Any, amplitude: float, frequency: float, *, cycles: int = CYCLES,
             rate: float = RATE) -> Measurement:
    """Simulate ``cycles`` periods of ``u = amplitude*sin(2*pi*frequency*t)`` (A) from rest."""
    if not (amplitude > 0 and frequency > 0):
        raise FcompError("the valve-current amplitude and frequency must be positive")
    w = 2.0 * math.pi * frequency
    return plant.simulate(lambda t: amplitude * np.sin(w * t), cycles / frequency, rate)


# ------------------------------------------------------------------ measures
def hf_rms(x: np.ndarray, rate: float, cutoff: float = HF_CUTOFF) -> float:
    """RMS of the zero-phase high-pass part of ``x`` above ``cutoff`` Hz (Butterworth, sosfiltfilt)."""
    from scipy import signal

    x = np.asarray(x, dtype=float)
    if not 0 < cutoff < rate / 2:
        raise FcompError(f"high-pass cutoff {cutoff} Hz must lie below the Nyquist rate {rate / 2} Hz")
    sos = signal.butter(HF_ORDER, cutoff, "highpass", fs=rate, output="sos")
    return float(np.sqrt(np.mean(signal.sosfiltfilt(sos, x - x.mean()) ** 2)))


def dominant_frequency(x: np.ndarray, rate: float, above: float = HF_CUTOFF) -> float:
    """Frequency (Hz) of the largest Welch-spectrum peak of ``x`` above ``above`` Hz."""
    from scipy import signal

    f, P = signal.welch(np.asarray(x, float) - np.mean(x), fs=rate,
                        nperseg=min(4096, len(x)))
    k = f > above
    return float(f[k][np.argmax(P[k])])


def hf_content(run: Measurement, frequency: float, cutoff: float = HF_CUTOFF) -> dict[str, float]:
    """High-frequency content of a run (whole cycles after the first; module docstring).

    Returns ``hf_velocity_rms`` (m/s), ``hf_force_rms`` (N), ``hf_pressure_rms`` (Pa),
    ``hf_p1_rms``, ``hf_p2_rms`` (Pa), ``dominant_hz`` (velocity spectrum peak) and
    ``peak_force`` (largest ``|F|``, N).
    """
    c = run.columns
    t = c["t"]
    rate = (t.size - 1) / (t[-1] - t[0])
    keep = t >= t[0] + 1.0 / frequency - 0.5 / rate
    if keep.sum() < 16:
        raise FcompError("the run is shorter than two input cycles: nothing left to analyse")
    p1, p2 = hf_rms(c["p1"][keep], rate, cutoff), hf_rms(c["p2"][keep], rate, cutoff)
    return {
        "peak_force": float(np.max(np.abs(c["F"][keep]))),
        "hf_velocity_rms": hf_rms(c["v"][keep], rate, cutoff),
        "hf_force_rms": hf_rms(c["F"][keep], rate, cutoff),
        "hf_pressure_rms": math.sqrt(0.5 * (p1 * p1 + p2 * p2)),
        "hf_p1_rms": p1,
        "hf_p2_rms": p2,
        "dominant_hz": dominant_frequency(c["v"][keep], rate, cutoff),
    }


def ratios(a: dict[str, float], b: dict[str, float]) -> dict[str, float]:
    """``a/b`` of the three high-frequency measures (velocity, force, pressure)."""
    return {s: a[f"hf_{s}_rms"] / b[f"hf_{s}_rms"] if b[f"hf_{s}_rms"] > 0 else math.inf
            for s in SIGNALS}


def claim_holds(lugre: dict[str, float], nmlgm: dict[str, float],
                ratio: float = CLAIM_RATIO) -> bool:
    """LuGre's high-frequency content is ``ratio`` times the NMLGM's or more, in every signal."""
    return all(r >= ratio for r in ratios(lugre, nmlgm).values())


# -------------------------------------------------------------------- physics
def oil_column_stiffness(plant: Any) -> float:
    """Hydraulic stiffness ``beta*(A1^2/V1 + A2^2/V2)`` (N/m) at mid-stroke, valve closed."""
    p = plant.plant_params.flat()
    A1, A2 = piston_areas(p["bore"], p["rod"])
    V1, V2 = chamber_volumes(0.5 * p["stroke"], p["stroke"], p["V10"], p["V20"], A1, A2)
    return p["beta"] * (A1 * A1 / V1 + A2 * A2 / V2)


def modes(plant: Any) -> dict[str, float]:
    """Natural frequencies (Hz) of the oil column and of the bristle-mass mode; damping ratio.

    ``f_h = sqrt(k_h/m)/(2 pi)`` (sliding: the bristle carries no force change);
    stuck on the bristles ``f_b = sqrt((sigma0 + k_h)/m)/(2 pi)`` with
    damping ratio ``(sigma1 + sigma2)/(2*sqrt((sigma0 + k_h)*m))``.
    """
    p = plant.plant_params.flat()
    fr = plant.friction.flat_params()
    m = p["mass"]
    kh = oil_column_stiffness(plant)
    out = {"oil_column_stiffness": kh, "oil_column_hz": math.sqrt(kh / m) / (2 * math.pi)}
    if "sigma0" in fr:
        k = fr["sigma0"] + kh
        s2 = fr.get("sigma2", fr.get("sigma2_pos", 0.0))
        out["bristle_mode_hz"] = math.sqrt(k / m) / (2 * math.pi)
        out["bristle_mode_damping"] = (fr.get("sigma1", 0.0) + s2) / (2 * math.sqrt(k * m))
        out["dissipative_below"] = float(plant.friction.passivity().get("v_max", math.inf))
    return out


# ---------------------------------------------------------------------- runs
@dataclass
class Runs:
    """Every simulation of the study (kept for the figures)."""

    paper: dict[str, Measurement]
    grid: list[dict[str, Any]]
    sweep: list[dict[str, Any]]


def run_study(fast: bool, progress: bool = True) -> tuple[dict[str, Any], Runs]:
    """All simulations and measures; returns the results (summary) and the runs (``progress``:
    a bar on a terminal)."""
    amp, freq = paper_input()
    plants = {k: hydraulic_plant(k) for k in MODEL_KEYS}
    s0_grid = FAST_SIGMA0 if fast else SWEEP_SIGMA0
    s1_grid = FAST_SIGMA1 if fast else SWEEP_SIGMA1
    grid_cases = [(amp, freq)] if fast else [(a, f) for f in GRID_FREQUENCIES
                                             for a in GRID_AMPLITUDES]
    bar = progress_bar("friction-models",
                       len(MODEL_KEYS) * (len(grid_cases) + 1) + len(s0_grid) * len(s1_grid) * 2,
                       enabled=progress)
    paper: dict[str, Measurement] = {}
    models: dict[str, dict[str, float]] = {}
    for k in MODEL_KEYS:
        paper[k] = run_sine(plants[k], amp, freq)
        models[k] = hf_content(paper[k], freq)
        bar.update()
    grid = []
    for a, f in grid_cases:
        entry: dict[str, Any] = {"amplitude": a, "frequency": f}
        for k in MODEL_KEYS:
            entry[k] = (models[k] if (a, f) == (amp, freq)
                        else hf_content(run_sine(plants[k], a, f), f))
            bar.update()
        entry["claim_holds"] = claim_holds(entry["lugre"], entry["nmlgm"])
        grid.append(entry)
    sweep = []
    base_lugre = plants["lugre"].friction.flat_params()
    for s0 in s0_grid:
        for s1 in s1_grid:
            same = s0 == base_lugre["sigma0"] and s1 == base_lugre["sigma1"]
            lug = plants["lugre"] if same else hydraulic_plant("lugre", sigma0=s0, sigma1=s1)
            hf_l = models["lugre"] if same else hf_content(run_sine(lug, amp, freq), freq)
            bar.update()
            row: dict[str, Any] = {
                "model": "lugre", "sigma0": s0, "sigma1": s1, **hf_l,
                "ratio_to_nmlgm": ratios(hf_l, models["nmlgm"]),
                "claim_holds": claim_holds(hf_l, models["nmlgm"]),
                **{k: v for k, v in modes(lug).items() if k != "oil_column_stiffness"},
                "bristle_time_constant": s1 / s0,
            }
            row["damper_over_spring"] = s1 * 2 * math.pi * row["oil_column_hz"] / s0
            if row["claim_holds"]:
                # control: the NMLGM with the same bristle parameters
                nml = hydraulic_plant("nmlgm", sigma0=s0, sigma1=s1)
                hf_n = hf_content(run_sine(nml, amp, freq), freq)
                row["nmlgm_same_bristles"] = {**hf_n, "ratio_lugre_to_it": ratios(hf_l, hf_n),
                                              "claim_holds": claim_holds(hf_l, hf_n)}
            bar.update()
            sweep.append(row)
    bar.close()
    phys = modes(plants["lugre"])
    phys["nmlgm_dissipative_below"] = modes(plants["nmlgm"])["dissipative_below"]
    c = paper["lugre"].columns
    results: dict[str, Any] = {
        "models": {k: {m: models[k][m] for m in ("hf_velocity_rms", "hf_force_rms",
                                                  "hf_pressure_rms")} for k in MODEL_KEYS},
        "claim_reproduced": claim_holds(models["lugre"], models["nmlgm"]),
        "sweep": sweep,
        "paper_case": {
            "amplitude": amp, "frequency": freq,
            "details": models,
            "ratio_lugre_to_nmlgm": ratios(models["lugre"], models["nmlgm"]),
            "velocity_range": [float(c["v"].min()), float(c["v"].max())],
            "paper_velocity_range": [-0.14, 0.14],
            "p1_above_p2_fraction": float(np.mean((c["p1"] > c["p2"])[c["t"] >= 1.0 / freq])),
        },
        "grid": grid,
        "physics": phys,
        "settings": {"hf_cutoff_hz": HF_CUTOFF, "hf_filter": f"Butterworth order {HF_ORDER}, "
                     "zero phase", "claim_ratio": CLAIM_RATIO, "cycles": CYCLES,
                     "analysed": "cycles 2..", "rate_hz": RATE, "paramset": PARAMSET,
                     "units": {"hf_velocity_rms": "m/s", "hf_force_rms": "N",
                               "hf_pressure_rms": "Pa", "sigma0": "N/m", "sigma1": "Ns/m"}},
        "parameters": {k: plants[k].friction.flat_params() for k in MODEL_KEYS},
        "plant_parameters": plants["lugre"].plant_params.flat(),
        "parameter_units": {**{n: spec.unit for k in MODEL_KEYS
                               for n, spec in plants[k].friction.param_specs().items()},
                            **{spec.name: spec.unit
                               for spec in plants["lugre"].plant_params.SPECS}},
    }
    return results, Runs(paper, grid, sweep)


# ---------------------------------------------------------------------- text
def findings(res: dict[str, Any]) -> list[str]:
    """The study's conclusions, written from the numbers."""
    pc = res["paper_case"]
    r = pc["ratio_lugre_to_nmlgm"]
    ph = res["physics"]
    d = pc["details"]
    out = [
        f"At the paper's input ({pc['amplitude'] * 1e3:.1f} mA, {pc['frequency']:g} Hz) the "
        f"simulated velocity spans {pc['velocity_range'][0]:.3f} to {pc['velocity_range'][1]:.3f} "
        "m/s (the paper measured about -0.14 to +0.14 m/s) and "
        + (f"P1 stays above P2 for {100 * pc['p1_above_p2_fraction']:.0f} % of the time after "
           "the first cycle (the paper measured P1 > P2 throughout)."),
        f"All three models ring after every velocity reversal at about {d['lugre']['dominant_hz']:.0f} "
        f"Hz, the oil-column mode of the plant (computed {ph['oil_column_hz']:.1f} Hz at "
        "mid-stroke): the friction force changes sign within milliseconds at each reversal and "
        "kicks the lightly damped load on its oil springs.",
        f"LuGre's high-frequency content is {r['velocity']:.2f}x (velocity), {r['force']:.2f}x "
        f"(force) and {r['pressure']:.2f}x (pressure) the NMLGM's: "
        + ("the claim reproduces with the assumed parameters." if res["claim_reproduced"]
           else f"below the {CLAIM_RATIO:g}x the claim needs, so with the assumed parameters "
           "(the same sigma0, sigma1 for both models) the claim does not reproduce."),
    ]
    holds = [s for s in res["sweep"] if s["claim_holds"]]
    if holds:
        s1_min = min(s["sigma1"] for s in holds)
        fs = res["parameters"]["lugre"]["Fs"]
        peak = max(s["peak_force"] for s in holds)
        calm = [s["peak_force"] for s in res["sweep"] if not s["claim_holds"]]
        r_hold = min(s["damper_over_spring"] for s in holds)
        r_fail = [s["damper_over_spring"] for s in res["sweep"] if not s["claim_holds"]]
        split = (f"; it holds wherever sigma1*w_h/sigma0 >= {r_hold:.2g} and fails wherever "
                 f"it is <= {max(r_fail):.2g} (w_h the oil-column frequency): the claim needs "
                 "bristles whose damper outweighs their spring at the oil-column frequency"
                 if r_fail and max(r_fail) < r_hold else "")
        out.append(
            f"The sweep of LuGre's bristle parameters finds the claim in {len(holds)} of "
            f"{len(res['sweep'])} cases, all with sigma1 >= {s1_min:.3g} Ns/m{split}. There "
            "LuGre is dissipative only below 4 Fc/sigma1 (at most "
            f"{4 * res['parameters']['lugre']['Fc'] / s1_min * 1e3:.1f} mm/s, the peak speed is "
            f"{max(abs(v) for v in pc['velocity_range']):.2f} m/s) and its friction force peaks "
            f"at up to {peak:.0f} N at break-away (Fs = {fs:g} N"
            + (f"; {max(calm):.0f} N at most where the claim fails" if calm else "")
            + "): the sigma1*dz/dt term spikes when the bristles let go, and the spike excites "
            "the oil-column mode.")
        ctrl = [s["nmlgm_same_bristles"] for s in holds if "nmlgm_same_bristles" in s]
        if ctrl:
            rv = [c["ratio_lugre_to_it"]["velocity"] for c in ctrl]
            out.append(
                "Control runs: given the same sigma0 and sigma1, the NMLGM oscillates as well "
                f"(LuGre's high-frequency velocity content is {min(rv):.2f} to {max(rv):.2f}x "
                f"its; the claim holds against it in {sum(c['claim_holds'] for c in ctrl)} of "
                f"{len(ctrl)} cases): in this plant the difference the paper reports comes "
                "from the bristle parameters identified for each model, not from the film "
                "state or the lead term of the NMLGM structure.")
    else:
        out.append("No point of the sweep reproduces the claim: within the swept sigma0, sigma1 "
                   "LuGre's high-frequency content stays within "
                   f"{CLAIM_RATIO:g}x the NMLGM's.")
    grid = res["grid"]
    if len(grid) > 1:
        n = sum(g["claim_holds"] for g in grid)
        rv = [g["lugre"]["hf_velocity_rms"] / g["nmlgm"]["hf_velocity_rms"] for g in grid]
        top = sum(g["steady-state"]["hf_velocity_rms"] >= max(g["lugre"]["hf_velocity_rms"],
                                                              g["nmlgm"]["hf_velocity_rms"])
                  for g in grid)
        out.append(f"Over the input grid ({len(grid)} amplitude/frequency pairs, assumed "
                   f"parameters) the claim holds in {n}: LuGre/NMLGM velocity ratios "
                   f"{min(rv):.2f} to {max(rv):.2f}; the steady-state model (Karnopp stick, "
                   f"an abrupt break-away) rings most in {top} of them.")
    return out


def finding(res: dict[str, Any]) -> Finding:
    """The conclusion: does LuGre oscillate where the NMLGM does not, how sure, what next."""
    r = res["paper_case"]["ratio_lugre_to_nmlgm"]
    holds = [s for s in res["sweep"] if s["claim_holds"]]
    ratios_text = (f"LuGre's high-frequency content is {r['velocity']:.2f}x the NMLGM's in "
                   f"velocity, {r['force']:.2f}x in force and {r['pressure']:.2f}x in pressure "
                   f"(the claim needs {CLAIM_RATIO:g}x in all three)")
    sweep = (f"; LuGre oscillates as the paper says at {len(holds)} of {len(res['sweep'])} "
             "points of the sweep of its bristle stiffness and damping, those with a large "
             "damping sigma1 (at least "
             f"{min(s['sigma1'] for s in holds):.3g} Ns/m)" if holds else
             f"; at none of the {len(res['sweep'])} points of the bristle-parameter sweep")
    if res["claim_reproduced"]:
        status, level = "reproduced", "ok"
        found = f"With the assumed friction parameters {ratios_text}{sweep}."
    else:
        status, level = "not reproduced", "bad"
        found = (f"With the assumed friction parameters LuGre does not oscillate more than the "
                 f"NMLGM: {ratios_text}{sweep}.")
    return Finding(
        status, level, found,
        sure="the plant follows the paper's Table 2, but the paper does not print its "
             "friction parameters (its Table 3): every friction value here is assumed, so "
             "the outcome says what these values do, not what the paper's did.",
        next="get the paper's Table 3 (or identify sigma0, sigma1 of LuGre and the NMLGM on "
             "the rig) and rerun; the sweep says the claim needs a bristle damping that "
             "outweighs the bristle stiffness at the oil-column frequency.",
        confidence="low")


# -------------------------------------------------------------------- report
def _decorate(ax: Any, title: str, xlabel: str, ylabel: str) -> None:
    ax.set_title(title, fontsize=10)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)


COLORS = {"steady-state": "#2f6db5", "lugre": "#c0392b", "nmlgm": "#27864a"}
#: Colours of the claim in the sweep map: holds, rings more but not enough, fails.
CLAIM_COLORS = {"ok": "#8fd19e", "warn": "#f5d67b", "bad": "#ee9a8f"}
LABELS = {"steady-state": "steady-state (Eq. 12)", "lugre": "LuGre", "nmlgm": "NMLGM"}


def _thin(c: dict[str, np.ndarray], keep: np.ndarray | None = None,
          points: int = PLOT_POINTS) -> dict[str, np.ndarray]:
    """Columns restricted to ``keep`` and thinned to about ``points`` samples (plots only)."""
    idx = np.flatnonzero(keep) if keep is not None else np.arange(c["t"].size)
    idx = idx[:: max(1, idx.size // points)]
    return {k: v[idx] for k, v in c.items()}


def _fig_time(out: StudyOutput, runs: Runs, freq: float) -> None:
    fig, axes = out.subplots(3, 3, figsize=(11.5, 7.2), sharex=True)
    for j, k in enumerate(MODEL_KEYS):
        c = _thin(runs.paper[k].columns)
        t = c["t"]
        axes[0, j].plot(t, c["v"] * 1e3, color=COLORS[k], lw=0.8)
        axes[1, j].plot(t, c["F"], color=COLORS[k], lw=0.8)
        axes[2, j].plot(t, c["p1"] / 1e5, color="#444", lw=0.8, label="P1")
        axes[2, j].plot(t, c["p2"] / 1e5, color="#999", lw=0.8, label="P2")
        _decorate(axes[0, j], LABELS[k], "", "v [mm/s]" if j == 0 else "")
        _decorate(axes[1, j], "", "", "F [N]" if j == 0 else "")
        _decorate(axes[2, j], "", "t [s]", "p [bar gauge]" if j == 0 else "")
    legend_above(axes[2, 0])
    out.figure(fig, "time-series",
               "Seed 002 Fig. 5 conditions simulated (valve current 4.5 mA at 1 Hz, 118 kg, "
               "from rest): piston velocity, friction force and chamber pressures (gauge) for "
               "each model.")


def _fig_force_velocity(out: StudyOutput, runs: Runs, freq: float) -> None:
    fig, ax = out.subplots(1, 1, figsize=(7.0, 4.6))
    for k in MODEL_KEYS:
        c = _thin(runs.paper[k].columns, runs.paper[k].columns["t"] >= 1.0 / freq)
        ax.plot(c["v"] * 1e3, c["F"], color=COLORS[k], lw=0.8, label=LABELS[k])
    _decorate(ax, "Friction force against velocity (cycles 2-3)", "v [mm/s]", "F [N]")
    legend_above(ax)
    out.figure(fig, "force-velocity",
               "Friction force against piston velocity at the paper's input, after the first "
               "cycle. The loops near v = 0 are the reversals; the spikes are the ringing.")


def _fig_spectrum(out: StudyOutput, runs: Runs, res: dict[str, Any], freq: float) -> None:
    from scipy import signal

    fig, ax = out.subplots(1, 1, figsize=(7.0, 4.2))
    shown: list[np.ndarray] = []
    for k in MODEL_KEYS:
        c = runs.paper[k].columns
        keep = c["t"] >= 1.0 / freq
        rate = (c["t"].size - 1) / (c["t"][-1] - c["t"][0])
        f, P = signal.welch(c["v"][keep], fs=rate, nperseg=min(4096, int(keep.sum())))
        ax.semilogy(f, P, color=COLORS[k], lw=0.9, label=LABELS[k])
        shown.append(P[(f > 0) & (f <= SPECTRUM_MAX_HZ)])
    ax.set_ylim(*psd_limits(np.concatenate(shown)))
    ph = res["physics"]
    ax.axvline(HF_CUTOFF, color="k", ls=":", lw=0.8, label=f"cutoff {HF_CUTOFF:g} Hz")
    ax.axvline(ph["oil_column_hz"], color="#8e44ad", ls="--", lw=0.8,
               label=f"oil column {ph['oil_column_hz']:.1f} Hz")
    ax.set_xlim(0, SPECTRUM_MAX_HZ)
    _decorate(ax, "Velocity spectrum (Welch)", "f [Hz]", "PSD [(m/s)$^2$/Hz]")
    legend_above(ax)
    out.figure(fig, "spectrum",
               "Power spectral density of the velocity at the paper's input: the content above "
               "the cutoff is the high-frequency measure; its peak sits at the oil-column mode.")


def psd_limits(P: np.ndarray, decades: float = PSD_DECADES) -> tuple[float, float]:
    """The y range of a spectrum plot: from the curves' top (rounded up to a decade) down
    ``decades`` decades, or to the lowest value shown if that is higher -- numerical floors
    far below the content (1e-23) would squeeze the curves into the top of the axes."""
    P = P[np.isfinite(P) & (P > 0)]
    if not P.size:
        return 1e-12, 1.0
    top = 10.0 ** math.ceil(math.log10(float(P.max())))
    low = 10.0 ** math.floor(math.log10(float(np.percentile(P, 1))))
    return max(low, top * 10.0 ** -decades), top


def _fig_sweep(out: StudyOutput, res: dict[str, Any]) -> None:
    sweep = res["sweep"]
    s0s = sorted({s["sigma0"] for s in sweep})
    s1s = sorted({s["sigma1"] for s in sweep})
    M = np.full((len(s0s), len(s1s)), np.nan)
    for s in sweep:
        M[s0s.index(s["sigma0"]), s1s.index(s["sigma1"])] = min(s["ratio_to_nmlgm"].values())
    from matplotlib.colors import BoundaryNorm, ListedColormap

    fig, ax = out.subplots(1, 1, figsize=(7.2, 0.9 + 0.75 * len(s0s) + 1.4))
    # green where the claim holds, amber where LuGre rings more but not enough, red where
    # it rings no more than the NMLGM
    cmap = ListedColormap([CLAIM_COLORS["bad"], CLAIM_COLORS["warn"], CLAIM_COLORS["ok"]])
    top = max(CLAIM_RATIO + 1.0, float(np.nanmax(M)) + 1.0)
    im = ax.imshow(M, origin="lower", cmap=cmap, norm=BoundaryNorm([0.0, 1.0, CLAIM_RATIO, top],
                                                                   3), aspect="auto")
    for i in range(len(s0s)):
        for j in range(len(s1s)):
            word = "holds" if M[i, j] >= CLAIM_RATIO else "fails"
            ax.text(j, i, f"{M[i, j]:.2f}\n{word}", ha="center", va="center", fontsize=9)
    ax.set_xticks(range(len(s1s)), [f"{v:.0e}" for v in s1s])
    ax.set_yticks(range(len(s0s)), [f"{v:.0e}" for v in s0s])
    ax.set_xlabel("LuGre sigma1 [Ns/m]")
    ax.set_ylabel("LuGre sigma0 [N/m]")
    ax.set_title("smallest LuGre/NMLGM high-frequency ratio (v, F, p)", fontsize=10)
    bar = fig.colorbar(im, ax=ax, ticks=[0.5, 0.5 * (1.0 + CLAIM_RATIO), 0.5 * (CLAIM_RATIO + top)])
    bar.ax.set_yticklabels(["< 1: fails", f"1-{CLAIM_RATIO:g}: fails", f">= {CLAIM_RATIO:g}: holds"])
    out.figure(fig, "sweep",
               "Sweep of LuGre's bristle stiffness and damping (NMLGM at the assumed values): "
               "the smallest of the three high-frequency ratios LuGre/NMLGM. Green: the claim "
               f"holds (ratio >= {CLAIM_RATIO:g} in velocity, force and pressure); amber: LuGre "
               "rings more, but not enough; red: LuGre rings no more than the NMLGM.")


def _fig_claim_case(out: StudyOutput, res: dict[str, Any], freq: float) -> None:
    holds = [s for s in res["sweep"] if s["claim_holds"]]
    if not holds:
        return
    s = min(holds, key=lambda r: (r["sigma1"], r["sigma0"]))
    amp = res["paper_case"]["amplitude"]
    runs = {"lugre": run_sine(hydraulic_plant("lugre", sigma0=s["sigma0"], sigma1=s["sigma1"]),
                              amp, freq),
            "nmlgm": run_sine(hydraulic_plant("nmlgm"), amp, freq)}
    fig, axes = out.subplots(2, 1, figsize=(9.0, 5.6), sharex=True)
    for k, run in runs.items():
        c = _thin(run.columns)
        lab = (f"LuGre sigma0={s['sigma0']:.0e}, sigma1={s['sigma1']:.0e}" if k == "lugre"
               else "NMLGM (assumed)")
        axes[0].plot(c["t"], c["v"] * 1e3, color=COLORS[k], lw=0.8, label=lab)
        axes[1].plot(c["t"], c["F"], color=COLORS[k], lw=0.8)
    _decorate(axes[0], "A sweep point where the claim holds", "", "v [mm/s]")
    _decorate(axes[1], "", "t [s]", "F [N]")
    legend_above(axes[0])
    axes[0].set_xlim(1.0 / freq, 2.2 / freq)
    out.figure(fig, "claim-case",
               "Velocity and friction force over one cycle at the smallest LuGre sigma1 of the "
               "sweep for which the claim holds, beside the NMLGM with the assumed parameters.")


def _fig_grid(out: StudyOutput, res: dict[str, Any]) -> None:
    grid = res["grid"]
    if len(grid) < 2:
        return
    freqs = sorted({g["frequency"] for g in grid})
    fig, axes = out.subplots(1, len(freqs), figsize=(3.6 * len(freqs) + 0.6, 3.6), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, f in zip(axes, freqs, strict=True):
        rows = sorted((g for g in grid if g["frequency"] == f), key=lambda g: g["amplitude"])
        a = [g["amplitude"] * 1e3 for g in rows]
        for k in MODEL_KEYS:
            ax.plot(a, [g[k]["hf_velocity_rms"] * 1e3 for g in rows], "o-", color=COLORS[k],
                    label=LABELS[k], ms=4)
        _decorate(ax, f"{f:g} Hz", "amplitude [mA]", "HF velocity RMS [mm/s]" if f == freqs[0]
                  else "")
    legend_above(axes[0])
    out.figure(fig, "grid",
               "High-frequency velocity content over the valve-current amplitude, at each input "
               "frequency, for the three models.")


def write_report(out: StudyOutput, res: dict[str, Any], runs: Runs, fast: bool) -> None:
    rep = out.report
    pc = res["paper_case"]
    freq = pc["frequency"]
    rep.section("Findings")
    rep.bullets(findings(res))
    if fast:
        rep.note("Fast mode (CI): the paper's input only and a reduced sweep; run without "
                 "`--fast` for the amplitude/frequency grid and the full sweep.", kind="info")

    rep.section("Method")
    rep.paragraph(
        "Plant: `hydraulic` with parameter set `seed002-type1` (seed 002 Table 2 for the valve, "
        "fluid and dead volumes; bore, rod, supply pressure and every friction parameter are "
        "assumed, see the parameter tables below). Input: valve current "
        "`u = A sin(2 pi f t)` from rest (mid-stroke, valve centred); "
        f"{CYCLES} cycles simulated with the package's RODAS4 engine, output at {RATE:g} Hz.")
    rep.paragraph(
        f"High-frequency content: RMS of the zero-phase Butterworth (order {HF_ORDER}) "
        f"high-pass part above {HF_CUTOFF:g} Hz, over cycles 2 and 3 (the first cycle holds the "
        "start from rest). Pressure: RMS over both chambers. The claim \"LuGre oscillates at "
        "high frequency, the NMLGM does not\" is taken to reproduce when LuGre's content is at "
        f"least {CLAIM_RATIO:g} times the NMLGM's in velocity, force and pressure alike.")
    rows = [[LABELS[k], pc["details"][k]["hf_velocity_rms"] * 1e3, pc["details"][k]["hf_force_rms"],
             pc["details"][k]["hf_pressure_rms"] / 1e3, pc["details"][k]["dominant_hz"]]
            for k in MODEL_KEYS]
    rep.section("The paper's case: 4.5 mA at 1 Hz")
    rep.table(["model", "HF velocity RMS [mm/s]", "HF force RMS [N]", "HF pressure RMS [kPa]",
               "velocity peak [Hz]"], rows,
              caption="High-frequency content at the paper's input (summary.json `models`).",
              digits=[None, 3, 2, 2, 1])
    _fig_time(out, runs, freq)
    _fig_force_velocity(out, runs, freq)
    _fig_spectrum(out, runs, res, freq)

    rep.section("Why: the plant's modes and the bristle parameters")
    ph = res["physics"]
    rep.table(["quantity", "value"], [
        ["oil-column stiffness at mid-stroke [N/m]", ph["oil_column_stiffness"]],
        ["oil-column natural frequency [Hz]", ph["oil_column_hz"]],
        ["bristle-mass mode, stuck [Hz]", ph["bristle_mode_hz"]],
        ["damping ratio of the bristle-mass mode", ph["bristle_mode_damping"]],
        ["LuGre dissipative below |v| = 4 Fc/sigma1 [m/s]", ph["dissipative_below"]],
        ["peak piston speed [m/s]", max(abs(v) for v in pc["velocity_range"])],
    ], caption="Modes of the load on its oil columns and bristles (assumed parameters).")
    rep.paragraph(
        "The 118 kg load on two oil columns of stiffness about "
        f"{ph['oil_column_stiffness']:.3g} N/m has a natural frequency of "
        f"{ph['oil_column_hz']:.1f} Hz, damped only by the valve's flow-pressure coefficient and "
        "the viscous friction. At each velocity reversal the friction force changes sign "
        "within a few milliseconds; that step excites the mode whatever the friction model. "
        "LuGre differs from the NMLGM only in how the force changes at that moment: its "
        "`sigma1 dz/dt` term acts on the bristle rate, and above `4 Fc/sigma1` it can return "
        "energy (the LuGre dissipativity bound). With a large sigma1 the piston sticks at the "
        "reversal and breaks away with a force spike well above Fs: the oscillation the paper "
        "saw. With the assumed, moderate sigma1 that spike is absent and both models behave "
        "alike.")

    rep.section("Sweep of the parameters the seed does not give")
    rep.paragraph(
        "LuGre's sigma0 and sigma1 (the seed identified them but the text does not print them) "
        "swept at the paper's input, the NMLGM kept at its assumed values; wherever the claim "
        "holds, the NMLGM was also run with the same sigma0 and sigma1 (control).")
    srows = []
    for s in res["sweep"]:
        ctrl = s.get("nmlgm_same_bristles")
        r = s["ratio_to_nmlgm"]
        srows.append([f"{s['sigma0']:.0e}", f"{s['sigma1']:.0e}",
                      f"{r['velocity']:.2f} / {r['force']:.2f} / {r['pressure']:.2f}",
                      s["damper_over_spring"], s["dissipative_below"] * 1e3, s["peak_force"],
                      ("holds" if s["claim_holds"] else "fails")
                      + ("" if ctrl is None else
                         f" ({'holds' if ctrl['claim_holds'] else 'fails'})")])
    rep.table(["sigma0 [N/m]", "sigma1 [Ns/m]", "ratio v / F / p", "damper/spring",
               "passive below [mm/s]", "peak |F| [N]", "claim"], srows,
              caption="LuGre/NMLGM high-frequency ratios (velocity / force / pressure) over "
              "the sweep (summary.json `sweep`); damper/spring: `sigma1 w_h/sigma0`, `w_h` = "
              "2 pi x the oil-column frequency; passive below: LuGre dissipative below "
              "`4 Fc/sigma1`; in brackets: the claim against the NMLGM given the same sigma0, "
              "sigma1 (control run).",
              digits=[None, None, None, 2, 1, 0, None])
    _fig_sweep(out, res)
    _fig_claim_case(out, res, freq)

    if len(res["grid"]) > 1:
        rep.section("Amplitudes and frequencies")
        grows = [[g["amplitude"] * 1e3, g["frequency"],
                  *(g[k]["hf_velocity_rms"] * 1e3 for k in MODEL_KEYS),
                  "yes" if g["claim_holds"] else "no"] for g in res["grid"]]
        rep.table(["amplitude [mA]", "frequency [Hz]",
                   *(f"{LABELS[k]} HF v [mm/s]" for k in MODEL_KEYS), "claim"], grows,
                  caption="High-frequency velocity content over the input grid.",
                  digits=[1, 2, 3, 3, 3, None])
        _fig_grid(out, res)

    rep.section("Parameters")
    rep.paragraph("Every number below is what produced this report (SI units). Friction "
                  "parameters: `seed002-type1` (assumed: the seed's Table 3 is not in its text).")
    units = res["parameter_units"]
    rep.table(["parameter", "unit", *(LABELS[k] for k in MODEL_KEYS)],
              [[n, units.get(n, ""), *(res["parameters"][k].get(n) for k in MODEL_KEYS)]
               for n in sorted({n for k in MODEL_KEYS for n in res["parameters"][k]})],
              caption="Friction parameters of the three models (SI units).")
    rep.table(["plant parameter", "unit", "value"],
              [[n, units.get(n, ""), v] for n, v in res["plant_parameters"].items()],
              caption="Plant parameters (`hydraulic`, `seed002-type1`; SI units, pressures "
              "absolute).")


# ------------------------------------------------------------------- study
class FrictionModelsStudy(Study):
    """Seed 002 reproduced on the hydraulic plant: does LuGre oscillate where the NMLGM does not?"""

    name = "friction-models"
    cost = 5.0
    title = "Friction models in an electrohydraulic servo: Tran, Dao & Yanada (2014) reproduced"
    summary = ("Steady-state, LuGre and NMLGM friction in the hydraulic servo of seed 002: "
               "high-frequency content, the paper's claim tested, and when it holds.")
    paper = PAPER
    figure_label = "Report figure"

    def finding(self, results: dict[str, Any]) -> Finding:
        return finding(results)

    def key_figure(self, results: dict[str, Any]) -> str | None:
        return "sweep"

    def headline(self, results: dict[str, Any]) -> str:
        r = results["paper_case"]["ratio_lugre_to_nmlgm"]
        n = sum(s["claim_holds"] for s in results["sweep"])
        return (f"claim {'reproduced' if results['claim_reproduced'] else 'not reproduced'} "
                f"with the assumed parameters (LuGre/NMLGM HF velocity ratio {r['velocity']:.2f}); "
                f"holds at {n} of {len(results['sweep'])} sweep points")

    def build(self, out: StudyOutput, config: StudyConfig) -> dict[str, Any]:
        results, runs = run_study(config.fast, progress=config.progress)
        results["findings"] = findings(results)
        write_report(out, results, runs, config.fast)
        return results


STUDY = FrictionModelsStudy()
main = STUDY.main
