"""Effects: named, composable physical add-ons to any friction model (models.md 1.8).

``model.with_effects("pressure-dependence", "dwell-time")`` adds effects by
name; :func:`register_effect` adds a user's own (an :class:`Effect` subclass);
:func:`load_effects_module` imports a user's ``.py`` file that registers
effects (the CLI's ``--effects path/to/module.py``). Each effect of the
catalogue is one module here (:mod:`fcomp.effects.catalogue` lists them). Every registered effect
is a diagnosis candidate; its diagnosis hooks (:class:`Effect`) read a
:class:`~fcomp.effects.record.RecordView` and may offer several forms
(:class:`~fcomp.effects.record.DiagnosisForm`).
"""

from __future__ import annotations

import os
from pathlib import Path

from fcomp.effects.base import EFFECTS, Effect, make_effect, register_effect, scale_levels
from fcomp.effects.catalogue import CATALOGUE
from fcomp.effects.record import DiagnosisForm, RecordView
from fcomp.errors import FcompError, UnknownNameError, term


def experiment_for(effect: str, kind: str = "") -> str:
    """The experiment that isolates ``effect`` on a rig of ``kind`` (the sidecar's ``kind``).

    Each effect words it for any rig (``experiment``) and, where a rig kind
    needs other words (no chambers to vent on an electromechanical axis), for
    that kind (``experiments``); see :meth:`Effect.experiment_for`.

    Raises
    ------
    UnknownNameError
        For an effect that is not registered.
    """
    return EFFECTS.get(effect).experiment_for(kind)


#: Model parameters that are not an effect's own but belong to one (the effect's parameter
#: is another, e.g. ``Fs_excess``; ``mass`` is measured by the inertia-error experiment).
_PARAMETER_EFFECT = {"Fs": "stribeck", "B": "viscous", "mass": "inertia-error"}


def effect_of_parameter(name: str) -> str | None:
    """The effect a flat parameter name (``Fs_pos``, ``sigma0``, ``mass``, ...) belongs to.

    ``None`` for the basic friction level ``Fc`` and names no effect carries.
    The experiment that determines the parameter is then
    :func:`experiment_for` of that effect.
    """
    base = name[:-4] if name.endswith(("_pos", "_neg")) else name
    if base in _PARAMETER_EFFECT:
        return _PARAMETER_EFFECT[base]
    for effect in EFFECTS.names():
        if any(s.name == base for s in EFFECTS.get(effect).Params.SPECS):
            return effect
    return None


def effect_holding(extra: str) -> type[Effect]:
    """The registered effect that holds the fit's extra term ``extra`` (``offset``, the
    constant force of ``fcomp fit --offset``) as its own parameter: its ``fit_extra``.

    Raises
    ------
    UnknownNameError
        When no registered effect holds it.
    """
    for name in EFFECTS.names():
        cls = EFFECTS.get(name)
        if cls.fit_extra == extra:
            return cls
    raise UnknownNameError(f"no registered effect holds a fit's {extra!r}")


def load_effects_module(path: str | Path) -> list[str]:
    """Import a user module (a ``.py`` file) that registers effects; return the new names.

    The file is *executed* (README, "Security"). Any error in it, ``sys.exit``
    included, becomes one :class:`FcompError` naming the file and the line; a
    file already loaded in this process is not executed again.
    """
    from fcomp.textdata import check_path
    from fcomp.usercode import USER_FILES, run_module

    if not str(path).strip():
        raise FcompError(f"{term('effects_module')}: no file name given (an empty argument)")
    p = Path(path)
    if not p.exists():
        raise FcompError(f"{p}: effects module not found")
    p = check_path(p, "effects module")
    if p.suffix != ".py":
        raise FcompError(f"{p}: an effects module is a Python file ending in .py")
    if os.path.realpath(p) in USER_FILES:
        return []
    before = set(EFFECTS.names())
    run_module(p, f"fcomp_user_effects_{len(USER_FILES)}_{p.stem}", "effects module")
    return sorted(set(EFFECTS.names()) - before)


__all__ = [
    "CATALOGUE", "EFFECTS", "DiagnosisForm", "Effect", "RecordView", "effect_holding",
    "effect_of_parameter", "experiment_for", "load_effects_module", "make_effect", "register_effect", "scale_levels",
]
