"""The BEM's wear runs against a baseline checkout, each run in a fresh process. Prints a table.

    python benchmarks/bench_bem_speed.py [--baseline main] [--runs paper:256,paper:512,ball_on_flat:256]
                                         [--repeat 1]

Each run (case:grid) is solved by the baseline (the commit ``--baseline`` of
this repository, extracted by ``git archive`` into a temporary directory and
imported from there) and by this working tree, alternately (ABAB with
``--repeat 2``), each in a fresh Python process. Per run: solve time
(``solve_seconds``, wall clock) and the CPU time of the solve (the process's
own, which the machine's load changes far less: on the shared two cores the
wall clock runs 2-6 times the CPU time at load 7-14), steps, CG iterations,
double- and single-precision operator applications, and the accuracy:

- against the baseline, the largest difference at the stages of the force
  (over F0), of the pressure field (over the stage's peak pressure), of the
  ring-averaged profile (over d, d0 under force control) and of the contact
  radius (over the stage's);
- against an independent reference, the MDR of the same case (its own
  ``mdr.elements``) in the same process: the largest difference at the
  stages of the force (over F0) and of the central wear (over d, d0), for
  each code, so that both are held to the same yardstick.

The machine is shared: the load average is printed before and after each run.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
PACKAGES = ("cases", "mdr", "fem", "bem", "meshes", "numerics", "comparisons")

CHILD = r"""
import json, sys, time
import numpy as np
from wearcheck import bem, cases, mdr
from wearcheck.cases import reference
name, grid, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
case = cases.load(cases.shipped(name), [f"bem.grid={grid}"])
cpu = time.process_time()
res = bem.solve(case)
cpu = time.process_time() - cpu
sc = reference.scales(case)
d = case.loading.depth if case.loading.control == "depth" else sc["d0"]
h = res.history
a = [float(np.interp(s, h["s"], h["contact_radius"])) for s in res.stage_s]
F = [float(np.interp(s, h["s"], h["force"])) for s in res.stage_s]
w = [float(np.interp(s, h["s"], h["wear_center"])) for s in res.stage_s]
ref = mdr.solve(case).history
dF = max(abs(f - float(np.interp(s, ref["s"], ref["force"]))) for s, f in zip(res.stage_s, F))
dw = max(abs(x - float(np.interp(s, ref["s"], ref["wear_center"])))
         for s, x in zip(res.stage_s, w))
np.savez(out, pressure=res.fields["pressure"], f=res.f, stage_s=res.stage_s, a=a, F=F,
         F0=sc["F0"], d=d)
info = res.info
print(json.dumps(dict(seconds=res.solve_seconds, cpu=cpu, steps=info["steps"],
                      cg=info["cg_iterations"], double=info["operator_applications"],
                      single=info.get("single_precision_applications", 0),
                      mdr_force=dF / sc["F0"], mdr_wear=dw / d, module=bem.__file__)))
"""


def stage_package(commit: str, into: Path) -> Path:
    """The package of ``commit`` laid out for import (wearcheck/ and its subpackages)."""
    tree = into / "tree"
    tree.mkdir()
    archive = subprocess.run(["git", "-C", str(REPO), "archive", commit], check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
    src = into / "src"
    shutil.copytree(tree / "wearcheck", src / "wearcheck")
    for pkg in PACKAGES:
        # packages still at the top level at that commit (later ones live in wearcheck/)
        if (tree / pkg).is_dir() and not (src / "wearcheck" / pkg).exists():
            shutil.copytree(tree / pkg, src / "wearcheck" / pkg)
    return src


def run_child(name, grid, out, src=None):
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    before = os.getloadavg()[0]
    # run outside the repository: `python -c` puts the working directory
    # first on sys.path, and the repository's wearcheck/ there would shadow
    # the staged baseline
    r = subprocess.run([sys.executable, "-c", CHILD, name, str(grid), str(out)], env=env,
                       capture_output=True, text=True, cwd=Path(out).parent)
    if r.returncode:
        raise RuntimeError(r.stderr)
    row = json.loads(r.stdout.strip().splitlines()[-1])
    row["load"] = f"{before:.1f}-{os.getloadavg()[0]:.1f}"
    return row


def accuracy(base, new):
    """Largest differences at the stages: force/F0, pressure/peak, ring profile/d, radius/a."""
    b, n = np.load(base), np.load(new)
    k = min(len(b["stage_s"]), len(n["stage_s"]))
    dF = np.max(np.abs(b["F"][:k] - n["F"][:k])) / float(b["F0"])
    dp = max(float(np.max(np.abs(b["pressure"][i] - n["pressure"][i]) / b["pressure"][i].max()))
             for i in range(k))
    df = float(np.max(np.abs(b["f"][:k] - n["f"][:k]))) / float(b["d"])
    da = float(np.max(np.abs(b["a"][:k] - n["a"][:k]) / b["a"][:k]))
    return dF, dp, df, da


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", default="main", help="commit of the baseline")
    ap.add_argument("--runs", default="paper:256,paper:512,ball_on_flat:256")
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args(argv)
    runs = [(r.split(":")[0], int(r.split(":")[1])) for r in args.runs.split(",")]
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", args.baseline],
                            check=True, capture_output=True, text=True).stdout.strip()
    head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"],
                          check=True, capture_output=True, text=True).stdout.strip()
    print(f"# BEM speed: baseline {args.baseline} ({commit}) against the working tree "
          f"(HEAD {head}); " + " ".join(sys.argv))
    print("| case | grid | code | solve [s] | ratio | CPU [s] | CPU ratio | steps | CG iterations "
          "| double / single applications | ΔF/F0 | Δp/p_max | Δf_ring/d | Δa/a "
          "| MDR: ΔF/F0 | MDR: Δw_c/d | load |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        src = stage_package(args.baseline, tmp)
        for name, grid in runs:
            for rep in range(args.repeat):
                base_out, new_out = tmp / f"b{rep}.npz", tmp / f"n{rep}.npz"
                b = run_child(name, grid, base_out, src)
                n = run_child(name, grid, new_out)
                assert str(tmp) in b["module"] and str(tmp) not in n["module"]
                acc = accuracy(base_out, new_out)
                for label, row, cells in (("baseline", b, ["–"] * 4),
                                          ("this tree", n, [f"{x:.1e}" for x in acc])):
                    ratio = row["seconds"] / b["seconds"]
                    cpu_ratio = row["cpu"] / b["cpu"]
                    print(f"| {name} | {grid} | {label} | {row['seconds']:.1f} | {ratio:.2f} | "
                          f"{row['cpu']:.1f} | {cpu_ratio:.2f} | "
                          f"{row['steps']} | {row['cg']} | {row['double']} / {row['single']} | "
                          + " | ".join(cells) + f" | {row['mdr_force']:.1e} | "
                          f"{row['mdr_wear']:.1e} | {row['load']} |", flush=True)


if __name__ == "__main__":
    main()
