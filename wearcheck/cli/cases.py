"""List the case files shipped with wearcheck, or print one.

Any command that takes a CASE accepts a shipped case by name, e.g.
'wearcheck run paper --solver mdr'. 'wearcheck cases NAME > my.toml' copies
one to start a case of your own.
"""

from __future__ import annotations

import sys

from wearcheck import cases


def add_parser(sub):
    p = sub.add_parser("cases", help="list the shipped cases, or print one",
                       description=__doc__)
    p.add_argument("name", nargs="?", metavar="NAME",
                   help="print this shipped case's file (TOML) instead of the list")
    p.add_argument("--paths", action="store_true", help="also show where each file is")
    p.add_argument("--schema", action="store_true",
                   help="print the path of the JSON Schema of case files (for editors: "
                        "put '#:schema PATH' on the first line of a case file)")
    return p


def main(args) -> int:
    if args.schema:
        from wearcheck.cases.json_schema import SCHEMA_FILE
        print(SCHEMA_FILE)
        return 0
    available = cases.shipped_cases()
    if args.name is not None:
        sys.stdout.write(cases.shipped(args.name).read_text(encoding="utf-8"))
        return 0
    width = max(len(n) for n in available)
    for name, path in available.items():
        print(f"{name:<{width}}  {cases.describe(path)}"
              + (f"\n{'':<{width}}  {path}" if args.paths else ""))
    return 0
