"""Refinement studies: observed order on problems of known order, a study end
to end through a LocalCluster on loopback, failed levels kept in the table."""

from __future__ import annotations

import csv
import json
import sys
import math

import cloudpickle
import numpy as np
import pytest

from wearcheck import cases
from wearcheck.cases import reference
from wearcheck.comparisons.analysis import convergence as rf
from wearcheck.rundir import Run

# the stand-in solvers below travel to the Dask workers by value, so the
# workers need not import this test module
cloudpickle.register_pickle_by_value(sys.modules[__name__])

# ----------------------------------------------------------------------------
# The pure part against problems of known order


def test_observed_order_of_a_power_law_is_exact():
    # e = C h^p is a straight line in log-log: the fit recovers p and C to rounding
    h = np.array([0.1, 0.05, 0.025, 0.0125])
    p, c = rf.observed_order(h, 3.7 * h**1.5)
    assert p == pytest.approx(1.5, abs=1e-12)
    assert c == pytest.approx(3.7, rel=1e-10)


def trapezoid(n):
    """Composite trapezoid rule for ∫_0^1 e^x dx with n panels (error ∝ h² exactly
    to leading order, Euler-Maclaurin: -(h²/12)(e-1) + O(h⁴))."""
    x = np.linspace(0.0, 1.0, n + 1)
    y = np.exp(x)
    return (y.sum() - 0.5 * (y[0] + y[-1])) / n


def test_observed_order_of_the_trapezoid_rule_is_two():
    n = np.array([4, 8, 16, 32, 64])
    err = np.abs([trapezoid(k) - (math.e - 1) for k in n])
    p, _ = rf.observed_order(1.0 / n, err)
    # the O(h⁴) term shifts the slope by ~h²/60 relative at n = 4: well below 0.01
    assert p == pytest.approx(2.0, abs=0.01)


def test_richardson_on_the_trapezoid_rule():
    n = np.array([8, 16, 32])
    p, q = rf.richardson(1.0 / n, [trapezoid(k) for k in n])
    assert p == pytest.approx(2.0, abs=0.01)  # the h⁴ term perturbs p by O(h²)
    # one Richardson step removes the h² term; what is left is O(h⁴) ≈ 1e-7 at n = 16
    assert q == pytest.approx(math.e - 1, abs=1e-6)


def test_richardson_with_unequal_ratios_is_exact_for_a_power_law():
    # the FEM default levels are not in a constant ratio (60, 125, 250)
    h = 1.0 / np.array([60.0, 125.0, 250.0])
    p, q = rf.richardson(h, 0.7 + 2.3 * h**1.3)
    assert p == pytest.approx(1.3, abs=1e-9)
    assert q == pytest.approx(0.7, abs=1e-12)


def test_richardson_refuses_oscillating_values():
    # the premise q = q* + C h^p fails when the differences change sign
    p, q = rf.richardson([0.4, 0.2, 0.1], [1.0, 0.9, 0.95])
    assert math.isnan(p) and math.isnan(q)


def test_differences_interpolate_onto_the_finest_grid():
    # level: f = 1 + r on a coarse grid; finest: f = 1 + r + 0.1 sin(πr) on a fine
    # grid; linear interpolation of the level is exact, so the difference is 0.1
    coarse, fine = np.linspace(0, 2, 5), np.linspace(0, 2, 401)
    s = np.linspace(0, 1, 11)

    def sol(r, extra, force):
        f = (1 + r + extra)[None, :]
        p = np.clip(1 - r**2, 0, None)[None, :]
        return rf.Solution(s, force, np.ones_like(s), np.array([0.0]), r, f, p)
    d = rf.differences(sol(coarse, 0 * coarse, 1 - s), sol(fine, 0.1 * np.sin(np.pi * fine),
                                                         1 - s + 0.02 * s**2))
    assert d["profile"] == pytest.approx(0.1, abs=1e-12)  # max of 0.1 sin(πr) on the grid
    assert d["force"] == pytest.approx(0.02, abs=1e-12)   # 0.02 s² at s = 1
    # pressure: interpolating 1 - r² on spacing 0.5 errs by at most (0.5/2)² = 1/16
    assert d["pressure"] == pytest.approx(1 / 16, abs=1e-3)


