"""Parameter sweeps: one run directory per value, a summary row per run."""

from __future__ import annotations

import csv
import json
import sys

import cloudpickle
import numpy as np
import pytest

import wearcheck
from wearcheck import cases
from wearcheck.cases import reference
from wearcheck.cases.case import parse_vary, split_values
from wearcheck.studies.sweep import sweep
from wearcheck.rundir import Run

# the stand-in solvers below travel to the Dask workers by value, so the
# workers need not import this test module
cloudpickle.register_pickle_by_value(sys.modules[__name__])


def fake_solve(case, solver, progress=None):
    """A stand-in solver: the force falls as exp(-ŝ) up to ŝ = 2 (SI history)."""
    sc = reference.scales(case)
    s_hat = np.linspace(0.0, 2.0, 21)
    r = np.linspace(0.0, 2.0 * sc["a0"], 11)
    stage = np.array([0.0])
    hist = dict(s=s_hat / sc["s_hat_per_m"], force=sc["F0"] * np.exp(-s_hat),
                depth=np.full_like(s_hat, sc["d0"]), contact_radius=np.full_like(s_hat, sc["a0"]),
                wear_center=np.zeros_like(s_hat), wear_volume=np.zeros_like(s_hat))
    return cases.RunResult(history=hist, stage_s=stage, r=r, f=np.zeros((1, 11)),
                           p=np.zeros((1, 11)), solve_seconds=1e-3)


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as c:
        yield c.scheduler_address


def test_vary_values_split_like_set():
    assert split_values("1e-5, 1e-4,1e-3") == ["1e-5", "1e-4", "1e-3"]
    assert split_values("[0.0, 1.0],[0.0, 2.0]") == ["[0.0, 1.0]", "[0.0, 2.0]"]
    assert parse_vary("loading.control=depth,force") == ("loading.control", ["depth", "force"])
    # typed once, as --set types a value
    assert parse_vary("stages.s_hat=[0, 1],[0.0, 2.0]") == ("stages.s_hat", [[0, 1], [0.0, 2.0]])
    assert parse_vary("wear.k=1e-5,2") == ("wear.k", [1e-5, 2])
    for bad in ("wear.k", "wear.kk=1,2", "nosection.k=1", "wear.k=1,,2"):
        with pytest.raises(cases.CaseError):
            parse_vary(bad)


def test_sweep_writes_one_run_per_value(cluster, tmp_path):
    out = tmp_path / "sweep"
    # 2 x 2 x 2 combinations; sliding.until = "distance" is a fine value whose
    # runs fail (the case gives no sliding.distance): error rows, no directory
    rows = sweep(cases.load(cases.shipped("paper")),
                 {"wear.k": [1e-5, 1e-4], "loading.depth": [1e-6, 2e-6],
                  "sliding.until": ["force_fraction", "distance"]},
                 "mdr", out, scheduler=cluster, quiet=True, solve=fake_solve)
    assert len(rows) == 8
    with open(out / "sweep.csv", newline="") as fh:
        table = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    assert [r["run"] for r in table] == [r["run"] for r in rows]
    for r in table:
        if r["sliding.until"] == "distance":
            assert "sliding.distance" in r["status"] and not (out / r["run"]).exists()
            continue
        assert r["status"] == "ok"
        run = Run(out / r["run"])  # a complete run directory, read back
        assert run.case.wear.k == float(r["wear.k"])
        assert run.case.loading.depth == float(r["loading.depth"])
        # the fake ends at ŝ = 2; s = ŝ / (k μ E*/(σ0 a0)) with a0 = sqrt(R d) (Hertz)
        E = run.case.E_star
        a0 = np.sqrt(run.case.indenter.radius * run.case.loading.depth)
        s_expected = 2.0 / (run.case.wear.k * 0.3 * E / (2e9 * a0))
        # the sphere's a0 differs from Hertz's by ~(a0/R)²/6 = 1.7e-5 relative
        assert float(r["final_s"]) == pytest.approx(s_expected, rel=1e-4)
    meta = json.loads((out / "meta.json").read_text())
    assert "sweep-mdr" in meta["studies"]


