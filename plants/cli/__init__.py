"""The runs of the plants' commands (``fcomp simulate``, ``fcomp plant template``); importing
this package registers them with the command line (:data:`fcomp.registry.COMMANDS`, entry
point ``fcomp.commands``). Their options and help are in :mod:`fcomp.cli`."""

from fcomp.registry import COMMANDS
from plants.cli import simulate, template

COMMANDS.register("simulate", simulate.run)
COMMANDS.register("plant template", template.run_template)
