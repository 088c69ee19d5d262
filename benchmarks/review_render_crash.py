"""Issue 20, item 6, the reviewer's procedure: a render window that crashes.

    python benchmarks/review_render_crash.py [--case paper] [--solvers mdr,fem]

With ``VTK_DEFAULT_OPENGL_WINDOW=vtkOSOpenGLRenderWindow`` and no OSMesa
library, VTK segfaults when it opens its window. Before the fix ``compare``
died with it (exit 139) after both solvers had finished, its results lost in
a ``.partial``; ``render`` too. Checked here:

1. ``wearcheck compare CASE --solvers ... --out DIR`` with that window: the
   exit code is the verdict's (0 or 1), DIR holds the comparison (metrics,
   report, each solver's run readable), the crash is a note on stderr and in
   the report, nothing hidden is left.
2. ``wearcheck render DIR/fem``: exit 1, one line naming the crash and the
   variable; the run untouched.
3. The same two without the variable: the pictures are drawn.

Prints one line per check and PASS/FAIL; exits 1 on any failure, 2 when
OSMesa is installed (the window works, nothing to reproduce).
"""

from __future__ import annotations

import argparse
import ctypes.util
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def wearcheck(*argv, env):
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "wearcheck", *argv], capture_output=True,
                          text=True, env=env, timeout=3600)
    return done, time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", default="paper")
    ap.add_argument("--solvers", default="mdr,fem")
    args = ap.parse_args()
    if ctypes.util.find_library("OSMesa"):
        print("OSMesa is installed: vtkOSOpenGLRenderWindow works here, nothing to reproduce")
        return 2
    from wearcheck.rundir import Run
    work = Path(tempfile.mkdtemp(prefix="review-render-"))
    crash = dict(os.environ, VTK_DEFAULT_OPENGL_WINDOW="vtkOSOpenGLRenderWindow")
    plain = {k: v for k, v in os.environ.items() if k != "VTK_DEFAULT_OPENGL_WINDOW"}
    ok = True

    def check(label, good, detail=""):
        nonlocal ok
        ok &= bool(good)
        print(f"{label:<46} {'PASS' if good else 'FAIL'} {detail}", flush=True)

    out = work / "cmp"
    done, wall = wearcheck("compare", args.case, "--solvers", args.solvers, "--out", str(out),
                           env=crash)
    notes = [l for l in done.stderr.splitlines() if l.startswith("note: rendering")]
    solvers = args.solvers.split(",")
    check("compare: exit code is the verdict's", done.returncode in (0, 1),
          f"(exit {done.returncode}, {wall:.0f} s)")
    check("compare: the comparison is written", (out / "metrics.json").is_file()
          and all(Run(out / s).solver == s for s in solvers))
    check("compare: one note per solver names the crash",
          len(notes) == len(solvers) and all("SIGSEGV" in n for n in notes),
          notes[0] if notes else done.stderr[-300:])
    check("compare: the report says it", "SIGSEGV" in (out / "report.md").read_text()
          if (out / "report.md").is_file() else False)
    check("compare: nothing hidden left", [p.name for p in work.iterdir()] == ["cmp"])
    run = out / solvers[-1]
    before = sorted(p.name for p in run.iterdir())
    done, _ = wearcheck("render", str(run), env=crash)
    lines = [l for l in done.stderr.splitlines() if l.strip()]
    check("render: exit 1, one line", done.returncode == 1 and len(lines) == 1,
          lines[0] if lines else "")
    check("render: the run untouched", sorted(p.name for p in run.iterdir()) == before)
    done, _ = wearcheck("render", str(run), "--quiet", env=plain)
    check("render without the variable: pictures", done.returncode == 0
          and any((run / "render").glob("*.png")), done.stderr[-200:])
    print("ALL PASS" if ok else "FAILURES")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
