"""Hostile cases through the command line: a few hundred bad (and a few good) inputs on the
surfaces of plant files, model files, ``plant template/check``, ``compensate``, ``export``,
``sweep``, ``--save-model``, ``--params``, ``import csv --map``, shipped data sets, output
names and signals, each run as a real process and its outcome classified.

Every case runs ``python -m fcomp.cli.main ARGS`` (or a shell line for redirections) in a
fresh copy of a folder of inputs (the *lab*), with ``PYTHONPATH`` set to the tree under
test (``--root``, default this repository), so the same script measures another checkout
(``git worktree add /tmp/base 2d5cfbf`` and ``--root /tmp/base``). Outcomes:

``clean``
    as expected: a refusal is exit status 2 with one line ``fcomp: error: ...`` naming
    what the case names (``match``; ``plant check`` may print one such line per problem);
    an expected warning is exit status 0 with a ``fcomp: warning: ...`` line matching; a
    valid input is exit status 0; a signal is exit status 130 (SIGINT) or 143 (SIGTERM)
    with its one line, nothing on stdout, no process of the command left.
``traceback``
    a Python traceback (or ``Exception ignored in ...``) anywhere in the output.
``internal``
    ``fcomp: internal error`` or exit status 1.
``hang``
    no end within the time limit (the process group is killed).
``wrong``
    anything else: another exit status, several lines, a message not naming the file, a
    result written where a refusal was due, an input changed, a temporary file left.

Every case also checks that no input of the lab changed and that a refusal left no file.
Cases owned by a concurrent piece of work carry their ``owner``; the summary counts them
apart.

Usage::

    python benchmarks/hostile_cases.py [--root DIR] [--jobs 2] [--json OUT] [-k PATTERN]
        [--timeout 120] [--list]
"""

from __future__ import annotations

import argparse
import concurrent.futures
import contextlib
import hashlib
import json
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(HERE / "tests"))  # the suite's process helpers, shared with the runner
from helpers import processes  # noqa: E402
from helpers.design_inputs import RIG as DESIGN_RIG  # noqa: E402


# ------------------------------------------------------------------ cases
@dataclass
class Case:
    """One hostile input and what it must give.

    ``expect``: ``refuse`` (exit 2, one error line), ``warn`` (exit 0, a warning line),
    ``ok`` (exit 0), ``refuse-or-warn`` (either), ``quiet`` (no traceback, no error line,
    any exit status: a closed pipe), ``signal`` (see ``sig``). ``match``: texts the error or
    warning line must hold (the file named, the key). ``shell``: the arguments are a shell
    line (``{fcomp}`` the command) for redirections. ``user``: run as this user
    (``nobody``: a read-only folder really is read-only to the command). ``sig``:
    ``(signal, when, second)`` with ``when`` seconds after the start, ``"handler"`` (as
    soon as the process has its SIGTERM handler) or ``"children"`` (as soon as it has
    started a process), ``second`` a second signal that many seconds after the first (None:
    none). ``check``: a function of the case's folder and output returning a problem (or
    None) for cases whose output must be right too. ``max_cpu``: a refusal due before the
    work must come within this much CPU time (s; the work itself takes far more).
    """

    id: str
    args: str
    expect: str = "refuse"
    match: tuple[str, ...] = ()
    item: str = ""
    owner: str = "hostile"
    shell: bool = False
    user: str | None = None
    env: dict[str, str] = field(default_factory=dict)
    sig: tuple[int, float | str, float | None] | None = None
    multi: bool = False
    check: Callable[[Path, str, str], str | None] | None = None
    timeout: float | None = None
    max_cpu: float | None = None


# ------------------------------------------------------------------ the lab
def _record_text() -> str:
    t = np.arange(300) * 0.01
    amp = np.where(t < 1.5, 0.05, 0.02)
    v = amp * np.sin(2 * np.pi * t)
    x = 0.01 + amp / (2 * np.pi) * (1 - np.cos(2 * np.pi * t))
    a = amp * 2 * np.pi * np.cos(2 * np.pi * t)
    rng = np.random.default_rng(3)
    F = 2.0 * np.tanh(v / 1e-3) + 30.0 * v + 0.01 * rng.standard_normal(t.size)
    rows = ["t,x,v,a,F"] + [",".join(f"{c:.9g}" for c in r)
                            for r in np.column_stack([t, x, v, a, F])]
    return "\n".join(rows) + "\n"


def _set(text: str, table: str, key: str, value: str | None) -> str:
    """``text`` (a plant file) with ``[table] key`` set to ``value`` (None: removed); a key
    not there is added under the table's header ('' table: the top)."""
    lines = text.splitlines()
    if table and not any(s.startswith(f"[{table}]") for s in lines):
        lines += ["", f"[{table}]"]
    start = 0 if table == "" else next(i for i, s in enumerate(lines)
                                       if s.startswith(f"[{table}]")) + 1
    end = next((i for i in range(start, len(lines)) if lines[i].startswith("[")), len(lines))
    pat = re.compile(rf"^{re.escape(key)}\s*=")
    for i in range(start, end):
        if pat.match(lines[i]):
            if value is None:
                del lines[i]
            else:
                lines[i] = f"{key} = {value}"
            return "\n".join(lines) + "\n"
    if value is not None:
        lines.insert(start, f"{key} = {value}")
    return "\n".join(lines) + "\n"


def _model(doc: dict | str) -> str:
    return doc if isinstance(doc, str) else json.dumps(doc)


LUGRE = {"format": "fcomp-model", "version": 1, "model": "lugre"}
POSDEP = {"format": "fcomp-model", "version": 1, "model": "coulomb-viscous",
          "effects": [{"name": "position-dependence",
                       "config": {"x_min": -0.0375, "x_max": 0.0032}}],
          "params": {"Fc": 20.0, "B": 300.0, "kx1": 0.6, "kx2": 0.5, "kx3": 0.4}}
#: A model fitted on x in [-37, 2.7] mm, |v| <= 0.05 m/s, 2-7 bar (the block this work adds).
RANGED = {**POSDEP, "fitted_range": {"x": [-0.037, 0.0027], "v": [-0.05, 0.05],
                                     "p": [2e5, 7e5]}}


def write_lab(lab: Path, root: Path) -> None:
    """The inputs every case starts from."""
    hyd = (root / "plants" / "data" / "hydraulic.toml").read_text()
    pneu = (root / "plants" / "data" / "pneumatic.toml").read_text()
    rec = _record_text()
    files: dict[str, str | bytes] = {
        "rec.csv": rec, "rec.toml": 'name = "rec"\nkind = "friction-rig"\n\n[rig]\nmass = 1.0\n',
        "hyd.toml": hyd, "pneu.toml": pneu,
        "lugre.json": _model(LUGRE),
        "cv.json": _model({"format": "fcomp-model", "version": 1, "model": "coulomb-viscous",
                           "params": {"Fc": 2.0, "B": 30.0}}),
        "posdep.json": _model(POSDEP), "ranged.json": _model(RANGED),
        "ref.csv": "t,x_ref\n0,0.1\n0.5,0.11\n1.0,0.1\n",
        "log.csv": "time_ms,pos_mm,force\n" + "".join(
            f"{10 * k},{0.1 * k:.3f},{1.0 + 0.01 * k:.3f}\n" for k in range(50)),
        "mine/notes.txt": "my notes\n",
        "empty.txt": "",
    }
    for name, content in {**files, **plant_files(hyd, pneu), **model_files(),
                          **reference_files(), **design_files(root)}.items():
        p = lab / name
        p.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(content)
    (lab / "ro").mkdir()
    (lab / "ro" / "keep.txt").write_text("read-only folder\n")


# ---- plant files -------------------------------------------------------------------
#: Required keys of a hydraulic / pneumatic plant file: (table, key).
H_REQUIRED = [("rig", k) for k in ("bore", "rod", "stroke", "mass")] + [
    ("supply", "ps"), ("supply", "pt"), ("valve", "kv"), ("valve", "omega_v"),
    ("valve", "zeta_v"), ("valve", "u_max"), ("valve", "du_max"), ("lines", "V10"),
    ("lines", "V20"), ("fluid", "beta"), ("fluid", "rho"), ("sensors", "x_resolution"),
    ("sensors", "x_noise"), ("sensors", "p_resolution"), ("sensors", "p_noise"),
    ("control", "rate")]
P_REQUIRED = [("rig", k) for k in ("bore", "rod", "stroke", "mass")] + [
    ("supply", "ps"), ("valve", "tau_v"), ("valve", "u_max"), ("valve", "du_max"),
    ("lines", "V10"), ("lines", "V20"), ("gas", "kappa"), ("gas", "R"), ("gas", "T"),
    ("sensors", "x_resolution"), ("sensors", "x_noise"), ("sensors", "p_resolution"),
    ("sensors", "p_noise"), ("control", "rate")]

