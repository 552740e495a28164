"""Outputs found unwritable before the work, names that fit (issue 42, items 8 and 9):
a read-only folder was found only after the whole run (31 s); a legal 250-character output
name was refused because its temporary sibling's name is longer; a full disk said
``[Errno 28]`` without the file; ``plant template >&-`` was an AttributeError.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import processes
from helpers.cli_cases import Case, check_case, run_cli, snapshot
from helpers.hostile import runner, write_lab

from fcomp.errors import FcompError
from fcomp.outputs import check_writable, name_max, temporary_prefix, write_text

FIT = "fit rec.csv --friction coulomb-viscous"
COMP = runner().COMP


@pytest.fixture()
def lab(tmp_path: Path) -> Path:
    return write_lab(tmp_path / "lab")


@pytest.mark.parametrize(("command", "option", "target"), [
    (COMP, "--json", "ro/c.json"), (COMP, "--report", "ro/rep"),
    ("sweep --controllers pid --samples 2 --no-progress", "--json", "ro/s.json"),
    (FIT, "--save-model", "ro/m.json"), (FIT, "--json", "ro/f.json"),
    ("export pid --plant hydraulic --no-progress", "-o", "ro/ctrl"),
    ("study compensators --fast --no-progress", "--out", "ro/st"),
    ("simulate motion --friction coulomb --input step:amplitude=0.01 --duration 0.1", "-o",
     "ro/o.csv"),
])
def test_an_unwritable_folder_is_refused_before_the_work(
        lab: Path, command: str, option: str, target: str, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A folder where this process may not create files (read-only; simulated here by the
    probe's own call failing, since the tests may run as root, who writes anywhere): one line
    naming the output, and no work done -- the commands' work functions are never called."""
    import tempfile

    import fcomp.outputs

    real = tempfile.mkstemp

    def mkstemp(*args: object, **kwargs: object) -> tuple[int, str]:
        folder = Path(str(kwargs.get("dir") or "")).resolve()
        if folder == (lab / "ro").resolve():
            raise PermissionError(13, "Permission denied", str(folder))
        return real(*args, **kwargs)  # type: ignore[call-overload]

    monkeypatch.setattr(fcomp.outputs.tempfile, "mkstemp", mkstemp)
    work: list[str] = []
    import controllers.cli.export
    import controllers.harness
    import fcomp.identification
    import plants.base
    import plants.motion

    def mark(name: str) -> object:
        return lambda *a, **k: work.append(name)

    monkeypatch.setattr(controllers.harness, "run_closed_loop", mark("closed loop"))
    monkeypatch.setattr(controllers.cli.export, "export_controller", mark("export"))
    monkeypatch.setattr(fcomp.identification.FrictionFit, "fit", mark("fit"))
    monkeypatch.setattr(plants.base.OdePlant, "simulate", mark("simulate"))
    monkeypatch.setattr(plants.motion.MotionPlant, "simulate", mark("simulate motion"))
    err = check_case(lab, Case(f"{command} {option} {target}",
                               match=(f"{option} {target}", "Permission denied")),
                     capsys, monkeypatch)
    assert "nothing was done" in err
    assert not work, f"the work ran before the refusal: {work}"


