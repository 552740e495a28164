"""fcomp: friction models, identification, diagnosis and compensation for fluid-power servos.

The main API is offered here, imported on first use (``import fcomp`` itself
stays light, so the command line starts fast)::

    import fcomp

    model = fcomp.make_model("lugre", params="canudas1995")
    rec = fcomp.simulate("motion", model, "sine:amplitude=0.01,frequency=0.5", duration=4.0)
    fit = fcomp.fit(rec, "lugre")
    comparison = fcomp.compare(fit.model_, rec)
    diagnosis = fcomp.Diagnosis("coulomb-viscous").fit(rec)

========================= ==========================================================
name                      what it is
========================= ==========================================================
``make_model``            a friction model by name (:mod:`fcomp.models`)
``load_model``            a friction model from its file (:mod:`fcomp.modelfile`);
                          ``model.save(path)`` writes one
``FrictionModel``         their base class
``make_effect``           an effect by name, with parameters and configuration
``Effect``                the effect base class; ``register_effect`` registers one
``Measurement``           a record (columns in SI units and the sidecar)
``read``                  a measurement file
``simulate``              a plant with a friction model (:mod:`fcomp.api`)
``friction_along_motion`` a model's force along a prescribed motion
``fit``, ``FrictionFit``  identification with uncertainties
``compare``               one model beside records (``Comparison``)
``compare_plant``         the plant domain (``PlantComparison``)
``diagnose``, ``Diagnosis`` the missing-physics search
``design``                the next experiment for a diagnosis's open questions
``AcceptanceRule``        the thresholds that accept an effect (``Diagnosis(rule=...)``)
``generate``              a synthetic record with hidden effects
========================= ==========================================================
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from fcomp.version import __version__

if TYPE_CHECKING:
    from fcomp.api import PlantComparison, compare, compare_plant, diagnose, fit, read, simulate
    from fcomp.diagnosis import AcceptanceRule, Comparison, Diagnosis
    from fcomp.effects import Effect, make_effect, register_effect
    from fcomp.identification import FrictionFit
    from fcomp.measurement import Measurement
    from fcomp.modelfile import load_model
    from fcomp.models import FrictionModel, make_model
    from fcomp.planning import design
    from fcomp.synthetic import generate
    from fcomp.trajectory import friction_along_motion

#: Public name -> the module that defines it.
_API: dict[str, str] = {
    "make_model": "fcomp.models", "FrictionModel": "fcomp.models",
    "load_model": "fcomp.modelfile",
    "make_effect": "fcomp.effects", "register_effect": "fcomp.effects", "Effect": "fcomp.effects",
    "Measurement": "fcomp.measurement", "friction_along_motion": "fcomp.trajectory",
    "FrictionFit": "fcomp.identification", "Diagnosis": "fcomp.diagnosis",
    "AcceptanceRule": "fcomp.diagnosis",
    "Comparison": "fcomp.diagnosis", "compare": "fcomp.api",
    "compare_plant": "fcomp.api", "PlantComparison": "fcomp.api",
    "fit": "fcomp.api", "diagnose": "fcomp.api", "simulate": "fcomp.api", "read": "fcomp.api",
    "generate": "fcomp.synthetic", "design": "fcomp.planning",
}

__all__ = [
    "AcceptanceRule", "Comparison", "Diagnosis", "Effect", "FrictionFit", "FrictionModel", "Measurement",
    "PlantComparison", "__version__", "compare", "compare_plant", "design", "diagnose", "fit",
    "friction_along_motion", "generate", "load_model", "make_effect", "make_model", "read",
    "register_effect", "simulate",
]


def __getattr__(name: str) -> Any:
    if name in _API:
        value = getattr(importlib.import_module(_API[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'fcomp' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_API})
