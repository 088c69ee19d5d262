"""MDR gross-slip wear: limits, conservation, schemes, stability, convergence."""

import math

import numpy as np
import pytest

from wearcheck import cases
from wearcheck import mdr
from wearcheck.cases import profiles, programme, reference
from wearcheck.mdr import linalg, solver, wear
from wearcheck.numerics import stepping

R = 0.01
D = 1e-6


def make(N=200, s_hat=None, stages=(0.0,), domain_factor=1.3, control="depth",
         linear_solver="auto", **sliding):
    """A paraboloid case; s_hat: slide to that ŝ (else until the force fraction).

    Fixed-step implicit Euler unless ``scheme`` is given (these tests are about it).
    ``linear_solver="iterative"`` runs a small grid on the GMRES path of fine ones.
    """
    sliding.setdefault("scheme", "implicit")
    loading = dict(control="depth", depth=D) if control == "depth" else \
        dict(control="force", force=20.0)
    raw = dict(indenter=dict(profile="paraboloid", radius=R, youngs_modulus=210e9,
                             poisson_ratio=0.3),
               loading=loading,
               wear=dict(k=1e-4, mu=0.3, hardness=2e9,
                         tangential_correction=sliding.pop("tangential", False)),
               sliding=dict(until="force_fraction", **sliding),
               stages=dict(s_hat=list(stages)),
               mdr=dict(elements=int(N), domain_factor=domain_factor,
                        linear_solver=linear_solver))
    if control == "force":
        raw["sliding"]["until"] = "distance"
        raw["sliding"]["distance"] = 0.0
    case = cases.from_dict(raw)
    if s_hat is not None:
        per = reference.scales(case)["s_hat_per_m"]
        raw["sliding"].update(until="distance", distance=s_hat / per)
        raw["sliding"].pop("force_fraction", None)
        case = cases.from_dict(raw)
    return case


def run_with_control(case, control):
    """The MDR run of ``case`` (adaptive) with the step control given: the
    solver's own choice is the ladder for direct solves, continuous for
    iterative ones. Returns :func:`mdr.solver.run`'s dict."""
    model, sc = solver.build_model(case)
    plan, _ = programme.stepping_plan(case, math.inf, sc, control=control)
    return solver.run(model, plan,
                      profile=lambda x: profiles.height(case.indenter, x, case.table))


def force_at(res, s_hat):
    h = res.history
    return np.interp(s_hat, h["s_hat"], h["force"] / h["force"][0])


def test_complete_wear_at_fixed_depth():
    # docs/theory.md §6: the worn tip ends flush at depth d, F -> 0, a -> sqrt(2) a0
    case = make(N=200, force_fraction=1e-4, step_hat=0.5)
    res = mdr.solve(case)
    sc = reference.scales(case)
    h = res.history
    assert h["force"][-1] < 1e-4 * h["force"][0]
    # measured a = (1 - 1.5e-3) sqrt(2) a0 at F = 1e-4 F0 (the edge keeps
    # creeping out as the last load is worn away)
    assert h["contact_radius"][-1] == pytest.approx(math.sqrt(2) * sc["a0"], rel=3e-3)
    # depth control: a only grows (to round-off in locating g(a) = d late in
    # the run, when d - g is 1e-7 d across the contact)
    assert np.all(np.diff(h["contact_radius"]) >= -1e-6 * sc["a0"])
    last = make(N=200, force_fraction=1e-4, step_hat=0.5, stages=(0.0, h["s_hat"][-1]))
    f = mdr.solve(last).f[-1]
    # measured 5.6e-5 d from max(r²/2R, d) everywhere on the grid
    np.testing.assert_allclose(f, reference.complete_wear_profile(res.r, R, D), rtol=0,
                               atol=2e-4 * D)


