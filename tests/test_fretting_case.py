"""The [fretting] case section, solver support, the run directory and the map."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from wearcheck import cases, fem, mdr
from wearcheck.cases import reference
from wearcheck.cases import reference_fretting as rf
from wearcheck.rundir import Run, write_run


def raw(**fretting):
    return dict(indenter=dict(profile="paraboloid", radius=0.01, youngs_modulus=210e9,
                              poisson_ratio=0.3),
                loading=dict(control="force", force=30.0),
                wear=dict(k=1e-4, mu=0.3, hardness=2e9),
                fretting=fretting, mdr=dict(elements=60))


def test_shipped_case_reads():
    case = cases.load(cases.shipped("fretting"))
    fr = case.fretting
    assert fr.cycles == 100000 and fr.increments % 4 == 0
    sc = reference.scales(case)
    u_star = rf.gross_slip_displacement(case.wear.mu, sc["F0"], case.G_star, sc["a0"])
    # the partial slip at about half the gross-slip threshold
    assert fr.amplitude / u_star == pytest.approx(0.5, abs=0.02)
    # a gross-slip case has no fretting section
    assert cases.load(cases.shipped("paper")).fretting is None


@pytest.mark.parametrize("fretting, extra, needle", [
    (dict(cycles=10), {}, "exactly one of 'fretting.amplitude'"),
    (dict(cycles=10, amplitude=1e-7, force_amplitude=1.0), {}, "exactly one of"),
    (dict(cycles=10, amplitude=1e-7, increments=10), {}, "'fretting.increments' = 10"),
    (dict(cycles=0, amplitude=1e-7), {}, "'fretting.cycles' = 0"),
    (dict(cycles=1.5, amplitude=1e-7), {}, "'fretting.cycles' = 1.5"),
    (dict(amplitude=1e-7), {}, "missing key 'fretting.cycles'"),
    (dict(cycles=10, amplitude=-1e-7), {}, "'fretting.amplitude' = -1e-07"),
    (dict(cycles=10, force_amplitude=9.5), {}, "'fretting.force_amplitude' = 9.5"),
    (dict(cycles=10, amplitude=1e-7, stage_cycles=[5, 1]), {}, "increase strictly"),
    (dict(cycles=10, amplitude=1e-7, stage_cycles=[0.5]), {}, "'fretting.stage_cycles' = 0.5: must be a whole number"),
    (dict(cycles=10, amplitude=1e-7, jump_tolerance=1.0), {}, "'fretting.jump_tolerance'"),
    (dict(cycles=10, amplitude=1e-7, bogus=1), {}, "unknown key 'fretting.bogus'"),
    (dict(cycles=10, amplitude=1e-7), dict(sliding=dict(until="distance", distance=1.0)),
     "section [sliding] given with [fretting]"),
    (dict(cycles=10, amplitude=1e-7), dict(stages=dict(s_hat=[0.0, 1.0])),
     "section [stages] given with [fretting]"),
])
def test_bad_fretting_input_is_one_clear_case_error(fretting, extra, needle):
    r = raw(**fretting)
    r.update(extra)
    with pytest.raises(cases.CaseError) as err:
        cases.from_dict(r)
    assert needle in str(err.value)


def test_tangential_correction_refused_with_fretting():
    r = raw(cycles=10, amplitude=1e-7)
    r["wear"]["tangential_correction"] = True
    with pytest.raises(cases.CaseError, match="wear.tangential_correction"):
        cases.from_dict(r)


def test_force_amplitude_beyond_friction_is_a_solver_error_under_wear():
    # depth control: wear lowers F, and a Q* that was below μF0 can end above μF
    # (16 increments: 8 do not resolve k = 1 and are refused for that first, §5)
    r = raw(cycles=400, force_amplitude=0.999 * 0.3 * 30.0, jump_tolerance=0.0, increments=16)
    r["loading"] = dict(control="depth",
                        depth=reference.hertz(230.7692e9, 0.01, force=30.0)["depth"])
    r["wear"]["k"] = 1.0
    case = cases.from_dict(r)
    with pytest.raises(cases.SolverError, match="friction limit"):
        mdr.solve(case)


def test_too_many_cycles_without_jumps_refused_before_starting():
    case = cases.from_dict(raw(cycles=10**6, amplitude=1e-7, jump_tolerance=0.0))
    with pytest.raises(cases.CaseError, match="fretting.cycles"):
        mdr.solve(case)


def test_supports_and_fem_refuses_fretting():
    case = cases.from_dict(raw(cycles=2, amplitude=1e-7))
    assert mdr.supports(case) is None
    reason = fem.supports(case)
    assert reason and "fretting" in reason
    with pytest.raises(cases.CaseError, match="fretting"):
        fem.solve(case)
    assert fem.supports(cases.load(cases.shipped("paper"))) is None


def test_run_directory_holds_tau_history_and_loops(tmp_path):
    case = cases.from_dict(raw(cycles=3, amplitude=1e-7, stage_cycles=[0, 2, 3]))
    res = mdr.solve(case)
    write_run(tmp_path / "run", case, res, "mdr")
    run = Run(tmp_path / "run")
    assert run.case.fretting == case.fretting
    for col in ("cycles", "s", "force", "depth", "contact_radius", "wear_center",
                "wear_volume", "tangential_force_amplitude", "stick_radius",
                "dissipated_energy"):
        assert col in run.history
    np.testing.assert_array_equal(run.history["cycles"], [0, 1, 2, 3])
    assert run.stages["tau"].shape == run.stages["p"].shape == (3, 61)
    # |τ| <= μ p everywhere (Coulomb), with equality somewhere in the slip annulus.
    # 1e-4: τ is recorded from the springs as clipped before their last
    # increment's wear, which lowers the pressure at the contact edge (measured
    # overshoot 9e-6 relative, at the last loaded nodes)
    tau, p = run.stages["tau"], run.stages["p"]
    assert np.all(np.abs(tau) <= 0.3 * p * (1 + 1e-4) + 1e-12 * p.max())
    assert np.any(np.isclose(np.abs(tau), 0.3 * p, rtol=1e-6) & (p > 0))
    assert run.fields["loop_displacement"].shape == (2, 41)
    np.testing.assert_array_equal(run.fields["loop_cycles"], [2, 3])


def test_stage_extra_is_validated():
    with pytest.raises(ValueError, match="tau"):
        cases.RunResult(history={k: np.zeros(1) for k in cases.HISTORY_COLUMNS},
                        stage_s=np.zeros(1), r=np.zeros(3), f=np.zeros((1, 3)),
                        p=np.zeros((1, 3)), solve_seconds=0.0,
                        stage_extra=dict(tau=np.zeros((2, 3))))


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as c:
        yield c.scheduler_address


def test_fretting_map_regimes_follow_cattaneo_mindlin(cluster, tmp_path):
    from wearcheck.cli import main
    out = tmp_path / "map"
    code = main(["fretting-map", str(cases.shipped("fretting")),
                 "--vary", "fretting.amplitude=1e-7,3e-7,6e-7", "--vary", "loading.force=10,30",
                 "--set", "mdr.elements=60", "--set", "fretting.cycles=3",
                 "--set", "fretting.stage_cycles=[0, 3]", "--scheduler", cluster, "--quiet",
                 "--out", str(out)])
    assert code == 0
    with open(out / "fretting_map.csv", newline="") as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    assert len(rows) == 6
    for r in rows:
        # the independent oracle: u* = 3μF/(4G*a) of the unworn contact
        ratio = float(r["amplitude_over_u_star"])
        assert r["regime"] == ("partial slip" if ratio < 1 else "gross slip")
        assert float(r["wear_volume_per_cycle"]) > 0
    assert (out / "fretting_map.png").stat().st_size > 10_000


def test_vtk_export_of_a_fretting_run_carries_the_shear_traction(tmp_path):
    import pyvista as pv
    from wearcheck.comparisons.present.vtk import export_run
    case = cases.from_dict(raw(cycles=2, amplitude=1e-7, stage_cycles=[0, 2]))
    res = mdr.solve(case)
    write_run(tmp_path / "run", case, res, "mdr")
    vtk = export_run(tmp_path / "run")
    mesh = pv.read(vtk / "profile_001.vtu")
    np.testing.assert_array_equal(mesh.point_data["shear_traction"], res.stage_extra["tau"][1])


def test_api_derives_and_round_trips_a_fretting_case():
    import wearcheck
    case = wearcheck.load_case("fretting", {"fretting.cycles": 3, "mdr.elements": 60})
    assert case.fretting.cycles == 3
    again = cases.from_dict(cases.to_dict(case))
    assert again.fretting == case.fretting and again.loading == case.loading
    # a gross-slip case whose [sliding] is not the default cannot become a fretting one
    with pytest.raises(cases.CaseError, match=r"\[(sliding|stages)\] given with \[fretting\]"):
        wearcheck.load_case("paper", {"fretting.amplitude": 1e-7, "fretting.cycles": 3})


def test_wearcheck_run_vtk_of_a_fretting_case_carries_the_shear_traction(tmp_path):
    # the command line end to end: `wearcheck run fretting --vtk`
    import pyvista as pv
    from wearcheck.cli import main
    out = tmp_path / "run"
    code = main(["run", "fretting", "--set", "mdr.elements=60", "--set", "fretting.cycles=3",
                 "--set", "fretting.stage_cycles=[0, 3]", "--out", str(out), "--vtk",
                 "--quiet"])
    assert code == 0
    tau = np.load(out / "stages.npz")["tau"]
    mesh = pv.read(out / "vtk" / "profile_001.vtu")
    np.testing.assert_array_equal(mesh.point_data["shear_traction"], tau[1])
    assert (out / "report.md").is_file()


def test_an_override_switches_the_tangential_loading_between_displacement_and_force():
    # the shipped case gives fretting.amplitude; setting force_amplitude (on the
    # command line or through derive) replaces it, as stages.s_hat replaces cycles
    case = cases.load(cases.shipped("fretting"), ["fretting.force_amplitude=4.5"])
    assert case.fretting.amplitude is None and case.fretting.force_amplitude == 4.5
    back = case.derive({"fretting.amplitude": 1e-7})
    assert back.fretting.force_amplitude is None and back.fretting.amplitude == 1e-7
    # both at once is still the one clear error
    with pytest.raises(cases.CaseError, match="exactly one"):
        cases.load(cases.shipped("fretting"), ["fretting.force_amplitude=4.5",
                                               "fretting.amplitude=1e-7"])


def test_the_bem_refusal_of_fretting_does_not_deny_its_tangential_solver():
    """It said the BEM "does not solve" the tangential contact problem, while
    bem.tangential does (one fretting cycle, without wear): what is missing is a
    fretting wear run."""
    import importlib
    from wearcheck import registry
    assert hasattr(importlib.import_module("wearcheck.bem.tangential"), "__file__")
    reason = registry.get("bem").supports(cases.load(cases.shipped("fretting")))
    assert "bem.tangential" in reason and "does not solve" not in reason and "MDR" in reason


def test_stages_that_end_before_the_last_cycle_are_remarked_on():
    # the shipped case run longer (--set fretting.cycles=1e8) kept its stages
    # 0 ... 10⁵: the final worn profile was in no output, and nothing said so
    import warnings
    import wearcheck
    base = {"mdr.elements": 100, "fretting.cycles": 40}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        short = wearcheck.solve(wearcheck.load_case(
            "fretting", dict(base, **{"fretting.stage_cycles": [0, 10]})), "mdr")
        full = wearcheck.solve(wearcheck.load_case(
            "fretting", dict(base, **{"fretting.stage_cycles": [0, 10, 40]})), "mdr")
    said = [w for w in short.info.get("warnings", []) if "stored stages end" in w]
    assert len(said) == 1
    assert "cycle 10 of fretting.cycles = 40" in said[0] and "fretting.stage_cycles" in said[0]
    assert not [w for w in full.info.get("warnings", []) if "stored stages end" in w]
    assert full.history["cycles"][-1] == 40 and len(full.stages["s"]) == 3
