"""The analysis of study ``coulomb-viscous``: seed 001 reproduced, then its assumptions tested.

Seed 001 (Dağdelen & Sarıgeçili 2020, J. Eng. Sci. Design 8(2) 397-406)
identifies the Coulomb-viscous model of a pneumatic cylinder pushed by hand
with both chambers open to atmosphere (seed 001 Eqs. 4-5)::

    F_ext = Fc + B * v                          (N; v in m/s, B in Ns/m)

in two steps: (1) ``Fc`` is the force at which the rod starts to move (the
break-away force), read at 12 positions along the stroke in 10 experiments
per direction (Tables 2, 3); (2) at a constant speed ``v_i`` the applied
force ``F_ext_i`` gives ``B_i = (F_ext_i - mean(Fc)) / v_i`` (Tables 4, 5).
Table 8 gives Student-t 95 % intervals ``mean +- t(0.975, n-1) s / sqrt(n)``
with ``s`` the sample standard deviation.

What this module computes, from the tables shipped in
``fcomp/data/datasets/seed001`` (via :mod:`fcomp.datasets`):

* **Table 8** for cylinder C1 from the raw values (Fc: the 120 break-away
  forces, 119 dof; B: the 10 experiments, 9 dof) and for cylinder C2 from
  what the paper prints (per-experiment averages only), with every number
  beside the printed one and the reason wherever they differ;
* what the printed C2 numbers imply (the sample size behind them, a
  population standard deviation, means that do not match their table);
* the paper's assumptions put to its own data: is the break-away force
  independent of the position along the stroke, are the 120 values
  independent and normal, is the break-away force the Coulomb level of the
  sliding force, is B constant over speed, do extension and retraction
  differ, and how uncertain is B once the uncertainty of ``mean(Fc)`` is
  carried into it.

All forces in N, speeds in m/s, viscous coefficients in Ns/m. The study
itself (:mod:`studies.coulomb_viscous`) runs this analysis and hands the
results to its report (:mod:`studies.coulomb_viscous_report`: text and
figures); docs/seed001.md summarises the results.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from fcomp.errors import FcompError

DIRECTIONS = ("extension", "retraction")
PARAMETERS = ("Fc_extension", "Fc_retraction", "B_extension", "B_retraction")
CYLINDERS = ("C1", "C2")

#: Confidence level of Table 8.
LEVEL = 0.95
#: Significance level of the assumption tests.
ALPHA = 0.05
#: Decimals of the Student-t quantile: the paper's digits are those of a printed
#: 3-decimal t table (t(0.975, 9) = 2.262, t(0.975, 119) = 1.980); ``None``: exact.
T_TABLE_DECIMALS = 3
#: A printed speed reproduces the printed B_i when they agree within this (Ns/m);
#: a speed rounded to 1 mm/s moves B_i by ~0.2-0.6 Ns/m, far more.
B_CONSISTENCY_TOL = 0.01
#: Resolution of the printed speeds (m/s): 3 decimals.
SPEED_RESOLUTION = 1e-3

#: Table 8 as printed: (standard deviation, lower limit, upper limit).
PAPER_TABLE8: dict[str, dict[str, tuple[float, float, float]]] = {
    "C1": {
        "Fc_extension": (1.225, 5.265, 5.708),
        "Fc_retraction": (1.275, 5.056, 5.516),
        "B_extension": (10.701, 95.774, 111.083),
        "B_retraction": (13.308, 75.395, 94.433),
    },
    "C2": {
        "Fc_extension": (1.605, 6.156, 6.736),
        "Fc_retraction": (2.216, 6.292, 7.093),
        "B_extension": (4.482, 44.475, 50.887),
        "B_retraction": (3.811, 42.662, 48.114),
    },
}
#: Means printed under Tables 2-7.
PAPER_MEANS: dict[str, dict[str, float]] = {
    "C1": {"Fc_extension": 5.486, "Fc_retraction": 5.286,
           "B_extension": 103.428, "B_retraction": 84.914},
    "C2": {"Fc_extension": 6.446, "Fc_retraction": 6.692,
           "B_extension": 47.681, "B_retraction": 45.387},
}
#: Per-experiment means printed at the foot of Tables 2 and 3 (C1), N.
PAPER_EXPERIMENT_MEANS: dict[str, tuple[float, ...]] = {
    "extension": (6.019, 5.098, 5.893, 5.794, 5.194, 5.821, 5.360, 4.997, 5.666, 5.020),
    "retraction": (5.148, 5.192, 5.727, 5.148, 5.404, 5.414, 5.782, 5.003, 4.774, 5.268),
}
FIELDS = ("std", "ci_low", "ci_high")


# ---------------------------------------------------------------------- data
@dataclass(frozen=True)
class Seed001Data:
    """The seed 001 tables (SI units).

    Attributes
    ----------
    fc
        Direction -> break-away forces, shape (12 position steps, 10 experiments), N.
    F_ext, v, B_printed
        Direction -> applied force (N), speed (m/s) and the printed B_i (Ns/m), 10 each.
    c2_fc, c2_B
        Direction -> C2 per-experiment averages of Fc (N) and B_i (Ns/m), 10 each.
    """

    fc: Mapping[str, np.ndarray]
    F_ext: Mapping[str, np.ndarray]
    v: Mapping[str, np.ndarray]
    B_printed: Mapping[str, np.ndarray]
    c2_fc: Mapping[str, np.ndarray]
    c2_B: Mapping[str, np.ndarray]


def _read_table(file: str, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
    import fcomp.datasets as datasets

    path = datasets.path("seed001", file)
    with path.open(newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        missing = set(columns) - set(reader.fieldnames or ())
        if missing:
            raise FcompError(f"{path}: missing column(s) {', '.join(sorted(missing))}")
        rows = list(reader)
    out: dict[str, np.ndarray] = {}
    for col in columns:
        try:
            out[col] = np.array([float(r[col]) for r in rows])
        except (TypeError, ValueError):
            raise FcompError(f"{path}: column {col!r} holds a value that is not a number") from None
        if not np.all(np.isfinite(out[col])):
            raise FcompError(f"{path}: column {col!r} holds a non-finite value")
    return out


def load_seed001() -> Seed001Data:
    """Read the seed 001 tables shipped with the package (Tables 2-7)."""
    fc, F, v, B, c2_fc, c2_B = {}, {}, {}, {}, {}, {}
    c2f = _read_table("c2_fc.csv", ("experiment", "Fc_extension", "Fc_retraction"))
    c2b = _read_table("c2_b.csv", ("experiment", "B_extension", "B_retraction"))
    for d in DIRECTIONS:
        t = _read_table(f"fc_{d}_c1.csv", ("position_step", "experiment", "Fc"))
        step, exp = t["position_step"].astype(int), t["experiment"].astype(int)
        grid = np.full((12, 10), np.nan)
        if step.min() < 1 or step.max() > 12 or exp.min() < 1 or exp.max() > 10:
            raise FcompError(f"fc_{d}_c1.csv: position steps must be 1-12, experiments 1-10")
        grid[step - 1, exp - 1] = t["Fc"]
        if np.isnan(grid).any() or len(step) != 120:
            raise FcompError(f"fc_{d}_c1.csv: expected 12 x 10 break-away forces")
        fc[d] = grid
        b = _read_table(f"b_{d}_c1.csv", ("experiment", "F_ext", "v", "B_reported"))
        if len(b["v"]) != 10 or np.any(b["v"] <= 0):
            raise FcompError(f"b_{d}_c1.csv: expected 10 experiments with positive speeds")
        F[d], v[d], B[d] = b["F_ext"], b["v"], b["B_reported"]
        c2_fc[d], c2_B[d] = c2f[f"Fc_{d}"], c2b[f"B_{d}"]
    return Seed001Data(fc, F, v, B, c2_fc, c2_B)


# ------------------------------------------------------------------ statistics
def t_quantile(dof: float, decimals: int | None = T_TABLE_DECIMALS, level: float = LEVEL) -> float:
    """Two-sided Student-t quantile ``t((1+level)/2, dof)``, rounded to ``decimals`` if given."""
    from scipy import stats

    t = float(stats.t.ppf(0.5 + level / 2.0, dof))
    return round(t, decimals) if decimals is not None else t


def t_interval(x: np.ndarray, *, decimals: int | None = T_TABLE_DECIMALS,
               ddof: int = 1) -> dict[str, float]:
    """Student-t interval of the mean: ``mean +- t(0.975, n-1) * s / sqrt(n)`` (seed 001 Table 8).

    ``s`` is the standard deviation with ``ddof`` (1: sample; 0: population).
    Returns ``mean, std, ci_low, ci_high, n, t``.
    """
    x = np.asarray(x, dtype=float).ravel()
    n = x.size
    mean, std = float(x.mean()), float(x.std(ddof=ddof))
    t = t_quantile(n - 1, decimals)
    half = t * std / math.sqrt(n)
    return {"mean": mean, "std": std, "ci_low": mean - half, "ci_high": mean + half,
            "n": n, "t": t}


def two_step_B(F: np.ndarray, v: np.ndarray, fc_mean: float,
               B_printed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-experiment ``B_i = (F_ext_i - mean Fc) / v_i`` (seed 001 Eq. 5, step 2).

    The printed speeds have 3 decimals; where the printed speed reproduces
    the printed ``B_i`` (within :data:`B_CONSISTENCY_TOL`), the recomputed
    value is kept (it carries more digits than the print); where it does not,
    the paper computed with an unrounded speed and the printed ``B_i`` is
    used. Returns ``(B, recomputed)`` with ``recomputed`` a boolean mask.
    """
    B_re = (F - fc_mean) / v
    ok = np.abs(B_re - B_printed) <= B_CONSISTENCY_TOL
    return np.where(ok, B_re, B_printed), ok