def test_worn_volume_equals_wear_law_integral():
    # rigid slip: dV/ds = K ∫2πr p dr = K F. Implicit Euler adds K h p_{n+1}
    # per step, so V must equal K Σ h F_{n+1} up to how well the discrete
    # pressure integrates to the discrete force (Eq. 12): measured relative
    # gaps 4.5e-4 (N = 200), 1.6e-4 (N = 400), converging at order 1.5
    gaps = []
    for N in (200, 400):
        case = make(N=N, s_hat=4.0, step_hat=0.1)
        h = mdr.solve(case).history
        V_law = case.wear_rate * np.sum(np.diff(h["s"]) * h["force"][1:])
        gaps.append(abs(h["wear_volume"][-1] / V_law - 1))
    assert gaps[0] < 1e-3
    assert gaps[1] < gaps[0] / 2


def test_force_control_keeps_the_force():
    case = make(N=200, control="force", s_hat=3.0, step_hat=0.2)
    h = mdr.solve(case).history
    np.testing.assert_allclose(h["force"], 20.0, rtol=1e-9)
    # the worn indenter must be pressed deeper and its contact grows
    assert np.all(np.diff(h["depth"]) > 0) and h["contact_radius"][-1] > h["contact_radius"][0]
    # V = K F s for a constant force (same 1e-3 pressure-integration gap as above)
    assert h["wear_volume"][-1] == pytest.approx(case.wear_rate * 20.0 * h["s"][-1], rel=1e-3)


def test_stages_land_exactly_and_stop_by_force():
    case = make(N=100, step_hat=0.3, stages=(0.0, 0.45, 1.0, 50.0), force_fraction=0.5)
    res = mdr.solve(case)
    per = reference.scales(case)["s_hat_per_m"]
    # the stage at ŝ = 50 lies beyond F < 0.5 F0 and is not reached
    np.testing.assert_allclose(res.stage_s * per, [0.0, 0.45, 1.0], rtol=1e-12)
    F = res.history["force"]
    assert F[-1] < 0.5 * F[0] <= F[-2]
    assert res.f.shape == (3, len(res.r)) and res.p.shape == (3, len(res.r))
    np.testing.assert_array_equal(res.f[0], res.r**2 / (2 * R))


def test_zero_distance_gives_the_unworn_contact_only():
    res = mdr.solve(make(N=100, s_hat=0.0))
    assert len(res.history["s"]) == 1 and res.info["steps"] == 0


def test_explicit_and_implicit_converge_to_one_history():
    # same spatial discretisation, two first-order time schemes: their gap
    # must halve with the step (measured 4.6e-4, 2.4e-4, 1.2e-4 at N = 200)
    N = 100
    limit = solver.stability_limit_hat(*_model_and_scale(make(N=N)))
    s_eval = np.linspace(0.2, 2.0, 10)
    steps = limit / np.array([2.0, 4.0, 8.0])
    gaps = []
    for st in steps:
        e = mdr.solve(make(N=N, s_hat=2.0, scheme="explicit", step_hat=float(st)))
        i = mdr.solve(make(N=N, s_hat=2.0, scheme="implicit", step_hat=float(st)))
        gaps.append(np.max(np.abs(force_at(e, s_eval) - force_at(i, s_eval))))
    rate = np.polyfit(np.log(steps), np.log(gaps), 1)[0]
    assert 0.85 < rate < 1.15
    assert gaps[-1] < 5e-4


def _model_and_scale(case):
    model, sc = solver.build_model(case)
    return model, sc["s_hat_per_m"]


def test_explicit_step_past_the_limit_is_refused():
    case = make(N=100, s_hat=1.0, scheme="explicit")
    limit = solver.stability_limit_hat(*_model_and_scale(case))
    with pytest.raises(cases.CaseError, match=r"sliding\.step_hat.*largest stable step is"
                                              rf" {limit:.4g}"):
        mdr.solve(make(N=100, s_hat=1.0, scheme="explicit", step_hat=2.0 * limit))
    # "auto" is half the limit
    assert mdr.solve(case).info["step_hat"] == pytest.approx(0.5 * limit)