def test_mdr_sweep_over_the_wear_coefficient_is_self_similar(cluster, tmp_path):
    from wearcheck.cli import main
    out = tmp_path / "k"
    code = main(["sweep", str(cases.shipped("paper")), "--vary", "wear.k=1e-5,1e-4,1e-3",
                 "--solver", "mdr", "--out", str(out), "--set", "mdr.elements=50",
                 "--set", "sliding.force_fraction=0.3", "--scheduler", cluster, "--quiet"])
    assert code == 0
    with open(out / "sweep.csv", newline="") as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    assert [float(r["wear.k"]) for r in rows] == [1e-5, 1e-4, 1e-3]
    # Archard wear depends on k and s only through ŝ ∝ k s (docs/theory.md §5): the
    # runs are one solution in ŝ, so k·s at the end and F/F0 agree to rounding
    # (sweep.csv keeps 10 digits)
    ks = [float(r["wear.k"]) * float(r["final_s"]) for r in rows]
    assert np.allclose(ks, ks[0], rtol=1e-8, atol=0)
    fend = [float(r["final_F_over_F0"]) for r in rows]
    assert np.allclose(fend, fend[0], rtol=1e-8, atol=0)
    for r in rows:
        assert Run(out / r["run"]).case.wear.k == float(r["wear.k"])


@pytest.mark.parametrize("command, vary", [
    ("sweep", "wear.mu=0.3,a"),
    ("fretting-map", "fretting.amplitude=-1e-7,1e-7"),
])
def test_a_value_its_key_cannot_take_is_refused_before_the_cluster(tmp_path, capsys,
                                                                    monkeypatch, command, vary):
    # one line naming the key and the value, exit 2, no directory; the
    # cluster never starts (run_cases would)
    from wearcheck.cli import main as cli_main
    from wearcheck.studies import fretting_map, sweep as sweep_mod

    def no_cluster(*args, **kwargs):
        raise AssertionError("the cluster started")
    for module in (sweep_mod, fretting_map):
        monkeypatch.setattr(module, "run_cases", no_cluster)
    case = "hertz" if command == "sweep" else "fretting"
    out = tmp_path / "out"
    assert cli_main([command, case, "--vary", vary, "--out", str(out), "--quiet"]) == 2
    err = [l for l in capsys.readouterr().err.splitlines() if not l.startswith("note:")]
    key, _, values = vary.partition("=")
    assert len(err) == 1 and f"key '{key}'" in err[0]
    assert not out.exists()


@pytest.mark.parametrize("argv", [
    ["refine", "ellipsoid", "--solver", "fem", "--levels", "16,32"],
    ["sweep", "ellipsoid", "--solver", "fem", "--vary", "wear.k=1e-5,1e-4"],
])
def test_a_solver_that_cannot_run_the_case_is_refused_before_the_cluster(tmp_path, capsys,
                                                                         monkeypatch, argv):
    """The FEM cannot run the ellipsoid (it is axisymmetric), at any resolution or wear
    coefficient: refine and sweep started the cluster, wrote a study of error rows and
    ended with exit 1. Now refused like ``run``: one line with the reason, exit 2, no
    directory."""
    from wearcheck.cli import main as cli_main
    from wearcheck.studies import refine as refine_mod, sweep as sweep_mod

    def no_cluster(*args, **kwargs):
        raise AssertionError("the cluster started")
    for module in (sweep_mod, refine_mod):
        monkeypatch.setattr(module, "run_cases", no_cluster)
    out = tmp_path / "out"
    assert cli_main([*argv, "--out", str(out), "--quiet"]) == 2
    err = [l for l in capsys.readouterr().err.splitlines() if not l.startswith("note:")]
    assert len(err) == 1 and "solver 'fem' cannot run this case" in err[0]
    assert "axisymmetric" in err[0]
    assert not out.exists()


