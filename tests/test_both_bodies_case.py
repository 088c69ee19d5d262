"""The keys of a counterface that wears and of the motion along its track (issue 24)."""

import math

import pytest

from wearcheck import cases
from wearcheck.cases import CaseError

BALL = "cases/ball_on_flat.toml"
WEARS = ["counterface.wears=true", "counterface.specific_rate=2e-15",
         'sliding.motion="reciprocating"']


def load(*overrides):
    return cases.load(BALL, list(overrides))


def test_counterface_rate_from_specific_rate_or_k():
    assert load(*WEARS).counterface_wear_rate == 2e-15
    case = load("counterface.wears=true", "counterface.k=1e-4", "counterface.hardness=2e9",
                'sliding.motion="reciprocating"')
    # K_flat = k μ / H with the case's μ = 0.3
    assert case.counterface_wear_rate == pytest.approx(1e-4 * 0.3 / 2e9, rel=1e-15)
    assert load().counterface_wear_rate is None


@pytest.mark.parametrize("overrides, words", [
    (["counterface.wears=true"], "missing key 'sliding.motion'"),
    (["counterface.wears=true", 'sliding.motion="reciprocating"'],
     "needs its wear rate; give counterface.specific_rate"),
    (["counterface.k=1e-5"], "given but counterface.wears = false"),
    (["counterface.hardness=1e9"], "given but counterface.wears = false"),
    (["counterface.wears=true", "counterface.k=1e-5", 'sliding.motion="reciprocating"'],
     "missing key 'counterface.hardness'"),
    (["counterface.wears=true", "counterface.k=1e-5", "counterface.specific_rate=1e-15",
      "counterface.hardness=1e9", 'sliding.motion="reciprocating"'], "both given"),
    (["counterface.wears=true", "counterface.specific_rate=1e-15"],
     "missing key 'sliding.motion'"),
    (['sliding.motion="unidirectional"'], "missing key 'sliding.track_radius'"),
    (["sliding.track_radius=0.01"], "set sliding.motion = \"unidirectional\""),
    (['sliding.motion="circular"'], "must be one of"),
    (['bem.track_model="moving"'], "bem.track_model applies to a counterface that wears"),
])
def test_bad_combinations_are_one_line(overrides, words):
    with pytest.raises(CaseError) as exc:
        load(*overrides)
    assert words in str(exc.value) and "\n" not in str(exc.value)


def test_stroke_with_unidirectional_refused():
    raw = cases.to_dict(load())
    raw["sliding"].update(motion="unidirectional", track_radius=0.01)   # keeps the stroke
    with pytest.raises(CaseError, match="'sliding.stroke' = 0.001 given but sliding.motion"):
        cases.from_dict(raw)


def test_a_cycle_of_a_disc_is_one_revolution():
    case = load('sliding.motion="unidirectional"', "sliding.track_radius=0.01")
    assert case.cycle_length == pytest.approx(2 * math.pi * 0.01, rel=1e-15)
    assert case.end_distance == pytest.approx(1e6 * 2 * math.pi * 0.01, rel=1e-15)
    assert case.cycles_per_metre * case.cycle_length == pytest.approx(1.0, rel=1e-15)
    # the stages in cycles are revolutions
    per_m = cases.reference.scales(case)["s_hat_per_m"]
    assert case.stages.s_hat[1] == pytest.approx(10 * 2 * math.pi * 0.01 * per_m, rel=1e-12)


def test_resolved_case_round_trips():
    case = load(*WEARS)
    again = cases.from_dict(cases.to_dict(case))
    assert again.counterface == case.counterface and again.sliding == case.sliding


def test_mdr_and_fem_say_why_they_skip_a_wearing_counterface():
    from wearcheck import registry
    case = load(*WEARS)
    for name in ("mdr", "fem"):
        reason = registry.get(name).supports(case)
        assert reason is not None and "counterface.wears" in reason and "BEM" in reason
    assert "bem" in registry.supporting(case)


def test_compare_names_the_skipped_solvers(tmp_path, capsys):
    # only the BEM wears a counterface: compare refuses with one line that
    # gives each other solver's reason (exit 2, a case the tool cannot compare)
    from wearcheck.cli import main
    code = main(["compare", "ball_on_flat_steel", "--out", str(tmp_path / "c"), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err
    assert "only bem can" in err and "mdr: counterface.wears" in err \
        and "fem: counterface.wears" in err
    assert not (tmp_path / "c").exists()
