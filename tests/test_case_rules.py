"""The table of cross-key rules (cases/rules.py): the loader and the JSON Schema accept
and refuse the same case files, and overrides drop what the rules make inapplicable.

The property test generates case files around valid ones (a profile, the bodies, a
programme), changes up to three keys or sections among the values each rule turns
on, and compares ``cases.from_dict`` with ``jsonschema``'s draft-07 validator on the
shipped schema. The loader checks every rule the schema states before any
loader-only one, so:

* loader accepts                    -> the schema accepts;
* loader refuses by a key's own declaration or a schema rule -> the schema refuses;
* loader refuses by a loader-only rule -> the schema accepts (every other rule held).

Each rule of the table must be the reason of some refusal in the run: a rule the
generator never breaks would be compared on nothing.
"""

from __future__ import annotations

import json
import sys
from collections import Counter
from pathlib import Path
from types import SimpleNamespace

import jsonschema
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from wearcheck import cases
from wearcheck.cases import CaseError, json_schema, rules
from wearcheck.cases.rule_kinds import Absent, Given, Is, RuleError, View, split
from wearcheck.cases.schema import PROFILES, SECTIONS, section_fields

SCHEMA = json.loads(json_schema.SCHEMA_FILE.read_text(encoding="utf-8"))
VALIDATOR = jsonschema.Draft7Validator(SCHEMA)

#: valid geometry of each profile at the loads below (a0 well inside every body)
GEOMETRY = {
    "paraboloid": {"radius": 0.01},
    "sphere": {"radius": 0.01},
    "truncated_paraboloid": {"radius": 0.01, "flat_radius": 1e-4},
    "cone": {"slope_angle": 0.1},
    "power_law": {"coefficient": 50.0, "exponent": 2.0},
    "table": {"file": "TABLE"},
    "ellipsoid": {"radius": 0.01, "radius_y": 0.03},
}
BODIES = [
    ({"youngs_modulus": 210e9, "poisson_ratio": 0.3}, None),
    ({"youngs_modulus": 210e9, "poisson_ratio": 0.3},
     {"rigid": False, "youngs_modulus": 70e9, "poisson_ratio": 0.2}),
    ({"rigid": True}, {"rigid": False, "youngs_modulus": 70e9, "poisson_ratio": 0.2}),
]
PROGRAMMES = [
    {"loading": {"control": "depth", "depth": 1e-6}},
    {"loading": {"control": "force", "force": 1.0},
     "sliding": {"until": "distance", "distance": 1e-3}},
    {"loading": {"control": "force", "force": 1.0},
     "sliding": {"until": "cycles", "stroke": 1e-3, "cycles": 10.0},
     "stages": {"cycles": [0.0, 5.0]}},
    {"loading": {"control": "depth", "depth": 1e-6}, "stages": {"s_hat": [0.0, 1.0]}},
    {"loading": {"control": "depth", "depth": 1e-6},
     "wear": {"tangential_correction": True}, "sliding": {"stroke": 1e-3}},
    {"loading": {"control": "force", "force": 1.0},
     "fretting": {"amplitude": 1e-8, "cycles": 10}},
    {"loading": {"control": "depth", "depth": 1e-6},
     "fretting": {"force_amplitude": 0.01, "cycles": 10, "stage_cycles": [0, 1, 10]}},
]
#: values each key takes in the changes: valid ones, and ones a rule refuses
POOL = {
    "indenter.profile": list(PROFILES),
    "indenter.radius": [0.01, 1e-4],
    "indenter.radius_y": [0.03],
    "indenter.flat_radius": [1e-4, 0.02],
    "indenter.slope_angle": [0.1],
    "indenter.coefficient": [50.0],
    "indenter.exponent": [2.0],
    "indenter.file": ["TABLE", "no such table.csv"],
    "indenter.rigid": [True, False],
    "indenter.youngs_modulus": [210e9],
    "indenter.poisson_ratio": [0.3],
    "counterface.rigid": [True, False],
    "counterface.youngs_modulus": [70e9],
    "counterface.poisson_ratio": [0.2],
    "counterface.wears": [True, False],
    "counterface.specific_rate": [1e-15],
    "counterface.k": [1e-4],
    "counterface.hardness": [2e9],
    "sliding.motion": ["reciprocating", "unidirectional"],
    "sliding.track_radius": [0.01],
    "bem.track_model": ["long_stroke", "moving"],
    "bem.jump_tolerance": [0.05],
    "loading.control": ["depth", "force"],
    "loading.depth": [1e-6, 0.02, 1e-300],
    "loading.force": [1.0, 1e12],
    "wear.k": [1e-4, 1e-300],
    "wear.specific_rate": [1e-15, 1e-300],
    "wear.tangential_correction": [True, False],
    "sliding.until": ["force_fraction", "distance", "cycles"],
    "sliding.distance": [1e-3, 0.0],
    "sliding.stroke": [1e-3, 1e-9],
    "sliding.cycles": [10.0],
    "sliding.force_fraction": [0.01, 0.5],
    "stages.s_hat": [[0.0, 1.0], [0.0], [1.0, 0.5]],
    "stages.s": [[0.0, 1e-3], [1e-3, 0.0]],
    "stages.cycles": [[0.0, 5.0], [5.0, 1.0]],
    "fretting.amplitude": [1e-8],
    "fretting.force_amplitude": [0.01, 100.0],
    "fretting.cycles": [10],
    "fretting.increments": [40, 10],
    "fretting.stage_cycles": [[0, 1, 10], [0, 1.5], [0, 5, 2]],
}
#: a value no key's declaration allows (a key's own check, not a rule's)
WRONG = "not a value"
#: what a section takes when a change adds it
SECTION_POOL = {"fretting": [{"amplitude": 1e-8, "cycles": 10}],
                "sliding": [{"until": "distance", "distance": 1e-3}, {}],
                "stages": [{"s_hat": [0.0, 1.0]}, {}]}
