"""Compiling an exported step: the C compiler, and the compiled controller called through
ctypes (:mod:`controllers.export`, "Compiler")."""

from __future__ import annotations

import ctypes
import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from controllers.export.cfiles import CFLAGS
from controllers.export.step import CASADI_NAME
from fcomp.compiled import run_compiler
from fcomp.errors import FcompError


def find_compiler() -> str | None:
    """The C compiler (module docstring: ``$FCOMP_CC``, else ``$CC``, cc, gcc, clang)."""
    forced = os.environ.get("FCOMP_CC")
    if forced is not None:
        return shutil.which(forced) if forced.strip() else None
    for cand in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if cand and shutil.which(cand):
            return cand
    return None


class CompiledController:
    """The exported C controller, built as a shared library and called through ctypes.

    The compiler runs in a process group of its own, ended whole on an interruption
    (:func:`fcomp.compiled.run_compiler`). A compiler that fails, or that reports success
    without leaving a loadable library, is an :class:`~fcomp.errors.FcompError` naming it.
    """

    def __init__(self, folder: Path, cc: str, n_state: int, build: Path, n_ref: int = 3) -> None:
        srcs = [folder / "fcomp_ctrl.c", folder / "fcomp_ctrl_bench.c",
                folder / f"{CASADI_NAME}.c"]
        lib = build / "libfcomp_ctrl.so"
        try:
            proc = run_compiler([cc, *CFLAGS, "-fPIC", "-shared", *map(str, srcs), "-o",
                                 str(lib), "-lm"])
        except OSError as exc:
            raise FcompError(f"export: the C compiler {cc} could not be run "
                             f"({exc.strerror or exc})") from None
        if proc.returncode != 0:
            first = (proc.stderr.strip().splitlines() or ["(no message)"])[0]
            raise FcompError(f"export: the C compiler {cc} failed on the generated code: {first}")
        try:
            self.dll = ctypes.CDLL(str(lib))
            self.dll.fcomp_ctrl_sizeof.restype = ctypes.c_ulong
            size = int(self.dll.fcomp_ctrl_sizeof())
        except (OSError, AttributeError):
            raise FcompError(f"export: the C compiler {cc} reported success but left no "
                             "usable library (is it a C compiler?)") from None
        self.size = size
        self.mem = ctypes.create_string_buffer(size + 64)
        dp = ctypes.POINTER(ctypes.c_double)
        self.dll.fcomp_ctrl_init.argtypes = [ctypes.c_void_p]
        self.dll.fcomp_ctrl_step_ref.argtypes = [ctypes.c_void_p, dp, dp]
        self.dll.fcomp_ctrl_step_ref.restype = ctypes.c_double
        self.dll.fcomp_ctrl_bench.argtypes = [ctypes.c_void_p, ctypes.c_long, ctypes.c_long,
                                              dp, dp, dp, dp]
        self.dll.fcomp_ctrl_bench.restype = ctypes.c_int
        self.dll.fcomp_ctrl_fault.argtypes = [ctypes.c_void_p]
        self.dll.fcomp_ctrl_fault.restype = _Fault
        self._y = np.zeros(3)
        self._ref = np.zeros(n_ref)
        self._yp = self._y.ctypes.data_as(dp)
        self._refp = self._ref.ctypes.data_as(dp)
        self._dp = dp
        self.n_state = n_state

    def instance(self) -> Any:
        """Memory of one more controller (an ``fcomp_ctrl_t``)."""
        return ctypes.create_string_buffer(self.size + 64)

    def init(self, mem: Any = None) -> None:
        self.dll.fcomp_ctrl_init(self.mem if mem is None else mem)

    def set_state(self, state: np.ndarray, mem: Any = None) -> None:
        """Overwrite the controller's state (``state`` is the struct's first member)."""
        buf = np.ascontiguousarray(state, dtype=float)
        if buf.size != self.n_state:
            raise ValueError(f"state of {buf.size} values, the controller has {self.n_state}")
        ctypes.memmove(self.mem if mem is None else mem, buf.ctypes.data, buf.nbytes)

    def state(self, mem: Any = None) -> np.ndarray:
        """A copy of the controller's state."""
        raw = ctypes.string_at(self.mem if mem is None else mem, 8 * self.n_state)
        return np.frombuffer(raw, dtype=float).copy()

    def fault(self, mem: Any = None) -> dict[str, int]:
        """``fcomp_ctrl_fault``: the fail-safe layer's fault state (faults, consecutive,
        good_run, latched, cause)."""
        f = self.dll.fcomp_ctrl_fault(self.mem if mem is None else mem)
        return {name: int(getattr(f, name)) for name, _ in _Fault._fields_}

    def step(self, y: np.ndarray, ref: Any, mem: Any = None) -> float:
        self._y[:] = y
        self._ref[:] = ref
        return float(self.dll.fcomp_ctrl_step_ref(self.mem if mem is None else mem, self._yp,
                                                  self._refp))

    def step_raw(self, y: Any, ref: Any, mem: Any = None) -> float:
        """``fcomp_ctrl_step_ref`` with the pointers as given (``None``: a NULL pointer)."""
        args = [None if a is None else np.ascontiguousarray(a, dtype=float).ctypes.data_as(
            self._dp) for a in (y, ref)]
        return float(self.dll.fcomp_ctrl_step_ref(self.mem if mem is None else mem, *args))

    def bench(self, n: int, Y: np.ndarray, REF: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``fcomp_ctrl_bench``: ``(cpu, wall)`` times (s) of ``n`` steps on the samples."""
        Y = np.ascontiguousarray(Y, dtype=float)
        REF = np.ascontiguousarray(REF, dtype=float)
        cpu = np.zeros(n)
        wall = np.zeros(n)
        self.dll.fcomp_ctrl_bench(self.mem, n, len(Y), Y.ctypes.data_as(self._dp),
                                  REF.ctypes.data_as(self._dp), cpu.ctypes.data_as(self._dp),
                                  wall.ctypes.data_as(self._dp))
        return cpu, wall


class _Fault(ctypes.Structure):
    """``fcomp_ctrl_fault_t`` (fcomp_ctrl.h)."""

    _fields_ = [("faults", ctypes.c_long), ("consecutive", ctypes.c_long),
                ("good_run", ctypes.c_long), ("latched", ctypes.c_int), ("cause", ctypes.c_int)]
