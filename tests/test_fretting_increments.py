"""The resolution check of the fretting increments (docs/fretting.md, §5).

The wear within a cycle is forward Euler; at the grid scale it is stable
while the increment wear number Λ = (k/σ0) μ E* |Δslip|/Δr stays below
2/β_max, β_max the largest eigenvalue of the grid's normal stiffness
(Δr/E*)·(−∂p/∂f). The solver refuses a run whose Λ exceeds
WEAR_NUMBER_LIMIT with a SolverError naming fretting.increments and a value
that would do. These tests check the limit against that eigenvalue and the
refusal against the thing it stands for: the error of the run against one
with 4x the increments (converged in time), large for a refused run, small
for the run the message proposes. N = 200 and k = 4 (4·10^4 times the
paper's) put Λ past the limit at 20 increments per cycle; 20 cycles
(k·n = 80) reach the limiting state.
"""

import math
import re

import numpy as np
import pytest

from test_fretting_mdr import make
from wearcheck.cases import SolverError
from wearcheck.mdr import fretting

N, K, CYCLES = 200, 4.0, 20
LIMIT = fretting.WEAR_NUMBER_LIMIT   # before a test switches the check off


def _case(control, increments):
    case, _, _ = make(N=N, amplitude=0.5, cycles=CYCLES, k=K, control=control,
                      jump_tolerance=0.02, increments=increments, stage_cycles=[0, CYCLES])
    return case


def _wear(res):
    return res.f[-1] - res.f[0]


def _profile_error(res, ref):
    w, wr = _wear(res), _wear(ref)
    return float(np.max(np.abs(w - wr)) / np.max(np.abs(wr)))


@pytest.fixture
def unchecked(monkeypatch):
    monkeypatch.setattr(fretting, "WEAR_NUMBER_LIMIT", math.inf)


@pytest.mark.parametrize("control", ["force", "depth"])
def test_under_resolved_increments_are_refused_and_the_proposal_is_resolved(control):
    with pytest.raises(SolverError, match=r"fretting\.increments = 20 does not resolve") as err:
        fretting.solve(_case(control, 20))
    proposed = int(re.search(r"fretting\.increments = (\d+) would do", str(err.value)).group(1))
    assert proposed % 4 == 0 and proposed > 20
    res = fretting.solve(_case(control, proposed))
    # the proposal resolves the whole run, not just its first cycles
    assert res.info["increment_wear_number"] <= fretting.WEAR_NUMBER_LIMIT
    # against a run with 4x its increments (Λ four times smaller): in the
    # calibration the runs at Λ <= 1.3 stay within 1.6e-3 of the wear
    # (profile) and 8.5e-4 (volume) but for one grid-edge split (docs §5);
    # 1e-2 is half the jump tolerance, the loosest of the run's other tolerances
    ref = fretting.solve(_case(control, 4 * proposed))
    assert _profile_error(res, ref) < 1e-2
    assert abs(res.history["wear_volume"][-1] / ref.history["wear_volume"][-1] - 1) < 1e-2


@pytest.mark.parametrize("amplitude, k, cycles", [(0.5, K, CYCLES), (2.0, 0.4, 1)])
def test_a_refused_run_is_wrong_beyond_the_runs_other_tolerances(unchecked, amplitude, k,
                                                                 cycles):
    # what the check refuses, run anyway: its worn profile is off by more
    # than the jump tolerance (0.02 of the wear per cycle, the loosest of the
    # run's own tolerances) against a run with 4x the increments; measured
    # 0.12 in partial slip (u0 = 0.5u*, Λ = 4.7) and 0.27 in gross slip
    # (u0 = 2u*, Λ = 2.9; benchmarks/bench_fretting_increments.py)
    def run(increments):
        case, _, _ = make(N=N, amplitude=amplitude, cycles=cycles, k=k, jump_tolerance=0.02,
                          increments=increments, stage_cycles=[0, cycles])
        return fretting.solve(case)

    res, ref = run(20), run(80)
    assert res.info["increment_wear_number"] > LIMIT
    assert _profile_error(res, ref) > 0.02


def test_limit_is_inside_the_linear_stability_of_the_explicit_wear():
    # a height δ on the worn profile changes the pressure by −(∂p/∂f) δ, and
    # the next increment wears (k/σ0) μ |Δslip| of that: forward Euler with
    # the matrix (Δr/E*)(−∂p/∂f) scaled by Λ, stable while Λ β_max <= 2.
    # β_max here from the MDR's transforms column by column, on the nodes in
    # contact (the grid-scale mode lives there); the limit must lie below 2/β_max
    from wearcheck.mdr import transforms
    case, _, _ = make(N=100, cycles=1)
    model, _ = fretting.build_model(case)
    st = fretting.initial_state(model)
    n = int(np.flatnonzero(st.normal["q"] > 0.0)[-1]) + 1
    S = np.empty((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = 1.0
        S[:, j] = transforms.pressure(model.E_star * transforms.to_1d(e), model.dt)
    beta = np.max(np.linalg.eigvals(model.h[:n, None] / model.E_star * S).real)
    assert LIMIT <= 2.0 / beta
    # and not far below it (a check that refused resolved runs would cost
    # increments for nothing): within 10 %
    assert LIMIT >= 0.9 * 2.0 / beta


def test_wear_number_scales_with_k_and_the_increments():
    # Λ = (k/σ0) μ E* |Δslip|/Δr: in the first cycle at a wear coefficient
    # this small the slip path does not feel the wear, so Λ is linear in k
    # (to 1e-6: the profile changed by 1e-9 of the depth), and the slip per
    # increment is the indenter's increment where the annulus slides, so
    # doubling the increments halves Λ (up to the increment in which a
    # spring starts to slide: within 10 %)
    def number(k, increments):
        case, _, _ = make(N=N, cycles=1, k=k, increments=increments)
        return fretting.solve(case).info["increment_wear_number"]

    base = number(1e-6, 20)
    assert number(2e-6, 20) == pytest.approx(2 * base, rel=1e-6)
    assert number(1e-6, 40) == pytest.approx(base / 2, rel=0.1)
    # and the paper's wear coefficient is far inside the limit at any grid up to
    # N = 3200 (Λ grows as N: Δr at the contact edge falls as 1/N)
    assert number(1e-4, 20) * 3200 / N < 0.1 * fretting.WEAR_NUMBER_LIMIT


def test_cycle_jumps_do_not_enter_the_wear_number():
    # a jump puts the springs on the limits its wear lowered, without wear (a
    # slip of the jumped cycles, several times an increment's when the increment
    # after the jump took it): with jumps Λ is that of the run simulating every
    # cycle, to 5 % (the jumps change the profile, and the slips, by up to the
    # tolerance)
    def number(jump_tolerance):
        case, _, _ = make(N=N, amplitude=0.5, cycles=CYCLES, k=K, jump_tolerance=jump_tolerance,
                          increments=160, stage_cycles=[0, CYCLES])
        res = fretting.solve(case)
        return res.info["increment_wear_number"], res.info["jumps"]

    (with_jumps, jumps), (every_cycle, _) = number(0.02), number(0.0)
    assert jumps > 0
    assert with_jumps == pytest.approx(every_cycle, rel=0.05)