#: how to break each loader-only rule (the schema cannot see these)
BREAK_LOADER_ONLY = {
    "profile_table": {"indenter.profile": "table", "indenter.file": "no such table.csv"},
    "flat_radius_below_radius": {"indenter.profile": "truncated_paraboloid",
                                 "indenter.radius": 0.01, "indenter.flat_radius": 0.02},
    "increasing('stages.s_hat')": {"stages.s_hat": [1.0, 0.5]},
    "increasing('stages.s')": {"stages.s": [1e-3, 0.0]},
    "increasing('stages.cycles')": {"sliding.stroke": 1e-3, "stages.cycles": [5.0, 1.0]},
    "increasing('fretting.stage_cycles')": {"fretting.amplitude": 1e-8, "fretting.cycles": 10,
                                            "fretting.stage_cycles": [0, 5, 2]},
    "sphere_depth": {"indenter.profile": "sphere", "indenter.radius": 0.01,
                     "loading.control": "depth", "loading.depth": 0.02},
    "sphere_force": {"indenter.profile": "sphere", "indenter.radius": 0.01,
                     "loading.control": "force", "loading.force": 1e12},
    "unworn_contact": {"indenter.profile": "paraboloid", "indenter.radius": 0.01,
                       "loading.control": "depth", "loading.depth": 1e-300},
    "track_radius_beyond_contact": {"sliding.motion": "unidirectional",
                                    "sliding.track_radius": 1e-12},
    "stroke_beyond_reversal": {"wear.tangential_correction": True, "sliding.stroke": 1e-9},
    "force_amplitude_below_friction": {"fretting.force_amplitude": 100.0,
                                       "fretting.cycles": 10},
}


def _set(doc, key, value):
    section, name = split(key)
    if not isinstance(doc.get(section, {}), dict):
        return
    if name is None:
        doc[section] = dict(value)
    else:
        # a section a change starts has what it needs besides (fretting.cycles)
        doc.setdefault(section, dict(SECTION_POOL.get(section, [{}])[0]))[name] = value


def _delete(doc, key):
    section, name = split(key)
    if name is None:
        doc.pop(section, None)
    elif isinstance(doc.get(section), dict):
        doc[section].pop(name, None)


