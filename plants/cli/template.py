"""The run of ``fcomp plant template KIND`` (options and help: :mod:`fcomp.cli.plant`)."""

from __future__ import annotations

import argparse
import sys

from plants.planfile import template


def run_template(args: argparse.Namespace) -> int:
    """Print the commented plant file of the built-in plant of ``args.kind``."""
    sys.stdout.write(template(args.kind))
    return 0
