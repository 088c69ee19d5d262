"""Read, validate and write one case; derive the effective moduli and scales."""

from __future__ import annotations

import csv
import hashlib
import io
import math
import tomllib
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from .errors import CaseError
from .schema import (BEMSettings, did_you_mean, OPTIONAL_SECTIONS, PROFILE_KEYS, PROFILE_REQUIRED,
                     REQUIRED_SECTIONS,
                     SECTIONS, CompareSettings, Counterface, FEMSettings, Fretting, Indenter,
                     Loading,
                     MDRSettings, Sliding, Stages, Wear, format_value, build_section,
                     section_fields, toml_string)


@dataclass(frozen=True)
class Case:
    """One validated case. Every solver and command reads this, nothing else."""

    indenter: Indenter
    counterface: Counterface
    loading: Loading
    wear: Wear
    sliding: Sliding
    stages: Stages
    mdr: MDRSettings
    fem: FEMSettings
    bem: BEMSettings
    compare: CompareSettings
    #: partial-slip (fretting) programme; None for a gross-slip run
    fretting: Fretting | None = None
    source: str = ""
    #: tabulated profile (r, f) in metres when indenter.profile == "table"
    table: tuple[np.ndarray, np.ndarray] | None = field(default=None, compare=False, repr=False)
    #: the table's file as read: path, SHA-256 of its bytes, rows, last radius
    #: (recorded in every run's meta.json as "profile_table")
    table_file: dict | None = field(default=None, compare=False, repr=False)
    #: non-fatal remarks on the case (e.g. elastic similarity violated)
    warnings: tuple[str, ...] = ()

    # -- derived material constants (paper Eqs. 5-7) ------------------------
    @property
    def E_star(self) -> float:
        """Effective modulus, 1/E* = (1-ν1²)/E1 + (1-ν2²)/E2 (paper Eq. 5)."""
        return effective_moduli(self.indenter, self.counterface)[0]

    @property
    def G_star(self) -> float:
        """Effective shear modulus, 1/G* = (2-ν1)/4G1 + (2-ν2)/4G2 (paper Eq. 6)."""
        return effective_moduli(self.indenter, self.counterface)[1]

    @property
    def wear_rate(self) -> float:
        """k_wear μ / σ0 [1/Pa]: wear depth per unit pressure and sliding distance."""
        return self.wear.k * self.wear.mu / self.wear.hardness

    @property
    def end_distance(self) -> float | None:
        """Sliding distance [m] at which the run stops; None: when the force has fallen."""
        sl = self.sliding
        if sl.until == "distance":
            return sl.distance
        if sl.until == "cycles":
            return 2.0 * sl.stroke * sl.cycles
        return None

    @property
    def cycles_per_metre(self) -> float | None:
        """Cycles per metre of sliding, 1/(2·stroke); None without a stroke."""
        return None if self.sliding.stroke is None else 0.5 / self.sliding.stroke

    def replace(self, **sections) -> "Case":
        """A copy with whole sections replaced, validated like a case file.

        ``case.replace(wear=dataclasses.replace(case.wear, mu=0.5))``; for single
        keys :meth:`derive` is shorter.
        """
        unknown = sorted(set(sections) - set(SECTIONS))
        if unknown:
            raise CaseError(f"unknown section '{unknown[0]}'{did_you_mean(unknown[0], SECTIONS)}"
                            "; allowed: " + ", ".join(SECTIONS))
        raw = to_dict(self)
        for name, obj in sections.items():
            raw[name] = _section_dict(obj)
        return from_dict(raw, source=self.source)

    def derive(self, changes=None, /, **keys) -> "Case":
        """A copy with some keys changed, validated like a case file.

        Parameters
        ----------
        changes : mapping of dotted keys to values, ``{"wear.mu": 0.5}``, or a
            list of ``"section.key=value"`` strings as on the command line.
        **keys : the same with ``__`` for the dot: ``case.derive(wear__mu=0.5)``;
            they win over ``changes``. numpy numbers and arrays are taken as
            Python numbers and lists. A relative ``indenter.file`` given here is
            relative to the working directory.

        Raises
        ------
        CaseError
            naming the key, the value and what is allowed, as for a case file.
        """
        items = {}
        if isinstance(changes, dict):
            for name, value in changes.items():
                if name in SECTIONS and isinstance(value, dict):
                    # {"wear": {"mu": 0.5}}, the shape of the TOML file, is {"wear.mu": 0.5}
                    items.update({f"{name}.{k}": v for k, v in value.items()})
                else:
                    items[name] = value
        elif changes is not None:
            for text in [changes] if isinstance(changes, str) else list(changes):
                section, key, value = parse_override(text)
                items[f"{section}.{key}"] = value
        items.update({k.replace("__", "."): v for k, v in keys.items()})
        raw = to_dict(self)
        for name, value in items.items():
            if not isinstance(name, str) or name.count(".") != 1 or not all(name.split(".")):
                raise CaseError(f"key '{name}': must be section.key, e.g. wear.mu")
            if isinstance(value, np.generic):
                value = value.item()
            elif isinstance(value, (np.ndarray, tuple)):
                value = np.asarray(value).tolist() if isinstance(value, np.ndarray) \
                    else list(value)
            if name == "indenter.file" and isinstance(value, str) \
                    and not Path(value).is_absolute():
                value = str(Path.cwd() / value)
            section, key = name.split(".")
            if section in raw and not isinstance(raw[section], dict):
                raise CaseError(f"'{section}' must be a table [{section}]")
            raw.setdefault(section, {})[key] = value
            # a fretting amplitude given the other way replaces the case's
            other = _OTHER_WAY.get((section, key)) if section == "fretting" else None
            if other and f"{section}.{other}" not in items:
                raw[section].pop(other, None)
        _drop_inapplicable(raw, {tuple(name.split(".")) for name in items})
        return from_dict(raw, source=self.source)


