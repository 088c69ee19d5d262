"""comparisons.metrics on synthetic inputs whose differences are known by construction."""

import math

import numpy as np
import pytest

from wearcheck.cases import RunResult, reference
from wearcheck.comparisons.analysis import metrics

#: tolerances and floors of these tests (relative to each stage's scale; floors in the
#: unworn scales)
TOL = dict(profile_tolerance=0.01, force_tolerance=0.01, pressure_tolerance=0.02,
           contact_radius_tolerance=0.02, profile_floor=0.01, force_floor=0.01,
           pressure_floor=0.001, contact_radius_floor=0.1, edge_band=0.1)


def test_to_grid_is_exact_for_linear_data_and_nan_outside():
    r_src = np.linspace(0.0, 1.0, 11)
    r_dst = np.array([-0.1, 0.0, 0.33, 0.999, 1.0, 1.2])
    y = metrics.to_grid(r_src, 2.0 * r_src + 1.0, r_dst)
    # linear interpolation reproduces a linear function to round-off
    np.testing.assert_allclose(y[1:5], 2.0 * r_dst[1:5] + 1.0, rtol=1e-14)
    assert math.isnan(y[0]) and math.isnan(y[-1])


def test_max_rms_of_known_vector_and_of_nothing():
    mx, rms, n = metrics.max_rms([3.0, -4.0, np.nan])
    assert (mx, n) == (4.0, 2)
    assert rms == pytest.approx(math.sqrt(12.5), rel=1e-15)
    assert all(math.isnan(v) for v in metrics.max_rms([np.nan])[:2])


def test_stage_differences_separate_interior_and_edge():
    d, p0, a = 2e-6, 1e9, 1.0e-4
    r = (np.arange(200) + 0.5) * 1e-6  # region boundaries fall half-way between nodes
    f1 = r**2 / 0.02
    f2 = f1 + 0.003 * d          # profile offset 0.3 % of d everywhere
    p1 = np.where(r < a, p0 * np.sqrt(np.clip(1 - (r / a) ** 2, 0, None)), 0.0)
    interior, edge = metrics.edge_masks(r, a, a, 0.1)
    p2 = p1 + np.where(interior, 0.015 * p0, 0.0) + np.where(edge, -0.2 * p0, 0.0)
    out = metrics.stage_differences(r, f1, f2, p1, p2, a, a, depth=d, p0=p0, edge_band=0.1)
    # by construction; rtol covers round-off of (f1 + c) - f1 at f ~ 1e-6
    assert out["profile_max"] == pytest.approx(0.003, rel=1e-9)
    assert out["profile_rms"] == pytest.approx(0.003, rel=1e-9)
    assert out["pressure_interior_max"] == pytest.approx(0.015, rel=1e-12)
    assert out["pressure_edge_max"] == pytest.approx(0.2, rel=1e-12)
    # interior r < 0.9 a: nodes 0..89; edge 0.9 a <= r <= 1.1 a: nodes 90..109
    assert out["pressure_interior_points"] == 90
    assert out["pressure_edge_points"] == 20


def test_edge_masks_use_smaller_and_larger_contact_radius():
    # interior below 0.9 · 1.0, edge band from there up to 1.1 · 1.1 = 1.21
    r = np.array([0.0, 0.85, 0.95, 1.0, 1.15, 1.25, 1.3])
    interior, edge = metrics.edge_masks(r, 1.0, 1.1, 0.1)
    np.testing.assert_array_equal(interior, [1, 1, 0, 0, 0, 0, 0])
    np.testing.assert_array_equal(edge, [0, 0, 1, 1, 1, 0, 0])


