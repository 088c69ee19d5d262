"""No silent wrong answer from a case the numerics cannot hold (issue 20, items 2-4, 8).

Each test failed on the code before the fix: the MDR ran an unresolved contact
with exit 0 (item 2), every solver wore a ball past its equator (item 3) and
extrapolated a profile table silently (item 4); the fretting, ellipsoid and
over-deep-force messages were wrong or missing (item 8). Expected values come
from closed forms (Hertz, the exact sphere), from a converged run of the same
solver, or from hashlib; each tolerance says why.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import wearcheck
from wearcheck import cases
from wearcheck.cases import CaseError, RunWarning, SolverError, reference, validity
from wearcheck.cli import main as cli_main
from wearcheck.mdr import resolution

PAPER = str(cases.shipped("paper"))
#: the reviewer's runaway ball: F = 500 N, k = 6e-3 (scar 1.82 R and 2.4 hemispheres worn)
PAST_THE_BALL = {"loading.force": 500.0, "wear.k": 6e-3}


def _force_at(result, s_hat):
    h = result.history
    return float(np.interp(s_hat, h["s"] * result.scales["s_hat_per_m"],
                           h["force"] / result.scales["F0"]))


def _one_error_line(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip() and not line.startswith("note:")]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


# -- item 2: an unresolved MDR contact ------------------------------------------

@pytest.mark.parametrize("override, key, proposal", [
    ({"mdr.elements": 2}, "mdr.elements", "mdr.elements >= 32"),
    ({"mdr.domain_factor": 100.0}, "mdr.domain_factor", "mdr.domain_factor <= 6.324"),
    ({"mdr.elements": 31}, "mdr.elements", "mdr.elements >= 32"),
])
def test_an_unresolved_mdr_contact_is_refused_naming_the_key_and_value(override, key, proposal):
    """mdr.elements = 2 gave F(0)/F0 = 1.25, F/F0 = 0.47 at ŝ = 3 (0.279) with exit 0;
    domain_factor = 100 gave F/F0 = 5.0. The grid has N cells uniform in r² on
    L² = 2·df²·a0², so the contact holds N/(2 df²) of them: 32 elements (10.24 cells)
    or df <= √(800/20) = 6.3246 reach the 10 of mdr.resolution."""
    case = wearcheck.load_case("paper", override)
    with pytest.raises(CaseError) as err:
        wearcheck.solve(case, "mdr")
    text = str(err.value)
    assert text.startswith(f"key '{key}' = {override[key]!r}") and proposal in text
    assert "\n" not in text


def test_the_smallest_resolved_grid_errs_by_less_than_the_criterion_says():
    """The proposal is honest: at the 32 elements proposed for mdr.elements = 2 the
    paper case's F/F0 at ŝ = 3 is within 1 % F0 (the criterion of mdr.resolution,
    docs/limits.md) of the shipped N = 800 run, itself within 5e-4 of N = 3200
    (README, convergence): measured 2.4e-3 (benchmarks/bench_mdr_resolution.py)."""
    coarse = wearcheck.solve(wearcheck.load_case("paper", {"mdr.elements": 32}), "mdr")
    fine = wearcheck.solve(wearcheck.load_case("paper"), "mdr")
    assert abs(_force_at(coarse, 3.0) - _force_at(fine, 3.0)) < 0.01
    assert abs(coarse.history["force"][0] / coarse.scales["F0"] - 1.0) < 0.01  # Hertz


def test_below_the_threshold_the_error_passes_one_percent(monkeypatch):
    """The threshold is where the error crosses 1 %, not an arbitrary number: on the
    cone (first order in the cells, the slowest profile of the benchmark) 8 cells
    (N = 25) err by more than 1 % F0 against N = 800 when the refusal is lifted;
    10.24 cells (N = 32) by less (benchmark, against N = 6400: 1.24e-2 at N = 25,
    9.2e-3 at N = 31)."""
    cone = {"indenter.profile": "cone", "indenter.slope_angle": 0.0064,
            "sliding.force_fraction": 0.25, "stages.s_hat": [0.0]}
    monkeypatch.setattr(resolution, "check", lambda case: None)

    def error(N):
        run = wearcheck.solve(wearcheck.load_case("paper", {**cone, "mdr.elements": N}), "mdr")
        ref = wearcheck.solve(wearcheck.load_case("paper", {**cone, "mdr.elements": 800}), "mdr")
        g = np.linspace(0.0, 2.5, 200)
        return max(abs(_force_at(run, s) - _force_at(ref, s)) for s in g)

    assert error(25) > 0.01
    assert error(32) < 0.01


def test_a_fine_grid_on_a_wide_domain_runs():
    """The refusal proposes a finer grid on a wide domain (mdr.domain_factor = 100:
    mdr.elements >= 200000); past mdr.wear.DENSE_MAX such a grid holds fewer contact
    nodes than GMRES's coarse grid, and GMRES did not converge (exit 3; paper case,
    N = 3000, domain factor 4.56: 72 cells). Now it runs, and agrees with the shipped
    grid to the error of 72 cells (1.4e-4 at 64 in benchmarks/bench_mdr_resolution.py;
    1e-3 allowed)."""
    over = {"sliding.force_fraction": 0.5, "stages.s_hat": [0.0]}
    wide = wearcheck.solve(wearcheck.load_case("paper", {**over, "mdr.elements": 3000,
                                                         "mdr.domain_factor": 4.56}), "mdr")
    ref = wearcheck.solve(wearcheck.load_case("paper", over), "mdr")
    assert abs(_force_at(wide, 0.5) - _force_at(ref, 0.5)) < 1e-3


def test_the_cli_refuses_in_one_line_before_writing(tmp_path, capsys):
    out = tmp_path / "r"
    assert cli_main(["run", "paper", "--solver", "mdr", "--set", "mdr.elements=2",
                     "--out", str(out), "--quiet"]) == 2
    assert "'mdr.elements' = 2" in _one_error_line(capsys.readouterr().err)
    assert not out.exists()


# -- item 3: wear past the ball ---------------------------------------------------

@pytest.mark.parametrize("solver", ["mdr", "fem", "bem"])
@pytest.mark.parametrize("override", [PAST_THE_BALL, {"sliding.stroke": 69.0}])
def test_every_solver_refuses_to_wear_the_ball_past_its_equator(solver, override):
    """F = 500 N, k = 6e-3: the MDR reached a scar of 1.82 R with exit 0, the FEM
    refused ("beyond indenter.radius"); now all three refuse alike, naming the
    run's length and the cycles that keep the scar on the sphere. The cycles
    proposed follow from the asymptote b⁴ = a0⁴ + 4RKFs/π (reference) at b = R/1.02."""
    case = wearcheck.load_case("ball_on_flat", override)
    with pytest.raises(CaseError) as err:
        wearcheck.solve(case, solver)
    text = str(err.value)
    assert text.startswith("key 'sliding.cycles' = 1000000.0: the run would wear the sphere "
                           "past its equator")
    R, K, F = case.indenter.radius, case.wear_rate, case.loading.force
    a0 = reference.scales(case)["a0"]
    cycles = ((R / 1.02) ** 4 - a0**4) * math.pi / (4 * R * K * F) * case.cycles_per_metre
    assert f"sliding.cycles <= {cycles:.4g}" in text


def test_the_proposed_cycles_keep_the_scar_on_the_ball():
    """Run (MDR, N = 200) at the cycles the refusal proposed: the scar stays inside R,
    and the proposal is not needlessly short (measured 0.88 R: the asymptote takes the
    worn cap as the paraboloid's b²/2R, the sphere's deeper cap holds the volume at a
    smaller b)."""
    case = wearcheck.load_case("ball_on_flat", PAST_THE_BALL)
    with pytest.raises(CaseError) as err:
        wearcheck.solve(case, "mdr")
    cycles = float(str(err.value).split("sliding.cycles <= ")[1].split(")")[0])
    shorter = case.derive({"sliding.cycles": cycles, "stages.cycles": [0.0],
                           "mdr.elements": 200})
    with pytest.warns(RunWarning, match="half-space theory is stretched"):
        run = wearcheck.solve(shorter, "mdr")
    assert 0.8 * case.indenter.radius < run.history["scar_radius"][-1] < case.indenter.radius


def test_the_watch_stops_at_the_body_and_warns_once_past_half_space_theory():
    """BodyWatch, as each solver calls it per recorded step: on the 5 mm ball the
    unworn surface's slope r/√(R² − r²) passes 0.1 at r = 0.0995 R (one RunWarning,
    kept in watch.remarks); a scar past R stops the run naming the key."""
    case = wearcheck.load_case("ball_on_flat")
    R = case.indenter.radius
    watch = validity.BodyWatch(case)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        watch(0.0, 0.099 * R, 0.0)     # slope 0.0995: inside
    with pytest.warns(RunWarning) as caught:
        watch(1.0, 0.0996 * R, 0.0)
        watch(2.0, 0.5 * R, 0.4 * R)   # already said: not again
    assert len(caught) == 1 and len(watch.remarks) == 1
    assert "slope is 0.1001 > 0.1" in watch.remarks[0]
    with pytest.raises(CaseError, match=r"^key 'sliding.cycles' = 1000000.0: the scar, at "
                                        r"ŝ = .*cycle 1500\), reaches r = 0.005001 m, past "
                                        r"the sphere's equator"):
        watch(3.0, 0.99 * R, 1.0002 * R)   # 1 mm stroke: 3 m is 1500 cycles


def test_a_run_past_half_space_theory_says_so_once_where_the_user_reads(tmp_path, capsys):
    """F = 500 N for 10³ cycles stays on the ball but its scar passes a/R = 0.1: exit 0,
    one note on the terminal, the remark in meta.json (warnings and info), none for
    the shipped paper case (a/R <= 0.0141)."""
    out = tmp_path / "r"
    assert cli_main(["run", "ball_on_flat", "--set", "loading.force=500", "--set",
                     "wear.k=6e-3", "--set", "sliding.cycles=1000", "--set",
                     "stages.cycles=[0.0]", "--set", "mdr.elements=200", "--out",
                     str(out)]) == 0
    err = capsys.readouterr().err
    assert err.count("note: half-space theory is stretched") == 1
    meta = json.loads((out / "meta.json").read_text())
    assert any("half-space theory" in w for w in meta["warnings"])
    # (500 N also passes the yield estimate, p0 = 5.9 GPa > 1.6 σ0/3 = 3.2 GPa: the other remark)
    assert meta["info"]["warnings"] == [w for w in meta["warnings"]
                                        if "half-space" in w or "onset of yield" in w]
    with warnings.catch_warnings():
        # (the paper case, p0 = 1.47 GPa > 1.6 σ0/3 = 1.07 GPa, has the yield remark)
        warnings.filterwarnings("error", "half-space", RunWarning)
        run = wearcheck.solve(wearcheck.load_case("paper", {"mdr.elements": 200}), "mdr")
    assert not any("half-space" in w for w in run.info.get("warnings", []))


# -- item 4: a profile table shorter than the contact -------------------------------

def _table(path: Path, r_end: float, R=0.01, rows=201) -> Path:
    r = np.linspace(0.0, r_end, rows)
    path.write_text("r,f\n" + "".join(f"{a:.17g},{a * a / (2 * R):.17g}\n" for a in r))
    return path


TABLE_RUN = {"indenter.profile": "table", "mdr.elements": 200, "fem.contact_nodes": 60,
             "bem.grid": 64}


@pytest.mark.parametrize("solver", ["mdr", "fem", "bem"])
def test_a_contact_that_leaves_the_table_stops_the_run(tmp_path, solver):
    """A paraboloid (R = 10 mm) tabulated to 1.001 a0 under the paper case's depth:
    the worn contact grows to √2 a0, and every solver continued the table with its
    last slope (F/F0 = 0.292 at ŝ = 3 against 0.279, compare said PASS). Refused
    at the first step past the table, naming indenter.file."""
    table = _table(tmp_path / "short.csv", 1.001e-4)
    case = wearcheck.load_case("paper", {**TABLE_RUN, "indenter.file": str(table)})
    with pytest.raises(CaseError) as err:
        wearcheck.solve(case, solver)
    text = str(err.value)
    assert text.startswith(f"key 'indenter.file' = {str(table)!r}: the ")
    assert "past the last radius of the profile table (0.0001001 m" in text
    assert "does not extrapolate a measured profile" in text


def test_compare_on_a_short_table_fails_instead_of_passing(tmp_path, capsys):
    table = _table(tmp_path / "short.csv", 1.001e-4)
    code = cli_main(["compare", "paper", "--no-render", "--out", str(tmp_path / "c"),
                     "--set", "indenter.profile=\"table\"", "--set", f"indenter.file=\"{table}\"",
                     "--set", "mdr.elements=200", "--set", "fem.contact_nodes=60",
                     "--set", "bem.grid=64", "--quiet"])
    assert code == 2
    assert "past the last radius of the profile table" in _one_error_line(
        capsys.readouterr().err)
    assert not (tmp_path / "c").exists()


def test_a_table_that_holds_the_contact_runs_and_its_digest_is_recorded(tmp_path):
    """Tabulated to 2 a0 (> √2 a0, the completely worn contact): the run agrees with
    the analytic paraboloid's to the table's interpolation (F/F0 at ŝ = 1 within
    1e-3), and meta.json records the table's SHA-256 as hashlib computes it."""
    table = _table(tmp_path / "long.csv", 2e-4, rows=401)
    over = {"mdr.elements": 200, "sliding.force_fraction": 0.3}
    run = wearcheck.solve(wearcheck.load_case("paper", {**over, **TABLE_RUN,
                                                        "indenter.file": str(table)}), "mdr")
    exact = wearcheck.solve(wearcheck.load_case("paper", {**over, "indenter.profile":
                                                          "paraboloid"}), "mdr")
    assert abs(_force_at(run, 1.0) - _force_at(exact, 1.0)) < 1e-3
    path = run.write(tmp_path / "run")
    meta = json.loads((Path(path) / "meta.json").read_text())
    assert meta["profile_table"]["sha256"] == hashlib.sha256(table.read_bytes()).hexdigest()
    assert meta["profile_table"]["last_radius"] == 2e-4
    assert set(meta) == set(meta["data_dictionary"]["meta_json"])   # described, as every key


