"""Read, validate and write one case; derive the effective moduli and scales."""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from . import rules
from .loader_checks import special_file
from .errors import ArgumentError, CaseError
from .schema import (BEMSettings, CCXSettings, did_you_mean, OPTIONAL_SECTIONS, REQUIRED_SECTIONS,
                     SECTIONS, CompareSettings, Counterface, FEMSettings, Fretting, Indenter,
                     Loading,
                     MDRSettings, Sliding, Stages, Wear, format_value, build_section,
                     key_problem,
                     section_fields, toml_string)
from . import both_bodies
from . import reference
from .errors import warn_once


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
    ccx: CCXSettings
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
    #: dotted keys the loader derived from their alternative (``wear.k`` from
    #: ``wear.specific_rate`` or back, ``stages.s_hat`` from ``stages.s`` or
    #: ``stages.cycles``): the resolved case names them as comments, not as keys
    derived: tuple[str, ...] = field(default=(), compare=False)

    def __repr__(self) -> str:
        """One line per section: the keys given (defaults filled in), with units."""
        head = f"Case({toml_string(Path(self.source).name) if self.source else ''})"
        return "\n".join([head] + [f"  [{name}] " + ", ".join(
            f"{k} = {v}" + (f" {u}" if u else "") for k, v, u, _ in rows)
            for name, rows in _shown(self)])

    def _repr_html_(self) -> str:
        """The case as a table per section (key, value, unit, meaning) in Jupyter."""
        import html
        title = html.escape(Path(self.source).name if self.source else "case")
        parts = [f"<details open><summary><b>Case</b> {title}</summary>"]
        for name, rows in _shown(self):
            parts.append(f"<table><caption style='text-align:left'><code>[{name}]</code>"
                         "</caption>")
            for k, v, u, f in rows:
                parts.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in (
                    k, v, u, f.metadata.get("doc", ""))) + "</tr>")
            parts.append("</table>")
        if self.warnings:
            parts.append("<p>" + "<br>".join(html.escape(w) for w in self.warnings) + "</p>")
        return "".join(parts) + "</details>"

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
        """K = k_wear μ / σ0 [1/Pa = m³/(N·m)]: wear depth per unit pressure and sliding
        distance (``wear.specific_rate``, given or derived)."""
        w = self.wear
        return w.specific_rate if w.specific_rate is not None else w.k * w.mu / w.hardness

    @property
    def end_distance(self) -> float | None:
        """Sliding distance [m] at which the run stops; None: when the force has fallen."""
        sl = self.sliding
        if sl.until == "distance":
            return sl.distance
        if sl.until == "cycles":
            return self.cycle_length * sl.cycles
        return None

    @property
    def end_condition(self) -> str:
        """How the run ends, in words: ``"it stops once F < 0.01 F0"``."""
        sl = self.sliding
        if self.fretting is not None:
            return f"it stops after {self.fretting.cycles} fretting cycles"
        if sl.until == "force_fraction":
            return f"it stops once F < {sl.force_fraction:g} F0"
        if sl.until == "distance":
            return f"it stops at s = {sl.distance:g} m"
        return f"it stops after {sl.cycles:g} cycles (s = {self.end_distance:g} m)"

    def stages_from(self, k: int) -> str:
        """The requested stages from the k-th on, in the unit they were given:
        ``"ŝ = 20"``, ``"s = 0.5, 1 m"`` or ``"1e+07 cycles"`` (for a note on stages a
        run did not reach)."""
        st = self.stages
        if st.cycles is not None:
            return ", ".join(f"{c:g}" for c in st.cycles[k:]) + " cycles"
        if st.s is not None:
            return "s = " + ", ".join(f"{x:g}" for x in st.s[k:]) + " m"
        return "ŝ = " + ", ".join(f"{x:g}" for x in st.s_hat[k:])

    @property
    def cycles_per_metre(self) -> float | None:
        """Cycles per metre of sliding, 1/(2·stroke) (1/(2π·track_radius) for a
        unidirectional track); None without either."""
        return None if self.cycle_length is None else 1.0 / self.cycle_length

    @property
    def cycle_length(self) -> float | None:
        """Sliding distance of one cycle [m]: 2·stroke, or one revolution 2π·track_radius
        (sliding.motion = "unidirectional"); None without either."""
        return both_bodies.cycle_length(self.sliding)

    @property
    def counterface_wear_rate(self) -> float | None:
        """K_flat [m³/(N·m) = 1/Pa] of a counterface that wears, else None."""
        return both_bodies.counterface_wear_rate(self.counterface, self.wear)

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
            raw[name] = self._given(name, obj)
        return from_dict(raw, source=self.source)

    def _given(self, section: str, obj) -> dict:
        """A replacing section as a file would give it: of keys given one way or another
        (``wear.k`` or ``wear.specific_rate``), those changed from this case win, else
        the one this case was given; the derived ones are dropped."""
        raw = _section_dict(obj)
        current = getattr(self, section, None)
        for group in rules.one_of_groups(section):
            present = [n for n in group if n in raw]
            if len(present) < 2 or current is None:
                continue
            changed = [n for n in present if getattr(obj, n) != getattr(current, n, None)]
            keep = changed or [n for n in present if f"{section}.{n}" not in self.derived]
            for n in present:
                if n not in keep:
                    raw.pop(n)
        return raw

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
            # a key given the other way (stages, a fretting amplitude) replaces the case's
            for other in rules.partners(section, key):
                if f"{section}.{other}" not in items:
                    raw[section].pop(other, None)
        rules.drop_inapplicable(raw, {tuple(name.split(".")) for name in items})
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


