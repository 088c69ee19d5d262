"""The kinds of cross-key rule, each with its check, its message and its JSON Schema.

A rule is a small frozen dataclass; the table of them is ``cases/rules.py``.
Each kind answers three questions from one declaration, so that they cannot
drift apart:

* :meth:`broken` -- the loader's check: a one-line message naming the key, its
  value and what is allowed, or None;
* :meth:`schema` -- the same rule as a draft-07 JSON Schema fragment;
* :meth:`text` -- the rule in words, for the documentation.

Conditions (:class:`Is`, :class:`Given`, :class:`Absent`) see a key at its
default when the file leaves it out, as the loader does: ``Is("sliding.until",
"force_fraction")`` holds for a case without ``sliding.until``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import combinations
from typing import Any, Callable

from .errors import CaseError
from .schema import REQUIRED_SECTIONS, format_value, section_fields


class RuleError(CaseError):
    """A case refused by a rule of ``cases/rules.py``; ``rule`` is that rule."""

    def __init__(self, message: str, rule):
        super().__init__(message)
        self.rule = rule


def split(key: str) -> tuple[str, str | None]:
    """``"sliding.until"`` -> ``("sliding", "until")``; a section name -> ``(name, None)``."""
    section, _, name = key.partition(".")
    return section, name or None


def default(key: str):
    """The declared default of ``section.key`` (None when it has none or is required)."""
    section, name = split(key)
    return dict(section_fields(section))[name].default


def switch_values(key: str) -> tuple:
    """Every value a switch (a key of choices, or true/false) takes."""
    section, name = split(key)
    return tuple(dict(section_fields(section))[name].metadata["choices"] or (True, False))


def _same(a, b) -> bool:
    """Equal and of the same type (true is not 1), as JSON Schema's const compares."""
    return a == b and isinstance(a, bool) == isinstance(b, bool)


def _unit(key: str) -> str:
    section, name = split(key)
    unit = dict(section_fields(section))[name].metadata["unit"]
    return f" ({unit})" if unit and unit != "1" else ""


@dataclass(frozen=True)
class View:
    """A case as the file gives it (``raw``), each key built and checked (``built``)."""

    raw: dict
    built: dict

    def given(self, key: str) -> bool:
        section, name = split(key)
        table = self.raw.get(section)
        return table is not None if name is None else isinstance(table, dict) and name in table

    def value(self, key: str):
        """The key's typed value: as given, else its default."""
        section, name = split(key)
        obj = self.built.get(section)
        return getattr(obj, name) if obj is not None else default(key)


# --------------------------------------------------------------------------
# Conditions

def _section_fragment(key: str, inner: dict, at: str | None, needs_section: bool) -> dict:
    """``inner`` (a condition on one section's table) seen from ``at``."""
    section, _ = split(key)
    if at == section:
        return inner
    out = {"properties": {section: inner}}
    if needs_section:
        out["required"] = [section]
    return out


@dataclass(frozen=True)
class Is:
    """``key`` has one of ``values`` (a value, or a tuple of them), given or by default."""

    key: str
    values: Any

    def __post_init__(self):
        if not isinstance(self.values, tuple):
            object.__setattr__(self, "values", (self.values,))

    def holds(self, view: View) -> bool:
        return any(_same(view.value(self.key), v) for v in self.values)

    def describe(self, view: View) -> str:
        out = f"{self.key} = {format_value(view.value(self.key))}"
        return out if view.given(self.key) else out + " (the default)"

    def text(self) -> str:
        return f"`{self.key} = " + " \\| ".join(format_value(v) for v in self.values) + "`"

    def schema(self, at: str | None) -> dict:
        _, name = split(self.key)
        values = list(self.values)
        inner = {"properties": {name: {"const": values[0]} if len(values) == 1
                                else {"enum": values}}}
        # a key left out takes its default: then the condition holds without it
        needs_key = not any(_same(default(self.key), v) for v in values)
        if needs_key:
            inner["required"] = [name]
        return _section_fragment(self.key, inner, at, needs_key)


@dataclass(frozen=True)
class Given:
    """``key`` (``section.key``, or a whole ``section``) is in the file."""

    key: str

    def holds(self, view: View) -> bool:
        return view.given(self.key)

    def describe(self, view: View) -> str:
        section, name = split(self.key)
        if name is None:
            return f"[{section}] given"
        return f"{self.key} = {format_value(_plain(view.value(self.key)))}"

    def text(self) -> str:
        section, name = split(self.key)
        return f"[{section}] given" if name is None else f"`{self.key}` given"

    def schema(self, at: str | None) -> dict:
        section, name = split(self.key)
        if name is None:
            return {"required": [section]}
        return _section_fragment(self.key, {"required": [name]}, at, True)


@dataclass(frozen=True)
class Absent:
    """``key`` (``section.key`` or ``section``) is not in the file."""

    key: str

    def holds(self, view: View) -> bool:
        return not view.given(self.key)

    def describe(self, view: View) -> str:
        return ""   # said by the rule that needs it, if at all

    def text(self) -> str:
        section, name = split(self.key)
        return f"without [{section}]" if name is None else f"without `{self.key}`"

    def schema(self, at: str | None) -> dict:
        return {"not": Given(self.key).schema(at)}


