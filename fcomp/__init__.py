"""fcomp: friction models, identification, diagnosis and compensation for fluid-power servos."""

from __future__ import annotations

__version__ = "0.1.0"