def test_coarsest_converged_needs_every_finer_level_within_tolerance():
    # the third level is within tolerance, the fourth is not: only the fifth counts
    assert rf.coarsest_converged([0.5, 0.1, 0.005, 0.02, 0.004, 0.0], 0.01) == 4
    assert rf.coarsest_converged([0.5, 0.05, 0.0], 0.01) is None
    # a failed level (NaN) is left out
    assert rf.coarsest_converged([0.5, 0.008, np.nan, 0.001, 0.0], 0.01) == 1


def test_levels_pair_resolutions_and_steps():
    lv = rf.levels("mdr", [400, 100, 200], [0.1])
    assert [x.name for x in lv] == ["mdr-elements-100-step-0.1", "mdr-elements-200-step-0.1",
                                    "mdr-elements-400-step-0.1"]
    assert lv[0].changes == {"mdr.elements": 100, "sliding.step_hat": 0.1}
    steps = rf.levels("fem", [250], [0.1, 0.05, 0.2])
    assert [x.step_hat for x in steps] == [0.2, 0.1, 0.05]  # coarsest first
    assert rf.refined_parameter(steps) == "step"
    assert [x.resolution for x in rf.levels("fem")] == [60, 125, 250, 500, 1000]
    with pytest.raises(cases.CaseError):
        rf.levels("mdr", [100, 200, 400], [0.1, 0.05])


# ----------------------------------------------------------------------------
# A study end to end through a LocalCluster on loopback, with a solver of
# known order: the error of every output is C h^2, h = 1/resolution.

ORDER, AMPLITUDE = 2.0, 5.0


def fake_solve(case, solver, progress=None):
    """A stand-in solver: f, p and F are exact plus AMPLITUDE * h^ORDER.

    Its profile is linear in r and its force history shares one ŝ grid across
    levels, so interpolation adds nothing to the differences.
    """
    n = case.mdr.elements if solver == "mdr" else case.fem.contact_nodes
    if n == 24:
        raise cases.SolverError("injected failure at 24")
    eps = AMPLITUDE * (1.0 / n) ** ORDER
    sc = reference.scales(case)
    s_hat = np.linspace(0.0, case.stages.s_hat[-1], 41)
    r = np.linspace(0.0, 2.0 * sc["a0"], n + 1)
    stage = np.asarray(case.stages.s_hat)
    x = r / sc["a0"]
    f = sc["d0"] * (x[None, :] * (1 + stage[:, None]) + 0.5 * eps * x[None, :])
    p = sc["p0"] * (1 + eps) * np.clip(1 - x**2, 0, None)[None, :].repeat(len(stage), 0)
    for k in range(5):
        if progress:
            progress(k / 5)
    hist = dict(s=s_hat / sc["s_hat_per_m"], force=sc["F0"] * np.exp(-s_hat) * (1 + eps),
                depth=np.full_like(s_hat, sc["d0"]), contact_radius=np.full_like(s_hat, sc["a0"]),
                wear_center=np.zeros_like(s_hat), wear_volume=np.zeros_like(s_hat))
    return cases.RunResult(history=hist, stage_s=stage / sc["s_hat_per_m"], r=r, f=f, p=p,
                           solve_seconds=1e-3, info={"fake": True})


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as c:
        yield c.scheduler_address


@pytest.fixture(scope="module")
def fake_study(cluster, tmp_path_factory):
    from wearcheck.studies.refine import refine
    out = tmp_path_factory.mktemp("study")
    case = cases.shipped("paper")
    # 24 fails in the solver (a level the case rejects is refused up front, below)
    summary = refine(cases.load(case, ["stages.s_hat=[0.0, 0.5, 1.0]"]), "mdr", out,
                     levels=[8, 16, 24, 32, 64, 128], scheduler=cluster, quiet=True,
                     solve=fake_solve)
    return out, summary