def test_a_sweep_holding_some_cases_the_solver_can_run_still_runs(cluster, tmp_path):
    """Varying the profile from the ellipsoid to a paraboloid: the FEM can run the
    paraboloid, so the sweep is not refused (the stand-in solver runs both)."""
    rows = sweep(cases.load(cases.shipped("ellipsoid")),
                 {"indenter.profile": ["ellipsoid", "paraboloid"]},
                 "fem", tmp_path / "s", scheduler=cluster, quiet=True, solve=fake_solve)
    assert {r["indenter.profile"]: r["status"] for r in rows} == {"ellipsoid": "ok",
                                                                   "paraboloid": "ok"}


def test_a_value_is_judged_with_the_other_varied_keys(tmp_path, monkeypatch):
    """``--vary loading.control=force --vary loading.force=1,2`` on a depth-controlled
    case was refused ("loading.force given but loading.control = depth"): the force is
    fine beside the varied control. A value wrong in every combination still is not."""
    from wearcheck.studies import sweep as sweep_mod
    seen = []

    def no_cluster(case, tasks, out, **kwargs):
        seen.extend(t.changes for t in tasks)
        raise KeyboardInterrupt
    monkeypatch.setattr(sweep_mod, "run_cases", no_cluster)
    hertz = cases.load(cases.shipped("hertz"))
    with pytest.raises(KeyboardInterrupt):
        sweep(hertz, {"loading.control": "force", "loading.force": [1, 2]}, "mdr",
              tmp_path / "s", quiet=True)
    assert seen == [{"loading.control": "force", "loading.force": 1},
                    {"loading.control": "force", "loading.force": 2}]
    with pytest.raises(cases.CaseError,
                       match=r"vary\['loading.force'\]: key 'loading.force' = -1"):
        sweep(hertz, {"loading.control": "force", "loading.force": [1, -1]}, "mdr",
              tmp_path / "t", quiet=True)


def _table(out):
    with open(out / "sweep.csv", newline="") as fh:
        return list(csv.DictReader(line for line in fh if not line.startswith("#")))


def test_a_second_sweep_into_a_study_keeps_the_first(cluster, tmp_path):
    """Issue 20: a second sweep replaced the first's sweep.csv and its meta.json entry.
    Now its runs join the first's table (more values, another key; a run done
    again replaces its row) and meta.json keeps both commands."""
    out = tmp_path / "s"
    paper = cases.load(cases.shipped("paper"))
    runs = []            # the run names of each sweep, as it returned them
    for vary in ({"wear.k": [1e-5, 1e-4]}, {"wear.k": [1e-4, 1e-3]}, {"wear.mu": [0.2]}):
        runs.append([r["run"] for r in sweep(paper, vary, "mdr", out, scheduler=cluster,
                                             quiet=True, solve=fake_solve)])
        if len(runs) == 1:
            first = {r["run"]: r for r in _table(out)}
    table = {r["run"]: r for r in _table(out)}
    # wear.k = 1e-4 run twice: one row
    assert sorted(table) == sorted({*runs[0], *runs[1], *runs[2]}) and len(table) == 4
    # the first sweep's row, as it wrote it; a key it did not vary holds the base value
    only_first, mu_run = runs[0][0], runs[2][0]
    assert table[only_first]["final_s"] == first[only_first]["final_s"]
    assert float(table[only_first]["wear.mu"]) == paper.wear.mu
    assert float(table[mu_run]["wear.k"]) == paper.wear.k
    for name, row in table.items():     # every row is its run directory's
        run = Run(out / name)
        assert run.case.wear.k == float(row["wear.k"])
        assert run.case.wear.mu == float(row["wear.mu"])
    entry = json.loads((out / "meta.json").read_text())["studies"]["sweep-mdr"]
    assert len(entry["earlier"]) == 2


