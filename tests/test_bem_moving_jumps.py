"""Cycle jumping for the BEM's moving-contact model (bem/moving.py, issue 24):
the jumped run against the run that simulates every move, the Archard balance
through the jumps, stages inside a cycle, and a run beyond the 200 000 moves
that the model refuses without jumping."""

import numpy as np
import pytest

from wearcheck import bem, cases
from wearcheck.bem import moving, track
from wearcheck.cases import CaseError, SolverError, reference

BALL = "cases/ball_on_flat.toml"


def small(stroke=1e-4, cycles=100, scale=0.01, flat=1.0, **more):
    """ball_on_flat on 24² pixels, both wearing (K_ball = scale·1e-13, K_flat = flat
    times it), ``cycles`` strokes of ``stroke`` there and back: the wear grows the
    contact by about half over the run (the box is sized for it)."""
    over = ["counterface.wears=true", f"counterface.specific_rate={1e-13 * scale * flat}",
            f"wear.k={2e-3 * scale}", 'sliding.motion="reciprocating"',
            f"sliding.stroke={stroke}", f"sliding.cycles={cycles}",
            f"stages.cycles=[0, {cycles}]", "bem.grid=24", "bem.box=3.0",
            'bem.track_model="moving"']
    return cases.load(BALL, over + [f"{k}={v}" for k, v in more.items()])


def model_of(case):
    """The moving model of ``case`` and its offsets over one cycle."""
    sc = reference.scales(case)
    base, _ = track.setup(case, sc)
    travel, dx = moving.track_rows(case.sliding.stroke, base.op.spacing)
    m, _x = track.setup(case, sc, spacing=dx)
    mm = moving.MovingModel(op=m.op, f0=m.f0, wear_rate=m.wear_rate,
                            flat_wear_rate=m.flat_wear_rate, rows=travel + m.op.n,
                            periodic=False, depth=None, force=m.force, p_scale=m.p_scale,
                            g_scale=m.g_scale, tol=m.tol)
    return mm, moving.reciprocating_offsets(travel, 1)


@pytest.fixture(scope="module")
def every_move():
    """The reference: every move simulated (moving.run, no cycle jumping), 100 cycles."""
    mm, one = model_of(small())
    moves = 100 * len(one)
    ref = moving.run(mm, np.tile(one, 100), record=[0, moves], keep=[moves])
    return mm, one, ref


@pytest.mark.parametrize("tol", [0.01, 0.05])
def test_jumped_wear_within_the_tolerance_of_every_move(every_move, tol):
    # Both bodies' wear after 100 cycles (4600 moves), jumped at tol, against the
    # run that simulates every move: the largest difference over the largest
    # wear is at most tol, what bem.jump_tolerance bounds (measured 0.34 tol and
    # 0.13 tol). The estimate reported is at most tol, and the error at most 1.5
    # times it (the integrator follows the ODE in the cycle count, the simulated
    # run the map of the cycles, which part by a little more than the steps'
    # estimates see: numerics.cycle_jumping; measured 1.26 and 1.16 times).
    # Most cycles are jumped (22 and 16 simulated).
    mm, one, ref = every_move
    moves = 100 * len(one)
    out = moving.run_jumped(mm, one, moves, tolerance=tol, keep=[moves])
    y_ref = np.concatenate([ref["states"]["ball_wear"][-1].ravel(),
                            ref["states"]["flat_wear"][-1].ravel()])
    y = np.concatenate([out["states"]["ball_wear"][-1].ravel(),
                        out["states"]["flat_wear"][-1].ravel()])
    err = float(np.max(np.abs(y - y_ref)) / np.max(np.abs(y_ref)))
    info = out["jumping"]
    assert err <= tol, (err, info)
    assert info["error_estimate"] <= tol
    assert err <= 1.5 * info["error_estimate"], (err, info["error_estimate"])
    assert info["simulated_cycles"] < 50 and out["counters"]["moves"] < moves / 2
    assert out["history"]["s"][-1] == pytest.approx(moves * mm.op.spacing, rel=1e-12)


def test_the_archard_balance_holds_through_the_jumps():
    # The ROS2 solves keep each body's summed wear (the Jacobian's 1ᵀJ = 0), so
    # each body still loses K_body·F·s and V_ball/V_flat = K_ball/K_flat at
    # every row, jumped or simulated: to round-off (1e-12; measured 2e-14),
    # with K_flat = 3 K_ball.
    case = small(cycles=400, scale=0.003, flat=3.0)
    res = bem.solve(case)
    jumping = res.info["cycle_jumping"]
    assert jumping["steps"] >= 5 and jumping["largest_step"] >= 20
    bal = res.info["archard_balance"]
    assert max(bal.values()) < 1e-12, bal
    h = res.history
    ratio = h["wear_volume"][1:] / h["wear_volume_counterface"][1:]
    np.testing.assert_allclose(ratio, 1.0 / 3.0, rtol=1e-12)
    assert res.info["jump_tolerance"] == case.bem.jump_tolerance
    assert 0.0 < jumping["error_estimate"] <= case.bem.jump_tolerance


