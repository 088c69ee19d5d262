"""The table of rules that tie case keys to each other: the one place they are written.

A key's own type, unit, range and choices are declared with it in
``cases/schema.py``. What one key's presence or value says about another's is
here, one rule per line (the kinds: ``cases/rule_kinds.py``). From this table

* the loader checks every case (:func:`check`, then :func:`check_loader_only`);
* an override that flips a switch drops the keys it makes inapplicable
  (:func:`inapplicable`), and one of several keys given one way or another
  replaces the others (:func:`partners`);
* the JSON Schema that editors read states every rule but the
  :class:`LoaderOnly` ones (``cases/json_schema.py``);
* the documentation lists them (:func:`reference`).

Rules are checked in the order of the table, the loader-only ones last, so
that a case refused by a loader-only rule has passed every rule the schema
states. Adding a rule: docs/case-files.md, "Adding a key or a rule".
"""

from __future__ import annotations

from . import loader_checks as lc
from .errors import CaseError
from .rule_kinds import (Absent, Excludes, Forbids, Given, Is, LoaderOnly, OneOf, Requires,
                         RuleError, View, split, switch_values)
from .schema import PROFILES

#: which geometry keys each profile takes (besides ``profile``), and which it requires
PROFILE_KEYS = {
    "paraboloid": {"radius"},
    "sphere": {"radius"},
    "truncated_paraboloid": {"radius", "flat_radius"},
    "cone": {"slope_angle", "radius"},
    "power_law": {"coefficient", "exponent", "radius"},
    "table": {"file", "radius"},
    "ellipsoid": {"radius", "radius_y"},
}
PROFILE_REQUIRED = {
    "paraboloid": {"radius"},
    "sphere": {"radius"},
    "truncated_paraboloid": {"radius", "flat_radius"},
    "cone": {"slope_angle"},
    "power_law": {"coefficient", "exponent"},
    "table": {"file"},
    "ellipsoid": {"radius", "radius_y"},
}
assert set(PROFILE_KEYS) == set(PROFILE_REQUIRED) == set(PROFILES)


def _profile_rules():
    geometry = sorted(set().union(*PROFILE_KEYS.values()))
    for profile in PROFILES:
        when = Is("indenter.profile", profile)
        yield Requires(when, tuple(f"indenter.{k}" for k in sorted(PROFILE_REQUIRED[profile])))
        banned = tuple(f"indenter.{k}" for k in geometry if k not in PROFILE_KEYS[profile])
        if banned:
            yield Excludes(when, banned, why="it takes " + ", ".join(sorted(PROFILE_KEYS[profile])))


def _body_rules(body):
    elastic = (f"{body}.youngs_modulus", f"{body}.poisson_ratio")
    yield Requires(Is(f"{body}.rigid", False), elastic, hint=f"or set {body}.rigid = true")
    yield Excludes(Is(f"{body}.rigid", True), elastic)


FRETTING_NOT_SLIDING = ("section [{section}] given with [fretting] ('{key}' = {value}, not its "
                        "default {default}): a fretting run lasts fretting.cycles and keeps "
                        "fretting.stage_cycles; remove [{section}] (to start from a shipped "
                        "case: wearcheck cases NAME > my.toml, then edit it)")

