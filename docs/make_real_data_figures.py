"""Regenerate docs/real-data.md and its figures from the data sets shipped with fcomp.

    python docs/make_real_data_figures.py            # writes docs/real-data.md, docs/figures/*

Everything in docs/real-data.md (numbers, tables, figures) comes from this
script, run on ``fcomp/data/datasets`` (EMPS benchmark, TU Delft pneumatic
seal-friction tests) through the package's importers and ``FrictionFit``.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import fcomp.datasets as datasets  # noqa: E402
from fcomp.identification import FrictionFit, fit_data  # noqa: E402

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
FIG = DOCS / "figures"

#: IDIM-LS values of the EMPS benchmark (Janot, Gautier, Brunot 2019) as obtained with the
#: benchmark's own scripts and quoted in github.com/meco-group/nlgreyfast
#: (nlgreyfast_emps_example.m, ``param_idimls_v``).
EMPS_REFERENCE = {"mass": 95.1089, "B": 203.5034, "Fc": 20.3935, "offset": -3.1648}


def fmt(x: float, se: float | None = None) -> str:
    if se is None or not math.isfinite(se):
        return f"{x:.4g}"
    digits = max(0, 1 - int(math.floor(math.log10(abs(se))))) if se > 0 else 3
    return f"{x:.{digits}f} ± {se:.{digits}f}" if digits < 8 else f"{x:.4g} ± {se:.2g}"


def fit_or_none(model: str, data, **kw) -> FrictionFit | None:
    try:
        return FrictionFit(model, **kw).fit(data)
    except ValueError as exc:  # FcompError / ConvergenceError: reported in the table
        print(f"  {model} {kw}: {exc}", file=sys.stderr)
        return None


# ------------------------------------------------------------------------ EMPS
def emps() -> dict:
    est = datasets.load("emps", "DATA_EMPS.mat")
    val = datasets.load("emps", "DATA_EMPS_PULSES.mat")
    runs = {}
    for label, model, kw in [
        ("coulomb-viscous + offset", "coulomb-viscous", {"offset": True}),
        ("coulomb-viscous, directional", "coulomb-viscous", {"directional": True}),
        ("dahl + offset", "dahl", {"offset": True}),
        ("lugre + offset", "lugre", {"offset": True}),
    ]:
        t0 = time.perf_counter()
        fit = fit_or_none(model, est, **kw)
        runs[label] = (fit, time.perf_counter() - t0)
    cv = runs["coulomb-viscous + offset"][0]
    if cv is None:
        raise SystemExit("the EMPS coulomb-viscous fit failed")

    # figure: measured vs predicted force, estimation and validation records
    fig, axs = plt.subplots(3, 1, figsize=(9, 9))
    for ax, data, title in ((axs[0], est, "estimation record DATA_EMPS"),
                            (axs[1], val, "validation record DATA_EMPS_PULSES")):
        d = fit_data(data, cutoff_hz=cv.cutoff_hz)
        y, yh = cv.target(data), cv.predict(data)
        ax.plot(d.sig["t"], y, lw=0.8, label="motor force (filtered), N")
        ax.plot(d.sig["t"], yh, lw=0.8, label="M*a + Fc*sign(v) + B*v + offset")
        ax.plot(d.sig["t"], y - yh, lw=0.8, label="residual")
        ax.set_title(f"{title}: RMS error over all samples {np.sqrt(np.mean((y - yh) ** 2)):.2f} N")
        ax.set_xlabel("t, s")
        ax.legend(fontsize=7, loc="upper right")
    d = fit_data(est, cutoff_hz=cv.cutoff_hz)
    fric = d.y - cv.params_["mass"] * d.inertia - cv.params_["offset"]
    v = d.sig["v"]
    axs[2].plot(v, fric, ".", ms=1, alpha=0.4, label="F_ext - M*a - offset (estimation record)")
    vv = np.linspace(v.min(), v.max(), 400)
    axs[2].plot(vv, cv.model_.steady_state(vv), "k", lw=1.2, label="fitted Fc*sign(v) + B*v")
    axs[2].set_xlabel("v, m/s")
    axs[2].set_ylabel("friction, N")
    axs[2].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(FIG / "emps_fit.png", dpi=110)
    plt.close(fig)

    rows = []
    for label, (fit, secs) in runs.items():
        if fit is None:
            rows.append({"label": label, "failed": True})
            continue
        rows.append({"label": label, "params": fit.params_, "stderr": fit.stderr_,
                     "ci": fit.ci_, "rms": fit.rms_, "rms_validation": fit.score(val),
                     "seconds": secs, "not_identifiable": fit.not_identifiable_,
                     "tau_int": fit.tau_int_, "n": fit.n_samples_,
                     "warnings": [w.to_dict() for w in fit.warnings_]})
    return {"rows": rows}


# ---------------------------------------------------------------------- Zillen
def zillen() -> dict:
    out: dict = {"seals": {}, "repeat": []}
    models = [("coulomb + offset", "coulomb", {"offset": True}),
              ("coulomb-viscous + offset", "coulomb-viscous", {"offset": True}),
              ("lugre + offset", "lugre", {"offset": True})]
    for seal in ("O-ring", "NAPN"):
        rows = []
        for bar in (1, 3, 5, 7):
            data = datasets.load("zillen", f"{seal}_{bar}bar.csv")
            p = float(np.median(data["p1"]))
            row = {"file": f"{seal}_{bar}bar.csv", "p": p}
            for label, model, kw in models:
                fit = fit_or_none(model, data, **kw)
                row[label] = None if fit is None else {
                    "params": fit.params_, "stderr": fit.stderr_, "ci": fit.ci_,
                    "rms": fit.rms_, "not_identifiable": fit.not_identifiable_,
                    "tau_int": fit.tau_int_}
            rows.append(row)
        out["seals"][seal] = rows
    for name in ("rerun_1_O-ring257_3bar.csv", "reconnected_3_O-ring257_3bar.csv"):
        fit = FrictionFit("coulomb", offset=True).fit(datasets.load("zillen", name))
        out["repeat"].append({"file": name, "Fc": fit.params_["Fc"], "se": fit.stderr_["Fc"],
                              "ci": fit.ci_["Fc"], "offset": fit.params_["offset"],
                              "rms": fit.rms_})

    # figure: Coulomb level vs chamber pressure, with 95 % intervals and a line
    fig, ax = plt.subplots(figsize=(7, 4.5))
    lines = {}
    for seal, marker in (("O-ring", "o"), ("NAPN", "s")):
        rows = [r for r in out["seals"][seal] if r["coulomb + offset"]]
        p = np.array([r["p"] for r in rows]) / 1e5
        fc = np.array([r["coulomb + offset"]["params"]["Fc"] for r in rows])
        ci = np.array([r["coulomb + offset"]["ci"]["Fc"] for r in rows])
        se = np.array([r["coulomb + offset"]["stderr"]["Fc"] for r in rows])
        ax.errorbar(p, fc, yerr=[fc - ci[:, 0], ci[:, 1] - fc], fmt=marker, capsize=3,
                    label=f"{seal}: Fc (coulomb + offset fit), 95 % CI")
        w = 1.0 / se**2
        A = np.column_stack([np.ones_like(p), p])
        coef = np.linalg.solve(A.T @ (A * w[:, None]), A.T @ (w * fc))
        pp = np.linspace(0, 7.5, 50)
        ax.plot(pp, coef[0] + coef[1] * pp, "--", lw=0.8)
        lines[seal] = {"Fc0": coef[0], "slope_per_bar": coef[1]}
    ax.set_xlabel("chamber pressure, bar (gauge)")
    ax.set_ylabel("Coulomb level Fc, N")
    ax.set_xlim(0, 7.5)
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(FIG / "zillen_fc_vs_pressure.png", dpi=110)
    plt.close(fig)
    out["lines"] = lines

    # figure: one record in detail (O-ring 5 bar)
    data = datasets.load("zillen", "O-ring_5bar.csv")
    fits = {label: fit_or_none(model, data, **kw) for label, model, kw in models}
    d = fit_data(data, mass=0.0)
    fig, axs = plt.subplots(2, 1, figsize=(9, 7))
    sel = (d.sig["t"] > 20) & (d.sig["t"] < 45)
    axs[0].plot(d.sig["t"][sel], d.y[sel], "k", lw=0.8, label="p*A + F_ext (friction), N")
    for label, fit in fits.items():
        if fit is not None:
            axs[0].plot(d.sig["t"][sel], fit.predict(data)[sel], lw=0.8,
                        label=f"{label} (RMS {fit.rms_:.2f} N)")
    axs[0].set_xlabel("t, s")
    axs[0].legend(fontsize=7)
    axs[0].set_title("O-ring, 5 bar: measured friction and fitted models (20-45 s)")
    axs[1].plot(d.sig["v"] * 1e3, d.y, ".", ms=1, alpha=0.4, color="k", label="measured")
    for label, fit in fits.items():
        if fit is not None:
            axs[1].plot(d.sig["v"] * 1e3, fit.predict(data), ".", ms=1, alpha=0.5, label=label)
    axs[1].set_xlabel("v, mm/s")
    axs[1].set_ylabel("friction, N")
    axs[1].legend(fontsize=7, markerscale=8)
    fig.tight_layout()
    fig.savefig(FIG / "zillen_oring_5bar.png", dpi=110)
    plt.close(fig)
    return out


# ------------------------------------------------------------ command transcripts
#: The commands whose output docs/real-data.md shows, run as a user would (shipped files
#: named by their path in the repository).
SESSION = [
    "fcomp import zillen fcomp/data/datasets/zillen/O-ring_3bar.csv -o oring3.csv",
    "fcomp fit oring3.csv --friction lugre",
    "fcomp fit oring3.csv --friction coulomb-viscous",
    "fcomp import emps fcomp/data/datasets/emps/DATA_EMPS.mat -o emps.csv",
    "fcomp fit emps.csv --friction nmlgm",
    "fcomp fit emps.csv --friction nmlgm --offset",
    "fcomp diagnose emps.csv --friction coulomb-viscous --no-progress",
    *(f"fcomp import zillen fcomp/data/datasets/zillen/O-ring_{k}bar.csv -o or{k}.csv"
      for k in (1, 3, 5, 7)),
    "fcomp diagnose or1.csv or3.csv or5.csv or7.csv --friction lugre --no-progress",
]


def transcripts() -> dict[str, str]:
    """Each command of :data:`SESSION` with what it prints (standard output, then the
    warnings on standard error, as a terminal shows them), run in a scratch folder."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for cmd in SESSION:
            args = [str(ROOT / a) if a.startswith("fcomp/data/") else a
                    for a in cmd.split()[1:]]
            proc = subprocess.run([sys.executable, "-m", "fcomp.cli.main", *args], cwd=tmp,
                                  env=env, capture_output=True, text=True, check=True)
            out[cmd] = f"$ {cmd}\n{proc.stdout}{proc.stderr}".rstrip()
    return out


