"""Make the external results of the verify tutorial (``examples/data/paper_fe_export/``).

    python benchmarks/make_example_results.py [--nodes 60] [--out DIR]

The paper case computed by CalculiX (``--solver ccx``: the CAX6 sphere's
compliance from CalculiX's ``*GREEN`` job, the wear stepped on it; CalculiX
must be installed), written as an FE post-processor exports tables (ANSYS
Mechanical, COMSOL): tab-separated, quoted names with brackets and units, the
sliding distance in the model's pseudo-time column "Time [s]" (in mm), the
reaction force negative, a step counter, and the wear at the pole as an
Abaqus-style column without a unit. Each file starts with comment lines
saying how it was made (the command, the versions).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import wearcheck
from wearcheck import rundir
from wearcheck.references.certified import unworn_profile

ROOT = Path(__file__).resolve().parents[1]


def comments(case, result, argv) -> list[str]:
    prov = rundir.provenance(["python", "benchmarks/make_example_results.py", *argv])
    ccx = result.info["ccx"]
    return [f"# wearcheck's paper case computed by CalculiX {ccx['version']} "
            f"(--solver ccx, ccx.contact_nodes = {case.ccx.contact_nodes}, "
            f"{case.sliding.scheme} scheme), written as FE codes export tables",
            f"# made by: {prov['command']} (wearcheck {prov['wearcheck_version']}, "
            f"numpy {prov['versions'].get('numpy')}, {prov['created']})"]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--nodes", type=int, default=60)
    p.add_argument("--out", type=Path, default=ROOT / "examples" / "data" / "paper_fe_export")
    args = p.parse_args(argv)
    argv = sys.argv[1:] if argv is None else argv
    case = wearcheck.load_case("paper", {"ccx.contact_nodes": args.nodes})
    result = wearcheck.solve(case, "ccx")
    h, st = result.history, result.stages
    head = comments(case, result, argv)
    args.out.mkdir(parents=True, exist_ok=True)
    rows = head + ['"Steps"\t"Time [s]"\t"Force Reaction (Y) [N]"\t"Contact Radius [mm]"\t'
                   '"Worn Volume [mm³]"\t"WEAR_DEPTH N: 1"']
    for i in range(len(h["s"])):
        rows.append(f"{i + 1}\t{h['s'][i] * 1e3:.8E}\t{-h['force'][i]:.8E}\t"
                    f"{h['contact_radius'][i] * 1e3:.8E}\t{h['wear_volume'][i] * 1e9:.8E}\t"
                    f"{h['wear_center'][i] * 1e3:.8E}")
    (args.out / "history.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    f0 = unworn_profile(case, st["r"])
    rows = head + ['"Time [s]"\t"X [mm]"\t"Contact Pressure [MPa]"\t"Wear Depth (Y) [µm]"']
    for k, s in enumerate(st["s"]):
        for j, r in enumerate(st["r"]):
            rows.append(f"{s * 1e3:.8E}\t{r * 1e3:.8E}\t{st['p'][k, j] / 1e6:.8E}\t"
                        f"{(st['f'][k, j] - f0[j]) * 1e6:.8E}")
    (args.out / "stages.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    print(f"{args.out}: {len(h['s'])} history rows, {len(st['s'])} stages of {len(st['r'])} "
          "radii")
    return 0


if __name__ == "__main__":
    sys.exit(main())
