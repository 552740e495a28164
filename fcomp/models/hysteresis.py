"""NMLGM with a hysteresis function: seed 000's "new model" (models.md 1.6).

Equations (seed 000 Eqs. 10-13)
===============================
The bristle force ``sigma0*z`` of the NMLGM (:mod:`fcomp.models.lugre_family`)
is replaced by a hysteresis function ``F(z)`` with nonlocal memory::

    dz/dt = v - F(z)*|v|/g(v, h)                          (Eq. 10)
    F     = F(z) + sigma1*dz/dt + sigma2*(v + T*dv/dt)    (Eq. 11)
    F(z)  = sigma0*z  for |z| >= Fs/sigma0 (sliding)      (Eq. 12)
          = f_i(z)    otherwise (pre-sliding)
    f_i(z) = f_i(z_i) + c_i*(1 - exp(-k_i*(z - z_i)))     (Eq. 13)

``g``, ``h`` (film state), ``h_ss``, ``tau_h`` and the lead ``T`` are those of
the family (they are inherited, not rewritten): in code ``F(z)`` enters the
family equations exactly where ``sigma0*z`` does, through the bristle
deflection ``F(z)/sigma0``. SI units throughout: ``z`` in m, forces in N,
``k_i`` in 1/m.

Transition curves (seed 000 "Identification of f(z)", Tables 2-3)
=================================================================
Each velocity reversal starts a *transition curve* at the reversal point
``(z_r, F_r)``. The seed identified the external loop of cylinder 1 between
the reversals ``z = -z1`` and ``z = z5`` (Table 2, read as metres, see
:mod:`fcomp.paramsets`):

* ascending (``dz > 0``): segments ``[-z1, 0]``, ``[0, z3]``, ``[z3, z5]`` with
  ``(c1, k1)``, ``(c2, k2)``, ``(c3, k3)``;
* descending: segments ``[z4, z5]``, ``[z2, z4]``, ``[-z1, z2]`` (in the order
  they are traversed from ``z5``) with ``c4..6 = -c1..3``, ``k4..6 = -k1..3``
  (the seed's mirror rule);
* internal loops: one segment each, ``(c8, k8)`` ascending and
  ``c7 = -c8, k7 = -k8`` descending, identified over ``[zc, zd]`` (Fig. 18).

Every curve is written as ``F = F_r + d*lam*Phi(Delta)`` with ``d = +1``
(ascending) or ``-1`` (descending), ``Delta = d*(z - z_r) >= 0`` the travel
since the reversal and ``Phi`` the *raw shape*: the chain of Eq. 13 segments
with ``f_i(z_i)`` equal to the end of the previous segment. Choices made
where the seed is silent, each stated with its reason:

1. **Segment boundaries relative to the reversal (Masing's rule).** The
   segment widths are those of the identified loop: ``z1, z3, z5 - z3``
   ascending, ``z5 - z4, z4 - z2, z2 + z1`` descending, ``zd - zc`` internal.
   For the seed's own loop (reversals at ``-z1`` and ``z5``) this *is* Table 2;
   for any other reversal point the curve keeps the seed's shape, starting
   steep (``c1*k1`` = 6e5 N/m) as every measured curve does after a reversal.
2. **Beyond the identified range the curve continues with the bristle
   stiffness** ``sigma0`` (slope ``lam*sigma0``): outside the deflection range
   the seed measured, the bristles are the NMLGM bristles. Without this the
   exponentials saturate ~5.5 N from the reversal (Table 3: ``c1+c2+c3``),
   ``z`` would run on at a plateau up to ``Fs/sigma0`` = 1.5 mm and the force
   would jump by about 19 N there (cylinder 1); after a reversal from sliding
   the friction would then *aid* the motion for ~3 mm. With the continuation
   the seed's observation that loops grow with the excursion (Fig. 12) holds,
   and the force reaches the sliding level ``g(v, h)`` through Eq. 10 itself,
   as in LuGre: the steady state is ``F(z) = sign(v)*g``, i.e. seed Eq. 9.
   The external loop's average stiffness, 5.49 N over 0.354 mm = 1.55e4 N/m,
   equals ``sigma0`` = 1.5e4 N/m of Table 4 to 3 %, so the continuation is the
   seed's own stiffness.
3. **Shape classes.** A curve that starts at a *global* extreme of the
   memory (the first two reversals after the virgin state, the first after
   leaving sliding, and every reversal beyond a point that was wiped out)
   uses the external shape; a curve that starts inside the memorised range
   is an internal loop (Fig. 16) and uses the ``c8, k8`` shape. "Inside"
   means short of the memorised extreme of the same kind by more than the
   width of the seed's internal loop, ``zd - zc`` (19 um for cylinder 1):
   the class, and with it the curve's shape, must not flip between two
   nearly equal cycles because one reversal falls a nanometre short of the
   previous one (repeated displacement cycles re-centre ``z`` slowly through
   Eq. 10 and would otherwise alternate between the two shapes).
4. **Return-point memory by affine scaling** (Preisach/Madelung rule). A curve
   with a *target* (the previous opposite reversal point still in memory) is
   scaled, ``lam = |F_t - F_r|/Phi(Delta_t)``, so that it passes exactly
   through the target; curves without a target use the raw shape,
   ``lam = 1``. With the raw Table 3 numbers the external ascending curve
   rises 5.486 N from ``-z1`` to ``z5`` but the descending one falls only
   5.399 N back, so unscaled curves would drift 0.087 N per closed cycle;
   with the scaling a closed deflection cycle returns to its start exactly.
5. **Memory rules** (seed 000 Figs. 15-16; Madelung's rules). A turning-point
   stack holds the reversal points. A reversal pushes the current point and
   starts a curve towards the previous reversal point. When the deflection
   reaches a curve's target the loop is closed and removed from memory
   (*wiping-out*): the state continues exactly on the outer curve it left,
   which passes through the target by construction. So minor loops close,
   an inner loop leaves no trace, the curve returns to every memorised
   reversal point (return-point memory) and a closed deflection cycle gives a
   closed force cycle (no drift).
6. **Virgin state** (the model's initial state ``z = 0, F = 0``; Masing's
   initial-loading rule). The seed gives no initial-loading curve. From the
   virgin state the deflection follows the *virgin curve*, the external
   shape halved, ``Phi(2*Delta)/2``, in the direction of motion, so that a
   symmetric cycle ``+-A`` about the virgin point has the external shapes.
   The first reversal ``A`` targets the mirror point ``(-A, virgin value)`` on
   the virgin curve of the other direction, and continues on that curve once
   it passes it (the extended Masing rules; the Preisach picture of a
   demagnetised start). Tiny loops near the start (noise) are therefore
   wiped out by larger excursions instead of being remembered forever.
7. **Direction.** The branch (ascending or descending) is the direction of
   ``dz/dt``, which equals ``sign(v)`` whenever ``|F(z)| < g`` (all of
   pre-sliding); using ``dz`` keeps ``F`` a rate-independent function of the
   deflection history even where ``F(z)`` reaches ``g`` while sliding.
8. **Sliding (Eq. 12).** When ``|z|`` reaches ``Fs/sigma0`` (``Fs`` of the side
   of the motion, after effects; ``Fc/sigma0`` for models without ``Fs``) the
   model switches to the NMLGM: ``F(z) = sigma0*z`` and the memory is
   cleared. This is latched until the next velocity reversal (otherwise the
   relaxation of ``sigma0*z`` towards ``g`` would bring ``|z|`` back below the
   threshold at once and the model would chatter between the regimes). At
   the reversal a new external curve starts at ``(z, sigma0*z)``; that point
   is kept as the root of the memory, so returning past it re-enters the
   sliding law it left (the outermost "curve"). The switch keeps ``z``, as
   the seed does, so the force jumps by ``sigma0*z - F(z)``. With rule 2 this
   is the offset of the curve's tail from the line ``sigma0*z``: for
   cylinder 1, from a point on the line, the external ascending tail lies
   ``Phi_a(z1 + z5) - sigma0*(z1 + z5)`` = 0.176 N above the line (the force
   drops by 0.176 N at the switch) and the descending tail 0.089 N below it
   (the force magnitude drops by 0.089 N); on the virgin curve half of that.
   That is <1 % of ``Fs``, and since ``g <= Fs`` the force usually reaches
   ``g`` before ``|z|`` reaches the threshold, so the switch is rarely met.
   (Without rule 2 the jump would be about 19 N.)
9. **Bounded memory.** At most :data:`MAX_POINTS` points are kept; when the
   stack is full the innermost loop is forgotten (its two points removed;
   the new curve then targets the next outer reversal point). Force stays
   continuous; only return-point memory of loops nested deeper than that is
   lost.

Defaults: the model's hysteresis parameters default to seed 000 Tables 2-3
(cylinder 1); :data:`NONLOCAL_MEMORY_DEFAULTS` are zero segment widths and
amplitudes, for which every transition curve is its continuation
``F_r + d*sigma0*Delta``: starting from ``F_r = sigma0*z_r`` this is
``sigma0*z`` itself, so the model is then exactly the LuGre-family model it
was built from (the no-op of the ``nonlocal-memory`` effect).

Behaviour worth knowing: a closed *deflection* cycle closes the force loop
exactly; under a closed *displacement* cycle ``z`` itself is re-centred
slowly by Eq. 10 (``dz/dx = 1 - sign(v)*F(z)/g``: a loop whose mean force is
not zero shifts ``z``), for cylinder 1 at +-0.15 mm over some 100-200 cycles,
and loops whose travel is close to ``z1 + z3`` (where segment 3 rises 1.8 N
within a few micrometres) change visibly with small changes of travel.
``friction_along_motion(..., state0=...)`` starts a virgin memory at that
state: the memory is not carried from one call to the next (use
:meth:`HysteresisFamily.stepper` to continue a simulation).

Numerics
========
Between samples the velocity is held at its interval mean and ``g`` at its
value for the film state at the start of the interval (as in
:mod:`fcomp.trajectory`). On each segment of a curve Eq. 10 is then a linear
ODE in a transformed coordinate (``exp(k*u)`` on an exponential segment,
``u`` on a linear one), solved *exactly*, including the instants at which a
segment ends, a target is reached or the sliding threshold is met. The
film state ``h`` and effect states do not depend on ``z``; they are
integrated by the compiled family model (the *carrier*). Pure Python per
sample (~10 us).

The memory is discrete, so the model has no symbolic (CasADi) form: it
answers :meth:`~fcomp.models.base.FrictionModel.discrete_memory` with itself
(``symbolic`` is false); :meth:`casadi_functions` and :meth:`rhs` raise
:class:`~fcomp.models.base.NotSymbolicError`. Callers ask for that capability:
:func:`fcomp.trajectory.friction_along_motion` then calls
:meth:`HysteresisFamily.integrate_motion`, the plants couple the memory to
their engine (:mod:`plants.discrete_memory`), identification differentiates
by finite differences; the stateful :class:`HysteresisStepper`
(``model.stepper()``) steps it one interval at a time.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

from fcomp.backend import NUMPY, Backend
from fcomp.compiled import Loop
from fcomp.errors import ConvergenceError, FcompError
from fcomp.models.base import SIGNAL_NAMES, NotSymbolicError, Signals
from fcomp.models.lugre_family import PRESETS, LuGreFamily, Structure, family_class, params_class
from fcomp.models.stepping import midpoint_signals, step_loop
from fcomp.parameters import ParamSet, ParamSpec, ParamValues, make_params_class, spec, with_recipe
from fcomp.stepper import SampledStepper

INF = math.inf

#: Maximum number of reversal points kept in memory (rule 9 of the module docstring).
MAX_POINTS = 128

#: ``k*width`` beyond which an exponential segment is continued as a flat one
#: (the neglected change is ``c*exp(-40)`` ~ 4e-18*c).
_EXP_CAP = 40.0

#: Relative force deadband for "already at the sliding level" (rounding only).
_DEADBAND = 1e-12


def _hyst_spec(name: str, unit: str, default: float, doc: str, *, positive: bool = False) -> ParamSpec:
    return spec(name, unit, default, 0.0, INF, doc, directional=False, lower_open=positive)


#: Seed 000 Table 2 (boundaries, metres) and Table 3 (segment parameters), cylinder 1.
SEED_DEFAULTS: dict[str, float] = {
    "c1": 2.0, "k1": 3.0e5, "c2": 1.7, "k2": 3.0e4, "c3": 1.8, "k3": 3.4e5,
    "c8": 4.05, "k8": 1.8e5,
    "z1": 1.25e-4, "z2": 0.84e-4, "z3": 1.59e-4, "z4": 1.78e-4, "z5": 2.29e-4,
    "internal_zc": 2.46e-4, "internal_zd": 2.65e-4,
}

#: No-op values: zero widths and amplitudes, every curve is the line ``sigma0*z``.
NONLOCAL_MEMORY_DEFAULTS: dict[str, float] = {
    **{k: v for k, v in SEED_DEFAULTS.items() if k.startswith("k")},
    **{k: 0.0 for k in SEED_DEFAULTS if not k.startswith("k")},
}

_HYST_DOCS: dict[str, tuple[str, str, bool]] = {
    "c1": ("N", "amplitude of segment 1 (ascending, steep start; c4 = -c1)", False),
    "k1": ("1/m", "rate of segment 1 (k4 = -k1)", True),
    "c2": ("N", "amplitude of segment 2 (c5 = -c2)", False),
    "k2": ("1/m", "rate of segment 2 (k5 = -k2)", True),
    "c3": ("N", "amplitude of segment 3 (c6 = -c3)", False),
    "k3": ("1/m", "rate of segment 3 (k6 = -k3)", True),
    "c8": ("N", "amplitude of the internal-loop curve (c7 = -c8)", False),
    "k8": ("1/m", "rate of the internal-loop curve (k7 = -k8)", True),
    "z1": ("m", "external loop: ascending segment 1 spans [-z1, 0]", False),
    "z2": ("m", "external loop: descending segments split at z2", False),
    "z3": ("m", "external loop: ascending segments 2/3 split at z3", False),
    "z4": ("m", "external loop: descending segments 4/5 split at z4", False),
    "z5": ("m", "external loop: upper reversal point", False),
    "internal_zc": ("m", "internal loop of Fig. 18: lower deflection", False),
    "internal_zd": ("m", "internal loop of Fig. 18: upper deflection", False),
}

HYSTERESIS_NAMES: tuple[str, ...] = tuple(_HYST_DOCS)

#: Order constraints (segment widths must not be negative).
HYSTERESIS_CONSTRAINTS: tuple[tuple[str, str], ...] = (
    ("z3", "z5"), ("z2", "z4"), ("z4", "z5"), ("internal_zc", "internal_zd"),
)


def hysteresis_specs(defaults: Mapping[str, float]) -> list[ParamSpec]:
    """Specs of the hysteresis-function parameters with the given defaults (SI units)."""
    return [_hyst_spec(n, unit, float(defaults[n]), doc + " (seed 000 Tables 2-3)", positive=pos)
            for n, (unit, doc, pos) in _HYST_DOCS.items()]


# ---------------------------------------------------------------- curve shapes
@dataclass(frozen=True)
class CurveShape:
    """The raw shape ``Phi(Delta)`` of a transition curve (N), ``Delta >= 0`` the travel (m).

    A chain of pieces starting at ``starts[j]`` with value ``values[j]``:
    exponential, ``values[j] + c[j]*(1 - exp(-k[j]*u))`` (seed 000 Eq. 13), or
    linear, ``values[j] + slope[j]*u``, with ``u = Delta - starts[j]``. The last
    piece is the continuation with the bristle stiffness (slope ``sigma0``).
    """

    starts: tuple[float, ...]
    values: tuple[float, ...]
    c: tuple[float, ...]
    k: tuple[float, ...]
    slope: tuple[float, ...]

    @classmethod
    def build(cls, segments: Sequence[tuple[float, float, float]], tail_slope: float) -> CurveShape:
        """Chain ``(width, c, k)`` segments (Eq. 13, each starting where the last ended)."""
        starts: list[float] = []
        values: list[float] = []
        cs: list[float] = []
        ks: list[float] = []
        slopes: list[float] = []
        d0 = phi = 0.0

        def add(width: float, c: float, k: float, slope: float, gain: float) -> None:
            nonlocal d0, phi
            starts.append(d0)
            values.append(phi)
            cs.append(c)
            ks.append(k)
            slopes.append(slope)
            d0 += width
            phi += gain

        for width, c, k in segments:
            if width <= 0.0:
                continue
            if c == 0.0:
                add(width, 0.0, 0.0, 0.0, 0.0)
                continue
            w_exp = min(width, _EXP_CAP / k)
            add(w_exp, c, k, 0.0, -c * math.expm1(-k * w_exp))
            if width > w_exp:  # saturated remainder: flat
                add(width - w_exp, 0.0, 0.0, 0.0, 0.0)
        starts.append(d0)
        values.append(phi)
        cs.append(0.0)
        ks.append(0.0)
        slopes.append(tail_slope)
        return cls(tuple(starts), tuple(values), tuple(cs), tuple(ks), tuple(slopes))

    def piece(self, delta: float) -> int:
        """Index of the piece containing ``delta``."""
        j = len(self.starts) - 1
        while j > 0 and self.starts[j] > delta:
            j -= 1
        return j

    def value(self, delta: float) -> float:
        """``Phi(delta)`` (N)."""
        j = self.piece(delta)
        u = delta - self.starts[j]
        if self.k[j]:
            return self.values[j] - self.c[j] * math.expm1(-self.k[j] * u)
        return self.values[j] + self.slope[j] * u

    @property
    def identified_range(self) -> float:
        """Travel over which the seed's segments apply (m); the continuation follows."""
        return self.starts[-1]

    def halved(self) -> CurveShape:
        """Masing's initial-loading curve ``Phi_v(Delta) = Phi(2*Delta)/2`` of this shape."""
        return CurveShape(tuple(s / 2.0 for s in self.starts), tuple(v / 2.0 for v in self.values),
                          tuple(c / 2.0 for c in self.c), tuple(2.0 * k for k in self.k),
                          self.slope)