def seals(reuse: Path | None = None) -> dict:
    """The real seals diagnosed and the 7 bar level predicted from 1-5 bar
    (``benchmarks/bench_real_seals.py --predict``; its JSON ``reuse``d when given)."""
    if reuse is not None:
        return json.loads(reuse.read_text())
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "seals.json"
        subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_real_seals.py"),
                        "--predict", "--json", str(out)], check=True,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)), capture_output=True)
        return json.loads(out.read_text())


def seals_md(res: dict) -> tuple[str, str]:
    """The table of the real records' diagnoses and that of the 7 bar predictions."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from bench_real_seals import prediction_table, table

    return table(res["table"]), prediction_table(res["prediction"])


def session_md(shown: dict[str, str], *commands: str) -> str:
    """A fenced block with the transcripts of ``commands`` (from :func:`transcripts`)."""
    return "```text\n" + "\n".join(shown[c] for c in commands) + "\n```"


# -------------------------------------------------------------------- markdown
def emps_md(res: dict) -> str:
    cv = next(r for r in res["rows"] if r["label"] == "coulomb-viscous + offset")
    lines = [
        "| parameter | fcomp (± standard error) | 95 % interval | IDIM-LS reference | difference / SE |",
        "|---|---|---|---|---|",
    ]
    units = {"mass": "kg", "B": "Ns/m", "Fc": "N", "offset": "N"}
    for k in ("mass", "Fc", "B", "offset"):
        v, se = cv["params"][k], cv["stderr"][k]
        lo, hi = cv["ci"][k]
        ref = EMPS_REFERENCE[k]
        lines.append(f"| `{k}` ({units[k]}) | {fmt(v, se)} | [{lo:.4g}, {hi:.4g}] | {ref} | "
                     f"{(v - ref) / se:+.1f} |")
    table2 = ["| model | parameters (± SE) | RMS estimation, N | RMS validation, N | time, s "
              "| warnings |",
              "|---|---|---|---|---|---|"]
    for r in res["rows"]:
        if r.get("failed"):
            table2.append(f"| {r['label']} | did not converge | | | | |")
            continue
        ps = ", ".join(f"{k} = {fmt(v, r['stderr'][k])}" for k, v in r["params"].items())
        if r["not_identifiable"]:
            ps += f" (not determined: {', '.join(r['not_identifiable'])})"
        warned = ", ".join(f"`{w['code']}` {w['parameter'] or ''}".strip()
                           for w in r["warnings"]) or "none"
        table2.append(f"| {r['label']} | {ps} | {r['rms']:.3f} | {r['rms_validation']:.3f} | "
                      f"{r['seconds']:.1f} | {warned} |")
    return "\n".join(lines), "\n".join(table2), cv


def zillen_md(res: dict) -> str:
    out = []
    for seal, rows in res["seals"].items():
        out.append(f"**{seal}** (25 mm bore)\n")
        out.append("| p, bar | Fc (coulomb + offset), N | offset, N | RMS, N | "
                   "coulomb-viscous + offset: Fc, B | RMS, N | lugre + offset: RMS, N | mass, kg |")
        out.append("|---|---|---|---|---|---|---|---|")
        for r in rows:
            c, cvf, lg = r["coulomb + offset"], r["coulomb-viscous + offset"], r["lugre + offset"]
            c_txt = (f"{fmt(c['params']['Fc'], c['stderr']['Fc'])} | "
                     f"{fmt(c['params']['offset'], c['stderr']['offset'])} | {c['rms']:.2f}"
                     ) if c else "failed | | "
            cv_txt = (f"{fmt(cvf['params']['Fc'], cvf['stderr']['Fc'])}, "
                      f"{fmt(cvf['params']['B'], cvf['stderr']['B'])} | {cvf['rms']:.2f}"
                      ) if cvf else "failed | "
            lg_txt = f"{lg['rms']:.2f}" if lg else "did not converge"
            mass = c["params"].get("mass") if c else None
            m_txt = fmt(mass, c["stderr"]["mass"]) if mass is not None else "-"
            out.append(f"| {r['p'] / 1e5:.2f} | {c_txt} | {cv_txt} | {lg_txt} | {m_txt} |")
        ln = res["lines"][seal]
        out.append(f"\nWeighted line through the four levels: Fc = {ln['Fc0']:.2f} N + "
                   f"{ln['slope_per_bar']:.3f} N/bar * p.\n")
    rep = res["repeat"]
    out.append("**Repeatability** (O-ring in the 25.7 mm bore, 3 bar, coulomb + offset):\n")
    out.append("| file | Fc, N | 95 % interval | offset, N | RMS, N |")
    out.append("|---|---|---|---|---|")
    for r in rep:
        out.append(f"| {r['file']} | {fmt(r['Fc'], r['se'])} | [{r['ci'][0]:.3f}, "
                   f"{r['ci'][1]:.3f}] | {r['offset']:.3f} | {r['rms']:.2f} |")
    return "\n".join(out)


TEMPLATE = """# Real data: identification results

