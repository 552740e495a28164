"""Compiled time-stepping loops built from CasADi step functions, with an on-disk cache.

Hot loops (friction along a motion, fitting, plant simulation) advance a
state with a CasADi *step function* ``step(x, u, dt, p) -> x_next`` built from
the model equations. :func:`stepping_loop` turns such a function into a
native loop: CasADi generates C code for the step, a small C driver
(``fcomp/csrc/stepping_loop.c``) calls it for every sample, the system C
compiler (``$CC``, ``cc``, ``gcc`` or ``clang``) builds a shared library, and
:mod:`ctypes` calls it on numpy arrays. Libraries are cached under ``$FCOMP_CACHE`` (default
``~/.cache/fcomp``) by the hash of the generated source, so each model
structure is compiled once per machine. Parameters are inputs, never baked
in: one library serves every parameter value.

Without a compiler, or with ``FCOMP_JIT=0``, the same step runs in CasADi's
virtual machine through ``mapaccum`` (slower, identical results).

Drivers longer than a few lines are C files shipped with the package
(``fcomp/csrc/*.c``, read with :mod:`importlib.resources`): :func:`c_source`
fills their ``@NAME@`` placeholders (sizes, function names, coefficients).

:func:`load_c` compiles a plain C kernel (no CasADi function: the fits' zero-phase
filter, :mod:`fcomp.reconstruction`) through the same cache; its callers run their
numpy or scipy equivalent without a compiler.

The cache and trust (README, "Security")
----------------------------------------
Cached libraries are *loaded and run* (``ctypes``): whoever can write into
the cache can run code in fcomp. The cache folder is therefore created
user-only (``0700``), and a cache folder that belongs to another user or is
writable by group or others is not used. Each library is stored with its
SHA-256 (``NAME.so.sha256``) and checked before loading, so a truncated or
corrupted file is rebuilt, not loaded. An unusable cache (``FCOMP_CACHE``
naming a file, a read-only folder, an unsafe folder) never stops a command:
fcomp warns once and runs the same equations uncompiled (slower, identical
results), as it does without a C compiler.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import re
import shutil
import signal
import stat
import subprocess
import tempfile
import warnings
from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any, Generic, TypeVar

import casadi as ca
import numpy as np

from fcomp.errors import FcompError, FcompWarning

T = TypeVar("T")

#: A :func:`build_library` prelude that keeps CasADi's functions and helpers inside the
#: library (hidden visibility): the compiler may then inline them into the driver, which
#: marks the functions it exports with :data:`EXPORT`. Without it, a shared library must
#: call even ``casadi_fabs`` through its symbol table (they could be interposed).
#: The standard headers come first: a hidden declaration of ``exp`` would not link.
HIDDEN = ("#include <math.h>\n#include <stdio.h>\n#include <stdlib.h>\n#include <string.h>\n"
          "#if defined(__GNUC__)\n#pragma GCC visibility push(hidden)\n#endif\n")
#: A prelude (after :data:`HIDDEN`) that computes ``fmax``/``fmin`` inline instead of calling
#: the C library: ``x > y ? x : y`` with a NaN giving the other operand, which is what
#: glibc's x86-64 ``fmax`` (``maxsd``) returns for every input, signed zeros included.
MINMAX = ("#define fmax(x, y) fcomp_fmax(x, y)\n#define fmin(x, y) fcomp_fmin(x, y)\n"
          "static inline double fcomp_fmax(double x, double y) "
          "{ return (x > y || y != y) ? x : y; }\n"
          "static inline double fcomp_fmin(double x, double y) "
          "{ return (x < y || y != y) ? x : y; }\n")
#: The attribute of a driver function called from Python when the prelude is :data:`HIDDEN`.
EXPORT = ("#if defined(__GNUC__)\n#define FCOMP_EXPORT __attribute__((visibility(\"default\")))\n"
          "#else\n#define FCOMP_EXPORT\n#endif\n")


@dataclass(frozen=True)
class Loop:
    """``loop(x0, U, dt, p) -> X``: a step applied sample by sample (:func:`stepping_loop`).

    Attributes
    ----------
    run
        The loop itself.
    compiled
        Whether it runs native code (else CasADi's virtual machine).
    """

    run: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]
    compiled: bool

    def __call__(self, x0: np.ndarray, U: np.ndarray, dt: np.ndarray,
                 p: np.ndarray) -> np.ndarray:
        return self.run(x0, U, dt, p)


_WARNED: set[str] = set()


def _warn(message: str) -> None:
    """Warn once per process (code ``compile-cache``)."""
    if message not in _WARNED:
        _WARNED.add(message)
        warnings.warn(FcompWarning("compile-cache", message), stacklevel=3)


def cache_dir() -> Path | None:
    """The folder of compiled kernels, created user-only; ``None`` (with a warning) when it
    cannot be used or is not safe to load code from (module docstring)."""
    d = Path(os.environ.get("FCOMP_CACHE") or Path.home() / ".cache" / "fcomp")
    slower = "running without compiled kernels (slower, same results)"
    try:
        d.mkdir(mode=0o700, parents=True, exist_ok=True)
        st = d.stat()
    except OSError as exc:
        why = "a file, not a folder" if d.exists() and not d.is_dir() else exc.strerror or exc
        _warn(f"compile cache {d} is not usable ({why}); {slower}")
        return None
    if hasattr(os, "getuid") and st.st_uid != os.getuid():
        _warn(f"compile cache {d} belongs to another user, so fcomp does not load code from "
              f"it; {slower} (set FCOMP_CACHE to a folder of your own)")
        return None
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        _warn(f"compile cache {d} is writable by group or others, who could make fcomp run "
              f"their code; {slower} (chmod go-w {d})")
        return None
    return d


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _verified(lib: Path) -> bool:
    """Whether ``lib`` is ours, not writable by others, and matches its stored SHA-256."""
    try:
        st = lib.stat()
        if hasattr(os, "getuid") and st.st_uid != os.getuid():
            return False
        if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
            return False
        want = Path(f"{lib}.sha256").read_text().strip()
        return want == _digest(lib)
    except (OSError, UnicodeDecodeError):
        return False


@cache
def compiler() -> str | None:
    """The C compiler to use, or ``None`` (``FCOMP_JIT=0`` disables compiling)."""
    if os.environ.get("FCOMP_JIT", "1") == "0":
        return None
    for cand in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if cand and shutil.which(cand):
            return cand
    return None


#: A placeholder of a C template: ``@NAME@`` (capitals, digits, underscores).
_PLACEHOLDER = re.compile(r"@([A-Z][A-Z0-9_]*)@")


def c_source(name: str, values: Mapping[str, str]) -> str:
    """The C template ``fcomp/csrc/NAME`` (package data) with every placeholder ``@KEY@``
    replaced by ``values[KEY]`` (C text: a number, an array initialiser, a name).

    Raises :class:`ValueError` when the template has a placeholder ``values`` does not fill,
    or ``values`` fills one the template does not have (a stale name on either side).
    """
    text = resources.files("fcomp").joinpath("csrc", name).read_text(encoding="utf-8")
    found = set(_PLACEHOLDER.findall(text))
    if found != set(values):
        raise ValueError(f"C template {name}: placeholders {sorted(found)} but values for "
                         f"{sorted(values)}")
    return _PLACEHOLDER.sub(lambda m: values[m.group(1)], text)


def _build(step: ca.Function, nx: int, nu: int) -> ctypes.CDLL | None:
    driver = c_source("stepping_loop.c", {"STEP": step.name(), "NX": str(nx), "NU": str(nu)})
    return load_library(step, driver)


def casadi_c(fns: Sequence[ca.Function], name: str, options: Mapping[str, Any]
             ) -> dict[str, str]:
    """CasADi's C code of ``fns`` (:class:`casadi.CodeGenerator` with ``options``) as
    ``{file name: text}``: ``NAME.c``, and ``NAME.h`` when ``options`` ask
    ``with_header``. Generated in a scratch folder; nothing is written elsewhere."""
    cg = ca.CodeGenerator(f"{name}.c", dict(options))
    for f in fns:
        cg.add(f)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(f"{tmp}{os.sep}")
        return {f.name: f.read_text() for f in sorted(Path(tmp).iterdir())}


def build_library(fn: ca.Function | Sequence[ca.Function], driver: str, *,
                  rebuild: bool = False, prelude: str = "") -> Path | None:
    """Compile CasADi's C code of ``fn`` (one or several functions) followed by the C
    ``driver`` into a cached shared library (verified, see the module docstring).

    Returns the library path, or ``None`` without a working compiler or usable
    cache (callers then fall back to CasADi's virtual machine or a Python
    loop). ``rebuild`` compiles again even if the cache holds the library.
    ``prelude`` is C placed before CasADi's code (e.g. :data:`HIDDEN`).
    """
    if compiler() is None:
        return None
    fns = [fn] if isinstance(fn, ca.Function) else list(fn)
    name = fns[0].name()
    generated = casadi_c(fns, name, {"with_header": False, "casadi_real": "double"})
    return _compile_cached(name, prelude + generated[f"{name}.c"] + driver, rebuild)


def run_compiler(args: Sequence[str]) -> subprocess.CompletedProcess[str]:
    """Run a C compiler (or a program it built) with its output captured, in a process group
    of its own: the driver's ``cc1``, ``as`` and ``ld`` are its children, so on any
    interruption (Ctrl-C and SIGTERM arrive as :class:`KeyboardInterrupt`) or error the
    whole group is ended before the exception goes on -- a compiler's driver alone, killed,
    leaves its ``cc1`` running."""
    proc = subprocess.Popen(list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    try:
        out, err = proc.communicate()
    except BaseException:
        end_group(proc)
        raise
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def end_group(proc: subprocess.Popen[str]) -> None:
    """End the process group a :func:`run_compiler` child leads (SIGKILL) and reap it."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (OSError, AttributeError):  # gone already (or no process groups here)
        proc.kill()
    proc.communicate()


def _compile_cached(name: str, code: str, rebuild: bool) -> Path | None:
    """The C source ``code`` compiled into the cache as ``NAME_HASH.so`` (verified, module
    docstring); ``None`` without a working compiler or usable cache."""
    cc = compiler()
    if cc is None:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / f"{name}.c"
        key = hashlib.sha1((code + cc).encode()).hexdigest()[:16]
        cache = cache_dir()
        if cache is None:
            return None
        lib = cache / f"{name}_{key}.so"
        if not rebuild and _verified(lib):
            return lib
        src.write_text(code)
        out = Path(tmp) / "lib.so"
        proc = run_compiler([cc, "-O2", "-fPIC", "-shared", str(src), "-o", str(out), "-lm"])
        if proc.returncode != 0:
            return None  # a broken toolchain must not break the package: use the VM
        from fcomp.outputs import write_files

        try:
            data = out.read_bytes()
            write_files({lib: data, Path(f"{lib}.sha256"): hashlib.sha256(data).hexdigest()
                         + "\n"})
        except (OSError, FcompError) as exc:
            _warn(f"compile cache {cache} is not writable ({exc}); running without compiled "
                  "kernels (slower, same results)")
            return None
        os.chmod(lib, 0o700)
        return lib


def load_library(fn: ca.Function | Sequence[ca.Function], driver: str, *,
                 prelude: str = "") -> ctypes.CDLL | None:
    """:func:`build_library`, loaded with :mod:`ctypes`; a cached library that does not load
    (corrupted on disk) is rebuilt once. ``None``: use the virtual machine."""
    return _loaded(lambda rebuild: build_library(fn, driver, rebuild=rebuild, prelude=prelude))


def load_c(name: str, code: str) -> ctypes.CDLL | None:
    """The plain C source ``code`` (no CasADi function) compiled into the cache as ``name``
    and loaded with :mod:`ctypes`, as :func:`load_library` does; ``None`` without a compiler
    or usable cache (callers then run their numpy or scipy equivalent)."""
    return _loaded(lambda rebuild: _compile_cached(name, code, rebuild))


def _loaded(build: Callable[[bool], Path | None]) -> ctypes.CDLL | None:
    """``build(rebuild)``'s library loaded; rebuilt once if the cached one does not load."""
    for rebuild in (False, True):
        lib = build(rebuild)
        if lib is None:
            return None
        try:
            return ctypes.CDLL(str(lib))
        except OSError:
            continue
    _warn("a compiled kernel does not load even after rebuilding it; running without "
          "compiled kernels (slower, same results)")
    return None


def stepping_loop(step: ca.Function, *, compiled: bool = True, chunk: int = 4096) -> Loop:
    """A loop ``run(x0, U, dt, p) -> X`` applying ``step(x, u, dt, p)`` sample by sample.

    ``U`` is ``(n, nu)``, ``dt`` ``(n,)``, ``p`` ``(np,)``; the result ``X`` is
    ``(n + 1, nx)`` with ``X[0] = x0``.
    """
    nx = step.size1_in(0)
    nu = step.size1_in(1)
    dll = _build(step, nx, nu) if compiled else None
    if dll is not None:
        fn = dll.fcomp_loop
        # addresses as plain integers: a ``data_as`` pointer object costs microseconds a
        # call, which a loop of one sample (a stepper's interval) pays on every call
        fn.argtypes = [ctypes.c_int] + [ctypes.c_void_p] * 5
        fn.restype = ctypes.c_int

        def run(x0: np.ndarray, U: np.ndarray, dt: np.ndarray, p: np.ndarray) -> np.ndarray:
            n = dt.size
            x0c = np.ascontiguousarray(x0, dtype=float)
            Uc = np.ascontiguousarray(U, dtype=float).reshape(n, nu)
            dtc = np.ascontiguousarray(dt, dtype=float)
            pc = np.ascontiguousarray(p, dtype=float)
            X = np.empty((n + 1, nx))
            err = fn(n, x0c.ctypes.data, Uc.ctypes.data, dtc.ctypes.data, pc.ctypes.data,
                     X.ctypes.data)
            if err:
                raise RuntimeError(f"compiled step failed at sample {err}")
            return X

        return Loop(run, True)

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

    return Loop(run_vm, False)


class Keyed(Generic[T]):
    """``value`` hashed and compared by ``key`` alone: the argument of a bounded kernel cache
    (:func:`functools.lru_cache`), so that values with equal keys (models of one structure)
    share their kernel, built from the first one seen, and the cache holds no more than
    its size."""

    __slots__ = ("key", "value")

    def __init__(self, value: T, key: Hashable) -> None:
        self.value = value
        self.key = key

    def __hash__(self) -> int:
        return hash(self.key)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Keyed) and self.key == other.key
