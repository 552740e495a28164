"""Friction models, registered by name (models.md section 1).

>>> from fcomp.models import make_model
>>> m = make_model("lugre", params="canudas1995")
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from fcomp.models.base import FrictionModel, NotSymbolicError, Signals, side_of
from fcomp.models.gms import GMS
from fcomp.models.hysteresis import NMLGMHysteresis
from fcomp.models.lugre_family import PRESETS, LuGreFamily
from fcomp.parameters import ParamSet
from fcomp.paramsets import friction_values
from fcomp.registry import Registry

MODELS: Registry[type[FrictionModel]] = Registry("friction model")
for _name, _cls in PRESETS.items():
    MODELS.register(_name, _cls)
MODELS.register(NMLGMHysteresis.name, NMLGMHysteresis)
MODELS.register(GMS.name, GMS)


def register_model(cls: type[FrictionModel], *, replace: bool = False) -> type[FrictionModel]:
    """Register a user model class under ``cls.name``."""
    MODELS.register(cls.name, cls, replace=replace)
    return cls


def make_model(
    name: str,
    params: str | Mapping[str, Any] | None = None,
    effects: Sequence[Any] = (),
) -> FrictionModel:
    """A friction model by name.

    Parameters
    ----------
    name
        Registered model name (``coulomb``, ..., ``nmlgm``, ``nmlgm-hysteresis``, ``gms``).
    params
        A parameter-set name (``canudas1995``, ``seed000-cylinder1``, ...), a
        mapping of flat parameter names, or ``None`` for the defaults.
    effects
        Effect names or instances to add (:meth:`FrictionModel.with_effects`).
    """
    cls = MODELS.get(name)
    model = cls(model_params(params, name)) if isinstance(params, str) else cls(params)
    return model.with_effects(*effects) if effects else model


def model_params(set_name: str, model_name: str) -> ParamSet:
    """The ``Params`` of model ``model_name`` filled from parameter set ``set_name``.

    Parameters the set does not give keep the model's defaults; parameters
    the model does not have are ignored (:func:`fcomp.paramsets.friction_values`).
    """
    cls = MODELS.get(model_name)
    accepted = set(cls.Params.names())
    values = friction_values(set_name, model_name)
    return cls.Params(**{k: v for k, v in values.items() if k in accepted})


__all__ = [
    "MODELS", "FrictionModel", "LuGreFamily", "NotSymbolicError", "Signals", "make_model",
    "model_params", "register_model", "side_of",
]