*Generated by `python docs/make_real_data_figures.py` from the data sets shipped in
`fcomp/data/datasets` (provenance and licences in docs/data.md); do not edit by hand.*
How the fits work: [identification.md](identification.md).

## EMPS (electro-mechanical positioning system)

Janot, Gautier & Brunot's benchmark (2019 Workshop on Nonlinear System
Identification Benchmarks): a prismatic axis driven by a DC motor through a
ball screw, 1 kHz, position `qm` from the encoder, motor force `gtau*vir`
(`F_ext`), measured **in closed loop** (position controller with gains `kp`,
`kv`). No mass is given, so `fcomp fit` estimates it with the rigid-body
inverse model `M*a + Fc*sign(v) + B*v + offset = F_ext`:

```bash
fcomp import emps DATA_EMPS.mat -o emps.csv
fcomp fit emps.csv --friction coulomb-viscous --offset --json emps.json
```

(`v`, `a` from `qm` by the zero-phase 10 Hz Butterworth of
`fcomp.reconstruction`, the force filtered alike.) Against the IDIM-LS values
of the benchmark's own scripts (as quoted in `meco-group/nlgreyfast`):

{emps_table}

The mass agrees with the reference to {mass_rel:.1f} %, every parameter within
{max_z:.1f} standard errors. The residual RMS is {cv_rms:.2f} N on the
estimation record and {cv_val:.2f} N on the validation record
`DATA_EMPS_PULSES` (force pulses added), predicted with the estimation
values: the rigid model with Coulomb and viscous friction generalises.

