"""The JSON Schema of case files: shipped file = generated, shipped cases valid,
bad input rejected as the loader rejects it (and tests/test_case_rules.py: the two
agree on generated cases)."""

import json
import tomllib

import pytest

from wearcheck import cases
from wearcheck.cases import CaseError, from_dict, json_schema
from wearcheck.cases.schema import SECTIONS, section_fields

import jsonschema

#: the keywords the schema may use: draft-07 ones that taplo (Even Better TOML) reads
KEYWORDS = {"$schema", "title", "description", "type", "properties", "additionalProperties",
            "required", "enum", "const", "minimum", "maximum", "exclusiveMinimum",
            "exclusiveMaximum", "multipleOf", "items", "minItems", "anyOf", "allOf", "oneOf",
            "if", "then", "else", "not", "default", "x-unit"}


def _keywords(schema):
    """Every keyword used anywhere in the schema."""
    if isinstance(schema, bool):
        return set()
    used = set(schema)
    for k in ("items", "if", "then", "else", "not"):
        if k in schema:
            used |= _keywords(schema[k])
    for k in ("anyOf", "allOf", "oneOf"):
        for s in schema.get(k, []):
            used |= _keywords(s)
    for s in schema.get("properties", {}).values():
        used |= _keywords(s)
    return used


SCHEMA = json_schema.case_schema()
VALIDATOR = jsonschema.Draft7Validator(SCHEMA)


def _valid(schema, value) -> bool:
    return jsonschema.Draft7Validator(schema).is_valid(value)


def test_the_shipped_file_is_the_generated_schema():
    shipped = json.loads(json_schema.SCHEMA_FILE.read_text(encoding="utf-8"))
    assert shipped == SCHEMA, ("cases/case.schema.json is stale: regenerate it with "
                               "python -m wearcheck.cases.json_schema > cases/case.schema.json")
    assert json_schema.SCHEMA_FILE.read_text(encoding="utf-8") == json_schema.schema_text()


def test_the_schema_uses_only_known_keywords_and_is_a_draft7_schema():
    assert _keywords(SCHEMA) <= KEYWORDS
    jsonschema.Draft7Validator.check_schema(SCHEMA)


def test_every_declared_key_is_in_the_schema_with_unit_and_default():
    props = SCHEMA["properties"]
    assert list(props) == list(SECTIONS)
    for section in SECTIONS:
        assert props[section]["additionalProperties"] is False
        for name, f in section_fields(section):
            key = props[section]["properties"][name]
            meta = f.metadata
            assert meta["doc"] in key["description"]
            if meta["unit"] not in ("", "1"):
                assert f"[{meta['unit']}]" in key["description"]
                assert key["x-unit"] == meta["unit"]
            if meta["choices"]:
                assert key["enum"] == list(meta["choices"])
            if meta["required"]:
                assert name in props[section]["required"]
            elif f.default is not None:
                default = list(f.default) if isinstance(f.default, tuple) else f.default
                assert key["default"] == default
                # a default must itself be valid
                assert _valid(key, default), (section, name)


@pytest.mark.parametrize("name", sorted(cases.shipped_cases()))
def test_every_shipped_case_validates(name):
    raw = tomllib.loads(cases.shipped(name).read_text(encoding="utf-8"))
    assert VALIDATOR.is_valid(raw), name


BASE = tomllib.loads("""
[indenter]
profile = "sphere"
radius = 0.01
youngs_modulus = 210e9
poisson_ratio = 0.3
[loading]
control = "depth"
depth = 1e-6
[wear]
k = 1e-4
mu = 0.3
hardness = 2e9
""")


def _with(*edits):
    """BASE changed by (section, key, value) edits; value None removes the key."""
    raw = {s: dict(t) for s, t in BASE.items()}
    for section, key, value in edits:
        if key is None:
            raw.pop(section, None) if value is None else raw.__setitem__(section, value)
            continue
        table = raw.setdefault(section, {})
        if value is None:
            table.pop(key, None)
        else:
            table[key] = value
    return raw


