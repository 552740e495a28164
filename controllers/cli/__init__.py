"""The runs of the controllers' commands (``fcomp compensate``, ``fcomp sweep``, ``fcomp
export``, ``fcomp plant check``, which tunes the compensators on the plant); importing this
package registers them with the command line (:data:`fcomp.registry.COMMANDS`, entry point
``fcomp.commands``). Their options and help are in :mod:`fcomp.cli`."""

from controllers.cli import compensate, export, plant_check, sweep
from fcomp.registry import COMMANDS

COMMANDS.register("compensate", compensate.run)
COMMANDS.register("sweep", sweep.run)
COMMANDS.register("export", export.run)
COMMANDS.register("plant check", plant_check.run_check)
