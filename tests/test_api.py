"""The Python API as a notebook uses it: what it accepts, what it refuses, and that it
says so (found by a reviewer trying it as a new user)."""

from pathlib import Path

import numpy as np
import pytest

import wearcheck
from wearcheck import cases
import wearcheck.cases.schema  # noqa: F401
from wearcheck.cases import RunResult
from wearcheck.registry import Solver, register, unregister


def test_progress_callable_receives_the_fraction():
    seen = []
    wearcheck.solve(wearcheck.load_case("hertz", {"mdr.elements": 100}), "mdr",
                    progress=seen.append)
    assert seen and seen[-1] == 1.0 and all(0.0 <= f <= 1.0 for f in seen)


def test_numpy_values_are_taken_as_python_values():
    case = wearcheck.load_case("paper", {"mdr.elements": np.int64(400),
                                         "wear.mu": np.float32(0.25),
                                         "stages.s_hat": np.array([0.0, 1.0])})
    assert case.mdr.elements == 400 and case.stages.s_hat == (0.0, 1.0)
    assert case.wear.mu == pytest.approx(0.25)


def test_keyword_changes_win_over_a_mapping_and_a_list_alike():
    case = wearcheck.load_case("paper")
    assert case.derive({"wear.mu": 0.4}, wear__mu=0.6).wear.mu == 0.6
    assert case.derive(["wear.mu=0.4"], wear__mu=0.6).wear.mu == 0.6


def test_a_relative_table_file_is_relative_to_the_working_directory(tmp_path, monkeypatch):
    r = np.linspace(0, 4e-4, 41)
    (tmp_path / "prof.csv").write_text("\n".join(f"{a:.17g},{a * a / 0.02:.17g}" for a in r))
    monkeypatch.chdir(tmp_path)
    case = wearcheck.load_case("paper", {"indenter.profile": "table",
                                         "indenter.file": "prof.csv"})
    assert case.table is not None and len(case.table[0]) == 41


def test_unreached_stages_are_said(recwarn):
    case = wearcheck.load_case("hertz", {"mdr.elements": 100, "stages.s_hat": [0.0, 5.0]})
    result = wearcheck.solve(case, "mdr")  # hertz.toml does not slide: ŝ = 5 is never reached
    assert len(result.stages["s"]) == 1
    assert any("ŝ = 5" in w for w in result.warnings)
    assert any("ŝ = 5" in str(w.message) for w in recwarn)


def test_result_repr_is_one_line():
    text = repr(wearcheck.solve(wearcheck.load_case("hertz", {"mdr.elements": 100}), "mdr"))
    assert "\n" not in text and len(text) < 200 and "solver='mdr'" in text


def test_read_run_of_a_missing_directory(tmp_path):
    with pytest.raises(cases.CaseError, match="does not exist"):
        wearcheck.read_run(tmp_path / "nothing")


def test_compare_names_solvers_as_a_string_or_list(tmp_path):
    # "fem" is one solver, not three letters; the refusal names those that can join it
    with pytest.raises(cases.CaseError, match=r"only fem was named \(those that can run "
                                              r"this case: mdr, fem"):
        wearcheck.compare("hertz", tmp_path / "a", solvers="fem")
    with pytest.raises(cases.CaseError, match="solvers = \\[\\]"):
        wearcheck.compare("hertz", tmp_path / "b", solvers=[])
    with pytest.raises(cases.CaseError, match="reference solver 'mdr': not among"):
        wearcheck.compare("hertz", tmp_path / "c", solvers=["fem", "fem"],
                          reference_solver="mdr")


def _early(case, progress=None):
    """A solver that stops after its first stage, whatever the case asks."""
    real = wearcheck.registry.get("mdr").solve(case)
    return RunResult(history={k: v[:1] for k, v in real.history.items()},
                     stage_s=real.stage_s[:1], r=real.r, f=real.f[:1], p=real.p[:1],
                     solve_seconds=0.0)


