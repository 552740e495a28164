"""A controller's step as C code: CasADi code generation, a plain C interface, a closed-loop check.

:func:`export_controller` turns one sample of a controller of this package
into a CasADi function ::

    step(state, y, ref) -> (u, state_next)

with a *fixed-size* state vector (layout in :class:`StepExport`), writes its
C code (CasADi's code generator) behind a plain C interface
(``fcomp_ctrl.h``: ``fcomp_ctrl_init``, ``fcomp_ctrl_step``,
``fcomp_ctrl_step_ref``; every work array a fixed-size member of the
``fcomp_ctrl_t`` struct, no allocation anywhere), a ``Makefile`` and a small
``example.c``; then, with a C compiler, builds a shared library, runs the
compiled controller in closed loop against the Python plant of the harness
(:mod:`controllers.harness`: the same plant integration, sensors and
tasks) and checks, at every sample, that its command equals the command of
the *Python* controller (the classes of :mod:`controllers`, stepped in
lock step on the same measurements and references: an independent
implementation of the same law, not the same CasADi function); last it
times the compiled step in a C loop (``fcomp_ctrl_bench``).

What each controller's step holds
---------------------------------
Every exported controller but ``mpc`` is the PID of :mod:`controllers.pid` with its
friction estimate and the force-to-valve inversion of
:mod:`controllers.force_to_valve` (the grid of force rates, its running
maximum and the linear interpolation of ``numpy.interp``, written out as a
chain of ``if_else``); the state vector is ::

    [started, integral, v_f, x_prev, <compensation states>]

``started`` is 0 after ``fcomp_ctrl_init``: the first step then resets the
controller from its measurement, as :meth:`controllers.base.Controller.reset`
does from ``y0`` (the harness resets with the first sample's measurement).
The compensation states are

* ``pid``, ``pid-ff``: none (the feedforward map is static);
* ``lugre-observer``: the observer's friction states, then the side of motion;
* ``ekf``: the scaled state estimate (``nx``), its covariance (``nx*nx``,
  column-major) and the previous command.

The model functions a controller evaluates (force-rate grid, observer step,
steady-state map, EKF prediction and friction) are the controller's own
CasADi functions, called inside the exported step, so the C code computes
the same equations as the Python controller.

``mpc`` solves the quadratic programme of its real-time iteration with DAQP,
an active-set solver with a data-dependent number of iterations that CasADi's
code generator cannot express. It is exported in its *fixed-iteration* form,
:class:`controllers.mpc_fixed.FixedIterationMPC` (the same EKF, linearisation,
warm start, limits and fallback law; the QP by a fixed number of ADMM
iterations), and checked against that form in Python (numpy's ADMM); how far
its commands are from DAQP's is measured in ``docs/compensators.md``. Its
state is ``[ekf_x, ekf_P, u_prev, U (horizon), lam (2*horizon)]``, and
``fcomp_ctrl_init`` sets the state the Python ``reset`` gives at rest at
mid-stroke (the reset solves the plant's equilibrium, which is not
generated); ``fcomp_ctrl_set_state`` sets another. In the check both
compiled instances start from the Python controller's reset state.

Reference input
---------------
``ref = [r, dr, ddr]`` (m, m/s, m/s^2), for ``mpc`` followed by the
positions at the next ``horizon`` samples: ``fcomp_ctrl_step_ref`` takes
them (a trajectory, as the harness gives it); ``fcomp_ctrl_step(c, y, r)``
is the set-point form, ``dr = ddr = 0`` and ``r`` over the horizon (exact for
a held set point).

Compiler
--------
``$FCOMP_CC`` names the C compiler; when it is set and not found, there is
*no* compiler (the documented way to test that path). Otherwise ``$CC``,
``cc``, ``gcc``, ``clang``, the first found. Without one the code is still
written and the check is skipped (``equivalent`` is ``None``).
"""

from __future__ import annotations

from controllers.export.cfiles import CFLAGS, write_c
from controllers.export.check import (
    HOSTILE_EVENTS,
    RTOL,
    CheckResult,
    block_deviations,
    block_difference,
    check_equivalence,
    hostile_script,
    python_state,
    relative_difference,
)
from controllers.export.compiled import CompiledController, find_compiler
from controllers.export.pipeline import (
    MAX_TIMING_STEPS,
    ExportResult,
    check_friction,
    export_controller,
)
from controllers.export.step import (
    CASADI_INT,
    CASADI_NAME,
    EXPORTABLE,
    StepExport,
    guarded_step_function,
    step_function,
)

__all__ = ["CASADI_INT", "CASADI_NAME", "CFLAGS", "EXPORTABLE", "HOSTILE_EVENTS",
           "MAX_TIMING_STEPS", "RTOL", "CheckResult", "CompiledController", "ExportResult",
           "StepExport", "block_deviations", "block_difference", "check_equivalence", "check_friction",
           "export_controller", "find_compiler", "guarded_step_function", "hostile_script",
           "python_state", "relative_difference", "step_function", "write_c"]
