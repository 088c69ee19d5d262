"""Cycle jumping against the run that simulates every cycle (docs/fretting.md, §4).

A jump extrapolates the wear per cycle W over n - 1 cycles (forward Euler in
the cycle number) and is accepted when W changed by at most 2·tol (max norm)
across it. The jumped cycles' wear lowers the spring limits in the slip
annulus; the slip by which the springs follow their limits down is part of
every simulated cycle, so it is in W already, and the next simulated cycle
must start from the springs on the new limits. The reference here is
independent of the jumps: the same case with every cycle simulated.

Case: N = 200, k = 0.01, 200 cycles (k·n = 2, the transient before the
limiting state, where W still changes), u0 = 0.2u* (a thin slip annulus: its
slip per cycle 2(U - L) is small, so a fall of L weighs much in it).
"""

from functools import lru_cache

import numpy as np
import pytest

from test_fretting_mdr import make
from wearcheck import mdr

N, K, CYCLES, AMPLITUDE = 200, 0.01, 200, 0.2


@lru_cache(maxsize=None)
def _run(control, jump_tolerance):
    case, _, _ = make(N=N, amplitude=AMPLITUDE, cycles=CYCLES, k=K, control=control,
                      jump_tolerance=jump_tolerance, increments=20, stage_cycles=[0, CYCLES])
    return mdr.solve(case)


@pytest.mark.parametrize("control", ["force", "depth"])
@pytest.mark.parametrize("tol", [0.05, 0.1])
def test_energy_per_cycle_after_jumps_is_the_every_cycle_runs(control, tol):
    # The jump's forward-Euler error in the profile is (n - 1)/2 times the change
    # of W across it, at most tol (n - 1) max|W| by the acceptance test: a
    # fraction tol of the wear jumped over. The energy per cycle E follows the
    # profile, so to first order its error is at most tol times its change over
    # the jumps, at most tol·X, X = max|E(c) - E(1)| its largest change over the
    # run. Measured (every simulated cycle against the same cycle of the
    # reference): 0.15-0.25 of tol·X (0.06-0.11 in the limiting state,
    # benchmarks/bench_fretting_jumps.py). With the springs left at the limits
    # from before the jump, the cycle after it slid less by the limits' fall and
    # its energy was low by 1.4-3.0 tol·X (force: 1.92, 1.36; depth: 2.99, 1.77
    # at tol = 0.05, 0.1).
    ref, res = _run(control, 0.0), _run(control, tol)
    assert res.info["jumps"] >= 10
    E_ref = ref.history["energy_per_cycle"]
    X = np.max(np.abs(E_ref[1:] - E_ref[1]))
    cycles = res.history["cycles"].astype(int)[1:]
    assert cycles[-1] == CYCLES and len(cycles) < CYCLES / 2   # most cycles were jumped
    err = res.history["energy_per_cycle"][1:] - E_ref[cycles]
    ratio = float(np.max(np.abs(err)) / (tol * X))
    assert ratio <= 1.0, f"energy per cycle off by {ratio:.3g} tol·X"


@pytest.mark.parametrize("control", ["force", "depth"])
def test_jumps_keep_the_energy_wear_identity_and_the_sliding_distance(control):
    # V = (k/σ0) W_dissipated holds for the jumped run as for the reference (to
    # round-off: the same quadrature), and the sliding distance, the indenter's
    # travel 4U per cycle, does not depend on how the cycles were taken (1e-12:
    # sums of equal increments)
    ref, res = _run(control, 0.0), _run(control, 0.1)
    for run in (ref, res):
        h = run.history
        np.testing.assert_allclose(h["wear_volume"], K / 2e9 * h["dissipated_energy"],
                                   rtol=1e-9, atol=1e-12 * h["wear_volume"][-1])
    assert res.history["s"][-1] == pytest.approx(ref.history["s"][-1], rel=1e-12)


@pytest.mark.parametrize("control", ["force", "depth"])
def test_under_a_tangential_force_amplitude_each_simulated_cycle_starts_at_it(control):
    # With a tangential force amplitude Q*, every cycle of the every-cycle run
    # starts where the last one ended, at Q* (u the output). A jump lowers the
    # spring limits; the springs put on them carry less than Q*, so the jump
    # reloads them to Q* by a little more travel, as the jumped cycles did.
    # Clipped only, the stage loops after jumps started 1.2e-3 (force) and
    # 2.7e-3 (depth control) below Q*
    # (the next cycle then slid and wore less); the reload solves the springs'
    # force exactly (displacement_for_force), so the start is Q* to round-off
    case, _, _ = make(N=N, force_amplitude=0.8, cycles=CYCLES, k=K, control=control,
                      jump_tolerance=0.1, increments=20, stage_cycles=[0, 50, 100, CYCLES])
    res = mdr.solve(case)
    assert res.info["jumps"] >= 10
    Q_star = case.fretting.force_amplitude
    start = res.fields["loop_tangential_force"][:, 0]
    assert len(start) >= 3
    np.testing.assert_allclose(start, Q_star, rtol=1e-9)
