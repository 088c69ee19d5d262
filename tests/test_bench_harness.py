"""The benchmark harness (benchmarks/harness.py) on commands whose cost is known."""

import importlib.util
import sys
from pathlib import Path

import pytest

if not sys.platform.startswith("linux"):
    pytest.skip("the harness reads wait4's ru_maxrss in kB (Linux)", allow_module_level=True)

_spec = importlib.util.spec_from_file_location(
    "harness", Path(__file__).resolve().parents[1] / "benchmarks" / "harness.py")
harness = sys.modules["harness"] = importlib.util.module_from_spec(_spec)   # (dataclasses)
_spec.loader.exec_module(harness)

PY = sys.executable


def test_a_sleep_is_slower_than_pass():
    # a 0.2 s sleep on top of an interpreter's start-up, which takes 0.15-0.5 s
    # here by the load (2 shared cores): the median of the per-round wall
    # ratios must exceed 1, and the medians must differ by at least half the
    # sleep (the rest is margin for start-ups that vary by more than the sleep
    # between rounds); the sleep costs no CPU, so the CPU times stay within a
    # factor 3 of each other. A harness that swapped, lost or mis-timed the
    # commands fails one of these.
    timed = harness.alternate([("pass", [PY, "-c", "pass"], None),
                               ("sleep", [PY, "-c", "import time; time.sleep(0.2)"], None)],
                              rounds=5, warmup=1)
    base, sleep = timed
    assert len(base.wall) == len(sleep.wall) == 5
    med = harness.statistics.median
    assert med(harness.ratios(sleep.wall, base.wall)) > 1.0
    assert med(sleep.wall) - med(base.wall) > 0.1
    assert 1 / 3 < med(sleep.cpu) / med(base.cpu) < 3
    text = harness.table(timed)
    assert "| sleep |" in text and "wall / pass" in text


def test_peak_memory_is_the_commands_own():
    # a child that fills 100 MiB peaks above 100 MiB; an empty interpreter
    # started while this process holds 300 MiB reads well under that (Linux
    # would report the parent's 300 MiB if the harness's spawner did not
    # stand between them)
    big = harness.measure([PY, "-c", "b = b'x' * (100 * 2**20)"])
    assert big.peak_mb > 100
    held = b"y" * (300 * 2**20)
    small = harness.measure([PY, "-c", "pass"])
    assert len(held) and small.peak_mb < 60
    assert small.cpu > 0 and small.wall > small.cpu / 4


def test_a_called_function_returns_its_result_and_timing():
    # math.fsum of ten 0.1 is exactly 1.0; call_seconds is added to a dict result
    value, run = harness.call("math:fsum", [0.1] * 10)
    assert value == 1.0
    assert run.returncode == 0 and run.peak_mb > 5
    out, _ = harness.call("json:loads", '{"a": 1}')
    assert out["a"] == 1 and 0 <= out["call_seconds"] < run.wall + 10


def test_a_failing_command_is_reported_with_its_error():
    with pytest.raises(RuntimeError, match="ZeroDivisionError"):
        harness.measure([PY, "-c", "1 / 0"])
    assert harness.measure([PY, "-c", "raise SystemExit(3)"], check=False).returncode == 3
