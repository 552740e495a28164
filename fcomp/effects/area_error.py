"""The ``area-error`` effect: pressure force reconstructed with the wrong areas.

One module holds the effect: its law, its diagnosis hints and its experiment
wording (the class :class:`AreaError`; its docstring is the physics).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from fcomp.backend import Backend
from fcomp.effects.base import Effect
from fcomp.effects.record import RecordView, constant_chambers, distinct_columns
from fcomp.parameters import ParamValues, make_params_class, spec

if TYPE_CHECKING:
    from fcomp.models.base import Signals


#: Largest area error the diagnosis fits (m^2): 5 % of the piston area of a 100 mm bore.
#: The fit's box is this (``m^2`` has no data scale in
#: :func:`fcomp.diagnosis.boxes.data_bounds`: its +-20 unit scales are +-20 m^2).
AREA_ERROR_BOUND = 0.05 * math.pi / 4 * 0.1**2

AreaErrorParams = make_params_class("AreaErrorParams", [
    spec("dA1", "m^2", 0.0, -AREA_ERROR_BOUND, AREA_ERROR_BOUND,
         "area error of chamber 1: nominal A1 minus the effective pressurised area",
         directional=False),
    spec("dA2", "m^2", 0.0, -AREA_ERROR_BOUND, AREA_ERROR_BOUND,
         "area error of chamber 2: nominal A2 minus the effective pressurised area",
         directional=False),
], owner="effect area-error")


class AreaError(Effect):
    """Area error: the pressure force reconstructed with areas the pressure does not act on.

    The friction force is reconstructed as ``p1*A1 - p2*A2 + F_ext - m*a`` with
    the nominal areas ``A1 = pi/4*bore^2`` and ``A2 = pi/4*(bore^2 - rod^2)``
    (models.md 3). The area the pressure actually acts on differs: a seal lip
    or an O-ring in its groove is pressurised on part of its own face, so the
    effective diameter lies between bore and groove bottom (about 1 % of the
    area); bore and rod tolerances, a cushioning spigot or a wrong rod
    diameter add to it. With ``dA1``, ``dA2`` the nominal minus the effective
    areas, the reconstructed force carries::

        F_add = dA1*p1 - dA2*p2

    (gauge pressures). A model without it leaves a residual proportional to
    the pressures that does not change sign with the direction of travel: at
    a constant pressure a constant offset, so ``|F|`` is larger in one
    direction than in the other by ``2*F_add`` -- the same force as a
    direction asymmetry of the levels or a force offset while sliding
    (confounded with both); across pressure levels it grows with the
    pressure, in both directions alike, and at rest against a stop it is all
    the force left. A chamber whose pressure is constant over the record
    (vented: ``p2 = 0``) leaves its coefficient a constant force the record
    cannot tell from an offset: it is held at 0 (:meth:`held`).

    It is an error of the *measurement* (the areas the force is reconstructed
    with), not a friction of the seal: a model file keeps it among its
    measurement terms, used when the model is compared with its record and
    dropped when the model is plant friction or a compensator's model.
    """

    name = "area-error"
    Params = AreaErrorParams
    factors = ("pressure",)
    # the areas of the force reconstruction, not the seal: a model file keeps it among its
    # measurement terms (a plant's or a compensator's friction must not carry dA*p)
    of_measurement = True
    needs = ("p1", "p2")
    # the pressure force of a reconstructed record is F + m*a: an area error scales the
    # inertia term as a mass error does (at rest, with a = 0, only the area error is left)
    confounded = ("direction-asymmetry", "force-offset", "inertia-error")
    signature = ("residual proportional to the pressures, the same sign in both directions "
                 "(|F| larger one way)")
    experiment = ("the force held at rest at several driving pressures, or the same motion "
                  "at several pressure levels in both directions of travel")
    experiments = {
        "pneumatic-cylinder": "the force at rest against a stop at several chamber pressures "
                              "(each chamber alone), or the same motion at several pressures "
                              "extending and retracting",
        "hydraulic-cylinder": "the force at rest against a stop (or a load cell) at several "
                              "pressures in each chamber, or the same motion at several "
                              "supply pressures extending and retracting",
        "friction-rig": "a calibration of the force reading at rest against known loads at "
                        "several normal-force levels (a gain error of the force channel)",
        "electromechanical-axis": "the motor force held against a load cell at rest at "
                                  "several force levels (a force-constant error; the axis "
                                  "has no fluid pressure)",
    }

    def extra_force(self, be: Backend, sig: Signals, P: ParamValues) -> tuple[Any, Any]:
        return P("dA1") * sig.p1 - P("dA2") * sig.p2, 0.0

    def unsuitable(self, view: RecordView) -> str | None:
        """An area error is seen only where the pressures and an *independent* force
        channel make up the force (a load cell on the rod, ``F_ext``, and the chamber
        pressures: ``F = F_ext + p1*A1 - p2*A2 - m*a``).

        A force column measured on the friction (``F``) holds no pressure force, so no
        area can be wrong in it. Where the pressures *are* the force sensor
        (``p1*A1 - p2*A2 - m*a`` alone), ``dA1*p1 - dA2*p2`` is a gain on the measured
        force itself plus a term in the pressure sum: the "prediction" would carry the
        measurement, noise and every unexplained structure included, and take a share
        of any residual (a ripple, a drift) -- a gain error of the only force channel
        cannot be told from the friction's level without a second force reading.
        """
        if view.source == "F" or "F" in view.force_channels:
            return ("the force is measured directly (an F column), not reconstructed from "
                    "the pressures: no area enters it")
        if view.force_channels and "F_ext" not in view.force_channels:
            return ("the pressures are the only force sensor: an area error is a gain of "
                    "the measured force itself, not separable from the friction level "
                    "without a second force reading (a load cell, F_ext)")
        return None

    def held(self, view: RecordView) -> list[str]:
        """The area error of a chamber whose pressure is constant over the training samples
        (:func:`constant_chambers`: vented, ``p2 = 0``), and ``dA2`` where the two pressures
        move together (centred, one a multiple of the other: only one combination is
        determined): held at 0."""
        still = constant_chambers(view)
        out = [n for n, p in (("dA1", "p1"), ("dA2", "p2")) if p in still]
        if not out:
            m = view.train
            cols = np.column_stack([view.signal("p1")[m], -view.signal("p2")[m]])
            use = distinct_columns(cols - cols.mean(axis=0))
            out = [n for i, n in enumerate(("dA1", "dA2")) if i not in use]
        return out

    def guess(self, view: RecordView, form: str | None = None) -> list[dict[str, float]]:
        """The training residual regressed on ``p1`` and ``-p2`` by least squares (the
        chambers :meth:`held` leaves out at 0): through the origin, and with an intercept
        (the slopes alone, where the residual also holds an offset)."""
        m = view.train
        held = set(self.held(view))
        names = [n for n in ("dA1", "dA2") if n not in held]
        out: dict[str, float] = {"dA1": 0.0, "dA2": 0.0}
        if not names or not m.any():
            return [out]
        p = {"dA1": view.signal("p1")[m], "dA2": -view.signal("p2")[m]}
        cols = np.column_stack([p[n] for n in names])
        r = view.residual[m]
        starts = []
        for design in (cols, np.column_stack([cols, np.ones(cols.shape[0])])):
            coef, *_ = np.linalg.lstsq(design, r, rcond=None)
            start = dict(out)
            for n, c in zip(names, coef, strict=False):
                value = float(c) if math.isfinite(c) else 0.0
                start[n] = float(np.clip(value, -AREA_ERROR_BOUND, AREA_ERROR_BOUND))
            starts.append(start)
        return starts