#: Plant variants: file stem -> (base, [(table, key, value)], expectation, match, item, owner).
PLANTS: dict[str, tuple[str, list[tuple[str, str, str | None]], str, tuple[str, ...], str, str]] = {
    "h_kind_list": ("h", [("", "kind", '["hydraulic"]')], "refuse", ("kind",), "5", ""),
    "h_kind_table": ("h", [("", "kind", "{ a = 1 }")], "refuse", ("kind",), "5", ""),
    "h_kind_int": ("h", [("", "kind", "5")], "refuse", ("kind",), "", ""),
    "h_kind_missing": ("h", [("", "kind", None)], "refuse", ("kind",), "", ""),
    "h_kind_case": ("h", [("", "kind", '"Hydraulic"')], "refuse", ("kind",), "", ""),
    "h_name_int": ("h", [("", "name", "5")], "refuse", ("name",), "", ""),
    "h_name_list": ("h", [("", "name", '["a"]')], "refuse", ("name",), "", ""),
    "h_name_empty": ("h", [("", "name", '""')], "refuse", ("name",), "", ""),
    "h_no_orientation": ("h", [("rig", "orientation", None)], "ok", (), "7", ""),
    "h_orientation_int": ("h", [("rig", "orientation", "5")], "refuse", ("orientation",), "", ""),
    "h_orientation_bad": ("h", [("rig", "orientation", '"sideways"')], "refuse",
                          ("orientation",), "", ""),
    "h_bore_text": ("h", [("rig", "bore", '"abc"')], "refuse", ("bore",), "", ""),
    "h_bore_bool": ("h", [("rig", "bore", "true")], "refuse", ("bore",), "", ""),
    "h_bore_nan": ("h", [("rig", "bore", "nan")], "refuse", ("bore",), "", ""),
    "h_bore_inf": ("h", [("rig", "bore", "inf")], "refuse", ("bore",), "", ""),
    "h_bore_huge": ("h", [("rig", "bore", "1e308")], "refuse", ("bore",), "", ""),
    "h_bore_table": ("h", [("rig", "bore", "{ x = 1 }")], "refuse", ("bore",), "", ""),
    "h_bore_zero": ("h", [("rig", "bore", "0.0")], "refuse", ("bore",), "", ""),
    "h_mass_negative": ("h", [("rig", "mass", "-1.0")], "refuse", ("mass",), "", ""),
    "h_mass_bigint": ("h", [("rig", "mass", "1" + "0" * 400)], "refuse", ("mass",), "5", ""),
    "h_mass_date": ("h", [("rig", "mass", "1979-05-27")], "refuse", ("mass",), "", ""),
    "h_stroke_zero": ("h", [("rig", "stroke", "0.0")], "refuse", ("stroke",), "", ""),
    "h_rod_over_bore": ("h", [("rig", "rod", "0.05")], "refuse", ("rod",), "", ""),
    "h_ps_below_pt": ("h", [("supply", "ps", "5.0e4")], "refuse", ("ps",), "8", ""),
    "h_pt_negative": ("h", [("supply", "pt", "-1.0")], "refuse", ("pt",), "", ""),
    "h_beta_zero": ("h", [("fluid", "beta", "0.0")], "refuse", ("beta",), "", ""),
    "h_rho_huge": ("h", [("fluid", "rho", "1e308")], "refuse", ("rho",), "", ""),
    "h_V10_zero": ("h", [("lines", "V10", "0.0")], "refuse", ("V10",), "", ""),
    "h_V10_huge": ("h", [("lines", "V10", "1e308")], "refuse", ("V10",), "", ""),
    "h_omega_tiny": ("h", [("valve", "omega_v", "1e-300")], "refuse", ("omega_v",), "", ""),
    "h_zeta_zero": ("h", [("valve", "zeta_v", "0.0")], "refuse", ("zeta_v",), "", ""),
    "h_umax_zero": ("h", [("valve", "u_max", "0.0")], "refuse", ("u_max",), "", ""),
    "h_dumax_neg": ("h", [("valve", "du_max", "-5.0")], "refuse", ("du_max",), "", ""),
    "h_rate_low": ("h", [("control", "rate", "1.0")], "refuse", ("rate",), "", ""),
    "h_rate_huge": ("h", [("control", "rate", "1e308")], "refuse", ("rate",), "", ""),
    "h_xnoise_neg": ("h", [("sensors", "x_noise", "-1e-6")], "refuse", ("x_noise",), "", ""),
    "h_pnoise_huge": ("h", [("sensors", "p_noise", "1e308")], "refuse", ("p_noise",), "5", ""),
    "h_pres_huge": ("h", [("sensors", "p_resolution", "1e308")], "refuse",
                    ("p_resolution",), "", ""),
    "h_xres_huge": ("h", [("sensors", "x_resolution", "1e308")], "refuse",
                    ("x_resolution",), "", ""),
    "h_unknown_table": ("h", [("", "extra", "{ a = 1 }")], "refuse", ("extra",), "", ""),
    "h_unknown_key": ("h", [("valve", "Kv", "0.02")], "refuse", ("Kv",), "", ""),
    "h_table_as_value": ("h", [("", "rig", "3")], "refuse", (), "", ""),
    "h_rated_cd_zero": ("h", [("valve", "w", None), ("valve", "cd", "0.0"),
                              ("valve", "rated_flow", "4.0e-4"), ("valve", "rated_dp", "7.0e6")],
                        "refuse", ("cd",), "5", ""),
    "h_rated_no_dp": ("h", [("valve", "w", None), ("valve", "rated_flow", "4.0e-4")],
                      "refuse", ("rated_dp",), "", ""),
    "h_rated_and_w": ("h", [("valve", "rated_flow", "4.0e-4"), ("valve", "rated_dp", "7.0e6")],
                      "refuse", ("rated",), "", ""),
    "h_rated_huge": ("h", [("valve", "w", None), ("valve", "rated_flow", "1e308"),
                           ("valve", "rated_dp", "1e-300")], "refuse", ("rated",), "5", ""),
    "h_load_beyond": ("h", [("mechanics", "F_load", "1.0e7")], "refuse", ("F_load",), "8", ""),
    "h_load_nan": ("h", [("mechanics", "F_load", "nan")], "refuse", ("F_load",), "", ""),
    "h_kv_zero": ("h", [("valve", "kv", "0.0")], "refuse", ("kv",), "3", ""),
    "h_w_zero": ("h", [("valve", "w", "0.0")], "refuse", ("w",), "3", ""),
    "h_pid_negative": ("h", [("control", "pid_bandwidth", "-1.0")], "refuse",
                       ("pid_bandwidth",), "", ""),
    "h_observer_zero": ("h", [("control", "observer_gain", "0.0")], "refuse",
                        ("observer_gain",), "", ""),
    # the fail-safe layer's [control] keys (the fourth wave's plant-file keys)
    "h_safe_name": ("h", [("control", "safe_output", '"open"')], "refuse", ("safe_output",),
                    "", ""),
    "h_safe_beyond": ("h", [("control", "safe_output", "99.0")], "refuse", ("safe_output",),
                      "", ""),
    "h_safe_bool": ("h", [("control", "safe_output", "true")], "refuse", ("safe_output",),
                    "", ""),
    "h_safe_nan": ("h", [("control", "safe_output", "nan")], "refuse", ("safe_output",), "", ""),
    "h_safe_list": ("h", [("control", "safe_output", "[0.0]")], "refuse", ("safe_output",),
                    "", ""),
    "h_safe_hold": ("h", [("control", "safe_output", '"hold"')], "ok", (), "", ""),
    "h_latch_zero": ("h", [("control", "fault_latch", "0")], "refuse", ("fault_latch",), "", ""),
    "h_latch_half": ("h", [("control", "fault_latch", "2.5")], "refuse", ("fault_latch",),
                     "", ""),
    "h_latch_huge": ("h", [("control", "fault_latch", "1e300")], "refuse", ("fault_latch",),
                     "", ""),
    "h_latch_bigint": ("h", [("control", "fault_latch", "9" * 400)], "refuse",
                       ("fault_latch",), "", ""),
    "h_recover_text": ("h", [("control", "fault_recover", '"x"')], "refuse", ("fault_recover",),
                       "", ""),
    "h_recover_neg": ("h", [("control", "fault_recover", "-3")], "refuse", ("fault_recover",),
                      "", ""),
    "h_margin_neg": ("h", [("control", "position_margin", "-0.01")], "refuse",
                     ("position_margin",), "", ""),
    "h_margin_huge": ("h", [("control", "position_margin", "1e308")], "refuse",
                      ("position_margin",), "", ""),
    "h_pmax_zero": ("h", [("control", "pressure_max", "0.0")], "refuse", ("pressure_max",),
                    "", ""),
    "h_pmax_huge": ("h", [("control", "pressure_max", "1e308")], "refuse", ("pressure_max",),
                    "", ""),
    "h_pmax_below_ps": ("h", [("control", "pressure_max", "1.0e5")], "refuse",
                        ("pressure_max",), "", ""),
    "p_tau_zero": ("p", [("valve", "tau_v", "0.0")], "refuse", ("tau_v",), "5", ""),
    "p_tau_neg": ("p", [("valve", "tau_v", "-0.005")], "refuse", ("tau_v",), "", ""),
    "p_gamma_one_sonic": ("p", [("valve", "A_valve", None),
                                ("valve", "sonic_conductance", "2.4e-8"), ("gas", "gamma", "1.0")],
                          "refuse", ("gamma",), "5", ""),
    "p_gamma_one": ("p", [("gas", "gamma", "1.0")], "refuse", ("gamma",), "", ""),
    "p_gamma_below": ("p", [("gas", "gamma", "0.5")], "refuse", ("gamma",), "", ""),
    "p_sonic_huge": ("p", [("valve", "A_valve", None), ("valve", "sonic_conductance", "1e308")],
                     "refuse", ("sonic_conductance",), "5", ""),
    "p_pnoise_huge": ("p", [("sensors", "p_noise", "1e308")], "refuse", ("p_noise",), "5", ""),
    "p_kappa_zero": ("p", [("gas", "kappa", "0.0")], "refuse", ("kappa",), "", ""),
    "p_R_zero": ("p", [("gas", "R", "0.0")], "refuse", ("R",), "", ""),
    "p_T_zero": ("p", [("gas", "T", "0.0")], "refuse", ("T",), "", ""),
    "p_bcrit_one": ("p", [("gas", "b_crit", "1.0")], "refuse", ("b_crit",), "", ""),
    "p_rlam_low": ("p", [("gas", "r_lam", "0.1")], "refuse", ("r_lam",), "", ""),
    "p_ps_below_atm": ("p", [("supply", "ps", "9.0e4")], "refuse", ("ps",), "", ""),
    "p_lap_neg": ("p", [("valve", "lap", "-1.0")], "refuse", ("lap",), "", ""),
    "p_uopen_zero": ("p", [("valve", "u_open", "0.0")], "refuse", ("u_open",), "", ""),
    "p_both_valves": ("p", [("valve", "sonic_conductance", "2.4e-8")], "refuse",
                      ("sonic_conductance",), "", ""),
    "p_no_valve": ("p", [("valve", "A_valve", None)], "refuse", ("A_valve",), "", ""),
    "p_sonic_zero": ("p", [("valve", "A_valve", None), ("valve", "sonic_conductance", "0.0")],
                     "refuse", ("sonic_conductance",), "3", ""),
    "p_avalve_zero": ("p", [("valve", "A_valve", "0.0")], "refuse", ("A_valve",), "3", ""),
    "p_mass_tiny": ("p", [("rig", "mass", "1e-300")], "refuse", ("mass",), "", ""),
    "p_load_beyond": ("p", [("mechanics", "F_load", "1.0e6")], "refuse", ("F_load",), "8", ""),
    "p_no_orientation": ("p", [("rig", "orientation", None)], "ok", (), "7", ""),
}