def _plain(value):
    return list(value) if isinstance(value, tuple) else value


_SIMPLE = {"properties", "required"}


def _merge(a, b):
    """Two fragments of only ``properties`` and ``required`` as one, or None if they clash."""
    if a is b or a == b:
        return a
    if not (isinstance(a, dict) and isinstance(b, dict) and set(a) | set(b) <= _SIMPLE):
        return None
    out = {}
    props = dict(a.get("properties", {}))
    for name, sub in b.get("properties", {}).items():
        merged = _merge(props[name], sub) if name in props else sub
        if merged is None:
            return None
        props[name] = merged
    if props:
        out["properties"] = props
    required = list(dict.fromkeys(a.get("required", []) + b.get("required", [])))
    if required:
        out["required"] = required
    return out


def _all(fragments: list[dict]) -> dict:
    """The conjunction of ``fragments``: one fragment where they merge, else ``allOf``."""
    merged = fragments[0]
    for fragment in fragments[1:]:
        merged = _merge(merged, fragment)
        if merged is None:
            return {"allOf": fragments}
    return merged


def _tuple(x) -> tuple:
    return x if isinstance(x, tuple) else (x,)


def _when(view: View, when) -> str:
    return " and ".join(d for d in (c.describe(view) for c in when) if d)


def _when_text(when) -> str:
    """The conditions in words: ``a`` and ``b`` (without [c])."""
    absent = [c.text() for c in when if isinstance(c, Absent)]
    return (" and ".join(c.text() for c in when if not isinstance(c, Absent))
            + (" (" + ", ".join(absent) + ")" if absent else ""))


def _keys_of(when) -> list[str]:
    return [c.key for c in when]


# --------------------------------------------------------------------------
# Rules

@dataclass(frozen=True)
class Rule:
    """What every kind shares: ``why`` (said in parentheses) and ``hint`` (after ``;``)."""

    def keys_named(self) -> list[str]:
        """Every key or section the rule reads (where the JSON Schema places it)."""
        raise NotImplementedError

    def placement(self) -> str | None:
        """The section whose schema holds this rule, None for the top level."""
        sections = {split(k)[0] if split(k)[1] else None for k in self.keys_named()}
        return sections.pop() if len(sections) == 1 and None not in sections else None

    def _tail(self) -> str:
        return (f" ({self.why})" if self.why else "") + (f"; {self.hint}" if self.hint else "")


@dataclass(frozen=True)
class Requires(Rule):
    """When every condition of ``when`` holds, each of ``keys`` must be given."""

    when: Any
    keys: Any
    why: str = ""
    hint: str = ""

    def __post_init__(self):
        object.__setattr__(self, "when", _tuple(self.when))
        object.__setattr__(self, "keys", _tuple(self.keys))

    def keys_named(self):
        return _keys_of(self.when) + list(self.keys)

    def broken(self, view: View) -> str | None:
        if not all(c.holds(view) for c in self.when):
            return None
        for key in self.keys:
            if not view.given(key):
                return f"missing key '{key}', required by {_when(view, self.when)}" + self._tail()
        return None

    def text(self) -> str:
        return _when_text(self.when) + " requires " + ", ".join(f"`{k}`" for k in self.keys)

    def schema(self, at):
        return {"if": _all([c.schema(at) for c in self.when]),
                "then": _all([Given(k).schema(at) for k in self.keys])}