def test_grid_scale_oscillation_is_detected():
    # forced past the limit through the lower-level driver: the clipped edge
    # keeps the saw-tooth bounded, so the run finishes with a wrong force
    # unless the oscillation is caught
    N = 200
    model, per = _model_and_scale(make(N=N))
    limit = solver.stability_limit_hat(model, per) / per

    def plan(scheme, step):
        return stepping.Plan(scheme=scheme, step=step, end=3.0 / per, per_m=per)

    with pytest.raises(cases.SolverError, match="oscillation"):
        solver.run(model, plan("explicit", 3.0 * limit))
    wrong = solver.run(model, plan("explicit", 3.0 * limit), check_oscillation=False)
    right = solver.run(model, plan("implicit", 0.01 / per))   # time error ~7e-4
    F_wrong = wrong["history"]["force"][-1] / wrong["history"]["force"][0]
    F_right = right["history"]["force"][-1] / right["history"]["force"][0]
    # measured 0.228 against 0.279: an error 100 times the time error of a
    # stable step, with nothing non-finite to betray it
    assert abs(F_wrong - F_right) > 0.02
    # a stable explicit run is not flagged
    solver.run(model, plan("explicit", 0.5 * limit))


def test_observed_order_in_N():
    # one step size for every grid, so the differences between grids are
    # spatial; measured successive differences 3.5e-4, 1.2e-4, 4.1e-5 of F0
    # (order 1.55) for the paraboloid at N = 100..800
    Ns = np.array([100, 200, 400, 800])
    s_eval = np.linspace(0.2, 4.0, 20)
    F = [force_at(mdr.solve(make(N=N, s_hat=4.0, step_hat=0.2, domain_factor=1.25)), s_eval)
         for N in Ns]
    diffs = [np.max(np.abs(a - b)) for a, b in zip(F, F[1:])]
    rate = -np.polyfit(np.log(Ns[:-1]), np.log(diffs), 1)[0]
    assert 1.3 < rate < 2.2
    assert diffs[-1] < 1e-4


def u_star_of(case):
    """Cattaneo–Mindlin's gross-slip displacement of the unworn contact, μE*d0/G*."""
    return case.wear.mu * case.E_star * reference.scales(case)["d0"] / case.G_star


def test_tangential_correction_slip_is_the_springs_reversal():
    # docs/theory.md §4: a spring reverses ±μq/G* at each stroke end, so of a
    # stroke ℓ it slides ℓ - 2μq/G*; Eq. 16 of the Hertz line load
    # E*(d - x²/R) is E*(d - r²/2R), so S(r) = 1 - 2u*(1 - r²/(2Rd))/ℓ on the
    # contact, u* = μE*d/G*. The line load is linear in t on every segment
    # inside the contact and T⁻¹ is causal and exact there: round-off (1e-12)
    case = make(N=200)
    u_star = u_star_of(case)
    stroke = 20.0 * u_star
    corrected = make(N=200, tangential=True, stroke=stroke)
    model, sc = solver.build_model(corrected)
    state = wear.contact_state(model, model.f0.copy())
    inside = model.x < sc["a0"] * (1 - 1e-9)
    r = model.x[inside][:-1]          # the last node's segment holds the edge's kink
    S = 1.0 - 2.0 * u_star * (1.0 - r**2 / (2.0 * R * D)) / stroke
    np.testing.assert_allclose(state.slip[:len(r)], S, rtol=0, atol=1e-12)
    # without the key there is no factor (S = 1, a scalar in the implicit step)
    plain, _ = solver.build_model(case)
    assert wear.contact_state(plain, plain.f0.copy()).slip is None


@pytest.mark.parametrize("ratio", [5.0, 20.0])
def test_tangential_correction_slows_the_wear_by_the_closed_form(ratio):
    # dV/ds = K ∫ p S dA; with Hertz's p and S above, ∫ p (d - r²/2R) dA =
    # (4/5) d F, so the initial volume rate is K F (1 - (8/5) u*/ℓ): 0.32 and
    # 0.08 slower at ℓ = 5u*, 20u*. Measured over ŝ = 0.001 as the ratio to
    # the run without the correction, which cancels most of the grid's error
    # of the volume rate. Tolerance 1e-3 of the correction: the wear moves the
    # ratio by 0.37 ŝ of the correction (measured at ŝ = 0.0025 and 0.01, at
    # N = 100-800), the grid by -7e-4 (N = 100), -3e-4 (200), 0 (800)
    case = make(N=200)
    u_star = u_star_of(case)
    stroke = ratio * u_star
    runs = [mdr.solve(make(N=200, s_hat=0.001, step_hat=0.00025, tangential=t, stroke=stroke))
            for t in (False, True)]
    V_plain, V_corr = (r.history["wear_volume"][-1] for r in runs)
    expected = 1.0 - 1.6 * u_star / stroke
    assert V_corr / V_plain == pytest.approx(expected, abs=1e-3 * (1.0 - expected))


