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


class RunWarning(UserWarning):
    """A remark on a run that still gives a result: half-space theory stretched, an approximation.

    Issued once per run through :mod:`warnings`; the solver registry also
    records it in the run's ``info["warnings"]`` (so ``meta.json`` has it) and
    the command line prints it as a ``note:`` line.
    """
