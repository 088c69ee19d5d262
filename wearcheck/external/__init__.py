"""Results produced elsewhere (another FE code, a lab's script), read for ``wearcheck verify``.

Three formats, each read by one module into the same :class:`External`:

- :mod:`.tables_dir`: a directory with ``history.csv`` and optionally ``stages.csv``;
- :mod:`.vtk_series`: a ``.pvd`` series or a single ``.vtu`` with surface point data
  (through meshio);
- :mod:`.calculix`: CalculiX's ``.frd`` (stage fields) and ``.dat`` (printed totals).

:func:`read` chooses by what ``path`` is. ``mapping`` holds the ``--map
name=field`` pairs of the command line: which of the user's columns, arrays or
result blocks is which wearcheck quantity, with a unit in brackets
(``"p [MPa]=CONTACT.CPRESS"``). Values come out in SI; the sliding distance as
the user gave it (``s``, ``s_hat`` or ``cycles``), converted by the caller that
knows the case.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wearcheck.cases import CaseError
from wearcheck.cases.tables import parse_quantity
from wearcheck.cases.tables import split_header

#: the history quantities a user may give (besides the sliding distance), with their kind
HISTORY_QUANTITIES = {"force": "force", "contact_radius": "length", "wear_center": "length",
                      "wear_volume": "volume", "depth": "length"}
#: the ways a user may give the sliding distance, with their kind
DISTANCES = {"s": "length", "s_hat": "number", "cycles": "number"}


@dataclass
class Stage:
    """One stage of the user's results: at distance ``time`` (in the unit of the
    results' ``stage_kind``), radii r [m] and the worn profile f [m] (or the wear
    depth ``wear`` [m]) and/or the pressure p [Pa] on them (None when not given);
    ``origin`` says where it was read (file and rows)."""

    time: float
    r: np.ndarray
    f: np.ndarray | None
    p: np.ndarray | None
    origin: str
    wear: np.ndarray | None = None


@dataclass
class External:
    """A user's results, in SI.

    kind : how the history's sliding distance is given: "s" [m], "s_hat" or "cycles";
        stage_kind : the same for the stages.
    history : {"time": (n,), quantity: (n,)}: the quantities of
        :data:`HISTORY_QUANTITIES` given (NaN where a row leaves one out).
    history_origin : (n,) where each history row was read ("history.csv row 7").
    stages : the stages with profiles or pressures, by increasing time; a profile
        given as the wear depth w is kept in ``Stage.wear`` (the caller forms
        f = f0 + w, knowing the unworn profile).
    source, format : the path read and its format; notes : what the reader decided.
    time_precision : how closely two distances written for the same time agree.
    """

    kind: str
    history: dict
    history_origin: list
    stages: list
    source: str
    format: str
    stage_kind: str = "s"
    notes: list = field(default_factory=list)
    #: relative precision of the distances as written: a stage and a history row
    #: within it are the same time (a table's stages and history written with
    #: different digits; CalculiX's .frd and .dat)
    time_precision: float = 1e-6
    #: what each ``--map`` item read, one line each ("history.csv: force read from
    #: column 'Fn [N]' (--map force=Fn); column 'force [N]' not read"), in its order
    mapped: list = field(default_factory=list)

    @property
    def given(self) -> list[str]:
        """The history quantities given in at least one row."""
        return [q for q in HISTORY_QUANTITIES
                if q in self.history and np.any(np.isfinite(self.history[q]))]


def parse_mapping(items) -> dict:
    """``["p [MPa]=CPRESS", ...]`` -> {"p [MPa]": "CPRESS"}; one line per bad item."""
    out = {}
    for item in items or ():
        if "=" not in item:
            raise CaseError(f"--map '{item}': expected name=field, e.g. --map p=CPRESS or "
                            "--map 'force [kN]=Fz'")
        key, value = item.split("=", 1)
        key, value = key.strip(), value.strip()
        if not key or not value:
            raise CaseError(f"--map '{item}': expected name=field with both sides given")
        out[key] = value
    return out


def read(path: str | Path, mapping: dict | None = None) -> External:
    """The results at ``path``: a directory or a file, in any of the three formats.

    Raises
    ------
    CaseError
        one line naming the file (and row and column, where they apply).
    """
    path = Path(path)
    mapping = dict(mapping or {})
    if not path.exists():
        raise CaseError(f"results '{path}' do not exist")
    if path.is_dir():
        if (path / "history.csv").is_file() or (path / "stages.csv").is_file():
            # lazy (c): the readers import this module's names (DISTANCES, External, ...)
            from .tables_dir import read as read_dir
            return read_dir(path, mapping)
        pvd = sorted(path.glob("*.pvd"))
        if len(pvd) == 1:
            # lazy (c): the readers import this module's names (DISTANCES, External, ...)
            from .vtk_series import read as read_vtk
            return read_vtk(pvd[0], mapping)
        ccx = sorted(path.glob("*.frd")) + sorted(path.glob("*.dat"))
        if ccx:
            # lazy (c): the readers import this module's names (DISTANCES, External, ...)
            from .calculix import read as read_ccx
            return read_ccx(ccx[0], mapping)
        raise CaseError(f"results '{path}': no history.csv, no single .pvd, no CalculiX "
                        ".frd or .dat file in this directory (docs/verify.md lists the "
                        "formats)")
    suffix = path.suffix.lower()
    if suffix in (".pvd", ".vtu"):
        # lazy (c): the readers import this module's names (DISTANCES, External, ...)
        from .vtk_series import read as read_vtk
        return read_vtk(path, mapping)
    if suffix in (".frd", ".dat"):
        # lazy (c): the readers import this module's names (DISTANCES, External, ...)
        from .calculix import read as read_ccx
        return read_ccx(path, mapping)
    if suffix == ".csv":
        raise CaseError(f"results '{path}': give the directory that holds history.csv "
                        "(and stages.csv), not the file")
    raise CaseError(f"results '{path}': unknown format '{suffix}'; a directory with "
                    "history.csv, a .pvd or .vtu file, or a CalculiX .frd or .dat file")


def map_item(key: str, value: str) -> str:
    """``--map force=Fn``, quoted as a shell needs it: ``--map 's [mm]=time'``."""
    item = f"{key}={value}"
    plain = all(c.isalnum() or c in "_.=*-+/:" for c in item)
    return f"--map {item}" if plain else f"--map '{item}'"


def unit_words(key: str) -> str:
    """' in MPa' for a mapping key 'p [MPa]', '' without a unit."""
    unit = split_header(key)[1]
    return f" in {unit}" if unit else ""


def geometry_line(source: str, name: str, key: str, value: str) -> str:
    """What ``--map axis=...`` or ``--map 'r [mm]=points'`` decided, in one line."""
    if name == "axis":
        return (f"{source}: the radius is the distance from the {value.lower()} axis "
                f"({map_item(key, value)})")
    return (f"{source}: r is the points' distance from the axis, their coordinates read"
            f"{unit_words(key) or ' in m'} ({map_item(key, value)})")


#: the coordinate axes of a point's (x, y, z)
AXES = {"x": 0, "y": 1, "z": 2}


def geometry_mapping(name: str, key: str, value: str, where: str) -> tuple[str, object]:
    """``--map axis=z`` -> ("axis", "z"); ``--map 'r [mm]=points'`` -> ("r", 1e-3): the
    symmetry axis and the unit of the coordinates, for the formats with points."""
    if name == "axis":
        if value.lower() not in AXES:
            raise CaseError(f"{where}: the axis is x, y or z")
        return "axis", value.lower()
    if value != "points":
        raise CaseError(f"{where}: r comes from the points' coordinates; give their unit as "
                        "--map 'r [mm]=points'")
    return "r", parse_quantity(key, "length", where)[1]


def check_unused(mapping: dict, used: set, fmt: str) -> None:
    """A --map name that the format does not know is an error, not ignored."""
    unknown = [k for k in mapping if split_header(k)[0] not in used]
    if unknown:
        raise CaseError(f"--map '{unknown[0]}={mapping[unknown[0]]}': '{split_header(unknown[0])[0]}' "
                        f"is not a quantity of the {fmt} format; known: "
                        + ", ".join(sorted(used)))


def time_columns(columns: dict) -> list[str]:
    """The distance columns given, in the order of :data:`DISTANCES`."""
    return [k for k in DISTANCES if k in columns]
