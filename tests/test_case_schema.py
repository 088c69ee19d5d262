"""The JSON Schema of case files: shipped file = generated, shipped cases valid,
bad input rejected as the loader rejects it."""

import json
import tomllib

import pytest

from wearcheck import cases
from wearcheck.cases import CaseError, from_dict, json_schema
from wearcheck.cases.schema import SECTIONS, section_fields

KEYWORDS = {"$schema", "title", "description", "type", "properties", "additionalProperties",
            "required", "enum", "const", "minimum", "maximum", "exclusiveMinimum",
            "exclusiveMaximum", "items", "minItems", "anyOf", "allOf", "if", "then", "else",
            "not", "default", "x-unit"}
TYPES = {"object": dict, "array": list, "string": str, "boolean": bool}


def _keywords(schema):
    """Every keyword used anywhere in the schema."""
    if isinstance(schema, bool):
        return set()
    used = set(schema)
    for k in ("items", "if", "then", "else", "not"):
        if k in schema:
            used |= _keywords(schema[k])
    for k in ("anyOf", "allOf"):
        for s in schema.get(k, []):
            used |= _keywords(s)
    for s in schema.get("properties", {}).values():
        used |= _keywords(s)
    return used


def _valid(schema, value) -> bool:
    """A small draft-07 validator for exactly the keywords in KEYWORDS, so the test
    does not depend on the jsonschema package (it is compared with it when present)."""
    if isinstance(schema, bool):
        return schema
    tp = schema.get("type")
    if tp == "number" and (isinstance(value, bool) or not isinstance(value, (int, float))):
        return False
    # draft-06 on: an integer is any number with a zero fractional part (1.6e3 is one)
    if tp == "integer" and (isinstance(value, bool) or not isinstance(value, (int, float))
                            or (isinstance(value, float) and not value.is_integer())):
        return False
    if tp in TYPES and not isinstance(value, TYPES[tp]):
        return False
    if "enum" in schema and value not in schema["enum"]:
        return False
    if "const" in schema and not (value == schema["const"]
                                  and type(value) is type(schema["const"])):
        return False
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if "minimum" in schema and value < schema["minimum"]:
            return False
        if "maximum" in schema and value > schema["maximum"]:
            return False
        if "exclusiveMinimum" in schema and value <= schema["exclusiveMinimum"]:
            return False
        if "exclusiveMaximum" in schema and value >= schema["exclusiveMaximum"]:
            return False
    if isinstance(value, list):
        if len(value) < schema.get("minItems", 0):
            return False
        if "items" in schema and not all(_valid(schema["items"], v) for v in value):
            return False
    if isinstance(value, dict):
        if any(k not in value for k in schema.get("required", [])):
            return False
        props = schema.get("properties", {})
        for k, v in value.items():
            if k in props:
                if not _valid(props[k], v):
                    return False
            elif schema.get("additionalProperties", True) is False:
                return False
    if "anyOf" in schema and not any(_valid(s, value) for s in schema["anyOf"]):
        return False
    if "allOf" in schema and not all(_valid(s, value) for s in schema["allOf"]):
        return False
    if "not" in schema and _valid(schema["not"], value):
        return False
    if "if" in schema:
        branch = schema.get("then" if _valid(schema["if"], value) else "else", True)
        if not _valid(branch, value):
            return False
    return True


try:
    import jsonschema
except ImportError:  # not a dependency: the walker above then stands alone
    jsonschema = None

SCHEMA = json_schema.case_schema()


def _validators():
    out = [_valid]
    if jsonschema is not None:
        v = jsonschema.Draft7Validator(SCHEMA)
        out.append(lambda schema, value: v.is_valid(value))
    return out


def test_the_shipped_file_is_the_generated_schema():
    shipped = json.loads(json_schema.SCHEMA_FILE.read_text(encoding="utf-8"))
    assert shipped == SCHEMA, ("cases/case.schema.json is stale: regenerate it with "
                               "python -m wearcheck.cases.json_schema > cases/case.schema.json")
    assert json_schema.SCHEMA_FILE.read_text(encoding="utf-8") == json_schema.schema_text()


def test_the_schema_uses_only_known_keywords_and_is_a_draft7_schema():
    assert _keywords(SCHEMA) <= KEYWORDS
    if jsonschema is not None:
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
    for valid in _validators():
        assert valid(SCHEMA, raw), name


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
    "stages in cycles with a stroke, any until": _with(("sliding", "stroke", 1e-3),
                                                       ("stages", "cycles", [0, 10])),
    "until = cycles": _with(("sliding", "until", "cycles"), ("sliding", "stroke", 1e-3),
                            ("sliding", "cycles", 100)),
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
    "stages in cycles without a stroke": _with(("stages", "cycles", [0, 10])),
    "until = cycles without a stroke": _with(("sliding", "until", "cycles"),
                                             ("sliding", "cycles", 100)),
    "cycles without until = cycles": _with(("sliding", "stroke", 1e-3),
                                           ("sliding", "cycles", 100)),
}


@pytest.mark.parametrize("label", GOOD)
def test_cases_the_loader_accepts_validate(label):
    from_dict(GOOD[label])  # the loader accepts it: the example is a valid case
    for valid in _validators():
        assert valid(SCHEMA, GOOD[label]), label


@pytest.mark.parametrize("label", BAD)
def test_bad_input_is_rejected_by_schema_and_loader(label):
    with pytest.raises(CaseError):
        from_dict(BAD[label])
    for valid in _validators():
        assert not valid(SCHEMA, BAD[label]), label