def plant_files(hyd: str, pneu: str) -> dict[str, str | bytes]:
    out: dict[str, str | bytes] = {}
    hyd = _set(hyd, "", "name", '"lab-hydraulic"')  # a file of the user's, named by them
    pneu = _set(pneu, "", "name", '"lab-pneumatic"')
    for stem, (base, edits, *_rest) in PLANTS.items():
        text = hyd if base == "h" else pneu
        for table, key, value in edits:
            text = _set(text, table, key, value)
        out[f"{stem}.toml"] = text
    for table, key in H_REQUIRED:
        out[f"hm_{key}.toml"] = _set(hyd, table, key, None)
    for table, key in P_REQUIRED:
        out[f"pm_{key}.toml"] = _set(pneu, table, key, None)
    out["h_dupkey.toml"] = hyd.replace("bore = 0.030", "bore = 0.030\nbore = 0.040", 1)
    out["h_binary.toml"] = b"\x00\x01\xff\xfe" * 10
    out["h_latin1.toml"] = hyd.encode() + "# K\xe4lte\n".encode("latin-1")
    out["h_empty.toml"] = ""
    out["h_name300.toml"] = _set(hyd, "", "name", '"' + "a" * 300 + '"')
    out["h_name_slash.toml"] = _set(hyd, "", "name", '"../../evil/name"')
    return out


# ---- model files ---------------------------------------------------------------------
def model_files() -> dict[str, str | bytes]:
    big = "1" + "0" * 400
    huge = "1" + "0" * 5000
    pd = {"name": "position-dependence"}
    m: dict[str, str | bytes] = {
        "m_notjson.json": "this is not JSON\n",
        "m_empty.json": "",
        "m_array.json": "[]",
        "m_string.json": '"lugre"',
        "m_deep_list.json": "[" * 100000 + "]" * 100000,
        "m_deep_dict.json": '{"a":' * 100000 + "1" + "}" * 100000,
        "m_dup_top.json": '{"format": "fcomp-model", "version": 1, "model": "lugre", '
                          '"model": "coulomb"}',
        "m_dup_params.json": '{"format": "fcomp-model", "version": 1, "model": "lugre", '
                             '"params": {"Fc": 1.0, "Fc": 2.0}}',
        "m_bigint.json": '{"format": "fcomp-model", "version": 1, "model": "lugre", '
                         f'"params": {{"Fc": {big}}}}}',
        "m_hugeint.json": '{"format": "fcomp-model", "version": 1, "model": "lugre", '
                          f'"params": {{"Fc": {huge}}}}}',
        "m_1e400.json": '{"format": "fcomp-model", "version": 1, "model": "lugre", '
                        '"params": {"Fc": 1e400}}',
        "m_nan.json": '{"format": "fcomp-model", "version": 1, "model": "lugre", '
                      '"params": {"Fc": NaN}}',
        "m_infinity.json": '{"format": "fcomp-model", "version": 1, "model": "lugre", '
                           '"params": {"Fc": Infinity}}',
        "m_version2.json": _model({**LUGRE, "version": 2}),
        "m_version_text.json": _model({**LUGRE, "version": "1"}),
        "m_version_bool.json": _model({**LUGRE, "version": True}),
        "m_version_bigint.json": '{"format": "fcomp-model", "version": ' + big
                                 + ', "model": "lugre"}',
        "m_no_format.json": _model({"version": 1, "model": "lugre"}),
        "m_unknown_key.json": _model({**LUGRE, "colour": "red"}),
        "m_model_unknown.json": _model({**LUGRE, "model": "magic"}),
        "m_model_int.json": _model({**LUGRE, "model": 5}),
        "m_effects_dict.json": _model({**LUGRE, "effects": {}}),
        "m_effects_int.json": _model({**LUGRE, "effects": [5]}),
        "m_effect_unknown.json": _model({**LUGRE, "effects": [{"name": "magic"}]}),
        "m_effect_key.json": _model({**LUGRE, "effects": [{"name": "stribeck", "colour": 1}]}),
        "m_config_typo.json": _model({**LUGRE, "effects": [{**pd, "config": {"x_mni": 0.0}}]}),
        "m_config_list.json": _model({**LUGRE, "effects": [{**pd, "config": [1]}]}),
        "m_config_form.json": _model({**LUGRE, "effects": [{"name": "nonlocal-memory",
                                                            "config": {"form": "magic"}}]}),
        "m_xmin_eq.json": _model({**LUGRE, "effects": [{**pd, "config": {"x_min": 0.1,
                                                                          "x_max": 0.1}}]}),
        "m_xmin_gt.json": _model({**LUGRE, "effects": [{**pd, "config": {"x_min": 0.3,
                                                                          "x_max": 0.0}}]}),
        "m_xmin_text.json": _model({**LUGRE, "effects": [{**pd, "config": {"x_min": "a"}}]}),
        "m_xmin_nan.json": '{"format": "fcomp-model", "version": 1, "model": "lugre", '
                           '"effects": [{"name": "position-dependence", '
                           '"config": {"x_min": NaN}}]}',
        "m_features_order.json": _model({**LUGRE, "features": [
            "viscous", "stribeck", "presliding", "damping"]}),
        "m_features_wrong.json": _model({**LUGRE, "features": ["viscous"]}),
        "m_features_int.json": _model({**LUGRE, "features": 5}),
        "m_param_text.json": _model({**LUGRE, "params": {"Fc": "a"}}),
        "m_param_bool.json": _model({**LUGRE, "params": {"Fc": True}}),
        "m_param_negative.json": _model({**LUGRE, "params": {"Fc": -1.0}}),
        "m_param_unknown.json": _model({**LUGRE, "params": {"zz": 1.0}}),
        "m_param_huge.json": _model({**LUGRE, "params": {"sigma0": 1e308}}),
        "m_params_list.json": _model({**LUGRE, "params": [1, 2]}),
        "m_mass_negative.json": _model({**LUGRE, "measurement_terms": {"params": {"mass": -5.0}}}),
        "m_mass_huge.json": _model({**LUGRE, "measurement_terms": {"params": {"mass": 1e300}}}),
        "m_lag_negative.json": _model({**LUGRE, "measurement_terms": {"params": {"lag": -5.0}}}),
        "m_terms_key.json": _model({**LUGRE, "measurement_terms": {"colour": 1}}),
        "m_terms_param.json": _model({**LUGRE, "measurement_terms": {"params": {"zz": 1.0}}}),
        "m_terms_ok.json": _model({**LUGRE, "measurement_terms": {"params": {"mass": 1.5}}}),
        "m_stderr_text.json": _model({**LUGRE, "stderr": {"Fc": "a"}}),
        "m_source_int.json": _model({**LUGRE, "source": 5}),
        "m_user_effect.json": _model({**LUGRE, "effects": [{"name": "my-bias",
                                                            "module": "my_effects.py"}]}),
        "m_binary.json": b"\x00\x01\x02\xff",
        "m_utf16.json": "\ufeff".encode("utf-16-le") + _model(LUGRE).encode("utf-16-le"),
        "m_bom.json": "\ufeff" + _model(LUGRE),
        "m_trailing.json": _model(LUGRE) + " garbage",
        "m_range_bad.json": _model({**LUGRE, "fitted_range": {"x": [1.0]}}),
        "m_range_inverted.json": _model({**LUGRE, "fitted_range": {"x": [0.3, 0.0]}}),
        "m_range_key.json": _model({**LUGRE, "fitted_range": {"colour": [0, 1]}}),
        "m_range_text.json": _model({**LUGRE, "fitted_range": "wide"}),
        "m_ok_extended.json": _model({"format": "fcomp-model", "version": 1, "model": "coulomb",
                                      "effects": [{"name": "stribeck"}, {"name": "viscous"}],
                                      "params": {"Fc": 20.0, "Fs": 35.0, "vs": 0.01, "n": 2.0,
                                                 "sigma2": 100.0}}),
        "fit_other.json": _model({"model": "coulomb", "params": {"Fc": 1.0}}),
        "fit_multi.json": _model({"model": "lugre", "records": [{}, {}]}),
        "fit_dup.json": '{"model": "lugre", "params": {"Fc": 1.0, "Fc": 3.0}}',
    }
    return m


#: Model-file variants: file stem -> (expectation, what the line names, issue item).
MODELS: dict[str, tuple[str, tuple[str, ...], str]] = {
    "m_notjson": ("refuse", (), ""), "m_empty": ("refuse", (), ""),
    "m_array": ("refuse", (), ""), "m_string": ("refuse", (), ""),
    "m_deep_list": ("refuse", ("too deep",), "8"),
    "m_deep_dict": ("refuse", ("too deep",), "8"),
    "m_dup_top": ("refuse", ("model",), "10"), "m_dup_params": ("refuse", ("Fc",), "10"),
    "m_bigint": ("refuse", ("Fc",), "5"), "m_hugeint": ("refuse", ("Fc",), "8"),
    "m_1e400": ("refuse", ("Fc",), ""), "m_nan": ("refuse", ("NaN",), ""),
    "m_infinity": ("refuse", ("Infinity",), ""), "m_version2": ("refuse", ("version",), ""),
    "m_version_text": ("refuse", ("version",), ""),
    "m_version_bool": ("refuse", ("version",), ""),
    "m_version_bigint": ("refuse", ("version",), ""),
    "m_no_format": ("refuse", ("format",), ""), "m_unknown_key": ("refuse", ("colour",), ""),
    "m_model_unknown": ("refuse", ("magic",), ""), "m_model_int": ("refuse", ("model",), ""),
    "m_effects_dict": ("refuse", ("effects",), ""), "m_effects_int": ("refuse", ("effects",), ""),
    "m_effect_unknown": ("refuse", ("magic",), ""),
    "m_effect_key": ("refuse", ("colour",), ""),
    "m_config_typo": ("refuse-or-warn", ("x_mni",), "10"),
    "m_config_list": ("refuse", ("config",), ""),
    "m_config_form": ("refuse", ("form",), ""),
    "m_xmin_eq": ("refuse", ("x_min",), "5"), "m_xmin_gt": ("refuse", ("x_min",), "10"),
    "m_xmin_text": ("refuse", ("x_min",), ""), "m_xmin_nan": ("refuse", ("NaN",), ""),
    "m_features_order": ("ok", (), "8"), "m_features_wrong": ("refuse", ("features",), ""),
    "m_features_int": ("refuse", ("features",), ""),
    "m_param_text": ("refuse", ("Fc",), ""), "m_param_bool": ("refuse", ("Fc",), ""),
    "m_param_negative": ("refuse", ("Fc",), ""), "m_param_unknown": ("refuse", ("zz",), ""),
    "m_param_huge": ("refuse", ("sigma0",), ""), "m_params_list": ("refuse", ("params",), ""),
    "m_mass_negative": ("refuse", ("mass",), "10"), "m_mass_huge": ("refuse", ("mass",), ""),
    "m_lag_negative": ("refuse", ("lag",), ""), "m_terms_key": ("refuse", ("colour",), ""),
    "m_terms_param": ("refuse", ("zz",), ""),
    "m_terms_ok": ("warn", ("measurement terms",), ""),
    "m_stderr_text": ("refuse", ("stderr",), ""), "m_source_int": ("refuse", ("source",), ""),
    "m_user_effect": ("refuse", ("my_effects.py",), ""), "m_binary": ("refuse", (), ""),
    "m_utf16": ("ok", (), ""), "m_bom": ("ok", (), ""), "m_trailing": ("refuse", (), ""),
    "m_range_bad": ("refuse", ("fitted_range",), "11"),
    "m_range_inverted": ("refuse", ("fitted_range",), "11"),
    "m_range_key": ("refuse", ("colour",), "11"),
    "m_range_text": ("refuse", ("fitted_range",), "11"),
    "m_ok_extended": ("ok", (), ""),
}


