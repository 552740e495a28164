"""One vocabulary (issue 27, items 1 and 6): the same option for the same idea on every
command, the old spellings working for one release with one warning line, the Python API
in the order data-then-friction, plain-text help, and ``fcomp list`` describing every name.
"""

from __future__ import annotations

import argparse
import io
import json
import pickle
import re
import warnings
from collections.abc import Iterator
from contextlib import redirect_stdout
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import fcomp
from fcomp.cli.main import build_parser, main
from fcomp.diagnosis import Diagnosis
from fcomp.measurement import Measurement
from fcomp.models import make_model
from fcomp.registry import COMMANDS
from fcomp.trajectory import friction_along_motion

WARNING = ("fcomp: warning: {old} is deprecated, use {new} (the old spelling will be removed "
           "in the next release)")


@pytest.fixture(scope="module")
def record(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short Coulomb-viscous record with a small offset and noise."""
    rng = np.random.default_rng(3)
    t = np.arange(2001) / 500.0
    v = 0.05 * np.sin(np.pi * t) + 0.02 * np.sin(2.6 * np.pi * t)
    a = 0.05 * np.pi * np.cos(np.pi * t) + 0.02 * 2.6 * np.pi * np.cos(2.6 * np.pi * t)
    model = make_model("coulomb-viscous").with_params(Fc=20.0, B=300.0)
    F = friction_along_motion(model, t, v, a=a).F + 0.5 + 0.05 * rng.standard_normal(t.size)
    path = tmp_path_factory.mktemp("vocab") / "rec.csv"
    Measurement({"t": t, "v": v, "a": a, "F": F}, {"name": "rec"}).write(path)
    return path


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def _json(path: Path) -> dict[str, Any]:
    """A command's JSON without what names the command line itself (``source.command``)."""
    doc = json.loads(path.read_text())
    if isinstance(doc.get("model_file"), dict):
        doc["model_file"].pop("source", None)
    return doc


def _old_and_new(capsys: pytest.CaptureFixture[str], tmp_path: Path, old: list[str],
                 new: list[str], old_flag: str, new_flag: str) -> tuple[dict, dict]:
    """Run ``old`` and ``new`` (each writing ``--json``); the old prints the one warning
    line, the new none; both JSON results."""
    a, b = tmp_path / "old.json", tmp_path / "new.json"
    code, _, err = _run([*old, "--json", str(a)], capsys)
    assert code == 0, err
    lines = [x for x in err.splitlines() if "deprecated" in x]
    assert lines == [WARNING.format(old=old_flag, new=new_flag)]
    code, _, err = _run([*new, "--json", str(b)], capsys)
    assert code == 0, err
    assert "deprecated" not in err
    return _json(a), _json(b)


# ------------------------------------------------------------- deprecated spellings
def test_fit_model_is_friction(record: Path, tmp_path: Path,
                               capsys: pytest.CaptureFixture[str]) -> None:
    old, new = _old_and_new(capsys, tmp_path,
                            ["fit", str(record), "--model", "coulomb-viscous", "--offset"],
                            ["fit", str(record), "--friction", "coulomb-viscous", "--offset"],
                            "--model", "--friction")
    assert old["params"] == new["params"] and old["rms"] == new["rms"]


def test_compare_model_is_friction(record: Path, tmp_path: Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    old, new = _old_and_new(capsys, tmp_path,
                            ["compare", str(record), "--model", "coulomb-viscous", "--set",
                             "Fc=20", "--set", "B=300"],
                            ["compare", str(record), "--friction", "coulomb-viscous", "--set",
                             "Fc=20", "--set", "B=300"], "--model", "--friction")
    assert old == new


def test_diagnose_baseline_is_friction(record: Path, tmp_path: Path,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    common = ["--no-search", "--no-baseline-check", "--no-progress", "--jobs", "1"]
    old, new = _old_and_new(capsys, tmp_path,
                            ["diagnose", str(record), "--baseline", "coulomb-viscous", *common],
                            ["diagnose", str(record), "--friction", "coulomb-viscous", *common],
                            "--baseline", "--friction")
    assert old == new


def test_diagnose_add_is_add_effect(record: Path, tmp_path: Path,
                                    capsys: pytest.CaptureFixture[str]) -> None:
    common = ["--friction", "coulomb-viscous", "--no-search", "--no-baseline-check",
              "--no-progress", "--jobs", "1"]
    old, new = _old_and_new(capsys, tmp_path,
                            ["diagnose", str(record), *common, "--add", "force-offset"],
                            ["diagnose", str(record), *common, "--add-effect", "force-offset"],
                            "--add", "--add-effect")
    assert old == new and new["added"] == ["force-offset"]


@pytest.fixture
def recorded(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[argparse.Namespace]]:
    """The long commands (study, sweep, compensate) replaced by one that records the
    options it is given: what the old and the new spelling give the command."""
    seen: list[argparse.Namespace] = []
    COMMANDS.names()  # the providers registered first
    saved = dict(COMMANDS._items)
    for name in ("study", "sweep", "compensate"):
        COMMANDS.register(name, lambda args: seen.append(args) or 0, replace=True)
    yield seen
    COMMANDS._items.clear()
    COMMANDS._items.update(saved)


_OPTIONS = ("friction", "controller_friction", "jobs", "scheduler", "fast", "no_progress")


@pytest.mark.parametrize("old, new, rest", [
    ("--workers", "--jobs", ["study", "presliding", "{flag}", "3"]),
    ("--workers", "--jobs", ["sweep", "{flag}", "3"]),
    ("--workers", "--jobs", ["compensate", "--plant", "hydraulic", "--friction", "nmlgm",
                             "--controller-friction", "lugre,nmlgm", "{flag}", "3"]),
    ("--models", "--controller-friction", ["compensate", "--plant", "hydraulic", "--friction",
                                           "nmlgm", "{flag}", "lugre,nmlgm"]),
])
def test_long_commands_old_spellings(old: str, new: str, rest: list[str],
                                     recorded: list[argparse.Namespace],
                                     capsys: pytest.CaptureFixture[str]) -> None:
    """study/sweep/compensate receive the same options from the old spelling, with the one
    warning line."""
    code, _, err = _run([w.replace("{flag}", old) for w in rest], capsys)
    assert code == 0 and err.splitlines() == [WARNING.format(old=old, new=new)]
    code, _, err = _run([w.replace("{flag}", new) for w in rest], capsys)
    assert code == 0 and err == ""
    first, second = ({k: getattr(a, k, None) for k in _OPTIONS} for a in recorded)
    assert first == second
    assert (first["jobs"] == 3) if new == "--jobs" else \
        first["controller_friction"] == "lugre,nmlgm"


@pytest.mark.parametrize("argv", [
    ["fit", "R.csv", "--model", "lugre", "--friction", "lugre"],
    ["fit", "R.csv", "--friction", "lugre", "--model", "lugre"],
    ["diagnose", "R.csv", "--friction", "lugre", "--baseline", "lugre"],
    ["diagnose", "R.csv", "--friction", "lugre", "--add", "stribeck", "--add-effect", "dwell-time"],
    ["sweep", "--jobs", "2", "--workers", "2"],
    ["compensate", "--friction", "nmlgm", "--models", "a", "--controller-friction", "b"],
])
def test_old_and_new_spelling_together_is_one_error(argv: list[str],
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert exc.value.code == 2 and len(err) == 1
    assert "same option" in err[0] and "deprecated" in err[0]


def _help(argv: list[str]) -> str:
    out = io.StringIO()
    with redirect_stdout(out), pytest.raises(SystemExit):
        main([*argv, "--help"])
    return out.getvalue()


def test_help_shows_only_the_canonical_spellings() -> None:
    for argv, gone in ((["fit"], "--model"), (["compare"], "--model"),
                       (["diagnose"], "--baseline "), (["diagnose"], "--add "),
                       (["study"], "--workers"), (["sweep"], "--workers"),
                       (["compensate"], "--models"), (["compensate"], "--workers")):
        text = _help(argv)
        assert gone not in text, (argv, gone)


# ---------------------------------------------------------- the same idea, one option
def test_every_command_speaks_the_same_words() -> None:
    """--friction, --jobs/--scheduler, --no-progress, --fast/--full, --params and --set
    where the table of docs/cli.md puts them, --set worded alike."""
    from fcomp.cli.common import SET_HELP

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    opts = {name: {s: a for a in p._actions for s in a.option_strings}
            for name, p in sub.choices.items()}
    for cmd in ("simulate", "fit", "compare", "diagnose", "sweep", "study", "export",
                "compensate"):
        assert "--friction" in opts[cmd], cmd
    for cmd in ("fit", "diagnose", "sweep", "study", "compensate", "compare"):
        assert "--jobs" in opts[cmd] and "--scheduler" in opts[cmd], cmd
    for cmd in ("simulate", "fit", "compare", "diagnose", "sweep", "study", "compensate",
                "export", "demo"):
        assert "--no-progress" in opts[cmd], cmd
    for cmd in ("study", "sweep", "compensate"):
        assert "--fast" in opts[cmd] and "--full" in opts[cmd], cmd
    for cmd in ("simulate", "fit", "compare", "export"):
        assert opts[cmd]["--params"].metavar == "SET|FIT.json|MODEL.json", cmd
    for cmd in ("simulate", "fit", "compare", "export"):
        assert opts[cmd]["--set"].help == SET_HELP, cmd
    for cmd in ("simulate", "fit", "compare", "diagnose", "export"):
        assert "--add-effect" in opts[cmd], cmd


@pytest.mark.parametrize("cmd, default", [("study", False), ("sweep", True),
                                          ("compensate", False)])
def test_fast_and_full_are_one_exclusive_pair(cmd: str, default: bool,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    """Each command keeps its default, says it in the help, and refuses both at once."""
    parser = build_parser()
    need = {"study": ["presliding"], "sweep": [],
            "compensate": ["--friction", "nmlgm", "--controller-friction", "lugre"]}[cmd]
    assert parser.parse_args([cmd, *need]).fast is default
    assert parser.parse_args([cmd, *need, "--fast"]).fast is True
    assert parser.parse_args([cmd, *need, "--full"]).fast is False
    assert re.search(rf"--{'fast' if default else 'full'}\s+.*\(default\)", _help([cmd]))
    with pytest.raises(SystemExit) as exc:
        parser.parse_args([cmd, *need, "--fast", "--full"])
    assert exc.value.code == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_params_takes_a_fit_json_and_a_model_file(record: Path, tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """--params FIT.json|MODEL.json: compare gives the same as with the model file itself;
    fit starts from those values; simulate runs with them."""
    fit_json, model_json = tmp_path / "fit.json", tmp_path / "model.json"
    assert main(["fit", str(record), "--friction", "coulomb-viscous", "--json", str(fit_json),
                 "--save-model", str(model_json)]) == 0
    capsys.readouterr()
    docs = []
    for extra in (["--friction", str(model_json)],
                  ["--friction", "coulomb-viscous", "--params", str(model_json)]):
        out = tmp_path / f"cmp{len(docs)}.json"
        assert main(["compare", str(record), *extra, "--json", str(out)]) == 0, \
            capsys.readouterr().err
        docs.append(json.loads(out.read_text()))
    assert docs[0]["rms"] == docs[1]["rms"]
    fitted = json.loads(fit_json.read_text())["params"]
    out = tmp_path / "refit.json"
    assert main(["fit", str(record), "--friction", "coulomb-viscous", "--params",
                 str(fit_json), "--json", str(out)]) == 0
    refit = json.loads(out.read_text())["params"]
    assert refit["Fc"] == pytest.approx(fitted["Fc"], rel=1e-6)
    sim = tmp_path / "sim.csv"
    assert main(["simulate", "motion", "--friction", "coulomb-viscous", "--params",
                 str(fit_json), "--input", "sine:amplitude=0.05,frequency=0.5",
                 "--duration", "1", "--rate", "200", "-o", str(sim)]) == 0
    F = Measurement.read(sim)["F"]
    assert np.max(np.abs(F)) == pytest.approx(fitted["Fc"] + fitted["B"] * 0.05, rel=0.05)
    capsys.readouterr()
    code, _, err = _run(["fit", str(record), "--friction", "lugre", "--params",
                         str(fit_json)], capsys)
    assert code == 2 and "not of lugre" in err and len(err.strip().splitlines()) == 1


def test_compare_runs_the_plant_replays_in_parallel_as_serially(tmp_path: Path) -> None:
    """compare --jobs: the plant-domain replays (one per record) in local processes give
    exactly the serial results."""
    true = make_model("lugre")
    runs = [fcomp.simulate("pneumatic", true, f"sine:amplitude=0.3,frequency={f}",
                           duration=1.5, rate=400.0) for f in (0.5, 0.8)]
    other = make_model("coulomb-viscous")
    serial = fcomp.compare(runs, other, plant="pneumatic", jobs=1)
    parallel = fcomp.compare(runs, other, plant="pneumatic", jobs=2)
    assert [p.rms for p in serial.plant] == [p.rms for p in parallel.plant]
    assert all(p.rms["x"] > 0 for p in serial.plant)


# ------------------------------------------------------------------ the Python API
def test_api_data_first_and_old_spellings_warn(record: Path) -> None:
    rec = Measurement.read(record)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        new = fcomp.fit(rec, "coulomb-viscous", offset=True)
        c_new = fcomp.compare(rec, new.model_)
    with pytest.warns(DeprecationWarning, match=r"fit\(friction=\.\.\.\)"):
        old = fcomp.fit(rec, model="coulomb-viscous", offset=True)
    assert old.params_ == new.params_
    with pytest.warns(DeprecationWarning, match=r"compare\(data, friction\)"):
        c_old = fcomp.compare(new.model_, rec)
    assert c_old.rms == c_new.rms
    with pytest.warns(DeprecationWarning, match=r"compare\(friction=\.\.\.\)"):
        assert fcomp.compare(rec, model=new.model_).rms == c_new.rms
    with pytest.warns(DeprecationWarning, match=r"compare\(data, friction\)"):
        assert fcomp.compare("coulomb-viscous", str(record)).rms == \
            fcomp.compare(str(record), "coulomb-viscous").rms
    with pytest.raises(TypeError, match="both"):
        fcomp.fit(rec, "coulomb-viscous", model="coulomb-viscous")


def test_api_diagnose_friction_and_candidates(record: Path) -> None:
    rec = Measurement.read(record)
    opts = {"search": True, "n_jobs": 1, "check_baseline": False, "max_steps": 1}
    new = fcomp.diagnose(rec, "coulomb-viscous", candidates=["force-offset"], **opts)
    with pytest.warns(DeprecationWarning, match=r"diagnose\(friction=\.\.\.\)"):
        old = fcomp.diagnose(rec, baseline="coulomb-viscous", candidates=["force-offset"],
                             **opts)
    assert old.added_ == new.added_ and old.rms_final_ == new.rms_final_
    with pytest.warns(DeprecationWarning, match=r"Diagnosis\(candidates=\.\.\.\)"):
        d = Diagnosis("coulomb-viscous", effects=["force-offset"])
    assert d.candidates == ["force-offset"]
    again = pickle.loads(pickle.dumps(d))
    assert again.candidates == ["force-offset"] and again.config.names == ["force-offset"]
    with pytest.raises(TypeError, match="both"):
        Diagnosis("lugre", candidates=["viscous"], effects=["viscous"])
    with pytest.raises(TypeError, match="unexpected"):
        Diagnosis("lugre", efects=["viscous"])


# ---------------------------------------------------------------- plain-text help
_REST = re.compile(r"``|:(?:class|func|meth|mod|data|attr|exc|obj|ref):`|`~|::\s*$|\{,,"
                   r"|(?<![\w*])\*[A-Za-z][^*\n]*\*(?![\w*])|`[^`\n]+`", re.M)


def _commands() -> list[list[str]]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    out: list[list[str]] = [[]]
    for name, p in sub.choices.items():
        out.append([name])
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                out += [[name, n] for n in a.choices]
    return out


def test_every_help_is_plain_text() -> None:
    cmds = _commands()
    assert ["plant", "template"] in cmds and ["plant", "check"] in cmds and len(cmds) > 12
    bad = []
    for argv in cmds:
        text = _help(argv)
        for m in _REST.finditer(text):
            line = text[:m.start()].count("\n")
            bad.append(f"fcomp {' '.join(argv)}: {text.splitlines()[line].strip()!r}")
    assert not bad, "\n".join(bad)


def test_plain_text_converts_rest() -> None:
    from fcomp.cli.common import plain_text

    assert plain_text("see :class:`~fcomp.diagnosis.Diagnosis` and ``--x`` *or* **y**. "
                      "Example::") == "see Diagnosis and --x or y. Example:"
    assert plain_text("a product (``*``), x='p [mm]'*1e-3") == "a product (*), x='p [mm]'*1e-3"


def test_import_delimiter_takes_words(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "log.csv"
    src.write_text("time;pos\n" + "".join(f"{k * 0.01:.2f};{k * 0.001:.3f}\n"
                                          for k in range(20)))
    outs = []
    for sep in ("semicolon", ";"):
        out = tmp_path / f"run{len(outs)}.csv"
        assert main(["import", "csv", str(src), "--map", "t=time,x=pos", "--delimiter", sep,
                     "-o", str(out)]) == 0
        outs.append(out.read_text())
    assert outs[0] == outs[1]
    with pytest.raises(SystemExit):
        main(["import", "csv", str(src), "--map", "t=time,x=pos", "--delimiter", "|", "-o",
              str(tmp_path / "x.csv")])
    err = capsys.readouterr().err
    assert "comma, semicolon or tab" in err and "{" not in err


# ----------------------------------------------------------------- fcomp list
def test_list_describes_every_name() -> None:
    from fcomp.cli.list_ import GROUPS, entries

    for group in GROUPS:
        items = entries(group)
        assert items, group
        for name, text in items:
            assert text.strip() and "\n" not in text, (group, name)
            assert "``" not in text and ":class:" not in text, (group, name)
    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["list", "plants"]) == 0
    assert re.search(r"^  hydraulic\s+\S", out.getvalue(), re.M)


def test_list_describes_a_user_model() -> None:
    from fcomp.cli.list_ import entries
    from fcomp.models import MODELS

    base = MODELS.get("coulomb")
    user = type("Mine", (base,), {"__doc__": "My own seal's friction, from ``bench 4``.\n\n"
                                  "More text."})
    MODELS.register("my-seal", user)
    assert dict(entries("models"))["my-seal"] == "My own seal's friction, from bench 4."


def test_docs_cli_lists_every_option_of_every_command() -> None:
    """docs/cli.md, "Every command's options": each command's section names each of its
    options by its canonical spelling, and no deprecated one."""
    text = (Path(__file__).resolve().parents[1] / "docs" / "cli.md").read_text()
    sections = dict(re.findall(r"^### fcomp ([a-z ]+)\n(.*?)(?=^### |\Z)", text, re.S | re.M))
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    missing = []
    for name, p in sub.choices.items():
        body = sections.get(name)
        assert body is not None, f"docs/cli.md has no section for fcomp {name}"
        for a in p._actions:
            old = getattr(a, "deprecated", ())
            for flag in a.option_strings:
                if flag in ("-h", "--help"):
                    continue
                if (flag in old) == bool(re.search(rf"[`\s]{re.escape(flag)}[ `,]", body)):
                    missing.append(f"{name} {flag}")
    assert not missing, "docs/cli.md out of step with the parsers: " + ", ".join(missing)


def test_bad_input_with_an_old_spelling_is_still_one_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The contract's one-line error holds for the old spellings too: the deprecation line
    comes only after a run that succeeded."""
    code, _, err = _run(["fit", str(tmp_path / "nope.csv"), "--model", "lugre"], capsys)
    assert code == 2
    assert err.splitlines() == [f"fcomp: error: {tmp_path / 'nope.csv'}: file not found"]
