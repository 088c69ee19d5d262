"""Start-up of the command line against the import of numpy and scipy (issue 26 §3).

    python benchmarks/bench_startup.py [--rounds 9] [--other PYTHON]

Times, in fresh processes alternated round by round, the floor
``python -c "import numpy, scipy.sparse, scipy.linalg"`` (what any wearcheck
command must load), the bare interpreter, ``import wearcheck``, ``wearcheck
--help`` and ``wearcheck sweep|refine|fit|fretting-map --help`` (the Dask studies'
parsers) and ``wearcheck run hertz --solver mdr`` (a solve of a few ms: the
rest is start-up and writing the run directory), and prints their wall and
CPU seconds and their ratios to the floor. Targets: each ``--help`` within 1×
and ``run hertz`` within 2× of the floor. Every process is this interpreter (the
console script ``wearcheck`` beside it when installed).

``--other PYTHON``: also time the ``--help`` commands of another environment's
wearcheck (e.g. one with the main branch installed) in the same rounds.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

import harness

#: the subcommands that run on Dask; their --help is timed as the bare --help is
DASK_COMMANDS = ("sweep", "refine", "fit", "fretting-map")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=9)
    ap.add_argument("--other", metavar="PYTHON",
                    help="also time the --help commands of this interpreter's environment")
    args = ap.parse_args()
    py, wc = sys.executable, harness.wearcheck_command()
    out = Path(tempfile.mkdtemp(prefix="bench-startup-"))
    commands = [
        ("floor", [py, "-c", "import numpy, scipy.sparse, scipy.linalg"], None),
        ("python -c pass", [py, "-c", "pass"], None),
        ("import wearcheck", [py, "-c", "import wearcheck"], None),
        ("wearcheck --help", [*wc, "--help"], None),
        # the Dask studies' parsers: built without importing the study (nor Dask)
        *((f"wearcheck {name} --help", [*wc, name, "--help"], None)
          for name in DASK_COMMANDS),
        ("wearcheck run hertz --solver mdr", [*wc, "run", "hertz", "--solver", "mdr",
                                              "--quiet", "--out", str(out / "hertz")], None),
    ]
    if args.other:
        other = harness.wearcheck_command(args.other)
        commands += [(f"{args.other}: wearcheck{' ' + name if name else ''} --help",
                      [*other, *([name] if name else []), "--help"], None)
                     for name in ("", *DASK_COMMANDS)]
    print(f"# bench_startup: {harness.load()} (before)\n")
    try:
        timed = harness.alternate(commands, args.rounds)
    finally:
        shutil.rmtree(out, ignore_errors=True)
    print(harness.table(timed, commands[0][0]))
    print(f"\nfloor: python -c \"import numpy, scipy.sparse, scipy.linalg\". {args.rounds} "
          f"rounds after one warm-up round; {harness.load()} (after). Targets: wearcheck "
          "--help <= 1x (and each subcommand's), run hertz <= 2x the floor.")


if __name__ == "__main__":
    main()
