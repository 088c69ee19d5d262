"""The case definition: shipped cases, overrides, and every class of bad input."""

import dataclasses
import math
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from wearcheck import cases
from wearcheck.cases import CaseError
from conftest import write_table_case

BASE = {
    "indenter": {"profile": "paraboloid", "radius": 0.01, "youngs_modulus": 210e9,
                 "poisson_ratio": 0.3},
    "counterface": {"rigid": True},
    "loading": {"control": "depth", "depth": 1e-6},
    "wear": {"k": 1e-4, "mu": 0.3, "hardness": 2e9},
}


def with_(section, **keys):
    raw = {s: dict(v) for s, v in BASE.items()}
    raw.setdefault(section, {}).update(keys)
    return raw


def test_shipped_cases_load():
    for name in ("hertz", "truncated", "paper"):
        case = cases.load(cases.shipped(name))
        assert case.E_star > 0


def test_paper_case_meets_issue_requirements():
    case = cases.load(cases.shipped("paper"))
    from wearcheck.cases.reference import scales
    sc = scales(case)
    assert case.loading.control == "depth"
    assert case.sliding.until == "force_fraction" and case.sliding.force_fraction == 0.01
    assert case.mdr.elements == 800
    assert len(case.stages.s_hat) >= 6
    assert sc["a0"] / case.indenter.radius <= 0.01 + 1e-12
    assert case.counterface.rigid and not case.indenter.rigid


def test_effective_moduli_against_paper_eqs_5_6():
    raw = with_("counterface", rigid=False, youngs_modulus=70e9, poisson_ratio=0.33)
    case = cases.from_dict(raw)
    E1, n1, E2, n2 = 210e9, 0.3, 70e9, 0.33
    G1, G2 = E1 / (2 * (1 + n1)), E2 / (2 * (1 + n2))
    assert case.E_star == pytest.approx(1 / ((1 - n1**2) / E1 + (1 - n2**2) / E2), rel=1e-14)
    assert case.G_star == pytest.approx(1 / ((2 - n1) / (4 * G1) + (2 - n2) / (4 * G2)), rel=1e-14)


def test_elastic_similarity_warning_quantifies_mismatch():
    # two identical materials are elastically similar: no warning
    same = with_("counterface", rigid=False, youngs_modulus=210e9, poisson_ratio=0.3)
    # (BASE's p0 passes the yield estimate from wear.hardness: a remark of its own)
    def similarity(case):
        return [w for w in case.warnings if "Dundurs" in w]
    assert similarity(cases.from_dict(same)) == []
    # steel on a rigid plane: beta = (1-2ν)/(2(1-ν)) = 0.4/1.4
    case = cases.from_dict(BASE)
    assert len(similarity(case)) == 1
    assert f"{0.4 / 1.4:.4f}" in similarity(case)[0]


def test_override_changes_and_is_validated():
    case = cases.from_dict(BASE, overrides=["loading.depth=2e-6", "sliding.scheme=explicit",
                                            "stages.s_hat=[0, 1, 2]"])
    assert case.loading.depth == 2e-6
    assert case.sliding.scheme == "explicit"
    assert case.stages.s_hat == (0.0, 1.0, 2.0)
    with pytest.raises(CaseError, match=r"loading\.depth.*-1.*> 0"):
        cases.from_dict(BASE, overrides=["loading.depth=-1"])
    with pytest.raises(CaseError, match=r"unknown key 'loading\.dept'"):
        cases.from_dict(BASE, overrides=["loading.dept=1e-6"])
    with pytest.raises(CaseError, match="section.key"):
        cases.from_dict(BASE, overrides=["depth=1e-6"])


def _shipped_and_stage_cycles():
    from cases.catalog import shipped_cases
    out = [(name, ()) for name in sorted(shipped_cases())]
    # fretting.stage_cycles is left out of the shipped fretting case: given, it is a
    # list of whole numbers held as floats
    return out + [("fretting", ("fretting.stage_cycles=[0, 10, 1000]", "fretting.cycles=2000"))]


