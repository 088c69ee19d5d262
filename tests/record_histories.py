"""Record the histories and stages of every shipped case and of the stepper's paths.

    python tests/record_histories.py OUT.npz

Run once before the time loops of the MDR, FEM and BEM moved into
:mod:`wearcheck.numerics.stepping`; ``tests/test_stepper_histories.py`` then
checks that the moved loops give the same histories (to 1e-10, relative to
each column's largest value). Shipped cases at their resolution (the BEM's
ball_on_flat at 128 pixels instead of 256, for time), then each scheme and
path of each solver on the paper case at small resolution. With each
run: the numbers meta.json records of its stepping (steps, rejections, the
time-error estimate, the solves' iteration counts).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from wearcheck import bem, cases, fem, mdr

SOLVERS = {"mdr": mdr.solve, "fem": fem.solve, "bem": bem.solve}

#: (name, case, solver, overrides)
RUNS = [
    ("paper-mdr", "paper", "mdr", []),
    ("paper-fem", "paper", "fem", []),
    ("paper-bem", "paper", "bem", []),
    ("ball_on_flat-mdr", "ball_on_flat", "mdr", []),
    ("ball_on_flat-fem", "ball_on_flat", "fem", []),
    ("ball_on_flat-bem", "ball_on_flat", "bem", ["bem.grid=128"]),
    ("ellipsoid-mdr", "ellipsoid", "mdr", []),
    ("ellipsoid-bem", "ellipsoid", "bem", []),
    ("hertz-mdr", "hertz", "mdr", []),
    ("hertz-fem", "hertz", "fem", []),
    ("hertz-bem", "hertz", "bem", []),
    ("truncated-mdr", "truncated", "mdr", []),
    ("truncated-fem", "truncated", "fem", []),
    ("truncated-bem", "truncated", "bem", []),
    ("fretting-mdr", "fretting", "mdr", ["fretting.cycles=1000"]),
]
SMALL = {"mdr": ["mdr.elements=200"], "fem": ["fem.contact_nodes=60"], "bem": ["bem.grid=48"]}
VARIANTS = [
    ("implicit", ["sliding.scheme=implicit"]),
    ("bdf2", ["sliding.scheme=bdf2"]),
    ("explicit", ["sliding.scheme=explicit"]),
    ("adaptive-1e-3", ["sliding.tolerance=1e-3"]),
    ("adaptive-n2", ["wear.pressure_exponent=2.0", "sliding.tolerance=1e-3"]),
    ("implicit-n2", ["wear.pressure_exponent=2.0", "sliding.scheme=implicit",
                     "sliding.step_hat=0.2", "sliding.until=\"distance\"",
                     "sliding.distance=0.1"]),
    ("distance-bdf2", ["sliding.until=\"distance\"", "sliding.distance=0.03",
                       "sliding.scheme=bdf2", "sliding.step_hat=0.07",
                       "stages.s_hat=[0.0, 0.25, 0.6]"]),
    ("distance-adaptive", ["sliding.until=\"distance\"", "sliding.distance=0.03",
                           "stages.s_hat=[0.0, 0.3, 0.77]"]),
]
for solver in ("mdr", "fem", "bem"):
    for name, over in VARIANTS:
        RUNS.append((f"paper-{solver}-{name}", "paper", solver, SMALL[solver] + over))
RUNS += [
    ("paper-mdr-tangential", "paper", "mdr", ["mdr.elements=200", "sliding.scheme=implicit",
                                              "wear.tangential_correction=true"]),
    # grids above 2048 nodes: GMRES, continuous step control, the far-gap check
    ("paper-mdr-4096", "paper", "mdr", ["mdr.elements=4096"]),
    ("paper-mdr-4096-force", "paper", "mdr", ["mdr.elements=4096", "loading.control=\"force\"",
                                              "loading.force=20.0", "sliding.until=\"distance\"",
                                              "sliding.distance=0.2"]),
    ("ball_on_flat-mdr-4096", "ball_on_flat", "mdr", ["mdr.elements=4096",
                                                      "sliding.cycles=2000"]),
    ("ball_on_flat-mdr-bdf2", "ball_on_flat", "mdr", ["sliding.scheme=bdf2",
                                                      "sliding.step_hat=2", "sliding.cycles=1e4"]),
    # paths the runs above miss: fixed steps on the GMRES grids (the regular
    # step's factorisation preconditions the others), a pressure exponent
    # there, the tangential correction under step doubling and BDF2, force
    # control with fixed steps in the FEM and BEM, explicit Euler under force
    ("paper-mdr-4096-bdf2", "paper", "mdr", ["mdr.elements=4096", "sliding.scheme=bdf2",
                                             "sliding.until=\"distance\"", "sliding.distance=0.05",
                                             "stages.s_hat=[0.0, 0.25, 0.6]"]),
    ("paper-mdr-4096-implicit-n2", "paper", "mdr", ["mdr.elements=4096",
                                                    "wear.pressure_exponent=2.0",
                                                    "sliding.scheme=implicit",
                                                    "sliding.step_hat=0.2",
                                                    "sliding.until=\"distance\"",
                                                    "sliding.distance=0.02"]),
    ("paper-mdr-4096-adaptive-n2", "paper", "mdr", ["mdr.elements=4096",
                                                    "wear.pressure_exponent=2.0",
                                                    "sliding.tolerance=1e-3",
                                                    "sliding.until=\"distance\"",
                                                    "sliding.distance=0.02"]),
    ("paper-mdr-tangential-adaptive", "paper", "mdr", ["mdr.elements=200",
                                                       "sliding.tolerance=1e-3",
                                                       "wear.tangential_correction=true"]),
    ("paper-mdr-tangential-bdf2", "paper", "mdr", ["mdr.elements=200", "sliding.scheme=bdf2",
                                                   "wear.tangential_correction=true"]),
]
FORCE = ["loading.control=\"force\"", "loading.force=20.0", "sliding.until=\"distance\"",
         "sliding.distance=0.1"]
for solver in ("mdr", "fem", "bem"):
    for scheme in ("implicit", "bdf2", "explicit"):
        RUNS.append((f"paper-{solver}-force-{scheme}", "paper", solver,
                     SMALL[solver] + FORCE + [f"sliding.scheme={scheme}"]))

#: what meta.json records of the stepping (numbers in info, nested keys joined by "/")
INFO = ("steps", "rejected_steps", "largest_step_hat", "time_error/estimate",
        "time_error/local_error_sum", "time_error/rejected_steps",
        "time_error/largest_step_hat", "contact_iterations", "gmres_iterations",
        "gmres_float32_iterations", "gmres_float64_fallbacks", "domain_growths",
        "lcp_iterations", "refactorisations", "borderings", "cg_iterations",
        "operator_applications")


def info_numbers(info: dict) -> dict:
    """The numbers of INFO that ``info`` holds."""
    out = {}
    for key in INFO:
        v = info
        for part in key.split("/"):
            v = v.get(part) if isinstance(v, dict) else None
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            out[key] = float(v)
    return out


def run_all(names=None):
    out = {}
    for name, case, solver, over in RUNS:
        if names is not None and name not in names:
            continue
        t = time.perf_counter()
        res = SOLVERS[solver](cases.load(cases.shipped(case), over))
        for k, v in res.history.items():
            out[f"{name}/history/{k}"] = np.asarray(v, dtype=float)
        out[f"{name}/stage_s"] = np.asarray(res.stage_s, dtype=float)
        out[f"{name}/f"] = np.asarray(res.f, dtype=float)
        out[f"{name}/p"] = np.asarray(res.p, dtype=float)
        for k, v in info_numbers(res.info).items():
            out[f"{name}/info/{k}"] = np.float64(v)
        print(f"{name}: {time.perf_counter() - t:.2f} s, {len(res.history['s'])} points",
              flush=True)
    return out


if __name__ == "__main__":
    names = set(sys.argv[2].split(",")) if len(sys.argv) > 2 else None
    np.savez_compressed(sys.argv[1], **run_all(names))