@dataclass(frozen=True)
class CurveShapes:
    """The raw shapes: external ascending and descending, internal, and the virgin curves."""

    ascending: CurveShape
    descending: CurveShape
    internal: CurveShape
    virgin_ascending: CurveShape
    virgin_descending: CurveShape
    internal_width: float

    @classmethod
    def from_values(cls, values: Mapping[str, float]) -> CurveShapes:
        """Shapes from flat parameter values (``c1..k8``, ``z1..z5``, ``internal_z*``, ``sigma0``)."""
        p = {n: float(values[n]) for n in (*HYSTERESIS_NAMES, "sigma0")}
        s1, s2, s3 = (p["c1"], p["k1"]), (p["c2"], p["k2"]), (p["c3"], p["k3"])
        tail = p["sigma0"]
        asc = [(p["z1"], *s1), (p["z3"], *s2), (p["z5"] - p["z3"], *s3)]
        desc = [(p["z5"] - p["z4"], *s1), (p["z4"] - p["z2"], *s2), (p["z2"] + p["z1"], *s3)]
        internal = [(p["internal_zd"] - p["internal_zc"], p["c8"], p["k8"])]
        a, b = CurveShape.build(asc, tail), CurveShape.build(desc, tail)
        return cls(a, b, CurveShape.build(internal, tail), a.halved(), b.halved(),
                   p["internal_zd"] - p["internal_zc"])

    def external(self, d: int) -> CurveShape:
        """External-loop shape of direction ``d`` (+1 ascending)."""
        return self.ascending if d > 0 else self.descending

    def virgin(self, d: int) -> CurveShape:
        """Initial-loading (virgin) shape of direction ``d``."""
        return self.virgin_ascending if d > 0 else self.virgin_descending