@pytest.mark.parametrize("name, overrides", _shipped_and_stage_cycles())
def test_resolved_case_round_trips(name, overrides, tmp_path):
    """load -> write -> load gives the same resolved case (every key, the remarks, the
    derived keys), for every shipped case."""
    case = cases.load(cases.shipped(name), list(overrides))
    text = cases.to_toml(case)
    path = tmp_path / "case.toml"
    path.write_text(text)
    again = cases.load(path)
    assert dataclasses.replace(again, source=case.source) == case
    assert again.derived == case.derived
    assert cases.to_toml(again).splitlines()[1:] == text.splitlines()[1:]   # (line 0: source)


def test_a_key_of_whole_numbers_is_written_as_integers():
    """fretting.stage_cycles (cycle numbers, schema multipleOf 1) was written
    [0.0, 10.0, 1000.0]; a float key keeps its floats."""
    case = cases.load(cases.shipped("fretting"), ["fretting.stage_cycles=[0, 10, 1000]",
                                                  "fretting.cycles=2000"])
    assert case.fretting.stage_cycles == (0.0, 10.0, 1000.0)    # held as floats
    written = tomllib.loads(cases.to_toml(case))
    assert written["fretting"]["stage_cycles"] == [0, 10, 1000]
    assert all(type(v) is int for v in written["fretting"]["stage_cycles"])
    assert type(written["fretting"]["cycles"]) is int
    paper = tomllib.loads(cases.to_toml(cases.load(cases.shipped("paper"),
                                                   ["stages.s_hat=[0, 1, 2.5]"])))
    assert paper["stages"]["s_hat"] == [0.0, 1.0, 2.5]
    assert all(type(v) is float for v in paper["stages"]["s_hat"])   # not whole-number keys


@pytest.mark.parametrize("raw, pattern", [
    (with_("loading", dept=1e-6), r"unknown key 'loading\.dept'"),
    ({**BASE, "lodaing": {}}, r"unknown section \[lodaing\]"),
    ({k: v for k, v in BASE.items() if k != "wear"}, r"missing section \[wear\]"),
    (with_("wear", k=None) | {"wear": {"mu": 0.3, "hardness": 2e9}},
     r"\[wear\] needs exactly one of 'wear\.k' and 'wear\.specific_rate'"),
    (with_("loading", depth="deep"), r"loading\.depth.*\"deep\".*number"),
    (with_("mdr", elements=800.5), r"mdr\.elements.*800\.5.*integer"),
    (with_("wear", tangential_correction=1), r"wear\.tangential_correction.*true or false"),
    (with_("loading", depth=float("nan")), r"loading\.depth.*nan.*finite"),
    (with_("wear", k=10**400), r"wear\.k.*finite"),
    (with_("mdr", elements=10**400), r"mdr\.elements.*finite"),
    (with_("loading", depth=1e-300), r"loading\.depth.*not computable"),
    ({**with_("indenter", profile="sphere", radius=1e-300), "loading": {"control": "depth",
                                                                        "depth": 1e-302}},
     r"not computable.*indenter\.radius"),
    ({**with_("indenter", profile="sphere", radius=0.01), "loading": {"control": "depth",
                                                                      "depth": 0.02}},
     r"loading\.depth.*0\.02.*not below the sphere's radius.*indenter\.radius = 0\.01"),
    (with_("wear", hardness=float("inf")), r"wear\.hardness.*inf.*finite"),
    (with_("indenter", youngs_modulus=0.0), r"indenter\.youngs_modulus.*0\.0.*> 0"),
    (with_("indenter", radius=-0.01), r"indenter\.radius.*-0\.01.*> 0"),
    (with_("loading", depth=-1e-6), r"loading\.depth.*> 0"),
    ({**with_("loading", control="force", force=-1.0), "loading": {"control": "force",
                                                                   "force": -1.0}},
     r"loading\.force.*-1\.0.*> 0"),
    (with_("wear", hardness=0), r"wear\.hardness.*> 0"),
    (with_("indenter", poisson_ratio=0.6), r"indenter\.poisson_ratio.*0\.6.*\(-1, 0\.5\]"),
    (with_("indenter", poisson_ratio=-1.0), r"indenter\.poisson_ratio.*\(-1, 0\.5\]"),
    (with_("loading", control="speed"), r"loading\.control.*\"speed\".*\"depth\", \"force\""),
    (with_("indenter", flat_radius=1e-5),
     r"indenter\.flat_radius' = 1e-05 given but indenter\.profile = \"paraboloid\" \(it takes "
     r"radius\); remove it, or set indenter\.profile = \"truncated_paraboloid\""),
    (with_("indenter", profile="cone"),
     r"missing key 'indenter\.slope_angle', required by indenter\.profile = \"cone\""),
    (with_("loading", force=3.0), r"loading\.force.*given but loading\.control"),
    (with_("counterface", rigid=False), r"counterface\.youngs_modulus"),
    (with_("indenter", rigid=True), r"indenter\.youngs_modulus.*given but"),
    (with_("stages", s_hat=[0.0, 2.0, 1.0]), r"stages\.s_hat.*increase"),
    (with_("sliding", step_hat="fast"), r"sliding\.step_hat.*number or \"auto\""),
    (with_("sliding", until="distance"), r"sliding\.distance.*required"),
    ({**BASE, "loading": {"control": "force", "force": 3.0}}, r"force_fraction.*cannot end"),
])
def test_bad_input_names_key_value_and_allowed(raw, pattern):
    with pytest.raises(CaseError, match=pattern):
        cases.from_dict(raw)


