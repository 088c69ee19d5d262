"""Lab units in the case file (issue 27 §3): wear.specific_rate, stages in metres and
cycles, the warning past a yield estimate."""

import json
import math
import tomllib
import warnings

import numpy as np
import pytest

import wearcheck
from wearcheck import cases
from wearcheck.cases import CaseError, reference
from wearcheck.cases import RunWarning, errors, validity
from wearcheck.cli import main as cli_main

BALL = cases.shipped("ball_on_flat")   # k = 2e-5, μ = 0.3, σ0 = 6 GPa: K = 1e-15 m³/(N·m)


def ball(*overrides):
    return cases.load(BALL, list(overrides))


# -- wear.specific_rate -------------------------------------------------------

def test_specific_rate_and_k_are_one_coefficient():
    by_k = ball()
    by_K = ball("wear.specific_rate=1e-15")          # replaces the file's k
    # K = k μ/σ0 and back, exactly as the wear law uses them (docs/theory.md §4)
    assert by_k.wear.specific_rate == pytest.approx(2e-5 * 0.3 / 6e9, rel=1e-15)
    assert by_K.wear.k == pytest.approx(1e-15 * 6e9 / 0.3, rel=1e-15)
    assert by_K.wear_rate == 1e-15
    assert by_k.derived[0] == "wear.specific_rate" and by_K.derived[0] == "wear.k"
    # the resolved case names the derived one as a comment and reads back to the same case
    text = cases.to_toml(by_K)
    wear = tomllib.loads(text)["wear"]
    assert wear["specific_rate"] == 1e-15 and "k" not in wear
    assert "# k = " in text and "derived: k = K σ0/μ" in text
    again = cases.from_dict(tomllib.loads(text))
    assert again.wear == by_K.wear and again.derived == by_K.derived


def test_overrides_of_one_replace_the_other():
    case = ball("wear.specific_rate=1e-15")
    # --set wear.k on a K case gives up K; derive and replace do as --set does
    raw = tomllib.loads(BALL.read_text(encoding="utf-8"))
    raw["wear"] = dict(specific_rate=1e-15, mu=0.3, hardness=6e9)
    assert cases.from_dict(raw, overrides=["wear.k=4e-5"]).wear.specific_rate == \
        pytest.approx(2e-15, rel=1e-15)
    # (both set by overrides at once: both given)
    with pytest.raises(CaseError, match="both given"):
        ball("wear.specific_rate=1e-15", "wear.k=4e-5")
    assert case.derive({"wear.k": 4e-5}).wear_rate == pytest.approx(2e-15, rel=1e-15)
    assert case.derive(wear__mu=0.6).wear.specific_rate == 1e-15    # K kept, k follows μ
    assert case.derive(wear__mu=0.6).wear.k == pytest.approx(1e-15 * 6e9 / 0.6, rel=1e-15)
    import dataclasses
    assert case.replace(wear=dataclasses.replace(case.wear, mu=0.6)).wear.specific_rate == 1e-15
    assert case.replace(wear=dataclasses.replace(case.wear, k=4e-5)).wear_rate == \
        pytest.approx(2e-15, rel=1e-15)


def test_cli_set_specific_rate_replaces_the_file_k(tmp_path):
    out = tmp_path / "run"
    code = cli_main(["run", "ball_on_flat", "--set", "wear.specific_rate=3e-15",
                     "--set", "sliding.cycles=10.0", "--set", "stages.cycles=[0.0, 10.0]",
                     "--set", "mdr.elements=100", "--quiet", "--out", str(out)])
    assert code == 0
    wear = tomllib.loads((out / "case.toml").read_text(encoding="utf-8"))["wear"]
    assert wear["specific_rate"] == 3e-15 and "k" not in wear


@pytest.mark.parametrize("raw_wear, pattern", [
    (dict(k=2e-5, specific_rate=1e-15, mu=0.3, hardness=6e9),
     r"'wear\.k' = 2e-05 and 'wear\.specific_rate' = 1e-15 both given; give the paper's "
     r"dimensionless k or the lab's specific wear rate K"),
    (dict(mu=0.3, hardness=6e9), r"needs exactly one of 'wear\.k' and 'wear\.specific_rate'.*got "
                                     r"neither.*the lab's specific wear rate K"),
    (dict(specific_rate=-1e-15, mu=0.3, hardness=6e9), r"'wear\.specific_rate' = -1e-15.*> 0"),
    (dict(specific_rate="1e-15 m3/Nm", mu=0.3, hardness=6e9),
     r"'wear\.specific_rate'.*m\^3/\(N m\).*without a unit"),
    # K σ0/μ overflows: one line naming the key given
    (dict(specific_rate=1e300, mu=1e-300, hardness=6e9),
     r"'wear\.specific_rate' = 1e\+300: the derived 'wear\.k' comes out inf"),
])
def test_bad_wear_coefficients_are_one_line(raw_wear, pattern):
    raw = tomllib.loads(BALL.read_text(encoding="utf-8"))
    raw["wear"] = raw_wear
    with pytest.raises(CaseError, match=pattern) as exc:
        cases.from_dict(raw)
    assert "\n" not in str(exc.value)