# -- item 8: messages -----------------------------------------------------------------

def test_a_tiny_fretting_amplitude_gets_a_positive_width_and_a_practical_remedy():
    """fretting.amplitude = 1e-30 said "-1.93e-07 m wide" and proposed a 300-digit
    mdr.elements. MDR springs slide where μ q/G* < U, q = E* g'(a)(a − r) near the
    edge, so the annulus is G*U/(μ E* g'(a)), g' = 2a/R for the sphere's paraboloid
    tip: the message gives that width (to 2 %, the sphere's tip against a paraboloid
    and q's slope from two nodes) and the amplitude that puts 4 cells in it."""
    case = wearcheck.load_case("fretting", {"fretting.amplitude": 1e-30,
                                            "fretting.cycles": 1})
    with pytest.raises(SolverError) as err:
        wearcheck.solve(case, "mdr")
    text = str(err.value)
    assert text.startswith("key 'fretting.amplitude' = 1e-30: ")
    a = reference.scales(case)["a0"]
    width = case.G_star * 1e-30 / (case.wear.mu * case.E_star * 2 * a / case.indenter.radius)
    said = float(text.split("about ")[1].split(" m")[0])
    assert said == pytest.approx(width, rel=0.02)
    assert not re.search(r"\d{9}", text)   # no 300-digit number
    amplitude = float(text.split("raise fretting.amplitude to about ")[1])
    # the proposal runs: 4 cells in the annulus at the proposed amplitude
    wearcheck.solve(case.derive({"fretting.amplitude": amplitude}), "mdr")