def test_table_profile_reads_relative_to_case(tmp_path):
    r = np.linspace(0, 4e-4, 41)
    text = "r,f\n" + "\n".join(f"{float(a)!r},{float(a * a / 0.02)!r}" for a in r)
    case = cases.load(write_table_case(tmp_path, text))
    from wearcheck.cases.profiles import height
    # PCHIP reproduces a parabola to interpolation accuracy (h = 1e-5, f'' = 1/R)
    rr = np.linspace(0, 4e-4, 333)
    assert np.max(np.abs(height(case.indenter, rr, case.table) - rr**2 / 0.02)) < 1e-3 * 1e-6


@pytest.mark.parametrize("text, pattern", [
    (None, r"indenter\.file.*does not exist"),
    ("0,0\n2e-4,1e-6\n1e-4,2e-7\n", r"indenter\.file.*increase strictly"),
    ("1e-5,0\n1e-4,1e-7\n2e-4,1e-6\n", r"indenter\.file.*first radius must be 0"),
    ("0,0\n1e-4,abc\n2e-4,1e-6\n", r"indenter\.file.*line 2"),
    ("0,0\n1e-4\n2e-4,1e-6\n", r"indenter\.file.*line 2 has 1 columns"),
    # a spreadsheet's export with another separator: say which (found by a review)
    ("0;0\n1e-4;1e-7\n2e-4;1e-6\n", r"line 2 is not two numbers.*by commas, not semicolons"),
    ("0\t0\n1e-4\t1e-7\n2e-4\t1e-6\n", r"by commas, not tabs"),
    ("0 0\n1e-4 1e-7\n2e-4 1e-6\n", r"by commas, not spaces"),
])
def test_bad_table_profile(tmp_path, text, pattern):
    with pytest.raises(CaseError, match=pattern):
        cases.load(write_table_case(tmp_path, text))


def test_toml_syntax_error_reports_line(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[indenter]\nprofile = \"sphere\"\nradius = = 0.01\n")
    with pytest.raises(CaseError, match=r"TOML syntax error.*line 3"):
        cases.load(path)


def test_missing_case_file():
    with pytest.raises(CaseError, match="does not exist"):
        cases.load("no/such/case.toml")


