"""The ``wearcheck`` command: one small module per subcommand.

Each module in this package defines ``add_parser(subparsers)`` (which returns
its parser) and ``main(args)`` (which returns an exit code), and has a line in
:data:`SUBCOMMANDS` (its name and one-line help): only the module of the
command being run is imported, so ``wearcheck --help`` and ``wearcheck run``
do not load what the studies, the renderer or the exports need.

Exit codes: 0 success; 1 a failed comparison or study level; 2 bad input (a
case, an option, an output path wearcheck may not write); 3 a numerical
failure; 4 a file could not be written or read (disk full, permissions, I/O
error: nothing incomplete is left); 70 an internal error (a bug: one line,
``WEARCHECK_TRACEBACK=1`` shows the traceback); 130 interrupted (SIGINT);
143 terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import re
import select
import signal
import sys
import warnings

from wearcheck.cases import ArgumentError, WearcheckError
from wearcheck.outputs import installed_from, watching_builds
from wearcheck.rundir import set_command
from wearcheck.extras import missing

#: exit codes beyond those of the WearcheckError classes
EXIT_IO, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_TERMINATED = 4, 70, 130, 143


class Terminated(KeyboardInterrupt):
    """SIGTERM, handled like SIGINT: whatever is being written is abandoned cleanly."""


def _on_sigterm(signum, frame):
    raise Terminated()


def _one_line(text: str) -> str:
    """A message as one printable line: whitespace runs collapsed, control
    characters (e.g. from a fuzzed key name) shown as escapes, not sent to the terminal."""
    text = " ".join(str(text).split())
    return "".join(ch if ch.isprintable() else ascii(ch)[1:-1] for ch in text)


#: subcommand -> its one-line help in ``wearcheck --help``. The module is the
#: name with "-" as "_" in this package; its ``add_parser`` gives the same help
#: (tests/test_cli_startup.py checks both). A new subcommand: its module here
#: and a line in this table.
SUBCOMMANDS = {
    "cases": "list the shipped cases, or print one",
    "compare": "run every solver that supports a case and compare them",
    "export": "write ParaView files (VTU/PVD) of a run directory",
    "fit": ("fit K (and n) of a ball, and K of a counterface that wears, to measured "
            "scars, tracks, volumes or depths, with 95 %% intervals"),
    "fretting-map": "running-condition map of a fretting case (partial/gross slip, "
                    "wear per cycle), on Dask",
    "mesh": "generate (or fetch from the cache) the FEM mesh of a case",
    "refine": "refinement study: one solver at several resolutions",
    "reference": "write a certified reference solution as a run directory",
    "render": "render PNG pictures of a run directory (no display needed)",
    "run": "run one solver on a case and write a run directory",
    "sweep": "one run per value of one or more case keys, on Dask",
    "verify": "judge results produced elsewhere against the certified reference (or a "
              "fresh run)",
}


#: subcommand -> examples shown at the end of its --help: (command line, what it
#: does). Every one must parse (tests/test_cli_text.py).
EXAMPLES = {
    "cases": [("wearcheck cases", "the shipped cases, one line each"),
              ("wearcheck cases paper > my_case.toml", "copy one to start your own")],
    "compare": [("wearcheck compare paper --out runs/paper", "MDR, FEM and BEM on the paper's "
                 "case, with verdicts"),
                ("wearcheck compare paper --solvers mdr,fem --set wear.mu=0.5",
                 "two solvers, one key changed")],
    "export": [("wearcheck export runs/paper-fem --revolve 36",
                "ParaView files, the FEM fields revolved into a 3D solid")],
    "fit": [("wearcheck fit ball_on_flat scars.csv --fit wear.specific_rate",
             "K with its 95 % interval from a sheet of cycles and scar diameters"),
            ("wearcheck fit ball_on_flat scars.csv --fit wear.specific_rate --out runs/fit "
             "--json", "the same as JSON, and a fit directory with the figure"),
            ("wearcheck fit my_ball.toml sheet.csv --fit wear.specific_rate "
             "--fit wear.pressure_exponent", "K and the wear law's exponent n (a scan over n)"),
            ("wearcheck fit ball_on_flat_steel g133.csv --fit wear.specific_rate "
             "--fit counterface.specific_rate --set bem.grid=64",
             "the ball's K and the counterface's, both bodies wearing (BEM)")],
    "fretting-map": [("wearcheck fretting-map fretting --vary fretting.amplitude=0.1e-6,0.3e-6,"
                      "1e-6 --set fretting.cycles=1000", "partial or gross slip, and the wear "
                      "per cycle, at three amplitudes")],
    "mesh": [("wearcheck mesh paper", "the FEM mesh of the paper's case (cached)")],
    "refine": [("wearcheck refine paper --solver mdr --levels 200,400,800",
                "three MDR grids: orders and converged level")],
    "reference": [("wearcheck reference --list", "the certified references shipped"),
                  ("wearcheck reference paper --out runs/paper-reference",
                   "the paper case's reference as a run directory")],
    "render": [("wearcheck render runs/paper-mdr", "PNG pictures of a run directory")],
    "run": [("wearcheck run paper --solver mdr", "the MDR on the paper's case, into "
             "runs/paper-mdr"),
            ("wearcheck run my_case.toml --solver fem --set wear.mu=0.5 --out runs/mu-0.5",
             "a case file of your own, one key changed"),
            ("wearcheck run hertz --solver mdr --json", "a summary on stdout as JSON")],
    "verify": [("wearcheck verify paper my_results.csv",
                "your model's history and stages against the paper case's reference"),
               ("wearcheck verify paper export.csv --map 's [mm]=Time' --out runs/verify",
                "an FE export whose column names and units are given, with a report")],
    "sweep": [("wearcheck sweep paper --vary wear.mu=0.2,0.3,0.5 --solver mdr",
               "one run per value, summarised in sweep.csv")],
}


def _epilog(command: str) -> str | None:
    """The examples of ``command`` as its help's last section."""
    lines = [f"  {line}\n      {what}" for line, what in EXAMPLES.get(command, ())]
    return "examples:\n" + "\n".join(lines) if lines else None


