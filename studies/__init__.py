"""Studies, selected by name (``fcomp study NAME``): each writes summary.json, figures, report.html.

Every module listed in :data:`_MODULES` exposes ``STUDY`` (a
:class:`studies.base.Study`) and ``main(config) -> results``; it is
registered under ``STUDY.name``. To add a study, write its module and add
its name to :data:`_MODULES`; ``all`` runs every registered study. A user
registers their own with ``STUDIES.register(study.name, study)``.
"""

from __future__ import annotations

import importlib

from fcomp import registry
from fcomp.registry import Registry
from studies.base import Study, StudyConfig, StudyError

#: fcomp's registry of studies (:mod:`fcomp.registry`, entry point ``fcomp.studies``),
#: filled here.
STUDIES: Registry[Study] = registry.STUDIES

#: Study modules of the package, in the order ``all`` runs them (``all`` itself last).
_MODULES = (
    "coulomb_viscous",
    "friction_models",
    "presliding",
    "missing_physics",
    "compensators",
    "all",
)

for _module in _MODULES:
    _study = importlib.import_module(f"studies.{_module}").STUDY
    STUDIES.register(_study.name, _study)

__all__ = ["STUDIES", "Study", "StudyConfig", "StudyError"]
