"""Both bodies wearing (issue 24): the cost of the BEM's two models on the shipped cases.

    python benchmarks/bench_both_bodies.py [--cases ball_on_flat_steel,pin_on_disc]
                                           [--moving-cycles 1]

Each run in a fresh process, one at a time:

1. the long-stroke model (bem/track.py) on the shipped case as it is: solve
   time, steps, CG iterations;
2. the same case with counterface.wears = false (today's ball-only BEM, the
   baseline of the same run): the ratio of the two is the cost of wearing the
   counterface too;
3. the moving-contact model (bem/moving.py) on the case's grid for
   ``--moving-cycles`` cycles: time per move (one contact solve), and the
   shipped run's number of moves (its sliding over the pixel) times it, the
   time the moving model would take without cycle jumping.

The machine is shared (2 cores, several users): times are wall-clock under
whatever load there was, printed with the load average.
"""

from __future__ import annotations

import argparse

import harness

def solve(name: str, mode: str, cycles: float = 0.0) -> dict:
    """One BEM run of the shipped case ``name`` (``mode``: both, ball_only or
    moving), run in a fresh process by :func:`child`: its solve time and counts."""
    import time
    import warnings

    warnings.simplefilter("ignore")
    from wearcheck import bem, cases
    case = cases.load(cases.shipped(name))
    if mode == "ball_only":
        case = case.derive({"counterface.wears": False})
    shipped_pixel = None
    if mode == "moving":
        from wearcheck.bem import track
        from wearcheck.cases import reference
        shipped_pixel = track.setup(case, reference.scales(case))[0].op.spacing
        end = case.end_distance
        case = case.derive({"bem.track_model": "moving", "sliding.cycles": cycles,
                            "stages.cycles": [0.0, cycles]})
    t = time.perf_counter()
    res = bem.solve(case)
    seconds = time.perf_counter() - t
    out = dict(seconds=seconds, steps=res.info.get("steps"), moves=res.info.get("moves"),
               cg=res.info.get("cg_iterations"), pixel=res.info["pixel"])
    if mode == "moving":
        out["shipped_moves"] = end / shipped_pixel
    return out


def child(name, mode, cycles=0.0):
    return harness.call(f"{__file__}:solve", name, mode, float(cycles))[0]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="ball_on_flat_steel,pin_on_disc")
    ap.add_argument("--moving-cycles", type=float, default=1.0)
    args = ap.parse_args(argv)
    print(harness.load())
    print("| case | long-stroke [s] | steps | CG its | ball only [s] | ratio | moving: s/move "
          "| moves of the shipped run | moving, shipped run [h] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in args.cases.split(","):
        both = child(name, "both")
        ball = child(name, "ball_only")
        mov = child(name, "moving", args.moving_cycles)
        per_move = mov["seconds"] / mov["moves"]
        print(f"| {name} | {both['seconds']:.1f} | {both['steps']} | {both['cg']} | "
              f"{ball['seconds']:.1f} | {both['seconds'] / ball['seconds']:.2f} | "
              f"{per_move * 1e3:.2f} ms | {mov['shipped_moves']:.3g} | "
              f"{per_move * mov['shipped_moves'] / 3600:.3g} |")
    print(harness.load())


if __name__ == "__main__":
    main()
