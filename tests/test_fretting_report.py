"""The report of a fretting run: written by every writer of a run directory, and its
checks against the closed forms are the closed forms' (not the run's own numbers)."""

import json

import pytest

import wearcheck
from wearcheck.cases import reference_fretting as rf
from wearcheck.comparisons.present import fretting_report


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    case = wearcheck.load_case("fretting", {"fretting.cycles": 30, "mdr.elements": 200})
    result = wearcheck.solve(case, "mdr")
    return case, result, result.write(tmp_path_factory.mktemp("fretting") / "run")


def test_fretting_run_directory_has_its_report(run):
    case, result, path = run
    for name in ("report.md", "report.html", "fretting_loops.png", "fretting_history.png"):
        assert (path / name).stat().st_size > 1000, name
    text = (path / "report.md").read_text()
    assert "c_CM/a" in text and "W_MD" in text and "Q*_CM" in text
    assert "energy–wear identity" in text
    # the shipped file leaves fretting.stage_cycles to its default (0, 1, 10, … and
    # the last cycle): the table of stored cycles ends at the run's last cycle
    stored = text.split("History at the stored cycles")[1].split("![")[0]
    assert [row.split("|")[1].strip() for row in stored.splitlines() if row.startswith("| ")
            and row[2].isdigit()] == ["0", "1", "10", "30"]
    # its 0-cycle row holds the first quarter cycle's wear (not an unworn state), and says so
    assert result.history["wear_volume"][0] > 0.0
    assert "first quarter cycle" in stored
    # every file is described in the run's data dictionary
    d = json.loads((path / "meta.json").read_text())["data_dictionary"]["files"]
    assert {p.name for p in path.iterdir()} <= set(d)


def test_first_cycle_against_the_closed_forms(run):
    case, result, _ = run
    checks = fretting_report.unworn_checks(case, result._run)
    assert checks["regime"] == "partial slip"
    # the closed forms, recomputed here from the case alone
    h = result.history
    a, F, mu = h["contact_radius"][0], h["force"][0], case.wear.mu
    u_star = rf.gross_slip_displacement(mu, F, case.G_star, a)
    c = rf.stick_radius(a, case.indenter.radius, case.E_star, case.G_star, mu,
                        case.fretting.amplitude)
    assert checks["stick_radius_closed_form"] == pytest.approx(c, rel=1e-12)
    # N = 200: stick radius within 1e-3 a (measured 1e-4), energy per cycle within
    # 3 % (its error falls from 1.1e-2 at N = 100 at order 1.3), Q* within 1e-2 μF
    assert checks["stick_radius_difference"] < 1e-3
    assert checks["energy_difference"] < 3e-2
    assert checks["force_amplitude_difference"] < 1e-2
    # V = (k/σ0) W holds to round-off at every cycle
    assert checks["energy_wear_identity"] < 1e-9
    assert u_star > case.fretting.amplitude


def test_no_report_for_a_gross_slip_run(tmp_path):
    path = wearcheck.solve(wearcheck.load_case("hertz", {"mdr.elements": 100}), "mdr").write(
        tmp_path / "run")
    assert not (path / "report.md").exists()


def test_force_controlled_tangential_loading_is_checked_too(tmp_path):
    # fretting.force_amplitude: c/a = (1 - Q*/μF)^(1/3), u0 = u*[1 - (1 - Q*/μF)^(2/3)]
    # and the energy per cycle of Q* (Mindlin–Deresiewicz), from the case alone
    from wearcheck import cases
    raw = cases.to_dict(wearcheck.load_case("fretting", {"fretting.cycles": 10,
                                                         "mdr.elements": 200}))
    del raw["fretting"]["amplitude"]
    raw["fretting"]["force_amplitude"] = 4.5            # Q*/μF = 0.5
    case = cases.from_dict(raw, source="force_amplitude.toml")
    result = wearcheck.solve(case, "mdr")
    path = result.write(tmp_path / "run")
    checks = fretting_report.unworn_checks(case, result._run)
    h = result.history
    a, F, mu = h["contact_radius"][0], h["force"][0], case.wear.mu
    u_star = rf.gross_slip_displacement(mu, F, case.G_star, a)
    assert checks["regime"] == "partial slip"
    assert checks["stick_radius_closed_form"] == pytest.approx(
        rf.stick_radius_from_force(a, 4.5, mu, F), rel=1e-12)
    assert checks["energy_closed_form"] == pytest.approx(
        rf.energy_per_cycle(4.5, mu, F, u_star), rel=1e-12)
    # N = 200: as for displacement control (stick radius 1e-3 a, energy 3 %),
    # the displacement amplitude within 1e-3 u* (measured: 1e-5 a, 0.7 %, 2e-5 u*)
    assert checks["stick_radius_difference"] < 1e-3
    assert checks["energy_difference"] < 3e-2
    assert checks["displacement_amplitude_difference"] < 1e-3
    text = (path / "report.md").read_text()
    assert "u0_CM" in text and "c_CM/a" in text and "W_MD" in text
    # the increment wear number the run reached, and the limit it was held to
    from wearcheck.mdr import fretting
    assert "increment wear number" in text
    assert f"refused above {fretting.WEAR_NUMBER_LIMIT}" in text
    assert 0.0 < result.info["increment_wear_number"] <= fretting.WEAR_NUMBER_LIMIT
    assert (path / "fretting_loops.png").stat().st_size > 1000


def test_the_report_states_the_cycle_jumping_error_estimate_of_meta_json(run):
    # the estimate a user is told about (docs/fretting.md §4; the key's doc in the
    # schema names where it is) is the one in meta.json, and within the tolerance
    import re
    from wearcheck.cases import schema
    case, result, path = run
    meta = json.loads((path / "meta.json").read_text())
    estimate = meta["info"]["cycle_jumping"]["error_estimate"]
    assert 0.0 < estimate <= case.fretting.jump_tolerance
    text = (path / "report.md").read_text()
    said = re.search(r"estimated error against every cycle simulated ([0-9.e+-]+) of the "
                     r"largest wear", text)
    assert said is not None, text[:600]
    assert float(said.group(1)) == pytest.approx(estimate, rel=0.05)   # printed to 2 digits
    doc = dict(schema.section_fields("fretting"))["jump_tolerance"].metadata["doc"]
    assert "info.cycle_jumping.error_estimate" in doc
    assert "2·jump_tolerance" not in doc     # the forward-Euler jumps' criterion, removed


def test_a_run_without_cycle_jumping_says_so(tmp_path):
    case = wearcheck.load_case("fretting", {"fretting.cycles": 6, "mdr.elements": 100,
                                            "fretting.jump_tolerance": 0,
                                            "fretting.stage_cycles": [0, 6]})
    path = wearcheck.solve(case, "mdr").write(tmp_path / "run")
    text = (path / "report.md").read_text()
    assert "every cycle simulated: 6" in text
    assert "cycle jumping" not in text
