"""Cost of the CalculiX solver (prints Markdown).

    python benchmarks/bench_ccx.py                    # every table
    python benchmarks/bench_ccx.py --only compliance  # the *GREEN job against contact nodes
    python benchmarks/bench_ccx.py --only in_loop     # one gap-element contact solve
    python benchmarks/bench_ccx.py --only paper       # the paper case, superelement mode
    python benchmarks/bench_ccx.py --only paper_in_loop  # the paper case in both modes
    python benchmarks/bench_ccx.py --sizes 60 125     # other contact-node counts

Every measurement runs in a fresh process with a fresh mesh and compliance
cache (the paper table also with the cache warm); the FEM on the same case and
mesh is the baseline of the same run. The paper case in the in-loop mode runs
explicit Euler at ``--loop-nodes`` contact nodes (one CalculiX job per step),
beside the superelement mode and the FEM with the same scheme and mesh. Not a
test: the numbers depend on the machine and its load (printed with the tables).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import harness
from harness import load

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "cases" / "paper.toml"
HERTZ = ROOT / "cases" / "hertz.toml"


def compliance(n: int) -> dict:
    """The *GREEN job of n contact nodes (paper case's arc), cold, then from the cache."""
    from wearcheck import cases, meshes
    from wearcheck.ccx import compliance as compliance_mod
    from wearcheck.ccx import deck, model, run, solver

    case = cases.load(PAPER, [f"ccx.contact_nodes={n}"])
    t = time.perf_counter()
    sphere = model.cax6_sphere(meshes.sphere_mesh(solver.mesh_parameters(case)))
    out = dict(n=n, mesh=time.perf_counter() - t, nodes=len(sphere.points),
               elements=len(sphere.elements))
    exe = run.find(case.ccx.executable)
    version = run.version(exe)
    jobs = run.Jobs(executable=exe, model=deck.model(sphere, 210e9, 0.3))
    t = time.perf_counter()
    compliance_mod.compliance(sphere, 210e9, 0.3, jobs, version)
    out["build"] = time.perf_counter() - t
    out["ccx"] = jobs.seconds["compliance"]
    t = time.perf_counter()
    _, info = compliance_mod.compliance(sphere, 210e9, 0.3, jobs, version)
    out["cached"] = time.perf_counter() - t
    assert info["cached"]
    return out


def in_loop(n: int) -> dict:
    """One gap-element contact solve of the unworn Hertz case at n contact nodes."""
    from wearcheck import cases, meshes
    from wearcheck.cases import reference
    from wearcheck.cases.profiles import height
    from wearcheck.ccx import deck, in_loop as loop, model, run, solver

    case = cases.load(HERTZ, [f"ccx.contact_nodes={n}"])
    sc = reference.scales(case)
    sphere = model.cax6_sphere(meshes.sphere_mesh(solver.mesh_parameters(case)))
    jobs = run.Jobs(executable=run.find("ccx"), model=deck.model(sphere, 210e9, 0.3,
                                                                  nonlinear=True))
    z = height(case.indenter, sphere.r, None)
    t = time.perf_counter()
    sol = loop.contact_solve(jobs, "solve", sphere, z, control="depth", value=1e-6,
                             stiffness=loop.gap_stiffness(sphere.area[1:], sc["p0"], sc["d0"]),
                             tension=loop.TENSION * sc["F0"] / 180, force_scale=sc["F0"],
                             depth_scale=sc["d0"])
    return dict(n=n, seconds=time.perf_counter() - t, F_over_F0=sol.f.sum() / sc["F0"])


def paper(solver_name: str, n: int, changes: dict | None = None) -> dict:
    """The paper case by ``solver_name`` at n contact nodes (cache as the caller left it),
    with ``changes`` to the case; its history's force [F0] at the stages and at the end."""
    import numpy as np

    import wearcheck

    case = wearcheck.load_case(PAPER, {f"{solver_name}.contact_nodes": n, **(changes or {})})
    t = time.perf_counter()
    res = wearcheck.solve(case, solver_name)
    F0, h = res.scales["F0"], res.history
    out = dict(solver=solver_name, n=n, seconds=time.perf_counter() - t,
               steps=len(h["s"]) - 1, final_F_over_F0=float(h["force"][-1] / F0),
               s_hat_end=float(h["s_hat"][-1]),
               stage_F_over_F0=[float(np.interp(s, h["s"], h["force"]) / F0)
                                for s in res.stages["s"]],
               stage_s_hat=[float(x) for x in res.stages["s_hat"]],
               s=[float(x) for x in h["s"]], force=[float(x / F0) for x in h["force"]])
    if solver_name == "ccx":
        out["compliance_cached"] = res.info["compliance"]["cached"]
        out["ccx_seconds"] = res.info["ccx"]["seconds"]
        out["ccx_jobs"] = res.info["ccx"]["jobs"]
    return out


def child(function: str, *args, cache: str) -> dict:
    """Run ``function(*args)`` of this file in a fresh process with the given cache."""
    result, _ = harness.call(f"{__file__}:{function}", *args,
                             env=dict(os.environ, WEARCHECK_CACHE=cache))
    return result


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--only", choices=("compliance", "in_loop", "paper", "paper_in_loop"))
    p.add_argument("--sizes", type=int, nargs="+", default=[60, 125, 250, 500])
    p.add_argument("--paper-nodes", type=int, default=250,
                   help="contact nodes of the paper case, superelement mode (default: the "
                        "shipped ccx.contact_nodes)")
    p.add_argument("--loop-nodes", type=int, default=51,
                   help="contact nodes of the paper case in both modes (explicit Euler)")
    a = p.parse_args(argv)
    print(f"{' '.join(sys.argv)}\n\n{load()}\n")
    if a.only in (None, "compliance"):
        print("| contact nodes | mesh nodes | CAX6 elements | *GREEN job [s] | build incl. "
              "parse [s] | from the cache [s] |\n|---|---|---|---|---|---|")
        for n in a.sizes:
            with tempfile.TemporaryDirectory() as cache:
                r = child("compliance", n, cache=cache)
            print(f"| {r['n']} | {r['nodes']} | {r['elements']} | {r['ccx']:.2f} | "
                  f"{r['build']:.2f} | {r['cached']:.3f} |", flush=True)
        print()
    if a.only in (None, "in_loop"):
        print("| contact nodes | one contact solve [s] | F/F0 |\n|---|---|---|")
        for n in a.sizes:
            with tempfile.TemporaryDirectory() as cache:
                r = child("in_loop", n, cache=cache)
            print(f"| {r['n']} | {r['seconds']:.2f} | {r['F_over_F0']:.6f} |", flush=True)
        print()
    if a.only in (None, "paper"):
        n = a.paper_nodes
        print(f"paper case, {n} contact nodes, adaptive scheme (the case's)\n\n"
              "| run | seconds | of which CalculiX | steps | ŝ at the end | F/F0 at the end |\n"
              "|---|---|---|---|---|---|")
        with tempfile.TemporaryDirectory() as cache:
            rows = [("FEM (baseline)", child("paper", "fem", n, cache=cache)),
                    ("CalculiX, compliance not cached", child("paper", "ccx", n, cache=cache)),
                    ("CalculiX, compliance cached", child("paper", "ccx", n, cache=cache))]
        for label, r in rows:
            ccx = f"{r['ccx_seconds']:.2f}" if "ccx_seconds" in r else "—"
            print(f"| {label} | {r['seconds']:.2f} | {ccx} | {r['steps']} | "
                  f"{r['s_hat_end']:.4f} | {r['final_F_over_F0']:.6f} |", flush=True)
        print(f"\n{load()}\n")
    if a.only in (None, "paper_in_loop"):
        n = a.loop_nodes
        explicit = {"sliding.scheme": "explicit"}
        with tempfile.TemporaryDirectory() as cache:
            rows = [("FEM (baseline)", child("paper", "fem", n, explicit, cache=cache)),
                    ("CalculiX superelement", child("paper", "ccx", n, explicit, cache=cache)),
                    ("CalculiX in_loop", child("paper", "ccx", n,
                                               dict(explicit, **{"ccx.mode": "in_loop"}),
                                               cache=cache))]
        stages = rows[0][1]["stage_s_hat"]
        print(f"paper case, {n} contact nodes, explicit Euler (Δŝ half the stability limit), "
              "to F < 0.01 F0\n\n| run | seconds | CalculiX jobs | steps | "
              + " | ".join(f"F/F0 at ŝ = {s:g}" for s in stages) + " |\n|---|---|---|---|"
              + "---|" * len(stages))
        for label, r in rows:
            print(f"| {label} | {r['seconds']:.1f} | {r.get('ccx_jobs', '—')} | {r['steps']} | "
                  + " | ".join(f"{F:.6f}" for F in r["stage_F_over_F0"]) + " |", flush=True)
        a_, b_ = rows[1][1], rows[2][1]
        if a_["s"] == b_["s"]:
            import numpy as np
            diff = np.max(np.abs(np.subtract(a_["force"], b_["force"])))
            print(f"\nin_loop against superelement over the whole history: max |ΔF| = "
                  f"{diff:.2e} F0 ({len(a_['s'])} states)")
        print(f"\n{load()}")


if __name__ == "__main__":
    main()
