"""MDR solver benchmark on cases/paper.toml (issue 2, §7). Prints tables.

    python benchmarks/bench_mdr.py [--max-n 102400] [--ns 800,6400,102400]
                                   [--explicit-max-n 3200] [--quick]

1. Resolution ladder N = 200 ... 102400 (or the sizes of --ns), run to
   F < 1 % F0: solve time, steps, peak memory (each run in a fresh process),
   implicit and bdf2 (auto steps) and explicit (auto: half the stability
   limit), and the error of the F/F0 history against the finest level of the
   same scheme (same steps, so the difference is spatial).
2. The paper's explicit scheme in plain vectorised numpy (uniform x grid,
   dense Eq. 2 / Eq. 13 matrices, forward Euler at half its stability
   limit) side by side at N = 800 and 3200.
3. Time error against step for implicit Euler and BDF2 at N = 800, and the
   space error there.
4. The ŝ at which F/F0 falls to 0.8, 0.5, 0.3, 0.15, 0.05, 0.02, 0.01.

Errors are max |F/F0 - reference| over the run's own history points (no
interpolation of the run under test; the reference is interpolated, its
step being fine enough for that to cost < 2e-6). The time-accurate
reference at N = 800 is BDF2 at Δŝ = 1/80 and 1/160, Richardson-extrapolated.

mdr.solve runs BLAS single-threaded itself (threadpoolctl); the plain-numpy
paper scheme of table 2 is given the same limit here.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_info, threadpool_limits  # noqa: E402

import harness  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]

from wearcheck import cases  # noqa: E402
from wearcheck.cases import reference  # noqa: E402

PAPER = ROOT / "cases" / "paper.toml"
#: time-accurate reference at N = 800: BDF2 at these steps, Richardson-extrapolated
REF_STEPS = (0.0125, 0.00625)


def one(N: int, scheme: str, step: str, extra=()) -> dict:
    """One MDR run in this process; returns timings, memory and the history."""
    import resource

    from wearcheck import mdr
    overrides = [f"mdr.elements={N}", f'sliding.scheme="{scheme}"', f"sliding.step_hat={step}",
                 "stages.s_hat=[0.0]", *extra]
    case = cases.load(PAPER, overrides)
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t, c = time.perf_counter(), time.process_time()
    res = mdr.solve(case)
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    h = res.history
    return dict(N=N, scheme=scheme, wall=wall, cpu=cpu, solve_seconds=res.solve_seconds,
                steps=res.info["steps"], step_hat=res.info["step_hat"],
                limit=res.info.get("stability_limit_hat"),
                peak_mb=rss1 / 1024, added_mb=(rss1 - rss0) / 1024,
                s_hat=h["s_hat"].tolist(),
                force=(h["force"] / h["force"][0]).tolist())


def run_child(N, scheme, step="auto", extra=(), timeout=3600):
    """:func:`one` in a fresh process; its peak_mb is the process's (the harness's)."""
    cmd = [sys.executable, __file__, "--one", str(N), scheme, str(step), *extra]
    run = harness.measure(cmd, timeout=timeout, check=False)
    if run.returncode != 0:
        return dict(N=N, scheme=scheme, error=run.stderr.strip().splitlines()[-1])
    return dict(json.loads(run.stdout.strip().splitlines()[-1]), peak_mb=run.peak_mb)


# -- the paper's scheme in plain numpy -----------------------------------------

def paper_explicit(N: int) -> dict:
    """Forward Euler on a uniform x grid with dense transforms (the paper's way).

    Springs at x_i = i Δx; Eq. 2 and Eq. 13 as dense matrices, integrating
    the kernels exactly over each segment of a piecewise-linear f or q;
    step at half the stability limit (power iteration on the rate matrix).
    """
    case = cases.load(PAPER, [f"mdr.elements={N}"])
    sc = reference.scales(case)
    from wearcheck.cases import profiles
    L = case.mdr.domain_factor * math.sqrt(2.0) * sc["a0"]
    x = np.linspace(0.0, L, N + 1)
    E, K, d = case.E_star, case.wear_rate, case.loading.depth
    t0, c0 = time.perf_counter(), time.process_time()
    xi, xj = x[:, None], x[None, :]
    # Eq. 2: g_i = f_0 + x_i Σ_j (f_{j+1}-f_j)/Δx [asin(x_{j+1}/x_i) - asin(x_j/x_i)]
    # (segments beyond x_i contribute asin(1) - asin(1) = 0; row 0 is g_0 = f_0)
    ratio = np.divide(xj, xi, out=np.zeros((N + 1, N + 1)), where=xi > 0)
    A = np.arcsin(np.minimum(ratio, 1.0))
    W = (A[:, 1:] - A[:, :-1]) * x[:, None] / (x[1] - x[0])      # weight of f_{j+1}-f_j
    # Eq. 13: p_i = -(1/π) Σ_j (q_{j+1}-q_j)/Δx [acosh(x_{j+1}/r_i) - acosh(x_j/r_i)], x_j >= r_i
    r = x.copy()
    r[0] = 0.5 * x[1]                     # the log-singular r = 0 is taken half a cell out
    with np.errstate(divide="ignore", invalid="ignore"):
        C = np.arccosh(np.maximum(xj / r[:, None], 1.0))
    P = -(C[:, 1:] - C[:, :-1]) / (math.pi * (x[1] - x[0]))
    f = profiles.height(case.indenter, x)

    def rate(f):
        g = f[0] + W @ np.diff(f)
        q = E * np.maximum(d - g, 0.0)
        return K * (P @ np.diff(q)), q

    # stability: largest eigenvalue of the linearised rate, by power iteration
    v = np.random.default_rng(0).random(N + 1)
    lam = 0.0
    for _ in range(200):
        w = K * E * (P @ np.diff(W @ np.diff(v) + v[0]))
        lam, v = np.linalg.norm(w) / np.linalg.norm(v), w / np.linalg.norm(w)
    h = 1.0 / lam                          # half of 2/λ
    dx = x[1] - x[0]
    wq = np.full(N + 1, dx)
    wq[[0, -1]] = dx / 2
    F_hist, s_hist = [], []
    s = 0.0
    F0 = None
    while True:
        dfds, q = rate(f)
        F = 2.0 * (wq @ q)
        F0 = F if F0 is None else F0
        F_hist.append(F / F0)
        s_hist.append(s * sc["s_hat_per_m"])
        if F < 0.01 * F0:
            break
        f = f + h * dfds
        s += h
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    return dict(N=N, wall=wall, cpu=cpu, steps=len(F_hist) - 1, step_hat=h * sc["s_hat_per_m"],
                s_hat=s_hist, force=F_hist)


# -- tables ------------------------------------------------------------------------

class Reference:
    """F/F0 as a function of ŝ from one history, or Richardson from two (order p)."""

    def __init__(self, fine, coarse=None, order=2):
        self.fine, self.coarse, self.order = fine, coarse, order
        self.end = fine["s_hat"][-1] if coarse is None else min(fine["s_hat"][-1],
                                                                 coarse["s_hat"][-1])

    def __call__(self, s):
        f = np.interp(s, self.fine["s_hat"], self.fine["force"])
        if self.coarse is None:
            return f
        c = np.interp(s, self.coarse["s_hat"], self.coarse["force"])
        return f + (f - c) / (2.0**self.order - 1.0)


def err(run, ref) -> float:
    """max |F/F0 - reference| over the run's history points within the reference's range."""
    s = np.asarray(run["s_hat"])
    F = np.asarray(run["force"])
    k = s <= ref.end
    return float(np.max(np.abs(F[k] - ref(s[k]))))


def blas_threads() -> str:
    return ",".join(str(i["num_threads"]) for i in threadpool_info() if i["user_api"] == "blas")


def row(r, e_space, e_time) -> str:
    if "error" in r:
        return f"| {r['N']} | {r['scheme']} | | | failed: {r['error']} | | | | | |"
    return (f"| {r['N']} | {r['scheme']} | {r['step_hat']:.4g} | {r['steps']} | "
            f"{r['solve_seconds']:.3g} | {r['cpu']:.3g} | {r['peak_mb']:.0f} | "
            f"{r['added_mb']:.0f} | {e_space} | {e_time} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--max-n", type=int, default=102400)
    ap.add_argument("--ns", help="comma-separated ladder sizes (instead of 200 ... --max-n)")
    ap.add_argument("--explicit-max-n", type=int, default=3200)
    ap.add_argument("--paper-max-n", type=int, default=3200)
    ap.add_argument("--quick", action="store_true", help="N <= 6400, no N = 3200 paper scheme")
    ap.add_argument("--one", nargs="+", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        N, scheme, step, *extra = args.one
        print(json.dumps(one(int(N), scheme, step, extra)))
        return
    if args.quick:
        args.max_n, args.paper_max_n = 6400, 800
    print(f"# MDR benchmark on {PAPER.name}, load average {os.getloadavg()[0]:.1f}, "
          f"{os.cpu_count()} CPUs, BLAS threads outside mdr.solve: {blas_threads()} "
          "(1 inside)\n")
    if args.ns:
        Ns = sorted(int(n) for n in args.ns.split(","))
    else:
        Ns = [n for n in (200, 400, 800, 1600, 3200, 6400, 12800, 25600, 51200, 102400)
              if n <= args.max_n]
    ladder = {sch: {N: run_child(N, sch) for N in Ns} for sch in ("implicit", "bdf2")}
    exp = {N: run_child(N, "explicit") for N in Ns if N <= args.explicit_max_n}
    # time-accurate reference at N = 800
    steps = [0.4, 0.2, 0.1, 0.05, 0.025]
    ref_runs = [run_child(800, "bdf2", st) for st in REF_STEPS]
    ref_t = Reference(ref_runs[1], ref_runs[0], order=2)
    print("## 1. Resolution ladder (to F < 1 % F0)\n")
    print("| N | scheme | Δŝ | steps | solve s (wall) | CPU s | peak RSS MB | +MB in solve | "
          "err vs finest (same scheme) | err vs time-accurate N=800 |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for N in Ns:
        for sch in ("implicit", "bdf2"):
            r = ladder[sch][N]
            finest = ladder[sch][Ns[-1]]
            e_s = ("" if "error" in r or "error" in finest else
                   "—" if N == Ns[-1] else f"{err(r, Reference(finest)):.2e}")
            print(row(r, e_s, "" if "error" in r else f"{err(r, ref_t):.2e}"))
        if N in exp:
            print(row(exp[N], "", "" if "error" in exp[N] else f"{err(exp[N], ref_t):.2e}"))
    print("\nerr = max over the run's history points of |F/F0 - reference|. Rows of one "
          "scheme share Δŝ with its finest level, so 'err vs finest' is their spatial error "
          f"(relative to N = {Ns[-1]}); at N = 800 'err vs time-accurate' is the time error, "
          "elsewhere time plus space.\n")

    print("## 2. The paper's explicit scheme in plain numpy, side by side\n")
    print("| N | scheme | Δŝ | steps | solve s (wall) | CPU s | err vs time-accurate N=800 "
          "| CPU time / paper's |")
    print("|---|---|---|---|---|---|---|---|")
    for N in (800, 3200):
        if N > args.paper_max_n:
            continue
        with threadpool_limits(limits=1, user_api="blas"):
            pe = paper_explicit(N)
        print(f"| {N} | paper explicit, numpy | {pe['step_hat']:.3g} | {pe['steps']} | "
              f"{pe['wall']:.3g} | {pe['cpu']:.3g} | {err(pe, ref_t):.2e} | |")
        for sch in ("implicit", "bdf2"):
            mine = ladder[sch].get(N) or run_child(N, sch)
            if "error" in mine:
                continue
            print(f"| {N} | mdr {sch} (auto) | {mine['step_hat']:.3g} | {mine['steps']} | "
                  f"{mine['solve_seconds']:.3g} | {mine['cpu']:.3g} | {err(mine, ref_t):.2e} | "
                  f"{mine['cpu'] / pe['cpu']:.3f} |")
    print()

    print("## 3. Time error against step at N = 800\n")
    runs = {(sch, st): run_child(800, sch, st) for sch in ("implicit", "bdf2") for st in steps}
    print("| Δŝ | implicit steps | implicit solve s | implicit time error | "
          "bdf2 steps | bdf2 solve s | bdf2 time error |")
    print("|---|---|---|---|---|---|---|")
    for st in steps:
        cells = []
        for sch in ("implicit", "bdf2"):
            r = runs[(sch, st)]
            cells += [str(r["steps"]), f"{r['solve_seconds']:.3g}", f"{err(r, ref_t):.2e}"]
        print(f"| {st} | " + " | ".join(cells) + " |")
    for sch in ("implicit", "bdf2"):
        e = [err(runs[(sch, st)], ref_t) for st in steps]
        order = np.polyfit(np.log(steps), np.log(e), 1)[0]
        print(f"\n{sch}: observed order {order:.2f}; error/Δŝ^p at Δŝ = 0.1: "
              f"{e[2] / 0.1 ** round(order):.3g}")
    print(f"\nreference: BDF2 at Δŝ = {REF_STEPS}, Richardson (its correction: "
          f"{err(ref_runs[1], ref_t):.1e})")
    if Ns[-1] > 800 and 800 in Ns:
        for sch in ("implicit", "bdf2"):
            r, finest = ladder[sch][800], ladder[sch][Ns[-1]]
            if "error" not in r and "error" not in finest:
                print(f"space error at N = 800 ({sch}, auto Δŝ = {r['step_hat']}): "
                      f"{err(r, Reference(finest)):.2e} against N = {Ns[-1]}")
    print("\n## 4. ŝ at which F/F0 falls to a fraction (N = 800, time-accurate)\n")
    s_fine = np.linspace(0, min(11.5, ref_t.end), 23001)
    F_r = ref_t(s_fine)
    print("| F/F0 | ŝ |")
    print("|---|---|")
    for frac in (0.8, 0.5, 0.3, 0.15, 0.05, 0.02, 0.01):
        k = int(np.argmax(F_r < frac))
        print(f"| {frac} | {s_fine[k]:.3f} |")


if __name__ == "__main__":
    main()
