"""Input signals from a SPEC string (public contract of ``fcomp simulate``).

``SPEC`` is one of

* ``sine:amplitude=A,frequency=F[,offset=O,phase=PHI]`` -- ``O + A*sin(2*pi*F*t + PHI)``
  (``PHI`` in rad);
* ``step:amplitude=A[,time=T0,initial=U0]`` -- ``U0`` before ``T0`` (default 0 s), ``A`` after;
* ``csv:PATH`` -- a file with columns ``t,u`` (header line), linearly interpolated,
  held constant outside its time range.

Units are those of the plant input (m/s for ``motion``, A for ``hydraulic``, ...).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fcomp.errors import FcompError

KINDS = ("sine", "step", "csv")


@dataclass(frozen=True)
class InputSignal:
    """A parsed input: ``signal(t)`` evaluates it on an array of times (s)."""

    spec: str
    kind: str
    fn: Callable[[np.ndarray], np.ndarray]

    def __call__(self, t: np.ndarray | float) -> np.ndarray:
        return self.fn(np.asarray(t, dtype=float))


def _kv(body: str, spec: str, allowed: dict[str, float | None]) -> dict[str, float]:
    out: dict[str, float] = {}
    if body.strip():
        for part in body.split(","):
            if "=" not in part:
                raise FcompError(f"--input {spec!r}: expected key=value, got {part!r}")
            k, val = (s.strip() for s in part.split("=", 1))
            if k not in allowed:
                raise FcompError(
                    f"--input {spec!r}: unknown key {k!r}; allowed: {', '.join(allowed)}"
                )
            try:
                f = float(val)
            except ValueError:
                raise FcompError(f"--input {spec!r}: {k} = {val!r} is not a number") from None
            if not math.isfinite(f):
                raise FcompError(f"--input {spec!r}: {k} must be finite")
            out[k] = f
    for k, default in allowed.items():
        if k not in out:
            if default is None:
                raise FcompError(f"--input {spec!r}: missing {k}=...")
            out[k] = default
    return out


def parse_input(spec: str) -> InputSignal:
    """Parse an input SPEC (see the module docstring); :class:`FcompError` if malformed."""
    if ":" not in spec:
        raise FcompError(
            f"--input {spec!r}: expected KIND:..., KIND one of {', '.join(KINDS)} "
            "(e.g. sine:amplitude=0.01,frequency=1)"
        )
    kind, body = spec.split(":", 1)
    kind = kind.strip()
    if kind == "sine":
        p = _kv(body, spec, {"amplitude": None, "frequency": None, "offset": 0.0, "phase": 0.0})
        if p["frequency"] < 0:
            raise FcompError(f"--input {spec!r}: frequency must be >= 0 Hz")
        A, f, o, ph = p["amplitude"], p["frequency"], p["offset"], p["phase"]
        return InputSignal(spec, kind, lambda t: o + A * np.sin(2 * np.pi * f * t + ph))
    if kind == "step":
        p = _kv(body, spec, {"amplitude": None, "time": 0.0, "initial": 0.0})
        A, t0, u0 = p["amplitude"], p["time"], p["initial"]
        return InputSignal(spec, kind, lambda t: np.where(t >= t0, A, u0) + 0.0 * t)
    if kind == "csv":
        return _csv_input(spec, body)
    raise FcompError(f"--input {spec!r}: unknown input kind {kind!r}; known: {', '.join(KINDS)}")


def _csv_input(spec: str, body: str) -> InputSignal:
    path = Path(body.strip())
    if not path.is_file():
        raise FcompError(f"--input {spec!r}: file {path} not found")
    try:
        with path.open() as fh:
            header = [h.strip() for h in fh.readline().strip().split(",")]
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except (ValueError, UnicodeDecodeError) as exc:
        raise FcompError(f"{path}: cannot read as CSV numbers ({str(exc).splitlines()[0]})") from None
    if "t" not in header or "u" not in header:
        raise FcompError(f"{path}: needs a header line with columns t,u (got {','.join(header)})")
    if data.shape[1] != len(header) or data.shape[0] < 1:
        raise FcompError(f"{path}: rows do not match the header")
    t = data[:, header.index("t")]
    u = data[:, header.index("u")]
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(u))):
        raise FcompError(f"{path}: non-finite values in t or u")
    if np.any(np.diff(t) <= 0):
        raise FcompError(f"{path}: time column t must be strictly increasing")
    return InputSignal(spec, "csv", lambda tq: np.interp(tq, t, u))