def test_a_run_given_K_wears_V_equal_to_K_F_s():
    """Under a constant force and n = 1, dV/ds = K ∫p dA = K F: V = K F s exactly
    (the definition of the lab's K), whatever the elastic contact does."""
    K, F = 1e-15, 2.0
    case = ball(f"wear.specific_rate={K}", "sliding.cycles=1000.0",
                "stages.cycles=[0.0, 10.0, 1000.0]", "mdr.elements=200")
    h = wearcheck.solve(case).history
    worn = h["s"] > 0
    # 1e-3: the MDR's volume quadrature on 200 elements (measured 6e-4 here)
    assert h["wear_volume"][worn] == pytest.approx(K * F * h["s"][worn], rel=1e-3)


# -- stages in metres and cycles ----------------------------------------------

def test_stages_in_metres_are_reached_at_those_distances():
    s = [0.0, 0.05, 0.5, 2.0]
    case = ball("sliding.cycles=1000.0", f"stages.s={s}", "mdr.elements=100")
    assert case.stages.cycles is None and "stages.s_hat" in case.derived
    per_m = reference.scales(case)["s_hat_per_m"]
    assert case.stages.s_hat == pytest.approx([x * per_m for x in s], rel=1e-15)
    result = wearcheck.solve(case)
    # the steps land on the stages: at exactly the distances given
    assert result.stages["s"] == pytest.approx(s, rel=1e-12)
    assert "s_hat" not in tomllib.loads(cases.to_toml(case))["stages"]


def test_stages_in_cycles_wherever_a_stroke_is_given():
    # a run that stops at a distance, its stages in cycles of a 1 mm stroke
    case = ball("sliding.until=distance", "sliding.distance=2.0", "stages.cycles=[0.0, 500.0]",
                "mdr.elements=100")
    assert case.stages.s_hat[1] == pytest.approx(500 * 2e-3 * reference.scales(case)
                                                 ["s_hat_per_m"], rel=1e-15)
    # the pin-on-disc stroke of issue 27: π·r_track, one cycle a revolution
    pin = ball("sliding.stroke=0.0314159", "stages.cycles=[0.0, 100.0]")
    assert pin.stages.s_hat[1] == pytest.approx(100 * 2 * 0.0314159 *
                                                reference.scales(pin)["s_hat_per_m"])
    # an override of one form replaces both others
    assert ball("stages.s=[0.0, 1.0]").stages.cycles is None
    assert ball("stages.s=[0.0, 1.0]").derive({"stages.s_hat": [0.0, 2.0]}).stages.s is None
    assert ball("stages.s=[0.0, 1.0]").derive({"stages.cycles": [0.0, 2.0]}).stages.s is None


@pytest.mark.parametrize("overrides, pattern", [
    (["stages.s=[0.0, 2.0, 1.0]"], r"stages\.s.*increase strictly"),
    (["stages.s=[-1.0]"], r"stages\.s.*>= 0"),
    (["sliding.stroke=1e-3", "sliding.until=distance", "sliding.distance=1.0"], None),
])
def test_bad_stages_in_metres(overrides, pattern):
    if pattern is None:
        ball(*overrides)   # (a stroke with until = distance is fine)
        return
    with pytest.raises(CaseError, match=pattern):
        ball(*overrides)


def test_two_forms_of_stages_in_one_file_are_one_error():
    raw = tomllib.loads(BALL.read_text(encoding="utf-8"))
    raw["stages"] = {"s": [0.0, 1.0], "cycles": [0.0, 10.0]}
    with pytest.raises(CaseError, match=r"'stages\.s' = \[0\.0, 1\.0\] and 'stages\.cycles'.*"
                                        "one way only"):
        cases.from_dict(raw)


# -- the warning past a yield estimate ----------------------------------------

@pytest.fixture
def fresh(monkeypatch):
    """A process that has said no remark through warnings yet."""
    monkeypatch.setattr(errors, "_SAID", set())


