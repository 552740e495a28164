"""What a fit reads from a measurement: the motion signals and the force the model must match.

Three cases, in this order (data-format.md, models.md section 2):

1. The measurement has an ``F`` column (friction measured or already
   reconstructed): the target is ``y = F``.
2. No ``F`` but a driving force can be formed,
   ``D = p1*A1 - p2*A2 + F_ext`` (gauge pressures, whichever terms the data
   hold), and the moving mass is known (``rig.mass`` or the ``mass``
   argument): the target is the reconstructed friction
   ``y = D - m*(a + g*s_o)`` (``s_o`` = +1 vertical-up, -1 vertical-down,
   0 horizontal).
3. Driving force but no mass: the mass is estimated with the friction
   parameters. The target is ``y = D`` and the prediction gains the term
   ``mass*(a + g*s_o)``; :attr:`FitData.inertia` holds ``a + g*s_o``.

Velocity and acceleration come from the ``v``/``a`` columns where present,
else from the position by the zero-phase low-pass and differentiation of
:mod:`fcomp.reconstruction` (Butterworth, forward-backward, cut-off
``cutoff_hz``). The driving force is then passed through the *same* filter
("parallel filtering" of inverse-model identification, Gautier & Janot):
``m*a`` and the force measured then have the same bandwidth. Without it the
acceleration's attenuated peaks bias the mass upwards (on the EMPS record,
102.7 kg instead of 95.1 kg at 10 Hz).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from fcomp.errors import FcompError
from fcomp.measurement import ORIENTATIONS, G, Measurement
from fcomp.models.base import side_of
from fcomp.trajectory import prepare_signals

#: Default cut-off (Hz) of the zero-phase filter deriving ``v``, ``a`` from ``x`` (and of the
#: driving force's parallel filtering) in a fit and in :func:`.estimator.model_rms`.
CUTOFF_HZ = 10.0


@dataclass(frozen=True)
class FitData:
    """The signals of a fit (SI).

    Attributes
    ----------
    sig
        Prepared motion signals ``t, v, a, x, p1, p2, s``
        (:func:`fcomp.trajectory.prepare_signals`; pressures gauge, Pa).
    y
        Force target (N), see the module docstring.
    inertia
        ``a + g*s_o`` (m/s^2) when the mass is estimated, else ``None``.
    source
        ``"F"``, ``"reconstructed"`` or ``"driving-force"``.
    mass
        The known moving mass used to reconstruct ``y`` (kg), if any.
    label
        The measurement's name, for messages.
    band_hz
        Cut-off (Hz) of the zero-phase low-pass the target went through
        ("parallel filtering"): a prediction must pass through the same filter
        (:func:`fcomp.reconstruction.band_limit`) before it is compared; None:
        the target is unfiltered.
    drive_rate
        ``dD/dt`` of the band-limited driving force (N/s) when the target comes
        from one (pressures, ``F_ext``) through the parallel filtering: the
        column of a fitted force-channel lag (:mod:`.dynamic`); else None.
    """

    sig: dict[str, np.ndarray]
    y: np.ndarray
    inertia: np.ndarray | None
    source: str
    mass: float | None
    label: str
    band_hz: float | None = None
    drive_rate: np.ndarray | None = None

    @property
    def n(self) -> int:
        return self.y.size

    def select(self, mask: np.ndarray) -> FitData:
        """The samples where ``mask`` is true (a contiguous slice keeps time increasing)."""
        sig = {k: v[mask] for k, v in self.sig.items()}
        inertia = None if self.inertia is None else self.inertia[mask]
        rate = None if self.drive_rate is None else self.drive_rate[mask]
        return FitData(sig, self.y[mask], inertia, self.source, self.mass, self.label,
                       self.band_hz, rate)

    def averaged(self, q: int) -> FitData:
        """This record averaged over blocks of ``q`` samples (:func:`block_mean`): every
        signal, the target and the extra columns; the sides ``s`` follow the averaged
        velocity. Block means preserve displacement, so a long record can be fitted on
        a shorter copy."""
        if q <= 1:
            return self
        sig = {k: block_mean(v, q) for k, v in self.sig.items() if k != "s"}
        sig["s"] = side_of(sig["v"])
        inertia = None if self.inertia is None else block_mean(self.inertia, q)
        rate = None if self.drive_rate is None else block_mean(self.drive_rate, q)
        return FitData(sig, block_mean(self.y, q), inertia, self.source, self.mass, self.label,
                       self.band_hz, rate)

    def holding(self, name: str, value: float) -> FitData:
        """This target with the fitted extra ``name`` held at ``value``: ``y - value*column``
        and no column left to fit (unchanged where this target has no such column)."""
        col = self.extra_column(name)
        if col is None:
            return self
        held = dataclasses.replace(self, y=self.y - value * col)
        if name == "mass":
            return dataclasses.replace(held, inertia=None)
        if name == "lag":
            return dataclasses.replace(held, drive_rate=None)
        return held

    def extra_column(self, name: str) -> np.ndarray | None:
        """``dF_hat/d(name)`` of a fitted extra of :mod:`.dynamic` (``mass``: the
        inertia ``a + g*s_o``; ``offset``: ones; ``lag``: ``-dD/dt``), None where
        this target has no such column."""
        if name == "mass":
            return self.inertia
        if name == "lag":
            return None if self.drive_rate is None else -self.drive_rate
        if name == "offset":
            return np.ones(self.n)
        raise KeyError(f"no fitted extra {name!r}")

    def band_limited(self, F: np.ndarray) -> np.ndarray:
        """A prediction ``F`` (or sensitivity columns) through the target's filter, if any."""
        if self.band_hz is None:
            return F
        from fcomp.reconstruction import band_limit

        return band_limit(self.sig["t"], F, self.band_hz)


