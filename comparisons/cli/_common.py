"""Arguments shared by the subcommands."""

from __future__ import annotations

import sys
from pathlib import Path

from wearcheck import cases


def add_case_arguments(parser) -> None:
    parser.add_argument("case", type=Path, help="case file (TOML)")
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="SECTION.KEY=VALUE",
                        help="override a case key (repeatable), validated like the file")
    parser.add_argument("--quiet", action="store_true", help="no progress bar, no remarks")


def load_case(args) -> cases.Case:
    """Load the case named on the command line; print its remarks unless quiet."""
    case = cases.load(args.case, args.overrides)
    if not getattr(args, "quiet", False):
        for text in case.warnings:
            print(f"note: {text}", file=sys.stderr)
    return case