# ---- references --------------------------------------------------------------------
def reference_files() -> dict[str, str | bytes]:
    return {
        "r_empty.csv": "",
        "r_header.csv": "t,x_ref\n",
        "r_one.csv": "t,x_ref\n0,0.1\n",
        "r_text.csv": "t,x_ref\n0,0.1\n0.5,a\n1.0,0.1\n",
        "r_nan.csv": "t,x_ref\n0,0.1\n0.5,nan\n1.0,0.1\n",
        "r_back.csv": "t,x_ref\n0,0.1\n1.0,0.1\n0.5,0.1\n",
        "r_outside.csv": "t,x_ref\n0,0.1\n0.5,5.0\n1.0,0.1\n",
        "r_negative.csv": "t,x_ref\n0,0.1\n0.5,-0.2\n1.0,0.1\n",
        "r_long.csv": "t,x_ref\n0,0.1\n1e7,0.1\n",
        "r_columns.csv": "time,x\n0,0.1\n1.0,0.1\n",
        "r_binary.csv": b"t,x_ref\n\x00\x01\xff",
        "r_mm.csv": "t,x_ref\n0,100\n1.0,110\n",
        "r_tiny.csv": "t,x_ref\n0,0.1\n1e-300,0.1\n",
        "r_bigint.csv": "t,x_ref\n0,0.1\n" + "1" + "0" * 5000 + ",0.1\n",
    }


# ---- fcomp design: a diagnosis with open questions and a rig ------------------------
#: Rig files: stem -> (edit of DESIGN_RIG (old, new), what the refusal names beside the file).
RIGS: dict[str, tuple[tuple[str, str], str]] = {
    "stroke-nan": (("stroke = 0.2", "stroke = nan"), "stroke"),
    "stroke-inf": (("stroke = 0.2", "stroke = inf"), "stroke"),
    "stroke-huge": (("stroke = 0.2", "stroke = 1e308"), "stroke"),
    "stroke-text": (("stroke = 0.2", 'stroke = "long"'), "stroke"),
    "stroke-list": (("stroke = 0.2", "stroke = [0.2]"), "stroke"),
    "stroke-bigint": (("stroke = 0.2", "stroke = 1" + "0" * 400), "stroke"),
    "speed-negative": (("speed_max = 0.2", "speed_max = -0.2"), "speed_max"),
    "speed-huge": (("speed_max = 0.2", "speed_max = 1e300"), "speed_max"),
    "accel-zero": (("accel_max = 4.0", "accel_max = 0"), "accel_max"),
    "accel-huge": (("accel_max = 4.0", "accel_max = 1e300"), "accel_max"),
    "rate-huge": (("rate = 500.0", "rate = 1e12"), "rate"),
    "rate-inf": (("rate = 500.0", "rate = inf"), "rate"),
    "duration-huge": (("duration_max = 20.0", "duration_max = 1e12"), "duration_max"),
    "duration-zero": (("duration_max = 20.0", "duration_max = 0"), "duration_max"),
    "pressure-crossed": (("pressure_max = 2.5e5", "pressure_max = 1.0e5"), "pressure"),
    "pressure-nan": (("pressure_min = 1.5e5", "pressure_min = nan"), "pressure_min"),
    "pressure-negative": (("pressure_min = 1.5e5", "pressure_min = -1e7"), "pressure_min"),
    "pressure-levels-empty": (("pressure_min = 1.5e5\npressure_max = 2.5e5",
                               "pressure_levels = []"), "pressure_levels"),
    "pressure-levels-text": (("pressure_min = 1.5e5\npressure_max = 2.5e5",
                              'pressure_levels = ["high"]'), "pressure_levels"),
    "pressure-both": (("pressure_max = 2.5e5", "pressure_max = 2.5e5\n"
                       "pressure_levels = [2e5]"), "pressure"),
    "noise-negative": (("rate = 500.0", "rate = 500.0\nnoise = -1"), "noise"),
    "bore-zero": (("bore = 0.032", "bore = 0"), "bore"),
    "rod-beyond-bore": (("rod = 0.012", "rod = 0.05"), "rod"),
    "mass-negative": (("mass = 1.2", "mass = -1.2"), "mass"),
    "orientation-bad": (('"horizontal"', '"sideways"'), "orientation"),
    "limits-table-missing": (("[limits]", "[limitz]"), "limit"),
    "unknown-key": (("rate = 500.0", "rate = 500.0\nspeed = 3"), "speed"),
    "duplicate-key": (("stroke = 0.2", "stroke = 0.2\nstroke = 0.3"), ""),
}

#: Diagnosis JSON files: stem -> (the text, or an edit of the good one: key -> value).
DIAGS: dict[str, str | dict[str, Any]] = {
    "notjson": "this is not JSON\n",
    "empty": "",
    "array": "[1, 2]",
    "deep": "[" * 100000 + "]" * 100000,
    "bigint": '{"verdict": "explained", "noise_floor": 1' + "0" * 5000 + "}",
    "noise-nan": {"noise_floor": float("nan")},
    "noise-negative": {"noise_floor": -0.05},
    "noise-huge": {"noise_floor": 1e308},
    "model-missing": {"model_file": None},
    "model-unknown": {"model_file": {"format": "fcomp-model", "version": 1,
                                     "model": "no-such-model"}},
    "ties-text": {"ties": "area-error"},
    "ties-unknown": {"ties": [["no-such-effect", "other-effect"]]},
    "skipped-list": {"skipped": ["pressure-dependence"]},
    "skipped-unknown": {"skipped": {"no-such-effect": "why"}},
}


def design_files(root: Path) -> dict[str, str | bytes]:
    """``diag.json`` (a diagnosis by hand, the JSON's fields: LuGre, pressure dependence
    untested at one level; the model document written by the tree under test), the rig
    ``rig.toml`` and their hostile variants ``rig_STEM.toml`` and ``diag_STEM.json``."""
    code = ("import json, sys; from fcomp.models import make_model; "
            "from fcomp.models.document import model_document; "
            "m = make_model('lugre', params='canudas1995'); "
            "json.dump(model_document(m, source={'data': []}), sys.stdout)")
    model = json.loads(subprocess.run([sys.executable, "-c", code], check=True, text=True,
                                      capture_output=True, env=processes.env()
                                      | {"PYTHONPATH": str(root)}).stdout)
    good = {"verdict": "explained", "noise_floor": 0.05, "added": [], "ties": [],
            "skipped": {"pressure-dependence": "needs p1: p1 + p2 hardly varies"},
            "warnings": [], "signals": {"force": "F"}, "model_file": model}
    out: dict[str, str | bytes] = {"diag.json": json.dumps(good), "rig.toml": DESIGN_RIG,
                                   "rig_empty.toml": "", "rig_binary.toml": b"\x00\xff\x01"}
    for stem, (edit, _) in RIGS.items():
        assert edit[0] in DESIGN_RIG, stem
        out[f"rig_{stem}.toml"] = DESIGN_RIG.replace(*edit)
    for stem, d in DIAGS.items():
        out[f"diag_{stem}.json"] = d if isinstance(d, str) else json.dumps({**good, **d})
    return out


# ------------------------------------------------------------------ the case table
SIM = "simulate motion --input sine:amplitude=0.01,frequency=1 --duration 0.2 --rate 100 -o o.csv"
COMP = ("compensate --plant hydraulic --friction lugre --controller-friction lugre,coulomb "
        "--controllers pid-ff --task steps --fast --samples 0 --no-progress")
SWEEP = "sweep --controllers pid --samples 2 --fast --no-progress --jobs 1"
EXPORT = "export pid --plant hydraulic -o ctrl --duration 0.05 --no-progress"
FIT = "fit rec.csv --friction coulomb-viscous"
LONG_SIM = ("simulate hydraulic --friction nmlgm-hysteresis --input "
            "sine:amplitude=4.5e-3,frequency=1 --duration 200 --rate 200 -o long.csv")


def _name_check(name: str) -> Callable[[Path, str, str], str | None]:
    def check(folder: Path, out: str, err: str) -> str | None:
        try:
            doc = json.loads((folder / "check.json").read_text())
        except (OSError, ValueError) as exc:
            return f"no check.json ({exc})"
        got = doc.get("plant") if isinstance(doc.get("plant"), str) else \
            (doc.get("plant") or {}).get("name") if isinstance(doc.get("plant"), dict) else None
        return None if got != name else f"the plant is still named {name!r}"
    return check


