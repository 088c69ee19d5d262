"""The edge study and the finite-sphere sweep of ``wearcheck compare``, orchestrated
around stand-in solvers whose answers are known by construction."""

import numpy as np
import pytest

from wearcheck import cases
from wearcheck.cases import RunResult, profiles, reference
from wearcheck.studies import compare as compare_mod
from wearcheck.studies import sphere_sweep as sphere_mod

PAPER = cases.shipped("paper")


def stand_in(finite_size_slope=0.0):
    """Hertz's unworn contact on each solver's grid; honours mdr.elements,
    fem.contact_nodes and sliding.step_hat, and (FEM only) multiplies the force by
    1 + finite_size_slope · a0/R, a finite-sphere error of known size."""
    def solve(case, name, progress=None):
        sc = reference.scales(case)
        a0, R = sc["a0"], case.indenter.radius
        n = case.mdr.elements + 1 if name == "mdr" else case.fem.contact_nodes
        r = np.linspace(0, 1.77 * a0, n)
        step = 0.1 if case.sliding.step_hat == "auto" else case.sliding.step_hat
        stages = np.asarray(case.stages.s_hat)
        s_hat = np.unique(np.concatenate([np.arange(0, stages[-1] + step / 2, step), stages]))
        s = s_hat / sc["s_hat_per_m"]
        F = sc["F0"] * (1 + (finite_size_slope * a0 / R if name == "fem" else 0.0))
        hist = dict(s=s, force=np.full(s.size, F), depth=np.full(s.size, sc["d0"]),
                    contact_radius=np.full(s.size, a0), wear_center=np.zeros(s.size),
                    wear_volume=np.zeros(s.size))
        K = stages.size
        p = reference.hertz_pressure(r, case.E_star, R, a0)
        return RunResult(history=hist, stage_s=stages / sc["s_hat_per_m"], r=r,
                         f=np.tile(profiles.height(case.indenter, r), (K, 1)),
                         p=np.tile(p, (K, 1)), solve_seconds=0.0)
    return solve


def test_edge_study_runs_the_levels_it_names(tmp_path):
    case = cases.load(PAPER, ["stages.s_hat=[0.0, 0.5, 1.0]", "mdr.elements=100",
                              "fem.contact_nodes=40", "indenter.profile=\"paraboloid\"",
                              "sliding.step_hat=\"auto\""])
    m = compare_mod.compare(case, tmp_path / "out", edge=True, solve=stand_in(), render=False)
    es = m["edge_study"]
    for name, n, spacing0 in (("mdr", 100, 1.77 / 100), ("fem", 40, 1.77 / 39)):
        lv = {d["label"].split(" (")[0]: d for d in es["solvers"][name]["levels"]}
        assert set(lv) == {"case", "grid x0.5", "grid x2", "step x0.5"}
        # the stand-in's grid spacing follows the overrides: 1.77 a0 / (intervals)
        assert lv["case"]["spacing"] == pytest.approx(spacing0, rel=1e-9)
        intervals = (n // 2, 2 * n) if name == "mdr" else (n // 2 - 1, 2 * n - 1)
        assert lv["grid x0.5"]["spacing"] == pytest.approx(1.77 / intervals[0], rel=1e-9)
        assert lv["grid x2"]["spacing"] == pytest.approx(1.77 / intervals[1], rel=1e-9)
        # the stand-in steps by 0.1 in ŝ under "auto"; the step level halves what was used
        assert lv["case"]["step_hat"] == pytest.approx(0.1, rel=1e-9)
        assert lv["step x0.5"]["step_hat"] == pytest.approx(0.05, rel=1e-9)
        # Hertz at every level: no peak anywhere, hence "no peak" at every stage
        assert [st["verdict"] for st in es["solvers"][name]["stages"]] == ["no peak"] * 3
    out = tmp_path / "out"
    assert (out / "edge_study" / "edge_peak.png").stat().st_size > 15_000
    assert (out / "edge_study" / "mdr-grid_x2" / "meta.json").is_file()
    assert "no peak" in es["summary"]


def test_sphere_sweep_recovers_a_known_finite_size_error(tmp_path):
    # a force tolerance of 1 % (of the unworn force, which the sweep compares)
    case = cases.load(PAPER, ["mdr.elements=50", "fem.contact_nodes=20",
                              "compare.force_tolerance=0.01"])
    sw = sphere_mod.sphere_sweep(case, (0.005, 0.01, 0.02, 0.05), solve=stand_in(0.6))
    rows = sw["rows"]
    # the stand-in errs by exactly 0.6 a0/R (a0 = the half-space contact radius of the
    # swept depth, which sphere_case must reproduce: 0.6·a0/R recovered means a0 = ratio·R)
    for row in rows:
        assert row["force_rel"] == pytest.approx(0.6 * row["a0_over_R"], rel=1e-6)
    assert sw["slope"] == pytest.approx(0.6, rel=1e-6)
    assert sw["ratio_at_tolerance"] == pytest.approx(0.01 / 0.6, rel=1e-6)
    # 0.6 · 0.01 = 0.6 % within 1 %; 0.6 · 0.02 = 1.2 % is not
    assert sw["largest_ratio_within_tolerance"] == 0.01
    assert sw["shipped"]["paper"]["a0_over_R"] == pytest.approx(0.01, rel=1e-3)


def test_sphere_sweep_refuses_profiles_without_a_radius():
    case = cases.load(PAPER, ["indenter.profile=\"cone\"", "indenter.slope_angle=0.1",
                              "indenter.radius=0.01"])
    with pytest.raises(cases.ArgumentError, match="^sphere_sweep: needs") as caught:
        sphere_mod.sphere_sweep(case, (0.01,), solve=stand_in())
    # the command line names its flag
    assert caught.value.on_command_line().startswith("--sphere-sweep: needs")


def test_shipped_cases_at_the_same_ratio_share_one_mark_in_the_sphere_figure():
    """hertz.toml and paper.toml both sit at a0/R = 0.01: finite_sphere.png printed
    their names over each other (an unreadable 'baper'). Marks within 2 % merge."""
    from wearcheck.comparisons.present.figures import group_marks
    marks = [(0.01, "hertz"), (0.0106, "truncated"), (0.01 * (1 + 1e-12), "paper")]
    assert group_marks(marks) == [(0.01, "hertz, paper"), (0.0106, "truncated")]
