"""Exceptions of the package.

Every error a user can cause is a :class:`FcompError` (a ``ValueError``), whose
message is one line naming the problem and, where possible, what to do. The
command line prints that line and exits with status 2.
"""

from __future__ import annotations


class FcompError(ValueError):
    """A problem with user input: names, parameters, files, options."""


class UnknownNameError(FcompError):
    """A model, effect, plant, parameter set, ... name that is not registered."""


class ConvergenceError(FcompError):
    """A simulation or fit that did not converge."""


class FcompWarning(UserWarning):
    """Something suspicious but legal, or a degraded mode (e.g. no usable compile cache).

    ``code`` names the kind (``"compile-cache"``, ...); the command line prints
    the message as one ``fcomp: warning: ...`` line and records it in the
    result's ``warnings`` list.
    """

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code