def test_verdict_fails_nan_and_values_above_tolerance():
    st = dict(profile_contact_max=0.005, force=0.02, pressure_interior_max=math.nan,
              contact_radius=0.0, stage_scales=dict(profile_contact_max=1.0, force=1.0,
                                                    pressure_interior_max=1.0,
                                                    contact_radius=1.0))
    v = metrics.verdict(st, TOL)
    assert v["profile_contact_max"]["passed"] and v["contact_radius"]["passed"]
    assert not v["force"]["passed"]
    assert not v["pressure_interior_max"]["passed"]  # nothing compared passes nothing


def test_verdict_judges_each_stage_against_its_own_scale_floored():
    # the same differences in unworn units at a late stage: force 0.02 F0, pressure
    # 0.004 p0 and contact radius 0.01 a0
    st = dict(profile_contact_max=0.005, force=0.0005, pressure_interior_max=0.0004,
              contact_radius=0.01,
              stage_scales=dict(profile_contact_max=1.0, force=0.02,
                                pressure_interior_max=0.0002, contact_radius=1.4))
    v = metrics.verdict(st, TOL)
    # force: 0.0005 F0 of the stage's 0.02 F0 is 2.5 % > 1 %, though 0.05 % of F0
    assert v["force"]["value"] == pytest.approx(0.025, rel=1e-12)
    assert v["force"]["scale_from"] == "stage" and not v["force"]["passed"]
    # pressure: the stage's peak 0.0002 p0 is below the floor 0.001 p0, so the floor is
    # the scale: 0.0004 / 0.001 = 40 % (not 200 %)
    assert v["pressure_interior_max"]["scale"] == 0.001
    assert v["pressure_interior_max"]["scale_from"] == "floor"
    assert v["pressure_interior_max"]["value"] == pytest.approx(0.4, rel=1e-12)
    # contact radius: 0.01 a0 of 1.4 a0 = 0.71 % < 2 %
    assert v["contact_radius"]["value"] == pytest.approx(0.01 / 1.4, rel=1e-12)
    assert v["contact_radius"]["passed"]
    # the difference in the unworn unit is kept beside the judged value
    assert v["force"]["unworn"] == 0.0005 and v["force"]["unit"] == "F0"


def _hertz_result(case_scales, r, n_stages, *, pressure_factor=1.0, force_factor=1.0,
                  radius_factor=1.0, profile_offset=0.0):
    sc = case_scales
    R = 0.01
    s = np.arange(n_stages) * 0.1 / sc["s_hat_per_m"]
    a = sc["a0"] * radius_factor
    p = reference.hertz_pressure(r, sc["E_star"], R, sc["a0"]) * pressure_factor
    f = r**2 / (2 * R) + profile_offset
    hist = dict(s=s, force=np.full(n_stages, sc["F0"] * force_factor),
                depth=np.full(n_stages, 1e-6),
                contact_radius=np.full(n_stages, a), wear_center=np.zeros(n_stages),
                wear_volume=np.zeros(n_stages))
    return RunResult(history=hist, stage_s=s, r=r, f=np.tile(f, (n_stages, 1)),
                     p=np.tile(p, (n_stages, 1)), solve_seconds=0.0)


@pytest.fixture
def hertz_scales():
    E = 2.308e11
    h = reference.hertz(E, 0.01, depth=1e-6)
    a0, F0 = h["contact_radius"], h["force"]
    return dict(E_star=E, a0=a0, F0=F0, p0=3 * F0 / (2 * math.pi * a0**2), s_hat_per_m=30.0)