def summary_fields(ti: Mapping[str, float]) -> dict[str, float]:
    """The summary.json fields of a Table 8 interval: ``mean``, ``std``, ``ci_low``, ``ci_high``."""
    return {k: float(ti[k]) for k in ("mean", "std", "ci_low", "ci_high")}


def table8(data: Seed001Data, *, decimals: int | None = T_TABLE_DECIMALS,
           b_values: str = "reconstructed") -> dict[str, dict[str, dict[str, Any]]]:
    """Table 8 from the tables, with details (``n``, ``t``, what the values are).

    Parameters
    ----------
    decimals
        Decimals of the t quantile (3: printed table; ``None``: exact).
    b_values
        C1 B_i used: ``"reconstructed"`` (:func:`two_step_B`), ``"printed"``
        (Tables 4-5 as printed) or ``"recomputed"`` (from the printed F_ext, v).

    Returns
    -------
    ``{"C1": {param: {mean, std, ci_low, ci_high, n, t, values}}, "C2": {...}}``.
    C2 Fc is computed from the 10 per-experiment averages of Table 6 (the
    120 single values behind the paper's numbers are not printed).
    """
    if b_values not in ("reconstructed", "printed", "recomputed"):
        raise FcompError(f"b_values must be reconstructed, printed or recomputed, got {b_values!r}")
    out: dict[str, dict[str, dict[str, Any]]] = {"C1": {}, "C2": {}}
    for d in DIRECTIONS:
        fc = data.fc[d].ravel()
        out["C1"][f"Fc_{d}"] = {**t_interval(fc, decimals=decimals),
                                "values": "120 break-away forces (12 positions x 10 experiments)"}
        if b_values == "printed":
            B = data.B_printed[d]
        elif b_values == "recomputed":
            B = (data.F_ext[d] - fc.mean()) / data.v[d]
        else:
            B, _ = two_step_B(data.F_ext[d], data.v[d], fc.mean(), data.B_printed[d])
        out["C1"][f"B_{d}"] = {**t_interval(B, decimals=decimals),
                               "values": f"10 two-step B_i ({b_values})"}
        out["C2"][f"Fc_{d}"] = {**t_interval(data.c2_fc[d], decimals=decimals),
                                "values": "10 per-experiment averages (Table 6)"}
        out["C2"][f"B_{d}"] = {**t_interval(data.c2_B[d], decimals=decimals),
                               "values": "10 B_i (Table 7)"}
    return out


