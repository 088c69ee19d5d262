"""A fretting run without cycle jumping is refused after its first cycles when it would
take longer than mdr/fretting.py EVERY_CYCLE_SECONDS.

Adversarial review: `wearcheck run fretting --set fretting.jump_tolerance=0`
(allowed: every one of the 10⁵ cycles simulated) ran more than 4 minutes with no
estimate (12-15 ms per cycle measured: about 25 minutes). With jump_tolerance = 0
the cycle count is known up front: the run measures its first cycles and refuses,
in one line naming the key, the cycles, the estimated time and the remedy, when
fretting.cycles × that cost passes the limit.
"""

import os
import subprocess
import sys
from types import SimpleNamespace

import pytest

from wearcheck.cases import CaseError
from wearcheck.mdr import fretting


class Clock:
    """A clock the test moves: the estimate is cost per cycle × cycles, checked exactly."""

    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def _drive(cycles, per_cycle, tol=0.0, upto=None):
    """Call the estimating watch as the run does (cycle 0 at the ramp's end, then each
    simulated cycle after ``per_cycle`` seconds); return the cycles watched."""
    clock, watched = Clock(), []
    guarded = fretting._every_cycle_estimate(
        SimpleNamespace(jump_tolerance=tol, cycles=cycles),
        lambda s, a, b, cycle=None: watched.append(cycle), clock=clock)
    for n in range(0, upto or cycles + 1):
        guarded(0.0, 1.0, 0.0, cycle=n)
        clock.now += per_cycle
    return watched


def test_the_refusal_is_at_the_stated_limit():
    limit = fretting.EVERY_CYCLE_SECONDS
    assert limit == 600.0
    per = 2.0**-7                # 7.8 ms per cycle, exact in binary: 76 800 cycles fit
    # 1 % either side of the limit; the measurement window (≥ 5 cycles and ≥ 0.2 s:
    # 26 cycles at 7.8 ms) is short of either run's end
    _drive(int(0.99 * limit / per), per, upto=100)
    with pytest.raises(CaseError) as refused:
        _drive(int(1.01 * limit / per), per, upto=100)
    text = str(refused.value)
    assert text.startswith("key 'fretting.jump_tolerance' = 0.0: simulating every one of "
                           "fretting.cycles = 77568 cycles would take about 606 s")
    assert "measured on the first 26" in text and "fretting.jump_tolerance > 0" in text
    assert "at most about 76800 cycles" in text
    assert "\n" not in text


def test_cycle_jumping_runs_and_short_runs_are_left_alone():
    # a jump tolerance > 0: the watch itself, no clock
    watch = object()
    assert fretting._every_cycle_estimate(SimpleNamespace(jump_tolerance=0.02, cycles=10**5),
                                          watch) is watch
    # every cycle of a run shorter than the measurement window: watched, never judged
    assert _drive(3, 10.0) == [0, 1, 2, 3]


def test_the_reviewers_command_stops_after_its_first_cycles(tmp_path):
    # fretting.cycles = 200 000 (the runaway cap): 20-30 min at the 6-15 ms per cycle
    # measured, so a machine 3x faster than this one still passes the 600 s (the
    # reviewer's 10⁵ cycles are 25 min here, refused the same way)
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, "-m", "wearcheck", "run", "fretting", "--set",
                           "fretting.jump_tolerance=0", "--set", "fretting.cycles=200000",
                           "--out", str(out), "--quiet"], capture_output=True, text=True,
                          timeout=240, cwd=tmp_path, env=dict(os.environ, PYTHONWARNINGS="ignore"))
    assert done.returncode == 2, done.stderr
    errors = [line for line in done.stderr.splitlines() if "error" in line]
    assert len(errors) == 1, done.stderr
    assert errors[0].startswith("wearcheck run: error: key 'fretting.jump_tolerance' = 0.0: "
                                "simulating every one of fretting.cycles = 200000 cycles")
    assert not out.exists()


def test_the_benchmarks_every_cycle_references_are_not_refused(monkeypatch, tmp_path):
    # docs/performance.md measures cycle jumping against every one of 10⁵ cycles
    # simulated (bench_fretting.py --reference-cycles 100000, bench_fretting_cycles.py
    # --write-every-cycle): 5-20 minutes on purpose, which the refusal stopped after
    # a second. Here any run is "too long" (limit 1 µs), so the solver refuses a
    # short one, and the benchmarks' own runs must still go through.
    from pathlib import Path
    from wearcheck import cases
    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parents[1] / "benchmarks"))
    import bench_fretting
    import bench_fretting_cycles
    monkeypatch.setattr(fretting, "EVERY_CYCLE_SECONDS", 1e-6)
    monkeypatch.setattr(fretting, "ESTIMATE_SECONDS", 0.0)
    overrides = ["mdr.elements=100", "fretting.cycles=8", "fretting.jump_tolerance=0",
                 "fretting.stage_cycles=[0, 8]"]
    with pytest.raises(CaseError, match="fretting.jump_tolerance"):
        fretting.solve(cases.load(cases.shipped("fretting"), overrides))
    _, res, _, _ = bench_fretting.run(cases.shipped("fretting"), overrides)
    assert res.info["simulated_cycles"] == 8
    assert fretting.EVERY_CYCLE_SECONDS == 1e-6          # the solver's limit is restored
    row = bench_fretting_cycles.worker("ros2", 6, "HEAD", 0.0, str(tmp_path / "every.npz"))
    assert row["simulated"] == 6 and (tmp_path / "every.npz").is_file()
