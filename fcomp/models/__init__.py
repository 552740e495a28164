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
    if isinstance(params, str):
        from fcomp.paramsets import model_params

        model = cls(model_params(params, name))
    else:
        model = cls(params)
    return model.with_effects(*effects) if effects else model


__all__ = [
    "MODELS", "FrictionModel", "LuGreFamily", "NotSymbolicError", "Signals", "make_model",
    "register_model", "side_of",
]
