"""The moving-contact model with cycle jumping on the shipped both-bodies cases (issue 24).

    python benchmarks/bench_moving_jumps.py [--cases ball_on_flat_steel,pin_on_disc]
                                            [--grid 64] [--cycles 100,1000]
                                            [--stroke M] [--tolerance 0.01]
    python benchmarks/bench_moving_jumps.py --tolerances

Each run in a fresh process, one at a time: the shipped case with
``bem.track_model = "moving"`` on ``--grid`` pixels, to ``--cycles`` cycles
(revolutions), jumped at ``--tolerance`` (``--stroke``: another stroke). Printed per run: the wall and CPU
seconds of the solve, the moves of the run and those simulated, the simulated
cycles, steps, the largest step, the error estimate, the seconds in the
wear Jacobian's solves; "every move" is the run's moves times the measured
time per simulated move (what the run cost before cycle jumping: one contact
solve per move, the same solves), and the ratio of the two.

``--tolerances``: the error of jumped runs against the run that simulates
every move, by tolerance, on the 24² case of tests/test_bem_moving_jumps.py
(ball_on_flat, both K = 1e-15, 0.1 mm stroke, 100 cycles): the table of
docs/both-bodies.md, CPU seconds in one process.

The machine is shared (2 cores, several users): wall-clock under whatever load
there was, printed with the load average; the CPU seconds are the steadier
figure.
"""

from __future__ import annotations

import argparse

import harness


def solve(name: str, grid: int, cycles: float, tolerance: float, stroke=None) -> dict:
    """One moving-contact run of the shipped case ``name``, in a fresh process."""
    import time
    import warnings

    warnings.simplefilter("ignore")
    from wearcheck import bem, cases
    over = [f"bem.grid={grid}", 'bem.track_model="moving"', f"bem.jump_tolerance={tolerance}",
            f"sliding.cycles={cycles}", f"stages.cycles=[0, {cycles}]"]
    if stroke is not None:
        over.append(f"sliding.stroke={stroke}")
    case = cases.load(cases.shipped(name), over)
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


def tolerances(values=(0.002, 0.005, 0.01, 0.02, 0.05, 0.1)):
    """The error of jumped runs against every move simulated (docs/both-bodies.md)."""
    import time
    import warnings

    import numpy as np

    warnings.simplefilter("ignore")
    from wearcheck import cases
    from wearcheck.bem import moving, track
    from wearcheck.cases import reference
    case = cases.load("cases/ball_on_flat.toml", [
        "counterface.wears=true", "counterface.specific_rate=1e-15", "wear.k=2e-5",
        'sliding.motion="reciprocating"', "sliding.stroke=1e-4", "sliding.cycles=100",
        "stages.cycles=[0, 100]", "bem.grid=24", "bem.box=3.0", 'bem.track_model="moving"'])
    sc = reference.scales(case)
    travel, dx = moving.track_rows(case.sliding.stroke, track.setup(case, sc)[0].op.spacing)
    m, _ = track.setup(case, sc, spacing=dx)
    model = moving.MovingModel(op=m.op, f0=m.f0, wear_rate=m.wear_rate,
                               flat_wear_rate=m.flat_wear_rate, rows=travel + m.op.n,
                               periodic=False, depth=None, force=m.force, p_scale=m.p_scale,
                               g_scale=m.g_scale, tol=m.tol)
    one = moving.reciprocating_offsets(travel, 1)
    moves = 100 * len(one)

    def final(out):
        st = out["states"]
        return np.concatenate([st["ball_wear"][-1].ravel(), st["flat_wear"][-1].ravel()])
    t = time.process_time()
    ref = final(moving.run(model, np.tile(one, 100), record=[0, moves], keep=[moves]))
    print(f"every move: {moves} moves, {time.process_time() - t:.1f} s of CPU")
    print("| tolerance | error | estimate | simulated cycles | steps | largest step | CPU [s] |")
    print("|---|---|---|---|---|---|---|")
    for tol in values:
        t = time.process_time()
        out = moving.run_jumped(model, one, moves, tolerance=tol, keep=[moves])
        cpu = time.process_time() - t
        err = np.max(np.abs(final(out) - ref)) / np.max(np.abs(ref))
        i = out["jumping"]
        print(f"| {tol:g} | {err:.2g} | {i['error_estimate']:.2g} | {i['simulated_cycles']} | "
              f"{i['steps']} | {i['largest_step']} | {cpu:.1f} |", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="ball_on_flat_steel,pin_on_disc")
    ap.add_argument("--grid", type=int, default=64)
    ap.add_argument("--cycles", default="100,1000")
    ap.add_argument("--tolerance", type=float, default=0.01)
    ap.add_argument("--stroke", type=float, default=None)
    ap.add_argument("--tolerances", action="store_true")
    args = ap.parse_args(argv)
    print(harness.load())
    if args.tolerances:
        tolerances()
        print(harness.load())
        return
    print("| case | grid | cycles | moves of the run | simulated moves | simulated cycles "
          "| steps | largest step | error estimate | wall [s] | CPU [s] | Jacobian [s] "
          "| every move [s] | ratio | balance |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in args.cases.split(","):
        for cycles in (float(c) for c in args.cycles.split(",")):
            r = harness.call(f"{__file__}:solve", name, args.grid, cycles, args.tolerance,
                             args.stroke, timeout=6 * 3600)[0]
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
