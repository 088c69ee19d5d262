"""``wearcheck fit CASE MEASUREMENTS.csv --fit KEY [--fit KEY]``.

Fits the ball's specific wear rate K (and the wear law's pressure exponent n)
to measured scar diameters, ball volumes or central wear depths by least
squares against the MDR (the ball alone, its elastic contact included); with
a counterface that wears, the ball's K and the counterface's K_flat
(counterface.specific_rate) to the ball's and the track's measurements (track
width, depth, cross-section, volume) against the BEM's long-stroke model of
both bodies wearing. With 95 % intervals, each measurement's residual, the
lab formula's K beside it and a warning when the residuals say the model does
not fit (exit code 1, as a failed comparison). The CSV names its columns with
units, e.g. ``cycles, D [um], ± D [um], track depth [um]`` (docs/fitting.md).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from wearcheck.cases import CaseError
from wearcheck.outputs import check_output
from wearcheck.rundir import jsonable
from ._common import add_case_arguments, add_cluster_arguments, case_notes, load_case


def add_parser(sub):
    p = sub.add_parser("fit", help="fit K (and n) of a ball, and K of a counterface that "
                                   "wears, to measured scars, tracks, volumes or depths, "
                                   "with 95 %% intervals",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_case_arguments(p)
    p.add_argument("measurements", type=Path, metavar="MEASUREMENTS.csv",
                   help="the measurement sheet: cycles or s, and any of D, V, h (and the "
                        "track's width, depth, area, volume) with units, e.g. 'cycles, "
                        "D [um], ± D [um]'")
    p.add_argument("--fit", dest="keys", action="append", required=True, metavar="KEY",
                   help="a case key to fit (repeatable): wear.specific_rate, and optionally "
                        "wear.pressure_exponent (a scan over n on Dask); "
                        "counterface.specific_rate (a scan over K_flat/K_ball, BEM runs)")
    p.add_argument("--exponents", type=_exponents, default=None, metavar="N1,N2,...",
                   help="with --fit wear.pressure_exponent: the exponents of the scan, at "
                        "least 4 in [1, 4] (default 1,1.25,...,4; each is one MDR run, and "
                        "runs with n != 1 are slow: docs/fitting.md)")
    p.add_argument("--out", type=Path, default=None, metavar="DIR",
                   help="also write a fit directory: fit.json, measurements.csv, fit.png, "
                        "the fitted case, meta.json")
    p.add_argument("--json", action="store_true",
                   help="print the result as JSON ({\"parameters\": {KEY: {\"value\", "
                        "\"ci95\"}}, ...}) instead of the tables")
    add_cluster_arguments(p)
    return p


def _exponents(text):
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}': numbers separated by commas, e.g. "
                                         "1,1.5,2,2.5") from None


def main(args) -> int:
    # the study (scipy.optimize, asyncio) is imported here, not for --help
    # (docs/performance.md, "Start-up")
    from wearcheck.comparisons.present.fit_report import text
    from wearcheck.studies.fit import WARNING_STARTS, fit, write
    case = load_case(args)
    if args.out is not None:
        check_output(args.out, "fit")   # before the runs: a path we may not write fails at once
    if args.exponents is not None and "wear.pressure_exponent" not in args.keys:
        raise CaseError("--exponents: the scan over n needs --fit wear.pressure_exponent")
    result = fit(case, args.measurements, args.keys, exponents=args.exponents,
                 scheduler=args.scheduler, workers=args.workers, quiet=args.quiet or args.json)
    if args.out is not None:
        write(result, args.out, data_path=args.measurements)
    case_notes(args, case)
    for remark in result.warnings:
        warned = remark.startswith(WARNING_STARTS)
        print(f"warning: {remark}" if warned else f"note: {remark}",
              file=sys.stderr)
    if args.json:
        print(json.dumps(jsonable(result.to_dict()), indent=2, allow_nan=True))
    else:
        print(text(result))
        if args.out is not None:
            print(f"-> {args.out}")
    # exit 1 only when a test says the model does not fit; untested (too few
    # measurements) is 0 with the statement printed and fit_tested false in the JSON
    return 1 if result.goodness_of_fit["fits"] is False else 0
