"""
A μ sweep on Dask
=================

A sweep over the coefficient of friction on Dask, from Python.

Each μ runs in its own worker process (an embedded local cluster: nothing to
set up; pass ``scheduler="tcp://host:8786"`` to use an existing one). Every run
is a complete run directory under ``runs/mu-sweep``; the rows returned are those
of ``sweep.csv``.
"""

import wearcheck


def main():
    case = wearcheck.load_case("paper", {"mdr.elements": 400})
    rows = wearcheck.sweep(case, {"wear.mu": [0.2, 0.3, 0.5]}, "runs/mu-sweep", solver="mdr",
                           workers=2)
    # ŝ = k μ E* s / (σ0 a0) contains μ: in ŝ every run wears alike, in metres of
    # sliding a rougher contact gets there sooner
    print(f"{'run':<24} {'sliding s [mm]':>14} {'final ŝ':>8} {'final F/F0':>10} "
          f"{'wear depth / d0':>16}")
    for row in rows:
        print(f"{row['run']:<24} {row['final_s'] * 1e3:>14.1f} {row['final_s_hat']:>8.3f} "
              f"{row['final_F_over_F0']:>10.4f} {row['final_wear_center_over_d0']:>16.4f}")

    # the runs read back as results, e.g. for the worn profiles
    for row in rows:
        result = wearcheck.read_run(f"runs/mu-sweep/{row['run']}")
        d0 = result.scales["d0"]
        print(row["run"], "profile at the last stage, f(0)/d0 =",
              f"{result.stages['f'][-1][0] / d0:.4f}")


# Dask's worker processes import this file again: the guard keeps them from
# starting sweeps of their own (not needed in a notebook).
if __name__ == "__main__":
    main()
