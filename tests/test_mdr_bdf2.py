"""MDR wear with the variable-step BDF2: order, agreement, conservation, BLAS threads."""

import numpy as np
import pytest
import threadpoolctl

from wearcheck import mdr
from wearcheck.mdr import solver
from wearcheck.numerics import stepping
from test_mdr_wear import make, u_star_of

# points away from the start: the run begins at a Hertz contact whose
# pressure has a square-root edge, and there the wear history is not smooth
# (measured: at ŝ = 0.05-0.15 the BDF2 error only halves with the step, at N
# = 400 and 1600 alike); it decays within a few tenths of ŝ
S_EVAL = np.array([0.4, 0.8, 1.2, 1.6, 2.0])


def force_at(res, s_hat):
    h = res.history
    return np.interp(s_hat, h["s_hat"], h["force"] / h["force"][0])


def reference(N, s_eval, s_hat=2.0):
    """F/F0 free of time error to ~1e-7: Richardson on BDF2 at Δŝ = 1/160, 1/320.

    Interpolating these fine histories costs < h²/8 |F''| ≈ 4e-7 at points
    that are not their nodes.
    """
    a, b = (mdr.solve(make(N=N, s_hat=s_hat, scheme="bdf2", step_hat=st))
            for st in (0.00625, 0.003125))
    return lambda s: (4.0 * force_at(b, s) - force_at(a, s)) / 3.0


def bdf2_textbook(h, h_prev):
    """(a, b, c) of the variable-step BDF2 written out here, independent of the stepper."""
    w = h / h_prev
    return (1 + w) ** 2 / (1 + 2 * w), -w ** 2 / (1 + 2 * w), (1 + w) / (1 + 2 * w)


def test_bdf2_is_second_order_and_implicit_first_order():
    # constant steps on one grid (N = 400), so the differences are temporal;
    # measured errors of BDF2 6.6e-4, 1.8e-4, 4.0e-5, 9.0e-6 (order 2.07),
    # of implicit Euler 1.45e-2 ... 1.9e-3 (order 0.98). At coarser grids
    # (N = 100, 200) the contact edge crossing nodes makes the semi-discrete
    # history non-smooth at the 2e-5 level and the fitted BDF2 order drops
    # to 1.4-1.7, hence N = 400
    N = 400
    ref = reference(N, S_EVAL)(S_EVAL)
    steps = np.array([0.2, 0.1, 0.05, 0.025])
    errs = {}
    for scheme in ("bdf2", "implicit"):
        errs[scheme] = np.array([
            np.max(np.abs(force_at(mdr.solve(make(N=N, s_hat=2.0, scheme=scheme,
                                                   step_hat=float(st))), S_EVAL) - ref))
            for st in steps])
    order = {k: np.polyfit(np.log(steps), np.log(e), 1)[0] for k, e in errs.items()}
    assert 1.8 < order["bdf2"] < 2.4
    assert 0.9 < order["implicit"] < 1.1
    # both converge to the same history: BDF2's error at the finest step is
    # below the spatial error at N = 400 (~1e-4, test_mdr_wear), and
    # implicit Euler's own Richardson extrapolation 2F(Δ/2) - F(Δ) lands on
    # the BDF2 reference (measured 1.1e-5 at Δŝ = 0.025)
    assert errs["bdf2"][-1] < 2e-5
    imp = [force_at(mdr.solve(make(N=N, s_hat=2.0, scheme="implicit", step_hat=st)), S_EVAL)
           for st in (0.025, 0.0125)]
    assert np.max(np.abs(2.0 * imp[1] - imp[0] - ref)) < 3e-5


def test_variable_steps_keep_second_order():
    # stages at ŝ = Δŝ (1.5 + 2.5 j) force a repeating pattern of landing
    # steps (ratios 0.5 ... 2, equal halves onto a stage) that scales with
    # the step, so a wrong step-ratio formula would show as first order.
    # Measured at N = 800: errors 4.7e-4, 1.36e-4, 3.8e-5 (ratios 3.45, 3.59;
    # implicit Euler on the same pattern: 1.95, 1.98). Errors at every history
    # point from ŝ = 0.4 (see S_EVAL) against the constant-step reference
    N = 800
    ref = reference(N, None)
    steps = np.array([0.2, 0.1, 0.05])
    errs = {"bdf2": [], "implicit": []}
    for scheme in errs:
        for st in steps:
            stages = (0.0,) + tuple(st * (1.5 + 2.5 * j) for j in range(int(2.0 / st))
                                    if st * (1.5 + 2.5 * j) < 2.0)
            res = mdr.solve(make(N=N, s_hat=2.0, scheme=scheme, step_hat=float(st),
                                 stages=stages))
            assert len(res.stage_s) == len(stages)
            s = res.history["s_hat"]
            s = s[s >= 0.4 - 1e-9]
            errs[scheme].append(np.max(np.abs(force_at(res, s) - ref(s))))
            if scheme == "bdf2":
                d = np.diff(res.history["s_hat"])
                assert np.max(d[1:] / d[:-1]) <= stepping.BDF2_MAX_RATIO * (1 + 1e-9)
    ratios = {k: np.array(e[:-1]) / np.array(e[1:]) for k, e in errs.items()}
    assert np.all(ratios["bdf2"] > 3.0)          # second order: 4; first: 2
    assert np.all(ratios["implicit"] < 2.3)


