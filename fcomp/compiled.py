"""Compiled time-stepping loops built from CasADi step functions, with an on-disk cache.

Hot loops (friction along a motion, fitting, plant simulation) advance a
state with a CasADi *step function* ``step(x, u, dt, p) -> x_next`` built from
the model equations. :func:`stepping_loop` turns such a function into a
native loop: CasADi generates C code for the step, a small C driver calls it
for every sample, the system C compiler (``$CC``, ``cc``, ``gcc`` or
``clang``) builds a shared library, and :mod:`ctypes` calls it on numpy
arrays. Libraries are cached under ``$FCOMP_CACHE`` (default
``~/.cache/fcomp``) by the hash of the generated source, so each model
structure is compiled once per machine. Parameters are inputs, never baked
in: one library serves every parameter value.

Without a compiler, or with ``FCOMP_JIT=0``, the same step runs in CasADi's
virtual machine through ``mapaccum`` (slower, identical results).
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable, Sequence
from functools import cache
from pathlib import Path

import casadi as ca
import numpy as np

_DRIVER = r"""
#include <string.h>
int fcomp_loop(int n, const double* x0, const double* u, const double* dt,
               const double* p, double* X) {
  casadi_int sz_arg, sz_res, sz_iw, sz_w;
  STEP_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
  const casadi_real* arg[sz_arg > 4 ? sz_arg : 4];
  casadi_real* res[sz_res > 1 ? sz_res : 1];
  casadi_int iw[sz_iw + 1];
  casadi_real w[sz_w + 1];
  memcpy(X, x0, NX * sizeof(double));
  for (int k = 0; k < n; ++k) {
    arg[0] = X + k * NX; arg[1] = u + k * NU; arg[2] = dt + k; arg[3] = p;
    res[0] = X + (k + 1) * NX;
    if (STEP(arg, res, iw, w, 0)) return k + 1;
  }
  return 0;
}
"""

Loop = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def cache_dir() -> Path:
    d = Path(os.environ.get("FCOMP_CACHE", Path.home() / ".cache" / "fcomp"))
    d.mkdir(parents=True, exist_ok=True)
    return d


@cache
def compiler() -> str | None:
    """The C compiler to use, or ``None`` (``FCOMP_JIT=0`` disables compiling)."""
    if os.environ.get("FCOMP_JIT", "1") == "0":
        return None
    for cand in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if cand and shutil.which(cand):
            return cand
    return None


def _build(step: ca.Function, nx: int, nu: int) -> Path | None:
    driver = _DRIVER.replace("STEP", step.name()).replace("NX", str(nx)).replace("NU", str(nu))
    return build_library(step, driver)


def build_library(fn: ca.Function | Sequence[ca.Function], driver: str) -> Path | None:
    """Compile CasADi's C code of ``fn`` (one or several functions) followed by the C
    ``driver`` into a cached shared library.

    Returns the library path, or ``None`` without a working compiler (callers
    then fall back to CasADi's virtual machine or a Python loop).
    """
    cc = compiler()
    if cc is None:
        return None
    fns = [fn] if isinstance(fn, ca.Function) else list(fn)
    name = fns[0].name()
    with tempfile.TemporaryDirectory() as tmp:
        cg = ca.CodeGenerator(f"{name}.c", {"with_header": False, "casadi_real": "double"})
        for f in fns:
            cg.add(f)
        cwd = os.getcwd()
        try:
            os.chdir(tmp)
            cg.generate()
        finally:
            os.chdir(cwd)
        src = Path(tmp) / f"{name}.c"
        code = src.read_text() + driver
        key = hashlib.sha1((code + cc).encode()).hexdigest()[:16]
        lib = cache_dir() / f"{name}_{key}.so"
        if lib.exists():
            return lib
        src.write_text(code)
        out = Path(tmp) / "lib.so"
        proc = subprocess.run(
            [cc, "-O2", "-fPIC", "-shared", str(src), "-o", str(out), "-lm"],
            capture_output=True, text=True,
        )
        if proc.returncode != 0:
            return None  # a broken toolchain must not break the package: use the VM
        tmp_lib = lib.with_suffix(f".{os.getpid()}.tmp")
        shutil.copy(out, tmp_lib)
        os.replace(tmp_lib, lib)
        return lib


def stepping_loop(step: ca.Function, *, compiled: bool = True, chunk: int = 4096) -> Loop:
    """A loop ``run(x0, U, dt, p) -> X`` applying ``step(x, u, dt, p)`` sample by sample.

    ``U`` is ``(n, nu)``, ``dt`` ``(n,)``, ``p`` ``(np,)``; the result ``X`` is
    ``(n + 1, nx)`` with ``X[0] = x0``.
    """
    nx = step.size1_in(0)
    nu = step.size1_in(1)
    lib = _build(step, nx, nu) if compiled else None
    if lib is not None:
        dll = ctypes.CDLL(str(lib))
        fn = dll.fcomp_loop
        dp = ctypes.POINTER(ctypes.c_double)
        fn.argtypes = [ctypes.c_int, dp, dp, dp, dp, dp]
        fn.restype = ctypes.c_int

        def run(x0: np.ndarray, U: np.ndarray, dt: np.ndarray, p: np.ndarray) -> np.ndarray:
            n = dt.size
            x0c = np.ascontiguousarray(x0, dtype=float)
            Uc = np.ascontiguousarray(U, dtype=float).reshape(n, nu)
            dtc = np.ascontiguousarray(dt, dtype=float)
            pc = np.ascontiguousarray(p, dtype=float)
            X = np.empty((n + 1, nx))
            err = fn(n, *(a.ctypes.data_as(dp) for a in (x0c, Uc, dtc, pc, X)))
            if err:
                raise RuntimeError(f"compiled step failed at sample {err}")
            return X

        run.compiled = True  # type: ignore[attr-defined]
        return run

    roll = step.mapaccum(step.name() + "_roll", chunk, [0], [0])

    def run_vm(x0: np.ndarray, U: np.ndarray, dt: np.ndarray, p: np.ndarray) -> np.ndarray:
        n = dt.size
        X = np.empty((n + 1, nx))
        X[0] = x0
        xk = np.asarray(x0, dtype=float)
        pm = np.repeat(np.asarray(p, dtype=float).reshape(-1, 1), chunk, axis=1)
        for start in range(0, n, chunk):
            stop = min(start + chunk, n)
            k = stop - start
            Uc = np.zeros((nu, chunk))
            dtc = np.zeros((1, chunk))
            Uc[:, :k] = np.asarray(U[start:stop]).T
            dtc[0, :k] = dt[start:stop]
            Xc = np.asarray(roll(xk, Uc, dtc, pm))
            X[start + 1 : stop + 1] = Xc[:, :k].T
            xk = Xc[:, k - 1]
        return X

    run_vm.compiled = False  # type: ignore[attr-defined]
    return run_vm