def _compliance(rigid: bool, E, nu):
    """(1-ν²)/E and (2-ν)/4G for one body; zero when rigid."""
    if rigid:
        return 0.0, 0.0
    G = E / (2.0 * (1.0 + nu))
    return (1.0 - nu**2) / E, (2.0 - nu) / (4.0 * G)


def effective_moduli(indenter: Indenter, counterface: Counterface) -> tuple[float, float]:
    c1, s1 = _compliance(indenter.rigid, indenter.youngs_modulus, indenter.poisson_ratio)
    c2, s2 = _compliance(counterface.rigid, counterface.youngs_modulus, counterface.poisson_ratio)
    return 1.0 / (c1 + c2), 1.0 / (s1 + s2)


def dundurs_beta(indenter: Indenter, counterface: Counterface) -> float:
    """Dundurs' second parameter β; zero exactly under elastic similarity (paper Eq. 7)."""
    def parts(rigid, E, nu):
        if rigid:
            return 0.0, 0.0
        G = E / (2.0 * (1.0 + nu))
        return (1.0 - 2.0 * nu) / G, (1.0 - nu) / G
    a1, b1 = parts(indenter.rigid, indenter.youngs_modulus, indenter.poisson_ratio)
    a2, b2 = parts(counterface.rigid, counterface.youngs_modulus, counterface.poisson_ratio)
    return 0.5 * (a1 - a2) / (b1 + b2)


# --------------------------------------------------------------------------
# Reading

def parse_override(text: str) -> tuple[str, str, Any]:
    """Parse ``section.key=value``; the value in TOML syntax, or a bare string."""
    if "=" not in text:
        raise CaseError(f"override '{text}': expected section.key=value")
    name, _, value = text.partition("=")
    name = name.strip()
    if name.count(".") != 1 or not all(name.split(".")):
        raise CaseError(f"override '{text}': the key must be section.key, e.g. loading.depth")
    section, k = name.split(".")
    if section not in SECTIONS:
        raise CaseError(f"override '{text}': unknown section '{section}'"
                        f"{did_you_mean(section, SECTIONS)}; allowed: "
                        + ", ".join(SECTIONS))
    value = value.strip()
    try:
        parsed = tomllib.loads(f"v = {value}")["v"]
    except tomllib.TOMLDecodeError:
        parsed = value  # bare word such as loading.control=force
    return section, k, parsed


