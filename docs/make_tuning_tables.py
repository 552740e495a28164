"""The tuning tables of docs/compensators.md ("Default tuning from the plant"), from the code.

Derives the default tuning (:mod:`controllers.tuning`, as ``fcomp plant check`` does:
the plant file with the ``nmlgm`` friction of its parameter set) on the built-in
``hydraulic`` and ``pneumatic`` plants and on ``docs/examples/axis40.toml`` and
``axis50.toml``, and computes the margins of the former fixed gains on the same loop as it
runs; writes both tables between their markers in docs/compensators.md, or with
``--check`` fails (exit 1) when the page differs from what the code gives::

    PYTHONPATH=. python3 docs/make_tuning_tables.py [--check]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "compensators.md"
PLANTS = ("hydraulic", "pneumatic", "docs/examples/axis40.toml", "docs/examples/axis50.toml")
#: The former fixed tuning by plant kind (force loop, PID bandwidth in rad/s; derivative
#: filter 60 Hz, observer 20 1/s, the inversion with the measured velocity).
FORMER = {"hydraulic": (150.0, 40.0), "pneumatic": (120.0, 30.0)}
MARKERS = ("derived", "former")


def plant_file(spec: str):  # noqa: ANN201 -- a PlantFile
    from plants.planfile import builtin_plant_file, read_plant_file

    return builtin_plant_file(spec) if spec in FORMER else read_plant_file(ROOT / spec)


def label(spec: str) -> str:
    return spec if spec in FORMER else Path(spec).name


def _m(m) -> str:  # noqa: ANN001 -- LoopMargins
    if not m.stable:
        return f"unstable ({m.mode_hz:.3g} Hz, growing {m.growth:.3g}/s)"
    return f"{m.gain:.2f} / {m.phase:.1f} / {m.ms:.2f}"


def tables() -> dict[str, str]:
    """``{"derived": markdown, "former": markdown}``."""
    from controllers.cli.plant_check import plant_model
    from controllers.tuning import fixed_tuning

    derived = ["| plant | `w_h` | `w_F` | `w_P` | `kp` [N/m] | `ki` [N/(m s)] | `kd` [N s/m] | "
               "`f_d` [Hz] | `lambda` | `k` [1/s] | observer `sigma0` [N/m] | mid stroke "
               "GM / PM / Ms (valve; sensor) | worst point of the grid, GM / PM / Ms | "
               "with the observer, worst |",
               "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|---|"]
    former = ["| plant | former `w_F` / `w_P` [rad/s] | mid stroke GM / PM / Ms (valve; "
              "sensor) | worst point of the grid |", "|---|---|---|---|"]
    for spec in PLANTS:
        pf = plant_file(spec)
        model = plant_model(pf)
        tu = model.tuning
        g = tu.pid_gains
        mid = tu.mid
        obs = tu.observer_margins
        derived.append(
            f"| {label(spec)} | {tu.column_frequency:.1f} | {tu.force_bandwidth:.1f} | "
            f"{tu.pid_bandwidth:.1f} | {g.kp:.3g} | {g.ki:.3g} | {g.kd:.3g} | "
            f"{tu.derivative_cutoff:.0f} | {tu.velocity_compensation:.3f} | "
            f"{tu.observer_gain:.3g} | "
            f"{tu.observer_stiffness:.3g} | {_m(mid['valve'])}; {_m(mid['position'])} | "
            f"{_m(tu.margins)} at {_where(tu.worst)} | "
            f"{_m(obs) if obs is not None else '-'} |")
        w_F, w_P = FORMER[pf.kind]
        old = fixed_tuning(model, force_bandwidth=w_F, pid_bandwidth=w_P,
                           derivative_cutoff=60.0, observer_gain=20.0,
                           mpc_horizon_time=0.040, mpc_velocity_ratio=100.0)
        former.append(f"| {label(spec)} | {w_F:g} / {w_P:g} | {_m(old.mid['valve'])}; "
                      f"{_m(old.mid['position'])} | {_m(old.margins)} at {_where(old.worst)} |")
    return {"derived": "\n".join(derived), "former": "\n".join(former)}


def _where(text: str) -> str:
    """The point and break of a worst-point phrase ('..., broken at the valve command, at
    POINT')."""
    if ", broken at " not in text:
        return text
    brk, point = text.split(", broken at ", 1)[1].split(", at ", 1)
    return f"{point} ({'valve' if 'valve' in brk else 'sensor'})"


def render(page: str, blocks: dict[str, str]) -> str:
    """``page`` with each block between ``<!-- tuning-NAME:start -->`` and ``:end``."""
    for name in MARKERS:
        start, end = f"<!-- tuning-{name}:start -->", f"<!-- tuning-{name}:end -->"
        i, j = page.index(start) + len(start), page.index(end)
        page = page[:i] + "\n" + blocks[name] + "\n" + page[j:]
    return page


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="fail if the page differs")
    args = ap.parse_args(argv)
    page = PAGE.read_text(encoding="utf-8")
    new = render(page, tables())
    if args.check:
        if new != page:
            sys.stderr.write("docs/compensators.md: the tuning tables differ from the code's; "
                             "run PYTHONPATH=. python3 docs/make_tuning_tables.py\n")
            return 1
        return 0
    if new != page:
        tmp = PAGE.with_suffix(".md.tmp")
        tmp.write_text(new, encoding="utf-8")
        tmp.replace(PAGE)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