def test_a_stage_inside_a_cycle_is_the_state_at_its_move(every_move):
    # A stage half-way through cycle 2 (before any jump: the first cycles are
    # simulated) is the every-move run's state at that move, to round-off; a
    # stage inside a later, jumped-to cycle lies at its own move, its wear
    # between the kept cycles' either side (wear only grows).
    mm, one, ref = every_move
    P = len(one)
    stage = int(1.5 * P)
    direct = moving.run(mm, np.tile(one, 2)[:stage], record=[stage], keep=[stage])
    late = 80 * P + P // 3
    out = moving.run_jumped(mm, one, 100 * P, tolerance=0.05, keep=[stage, late])
    assert list(out["states"]["move"]) == [stage, late]
    np.testing.assert_allclose(out["states"]["ball_wear"][0],
                               direct["states"]["ball_wear"][-1], rtol=0, atol=1e-12 *
                               np.max(direct["states"]["ball_wear"][-1]))
    np.testing.assert_allclose(out["states"]["flat_wear"][0],
                               direct["states"]["flat_wear"][-1], rtol=0, atol=1e-12 *
                               np.max(direct["states"]["flat_wear"][-1]))
    s = out["history"]["s"]
    V = out["history"]["wear_volume"]
    dx = mm.op.spacing
    V_late = float(np.sum(out["states"]["ball_wear"][1])) * dx * dx
    before = np.flatnonzero(s <= late * dx)[-1]
    assert s[before + 1] > late * dx
    assert V[before] < V_late < V[before + 1]


def test_a_run_beyond_the_moves_refused_without_jumping_completes():
    # 3000 cycles of a 0.25 mm stroke on 24² pixels of 5.3 µm: 282 000 moves,
    # more than the 200 000 the model simulates without jumping (refused,
    # naming the key); jumped it simulates under a tenth of them (measured
    # 1.9 %: 5452 moves, 58 cycles, 13 s of CPU).
    over = dict(stroke=2.5e-4, cycles=3000, scale=1e-3)
    with pytest.raises(CaseError, match=r"'bem.jump_tolerance' = 0: the run would take "
                                        r"282000 contact solves") as refused:
        bem.solve(small(**over, **{"bem.jump_tolerance": 0}))
    assert "give bem.jump_tolerance > 0" in str(refused.value)
    res = bem.solve(small(**over))
    assert res.history["cycles"][-1] == pytest.approx(3000, rel=1e-12)
    assert res.history["s"][-1] == pytest.approx(282_000 * res.info["pixel"], rel=1e-12)
    assert res.info["moves"] < 0.1 * 282_000, res.info["moves"]
    assert max(res.info["archard_balance"].values()) < 1e-12


def test_the_runaway_guard_names_the_tolerance(every_move):
    # a jumped run that would simulate more moves than its guard stops with one
    # line naming the key (moving.MAX_SIMULATED_MOVES in a case run)
    mm, one, _ = every_move
    with pytest.raises(SolverError, match=r"more than 5 cycles; raise bem.jump_tolerance"):
        moving.run_jumped(mm, one, 100 * len(one), tolerance=0.01,
                          max_simulated_moves=5 * len(one))


def test_a_jacobian_known_by_its_solves_propagates_as_the_matrix():
    # numerics.cycle_jumping.SolveJacobian builds R(hJ) e from (I − gJ)⁻¹ alone;
    # on a dense J it must equal ros2_propagate with the matrix (to 1e-12)
    from wearcheck.numerics import cycle_jumping as cj
    rng = np.random.default_rng(1)
    Q, _ = np.linalg.qr(rng.normal(size=(8, 8)))
    J = Q @ np.diag(-np.logspace(-3, 1, 8)) @ Q.T

    class Solves(cj.SolveJacobian):
        def filter(self, gh, x):
            return np.linalg.solve(np.eye(8) - gh * J, x)
    e = rng.normal(size=8)
    for h in (0.5, 10.0, 1e3):
        want = cj.ros2_propagate(e, h, cj.Jacobian(np.arange(8), J))
        np.testing.assert_allclose(Solves().propagate(e, h), want, rtol=0,
                                   atol=1e-12 * np.max(np.abs(e)))
