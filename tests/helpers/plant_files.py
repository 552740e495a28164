"""Plant files for tests: a built-in plant's file with some of its lines edited."""

from __future__ import annotations

from pathlib import Path

from plants.planfile import builtin_path


def edited(kind: str, tmp_path: Path, *changes: tuple[str, str]) -> Path:
    """The built-in ``kind`` plant file with each ``(old, new)`` text replaced (every ``old``
    must be there), written to ``tmp_path/<kind>-edited.toml``."""
    text = builtin_path(kind).read_text()
    for old, new in changes:
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / f"{kind}-edited.toml"
    path.write_text(text)
    return path