def cases() -> list[Case]:
    out: list[Case] = []
    add = out.append
    # ---- plant files: plant check, and every command that takes one ----
    for stem, (_base, _e, expect, match, item, owner) in PLANTS.items():
        add(Case(f"plant-check-{stem}", f"plant check {stem}.toml", expect,
                 (f"{stem}.toml", *match), item, owner or "hostile", multi=True))
    for _table, key in H_REQUIRED:
        add(Case(f"plant-check-missing-h-{key}", f"plant check hm_{key}.toml", "refuse",
                 (f"hm_{key}.toml", key), multi=True))
    for _table, key in P_REQUIRED:
        add(Case(f"plant-check-missing-p-{key}", f"plant check pm_{key}.toml", "refuse",
                 (f"pm_{key}.toml", key), multi=True))
    for stem, match in (("h_dupkey", ("h_dupkey.toml",)), ("h_binary", ("h_binary.toml",)),
                        ("h_latin1", ("h_latin1.toml",)), ("h_empty", ("h_empty.toml",))):
        add(Case(f"plant-check-{stem}", f"plant check {stem}.toml", "refuse", match,
                 multi=True))
    add(Case("plant-check-missing-file", "plant check nope.toml", "refuse", ("nope.toml",)))
    add(Case("plant-check-folder", "plant check mine", "refuse", ("mine",)))
    add(Case("plant-check-json-onto-input", "plant check hyd.toml --json hyd.toml", "refuse",
             ("hyd.toml",)))
    add(Case("plant-check-name300", "plant check h_name300.toml --json c.json", "refuse",
             ("h_name300.toml", "name"), "9", multi=True))
    add(Case("plant-check-json-disk-full", "plant check hyd.toml --json /dev/full", "refuse",
             ("/dev/full",), "8"))
    add(Case("plant-check-json-read-only", "plant check hyd.toml --json ro/c.json", "refuse",
             ("ro",), "9", user="nobody"))
    add(Case("plant-check-json-name-too-long", "plant check hyd.toml --json " + "c" * 300
             + ".json", "refuse", ("bytes long",), "9"))
    add(Case("plant-check-json-folder", "plant check hyd.toml --json mine", "refuse",
             ("mine",)))
    add(Case("plant-check-two-files", "plant check hyd.toml pneu.toml", "refuse", ()))
    for stem in ("h_kind_list", "h_rated_cd_zero", "p_tau_zero", "p_gamma_one_sonic",
                 "h_pnoise_huge", "p_pnoise_huge", "h_load_beyond", "h_ps_below_pt",
                 "h_mass_bigint"):
        item, owner = PLANTS[stem][4], PLANTS[stem][5] or "hostile"
        add(Case(f"simulate-plant-{stem}", f"simulate hydraulic --plant-params {stem}.toml "
                 "--friction coulomb --input step:amplitude=0 --duration 0.01 -o o.csv",
                 "refuse", (f"{stem}.toml",), item, owner))
        add(Case(f"compensate-plant-{stem}", f"{COMP} --plant-params {stem}.toml".replace(
            "--plant hydraulic ", ""), "refuse", (f"{stem}.toml",), item, owner))
    for stem in ("h_kind_table", "p_tau_zero", "h_load_beyond", "p_load_beyond"):
        add(Case(f"sweep-plant-{stem}", f"{SWEEP} --plant-params {stem}.toml", "refuse",
                 (f"{stem}.toml",), PLANTS[stem][4]))
        add(Case(f"export-plant-{stem}", f"{EXPORT} --plant-params {stem}.toml".replace(
            "--plant hydraulic ", ""), "refuse", (f"{stem}.toml",), PLANTS[stem][4]))
    add(Case("simulate-plant-no-orientation", "simulate hydraulic --plant-params "
             "h_no_orientation.toml --friction coulomb --input step:amplitude=0 --duration "
             "0.01 -o o.csv", "ok", (), "7"))
    add(Case("compensate-plant-kind-mismatch", f"{COMP} --plant-params pneu.toml".replace(
        "--plant hydraulic", "--plant hydraulic"), "refuse", ("pneu.toml",)))
    add(Case("study-plant-name300", "study compensators --fast --plant-params h_name300.toml "
             "--out st --no-progress", "refuse", ("h_name300.toml", "name"), "9", timeout=400,
             max_cpu=8.0))
    add(Case("study-plant-name-slash", "study compensators --fast --plant-params "
             "h_name_slash.toml --out st2 --no-progress", "ok", (), "9", timeout=400))
    # ---- plant template ----
    add(Case("template-stdout-closed", "{fcomp} plant template hydraulic >&-", "refuse",
             ("standard output",), "5", shell=True))
    add(Case("template-disk-full", "{fcomp} plant template hydraulic > /dev/full", "refuse",
             ("standard output",), "8", shell=True))
    add(Case("template-broken-pipe", "{fcomp} plant template hydraulic | head -c 10 "
             ">/dev/null", "quiet", shell=True))
    add(Case("template-unknown", "plant template magic", "refuse", ("magic",)))
    add(Case("template-name-placeholder", "{fcomp} plant template hydraulic > t.toml && "
             "{fcomp} plant check t.toml --json check.json", "ok", (), "16", shell=True,
             check=_name_check("seed002-type1")))
    add(Case("template-pneumatic-name", "{fcomp} plant template pneumatic > my-axis.toml && "
             "{fcomp} plant check my-axis.toml --json check.json", "ok", (), "16", shell=True,
             check=_name_check("seed000-servo")))
    # ---- model files ----
    for stem, (expect, match, item) in MODELS.items():
        add(Case(f"simulate-model-{stem}", f"{SIM} --friction {stem}.json", expect,
                 ((f"{stem}.json",) if expect.startswith("refuse") else ()) + match, item))
    for stem in ("m_deep_list", "m_dup_top", "m_bigint", "m_hugeint", "m_xmin_eq",
                 "m_config_typo", "m_features_order", "m_mass_negative"):
        expect, match, item = MODELS[stem]
        name = (f"{stem}.json",) if expect.startswith("refuse") else ()
        add(Case(f"compare-model-{stem}", f"compare rec.csv --friction {stem}.json",
                 expect, name + match, item))
        add(Case(f"sweep-model-{stem}", f"{SWEEP} --friction {stem}.json",
                 expect, name + match, item))
        add(Case(f"compensate-model-{stem}", COMP.replace(
            "lugre,coulomb", f"lugre,{stem}.json"),
            expect, name + match, item))
        add(Case(f"export-model-{stem}", f"{EXPORT} --friction {stem}.json",
                 expect, name + match, item))
    for stem in ("m_deep_list", "m_bigint", "m_dup_params"):
        add(Case(f"fit-model-{stem}", f"{FIT.replace('coulomb-viscous', stem + '.json')}",
                 "refuse", (f"{stem}.json",)))
    # ---- --params (one rule, item 7) ----
    add(Case("simulate-params-with-model-file", f"{SIM} --friction lugre.json --params "
             "canudas1995", "refuse", ("--params",), "7"))
    add(Case("simulate-hyd-params-with-model-file", "simulate hydraulic --friction lugre.json "
             "--params seed002-type1 --input step:amplitude=0 --duration 0.01 -o o.csv",
             "refuse", ("--params",), "7"))
    add(Case("export-params-with-model-file", f"{EXPORT} --friction lugre.json --params "
             "seed002-type1", "refuse", ("--params",), "7"))
    add(Case("compare-params-with-model-file", "compare rec.csv --friction lugre.json --params "
             "canudas1995", "refuse", ("--params",), "7"))
    add(Case("fit-params-with-model-file", "fit rec.csv --friction lugre.json --params "
             "canudas1995", "refuse", ("--params",), "7"))
    add(Case("compare-params-other-model", "compare rec.csv --friction lugre --params "
             "fit_other.json", "refuse", ("fit_other.json",)))
    add(Case("compare-params-multi", "compare rec.csv --friction lugre --params fit_multi.json",
             "refuse", ("fit_multi.json",)))
    add(Case("compare-params-dup", "compare rec.csv --friction lugre --params fit_dup.json",
             "refuse", ("fit_dup.json", "Fc"), "10"))
    add(Case("compare-params-deep", "compare rec.csv --friction lugre --params m_deep_dict.json",
             "refuse", ("m_deep_dict.json",), "8"))
    add(Case("compare-params-bigint", "compare rec.csv --friction lugre --params m_bigint.json",
             "refuse", ("m_bigint.json",), "5"))
    add(Case("simulate-params-missing", f"{SIM} --friction lugre --params nope.json", "refuse",
             ("nope.json",)))
    # ---- compensate ----
    for stem, match, item in (("r_empty", (), ""), ("r_header", (), ""), ("r_one", (), ""),
                              ("r_text", ("row",), "8"), ("r_nan", (), ""), ("r_back", (), ""),
                              ("r_outside", ("stroke",), ""), ("r_negative", ("stroke",), ""),
                              ("r_long", ("long",), "8"), ("r_columns", ("x_ref",), ""),
                              ("r_binary", (), ""), ("r_mm", ("stroke",), ""),
                              ("r_tiny", (), ""), ("r_bigint", (), "8")):
        add(Case(f"compensate-reference-{stem}", COMP.replace("--task steps ", "")
                 + f" --reference {stem}.csv", "refuse", (f"{stem}.csv", *match), item))
    add(Case("compensate-reference-missing", COMP.replace("--task steps ", "")
             + " --reference nope.csv", "refuse", ("nope.csv",)))
    add(Case("compensate-reference-and-task", f"{COMP} --reference ref.csv", "refuse",
             ("--task",)))
    for label, extra, match in (
            ("controllers-unknown", "--controllers nope", ("nope",)),
            ("controllers-empty", "--controllers ''", ("--controllers",)),
            ("controllers-twice", "--controllers pid,pid", ("twice",)),
            ("friction-unknown", "--friction magic", ("magic",)),
            ("task-unknown", "--task nope", ("nope",)),
            ("samples-negative", "--samples -1", ("--samples",)),
            ("samples-text", "--samples many", ("--samples",)),
            ("samples-huge", "--samples 100000000", ("--samples", "1000")),
            ("spread-negative", "--spread -1", ("--spread",)),
            ("spread-nan", "--spread nan", ("--spread",)),
            ("spread-huge", "--spread 5", ("--spread",)),
            ("seed-negative", "--seed -1", ("--seed",)),
            ("jobs-zero", "--jobs 0", ("--jobs",)),
            ("json-onto-input", "--json hyd.toml", ("hyd.toml",)),
            ("json-onto-model", "--json lugre.json --controller-friction lugre.json,coulomb",
             ("lugre.json",)),
            ("report-foreign", "--report mine", ("mine",)),
            ("report-cwd", "--report .", (".",)),
            ("json-name-too-long", "--json " + "a" * 300 + ".json", ("bytes long",)),
            ("scheduler-bad", "--scheduler nowhere", ("--scheduler",))):
        base = COMP
        if label == "json-onto-model":
            base = COMP.replace("--controller-friction lugre,coulomb ", "")
        if label == "task-unknown":
            base = COMP.replace("--task steps ", "")
        add(Case(f"compensate-{label}", f"{base} {extra}", "refuse", match))
    add(Case("compensate-controller-friction-one", COMP.replace("lugre,coulomb", "lugre"),
             "refuse", ("two",)))
    add(Case("compensate-controller-friction-twice", COMP.replace("lugre,coulomb", "lugre,lugre"),
             "refuse", ("twice",)))
    add(Case("compensate-controller-friction-missing-file",
             COMP.replace("lugre,coulomb", "lugre,nope.json"), "refuse", ("nope.json",)))
    add(Case("compensate-json-disk-full", f"{COMP} --json /dev/full", "refuse",
             ("/dev/full",), "8"))
    add(Case("compensate-json-250", f"{COMP} --json " + "b" * 245 + ".json", "ok", (), "9"))
    heavy = COMP.replace("--controllers pid-ff --task steps --fast --samples 0",
                         "--controllers pid,pid-ff,lugre-observer --fast --samples 4 --jobs 1")
    add(Case("compensate-json-read-only", f"{heavy} --json ro/c.json", "refuse", ("ro",), "9",
             user="nobody", max_cpu=8.0))
    add(Case("compensate-report-read-only", f"{heavy} --report ro/rep", "refuse", ("ro",), "9",
             user="nobody", max_cpu=8.0))
    add(Case("compensate-model-with-terms", COMP.replace("lugre,coulomb", "lugre,m_terms_ok.json"),
             "warn", ("measurement terms",)))
    # ---- the fitted range (item 11) ----
    add(Case("simulate-posdep-far", "simulate hydraulic --friction posdep.json --input "
             "step:amplitude=0.15 --duration 0.3 -o o.csv", "refuse-or-warn",
             ("posdep.json",), "11"))
    add(Case("simulate-ranged-far", "simulate hydraulic --friction ranged.json --input "
             "step:amplitude=0.15 --duration 0.3 -o o.csv", "refuse-or-warn",
             ("ranged.json",), "11"))
    add(Case("compensate-ranged", COMP.replace("lugre,coulomb", "lugre,ranged.json"),
             "refuse-or-warn", ("ranged.json",), "11"))
    add(Case("compensate-ranged-true", COMP.replace("--friction lugre", "--friction ranged.json"),
             "refuse-or-warn", ("ranged.json",), "11"))
    add(Case("sweep-ranged", f"{SWEEP} --friction ranged.json", "refuse-or-warn",
             ("ranged.json",), "11"))
    add(Case("export-ranged", f"{EXPORT} --friction ranged.json", "refuse-or-warn",
             ("ranged.json",), "11", env={"FCOMP_CC": "/nonexistent-cc"}))
    add(Case("compare-ranged-within", "compare rec.csv --friction cv.json", "ok"))
    # ---- sweep ----
    for label, extra, match in (
            ("samples-zero", "--samples 0", ("--samples",)),
            ("samples-negative", "--samples -3", ("--samples",)),
            ("samples-text", "--samples x", ("--samples",)),
            ("samples-huge", "--samples 100000000", ("--samples", "1000")),
            ("spread-negative", "--spread -1", ("--spread",)),
            ("spread-inf", "--spread inf", ("--spread",)),
            ("noise-reversed", "--noise 3,0.5", ("--noise",)),
            ("noise-text", "--noise a,b", ("--noise",)),
            ("noise-one", "--noise 1", ("--noise",)),
            ("noise-negative", "--noise -1,2", ("--noise",)),
            ("noise-three", "--noise 1,2,3", ("--noise",)),
            ("grid-empty", "--grid Fc=", ("--grid",)),
            ("grid-text", "--grid Fc=a", ("--grid",)),
            ("grid-unknown", "--grid nope=1,2", ("nope",)),
            ("grid-negative", "--grid Fc=-1,1", ("Fc",)),
            ("grid-overflow", "--grid Fc=1e400", ("--grid",)),
            ("grid-twice", "--grid Fc=1,2 --grid Fc=3", ("Fc",)),
            ("grid-no-equals", "--grid Fc", ("--grid",)),
            ("controller-friction-unknown", "--controller-friction magic", ("magic",)),
            ("controller-friction-missing", "--controller-friction nope.json", ("nope.json",)),
            ("task-unknown", "--task nope", ("nope",)),
            ("plant-unknown", "--plant nope", ("nope",)),
            ("controllers-unknown", "--controllers pid,nope", ("nope",)),
            ("json-onto-input", "--json rec.csv", ("rec.csv",)),
            ("json-disk-full", "--json /dev/full", ("/dev/full",))):
        add(Case(f"sweep-{label}", f"{SWEEP} {extra}", "refuse", match,
                 "8" if "disk-full" in label else ""))
    add(Case("sweep-model-file-grid", f"{SWEEP.replace('--samples 2 ', '')} "
             "--controller-friction lugre,lugre.json", "ok", (), "1", "honest"))
    add(Case("sweep-report-read-only", f"{SWEEP.replace('--samples 2', '--samples 12')} "
             "--report ro/rep", "refuse", ("ro",), "9", user="nobody", max_cpu=8.0))
    add(Case("sweep-json-read-only", f"{SWEEP.replace('--samples 2', '--samples 12')} "
             "--json ro/s.json", "refuse", ("ro",), "9", user="nobody", max_cpu=8.0))
    # ---- export ----
    for label, extra, match, owner in (
            ("controller-unknown", "--friction lugre", ("nope",), ""),
            ("duration-zero", "--duration 0", ("--duration",), ""),
            ("duration-negative", "--duration -1", ("--duration",), ""),
            ("duration-inf", "--duration inf", ("--duration",), ""),
            ("duration-huge", "--duration 1e9", ("--duration",), ""),
            ("option-unknown", "--option nope=1", ("nope",), ""),
            ("option-no-value", "--option observer_gain", ("--option",), ""),
            ("option-text", "--option bandwidth=a", ("--option",), ""),
            ("option-negative", "--option bandwidth=-5", ("bandwidth",), ""),
            ("task-unknown", "--task nope", ("nope",), ""),
            ("json-onto-input", "--json hyd.toml --plant-params hyd.toml", ("hyd.toml",), ""),
            ("output-empty", "-o ''", ("-o",), ""),
            ("output-onto-input", "-o rec.csv", ("rec.csv",), ""),
            ("output-foreign", "-o mine", ("mine",), "failsafe"),
            ("timing-steps-zero", "--timing-steps 0", ("--timing-steps",), "failsafe"),
            ("timing-steps-huge", "--timing-steps 1e12", ("--timing-steps",), "failsafe"),
            ("set-unknown", "--set nope=1", ("nope",), ""),
            ("add-effect-unknown", "--add-effect magic", ("magic",), ""),
            ("output-read-only", "-o ro/ctrl", ("ro",), "")):
        args = f"{EXPORT} {extra}"
        if label == "controller-unknown":
            args = EXPORT.replace("export pid", "export nope")
        if label == "output-empty" or label == "output-onto-input" or label == "output-foreign" \
                or label == "output-read-only":
            args = EXPORT.replace("-o ctrl", extra)
        add(Case(f"export-{label}", args, "refuse", match, "9" if "read-only" in label else "",
                 owner or "hostile", user="nobody" if "read-only" in label else None,
                 env={"FCOMP_CC": "/nonexistent-cc"}))
    # ---- --save-model ----
    for label, target, expect, match, user in (
            ("onto-input", "rec.csv", "refuse", ("rec.csv",), None),
            ("onto-sidecar", "rec.toml", "refuse", ("rec.toml",), None),
            ("txt", "m.txt", "refuse", (".json",), None),
            ("empty", "''", "refuse", ("--save-model",), None),
            ("folder", "mine", "refuse", ("mine",), None),
            ("under-a-file", "rec.csv/m.json", "refuse", ("rec.csv",), None),
            ("name-250", "c" * 245 + ".json", "ok", (), None),
            ("name-300", "c" * 300 + ".json", "refuse", ("bytes long",), None),
            ("disk-full", "/dev/full", "refuse", ("/dev/full",), None),
            ("read-only", "ro/m.json", "refuse", ("ro",), "nobody")):
        add(Case(f"save-model-{label}", f"{FIT} --save-model {target}", expect, match,
                 "9" if label in ("name-250", "read-only") else "8" if label == "disk-full"
                 else "", user=user))
    add(Case("json-name-250", f"{FIT} --json " + "d" * 245 + ".json", "ok", (), "9"))
    add(Case("json-name-255-exact", f"{FIT} --json " + "e" * 250 + ".json", "ok", (), "9"))
    add(Case("json-read-only", f"{FIT} --json ro/f.json", "refuse", ("ro",), "9",
             user="nobody"))
    add(Case("report-read-only", f"{FIT} --report ro/rep", "refuse", ("ro",), "9",
             user="nobody"))
    add(Case("simulate-output-read-only", f"{SIM} --friction lugre".replace("-o o.csv",
                                                                         "-o ro/o.csv"),
             "refuse", ("ro",), "9", user="nobody"))
    add(Case("simulate-output-disk-full-folder", f"{SIM} --friction lugre".replace(
        "-o o.csv", "-o /dev/full/o.csv"), "refuse", ("/dev/full",), ""))
    add(Case("diagnose-json-disk-full", "diagnose rec.csv --friction coulomb --candidates "
             "viscous --no-progress --no-baseline-check --json /dev/full", "refuse",
             ("/dev/full",), "8"))
    # ---- import csv --map ----
    for label, extra, match in (
            ("map-empty", "--map ''", ("--map",)),
            ("map-no-equals", "--map t", ("--map",)),
            ("map-no-column", "--map =time_ms", ("--map",)),
            ("map-no-expr", "--map t=", ("--map",)),
            ("map-twice", "--map t=time_ms,t=time_ms", ("twice",)),
            ("map-unknown-column", "--map t=nope --drop '*'", ("nope",)),
            ("map-unbalanced-quote", "--map \"t='time_ms\" --drop '*'", ("log.csv", "'t'")),
            ("map-dangling-star", "--map 't=time_ms*' --drop '*'", ("log.csv", "'t'")),
            ("map-power", "--map 't=time_ms**2' --drop '*'", ("log.csv", "'t'")),
            ("map-division", "--map t=time_ms/1000 --drop '*'", ("log.csv", "'t'")),
            ("map-parens", "--map 't=(time_ms)' --drop '*'", ("log.csv", "'t'")),
            ("map-inf", "--map t=time_ms,x=pos_mm*inf --drop '*'", ("log.csv", "'x'")),
            ("map-nan", "--map t=time_ms,x=pos_mm*nan --drop '*'", ("log.csv", "'x'")),
            ("map-bigint", "--map t=time_ms,x=pos_mm*1" + "0" * 5000 + " --drop '*'",
             ("log.csv", "'x'", "characters")),
            ("map-zero-time", "--map t=time_ms*0,x=pos_mm --drop '*'", ("t",)),
            ("units-unknown", "--map t=time_ms --units t=furlong --drop '*'", ("furlong",)),
            ("units-twice", "--map t=time_ms --units t=ms,t=s --drop '*'", ("twice",)),
            ("units-unmapped", "--map t=time_ms --units x=mm --drop '*'", ("x",)),
            ("drop-mapped", "--map t=time_ms,x=pos_mm,F=force --drop time_ms", ("time_ms",)),
            ("unmapped-left", "--map t=time_ms", ("pos_mm",)),
            ("delimiter-bad", "--map t=time_ms --drop '*' --delimiter pipe", ("pipe",)),
            ("decimal-clash", "--map t=time_ms --drop '*' --delimiter comma --decimal comma",
             ("decimal",)),
            ("sidecar-missing", "--map t=time_ms --drop '*' --sidecar nope.toml", ("nope.toml",)),
            ("sidecar-plant", "--map t=time_ms --drop '*' --sidecar hyd.toml", ("hyd.toml",)),
            ("output-onto-source", "--map t=time_ms --drop '*' -o log.csv", ("log.csv",))):
        args = f"import csv log.csv {extra}"
        if "-o " not in extra:
            args += " -o i.csv"
        add(Case(f"import-csv-{label}", args, "refuse", match))
    add(Case("import-csv-ok", "import csv log.csv --map t=time_ms,x=pos_mm,F=force --units "
             "t=ms,x=mm -o i.csv", "ok"))
    add(Case("import-csv-extra-column", "import csv log.csv --map t=time_ms,zz=pos_mm --drop '*' "
             "-o i.csv", "ok"))  # columns of one's own are part of the format
    # ---- shipped data sets by name (item 16) ----
    add(Case("import-zillen-by-name", "import zillen O-ring_3bar -o z.csv", "ok", (), "16"))
    add(Case("import-zillen-by-file-name", "import zillen O-ring_3bar.csv -o z.csv", "ok", (),
             "16"))
    add(Case("import-mataveid-by-name", "import mataveid HangingLoad -o m.csv", "ok", (), "16"))
    add(Case("import-emps-by-name", "import emps DATA_EMPS -o e.csv", "ok", (), "16"))
    add(Case("import-zillen-unknown-name", "import zillen O-ring_9bar -o z.csv", "refuse",
             ("O-ring_9bar",), "16"))
    add(Case("list-data", "list data", "ok", (), "16",
             check=lambda folder, out, err: None if "O-ring_3bar" in out else "not listed"))
    # ---- messages ----
    add(Case("fit-json-disk-full", f"{FIT} --json /dev/full", "refuse", ("/dev/full",), "8"))
    add(Case("compensate-reference-deep", COMP.replace("--task steps ", "")
             + " --reference m_deep_list.json", "refuse", ("m_deep_list.json",), ""))
    # ---- fcomp design (issue 40): rig files, diagnoses, options, outputs, signals ----
    DESIGN = "design diag.json --rig rig.toml -o prog"
    add(Case("design-ok", f"{DESIGN} --json d.json", "ok", (), owner="design",
             check=lambda folder, out, err: None if list((folder / "prog").glob("*.csv"))
             and (folder / "d.json").is_file() else "no programme written"))
    add(Case("design-template", "design --template", "ok", (), owner="design",
             check=lambda folder, out, err: None if "[limits]" in out else "no template"))
    for stem, (_, what) in RIGS.items():
        add(Case(f"design-rig-{stem}", DESIGN.replace("rig.toml", f"rig_{stem}.toml"),
                 "refuse", (f"rig_{stem}.toml", *((what,) if what else ())), owner="design"))
    for given, wrong in (("rig.toml", ("rig_empty.toml", "rig_binary.toml", "nope.toml", "mine",
                                       "hyd.toml")),
                         ("diag.json", ("nope.json", "mine", "lugre.json", "rec.csv"))):
        for name in wrong:  # no file, a folder, a file of another kind
            add(Case(f"design-{given.split('.')[0]}-given-{name.replace('.', '-')}",
                     DESIGN.replace(given, name), "refuse", (name,), owner="design"))
    for missing, what in (("--rig rig.toml ", "--rig"), ("-o prog", "-o")):
        add(Case(f"design-without-{what.lstrip('-')}", DESIGN.replace(missing, "").strip(),
                 "refuse", (what,), owner="design"))
    for stem in DIAGS:  # an effect fcomp does not know: left out, said (an effects file's?)
        expect, match = {"ties-unknown": ("warn", ("no-such-effect",)),
                         "skipped-unknown": ("refuse", (f"diag_{stem}.json", "no-such-effect"))
                         }.get(stem, ("refuse", (f"diag_{stem}.json",)))
        add(Case(f"design-diag-{stem}", DESIGN.replace("diag.json", f"diag_{stem}.json"),
                 expect, match, owner="design"))
    for label, value in (("nan", "nan"), ("negative", "-1"), ("zero", "0"), ("huge", "1e308"),
                         ("text", "loud")):
        add(Case(f"design-noise-{label}", f"{DESIGN} --noise {value}", "refuse", ("noise",),
                 owner="design"))
    for label, extra, match in (
            ("output-onto-diag", "-o diag.json", ("diag.json",)),
            ("output-onto-rig", "-o rig.toml", ("rig.toml",)),
            ("output-foreign-folder", "-o mine", ("mine",)),
            ("output-read-only", "-o ro/prog", ("ro",)),
            ("output-name-too-long", "-o " + "p" * 300, ("bytes long",)),
            ("json-onto-diag", "-o prog --json diag.json", ("diag.json",)),
            ("json-onto-rig", "-o prog --json rig.toml", ("rig.toml",)),
            ("json-disk-full", "-o prog --json /dev/full", ("/dev/full",)),
            ("json-folder", "-o prog --json mine", ("mine",)),
            ("report-onto-diag", "-o prog --report diag.json", ("diag.json",)),
            ("json-into-programme", "-o prog --json prog/d.json", ("prog",))):
        add(Case(f"design-{label}", f"design diag.json --rig rig.toml {extra}", "refuse",
                 match, owner="design", user="nobody" if "read-only" in label else None))
    for sig, name in ((signal.SIGINT, "int"), (signal.SIGTERM, "term")):
        for when in ("handler", 1.0, 3.0):
            add(Case(f"design-signal-{name}-at-{when}", f"{DESIGN} --json d.json --report rep",
                     "signal", (), owner="design", sig=(sig, when, None)))
    # ---- signals (item 4) ----
    for sig, name in ((signal.SIGINT, "int"), (signal.SIGTERM, "term")):
        for when in ("handler", 0.2, 0.5, 1.0, 1.5, 2.5):
            add(Case(f"signal-{name}-at-{when}", LONG_SIM, "signal", (), "4",
                     sig=(sig, when, None)))
    add(Case("signal-double-int-sweep", "sweep --samples 20 --jobs 2 --no-progress --json s.json",
             "signal", (), "4", sig=(signal.SIGINT, 4.0, 0.15)))
    add(Case("signal-double-int-compensate", COMP.replace("--samples 0", "--samples 6") +
             " --jobs 2 --json c.json", "signal", (), "4", sig=(signal.SIGINT, 4.0, 0.15)))
    add(Case("signal-term-pool-start", "sweep --samples 20 --jobs 2 --no-progress --json s.json",
             "signal", (), "4", sig=(signal.SIGTERM, "children", None)))
    add(Case("signal-int-pool-start", "sweep --samples 20 --jobs 2 --no-progress --json s.json",
             "signal", (), "4", sig=(signal.SIGINT, "children", None)))
    return out