def test_tangential_correction_needs_a_stroke_longer_than_the_reversal():
    u_star = u_star_of(make(N=50))
    # a case file of the earlier reading (no stroke) is told what to do
    with pytest.raises(cases.CaseError, match=r"missing key 'sliding\.stroke', required by "
                                                    r"wear\.tangential_correction = true"):
        make(N=50, tangential=True)
    # a stroke within 2u* is partial slip: the fretting solver's case
    with pytest.raises(cases.CaseError, match=r"sliding\.stroke.*partial slip.*\[fretting\]"):
        make(N=50, tangential=True, stroke=1.99 * u_star)
    make(N=50, tangential=True, stroke=2.01 * u_star)


def test_runaway_guard():
    # the plan's step cap stops an MDR run that would pass it (ten steps
    # asked, five allowed)
    model, per = _model_and_scale(make(N=50))
    plan = stepping.Plan(scheme="implicit", step=0.1 / per, end=1.0 / per, per_m=per,
                         max_steps=5)
    with pytest.raises(cases.SolverError, match="more than 5 steps"):
        solver.run(model, plan)


def test_matrix_free_path_solves_the_same_equations():
    # grids above DENSE_MAX use FFT operators, GMRES and a coarse-grid
    # preconditioner instead of the nested LU: the same discrete equations,
    # so the histories agree to the GMRES tolerance (rtol 1e-9; measured 3e-10
    # in F, 1e-8 of the peak in p)
    dense, free = ([mdr.solve(make(N=300, s_hat=2.0, step_hat=0.15, control=c,
                                   stages=(0.0, 1.0), linear_solver=solver_))
                    for c in ("depth", "force")] for solver_ in ("direct", "iterative"))
    for a, b in zip(dense, free):
        assert b.info["gmres_iterations"] > 0
        for key in ("force", "depth", "contact_radius", "wear_volume"):
            np.testing.assert_allclose(b.history[key], a.history[key], rtol=1e-7)
        np.testing.assert_allclose(b.p, a.p, rtol=0, atol=1e-7 * np.max(a.p))


def test_the_solve_settings_are_validated_case_keys():
    # mdr.linear_solver and mdr.krylov_precision: a value outside the choices
    # is refused naming the key, the value and what is allowed; a direct solve
    # above the "auto" limit is costed as the dense factorisations it makes
    # (at least one of (N+1)² doubles), so the memory guard sees it
    paper = cases.shipped("paper")
    for key, bad, allowed in (("mdr.linear_solver", "gmres", '"auto", "direct", "iterative"'),
                              ("mdr.krylov_precision", "float16", '"float32", "float64"')):
        with pytest.raises(cases.CaseError) as err:
            cases.load(paper, [f"{key}={bad}"])
        assert str(err.value) == f"key '{key}' = \"{bad}\": must be one of {allowed}"
    from wearcheck.mdr.resources import memory_bytes
    auto, direct = (cases.load(paper, ["mdr.elements=4096", f"mdr.linear_solver={s}"])
                    for s in ("auto", "direct"))
    assert memory_bytes(direct) - memory_bytes(auto) >= 8.0 * 4097**2