def _value(draw, key):
    section, name = split(key)
    if name is None:
        return draw(st.sampled_from(SECTION_POOL[section]))
    assert key in POOL, f"give POOL values of {key} (tests/test_case_rules.py)"
    return draw(st.sampled_from(POOL[key]))


def _view(doc):
    """The rules' view of a file: each key as given, else its default."""
    built = {}
    for section in SECTIONS:
        table = doc.get(section, {})
        if isinstance(table, dict):
            built[section] = SimpleNamespace(**{n: table.get(n, f.default)
                                                for n, f in section_fields(section)})
    return View(doc, built)


def _falsify(draw, doc, rule, protected):
    """Make one condition of ``rule`` fail, on a key outside ``protected``."""
    for cond in rule.when:
        if cond.key in protected:
            continue
        others = [v for v in POOL.get(cond.key, ()) if v not in getattr(cond, "values", ())]
        if isinstance(cond, Given):
            _delete(doc, cond.key)
            return
        if isinstance(cond, Is) and others:
            _set(doc, cond.key, draw(st.sampled_from(others)))
            return


def _keep_other_rules(draw, doc, aimed):
    """Mend ``doc`` where it breaks a rule (the schema states) before ``aimed`` in the
    table, leaving the keys ``aimed`` reads alone, so that ``aimed`` is the one broken."""
    protected = set(aimed.keys_named())
    before = rules.RULES[:rules.RULES.index(aimed)]   # only these speak before it
    for _ in range(4):
        for rule in before:
            if rules.is_loader_only(rule) or not rule.broken(_view(doc)):
                continue
            given = [k for k in getattr(rule, "keys", ()) if _view(doc).given(k)]
            kind = type(rule).__name__
            if kind == "Requires":
                missing = [k for k in rule.keys if k not in given]
                if set(missing) & protected or not set(missing) <= set(POOL):
                    _falsify(draw, doc, rule, protected)
                for key in set(missing) - protected:
                    _set(doc, key, POOL[key][0])
            elif kind == "Excludes":
                if set(rule.keys) & protected:
                    _falsify(draw, doc, rule, protected)
                for key in set(rule.keys) - protected:
                    _delete(doc, key)
            elif kind == "OneOf":
                keep = [k for k in given if k in protected][:1] or given[:1]
                for key in set(given) - set(keep) - protected:
                    _delete(doc, key)
                if rule.required and not given:
                    _set(doc, rule.keys[0], POOL[rule.keys[0]][0])
            else:
                _falsify(draw, doc, rule, protected)


def _aim(draw, doc, rule):
    """Change ``doc`` so that ``rule`` is broken, and as far as the table allows no rule
    before it (another may still speak first: the comparison holds whichever does)."""
    if rules.is_loader_only(rule):
        for key, value in BREAK_LOADER_ONLY[rule.check.__name__].items():
            _set(doc, key, value)
        _keep_other_rules(draw, doc, rule)
        return
    for cond in getattr(rule, "when", ()):
        if isinstance(cond, Is):
            _set(doc, cond.key, draw(st.sampled_from(cond.values)))
        elif isinstance(cond, Given) and not _view(doc).given(cond.key):
            _set(doc, cond.key, _value(draw, cond.key))
        elif isinstance(cond, Absent):
            _delete(doc, cond.key)
    kind = type(rule).__name__
    keys = list(getattr(rule, "keys", ()))
    if kind == "Requires":
        _delete(doc, draw(st.sampled_from(keys)))
    elif kind == "Excludes":
        key = draw(st.sampled_from(keys))
        if split(key)[1] is None:   # a whole section, given at values not its defaults
            _set(doc, key, draw(st.sampled_from([v for v in SECTION_POOL[key] if v])))
        else:
            _set(doc, key, _value(draw, key))
    elif kind == "OneOf":
        if rule.required and draw(st.booleans()):
            for key in keys:
                _delete(doc, key)
        else:
            for key in draw(st.lists(st.sampled_from(keys), min_size=2, max_size=2,
                                     unique=True)):
                _set(doc, key, _value(draw, key))
    _keep_other_rules(draw, doc, rule)