# -------------------------------------------------------------- linear ODE help
def _phi1(x: float) -> float:
    return math.expm1(x) / x if abs(x) > 1e-12 else 1.0 + 0.5 * x


def _time_to(A: float, rate0: float, dy: float) -> float:
    """Time for ``dy/dt = A*y + B`` (``rate0`` = dy/dt now) to advance ``y`` by ``dy >= 0``."""
    if dy <= 0.0:
        return 0.0
    if rate0 <= 0.0 or math.isinf(dy):
        return INF
    q = A * dy / rate0
    if q <= -1.0:
        return INF
    return dy / rate0 * (math.log1p(q) / q if abs(q) > 1e-12 else 1.0 - 0.5 * q)


# --------------------------------------------------------------------- memory
class HysteresisFunction:
    """The hysteresis function ``F(z)`` with its turning-point memory (seed 000 Eqs. 12-13).

    Rules: module docstring (Masing shapes and virgin curve, affine
    return-point scaling, Madelung wiping-out, sliding latch). Two ways to
    drive it:

    * :meth:`move_to` ``(z)``: the rate-independent operator, deflection in,
      ``F(z)`` out (used to test the memory properties);
    * :meth:`step` ``(dt, v, g, zs)``: the bristle equation (Eq. 10) advanced
      exactly over ``dt`` at constant ``v`` and ``g``.

    Memory: :attr:`points` is the turning-point stack, oldest first. Each
    entry ``[z_r, F_r, d, shape, lam, z_t, F_t]`` starts a curve
    ``F = F_r + d*lam*shape(d*(z - z_r))`` in direction ``d`` with target
    ``(z_t, F_t)`` (``z_t = None``: no target); the last entry is the current
    curve. The first entry is the *root*: the virgin state (its curve is the
    virgin curve in the direction of motion) or the point where the sliding
    law was left (:attr:`root_sliding`).

    Parameters
    ----------
    shapes
        The raw curve shapes.
    sigma0
        Bristle stiffness (N/m): the sliding law ``F(z) = sigma0*z``.
    max_points
        Memory bound (rule 9).
    """

    def __init__(self, shapes: CurveShapes, sigma0: float, max_points: int = MAX_POINTS) -> None:
        if not sigma0 > 0.0:
            raise ValueError(f"hysteresis function: sigma0 must be positive, got {sigma0}")
        if max_points < 4:
            raise ValueError(f"hysteresis function: max_points must be >= 4, got {max_points}")
        self.shapes = shapes
        self.sigma0 = float(sigma0)
        self.max_points = int(max_points)
        self.reset()

    # ---------------------------------------------------------------- state
    def reset(self, z: float = 0.0, F: float | None = None) -> None:
        """Virgin state at deflection ``z`` (m) and force ``F`` (N, default ``sigma0*z``)."""
        self.z = float(z)
        self.F = self.sigma0 * self.z if F is None else float(F)
        self.points: list[list[Any]] = []
        self.root_sliding = False
        self.sliding = False
        self.slide_dir = 0
        self._delta = 0.0

    @property
    def depth(self) -> int:
        """Number of points in memory (root included)."""
        return len(self.points)

    @property
    def direction(self) -> int:
        """Direction of the current curve (+1 ascending, -1 descending, 0 none)."""
        if self.sliding:
            return self.slide_dir
        return self.points[-1][2] if self.points else 0

    def reversal_points(self) -> list[tuple[float, float]]:
        """The memorised points ``(z, F)``, root first."""
        return [(p[0], p[1]) for p in self.points]

    def snapshot(self) -> tuple:
        """An immutable copy of the whole memory (for :meth:`restore`)."""
        return (self.z, self.F, tuple(tuple(p) for p in self.points), self.root_sliding,
                self.sliding, self.slide_dir, self._delta)

    def restore(self, snap: tuple) -> None:
        """Return to a :meth:`snapshot`."""
        (self.z, self.F, pts, self.root_sliding, self.sliding, self.slide_dir,
         self._delta) = snap
        self.points = [list(p) for p in pts]

    # --------------------------------------------------------- memory rules
    def _start(self, d: int) -> None:
        """Begin a curve in direction ``d`` at the current point (root or reversal)."""
        z, F = self.z, self.F
        self._delta = 0.0
        if self.sliding:  # velocity reversal: leave the sliding law, its exit point is the root
            self.sliding = False
            self.root_sliding = True
            self.points = [[z, F, d, self.shapes.external(d), 1.0, None, 0.0]]
            return
        if not self.points:  # first motion from the virgin state: the virgin curve
            self.points = [[z, F, d, self.shapes.virgin(d), 1.0, None, 0.0]]
            return
        if len(self.points) >= self.max_points:
            del self.points[-2:]  # forget the innermost loop (rule 9)
        j = len(self.points)
        root = self.points[0]
        if j == 1 and not self.root_sliding:
            # first reversal on the virgin curve: target its mirror point on the other branch
            dist = abs(z - root[0])
            zt, Ft = root[0] + d * dist, root[1] + d * self.shapes.virgin(d).value(dist)
        else:
            zt, Ft = self.points[-1][0], self.points[-1][1]
        cur = self.points[-1]
        inside = cur[2] * (cur[5] - z) if cur[5] is not None else 0.0  # short of the extreme by
        external = j <= (1 if self.root_sliding else 2) or inside <= self.shapes.internal_width
        shape = self.shapes.external(d) if external else self.shapes.internal
        span = d * (zt - z)
        phi = shape.value(span) if span > 0.0 else 0.0
        # (a target at or behind the start closes the loop at once; lam is then irrelevant)
        lam = max(d * (Ft - F), 0.0) / phi if phi > 0.0 else 1.0
        self.points.append([z, F, d, shape, lam, zt, Ft])

    def _close(self, zt: float, Ft: float, d: int) -> None:
        """The current curve reached its target: remove the loop, continue on the outer curve."""
        self.points.pop()
        self.z, self.F = zt, Ft
        if len(self.points) == 1 and not self.root_sliding:
            # reached the mirror point: continue on the virgin curve of this direction
            root = self.points[0]
            root[2], root[3] = d, self.shapes.virgin(d)
        else:
            self.points.pop()  # the target's own reversal point (wiping-out)
            if not self.points:  # passed the point where sliding ended: back on the sliding law
                self.sliding = True
                self.slide_dir = d
                self.F = self.sigma0 * zt
                return
        self._delta = max(d * (zt - self.points[-1][0]), 0.0)

    def _enter_sliding(self, z: float, d: int) -> None:
        self.z = z
        self.F = self.sigma0 * z
        self.points = []
        self.sliding = True
        self.slide_dir = d

    # -------------------------------------------------------------- drivers
    def move_to(self, z: float, zs: float = INF) -> float:
        """Drive the deflection to ``z`` (m) and return ``F(z)`` (N); ``zs`` = sliding threshold."""
        z = float(z)
        if z == self.z:
            return self.F
        d = 1 if z > self.z else -1
        if self.sliding and d == self.slide_dir:
            self.z, self.F = z, self.sigma0 * z
            return self.F
        if self.sliding or not self.points or d != self.points[-1][2]:
            self._start(d)
        self._advance(d, goal=z, zs=zs)
        return self.F

    def step(self, dt: float, v: float, g: float, zs: float = INF) -> None:
        """Advance Eq. 10 over ``dt`` (s) at constant ``v`` (m/s) and ``g`` (N); ``zs`` threshold (m)."""
        if v == 0.0 or dt <= 0.0:
            return
        a = abs(v) / g
        sv = 1.0 if v > 0.0 else -1.0
        if self.sliding and sv == self.slide_dir:
            self._slide(dt, a, sv * g)
            return
        D = sv * g - self.F  # dz/dt = a*D (Eq. 10)
        if abs(D) <= _DEADBAND * g:
            return
        d = 1 if D > 0.0 else -1
        if self.sliding or not self.points or d != self.points[-1][2]:
            self._start(d)  # new curve (after a reversal of dz/dt, or leaving sliding)
        self._advance(d, t=dt, a=a, sg=sv * g, zs=zs)

    def _slide(self, t: float, a: float, sg: float) -> None:
        """Exact NMLGM bristle over ``t``: ``z -> sg/sigma0`` with rate ``sigma0*a``."""
        zss = sg / self.sigma0
        self.z = zss + (self.z - zss) * math.exp(-self.sigma0 * a * t)
        self.F = self.sigma0 * self.z

    def _advance(self, d: int, *, goal: float | None = None, t: float = 0.0, a: float = 0.0,
                 sg: float = 0.0, zs: float = INF) -> None:
        """Move along the curves in direction ``d`` until ``goal`` is reached or ``t`` has elapsed."""
        for _ in range(100 * self.max_points + 1000):
            if self.sliding:
                if goal is not None:
                    self.z, self.F = goal, self.sigma0 * goal
                elif t > 0.0:
                    self._slide(t, a, sg)
                return
            z0, F0, _, shape, lam, zt, Ft = self.points[-1]
            delta = self._delta
            j = shape.piece(delta)
            bound = shape.starts[j + 1] if j + 1 < len(shape.starts) else INF
            kind = "piece"
            if zt is not None and d * (zt - z0) <= bound:
                bound, kind = d * (zt - z0), "target"
            if zs - d * z0 < bound:
                bound, kind = zs - d * z0, "threshold"
            if goal is not None and d * (goal - z0) < bound:
                bound, kind = d * (goal - z0), "goal"
            if goal is None:
                # Eq. 10 along this piece: a linear ODE dy/dt = A*y + B (module docstring)
                u = delta - shape.starts[j]
                G = d * sg - d * F0
                kj = shape.k[j]
                if kj:
                    A = kj * a * (G - lam * (shape.values[j] + shape.c[j]))
                    rate0 = A + kj * a * lam * shape.c[j] * math.exp(-kj * u)
                    dy = math.expm1(kj * (bound - delta)) if bound < INF else INF
                else:
                    m = lam * shape.slope[j]
                    A = -a * m
                    rate0 = a * (G - lam * shape.values[j] - m * u)
                    dy = bound - delta
                tb = _time_to(A, rate0, max(dy, 0.0))
                if tb > t:
                    if rate0 > 0.0:
                        y = rate0 * t * _phi1(A * t)
                        du = math.log1p(y) / kj if kj else y
                        self._set(z0, F0, d, shape, lam, min(delta + du, bound))
                    return
                t -= tb
            if kind == "target":
                self._close(zt, Ft, d)
            elif kind == "threshold":
                self._enter_sliding(d * zs, d)
            else:
                self._set(z0, F0, d, shape, lam, max(bound, delta))
                if goal is not None and kind == "goal":
                    self.z = goal
                    return
        raise ConvergenceError("hysteresis function: too many events in one step")

    def _set(self, z0: float, F0: float, d: int, shape: CurveShape, lam: float,
             delta: float) -> None:
        self._delta = delta
        self.z = z0 + d * delta
        self.F = F0 + d * lam * shape.value(delta)


