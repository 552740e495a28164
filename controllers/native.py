"""Native-code calls of CasADi functions for the hot path of controllers (EKF, MPC, observers).

A controller evaluates a few small CasADi functions every sample (a model
step and its Jacobian, a condensed QP). Called through CasADi's Python
interface each costs some 30 us of wrapping alone; :func:`native` compiles the
function's generated C code with a small driver into a cached shared
library (:func:`fcomp.compiled.load_library`) and calls it through
:mod:`ctypes` on preallocated numpy buffers (a few microseconds).

Inputs and outputs are dense vectors/matrices: the function is wrapped so
every output is densified, and :class:`NativeFunction` returns numpy arrays
of the declared shapes (column-major from CasADi, reshaped to row-major
numpy). Without a C compiler (or with ``FCOMP_JIT=0``) the same function
runs in CasADi's virtual machine, with identical results.
"""

from __future__ import annotations

import ctypes
from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

from fcomp.compiled import load_library

_DRIVER = r"""
int NAME_eval(const double* in, double* out) {
  casadi_int sz_arg, sz_res, sz_iw, sz_w;
  NAME_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
  const casadi_real* arg[sz_arg > NIN ? sz_arg : NIN];
  casadi_real* res[sz_res > NOUT ? sz_res : NOUT];
  casadi_int iw[sz_iw + 1];
  casadi_real w[sz_w + 1];
  static const int in_off[NIN + 1] = {IN_OFF};
  static const int out_off[NOUT + 1] = {OUT_OFF};
  for (int i = 0; i < NIN; ++i) arg[i] = in + in_off[i];
  for (int i = 0; i < NOUT; ++i) res[i] = out + out_off[i];
  return NAME(arg, res, iw, w, 0);
}
"""


def _view(buf: np.ndarray, start: int, shape: tuple[int, int]) -> np.ndarray:
    r, c = shape
    flat = buf[start:start + r * c]
    return flat if c == 1 else flat.reshape((r, c), order="F")


def _offsets(sizes: Sequence[int]) -> list[int]:
    out = [0]
    for s in sizes:
        out.append(out[-1] + s)
    return out


class NativeFunction:
    """A CasADi function called natively (see the module docstring).

    Calling it with the inputs (array-likes of the declared sizes) returns a
    tuple of numpy arrays, one per output, shaped ``(rows,)`` for column
    vectors and ``(rows, cols)`` otherwise.
    """

    def __init__(self, fn: ca.Function, *, compiled: bool = True) -> None:
        ins = fn.mx_in()
        outs = fn.call(ins)
        dense = ca.Function(fn.name() + "_dense", ins, [ca.densify(o) for o in outs])
        self.fn = dense
        self.in_sizes = [dense.numel_in(i) for i in range(dense.n_in())]
        self.out_shapes = [(dense.size1_out(i), dense.size2_out(i)) for i in range(dense.n_out())]
        self.out_sizes = [r * c for r, c in self.out_shapes]
        self._in_off = _offsets(self.in_sizes)
        self._out_off = _offsets(self.out_sizes)
        self._in = np.zeros(self._in_off[-1])
        self._out = np.zeros(self._out_off[-1])
        in_shapes = [(dense.size1_in(i), dense.size2_in(i)) for i in range(dense.n_in())]
        # views shaped like each argument (column-major, as CasADi stores them)
        self._in_views = [_view(self._in, a, shp)
                          for a, shp in zip(self._in_off, in_shapes, strict=False)]
        self._out_views = [_view(self._out, a, shp)
                           for a, shp in zip(self._out_off, self.out_shapes, strict=False)]
        self._fn = None
        if compiled:
            name = dense.name()
            driver = (_DRIVER.replace("NAME", name)
                      .replace("NIN", str(len(self.in_sizes)))
                      .replace("NOUT", str(len(self.out_sizes)))
                      .replace("IN_OFF", ", ".join(map(str, self._in_off)))
                      .replace("OUT_OFF", ", ".join(map(str, self._out_off))))
            dll = load_library(dense, driver)
            if dll is not None:
                f = getattr(dll, f"{name}_eval")
                dp = ctypes.POINTER(ctypes.c_double)
                f.argtypes = [dp, dp]
                f.restype = ctypes.c_int
                self._fn = f
                self._in_p = self._in.ctypes.data_as(dp)
                self._out_p = self._out.ctypes.data_as(dp)
        self.compiled = self._fn is not None

    def __call__(self, *args: object) -> tuple[np.ndarray, ...]:
        if len(args) != len(self._in_views):
            raise TypeError(f"{self.fn.name()}: expected {len(self._in_views)} inputs")
        if self._fn is None:
            raw: Any = self.fn(*args)
            res = raw if isinstance(raw, tuple) else (raw,)
            return tuple(np.asarray(r, dtype=float).reshape(v.shape, order="F")
                         for r, v in zip(res, self._out_views, strict=True))
        for view, a in zip(self._in_views, args, strict=True):
            view[...] = a
        if self._fn(self._in_p, self._out_p):
            raise FloatingPointError(f"{self.fn.name()}: native evaluation failed")
        return tuple([v.copy() for v in self._out_views])


def native(fn: ca.Function, *, compiled: bool = True) -> NativeFunction:
    """``fn`` as a :class:`NativeFunction` (compiled when a C compiler is available)."""
    return NativeFunction(fn, compiled=compiled)
