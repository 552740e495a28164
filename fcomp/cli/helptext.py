"""Plain-text help: every ``--help`` goes through :class:`HelpFormatter`, which writes the
docstrings' reST plainly."""

from __future__ import annotations

import argparse
import re

_REST = [
    (re.compile(r":(?:class|func|meth|mod|data|attr|exc|obj|ref|doc):`~?([^`<]*?)(?:\s*<[^>]*>)?`"),
     lambda m: m.group(1).rsplit(".", 1)[-1] if "." in m.group(1) and "(" not in m.group(1)
     else m.group(1)),
    (re.compile(r"``(.+?)``", re.S), lambda m: m.group(1)),
    (re.compile(r"(?<![\w`])`([^`\n]+)`_{0,2}(?![\w`])"), lambda m: m.group(1)),
    (re.compile(r"(?<![\w*])\*\*(?=\S)([^*\n]+?)(?<=\S)\*\*(?![\w*])"), lambda m: m.group(1)),
    (re.compile(r"(?<![\w*'\\])\*(?=[A-Za-z])([A-Za-z][^*\n]*?)(?<=[A-Za-z.])\*(?![\w*])"),
     lambda m: m.group(1)),
    (re.compile(r"(\S)::$", re.M), lambda m: m.group(1) + ":"),
    (re.compile(r"^(\s*)::$", re.M), lambda m: ""),
    (re.compile(r"\\\\"), lambda m: "\\"),
]


def plain_text(text: str) -> str:
    """``text`` (a module docstring in reST) as plain text for ``--help``: roles
    (``:class:`~a.B``` -> ``B``), literals (````x```` -> ``x``), emphasis and ``Example::``
    written plainly."""
    for pattern, repl in _REST:
        text = pattern.sub(repl, text)
    return text


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """The help of every command: descriptions as written (line breaks kept), in plain
    text (:func:`plain_text`), an option listed by its canonical spelling only (the
    deprecated ones of :func:`add_option` stay out of the help)."""

    def _format_action_invocation(self, action: argparse.Action) -> str:
        hidden = getattr(action, "deprecated", ())
        if not hidden:
            return super()._format_action_invocation(action)
        shown = argparse.Action([s for s in action.option_strings if s not in hidden],
                                action.dest, nargs=action.nargs, metavar=action.metavar)
        return super()._format_action_invocation(shown)

    def _expand_help(self, action: argparse.Action) -> str:
        return plain_text(super()._expand_help(action))

    def _format_text(self, text: str) -> str:
        return super()._format_text(plain_text(text))
