"""The moving-contact model with cycle jumping on the shipped both-bodies cases (issue 24).

    python benchmarks/bench_moving_jumps.py [--cases ball_on_flat_steel,pin_on_disc]
                                            [--grid 64] [--cycles 100,1000]
                                            [--tolerance 0.01]

Each run in a fresh process, one at a time: the shipped case with
``bem.track_model = "moving"`` on ``--grid`` pixels, to ``--cycles`` cycles
(revolutions), jumped at ``--tolerance``. Printed per run: the wall and CPU
seconds of the solve, the moves of the run and those simulated, the simulated
cycles, steps, the largest step, the error estimate, the seconds in the
wear Jacobian's solves; "every move" is the run's moves times the measured
time per simulated move (what the run cost before cycle jumping: one contact
solve per move, the same solves), and the ratio of the two.

The machine is shared (2 cores, several users): wall-clock under whatever load
there was, printed with the load average; the CPU seconds are the steadier
figure.
"""

from __future__ import annotations

import argparse

import harness


def solve(name: str, grid: int, cycles: float, tolerance: float) -> dict:
    """One moving-contact run of the shipped case ``name``, in a fresh process."""
    import time
    import warnings

    warnings.simplefilter("ignore")
    from wearcheck import bem, cases
    case = cases.load(cases.shipped(name), [f"bem.grid={grid}", 'bem.track_model="moving"',
                                            f"bem.jump_tolerance={tolerance}",
                                            f"sliding.cycles={cycles}",
                                            f"stages.cycles=[0, {cycles}]"])
    t, c = time.perf_counter(), time.process_time()
    res = bem.solve(case)
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    i = res.info
    jumping = i.get("cycle_jumping") or {}
    return dict(wall=wall, cpu=cpu, moves=i["moves"],
                run_moves=round(res.history["s"][-1] / i["pixel"]),
                simulated_cycles=jumping.get("simulated_cycles"),
                steps=jumping.get("steps"), largest_step=jumping.get("largest_step"),
                error_estimate=jumping.get("error_estimate"),
                jacobian_seconds=i.get("jacobian_seconds", 0.0),
                balance=max(i["archard_balance"].values()))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="ball_on_flat_steel,pin_on_disc")
    ap.add_argument("--grid", type=int, default=64)
    ap.add_argument("--cycles", default="100,1000")
    ap.add_argument("--tolerance", type=float, default=0.01)
    args = ap.parse_args(argv)
    print(harness.load())
    print("| case | grid | cycles | moves of the run | simulated moves | simulated cycles "
          "| steps | largest step | error estimate | wall [s] | CPU [s] | Jacobian [s] "
          "| every move [s] | ratio | balance |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in args.cases.split(","):
        for cycles in (float(c) for c in args.cycles.split(",")):
            r = harness.call(f"{__file__}:solve", name, args.grid, cycles, args.tolerance,
                             timeout=6 * 3600)[0]
            per_move = (r["wall"] - r["jacobian_seconds"]) / r["moves"]
            every = per_move * r["run_moves"]
            print(f"| {name} | {args.grid} | {cycles:g} | {r['run_moves']} | {r['moves']} | "
                  f"{r['simulated_cycles']} | {r['steps']} | {r['largest_step']} | "
                  f"{r['error_estimate']:.2g} | {r['wall']:.0f} | {r['cpu']:.0f} | "
                  f"{r['jacobian_seconds']:.0f} | {every:.0f} | {every / r['wall']:.1f} | "
                  f"{r['balance']:.1g} |", flush=True)
    print(harness.load())


if __name__ == "__main__":
    main()
