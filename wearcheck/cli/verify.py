"""``wearcheck verify CASE RESULTS [--out DIR]``: results produced elsewhere (your FE
model, a lab's script) judged against the certified reference of the case, or with
``--reference-solver NAME`` against a fresh wearcheck run.

RESULTS is a directory holding history.csv (and optionally stages.csv), a .pvd or
.vtu file (or a directory holding one .pvd), or CalculiX output (.frd, .dat).
``--map name=field`` names your columns, arrays or result blocks, with a unit in
brackets where they are not SI (--map 'p [MPa]=CONTACT.CPRESS'). The formats are
in docs/verify.md.

Exit code 0 when every check is within the case's [compare] tolerances, 1 when
the verification fails (DIR is still written, with the failing verdict), 2 for
bad input (a file that cannot be read: one line naming the file, row and column).
"""

from __future__ import annotations

import sys
from pathlib import Path

from wearcheck import registry
from wearcheck.external import parse_mapping
from ._common import (add_case_arguments, case_notes, load_case, output, print_json,
                      verdict)
from wearcheck.comparisons.present.verify_report import print_summary
from wearcheck.studies.verify import verify


def add_parser(sub):
    p = sub.add_parser("verify", help="judge results produced elsewhere against the "
                                      "certified reference (or a fresh run)",
                       description=__doc__)
    add_case_arguments(p)
    p.add_argument("results", type=Path, metavar="RESULTS",
                   help="a directory with history.csv (and stages.csv), a .pvd/.vtu file, or "
                        "CalculiX output (.frd, .dat)")
    p.add_argument("--map", dest="mapping", action="append", default=[],
                   metavar="NAME=FIELD",
                   help="which of your columns, arrays or result blocks is which quantity, "
                        "e.g. --map force=Fz, --map 'p [MPa]=CONTACT.CPRESS' (repeatable)")
    p.add_argument("--reference-solver", default=None, metavar="NAME",
                   help="judge against a fresh run of this solver instead of the certified "
                        "reference (registered: " + ", ".join(registry.names()) + ")")
    p.add_argument("--out", type=Path, default=None,
                   help="output directory (default: runs/verify-<case name>)")
    p.add_argument("--json", action="store_true",
                   help="print the verdict on stdout as JSON (passed, each check's verdict, "
                        "the path of metrics.json) instead of the summary")
    return p


def main(args) -> int:
    case = load_case(args)
    mapping = parse_mapping(args.mapping)
    out = output(args, Path("runs") / f"verify-{args.case.stem}")
    m = verify(case, args.results, out, mapping=mapping,
               reference_solver=args.reference_solver, quiet=args.quiet)
    case_notes(args, case)
    if args.json:
        print_json(verdict(m, out))
    elif not args.quiet:
        print_summary(m, out)
    if not m["passed"]:
        print(f"wearcheck verify: the results FAILED (see {out}/report.md)", file=sys.stderr)
        return 1
    return 0
