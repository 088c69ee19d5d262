"""Exceptions shared by every part of wearcheck, and the remarks on a run (:class:`RunWarning`).

The exceptions carry a message meant for the user; the command line prints it
without a traceback and exits non-zero.
"""


import sys
import threading
import warnings


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


#: the kinds of remark said through :mod:`warnings` in this process (:func:`warn_once`)
_SAID: set[str] = set()
_SAID_LOCK = threading.Lock()


def warn_once(kind: str, text: str) -> None:
    """Issue ``text`` as a :class:`RunWarning` the first time a remark of ``kind`` is
    made in this process, pointing at the first caller outside wearcheck.

    Once per process whatever the thread: the record is wearcheck's own, not Python's
    warnings registry, which forgets what it said whenever any code enters
    ``warnings.catch_warnings`` (libraries and test harnesses do, in every thread).
    A remark that the filters ignore where it is made (the command line prints
    remarks as note lines; a fit's forward runs) is not used up; one they make an
    error is raised every time.
    """
    frame = sys._getframe(1)
    while frame is not None and \
            str(frame.f_globals.get("__name__", "")).split(".")[0] == "wearcheck":
        frame = frame.f_back
    if frame is None:
        frame = sys._getframe(1)
    module = frame.f_globals.get("__name__", "<string>")
    if _action(text, module, frame.f_lineno) == "ignore":
        return
    with _SAID_LOCK:
        if kind in _SAID:
            return
        _SAID.add(kind)
    try:
        # (no registry: the record above says it once; Python's would be reset. No
        # module_globals: their loader is asked for the source, and that of a
        # `python -c` program raises ImportError; the line is read by file name)
        warnings.warn_explicit(text, RunWarning, frame.f_code.co_filename, frame.f_lineno,
                               module=module, registry=None)
    except BaseException:
        with _SAID_LOCK:
            _SAID.discard(kind)
        raise


def _action(text: str, module: str, lineno: int) -> str:
    """The action of the first of :data:`warnings.filters` that a RunWarning ``text``
    issued from ``module`` at ``lineno`` matches (as :func:`warnings.warn_explicit` finds it)."""
    for action, message, category, mod, line in warnings.filters:
        if (message is None or message.match(text)) and issubclass(RunWarning, category) \
                and (mod is None or mod.match(module)) and line in (0, lineno):
            return action
    return warnings.defaultaction
