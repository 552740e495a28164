"""Exceptions of the package.

Every error a user can cause is a :class:`FcompError` (a ``ValueError``), whose
message is one line naming the problem and, where possible, what to do. The
command line prints that line and exits with status 2.

Library messages speak the library's terms: they name a setting by the
Python parameter that sets it (``max_steps``, ``duration``, ``coupling``),
marked with :func:`term`; ``str(error)`` shows the plain name, and the
command line shows the option that sets it there (``--max-steps``;
:meth:`FcompError.render` with :data:`fcomp.cli.common.OPTIONS`).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping

#: Delimits a parameter name marked by :func:`term` inside a message.
_MARK = "\x1f"
_TERM = re.compile(f"{_MARK}([^{_MARK}]*){_MARK}")


def term(name: str) -> str:
    """``name`` (a library parameter, e.g. ``max_steps``) marked in a message, so that the
    command line can write it as its option."""
    return f"{_MARK}{name}{_MARK}"


def render_terms(message: str, names: Mapping[str, str] | Callable[[str], str] | None = None
                 ) -> str:
    """``message`` with every :func:`term` written as ``names[term]`` (default: the term)."""
    def name(m: re.Match[str]) -> str:
        if callable(names):
            return names(m[1])
        return (names or {}).get(m[1], m[1])

    return _TERM.sub(name, message)


class FcompError(ValueError):
    """A problem with user input: names, parameters, files, options.

    Parameters
    ----------
    message
        One line; library parameters in it marked with :func:`term`.
    """

    def __init__(self, message: str = "") -> None:
        super().__init__(render_terms(message))
        self.template = message

    def render(self, names: Mapping[str, str]) -> str:
        """The message with the marked parameters written as ``names`` gives them."""
        return render_terms(self.template, names)


class UnknownNameError(FcompError):
    """A model, effect, plant, parameter set, ... name that is not registered."""


class FileFormatError(FcompError):
    """A model file or a plant file that this release cannot read: malformed, of another
    format or version, naming an unknown effect, or with a bad value (one line, naming the
    file and the key)."""


class ConvergenceError(FcompError):
    """A simulation or fit that did not converge."""


class FcompWarning(UserWarning):
    """Something suspicious but legal, or a degraded mode (e.g. no usable compile cache).

    ``code`` names the kind (``"compile-cache"``, ...); the command line prints
    the message as one ``fcomp: warning: ...`` line and records it in the
    result's ``warnings`` list.
    """

    def __init__(self, code: str, message: str) -> None:
        super().__init__(render_terms(message))
        self.code = code
        self.template = message


def deprecation_message(old: str, new: str) -> str:
    """The one line naming a deprecated spelling ``old`` and the one to use instead,
    ``new``: the command line prints it after ``fcomp: warning:``, the Python API raises it
    as a :class:`DeprecationWarning` (:func:`deprecated`)."""
    return (f"{old} is deprecated, use {new} (the old spelling will be removed in the next "
            "release)")


def deprecated(old: str, new: str, stacklevel: int = 3) -> None:
    """Warn (:class:`DeprecationWarning`, at the caller's caller by default) that ``old``
    is deprecated in favour of ``new`` (:func:`deprecation_message`)."""
    import warnings

    warnings.warn(deprecation_message(old, new), DeprecationWarning, stacklevel=stacklevel)