def test_study_reports_failed_levels_and_writes_the_others(fake_study):
    out, summary = fake_study
    with open(out / "refinement-mdr.csv", newline="") as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    status = {r["level"]: r["status"] for r in rows}
    assert len(rows) == 6
    assert "injected failure at 24" in status["mdr-elements-24"]
    for n in (8, 16, 32, 64, 128):
        assert status[f"mdr-elements-{n}"] == "ok"
        run = Run(out / f"mdr-elements-{n}")  # complete and readable back
        assert run.case.mdr.elements == n
    assert not (out / "mdr-elements-1").exists() and not (out / "mdr-elements-24").exists()
    meta = json.loads((out / "meta.json").read_text())
    assert "git_revision" in meta["studies"]["refine-mdr"]
    assert "[mdr]" in meta["studies"]["refine-mdr"]["resolved_case"]


def test_study_recovers_the_known_order(fake_study):
    _, summary = fake_study
    # the differences between successive levels (ratio 2, also across the failed
    # level 24) are C (1 - 2^-p) h^p exactly: the fit recovers p to rounding
    for m in ("profile", "force"):
        assert summary["observed_order"][m]["order"] == pytest.approx(ORDER, abs=1e-9)
    rich = summary["richardson"]
    # three finest levels 32, 64, 128; F/F0 at ŝ = 1 is e^-1 (1 + C h²)
    assert rich["order"] == pytest.approx(ORDER, abs=1e-6)
    assert rich["estimate"] == pytest.approx(math.exp(-1.0), abs=1e-10)
    # worst difference C (h² - h_f²) (profile: C h² r/2a0 with r/a0 up to 2, and
    # force) is 5 (1/32² - 1/128²) = 0.0046 at N = 32 and 0.0192 at N = 16, against
    # the tolerance 0.01
    assert summary["converged"]["level"] == "mdr-elements-32"


def test_second_solver_joins_the_same_directory(fake_study, cluster):
    from wearcheck.studies.refine import refine
    from wearcheck.comparisons.present.study_figures import FIGURES, studies
    out, _ = fake_study
    refine(cases.load(cases.shipped("paper"), ["stages.s_hat=[0.0, 0.5, 1.0]"]), "fem", out,
           levels=[10, 20, 40], scheduler=cluster, quiet=True, solve=fake_solve)
    assert [s["solver"] for s in studies(out)] == ["mdr", "fem"]
    # refinement.csv holds both studies' rows, each as in its own per-solver file
    import csv
    def rows(path):
        lines = [l for l in path.read_text().splitlines() if not l.startswith("#")]
        return list(csv.DictReader(lines))
    both = rows(out / "refinement.csv")
    for solver in ("mdr", "fem"):
        own = rows(out / f"refinement-{solver}.csv")
        mine = [{k: v for k, v in r.items() if k != "solver"} for r in both
                if r["solver"] == solver]
        assert mine == own and len(own) > 0
    meta = json.loads((out / "meta.json").read_text())
    assert set(meta["studies"]) == {"refine-mdr", "refine-fem"}
    for name in FIGURES:
        assert (out / name).stat().st_size > 1000
    # no temporary leftovers; the study's ownership marker only
    assert [p.name for p in out.glob(".*")] == [".wearcheck-output"]


# ----------------------------------------------------------------------------
# The real MDR solver at small N, through the command line


