"""Bad input against every command (issue 12): one clean line, exit 2, nothing lost, nothing left.

Every case of :data:`CASES` runs the command line in-process
(:func:`fcomp.cli.main.main`) inside a folder of inputs, the *lab*, and checks

* the exit status: 2 for bad input, 0 where the input is valid after all
  (a byte-order mark, quoted names, CRLF line ends, ...);
* stderr: exactly one line for an error, naming the problem (``match``), and
  no ``Traceback``; a success prints nothing there but one
  ``fcomp: warning: ...`` line per expected warning (the *warnings* cases:
  aliasing, command saturation, cavitation, ...), also written into the
  output's sidecar or JSON;
* nothing lost, nothing left: every file of the lab is byte-identical
  afterwards (SHA-256, hidden files included) and, after an error, the lab
  holds exactly the files it held before (no output, no temporary, no empty
  folder); a success adds only its declared outputs.

The interrupt cases (a study, the demo, a diagnose report, Ctrl-C and SIGTERM
on a real process) check that an interrupted run leaves the old result whole
or nothing, and a few cases run as real subprocesses to prove that no
traceback escapes the interpreter. ``test_case_count`` states how many cases
there are.

The cases of issue 42 -- plant and model files, outputs, signals, fitted ranges,
messages -- live in ``tests/bad_input/`` (one module per surface), on the inputs of
the hostile-case runner ``benchmarks/hostile_cases.py``; the helpers shared with this
file are ``tests/helpers/cli_cases.py`` and ``tests/helpers/processes.py``.
"""

from __future__ import annotations

import contextlib
import json
import os
import shlex
import shutil
import signal
import subprocess
import sys
import time
import tomllib
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from helpers.cli_cases import run_cli as _run
from helpers.cli_cases import snapshot
from helpers.processes import (
    PATIENCE,
    alive,
    children,
    cmdline,
    env,
    finish,
    group,
    group_gone,
    send,
    start,
    wait_for,
)
from helpers.terminal import drain
from test_effects import USER_MODULE

from fcomp import datasets
from fcomp.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
TAG = uuid.uuid4().hex[:8]  # effect names are process-global: one set per test session


# ------------------------------------------------------------------ the lab
def _good_text() -> str:
    t = np.arange(200) * 0.01
    amp = np.where(t < 1.0, 0.05, 0.02)  # two speeds: a clean fit, Fc and B apart (no warning)
    v = amp * np.sin(2 * np.pi * t)
    x = amp / (2 * np.pi) * (1 - np.cos(2 * np.pi * t))
    a = amp * 2 * np.pi * np.cos(2 * np.pi * t)
    rng = np.random.default_rng(3)
    F = 2.0 * np.tanh(v / 1e-3) + 30.0 * v + 0.01 * rng.standard_normal(t.size)
    rows = ["t,x,v,a,F"] + [",".join(repr(float(c)) for c in r)
                            for r in np.column_stack([t, x, v, a, F])]
    return "\n".join(rows) + "\n"


def _lines(text: str, line: int, cell: int, value: str) -> str:
    """``text`` with cell ``cell`` of file line ``line`` (1-based) replaced by ``value``."""
    rows = text.splitlines()
    cells = rows[line - 1].split(",")
    cells[cell] = value
    rows[line - 1] = ",".join(cells)
    return "\n".join(rows) + "\n"


#: A user's effects module (test_effects.USER_MODULE) whose ``extra_force`` runs ``{body}``.
EFFECT = USER_MODULE.replace("def extra_force(self, be, sig, P):\n",
                             "def extra_force(self, be, sig, P):\n        {body}\n")
#: The line of ``{body}`` in :data:`EFFECT`, which errors raised there must name.
BODY = EFFECT.splitlines().index("        {body}") + 1


def _effect(name: str, body: str = "pass") -> str:
    return EFFECT.replace("{body}", body).format(name=name)