def implied_sample_size(std: float, low: float, high: float, *,
                        resolution: float = 1e-3) -> dict[str, float]:
    """The ``n`` behind a printed interval ``mean +- t(0.975, n-1) std / sqrt(n)``.

    Solves ``t(0.975, n-1) * std / sqrt(n) = (high - low) / 2`` for a
    continuous ``n``, and the range of ``n`` the rounding of the three
    printed numbers (half a unit of ``resolution`` each) allows.
    """
    from scipy import optimize

    def n_for(s: float, h: float) -> float:
        f = lambda n: t_quantile(n - 1.0, None) * s / math.sqrt(n) - h  # noqa: E731
        return float(optimize.brentq(f, 2.0001, 1e7))

    half = (high - low) / 2.0
    r = resolution / 2.0
    return {"n": n_for(std, half), "n_min": n_for(std - r, half + r),
            "n_max": n_for(std + r, half - r)}


def ols_line(x: np.ndarray, y: np.ndarray) -> dict[str, Any]:
    """Least-squares line ``y = a + b x`` with standard errors, 95 % intervals, R^2, p of b."""
    from scipy import stats

    fit = stats.linregress(x, y)
    n = len(x)
    t = t_quantile(n - 2, None)
    return {
        "intercept": float(fit.intercept), "intercept_se": float(fit.intercept_stderr),
        "intercept_ci": [float(fit.intercept - t * fit.intercept_stderr),
                         float(fit.intercept + t * fit.intercept_stderr)],
        "slope": float(fit.slope), "slope_se": float(fit.stderr),
        "slope_ci": [float(fit.slope - t * fit.stderr), float(fit.slope + t * fit.stderr)],
        "r2": float(fit.rvalue**2), "slope_p": float(fit.pvalue), "n": n,
    }


