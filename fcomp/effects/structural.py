"""Structural effects: terms of the LuGre family itself, not riding along a model.

``stribeck``, ``viscous``, ``viscous-lead``, ``presliding``, ``frictional-lag``
and ``nonlocal-memory`` are terms of the family's equations
(:mod:`fcomp.models.lugre_family`): attaching one turns the model into the
richer member of the family (``lugre`` + ``frictional-lag`` *is*
``modified-lugre``). Each says which term it adds -- a
:class:`~fcomp.models.lugre_family.Structure`: the features it switches on
and the values of their parameters -- and the family builds the model, through
its one public method :meth:`~fcomp.models.lugre_family.LuGreFamily.with_structure`.
An effect never builds a model class itself.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar

from fcomp.effects.base import Effect
from fcomp.models.lugre_family import Structure

if TYPE_CHECKING:
    from fcomp.models.base import FeatureFamily, FrictionModel


def family_of(model: FrictionModel, effect: str) -> FeatureFamily:
    """The model as a member of the LuGre family (its :meth:`feature_family`), else an error."""
    fam = model.feature_family()
    if fam is None:
        raise ValueError(
            f"effect {effect!r} is a term of the LuGre family and does not apply to "
            f"model {model.describe()!r}"
        )
    return fam


def features_of(model: FrictionModel) -> frozenset[str] | None:
    """The feature set of a family model, ``None`` for models outside a feature family."""
    fam = model.feature_family()
    return None if fam is None else fam.features


class StructuralEffect(Effect):
    """An effect that is a term of the LuGre family: attaching it changes the model class.

    ``adds`` are the features attaching it switches on; a model that already has
    every feature of ``marks`` (default: ``adds``) already has the effect;
    ``requires`` are the features it builds on. :meth:`term` is the
    :class:`~fcomp.models.lugre_family.Structure` it adds (:meth:`added_features`
    with :meth:`new_values`), :meth:`check` refuses a model it cannot extend.
    """

    adds: ClassVar[frozenset[str]] = frozenset()
    marks: ClassVar[frozenset[str] | None] = None
    requires: ClassVar[frozenset[str]] = frozenset()

    def applies_to(self, model: FrictionModel) -> bool:
        features = features_of(model)
        marks = self.adds if self.marks is None else self.marks
        return features is not None and not marks <= features

    def added_features(self) -> set[str]:
        """The features attaching this instance switches on (default :attr:`adds`)."""
        return set(self.adds)

    def new_values(self, fam: FeatureFamily) -> dict[str, float]:
        """Parameter values of the added terms (from this effect's parameters)."""
        return dict(self.params.flat())

    @classmethod
    def config_in(cls, model: FrictionModel) -> dict[str, Any]:
        """The configuration that attaches this effect as ``model`` has it (``model`` a
        model it was attached to): its ``form`` where it has several (default: none).

        The model keeps the effect as features, not as an instance
        (:meth:`attach`); a model file (:mod:`fcomp.modelfile`) writes this to
        rebuild it.
        """
        return {}

    def check(self, model: FrictionModel, fam: FeatureFamily) -> None:
        """Raise ``ValueError`` where ``model`` (``fam`` as a family member) has the effect
        already or lacks a feature of :attr:`requires`."""
        if not self.applies_to(model):
            raise ValueError(f"model {fam.describe()!r} already has effect {self.name!r}")
        missing = self.requires - fam.features
        if missing:
            raise ValueError(
                f"effect {self.name!r} needs {', '.join(sorted(missing))} in the model "
                f"{fam.describe()!r} first"
            )

    def term(self, fam: FeatureFamily) -> Structure:
        """The term this instance adds to ``fam``: :meth:`added_features`, :meth:`new_values`."""
        return Structure(self.name, frozenset(self.added_features()), self.new_values(fam))

    def attach(self, model: FrictionModel) -> FrictionModel:
        """``model`` as the family member with this term (:meth:`check`, then
        :meth:`~fcomp.models.lugre_family.LuGreFamily.with_structure` of :meth:`term`)."""
        fam = family_of(model, self.name)
        self.check(model, fam)
        return fam.with_structure(self.term(fam))