# ---------------------------------------------------------------------- model
def hysteresis_params_class(features: frozenset[str], viscous_name: str = "sigma2",
                            cls_name: str = "HysteresisParams",
                            owner: str = "") -> type[ParamSet]:
    """The family's parameters of ``features`` and those of the hysteresis function (cached;
    pickles by its recipe)."""
    return _hysteresis_params_class(frozenset(features), viscous_name, cls_name, owner)


@cache
def _hysteresis_params_class(features: frozenset[str], viscous_name: str, cls_name: str,
                             owner: str) -> type[ParamSet]:
    base = params_class(features, viscous_name)
    cls = make_params_class(
        cls_name, [*base.SPECS, *hysteresis_specs(SEED_DEFAULTS)],
        owner=owner or "model " + "+".join(sorted(features)) + "+nonlocal-memory",
        constraints=[("Fc", "Fs"), *HYSTERESIS_CONSTRAINTS], module=__name__,
    )
    return with_recipe(cls, _hysteresis_params_class, features, viscous_name, cls_name, owner)


class HysteresisFamily(LuGreFamily):
    """A LuGre-family model whose bristle force ``sigma0*z`` is the hysteresis function ``F(z)``.

    States: the family's (``z``, and ``h`` with the film lag) plus ``Fz``, the
    value of ``F(z)`` (N) at each sample, so that the force is evaluated with
    the memory of that sample. The equations are the family's with the
    bristle deflection ``Fz/sigma0`` in place of ``z`` (module docstring).
    """

    #: the state the memory sets: the value of ``F(z)`` (N)
    memory_state = "Fz"

    def discrete_memory(self) -> HysteresisFamily:
        """The model itself: it is its own :class:`~fcomp.models.base.DiscreteMemory`."""
        return self

    @property
    def base_states(self) -> tuple[str, ...]:  # type: ignore[override]
        return (*super().base_states, self.memory_state)

    def _family_states(self, x: list[Any], P: ParamValues) -> list[Any]:
        """The family's state list with the deflection carrying ``F(z)``: ``[Fz/sigma0, h]``."""
        return [x[-1] / P("sigma0"), *x[1:-1]]

    def base_rhs(self, be: Backend, x: list[Any], sig: Signals, P: ParamValues, L: dict) -> list:
        """``[dz/dt, dh/dt]`` with ``dz/dt = v - F(z)*|v|/g`` (Eq. 10); ``Fz`` has no ODE."""
        return super().base_rhs(be, self._family_states(x, P), sig, P, L)

    def base_force(
        self, be: Backend, x: list[Any], dx: list[Any], sig: Signals, P: ParamValues, L: dict
    ) -> tuple[Any, Any]:
        """``F = F(z) + sigma1*dz/dt + sigma2*(v + T*a)`` (Eq. 11) as ``(F0, c_a)``."""
        return super().base_force(be, self._family_states(x, P), dx, sig, P, L)

    def base_steady_state(self, be: Backend, sig: Signals, P: ParamValues, L: dict) -> list:
        """At constant ``v``: ``F(z) = sign(v)*g(v, h_ss)`` (seed 000 Eq. 9); ``z`` as the NMLGM's."""
        fam = super().base_steady_state(be, sig, P, L)
        return [*fam, P("sigma0") * fam[0]]

    def rhs(self, be: Backend, x: Sequence[Any], sig: Signals, P: ParamValues) -> list:
        """Not available: ``dF(z)/dt`` depends on the memory, not on the state vector."""
        raise NotSymbolicError(
            f"model {self.describe()!r}: the hysteresis function F(z) has discrete "
            "turning-point memory, so dx/dt is not a function of the state vector; use "
            "fcomp.trajectory.friction_along_motion or model.stepper()"
        )

    def _with_features(self, add: frozenset[str], values: Mapping[str, float]) -> LuGreFamily:
        """The family model with more features, keeping the hysteresis function."""
        return with_hysteresis(super()._with_features(add, values), self.hysteresis_values())

    def hysteresis_values(self) -> dict[str, float]:
        """The hysteresis-function parameters (flat)."""
        flat = self.params.flat()
        return {n: flat[n] for n in HYSTERESIS_NAMES}

    def carrier(self) -> LuGreFamily:
        """The family model with the same features and effects (integrates ``h`` and effect states)."""
        cls = family_class(self.features, self.viscous_name)
        flat = self.params.flat()
        own = {k: v for k, v in flat.items()
               if k.removesuffix("_pos").removesuffix("_neg") in cls.Params.names()}
        return cls(cls.Params.from_flat(own), effects=self.effects)

    def hysteresis_function(self, values: Mapping[str, float] | None = None) -> HysteresisFunction:
        """A fresh :class:`HysteresisFunction` with this model's (or ``values``') curves."""
        flat = {**self.flat_params(), **(values or {})}
        return HysteresisFunction(CurveShapes.from_values(flat), flat["sigma0"])

    def bristle_inputs(
        self, x: Sequence[Any], sig: Signals, P: ParamValues
    ) -> tuple[Any, Any]:
        """``g(v, h)`` (N) and the sliding threshold ``zs = Fs/sigma0`` (m) for states ``x``."""
        x = list(x)
        L = self.levels(NUMPY, x, sig, P)
        nb = len(self.base_states)
        h = self._h(x[:nb], NUMPY, sig, P, L)
        g = self.g(NUMPY, sig.v, h, P, L, sig.s)
        zs = NUMPY.abs(L["Fs"] if "Fs" in L else L["Fc"]) / P("sigma0")
        if np.any(np.asarray(g) <= 0.0):
            raise FcompError(f"{self.describe()}: the sliding force g(v, h) must be positive "
                             "(check Fc and the effects' level changes)")
        return g, zs

    def integrate_motion(
        self, sig: Mapping[str, np.ndarray], x0: np.ndarray, flat: Mapping[str, float],
        substeps: int,
    ) -> np.ndarray:
        """States ``(N, n_states)`` along a sampled motion (used by ``friction_along_motion``).

        ``sig`` holds the samples ``t, v, a, x, p1, p2, s``. The carrier model
        integrates ``h`` and the effect states; the hysteresis function then
        advances Eq. 10 exactly on every interval with the interval-mean
        velocity and ``g`` at the interval start. ``substeps > 1`` refines the
        sample grid (signals linearly interpolated).
        """
        fine = _refine(sig, substeps)
        iF = len(self.base_states) - 1
        x0 = np.asarray(x0, dtype=float)
        carrier = self.carrier()
        M, dt = midpoint_signals(fine)
        pc = np.array([flat[k] for k in carrier.flat_params()], dtype=float)
        X = np.insert(step_loop(carrier)(np.delete(x0, iF), M.T, dt, pc), iF, 0.0, axis=1)
        P = ParamValues(flat, NUMPY)
        mid = Signals(v=M[0], a=M[1], x=M[2], p1=M[3], p2=M[4], s=M[5])
        g, zs = self.bristle_inputs([X[:-1, i] for i in range(X.shape[1])], mid, P)
        n = dt.size
        g = np.broadcast_to(np.asarray(g, dtype=float), (n,))
        zs = np.broadcast_to(np.asarray(zs, dtype=float), (n,))
        hf = HysteresisFunction(CurveShapes.from_values(flat), float(flat["sigma0"]))
        hf.reset(x0[0], x0[iF])
        zcol = np.empty(n + 1)
        fcol = np.empty(n + 1)
        zcol[0], fcol[0] = hf.z, hf.F
        step = hf.step
        for k, (dtk, vk, gk, zk) in enumerate(zip(dt.tolist(), M[0].tolist(), g.tolist(),
                                                  zs.tolist(), strict=True)):
            step(dtk, vk, gk, zk)
            zcol[k + 1] = hf.z
            fcol[k + 1] = hf.F
        X[:, 0] = zcol
        X[:, iF] = fcol
        return X[::substeps]

    def stepper(self, values: Mapping[str, float] | None = None) -> HysteresisStepper:
        """A stateful :class:`HysteresisStepper` (``reset``/``step``) for plant simulation."""
        return HysteresisStepper(self, values)

    def passivity(self) -> dict[str, Any]:
        """Not analysed: the LuGre dissipation bound does not carry over to a hysteretic ``F(z)``."""
        return {"applies": False, "passive": None,
                "reason": "hysteresis function with discrete memory: dissipativity not analysed"}