def linear_model(X: np.ndarray, y: np.ndarray, names: tuple[str, ...]) -> dict[str, dict[str, float]]:
    """Ordinary least squares ``y = X beta``: coefficient, standard error, t, two-sided p."""
    from scipy import stats

    n, k = X.shape
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    resid = y - X @ beta
    s2 = float(resid @ resid) / (n - k)
    se = np.sqrt(np.diag(s2 * np.linalg.inv(X.T @ X)))
    tval = beta / se
    p = 2.0 * stats.t.sf(np.abs(tval), n - k)
    return {nm: {"coef": float(b), "se": float(s), "t": float(tv), "p": float(pp)}
            for nm, b, s, tv, pp in zip(names, beta, se, tval, p, strict=True)}


def two_way_anova(M: np.ndarray) -> dict[str, float]:
    """Two-way ANOVA without replication: rows (positions) x columns (experiments).

    ``SS_rows = b sum(rowmean - g)^2``, ``SS_cols = a sum(colmean - g)^2``,
    ``SS_err = SS_tot - SS_rows - SS_cols`` with ``(a-1)(b-1)`` dof.
    """
    from scipy import stats

    a, b = M.shape
    g = M.mean()
    ss_r = b * float(((M.mean(axis=1) - g) ** 2).sum())
    ss_c = a * float(((M.mean(axis=0) - g) ** 2).sum())
    ss_e = float(((M - g) ** 2).sum()) - ss_r - ss_c
    df_r, df_c, df_e = a - 1, b - 1, (a - 1) * (b - 1)
    ms_e = ss_e / df_e
    F_r, F_c = ss_r / df_r / ms_e, ss_c / df_c / ms_e
    return {"F_rows": F_r, "p_rows": float(stats.f.sf(F_r, df_r, df_e)),
            "F_cols": F_c, "p_cols": float(stats.f.sf(F_c, df_c, df_e)),
            "df_rows": df_r, "df_cols": df_c, "df_err": df_e}


def intraclass_correlation(M: np.ndarray) -> float:
    """ICC(1) of the columns (experiments) of ``M``: ``(MSB - MSW) / (MSB + (k-1) MSW)``."""
    k, m = M.shape
    col = M.mean(axis=0)
    msb = k * float(((col - M.mean()) ** 2).sum()) / (m - 1)
    msw = float(((M - col) ** 2).sum()) / (m * (k - 1))
    return (msb - msw) / (msb + (k - 1) * msw)


# ------------------------------------------------------------- the analyses
def reproduction(ours: Mapping[str, Mapping[str, Mapping[str, float]]]) -> list[dict[str, Any]]:
    """Every Table 8 number beside the printed one (3 decimals, as printed)."""
    rows = []
    for cyl in CYLINDERS:
        for par in PARAMETERS:
            for i, field in enumerate(FIELDS):
                value, paper = float(ours[cyl][par][field]), PAPER_TABLE8[cyl][par][i]
                rows.append({"cylinder": cyl, "parameter": par, "field": field,
                             "computed": value, "paper": paper,
                             "match": f"{value:.3f}" == f"{paper:.3f}"})
    return rows


