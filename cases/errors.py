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


_UNSET = object()


class ArgumentError(CaseError):
    """An argument of a study refused: said as the caller named it.

    ``str(exc)`` names the Python argument (``tolerance = 0.0: must be > 0``,
    ``vary['wear.mu']: ...``); :meth:`on_command_line` names the flag the command
    line gives it (``--tolerance 0.0: ...``, ``--vary wear.mu: ...``), so one check
    serves both. ``problem`` may name other arguments as ``{name}`` for each name
    in ``also``.
    """

    def __init__(self, argument: str, problem: str, *, key: str | None = None,
                 value=_UNSET, also: tuple[str, ...] = ()):
        self.argument, self.problem, self.key, self.value = argument, problem, key, value
        self.also = tuple(also)
        super().__init__(self.said(command_line=False))

    @staticmethod
    def flag(argument: str) -> str:
        """The command line's flag for a Python argument: ``step_hat`` -> ``--step-hat``."""
        return "--" + argument.replace("_", "-")

    def said(self, command_line: bool) -> str:
        name = self.flag if command_line else (lambda a: a)
        head = name(self.argument)
        if self.key is not None:
            head += f" {self.key}" if command_line else f"[{self.key!r}]"
        if self.value is not _UNSET:
            value = self.value
            if command_line:
                text = (",".join(str(v) for v in value) if isinstance(value, (list, tuple))
                        else str(value))
                head += f" {text}"
            else:
                head += f" = {value!r}"
        problem = self.problem
        for other in self.also:
            problem = problem.replace("{" + other + "}", name(other))
        return f"{head}: {problem}"

    def on_command_line(self) -> str:
        """The message with the command line's flags."""
        return self.said(command_line=True)


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