def test_mdr_study_through_the_command_line(cluster, tmp_path):
    from wearcheck.cli import main
    out = tmp_path / "mdr"
    # a level the case rejects (mdr.elements >= 2) refuses the study before it starts
    args = ["refine", str(cases.shipped("paper")), "--solver", "mdr", "--out", str(out),
            "--set", "sliding.force_fraction=0.3", "--set", "stages.s_hat=[0.0, 1.0, 2.0]",
            "--scheduler", cluster, "--quiet"]
    assert main(args + ["--levels", "1,25,50"]) == 2 and not out.exists()
    # a short run (until F < 0.3 F0, stages ŝ = 0, 1, 2)
    code = main(args + ["--levels", "32,50,100,200"])
    assert code == 0
    summary = json.loads((out / "refinement-mdr.json").read_text())
    rows = {r["resolution"]: r for r in summary["levels"]}
    ok = [32, 50, 100, 200]
    assert all(rows[n]["status"] == "ok" for n in ok)
    # the unworn contact (ŝ = 0) against the exact sphere solution (F0 by
    # cases.reference): even N = 32 (10.24 cells in the contact, the fewest
    # mdr.resolution accepts) is within 1e-3 for a consistent discretisation
    f0 = np.array([abs(rows[n]["stage_force"]["0.0"] - 1.0) for n in ok])
    assert np.all(f0 < 1e-3)
    # the worn solution converges: differences to N = 200 fall with N at a
    # fitted order well above 0 (a scheme that stalls would give ~0)
    for m in ("profile", "force"):
        e = [rows[n]["differences"][m] for n in ok[:-1]]
        assert np.all(np.diff(e) < 0), (m, e)
        assert summary["observed_order"][m]["order"] > 0.5
    for name in ("fig4_profiles.png", "fig4_force.png", "convergence.png", "cost.png"):
        assert (out / name).is_file()


def crashing_solve(case, solver, progress=None):
    """fake_solve, except that the worker process dies at N = 16."""
    import os
    if case.mdr.elements == 16:
        os._exit(3)
    return fake_solve(case, solver, progress)


def test_a_dead_worker_fails_only_its_level(tmp_path):
    from wearcheck.studies.distributed import Task, run_cases
    # the embedded cluster (no scheduler given): loopback, one task per worker
    tasks = [Task(f"mdr-elements-{n}", "mdr", {"mdr.elements": n}) for n in (8, 16, 32, 64)]
    outcomes = run_cases(cases.load(cases.shipped("paper")), tasks, tmp_path, workers=2,
                         quiet=True, solve=crashing_solve)
    status = {o.task.name: o for o in outcomes}
    assert "worker died" in status["mdr-elements-16"].message
    for n in (8, 32, 64):
        assert status[f"mdr-elements-{n}"].ok
        assert Run(tmp_path / f"mdr-elements-{n}").case.mdr.elements == n


def test_mdr_step_refinement_shows_backward_euler_first_order(cluster, tmp_path):
    from wearcheck.studies.refine import refine
    # implicit (backward) Euler in ŝ has a global error Δŝ e1(ŝ) + O(Δŝ²): order
    # 1. With Δŝ <= 0.2 the O(Δŝ²) part moves the fitted slope by O(0.1)
    summary = refine(cases.load(cases.shipped("paper"), ["sliding.force_fraction=0.3",
                                                         "stages.s_hat=[0.0, 1.0, 2.0]",
                                                         "sliding.scheme=implicit"]),
                     "mdr", tmp_path, levels=[50], steps=[0.2, 0.1, 0.05, 0.025],
                     scheduler=cluster, quiet=True)
    assert summary["refined"] == "step"
    for m in ("profile", "force"):
        assert summary["observed_order"][m]["order"] == pytest.approx(1.0, abs=0.1)
    assert summary["richardson"]["by_stage"][1.0]["order"] == pytest.approx(1.0, abs=0.1)


def test_a_failed_level_removes_an_earlier_run_of_that_level(cluster, tmp_path):
    import shutil
    from wearcheck.studies.refine import refine
    out = tmp_path / "study"
    refine(cases.load(cases.shipped("paper"), ["stages.s_hat=[0.0, 0.5, 1.0]"]), "mdr", out,
           levels=[8, 16], scheduler=cluster, quiet=True, solve=fake_solve)
    # a complete run of level 24 from an earlier study (here: a copy of level 16)
    shutil.copytree(out / "mdr-elements-16", out / "mdr-elements-24")
    refine(cases.load(cases.shipped("paper"), ["stages.s_hat=[0.0, 0.5, 1.0]"]), "mdr", out,
           levels=[8, 24], scheduler=cluster, quiet=True, solve=fake_solve)  # 24 fails
    assert not (out / "mdr-elements-24").exists()
    assert (out / "mdr-elements-8" / "meta.json").is_file()