def test_adaptive_iterative_solves_keep_to_a_share_of_the_tolerance(monkeypatch):
    # an adaptive run solves GMRES to ADAPTIVE_SOLVE_SHARE of its tolerance
    # (1e-7 at 1e-4), not to 1e-9: over the steps both paths take alike, the
    # iterative history stays within 1e-2 of the tolerance of the direct one,
    # the budget a solve may take from the time error (measured 2e-8 in F/F0
    # and 1e-7 of the depth in the wear at the centre; with the 1e-7 cap
    # lifted, a share of 1e-2 fails on the central wear, 1.2 times the bound,
    # and 1e-1 parts the steps early)
    tol = 1e-4
    runs = {}
    used = []
    gmres = linalg.gmres

    def spy(*args, rtol, **kwargs):
        used.append(rtol)
        return gmres(*args, rtol=rtol, **kwargs)

    monkeypatch.setattr(linalg, "gmres", spy)
    for path in ("direct", "iterative"):
        # the ladder's steps on both paths (iterative ones otherwise set them
        # continuously), so that the histories can be compared
        runs[path] = [run_with_control(make(N=300, s_hat=2.0, scheme="adaptive", tolerance=tol,
                                            control=c, stages=(0.0, 1.0), linear_solver=path),
                                       "ladder")
                      for c in ("depth", "force")]
    # the share reaches every iterative solve of the adaptive runs; a fixed-step
    # run keeps the accurate solves
    assert used and np.allclose(used, solver.ADAPTIVE_SOLVE_SHARE * tol, rtol=1e-12, atol=0)
    used.clear()
    mdr.solve(make(N=300, s_hat=0.5, step_hat=0.15))
    assert used and set(used) == {wear.ACCURATE_RTOL}
    for a, b in zip(runs["direct"], runs["iterative"]):
        assert b["counters"]["gmres_iterations"] > 10 * a["counters"]["gmres_iterations"]
        ha, hb = a["history"], b["history"]
        k = 0
        while k < min(len(ha["s"]), len(hb["s"])) and ha["s"][k] == hb["s"][k]:
            k += 1
        assert k > 0.8 * len(ha["s"])      # the same steps, all but a few at the end
        scale = np.max(np.abs(ha["depth"]))
        assert np.max(np.abs(hb["force"][:k] - ha["force"][:k])) <= 1e-2 * tol * ha["force"][0]
        for key in ("depth", "wear_center"):
            assert np.max(np.abs(hb[key][:k] - ha[key][:k])) <= 1e-2 * tol * scale


def test_explicit_force_control_keeps_the_force():
    case = make(N=100, control="force", s_hat=1.0, scheme="explicit")
    h = mdr.solve(case).history
    # the depth for a force is found exactly from the piecewise-linear discrete Eq. 12
    np.testing.assert_allclose(h["force"], 20.0, rtol=1e-12)
    assert np.all(np.diff(h["depth"]) > 0)


def test_progress_is_reported():
    calls = []
    mdr.solve(make(N=100, step_hat=0.2), progress=lambda f, text="": calls.append(f))
    assert calls and calls[-1] == 1.0
    assert all(0.0 <= f <= 1.0 for f in calls) and calls == sorted(calls)


