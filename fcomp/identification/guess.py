"""Initial parameter values read off the data (the start of every fit).

* **Levels, mass, offset** -- linear least squares on the moving samples
  (``|v| >= v_min``) of ``y = Fc*sign(v) + B*v [+ mass*(a + g*s_o)] [+ offset]``
  (separate ``Fc``/``B`` per direction for direction-dependent fits): the
  inverse-model regression used for the EMPS benchmark (IDIM-LS, Janot et al.).
* **Stribeck hump** -- ``Fs`` is the largest binned ``sign(v)*f - B*|v|`` at low
  speed (``f`` the friction estimate), ``vs`` the speed at which the excess
  over ``Fc`` has decayed to ``1/e`` of its peak
  (:func:`fcomp.effects.record.stribeck_start`).
* **Bristle stiffness** -- after each velocity reversal the LuGre force moves
  from ``-g`` to ``+g`` along ``dF/dx = sigma0*(1 + F/g)`` (from
  ``dz/dt = v - sigma0*|v|*z/g`` at constant ``g``), so it crosses zero after a
  displacement ``ln(2)*g/sigma0``: ``sigma0 = ln(2)*g/dx_half``, median over
  reversals.
* **Bristle damping** -- small: ``sigma1 = 0.1*Fc/median|v|`` (its term is a
  tenth of the Coulomb level at typical speed).

Everything else (film time constants, ``vb``, ``T``, ``n``) starts from the
model's current values.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# the Stribeck hump lives with the effects, whose guesses read it too (re-exported here)
from fcomp.effects.record import stribeck_start as stribeck_start
from fcomp.identification.target import FitData


def default_v_min(v: np.ndarray) -> float:
    """Speed below which a sample counts as 'at rest' for static fits: 2 % of the 99th
    percentile of ``|v|`` (m/s)."""
    top = float(np.percentile(np.abs(v), 99.0)) if v.size else 0.0
    return 0.02 * top if top > 0 else 1e-12


@dataclass(frozen=True)
class LinearStart:
    """Result of the linear regression (see the module docstring)."""

    Fc: tuple[float, float]   # (v > 0, v < 0) magnitudes, N
    B: tuple[float, float]    # Ns/m
    mass: float | None        # kg
    offset: float             # N
    friction: np.ndarray      # y - mass*inertia - offset, N


def linear_start(d: FitData, v_min: float, *, offset: bool, directional: bool,
                 viscous: bool = True) -> LinearStart:
    """Coulomb(-viscous) levels, mass and offset by linear least squares on moving samples.

    ``viscous=False`` leaves the ``B*v`` column out (``B`` is then reported as 0).
    """
    v = d.sig["v"]
    moving = np.abs(v) >= v_min
    if moving.sum() < 4:
        raise ValueError(f"{d.label}: fewer than 4 samples move faster than {v_min:.3g} m/s")
    pos = (v > 0).astype(float)
    neg = (v < 0).astype(float)
    cols: list[np.ndarray] = []
    cols += [pos, -neg] if directional else [np.sign(v)]
    if viscous:
        cols += [v * pos, v * neg] if directional else [v]
    if d.inertia is not None:
        cols.append(d.inertia)
    if offset:
        cols.append(np.ones_like(v))
    A = np.column_stack(cols)[moving]
    coef, *_ = np.linalg.lstsq(A, d.y[moving], rcond=None)
    i = 2 if directional else 1
    Fc = (coef[0], coef[i - 1])
    B = (0.0, 0.0)
    if viscous:
        B = (coef[i], coef[i + 1]) if directional else (coef[i], coef[i])
        i += 2 if directional else 1
    mass = None
    if d.inertia is not None:
        mass = float(max(coef[i], 0.0))
        i += 1
    off = float(coef[i]) if offset else 0.0
    fric = d.y - (0.0 if mass is None else mass * d.inertia) - off  # type: ignore[operator]
    scale = float(np.median(np.abs(d.y[moving]))) or 1.0
    Fc = tuple(max(float(c), 1e-3 * scale) for c in Fc)  # type: ignore[assignment]
    B = tuple(max(float(b), 0.0) for b in B)  # type: ignore[assignment]
    return LinearStart(Fc, B, mass, off, fric)  # type: ignore[arg-type]


