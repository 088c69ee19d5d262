"""The checks only the loader can make: numeric relations between keys, and file contents.

Each is a :class:`~wearcheck.cases.rule_kinds.LoaderOnly` rule of ``cases/rules.py``
(the JSON Schema cannot state them) and takes the built case, after every other
rule has passed. Each raises :class:`CaseError` with one line naming the key,
its value and what is allowed.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from . import reference
from .errors import CaseError
from .schema import format_value


def profile_table(case):
    """``indenter.profile = "table"``: read ``indenter.file`` (relative to the case file);
    the case completed with the table, its record and the file's absolute path."""
    ind = case.indenter
    if ind.profile != "table":
        return None
    file = Path(ind.file)
    if not file.is_absolute():
        base = Path(case.source).parent if case.source != "<dict>" else Path.cwd()
        file = (base / file).resolve()
    table, digest = read_profile_table(file)
    table_file = dict(file=str(file), sha256=digest, rows=len(table[0]),
                      last_radius=float(table[0][-1]))
    return replace(case, indenter=replace(ind, file=str(file)), table=table,
                   table_file=table_file)


def special_file(path: Path) -> str | None:
    """What ``path`` is when it exists but is no regular file nor directory: "a pipe"
    (``/dev/stdin`` fed by ``|``, ``<(...)``), "a character device" (``/dev/null``),
    "a socket", "a block device"; None otherwise. Such a path exists, but a case or
    a table cannot be read from it as from a file (more than once, beside its
    other files), which "does not exist" would hide."""
    import stat
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    for test, what in ((stat.S_ISFIFO, "a pipe"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISSOCK, "a socket"), (stat.S_ISBLK, "a block device")):
        if test(mode):
            return what
    return None


def read_profile_table(file: Path) -> tuple[tuple[np.ndarray, np.ndarray], str]:
    """Read a tabulated profile: two columns r, f in metres; and the SHA-256 of the file."""
    name = "indenter.file"
    if file.is_dir():
        raise CaseError(f"key '{name}' = \"{file}\": is a directory, not a CSV file")
    if special_file(file):
        raise CaseError(f"key '{name}' = \"{file}\": is {special_file(file)}, not a file; "
                        "save the table to a CSV file and name that")
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


def flat_radius_below_radius(case) -> None:
    """A truncated paraboloid's flat tip lies inside its radius of curvature."""
    ind = case.indenter
    if ind.profile == "truncated_paraboloid" and ind.flat_radius >= ind.radius:
        raise CaseError(f"key 'indenter.flat_radius' = {ind.flat_radius!r}: must be smaller "
                        f"than indenter.radius = {ind.radius!r}")


def increasing(key: str):
    """The check that the list ``key`` (``section.name``) increases strictly, when given."""
    section, name = key.split(".")

    def check(case) -> None:
        values = getattr(getattr(case, section) or object(), name, None)
        if values is not None and any(b <= a for a, b in zip(values, values[1:])):
            raise CaseError(f"key '{key}' = {list(values)}: must increase strictly")
    check.__name__ = check.__qualname__ = f"increasing({key!r})"
    return check


def sphere_depth(case) -> None:
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


def sphere_force(case) -> None:
    """A force that would press the sphere deeper than its radius (as sphere_depth).

    Checked before the contact is solved for: past about 34 E* R² (a = R - 1e-15 R)
    no contact radius on the sphere carries the force, and the root finder's
    failure said only "not computable in floating point".
    """
    ind, ld = case.indenter, case.loading
    if ind.profile != "sphere" or ld.control != "force":
        return
    try:
        deepest = reference.sphere(case.E_star, ind.radius, depth=ind.radius)["force"]
        valid = reference.sphere(case.E_star, ind.radius,
                                 depth=0.1 * ind.radius * math.atanh(0.1))["force"]
    except (ArithmeticError, ValueError, RuntimeError):
        return   # moduli out of range: unworn_contact says so
    if _usable(deepest) and ld.force >= deepest:
        raise CaseError(f"key 'loading.force' = {ld.force!r}: presses the sphere deeper than its "
                        f"radius (indenter.radius = {ind.radius!r} m), where it has no surface; "
                        f"the force must be below {deepest:.4g} N, which presses it as deep as "
                        f"its radius (half-space theory wants a0/R <= 0.1: at most "
                        f"{valid:.4g} N)")


def unworn_contact(case) -> None:
    """The unworn contact must be computable: extreme (valid) numbers can underflow."""
    try:
        sc = reference.scales(case)
        ok = all(_usable(sc[k]) for k in ("a0", "d0", "F0", "p0"))
    except (ArithmeticError, ValueError, RuntimeError):  # RuntimeError: a root not found
        ok = False
    if ok and not _usable(sc["s_hat_per_m"]):
        # the contact is fine: the wear keys put the sliding scale out of range
        w = case.wear
        given = "specific_rate" if "wear.k" in case.derived else "k"
        raise CaseError(f"keys 'wear.{given}' = {getattr(w, given)!r}, 'wear.mu' = {w.mu!r}, "
                        f"'wear.hardness' = {w.hardness!r}: the sliding scale k μ E*/(σ0 a0) comes out "
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


def track_radius_beyond_contact(case) -> None:
    """A pin-on-disc track's radius holds the unworn contact (a0 from reference.scales).

    A track radius below the contact radius puts the disc's centre inside the
    contact: the pin spins about a point of its own contact instead of sliding
    along a track, and no solver's model (a groove along the track, the ball
    moving over the flat) describes that.
    """
    sl = case.sliding
    if sl is None or sl.motion != "unidirectional" or sl.track_radius is None:
        return
    try:
        a0 = reference.scales(case)["a0"]
    except (ArithmeticError, ValueError, RuntimeError):
        return   # unworn_contact says so
    if _usable(a0) and sl.track_radius < a0:
        raise CaseError(f"key 'sliding.track_radius' = {sl.track_radius!r}: smaller than the "
                        f"unworn contact radius a0 = {a0:.4g} m, so the disc's centre lies "
                        "inside the contact (the pin spins instead of sliding along a track); "
                        f"the track radius must be at least a0 = {a0:.4g} m (a pin-on-disc "
                        "track is many contact radii: docs/both-bodies.md, \"Range\")")


def stroke_beyond_reversal(case) -> None:
    """The correction is the springs' reversal at each stroke end: it needs a stroke
    longer than that reversal (docs/theory.md §4). (That it needs a stroke at all is a
    rule of the table.)"""
    if not case.wear.tangential_correction or case.fretting is not None:
        return
    sl = case.sliding
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


def force_amplitude_below_friction(case) -> None:
    """A tangential force amplitude has a partial-slip equilibrium only below μF."""
    fr = case.fretting
    if fr is None or fr.force_amplitude is None:
        return
    F = reference.scales(case)["F0"]
    if fr.force_amplitude >= case.wear.mu * F:
        raise CaseError(f"key 'fretting.force_amplitude' = {fr.force_amplitude!r}: must be "
                        f"below μF = {case.wear.mu * F:.4g} N (the friction limit of the "
                        "unworn contact); a larger force has no partial-slip equilibrium — "
                        "use fretting.amplitude for gross slip")