def test_short_stage_step_grows_back_gradually():
    # a stage 4e-4 after another makes a sliver step; the next steps grow by
    # at most BDF2_MAX_RATIO (variable-step BDF2 is zero-stable below 1 + √2)
    # and the result stays as accurate as without the stages (measured error
    # 1.6e-4 against 1.8e-4 at Δŝ = 0.1: the extra short steps only help)
    N, st = 400, 0.1
    ref = reference(N, S_EVAL)(S_EVAL)
    plain = mdr.solve(make(N=N, s_hat=2.0, scheme="bdf2", step_hat=st))
    staged = mdr.solve(make(N=N, s_hat=2.0, scheme="bdf2", step_hat=st,
                            stages=(0.0, 0.5, 0.5004)))
    d = np.diff(staged.history["s_hat"])
    assert np.min(d) < 1e-3 and np.max(d[1:] / d[:-1]) <= 2.0 * (1 + 1e-9)
    e_plain = np.max(np.abs(force_at(plain, S_EVAL) - ref))
    e_staged = np.max(np.abs(force_at(staged, S_EVAL) - ref))
    assert e_staged < 1.5 * e_plain


def test_bdf2_worn_volume_follows_the_wear_law():
    # rigid slip: dV/ds = K ∫2πr p dr = K F. Each BDF2 step sets
    # V_{n+1} = a V_n + b V_{n-1} + c h K vol(p_{n+1}) (the volume is linear
    # in the profile, a + b = 1 cancels the unworn one), so V must equal this
    # recursion driven by K F_{n+1} up to how well the discrete pressure
    # integrates to the discrete force, a spatial gap converging at order 1.5
    # as for implicit Euler (test_mdr_wear); measured here as the largest
    # over the history: 6.7e-4 at N = 200, 2.4e-4 at N = 400
    gaps = []
    for N in (200, 400):
        case = make(N=N, s_hat=4.0, scheme="bdf2", step_hat=0.1, stages=(0.0, 0.55, 1.3))
        h = mdr.solve(case).history
        s, F = h["s"], h["force"]
        V = np.zeros_like(s)
        for n in range(len(s) - 1):
            hn = s[n + 1] - s[n]
            # the first step is backward Euler
            a, b, c = (1.0, 0.0, 1.0) if n == 0 else bdf2_textbook(hn, s[n] - s[n - 1])
            V[n + 1] = a * V[n] + (b * V[n - 1] if n else 0.0) + c * hn * case.wear_rate * F[n + 1]
        gaps.append(np.max(np.abs(h["wear_volume"][1:] / V[1:] - 1)))
    assert gaps[0] < 1e-3
    assert gaps[1] < gaps[0] / 2


def test_bdf2_force_control():
    case = make(N=200, control="force", s_hat=3.0, scheme="bdf2", step_hat=0.2)
    h = mdr.solve(case).history
    np.testing.assert_allclose(h["force"], 20.0, rtol=1e-9)
    assert np.all(np.diff(h["depth"]) > 0)
    # BDF2 integrates V' = K F (constant) exactly, so V = K F s up to the
    # same 1e-3 pressure-integration gap as implicit Euler (test_mdr_wear)
    assert h["wear_volume"][-1] == pytest.approx(case.wear_rate * 20.0 * h["s"][-1], rel=1e-3)


def test_bdf2_matrix_free_path_solves_the_same_equations():
    # the first and stage-landing BDF2 steps have another wear compliance
    # than the regular one: GMRES preconditioned by the regular factors on
    # the dense path, the coarse grid on the matrix-free one. Same discrete
    # equations, so the histories agree to the GMRES tolerance (as for
    # implicit Euler in test_mdr_wear)
    dense, free = ([mdr.solve(make(N=300, s_hat=2.0, step_hat=0.15, scheme="bdf2", control=c,
                                   stages=(0.0, 1.0), linear_solver=solver_))
                    for c in ("depth", "force")] for solver_ in ("direct", "iterative"))
    for a, b in zip(dense, free):
        for key in ("force", "depth", "contact_radius", "wear_volume"):
            np.testing.assert_allclose(b.history[key], a.history[key], rtol=1e-7)
        np.testing.assert_allclose(b.p, a.p, rtol=0, atol=1e-7 * np.max(a.p))


def test_auto_step_and_tangential_correction():
    res = mdr.solve(make(N=100, s_hat=1.0, scheme="bdf2"))
    assert res.info["step_hat"] == solver.BDF2_STEP_HAT and res.info["scheme"] == "bdf2"
    # the tangential correction's slip factor S is the end state's, as the
    # rest of the wear rate: against a run at 1/8 of the step, BDF2 at
    # Δŝ = 0.1 is as accurate with it as without (ℓ = 5u*, where S is 0.68
    # at the centre; measured 1.9e-4 in F/F0 with, 2.8e-4 without; the start
    # state's S, lagged by one step, made it first order: 3.5e-3 at N = 200)
    u_star = u_star_of(make(N=50))
    err = {}
    for corrected in (False, True):
        kw = dict(N=100, s_hat=2.0, scheme="bdf2", tangential=corrected, stroke=5.0 * u_star)
        fine, coarse = (mdr.solve(make(step_hat=h, **kw)) for h in (0.0125, 0.1))
        F = coarse.history["force"] / coarse.history["force"][0]
        F_fine = np.interp(coarse.history["s_hat"], fine.history["s_hat"],
                           fine.history["force"] / fine.history["force"][0])
        err[corrected] = np.max(np.abs(F - F_fine))
    assert err[True] < 1.5 * err[False]


def test_blas_is_single_threaded_during_the_solve_only():
    def blas_threads():
        return [i["num_threads"] for i in threadpoolctl.threadpool_info()
                if i["user_api"] == "blas"]

    before = blas_threads()
    seen = []
    mdr.solve(make(N=100, s_hat=0.5, scheme="bdf2", step_hat=0.1),
              progress=lambda f, text="": seen.append(blas_threads()))
    assert seen and all(all(n == 1 for n in threads) for threads in seen)
    assert blas_threads() == before