@pytest.mark.parametrize("argv, what", [
    (["--set", "loading.depth=2e-6"], "loading.depth"),
    (["--solver", "bem"], "solver 'mdr'"),
])
def test_a_sweep_of_another_base_into_a_study_is_refused(cluster, tmp_path, capsys,
                                                         monkeypatch, argv, what):
    """One table for two different studies would pass for one: refused before the
    cluster starts, one line naming what differs; the first sweep untouched."""
    from wearcheck.cli import main as cli_main
    from wearcheck.studies import sweep as sweep_mod
    out = tmp_path / "s"
    paper = str(cases.shipped("paper"))
    sweep(cases.load(paper), {"wear.k": [1e-5, 1e-4]}, "mdr", out, scheduler=cluster,
          quiet=True, solve=fake_solve)
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}

    def no_cluster(*args, **kwargs):
        raise AssertionError("the cluster started")
    monkeypatch.setattr(sweep_mod, "run_cases", no_cluster)
    assert cli_main(["sweep", paper, "--vary", "wear.k=1e-3", "--out", str(out), "--quiet",
                     *argv]) == 2
    err = [l for l in capsys.readouterr().err.splitlines() if not l.startswith("note:")]
    assert len(err) == 1 and what in err[0], err
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before



def test_the_same_sweep_from_python_and_from_the_command_line_gives_the_same_runs(cluster,
                                                                                tmp_path):
    """The command line types its text once and hands the study what Python hands it:
    the same run directories, the same cases and the same histories, a list-valued key
    (stages.s_hat) included."""
    from wearcheck.cli import main
    cli_out, py_out = tmp_path / "cli", tmp_path / "py"
    assert main(["sweep", "hertz", "--set", "mdr.elements=50", "--vary", "wear.mu=0.2,0.3",
                 "--vary", "stages.s_hat=[0.0, 0.5],[0.0, 1.0]", "--scheduler", cluster,
                 "--out", str(cli_out), "--quiet"]) == 0
    rows = wearcheck.sweep(wearcheck.load_case("hertz", {"mdr.elements": 50}),
                           {"wear.mu": [0.2, 0.3], "stages.s_hat": [[0.0, 0.5], [0.0, 1.0]]},
                           py_out, scheduler=cluster)
    assert [(r["wear.mu"], r["stages.s_hat"]) for r in rows] == [
        (0.2, [0.0, 0.5]), (0.2, [0.0, 1.0]), (0.3, [0.0, 0.5]), (0.3, [0.0, 1.0])]
    with open(cli_out / "sweep.csv", newline="") as fh:
        cli_rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    assert [r["run"] for r in cli_rows] == [r["run"] for r in rows]
    assert all(r["status"] == "ok" for r in rows)
    for row in rows:
        a, b = Run(cli_out / row["run"]), Run(py_out / row["run"])
        for section in cases.schema.SECTIONS:
            assert getattr(a.case, section) == getattr(b.case, section), section
        assert b.case.wear.mu == row["wear.mu"]
        assert list(b.case.stages.s_hat) == row["stages.s_hat"]
        # one case, one solver, one code: the same numbers (the tolerance allows only
        # a different order of floating-point sums in another process)
        for column in ("s", "force", "wear_center"):
            np.testing.assert_allclose(a.history[column], b.history[column], rtol=1e-12)


