"""`wearcheck run` end to end: the files, their contents, atomicity, progress."""

import io
import json
import math
import os
import re

import numpy as np
import pytest

import wearcheck
from wearcheck import cases
from wearcheck.cases import reference
from wearcheck import outputs, rundir as runio
from wearcheck.cli import main as cli_main
from wearcheck.comparisons.present.progress import ProgressBar

SMALL = ["--set", "mdr.elements=100", "--set", "sliding.until=distance",
         "--set", "sliding.scheme=implicit",
         "--set", "stages.s_hat=[0, 0.5, 1]", "--quiet"]


def _distance_override(case_path, s_hat):
    case = cases.load(case_path)
    s = s_hat / reference.scales(case)["s_hat_per_m"]
    return ["--set", f"sliding.distance={s!r}"]


@pytest.fixture(scope="module")
def mdr_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "paper-mdr"
    paper = cases.shipped("paper")
    argv = ["run", str(paper), "--solver", "mdr", "--out", str(out)] + SMALL \
        + _distance_override(paper, 1.0)
    assert cli_main(argv) == 0
    return out, argv


def test_run_writes_exactly_the_documented_files(mdr_run):
    out, _ = mdr_run
    assert sorted(p.name for p in out.iterdir()) == [outputs.OUTPUT_MARKER, "case.toml",
                                                     "history.csv", "meta.json", "stages.npz"]
    header = (out / "history.csv").read_text().splitlines()[0].split(",")
    assert header[:6] == list(cases.HISTORY_COLUMNS)
    with np.load(out / "stages.npz") as z:
        assert {"s", "s_hat", "r", "f", "p"} <= set(z.files)
        K, M = len(z["s"]), len(z["r"])
        assert z["f"].shape == (K, M) and z["p"].shape == (K, M)
        np.testing.assert_allclose(z["s_hat"], [0, 0.5, 1], rtol=1e-12, atol=1e-12)
    # no temporary directory left beside it
    assert [p.name for p in out.parent.iterdir()] == [out.name]


def test_run_meta_records_scales_provenance_and_the_resolved_case(mdr_run):
    out, argv = mdr_run
    meta = json.loads((out / "meta.json").read_text())
    case = cases.load(out / "case.toml")
    sc = meta["scales"]
    # scales are the exact-sphere unworn contact (closed form, independent of the solver)
    exact = reference.sphere(case.E_star, case.indenter.radius, depth=case.loading.depth)
    assert sc["a0"] == pytest.approx(exact["contact_radius"], rel=1e-12)
    assert sc["F0"] == pytest.approx(exact["force"], rel=1e-12)
    assert sc["p0"] == pytest.approx(3 * sc["F0"] / (2 * math.pi * sc["a0"] ** 2), rel=1e-12)
    for k in ("E_star", "G_star", "s_hat_per_m"):
        assert k in sc
    assert meta["solve_seconds"] > 0
    assert meta["command"].startswith("wearcheck run")
    assert "mdr.elements=100" in meta["command"]
    assert meta["versions"]["numpy"] == np.__version__
    assert case.mdr.elements == 100  # the resolved case carries the override


def test_run_history_obeys_hertz_and_the_wear_law(mdr_run):
    out, _ = mdr_run
    run = runio.Run(out)
    h, case = run.history, run.case
    sc = run.scales
    # unworn start: Hertz force of the sphere within the N = 100 grid error
    # (second order in N; 1e-3 is ~10x the N = 100 error measured by the MDR tests)
    assert h["force"][0] == pytest.approx(sc["F0"], rel=1e-3)
    assert h["contact_radius"][0] == pytest.approx(sc["a0"], rel=1e-2)
    # wear law: V = (kμ/σ0) ∫F ds; backward Euler wears each step with the force at
    # its end, so the discrete identity is V = (kμ/σ0) Σ Δs F_{n+1}. The volume
    # (∫2πr w dr on the 3D grid) and the force (Eq. 12 on the 1D grid) are separate
    # quadratures: at N = 100 they agree to ~0.2 %, hence 5e-3
    rate = case.wear_rate
    ds = np.diff(h["s"])
    assert h["wear_volume"][-1] == pytest.approx(rate * np.sum(ds * h["force"][1:]), rel=5e-3)
    # the run reached the distance asked for, exactly
    assert h["s"][-1] == pytest.approx(case.sliding.distance, rel=1e-12)
    # depth control: the depth column is the case's depth throughout
    np.testing.assert_allclose(h["depth"], case.loading.depth, rtol=1e-12)
    # wear at the centre raises the profile there: f(0) equals wear_center at the last stage
    assert run.stages["f"][-1, 0] == pytest.approx(h["wear_center"][-1], rel=1e-9, abs=1e-15)


