"""The ``wearcheck`` command: one small module per subcommand.

Each module in this package defines ``add_parser(subparsers)`` (which returns
its parser) and ``main(args)`` (which returns an exit code).
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys

from wearcheck.cases import WearcheckError


def _subcommands():
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if not info.name.startswith("_"):
            yield importlib.import_module(f"{__name__}.{info.name}")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="wearcheck",
        description="Gross-slip Reye-Archard wear of axisymmetric contacts: MDR and FEM, "
                    "cross-checked.")
    from importlib.metadata import PackageNotFoundError, version
    try:
        v = version("wearcheck")
    except PackageNotFoundError:
        v = "unknown"
    parser.add_argument("--version", action="version", version=f"wearcheck {v}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in _subcommands():
        p = module.add_parser(sub)
        p.set_defaults(_main=module.main)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser.parse_args(argv)
    from wearcheck.comparisons.rundir import set_command
    set_command(["wearcheck", *argv])
    try:
        return int(args._main(args) or 0)
    except WearcheckError as exc:
        print(f"wearcheck {args.command}: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print(f"wearcheck {args.command}: interrupted; nothing was written", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