def test_a_solver_that_stops_early_fails_the_comparison(tmp_path):
    register(Solver(name="early", title="Early", solve_function=_early))
    try:
        case = wearcheck.load_case("paper", {"mdr.elements": 200,
                                             "stages.s_hat": [0.0, 0.5, 1.0]})
        m = wearcheck.compare(case, tmp_path / "cmp", solvers=["mdr", "early"], render=False)
    finally:
        unregister("early")
    # its first stage is MDR's own, so every difference there is zero ...
    assert m["pairs"]["early"]["stages"][0]["passed"]
    # ... but it reached 1 of 3 stages: that alone fails
    assert not m["passed"]
    assert m["pairs"]["early"]["checks"]["stages_reached"] == dict(value=1, tolerance=3,
                                                                    passed=False)
    assert "reached 1 stage(s), MDR 3" in (tmp_path / "cmp" / "report.md").read_text()


def test_plugins_are_checked():
    with pytest.raises(ValueError, match="lower-case"):
        register(Solver(name="bad name/with slash", title="x", solve_function=_early))
    with pytest.raises(ValueError, match="not declared in cases/schema.py"):
        register(Solver(name="sec", title="x", section="sec", solve_function=_early))
    register(Solver(name="none", title="None", solve_function=lambda c, progress=None: None))
    try:
        with pytest.raises(TypeError, match="returned NoneType, not a wearcheck RunResult"):
            wearcheck.solve("hertz", "none")
    finally:
        unregister("none")


def test_undeclared_history_columns_are_listed_in_the_dictionary(tmp_path):
    def extra(case, progress=None):
        r = wearcheck.registry.get("mdr").solve(case)
        r.history["my_extra"] = np.zeros_like(r.history["s"])
        return r
    register(Solver(name="extra", title="Extra", solve_function=extra))
    try:
        path = wearcheck.solve(wearcheck.load_case("hertz", {"mdr.elements": 100}),
                               "extra").write(tmp_path / "run")
    finally:
        unregister("extra")
    d = wearcheck.read_run(path).meta["data_dictionary"]["history_csv"]
    assert "not declared" in d["my_extra"]["meaning"]


def test_studies_refuse_bad_input_before_starting_dask(tmp_path, monkeypatch):
    from wearcheck.studies import distributed

    def no_cluster(*args, **kwargs):
        raise AssertionError("a Dask cluster was started")
    monkeypatch.setattr(distributed, "_Client", no_cluster)
    for kwargs, pattern in (
            (dict(levels=[100.5, 200]), "100.5 is not a whole number"),
            (dict(levels=[200]), "at least two levels"),
            (dict(levels=[1, 200]), r"mdr\.elements.*= 1"),
            (dict(levels=np.array([100, 200]), solver="nope"), "solver 'nope'")):
        with pytest.raises(cases.CaseError, match=pattern):
            wearcheck.refine("hertz", tmp_path / "r", **kwargs)
    for vary, pattern in (({"wear.mu": -1.0}, r"wear\.mu.*> 0"),
                          ({"sliding.scheme": "bdf3"}, r"sliding\.scheme.*\"bdf3\"")):
        with pytest.raises(cases.CaseError, match=pattern):
            wearcheck.sweep("hertz", vary, tmp_path / "s")
    with pytest.raises(cases.CaseError, match="solver 'nope'"):
        wearcheck.sweep("hertz", {"wear.mu": 0.3}, tmp_path / "s", solver="nope")
    assert not (tmp_path / "r").exists() and not (tmp_path / "s").exists()


def test_sweep_values_are_single_values_and_come_back_typed(tmp_path):
    rows = wearcheck.sweep(wearcheck.load_case("hertz", {"mdr.elements": 100}),
                           {"sliding.scheme": "bdf2", "wear.mu": 0.3}, tmp_path / "s",
                           workers=1)
    assert len(rows) == 1 and rows[0]["status"] == "ok"
    assert rows[0]["sliding.scheme"] == "bdf2" and rows[0]["wear.mu"] == 0.3


