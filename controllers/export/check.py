"""The equivalence check: the compiled controller in closed loop against the Python
plant, the Python controller stepped in lock step (:mod:`controllers.export`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from controllers.export.compiled import CompiledController
from fcomp.errors import FcompError

#: Relative tolerance of the equivalence check.
RTOL = 1e-9


def python_state(ctrl: Any) -> np.ndarray:
    """The Python controller's state in the exported layout (:class:`StepExport`; after its
    ``reset``, so ``started = 1``)."""
    from controllers.ekf import EKFController
    from controllers.lugre_observer import LuGreObserverController
    from controllers.mpc_fixed import FixedIterationMPC

    if isinstance(ctrl, FixedIterationMPC):
        kf = ctrl.ekf.kf
        lam = ctrl.solver._lam
        N = ctrl.problem.horizon
        return np.concatenate([np.asarray(kf.x, dtype=float)[:, 0],
                               np.asarray(kf.P, dtype=float).ravel(order="F"),
                               [ctrl._u_prev], np.asarray(ctrl.solver.U, dtype=float),
                               np.zeros(2 * N) if lam is None else np.asarray(lam, dtype=float)])
    law = ctrl.law
    parts = [np.array([1.0, law.integral, law.v_f, law.x_prev], dtype=float)]
    if isinstance(ctrl, LuGreObserverController):
        parts += [np.asarray(ctrl.x_hat, dtype=float).ravel(), np.array([ctrl._side])]
    elif isinstance(ctrl, EKFController):
        kf = ctrl.ekf.kf
        parts += [np.asarray(kf.x, dtype=float)[:, 0],
                  np.asarray(kf.P, dtype=float).ravel(order="F"), np.array([ctrl._u_prev])]
    return np.concatenate(parts)


@dataclass
class CheckResult:
    """The lock-step closed loop of :func:`check_equivalence` (SI units).

    Attributes
    ----------
    u_python
        The Python controller's commands.
    u_step
        The compiled step's commands from the Python controller's state at every sample
        (the step, compared step for step).
    u_free
        The commands of the compiled controller running on its own state (these drive
        the plant).
    state_rel_diff
        Per sample, the largest difference of the compiled step's next state from the
        Python controller's, relative per block (:func:`block_difference`).
    Y, REF
        Measurements and references of the run (for the timing loop).
    u_max
        The valve range (floor of the relative differences).
    """

    u_python: np.ndarray
    u_step: np.ndarray
    u_free: np.ndarray
    state_rel_diff: np.ndarray
    Y: np.ndarray
    REF: np.ndarray
    u_max: float

    @property
    def max_rel_diff(self) -> float:
        return float(np.max(relative_difference(self.u_step, self.u_python, self.u_max)))

    @property
    def free_max_rel_diff(self) -> float:
        return float(np.max(relative_difference(self.u_free, self.u_python, self.u_max)))

    @property
    def free_max_abs_diff(self) -> float:
        return float(np.max(np.abs(self.u_free - self.u_python)))

    @property
    def max_state_rel_diff(self) -> float:
        return float(np.max(self.state_rel_diff))


def relative_difference(u_c: np.ndarray, u_py: np.ndarray, u_max: float) -> np.ndarray:
    """``|u_c - u_py| / max(|u_py|, 1e-6*u_max)``: relative, with a floor a millionth of the
    valve range (a command of exactly zero has no relative error of its own)."""
    return np.abs(u_c - u_py) / np.maximum(np.abs(u_py), 1e-6 * u_max)


def block_difference(s_c: np.ndarray, s_py: np.ndarray, layout: list[tuple[str, int]]) -> float:
    """Largest over the state's blocks of ``max|s_c - s_py| / max(max|s_py|, 1e-300)``."""
    worst = 0.0
    i = 0
    for _name, k in layout:
        a, b = s_c[i:i + k], s_py[i:i + k]
        d = float(np.max(np.abs(a - b)))
        if d > 0:
            worst = max(worst, d / max(float(np.max(np.abs(b))), 1e-300))
        i += k
    return worst


def check_equivalence(ctrl: Any, compiled: CompiledController, plant: Any, *,
                      layout: list[tuple[str, int]] | None = None, start_from_init: bool = True,
                      task: str = "seed002-sine", duration: float = 0.6, noise: float = 1.0,
                      seed: int = 0) -> CheckResult:
    """Run the compiled controller in closed loop against ``plant`` (the harness's plant
    integration and sensors) with the Python controller ``ctrl`` stepped on the same
    measurements and references.

    Two compiled instances run: one on its own state from ``fcomp_ctrl_init`` (its
    commands drive the plant: ``u_free``; without ``start_from_init``, from the Python
    controller's state after its reset, as the MPC needs), and one whose state is set to the Python
    controller's before every sample (``u_step``: the step itself, compared step for
    step, and its next state against the Python controller's).
    """
    from controllers.base import Reference
    from controllers.harness import SensorModel
    from controllers.plant_model import equilibrium
    from controllers.tasks import get_task

    model = ctrl.model
    tk = get_task(task)
    x_mid = 0.5 * model.stroke
    dt = ctrl.dt
    n = max(1, int(round(duration / dt)))
    t = np.arange(n + 1) * dt
    r, dr, ddr = tk.sample(t)
    r = r + x_mid
    if r.min() < 0.005 or r.max() > model.stroke - 0.005:
        raise FcompError(f"export: task {task} leaves the stroke within {duration} s")
    x0, _ = equilibrium(plant, x_mid)
    stepper = plant.stepper(dt, x0=x0, rtol=1e-5, atol=1e-5)
    sensors = SensorModel(model.sensors, noise, seed)
    names = plant.state_names
    meas = [names.index(k) for k in ("x", "p1", "p2")]
    state = stepper.reset()
    u_py, u_step, u_free, s_diff = (np.zeros(n + 1) for _ in range(4))
    Y = np.zeros((n + 1, 3))
    preview = int(getattr(ctrl, "preview", 0))
    r_pad = np.concatenate([r, np.full(preview, r[-1])])
    REF = np.zeros((n + 1, 3 + preview))
    synced = compiled.instance()
    compiled.init()
    compiled.init(synced)
    lay = layout or [("state", compiled.n_state)]
    u_max = model.u_max
    for k in range(n + 1):
        y = sensors.measure(state[meas])
        Y[k] = y
        fut = tuple(float(v) for v in r_pad[k + 1:k + 1 + preview])
        ref = Reference(float(r[k]), float(dr[k]), float(ddr[k]), fut)
        REF[k] = (ref.r, ref.dr, ref.ddr, *fut)
        if k == 0:
            ctrl.reset(0.0, y, ref)
            if not start_from_init:  # the MPC's start needs the plant's equilibrium (Python)
                compiled.set_state(python_state(ctrl))
        compiled.set_state(python_state(ctrl), synced)
        u_step[k] = compiled.step(y, REF[k], synced)
        u_py[k] = ctrl.step(float(t[k]), y, ref)
        s_diff[k] = block_difference(compiled.state(synced), python_state(ctrl), lay)
        u_free[k] = compiled.step(y, REF[k])
        if not math.isfinite(u_free[k]):
            raise FcompError(f"export: the compiled controller returned {u_free[k]} at "
                             f"t = {t[k]:.4f} s")
        if k < n:
            state = stepper.step(min(max(u_free[k], -u_max), u_max))
    return CheckResult(u_python=u_py, u_step=u_step, u_free=u_free, state_rel_diff=s_diff,
                       Y=Y, REF=REF, u_max=u_max)