def test_the_mdr_ellipsoid_says_what_the_stand_in_costs_on_the_terminal(tmp_path, capsys):
    """R2/R1 = 1e8 gave F/F0 = 0.055 with "approximate" only in meta.json. The note
    gives the unworn force of the paraboloid of radius √(R1 R2) over Hertz's
    elliptical one (reference), which is the run's own F(0)/F0 (to the MDR's
    discretisation, 1e-4 at N = 200)."""
    out = tmp_path / "e"
    assert cli_main(["run", "ellipsoid", "--solver", "mdr", "--set", "indenter.radius_y=1e6",
                     "--set", "mdr.elements=200", "--set", "sliding.until=\"distance\"",
                     "--set", "sliding.distance=0.0", "--set", "stages.s_hat=[0.0]",
                     "--out", str(out)]) == 0
    err = capsys.readouterr().err
    note = [line for line in err.splitlines() if "equivalent radius" in line]
    assert len(note) == 1 and note[0].startswith("note: ")
    ratio = float(note[0].split("its unworn force is ")[1].split()[0])
    E = wearcheck.load_case("ellipsoid").E_star
    exact = reference.hertz_elliptical(E, 0.01, 1e6, depth=1e-6)["force"]
    assert ratio == pytest.approx(reference.hertz(E, math.sqrt(0.01 * 1e6), depth=1e-6)["force"]
                                  / exact, rel=1e-3)
    run = wearcheck.read_run(out)
    assert run.history["force"][0] / run.scales["F0"] == pytest.approx(ratio, rel=1e-3)


