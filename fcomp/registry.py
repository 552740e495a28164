"""Registries: selection by name (models, effects, plants, controllers, studies, commands).

fcomp's own registries (models, effects, ...) are filled by the modules that
define what they hold. The registries of the packages above fcomp (plants,
controllers, studies, and the commands they run for the command line) live
here, at the bottom of fcomp, and are filled by those packages: a registry
with an entry-point ``group`` loads, on its first lookup, every provider
installed under that group (``[project.entry-points."fcomp.plants"]`` etc. of
``pyproject.toml``; a provider is a module that registers when imported). So
fcomp's public face (:mod:`fcomp.api`, :mod:`fcomp.cli`) reaches the packages
above it by name, never by importing them, and a user's package adds its own
plants, controllers, studies or commands by declaring an entry point.

A working copy whose installed metadata predates a group (nothing installed
under it) loads the providers this distribution declares, :data:`PROVIDERS`.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterator
from importlib.metadata import entry_points
from typing import Any, Generic, TypeVar

from fcomp.errors import UnknownNameError

T = TypeVar("T")

#: Entry-point group -> the provider modules this distribution declares under it in
#: ``pyproject.toml`` (``[project.entry-points.GROUP]``); imported when nothing is installed
#: under the group.
PROVIDERS: dict[str, tuple[str, ...]] = {
    "fcomp.plants": ("plants",),
    "fcomp.controllers": ("controllers",),
    "fcomp.studies": ("studies",),
    "fcomp.commands": ("plants.cli", "controllers.cli", "studies.cli"),
}


def load_providers(group: str) -> None:
    """Import every provider of the entry-point ``group`` (they register when imported).

    The entry points installed under ``group``; none installed, the modules of
    :data:`PROVIDERS` (a module of a package this build leaves out is skipped).
    """
    installed = entry_points(group=group)
    if installed:
        for point in installed:
            point.load()
        return
    for name in PROVIDERS.get(group, ()):
        try:
            importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name is None or not (name == exc.name or name.startswith(exc.name + ".")):
                raise


class Registry(Generic[T]):
    """A mapping from public names to objects of one kind.

    Parameters
    ----------
    kind
        What the registry holds, for error messages (``"friction model"``).
    group
        The entry-point group whose providers fill the registry, loaded on the first
        lookup (:func:`load_providers`); ``None``: filled by fcomp's own modules.
    """

    def __init__(self, kind: str, group: str | None = None) -> None:
        self.kind = kind
        self.group = group
        self._items: dict[str, T] = {}
        self._loaded = group is None

    def _load(self) -> None:
        """Load the providers of :attr:`group` once, before the first lookup."""
        if self._loaded or self.group is None:
            return
        self._loaded = True  # first: a provider's own lookups while it registers must not reload
        try:
            load_providers(self.group)
        except BaseException:
            self._loaded = False
            raise

    def register(self, name: str, obj: T, *, replace: bool = False) -> T:
        """Register ``obj`` under ``name``; refuse to shadow an existing name."""
        if not name or not isinstance(name, str):
            raise ValueError(f"{self.kind} name must be a non-empty string, got {name!r}")
        if name in self._items and not replace:
            raise ValueError(f"{self.kind} {name!r} is already registered")
        self._items[name] = obj
        return obj

    def decorator(self, name: str) -> Callable[[T], T]:
        """``@registry.decorator("name")`` registers the decorated object."""

        def wrap(obj: T) -> T:
            return self.register(name, obj)

        return wrap

    def get(self, name: str) -> T:
        """Return the object registered as ``name``.

        Raises
        ------
        UnknownNameError
            With the list of known names.
        """
        self._load()
        try:
            return self._items[name]
        except KeyError:
            known = ", ".join(sorted(self._items))
            raise UnknownNameError(f"unknown {self.kind} {name!r}; known: {known}") from None

    def names(self) -> list[str]:
        """The registered names, sorted."""
        self._load()
        return sorted(self._items)

    def __contains__(self, name: object) -> bool:
        self._load()
        return name in self._items

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())


#: Plant classes by name (:mod:`plants`).
PLANTS: Registry[Any] = Registry("plant", group="fcomp.plants")
#: What fcomp's face uses of the plants beyond their classes, by name (:mod:`plants`):
#: ``compare_plant``, ``PlantComparison``, ``read_plant_file``.
PLANT_TOOLS: Registry[Any] = Registry("plant tool", group="fcomp.plants")
#: Controller classes by name (:mod:`controllers`).
CONTROLLERS: Registry[Any] = Registry("controller", group="fcomp.controllers")
#: Studies by name (:mod:`studies`).
STUDIES: Registry[Any] = Registry("study", group="fcomp.studies")
#: The runs of the commands the packages above fcomp give the command line, by command
#: (``"sweep"``, ``"plant check"``): ``run(args) -> exit status``. The command's options stay
#: in :mod:`fcomp.cli` (``fcomp --help`` imports no package above fcomp).
COMMANDS: Registry[Callable[[Any], int]] = Registry("command", group="fcomp.commands")