def split_values(text: str) -> list[str]:
    """Split at commas outside brackets and quotes: ``[0, 1],[2]`` is two values."""
    values, depth, quote, cur = [], 0, None, ""
    for ch in text:
        if quote:
            quote = None if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch == "[":
            depth += 1
        elif ch == "]":
            depth -= 1
        elif ch == "," and depth == 0:
            values.append(cur.strip())
            cur = ""
            continue
        cur += ch
    values.append(cur.strip())
    return values


def parse_vary(text: str) -> tuple[str, list]:
    """``section.key=v1,v2`` -> (``"section.key"``, [v1, v2]), each value read as ``--set``
    reads it (TOML, or a bare word): the command line's values, typed once."""
    if "=" not in text:
        raise ArgumentError("vary", "expected section.key=v1,v2,...", value=text)
    name, _, rest = text.partition("=")
    name = name.strip()
    problem = key_problem(name)
    if problem:
        raise ArgumentError("vary", problem, value=text)
    texts = split_values(rest)
    if not all(texts):
        raise ArgumentError("vary", "an empty value", value=text)
    return name, [parse_override(f"{name}={v}")[2] for v in texts]


def read_raw(path: str | Path) -> dict:
    """The TOML tables of a case file, unvalidated; every failure a one-line CaseError."""
    path = Path(path)
    if path.is_dir():
        raise CaseError(f"case file '{path}' is a directory, not a TOML file")
    what = special_file(path)
    if what:
        raise CaseError(f"case file '{path}' is {what}, not a file: wearcheck reads a case "
                        "from a file (more than once, and finds a profile table beside it); "
                        "save it first, e.g. 'cat > case.toml', and give that")
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
        for other in rules.partners(section, k):
            if (section, other) not in overridden:
                raw[section].pop(other, None)
    rules.drop_inapplicable(raw, overridden)
    for section in REQUIRED_SECTIONS:
        if section not in raw:
            raise CaseError(f"missing section [{section}]")
    built = {name: build_section(name, raw.get(name, {})) for name in SECTIONS
             if name not in OPTIONAL_SECTIONS or name in raw}
    rules.check(raw, built)
    built["wear"], derived = _derive_wear(built["wear"])
    case = rules.check_loader_only(Case(**built, source=str(source), derived=derived))
    st = case.stages
    if st.cycles is not None or st.s is not None:
        # the stages in ŝ, derived once here, so every reader of stages.s_hat sees them
        per_m = reference.scales(case)["s_hat_per_m"]
        s = st.s if st.s is not None else [c * case.cycle_length for c in st.cycles]
        case = replace(case, stages=replace(st, s_hat=tuple(x * per_m for x in s)))
        derived += ("stages.s_hat",)
    return replace(case, warnings=_warnings(case), derived=derived)


def _derive_wear(w: Wear) -> tuple[Wear, tuple[str, ...]]:
    """Both wear coefficients from the one given (the rule table requires exactly one):
    K = k μ/σ0 (V = K F s for n = 1)."""
    if w.specific_rate is None:
        name, value, other = "wear.k", w.k, "wear.specific_rate"
        w = replace(w, specific_rate=w.k * w.mu / w.hardness)
        derived = w.specific_rate
    else:
        name, value, other = "wear.specific_rate", w.specific_rate, "wear.k"
        w = replace(w, k=w.specific_rate * w.hardness / w.mu)
        derived = w.k
    if not (math.isfinite(derived) and derived > 0):
        raise CaseError(f"key '{name}' = {format_value(value)}: the derived '{other}' comes "
                        f"out {derived!r} (k = K·σ0/μ, wear.mu = {w.mu!r}, wear.hardness = "
                        f"{w.hardness!r} Pa), not a positive finite number; check the "
                        "magnitudes (K in m^3/(N m), σ0 in Pa)")
    return w, (other,)


