"""The adversarial review of issue 20 (items 2-4 and the numerical parts of 8), replayed.

    python benchmarks/review_numerics.py [--keep DIR]

Runs the reviewer's commands, and their neighbours, as a user would: the
``wearcheck`` command line in a fresh process each, in a scratch directory.
For each it prints the exit code and the first line of stderr, and checks
what must hold now: a refusal is one line naming the key (exit 2, nothing
written), a run that is made is complete (exit 0) and says on the terminal
what it approximates. Exit status 1 if any check fails. Takes a few minutes
(the BEM and FEM runs dominate).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np


def wearcheck(*argv, cwd):
    proc = subprocess.run([sys.executable, "-m", "wearcheck", *argv], cwd=cwd,
                          capture_output=True, text=True, timeout=900)
    return proc.returncode, proc.stderr


def table(path: Path, r_end: float, rows: int) -> Path:
    """The paper sphere's paraboloid f = r²/2R (R = 10 mm) tabulated to r_end."""
    r = np.linspace(0.0, r_end, rows)
    path.write_text("r,f\n" + "".join(f"{a:.17g},{a * a / 0.02:.17g}\n" for a in r))
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--keep", type=Path, default=None, help="work here and keep the runs")
    args = parser.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="wearcheck-review-"))
    work.mkdir(parents=True, exist_ok=True)
    short = table(work / "short.csv", 1.001e-4, 201)     # ends at 1.001 a0
    long = table(work / "long.csv", 2e-4, 401)           # beyond √2 a0
    failures = []

    def check(label, argv, code, must=(), must_not=(), written=None):
        out = work / f"out{len(results)}"
        got, err = wearcheck(*argv, "--out", str(out), cwd=work)
        lines = [line for line in err.splitlines() if line.strip()]
        errors = [line for line in lines if not line.startswith(("note:", "mdr:", "fem:", "bem:",
                                                                 "  ", "compare:"))
                  and " against " not in line]
        ok = got == code and all(m in err for m in must) and not any(
            re.search(m, err) for m in must_not) and "Traceback" not in err
        if code == 2:
            ok = ok and len(errors) == 1 and not out.exists()
        if ok and written is not None:
            try:
                ok = bool(written(out, err))
            except (KeyError, IndexError, ValueError, OSError):   # a key or file missing
                ok = False
        results.append((label, got, ok, (errors or lines or [""])[0][:160]))
        if not ok:
            failures.append((label, err))

    results: list = []
    paper, ball = ["paper", "--solver"], ["ball_on_flat", "--solver"]
    # item 2: an unresolved MDR contact
    check("mdr.elements=2", ["run", *paper, "mdr", "--set", "mdr.elements=2"], 2,
          ["'mdr.elements' = 2", "mdr.elements >= 32"])
    check("mdr.domain_factor=100", ["run", *paper, "mdr", "--set", "mdr.domain_factor=100"], 2,
          ["'mdr.domain_factor' = 100", "mdr.domain_factor <= 6.324"])
    check("neighbour: elements=2 and domain_factor=1e150",
          ["run", *paper, "mdr", "--set", "mdr.elements=2", "--set", "mdr.domain_factor=1e150"],
          2, ["mdr.domain_factor = 1.25 with mdr.elements >= 32"], [r"\d{12}"])
    check("neighbour: fretting, mdr.elements=20", ["run", "fretting", "--set",
                                                   "mdr.elements=20"], 2, ["mdr.elements >= 32"])

    def force_at_3(out, err):
        F0 = json.loads((out / "meta.json").read_text())["scales"]["F0"]
        h = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
        # README: F/F0 = 0.2789 at ŝ = 3 (MDR, FEM and BEM); the criterion: within 1 %
        return abs(np.interp(3.0, h["s_hat"], h["force"] / F0) - 0.2789) < 0.01
    check("the proposal: mdr.elements=32", ["run", *paper, "mdr", "--set", "mdr.elements=32"],
          0, written=force_at_3)
    # item 3: wear past the ball
    for solver in ("mdr", "fem", "bem"):
        check(f"{solver}: force=500 N, k=6e-3", ["run", *ball, solver, "--set",
                                                 "loading.force=500", "--set", "wear.k=6e-3"],
              2, ["the run would wear the sphere past its equator", "sliding.cycles <= "])
        check(f"{solver}: stroke=69", ["run", *ball, solver, "--set", "sliding.stroke=69"], 2,
              ["past its equator"])
    check("neighbour: paper at depth 0.8 R", ["run", *paper, "mdr", "--set",
                                              "loading.depth=0.008"], 2,
          ["'loading.depth' = 0.008", "past its equator"])

    def one_note(out, err):
        meta = json.loads((out / "meta.json").read_text())
        return err.count("note: half-space theory") == 1 and \
            any("half-space" in w for w in meta["warnings"])
    check("mdr: F=500 N for 1000 cycles (past a/R = 0.1)",
          ["run", *ball, "mdr", "--set", "loading.force=500", "--set", "wear.k=6e-3",
           "--set", "sliding.cycles=1000", "--set", "stages.cycles=[0.0]"], 0, written=one_note)
    check("neighbour: cone of slope tan 0.3 = 0.31 (past it from the start)",
          ["run", *paper, "mdr", "--set", "indenter.profile=\"cone\"", "--set",
           "indenter.slope_angle=0.3", "--set", "sliding.force_fraction=0.5"], 0,
          ["note: half-space theory is stretched: the unworn contact"])
    # item 4: a table shorter than the contact
    for solver in ("mdr", "fem", "bem"):
        check(f"{solver}: table to 1.001 a0", ["run", *paper, solver, "--set",
                                              "indenter.profile=\"table\"", "--set",
                                              f"indenter.file=\"{short}\"", "--set",
                                              "bem.grid=64"], 2,
              ["past the last radius of the profile table"])
    check("compare: table to 1.001 a0", ["compare", "paper", "--no-render", "--set",
                                         "indenter.profile=\"table\"", "--set",
                                         f"indenter.file=\"{short}\"", "--set", "bem.grid=64"],
          2, ["past the last radius of the profile table"])

    def digest(out, err):
        meta = json.loads((out / "meta.json").read_text())
        return meta["profile_table"]["sha256"] == hashlib.sha256(long.read_bytes()).hexdigest()
    check("mdr: table to 2 a0 (holds the contact)",
          ["run", *paper, "mdr", "--set", "indenter.profile=\"table\"", "--set",
           f"indenter.file=\"{long}\""], 0, written=digest)
    # item 8
    check("fretting.amplitude=1e-30", ["run", "fretting", "--set", "fretting.amplitude=1e-30"],
          3, ["'fretting.amplitude' = 1e-30", "raise fretting.amplitude to about"],
          [r"-\d\.\d+e-\d+ m wide", r"\d{9}"])
    check("neighbour: fretting.force_amplitude=1e-20",
          ["run", "fretting", "--set", "fretting.force_amplitude=1e-20"], 3,
          ["raise fretting.force_amplitude to about"], [r"\d{9}"])

    def says_ratio(out, err):
        meta = json.loads((out / "meta.json").read_text())
        F0 = meta["scales"]["F0"]
        h = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
        said = float(err.split("its unworn force is ")[1].split()[0])
        return math.isclose(h["force"][0] / F0, said, rel_tol=1e-3)
    check("ellipsoid R2/R1 = 1e8 (MDR)", ["run", "ellipsoid", "--solver", "mdr", "--set",
                                          "indenter.radius_y=1e6"], 0,
          ["note: the ellipsoid (radii R1, R2) is run as the paraboloid"], written=says_ratio)
    for force in ("1e9", "1e12"):
        check(f"ball_on_flat force={force}", ["run", *ball, "mdr", "--set",
                                              f"loading.force={force}"], 2,
              ["presses the sphere deeper than its radius", "below 6.921e+06 N"],
              ["floating point"])

    width = max(len(r[0]) for r in results)
    for label, got, ok, line in results:
        print(f"{'ok  ' if ok else 'FAIL'} {label:<{width}}  exit {got}  {line}")
    for label, err in failures:
        print(f"\n--- {label}\n{err}", file=sys.stderr)
    print(f"\n{len(results) - len(failures)} of {len(results)} as required; runs in {work}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