def test_peak_pressure_past_the_yield_estimate_warns_once(fresh):
    """The yield remark is checked where the half-space remark is (cases/validity.py):
    one RunWarning at the run's first recorded step, kept in the watch's remarks (the
    run's info["warnings"], meta.json, the note lines), not repeated, and not in the
    way of the half-space remark."""
    # ball_on_flat: p0 = 0.94 GPa. The estimate: onset of yield at p0 = 1.6 Y, Y = H/3
    case = ball()
    p0 = reference.scales(case)["p0"]
    onset = 1.6 * case.wear.hardness / 3
    assert p0 < onset and validity.yield_remark(case) is None
    # σ0 1 % either side of the hardness at which p0 is the onset (3 p0/1.6): the
    # threshold is where the estimate puts it, not a rounded neighbour
    assert validity.yield_remark(ball(f"wear.hardness={3 * p0 / 1.6 * 1.01}")) is None
    soft = ball(f"wear.hardness={3 * p0 / 1.6 * 0.99}")
    text = validity.yield_remark(soft)
    assert "p0 ≈ 1.6 Y" in text and "Y ≈ H/3" in text
    assert not any("yield" in w for w in soft.warnings)   # a remark on the run, not the case
    R = soft.indenter.radius
    watch = validity.BodyWatch(soft)
    with pytest.warns(RunWarning, match=r"p0 ≈ 1\.6 Y.*Y ≈ H/3") as caught:
        watch(0.0, 0.01 * R, 0.0)
        watch(1.0, 0.02 * R, 0.01 * R)      # said once per run
    assert len(caught) == 1 and caught[0].filename == __file__   # points at the caller
    assert watch.remarks == [text]
    with pytest.warns(RunWarning, match="half-space theory is stretched"):
        watch(2.0, 0.2 * R, 0.2 * R)        # the other remark still comes, once
    assert len(watch.remarks) == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        watch(3.0, 0.3 * R, 0.3 * R)
        validity.BodyWatch(case)(0.0, 0.01 * R, 0.0)   # the hard ball: no remark


def test_the_cli_prints_the_yield_note_once(tmp_path, capsys):
    out = tmp_path / "run"
    code = cli_main(["run", "ball_on_flat", "--set", "wear.hardness=1e9",
                     "--set", "sliding.cycles=10.0", "--set", "stages.cycles=[0.0, 10.0]",
                     "--set", "mdr.elements=100", "--out", str(out)])
    assert code == 0
    err = capsys.readouterr().err
    assert err.count("passes the onset of yield") == 1
    meta = json.loads((out / "meta.json").read_text())
    assert sum("onset of yield" in w for w in meta["warnings"]) == 1


def test_the_yield_warning_is_said_once_per_process_from_several_threads(fresh):
    """The API from several threads, each of which (as libraries and test harnesses
    do) enters warnings.catch_warnings before it solves: the yield RunWarning once in
    the process, as the case's own notes (before: once per thread, since entering
    catch_warnings resets Python's record of what it said), and every run keeps its
    remark. A filter that ignores it (the command line, a fit's forward runs) does
    not use it up; one that makes it an error raises it every time."""
    import threading
    hertz = wearcheck.load_case("hertz", {"mdr.elements": 40})   # p0 1.47 > 1.07 GPa
    assert validity.yield_remark(hertz)
    results = []

    def solve(barrier=None):
        if barrier is not None:
            barrier.wait()
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", category=DeprecationWarning)
        results.append(wearcheck.solve(hertz, "mdr"))

    def yields(caught):
        return [w for w in caught if issubclass(w.category, RunWarning)
                and "onset of yield" in str(w.message)]

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("ignore", RunWarning)
        wearcheck.solve(hertz, "mdr")                       # ignored: not used up
        warnings.simplefilter("error", RunWarning)
        for _ in range(2):
            with pytest.raises(RunWarning, match="onset of yield"):
                wearcheck.solve(hertz, "mdr")
        warnings.resetwarnings()
        warnings.simplefilter("default")                    # Python's default for it
        for _ in range(3):                                  # one thread after another
            thread = threading.Thread(target=solve)
            thread.start()
            thread.join()
        barrier = threading.Barrier(3)                      # three at once
        threads = [threading.Thread(target=solve, args=(barrier,)) for _ in range(3)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
    said = yields(caught)
    assert len(said) == 1 and "said once per process" in str(said[0].message)
    assert len(results) == 6
    assert all(sum("onset of yield" in w for w in r.warnings) == 1 for r in results)



def test_a_remark_said_once_reaches_a_program_given_with_python_c(fresh):
    """The first caller outside wearcheck may be a ``python -c`` program, whose module
    has the built-in importer as its loader, which raises ImportError when asked for
    the source (warnings.warn_explicit asks it when handed the module's globals)."""
    import importlib.machinery
    program = {"__name__": "__main__", "__loader__": importlib.machinery.BuiltinImporter,
               "errors": errors}
    with pytest.warns(RunWarning, match="^a probe remark$") as caught:
        exec(compile("errors.warn_once('probe', 'a probe remark')", "<string>", "exec"),
             program)
    assert caught[0].filename == "<string>" and caught[0].lineno == 1