@st.composite
def case_files(draw, table: str, aimed=None):
    """A valid case, changed by up to three keys; with ``aimed``, first changed to break
    that rule of the table."""
    profile = draw(st.sampled_from(PROFILES))
    indenter_body, counterface = draw(st.sampled_from(BODIES))
    doc = {"indenter": {"profile": profile, **GEOMETRY[profile], **indenter_body},
           "wear": {"k": 1e-4, "mu": 0.3, "hardness": 2e9}}
    if counterface is not None:
        doc["counterface"] = dict(counterface)
    for section, table_ in draw(st.sampled_from(PROGRAMMES)).items():
        doc.setdefault(section, {}).update(table_)
    if aimed is not None:
        _aim(draw, doc, aimed)
    for _ in range(draw(st.sampled_from([0, 0, 1] if aimed else [0, 1, 1, 2, 3]))):
        action = draw(st.sampled_from(["set"] * 6 + ["delete"] * 2 + ["section", "wrong"]))
        key = draw(st.sampled_from(sorted(POOL)))
        section, name = split(key)
        if action == "set":
            _set(doc, key, draw(st.sampled_from(POOL[key])))
        elif action == "delete":
            _delete(doc, key)
        elif action == "section":
            if section in doc:
                del doc[section]
            else:
                doc[section] = {}
        else:
            _set(doc, key, WRONG)
    for section in doc.values():
        if isinstance(section, dict) and section.get("file") == "TABLE":
            section["file"] = table
    return doc


def _loader(doc):
    """None if the loader accepts ``doc``, else (the rule that refused it or None, message)."""
    try:
        cases.from_dict(doc)
    except RuleError as exc:
        return exc.rule, str(exc)
    except CaseError as exc:
        return None, str(exc)
    return None


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    """A valid profile table: the paraboloid of R = 0.01 m out to r = 1 mm."""
    path = tmp_path_factory.mktemp("table") / "profile.csv"
    path.write_text("r,f\n" + "\n".join(f"{i * 1e-5!r},{(i * 1e-5) ** 2 / 0.02!r}"
                                         for i in range(101)), encoding="utf-8")
    return str(path)


def _compare(doc, hits: Counter) -> None:
    """Loader and schema on one file (module docstring); counts why it was refused."""
    refused = _loader(doc)
    schema_ok = VALIDATOR.is_valid(doc)
    if refused is None:
        hits["accepted"] += 1
        assert schema_ok, f"loader accepts, schema refuses: {doc}"
        return
    rule, message = refused
    assert "\n" not in message
    if rule is None:
        hits["a key's own declaration"] += 1
        assert not schema_ok, f"loader refuses ({message}), schema accepts: {doc}"
        return
    hits[rule] += 1
    # the message names a key (or section) the rule reads
    assert any(k in message or f"[{k}]" in message for k in rule.keys_named()), message
    if rules.is_loader_only(rule):
        assert schema_ok, (f"refused by a loader-only rule ({message}) but the schema "
                           f"refuses it too: a rule it states was not checked first: {doc}")
    else:
        assert not schema_ok, f"loader refuses ({message}), schema accepts: {doc}"


#: derandomized: the same files on every run
RUN = dict(deadline=None, derandomize=True, database=None,
           suppress_health_check=[HealthCheck.too_slow])


def test_loader_and_json_schema_agree_on_changed_files(table):
    hits = Counter()

    @settings(max_examples=300, **RUN)
    @given(doc=case_files(table))
    def agree(doc):
        _compare(doc, hits)

    agree()
    # both sides of the comparison were exercised (counts of this derandomized run:
    # well above these floors)
    assert hits["accepted"] >= 50 and hits["a key's own declaration"] >= 20
    assert len(hits) - 2 >= 15   # distinct rules that refused a file


@pytest.mark.parametrize("rule", rules.RULES,
                         ids=[f"{i}-{type(r).__name__}" for i, r in enumerate(rules.RULES)])
