"""Arguments shared by the subcommands."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from wearcheck import cases
from wearcheck.cases.case import parse_vary


def add_case_arguments(parser) -> None:
    parser.add_argument("case", type=Path, metavar="CASE",
                        help="case file (TOML), or the name of a shipped case such as paper "
                             "('wearcheck cases' lists them)")
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="SECTION.KEY=VALUE",
                        help="override a case key (repeatable), validated like the file")
    parser.add_argument("--quiet", action="store_true", help="no progress bar, no remarks")


def load_case(args) -> cases.Case:
    """Load the case named on the command line (its remarks: :func:`case_notes`).

    ``args.case`` becomes the case file's path (a shipped case's name resolved),
    which is what the studies hand on to their workers.
    """
    args.case = cases.resolve(args.case)
    return cases.load(args.case, args.overrides)


def case_notes(args, case) -> None:
    """Print the case's remarks (``note:`` lines on stderr) unless quiet.

    A command calls this once its result is in, before it reports it: a refusal
    (exit 2), whether from the command's own checks or from inside a solver, is
    then the one line it prints, never preceded by a remark on a case it did not run.
    """
    if not getattr(args, "quiet", False):
        for text in case.warnings:
            print(f"note: {text}", file=sys.stderr)


def add_cluster_arguments(p) -> None:
    """--scheduler and --workers of the studies on Dask (sweep, refine, fit, fretting-map)."""
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on an existing Dask scheduler, e.g. tcp://host:8786 "
                        "(default: an embedded local cluster)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="worker processes of the embedded cluster (default: one per core)")


def output(args, default: Path) -> Path:
    """The command's output directory: ``--out``, else ``default``; kept in
    ``args.out`` so that an interrupt after it was written names it."""
    args.out = args.out or default
    return args.out


def varied(args) -> dict[str, list]:
    """The ``--vary`` flags, typed once: ``{"section.key": [values]}`` as ``--set`` reads
    them (a relative ``indenter.file`` relative to the case file, as there).

    A key varied twice, or both set and varied, is refused.
    """
    out = {}
    for text in args.vary:
        name, values = parse_vary(text)
        if name in out:
            raise cases.CaseError(f"--vary names the key {name} twice")
        if name == "indenter.file":
            values = [str(Path(args.case).absolute().parent / v)
                      if isinstance(v, str) and not Path(v).is_absolute() else v
                      for v in values]
        out[name] = values
    both = set(out) & {o.partition("=")[0].strip() for o in args.overrides}
    if both:
        raise cases.CaseError(f"key {sorted(both)[0]} is both in --set and --vary")
    return out


def study_exit(rows) -> int:
    """1 if a run of the study failed (said on stderr, with --quiet too: it is an error), else 0."""
    failed = [r for r in rows if r["status"] != "ok"]
    if failed:
        print(f"{len(failed)} of {len(rows)} runs failed", file=sys.stderr)
    return 1 if failed else 0


def add_json_argument(parser, what: str) -> None:
    """``--json``: ``what`` on stdout as JSON, for scripts, instead of the table."""
    parser.add_argument("--json", action="store_true",
                        help=f"print {what} on stdout as JSON instead of the table")


def jsonable(value):
    """``value`` with numpy numbers as Python ones, a non-finite number as null
    (strict JSON has no NaN) and paths as text."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if hasattr(value, "tolist"):           # a numpy array or number
        return jsonable(value.tolist())
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Path):
        return str(value)
    return value


def print_json(value) -> None:
    """``value`` (:func:`jsonable`) as one line of JSON on stdout."""
    print(json.dumps(jsonable(value)))


def verdict(m: dict, out: Path) -> dict:
    """What ``--json`` prints: the comparison's verdict and where its numbers are."""
    return dict(passed=bool(m["passed"]), reference=m.get("reference"),
                pairs={name: bool(pair.get("passed")) for name, pair in m.get("pairs", {}).items()},
                skipped=m.get("skipped", {}), diagnosis=m.get("diagnosis"),
                metrics=str(Path(out) / "metrics.json"), report=str(Path(out) / "report.md"))