def test_failed_run_leaves_an_earlier_complete_run_untouched(mdr_run, tmp_path):
    out, _ = mdr_run
    target = tmp_path / "run"
    import shutil
    shutil.copytree(out, target)
    before = {p.name: p.read_bytes() for p in target.iterdir()}
    # a domain smaller than the worn contact makes the solver fail
    code = cli_main(["run", str(cases.shipped("paper")), "--out", str(target), "--quiet",
                     "--set", "mdr.elements=50", "--set", "mdr.domain_factor=0.75"])
    assert code != 0
    assert {p.name: p.read_bytes() for p in target.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_interrupted_write_leaves_nothing(tmp_path, monkeypatch):
    def interrupted(*args, **kwargs):
        (args[0] / "history.csv").write_text("s,force\n")
        raise KeyboardInterrupt

    monkeypatch.setattr("wearcheck.cli.run.write_run_files", interrupted)
    code = cli_main(["run", str(cases.shipped("hertz")), "--out", str(tmp_path / "x"),
                     "--quiet", "--set", "mdr.elements=50"])
    assert code == 130
    assert list(tmp_path.iterdir()) == []


def test_atomic_directory_replaces_only_on_success(tmp_path):
    target = tmp_path / "d"
    with outputs.atomic_directory(target) as tmp:
        (tmp / "a").write_text("1")
    with pytest.raises(RuntimeError):
        with outputs.atomic_directory(target) as tmp:
            (tmp / "a").write_text("2")
            raise RuntimeError
    assert (target / "a").read_text() == "1"
    assert os.listdir(tmp_path) == ["d"]


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_bar_only_on_a_terminal():
    quiet_stream, tty = io.StringIO(), _Terminal()
    for stream, quiet in ((quiet_stream, False), (tty, True)):
        bar = ProgressBar("x", quiet=quiet, stream=stream)
        bar(1.0)
        bar.close()
        assert stream.getvalue() == ""
    bar = ProgressBar("mdr", stream=tty)
    bar(1.0, "done")
    bar.close()
    assert "100.0%" in tty.getvalue() and "mdr" in tty.getvalue()


def test_output_path_that_is_not_a_wearcheck_output_is_refused(tmp_path):
    precious = tmp_path / "thesis"
    precious.mkdir()
    (precious / "thesis.tex").write_text("important")
    code = cli_main(["run", str(cases.shipped("hertz")), "--out", str(precious), "--quiet",
                     "--set", "mdr.elements=50"])
    assert code == 2
    assert (precious / "thesis.tex").read_text() == "important"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["thesis"]
    # a file is refused the same way
    with pytest.raises(cases.CaseError, match="not a wearcheck output"):
        with outputs.atomic_directory(precious / "thesis.tex"):
            pass


def test_revolve_below_three_segments_is_bad_input_before_solving(tmp_path):
    code = cli_main(["run", str(cases.shipped("hertz")), "--revolve", "2", "--quiet",
                     "--out", str(tmp_path / "x")])
    assert code == 2 and not (tmp_path / "x").exists()


def test_run_says_which_requested_stages_it_did_not_reach(tmp_path, capsys):
    """The paper case stops once F < 1 % F0 (ŝ ≈ 11.25): a stage at ŝ = 20 cannot be
    stored. The Python API warned; ``wearcheck run`` said only "1 stages"."""
    from wearcheck.cli import main
    out = tmp_path / "run"
    assert main(["run", "paper", "--solver", "mdr", "--set", "mdr.elements=100",
                 "--set", "stages.s_hat=[0.0, 20.0]", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "the run ended before the stages at ŝ = 20 (it stops once F < 0.01 F0)" in err


@pytest.mark.parametrize("given, expect", [
    ("stages.cycles=[0, 10, 1e4, 2e4]", "the stages at 10000, 20000 cycles "
                                         "(it stops after 1000 cycles (s = 2 m))"),
    ("stages.s=[0, 0.5, 4]", "the stages at s = 4 m (it stops after 1000 cycles (s = 2 m))"),
])
def test_stages_not_reached_are_named_in_the_unit_given(tmp_path, capsys, given, expect):
    """Stages given in cycles or in metres are named so when the run ends before them
    (the note said "ŝ = 144627" for a stage at 1e7 cycles)."""
    from wearcheck.cli import main
    over = ["mdr.elements=100", "sliding.until=\"cycles\"", "sliding.cycles=1000", given]
    args = [x for o in over for x in ("--set", o)]
    assert main(["run", "ball_on_flat", "--solver", "mdr", *args,
                 "--out", str(tmp_path / "run")]) == 0
    err = capsys.readouterr().err
    assert f"note: the run ended before {expect}" in err, err
    # the Python API's warning says the same
    case = cases.load(cases.shipped("ball_on_flat"), over)
    with pytest.warns(UserWarning, match="the run ended before " + re.escape(expect)):
        wearcheck.solve(case, "mdr")