GOOD = {
    "base": _with(),
    "cone": _with(("indenter", "profile", "cone"), ("indenter", "radius", None),
                  ("indenter", "slope_angle", 0.1)),
    "force control": _with(("loading", "control", "force"), ("loading", "depth", None),
                           ("loading", "force", 1.0), ("sliding", "until", "distance"),
                           ("sliding", "distance", 1e-3)),
    "elastic counterface": _with(("counterface", "rigid", False),
                                 ("counterface", "youngs_modulus", 70e9),
                                 ("counterface", "poisson_ratio", 0.2)),
    "rigid indenter": _with(("indenter", "rigid", True), ("indenter", "youngs_modulus", None),
                            ("indenter", "poisson_ratio", None), ("counterface", "rigid", False),
                            ("counterface", "youngs_modulus", 70e9),
                            ("counterface", "poisson_ratio", 0.2)),
    "integer where a number is asked": _with(("wear", "hardness", 2000000000)),
    "integral float for an integer": _with(("mdr", "elements", 1.6e3)),
    "step auto and stages": _with(("sliding", "step_hat", "auto"), ("stages", "s_hat", [0, 1.5])),
    "numeric step": _with(("sliding", "scheme", "bdf2"), ("sliding", "step_hat", 0.05)),
    "specific wear rate instead of k": _with(("wear", "k", None),
                                             ("wear", "specific_rate", 1e-14)),
    "stages in metres": _with(("stages", "s", [0.0, 0.5, 2.0])),
    "until = cycles": _with(("sliding", "until", "cycles"), ("sliding", "stroke", 1e-3),
                            ("sliding", "cycles", 100)),
    "stages in cycles with a stroke": _with(("sliding", "stroke", 1e-3),
                                            ("stages", "cycles", [0, 10])),
    "fretting, [sliding] at its defaults": _with(
        ("fretting", None, {"amplitude": 1e-7, "cycles": 10, "stage_cycles": [0.0, 2.0]}),
        ("sliding", "until", "force_fraction"), ("stages", "s_hat", [0])),
}

