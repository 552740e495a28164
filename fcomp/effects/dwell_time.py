"""The ``dwell-time`` effect: static friction rising with the time at rest.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`DwellTime`; its docstring is the physics).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from fcomp.backend import Backend
from fcomp.effects.base import Effect
from fcomp.effects.record import DiagnosisForm, RecordView
from fcomp.parameters import ParamValues, make_params_class, spec

if TYPE_CHECKING:
    from fcomp.models.base import FrictionModel, Signals


DwellTimeParams = make_params_class("DwellTimeParams", [
    spec("dFs", "N", 0.0, 0.0, math.inf, "break-away increase after a long dwell"),
    spec("tau_dwell", "s", 1.0, 0.0, math.inf, "ageing time constant", lower_open=True,
         directional=False),
    spec("L_dwell", "m", 1e-4, 0.0, math.inf, "sliding distance that erases the age",
         lower_open=True, directional=False),
    spec("k_dwell", "-", 0.0, 0.0, 5.0, "ageing shape: 0 exponential (Kato), > 0 "
         "towards logarithmic (Dieterich)", directional=False),
    spec("v_rest", "m/s", 1e-5, 0.0, math.inf, "speed scale of rest (fixed): ageing "
         "weighted by exp(-|v|/v_rest)", lower_open=True, directional=False),
], owner="effect dwell-time")


class DwellTime(Effect):
    """Dwell-time dependence: static friction rising with time at rest.

    At rest, seal asperities creep and the rubber settles into the surface
    texture; the longer the stop the higher the next break-away force. The
    contact "age" ``w`` in [0, 1] grows while the piston rests and is erased
    by sliding (Rabinowicz; Kato et al.; the ageing term of Dieterich-Ruina
    rate-and-state friction restricted to rest)::

        dw/dt = r(v)*(1 - w)^(1 + k)/tau_dwell - w*|v|/L_dwell,   r(v) = exp(-|v|/v_rest)

    and raises the friction level by ``dFs*w`` in one of two forms (``form=``):

    ``"static"`` (the default)
        the static level, ``Fs -> Fs + dFs*w``: the Stribeck hump grows and,
        like it, fades above the Stribeck speed (the dwell-dependent static
        friction of Armstrong-Helouvry's seven-parameter model);
    ``"level"``
        the whole curve, ``Fc -> Fc + dFs*w`` and ``Fs -> Fs + dFs*w``: the
        excess is erased by the sliding distance alone, at any speed (the
        state of rate-and-state friction).

    The two are one law for models without ``Fs`` (``Fc -> Fc + dFs*w``).
    After a dwell ``t_d`` from ``w = 0`` the age is
    ``1 - exp(-t_d/tau_dwell)`` for ``k = 0`` (Kato's exponential law) and
    ``1 - (1 + k*t_d/tau_dwell)^(-1/k)`` for ``k > 0``, which grows about
    logarithmically over the middle decades (Dieterich's log ageing); it is
    erased over a sliding distance ``L_dwell``. ``r(v)`` limits the ageing to
    rest (``v_rest``, fixed, far below any sliding speed), so the effect adds no
    force while sliding. A model without it leaves positive spikes at
    break-away whose height grows with the dwell time before the start.
    """

    name = "dwell-time"
    FORMS: ClassVar[tuple[str, ...]] = ("static", "level")
    states = ("w",)
    initial = (0.0,)
    Params = DwellTimeParams
    fixed: ClassVar[tuple[str, ...]] = ("v_rest",)
    signature = "break-away spikes growing with the dwell time before the start"
    experiment = "starts after dwells of different lengths (0.1 s to 10 s)"
    dynamic = True

    def modify_levels(self, be: Backend, L: dict, w: list[Any], sig: Signals,
                      P: ParamValues) -> dict:
        out = dict(L)
        keys = ("Fs",) if "Fs" in out and self.form == "static" else ("Fc", "Fs")
        for key in keys:
            if key in out:
                out[key] = out[key] + P("dFs", sig.s) * w[0]
        return out

    @classmethod
    def diagnosis_forms(cls) -> tuple[DiagnosisForm, ...]:
        """Both forms: the hump grows, or the whole curve."""
        return DiagnosisForm.each(cls.FORMS)

    @classmethod
    def forms_for(cls, model: FrictionModel) -> tuple[DiagnosisForm, ...]:
        """Both forms where the model has a static level ``Fs``; one law without it."""
        forms = cls.diagnosis_forms()
        flat = model.flat_params()
        return forms if any(n == "Fs" or n.startswith("Fs_") for n in flat) else forms[:1]

    def rhs(self, be: Backend, w: list[Any], sig: Signals, P: ParamValues) -> list:
        rest = be.exp(-be.abs(sig.v) / P("v_rest"))
        young = be.power(be.fmax(1.0 - w[0], 1e-30), 1.0 + P("k_dwell"))
        return [rest * young / P("tau_dwell") - w[0] * be.abs(sig.v) / P("L_dwell")]

    def steady_state(self, be: Backend, sig: Signals, P: ParamValues) -> list:
        # exact for k = 0; at any sliding speed r(v) ~ 0 and the age is ~0
        L, tau = P("L_dwell"), P("tau_dwell")
        rest = be.exp(-be.abs(sig.v) / P("v_rest"))
        return [L * rest / (L * rest + be.abs(sig.v) * tau)]

    def unsuitable(self, view: RecordView) -> str | None:
        """A record without a start after a dwell cannot show it."""
        return None if view.dwell_starts else "the record has no start after a dwell"

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """Break-away peaks of the residual against the dwell time before each start."""
        x, v = view.signal("x"), view.signal("v")
        r = view.residual
        zone = 3.0 * view.d_pre
        dwells, peaks = [], []
        for k, dw in view.dwell_starts:
            j = k
            s = math.copysign(1.0, v[k]) if v[k] != 0 else 1.0
            while j < view.n and abs(x[j] - x[k]) < zone and j - k < 10_000:
                j += 1
            win = slice(k, max(j, k + 1))
            sel = view.train[win]
            if sel.any():
                dwells.append(dw)
                peaks.append(float(np.max(s * r[win][sel])))
        level = view.level
        if len(dwells) < 2:
            return [{"dFs": 0.2 * level, "tau_dwell": 1.0, "L_dwell": 2 * view.d_pre}]
        d, p = np.array(dwells), np.array(peaks)
        best = None
        for tau in np.geomspace(max(d.min(), 0.01), max(d.max(), 0.02), 5):
            A = np.column_stack([np.ones_like(d), 1.0 - np.exp(-d / tau)])
            coef, *_ = np.linalg.lstsq(A, p, rcond=None)
            cost = float(np.sum((p - A @ coef) ** 2))
            if best is None or cost < best[0]:
                best = (cost, max(float(coef[1]), 0.05 * level), float(tau))
        _, dFs, tau = best  # type: ignore[misc]
        L = max(2 * view.d_pre, 20 * view.scales.resolution)
        return [{"dFs": dFs, "tau_dwell": tau, "L_dwell": L},
                {"dFs": dFs, "tau_dwell": tau, "L_dwell": 8 * L},
                {"dFs": 1.5 * dFs, "tau_dwell": 0.3 * tau, "L_dwell": 2 * L, "k_dwell": 1.0}]