Other models on the same record (all with `mass` estimated):

{emps_models}

* Direction-dependent friction (`--directional`, no offset: the two are
  confounded) lowers the error: the viscous coefficient differs between the
  directions, which the symmetric model with offset can only average.
* LuGre and Dahl add a bristle state; LuGre improves the RMS error, but
  its `Fc`, `Fs`, `vs` trade against each other on this record (look at
  their standard errors; `Fc` ends at its bound 0, the warnings column): the
  ball screw's friction has no clear Stribeck hump at the speeds the
  trajectory visits.
* **Bias.** The data are closed loop: the motor force is computed from the
  position error, so the measurement noise of `qm` enters both the regressors
  (`a`, `v`) and the force. Ordinary least squares on such data is biased in
  principle (Janot et al. use instrumental variables, IDIM-IV, for that
  reason). The bias is small here because the encoder is precise and the
  filter removes most of the noise before differentiation, but the standard
  errors above describe noise only: they do not bound that bias, nor the
  bias of the filter (the smoothed Coulomb steps; a few per cent on `Fc`
  in the package's tests). The batch-means standard errors account for the
  residual autocorrelation (integrated autocorrelation time
  {cv_tau:.0f} samples here); the i.i.d. formula would be several times smaller.

![EMPS fit](figures/emps_fit.png)

*Top: estimation record, filtered motor force, the fitted inverse model and the
residual. Middle: validation record with the same parameters. Bottom:
friction (`F_ext - M*a - offset`) against velocity with the fitted
Coulomb-viscous map.*

## TU Delft pneumatic cylinders (Zillen, Vallery & Smit 2021)

Seal-friction tests of 3D-printed pneumatic actuators: a 25 mm bore pushed
back and forth through a load cell over ~40 mm at two speeds (about
+11.5 mm/s extending and -5.5 mm/s retracting) with the chamber held at 1, 3,
5 and 7 bar. The importer gives `x`, `p1` (one chamber, the other side
open) and `F_ext = -(load cell)`, so the friction is `p1*A1 + F_ext` (minus
the mass term, which `fcomp fit` estimates: such slow motion does not
determine it, it ends at its bound 0 and `fit` warns `mass-implausible`, see
[Warnings](#warnings-what-the-records-do-not-establish)). Per file and pressure level:

```bash
fcomp import zillen O-ring_5bar.csv -o oring5.csv
fcomp fit oring5.csv --friction coulomb --offset --json oring5.json
```

{zillen_tables}

![Coulomb level against chamber pressure](figures/zillen_fc_vs_pressure.png)

*Coulomb level (half the difference between the extending and retracting
friction at the test speeds) against chamber pressure, 95 % intervals, with
the weighted straight line. The seals' normal force, and so the friction,
grows with pressure (seed 000 Fig. 12, seed 001 Eq. 1): the
`pressure-dependence` effect.*

![O-ring at 5 bar](figures/zillen_oring_5bar.png)

*O-ring at 5 bar. Top: friction and fits over two strokes. Bottom: against
velocity.*

What the fits show, and what they cannot:

* The friction level grows with pressure for both seals, roughly linearly:
  {slope_oring:.2f} N/bar for the O-ring and {slope_napn:.2f} N/bar for the NAPN
  seal (weighted lines above); the intervals at 1 bar and 7 bar are far apart.
  The NAPN seal's level grows about {slope_ratio:.1f} times as fast with pressure.
* The `offset` is large and grows with pressure: extending and retracting
  friction differ (by twice the offset). With one speed per direction this
  direction asymmetry cannot be told apart from a constant force offset
  (a load-cell zero or a vertical mounting); the two are confounded.
* **Coulomb-viscous on two speeds.** With one speed per direction, `Fc` and
  `B` are separated only by the samples in the transitions at the reversals,
  which are dynamic (the seal's pre-sliding, which a static map cannot
  follow), so the split is model error rather than physics, however small
  its standard errors (they measure noise, not the model's inadequacy).
  `coulomb + offset` gives the robust quantity: the level at the test speeds.
* LuGre reproduces the transitions after each reversal (the bristle
  stiffness and damping) and lowers the RMS error by {lugre_gain:.0f} % on average
  against coulomb + offset; on a two-speed record its Stribeck parameters
  are weakly determined or not at all (listed as not determined in
  `real_data_results.json`, large errors otherwise).
* Repeatability: the two 3 bar records of the O-ring in the 25.7 mm bore (a
  rerun, and a run after disconnecting and reconnecting the set-up) give
  Coulomb levels {rep_diff:.2f} N apart, {rep_z:.0f} combined standard errors:
  run-to-run variation of the set-up that the standard errors of one record
  do not contain. They describe the noise in one record, not the whole
  uncertainty of a friction measurement.

## Warnings: what the records do not establish

Every fit is checked for what a careful engineer would question
([identification.md](identification.md#warnings-plausibility-of-the-estimates)
has the rules): an estimate at a bound of its range (`at-bound`), a positive
quantity whose interval reaches zero (`interval-crosses-zero`), a moving mass
the rig cannot have (`mass-implausible`), parameters the record does not
determine or that trade off (`not-identified`, with the experiment that would
determine them, worded for the rig in the sidecar's `kind`), a fit that did not
converge (`not-converged`). `fcomp fit` prints them under its table, one
`fcomp: warning:` line each, and lists them in the JSON's `warnings`.

**Zillen O-ring, 3 bar, LuGre.** The fit lowers the error, but its Coulomb
level's interval reaches below zero (the record, at one speed per direction,
does not establish it) and the Stribeck exponent `n` sits at its upper bound:

{session_lugre}

**The same record, Coulomb-viscous, mass estimated.** At about 10 mm/s the
acceleration is too small to weigh the piston: the mass ends at its bound
zero, below what a piston of the 25 mm bore can weigh, and the viscous
coefficient at its bound too (without `--offset`, the difference between the
extending and retracting friction of this record would need a negative `B`).
Give the mass (`--mass`, or `rig.mass` in the sidecar) and fit with
`--offset`:

{session_cv}

**EMPS, NMLGM.** The full fit (every NMLGM parameter free) stops at its
evaluation budget; the parameters it barely determines where it stopped
(standard error above their value) are then held there and the others
refitted, which converges. The held ones are shown as such in the table, and
each warning names the experiment that would determine it. Parameters that
still trade off are named with their correlation. The standard errors of the
others are conditional on the held values: `Fs` six times `Fc` is how this
model bends its film transients to the record, not a break-away force the
record shows.

{session_nmlgm}

Most of that trouble is the record's constant force offset, which no friction
term produces and the model contorts itself to imitate. With `--offset` the
full fit converges at once (the film parameters but `tau_hp`, which the motion
never exercises, held), its error falls well below the fit without offset, and
the warnings narrow to what the record really leaves open: `n` at its bound,
the bristle stiffness and damping not established and trading off. `Fs` is
again several times `Fc`: the same film transients.

{session_nmlgm_offset}

**EMPS, diagnosis.** The importer writes `kind = "electromechanical-axis"`,
so the experiments that separate confounded effects are worded for a motor-driven
axis (no chambers to vent):

{session_diag}

## The real seals diagnosed

Every shipped record set diagnosed as a user types it (`fcomp diagnose FILES
--friction BASELINE --json OUT`, the default baseline check), by
`python benchmarks/bench_real_seals.py --predict` on a 2-core machine shared with
other work (times are wall times there). Held-out RMS of the scored residual;
ties, pairs (effects that qualified only together, docs/diagnosis.md section 3)
and the forms of the pressure law kept are in brackets:

{seals_table}

**The 7 bar level predicted from 1, 3 and 5 bar.** Each seal diagnosed from
LuGre on its 1, 3 and 5 bar records alone (`--save-model`), its final model (with
its measurement terms, as fitted) run along the 7 bar record's motion, and the
friction level there: the median over the steady sliding samples of each
direction, measured and predicted:

{seals_prediction}

**Zillen O-ring, 1-7 bar together, diagnosed from LuGre.** The whole output, as
a terminal shows it (the progress bar is drawn on a terminal only):

{session_oring}
"""


def main(argv: list[str] | None = None) -> None:
    import argparse

    p = argparse.ArgumentParser(description="Regenerate docs/real-data.md and its figures.")
    p.add_argument("--seals-json", type=Path, default=None,
                   help="the JSON of benchmarks/bench_real_seals.py --predict to use instead "
                   "of running it")
    args = p.parse_args(argv)
    FIG.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    seals_table, seals_prediction = seals_md(seals(args.seals_json))
    e = emps()
    z = zillen()
    emps_table, emps_models, cv = emps_md(e)
    zs = [abs(cv["params"][k] - ref) / cv["stderr"][k] for k, ref in EMPS_REFERENCE.items()]
    lines = z["lines"]
    gains = [1 - r["lugre + offset"]["rms"] / r["coulomb + offset"]["rms"]
             for rows in z["seals"].values() for r in rows
             if r["lugre + offset"] and r["coulomb + offset"]]
    a, b = z["repeat"]
    shown = transcripts()
    text = TEMPLATE.format(
        session_lugre=session_md(shown, *SESSION[:2]), session_cv=session_md(shown, SESSION[2]),
        session_nmlgm=session_md(shown, *SESSION[3:5]),
        session_nmlgm_offset=session_md(shown, SESSION[5]),
        session_diag=session_md(shown, SESSION[6]),
        session_oring=session_md(shown, *SESSION[7:12]),
        seals_table=seals_table, seals_prediction=seals_prediction,
        emps_table=emps_table, emps_models=emps_models, cv_rms=cv["rms"],
        cv_val=cv["rms_validation"], cv_tau=cv["tau_int"], zillen_tables=zillen_md(z),
        mass_rel=100 * abs(cv["params"]["mass"] / EMPS_REFERENCE["mass"] - 1), max_z=max(zs),
        slope_oring=lines["O-ring"]["slope_per_bar"], slope_napn=lines["NAPN"]["slope_per_bar"],
        slope_ratio=lines["NAPN"]["slope_per_bar"] / lines["O-ring"]["slope_per_bar"],
        lugre_gain=100 * float(np.mean(gains)), rep_diff=abs(a["Fc"] - b["Fc"]),
        rep_z=abs(a["Fc"] - b["Fc"]) / math.hypot(a["se"], b["se"]))
    (DOCS / "real-data.md").write_text(text)
    (FIG / "real_data_results.json").write_text(json.dumps({"emps": e, "zillen": z}, indent=1,
                                                           default=float))
    print(f"wrote docs/real-data.md and docs/figures/ in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