def test_loader_and_json_schema_agree_on_files_that_break_each_rule(table, rule):
    """Files aimed at one rule: the rule must be the reason of some refusal (a rule no
    file breaks would be compared on nothing)."""
    hits = Counter()

    @settings(max_examples=12, **RUN)
    @given(doc=case_files(table, aimed=rule))
    def agree(doc):
        _compare(doc, hits)

    agree()
    assert hits[rule] >= 1, dict(hits)


def test_every_rule_is_stated_by_the_schema_or_marked_loader_only():
    """The shipped schema holds each non-loader-only rule's fragment where the table puts it."""
    placed = rules.schema_rules()
    count = sum(len(v) for v in placed.values())
    assert count == sum(not rules.is_loader_only(r) for r in rules.RULES)
    for at, fragments in placed.items():
        holder = SCHEMA if at is None else SCHEMA["properties"][at]
        assert holder["allOf"] == fragments


def _old_inapplicable(section, key, value):
    """The hand-written function the table replaces (cases/case.py before the table)."""
    geometry = {"radius", "radius_y", "flat_radius", "slope_angle", "coefficient", "exponent",
                "file"}
    if (section, key) == ("loading", "control") and value in ("depth", "force"):
        return {"force"} if value == "depth" else {"depth"}
    if section in ("indenter", "counterface") and key == "rigid" and value is True:
        return {"youngs_modulus", "poisson_ratio"}
    if (section, key) == ("indenter", "profile") and value in rules.PROFILE_KEYS:
        return geometry - rules.PROFILE_KEYS[value]
    if (section, key) == ("sliding", "until") and isinstance(value, str):
        return {k for k in ("distance", "cycles") if k != value}
    return set()


@pytest.mark.parametrize("section, key, value", [
    *(("indenter", "profile", p) for p in PROFILES),
    ("loading", "control", "depth"), ("loading", "control", "force"),
    ("indenter", "rigid", True), ("indenter", "rigid", False),
    ("counterface", "rigid", True), ("counterface", "rigid", False),
    ("sliding", "until", "force_fraction"), ("sliding", "until", "distance"),
    ("sliding", "until", "cycles"), ("wear", "mu", 0.3), ("indenter", "rigid", 1),
])
def test_overrides_drop_what_the_old_hand_written_list_dropped(section, key, value):
    assert set(rules.inapplicable(section, key, value)) == _old_inapplicable(section, key, value)


def test_keys_given_one_way_or_another_replace_each_other():
    assert rules.partners("stages", "s_hat") == ("s", "cycles")
    assert rules.partners("stages", "cycles") == ("s_hat", "s")
    assert rules.partners("fretting", "amplitude") == ("force_amplitude",)
    assert rules.partners("wear", "specific_rate") == ("k",)
    assert rules.partners("wear", "mu") == ()
    # derive() replaces as --set does (before the table only the fretting amplitudes did:
    # case.derive(stages__cycles=...) was refused as "both given")
    paper = cases.load(cases.shipped("paper"))
    derived = paper.derive({"sliding.stroke": 1e-3, "stages.cycles": [0.0, 5.0]})
    assert derived == cases.load(cases.shipped("paper"),
                                 ["sliding.stroke=1e-3", "stages.cycles=[0.0, 5.0]"])
    assert derived.stages.cycles == (0.0, 5.0)


def test_every_rule_reads_declared_keys():
    keys = {f"{s}.{n}" for s in cases.case.SECTIONS for n, _ in section_fields(s)}
    for rule in rules.RULES:
        for k in rule.keys_named():
            assert k in keys or k in cases.case.SECTIONS, (rule, k)


def test_the_docs_list_every_rule_and_who_checks_it():
    text = rules.reference()
    assert len(text.splitlines()) == len(rules.RULES) + 2
    assert text.count("the loader only") == sum(map(rules.is_loader_only, rules.RULES))
    # docs/case-files.md includes the table, generated at every docs build
    docs = Path(__file__).resolve().parents[1] / "docs"
    assert "```{include} _generated/case-rules.md" in (docs / "case-files.md").read_text()
    sys.path.insert(0, str(docs / "_ext"))
    try:
        import wearcheck_docs
    finally:
        sys.path.remove(str(docs / "_ext"))
    assert wearcheck_docs.generated_pages()["case-rules.md"].strip() == text