def read_raw(path: str | Path) -> dict:
    """The TOML tables of a case file, unvalidated; every failure a one-line CaseError."""
    path = Path(path)
    if path.is_dir():
        raise CaseError(f"case file '{path}' is a directory, not a TOML file")
    if not path.is_file():
        raise CaseError(f"case file '{path}' does not exist")
    try:
        # utf-8-sig: editors on some systems start the file with a byte-order mark
        return tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"case file '{path}': TOML syntax error: {exc}") from None
    except UnicodeDecodeError as exc:
        raise CaseError(f"case file '{path}' is not UTF-8 text: {exc}") from None
    except OSError as exc:
        raise CaseError(f"case file '{path}' cannot be read: {exc.strerror or exc}") from None
    except RecursionError:
        raise CaseError(f"case file '{path}': nested too deeply to be a case") from None


#: keys of which a case gives one; setting one by an override drops the other
_OTHER_WAY = {("stages", "s_hat"): "cycles", ("stages", "cycles"): "s_hat",
              ("fretting", "amplitude"): "force_amplitude",
              ("fretting", "force_amplitude"): "amplitude"}


def _inapplicable(section: str, key: str, value) -> tuple[str, ...]:
    """The keys of ``section`` that do not apply once the switch ``section.key`` is ``value``.

    A case file gives only the keys of its choice (the depth of a depth-controlled
    run, the moduli of an elastic body); an override that flips the choice makes
    them wrong, and ``--set`` cannot remove a key, so they are dropped with it.
    """
    if (section, key) == ("loading", "control") and value in ("depth", "force"):
        return ("force",) if value == "depth" else ("depth",)
    if section in ("indenter", "counterface") and key == "rigid" and value is True:
        return ("youngs_modulus", "poisson_ratio")
    if (section, key) == ("indenter", "profile") and value in PROFILE_KEYS:
        return tuple(sorted(set().union(*PROFILE_KEYS.values()) - PROFILE_KEYS[value]))
    if (section, key) == ("sliding", "until") and isinstance(value, str):
        return tuple(k for k in ("distance", "cycles")
                     if (k, value) not in (("distance", "distance"), ("cycles", "cycles")))
    return ()


def _drop_inapplicable(raw: dict, changed) -> None:
    """Drop from ``raw`` the keys a changed switch makes inapplicable, unless also changed."""
    for section, key in list(changed):
        table = raw.get(section)
        if isinstance(table, dict) and key in table:
            for other in _inapplicable(section, key, table[key]):
                if (section, other) not in changed:
                    table.pop(other, None)


