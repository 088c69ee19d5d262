"""A friction coefficient past dry metallic sliding gets a remark, not a refusal.

Adversarial review: `--set wear.mu=1e6` ran with exit 0 and no word. μ enters
the wear law (V = k μ F s/σ0) and the tangential problems; a coefficient far above
the dry range of metals in air (cases/case.py FRICTION_REMARK_MU = 1.5) is a case
outside the gross-slip Reye–Archard setting: warned once per process through the
same mechanism as the elastic-similarity note, recorded on every case; μ ≤ 0 and
non-finite μ are refused as before.
"""

import subprocess
import sys
import warnings

import pytest

import wearcheck
from wearcheck.cases import CaseError, RunWarning, case as case_module, errors


@pytest.fixture
def fresh(monkeypatch):
    """A process that has not said the notes yet."""
    monkeypatch.setattr(errors, "_SAID", set())


def _load(mu):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        case = wearcheck.load_case("ball_on_flat_steel", {"wear.mu": mu})
    said = [w for w in caught if issubclass(w.category, RunWarning) and "wear.mu" in str(w.message)]
    return case, said


def _noted(case):
    return [w for w in case.warnings if "key 'wear.mu'" in w]


def test_the_threshold_is_where_it_is_stated(fresh):
    limit = case_module.FRICTION_REMARK_MU
    assert limit == 1.5
    # 1 % either side: the remark starts at the stated value, not a rounded neighbour
    below, said = _load(limit * 0.99)
    assert said == [] and _noted(below) == []
    above, said = _load(limit * 1.01)
    assert len(said) == 1 and said[0].filename == __file__    # points at the caller
    assert _noted(above)[0].startswith(f"key 'wear.mu' = {limit * 1.01!r}: ")
    # once per process; each case keeps its own
    again, said_again = _load(1e6)
    assert said_again == [] and "key 'wear.mu' = 1000000.0" in _noted(again)[0]


@pytest.mark.parametrize("mu", ["0", "-0.5", "nan", "inf"])
def test_non_positive_and_non_finite_friction_is_still_refused(mu):
    with pytest.raises(CaseError, match=r"wear\.mu"):
        wearcheck.load_case("ball_on_flat_steel", {"wear.mu": float(mu)})


def test_the_reviewers_command_says_it(tmp_path):
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, "-m", "wearcheck", "run", "paper", "--solver", "mdr",
                           "--set", "wear.mu=1e6", "--out", str(out)],
                          capture_output=True, text=True, timeout=240, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    notes = [line for line in done.stderr.splitlines() if "key 'wear.mu'" in line]
    assert len(notes) == 1, done.stderr
    assert "above 1.5" in notes[0]
    assert "key 'wear.mu' = 1000000.0" in (out / "meta.json").read_text(encoding="utf-8")