@pytest.mark.parametrize("name", sorted(wearcheck.shipped_cases()))
def test_every_shipped_case_derives_to_itself(name):
    """A derived case with nothing changed is the case (to_dict inverts from_dict)."""
    case = wearcheck.load_case(name)
    same = case.derive({"wear.mu": case.wear.mu})
    for section in cases.schema.SECTIONS:
        assert getattr(same, section) == getattr(case, section), section


@pytest.mark.parametrize("solver", ["mdr", "bem"])
def test_runs_past_the_caps_are_refused_before_solving(solver):
    # ŝ per metre of the paper case is 34.6: 1e12 m is ŝ = 3.5e13, past the cap of 1e9
    case = wearcheck.load_case("paper", {"sliding.until": "distance",
                                         "sliding.distance": 1e12})
    with pytest.raises(cases.CaseError, match=r"sliding\.distance.*exceeds the solver's cap"):
        wearcheck.solve(case, solver)
    fixed = case.derive({"sliding.scheme": "implicit", "sliding.step_hat": 1e-3,
                         "sliding.distance": 200.0})  # ŝ = 6924: 6.9e6 steps of 1e-3
    with pytest.raises(cases.CaseError, match=r"sliding\.step_hat.*steps \(cap"):
        wearcheck.solve(fixed, solver)


def test_a_comparison_or_study_is_named_as_such_not_as_a_damaged_run(tmp_path, capsys):
    """``wearcheck export runs/paper`` right after ``compare`` (a reviewer's first try)
    said "not a complete run directory (no meta.json)", and on a study "meta.json is
    damaged": neither is damaged, they are not runs. The message names the runs inside."""
    from wearcheck.cli import main
    from wearcheck.outputs import atomic_directory, study_directory
    result = wearcheck.solve(wearcheck.load_case("hertz", {"mdr.elements": 60}), "mdr")
    with atomic_directory(tmp_path / "cmp", "comparison") as tmp:
        result.write(tmp / "mdr")
    study = study_directory(tmp_path / "study")
    result.write(study / "mdr-elements-60")
    (study / "meta.json").write_text('{"command": "wearcheck sweep"}')  # a study's own meta
    for out, kind, run in [("cmp", "comparison", "mdr"), ("study", "study", "mdr-elements-60")]:
        with pytest.raises(cases.CaseError, match=f"is a wearcheck {kind} directory, not a run"):
            wearcheck.read_run(tmp_path / out)
        for command in ("export", "render"):
            assert main([command, str(tmp_path / out)]) == 2
            err = capsys.readouterr().err
            assert err.count("\n") == 1 and f"{kind} directory" in err
            assert str(tmp_path / out / run) in err     # where the user should point instead
        assert wearcheck.read_run(tmp_path / out / run).solver == "mdr"
    (tmp_path / "file").write_text("x")
    with pytest.raises(cases.CaseError, match="is a file, not a run directory"):
        wearcheck.read_run(tmp_path / "file")


def test_compare_takes_solvers_as_the_command_line_writes_them(tmp_path):
    """``solvers="mdr,fem"`` (as ``--solvers mdr,fem``) was one solver named 'mdr,fem'."""
    with pytest.raises(cases.CaseError, match="solver 'nonsense': must be one of"):
        wearcheck.compare("hertz", tmp_path / "a", solvers="mdr, nonsense")
    metrics = wearcheck.compare(wearcheck.load_case("hertz", {"mdr.elements": 100,
                                                              "fem.contact_nodes": 40}),
                                tmp_path / "b", solvers="mdr,fem", render=False)
    assert metrics["solvers"] == ["mdr", "fem"]


