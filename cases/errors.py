"""Exceptions shared by every part of wearcheck.

They carry a message meant for the user; the command line prints it without a
traceback and exits non-zero.
"""


class WearcheckError(Exception):
    """Base class of every error wearcheck reports to the user."""

    exit_code = 1


class CaseError(WearcheckError):
    """The case (file, override or combination of keys) is not valid."""

    exit_code = 2


class SolverError(WearcheckError):
    """A numerical failure: no convergence, instability, a domain too small.

    Raised instead of returning a result that cannot be trusted.
    """

    exit_code = 3


class CaseWarning(UserWarning):
    """A remark on a valid case whose results are approximate (e.g. its load past a
    yield estimate); also kept in ``Case.warnings``, which the command line prints
    as ``note:`` lines and every output records."""


#: the texts :func:`warn_once` has issued in this process
_WARNED: set[str] = set()


def warn_once(text: str, category=CaseWarning) -> None:
    """Issue ``text`` as a warning once per process, pointing at the first caller
    outside wearcheck (a case loaded, derived or swept many times warns once)."""
    if text in _WARNED:
        return
    _WARNED.add(text)
    import os
    import sys
    import warnings
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep
    inside = tuple(root + name + os.sep for name in
                   ("cases", "mdr", "fem", "bem", "comparisons", "wearcheck", "numerics", "ccx"))
    level, frame = 2, sys._getframe(1)
    while frame is not None and frame.f_code.co_filename.startswith(inside):
        level, frame = level + 1, frame.f_back
    warnings.warn(text, category, stacklevel=level)