class _HelpFormatter(argparse.HelpFormatter):
    """argparse's, with an indented paragraph (the examples) kept as written."""

    def _fill_text(self, text, width, indent):
        paragraphs = text.split("\n\n")
        return "\n\n".join(
            "\n".join(indent + line for line in part.splitlines())
            if part.startswith("examples:") else super(_HelpFormatter, self)._fill_text(
                part, width, indent) for part in paragraphs)


def module_name(command: str) -> str:
    """The module of this package that implements ``command``."""
    return f"{__name__}.{command.replace('-', '_')}"


def _unlisted() -> list[str]:
    """Subcommand modules of this package missing from SUBCOMMANDS (imported
    eagerly, so that they work; tests/test_cli_startup.py asks for their line)."""
    listed = {name.replace("-", "_") for name in SUBCOMMANDS}
    return sorted(info.name for info in pkgutil.iter_modules(__path__)
                  if not info.name.startswith("_") and info.name not in listed)


def _load(command: str):
    # imported when the command runs, not with the parser: importing every
    # subcommand's module made `wearcheck --help` slower than loading numpy and
    # scipy (the studies load scipy.optimize, asyncio; docs/performance.md,
    # "Start-up")
    return importlib.import_module(module_name(command))


def plain(text: str | None) -> str | None:
    """Help text without reST markup: ``x`` and :role:`x` become x (the module
    docstrings that serve as descriptions are written for Sphinx too)."""
    if not text:
        return text
    text = re.sub(r":[a-z]+:`~?([^`]+)`", r"\1", text)
    return text.replace("``", "")


class _Parser(argparse.ArgumentParser):
    """argparse with its usage errors on one line (exit 2), like every other error."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {_one_line(message)} (see {self.prog} --help)\n")


def _unrecognized(command: str, argv: list, extra: list) -> None:
    """Unknown arguments, named with the subcommand; ``--set key value`` (a space for
    the "=") gets the spelling that works."""
    hint = ""
    for i, token in enumerate(argv[:-2]):
        if token in ("--set", "--vary") and "=" not in argv[i + 1] \
                and argv[i + 2] == extra[0]:
            hint = (f"; {token} takes one word, section.key=value: "
                    f"{token} {argv[i + 1]}={extra[0]}")
            break
    prog = f"wearcheck {command}"
    sys.stderr.write(f"{prog}: error: unrecognized arguments: {' '.join(extra)}{hint} "
                     f"(see {prog} --help)\n")
    raise SystemExit(2)


class _Version(argparse.Action):
    """``--version``: the installed version, looked up only when asked for
    (importlib.metadata is most of a bare ``--help``'s own imports)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS,
                         help="show program's version number and exit")

    def __call__(self, parser, namespace, values, option_string=None):
        from importlib.metadata import PackageNotFoundError, version
        try:
            v = version("wearcheck")
        except PackageNotFoundError:
            v = "unknown"
        parser._print_message(f"wearcheck {v}\n", sys.stdout)   # as argparse's "version"
        parser.exit()


def build_parser(commands=None) -> argparse.ArgumentParser:
    """The ``wearcheck`` parser; ``commands``: the subcommands whose own parsers
    are built (their modules imported), the others listed by name and help
    only. None: every one (the documentation's reference and the tests)."""
    parser = _Parser(
        prog="wearcheck",
        description="Wear of contacts (Reye-Archard, gross slip and fretting): MDR, "
                    "axisymmetric FEM and 3D BEM, cross-checked against each other and "
                    "closed forms.")
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    unlisted = _unlisted()
    names = sorted([*SUBCOMMANDS, *unlisted])
    for name in names:
        if commands is not None and name not in commands and name not in unlisted:
            sub.add_parser(name, help=SUBCOMMANDS[name], add_help=False)
            continue
        module = _load(name)
        p = module.add_parser(sub)
        p.description = plain(p.description)
        p.epilog, p.formatter_class = _epilog(name), _HelpFormatter
        for action in p._actions:
            action.help = plain(action.help)
        p.set_defaults(_main=module.main)
    return parser