def test_compare_reports_each_solvers_remarks(tmp_path, capsys):
    """The shipped ellipsoid (R2/R1 = 3) in compare: the MDR's note on the terminal
    and in the report beside its "Approximate" line; a note all solvers make, once."""
    out = tmp_path / "c"
    cli_main(["compare", "ellipsoid", "--no-render", "--out", str(out), "--set",
              "mdr.elements=100", "--set", "bem.grid=32", "--set", "sliding.until=\"distance\"",
              "--set", "sliding.distance=0.0", "--set", "stages.s_hat=[0.0]"])
    err = capsys.readouterr().err
    assert "note: MDR: the ellipsoid (radii R1, R2) is run as the paraboloid" in err
    assert "its unworn force is 0.9756 of the exact" in (out / "report.md").read_text()
    # a remark every solver makes on the same case (its p0 = 1.16 GPa passes the yield
    # estimate 1.6·σ0/3 = 1.07 GPa) is said once, naming them
    assert err.count("passes the onset of yield") == 1
    assert re.search(r"note: (MDR, BEM|BEM, MDR): the peak pressure of the unworn", err)
    assert (out / "report.md").read_text().count("passes the onset of yield") == 1


@pytest.mark.parametrize("force", [1e9, 1e12, 1e300])
def test_an_over_deep_force_on_a_sphere_says_so_and_gives_the_limit(force):
    """F = 1e9 N on the 5 mm ball said "not computable in floating point". No contact
    on the sphere carries more than the force at depth R, where a·atanh(a/R) = R
    (exact sphere, paper Eq. 2): the message gives it."""
    with pytest.raises(CaseError) as err:
        wearcheck.load_case("ball_on_flat", {"loading.force": force})
    text = str(err.value)
    assert "presses the sphere deeper than its radius" in text
    case = wearcheck.load_case("ball_on_flat")
    R, E = case.indenter.radius, case.E_star
    from scipy.optimize import brentq
    a = brentq(lambda a: a * math.atanh(a / R) - R, 1e-9 * R, R * (1 - 1e-12), xtol=1e-15)
    limit = E * ((a**2 + R**2) * math.atanh(a / R) - R * a)
    assert f"below {limit:.4g} N" in text
    below = wearcheck.load_case("ball_on_flat", {"loading.force": 0.99 * limit})
    assert reference.scales(below)["d0"] < R