def test_cli_bad_input_is_one_clear_line_without_traceback(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text(cases.shipped("hertz").read_text().replace("depth = 1e-6", "depth = -1e-6"))
    out = subprocess.run([sys.executable, "-m", "wearcheck", "run", str(path),
                          "--out", str(tmp_path / "run")], capture_output=True, text=True,
                         cwd=Path(__file__).parents[1])
    assert out.returncode == 2
    assert "Traceback" not in out.stderr
    assert "loading.depth" in out.stderr and "-1e-06" in out.stderr
    assert not (tmp_path / "run").exists()


def test_docs_document_every_key():
    # docs/case-files.md includes the key table generated from the declarations at
    # every docs build; every key must be in it, with its meaning
    docs = Path(__file__).parents[1] / "docs"
    assert "```{include} _generated/case-keys.md" in (docs / "case-files.md").read_text()
    from wearcheck.cases.schema import SECTIONS, section_fields
    table = cases.key_reference()
    for section in SECTIONS:
        for name, f in section_fields(section):
            row = next((line for line in table.splitlines()
                        if line.startswith(f"| `{section}.{name}` |")), None)
            assert row is not None, f"{section}.{name} missing from the key reference"
            assert f.metadata["doc"] and f.metadata["doc"] in row


def test_case_file_with_byte_order_mark_and_a_directory(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + cases.shipped("hertz").read_bytes())
    assert cases.load(path).loading.depth == 1e-6
    with pytest.raises(CaseError, match="is a directory"):
        cases.load(tmp_path)


# Every class of bad input the file loader rejects, as one changed key of BASE.
# (Missing keys and sections cannot be made by changing a complete case.)
BAD_CHANGES = [
    ("loading.dept", 1e-6), ("lodaing.depth", 1e-6), ("depth", 1e-6),
    ("loading.depth", "deep"), ("mdr.elements", 800.5), ("wear.tangential_correction", 1),
    ("loading.depth", float("nan")), ("wear.k", 10**400), ("mdr.elements", 10**400),
    ("loading.depth", 1e-300), ("wear.hardness", float("inf")),
    ("indenter.youngs_modulus", 0.0), ("indenter.radius", -0.01), ("loading.depth", -1e-6),
    ("wear.hardness", 0), ("wear.k", -1e-4), ("indenter.poisson_ratio", 0.6),
    ("indenter.poisson_ratio", -1.0), ("loading.control", "speed"),
    ("indenter.flat_radius", 1e-5), ("indenter.profile", "cone"), ("loading.force", 3.0),
    ("counterface.rigid", False), ("indenter.rigid", True),
    ("stages.s_hat", [0.0, 2.0, 1.0]), ("sliding.step_hat", "fast"),
    ("sliding.until", "distance"),
]


#: what the override of a choice removes with it (README, "--set")
FLIPPED = {("indenter.rigid", "True"): ("youngs_modulus", "poisson_ratio")}


@pytest.mark.parametrize("key, value", BAD_CHANGES, ids=[f"{k}={v!r}"[:40] for k, v in BAD_CHANGES])
def test_derived_case_is_rejected_exactly_as_the_file(key, value):
    """``Case.derive`` (the Python way to change a case) says what the loader says."""
    case = cases.from_dict(BASE)
    section, _, name = key.rpartition(".")
    raw = {s: dict(v) for s, v in BASE.items()}
    if section:
        raw.setdefault(section, {})[name] = value
        # an override that flips a choice drops the keys the file gave for the old one
        for dropped in FLIPPED.get((key, repr(value)), ()):
            raw[section].pop(dropped, None)
        with pytest.raises(CaseError) as from_file:
            cases.from_dict(raw)
    with pytest.raises(CaseError) as derived:
        case.derive({key: value})
    if section:
        assert str(derived.value) == str(from_file.value)
    else:
        assert "section.key" in str(derived.value)
    # the same through the keyword spelling and the command-line spelling
    if section:
        with pytest.raises(CaseError) as keyword:
            case.derive(**{f"{section}__{name}": value})
        assert str(keyword.value) == str(derived.value)


def test_replace_validates_whole_sections():
    import dataclasses
    case = cases.from_dict(BASE)
    with pytest.raises(CaseError, match=r"wear\.k.*> 0"):
        case.replace(wear=dataclasses.replace(case.wear, k=-1e-4))
    assert case.replace(wear=dataclasses.replace(case.wear, k=2e-4)).wear.k == 2e-4


# -- an override that flips a choice (found by a new-user review) ----------

@pytest.mark.parametrize("name, changes, check", [
    # the paper's depth-controlled sphere under a held force instead
    ("paper", {"loading.control": "force", "loading.force": 5.0, "sliding.until": "distance",
               "sliding.distance": 0.01},
     lambda c: c.loading.depth is None and c.loading.force == 5.0),
    # the ball-on-flat test under a held depth, then stopped at a distance
    ("ball_on_flat", {"loading.control": "depth", "loading.depth": 1e-7},
     lambda c: c.loading.force is None and c.loading.depth == 1e-7),
    ("ball_on_flat", {"sliding.until": "distance", "sliding.distance": 1.0},
     lambda c: c.sliding.cycles is None and c.sliding.stroke == 1e-3),
    # a rigid sphere on an elastic flat
    ("paper", {"indenter.rigid": True, "counterface.rigid": False,
               "counterface.youngs_modulus": 1e11, "counterface.poisson_ratio": 0.3},
     lambda c: c.indenter.youngs_modulus is None and c.counterface.youngs_modulus == 1e11),
    # the flat tip away: the plain paraboloid of the same radius
    ("truncated", {"indenter.profile": "paraboloid"},
     lambda c: c.indenter.flat_radius is None and c.indenter.radius == 0.01),
])
def test_an_override_that_flips_a_choice_drops_the_keys_of_the_old_one(name, changes, check):
    """``--set loading.control=force --set loading.force=5`` on the paper case was refused
    ("key 'loading.depth' given ... remove it"), and --set cannot remove a key: no
    override could switch a shipped case's load control, body or profile."""
    argv = [f"{k}={str(v).lower() if isinstance(v, bool) else v}" for k, v in changes.items()]
    from_cli = cases.load(cases.shipped(name), argv)
    from_api = cases.load(cases.shipped(name)).derive(changes)
    assert check(from_cli) and from_cli == from_api


def test_a_key_set_with_the_flipped_choice_is_still_refused():
    """Only keys the file gave are dropped: one given in the same overrides is the
    user's and still wrong."""
    with pytest.raises(CaseError, match="loading.depth' = 1e-06 given but loading.control"):
        cases.load(cases.shipped("paper"), ["loading.control=force", "loading.force=1",
                                            "loading.depth=1e-6"])
    with pytest.raises(CaseError, match="missing key 'loading.force'"):
        cases.load(cases.shipped("paper"), ["loading.control=force"])


@pytest.mark.parametrize("key, value", [("wear.hardness", 1e-300), ("wear.k", 1e-320)])
def test_a_sliding_scale_out_of_range_names_the_wear_keys(key, value):
    """k μ E*/(σ0 a0) = 1e-4·0.3·2.3e11/(1e-300·1e-4) overflows (and 1e-320·... underflows
    to 0) while the contact itself is fine: the message named 'loading.depth' = 1e-06
    and "the unworn contact", sending the user to the one key that was right."""
    with pytest.raises(CaseError) as err:
        cases.load(cases.shipped("paper"), [f"{key}={value}"])
    text = str(err.value)
    assert f"'{key}' = {value!r}" in text and "loading.depth" not in text


def test_a_directory_as_the_profile_table_is_named_as_one(tmp_path):
    """It said "file does not exist" of a directory that exists."""
    (tmp_path / "profile.csv").mkdir()
    with pytest.raises(CaseError, match=r"indenter\.file.*is a directory, not a CSV file"):
        cases.load(write_table_case(tmp_path, None))


@pytest.mark.parametrize("key, value, unit", [("wear.hardness", "2 GPa", "Pa"),
                                              ("loading.depth", "1 um", "m")])
def test_a_number_written_with_its_unit_says_the_file_is_si(key, value, unit):
    """``hardness = "2 GPa"`` said only "must be a number", which a user who wrote a
    number reads as a riddle: the message names the key's unit and that files are SI."""
    with pytest.raises(CaseError) as err:
        cases.load(cases.shipped("paper"), [f'{key}="{value}"'])
    assert f"must be a number in {unit} (case files are SI" in str(err.value)


def test_a_force_that_presses_a_sphere_past_its_radius_is_bad_input():
    """ball_on_flat (R = 5 mm, E* = 231 GPa) at F = 1e7 N: even Hertz's paraboloid goes
    (3FR/4E*)^(2/3)/R = 6.1 mm > R deep. The MDR ran into its domain's edge ("raise
    mdr.domain_factor", exit 3), the BEM said "the profile does not rise to the depth
    within 10^6 a0". Like a depth past the radius, it is the case's fault: the key."""
    case = cases.load(cases.shipped("ball_on_flat"))
    R, E = case.indenter.radius, case.E_star
    assert (3 * 1e7 * R / (4 * E)) ** (2 / 3) / R > R
    with pytest.raises(CaseError, match=r"'loading.force' = 10000000.0: presses the sphere "
                                        r"deeper than its radius"):
        case.derive({"loading.force": 1e7})
    assert case.derive({"loading.force": 1e5}).loading.force == 1e5  # a0/R = 0.23: allowed


@pytest.mark.parametrize("override, hint", [
    ("wear.muu=0.3", "(did you mean 'mu'?)"),
    ("sliding.schme=\"bdf2\"", "(did you mean 'scheme'?)"),
    ("sliding.mu=0.3", "('mu' is a key of [wear])"),
    ("wera.mu=0.3", "(did you mean 'wear'?)"),
])
def test_a_misspelt_or_misplaced_key_gets_the_near_one(override, hint):
    """A typo was answered with the list of allowed keys only; the near miss is named
    (difflib), and a key put in the wrong section names the section that has it."""
    with pytest.raises(CaseError) as err:
        cases.load(cases.shipped("paper"), [override])
    assert hint in str(err.value)


def test_a_list_written_without_brackets_is_shown_with_them():
    """``--set stages.s_hat=0,1`` said "must be a non-empty list of numbers", to a user
    who gave two numbers: the message shows the TOML spelling."""
    with pytest.raises(CaseError, match=r"written in brackets: \[0, 1\]"):
        cases.load(cases.shipped("paper"), ["stages.s_hat=0,1"])
    # and the spelling it shows is read
    assert cases.load(cases.shipped("paper"), ["stages.s_hat=[0, 1]"]).stages.s_hat == (0, 1)


def test_the_end_condition_says_how_each_kind_of_run_ends():
    """Case.end_condition (the reason a stage was not reached, in ``wearcheck run``'s note
    and the API's warning) names the key that ends the run; under until = "cycles" the
    distance is 2·stroke·cycles."""
    base = cases.from_dict(BASE)
    assert base.end_condition == f"it stops once F < {base.sliding.force_fraction:g} F0"
    assert base.derive({"sliding.until": "distance", "sliding.distance": 0.002}) \
        .end_condition == "it stops at s = 0.002 m"
    cyc = base.derive({"sliding.until": "cycles", "sliding.stroke": 1e-3,
                       "sliding.cycles": 50.0})
    assert cyc.end_condition == "it stops after 50 cycles (s = 0.1 m)"
    fretting = base.derive({"fretting.amplitude": 1e-8, "fretting.cycles": 7})
    assert fretting.end_condition == "it stops after 7 fretting cycles"