RULES = (
    # [fretting] is a programme of its own: it replaces [sliding] and [stages]
    Excludes(Given("fretting"), ("sliding", "stages"), defaults_allowed=True,
             message=FRETTING_NOT_SLIDING),
    Forbids((Is("wear.tangential_correction", True), Given("fretting")),
            why="a fretting run always includes the elastic tangential displacement (the "
                "springs' deformation)", hint="remove wear.tangential_correction"),
    OneOf(("fretting.amplitude", "fretting.force_amplitude"), required=True),
    # the indenter's shape
    *_profile_rules(),
    # rigid or elastic bodies
    *_body_rules("indenter"),
    *_body_rules("counterface"),
    Forbids((Is("indenter.rigid", True), Is("counterface.rigid", True)),
            why="at least one body must be elastic", hint="set one of them to false"),
    # the load
    Requires(Is("loading.control", "depth"), "loading.depth"),
    Excludes(Is("loading.control", "depth"), "loading.force"),
    Requires(Is("loading.control", "force"), "loading.force"),
    Excludes(Is("loading.control", "force"), "loading.depth"),
    # both bodies wearing (docs/both-bodies.md): the counterface's wear rate, its track.
    # (A wearing counterface in a fretting run is refused by [fretting]'s exclusion
    # of a [sliding] that gives sliding.motion.)
    Excludes(Is("counterface.wears", False),
             ("counterface.specific_rate", "counterface.k", "counterface.hardness"),
             hint="set counterface.wears = true to wear the counterface too, or remove it"),
    Requires(Is("counterface.wears", True), "sliding.motion",
             why="the counterface wears along the track the motion traces: \"reciprocating\" "
                 "or \"unidirectional\""),
    Requires(Is("sliding.motion", "reciprocating"), "sliding.stroke", why="one way"),
    Requires(Is("sliding.motion", "unidirectional"), "sliding.track_radius"),
    Excludes(Is("sliding.motion", "unidirectional"), "sliding.stroke",
             why="a circular track of sliding.track_radius; a cycle is one revolution"),
    Excludes(Is("sliding.motion", (None, "reciprocating")), "sliding.track_radius",
             message="key '{key}' = {value} given but {when}: the radius of a pin-on-disc "
                     "track; remove it, or set sliding.motion = \"unidirectional\""),
    OneOf(("counterface.specific_rate", "counterface.k"),
          hint="give one (K_flat = counterface.k·wear.mu/counterface.hardness)"),
    Forbids((Is("counterface.wears", True), Absent("counterface.specific_rate"),
             Absent("counterface.k")),
            why="a counterface that wears needs its wear rate",
            hint="give counterface.specific_rate (m^3/(N m)) or counterface.k with "
                 "counterface.hardness"),
    Requires(Given("counterface.k"), "counterface.hardness",
             why="K_flat = k·wear.mu/counterface.hardness"),
    Forbids((Is("counterface.wears", False), Is("bem.track_model", "moving")),
            why="bem.track_model applies to a counterface that wears",
            hint="set counterface.wears = true or remove bem.track_model"),
    Excludes.unless(Is("bem.track_model", "moving"), "bem.jump_tolerance",
                    defaults_allowed=True),
    # the end of the run
    Requires(Is("sliding.until", "distance"), "sliding.distance"),
    Excludes(Is("sliding.until", "force_fraction"), "sliding.distance"),
    Excludes(Is("sliding.until", "cycles"), "sliding.distance",
             why="the distance is 2·stroke·cycles"),
    Requires(Is("sliding.until", "cycles"), "sliding.cycles"),
    # (a disc's cycle is a revolution of its track_radius, below)
    Requires((Is("sliding.until", "cycles"), Absent("sliding.track_radius")), "sliding.stroke"),
    Excludes.unless(Is("sliding.until", "cycles"), "sliding.cycles"),
    Forbids((Is("sliding.until", "force_fraction"), Is("loading.control", "force"),
             Absent("fretting")),
            why="a force-controlled run cannot end on a falling force (the force does not "
                "fall)", hint="set sliding.until = \"distance\" or \"cycles\""),
    # the wear coefficient: the paper's k or the lab's K (the other derived)
    OneOf(("wear.k", "wear.specific_rate"), required=True,
          why="k = K·σ0/μ, σ0 = wear.hardness",
          hint="give the paper's dimensionless k or the lab's specific wear rate K in "
               "m^3/(N m) (V = K·F·s), the other is derived"),
    # the stages, and what needs a stroke
    OneOf(("stages.s_hat", "stages.s", "stages.cycles"), hint="give the stages one way only"),
    Requires((Given("stages.cycles"), Absent("sliding.track_radius")), "sliding.stroke",
             why="one cycle slides 2·stroke"),
    Requires(Is("wear.tangential_correction", True), "sliding.stroke",
             why="the correction is the sliding each stroke end loses while the tangential "
                 "springs reverse, 2μq/G* per stroke, so it depends on the stroke",
             hint="give the reciprocating stroke (one way), or remove "
                  "wear.tangential_correction (the earlier reading without a stroke changed "
                  "nothing measurable)"),
    # -- loader-only: after every rule above, on the built case, in this order
    LoaderOnly(("indenter.file",), "`indenter.file` is a readable UTF-8 CSV of at least 3 rows "
               "(r, f), r strictly increasing from 0, f(0) = 0, f > 0 beyond", lc.profile_table),
    LoaderOnly(("indenter.flat_radius", "indenter.radius"),
               "`indenter.flat_radius` < `indenter.radius`", lc.flat_radius_below_radius),
    *(LoaderOnly((key,), f"`{key}` increases strictly", lc.increasing(key))
      for key in ("stages.s_hat", "stages.s", "stages.cycles", "fretting.stage_cycles")),
    LoaderOnly(("loading.depth", "indenter.radius"),
               "a sphere's `loading.depth` < `indenter.radius`", lc.sphere_depth),
    LoaderOnly(("loading.force", "indenter.radius"),
               "a sphere's `loading.force` presses it less deep than `indenter.radius`",
               lc.sphere_force),
    LoaderOnly(("loading.depth", "loading.force", "wear.k", "wear.specific_rate", "wear.mu",
                "wear.hardness"),
               "the unworn contact and the sliding scale are finite and positive "
               "(a tabulated profile: the load within the table)", lc.unworn_contact),
    LoaderOnly(("sliding.track_radius",),
               "`sliding.track_radius` >= the unworn contact radius a0",
               lc.track_radius_beyond_contact),
    LoaderOnly(("sliding.stroke", "wear.tangential_correction"),
               "with `wear.tangential_correction`, `sliding.stroke` > the springs' reversal "
               "2μE*d0/G*", lc.stroke_beyond_reversal),
    LoaderOnly(("fretting.force_amplitude", "wear.mu"),
               "`fretting.force_amplitude` < μF of the unworn contact",
               lc.force_amplitude_below_friction),
)