def _refine(sig: Mapping[str, np.ndarray], m: int) -> Mapping[str, np.ndarray]:
    """The sample grid with ``m`` equal sub-intervals per interval (signals interpolated)."""
    if m < 1:
        raise ValueError(f"substeps must be >= 1, got {m}")
    if m == 1:
        return sig
    from fcomp.models.base import side_of

    t = sig["t"]
    frac = np.arange(m) / m
    tt = np.concatenate([(t[:-1, None] + np.diff(t)[:, None] * frac).ravel(), t[-1:]])
    out = {k: np.interp(tt, t, sig[k]) for k in ("v", "a", "x", "p1", "p2")}
    out["t"] = tt
    out["s"] = side_of(out["v"], initial=float(sig["s"][0]))
    return out


def with_hysteresis(model: LuGreFamily, values: Mapping[str, float]) -> HysteresisFamily:
    """``model`` (LuGre family, with a bristle state) with ``sigma0*z`` replaced by ``F(z)``.

    ``values`` are the hysteresis-function parameters (others keep their defaults).
    """
    if model.feature_family() is None or "presliding" not in model.features:
        raise ValueError(
            f"the hysteresis function replaces sigma0*z: model {model.describe()!r} has no "
            "bristle state (add 'presliding' first)"
        )
    cls = hysteresis_class(model.features, model.viscous_name)
    flat = {**model.params.flat(), **values}
    new = cls(cls.Params.from_flat(flat), effects=model.effects)
    new.lineage = model.lineage
    return new


