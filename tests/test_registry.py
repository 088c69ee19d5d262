"""The solver registry: a solver plugs in with one entry, and compare, run and refine
take it without any other change.

The toy solver is Hertz's closed form (``cases.reference``), registered from
this file: it supports the unworn paraboloid only and says why otherwise.
"""

import json

import numpy as np
import pytest

import wearcheck
from wearcheck import cases
from wearcheck.cases import RunResult, reference
from wearcheck import registry
from wearcheck.cli import main as cli_main

HERTZ = cases.shipped("hertz")
PAPER = cases.shipped("paper")


def _hertz_supports(case):
    if case.indenter.profile != "paraboloid":
        return f"Hertz's solution is for a paraboloid, not \"{case.indenter.profile}\""
    if any(s > 0 for s in case.stages.s_hat) or case.sliding.until != "distance" \
            or case.sliding.distance != 0.0:
        return "Hertz's solution is the unworn contact only (no sliding)"
    return None


def _hertz_solve(case, progress=None, pressure_factor=1.0):
    sc = reference.scales(case)
    a0, R = sc["a0"], case.indenter.radius
    r = np.linspace(0.0, 1.5 * a0, 301)
    p = pressure_factor * reference.hertz_pressure(r, case.E_star, R, a0)
    history = dict(s=np.zeros(1), force=np.array([sc["F0"]]), depth=np.array([sc["d0"]]),
                   contact_radius=np.array([a0]), wear_center=np.zeros(1),
                   wear_volume=np.zeros(1))
    if progress is not None:
        progress(1.0)
    return RunResult(history=history, stage_s=np.zeros(1), r=r, f=(r * r / (2 * R))[None, :],
                     p=p[None, :], solve_seconds=0.0, info={"closed_form": "Hertz"})


@pytest.fixture
def toy():
    entry = registry.register(registry.Solver(
        name="hertz", title="Hertz", solve_function=_hertz_solve,
        supports_function=_hertz_supports, description="Hertz's closed form (toy)",
        style=dict(ls="none", marker="s", ms=3)))
    yield entry
    registry.unregister("hertz")


def test_a_registered_solver_is_compared_by_name(toy, tmp_path):
    # MDR at N = 800 against Hertz: the unworn contact is MDR's exact solution up to
    # its grid, which docs/performance.md puts at ~1e-4 p0 (spatial error 2.3e-5 in F/F0):
    # the default tolerances (2 % p0, 1 % F0, 2 % a0) must pass, and the toy's
    # results must arrive under its own name everywhere.
    case = wearcheck.load_case(HERTZ)
    assert "hertz" in wearcheck.solvers(case) and "hertz" not in wearcheck.solvers(
        wearcheck.load_case(PAPER))
    m = wearcheck.compare(case, tmp_path / "cmp", solvers=["mdr", "hertz"], render=False)
    assert m["passed"] and m["solvers"] == ["mdr", "hertz"] and list(m["pairs"]) == ["hertz"]
    stage = m["pairs"]["hertz"]["stages"][0]
    assert stage["force"] < 1e-3 and stage["pressure_interior_max"] < 5e-3
    written = json.loads((tmp_path / "cmp" / "metrics.json").read_text())
    assert written["pairs"]["hertz"]["passed"]
    assert wearcheck.read_run(tmp_path / "cmp" / "hertz").info["closed_form"] == "Hertz"
    report = (tmp_path / "cmp" / "report.md").read_text()
    assert "Hertz against MDR" in report


def test_the_toy_can_be_the_reference_and_a_wrong_toy_fails(toy, tmp_path):
    wrong = registry.register(registry.Solver(
        name="hertz5", title="Hertz +5 %", supports_function=_hertz_supports,
        solve_function=lambda c, progress=None: _hertz_solve(c, progress, 1.05)))
    try:
        m = wearcheck.compare(HERTZ, tmp_path / "cmp", solvers=["hertz", "hertz5"],
                              reference_solver="hertz", render=False)
    finally:
        registry.unregister(wrong.name)
    # 5 % more pressure everywhere: 0.05 p0 at the centre, beyond the 2 % tolerance
    assert not m["passed"]
    assert m["pairs"]["hertz5"]["stages"][0]["pressure_interior_max"] == pytest.approx(0.05,
                                                                                      rel=1e-3)


def test_the_command_line_knows_registered_solvers(toy, tmp_path, capsys):
    out = tmp_path / "run"
    assert cli_main(["run", str(HERTZ), "--solver", "hertz", "--out", str(out), "--quiet"]) == 0
    assert json.loads((out / "meta.json").read_text())["solver"] == "hertz"
    # a case the toy does not support: one line with its reason, exit 2
    assert cli_main(["run", str(PAPER), "--solver", "hertz", "--quiet",
                     "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "cannot run this case" in err and "paraboloid, not \"sphere\"" in err
    assert not (tmp_path / "x").exists()
    assert cli_main(["run", str(HERTZ), "--solver", "nonsense", "--quiet"]) == 2
    assert "must be one of " + ", ".join(registry.names()) in capsys.readouterr().err
    assert registry.names()[-1] == "hertz"   # the toy, registered last


def test_compare_needs_two_supporting_solvers(tmp_path):
    # an elastic counterface: the FEM (rigid plane) declines; MDR and the BEM
    # (E* of both bodies) run it, but MDR alone cannot compare
    case = wearcheck.load_case(HERTZ, {"counterface.rigid": False,
                                       "counterface.youngs_modulus": 210e9,
                                       "counterface.poisson_ratio": 0.3})
    assert wearcheck.solvers(case) == ("mdr", "bem")
    # mdr named alone: the refusal names those that could join it (it said "only mdr
    # can", with bem "not among the solvers asked for", although bem can)
    with pytest.raises(cases.CaseError, match=r"two solvers; only mdr was named \(those that "
                                              r"can run this case: mdr, bem\)"):
        wearcheck.compare(case, tmp_path / "cmp", solvers=["mdr"])
    assert not (tmp_path / "cmp").exists()


def test_registering_twice_is_refused(toy):
    with pytest.raises(ValueError, match="registered already"):
        registry.register(toy)
    with pytest.raises(ValueError, match="module or solve_function"):
        registry.register(registry.Solver(name="empty", title="Empty"))


@pytest.mark.parametrize("failure", [
    np.linalg.LinAlgError("SVD did not converge in Linear Least Squares"),
    OverflowError("cannot convert float infinity to integer"),
    FloatingPointError("overflow encountered in multiply"),
])
def test_a_solver_whose_numbers_break_down_is_a_numerical_failure(tmp_path, capsys, failure):
    """``wearcheck run paper --solver mdr --set indenter.youngs_modulus=1e300`` (and
    1e-300) ended as exit 70, "internal error ... (a bug in wearcheck)": an SVD in the
    GMRES least squares, and int(inf), broke down on numbers out of range. A breakdown
    of the arithmetic is a numerical failure (docs/cli.md: exit 3, one line), not a bug."""
    def breaks(case, progress=None):
        raise failure
    registry.register(registry.Solver(name="brittle", title="Brittle", solve_function=breaks))
    try:
        with pytest.raises(cases.SolverError, match="brittle.*numerical failure"):
            wearcheck.solve(cases.load(HERTZ), "brittle")
        out = tmp_path / "run"
        assert cli_main(["run", str(HERTZ), "--solver", "brittle", "--out", str(out),
                         "--quiet"]) == 3
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and type(failure).__name__ in err
        assert not out.exists()
    finally:
        registry.unregister("brittle")
