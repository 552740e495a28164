"""A demonstration: every registered friction model along one rich motion, plotted.

The motion (velocity prescribed, seed 000 cylinder 1 parameters) contains what
separates the models: a start from rest, a slide with reversals, a dwell, a
restart after the dwell, and small displacement cycles in the pre-sliding
regime. For each model the figure shows the force against time, against
velocity (friction lag, Stribeck hump) and against displacement during the
small cycles (pre-sliding hysteresis, nonlocal memory).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fcomp.errors import FcompError
from fcomp.measurement import Measurement


def demo_motion(rate: float = 2000.0) -> tuple[np.ndarray, np.ndarray]:
    """Time (s) and velocity (m/s) of the demonstration motion (about 9 s)."""
    t = np.arange(0.0, 9.0, 1.0 / rate)
    v = np.zeros_like(t)
    slide = (t >= 0.2) & (t < 4.2)
    v[slide] = 0.05 * np.sin(2 * np.pi * 0.5 * (t[slide] - 0.2))  # two slides with reversals
    restart = (t >= 5.2) & (t < 6.2)  # restart after a 1 s dwell
    v[restart] = 0.03 * np.sin(np.pi * (t[restart] - 5.2))
    small = t >= 6.5  # pre-sliding cycles: displacement amplitude about 0.1 mm
    tau = t[small] - 6.5
    amp = 1e-4 * (1.0 - 0.5 * (tau > 1.25))
    v[small] = amp * 2 * np.pi * 2.0 * np.cos(2 * np.pi * 2.0 * tau)
    return t, v


def run_demo(out_dir: str | Path, params: str = "seed000-cylinder1") -> list[Path]:
    """Simulate every registered model along :func:`demo_motion`; write CSVs and ``demo.png``."""
    from fcomp import figstyle as fs
    from fcomp.models import MODELS, make_model
    from fcomp.trajectory import friction_along_motion

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise FcompError(f"{out}: exists and is not a directory")
    out.mkdir(parents=True, exist_ok=True)
    t, v = demo_motion()
    names = MODELS.names()
    fig, axes = fs.new_figure(height=2.3 * len(names) + 0.4, nrows=len(names), ncols=3,
                              squeeze=False)
    written: list[Path] = []
    small = t >= 6.5
    for row, name in enumerate(names):
        model = make_model(name, params=params)
        run = friction_along_motion(model, t, v)
        meas = Measurement(
            {"t": run.t, "x": run.x, "v": run.v, "a": run.a, "F": run.F},
            {"name": f"demo-{name}", "kind": "friction-rig", "pressure": "gauge",
             "simulation": {"plant": "motion", "friction": name, "params": params}},
        )
        csv, _ = meas.write(out / f"demo-{name}.csv")
        written.append(csv)
        ax_t, ax_v, ax_x = axes[row]
        ax_t.plot(t, run.F, lw=0.8)
        ax_t.set_ylabel(f"{name}\nF (N)")
        ax_v.plot(fs.scaled("v", run.v[~small]), run.F[~small], lw=0.6)
        ax_x.plot((run.x[small] - run.x[small][0]) * 1e3, run.F[small], lw=0.8)
        for ax in (ax_t, ax_v, ax_x):
            ax.grid(alpha=0.3)
    axes[0, 0].set_title("force vs time")
    axes[0, 1].set_title("force vs velocity (slides)")
    axes[0, 2].set_title("force vs displacement (small cycles)")
    axes[-1, 0].set_xlabel("t (s)")
    axes[-1, 1].set_xlabel(fs.label("v", "v"))
    axes[-1, 2].set_xlabel("x - x0 (mm)")
    png = out / "demo.png"
    fs.save(fig, png)
    written.append(png)
    return written
