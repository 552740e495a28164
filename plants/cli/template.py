"""The run of ``fcomp plant template KIND`` (options and help: :mod:`fcomp.cli.plant`)."""

from __future__ import annotations

import argparse

from fcomp.cli.emit import write_stdout
from plants.planfile import template


def run_template(args: argparse.Namespace) -> int:
    """Print the commented plant file of the built-in plant of ``args.kind``."""
    write_stdout(template(args.kind), "the template")
    return 0