@dataclass(frozen=True)
class Excludes(Rule):
    """When every condition of ``when`` holds, none of ``keys`` may be given.

    ``keys`` may name whole sections; with ``defaults_allowed`` their keys may
    still be given at their defaults (a case derived from another carries them).
    A rule whose one condition is an :class:`Is` on a key of the keys' own
    section makes them *inapplicable*: an override that sets that key drops them
    (``cases.rules.inapplicable``). Without a ``hint`` the message names the
    values of that key under which the key given applies (``alternatives``, filled in
    by the table from its other rules on the same switch).
    """

    when: Any
    keys: Any
    why: str = ""
    hint: str = ""
    defaults_allowed: bool = False
    #: a message of its own, with {key}, {value}, {default}, {section}, {when}
    message: str = ""
    #: (key, the switch's values under which it applies) pairs, filled in by the table
    alternatives: tuple = field(default=(), compare=False)

    def __post_init__(self):
        object.__setattr__(self, "when", _tuple(self.when))
        object.__setattr__(self, "keys", _tuple(self.keys))

    @classmethod
    def unless(cls, switch: Is, keys, **kw) -> "Excludes":
        """``keys`` apply only when ``switch`` holds: excluded at the switch's other values."""
        return cls(Is(switch.key, tuple(v for v in switch_values(switch.key)
                                        if not any(_same(v, w) for w in switch.values))),
                   keys, **kw)

    def keys_named(self):
        return _keys_of(self.when) + list(self.keys)

    def switch(self) -> str | None:
        """The key whose value makes ``keys`` inapplicable (same section), or None."""
        if len(self.when) == 1 and isinstance(self.when[0], Is):
            key = self.when[0].key
            if all(split(k)[1] and split(k)[0] == split(key)[0] for k in self.keys):
                return key
        return None

    def _offending(self, view: View):
        """(key, value) of the first key given against the rule, else None."""
        for key in self.keys:
            section, name = split(key)
            names = [name] if name else [n for n, _ in section_fields(section)]
            for n in names:
                full = f"{section}.{n}"
                if not view.given(full):
                    continue
                value = view.value(full)
                if self.defaults_allowed and value == default(full):
                    continue
                return full, value
        return None

    def broken(self, view: View) -> str | None:
        if not all(c.holds(view) for c in self.when):
            return None
        hit = self._offending(view)
        if hit is None:
            return None
        key, value = hit
        fields = dict(key=key, value=format_value(_plain(value)),
                      default=format_value(_plain(default(key))), section=split(key)[0],
                      when=_when(view, self.when))
        if self.message:
            return self.message.format(**fields)
        alternatives = dict(self.alternatives).get(key, ())
        hint = self.hint or "remove it" + (
            f", or set {self.switch()} = " + " or ".join(format_value(v) for v in alternatives)
            if alternatives else "")
        return (f"key '{key}' = {fields['value']} given but {fields['when']}"
                + (f" ({self.why})" if self.why else "") + f"; {hint}")

    def text(self) -> str:
        keys = ", ".join(f"[{k}]" if not split(k)[1] else f"`{k}`" for k in self.keys)
        return (_when_text(self.when) + " excludes " + keys
                + (" (but for keys at their defaults)" if self.defaults_allowed else ""))

    def schema(self, at):
        then = []
        for key in self.keys:
            section, name = split(key)
            if name is None:
                if not self.defaults_allowed:
                    then.append({"not": {"required": [section]}})
                    continue
                inner = {"properties": {n: {"const": _plain(f.default)} if f.default is not None
                                        else False for n, f in section_fields(section)}}
            else:
                d = default(key)
                inner = {"properties": {name: {"const": _plain(d)}
                                        if self.defaults_allowed and d is not None else False}}
            then.append(_section_fragment(key, inner, at, False))
        return {"if": _all([c.schema(at) for c in self.when]), "then": _all(then)}


@dataclass(frozen=True)
class Forbids(Rule):
    """The conditions of ``when`` may not all hold together; ``why`` says why not."""

    when: Any
    why: str
    hint: str = ""

    def __post_init__(self):
        object.__setattr__(self, "when", _tuple(self.when))

    def keys_named(self):
        return _keys_of(self.when)

    def broken(self, view: View) -> str | None:
        if not all(c.holds(view) for c in self.when):
            return None
        return f"{_when(view, self.when)}: {self.why}" + (f"; {self.hint}" if self.hint else "")

    def text(self) -> str:
        return _when_text(self.when) + ": refused together"

    def schema(self, at):
        return {"not": _all([c.schema(at) for c in self.when])}


@dataclass(frozen=True)
class OneOf(Rule):
    """At most one of ``keys`` (one section's) is given; exactly one if ``required``.

    An override of one of them drops the others the file gave (``cases.rules.partners``).
    """

    keys: tuple
    required: bool = False
    why: str = ""
    hint: str = ""

    def keys_named(self):
        return list(self.keys)

    def broken(self, view: View) -> str | None:
        section = split(self.keys[0])[0]
        if not view.given(section) and section not in REQUIRED_SECTIONS:
            return None
        given = [k for k in self.keys if view.given(k)]
        names = " and ".join(f"'{k}'{_unit(k)}" for k in self.keys)
        if len(given) > 1:
            listing = " and ".join(f"'{k}' = {format_value(_plain(view.value(k)))}"
                                   for k in given)
            together = "both given" if len(given) == 2 else "given together"
            return (f"keys {listing} {together}; "
                    + (self.hint or f"give {'exactly' if self.required else 'at most'} one of "
                       + names) + (f" ({self.why})" if self.why else ""))
        if self.required and not given:
            return (f"[{section}] needs exactly one of {names}; got neither"
                    if len(self.keys) == 2 else
                    f"[{section}] needs exactly one of {names}; got none") + self._tail()
        return None

    def text(self) -> str:
        return (("exactly" if self.required else "at most") + " one of "
                + ", ".join(f"`{k}`" for k in self.keys))

    def schema(self, at):
        names = [split(k)[1] for k in self.keys]
        if self.required:
            return {"oneOf": [{"required": [n]} for n in names]}
        pairs = [{"required": list(p)} for p in combinations(names, 2)]
        return {"not": pairs[0] if len(pairs) == 1 else {"anyOf": pairs}}


@dataclass(frozen=True)
class LoaderOnly(Rule):
    """A rule no JSON Schema can state (a numeric relation between keys, a file's contents).

    ``check(case)`` raises :class:`CaseError` with the message, or returns None,
    or returns the case completed with what it read (the profile table). These
    run after every other rule, on the built :class:`~wearcheck.cases.Case`.
    """

    keys: tuple
    says: str
    check: Callable = field(compare=False)

    def keys_named(self):
        return list(self.keys)

    def text(self) -> str:
        return self.says