def test_a_read_only_folder_for_real(tmp_path: Path) -> None:
    """The same, for real: when the tests run as root, the command runs without the
    capabilities that let root write anywhere (setpriv drops CAP_DAC_OVERRIDE and
    CAP_DAC_READ_SEARCH from the bounding set: the folder's mode bits then hold for it, and
    the interpreter and its packages -- perhaps under a home only root may enter -- stay
    readable)."""
    lab = write_lab(tmp_path / "lab")
    (lab / "ro").chmod(0o555)
    argv = [sys.executable, "-m", "fcomp.cli.main", *FIT.split(), "--json", "ro/f.json"]
    if os.geteuid() == 0:
        setpriv = shutil.which("setpriv")
        assert setpriv, "root without setpriv: cannot drop privileges to test a read-only folder"
        argv = [setpriv, "--bounding-set=-dac_override,-dac_read_search", "--", *argv]
    env = processes.env(HOME=str(tmp_path), FCOMP_CACHE=str(tmp_path / "cache"))
    before = snapshot(lab)
    proc = subprocess.run(argv, cwd=lab, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith("fcomp: error: --json ro/f.json: cannot write into the folder "
                                  "ro (Permission denied)"), proc.stderr
    assert proc.stderr.count("\n") == 1
    assert snapshot(lab) == before


def test_a_legal_long_name_is_written(tmp_path: Path) -> None:
    """A name of NAME_MAX bytes is legal: its hidden temporary sibling is cut to fit (item 9:
    refused, the temporary's name being longer than the file system takes)."""
    limit = name_max(tmp_path)
    for name in ("a" * (limit - 5) + ".json", "é" * ((limit - 5) // 2) + ".json"):
        path = tmp_path / name
        assert len(os.fsencode(path.name)) <= limit
        check_writable("--json", path)
        write_text(path, "{}\n")
        assert path.read_text() == "{}\n"
        prefix = temporary_prefix(path.name, tmp_path)
        assert len(os.fsencode(prefix)) + 8 + len(".tmp") <= limit
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


def test_an_overlong_name_is_refused_up_front(tmp_path: Path) -> None:
    """A name longer than the file system takes, or a folder to create on the way with one:
    one line before any work, saying so (not "File name too long" after the run)."""
    limit = name_max(tmp_path)
    for path in (tmp_path / ("b" * (limit + 1) + ".json"),
                 tmp_path / ("c" * (limit + 1)) / "out.json"):
        with pytest.raises(FcompError, match=f"more than the {limit} a file name may have"):
            check_writable("--json", path)


def test_save_model_with_a_250_character_name(lab: Path, capsys: pytest.CaptureFixture[str],
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    name = "m" * 245 + ".json"
    check_case(lab, Case(f"{FIT} --save-model {name}", code=0, outputs=(name,)), capsys,
               monkeypatch)
    assert (lab / name).is_file()
    check_case(lab, Case(f"{FIT} --save-model {'m' * 300}.json", match=("--save-model",
                                                                        "bytes long")),
               capsys, monkeypatch)


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (Linux)")
def test_a_full_disk_names_the_output(lab: Path, capsys: pytest.CaptureFixture[str],
                                      monkeypatch: pytest.MonkeyPatch) -> None:
    """``--json /dev/full`` (a device that is always full): the file is named with the reason
    (item 8: ``[Errno 28] No space left on device`` alone)."""
    err = check_case(lab, Case(f"{FIT} --json /dev/full", match=("/dev/full",
                                                                  "No space left on device")),
                     capsys, monkeypatch)
    assert "[Errno" not in err


def test_standard_output_closed_full_or_gone(tmp_path: Path) -> None:
    """``plant template hydraulic >&-`` was an AttributeError (item 5); ``> /dev/full`` said
    ``[Errno 28]``; a reader that stops (``| head``) ends the command quietly."""
    cmd = f"{sys.executable} -m fcomp.cli.main"
    env = processes.env()
    closed = subprocess.run(f"{cmd} plant template hydraulic >&-", shell=True, cwd=tmp_path,
                            env=env, capture_output=True, text=True, timeout=300)
    assert closed.returncode == 2
    assert closed.stderr == ("fcomp: error: standard output is closed: nowhere to write the "
                             "template; redirect it to a file (> FILE)\n")
    if Path("/dev/full").exists():
        full = subprocess.run(f"{cmd} plant template hydraulic > /dev/full", shell=True,
                              cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
        assert full.returncode == 2
        assert full.stderr == ("fcomp: error: standard output: cannot write the template (No "
                               "space left on device)\n")
    gone = subprocess.run(f"{cmd} list | head -c 1 > /dev/null; echo ${{PIPESTATUS[0]}}",
                          shell=True, executable="/bin/bash", cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert gone.stderr == "" and gone.stdout.strip() in ("0", "141"), gone


def test_the_json_result_to_a_closed_standard_output(tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str],
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    lab = write_lab(tmp_path / "lab")
    monkeypatch.chdir(lab)
    monkeypatch.setattr(sys, "stdout", None)
    code, _, err = run_cli([*FIT.split(), "--json", "-"], capsys)
    assert code == 2 and err.startswith("fcomp: error: standard output is closed")