#: What β = 0 (uncoupled normal and tangential problems) neglects in what ``compare``
#: checks, per power of βμ: the largest change over a run, measured on paper.toml and
#: ball_on_flat.toml by benchmarks/bench_coupling.py (docs/bem-tangential.md §6.5).
#: Reciprocating strokes: second order (table 3: slopes 2, constants independent of
#: βμ), the ring-averaged profile by 0.13 (βμ)² d, the force by 0.81 (βμ)² of itself
#: (late in a depth-controlled run). One direction: first order (table 2 at βμ =
#: 0.0857), the profile by 2.5e-3 d (0.029 βμ), the force by 2.0e-3 (0.023 βμ).
COUPLING_CHANGE = {"reciprocating": {"order": 2, "profile": 0.13, "force": 0.81},
                   "one direction": {"order": 1, "profile": 0.029, "force": 0.023}}
#: the similarity note is given when a neglected change reaches this fraction of
#: the case's own compare tolerance: below a tenth it moves no verdict by more than
#: a tenth of its margin, less than the solvers' own differences on the shipped cases
COUPLING_NOTE_FRACTION = 0.1


def coupling_change(case: Case) -> dict | None:
    """The largest change β = 0 neglects in the worn profile [d] and the force
    [of itself], scaled from the measurement (:data:`COUPLING_CHANGE`); None when
    no measurement covers the case (partial slip, wear.tangential_correction)."""
    if case.fretting is not None or case.wear.tangential_correction:
        return None
    regime = "reciprocating" if case.sliding.stroke is not None else "one direction"
    c = COUPLING_CHANGE[regime]
    size = abs(dundurs_beta(case.indenter, case.counterface) * case.wear.mu) ** c["order"]
    force = c["force"] * size if case.loading.control == "depth" else 0.0  # F held fixed
    return {"regime": regime, "profile": c["profile"] * size, "force": force}


def coupling_matters(case: Case) -> bool:
    """Whether neglecting the normal-tangential coupling (β ≠ 0) reaches
    :data:`COUPLING_NOTE_FRACTION` of the case's compare tolerances; always, when
    β ≠ 0 in a regime no measurement covers (:func:`coupling_change` is None)."""
    if abs(dundurs_beta(case.indenter, case.counterface)) <= 1e-9:
        return False
    change = coupling_change(case)
    if change is None:
        return True
    tol = case.compare
    return (change["profile"] >= COUPLING_NOTE_FRACTION * tol.profile_tolerance
            or change["force"] >= COUPLING_NOTE_FRACTION * tol.force_tolerance)


def _similarity_note(case: Case) -> str:
    beta = dundurs_beta(case.indenter, case.counterface)
    beta_mu = beta * case.wear.mu
    change = coupling_change(case)
    text = (f"elastic similarity (paper Eq. 7) does not hold: Dundurs' beta = {beta:.4f} "
            f"(0 when similar), beta·mu = {beta_mu:.3f}. The normal and tangential problems "
            "are treated as uncoupled: the friction traction moves the pressure against the "
            "traction on the worn body by 3·beta·mu/(2π) = "
            f"{3 * abs(beta_mu) / (2 * math.pi):.3f} contact radii, which bem.coupling = true "
            "solves (docs/bem-tangential.md §6)")
    if change is not None:
        text += (f". Scaled from the measurement ({change['regime']}), this case's "
                 f"ring-averaged worn profile changes by up to {change['profile']:.1e} d")
        if change["force"]:
            text += f" and its force by up to {100 * change['force']:.2g} % of itself"
        if change["regime"] == "one direction":
            text += ", and the wear is asymmetric (up to 9 % of the central wear at beta·mu = 0.086)"
    if case.wear.tangential_correction:
        text += "; the tangential correction is approximate"
    if case.fretting is not None:
        text += "; the partial-slip (fretting) solution is approximate"
    return text + "."


#: the friction coefficient above which a case gets a remark (not refused): dry
#: metal pairs in air slide at μ ≈ 0.1-1 (steel on steel 0.6-0.8, aluminium on steel
#: up to about 1.2); μ well above 1 means adhesion and junction growth (clean metals in
#: vacuum, seizure), where the gross-slip Reye-Archard setting with τ = μp no longer
#: describes the contact. 1.5 leaves the measured dry range, vacuum excepted, unremarked.
FRICTION_REMARK_MU = 1.5


def _friction_note(case: Case) -> str | None:
    mu = case.wear.mu
    if not mu > FRICTION_REMARK_MU:
        return None
    return (f"key 'wear.mu' = {mu!r}: a friction coefficient above {FRICTION_REMARK_MU:g} is "
            "outside dry sliding of metals in air (μ ≈ 0.1-1.2); past it the contact adheres "
            "or seizes, which the gross-slip Reye–Archard model with τ = μp does not describe "
            "(docs/case-files.md, \"Friction\"); results are approximate")