def test_a_reference_that_cannot_run_the_case_says_why(tmp_path):
    """``compare ellipsoid --reference fem`` said only "not among the compared solvers
    (mdr, bem)"; the FEM is left out because it is axisymmetric, which is the answer."""
    with pytest.raises(cases.CaseError, match="not among the compared solvers.*it cannot "
                                              "run this case: .*axisymmetric"):
        wearcheck.compare("ellipsoid", tmp_path / "c", reference_solver="fem")
    assert not (tmp_path / "c").exists()


@pytest.mark.parametrize("solver", ["mdr", "fem"])
def test_a_run_that_reaches_no_stage_is_a_result_with_none(tmp_path, solver):
    """The paper case ends once F < 1 % F0, at ŝ ≈ 11.25: stages at ŝ = 20 and 30 are
    never reached. The MDR returned its empty stage table as (0, 0) and the run ended
    as exit 70 ("f has shape (0, 0), expected (0, 801)", a bug); now a run with no
    stage, as the FEM's and BEM's are, said in its warnings."""
    case = wearcheck.load_case("paper", {"mdr.elements": 100, "fem.contact_nodes": 40,
                                         "stages.s_hat": [20.0, 30.0]})
    with pytest.warns(UserWarning, match="ŝ = 20, 30"):
        result = wearcheck.solve(case, solver)
    assert result.stages["f"].shape == (0, len(result.stages["r"]))
    assert result.stages["p"].shape == result.stages["f"].shape
    assert any("ŝ = 20" in w for w in result.warnings)
    back = wearcheck.read_run(result.write(tmp_path / solver))
    assert back.stages["f"].shape[0] == 0 and back.meta["stages_reached"] == 0


def test_changes_in_the_shape_of_the_case_file_are_taken():
    """``{"wear": {"mu": 0.5}}`` (a TOML table as Python reads it) said "key 'wear': must be
    section.key": it is the same change as {"wear.mu": 0.5}."""
    case = wearcheck.load_case("paper", {"wear": {"mu": 0.5, "k": 2e-4}})
    assert (case.wear.mu, case.wear.k) == (0.5, 2e-4)
    with pytest.raises(cases.CaseError, match="unknown key 'wear.muu'"):
        wearcheck.load_case("paper", {"wear": {"muu": 0.5}})


def test_studies_take_their_arguments_as_the_command_line_writes_them(tmp_path, monkeypatch):
    """``sweep(case, "wear.mu=0.2,0.3", out)`` was an AttributeError, ``refine(...,
    levels="50,100")`` a ValueError, and ``sweep(case, {}, out)`` started a cluster."""
    from wearcheck.studies import refine as refine_mod, sweep as sweep_mod
    seen = {}

    def no_cluster(case, tasks, out, **kwargs):
        seen[Path(out).name] = [t.changes for t in tasks]
        raise KeyboardInterrupt   # stop here: the tasks are what is checked
    for module in (sweep_mod, refine_mod):
        monkeypatch.setattr(module, "run_cases", no_cluster)
    for name, call in (("s", lambda o: wearcheck.sweep("hertz", "wear.mu=0.2,0.3", o)),
                       ("t", lambda o: wearcheck.sweep("hertz", ["wear.mu=0.2", "wear.k=1e-5"], o)),
                       ("r", lambda o: wearcheck.refine("hertz", o, "mdr", levels="50,100"))):
        with pytest.raises(KeyboardInterrupt):
            call(tmp_path / name)
    assert seen["s"] == [{"wear.mu": 0.2}, {"wear.mu": 0.3}]
    assert seen["t"] == [{"wear.mu": 0.2, "wear.k": 1e-5}]
    assert seen["r"] == [{"mdr.elements": 100}, {"mdr.elements": 50}]   # finest first
    for vary in ({}, 5):
        with pytest.raises(cases.CaseError, match="vary"):
            wearcheck.sweep("hertz", vary, tmp_path / "x")
    with pytest.raises(cases.CaseError, match="levels = '50,abc'"):
        wearcheck.refine("hertz", tmp_path / "y", "mdr", levels="50,abc")
