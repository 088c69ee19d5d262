"""A wear rate lost in round-off is a numerical failure (mdr/solver.py,
check_archard_balance): Archard's law with n = 1 under a constant force wears
V = K·F·s exactly, whatever the profile; a run whose volume misses it is refused."""

import numpy as np
import pytest

from wearcheck import cases, mdr
from wearcheck.cases import SolverError
from wearcheck.mdr import solver

BALL = "cases/ball_on_flat.toml"


def test_the_balance_measures_the_volume_against_archard():
    # synthetic histories: V = K F s exactly is 0, half of it 0.5
    K, F, s = 2e-15, 10.0, np.array([0.0, 1.0, 3.0])
    assert solver.archard_balance(dict(s=s, wear_volume=K * F * s), K, F) == 0.0
    assert solver.archard_balance(dict(s=s, wear_volume=0.5 * K * F * s), K, F) == \
        pytest.approx(0.5, rel=1e-12)
    assert solver.archard_balance(dict(s=s[:1], wear_volume=s[:1]), K, F) == 0.0


def test_a_resolved_run_keeps_the_balance():
    # ball_on_flat at N = 200: the grid's and the steps' errors leave the volume
    # within 2e-3 of K F s (measured 9e-5; 7.5e-4 at N = 50), ten times inside the
    # refusal's ARCHARD_BALANCE_TOL
    res = mdr.solve(cases.load(BALL, ["mdr.elements=200"]))
    assert res.info["archard_balance_error"] < 2e-3
    assert solver.ARCHARD_BALANCE_TOL >= 10 * 2e-3


@pytest.mark.parametrize("k", [1e-25, 1e-30])
def test_a_wear_rate_lost_in_round_off_is_refused_naming_the_key(k):
    # K = 5e-36 and 5e-41 1/Pa: each step's wear is below 1e-16 of the profile's
    # heights; the volume came out 0.52 and 0.012 of K F s before this check
    case = cases.load(BALL, ["mdr.elements=200", f"wear.k={k}"])
    with pytest.raises(SolverError, match=r"key 'wear.k' = 1e-(25|30):.*Archard"):
        mdr.solve(case)


def test_the_key_named_is_the_one_the_case_gave():
    case = cases.load(BALL, ["mdr.elements=200", "wear.specific_rate=5e-36"])
    assert case.derived and "wear.k" in case.derived
    with pytest.raises(SolverError, match=r"key 'wear.specific_rate' = 5e-36"):
        mdr.solve(case)