def c2_reconstruction(data: Seed001Data) -> dict[str, Any]:
    """What the printed C2 numbers imply (Tables 6-8)."""
    out: dict[str, Any] = {}
    for d in DIRECTIONS:
        std, lo, hi = PAPER_TABLE8["C2"][f"Fc_{d}"]
        avg = data.c2_fc[d]
        n_imp = implied_sample_size(std, lo, hi)
        n = round(n_imp["n"])
        half = t_quantile(n - 1) * std / math.sqrt(n)
        mean6 = float(avg.mean())
        out[f"Fc_{d}"] = {
            "implied_n": n_imp,
            "paper_mean": PAPER_MEANS["C2"][f"Fc_{d}"],
            "paper_ci_centre": (lo + hi) / 2.0,
            "table6_mean": mean6,
            "table6_std_of_averages": float(avg.std(ddof=1)),
            "paper_std_over_sqrt12": std / math.sqrt(12),
            "interval_paper_std_table6_mean": [mean6 - half, mean6 + half],
            "interval_paper_std_paper_centre": [(lo + hi) / 2 - half, (lo + hi) / 2 + half],
        }
        B = data.c2_B[d]
        std_p, lo_p, hi_p = PAPER_TABLE8["C2"][f"B_{d}"]
        samp, pop = float(B.std(ddof=1)), float(B.std(ddof=0))
        ddof = 1 if abs(samp - std_p) <= abs(pop - std_p) else 0
        ti = t_interval(B, ddof=ddof)
        out[f"B_{d}"] = {
            "sample_std": samp, "population_std": pop, "paper_std": std_p,
            "paper_std_is": "sample (n-1)" if ddof == 1 else "population (n)",
            "interval_with_that_std": [ti["ci_low"], ti["ci_high"]],
            "implied_n": implied_sample_size(std_p, lo_p, hi_p),
            "table7_mean": float(B.mean()), "paper_mean": PAPER_MEANS["C2"][f"B_{d}"],
        }
    return out


def transcription_checks(data: Seed001Data) -> dict[str, Any]:
    """The tables' own printed means recomputed from their rows (a transcription check)."""
    out: dict[str, Any] = {}
    for d in DIRECTIONS:
        exp_means = data.fc[d].mean(axis=0)
        out[f"C1_Fc_{d}_experiment_means_match"] = bool(np.all(
            np.round(exp_means, 3) == np.array(PAPER_EXPERIMENT_MEANS[d])))
        out[f"C1_Fc_{d}_mean"] = [float(data.fc[d].mean()), PAPER_MEANS["C1"][f"Fc_{d}"]]
        out[f"C1_B_{d}_mean_of_printed"] = [float(data.B_printed[d].mean()),
                                            PAPER_MEANS["C1"][f"B_{d}"]]
        out[f"C2_Fc_{d}_mean_of_averages"] = [float(data.c2_fc[d].mean()),
                                              PAPER_MEANS["C2"][f"Fc_{d}"]]
        out[f"C2_B_{d}_mean"] = [float(data.c2_B[d].mean()), PAPER_MEANS["C2"][f"B_{d}"]]
    return out


def position_dependence(M: np.ndarray) -> dict[str, Any]:
    """Is the break-away force independent of the position step (12 x 10 table)?

    One-way ANOVA and Kruskal-Wallis over the 12 steps, Friedman with the
    experiments as blocks, the same without step 1, and step 1 (the first
    break-away of each run, after rest at the stroke end) against the rest.
    """
    from scipy import stats

    rest = M[1:].ravel()
    welch = stats.ttest_ind(M[0], rest, equal_var=False)
    return {
        "step_means": M.mean(axis=1).tolist(),
        "anova_p": float(stats.f_oneway(*M).pvalue),
        "kruskal_p": float(stats.kruskal(*M).pvalue),
        "friedman_p": float(stats.friedmanchisquare(*M).pvalue),
        "anova_p_without_step1": float(stats.f_oneway(*M[1:]).pvalue),
        "friedman_p_without_step1": float(stats.friedmanchisquare(*M[1:]).pvalue),
        "step1_mean": float(M[0].mean()), "other_steps_mean": float(rest.mean()),
        "step1_excess": float(M[0].mean() - rest.mean()),
        "step1_welch_p": float(welch.pvalue),
        "step1_mannwhitney_p": float(stats.mannwhitneyu(M[0], rest).pvalue),
        "step1_highest_in_experiments": int(np.sum(M.argmax(axis=0) == 0)),
    }


