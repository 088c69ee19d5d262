"""Cycle jumping against the run that simulates every cycle (docs/fretting.md, §4).

The cycle-averaged wear is integrated in the cycle count by ROS2 steps
(numerics.cycle_jumping), the stiff part of its Jacobian the wear's response
to the pressure. The jumped cycles' wear lowers the spring limits in the slip
annulus; the slip by which the springs follow their limits down is part of
every simulated cycle, so the next simulated cycle must start from the
springs on the new limits. The references here are independent of the jumps:
the same case with every cycle simulated (short runs), Popov's limit (long
runs) and the normal contact solved afresh (the Jacobian).

Case: N = 200, k = 0.01, 200 cycles (k·n = 2, the transient before the
limiting state, where W still changes), u0 = 0.2u* (a thin slip annulus: its
slip per cycle 2(U - L) is small, so a fall of L weighs much in it).
"""

from functools import lru_cache

import numpy as np
import pytest

from test_fretting_mdr import FORCE, MU, R, make
from wearcheck import mdr
from wearcheck.cases import reference_fretting as rf
from wearcheck.mdr import fretting

N, K, CYCLES, AMPLITUDE = 200, 0.01, 200, 0.2


@lru_cache(maxsize=None)
def _run(control, jump_tolerance):
    case, _, _ = make(N=N, amplitude=AMPLITUDE, cycles=CYCLES, k=K, control=control,
                      jump_tolerance=jump_tolerance, increments=20, stage_cycles=[0, CYCLES])
    return mdr.solve(case)


@pytest.mark.parametrize("control", ["force", "depth"])
@pytest.mark.parametrize("tol", [0.05, 0.1])
def test_energy_per_cycle_after_jumps_is_the_every_cycle_runs(control, tol):
    # The profile's error is held at tol of its change (test below); the energy
    # per cycle E follows the profile, so to first order its error is at most
    # tol times its change over the run, tol·X, X = max|E(c) - E(1)|. With the
    # springs left at the limits from before a jump, the cycle after it slid
    # less by the limits' fall and its energy was low by 1.4-3.0 tol·X under
    # the forward-Euler jumps this test was written for.
    ref, res = _run(control, 0.0), _run(control, tol)
    assert res.info["jumps"] >= 5
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
    assert res.info["jumps"] >= 5
    Q_star = case.fretting.force_amplitude
    start = res.fields["loop_tangential_force"][:, 0]
    assert len(start) >= 3
    np.testing.assert_allclose(start, Q_star, rtol=1e-9)


@pytest.mark.parametrize("control", ["force", "depth"])
@pytest.mark.parametrize("tol", [0.02, 0.1])
def test_profile_within_the_tolerance_of_every_cycle(control, tol):
    # The worn profile at the last cycle against the run that simulates every
    # cycle, over the largest wear: at most tol (what fretting.jump_tolerance
    # bounds); measured 0.17-0.39 tol. The estimate reported in meta.json is at
    # most tol, and the error at most 1.5 times it (measured 0.96-1.27 with the
    # map drift counted, 1.1-1.5 before: the estimate is asymptotic in the step).
    ref, res = _run(control, 0.0), _run(control, tol)
    f0 = ref.f[0]
    Y = np.max(np.abs(ref.f[-1] - f0))
    err = float(np.max(np.abs(res.f[-1] - ref.f[-1])) / Y)
    est = res.info["cycle_jumping"]["error_estimate"]
    assert err <= tol
    assert est <= tol
    assert err <= 1.5 * est, f"error {err:.3g}, estimated {est:.3g}"


