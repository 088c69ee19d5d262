"""``wearcheck compare`` end to end: on analytic stand-in solvers (the layer itself) and
on the real MDR and FEM solvers (a small case)."""

import base64
import json
import math
import re

import numpy as np
import pytest

from wearcheck import cases
from wearcheck.cases import RunResult, profiles, reference
from wearcheck.studies import compare as compare_mod
from wearcheck import registry
from wearcheck import rundir as runio
from wearcheck.cli import main as cli_main

HERTZ = str(cases.shipped("hertz"))
TRUNCATED = str(cases.shipped("truncated"))
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def analytic_solver(pressure_factor=1.0):
    """A stand-in for both solvers: the unworn analytic contact at every stage.

    "mdr" answers on a uniform grid of mdr.elements + 1 radii, "fem" on
    fem.contact_nodes radii (offset, so that no node sits on r = b), the FEM's
    pressure scaled by ``pressure_factor``.
    """
    def solve(case, name, progress=None):
        sc = reference.scales(case)
        a0 = sc["a0"]
        if name == "mdr":
            r = np.linspace(0, case.mdr.domain_factor * math.sqrt(2) * a0, case.mdr.elements + 1)
        else:
            n = case.fem.contact_nodes
            r = np.linspace(0, case.fem.contact_factor * math.sqrt(2) * a0, n) + 0.37 * a0 / n
            r[0] = 0.0
        ind = case.indenter
        if ind.profile == "truncated_paraboloid":
            p = reference.truncated_paraboloid_pressure(r, case.E_star, ind.radius,
                                                        ind.flat_radius, a0)
        else:
            p = reference.hertz_pressure(r, case.E_star, ind.radius, a0)
        if name == "fem":
            p = p * pressure_factor
        s = np.asarray(case.stages.s_hat) / sc["s_hat_per_m"]
        K = len(s)
        hist = dict(s=s, force=np.full(K, sc["F0"]), depth=np.full(K, sc["d0"]),
                    contact_radius=np.full(K, a0), wear_center=np.zeros(K),
                    wear_volume=np.zeros(K))
        f = profiles.height(ind, r)
        return RunResult(history=hist, stage_s=s, r=r, f=np.tile(f, (K, 1)),
                         p=np.tile(p, (K, 1)), solve_seconds=0.0, info={"stand_in": True})
    return solve


STAGES = ["--set", "stages.s_hat=[0.0, 0.5, 1.0]", "--set", "mdr.elements=200",
          "--set", "fem.contact_nodes=60"]


def _png_ok(path):
    data = path.read_bytes()
    # a real plot with axes, curves and text is tens of kB; an empty canvas is ~2-5 kB
    return data[:8] == PNG_MAGIC and len(data) > 15_000