#: the fewest profile-table radii in (0, a0] (a0 the table's unworn contact radius)
#: without a remark: every solver reads the table through one PCHIP interpolant,
#: and a paraboloid sampled at spacing a0/2 (2 radii) gives F0 to 1.5e-4 and a0 to
#: 5.5e-3, at a0 (1 radius) F0 2.5 % low, at 2 a0 12 % (docs/case-files.md, tables)
TABLE_RADII_IN_CONTACT = 2


def _table_note(case: Case) -> str | None:
    if case.indenter.profile != "table" or case.table is None:
        return None
    a0 = reference.scales(case)["a0"]
    r = np.asarray(case.table[0], float)
    inside = int(np.count_nonzero((r > 0.0) & (r <= a0 * (1.0 + 1e-9))))
    if inside >= TABLE_RADII_IN_CONTACT:
        return None
    return (f"key 'indenter.file' = {case.indenter.file!r}: the profile table holds "
            f"{inside} radius(es) inside the unworn contact radius a0 = {a0:.4g} m; every "
            "solver interpolates it (PCHIP) between its rows, so the results are the "
            "interpolant's, not those of a smooth body the rows may sample (a paraboloid "
            "sampled every a0 gives F0 2.5 % low): give at least "
            f"{TABLE_RADII_IN_CONTACT} rows in 0 < r <= a0 (docs/case-files.md)")


def _warnings(case: Case) -> tuple[str, ...]:
    """The case's remarks (recorded in every output): the elastic-similarity note only
    where the coupling matters (:func:`coupling_matters`), the friction note above
    :data:`FRICTION_REMARK_MU`; each kind issued through :mod:`warnings` once per
    process (a μ sweep would repeat it for every run)."""
    out = []
    for kind, note in (("similarity", coupling_matters(case) and _similarity_note(case)),
                       ("friction", _friction_note(case)), ("table", _table_note(case))):
        if not note:
            continue
        out.append(note)
        warn_once(kind, note + " (said once per process; each case's own is in case.warnings)")
    return tuple(out)


# --------------------------------------------------------------------------
# Writing

def _value_text(value, f) -> str:
    """One value of the key ``f`` as TOML. A key of whole numbers (its ``multiple_of`` an
    integer: ``fretting.stage_cycles``) held as floats is written as the integers it
    holds, ``[0, 10, 1000]``, not ``[0.0, 10.0, 1000.0]``; it reads back to the same floats."""
    step = f.metadata.get("multiple_of")
    if (isinstance(value, float) and value.is_integer() and step is not None
            and float(step).is_integer()):
        return str(int(value))
    return format_value(value)


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
            if section == "stages" and name == "s_hat" and "stages.s_hat" in case.derived:
                continue  # derived from stages.s or stages.cycles (giving both is an error)
            if isinstance(value, tuple):
                text = "[" + ", ".join(_value_text(v, f) for v in value) + "]"
            else:
                text = _value_text(value, f)
            unit = f.metadata["unit"]
            line = f"{name} = {text}" + (f"  # {unit}" if unit and unit != "1" else "")
            if f"{section}.{name}" in case.derived:
                # recorded, as a comment: giving both is an error
                how = "K = k μ/σ0" if name == "specific_rate" else "k = K σ0/μ"
                line = f"# {line.replace('  # ', ' ')}, derived: {how}"
            lines.append(line)
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


def _shown(case: Case):
    """(section, [(key, value text, unit, Field)]) of the sections a case has (numbers
    to 6 significant digits: a display, not the resolved case file)."""
    out = []
    for name in SECTIONS:
        obj = getattr(case, name, None)
        if obj is None:
            continue
        rows = []
        for f in fields(obj):
            value = getattr(obj, f.name)
            if value is None:
                continue
            unit = f.metadata.get("unit", "") if f.metadata else ""
            text = _shown_value(value)
            if f"{name}.{f.name}" in case.derived:   # (e.g. k from specific_rate)
                text += " (derived)"
            rows.append((f.name, text, "" if unit == "1" else unit, f))
        out.append((name, rows))
    return out


def _shown_value(value) -> str:
    if isinstance(value, tuple):
        return "[" + ", ".join(_shown_value(v) for v in value) + "]"
    if isinstance(value, float):
        return f"{value:.6g}"
    return format_value(value)


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
    for name in case.derived:  # e.g. s_hat derived from the cycles
        section, key = name.split(".")
        out.get(section, {}).pop(key, None)
    return out
