"""The JSON Schema of a case file, generated from the declarations in ``schema.py``.

Editors that read JSON Schemas for TOML (taplo, VS Code's Even Better TOML) use
it for completion, hover documentation and checks as you type. The package
ships it as ``case.schema.json``; regenerate that file after changing a key::

    python -m wearcheck.cases.json_schema > cases/case.schema.json

The schema states every key's type, unit, allowed values, range and default,
unknown keys, and every rule between keys of ``cases/rules.py`` but those the
table marks loader-only (numeric relations between keys such as a flat radius
below the radius, strictly increasing stages, a profile table's contents, the
unworn contact computable): ``cases.load`` checks those too, so a file the
schema accepts may still be refused there, with a message; a file the schema
refuses the loader refuses (tests/test_case_rules.py).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from . import rules
from .schema import REQUIRED_SECTIONS, SECTIONS, base_types, section_fields

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
    if meta["multiple_of"] is not None:
        out["multipleOf"] = meta["multiple_of"]
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


def case_schema() -> dict:
    """The JSON Schema (draft-07) of a wearcheck case file, as a dict."""
    sections = {name: _section_schema(name) for name in SECTIONS}
    placed = rules.schema_rules()
    for name, fragments in placed.items():
        if name is not None:
            sections[name]["allOf"] = fragments
    out = {
        "$schema": DIALECT,
        "title": "wearcheck case file",
        "description": "One wearcheck case (TOML, SI units). Generated from "
                       "wearcheck.cases.schema; every key's unit is in its description "
                       "and in x-unit.",
        "type": "object",
        "additionalProperties": False,
        "required": list(REQUIRED_SECTIONS),
        "properties": sections,
    }
    if None in placed:   # rules across sections
        out["allOf"] = placed[None]
    return out


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