@pytest.mark.parametrize("direct", [True, False])
def test_implicit_step_state_satisfies_its_contact_problem(direct):
    # one backward-Euler step from a worn start, solved directly (nested LU,
    # bordered as the contact grows) or by GMRES (the coarse-grid path, forced
    # on this small grid): the state must solve T⁻¹[q/E*] + σ p = d − f_n on
    # the contact (checked with the transforms themselves, not the solver's
    # matrix), its line load must be P⁻¹ p and its force Eq. 12 of that line
    # load
    from wearcheck.mdr import transforms
    case = make(N=400, linear_solver="direct" if direct else "iterative")
    model, sc = solver.build_model(case)
    st = wear.contact_state(model, model.f0.copy())
    h = 0.3 / sc["s_hat_per_m"]
    st = wear.implicit_step(model, st, h)                  # a worn start
    system = wear.ImplicitSystem(model, h, nodes=st.m // 2)   # grows by bordering
    assert not direct or system.lu.n < st.m
    assert system.nested == direct
    new = wear.implicit_step(model, st, h, system=system)
    n = new.m + 1
    p = new.p[:n]
    sigma = h * model.wear_rate
    lhs = transforms.from_1d_exact(transforms.line_load(p, model.dt)) / model.E_star + sigma * p
    # the solve's tolerance: round-off of a direct solve, GMRES's 1e-9 residual
    np.testing.assert_allclose(lhs, new.depth - st.f[:n], rtol=0,
                               atol=(1e-12 if direct else 1e-8) * new.depth)
    q = np.maximum(transforms.line_load(p, model.dt), 0.0)
    # the line load of the recorded state to 1e-9 of its largest value (a
    # direct solve's two routes differ by round-off, measured 1e-12)
    np.testing.assert_allclose(new.q[:n], q, rtol=0, atol=1e-9 * q.max())
    assert new.force == pytest.approx(transforms.force(np.r_[q, np.zeros(len(new.q) - n)],
                                                       model.dt), rel=1e-9)
    # nothing penetrates outside the contact, no tension inside
    g = transforms.to_1d(new.f)
    assert np.all(new.depth - g[n:] <= wear.EDGE_TOL * new.depth)
    assert q[-1] >= 0.0


def test_a_run_that_reaches_no_stage_keeps_its_grid():
    # every stage past the end of the run: no stage rows, but the arrays keep
    # the shape (stages x nodes) every result has, on the run's grid
    case = make(N=200, s_hat=0.5, stages=(20.0, 30.0), step_hat=0.1)
    res = mdr.solve(case)
    assert len(res.stage_s) == 0
    assert res.f.shape == res.p.shape == (0, len(res.r)) and len(res.r) == 201


def test_far_bound_holds_against_the_transform():
    # the bound on the 1D transform of a change confined to nodes 0..M-1, at
    # every node from M on, against the transform itself (FFT) and a direct sum
    # of the paper's Eq. 2 discretisation written out here: wear-like bumps,
    # signed noise and a step (the worst case of the summation by parts)
    from wearcheck.mdr import transforms
    rng = np.random.default_rng(7)
    N1 = 3001
    j = np.arange(N1)
    c = np.sqrt(j + 1.0) - np.sqrt(j)

    def eq2_at(delta, i):       # g_i = Δ_0 + 2 sqrt(i) Σ_{j<i} c[i-1-j] (Δ_{j+1} - Δ_j)
        return delta[0] + 2 * np.sqrt(i) * (c[i - 1::-1] @ np.diff(delta[:i + 1]))

    for M in (1, 2, 41, 1000, 2250, 3000):
        bumps = [np.where(j < M, np.cos(0.5 * np.pi * j / M), 0.0),
                 np.where(j < M, rng.standard_normal(N1), 0.0),
                 np.where(j < M, 1.0, 0.0),
                 np.where(j < M, rng.random(N1) * j, 0.0)]
        for delta in bumps:
            bound = transforms.far_bound(delta[:M])
            exact = np.abs(transforms.to_1d(delta)[M:])
            # (the FFT's round-off: 1e-13 of the change)
            assert np.all(exact <= bound * (1 + 1e-12) + 1e-13 * np.max(np.abs(delta))), M
            for i in {M, min(M + 1, N1 - 1), (M + N1) // 2, N1 - 1}:
                if i >= M:
                    assert abs(eq2_at(delta, i)) <= bound * (1 + 1e-12) + 1e-300, (M, i)
        # one-signed: the bound is the transform at node M itself but for Δ_0's
        # weight (taken about twice its own: a share ~1/M of the bound)
        if M < N1:
            assert bound == pytest.approx(abs(transforms.to_1d(bumps[3])[M]), rel=1e-3)


def test_far_bound_weights_decrease_away_from_the_change():
    # the bound rests on every weight of the summation by parts decreasing with
    # the node i: w_0(i) - 1 = c[i-1]² and a_k(i) = 2 sqrt(i) (c[i-1-k] - c[i-k])
    # (docs/performance.md proves it; here on i up to 20000 and a few k, c from
    # its definition sqrt(k+1) - sqrt(k) in long double where available)
    i = np.arange(1, 20001, dtype=np.longdouble)
    c = np.sqrt(np.arange(20002, dtype=np.longdouble) + 1) - np.sqrt(np.arange(20002,
                                                                          dtype=np.longdouble))
    w0 = 2 * np.sqrt(i) * c[:20000] - 1
    assert np.all(np.diff(w0) < 0) and np.all(w0 > 0)
    # and Δ_0's weight in the bound, a_0(M) = 2 sqrt(M) (c[M-1] - c[M]), covers c[M-1]²
    a0 = 2 * np.sqrt(i) * (c[:20000] - c[1:20001])
    assert np.all(a0 >= c[:20000] ** 2)
    for k in (0, 1, 2, 5, 100, 5000):
        ii = np.arange(k + 1, 20001)
        a = 2 * np.sqrt(ii.astype(np.longdouble)) * (c[ii - 1 - k] - c[ii - k])
        assert np.all(np.diff(a) < 0) and np.all(a > 0), k


def test_to_1d_rows_are_the_transform_on_those_nodes():
    # direct sums on a few nodes against the FFT transform of the whole profile
    from wearcheck.mdr import transforms
    rng = np.random.default_rng(3)
    for N1 in (2, 3, 65, 801, 3001):
        f = np.cumsum(rng.standard_normal(N1))
        g = transforms.to_1d(f)
        for first, stop in ((0, N1), (max(N1 - 9, 0), N1), (0, 1),
                            (N1 // 2, min(N1, N1 // 2 + 9))):
            # (the FFT's round-off, 1e-15 of the largest value, and the sums')
            np.testing.assert_allclose(transforms.to_1d_rows(f, first, stop), g[first:stop],
                                       rtol=0, atol=1e-14 * np.max(np.abs(g)))


def test_pressure_force_weights_are_eq12_of_the_line_load():
    # Δt v·p against the force of the line load of p (Eq. 12 of P⁻¹ p), p >= 0
    from wearcheck.mdr import transforms
    rng = np.random.default_rng(5)
    for N in (10, 800, 3000):
        for k in (1, 2, N // 2, N - 1):
            p = rng.random(k)
            q = np.zeros(N + 1)
            q[:k] = transforms.line_load(p, 0.37)
            assert q.min() >= 0.0
            # (two roundings of one sum: 1e-14)
            assert 0.37 * (transforms.pressure_force_weights(N)[:k] @ p) == \
                pytest.approx(transforms.force(q, 0.37), rel=1e-14)


def test_far_gap_sees_a_penetration_beyond_its_window():
    # a reference profile, then a change near the centre large enough to
    # bring the whole grid below the depth: the bound cannot clear it, so the
    # check falls back to the full transform, which finds the nodes
    from wearcheck.mdr import transforms
    N1 = 2001
    f_ref = np.linspace(0, 1, N1)       # a paraboloid: linear in t
    far = wear.FarGap()
    g_ref = far.full(f_ref)             # 2 f_ref
    d = g_ref[600]                      # in contact up to node 600
    f = f_ref.copy()
    f[:300] += 10.0                      # a worn cap: pulls g down beyond it
    assert not far.clears(f, 800, d, 1e-9)
    assert np.any(d - transforms.to_1d(f)[800:] > 1e-9 * d)
    # the check falls back to the whole transform and finds the last such node
    below, _ = far.check(f, 601, d, 1e-9)
    g = transforms.to_1d(f)
    assert 601 + below[-1] == np.flatnonzero(d - g > 1e-9 * d)[-1]
    assert np.array_equal(far.reference[0], f)      # (its reference now)
    # a small change leaves the nodes beyond the window clear without a transform
    far.full(f_ref)
    f = f_ref.copy()
    f[:300] += 1e-4 * np.cos(np.linspace(0, 0.5 * np.pi, 300))
    assert far.clears(f, 800, d, 1e-9)
    assert not np.any(d - transforms.to_1d(f)[800:] > 1e-9 * d)
    # and a change beyond the window is never cleared by the bound
    f = f_ref.copy()
    f[900] += 1e-12
    assert not far.clears(f, 800, d, 1e-9)


@pytest.mark.parametrize("linear_solver", ["direct", "iterative"])
def test_far_gap_leaves_the_steps_unchanged(monkeypatch, linear_solver):
    # the contact check sums the 1D profile on a window at the contact edge and
    # clears the nodes beyond by a bound against a reference: the same contact
    # sets as the full transform of every contact iteration, so the same steps
    # to round-off, with the full transform done a few times per run instead of
    # once per contact iteration. Here 30 backward-Euler steps, with the check
    # and with the bound made to fail always (the full transform each time), by
    # depth and by force; every state also checked against the transform itself
    from wearcheck.mdr import transforms
    full = []
    original, clears = wear.FarGap.full, wear.FarGap.clears

    def spy(self, f):
        full.append(1)
        return original(self, f)

    monkeypatch.setattr(wear.FarGap, "full", spy)
    iterations = 0
    for control in ("depth", "force"):
        model, sc = solver.build_model(make(N=300, control=control, linear_solver=linear_solver))
        h = 0.1 / sc["s_hat_per_m"]
        system = wear.ImplicitSystem(model, h)
        runs = []
        for bound in (True, False):
            monkeypatch.setattr(wear.FarGap, "clears",
                                clears if bound else (lambda *args: False))
            del full[:]
            st = wear.contact_state(model, model.f0.copy())
            steps = []
            for _ in range(30):
                st = wear.implicit_step(model, st, h, system=system)
                steps.append((st.m, st.stats["contact_iterations"], st.force, st.depth, st.f[0],
                              st.contact_radius))
                g = transforms.to_1d(st.f)
                assert np.all(st.depth - g[st.m + 1:] <= wear.EDGE_TOL * st.depth)
            runs.append(np.array(steps))
            if bound:
                iterations += runs[-1][:, 1].sum()
                assert len(full) < 0.1 * runs[-1][:, 1].sum()
        with_check, without = runs
        np.testing.assert_array_equal(with_check[:, :2], without[:, :2])
        # round-off: the window's direct sums against the FFT
        np.testing.assert_allclose(with_check[:, 2:], without[:, 2:], rtol=1e-12, atol=0)
    assert iterations > 60


def test_coarse_solve_through_eigenvectors_is_the_shifted_solve():
    # the preconditioner's coarse solve for any contact set and step size,
    # through the unit matrix's eigenvectors, against np.linalg.solve of the
    # assembled coarse matrix (scaled by sqrt(n Δt / nc)/E*, shifted by σ)
    from wearcheck.mdr import transforms
    case = make(N=400)
    model, sc = solver.build_model(case)
    system = wear.ImplicitSystem.__new__(wear.ImplicitSystem)
    system.dt, system.E = model.dt, model.E_star
    nc = system.nc = wear.COARSE_NODES
    system._eigen = wear.coarse_eigen(nc)
    rng = np.random.default_rng(1)
    for n, h_hat in ((3000, 2.0 ** -7), (50000, 0.25), (700, 1.0)):
        sigma = h_hat / sc["s_hat_per_m"] * model.wear_rate
        A = transforms.compliance_matrix(nc, n * model.dt / nc, model.E_star)
        A[np.diag_indices(nc)] += sigma
        rc = rng.standard_normal(nc)
        e = system._coarse_solve(rc, n, sigma)
        assert np.linalg.norm(A @ e - rc) <= 1e-12 * np.linalg.norm(rc)


@pytest.mark.parametrize("n", [30, 47, 48, 49, 257, 5000])
def test_restriction_is_the_interpolation_transposed(n):
    # the preconditioner's restriction by segment sums (or bincounts where a
    # coarse cell is empty, n < nc) against the sparse transpose of its
    # interpolation matrix, and that matrix against np.interp (nc = 48)
    wear._TRANSFERS.clear()
    system = wear.ImplicitSystem.__new__(wear.ImplicitSystem)
    system.nc = 48
    j, w0, w1, P, starts = system._transfer(n)
    rng = np.random.default_rng(n)
    r = rng.standard_normal(n)
    ref = (P.T @ r)[:48]
    assert np.allclose(system._restrict(r), ref, rtol=0, atol=1e-13 * np.abs(r).sum())
    e = rng.standard_normal(49)
    # (the fine nodes' coarse coordinates round alike to 1e-16)
    assert np.allclose(P @ e, np.interp(np.arange(n) * (48 / n), np.arange(49.0), e),
                       rtol=0, atol=1e-13 * np.max(np.abs(e)))
