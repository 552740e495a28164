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

import numpy as np

from fcomp.errors import FcompError, FcompWarning, term
from fcomp.measurement import check_values
from fcomp.parameters import MAX_VALUE
from fcomp.textdata import check_path, data_rows, header_names, parse_rows, read_text

KINDS = ("sine", "step", "csv")


@dataclass(frozen=True)
class InputSignal:
    """A parsed input: ``signal(t)`` evaluates it on an array of times (s)."""

    spec: str
    kind: str
    fn: Callable[[np.ndarray], np.ndarray]
    #: sine: its frequency (Hz)
    frequency: float = 0.0
    #: csv: the smallest sampling interval of the file (s)
    interval: float | None = None

    def __call__(self, t: np.ndarray | float) -> np.ndarray:
        return self.fn(np.asarray(t, dtype=float))


def _bad(spec: str, what: str) -> FcompError:
    """The error of a malformed input SPEC (the CLI's ``--input``)."""
    return FcompError(f"{term('input')} {spec!r}: {what}")


def _kv(body: str, spec: str, allowed: dict[str, float | None]) -> dict[str, float]:
    out: dict[str, float] = {}
    if body.strip():
        for part in body.split(","):
            if "=" not in part:
                raise _bad(spec, f"expected key=value, got {part!r}")
            k, val = (s.strip() for s in part.split("=", 1))
            if k in out:
                raise _bad(spec, f"{k} is given twice")
            if k not in allowed:
                raise _bad(spec, f"unknown key {k!r}; allowed: {', '.join(allowed)}")
            try:
                f = float(val)
            except ValueError:
                raise _bad(spec, f"{k} = {val!r} is not a number") from None
            if not math.isfinite(f):
                raise _bad(spec, f"{k} must be a finite number")
            if abs(f) > MAX_VALUE:
                raise _bad(spec, f"{k} = {val} is beyond any plausible value in SI units")
            out[k] = f
    for k, default in allowed.items():
        if k not in out:
            if default is None:
                raise _bad(spec, f"missing {k}=...")
            out[k] = default
    return out


def parse_input(spec: str) -> InputSignal:
    """Parse an input SPEC (see the module docstring); :class:`FcompError` if malformed."""
    if ":" not in spec:
        raise _bad(spec, f"expected KIND:..., KIND one of {', '.join(KINDS)} "
                   "(e.g. sine:amplitude=0.01,frequency=1)")
    kind, body = spec.split(":", 1)
    kind = kind.strip()
    if kind == "sine":
        p = _kv(body, spec, {"amplitude": None, "frequency": None, "offset": 0.0, "phase": 0.0})
        if p["frequency"] < 0:
            raise _bad(spec, "frequency must be >= 0 Hz")
        A, f, o, ph = p["amplitude"], p["frequency"], p["offset"], p["phase"]
        return InputSignal(spec, kind, lambda t: o + A * np.sin(2 * np.pi * f * t + ph),
                           frequency=f)
    if kind == "step":
        p = _kv(body, spec, {"amplitude": None, "time": 0.0, "initial": 0.0})
        A, t0, u0 = p["amplitude"], p["time"], p["initial"]
        return InputSignal(spec, kind, lambda t: np.where(t >= t0, A, u0) + 0.0 * t)
    if kind == "csv":
        return _csv_input(spec, body)
    raise _bad(spec, f"unknown input kind {kind!r}; known: {', '.join(KINDS)}")


def _csv_input(spec: str, body: str) -> InputSignal:
    path = check_path(body.strip(), "input file")
    label = str(path)
    text = read_text(path, label, what="CSV numbers")
    names, start = header_names(label, text)
    if "t" not in names or "u" not in names:
        raise FcompError(f"{path}: needs a header line with columns t,u (got {','.join(names)})")
    table = parse_rows(label, data_rows(text, start), ",", names, what="CSV numbers")
    data, lines = table.data, table.lines
    cols = {n: data[:, names.index(n)] for n in ("t", "u")}
    check_values(cols, label, lines)
    t, u = cols["t"], cols["u"]
    if t.size < 2:
        raise FcompError(f"{path}: needs at least two samples of t,u")
    return InputSignal(spec, "csv", lambda tq: np.interp(tq, t, u),
                       interval=float(np.min(np.diff(t))))


def sampling_warning(signal: InputSignal, rate: float) -> FcompWarning | None:
    """An ``aliasing`` warning when ``signal`` has content the output ``rate`` (Hz) cannot
    represent (plants see the input at the output instants): a sine above the
    Nyquist frequency ``rate/2``, or a ``csv:`` signal sampled more finely than
    the output; ``None`` when it has none."""
    text = _aliasing(signal, rate)
    return None if text is None else FcompWarning("aliasing", text)


def _aliasing(signal: InputSignal, rate: float) -> str | None:
    nyquist = rate / 2.0
    if signal.kind == "sine" and signal.frequency > nyquist:
        return (f"the input sine at {signal.frequency:g} Hz is above the Nyquist frequency "
                f"{nyquist:g} Hz of {term('rate')} {rate:g}: the plant sees it aliased to "
                f"{_alias(signal.frequency, rate):g} Hz; raise {term('rate')} above "
                f"{2 * signal.frequency:g} Hz")
    if signal.kind == "csv" and signal.interval is not None and signal.interval < 0.5 / rate:
        return (f"the input file is sampled every {signal.interval:g} s, finer than the output "
                f"interval {1 / rate:g} s; the plant sees it only at the output instants "
                f"(content above the Nyquist frequency aliases); raise {term('rate')}")
    return None


def _alias(f: float, rate: float) -> float:
    r = math.fmod(f, rate)
    return min(r, rate - r)