def block_mean(arr: np.ndarray, q: int) -> np.ndarray:
    """Means of ``arr`` over consecutive blocks of ``q`` samples (the last block may be
    shorter): ``b_j = mean(arr[j*q:(j+1)*q])``; ``arr`` itself for ``q <= 1``."""
    if q <= 1:
        return arr
    m = arr.size // q
    head = arr[: m * q].reshape(m, q).mean(axis=1)
    return np.concatenate([head, [arr[m * q:].mean()]]) if arr.size % q else head


def motion(meas: Measurement, cutoff_hz: float = CUTOFF_HZ
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, bool]:
    """``(v, a, x, filtered)`` of a measurement: columns where present, else derived.

    A missing ``v``/``a`` is derived from ``x`` by the zero-phase low-pass and
    differentiation of :func:`fcomp.reconstruction.differentiate` (cut-off
    ``cutoff_hz``); ``filtered`` says whether that happened.
    """
    has_v, has_a, has_x = "v" in meas, "a" in meas, "x" in meas
    if not has_v and not has_x:
        raise FcompError(f"{meas.label}: a fit needs a velocity 'v' or a position 'x' column")
    x = meas["x"] if has_x else None
    if has_v and has_a:
        return meas["v"], meas["a"], x, False
    from fcomp.reconstruction import derivatives

    if has_x:
        v_est, a_est = derivatives(meas, cutoff_hz=cutoff_hz)
    else:
        v_est, a_est = meas["v"], np.gradient(meas["v"], meas.t)
    v = meas["v"] if has_v else v_est
    a = meas["a"] if has_a else a_est
    return v, a, x, has_x


def fit_data(
    meas: Measurement,
    *,
    estimate_mass: bool | None = None,
    mass: float | None = None,
    cutoff_hz: float = CUTOFF_HZ,
    force_cutoff_hz: float | None = None,
) -> FitData:
    """The :class:`FitData` of a measurement (see the module docstring for the cases).

    Parameters
    ----------
    meas
        The measurement.
    estimate_mass
        ``None`` (default): estimate the mass exactly when there is no ``F``
        column, a driving force can be formed and no mass is known.
        ``True`` forces it (needs a driving force and no ``F`` column);
        ``False`` forbids it (a mass must then be known if there is no ``F``).
    mass
        Moving mass (kg) overriding ``rig.mass``.
    cutoff_hz
        Cut-off (Hz) of the zero-phase filter that derives ``v``, ``a`` from ``x``.
    force_cutoff_hz
        Band (Hz) of the parallel filtering of a driving force: the force and
        the inertia term ``a + g*s_o`` are low-passed, and the returned
        :attr:`FitData.band_hz` tells a fit to pass its prediction through the
        same filter (:mod:`fcomp.conditioning`). Ignored for an ``F`` column.
    """
    from fcomp.reconstruction import driving_force, smooth

    v, a, x, filtered = motion(meas, cutoff_hz)
    n = len(meas)
    zero = np.zeros(n)
    p1 = meas.gauge_pressure("p1") if "p1" in meas else zero
    p2 = meas.gauge_pressure("p2") if "p2" in meas else zero
    sig = prepare_signals(meas.t, v, a, x, p1, p2)
    known = mass if mass is not None else meas.rig.get("mass")
    if known is not None and (not np.isfinite(float(known)) or float(known) < 0):
        raise FcompError(f"{meas.label}: the moving mass must be a non-negative number (kg)")
    has_F = "F" in meas
    can_drive = any(k in meas for k in ("p1", "p2", "F_ext"))
    D = driving_force(meas) if can_drive and not has_F else None
    if D is not None and filtered:  # parallel filtering: every term with the same bandwidth
        D = smooth(meas.t, D, cutoff_hz=cutoff_hz, label=meas.label)
    if estimate_mass is None:
        estimate_mass = not has_F and D is not None and known is None
    if estimate_mass:
        if has_F:
            raise FcompError(f"{meas.label}: the mass cannot be estimated from an 'F' column "
                             "(friction already has the inertia removed); give F_ext or "
                             "pressures instead")
        if D is None:
            raise FcompError(f"{meas.label}: estimating the mass needs a driving force "
                             "(F_ext and/or p1, p2 columns)")
    s_o = ORIENTATIONS[meas.rig.get("orientation", "horizontal")]
    label = meas.label
    if has_F:
        return FitData(sig, meas["F"].copy(), None, "F", None, label)
    if D is None:
        raise FcompError(f"{label}: no force to fit: the data need an 'F' column, or "
                         "F_ext and/or p1, p2 columns")
    inertia = sig["a"] + G * s_o
    band = None
    rate = None
    if force_cutoff_hz is not None:
        from fcomp.reconstruction import band_limit

        band = float(force_cutoff_hz)
        D = band_limit(meas.t, D, band)
        inertia = band_limit(meas.t, inertia, band)
        rate = np.gradient(D, meas.t)
    if estimate_mass:
        return FitData(sig, D, inertia, "driving-force", None, label, band, rate)
    if known is None:
        raise FcompError(f"{label}: sidecar key rig.mass is missing (needed to reconstruct the "
                         "friction force; or let the mass be estimated)")
    return FitData(sig, D - float(known) * inertia, None, "reconstructed", float(known), label,
                   band, rate)