def _fill_alternatives(rules):
    """An Excludes rule on a switch names, for each of its keys, the switch's values
    under which that key applies (no rule on the switch excludes it there)."""
    for rule in rules:
        switch = rule.switch() if isinstance(rule, Excludes) else None
        if switch is None or rule.hint:
            continue
        pairs = []
        for key in rule.keys:
            excluded_at = {v for r in rules if isinstance(r, Excludes) and r.switch() == switch
                           and key in r.keys for v in r.when[0].values}
            pairs.append((key, tuple(v for v in switch_values(switch) if v not in excluded_at)))
        object.__setattr__(rule, "alternatives", tuple(pairs))
    return rules


RULES = _fill_alternatives(RULES)


def is_loader_only(rule) -> bool:
    """Whether the JSON Schema leaves this rule to the loader."""
    return isinstance(rule, LoaderOnly)


def check(raw: dict, built: dict) -> None:
    """Raise :class:`RuleError` on the first rule (of those the schema states too) that
    the case breaks. ``raw``: the tables as given; ``built``: each section built."""
    view = View(raw, built)
    for rule in RULES:
        if not is_loader_only(rule):
            message = rule.broken(view)
            if message:
                raise RuleError(message, rule)


def check_loader_only(case):
    """Run the loader-only rules on the built case; the case, completed by them."""
    for rule in RULES:
        if is_loader_only(rule):
            try:
                case = rule.check(case) or case
            except CaseError as exc:
                raise RuleError(str(exc), rule) from None
    return case


def inapplicable(section: str, key: str, value) -> tuple[str, ...]:
    """The keys of ``section`` that do not apply once the switch ``section.key`` is ``value``.

    A case file gives only the keys of its choice (the depth of a depth-controlled
    run, the moduli of an elastic body); an override that flips the choice makes
    them wrong, and ``--set`` cannot remove a key, so they are dropped with it.
    """
    out = []
    for rule in RULES:
        if isinstance(rule, Excludes) and rule.switch() == f"{section}.{key}" \
                and any(v == value and isinstance(v, bool) == isinstance(value, bool)
                        for v in rule.when[0].values):
            out += [split(k)[1] for k in rule.keys if split(k)[1] not in out]
    return tuple(out)


def drop_inapplicable(raw: dict, changed) -> None:
    """Drop from ``raw`` the keys a changed switch makes inapplicable, unless also changed."""
    for section, key in list(changed):
        table = raw.get(section)
        if isinstance(table, dict) and key in table:
            for other in inapplicable(section, key, table[key]):
                if (section, other) not in changed:
                    table.pop(other, None)


def one_of_groups(section: str) -> list[tuple[str, ...]]:
    """The groups of keys of ``section`` given one way or another (:class:`OneOf`)."""
    return [tuple(split(k)[1] for k in rule.keys) for rule in RULES
            if isinstance(rule, OneOf) and split(rule.keys[0])[0] == section]


def partners(section: str, key: str) -> tuple[str, ...]:
    """The keys of ``section`` given instead of ``key`` (a :class:`OneOf`): an override
    of ``key`` drops them."""
    for group in one_of_groups(section):
        if key in group:
            return tuple(k for k in group if k != key)
    return ()


def schema_rules() -> dict[str | None, list[dict]]:
    """The JSON Schema fragments of every rule the schema states, by the section that
    holds them (None: the top level, for rules across sections)."""
    out: dict[str | None, list[dict]] = {}
    for rule in RULES:
        if not is_loader_only(rule):
            at = rule.placement()
            out.setdefault(at, []).append(rule.schema(at))
    return out


def reference() -> str:
    """A Markdown table of every rule (docs/case-files.md includes it, generated at every
    docs build)."""
    rows = ["| rule | checked by |", "|---|---|"]
    for rule in RULES:
        where = "the loader only" if is_loader_only(rule) else "the loader and the JSON Schema"
        rows.append(f"| {rule.text()} | {where} |")
    return "\n".join(rows)
