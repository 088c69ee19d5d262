"""The JSON Schema of a case file, generated from the declarations in ``schema.py``.

Editors that read JSON Schemas for TOML (taplo, VS Code's Even Better TOML) use
it for completion, hover documentation and checks as you type. The package
ships it as ``case.schema.json``; regenerate that file after changing a key::

    python -m wearcheck.cases.json_schema > cases/case.schema.json

The schema states types, units, allowed values, ranges, defaults, unknown keys,
which keys each profile, load control, end of run and rigid or elastic body
needs or refuses, that wear takes one of ``k`` and ``specific_rate`` and the
stages one of ``s_hat``, ``s`` and ``cycles``, and that cycles need a stroke. The loader's other checks (a table file's contents, flat
radius below radius, strictly increasing stages, at least one elastic body,
the unworn contact computable) stay with ``cases.load``, which remains the
authority: a file the schema accepts may still be refused there, with a message.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from .schema import (PROFILE_KEYS, PROFILE_REQUIRED, REQUIRED_SECTIONS, SECTIONS, base_types,
                     section_fields)

#: where the package keeps the generated schema
SCHEMA_FILE = Path(__file__).resolve().parent / "case.schema.json"

# draft-07: the newest draft that taplo (and so Even Better TOML) reads
DIALECT = "http://json-schema.org/draft-07/schema#"

_JSON_TYPES = {float: "number", int: "integer", bool: "boolean", str: "string"}


def _number_bounds(meta) -> dict:
    out = {}
    if meta["positive"]:
        out["exclusiveMinimum"] = 0
    lo, hi = meta["minimum"], meta["maximum"]
    if lo is not None:
        out["exclusiveMinimum" if meta["open_minimum"] else "minimum"] = lo
    if hi is not None:
        out["exclusiveMaximum" if meta["open_maximum"] else "maximum"] = hi
    return out


def _description(meta) -> str:
    text = meta["doc"]
    unit = meta["unit"]
    if unit and unit != "1":
        text += f" [{unit}]"
    elif unit == "1":
        text += " [dimensionless]"
    if meta["choices"]:
        text += " (one of: " + ", ".join(meta["choices"]) + ")"
    return text


def key_schema(f) -> dict:
    """The schema of one declared key (a dataclass field of ``schema.py``)."""
    meta = f.metadata
    allowed = base_types(f.type)
    out: dict = {"description": _description(meta)}
    if any(getattr(t, "__origin__", None) is tuple for t in allowed):  # list of numbers
        out.update(type="array", minItems=1, items={"type": "number", **_number_bounds(meta)})
    elif float in allowed and str in allowed:  # a number or "auto"
        out["anyOf"] = [{"type": "number", **_number_bounds(meta)}, {"const": "auto"}]
    else:
        (tp,) = allowed
        out["type"] = _JSON_TYPES[tp]
        if tp in (float, int):
            out.update(_number_bounds(meta))
        if meta["choices"]:
            out["enum"] = list(meta["choices"])
    if not meta["required"] and f.default is not None:
        out["default"] = list(f.default) if isinstance(f.default, tuple) else f.default
    if meta["unit"]:
        out["x-unit"] = meta["unit"]
    return out


def _section_schema(section: str) -> dict:
    cls = SECTIONS[section]
    doc = (cls.__doc__ or "").strip()
    if doc.startswith(cls.__name__ + "("):  # the dataclass's generated signature
        doc = ""
    out: dict = {"type": "object", "additionalProperties": False}
    if doc:
        out["description"] = doc.splitlines()[0]
    out["properties"] = {name: key_schema(f) for name, f in section_fields(section)}
    required = [name for name, f in section_fields(section) if f.metadata["required"]]
    if required:
        out["required"] = required
    return out


def _indenter_rules() -> list[dict]:
    """Per profile: the geometry keys it needs, and those it does not take."""
    geometry = sorted(set().union(*PROFILE_KEYS.values()))
    rules = []
    for profile in PROFILE_KEYS:
        then: dict = {}
        if PROFILE_REQUIRED[profile]:
            then["required"] = sorted(PROFILE_REQUIRED[profile])
        banned = [k for k in geometry if k not in PROFILE_KEYS[profile]]
        if banned:
            then["properties"] = {k: False for k in banned}
        rules.append({"if": {"properties": {"profile": {"const": profile}},
                             "required": ["profile"]},
                      "then": then})
    return rules


def _loading_rules() -> list[dict]:
    """The load control needs its own key and refuses the other one."""
    return [{"if": {"properties": {"control": {"const": control}}, "required": ["control"]},
             "then": {"required": [control], "properties": {other: False}}}
            for control, other in (("depth", "force"), ("force", "depth"))]


def _sliding_rules() -> list[dict]:
    """until = distance needs sliding.distance; until = force_fraction (the default)
    refuses it."""
    by_distance = {"properties": {"until": {"const": "distance"}}, "required": ["until"]}
    return [{"if": by_distance, "then": {"required": ["distance"]},
             "else": {"properties": {"distance": False}}}]


def _one_of_rules(section: str) -> list[dict]:
    """Keys given one way or another (``case._ONE_OF``): never two of a group; wear needs
    one of its pair (k or specific_rate), the stages take the default ŝ without any."""
    from .case import _ONE_OF
    rules = []
    for group in _ONE_OF[section]:
        pairs = [[a, b] for i, a in enumerate(group) for b in group[i + 1:]]
        rules.append({"not": {"anyOf": [{"required": pair} for pair in pairs]}})
        if section == "wear":
            rules.append({"anyOf": [{"required": [name]} for name in group]})
    return rules


def _cycles_rules() -> list[dict]:
    """Cycles need a stroke: until = cycles needs sliding.stroke and sliding.cycles (and
    refuses sliding.cycles otherwise); stages.cycles needs sliding.stroke (across sections)."""
    by_cycles = {"properties": {"until": {"const": "cycles"}}, "required": ["until"]}
    sliding = [{"if": by_cycles, "then": {"required": ["stroke", "cycles"]},
                "else": {"properties": {"cycles": False}}}]
    stages = [{"if": {"properties": {"stages": {"required": ["cycles"]}},
                      "required": ["stages"]},
               "then": {"required": ["sliding"],
                        "properties": {"sliding": {"required": ["stroke"]}}}}]
    return sliding, stages


def _body_rules(section: str) -> list[dict]:
    """A rigid body takes no elastic constants; an elastic one needs both."""
    default = dict(section_fields(section))["rigid"].default
    elastic = ["youngs_modulus", "poisson_ratio"]
    if default:
        rigid = {"not": {"properties": {"rigid": {"const": False}}, "required": ["rigid"]}}
    else:
        rigid = {"properties": {"rigid": {"const": True}}, "required": ["rigid"]}
    return [{"if": rigid, "then": {"properties": {k: False for k in elastic}},
             "else": {"required": elastic}}]


def case_schema() -> dict:
    """The JSON Schema (draft-07) of a wearcheck case file, as a dict."""
    sections = {name: _section_schema(name) for name in SECTIONS}
    sections["indenter"]["allOf"] = _indenter_rules()
    sections["loading"]["allOf"] = _loading_rules()
    sliding_cycles, stages_cycles = _cycles_rules()
    sections["sliding"]["allOf"] = _sliding_rules() + sliding_cycles
    sections["indenter"]["allOf"] += _body_rules("indenter")
    sections["counterface"]["allOf"] = _body_rules("counterface")
    sections["wear"]["allOf"] = _one_of_rules("wear")
    sections["stages"]["allOf"] = _one_of_rules("stages")
    return {
        "$schema": DIALECT,
        "title": "wearcheck case file",
        "description": "One wearcheck case (TOML, SI units). Generated from "
                       "wearcheck.cases.schema; every key's unit is in its description "
                       "and in x-unit.",
        "type": "object",
        "additionalProperties": False,
        "required": list(REQUIRED_SECTIONS),
        "properties": sections,
        "allOf": stages_cycles,
    }


def schema_text() -> str:
    """The schema as the text of ``case.schema.json``."""
    def finite(x):  # JSON has no inf; no declared bound is infinite, checked here
        if isinstance(x, float) and not math.isfinite(x):
            raise ValueError(f"bound {x!r} is not finite")
        return x
    text = json.dumps(case_schema(), indent=2, ensure_ascii=False, allow_nan=False)
    json.loads(text, parse_float=lambda s: finite(float(s)))
    return text + "\n"


if __name__ == "__main__":
    import sys
    sys.stdout.write(schema_text())