@dataclass(frozen=True)
class HysteresisTerm(Structure):
    """The hysteresis function ``F(z)`` in place of the bristle force ``sigma0*z``
    (:func:`with_hysteresis`), as the ``nonlocal-memory`` effect adds it; ``values`` are
    its parameters, ``features`` empty."""

    def apply(self, model: LuGreFamily) -> LuGreFamily:
        return with_hysteresis(model, self.values)


class NMLGMHysteresis(HysteresisFamily):
    """NMLGM with the hysteresis function of seed 000 (Eqs. 10-13; models.md 1.6).

    ``make_model("nmlgm-hysteresis", params="seed000-cylinder1")`` takes Table 4
    (NMLGM) and Tables 2-3 (hysteresis function, Table 2 read as metres). The
    memory rules and the choices where the seed is silent are in the module
    docstring of :mod:`fcomp.models.hysteresis`.
    """

    name = "nmlgm-hysteresis"
    features = PRESETS["nmlgm"].features
    viscous_name = "sigma2"
    Params = hysteresis_params_class(features, "sigma2", "NMLGMHysteresisParams",
                                     "nmlgm-hysteresis")


NMLGMHysteresisParams = NMLGMHysteresis.Params


def hysteresis_class(features: frozenset[str], viscous_name: str = "sigma2") -> type[HysteresisFamily]:
    """The hysteresis model class of a family feature set (``nmlgm-hysteresis`` if it matches;
    other classes are made here, cached, and pickle by their recipe)."""
    return _hysteresis_class(frozenset(features), viscous_name)