BAD = {
    "unknown key": _with(("indenter", "radiuss", 0.01)),
    "unknown section": _with(("mdrr", "elements", 800)),
    "missing section": _with(("wear", None, None)),
    "missing key": _with(("wear", "k", None)),
    "string for a number": _with(("wear", "k", "big")),
    "boolean for a number": _with(("wear", "mu", True)),
    "number below its range": _with(("wear", "k", -1e-4)),
    "number above its range": _with(("indenter", "poisson_ratio", 0.7)),
    "open bound reached": _with(("indenter", "poisson_ratio", -1.0)),
    "not a choice": _with(("sliding", "scheme", "rk4")),
    "float for an integer": _with(("mdr", "elements", 800.5)),
    "integer below its minimum": _with(("mdr", "elements", 1)),
    "word for a step": _with(("sliding", "step_hat", "fast")),
    "zero step": _with(("sliding", "step_hat", 0)),
    "empty stage list": _with(("stages", "s_hat", [])),
    "negative stage": _with(("stages", "s_hat", [-1.0])),
    "section not a table": _with(("wear", None, 3)),
    "profile lacks its key": _with(("indenter", "radius", None)),
    "key the profile does not take": _with(("indenter", "flat_radius", 1e-5)),
    "control lacks its key": _with(("loading", "depth", None)),
    "both depth and force": _with(("loading", "force", 1.0)),
    "distance without until = distance": _with(("sliding", "distance", 1e-3)),
    "until = distance without a distance": _with(("sliding", "until", "distance")),
    "rigid body with a modulus": _with(("counterface", "youngs_modulus", 70e9)),
    "elastic body without moduli": _with(("indenter", "youngs_modulus", None)),
    "k and specific_rate both": _with(("wear", "specific_rate", 1e-14)),
    "neither k nor specific_rate": _with(("wear", "k", None), ("wear", "specific_rate", None)),
    "specific_rate not positive": _with(("wear", "k", None), ("wear", "specific_rate", 0.0)),
    "stages in metres and in ŝ": _with(("stages", "s", [0.0, 1.0]), ("stages", "s_hat", [0.0])),
    "stages in metres and cycles": _with(("sliding", "stroke", 1e-3), ("stages", "s", [0.0]),
                                         ("stages", "cycles", [0.0])),
    "negative stage in metres": _with(("stages", "s", [-1.0])),
    # rules the loader enforced and the schema had lost before cases/rules.py
    "until = cycles without a stroke": _with(("sliding", "until", "cycles"),
                                             ("sliding", "cycles", 100)),
    "cycles without until = cycles": _with(("sliding", "stroke", 1e-3),
                                           ("sliding", "cycles", 100)),
    "force_fraction under force control": _with(("loading", "control", "force"),
                                                ("loading", "depth", None),
                                                ("loading", "force", 1.0)),
    "stages both ways": _with(("sliding", "stroke", 1e-3), ("stages", "s_hat", [0.0]),
                              ("stages", "cycles", [0.0])),
    "stages in cycles without a stroke": _with(("stages", "cycles", [0, 10])),
    "both bodies rigid": _with(("indenter", "rigid", True), ("indenter", "youngs_modulus", None),
                               ("indenter", "poisson_ratio", None)),
    "tangential correction without a stroke": _with(("wear", "tangential_correction", True)),
    "fretting with [sliding]": _with(("fretting", None, {"amplitude": 1e-7, "cycles": 10}),
                                     ("sliding", "until", "distance"),
                                     ("sliding", "distance", 1.0)),
    "fretting without an amplitude": _with(("fretting", None, {"cycles": 10})),
    "fretting with both amplitudes": _with(("fretting", None, {"amplitude": 1e-7, "cycles": 10,
                                                               "force_amplitude": 1.0})),
    "fretting with the tangential correction": _with(
        ("fretting", None, {"amplitude": 1e-7, "cycles": 10}),
        ("wear", "tangential_correction", True)),
    "fretting increments not a multiple of 4": _with(
        ("fretting", None, {"amplitude": 1e-7, "cycles": 10, "increments": 10})),
    "fretting stage not a whole cycle": _with(
        ("fretting", None, {"amplitude": 1e-7, "cycles": 10, "stage_cycles": [0, 1.5]})),
}


@pytest.mark.parametrize("label", GOOD)
def test_cases_the_loader_accepts_validate(label):
    from_dict(GOOD[label])  # the loader accepts it: the example is a valid case
    assert VALIDATOR.is_valid(GOOD[label]), label


@pytest.mark.parametrize("label", BAD)
def test_bad_input_is_rejected_by_schema_and_loader(label):
    with pytest.raises(CaseError):
        from_dict(BAD[label])
    assert not VALIDATOR.is_valid(BAD[label]), label


@pytest.mark.parametrize("value", ["1e-15", "1e-11", "0"])
def test_an_adaptive_tolerance_below_round_off_is_refused(value):
    """sliding.tolerance below 1e-10 is never met in float64 (the step-doubling estimate
    carries ~1e-13-1e-12 round-off): refused up front, naming the key, value and range,
    instead of a run that shrinks its step for minutes."""
    with pytest.raises(CaseError, match=r"key 'sliding\.tolerance' = .*: must be in "
                                        r"\[1e-10, 0\.1\]"):
        cases.load(cases.shipped("paper"), [f"sliding.tolerance={value}"])
    # the floor itself and the smallest tolerance used anywhere (1e-6) are accepted
    assert cases.load(cases.shipped("paper"), ["sliding.tolerance=1e-10"]).sliding.tolerance == 1e-10
