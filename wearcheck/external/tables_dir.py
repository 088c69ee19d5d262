"""A results directory of CSV tables: ``history.csv`` and, optionally, ``stages.csv``.

``history.csv``: a header row, then one row per step (any order of columns,
extra columns ignored). Required: the sliding distance as ``s`` [m], ``s_hat``
or ``cycles``, and ``force`` [N]. Optional: ``contact_radius`` [m],
``wear_center`` [m], ``wear_volume`` [m³], ``depth`` [m]. A unit in brackets
after a name (``s [mm]``, ``force [kN]``) is converted to SI.

``stages.csv`` (long form): one row per node and stage, with the stage's
distance (``s``, ``s_hat`` or ``cycles``), the radius ``r`` [m] and ``f``
(worn profile) or ``wear`` (wear depth) [m] and/or ``p`` [Pa]. The rows of a
stage share its distance exactly as written.

``--map force=Fz`` reads the user's column ``Fz`` as ``force`` in the unit of its
header; ``--map 'force [kN]=Fz'`` in kN whatever the header says (an export
without units, or a pseudo-time column "Time [s]" that holds the sliding
distance: ``--map 's [mm]=Time'``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.cases import CaseError
from wearcheck.cases.tables import parse_quantity, read_table, split_header

from . import (DISTANCES, HISTORY_QUANTITIES, External, Stage, check_unused, map_item,
               time_columns, unit_words)

STAGE_COLUMNS = {"r": "length", "f": "length", "wear": "length", "p": "pressure"}
#: names that give one quantity: a --map of one of them displaces the others' columns
GROUPS = (tuple(DISTANCES), ("f", "wear"))


def _aliases(mapping: dict, known: dict) -> tuple[dict, dict, list]:
    """From --map name=column: {the user's column name: wearcheck's name}, {wearcheck's
    name: the unit given in --map}, and notes saying which units --map set."""
    check_unused(mapping, set(known), "CSV")
    aliases, units, notes = {}, {}, []
    for key, column in mapping.items():
        name, unit = split_header(key)
        aliases[column.strip()] = name
        if unit is not None:
            parse_quantity(key, known[name], f"--map '{key}={column}'")
            units[name] = unit
            notes.append(f"column '{column}' read as {name} in {unit} (--map)")
    return aliases, units, notes


def read(directory: Path, mapping: dict) -> External:
    """The tables in ``directory`` (see the module docstring)."""
    directory = Path(directory)
    known = dict(DISTANCES, **HISTORY_QUANTITIES, **STAGE_COLUMNS)
    aliases, units, notes = _aliases(mapping, known)
    hist_path, stages_path = directory / "history.csv", directory / "stages.csv"
    if not hist_path.is_file():
        raise CaseError(f"{hist_path}: missing (a results directory holds history.csv, "
                        "with s, s_hat or cycles and force, and optionally stages.csv)")
    columns = dict(DISTANCES, **HISTORY_QUANTITIES)
    table = read_table(hist_path, columns, required=[tuple(DISTANCES), "force"],
                       aliases=aliases, units=units, groups=GROUPS)
    times = time_columns(table.columns)
    kind = times[0]
    if len(times) > 1:
        notes.append(f"{hist_path.name}: the distance is read from '{kind}'; "
                     + ", ".join(f"'{t}'" for t in times[1:]) + " not used")
    notes += mapped_notes(table, aliases)
    if table.ignored:
        notes.append(f"{hist_path.name}: columns not read: " + ", ".join(table.ignored))
    t = table[kind]
    _check_increasing(t, table, kind)
    history = {"time": t}
    for q in HISTORY_QUANTITIES:
        if q in table:
            history[q] = table[q]
    history["force"] = _magnitude(table, "force", notes)
    origin = [f"{hist_path.name} row {int(r)}" for r in table.rows]
    stages, stage_kind, tables = [], kind, [table]
    if stages_path.is_file():
        stages, stage_kind, more, stage_table = read_stages(stages_path, aliases, units)
        notes += more
        tables.append(stage_table)
    else:
        for column, name in aliases.items():
            if name not in columns:
                raise CaseError(f"--map {name}={column}: {stages_path} does not exist (the "
                                f"stages' {name} is read from stages.csv)")
    return External(kind=kind, history=history, history_origin=origin, stages=stages,
                    source=str(directory), format="csv", stage_kind=stage_kind, notes=notes,
                    mapped=mapped_lines(tables, mapping))


def mapped_lines(tables, mapping: dict) -> list[str]:
    """One line per --map item: the tables and the column it was read from, in which
    unit, and the columns of that name it displaced (as :func:`mapped_notes` says
    them per table)."""
    out = []
    for key, column in mapping.items():
        name = split_header(key)[0]
        reads = [(t.path.name, t.headers[name],
                  [c for c in t.ignored if split_header(c)[0] == name])
                 for t in tables if name in t.headers]
        if not reads:
            continue
        headers = {h for _, h, _ in reads}
        where = (" and ".join(f for f, _, _ in reads) + f": {name} read from column "
                 f"'{reads[0][1]}'" if len(headers) == 1 else
                 f"{name} read from " + " and ".join(f"{f} column '{h}'" for f, h, _ in reads))
        passed = [c for _, _, over in reads for c in over]
        out.append(where + unit_words(key) + f" ({map_item(key, column)})"
                   + "".join(f"; column '{c}' not read" for c in dict.fromkeys(passed)))
    return out


def mapped_notes(table, aliases: dict) -> list[str]:
    """What --map decided in ``table``: which column each mapped name was read from,
    and the columns of that name it displaced."""
    out = []
    for column, name in aliases.items():
        if name not in table.headers:
            continue
        passed_over = [c for c in table.ignored if split_header(c)[0] == name]
        out.append(f"{table.path.name}: {name} read from column '{table.headers[name]}' "
                   f"(--map {name}={column})"
                   + "".join(f"; column '{c}' not read" for c in passed_over))
    return out


def _magnitude(table, name, notes) -> np.ndarray:
    """A force column negative throughout (a reaction force, as FE codes export it) as
    its magnitude, with a note; one that changes sign is an error naming the row."""
    v = table[name]
    if not np.any(v < 0):
        return v
    positive = np.flatnonzero(v > 0)
    if positive.size:
        i = int(positive[0]) if v[0] < 0 else int(np.flatnonzero(v < 0)[0])
        raise CaseError(f"{table.where(i, name)}: the force changes sign ({v[i]:g}); give "
                        "the normal force, of one sign throughout")
    notes.append(f"{table.path.name}: the force is negative throughout (a reaction force): "
                 "its magnitude is judged")
    return -v


def _check_increasing(t, table, kind) -> None:
    if np.any(np.isnan(t)):
        i = int(np.flatnonzero(np.isnan(t))[0])
        raise CaseError(f"{table.where(i, kind)}: empty")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise CaseError(f"{table.where(i, kind)}: the distance must increase from row to "
                        f"row; {t[i]:g} follows {t[i - 1]:g}")
    if np.any(t < 0):
        i = int(np.flatnonzero(t < 0)[0])
        raise CaseError(f"{table.where(i, kind)}: negative distance {t[i]:g}")


def read_stages(path: Path, aliases: dict, units: dict | None = None) -> tuple:
    """The long-form stages table: ([Stage], distance kind, notes, the table read)."""
    columns = dict(DISTANCES, **STAGE_COLUMNS)
    table = read_table(path, columns, required=[tuple(DISTANCES), "r"], aliases=aliases,
                       units=units, groups=GROUPS)
    times = time_columns(table.columns)
    kind = times[0]
    notes = mapped_notes(table, aliases)
    if table.ignored:
        notes.append(f"{path.name}: columns not read: " + ", ".join(table.ignored))
    if "f" in table and "wear" in table:
        notes.append(f"{path.name}: the profile is read from 'f'; 'wear' not used")
    has_f, has_w, has_p = "f" in table, "wear" in table and "f" not in table, "p" in table
    if not (has_f or has_w or has_p):
        raise CaseError(f"{path}: no column 'f', 'wear' or 'p' (a stage needs the worn "
                        "profile f [m], the wear depth wear [m] or the pressure p [Pa])")
    t = table[kind]
    if np.any(np.isnan(t)):
        i = int(np.flatnonzero(np.isnan(t))[0])
        raise CaseError(f"{table.where(i, kind)}: empty")
    if np.any(t < 0):
        i = int(np.flatnonzero(t < 0)[0])
        raise CaseError(f"{table.where(i, kind)}: negative distance {t[i]:g}")
    r = table["r"]
    if np.any(r < 0):
        i = int(np.flatnonzero(r < 0)[0])
        raise CaseError(f"{table.where(i, 'r')}: negative radius {r[i]:g}")
    stages = []
    for value in np.unique(t):
        rows = np.flatnonzero(t == value)
        order = rows[np.argsort(r[rows], kind="stable")]
        rr = r[order]
        same = np.flatnonzero(np.diff(rr) == 0)
        if same.size:
            i = int(order[same[0] + 1])
            raise CaseError(f"{table.where(i, 'r')}: radius {rr[same[0]]:g} appears twice "
                            f"in the stage at {kind} = {value:g}")
        if len(rr) < 2:
            raise CaseError(f"{table.where(int(order[0]), kind)}: the stage at {kind} = "
                            f"{value:g} has one row; a stage needs its radii, one row each")
        first, last = int(table.rows[rows.min()]), int(table.rows[rows.max()])

        def col(name, on):
            if not on:
                return None
            v = table[name][order]
            if np.any(np.isnan(v)):
                i = int(order[np.flatnonzero(np.isnan(v))[0]])
                raise CaseError(f"{table.where(i, name)}: empty")
            return v
        stages.append(Stage(time=float(value), r=rr, f=col("f", has_f), p=col("p", has_p),
                            wear=col("wear", has_w),
                            origin=f"{path.name} rows {first}-{last}"))
    return stages, kind, notes, table