def _reader_gone() -> bool:
    """Whether standard output is a pipe whose reader has closed it
    (``wearcheck cases | head -1``); if so, what is left to write goes nowhere,
    quietly, as for any command line tool."""
    try:
        fd = sys.stdout.fileno()
        poller = select.poll()          # a pipe without a reader polls as an error
        poller.register(fd, select.POLLOUT)
        if not any(events & select.POLLERR for _, events in poller.poll(0)):
            return False
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, fd)
        os.close(devnull)
        return True
    except (OSError, ValueError, AttributeError):   # no fd, no poll (Windows)
        return False


def _command(argv: list) -> str | None:
    """The subcommand named on the command line (the first word that is not an
    option: the top level's options take no value)."""
    return next((a for a in argv if not a.startswith("-")), None)


def _closing() -> None:
    """The command has ended: a Ctrl-C from here on is ignored, while the interpreter
    closes (its own finalisation, about 0.2 s with numpy and scipy loaded, restores
    Ctrl-C's default, which would end the process silently, exit status 130 with
    the command's output whole and its last line printed). The process exits with
    the command's code."""
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:   # not the main thread
        pass


def _after_output(args, built) -> str:
    """What an interrupt leaves: the command's output, if it was already in place."""
    out = getattr(args, "out", None)
    if out is not None and installed_from(os.path.abspath(out), built):
        return f" after its output was complete: '{out}' holds it, whole"
    return ""


def main(argv=None) -> int:
    """Run the command ``argv`` (a list of words) and return its exit code.

    Without ``argv`` it is the process's own command line (the console script,
    ``python -m wearcheck``): once the command has ended, Ctrl-C is ignored for the
    rest of the process (:func:`_closing`).
    """
    program = argv is None
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser({_command(argv)})
    args, extra = parser.parse_known_args(argv)
    if extra:
        _unrecognized(args.command, argv, extra)
    set_command(["wearcheck", *argv])
    name = f"wearcheck {args.command}"
    previous = None
    try:
        previous = signal.signal(signal.SIGTERM, _on_sigterm)
    except ValueError:  # not the main thread (e.g. called from a test's thread)
        pass
    built: set = set()
    try:
        with warnings.catch_warnings(), watching_builds() as built:
            # library warnings (numpy overflow inside a solver that then reports
            # the failure itself, Dask, pyvista) are not the user's business;
            # wearcheck's own remarks are printed as "note:" lines
            warnings.simplefilter("ignore")
            os.environ.setdefault("PYTHONWARNINGS", "ignore")  # Dask worker processes
            code = int(args._main(args) or 0)
            sys.stdout.flush()     # a reader that has gone shows here, not at exit
            if program:
                # (inside the try: an interrupt before this is the one said below)
                _closing()
            return code
    except WearcheckError as exc:
        # a study's argument is named by its flag here, by its Python name in Python
        said = exc.on_command_line() if isinstance(exc, ArgumentError) else exc
        print(f"{name}: error: {_one_line(said)}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt as exc:
        if program:
            _closing()     # a second Ctrl-C does not cut this message short
        said = "terminated" if isinstance(exc, Terminated) else "interrupted"
        print(f"{name}: {said}{_after_output(args, built)}; nothing incomplete was written",
              file=sys.stderr)
        return EXIT_TERMINATED if isinstance(exc, Terminated) else EXIT_INTERRUPTED
    except MemoryError:
        print(f"{name}: error: out of memory; nothing was written (reduce the resolution)",
              file=sys.stderr)
        return EXIT_IO
    except OSError as exc:
        if isinstance(exc, BrokenPipeError) and _reader_gone():
            return 0        # our reader has gone (`wearcheck cases | head -1`): nothing to say
        where = f" '{exc.filename}'" if getattr(exc, "filename", None) else ""
        print(f"{name}: error: cannot write or read{where}: "
              f"{_one_line(exc.strerror or exc)}; nothing incomplete was left",
              file=sys.stderr)
        return EXIT_IO
    except Exception as exc:
        found = missing("this command", exc)   # an optional module not imported by need()
        if found is not None:
            print(f"{name}: error: {_one_line(found)}", file=sys.stderr)
            return found.exit_code
        if os.environ.get("WEARCHECK_TRACEBACK"):
            raise
        print(f"{name}: internal error: {type(exc).__name__}: {_one_line(exc)[:300]} "
              "(a bug in wearcheck; WEARCHECK_TRACEBACK=1 shows where)", file=sys.stderr)
        return EXIT_INTERNAL
    finally:
        if program:
            _closing()     # (an error's exit as well)
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":
    sys.exit(main())