# ------------------------------------------------------------------ running
def _snapshot(folder: Path) -> dict[str, str]:
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = str(p.relative_to(folder))
        if p.is_symlink():
            out[rel] = "link"
        elif p.is_dir():
            out[rel] = "dir"
        else:
            out[rel] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


@dataclass
class Result:
    id: str
    outcome: str
    reason: str
    code: int | None
    seconds: float
    item: str
    owner: str
    stderr: str
    cpu: float = 0.0


def _classify(case: Case, code: int | None, out: str, err: str, changed: list[str],
              left: list[str]) -> tuple[str, str]:
    text = out + err
    if code is None:
        return "hang", "no end within the time limit"
    if "Traceback (most recent call last)" in text or "Exception ignored" in text:
        return "traceback", err.strip().splitlines()[-1] if err.strip() else "traceback"
    if "internal error" in err or code == 1:
        return "internal", err.strip().splitlines()[-1] if err.strip() else f"exit {code}"
    if changed:
        return "wrong", f"input changed: {', '.join(changed[:3])}"
    lines = [s for s in err.splitlines() if s.strip()]
    errors = [s for s in lines if s.startswith(("fcomp: error:", "fcomp plant check: error:"))
              or ": error: " in s]
    warns = [s for s in lines if s.startswith("fcomp: warning:")]
    want = case.expect
    if want == "quiet":
        return ("clean", "") if not errors else ("wrong", errors[0])
    if want == "signal":
        return "wrong", "handled apart"
    refused = code == 2 and errors and len(errors) == len(lines) and \
        (case.multi or len(lines) == 1)
    refused_ok = bool(refused) and all(any(m in e for e in errors) for m in case.match)
    warned = code == 0 and bool(warns) and all(any(m in w for w in warns) for m in case.match)
    if want in ("refuse", "refuse-or-warn") and refused_ok:
        return ("clean", "") if not left else ("wrong", f"left {', '.join(left[:3])}")
    if want in ("warn", "refuse-or-warn") and warned:
        return "clean", ""
    if want == "ok" and code == 0 and not errors:
        return "clean", ""
    if code == 2 and errors:
        why = "several lines" if len(lines) > 1 and not case.multi else \
            f"does not name {[m for m in case.match if not any(m in e for e in errors)]}" \
            if want != "ok" else "refused a valid input"
        return "wrong", f"{why}: {errors[0][:200]}"
    if code == 0:
        return "wrong", f"exit 0 where {want} was due" + (f" ({warns[0][:150]})" if warns else "")
    return "wrong", f"exit {code}: {(lines or [''])[-1][:200]}"