def test_compare_results_recovers_constructed_differences(hertz_scales):
    sc = hertz_scales
    a0 = sc["a0"]
    mdr = _hertz_result(sc, np.linspace(0, 1.77 * a0, 801), 4)
    # FEM on other radii, reaching only 3 stages, with 1 % more pressure, 0.4 % more
    # force, a 1.5 % larger contact radius and its profile 0.2 % of d higher
    fem = _hertz_result(sc, np.linspace(0, 1.77 * a0, 97), 3, pressure_factor=1.01,
                        force_factor=1.004, radius_factor=1.015, profile_offset=0.002e-6)
    m = metrics.compare_results(mdr, fem, s_hat_per_m=sc["s_hat_per_m"], a0=a0, F0=sc["F0"],
                                p0=sc["p0"], depth=1e-6, tolerances=TOL, edge_band=0.1)
    assert m["stages_compared"] == 3
    assert m["stages_reached"] == dict(reference=4, solver=3)
    for st in m["stages"]:
        assert st["force"] == pytest.approx(0.004, rel=1e-9)
        assert st["contact_radius"] == pytest.approx(0.015, rel=1e-9)
        assert st["profile_max"] == pytest.approx(0.002, rel=1e-6)
        assert st["profile_contact_max"] == pytest.approx(0.002, rel=1e-6)
        # the unworn Hertz contact at every stage: its own scales are the unworn ones
        # (force F0, contact radius a0, depth d, peak pressure p0 at r = 0)
        assert st["stage_scales"] == pytest.approx(dict(
            profile_contact_max=1.0, force=1.0, pressure_interior_max=1.0, contact_radius=1.0),
            rel=1e-12)
        # p0 is Hertz's maximum pressure, reached at r = 0 (a node of both grids): 1 % of
        # p(0) = 0.01 p0; the MDR pressure interpolated to FEM radii errs by O(h²), <1e-5
        assert st["pressure_interior_max"] == pytest.approx(0.01, abs=1e-5)
        assert st["passed"]
    assert m["passed"]
    # the largest share of each tolerance: 0.004 of 0.01 F0, 0.015 of 0.02 a0
    assert m["worst"]["force"]["used"] == pytest.approx(0.4, rel=1e-9)
    assert m["worst"]["contact_radius"]["used"] == pytest.approx(0.75, rel=1e-9)
    tight = dict(TOL, force_tolerance=0.003)
    m = metrics.compare_results(mdr, fem, s_hat_per_m=sc["s_hat_per_m"], a0=a0, F0=sc["F0"],
                                p0=sc["p0"], depth=1e-6, tolerances=tight, edge_band=0.1)
    assert not m["passed"]
    assert all(not st["checks"]["force"]["passed"] for st in m["stages"])
    assert all(st["checks"]["profile_contact_max"]["passed"] for st in m["stages"])


def test_compare_results_without_common_stage_fails(hertz_scales):
    sc = hertz_scales
    r = np.linspace(0, 1.7 * sc["a0"], 50)
    mdr = _hertz_result(sc, r, 2)
    fem = _hertz_result(sc, r, 1)
    # a run that stopped before its first stage: one history row, no stage
    fem = RunResult(history=fem.history, stage_s=np.zeros(0), r=r, f=np.zeros((0, r.size)),
                    p=np.zeros((0, r.size)), solve_seconds=0.0)
    m = metrics.compare_results(mdr, fem, s_hat_per_m=sc["s_hat_per_m"], a0=sc["a0"],
                                F0=sc["F0"], p0=sc["p0"], depth=1e-6, tolerances=TOL,
                                edge_band=0.1)
    assert m["stages_compared"] == 0 and not m["passed"]


def test_history_differences_of_linear_histories():
    s1 = np.linspace(0, 1.0, 11)
    s2 = np.linspace(0, 0.8, 5)   # shorter run: only s <= 0.8 is compared
    h1 = dict(s=s1, force=10 - 2 * s1, contact_radius=1 + 0.1 * s1)
    h2 = dict(s=s2, force=10 - 2 * s2 + 0.05 * s2, contact_radius=1 + 0.1 * s2)
    out = metrics.history_differences(h1, h2, F0=10.0, a0=1.0)
    assert out["s_common_max"] == pytest.approx(0.8)
    # largest offset 0.05·0.8 at s = 0.8, relative to F0 = 10 (interpolation exact: linear)
    assert out["force_max"] == pytest.approx(0.004, rel=1e-12)
    assert out["contact_radius_max"] == pytest.approx(0.0, abs=1e-14)