@pytest.mark.parametrize("python, argv, said_in_python, said_on_the_command_line", [
    (lambda out: wearcheck.sweep("hertz", {"wear.mu": [0.3, -1.0]}, out),
     ["sweep", "hertz", "--vary", "wear.mu=0.3,-1.0"],
     "vary['wear.mu']: key 'wear.mu' = -1.0: must be > 0",
     "--vary wear.mu: key 'wear.mu' = -1.0: must be > 0"),
    (lambda out: wearcheck.sweep("hertz", {"wear.mu": [0.3]}, out, workers=-1),
     ["sweep", "hertz", "--vary", "wear.mu=0.3", "--workers", "-1"],
     "workers = -1: must be a whole number", "--workers -1: must be a whole number"),
    (lambda out: wearcheck.refine("hertz", out, levels=[20, 40], tolerance=0),
     ["refine", "hertz", "--levels", "20,40", "--tolerance", "0"],
     "tolerance = 0: must be a number > 0", "--tolerance 0.0: must be a number > 0"),
    (lambda out: wearcheck.refine("hertz", out, levels=[20, 40, 80], steps=[0.1, 0.2]),
     ["refine", "hertz", "--levels", "20,40,80", "--steps", "0.1,0.2"],
     "steps = [0.1, 0.2]: 2 steps for 3 levels:", "--steps 0.1,0.2: 2 steps for 3 --levels:"),
    (lambda out: wearcheck.refine("hertz", out, levels=[1, 40]),
     ["refine", "hertz", "--levels", "1,40"],
     "levels: key 'mdr.elements' = 1:", "--levels: key 'mdr.elements' = 1:"),
], ids=["vary", "workers", "tolerance", "steps", "levels"])
def test_study_errors_name_the_python_argument_or_the_flag(tmp_path, capsys, monkeypatch, python,
                                                          argv, said_in_python,
                                                          said_on_the_command_line):
    """Called from Python a study's error names the argument the caller wrote; only the
    command line's names its flag (it said --vary, --tolerance from Python too)."""
    from wearcheck.cli import main
    from wearcheck.studies import distributed

    def no_cluster(*args, **kwargs):
        raise AssertionError("the cluster started")
    monkeypatch.setattr(distributed, "_Client", no_cluster)
    with pytest.raises(cases.ArgumentError) as caught:
        python(tmp_path / "py")
    assert str(caught.value).startswith(said_in_python), str(caught.value)
    assert "--" not in str(caught.value)
    assert main([*argv, "--out", str(tmp_path / "cli"), "--quiet"]) == 2
    err = [l for l in capsys.readouterr().err.splitlines() if not l.startswith("note:")]
    assert len(err) == 1 and f"error: {said_on_the_command_line}" in err[0], err
    assert not (tmp_path / "py").exists() and not (tmp_path / "cli").exists()


def test_the_command_line_reads_a_varied_table_file_as_set_does(tmp_path, monkeypatch):
    """``--set indenter.file=t.csv`` is relative to the case file; so is ``--vary``'s, typed
    once on the command line. From Python a relative file is relative to the working
    directory (as ``Case.derive`` reads it), made absolute before it goes to a worker,
    whose working directory may differ."""
    from types import SimpleNamespace
    from wearcheck.cli._common import varied
    from wearcheck.studies.sweep import task_changes
    case_file = tmp_path / "sub" / "case.toml"
    args = SimpleNamespace(case=case_file, overrides=["wear.mu=0.3"],
                           vary=["indenter.file=a.csv,/abs/b.csv", "wear.k=1e-5"])
    assert varied(args) == {"indenter.file": [str(tmp_path / "sub" / "a.csv"), "/abs/b.csv"],
                            "wear.k": [1e-5]}
    args.vary.append("wear.mu=0.2")
    with pytest.raises(cases.CaseError, match="wear.mu is both in --set and --vary"):
        varied(args)
    monkeypatch.chdir(tmp_path)
    assert task_changes({"indenter.file": "a.csv", "wear.k": 1e-5}) == {
        "indenter.file": str(tmp_path / "a.csv"), "wear.k": 1e-5}


def test_sweep_json_rows_are_the_runs(cluster, tmp_path, capsys):
    # the rows on stdout: one per value, as sweep.csv has them, and Archard's
    # self-similarity (ŝ ∝ k s, docs/theory.md §5) makes k·s at the end one number
    out = tmp_path / "k"
    from wearcheck.cli import main
    code = main(["sweep", "paper", "--vary", "wear.k=1e-5,1e-4", "--solver", "mdr",
                     "--out", str(out), "--set", "mdr.elements=50",
                     "--set", "sliding.force_fraction=0.3", "--scheduler", cluster, "--quiet",
                     "--json"])
    assert code == 0
    rows = json.loads(capsys.readouterr().out)    # stdout: the JSON only
    assert [r["wear.k"] for r in rows] == [1e-5, 1e-4]
    ks = [r["wear.k"] * r["final_s"] for r in rows]
    assert ks[1] == pytest.approx(ks[0], rel=1e-8)
    assert all(r["status"] == "ok" for r in rows)