def run_case(case: Case, lab: Path, root: Path, timeout: float) -> Result:
    folder = Path(tempfile.mkdtemp(prefix="hostile-"))
    work = folder / "lab"
    shutil.copytree(lab, work, symlinks=True)
    if case.user:
        os.chmod(work / "ro", 0o555)
    before = _snapshot(work)
    env = dict(os.environ, PYTHONPATH=str(root), **case.env)
    env.pop("FCOMP_DEBUG", None)
    env["FCOMP_CACHE"] = str(folder / "cache") if case.user else env.get("FCOMP_CACHE", "")
    if not env["FCOMP_CACHE"]:
        env.pop("FCOMP_CACHE")
    fcomp = f"{shlex.quote(sys.executable)} -m fcomp.cli.main"
    if case.shell:
        argv = ["/bin/sh", "-c", case.args.replace("{fcomp}", fcomp)]
    else:
        argv = [sys.executable, "-m", "fcomp.cli.main", *shlex.split(case.args)]
    if case.user and os.geteuid() == 0:  # root without the capabilities to write anywhere:
        # the folder's mode bits hold, and the interpreter stays readable wherever it is
        argv = ["setpriv", "--bounding-set=-dac_override,-dac_read_search", "--", *argv]
        env["HOME"] = str(folder)
    start = time.monotonic()
    limit = case.timeout or timeout
    proc = subprocess.Popen(argv, cwd=work, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
                            start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    if case.sig is not None:
        return _run_signal(case, proc, start, folder, work, before)
    code, out_b, err_b, cpu = _wait(proc, limit)
    seconds = time.monotonic() - start
    out, err = out_b.decode(errors="replace"), err_b.decode(errors="replace")
    after = _snapshot(work)
    changed = [k for k, v in before.items() if after.get(k) != v]
    new = [k for k in after if k not in before]
    left = new if code == 2 else [k for k in new if k.endswith((".tmp", ".old"))
                                  or "/." in k or k.startswith(".")]
    outcome, reason = _classify(case, code, out, err, changed, left)
    if outcome == "clean" and code == 2 and case.max_cpu is not None and cpu > case.max_cpu:
        outcome, reason = "wrong", f"refused late, after {cpu:.1f} s of CPU (the work ran)"
    if outcome == "clean" and case.check is not None:
        problem = case.check(work, out, err)
        if problem:
            outcome, reason = "wrong", problem
    shutil.rmtree(folder, ignore_errors=True)
    return Result(case.id, outcome, reason, code, seconds, case.item, case.owner, err[-2000:],
                  round(cpu, 2))


def _wait(proc: subprocess.Popen, limit: float) -> tuple[int | None, bytes, bytes, float]:
    """Exit status (None: killed at ``limit`` s), stdout, stderr and the CPU seconds
    (user + system) of the process and the children it waited for."""
    chunks: dict[str, list[bytes]] = {"out": [], "err": []}

    def read(name: str, stream: Any) -> None:
        for block in iter(lambda: stream.read(65536), b""):
            chunks[name].append(block)

    readers = [threading.Thread(target=read, args=(n, s), daemon=True)
               for n, s in (("out", proc.stdout), ("err", proc.stderr))]
    for r in readers:
        r.start()
    end = time.monotonic() + limit
    code: int | None = None
    cpu = 0.0
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            code = os.waitstatus_to_exitcode(status)
            cpu = usage.ru_utime + usage.ru_stime
            proc.returncode = code
            break
        if time.monotonic() > end:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
            os.wait4(proc.pid, 0)
            proc.returncode = -9
            break
        time.sleep(0.02)
    for r in readers:
        r.join(5)
    return code, b"".join(chunks["out"]), b"".join(chunks["err"]), cpu


def _run_signal(case: Case, proc: subprocess.Popen, start: float, folder: Path, work: Path,
                before: dict[str, str]) -> Result:
    assert case.sig is not None
    sig, when, second = case.sig
    limit = 60.0
    while proc.poll() is None and time.monotonic() - start < limit:
        if when == "handler" and processes.sigterm_caught(proc.pid):
            break
        if when == "children" and processes.children(proc.pid):
            break
        if isinstance(when, float) and time.monotonic() - start >= when:
            break
        time.sleep(0.002)
    if proc.poll() is not None:
        out_b, err_b = proc.communicate()
        shutil.rmtree(folder, ignore_errors=True)
        return Result(case.id, "wrong", "ended before the signal", proc.returncode,
                      time.monotonic() - start, case.item, case.owner, err_b.decode()[-2000:])

    def send(s: int) -> None:
        with contextlib.suppress(ProcessLookupError):
            if s == signal.SIGINT:
                os.killpg(proc.pid, s)  # Ctrl-C at a terminal: the whole group
            else:
                os.kill(proc.pid, s)
    sent = time.monotonic()
    send(sig)
    if second is not None:
        time.sleep(second)
        send(sig)
    try:
        out_b, err_b = proc.communicate(timeout=30)
        code: int | None = proc.returncode
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        out_b, err_b = proc.communicate()
        code = None
    took = time.monotonic() - sent
    end = time.monotonic() + 5.0
    alive = processes.group(proc.pid)
    while alive and time.monotonic() < end:
        time.sleep(0.1)
        alive = processes.group(proc.pid)
    for pid in alive:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
    out, err = out_b.decode(errors="replace"), err_b.decode(errors="replace")
    line = "fcomp: interrupted" if sig == signal.SIGINT else "fcomp: terminated"
    want = 130 if sig == signal.SIGINT else 143
    time.sleep(0.3)
    after = _snapshot(work)
    changed = [k for k, v in before.items() if after.get(k) != v] + \
        [k for k in after if k not in before]
    shutil.rmtree(folder, ignore_errors=True)
    if code is None:
        outcome, reason = "hang", f"no end 30 s after the signal ({when})"
    elif "Traceback" in err or "Exception ignored" in err:
        outcome, reason = "traceback", f"{err.count(chr(10))} lines after the signal at {when}"
    elif code != want or err != line + "\n" or out:
        outcome, reason = "wrong", f"exit {code}, stderr {err.strip()[:120]!r}"
    elif alive:
        outcome, reason = "wrong", f"{len(alive)} processes left running"
    elif changed:
        outcome, reason = "wrong", f"left {', '.join(changed[:3])}"
    elif took > 10.0:
        outcome, reason = "wrong", f"took {took:.1f} s to stop"
    else:
        outcome, reason = "clean", f"stopped {took:.2f} s after the signal"
    return Result(case.id, outcome, reason, code, time.monotonic() - start, case.item,
                  case.owner, err[-2000:])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", default=str(HERE), help="the tree under test (default: this one)")
    ap.add_argument("--jobs", type=int, default=2, help="cases run at once (default 2)")
    ap.add_argument("--timeout", type=float, default=180.0, help="seconds before a hang")
    ap.add_argument("--json", default=None, help="write every outcome to this file")
    ap.add_argument("-k", default=None, help="only the cases whose id holds this text")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    args = ap.parse_args(argv)
    root = Path(args.root).resolve()
    todo = [c for c in cases() if args.k is None or args.k in c.id]
    if args.list:
        for c in todo:
            print(f"{c.id:50s} {c.expect:15s} item {c.item or '-':3s} {c.owner}")
        print(f"{len(todo)} cases")
        return 0
    lab = Path(tempfile.mkdtemp(prefix="hostile-lab-"))
    write_lab(lab, root)
    results: list[Result] = []
    t0 = time.monotonic()
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        futures = {pool.submit(run_case, c, lab, root, args.timeout): c for c in todo}
        for fut in concurrent.futures.as_completed(futures):
            r = fut.result()
            results.append(r)
            mark = "ok " if r.outcome == "clean" else "BAD"
            print(f"{mark} {r.outcome:9s} {r.seconds:6.1f}s {r.cpu:5.1f}cpu {r.id}"
                  + (f"  -- {r.reason[:160]}" if r.outcome != "clean" else ""), flush=True)
    shutil.rmtree(lab, ignore_errors=True)
    results.sort(key=lambda r: r.id)
    mine = [r for r in results if r.owner == "hostile"]
    others = [r for r in results if r.owner != "hostile"]
    summary = {
        "root": str(root), "cases": len(results), "seconds": round(time.monotonic() - t0, 1),
        "clean": sum(r.outcome == "clean" for r in results),
        "failed": sum(r.outcome != "clean" for r in results),
        "outcomes": dict(Counter(r.outcome for r in results)),
        "this_work": {"cases": len(mine), "clean": sum(r.outcome == "clean" for r in mine)},
        "other_owners": {o: {"cases": sum(r.owner == o for r in others),
                             "clean": sum(r.owner == o and r.outcome == "clean" for r in others)}
                         for o in sorted({r.owner for r in others})},
    }
    print(json.dumps(summary, indent=2))
    if args.json:
        Path(args.json).write_text(json.dumps({"summary": summary, "results": [
            r.__dict__ for r in results]}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
