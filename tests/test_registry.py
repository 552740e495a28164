"""fcomp's registries of the packages above it: filled by providers found through entry points.

fcomp's face (``fcomp.api``, ``fcomp.cli``) reaches plants, controllers and
studies by name (:mod:`fcomp.registry`), never by import; a registry loads the
providers of its entry-point group on its first lookup, or, where nothing is
installed under the group, the modules of ``PROVIDERS``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path
from types import SimpleNamespace

import pytest

import fcomp.registry as registry
from fcomp.errors import UnknownNameError
from fcomp.registry import COMMANDS, CONTROLLERS, PLANT_TOOLS, PLANTS, STUDIES, Registry

ROOT = Path(__file__).resolve().parents[1]


def _provider(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, name: str, body: str) -> None:
    """A module ``name`` on the path whose import runs ``body``."""
    (tmp_path / f"{name}.py").write_text(body)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, name, raising=False)


def test_declared_entry_points_are_the_fallback_providers() -> None:
    """``pyproject.toml`` declares, group by group, the modules ``PROVIDERS`` imports."""
    with open(ROOT / "pyproject.toml", "rb") as fh:
        declared = tomllib.load(fh)["project"]["entry-points"]
    assert {group: tuple(points.values()) for group, points in declared.items()} \
        == registry.PROVIDERS


def test_the_packages_fill_the_registries() -> None:
    import controllers
    import plants
    import studies

    assert plants.PLANTS is PLANTS and controllers.CONTROLLERS is CONTROLLERS
    assert studies.STUDIES is STUDIES
    assert PLANTS.names() == ["force-rig", "hydraulic", "motion", "pneumatic", "presliding-rig"]
    assert CONTROLLERS.names() == ["ekf", "lugre-observer", "mpc", "pid", "pid-ff"]
    assert "missing-physics" in STUDIES
    assert PLANT_TOOLS.names() == ["PlantComparison", "compare_plant", "read_plant_file"]
    assert COMMANDS.names() == ["compensate", "export", "plant check", "plant template",
                                "simulate", "study", "sweep"]


def test_first_lookup_loads_the_fallback_providers(tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    reg: Registry[int] = Registry("gadget", group="tests.gadgets")
    _provider(tmp_path, monkeypatch, "gadget_provider",
              "import test_registry_target as t\nt.REG.register('one', 1)\n")
    monkeypatch.setitem(sys.modules, "test_registry_target", SimpleNamespace(REG=reg))
    monkeypatch.setitem(registry.PROVIDERS, "tests.gadgets",
                        ("gadget_provider", "absent_package.cli"))  # absent: skipped
    monkeypatch.setattr(registry, "entry_points", lambda group: [])
    assert reg.get("one") == 1 and reg.names() == ["one"]
    with pytest.raises(UnknownNameError, match="unknown gadget 'two'; known: one"):
        reg.get("two")


def test_installed_entry_points_win_over_the_fallback(tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    reg: Registry[int] = Registry("gadget", group="tests.gadgets")
    _provider(tmp_path, monkeypatch, "gadget_plugin",
              "import test_registry_target as t\nt.REG.register('plugin', 2)\n")
    monkeypatch.setitem(sys.modules, "test_registry_target", SimpleNamespace(REG=reg))
    monkeypatch.setitem(registry.PROVIDERS, "tests.gadgets", ("not_imported_at_all",))
    points = [SimpleNamespace(load=lambda: __import__("gadget_plugin"))]
    monkeypatch.setattr(registry, "entry_points",
                        lambda group: points if group == "tests.gadgets" else [])
    assert reg.names() == ["plugin"]


def test_a_failing_provider_is_retried(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A provider whose import fails leaves the registry unloaded: the next lookup tries again
    (and a missing dependency inside a provider is not taken for a package left out)."""
    reg: Registry[int] = Registry("gadget", group="tests.gadgets")
    _provider(tmp_path, monkeypatch, "gadget_broken", "import no_such_dependency_xyz\n")
    monkeypatch.setitem(registry.PROVIDERS, "tests.gadgets", ("gadget_broken",))
    monkeypatch.setattr(registry, "entry_points", lambda group: [])
    for _ in range(2):
        with pytest.raises(ModuleNotFoundError, match="no_such_dependency_xyz"):
            reg.names()


def test_the_command_line_options_import_no_package_above_fcomp() -> None:
    """``fcomp --help`` (every command's options) needs no plant, controller or study."""
    code = ("import sys\nfrom fcomp.cli.main import build_parser\nbuild_parser()\n"
            "print(sorted({m.split('.')[0] for m in sys.modules} "
            "& {'plants', 'controllers', 'studies'}))")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                         text=True, timeout=120, check=True).stdout
    assert out.strip() == "[]"