def test_compare_writes_the_complete_directory(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(compare_mod, "solve_case", analytic_solver())
    out = tmp_path / "cmp"
    code = cli_main(["compare", HERTZ, "--out", str(out), "--no-render"] + STAGES)
    assert code == 0
    for name in ("fig2_profiles", "fig2_pressure", "force_vs_sliding"):
        assert _png_ok(out / f"{name}.png"), name
        assert (out / f"{name}.pdf").stat().st_size > 5_000
    m = json.loads((out / "metrics.json").read_text())
    assert m["passed"] and m["stages_compared"] == 3
    # both run directories read back as runs of the same case
    for solver in ("mdr", "fem"):
        run = runio.Run(out / solver)
        assert run.solver == solver and run.stages["f"].shape[0] == 3
    assert "compare" in m["provenance"]["command"]
    md = (out / "report.md").read_text()
    html = (out / "report.html").read_text()
    # every stage has its row in the metrics table: "| k | ŝ | ŝ | ..."
    for k, s in enumerate(["0", "0.5", "1"]):
        assert re.search(rf"^\| {k} \| {re.escape(s)} \| {re.escape(s)} \|", md, re.M), k
    assert "**PASS**" in md and "class='pass'" in html
    # the HTML carries its three figures inline and stands alone
    imgs = re.findall(r"data:image/png;base64,([A-Za-z0-9+/=]+)", html)
    assert len(imgs) == 3 and all(base64.b64decode(i)[:8] == PNG_MAGIC for i in imgs)
    assert "src='fig2" not in html
    # nothing half-written is left beside the output
    assert [p.name for p in tmp_path.iterdir()] == ["cmp"]


def test_failing_comparison_exits_1_and_still_writes_the_verdict(tmp_path, monkeypatch, capsys):
    # FEM pressure 5 % higher: the interior difference is 5 % of the stage's peak
    # pressure (p0: the unworn Hertz contact at every stage), beyond the default 3 %
    monkeypatch.setattr(compare_mod, "solve_case", analytic_solver(pressure_factor=1.05))
    out = tmp_path / "cmp"
    code = cli_main(["compare", HERTZ, "--out", str(out), "--no-render", "--quiet"] + STAGES)
    assert code == 1
    assert "FAILED" in capsys.readouterr().err
    m = json.loads((out / "metrics.json").read_text())
    assert not m["passed"]
    for st in m["pairs"]["fem"]["stages"]:
        assert st["pressure_interior_max"] == pytest.approx(0.05, abs=1e-3)
        assert not st["checks"]["pressure_interior_max"]["passed"]
        assert st["checks"]["force"]["passed"]
    md = (out / "report.md").read_text()
    assert "**FAIL**" in md and "stage 0 (ŝ=0) pressure 0.05 > 0.03 of the stage's own" in md


def test_a_solver_that_cannot_run_the_case_is_listed_as_skipped(tmp_path, monkeypatch,
                                                                capsys):
    # an elastic counterface: the FEM (an elastic sphere on a rigid plane) cannot run
    # it, so MDR and BEM are compared and the FEM is named, with its reason, everywhere
    monkeypatch.setattr(compare_mod, "solve_case", analytic_solver())
    out = tmp_path / "cmp"
    code = cli_main(["compare", HERTZ, "--out", str(out), "--no-render",
                     "--set", "counterface.rigid=false",
                     "--set", "counterface.youngs_modulus=210e9",
                     "--set", "counterface.poisson_ratio=0.3"] + STAGES)
    assert code == 0
    reason = registry.get("fem").supports(cases.load(HERTZ, [
        "counterface.rigid=false", "counterface.youngs_modulus=210e9",
        "counterface.poisson_ratio=0.3"]))
    assert reason.startswith("counterface.rigid = false")
    m = json.loads((out / "metrics.json").read_text())
    assert m["solvers"] == ["mdr", "bem"] and m["skipped"]["fem"] == reason
    # every other registered solver is listed too (CalculiX: the same model limit)
    assert set(m["skipped"]) == set(registry.names()) - {"mdr", "bem"}
    assert f"skipped FEM: {reason}" in capsys.readouterr().err
    assert f"Skipped: FEM — {reason}" in (out / "report.md").read_text()


@pytest.mark.parametrize("executable", ["ccx", "/nowhere/ccx"])
def test_calculix_is_listed_as_opt_in_or_with_why_it_cannot_run(tmp_path, monkeypatch,
                                                                  capsys, executable):
    # CalculiX runs only when named: a plain compare lists it as opt-in when it could run
    # here, and with supports()'s reason (the key and the install line) when it cannot
    monkeypatch.setattr(compare_mod, "solve_case", analytic_solver())
    out = tmp_path / "cmp"
    sets = ["--set", f"ccx.executable={executable}"]
    assert cli_main(["compare", HERTZ, "--out", str(out), "--no-render", "--solvers",
                     "mdr,fem"] + sets + STAGES) == 0
    reason = registry.get("ccx").supports(cases.load(HERTZ, [f"ccx.executable={executable}"]))
    m = json.loads((out / "metrics.json").read_text())
    if reason is None:
        assert m["skipped"]["ccx"].startswith("opt-in (an external program): name it")
        assert "--solvers mdr,fem,ccx" in m["skipped"]["ccx"]
    else:
        assert m["skipped"]["ccx"] == reason
    if executable.startswith("/nowhere"):
        assert "apt-get install calculix-ccx" in m["skipped"]["ccx"]
    assert f"skipped CalculiX: {m['skipped']['ccx']}" in capsys.readouterr().err
    assert f"CalculiX — {m['skipped']['ccx']}" in (out / "report.md").read_text()


def test_truncated_case_is_checked_against_the_reference(tmp_path, monkeypatch):
    monkeypatch.setattr(compare_mod, "solve_case", analytic_solver())
    out = tmp_path / "trunc"
    code = cli_main(["compare", TRUNCATED, "--out", str(out), "--no-render", "--quiet",
                     "--set", "mdr.elements=200", "--set", "fem.contact_nodes=60"])
    assert code == 0
    m = json.loads((out / "metrics.json").read_text())
    tr = m["truncated_reference"]
    # the stand-in returns the reference itself: differences are interpolation-free zeros
    for name in ("mdr", "fem"):
        assert tr["solvers"][name]["pressure_interior_max"] < 1e-12
    assert "Fig. 3" in (out / "report.md").read_text()


def test_an_error_leaves_no_directory(tmp_path, monkeypatch):
    def broken(case, name, progress=None):
        raise cases.SolverError("diverged on purpose")
    monkeypatch.setattr(compare_mod, "solve_case", broken)
    out = tmp_path / "cmp"
    code = cli_main(["compare", HERTZ, "--out", str(out), "--quiet"])
    assert code == cases.SolverError.exit_code
    assert not out.exists() and list(tmp_path.iterdir()) == []


# -- the real solvers --------------------------------------------------------

PAPER = str(cases.shipped("paper"))
# ŝ = 1 is reached after s = 1 / s_hat_per_m ≈ 0.029 m on paper.toml. Both solvers take
# the same step Δŝ = 0.05, so that their (first-order) time errors match and the
# comparison measures the spatial models (with MDR's auto step 0.1 against FEM's 0.02,
# the time error alone is ~0.8 % d of the 1 % d profile budget).
SMALL = ["--set", "stages.s_hat=[0.0, 0.5, 1.0]", "--set", 'sliding.until="distance"',
         "--set", "sliding.distance=0.03", "--set", "sliding.step_hat=0.05",
         "--set", "mdr.elements=200", "--set", "fem.contact_nodes=60", "--no-render",
         "--quiet"]


def test_real_solvers_agree_on_a_small_paper_case(tmp_path):
    out = tmp_path / "small"
    code = cli_main(["compare", PAPER, "--out", str(out)] + SMALL)
    m = json.loads((out / "metrics.json").read_text())
    assert m["stages_compared"] == 3
    # at this resolution the two independent solvers must still agree within the
    # case's default tolerances, relative to each stage's own scale (1 % of its depth,
    # 3 % of its force, 3 % of its peak pressure in the interior, 2 % of its contact radius)
    assert code == 0 and m["passed"], [st["checks"] for st in m["pairs"]["fem"]["stages"]]
    # the worn profiles genuinely changed between stages: the test compares wear, not
    # three copies of the unworn contact (wear at r = 0 is > 10 % of d by ŝ = 1)
    run = runio.Run(out / "mdr")
    assert run.stages["f"][2][0] - run.stages["f"][0][0] > 0.1 * 1e-6


def test_real_solvers_made_to_disagree_fail_with_exit_code_1(tmp_path, capsys):
    # The coarsest MDR grid the solver accepts (mdr.resolution: 10 cells in the contact):
    # N = 32 cells uniform in t = r² on L² = 3.125 a0² put n0 = 10.24 in the contact,
    # the first one r < h with h² = a0²/n0. The comparison interpolates the profile
    # f = r²/2R linearly in r between nodes, which over [0, h] errs by h²/(8R) =
    # d/(8 n0) = 0.0122 d (d = a0²/R), past the 1 % d profile tolerance before any
    # error of the solve itself: the comparison must fail on the profile
    out = tmp_path / "coarse"
    code = cli_main(["compare", PAPER, "--out", str(out)] + SMALL
                    + ["--set", "mdr.elements=32"])
    assert code == 1
    assert "FAILED" in capsys.readouterr().err
    m = json.loads((out / "metrics.json").read_text())
    assert not m["passed"]
    assert not m["pairs"]["fem"]["stages"][0]["checks"]["profile_contact_max"]["passed"]
    md = (out / "report.md").read_text()
    assert "**FAIL**" in md
    # the reference is the coarse one here: its resolution key is the fix named, with its
    # value, in metrics.json and in the report (its ~10 cells against the FEM's 34 nodes
    # across the contact radius)
    assert (m["diagnosis"]["setting"], m["diagnosis"]["value"]) == ("mdr.elements", 32)
    assert "Most likely fix: raise mdr.elements (now 32; try 64): MDR has" in md


def test_a_quiet_failing_comparison_still_names_its_fix(tmp_path, capsys):
    # --quiet drops the summary, which names the fix; the FAIL line must still carry it
    # (the same coarse MDR as above)
    code = cli_main(["compare", PAPER, "--out", str(tmp_path / "coarse"), "--quiet",
                     "--no-render", "--solvers", "mdr,fem"] + SMALL
                    + ["--set", "mdr.elements=32"])
    assert code == 1
    err = capsys.readouterr().err
    assert "FAILED" in err and "most likely fix: raise mdr.elements (now 32; try 64)" in err


def test_real_solvers_match_the_flattened_sphere_reference(tmp_path):
    # paper Fig. 3: each solver against the quadrature of paper Eqs. 13/19, away from
    # the singularity at r = b and from the edge, within the default 2 % p0 and 1 % F0
    out = tmp_path / "trunc"
    code = cli_main(["compare", TRUNCATED, "--out", str(out), "--set", "mdr.elements=200",
                     "--set", "fem.contact_nodes=80", "--no-render", "--quiet"])
    m = json.loads((out / "metrics.json").read_text())
    tr = m["truncated_reference"]
    # every registered solver that supports the case (the BEM too, at its default grid)
    assert set(tr["solvers"]) == {"mdr", "fem", "bem"}
    for name, v in tr["solvers"].items():
        assert v["pressure_interior_max"] < 0.02, name
        assert v["force"] < 0.01, name
    assert code == 0 and m["passed"]


def _flat_result(case, r, p):
    sc = reference.scales(case)
    s = np.array([0.0])
    hist = dict(s=s, force=np.array([sc["F0"]]), depth=np.array([sc["d0"]]),
                contact_radius=np.array([sc["a0"]]), wear_center=np.zeros(1),
                wear_volume=np.zeros(1))
    return RunResult(history=hist, stage_s=s, r=r, f=profiles.height(case.indenter, r)[None],
                     p=p[None], solve_seconds=0.0)


def test_cone_tip_singularity_is_left_out_of_the_pressure_check():
    case = cases.from_dict({
        "indenter": {"profile": "cone", "slope_angle": 0.0064, "youngs_modulus": 210e9,
                     "poisson_ratio": 0.3},
        "loading": {"control": "depth", "depth": 1e-6},
        "wear": {"k": 1e-4, "mu": 0.3, "hardness": 2e9}})
    sc = reference.scales(case)
    a0, p0 = sc["a0"], sc["p0"]
    r = np.linspace(0.0, 1.5 * a0, 301)
    # the exact cone pressure (E*/2) tan θ acosh(a/r), infinite at r = 0
    p = case.E_star / 2 * np.tan(0.0064) * np.arccosh(np.clip(a0 / np.maximum(r, 1e-30), 1, None))
    p[0] = 50 * p0
    near_tip = p.copy()
    near_tip[1:5] *= 1.5            # r < 0.02 a0: inside the excluded tip band
    away = p.copy()
    # r = 0.5 a0: a real difference of 5 % of the stage's peak pressure outside the tip
    # band (there the largest p is at the band's edge r = 0.1 a0, ≈ 2 p0)
    peak = p[r >= 0.1 * a0].max()
    away[100] += 0.05 * peak
    ok = compare_mod.analyse(case, {"mdr": _flat_result(case, r, p),
                                    "fem": _flat_result(case, r, near_tip)})
    bad = compare_mod.analyse(case, {"mdr": _flat_result(case, r, p),
                                     "fem": _flat_result(case, r, away)})
    assert ok["passed"] and not bad["passed"]