def independence(M: np.ndarray) -> dict[str, Any]:
    """Are the 120 values independent (Table 8 uses 119 dof), or do experiments cluster?"""
    anova = two_way_anova(M)
    icc = intraclass_correlation(M)
    k = M.shape[0]
    deff = 1.0 + (k - 1) * max(icc, 0.0)
    ti = t_interval(M.mean(axis=0), decimals=None)
    return {"two_way_anova": anova, "icc": icc, "design_effect": deff,
            "effective_n": M.size / deff,
            "interval_experiment_means": [ti["ci_low"], ti["ci_high"]]}


def normality(data: Seed001Data, B: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """Shapiro-Wilk p-values and skewness (Table 8 assumes normal values)."""
    from scipy import stats

    out: dict[str, Any] = {}
    for d in DIRECTIONS:
        M = data.fc[d]
        out[d] = {
            "Fc_shapiro_p": float(stats.shapiro(M.ravel()).pvalue),
            "Fc_skewness": float(stats.skew(M.ravel())),
            "Fc_without_step1_shapiro_p": float(stats.shapiro(M[1:].ravel()).pvalue),
            "Fc_without_step1_skewness": float(stats.skew(M[1:].ravel())),
            "B_shapiro_p": float(stats.shapiro(B[d]).pvalue),
        }
    return out


def sliding_force(data: Seed001Data, B: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """Is the break-away force the Coulomb level of the sliding force, and is B constant?

    Fits ``F_ext = a + b v`` to the 10 constant-speed runs of each direction:
    ``a`` is the Coulomb level the sliding runs themselves give, ``b`` their
    viscous slope; compares them with ``mean(Fc)`` and the two-step ``mean(B)``.
    Also the correlation of the two-step ``B_i`` with ``v_i`` (a constant B
    gives none).
    """
    from scipy import stats

    out: dict[str, Any] = {}
    for d in DIRECTIONS:
        F, v, M = data.F_ext[d], data.v[d], data.fc[d]
        line = ols_line(v, F)
        fc_mean = float(M.mean())
        se_fc = float(M.std(ddof=1)) / math.sqrt(M.size)
        z = (line["intercept"] - fc_mean) / math.hypot(line["intercept_se"], se_fc)
        out[d] = {
            "line": line,
            "breakaway_mean": fc_mean,
            "intercept_minus_breakaway": line["intercept"] - fc_mean,
            "intercept_vs_breakaway_p": float(2 * stats.t.sf(abs(z), line["n"] - 2)),
            "two_step_B_mean": float(B[d].mean()),
            "speed_range": [float(v.min()), float(v.max())],
            "F_mean": float(F.mean()), "F_std": float(F.std(ddof=1)),
            "B_vs_v_pearson_r": float(stats.pearsonr(v, B[d]).statistic),
            "B_vs_v_pearson_p": float(stats.pearsonr(v, B[d]).pvalue),
            "B_vs_v_spearman_rho": float(stats.spearmanr(v, B[d]).statistic),
            "B_vs_v_spearman_p": float(stats.spearmanr(v, B[d]).pvalue),
            "B_slope_per_speed": ols_line(v, B[d])["slope"],
        }
    return out


def direction_difference(data: Seed001Data, B: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """Extension against retraction: Welch t-tests, and B adjusted for the different speeds.

    ``B_i = b0 + b1 v_i + b2 [extension]`` (ANCOVA): ``b2`` is the direction
    effect on B at equal speed; the same for ``F_ext``.
    """
    from scipy import stats

    ext, ret = DIRECTIONS

    def welch(a: np.ndarray, b: np.ndarray) -> dict[str, float]:
        r = stats.ttest_ind(a, b, equal_var=False)
        return {"difference": float(a.mean() - b.mean()), "t": float(r.statistic),
                "dof": float(r.df), "p": float(r.pvalue)}

    v = np.concatenate([data.v[ext], data.v[ret]])
    X = np.column_stack([np.ones(20), v, np.r_[np.ones(10), np.zeros(10)]])
    names = ("intercept", "speed", "extension")
    return {
        "Fc": welch(data.fc[ext].ravel(), data.fc[ret].ravel()),
        "Fc_mannwhitney_p": float(stats.mannwhitneyu(data.fc[ext].ravel(),
                                                     data.fc[ret].ravel()).pvalue),
        "B": welch(B[ext], B[ret]),
        "v": welch(data.v[ext], data.v[ret]),
        "F_ext": welch(data.F_ext[ext], data.F_ext[ret]),
        "B_given_speed": linear_model(X, np.concatenate([B[ext], B[ret]]), names),
        "F_given_speed": linear_model(X, np.concatenate([data.F_ext[ext], data.F_ext[ret]]),
                                      names),
    }


def uncertainty_of_B(data: Seed001Data, B: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """The uncertainty of ``mean(B)`` with the uncertainty of ``mean(Fc)`` carried into it.

    ``mean B = mean_i (F_i - Fc)/v_i`` depends on the one estimate ``Fc`` shared
    by all ten experiments, so its error does not average out::

        Var(mean B) = s_B^2 / n + (mean 1/v)^2 * s_Fc^2 / N

    with Welch-Satterthwaite dof for the 95 % interval. Also the sensitivity
    ``d(mean B)/d(Fc) = -mean(1/v)``, ``mean(B)`` for other readings of the
    Coulomb level, and the bound the 3-decimal speeds put on each ``B_i``.
    """
    out: dict[str, Any] = {}
    for d in DIRECTIONS:
        M, F, v, Bd = data.fc[d], data.F_ext[d], data.v[d], B[d]
        n, N = Bd.size, M.size
        var_b = float(Bd.var(ddof=1)) / n
        k = float(np.mean(1.0 / v))
        var_fc = k**2 * float(M.var(ddof=1)) / N
        total = var_b + var_fc
        dof = total**2 / (var_b**2 / (n - 1) + var_fc**2 / (N - 1))
        half = t_quantile(dof, None) * math.sqrt(total)
        intercept = ols_line(v, F)["intercept"]
        out[d] = {
            "mean_B": float(Bd.mean()),
            "se_from_scatter": math.sqrt(var_b), "se_from_Fc": math.sqrt(var_fc),
            "se_total": math.sqrt(total), "dof": dof,
            "interval": [float(Bd.mean()) - half, float(Bd.mean()) + half],
            "paper_interval": list(PAPER_TABLE8["C1"][f"B_{d}"][1:]),
            "dB_dFc": -k,
            "mean_B_if_Fc_is_breakaway_without_step1": float(np.mean((F - M[1:].mean()) / v)),
            "mean_B_if_Fc_is_sliding_intercept": float(np.mean((F - intercept) / v)),
            "speed_rounding_bound_mean": float(np.mean(Bd * (SPEED_RESOLUTION / 2) / v)),
        }
    return out


def printed_speeds(data: Seed001Data) -> dict[str, Any]:
    """Experiments whose printed speed does not reproduce the printed B_i, and the speed it implies."""
    out: dict[str, Any] = {}
    for d in DIRECTIONS:
        fc_mean = float(data.fc[d].mean())
        B, ok = two_step_B(data.F_ext[d], data.v[d], fc_mean, data.B_printed[d])
        implied = (data.F_ext[d] - fc_mean) / data.B_printed[d]
        out[d] = {
            "B_used": B.tolist(), "recomputed": ok.tolist(),
            "B_recomputed": ((data.F_ext[d] - fc_mean) / data.v[d]).tolist(),
            "implied_speed": implied.tolist(),
            "inconsistent_experiments": [int(i) + 1 for i in np.flatnonzero(~ok)],
        }
    return out


def format_p(p: float) -> str:
    """A p-value in 2 significant digits (scientific below 0.001)."""
    return f"{p:.2g}" if p >= 1e-3 else f"{p:.1e}"


def significance(p: float) -> str:
    """``"significant"`` below :data:`ALPHA`, else ``"not significant"``."""
    return "significant" if p < ALPHA else "not significant"


def findings(res: dict[str, Any]) -> list[str]:
    """The study's conclusions in words, each stated from the numbers that support it."""
    A = res["assumptions"]
    pos, sl, dr = A["position_dependence"], A["sliding_force"], A["direction"]
    c2 = res["c2_reconstruction"]
    ext, ret = DIRECTIONS
    out = []
    pop = [d for d in DIRECTIONS if c2[f"B_{d}"]["paper_std_is"].startswith("population")]
    out.append(
        "Cylinder C2: the B intervals follow from Table 7"
        + (f" ({', '.join(pop)} only with a population standard deviation, used nowhere else)"
           if pop else "")
        + "; the Fc intervals rest on single values the paper does not print (the printed "
        f"widths imply n = {c2['Fc_extension']['implied_n']['n']:.1f} and "
        f"{c2['Fc_retraction']['implied_n']['n']:.1f}), so they cannot be recomputed.")
    step1 = all(pos[d]["step1_welch_p"] < ALPHA for d in DIRECTIONS)
    flat = all(pos[d]["anova_p_without_step1"] >= ALPHA for d in DIRECTIONS)
    out.append(
        f"Fc along the stroke: the first break-away of each run, from rest at the stroke end, "
        f"is {pos[ext]['step1_excess']:.2f} N (extension) and {pos[ret]['step1_excess']:.2f} N "
        f"(retraction) above the other steps (Welch p = {format_p(pos[ext]['step1_welch_p'])}, "
        f"{format_p(pos[ret]['step1_welch_p'])}, {'both' if step1 else 'not both'} significant); "
        f"without step 1 the position effect is {'gone' if flat else 'still there'} (ANOVA p = "
        f"{format_p(pos[ext]['anova_p_without_step1'])}, "
        f"{format_p(pos[ret]['anova_p_without_step1'])})."
        + (" Step 1 measures static friction after a dwell, not the Coulomb level."
           if step1 else ""))
    for d in DIRECTIONS:
        line = sl[d]["line"]
        lo, hi = line["intercept_ci"]
        above = lo > sl[d]["breakaway_mean"]
        out.append(
            f"{d.capitalize()}: the straight line through the constant-speed runs meets v = 0 "
            f"at {line['intercept']:.1f} N (95 % {lo:.1f} to {hi:.1f} N), against a mean "
            f"break-away force of {sl[d]['breakaway_mean']:.2f} N"
            + (": the break-away force is not the Coulomb level of the sliding force"
               if above else ": the break-away force lies inside that interval, so these "
               "runs alone cannot tell")
            + f"; slope {line['slope']:.0f} Ns/m (95 % {line['slope_ci'][0]:.0f} to "
            f"{line['slope_ci'][1]:.0f}) against the two-step mean B "
            f"{sl[d]['two_step_B_mean']:.1f} Ns/m"
            + (" (outside that interval)" if not line["slope_ci"][0] <= sl[d]["two_step_B_mean"]
               <= line["slope_ci"][1] else "")
            + "; the two-step B_i "
            + ("fall with speed" if sl[d]["B_vs_v_pearson_p"] < ALPHA
               and sl[d]["B_vs_v_pearson_r"] < 0 else "show no significant trend with speed")
            + f" (Pearson r = {sl[d]['B_vs_v_pearson_r']:.2f}, p = "
            f"{format_p(sl[d]['B_vs_v_pearson_p'])}).")
    bdir = dr["B_given_speed"]["extension"]
    out.append(
        f"Extension against retraction: Fc differs by {dr['Fc']['difference']:.2f} N "
        f"(p = {format_p(dr['Fc']['p'])}), B by {dr['B']['difference']:.1f} Ns/m "
        f"(p = {format_p(dr['B']['p'])}); but the applied forces differ by only "
        f"{dr['F_ext']['difference']:.2f} N (p = {format_p(dr['F_ext']['p'])}) while the speeds "
        f"differ by {dr['v']['difference'] * 1e3:+.0f} mm/s (p = {format_p(dr['v']['p'])}). At "
        f"equal speed the direction effect on B is {bdir['coef']:.1f} Ns/m "
        f"({significance(bdir['p'])}, p = {format_p(bdir['p'])}).")
    un = A["uncertainty_of_B"]
    out.append(
        "Carrying the uncertainty of mean Fc into B widens its standard error from "
        f"{un[ext]['se_from_scatter']:.2f} to {un[ext]['se_total']:.2f} Ns/m (extension) and "
        f"{un[ret]['se_from_scatter']:.2f} to {un[ret]['se_total']:.2f} Ns/m (retraction); "
        f"the choice of the Coulomb level matters far more ({un[ext]['dB_dFc']:.1f} and "
        f"{un[ret]['dB_dFc']:.1f} Ns/m per N).")
    return out
