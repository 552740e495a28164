"""Compiling an exported step: the C compiler, and the compiled controller called through
ctypes (:mod:`controllers.export`, "Compiler")."""

from __future__ import annotations

import ctypes
import os
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np

from controllers.export.cfiles import CFLAGS
from controllers.export.step import CASADI_NAME
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
    """The exported C controller, built as a shared library and called through ctypes."""

    def __init__(self, folder: Path, cc: str, n_state: int, build: Path, n_ref: int = 3) -> None:
        srcs = [folder / "fcomp_ctrl.c", folder / "fcomp_ctrl_bench.c",
                folder / f"{CASADI_NAME}.c"]
        lib = build / "libfcomp_ctrl.so"
        proc = subprocess.run([cc, *CFLAGS, "-fPIC", "-shared", *map(str, srcs), "-o", str(lib),
                               "-lm"], capture_output=True, text=True)
        if proc.returncode != 0:
            first = (proc.stderr.strip().splitlines() or ["(no message)"])[0]
            raise FcompError(f"export: the C compiler {cc} failed on the generated code: {first}")
        self.dll = ctypes.CDLL(str(lib))
        size = self._struct_size(folder, cc, build)
        self.size = size
        self.mem = ctypes.create_string_buffer(size + 64)
        dp = ctypes.POINTER(ctypes.c_double)
        self.dll.fcomp_ctrl_init.argtypes = [ctypes.c_void_p]
        self.dll.fcomp_ctrl_step_ref.argtypes = [ctypes.c_void_p, dp, dp]
        self.dll.fcomp_ctrl_step_ref.restype = ctypes.c_double
        self.dll.fcomp_ctrl_bench.argtypes = [ctypes.c_void_p, ctypes.c_long, ctypes.c_long,
                                              dp, dp, dp]
        self.dll.fcomp_ctrl_bench.restype = ctypes.c_int
        self._y = np.zeros(3)
        self._ref = np.zeros(n_ref)
        self._yp = self._y.ctypes.data_as(dp)
        self._refp = self._ref.ctypes.data_as(dp)
        self._dp = dp
        self.n_state = n_state

    @staticmethod
    def _struct_size(folder: Path, cc: str, build: Path) -> int:
        """``sizeof(fcomp_ctrl_t)``, asked of the compiler (a tiny program run once)."""
        src = build / "size.c"
        src.write_text('#include <stdio.h>\n#include "fcomp_ctrl.h"\n'
                       'int main(void) { printf("%zu\\n", sizeof(fcomp_ctrl_t)); return 0; }\n')
        exe = build / "size"
        proc = subprocess.run([cc, f"-I{folder}", str(src), "-o", str(exe)],
                              capture_output=True, text=True)
        if proc.returncode != 0:
            raise FcompError(f"export: the C compiler {cc} failed on fcomp_ctrl.h")
        return int(subprocess.run([str(exe)], capture_output=True, text=True,
                                  check=True).stdout)

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

    def step(self, y: np.ndarray, ref: Any, mem: Any = None) -> float:
        self._y[:] = y
        self._ref[:] = ref
        return float(self.dll.fcomp_ctrl_step_ref(self.mem if mem is None else mem, self._yp,
                                                  self._refp))

    def bench(self, n: int, Y: np.ndarray, REF: np.ndarray) -> np.ndarray:
        Y = np.ascontiguousarray(Y, dtype=float)
        REF = np.ascontiguousarray(REF, dtype=float)
        times = np.zeros(n)
        self.dll.fcomp_ctrl_bench(self.mem, n, len(Y), Y.ctypes.data_as(self._dp),
                                  REF.ctypes.data_as(self._dp), times.ctypes.data_as(self._dp))
        return times