def load(path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> Case:
    """Read a case file, apply ``section.key=value`` overrides, validate."""
    path = Path(path)
    return from_dict(read_raw(path), source=path, overrides=overrides)


def from_dict(raw: dict, source: str | Path = "<dict>",
              overrides: list[str] | tuple[str, ...] = ()) -> Case:
    """Validate a case given as nested dicts (as TOML reads it)."""
    raw = {k: (dict(v) if isinstance(v, dict) else v) for k, v in raw.items()}
    unknown = sorted(set(raw) - set(SECTIONS))
    if unknown:
        raise CaseError(f"unknown section [{unknown[0]}]{did_you_mean(unknown[0], SECTIONS)}; "
                        "allowed: " + ", ".join(SECTIONS))
    overridden = set()
    for text in overrides:
        section, k, value = parse_override(text)
        raw.setdefault(section, {})
        if not isinstance(raw[section], dict):
            raise CaseError(f"'{section}' must be a table [{section}]")
        raw[section][k] = value
        overridden.add((section, k))
        # stages (a fretting amplitude) given one way by an override replace
        # the file's other way
        other = _OTHER_WAY.get((section, k))
        if other and (section, other) not in overridden:
            raw[section].pop(other, None)
    _drop_inapplicable(raw, overridden)
    for section in REQUIRED_SECTIONS:
        if section not in raw:
            raise CaseError(f"missing section [{section}]")
    st = raw.get("stages", {})
    if isinstance(st, dict) and "s_hat" in st and "cycles" in st:
        raise CaseError(f"keys 'stages.s_hat' = {format_value(st['s_hat'])} and 'stages.cycles' = "
                        f"{format_value(st['cycles'])} both given; give the stages one way only")
    built = {name: build_section(name, raw.get(name, {})) for name in SECTIONS
             if name not in OPTIONAL_SECTIONS or name in raw}
    if "fretting" in raw:
        for section in ("sliding", "stages"):
            # (a case derived from a gross-slip one carries their defaults: harmless)
            if raw.get(section) and built[section] != SECTIONS[section]():
                raise CaseError(f"section [{section}] given with [fretting]; a fretting run "
                                "lasts fretting.cycles and keeps fretting.stage_cycles — "
                                f"remove [{section}] (to start from a shipped case: "
                                "wearcheck cases NAME > my.toml, then edit it)")
    base = Path(source).parent if source != "<dict>" else Path.cwd()
    built, table, table_file = _check_indenter(built, base)
    _check_materials(built)
    _check_programme(built)
    case = Case(**built, source=str(source), table=table, table_file=table_file)
    _check_sphere_depth(case)
    _check_sphere_force(case)
    _check_scales(case)
    if case.fretting is None:
        _check_tangential_correction(case)
    if case.stages.cycles is not None:
        # the stages in ŝ, derived once here, so every reader of stages.s_hat sees them
        from . import reference
        per_m = reference.scales(case)["s_hat_per_m"]
        s_hat = tuple(c * 2.0 * case.sliding.stroke * per_m for c in case.stages.cycles)
        case = replace(case, stages=replace(case.stages, s_hat=s_hat))
    if case.fretting is not None:
        _check_fretting(case)
    return replace(case, warnings=_warnings(case))


def _check_sphere_depth(case: Case) -> None:
    """A sphere pressed as deep as its radius has no surface there to touch."""
    ind, ld = case.indenter, case.loading
    if ind.profile == "sphere" and ld.control == "depth" and ld.depth >= ind.radius:
        raise CaseError(f"key 'loading.depth' = {ld.depth!r}: not below the sphere's radius "
                        f"(indenter.radius = {ind.radius!r} m), where the sphere has no "
                        "surface; the depth must be smaller (half-space theory wants it far "
                        "smaller: d/R <= 0.01 gives a0/R <= 0.1)")


def _usable(value) -> bool:
    """A positive finite number."""
    return math.isfinite(value) and value > 0


def _check_sphere_force(case: Case) -> None:
    """A force that would press the sphere deeper than its radius (as _check_sphere_depth).

    Checked before the contact is solved for: past about 34 E* R² (a = R - 1e-15 R)
    no contact radius on the sphere carries the force, and the root finder's
    failure said only "not computable in floating point".
    """
    from . import reference
    ind, ld = case.indenter, case.loading
    if ind.profile != "sphere" or ld.control != "force":
        return
    try:
        deepest = reference.sphere(case.E_star, ind.radius, depth=ind.radius)["force"]
        valid = reference.sphere(case.E_star, ind.radius,
                                 depth=0.1 * ind.radius * math.atanh(0.1))["force"]
    except (ArithmeticError, ValueError, RuntimeError):
        return   # moduli out of range: _check_scales says so
    if _usable(deepest) and ld.force >= deepest:
        raise CaseError(f"key 'loading.force' = {ld.force!r}: presses the sphere deeper than its "
                        f"radius (indenter.radius = {ind.radius!r} m), where it has no surface; "
                        f"the force must be below {deepest:.4g} N, which presses it as deep as "
                        f"its radius (half-space theory wants a0/R <= 0.1: at most "
                        f"{valid:.4g} N)")


def _check_scales(case: Case) -> None:
    """The unworn contact must be computable: extreme (valid) numbers can underflow."""
    from . import reference
    try:
        sc = reference.scales(case)
        ok = all(_usable(sc[k]) for k in ("a0", "d0", "F0", "p0"))
    except (ArithmeticError, ValueError, RuntimeError):  # RuntimeError: a root not found
        ok = False
    if ok and not _usable(sc["s_hat_per_m"]):
        # the contact is fine: the wear keys put the sliding scale out of range
        w = case.wear
        raise CaseError(f"keys 'wear.k' = {w.k!r}, 'wear.mu' = {w.mu!r}, 'wear.hardness' = "
                        f"{w.hardness!r}: the sliding scale k μ E*/(σ0 a0) comes out "
                        f"{sc['s_hat_per_m']!r} per metre (E* = {sc['E_star']:.4g} Pa, a0 = "
                        f"{sc['a0']:.4g} m), not a positive finite number; check their "
                        "magnitudes (σ0 in Pa)")
    if not ok:
        control = case.loading.control
        raise CaseError(f"key 'loading.{control}' = {getattr(case.loading, control)!r}: the "
                        "unworn contact of this profile under this load is not computable in "
                        "floating point (its radius, force or pressure comes out 0 or "
                        "infinite); check the load against the profile's size"
                        + (f" (indenter.radius = {case.indenter.radius!r})"
                           if case.indenter.radius is not None else ""))


def _check_tangential_correction(case: Case) -> None:
    """The correction is the springs' reversal at each stroke end: it needs a stroke
    longer than that reversal (docs/theory.md §4)."""
    if not case.wear.tangential_correction:
        return
    sl = case.sliding
    if sl.stroke is None:
        # case files written for the earlier reading (an increment of paper
        # Eq. 15, which changed F/F0 by 1e-6) have the key without a stroke
        raise CaseError("key 'wear.tangential_correction' = true needs 'sliding.stroke' (m): "
                        "the correction is the sliding each stroke end loses while the "
                        "tangential springs reverse (2μq/G* per stroke), so it depends on the "
                        "stroke; give the reciprocating stroke (one way), or remove the key "
                        "(the earlier reading without a stroke changed nothing measurable)")
    from . import reference
    sc = reference.scales(case)
    # the largest spring limit of the unworn contact, μ E* d0/G* (the line load
    # E*(d0 - g) peaks where g = 0): u* of Cattaneo-Mindlin for the paraboloid.
    # Wear lowers it (the line load spreads), so the start decides
    u_star = case.wear.mu * case.E_star * sc["d0"] / case.G_star
    if sl.stroke <= 2.0 * u_star:
        raise CaseError(f"key 'sliding.stroke' = {sl.stroke!r}: with "
                        "wear.tangential_correction the stroke must exceed the springs' "
                        f"reversal 2u* = 2μE*d0/G* = {2.0 * u_star:.4g} m of the unworn contact; "
                        "a shorter stroke is partial slip (give a [fretting] section instead)")


def _check_indenter(built, base: Path):
    ind: Indenter = built["indenter"]
    allowed, needed = PROFILE_KEYS[ind.profile], PROFILE_REQUIRED[ind.profile]
    geometry = ("radius", "radius_y", "flat_radius", "slope_angle", "coefficient", "exponent", "file")
    for name in geometry:
        given = getattr(ind, name) is not None
        if given and name not in allowed:
            raise CaseError(f"key 'indenter.{name}' does not apply to profile "
                            f"\"{ind.profile}\"; it takes: " + ", ".join(sorted(allowed)))
        if not given and name in needed:
            raise CaseError(f"missing key 'indenter.{name}', required by profile \"{ind.profile}\"")
    if ind.profile == "truncated_paraboloid" and ind.flat_radius >= ind.radius:
        raise CaseError(f"key 'indenter.flat_radius' = {ind.flat_radius!r}: must be smaller "
                        f"than indenter.radius = {ind.radius!r}")
    table = table_file = None
    if ind.profile == "table":
        file = Path(ind.file)
        if not file.is_absolute():
            file = (base / file).resolve()
        table, digest = read_profile_table(file)
        table_file = dict(file=str(file), sha256=digest, rows=len(table[0]),
                          last_radius=float(table[0][-1]))
        built["indenter"] = replace(ind, file=str(file))
    return built, table, table_file


def read_profile_table(file: Path) -> tuple[tuple[np.ndarray, np.ndarray], str]:
    """Read a tabulated profile: two columns r, f in metres; and the SHA-256 of the file."""
    name = "indenter.file"
    if file.is_dir():
        raise CaseError(f"key '{name}' = \"{file}\": is a directory, not a CSV file")
    if not file.is_file():
        raise CaseError(f"key '{name}' = \"{file}\": file does not exist")
    rows = []
    try:
        # one read: the digest is of the bytes parsed (the file may change afterwards)
        raw = file.read_bytes()
        # utf-8-sig: a byte-order mark would otherwise glue onto the first number
        lines = list(csv.reader(io.StringIO(raw.decode("utf-8-sig"), newline="")))
    except UnicodeDecodeError as exc:
        raise CaseError(f"key '{name}' = {format_value(str(file))}: not UTF-8 text ({exc.reason} at "
                        f"byte {exc.start}); save the table as UTF-8") from None
    except (OSError, csv.Error) as exc:
        raise CaseError(f"key '{name}' = {format_value(str(file))}: cannot be read: {exc}") from None
    for lineno, row in enumerate(lines, start=1):
        row = [c.strip() for c in row if c.strip()]
        if not row or row[0].startswith("#"):
            continue
        try:
            values = [float(c) for c in row]
        except ValueError:
            if not rows and lineno == 1:
                continue  # header line
            other = next((sep for sep in (";", "\t", " ") if len(row) == 1 and sep in row[0]),
                         None)
            said = {";": "semicolons", "\t": "tabs", " ": "spaces"}
            hint = f" (columns are separated by commas, not {said[other]})" if other else ""
            raise CaseError(f"key '{name}' = \"{file}\": line {lineno} is not two numbers: "
                            f"{','.join(row)}{hint}") from None
        if len(values) != 2:
            raise CaseError(f"key '{name}' = \"{file}\": line {lineno} has {len(values)} "
                            "columns; expected 2 (r, f)")
        rows.append(values)
    if len(rows) < 3:
        raise CaseError(f"key '{name}' = \"{file}\": needs at least 3 rows (r, f), got {len(rows)}")
    data = np.array(rows)
    r, f = data[:, 0], data[:, 1]
    if not np.all(np.isfinite(data)):
        raise CaseError(f"key '{name}' = \"{file}\": contains NaN or inf")
    if r[0] != 0.0:
        raise CaseError(f"key '{name}' = \"{file}\": the first radius must be 0, got {float(r[0])!r}")
    if np.any(np.diff(r) <= 0):
        i = int(np.argmax(np.diff(r) <= 0))
        raise CaseError(f"key '{name}' = \"{file}\": radii must increase strictly; "
                        f"row {i + 2} has r = {float(r[i + 1])!r} after r = {float(r[i])!r}")
    if f[0] != 0.0:
        raise CaseError(f"key '{name}' = \"{file}\": the profile must start at f(0) = 0 "
                        f"(the unworn tip), got {float(f[0])!r}")
    if np.any(f[1:] <= 0):
        raise CaseError(f"key '{name}' = \"{file}\": f must be positive for r > 0 "
                        "(the tip at r = 0 touches first)")
    return (r, f), hashlib.sha256(raw).hexdigest()


def _check_materials(built):
    ind, cf = built["indenter"], built["counterface"]
    for sec, body in (("indenter", ind), ("counterface", cf)):
        if body.rigid:
            for name in ("youngs_modulus", "poisson_ratio"):
                if getattr(body, name) is not None:
                    raise CaseError(f"key '{sec}.{name}' given but '{sec}.rigid' = true")
        else:
            for name in ("youngs_modulus", "poisson_ratio"):
                if getattr(body, name) is None:
                    raise CaseError(f"missing key '{sec}.{name}' (or set '{sec}.rigid = true')")
    if ind.rigid and cf.rigid:
        raise CaseError("indenter.rigid = true and counterface.rigid = true: at least one body "
                        "must be elastic")


def _check_programme(built):
    ld: Loading = built["loading"]
    sl: Sliding = built["sliding"]
    other = "force" if ld.control == "depth" else "depth"
    if getattr(ld, ld.control) is None:
        raise CaseError(f"missing key 'loading.{ld.control}', required by loading.control = "
                        f"\"{ld.control}\"")
    if getattr(ld, other) is not None:
        raise CaseError(f"key 'loading.{other}' given but loading.control = \"{ld.control}\"; "
                        f"remove it or set loading.control = \"{other}\"")
    if built.get("fretting") is not None:
        return  # [sliding] and [stages] do not apply (from_dict refuses them)
    if sl.until == "distance" and sl.distance is None:
        raise CaseError("missing key 'sliding.distance', required by sliding.until = \"distance\"")
    if sl.until == "force_fraction" and sl.distance is not None:
        raise CaseError("key 'sliding.distance' given but sliding.until = \"force_fraction\"; "
                        "set sliding.until = \"distance\" to stop at a distance")
    if sl.until == "force_fraction" and ld.control == "force":
        raise CaseError("sliding.until = \"force_fraction\" cannot end a force-controlled run "
                        "(the force does not fall); use sliding.until = \"distance\" or "
                        "\"cycles\"")
    if sl.until == "cycles":
        for name in ("stroke", "cycles"):
            if getattr(sl, name) is None:
                raise CaseError(f"missing key 'sliding.{name}', required by sliding.until = "
                                "\"cycles\"")
        if sl.distance is not None:
            raise CaseError(f"key 'sliding.distance' = {sl.distance!r} given but sliding.until = "
                            "\"cycles\" (the distance is 2·stroke·cycles); remove one")
    elif sl.cycles is not None:
        raise CaseError(f"key 'sliding.cycles' = {sl.cycles!r} given but sliding.until = "
                        f"\"{sl.until}\"; set sliding.until = \"cycles\" to stop after cycles")
    st = built["stages"]
    if st.cycles is not None:
        if sl.stroke is None:
            raise CaseError(f"key 'stages.cycles' = {list(st.cycles)} needs 'sliding.stroke' "
                            "(one cycle slides 2·stroke)")
        if any(b <= a for a, b in zip(st.cycles, st.cycles[1:])):
            raise CaseError(f"key 'stages.cycles' = {list(st.cycles)}: must increase strictly")
    s = st.s_hat
    if any(b <= a for a, b in zip(s, s[1:])):
        raise CaseError(f"key 'stages.s_hat' = {list(s)}: must increase strictly")


def _check_fretting(case: Case) -> None:
    """Combinations of [fretting] keys with each other and with the rest of the case."""
    fr = case.fretting
    given = [k for k in ("amplitude", "force_amplitude") if getattr(fr, k) is not None]
    if len(given) != 1:
        raise CaseError("[fretting] needs exactly one of 'fretting.amplitude' (m) and "
                        "'fretting.force_amplitude' (N); got "
                        + (" and ".join(given) if given else "neither"))
    if fr.increments % 4:
        raise CaseError(f"key 'fretting.increments' = {fr.increments}: must be a multiple of 4 "
                        "(a quarter cycle ramps from 0 to the amplitude)")
    if case.wear.tangential_correction:
        raise CaseError("key 'wear.tangential_correction' = true: a fretting run always "
                        "includes the elastic tangential displacement (the springs' "
                        "deformation); remove the key")
    if fr.stage_cycles is not None:
        st = fr.stage_cycles
        if any(c != int(c) for c in st):
            raise CaseError(f"key 'fretting.stage_cycles' = {list(st)}: must be whole cycle "
                            "numbers")
        if any(b <= a for a, b in zip(st, st[1:])):
            raise CaseError(f"key 'fretting.stage_cycles' = {list(st)}: must increase strictly")
    if fr.force_amplitude is not None:
        from . import reference
        F = reference.scales(case)["F0"]
        if fr.force_amplitude >= case.wear.mu * F:
            raise CaseError(f"key 'fretting.force_amplitude' = {fr.force_amplitude!r}: must be "
                            f"below μF = {case.wear.mu * F:.4g} N (the friction limit of the "
                            "unworn contact); a larger force has no partial-slip equilibrium — "
                            "use fretting.amplitude for gross slip")


def _warnings(case: Case) -> tuple[str, ...]:
    out = []
    beta = dundurs_beta(case.indenter, case.counterface)
    if abs(beta) > 1e-9:
        out.append(
            f"elastic similarity (paper Eq. 7) does not hold: Dundurs' beta = {beta:.4f} "
            "(0 when similar). The normal and tangential problems are coupled in reality; "
            "they are treated as uncoupled here"
            + (", and the tangential correction is approximate" if case.wear.tangential_correction
               else "")
            + (", and the partial-slip (fretting) solution is approximate"
               if case.fretting is not None else "") + ".")
    return tuple(out)


# --------------------------------------------------------------------------
# Writing

def to_toml(case: Case) -> str:
    """The resolved case, every default filled in, as TOML text."""
    # the source in TOML string form: a newline in a file name must not end the comment
    lines = [f"# resolved case, read from {toml_string(str(case.source))}"]
    for section in SECTIONS:
        obj = getattr(case, section)
        if obj is None:
            continue
        if case.fretting is not None and section in ("sliding", "stages"):
            continue
        lines.append(f"\n[{section}]")
        for name, f in section_fields(section):
            value = getattr(obj, name)
            if value is None:
                continue
            if section == "stages" and name == "s_hat" and case.stages.cycles is not None:
                continue  # derived from stages.cycles (giving both is an error)
            if isinstance(value, tuple):
                text = "[" + ", ".join(repr(v) for v in value) + "]"
            else:
                text = format_value(value)
            unit = f.metadata["unit"]
            lines.append(f"{name} = {text}" + (f"  # {unit}" if unit and unit != "1" else ""))
    return "\n".join(lines) + "\n"


def key_reference() -> str:
    """A Markdown table of every key (``docs/case-files.md`` includes it, generated at every
    docs build)."""
    rows = ["| key | unit | default | meaning |", "|---|---|---|---|"]
    for section in SECTIONS:
        for name, f in section_fields(section):
            meta = f.metadata
            if meta["required"]:
                default = "required"
            elif f.default is None:
                default = "—"
            elif isinstance(f.default, tuple):
                default = "`[" + ", ".join(repr(v) for v in f.default) + "]`"
            else:
                default = f"`{format_value(f.default)}`"
            doc = meta["doc"]
            if meta["choices"]:
                doc += " (" + " \\| ".join(f"`{c}`" for c in meta["choices"]) + ")"
            rows.append(f"| `{section}.{name}` | {meta['unit'] or ''} | {default} | {doc} |")
    return "\n".join(rows)


def _section_dict(obj) -> dict:
    """One section as TOML would read it (keys left at None omitted)."""
    out = {}
    for f in fields(obj):
        value = getattr(obj, f.name)
        if value is not None:
            out[f.name] = list(value) if isinstance(value, tuple) else value
    return out


def to_dict(case: Case) -> dict:
    """The case as nested dicts, as a TOML file of it would read (``from_dict`` inverts it)."""
    out = {name: _section_dict(getattr(case, name)) for name in SECTIONS
           if getattr(case, name) is not None}
    if case.fretting is not None:  # a fretting run has no [sliding] or [stages]
        out.pop("sliding", None)
        out.pop("stages", None)
    elif case.stages.cycles is not None:  # s_hat is derived from the cycles
        out["stages"].pop("s_hat", None)
    return out
