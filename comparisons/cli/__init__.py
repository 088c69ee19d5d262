"""The ``wearcheck`` command: one small module per subcommand.

Each module in this package defines ``add_parser(subparsers)`` (which returns
its parser) and ``main(args)`` (which returns an exit code).

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
import signal
import sys
import warnings

from wearcheck.cases import ArgumentError, WearcheckError

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


def _subcommands():
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if not info.name.startswith("_"):
            yield importlib.import_module(f"{__name__}.{info.name}")


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


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="wearcheck",
        description="Wear of contacts (Reye-Archard, gross slip and fretting): MDR, "
                    "axisymmetric FEM and 3D BEM, cross-checked against each other and "
                    "closed forms.")
    from importlib.metadata import PackageNotFoundError, version
    try:
        v = version("wearcheck")
    except PackageNotFoundError:
        v = "unknown"
    parser.add_argument("--version", action="version", version=f"wearcheck {v}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in _subcommands():
        p = module.add_parser(sub)
        p.description = plain(p.description)
        for action in p._actions:
            action.help = plain(action.help)
        p.set_defaults(_main=module.main)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    args, extra = parser.parse_known_args(argv)
    if extra:
        _unrecognized(args.command, argv, extra)
    from wearcheck.comparisons.rundir import set_command
    set_command(["wearcheck", *argv])
    name = f"wearcheck {args.command}"
    previous = None
    try:
        previous = signal.signal(signal.SIGTERM, _on_sigterm)
    except ValueError:  # not the main thread (e.g. called from a test's thread)
        pass
    try:
        with warnings.catch_warnings():
            # library warnings (numpy overflow inside a solver that then reports
            # the failure itself, Dask, pyvista) are not the user's business;
            # wearcheck's own remarks are printed as "note:" lines
            warnings.simplefilter("ignore")
            os.environ.setdefault("PYTHONWARNINGS", "ignore")  # Dask worker processes
            return int(args._main(args) or 0)
    except WearcheckError as exc:
        # a study's argument is named by its flag here, by its Python name in Python
        said = exc.on_command_line() if isinstance(exc, ArgumentError) else exc
        print(f"{name}: error: {_one_line(said)}", file=sys.stderr)
        return exc.exit_code
    except Terminated:
        print(f"{name}: terminated; nothing incomplete was written", file=sys.stderr)
        return EXIT_TERMINATED
    except KeyboardInterrupt:
        print(f"{name}: interrupted; nothing was written", file=sys.stderr)
        return EXIT_INTERRUPTED
    except MemoryError:
        print(f"{name}: error: out of memory; nothing was written (reduce the resolution)",
              file=sys.stderr)
        return EXIT_IO
    except OSError as exc:
        where = f" '{exc.filename}'" if getattr(exc, "filename", None) else ""
        print(f"{name}: error: cannot write or read{where}: "
              f"{_one_line(exc.strerror or exc)}; nothing incomplete was left",
              file=sys.stderr)
        return EXIT_IO
    except Exception as exc:
        if os.environ.get("WEARCHECK_TRACEBACK"):
            raise
        print(f"{name}: internal error: {type(exc).__name__}: {_one_line(exc)[:300]} "
              "(a bug in wearcheck; WEARCHECK_TRACEBACK=1 shows where)", file=sys.stderr)
        return EXIT_INTERNAL
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":
    sys.exit(main())