def test_a_table_coarser_than_the_contact_gets_a_remark(tmp_path):
    """A 3-row table r = 0, 1, 2 mm of the paper's paraboloid (a0 = 0.1 mm) was read as
    a cone inside the contact with no word: F0 26.5 N against 30.8 N (the second
    adversarial review). Its F0 by quadrature is checked against Hertz's to show the
    remark's premise, and a table with a row every a0/4 (F0 within 1e-4 of Hertz's,
    measured 1.5e-4 at a0/2) gets none."""
    from wearcheck.cases import reference
    hertz = reference.scales(wearcheck.load_case("paper"))
    coarse = _table(tmp_path / "coarse.csv", 2e-3, rows=3)
    case = wearcheck.load_case("paper", {"indenter.profile": "table",
                                         "indenter.file": str(coarse)})
    assert abs(reference.scales(case)["F0"] / hertz["F0"] - 1) > 0.05
    assert any("holds 0 radius(es) inside the unworn contact radius" in w for w in case.warnings)
    fine = _table(tmp_path / "fine.csv", 4e-3, rows=161)     # every 2.5e-5 m = a0/4
    case = wearcheck.load_case("paper", {"indenter.profile": "table", "indenter.file": str(fine)})
    assert abs(reference.scales(case)["F0"] / hertz["F0"] - 1) < 1e-4
    assert not any("profile table holds" in w for w in case.warnings)