@cache
def _hysteresis_class(features: frozenset[str], viscous_name: str) -> type[HysteresisFamily]:
    if "presliding" not in features:
        raise ValueError("the hysteresis function needs the bristle state (presliding)")
    if features == NMLGMHysteresis.features and viscous_name == NMLGMHysteresis.viscous_name:
        return NMLGMHysteresis
    label = "+".join(sorted(features)) + "+nonlocal-memory"
    made = type("HysteresisModel", (HysteresisFamily,), {
        "name": "custom", "features": features, "viscous_name": viscous_name,
        "Params": hysteresis_params_class(features, viscous_name),
        "__doc__": f"LuGre-family model ({label}) with the hysteresis function.",
        "__module__": __name__,
    })
    return with_recipe(made, _hysteresis_class, features, viscous_name)


# -------------------------------------------------------------------- stepper
class HysteresisStepper(SampledStepper):
    """Stateful stepping of a hysteresis model, for plant simulation engines.

    The stepper contract of :mod:`fcomp.stepper`: ``reset(state)``, then
    ``advance(u, dt)`` per interval with the signals ``u = (v, a, x, p1, p2)``
    (:attr:`input_names`; m/s, m/s^2, m, Pa, Pa) held over ``dt`` (sampled data), or
    its named form ``step(dt, v, a, x, p1, p2)``; :meth:`force` / :meth:`force_parts`
    evaluate the friction at the current state. The same scheme as
    :meth:`HysteresisFamily.integrate_motion`, one interval at a time: the carrier's
    exponential step for the film and effect states, the memory's for ``z`` and ``F(z)``.

    Parameters
    ----------
    model
        A hysteresis model (``nmlgm-hysteresis`` or a family model with ``nonlocal-memory``).
    values
        Flat parameter values overriding the model's.
    """

    #: The held signals of :meth:`advance` (the side ``s`` follows from ``v``).
    input_names = SIGNAL_NAMES[:5]

    def __init__(self, model: HysteresisFamily, values: Mapping[str, float] | None = None) -> None:
        if model.discrete_memory() is None:
            raise ValueError(f"HysteresisStepper needs a hysteresis model, got {model.describe()!r}")
        self.model = model
        self.flat = {**model.flat_params(), **(values or {})}
        self.P = ParamValues(self.flat, NUMPY)
        self.function = model.hysteresis_function(self.flat)
        self.carrier = model.carrier()
        self._iF = len(model.base_states) - 1
        self._cidx = np.delete(np.arange(model.n_states), self._iF)  # carrier's states
        self._cstep: Loop | None = None
        if self.carrier.n_states > 1:  # film or effect states besides z: the family's step
            self._cstep = step_loop(self.carrier)
            self._cp = np.array([self.flat[k] for k in self.carrier.flat_params()], dtype=float)
        self.reset()

    @property
    def name(self) -> str:
        return self.model.describe()

    @property
    def state_names(self) -> tuple[str, ...]:
        return self.model.state_names

    def initial_state(self) -> np.ndarray:
        """:meth:`FrictionModel.initial_state`; :meth:`reset` starts with a virgin memory."""
        return self.model.initial_state()

    def _start(self, x: np.ndarray) -> None:
        self.side = 1.0
        self.function.reset(x[0], x[self._iF])

    @property
    def state(self) -> np.ndarray:
        """Current state vector (copy), in :attr:`FrictionModel.state_names` order."""
        return self.x.copy()

    def _signals(self, v: float, a: float, x: float, p1: float, p2: float) -> Signals:
        if v != 0.0:
            self.side = 1.0 if v > 0.0 else -1.0
        return Signals(v=float(v), a=float(a), x=float(x), p1=float(p1), p2=float(p2),
                       s=self.side)

    def _advance(self, u: np.ndarray, dt: float) -> np.ndarray:
        sig = self._signals(*u.tolist())
        g, zs = self.model.bristle_inputs(self.x.tolist(), sig, self.P)
        x = self.x.copy()
        if self._cstep is not None:
            sigv = np.array([[sig.v, sig.a, sig.x, sig.p1, sig.p2, sig.s]])
            xc = self._cstep(x[self._cidx], sigv, np.array([dt]), self._cp)
            x[self._cidx] = xc[-1]
        self.function.step(dt, sig.v, float(g), float(zs))
        x[0] = self.function.z
        x[self._iF] = self.function.F
        return x

    def step(self, dt: float, v: float, a: float = 0.0, x: float = 0.0, p1: float = 0.0,
             p2: float = 0.0) -> np.ndarray:
        """:meth:`advance` over ``dt`` (s) with ``v`` (m/s), ``a`` (m/s^2), ``x`` (m),
        ``p1, p2`` (Pa) held; the state at the end."""
        return self.advance((v, a, x, p1, p2), dt)

    def force_parts(self, v: float, a: float = 0.0, x: float = 0.0, p1: float = 0.0,
                    p2: float = 0.0) -> tuple[float, float]:
        """``(F0, c_a)`` at the current state, ``F = F0 + c_a*a`` (N, kg)."""
        sig = self._signals(v, a, x, p1, p2)
        F0, c = self.model.force_parts(NUMPY, list(self.x), sig, self.P)
        return float(F0), float(c)

    def force(self, v: float, a: float = 0.0, x: float = 0.0, p1: float = 0.0,
              p2: float = 0.0) -> float:
        """Friction force (N) at the current state."""
        F0, c = self.force_parts(v, a, x, p1, p2)
        return F0 + c * float(a)