@pytest.mark.parametrize("control", ["force", "depth"])
def test_pressure_response_is_the_normal_contacts(control):
    # The jumps' Jacobian rests on ∂p/∂f on the contact set: against central
    # differences of the normal contact solved afresh (FFT transforms and the
    # exact depth-for-force; the matrices are built column by column). Linear
    # on a fixed contact set, so the differences agree but for the edge: the
    # last node carries q ~ 0 and leaves under the probe (steps of 1e-9 of the
    # depth), which moves the columns of nodes next to it by up to 1.4e-4 of
    # the largest entry. Nodes 8 or more from the edge, bound 1e-4.
    case, _, _ = make(N=N, amplitude=0.5, cycles=1, k=K, control=control)
    model, _ = fretting.build_model(case)
    st = fretting.initial_state(model)
    m = st.normal["m"]
    index = np.arange(m // 2, m - 8, 3)
    P = fretting._pressure_response(model, m, index)
    eps = 1e-9 * st.normal["depth"]
    for k, j in enumerate(index):
        p = []
        for sign in (1.0, -1.0):
            s = st.copy()
            s.f = st.f.copy()
            s.f[j] += sign * eps
            fretting.solve_normal(model, s)
            # the last node of the unworn contact carries q ~ 0 (the edge falls on it):
            # it may leave, which moves p by that q only
            assert abs(s.normal["m"] - m) <= 1
            p.append(s.normal["p"][index])
        column = (p[0] - p[1]) / (2 * eps)
        np.testing.assert_allclose(P[:, k], column, atol=1e-4 * np.max(np.abs(P)))


def test_long_runs_reach_popovs_limit_at_a_cost_in_the_logarithm_of_the_cycles():
    # k·n = 1e4 and 1e6, far past the limiting state (reached by k·n = 160,
    # docs/fretting.md §2). Against Popov's d∞(c) = F/(2E*c) + c²/(3R) at the
    # run's own stick radius: the solver's limit lies below it by the grid's
    # floor, -2.85e-3 at N = 200 (first order in N, docs/fretting.md §2, every
    # cycle simulated), and above it in the continuum by 5e-5: the window is
    # -3.5e-3 .. +1e-4. The stick radius within the closed-form bounds c0 <= c
    # <= c_max (docs/fretting.md §2.1). From 10⁶ to 10⁸ cycles the rate has
    # vanished and the steps grow geometrically: at most 300 more cycles
    # simulated (measured 148, some steps retried at half length by the
    # monotone-load check), where the forward-Euler jumps took 6400 more (9258
    # at N = 800, benchmarks/bench_fretting_cycles.py).
    runs = {}
    for cycles in (10**6, 10**8):
        case, _, _ = make(N=N, amplitude=0.5, cycles=cycles, k=K, jump_tolerance=0.02,
                          increments=20, stage_cycles=[0, cycles])
        runs[cycles] = res = mdr.solve(case)
        h = res.history
        c, d = h["stick_radius"][-1], h["depth"][-1]
        c0, c_max = rf.stick_radius_bounds(FORCE, case.E_star, case.G_star, MU,
                                           case.fretting.amplitude, R)
        assert c0 <= c <= c_max
        popov = d / rf.limiting_depth(FORCE, case.E_star, c, R) - 1.0
        assert -3.5e-3 <= popov <= 1e-4, f"{cycles} cycles: d/d∞(c) - 1 = {popov:.3g}"
        assert res.info["cycle_jumping"]["error_estimate"] <= 0.02
    more = runs[10**8].info["simulated_cycles"] - runs[10**6].info["simulated_cycles"]
    assert more <= 300


@pytest.mark.parametrize("N, tol", [(175, 0.05), (200, 0.02)])
def test_depth_control_limit_with_the_stick_edge_on_a_node(N, tol):
    # Depth control, u0 = 0.5u*: c0² = a²/2 falls on node 0.16 N (t uniform,
    # t_max = 3.125 a²), where the spring limit equals U to round-off (1e-15 U).
    # In exact arithmetic that spring never slides and the stick zone never
    # wears (Eq. 16 at r needs the 1D slip on [0, r] only; the depth is held),
    # so c = c0 throughout (docs/fretting.md §2); once it slides, its wear
    # lowers its limit and it slides more: a mode of the cycle map growing
    # by ~4 % per cycle (k = 0.1, N = 200). The FFT's round-off leaves 1e-15 of
    # the annulus's wear on the stick nodes: a simulated cycle rounds it away
    # (below one ulp of the profile), a step of h cycles lays h times it down,
    # and the mode grew from there: the profile ended 0.36 (N = 175) and 0.35
    # (N = 200) of the wear off, c 1.7 % and 1.5 % low, unseen by the estimate.
    # k = 1 puts the limiting state (k·n = 160) into 160 cycles.
    case, _, _ = make(N=N, amplitude=0.5, cycles=160, k=1.0, control="depth",
                      jump_tolerance=0.0, increments=20, stage_cycles=[0, 160])
    ref = mdr.solve(case)
    case, _, _ = make(N=N, amplitude=0.5, cycles=160, k=1.0, control="depth",
                      jump_tolerance=tol, increments=20, stage_cycles=[0, 160])
    res = mdr.solve(case)
    assert res.info["simulated_cycles"] < 120
    # the reference keeps the law: c = c0 to round-off (the sub-grid crossing)
    c_ref = ref.history["stick_radius"]
    np.testing.assert_allclose(c_ref[1:], c_ref[1], rtol=1e-12)
    Y = np.max(np.abs(ref.f[-1] - ref.f[0]))
    err = float(np.max(np.abs(res.f[-1] - ref.f[-1])) / Y)
    assert err <= tol, f"profile off by {err:.3g} of the wear (tolerance {tol})"
    c = res.history["stick_radius"]
    assert c[-1] == pytest.approx(c_ref[-1], rel=1e-12)
