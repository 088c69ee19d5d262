"""Speed and accuracy tables of the FEM superelement model (prints Markdown).

    python benchmarks/bench_fem.py            # everything (~1-2 min)
    python benchmarks/bench_fem.py --quick    # sizes 125, 250 only
    python benchmarks/bench_fem.py --steps    # the time-error table only

Each size runs in a fresh process (peak memory = its maximum resident set),
with a fresh mesh cache so that gmsh's time is included. Not a test: numbers
depend on the machine and its load (printed with the tables).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import harness

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "cases" / "paper.toml"


def one_size(n: int) -> dict:
    """Timings of one contact-node count (run in a child process)."""
    import numpy as np

    from wearcheck import cases
    from wearcheck import fem
    from wearcheck import meshes
    from wearcheck.cases import reference
    from threadpoolctl import threadpool_limits
    from wearcheck.numerics.superelement import PrefixCholesky, solve_lcp
    from wearcheck.fem.model import build
    from wearcheck.fem.solver import mesh_parameters

    case = cases.load(PAPER, [f"fem.contact_nodes={n}"])
    out = {"n": n}
    with threadpool_limits(limits=1, user_api="blas"):
        params = mesh_parameters(case)
        t = time.perf_counter()
        sm = meshes.sphere_mesh(params)
        out["mesh"] = time.perf_counter() - t
        model = build(sm, case.indenter.youngs_modulus, case.indenter.poisson_ratio, 2)
        out["assembly"] = model.timings["assembly"]
        model.factorise()
        out["factorisation"] = model.timings["factorisation"]
        C = model.compliance()
        out["compliance"] = model.timings["compliance"]
        out.update(model.stats())
        # one implicit wear step at the unworn state: C + D factor, warm start
        sc = reference.scales(case)
        Ci = C[1:, 1:]
        z = cases.profiles.height(case.indenter, model.r[1:])
        area = model.area_rowsum[1:]
        D = case.wear_rate * 0.02 / sc["s_hat_per_m"] / area
        t = time.perf_counter()
        fac = PrefixCholesky(Ci + np.diag(D))
        out["factor_C_plus_K"] = time.perf_counter() - t
        res = solve_lcp(fac, z, depth=case.loading.depth, gap_scale=sc["d0"],
                        force_scale=sc["F0"])
        reps = 20
        t = time.perf_counter()
        for _ in range(reps):
            solve_lcp(fac, z, depth=case.loading.depth, active=res.active, gap_scale=sc["d0"],
                      force_scale=sc["F0"])
        out["wear_step"] = (time.perf_counter() - t) / reps
        # the same active block factorised from scratch, for comparison
        A = res.active
        t = time.perf_counter()
        for _ in range(reps):
            from scipy import linalg
            linalg.cho_solve(linalg.cho_factor(fac.M[np.ix_(A, A)]), z[A])
        out["refactor_active_block"] = (time.perf_counter() - t) / reps
    # the whole run, case file to F < 1 % F0 (fresh model, mesh from the cache)
    t = time.perf_counter()
    r = fem.solve(cases.load(PAPER, [f"fem.contact_nodes={n}"]))
    out["paper_run"] = time.perf_counter() - t
    out["steps"] = r.info["steps"]
    out["wear_loop"] = r.info["timings"]["wear_loop"]
    t = time.perf_counter()
    r = fem.solve(cases.load(PAPER, [f"fem.contact_nodes={n}", "sliding.scheme=explicit"]))
    out["paper_run_explicit"] = time.perf_counter() - t
    out["steps_explicit"] = r.info["steps"]
    t = time.perf_counter()
    r = fem.solve(cases.load(PAPER, [f"fem.contact_nodes={n}", "sliding.scheme=bdf2"]))
    out["paper_run_bdf2"] = time.perf_counter() - t
    out["steps_bdf2"] = r.info["steps"]
    return out


def factorisation_options(n: int) -> list[dict]:
    """Factorise + compliance with each scipy option (run in a child process)."""
    import numpy as np

    from wearcheck import cases
    from wearcheck import meshes
    from threadpoolctl import threadpool_limits
    from wearcheck.fem.model import FACTORISATIONS, build
    from wearcheck.fem.solver import mesh_parameters

    case = cases.load(PAPER, [f"fem.contact_nodes={n}"])
    sm = meshes.sphere_mesh(mesh_parameters(case))
    rows, ref = [], None
    with threadpool_limits(limits=1, user_api="blas"):
        for method in FACTORISATIONS[:3]:
            for route in ("schur", "columns"):
                model = build(sm, case.indenter.youngs_modulus, case.indenter.poisson_ratio, 2)
                model.factorise(method, contact_last=route == "schur")
                C = model.compliance(route)
                ref = C if ref is None else ref
                rows.append(dict(method=method, route=model.timings["compliance_method"],
                                 factorisation=model.timings["factorisation"],
                                 compliance=model.timings["compliance"],
                                 nnz=int(model.lu.L.nnz + model.lu.U.nnz),
                                 diff=float(np.max(np.abs(C - ref)) / np.max(np.abs(ref)))))
    return rows


def child(what: str, n: int):
    """``what`` at n contact nodes in a fresh process with an empty mesh cache;
    a dict result gets the process's peak memory (the harness's) as peak_rss_mb."""
    with tempfile.TemporaryDirectory() as cache:
        run = harness.measure([sys.executable, __file__, "--child", what, str(n)],
                              env=dict(os.environ, WEARCHECK_CACHE=cache))
    out = json.loads(run.stdout.strip().splitlines()[-1])
    if isinstance(out, dict):
        out["peak_rss_mb"] = run.peak_mb
    return out


#: time-step table: schemes and steps Δŝ (paper case, default mesh)
STEP_TABLE = (("implicit", (0.005, 0.01, 0.02, 0.04, 0.08)),
              ("bdf2", (0.005, 0.01, 0.02, 0.025, 0.04, 0.05, 0.1, 0.2)))
#: the time-converged reference step (bdf2) and the end of the compared runs
REFERENCE_STEP, S_HAT_END = 0.0025, 4.0


def step_accuracy(n: int = 250):
    """Time error against a fine bdf2 step, and the mesh's spatial error.

    Paper case on ``n`` contact nodes, ŝ <= 4 (stages 0.5, 2, 4): the largest
    force difference over the history (the reference interpolated to each
    run's s) and profile difference over the stages, against bdf2 at
    Δŝ = 0.0025 on the same mesh; plus the wall time and steps of the full
    paper run (to F < 1 % F0) with that scheme and step. The spatial line
    compares the reference with the same run on 1000 nodes (profile
    interpolated in r).
    """
    import numpy as np

    from wearcheck import cases
    from wearcheck import fem
    from wearcheck.cases import reference

    sc = reference.scales(cases.load(PAPER))
    dist = S_HAT_END / sc["s_hat_per_m"]

    def run(scheme, st, nodes=n):
        return fem.solve(cases.load(PAPER, [
            f"fem.contact_nodes={nodes}", "sliding.until=distance", f"sliding.distance={dist!r}",
            f"sliding.scheme={scheme}", f"sliding.step_hat={st}", "stages.s_hat=[0.5, 2.0, 4.0]"]))

    def error(r, ref):
        F = np.interp(r.history["s"], ref.history["s"], ref.history["force"])
        dF = np.max(np.abs(r.history["force"] - F)) / sc["F0"]
        df = max(np.max(np.abs(r.f[k] - np.interp(r.r, ref.r, ref.f[k])))
                 for k in range(len(r.stage_s))) / sc["d0"]
        return dF, df

    ref = run("bdf2", REFERENCE_STEP)
    rows = [("spatial: reference vs 1001 nodes", REFERENCE_STEP,
             *error(ref, run("bdf2", REFERENCE_STEP, 1000)), None, None, None)]
    for scheme, steps in STEP_TABLE:
        for st in steps:
            dF, df = error(run(scheme, st), ref)
            full = cases.load(PAPER, [f"fem.contact_nodes={n}", f"sliding.scheme={scheme}",
                                      f"sliding.step_hat={st}"])
            t = time.perf_counter()
            r = fem.solve(full)
            rows.append((scheme, st, dF, df, time.perf_counter() - t, r.info["steps"],
                         r.info["refactorisations"]))
    return rows


def recovery_wiggle():
    """Odd-even component of the nodal pressure near the worn contact edge."""
    import numpy as np

    from wearcheck import cases
    from wearcheck import fem
    from wearcheck.cases import reference

    out = []
    for rec in ("lumped", "consistent"):
        c = cases.load(PAPER, [f"fem.pressure_recovery={rec}"])
        r = fem.solve(c)
        sc = reference.scales(c)
        for k, s in enumerate(r.stage_s):
            a = np.interp(s, r.history["s"], r.history["contact_radius"])
            p = r.p[k]
            odd = np.abs(p[1:-1] - 0.5 * (p[:-2] + p[2:]))
            band = (r.r[1:-1] > 0.8 * a) & (r.r[1:-1] < a)
            inner = r.r[1:-1] < 0.5 * a
            out.append((rec, s * sc["s_hat_per_m"], odd[band].max() / sc["p0"],
                        odd[inner].max() / sc["p0"], p.max() / sc["p0"], p.min() / sc["p0"]))
    return out


def cli_run():
    """``wearcheck run cases/paper.toml --solver fem``, wall clock, cold and warm cache."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, WEARCHECK_CACHE=str(Path(tmp) / "cache"))
        for label in ("cold mesh cache", "warm mesh cache"):
            run = harness.measure([sys.executable, "-m", "wearcheck", "run", str(PAPER),
                                   "--solver", "fem", "--out", str(Path(tmp) / "run"),
                                   "--quiet"], cwd=ROOT, env=env)
            rows.append((label, run.wall))
    return rows


def print_step_table():
    """Print the time-error table of :func:`step_accuracy` (Markdown)."""
    print(f"\n## Time error (paper case, 251 contact nodes, ŝ <= {S_HAT_END:g}) against "
          f"bdf2 at Δŝ = {REFERENCE_STEP}\n")
    print("| scheme | step_hat | max ΔF / F0 | max Δprofile / d | paper run s "
          "| steps | factorisations |\n|---|---|---|---|---|---|---|")
    for scheme, st, dF, df, sec, steps, refac in step_accuracy():
        if sec is None:
            print(f"| {scheme} | {st} | {dF:.2e} | {df:.2e} | | | |")
        else:
            print(f"| {scheme} | {st} | {dF:.2e} | {df:.2e} | {sec:.2f} | {steps} | {refac} |")
    print("\nΔF: largest over the history; Δprofile: largest over the stages ŝ = 0.5, 2, 4. "
          "The spatial line compares the reference with the same run on 1001 nodes (the "
          "default mesh's spatial error, for scale). paper run: cases/paper.toml to "
          "F < 1 % F0 with that scheme and step, in-process, mesh cached; factorisations: "
          "Cholesky factors of C + c·K (stage landings change ω).\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--steps", action="store_true", help="the time-error table only")
    ap.add_argument("--child", nargs=2, metavar=("WHAT", "N"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        what, n = args.child[0], int(args.child[1])
        print(json.dumps(one_size(n) if what == "size" else factorisation_options(n)))
        return
    sizes = (125, 250) if args.quick else (125, 250, 500, 1000)
    print(f"# FEM benchmark ({os.cpu_count()} CPUs, load average "
          f"{' '.join(f'{x:.1f}' for x in os.getloadavg())}, {time.strftime('%Y-%m-%d %H:%M')})\n")
    if args.steps:
        print_step_table()
        return
    print("## Superelement and wear loop by contact-node count (paper case, P2)\n")
    print("| contact nodes | DOFs | mesh s | assembly s | factorisation s | compliance s "
          "| C+K factor s | wear step ms | refactor active block ms | paper run s (steps) "
          "| bdf2 run s (steps) | explicit run s (steps) | peak RSS MB |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for n in sizes:
        o = child("size", n)
        print(f"| {o['contact_nodes']} | {o['dofs']} | {o['mesh']:.3f} | {o['assembly']:.3f} "
              f"| {o['factorisation']:.3f} | {o['compliance']:.3f} | {o['factor_C_plus_K']:.3f} "
              f"| {1e3 * o['wear_step']:.2f} | {1e3 * o['refactor_active_block']:.2f} "
              f"| {o['paper_run']:.2f} ({o['steps']}) "
              f"| {o['paper_run_bdf2']:.2f} ({o['steps_bdf2']}) "
              f"| {o['paper_run_explicit']:.2f} ({o['steps_explicit']}) "
              f"| {o['peak_rss_mb']:.0f} |")
    print("\nwear step: one warm-started implicit LCP solve (prefix factor of C + K); "
          "refactor active block: a fresh Cholesky of the active block instead. paper run: "
          "cases/paper.toml in-process (mesh from the cache) to F < 1 % F0, implicit "
          "(default), bdf2 and explicit at their auto steps (explicit: half its stability "
          "limit).\n")

    print("## Factorisation options (scipy SuperLU orderings; compliance route)\n")
    print("| contact nodes | ordering | route | factorisation s | compliance s | nnz(L+U) "
          "| max rel. diff of C |")
    print("|---|---|---|---|---|---|---|")
    for n in (sizes[1], sizes[-1]):
        for row in child("factor", n):
            print(f"| {n} | {row['method']} | {row['route']} | {row['factorisation']:.3f} "
                  f"| {row['compliance']:.3f} | {row['nnz']} | {row['diff']:.1e} |")

    print("\n## `wearcheck run cases/paper.toml --solver fem` (wall clock, incl. start-up)\n")
    print("| mesh cache | seconds |\n|---|---|")
    for label, sec in cli_run():
        print(f"| {label} | {sec:.2f} |")

    print_step_table()

    print("\n## Pressure recovery: odd-even component |p_i - (p_i-1 + p_i+1)/2| / p0\n")
    print("| recovery | ŝ | near edge (0.8a-a) | inside (r < 0.5a) | max p/p0 | min p/p0 |")
    print("|---|---|---|---|---|---|")
    for rec, sh, edge, inner, pmax, pmin in recovery_wiggle():
        print(f"| {rec} | {sh:g} | {edge:.2e} | {inner:.2e} | {pmax:.3f} | {pmin:+.3f} |")


if __name__ == "__main__":
    main()