def _write_lab(lab: Path) -> None:
    good = _good_text()
    files: dict[str, str | bytes] = {
        "good.csv": good,
        "good.toml": 'name = "good"\nkind = "friction-rig"\n\n[rig]\nmass = 1.0\n',
        "bare.csv": good,
        "prev.csv": good, "prev.toml": 'name = "prev"\n',
        "sim.csv": good, "sim.toml": 'name = "sim"\n',
        "old.json": '{"old": true}\n',
        "u.csv": "t,u\n0,0\n0.2,0.01\n0.5,0.02\n",
        "u_header.csv": "t,u\n",
        "u_one.csv": "t,u\n0,1\n",
        "u_nan.csv": "t,u\n0,0\n1,nan\n",
        "u_back.csv": "t,u\n0,0\n-1,0\n",
        "u_fine.csv": "t,u\n" + "".join(f"{k * 1e-4!r},{0.01 * np.sin(k / 7):.6f}\n"
                                         for k in range(6000)),
        # valid after all: a reader that accepts what spreadsheets write
        "bom.csv": "\ufeff" + good,
        "quoted.csv": '"t","x","v","a","F"\n' + good.split("\n", 1)[1],
        "crlf.csv": good.replace("\n", "\r\n"),
        "comments.csv": "# exported by the rig\n\n" + good.replace("\n", "\n\n", 3),
        "spaces.csv": " t , x , v , a , F \n" + good.split("\n", 1)[1],
        # bad CSVs
        "empty.csv": "",
        "header_only.csv": "t,x,v,a,F\n",
        "blank_only.csv": "\n\n\n",
        "one_row.csv": "t,x,v,a,F\n0,0,0,0,0\n",
        "text12.csv": _lines(good, 12, 1, "abc"),
        "nan12.csv": _lines(good, 12, 1, "nan"),
        "inf12.csv": _lines(good, 12, 4, "inf"),
        "empty_cell.csv": _lines(good, 7, 2, ""),
        "huge.csv": _lines(good, 9, 4, "1e300"),
        "ns_time.csv": "t,F\n" + "".join(f"{1.7e18 + k * 1e6!r},1.0\n" for k in range(5)),
        "tiny_steps.csv": "t,x,F\n" + "".join(f"{k * 1e-300!r},{1e-4 * k},1.0\n"
                                               for k in range(50)),
        "underscore.csv": "t,x,F\n0,0,1\n0.01,1_000,1\n",
        "gap_nan.csv": good.replace("\n", "\n\n", 4).replace(
            good.splitlines()[9], good.splitlines()[9].rsplit(",", 1)[0] + ",nan"),
        "ragged.csv": _lines(good, 5, 4, "1,2"),
        "semicolon.csv": good.replace(",", ";"),
        "tabs.csv": good.replace(",", "\t"),
        "decimal_comma.csv": "t;F\n0,0;1,5\n0,1;1,6\n",
        "dupcol.csv": "t,x,x\n0,0,0\n1,0,0\n",
        "emptycol.csv": "t,,x\n0,0,0\n1,0,0\n",
        "no_t.csv": "x,F\n0,1\n1,2\n",
        "t_back.csv": "t,F\n0,1\n2,1\n1,1\n",
        "t_repeat.csv": "t,F\n0,1\n1,1\n1,1\n",
        "x_mm.csv": "t,x,F\n0,0,1\n1,150,1\n",
        "p_bar.csv": "t,x,p1,F\n0,0,3.5,1\n1,0.01,4.0,1\n",
        "latin1.csv": b"t,F\n0,1\n1,2\n# Kraft \xe4\n",
        "binary.csv": b"t,F\n\x00\x01\x02\xff\xfe",
        "utf16.csv": "\ufeff".encode("utf-16-le") + good.encode("utf-16-le"),
        # sidecars
        "kind.csv": good, "kind.toml": 'kind = "pneumatic_cylinder"\n',
        "orient.csv": good, "orient.toml": '[rig]\norientation = "sideways"\n',
        "bore_mm.csv": good, "bore_mm.toml": "[rig]\nbore = 25.0\n",
        "rod_big.csv": good, "rod_big.toml": "[rig]\nbore = 0.02\nrod = 0.03\n",
        "mass_neg.csv": good, "mass_neg.toml": "[rig]\nmass = -1.0\n",
        "mass_text.csv": good, "mass_text.toml": '[rig]\nmass = "heavy"\n',
        "psi.csv": good, "psi.toml": 'pressure = "psi"\n',
        "unit.csv": good, "unit.toml": '[signals]\nu_unit = "mA"\n',
        "badtoml.csv": good, "badtoml.toml": "[rig\nmass = 1\n",
        "bintoml.csv": good, "bintoml.toml": b"\x00\xff\x00",
        "rigtable.csv": good, "rigtable.toml": "rig = 3\n",
        "mass_inf.csv": good, "mass_inf.toml": "[rig]\nmass = inf\n",
        "mass_huge.csv": good, "mass_huge.toml": "[rig]\nmass = 1e308\n",
        "name_num.csv": good, "name_num.toml": "name = 5\n",
        "exp_key.csv": good, "exp_key.toml": "experiment = 1.5\n[rig]\nmass = 1.0\n",
        "top_mass.csv": good, "top_mass.toml": "mass = 1.0\n",
        "huge_fit.json": '{"model": "coulomb-viscous", "params": {"Fc": 1.0, "B": 1e308}}\n',
        "lugre_1e308.json": json.dumps({"format": "fcomp-model", "version": 1, "model": "lugre",
                                        "params": {"Fc": 1e308, "Fs": 1e308, "vs": 0.008,
                                                   "n": 1.0, "sigma2": 900.0, "sigma0": 2e6,
                                                   "sigma1": 300.0}}),
        "patm_bar.csv": good, "patm_bar.toml": "p_atm = 1.013\n",
        "typo.csv": good, "typo.toml": "[rig]\nmas = 2.0\n",
        "absneg.csv": "t,x,p1\n0,0,-1000\n1,0.01,200000\n",
        "absneg.toml": 'pressure = "absolute"\n[rig]\nbore = 0.03\n',
        # importers
        "z.csv": "".join(datasets.path("zillen", "O-ring_3bar.csv").read_text()
                         .splitlines(keepends=True)[:60]),
        "z_empty.csv": "",
        "z_six.csv": "0 1 2 3 4 5\n10 1 2 3 4 5\n",
        "z_nan.csv": "0 1 2 3 4 5 6\n10 1 2 3 4 nan 6\n20 1 2 3 4 5 6\n",
        "z_back.csv": "0 1 2 3 4 5 6\n20 1 2 3 4 5 6\n10 1 2 3 4 5 6\n",
        "z_text.csv": "time laser pressure force position p F\n0 1 2 3 4 5 6\n",
        "m.csv": "".join(datasets.path("mataveid", "HangingLoad.csv").read_text()
                         .splitlines(keepends=True)[:60]),
        "m_empty.csv": "",
        "m_three.csv": "0,1,2\n0.02,1,2\n",
        "junk.mat": "this is not a MATLAB file\n",
        "fake73.mat": b"MATLAB 7.3 MAT-file, Platform: GLNXA64" + b"\x00" * 200,
        "rig.toml": 'kind = "friction-rig"\n[rig]\nmass = 2.0\n',
        "rig_bad.toml": "[rig\n",
        "rig_kind.toml": 'kind = "wheel"\n',
        # user code
        "eff_ok.py": _effect(f"ok-{TAG}"),
        "eff_exit0.py": "import sys\nsys.exit(0)\n",
        "eff_exitmsg.py": "import sys\n\nsys.exit('bye')\n",
        "eff_raise.py": '"""Broken."""\n\nraise RuntimeError("boom")\n',
        "eff_syntax.py": "def broken(:\n    pass\n",
        "eff_nul.py": b"x = 1\x00\n",
        "eff_ctrlc.py": "raise KeyboardInterrupt\n",
        "eff_osexit.py": "import os\nos._exit(0)\n",
        "eff_import.py": "import no_such_package_xyz\n",
        "eff_dup.py": _effect("viscous"),
        "eff_zdiv.py": _effect(f"zdiv-{TAG}", "1 / 0"),
        "eff_exit.py": _effect(f"exit-{TAG}", "__import__('sys').exit(3)"),
        "eff_name.py": _effect(f"name-{TAG}", "undefined_name + 1"),
        "effects.txt": "print('hi')\n",
        # a folder that is not fcomp's
        "mine/notes.txt": "my notes\n",
        "folder.csv/keep.txt": "a folder named like a file\n",
        "old/summary.json": '{"meta": {}}\n',
        "outer/fcomp/.fcomp-output": "Written by fcomp.\n",
        "outer/mine/notes.txt": "my notes\n",
    }
    for name, content in files.items():
        path = lab / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content)
    scipy.io.savemat(lab / "good.mat", {"time": np.arange(50) * 0.01,
                                        "pos": np.linspace(0, 0.01, 50),
                                        "force": np.ones(50), "gain": 2.0,
                                        "label": "text", "big": np.full(50, 1e300)})
    (lab / "link.csv").symlink_to("good.csv")
    (lab / "lk.json").symlink_to("lk_target.json")
    os.link(lab / "good.csv", lab / "hard.csv")
    (lab / "data_dir").mkdir()
    (lab / "empty_dir").mkdir()


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The folder of inputs; the user effects its modules register are removed afterwards
    (they are process-global, and some are broken on purpose)."""
    from fcomp.effects import EFFECTS
    from fcomp.usercode import USER_FILES

    path = tmp_path_factory.mktemp("lab")
    _write_lab(path)
    effects, files = set(EFFECTS.names()), set(USER_FILES)
    yield path
    for name in set(EFFECTS.names()) - effects:
        del EFFECTS._items[name]
    for f in set(USER_FILES) - files:
        del USER_FILES[f]


# ---------------------------------------------------------------- the cases
@dataclass(frozen=True)
class Case:
    """One command line and what it must do.

    ``code``: exit status; ``match``: text the error line must contain;
    ``outputs``: files a success writes; ``warnings``: codes of the expected
    warnings (each one ``fcomp: warning:`` line, and in the output).
    """

    args: str
    code: int = 2
    match: str = ""
    outputs: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    env: dict[str, str] = field(default_factory=dict)


#: What ``fcomp export ... -o c --json c.json`` writes (files before their folder).
EXPORT_FILES = ("c.json", "c/.fcomp-output", "c/fcomp_ctrl.h", "c/fcomp_ctrl.c",
                "c/fcomp_ctrl_bench.c", "c/example.c", "c/Makefile", "c/fcomp_ctrl_casadi.c",
                "c/fcomp_ctrl_casadi.h")
SIM = "simulate motion --friction coulomb --input sine:amplitude=0.01,frequency=1 " \
      "--duration 0.2 --rate 100"
SIM_NO_INPUT = "simulate motion --friction coulomb --duration 0.2 --rate 100"
FIT = "fit good.csv --friction coulomb-viscous"
DIAG = "diagnose good.csv --friction coulomb --no-progress"
E = {"ok": f"ok-{TAG}", "zdiv": f"zdiv-{TAG}", "exit": f"exit-{TAG}", "name": f"name-{TAG}"}

CASES: dict[str, Case] = {
    # ---- outputs onto inputs (the severe ones) ----
    "fit-json-onto-csv": Case(f"{FIT} --json good.csv", match="is the input file good.csv"),
    "fit-json-onto-sidecar": Case(f"{FIT} --json good.toml", match="sidecar of the input"),
    "fit-json-onto-absent-sidecar": Case("fit bare.csv --friction coulomb --json bare.toml",
                                         match="sidecar of the input"),
    "fit-json-onto-input-via-dotslash": Case(f"{FIT} --json ./good.csv", match="input file"),
    "fit-json-onto-symlinked-input": Case("fit link.csv --friction coulomb --json good.csv",
                                          match="input file"),
    "fit-json-onto-hardlinked-input": Case(f"{FIT} --json hard.csv", match="same file"),
    "fit-json-onto-effects-module": Case(f"{FIT} --effects eff_ok.py --json eff_ok.py",
                                         match="input file"),
    "fit-json-csv-suffix": Case(f"{FIT} --json result.csv", match="name it .json"),
    "fit-json-is-dir": Case(f"{FIT} --json data_dir", match="is a directory"),
    # one rule for missing output folders (issue 27): every output creates them
    "fit-json-missing-folder": Case(f"{FIT} --json nowhere/fit.json", code=0,
                                    outputs=("nowhere/fit.json", "nowhere")),
    "compare-json-missing-folder": Case("compare good.csv --friction coulomb --json a/b/c.json",
                                        code=0, outputs=("a/b/c.json", "a/b", "a"),
                                        warnings=("default-params",)),
    "fit-save-model-missing-folder": Case(f"{FIT} --save-model m/fit.json", code=0,
                                          outputs=("m/fit.json", "m")),
    "fit-json-under-a-file": Case(f"{FIT} --json good.csv/fit.json", match="is a file"),
    "fit-json-empty": Case(f"{FIT} --json ''", match="no file name"),
    "diagnose-json-onto-csv": Case(f"{DIAG} --json good.csv", match="input file"),
    "diagnose-json-onto-sidecar": Case(f"{DIAG} --json good.toml", match="sidecar"),
    "diagnose-report-cwd": Case(f"{DIAG} --report .", match="contains the input"),
    "diagnose-report-parent": Case(f"{DIAG} --report ..", match="contains the input"),
    "diagnose-report-is-input": Case(f"{DIAG} --report good.csv", match="is the input file"),
    "diagnose-report-foreign-folder": Case(f"{DIAG} --report mine", match="did not write"),
    "diagnose-report-json-inside": Case(f"{DIAG} --report empty_dir --json empty_dir/d.json",
                                        match="overlap"),
    "diagnose-report-json-same": Case(f"{DIAG} --report rep --json rep", match="overlap"),
    "diagnose-report-empty": Case(f"{DIAG} --report ''", match="no folder name"),
    "simulate-output-is-input-csv": Case(
        f"{SIM_NO_INPUT} --input csv:u.csv -o u.csv", match="input file u.csv"),
    "simulate-output-is-input-dotslash": Case(
        f"{SIM_NO_INPUT} --input csv:./u.csv -o ./u.csv", match="input file"),
    "simulate-output-sidecar-is-effects": Case(
        f"{SIM} --effects eff_ok.py -o eff_ok.csv", code=0, outputs=("eff_ok.csv", "eff_ok.toml")),
    "simulate-output-is-dir": Case(f"{SIM} -o folder.csv", match="is a directory"),
    "simulate-output-no-suffix": Case(f"{SIM} -o out.txt", match="must end in .csv"),
    "simulate-output-dotcsv": Case(f"{SIM} -o .csv", match="must end in .csv"),
    "simulate-output-empty": Case(f"{SIM} -o ''", match="no file name"),
    "simulate-output-under-a-file": Case(f"{SIM} -o good.csv/x.csv", match="not a folder"),
    "import-zillen-in-place": Case("import zillen z.csv -o z.csv", match="input file z.csv"),
    "import-mataveid-in-place": Case("import mataveid m.csv -o m.csv", match="input file"),
    "import-mat-sidecar-in-place": Case(
        "import mat good.mat --map t=time,x=pos --sidecar rig.toml -o rig.csv",
        match="input file rig.toml"),
    "import-mat-onto-mat": Case("import mat good.mat --map t=time -o good.mat",
                                match="must end in .csv"),
    "import-output-replaces-measurement": Case("import zillen z.csv -o prev.csv", code=0,
                                               outputs=("prev.csv", "prev.toml")),
    "study-out-cwd": Case("study coulomb-viscous --out .", match="contains the current folder"),
    "study-out-file": Case("study coulomb-viscous --out good.csv", match="not a directory"),
    "study-out-foreign": Case("study coulomb-viscous --out mine", match="did not write"),
    "study-out-empty": Case("study coulomb-viscous --out ''", match="no folder name"),
    "demo-out-cwd": Case("demo --out .", match="contains the current folder"),
    "demo-out-file": Case("demo --out good.csv", match="not a directory"),
    "demo-out-foreign": Case("demo --out mine", match="did not write"),
    "demo-out-study-folder": Case("demo --out old", match="did not write"),
    "demo-out-holding-a-foreign-subfolder": Case("demo --out outer", match="did not write"),
    "demo-out-empty": Case("demo --out ''", match="no folder name"),
    "demo-params-unknown": Case("demo --out d --params nope", match="unknown parameter set"),
    # ---- numbers: overflow, infinity, NaN ----
    "set-sigma0-inf": Case("fit good.csv --friction lugre --set sigma0=inf", match="finite"),
    "set-fs-fc-inf": Case("fit good.csv --friction lugre --set Fs=inf --set Fc=inf",
                          match="finite"),
    "set-nan": Case(f"{FIT} --set Fc=nan", match="finite"),
    "set-1e300": Case(f"{FIT} --set Fc=1e300", match="plausible"),
    "set-text": Case(f"{FIT} --set Fc=abc", match="not a number"),
    "set-no-equals": Case(f"{FIT} --set Fc", match="NAME=VALUE"),
    "set-no-name": Case(f"{FIT} --set =3", match="name before"),
    "set-twice": Case(f"{FIT} --set Fc=1 --set Fc=2", match="given twice"),
    "set-unknown": Case(f"{FIT} --set nope=1", match="nope"),
    "set-negative": Case(f"{FIT} --set Fc=-5", match="Fc"),
    "fix-inf": Case(f"{FIT} --fix B=inf", match="finite"),
    "fix-and-set": Case(f"{FIT} --fix B=1 --set B=2", match="choose one"),
    "fit-mass-inf": Case(f"{FIT} --mass inf", match="finite"),
    "fit-mass-nan": Case(f"{FIT} --mass nan", match="finite"),
    "fit-mass-negative": Case(f"{FIT} --mass -1", match="non-negative"),
    "fit-cutoff-zero": Case(f"{FIT} --cutoff 0", match="positive"),
    "fit-cutoff-inf": Case(f"{FIT} --cutoff inf", match="finite"),
    "fit-vmin-zero": Case(f"{FIT} --v-min 0", match="positive"),
    "fit-confidence-2": Case(f"{FIT} --confidence 2", match="between 0 and 1"),
    "fit-confidence-0": Case(f"{FIT} --confidence 0", match="between 0 and 1"),
    "fit-max-nfev-0": Case(f"{FIT} --max-nfev 0", match="positive"),
    "fit-max-nfev-text": Case(f"{FIT} --max-nfev many", match="invalid int"),
    "fit-free-empty": Case(f"{FIT} --free ''", match="at least one"),
    "fit-free-commas": Case(f"{FIT} --free ,,", match="at least one"),
    "fit-free-twice": Case(f"{FIT} --free Fc,Fc", match="given twice"),
    "fit-free-unknown": Case(f"{FIT} --free nope", match="nope"),
    "fit-method-unknown": Case(f"{FIT} --method magic", match="invalid choice"),
    "fit-model-unknown": Case("fit good.csv --friction magic", match="unknown friction model"),
    "fit-params-unknown": Case(f"{FIT} --params nope", match="unknown parameter set"),
    "fit-add-effect-unknown": Case(f"{FIT} --add-effect magic", match="unknown effect"),
    "fit-no-model": Case("fit good.csv", match="required"),
    "simulate-duration-inf": Case(f"{SIM_NO_INPUT} --input step:amplitude=1 --duration inf "
                                  "-o o.csv", match="finite"),
    "simulate-duration-zero": Case("simulate motion --friction coulomb --input step:amplitude=1 "
                                   "--duration 0 -o o.csv", match="positive"),
    "simulate-duration-negative": Case("simulate motion --friction coulomb --input "
                                       "step:amplitude=1 --duration -1 -o o.csv",
                                       match="positive"),
    "simulate-duration-huge": Case("simulate motion --friction coulomb --input step:amplitude=1 "
                                   "--duration 1e9 -o o.csv", match="samples requested"),
    "simulate-rate-zero": Case(f"{SIM} --rate 0 -o o.csv", match="positive"),
    "simulate-rate-nan": Case(f"{SIM} --rate nan -o o.csv", match="finite"),
    "simulate-rate-too-low": Case("simulate motion --friction coulomb --input step:amplitude=1 "
                                  "--duration 0.1 --rate 1 -o o.csv", match="no samples"),
    "simulate-set-inf": Case(f"{SIM} --set Fc=inf -o o.csv", match="finite"),
    "simulate-set-plant-inf": Case("simulate hydraulic --friction coulomb --input "
                                   "step:amplitude=0 --duration 0.01 --set mass=inf -o o.csv",
                                   match="finite"),
    "simulate-set-plant-negative": Case("simulate hydraulic --friction coulomb --input "
                                        "step:amplitude=0 --duration 0.01 --set mass=-3 -o o.csv",
                                        match="mass"),
    "simulate-rtol-zero": Case("simulate hydraulic --friction coulomb --input step:amplitude=0 "
                               "--duration 0.01 --rtol 0 -o o.csv", match="rtol"),
    "simulate-atol-big": Case("simulate hydraulic --friction coulomb --input step:amplitude=0 "
                              "--duration 0.01 --atol 5 -o o.csv", match="atol"),
    "simulate-max-steps-zero": Case("simulate hydraulic --friction coulomb --input "
                                    "step:amplitude=0 --duration 0.01 --max-steps 0 -o o.csv",
                                    match="max-steps"),
    "simulate-max-steps-tiny": Case("simulate hydraulic --friction coulomb --input "
                                    "sine:amplitude=4.5e-3,frequency=1 --duration 0.1 "
                                    "--max-steps 3 -o o.csv", match="--max-steps = "),
    "simulate-method-unknown": Case("simulate hydraulic --friction coulomb --input "
                                    "step:amplitude=0 --duration 0.01 --method euler -o o.csv",
                                    match="unknown integration method"),
    "simulate-max-steps-radau": Case("simulate hydraulic --friction coulomb --input "
                                     "sine:amplitude=4.5e-3,frequency=1 --duration 0.1 "
                                     "--method radau --max-steps 5 -o o.csv",
                                     match="--max-steps = "),
    "simulate-max-steps-bdf": Case("simulate hydraulic --friction coulomb --input "
                                   "sine:amplitude=4.5e-3,frequency=1 --duration 0.1 "
                                   "--method bdf --max-steps 5 -o o.csv", match="--max-steps = "),
    "simulate-max-steps-lsoda": Case("simulate hydraulic --friction coulomb --input "
                                     "sine:amplitude=4.5e-3,frequency=1 --duration 0.1 "
                                     "--method lsoda --max-steps 5 -o o.csv", match="--max-steps = "),
    "simulate-coupling-runaway": Case("simulate hydraulic --friction nmlgm-hysteresis "
                                      "--coupling 1e-9 --input sine:amplitude=4.5e-3,frequency=1 "
                                      "--duration 0.5 --rate 100 -o o.csv",
                                      match="coupling intervals"),
    "simulate-coupling-steps": Case("simulate hydraulic --friction nmlgm-hysteresis --coupling "
                                    "1e-4 --max-steps 50 --input "
                                    "sine:amplitude=4.5e-3,frequency=1 --duration 0.5 --rate 100 "
                                    "-o o.csv", match="--max-steps = "),
    "simulate-coupling-zero": Case("simulate hydraulic --friction nmlgm-hysteresis --coupling 0 "
                                   "--input step:amplitude=0 --duration 0.01 -o o.csv",
                                   match="coupling"),
    "simulate-coupling-symbolic": Case("simulate hydraulic --friction lugre --coupling 1e-4 "
                                       "--input step:amplitude=0 --duration 0.01 -o o.csv",
                                       match="coupling"),
    "simulate-engine-on-motion": Case(f"{SIM} --rtol 1e-6 -o o.csv", match="ODE plants"),
    # ---- initial state ----
    "x0-negative-pressure": Case("simulate hydraulic --friction coulomb --input step:amplitude=0 "
                                 "--duration 0.01 --x0 p1=-5 -o o.csv", match="absolute"),
    "x0-negative-pressure-pneumatic": Case("simulate pneumatic --friction coulomb --input "
                                           "step:amplitude=0 --duration 0.01 --x0 p2=-1e5 "
                                           "-o o.csv", match="absolute"),
    "simulate-valve-gain-zero": Case("simulate hydraulic --friction coulomb --input "
                                     "step:amplitude=1 --duration 0.01 --set kv=0 -o w.csv",
                                     code=0, outputs=("w.csv", "w.toml")),
    "x0-outside-stroke": Case("simulate hydraulic --friction coulomb --input step:amplitude=0 "
                              "--duration 0.01 --x0 x=100 -o o.csv", match="within its stroke"),
    "simulate-runaway-motion": Case("simulate motion --friction coulomb --input "
                                    "step:amplitude=1e6 --duration 0.1 -o o.csv",
                                    match="the simulated piston left its plausible range"),
    "fix-comma-list": Case(f"{FIT} --fix Fc=1,B=2", match="one NAME=VALUE per --fix"),
    "x0-unknown-state": Case("simulate hydraulic --friction coulomb --input step:amplitude=0 "
                             "--duration 0.01 --x0 q=1 -o o.csv", match="unknown state"),
    "x0-inf": Case("simulate hydraulic --friction coulomb --input step:amplitude=0 "
                   "--duration 0.01 --x0 x=inf -o o.csv", match="finite"),
    "x0-twice": Case("simulate hydraulic --friction coulomb --input step:amplitude=0 "
                     "--duration 0.01 --x0 x=0.1 --x0 x=0.2 -o o.csv", match="given twice"),
    "x0-text": Case("simulate hydraulic --friction coulomb --input step:amplitude=0 "
                    "--duration 0.01 --x0 x=mid -o o.csv", match="not a number"),
    # ---- input specs ----
    "input-duplicate-key": Case(f"{SIM_NO_INPUT} --input sine:amplitude=1,amplitude=2,"
                                "frequency=1 -o o.csv", match="given twice"),
    "input-no-colon": Case(f"{SIM_NO_INPUT} --input sine -o o.csv", match="expected KIND"),
    "input-unknown-kind": Case(f"{SIM_NO_INPUT} --input ramp:slope=1 -o o.csv",
                               match="unknown input kind"),
    "input-unknown-key": Case(f"{SIM_NO_INPUT} --input sine:amplitude=1,freq=1 -o o.csv",
                              match="unknown key"),
    "input-missing-key": Case(f"{SIM_NO_INPUT} --input sine:amplitude=1 -o o.csv",
                              match="missing frequency"),
    "input-not-number": Case(f"{SIM_NO_INPUT} --input step:amplitude=big -o o.csv",
                             match="not a number"),
    "input-inf": Case(f"{SIM_NO_INPUT} --input step:amplitude=inf -o o.csv", match="finite"),
    "input-huge": Case(f"{SIM_NO_INPUT} --input step:amplitude=1e300 -o o.csv",
                       match="plausible"),
    "input-negative-frequency": Case(f"{SIM_NO_INPUT} --input sine:amplitude=1,frequency=-1 "
                                     "-o o.csv", match=">= 0"),
    "input-no-key-value": Case(f"{SIM_NO_INPUT} --input sine:amplitude -o o.csv",
                               match="key=value"),
    "input-csv-missing": Case(f"{SIM_NO_INPUT} --input csv:nope.csv -o o.csv",
                              match="not found"),
    "input-csv-dir": Case(f"{SIM_NO_INPUT} --input csv:data_dir -o o.csv", match="folder"),
    "input-csv-empty-name": Case(f"{SIM_NO_INPUT} --input csv: -o o.csv", match="no input file"),
    "input-csv-empty": Case(f"{SIM_NO_INPUT} --input csv:empty.csv -o o.csv",
                            match="file is empty"),
    "input-csv-header-only": Case(f"{SIM_NO_INPUT} --input csv:u_header.csv -o o.csv",
                                  match="no data rows after the header"),
    "input-csv-wrong-columns": Case(f"{SIM_NO_INPUT} --input csv:header_only.csv -o o.csv",
                                    match="columns t,u"),
    "input-csv-nan": Case(f"{SIM_NO_INPUT} --input csv:u_nan.csv -o o.csv",
                          match="column 'u' has a non-finite value (nan) at row 3"),
    "input-csv-time-backwards": Case(f"{SIM_NO_INPUT} --input csv:u_back.csv -o o.csv",
                                     match="not strictly increasing at row 3"),
    "input-csv-no-u": Case(f"{SIM_NO_INPUT} --input csv:no_t.csv -o o.csv", match="t,u"),
    "input-csv-one-row": Case(f"{SIM_NO_INPUT} --input csv:u_one.csv -o o.csv",
                              match="at least two samples"),
    "input-csv-binary": Case(f"{SIM_NO_INPUT} --input csv:binary.csv -o o.csv",
                             match="binary"),
    # ---- measurement files ----
    "read-empty-name": Case("fit '' --friction coulomb", match="no measurement file given"),
    "read-dot": Case("fit . --friction coulomb", match=".: is a folder"),
    "read-dir": Case("fit data_dir --friction coulomb", match="data_dir: is a folder"),
    "read-missing": Case("fit nope.csv --friction coulomb", match="nope.csv: file not found"),
    "read-missing-no-suffix": Case("fit nope --friction coulomb", match="nope: file not found"),
    "read-sidecar-given": Case("fit good.toml --friction coulomb", match="is a sidecar"),
    "read-empty": Case("fit empty.csv --friction coulomb", match="file is empty"),
    "read-blank-only": Case("fit blank_only.csv --friction coulomb", match="file is empty"),
    "read-header-only": Case("fit header_only.csv --friction coulomb", match="no data rows"),
    "read-one-row": Case("fit one_row.csv --friction coulomb", match="at least two samples"),
    "read-text-line-12": Case("fit text12.csv --friction coulomb",
                              match="row 12, column 'x': 'abc' is not a number"),
    "read-nan-line-12": Case("fit nan12.csv --friction coulomb",
                             match="column 'x' has a non-finite value (nan) at row 12"),
    "read-inf-line-12": Case("fit inf12.csv --friction coulomb", match="(inf) at row 12"),
    "read-empty-cell": Case("fit empty_cell.csv --friction coulomb",
                            match="row 7, column 'v': the value is missing"),
    "read-nan-after-blank-lines": Case("fit gap_nan.csv --friction coulomb", match="at row 14"),
    "read-1e300": Case("fit huge.csv --friction coulomb",
                       match="column 'F' has 1e+300 at row 9, beyond any plausible value"),
    "read-time-in-ns": Case("fit ns_time.csv --friction coulomb", match="column 't' has 1.7e+18"),
    "read-ragged": Case("fit ragged.csv --friction coulomb", match="row 5 has 6 values"),
    "read-semicolon": Case("fit semicolon.csv --friction coulomb", match="semicolons"),
    "read-tabs": Case("fit tabs.csv --friction coulomb", match="tabs"),
    "read-decimal-comma": Case("fit decimal_comma.csv --friction coulomb", match="semicolons"),
    "read-duplicate-columns": Case("fit dupcol.csv --friction coulomb", match="'x' twice"),
    "read-empty-column-name": Case("fit emptycol.csv --friction coulomb", match="one is empty"),
    "read-no-time": Case("fit no_t.csv --friction coulomb", match="column 't'"),
    "read-time-backwards": Case("fit t_back.csv --friction coulomb",
                                match="not strictly increasing at row 4"),
    "read-time-repeated": Case("fit t_repeat.csv --friction coulomb",
                               match="not strictly increasing at row 4"),
    "read-x-in-mm": Case("fit x_mm.csv --friction coulomb", match="not millimetres"),
    "read-p-in-bar": Case("fit p_bar.csv --friction coulomb", match="bar"),
    "read-latin1": Case("fit latin1.csv --friction coulomb", match="not UTF-8"),
    "read-binary": Case("fit binary.csv --friction coulomb", match="binary"),
    "read-mat-as-csv": Case("fit good.mat --friction coulomb", match="binary"),
    "sidecar-unknown-kind": Case("fit kind.csv --friction coulomb",
                                 match="kind = 'pneumatic_cylinder' is not one of"),
    "sidecar-orientation": Case("fit orient.csv --friction coulomb", match="got 'sideways'"),
    "sidecar-bore-mm": Case("fit bore_mm.csv --friction coulomb", match="25.0 m is implausible"),
    "sidecar-rod-over-bore": Case("fit rod_big.csv --friction coulomb", match="smaller than"),
    "sidecar-mass-negative": Case("fit mass_neg.csv --friction coulomb", match="got -1.0"),
    "sidecar-mass-text": Case("fit mass_text.csv --friction coulomb", match="got 'heavy'"),
    "sidecar-pressure": Case("fit psi.csv --friction coulomb", match="got 'psi'"),
    "sidecar-u-unit": Case("fit unit.csv --friction coulomb", match="got 'mA'"),
    "sidecar-invalid-toml": Case("fit badtoml.csv --friction coulomb", match="not valid TOML"),
    "sidecar-binary": Case("fit bintoml.csv --friction coulomb", match="binary"),
    "sidecar-rig-not-table": Case("fit rigtable.csv --friction coulomb", match="must be a table"),
    "sidecar-mass-inf": Case("fit mass_inf.csv --friction coulomb", match="got inf"),
    "sidecar-mass-huge": Case("fit mass_huge.csv --friction coulomb",
                              match="rig.mass = 1e+308 kg is implausible"),
    "sidecar-name-number": Case("fit name_num.csv --friction coulomb", match="name = 5 must be text"),
    "sidecar-column-name-as-key": Case("fit exp_key.csv --friction coulomb-viscous --json ek.json",
                                       code=0, outputs=("ek.json",), warnings=("unknown-key",)),
    "sidecar-rig-key-at-top": Case("fit top_mass.csv --friction coulomb-viscous --json tm.json",
                                   code=0, outputs=("tm.json",), warnings=("unknown-key",)),
    "import-csv-sidecar-rod-ge-bore": Case(
        "import csv good.csv --map t=t,x=x,v=v,a=a,F=F --sidecar rod_big.toml -o i.csv",
        match="rod_big.toml: sidecar rig.rod (0.03 m) must be smaller"),
    "import-csv-map-number-overflows": Case(
        "import csv good.csv --map t=t,x=x,v=v,a=a,F=F*1e400 -o i.csv",
        match="the number 1e400 in the mapping is not a finite number"),
    "compare-params-huge-values": Case("compare good.csv --friction coulomb-viscous "
                                       "--params huge_fit.json", match="B = 1e+308"),
    # stamps 1e-300 s apart ended in an OverflowError inside the conditioning
    "read-tiny-time-steps-compare": Case("compare tiny_steps.csv --friction coulomb",
                                         match="shorter than 1e-09 s: no rig logs that fast"),
    "read-tiny-time-steps-diagnose": Case("diagnose tiny_steps.csv --friction coulomb",
                                          match="shorter than 1e-09 s"),
    "read-tiny-time-steps-fit": Case("fit tiny_steps.csv --friction coulomb",
                                     match="check that column 't' is in seconds"),
    "read-digit-separator": Case("compare underscore.csv --friction coulomb",
                                 match="row 3, column 'x': '1_000' is not a number (digit "
                                       "separators are not read"),
    "sweep-negative-seed": Case("sweep --seed -1", match="--seed must be a non-negative integer"),
    "sidecar-p-atm-in-bar": Case("fit patm_bar.csv --friction coulomb",
                                 match="p_atm = 1.013 is not an atmospheric pressure in Pa"),
    "warn-sidecar-typo": Case("fit typo.csv --friction coulomb-viscous --json typo.json", code=0,
                              outputs=("typo.json",), warnings=("unknown-key",)),
    "sidecar-absolute-negative": Case("fit absneg.csv --friction coulomb",
                                      match="negative absolute pressure"),
    # ---- valid after all ----
    "read-bom": Case("fit bom.csv --friction coulomb-viscous --json bom.json", code=0,
                     outputs=("bom.json",)),
    "read-quoted-header": Case("fit quoted.csv --friction coulomb-viscous", code=0),
    "read-crlf": Case("fit crlf.csv --friction coulomb-viscous", code=0),
    "read-comments-blank-lines": Case("fit comments.csv --friction coulomb-viscous", code=0),
    "read-spaces-in-header": Case("fit spaces.csv --friction coulomb-viscous", code=0),
    "read-utf16": Case("fit utf16.csv --friction coulomb-viscous", code=0),
    "read-no-suffix": Case("fit good --friction coulomb-viscous", code=0),
    "fit-json-replaces-old-result": Case(f"{FIT} --json old.json", code=0, outputs=("old.json",)),
    "fit-json-to-dev-null": Case(f"{FIT} --json /dev/null", code=0),
    "fit-json-through-a-link": Case(f"{FIT} --json lk.json", code=0,
                                    outputs=("lk_target.json",)),
    "simulate-replaces-old-result": Case(f"{SIM} -o sim.csv", code=0,
                                         outputs=("sim.csv", "sim.toml")),
    # ---- diagnose ----
    "diagnose-same-file-twice": Case("diagnose good.csv good.csv --friction coulomb",
                                     match="given twice"),
    "diagnose-same-file-dotslash": Case("diagnose good.csv ./good.csv --friction coulomb",
                                        match="given twice"),
    "diagnose-same-file-symlink": Case("diagnose good.csv link.csv --friction coulomb",
                                       match="given twice"),
    "diagnose-same-file-hardlink": Case("diagnose good.csv hard.csv --friction coulomb",
                                        match="given twice"),
    "diagnose-baseline-unknown": Case("diagnose good.csv --friction magic",
                                      match="unknown friction model"),
    "diagnose-add-unknown": Case(f"{DIAG} --add-effect magic", match="unknown effect"),
    "diagnose-candidates-empty": Case(f"{DIAG} --candidates ''", match="at least one"),
    "diagnose-candidates-commas": Case(f"{DIAG} --candidates ,", match="at least one"),
    "diagnose-candidates-twice": Case(f"{DIAG} --candidates viscous,viscous",
                                      match="given twice"),
    "diagnose-candidates-unknown": Case(f"{DIAG} --candidates magic", match="magic"),
    "diagnose-max-steps-negative": Case(f"{DIAG} --max-steps -1", match="non-negative"),
    "diagnose-jobs-zero": Case(f"{DIAG} --jobs 0", match="positive"),
    "diagnose-cutoff-negative": Case(f"{DIAG} --cutoff -1", match="positive"),
    "diagnose-cutoff-inf": Case(f"{DIAG} --cutoff inf", match="finite"),
    "diagnose-split-unknown": Case(f"{DIAG} --split random", match="invalid choice"),
    "diagnose-missing": Case("diagnose nope.csv --friction coulomb", match="not found"),
    "diagnose-empty-file": Case("diagnose good.csv empty.csv --friction coulomb",
                                match="empty.csv"),
    "diagnose-no-data": Case("diagnose --friction coulomb", match="required"),
    # ---- user code ----
    "effects-sys-exit-0": Case(f"{SIM} --effects eff_exit0.py -o o.csv",
                               match="eff_exit0.py line 2: importing the effects module failed: "
                               "it called sys.exit(0)"),
    "effects-sys-exit-msg": Case(f"{SIM} --effects eff_exitmsg.py -o o.csv",
                                 match="eff_exitmsg.py line 3"),
    "effects-raise-at-import": Case(f"{FIT} --effects eff_raise.py",
                                    match="eff_raise.py line 3: importing the effects module "
                                    "failed: RuntimeError: boom"),
    "effects-syntax-error": Case(f"{FIT} --effects eff_syntax.py",
                                 match="eff_syntax.py line 1: the effects module has a syntax"),
    # a NUL byte has no line: the file is named alone (it said "line None")
    "effects-nul-byte": Case(f"{FIT} --effects eff_nul.py",
                             match="eff_nul.py: the effects module has a syntax error"),
    # a plugin raising KeyboardInterrupt itself is its error (exit 2, file and line), not Ctrl-C
    "effects-raises-keyboard-interrupt": Case(f"{FIT} --effects eff_ctrlc.py",
                                              match="eff_ctrlc.py line 1"),
    "effects-os-exit": Case(f"{FIT} --effects eff_osexit.py",
                            match="eff_osexit.py line 2: importing the effects module failed: "
                                  "it called os._exit(0)"),
    "effects-import-error": Case(f"{FIT} --effects eff_import.py",
                                 match="No module named 'no_such_package_xyz'"),
    "effects-duplicate-name": Case(f"{FIT} --effects eff_dup.py",
                                   match="'viscous' is already registered"),
    "effects-missing": Case(f"{FIT} --effects nope.py", match="effects module not found"),
    "effects-dir": Case(f"{FIT} --effects data_dir", match="is a folder"),
    "effects-not-py": Case(f"{FIT} --effects effects.txt", match="ending in .py"),
    "effects-empty-name": Case(f"{FIT} --effects ''", match="no file name"),
    "effects-extra-force-raises": Case(
        f"{SIM} --effects eff_zdiv.py --add-effect {E['zdiv']} -o o.csv",
        match=f"eff_zdiv.py line {BODY}, in extra_force: ZeroDivisionError: division by zero "
              "(an error in your --effects module, not in fcomp)"),
    "effects-extra-force-exits": Case(
        f"{SIM} --effects eff_exit.py --add-effect {E['exit']} -o o.csv",
        match=f"eff_exit.py line {BODY}, in extra_force: it called sys.exit(3)"),
    "effects-extra-force-name-error": Case(
        f"{FIT} --effects eff_name.py --add-effect {E['name']}",
        match=f"eff_name.py line {BODY}, in extra_force: NameError"),
    "effects-diagnose-raises": Case(
        f"{DIAG} --effects eff_zdiv.py --add-effect {E['zdiv']}", match=f"eff_zdiv.py line {BODY}"),
    "effects-ok": Case(f"{SIM} --effects eff_ok.py --add-effect {E['ok']} -o eo.csv", code=0,
                       outputs=("eo.csv", "eo.toml")),
    # ---- import ----
    "import-kind-unknown": Case("import magic z.csv -o o.csv", match="unknown import kind"),
    "import-src-missing": Case("import zillen nope.csv -o o.csv", match="not found"),
    "import-src-dir": Case("import zillen data_dir -o o.csv", match="is a folder"),
    "import-src-empty-name": Case("import zillen '' -o o.csv", match="no file name"),
    "import-zillen-empty": Case("import zillen z_empty.csv -o o.csv", match="no data rows"),
    "import-zillen-six-columns": Case("import zillen z_six.csv -o o.csv", match="7"),
    "import-zillen-nan": Case("import zillen z_nan.csv -o o.csv", match="at line 2, column 6"),
    "import-zillen-backwards": Case("import zillen z_back.csv -o o.csv",
                                    match="time goes backwards at line 3"),
    "import-zillen-text": Case("import zillen z_text.csv -o o.csv",
                               match="row 1, column 1: 'time' is not a number"),
    "import-zillen-binary": Case("import zillen good.mat -o o.csv", match="binary"),
    "import-zillen-bore-mm": Case("import zillen z.csv --bore 25 -o o.csv", match="metres"),
    "import-zillen-bore-zero": Case("import zillen z.csv --bore 0 -o o.csv", match="positive"),
    "import-zillen-bore-inf": Case("import zillen z.csv --bore inf -o o.csv", match="finite"),
    "import-zillen-wrong-option": Case("import zillen z.csv --position-scale 2 -o o.csv",
                                       match="do not apply"),
    "import-mataveid-empty": Case("import mataveid m_empty.csv -o o.csv", match="no data rows"),
    "import-mataveid-three": Case("import mataveid m_three.csv -o o.csv", match="4 columns"),
    "import-mataveid-scale-zero": Case("import mataveid m.csv --position-scale 0 -o o.csv",
                                       match="non-zero"),
    "import-mataveid-scale-nan": Case("import mataveid m.csv --position-scale nan -o o.csv",
                                      match="finite"),
    "import-mat-no-map": Case("import mat good.mat -o o.csv", match="--map"),
    "import-mat-bad-map": Case("import mat good.mat --map t -o o.csv", match="COLUMN=VARIABLE"),
    "import-mat-map-twice": Case("import mat good.mat --map t=time,t=time -o o.csv",
                                 match="mapped twice"),
    "import-mat-no-t": Case("import mat good.mat --map x=pos -o o.csv", match="'t'"),
    "import-mat-missing-var": Case("import mat good.mat --map t=time,x=nope -o o.csv",
                                   match="no variable 'nope'"),
    "import-mat-text-var": Case("import mat good.mat --map t=time,x=label -o o.csv",
                                match="label"),
    "import-mat-overflow": Case("import mat good.mat --map t=time,F_ext=big*big -o o.csv",
                                match="overflows"),
    "import-mat-huge": Case("import mat good.mat --map t=time,F_ext=big -o o.csv",
                            match="beyond any plausible value"),
    "import-mat-v73": Case("import mat fake73.mat --map t=time -o o.csv", match="v7.3"),
    "import-mat-junk": Case("import mat junk.mat --map t=time -o o.csv",
                            match="cannot read as a MATLAB .mat file"),
    "import-mat-sidecar-missing": Case("import mat good.mat --map t=time --sidecar nope.toml "
                                       "-o o.csv", match="not found"),
    "import-mat-sidecar-invalid": Case("import mat good.mat --map t=time --sidecar rig_bad.toml "
                                       "-o o.csv", match="not valid TOML"),
    "import-mat-sidecar-kind": Case("import mat good.mat --map t=time --sidecar rig_kind.toml "
                                    "-o o.csv", match="kind = 'wheel'"),
    "import-emps-wrong-file": Case("import emps z.csv -o o.csv", match="MATLAB"),
    "import-emps-no-options": Case("import emps good.mat --bore 0.02 -o o.csv",
                                   match="do not apply"),
    "import-mat-ok": Case("import mat good.mat --map t=time,x=pos,F_ext=gain*force --sidecar "
                          "rig.toml -o imported.csv", code=0,
                          outputs=("imported.csv", "imported.toml")),
    # ---- study, demo, list, the parser ----
    "study-unknown": Case("study magic --out s", match="unknown study"),
    "list-unknown": Case("list magic", match="invalid choice"),
    "no-command": Case("", match="required"),
    "unknown-command": Case("frobnicate", match="invalid choice"),
    "unknown-option": Case(f"{FIT} --colour red", match="unrecognized arguments"),
    # ---- warnings: suspicious but legal ----
    "warn-aliasing": Case("simulate motion --friction coulomb --input "
                          "sine:amplitude=0.01,frequency=1e12 --duration 0.5 --rate 100 -o w.csv",
                          code=0, outputs=("w.csv", "w.toml"), warnings=("aliasing",)),
    "warn-aliasing-csv": Case("simulate motion --friction coulomb --input csv:u_fine.csv "
                              "--duration 0.5 --rate 100 -o w.csv", code=0,
                              outputs=("w.csv", "w.toml"), warnings=("aliasing",)),
    "warn-saturation-pneumatic": Case("simulate pneumatic --friction coulomb --input "
                                      "step:amplitude=1e6 --duration 0.02 -o w.csv", code=0,
                                      outputs=("w.csv", "w.toml"),
                                      warnings=("command-saturation",)),
    "warn-saturation-presliding": Case("simulate presliding-rig --friction lugre --input "
                                       "step:amplitude=20 --duration 0.02 -o w.csv", code=0,
                                       outputs=("w.csv", "w.toml"),
                                       warnings=("command-saturation",)),
    "warn-cavitation": Case("simulate hydraulic --friction coulomb --input "
                            "sine:amplitude=0.04,frequency=5 --duration 0.3 -o w.csv", code=0,
                            outputs=("w.csv", "w.toml"), warnings=("cavitation",)),
    "warn-compile-cache-is-a-file": Case(
        "simulate hydraulic --friction dahl --input step:amplitude=0 --duration 0.01 -o w.csv",
        code=0, outputs=("w.csv", "w.toml"), warnings=("compile-cache",),
        env={"FCOMP_CACHE": "good.csv"}),
    "warn-import-repeated-times": Case("import zillen z_repeat.csv -o w.csv", code=0,
                                       outputs=("w.csv", "w.toml"), warnings=("rows-dropped",)),
    # ---- export (issue 42, items 6, 8, 10, 16) ----
    "export-onto-a-foreign-folder": Case("export pid -o mine", match="holds files fcomp did "
                                         "not write"),
    "export-compiler-without-output": Case(
        "export pid --duration 0.05 -o c --json c.json", code=0, outputs=(*EXPORT_FILES, "c"),
        warnings=("export",), env={"FCOMP_CC": "true"}),
    "export-timing-steps-huge": Case("export pid -o c --timing-steps 1000000000000",
                                     match="--timing-steps 1000000000000: time 100000 to"),
    # the model file itself refuses numbers beyond 1e15 (as the command line does), before
    # the export's own check of the force range (the next case)
    "export-friction-1e308": Case("export pid --friction lugre_1e308.json -o c",
                                  match="lugre_1e308.json: params.Fc = 1e+308 is beyond any "
                                        "plausible value"),
    "export-friction-beyond-the-force-range": Case(
        "export pid --friction lugre --set Fc=2e4 --set Fs=2e4 -o c",
        match="beyond the actuator's whole force range"),
    "export-mpc-rate-said": Case("export mpc --plant pneumatic --option horizon=3 --option "
                                 "qp_iterations=3 --duration 0.05 -o c --json c.json", code=0,
                                 outputs=(*EXPORT_FILES, "c"), warnings=("export",)),
}


@pytest.fixture(scope="module")
def repeat_file(lab: Path) -> None:
    rows = (lab / "z.csv").read_text().splitlines(keepends=True)
    (lab / "z_repeat.csv").write_text("".join(rows[:10] + rows[9:10] + rows[10:]))


@pytest.mark.parametrize("name", list(CASES))
def test_bad_input(name: str, lab: Path, repeat_file: None, capsys: pytest.CaptureFixture[str],
                   monkeypatch: pytest.MonkeyPatch) -> None:
    case = CASES[name]
    monkeypatch.chdir(lab)
    for k, v in case.env.items():
        monkeypatch.setenv(k, str(lab / v) if (lab / v).exists() else v)
    if "compile-cache" in case.warnings:  # a fresh process would warn: reset the once-only state
        import fcomp.compiled
        import fcomp.simulation

        monkeypatch.setattr(fcomp.compiled, "_WARNED", set())
        fcomp.simulation.clear_kernel_cache()
    old = {o: (lab / o).read_bytes() for o in case.outputs if (lab / o).is_file()}
    before = snapshot(lab)
    code, out, err = _run(shlex.split(case.args), capsys)
    after = snapshot(lab)
    try:
        assert "Traceback" not in err and "Traceback" not in out
        assert code == case.code, (code, err)
        lines = err.splitlines()
        if case.code != 0:
            assert len(lines) == 1, err
            assert "error: " in lines[0] and case.match in lines[0], lines[0]
            assert after == before, "the lab changed"
            return
        warned = [ln for ln in lines if ln.startswith("fcomp: warning: ")]
        assert len(warned) == len(lines), err
        for k, v in before.items():
            if k not in case.outputs:
                assert after.get(k) == v, f"{k} changed"
        assert set(after) - set(before) <= set(case.outputs), set(after) - set(before)
        for o in case.outputs:
            assert o in after and after[o] != old.get(o), f"{o} not written"
        recorded = _recorded_warnings(lab, case.outputs)
        assert sorted({w["code"] for w in recorded}) == sorted(case.warnings), recorded
        codes = [w["code"] for w in recorded]  # several of one code: one counted line
        assert len(warned) == len(set(codes)) + (len(set(codes)) < len(codes)), (warned, recorded)
    finally:  # restore the lab for the next case
        for o in case.outputs:  # files first, then the folders created for them
            if o in old:
                (lab / o).write_bytes(old[o])
            elif (lab / o).is_dir():
                (lab / o).rmdir()
            else:
                (lab / o).unlink(missing_ok=True)


def _recorded_warnings(lab: Path, outputs: tuple[str, ...]) -> list[dict]:
    found: list[dict] = []
    for o in outputs:
        p = lab / o
        if p.suffix == ".toml":
            found += tomllib.loads(p.read_text()).get("warnings", [])
        elif p.suffix == ".json":
            found += json.loads(p.read_text()).get("warnings", [])
    return found


# ------------------------------------------------------- interrupted runs
class _Study:
    """A tiny study that writes a figure, then fails or is interrupted on request."""

    def __init__(self, fail: BaseException | None = None, figure: str = "a") -> None:
        from studies.base import Study

        outer = self

        class Tiny(Study):
            name = "tiny-bad-input"
            title = "Tiny"
            summary = "a study for the bad-input tests"

            def build(self, out, config):  # type: ignore[no-untyped-def]
                fig, ax = out.subplots()
                ax.plot([0, 1], [0, 1])
                out.figure(fig, outer.figure, "a line")
                out.report.section("Result").paragraph("ok")
                if outer.fail is not None:
                    raise outer.fail
                return {"value": 1.0}

        self.study = Tiny()
        self.fail = fail
        self.figure = figure


@pytest.fixture
def tiny(monkeypatch: pytest.MonkeyPatch) -> _Study:
    from studies import STUDIES

    t = _Study()
    monkeypatch.setitem(STUDIES._items, t.study.name, t.study)
    return t


def test_study_interrupted_in_a_fresh_folder_leaves_nothing(
        lab: Path, tiny: _Study, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(lab)
    before = snapshot(lab)
    tiny.fail = KeyboardInterrupt()
    code, _, err = _run(["study", tiny.study.name, "--out", "fresh"], capsys)
    assert (code, err) == (130, "fcomp: interrupted\n")
    assert snapshot(lab) == before


def test_study_error_in_a_fresh_folder_leaves_no_empty_folder(
        lab: Path, tiny: _Study, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(lab)
    before = snapshot(lab)
    tiny.fail = RuntimeError("a bug")
    code, _, err = _run(["study", tiny.study.name, "--out", "new/deeper/fresh"], capsys)
    assert code == 1 and len(err.splitlines()) == 1 and "a bug" in err
    assert snapshot(lab) == before


def test_study_interrupted_over_a_complete_result_keeps_it_whole(
        lab: Path, tiny: _Study, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(lab)
    assert _run(["study", tiny.study.name, "--out", "done"], capsys)[0] == 0
    complete = snapshot(lab)
    assert {"done/summary.json", "done/report.html", "done/fig-a.png"} <= set(complete)
    tiny.fail, tiny.figure = KeyboardInterrupt(), "b"
    code, _, err = _run(["study", tiny.study.name, "--out", "done"], capsys)
    assert (code, err) == (130, "fcomp: interrupted\n")
    assert snapshot(lab) == complete
    tiny.fail = None  # a complete rerun replaces the folder whole: no figure of the old run
    assert _run(["study", tiny.study.name, "--out", "done"], capsys)[0] == 0
    names = {p.name for p in (lab / "done").iterdir()}
    assert "fig-b.png" in names and "fig-a.png" not in names
    # a folder holding earlier results (docs/seed001.md: one study, then all into the parent)
    assert _run(["study", tiny.study.name, "--out", "done2/one"], capsys)[0] == 0
    assert _run(["study", tiny.study.name, "--out", "done2"], capsys)[0] == 0
    assert not (lab / "done2" / "one").exists()
    shutil.rmtree(lab / "done")
    shutil.rmtree(lab / "done2")


def test_demo_interrupted_leaves_nothing(lab: Path, capsys: pytest.CaptureFixture[str],
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    import fcomp.demo

    def partial(out: Path, params: str) -> list[Path]:
        (Path(out) / "demo-coulomb.csv").write_text("t\n0\n")
        raise KeyboardInterrupt

    monkeypatch.chdir(lab)
    monkeypatch.setattr(fcomp.demo, "run_demo", partial)
    before = snapshot(lab)
    code, _, err = _run(["demo", "--out", "demo-out"], capsys)
    assert (code, err) == (130, "fcomp: interrupted\n")
    assert snapshot(lab) == before


def test_diagnose_report_failure_leaves_nothing(lab: Path, capsys: pytest.CaptureFixture[str],
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    import fcomp.diagnosis
    import fcomp.diagnosis.report

    monkeypatch.setattr(fcomp.diagnosis.Diagnosis, "fit", lambda self, data: self)
    monkeypatch.setattr(fcomp.diagnosis.Diagnosis, "to_dict", lambda self: {"baseline": "x"})
    monkeypatch.setattr(fcomp.diagnosis.Diagnosis, "model_file", lambda self, source=None: {})

    def half(diag: object, directory: Path, command: str | None = None) -> Path:
        (Path(directory) / "report.html").write_text("<html>half")
        raise fcomp.errors.FcompError("the report failed")

    import fcomp.errors

    monkeypatch.setattr(fcomp.diagnosis.report, "write_report", half)
    monkeypatch.chdir(lab)
    before = snapshot(lab)
    code, _, err = _run([*shlex.split(DIAG), "--report", "rep/sub", "--json", "d.json"], capsys)
    assert code == 2 and err == "fcomp: error: the report failed\n"
    assert snapshot(lab) == before


def test_measurement_write_interrupted_keeps_the_old_pair(
        lab: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    import fcomp.outputs

    calls = []

    def fsync(fd: int) -> None:
        calls.append(fd)
        if len(calls) == 2:  # the CSV is written, the sidecar is not yet
            raise KeyboardInterrupt

    monkeypatch.setattr(fcomp.outputs.os, "fsync", fsync)
    monkeypatch.chdir(lab)
    before = snapshot(lab)
    code, _, err = _run([*shlex.split(SIM), "-o", "sim.csv"], capsys)
    assert (code, err) == (130, "fcomp: interrupted\n")
    assert snapshot(lab) == before


def test_unwritable_folder_names_the_output_not_its_temporary(
        lab: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """A read-only output folder (simulated: root writes anywhere) is reported with the file
    asked for, never the hidden temporary name fcomp writes first -- and before any work
    (issue 42: it was found only after the whole run)."""
    import fcomp.outputs

    def mkstemp(prefix: str = "", suffix: str = "", dir: str | None = None) -> tuple[int, str]:
        name = os.path.join(dir or ".", f"{prefix}abc123{suffix}")
        raise PermissionError(13, "Permission denied", name)

    monkeypatch.setattr(fcomp.outputs.tempfile, "mkstemp", mkstemp)
    monkeypatch.chdir(lab)
    before = snapshot(lab)
    code, _, err = _run([*shlex.split(FIT), "--json", "ro.json"], capsys)
    assert code == 2
    assert err == ("fcomp: error: --json ro.json: cannot write into the current folder "
                   "(Permission denied); choose another place (nothing was done)\n")
    assert snapshot(lab) == before


# ------------------------------------------------- real processes, no traceback
SUBPROCESS = ["fit-json-onto-sidecar", "read-empty", "input-csv-empty", "import-zillen-empty",
              "import-mataveid-empty", "set-fs-fc-inf", "read-1e300", "effects-sys-exit-0",
              "effects-extra-force-raises", "read-bom", "simulate-coupling-runaway"]


def _proc(args: list[str], cwd: Path, **kw: object) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "fcomp.cli.main", *args], cwd=cwd,
                            env=env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, **kw)  # type: ignore[call-overload]


@pytest.mark.slow
def test_real_processes_print_one_line_and_no_traceback(lab: Path, repeat_file: None) -> None:
    before = snapshot(lab)
    procs = {n: _proc(shlex.split(CASES[n].args), lab) for n in SUBPROCESS}
    for name, proc in procs.items():
        out, err = proc.communicate(timeout=120)
        case = CASES[name]
        assert "Traceback" not in err and "Warning" not in err, (name, err)
        assert proc.returncode == case.code, (name, err)
        if case.code:
            assert err.count("\n") == 1 and case.match in err, (name, err)
        else:
            assert err == "", (name, err)
    for o in ("bom.json",):
        (lab / o).unlink()
    assert snapshot(lab) == before


@pytest.mark.parametrize(("sig", "code", "line"), [(signal.SIGINT, 130, "fcomp: interrupted"),
                                                   (signal.SIGTERM, 143, "fcomp: terminated")])
@pytest.mark.slow
def test_long_run_shows_progress_and_a_signal_leaves_nothing(lab: Path, sig: int, code: int,
                                                             line: str) -> None:
    """A long simulation on a terminal shows its progress (erased at the end); Ctrl-C or
    SIGTERM stops it with one line and no output, no temporary left."""
    import pty
    import select

    before = snapshot(lab)
    master, slave = pty.openpty()
    proc = subprocess.Popen(
        [sys.executable, "-m", "fcomp.cli.main", "simulate", "hydraulic", "--friction",
         "nmlgm-hysteresis", "--input", "sine:amplitude=4.5e-3,frequency=1", "--duration",
         "200", "--rate", "200", "-o", "long.csv"],
        cwd=lab, env=env(), stdout=subprocess.PIPE, stderr=slave,
        # a suite started as a background job of a non-interactive shell inherits SIGINT
        # ignored (POSIX), and Python then keeps ignoring it: Ctrl-C at a terminal is not
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    os.close(slave)
    seen = b""
    start = time.monotonic()
    while b"%" not in seen and time.monotonic() - start < PATIENCE and proc.poll() is None:
        if select.select([master], [], [], 0.5)[0]:
            seen += os.read(master, 4096)
    assert b"simulate hydraulic:" in seen and b"% (t = " in seen, seen
    proc.send_signal(sig)
    proc.communicate(timeout=PATIENCE)
    seen += drain(master)
    os.close(master)
    assert proc.returncode == code
    assert seen.decode().rsplit("\x1b[K", 1)[-1].strip() == line, seen
    assert snapshot(lab) == before


def test_a_plugin_that_failed_to_load_is_not_run_again_in_workers(
        lab: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    """A module that raised ``KeyboardInterrupt`` while loading is forgotten like one that
    raised anything else: a later command's worker processes (and Dask workers) would run it
    again and die (it hung a Dask run in the test suite)."""
    from fcomp.usercode import user_sources

    monkeypatch.chdir(lab)
    assert main(shlex.split(f"{FIT} --effects eff_ctrlc.py")) == 2
    assert "eff_ctrlc.py line 1" in capsys.readouterr().err
    assert not [s for s in user_sources() if s[1].endswith("eff_ctrlc.py")]


@pytest.mark.slow
def test_ctrl_c_during_parallel_work_is_one_line(tmp_path: Path) -> None:
    """Ctrl-C sent to the whole process group, as a terminal sends it, while a diagnosis
    refits its candidates in worker processes: ``fcomp: interrupted``, exit 130, and not a
    line from the workers (each used to print its traceback: 126 lines); nothing written."""
    from fcomp.synthetic import generate

    generate(["pressure-dependence"], base="lugre", duration=20.0, seed=1
             ).measurement.write(tmp_path / "long.csv")
    before = snapshot(tmp_path)
    proc = subprocess.Popen(
        [sys.executable, "-m", "fcomp.cli.main", "diagnose", "long.csv", "--friction", "lugre",
         "--jobs", "2", "--no-progress", "--json", "d.json"],
        cwd=tmp_path, env=env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        start_new_session=True,  # a group of its own, as a terminal's foreground job
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    # the workers started (a condition, not a clock: on a loaded machine 8 s may not be
    # enough to have imported numpy)
    assert wait_for(lambda: len(children(proc.pid)) >= 2, proc), "no workers started"
    sent = time.monotonic()
    os.killpg(proc.pid, signal.SIGINT)
    out, err = finish(proc)
    print(f"stopped {time.monotonic() - sent:.1f} s after Ctrl-C")
    assert proc.returncode == 130, err.decode()
    assert err.decode().strip() == "fcomp: interrupted" and out == b""
    assert snapshot(tmp_path) == before


def _models_for_compensate(folder: Path) -> None:
    """``true.json`` (LuGre with a retracting side 1.5 times as strong) and ``base.json``."""
    from fcomp.models import make_model

    lugre = make_model("lugre", params="seed002-type1")
    lugre.with_effects("direction-asymmetry").with_params(r_neg=1.5).save(folder / "true.json")
    lugre.save(folder / "base.json")


#: Long commands, each stopped during its parallel work: (label, arguments, processes of
#: its group to wait for -- the work is under way once they exist). ``study all`` runs a
#: pool of studies whose workers run pools of their own.
LONG_COMMANDS = [
    ("study-all", ["study", "all", "--fast", "--out", "site"], 4),
    ("study-compensators", ["study", "compensators", "--fast", "--out", "comp"], 2),
    ("sweep", ["sweep", "--samples", "20", "--json", "sweep.json", "--report", "sweep"], 2),
    ("compensate", ["compensate", "--plant-params", str(ROOT / "docs" / "examples" /
                                                         "axis50.toml"),
                    "--friction", "true.json", "--controller-friction", "base.json,true.json",
                    "--samples", "10", "--json", "comp.json", "--report", "comp"], 2),
]


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc (Linux)")
@pytest.mark.parametrize(("sig", "code", "line"), [(signal.SIGINT, 130, "fcomp: interrupted"),
                                                   (signal.SIGTERM, 143, "fcomp: terminated")])
@pytest.mark.parametrize(("label", "args", "processes"), LONG_COMMANDS,
                         ids=[c[0] for c in LONG_COMMANDS])
@pytest.mark.slow
def test_a_signal_stops_a_long_command_at_once(tmp_path: Path, label: str, args: list[str],
                                               processes: int, sig: int, code: int,
                                               line: str) -> None:
    """Ctrl-C (SIGINT to the process group, as a terminal sends it) or SIGTERM (to the main
    process) during a command's parallel work -- sent once its workers exist, a condition
    rather than a clock, which a loaded machine reaches later: it ends with its one line and
    exit status, nothing on stdout, nothing written and no process of it left, long before
    its work could have finished (what was seen: ``study all`` never ended after Ctrl-C --
    its studies' own workers, left running, held its pipes -- and wrote into the removed
    staging folder). How fast it stops is printed, not asserted: a time bound tests the
    machine's load (benchmarks/hostile_cases.py measures it)."""
    _models_for_compensate(tmp_path)
    before = snapshot(tmp_path)
    proc = subprocess.Popen(
        [sys.executable, "-m", "fcomp.cli.main", *args], cwd=tmp_path, env=env(),
        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        start_new_session=True,  # a group of its own, as a terminal's foreground job
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert wait_for(lambda: len(group(proc.pid)) > processes, proc), \
        f"{label} ended before its workers started"
    sent = time.monotonic()
    send(proc, sig)
    try:
        out, err = finish(proc)
    finally:
        gone = group_gone(proc.pid)
    print(f"{label}: stopped {time.monotonic() - sent:.2f} s after {signal.Signals(sig).name}")
    assert proc.returncode == code, err.decode()
    assert err.decode() == line + "\n" and out == b""
    assert gone, f"{label} left processes running"
    assert snapshot(tmp_path) == before
    assert not wait_for(lambda: snapshot(tmp_path) != before, limit=0.5), \
        "a straggler wrote after the command ended"


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc (Linux)")
@pytest.mark.parametrize(("sig", "code", "line", "args", "marker"), [
    (signal.SIGINT, 130, "fcomp: interrupted",
     ["export", "mpc", "--option", "horizon=4", "--option", "qp_iterations=5"], "cc1"),
    (signal.SIGTERM, 143, "fcomp: terminated", ["export", "mpc"], "fcomp_ctrl_casadi.c"),
], ids=["ctrl-c-kernel-compile", "sigterm-export-compile"])
@pytest.mark.slow
def test_interrupting_export_ends_the_whole_compiler(tmp_path: Path, sig: int, code: int,
                                                     line: str, args: list[str],
                                                     marker: str) -> None:
    """Issue 42 item 4: Ctrl-C (to the process group, as a terminal sends it) while the
    controller's kernels compile, SIGTERM while the export's C compiles: the compiler runs
    in a process group of its own, ended whole -- no ``cc1`` left running (5 of 9 runs
    left one before) -- with the command's one line, exit status, and nothing written."""
    proc = start([*args, "-o", "c", "--no-progress"], tmp_path,
                 env=env(FCOMP_CACHE=str(tmp_path / "cache")))  # a fresh cache: compiles
    compilers: list[int] = []
    try:
        def compiling() -> bool:
            found = children(proc.pid)
            if any("cc1" in c and marker in c for c in map(cmdline, found)):
                compilers[:] = found
                return True
            return False

        assert wait_for(compiling, proc, limit=300), \
            f"no compiler ({marker}) seen before {args} ended"
        send(proc, sig)
        out, err = proc.communicate(timeout=60)
        # cc1 on the MPC's C alone runs for a minute: ended, it is gone at once
        wait_for(lambda: not alive(compilers), limit=2)
        left = alive(compilers)
    finally:
        for pid in alive(compilers):
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        if proc.poll() is None:
            proc.kill()
    assert not left, f"compiler processes left running: {left}"
    assert proc.returncode == code and err.decode() == line + "\n", err.decode()
    assert not (tmp_path / "c").exists()


def test_messages_show_plain_numbers() -> None:
    from fcomp.cli.main import plain

    assert plain("got np.float64(0.05), np.int64(3) and np.True_") == "got 0.05, 3 and True"


def test_case_count() -> None:
    """The closing note of issue 12 gives this count: table cases plus the tests above."""
    extra = 7 + len(SUBPROCESS) + 2 + 2
    assert len(CASES) + extra >= 150
    print(f"{len(CASES)} table cases + {extra} interrupt/process cases")


def test_a_result_with_non_finite_numbers_is_strict_json_with_nulls() -> None:
    """A failed run's NaN error or an infinite bound is written as null, never as the
    non-standard NaN/Infinity and never as a ValueError out of json.dumps."""
    import json as _json

    import numpy as np

    from fcomp.cli.common import result_text

    doc = {"rms_error": float("nan"), "runs": [{"max": np.float64(np.inf)}, (1.5, -np.inf)],
           "ok": 2.0}
    text = result_text(doc)
    assert "NaN" not in text and "Infinity" not in text
    assert _json.loads(text) == {"rms_error": None, "runs": [{"max": None}, [1.5, None]],
                                 "ok": 2.0}
