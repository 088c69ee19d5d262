"""Reading a user's CSV table with units in its header: ``force [N]``, ``s [mm]``.

One job: a header row names the columns (in any order; extra columns are kept
aside, not read), a unit in brackets after a name is converted to SI, an
unknown unit or a cell that is not a number is one :class:`CaseError` naming
the file, the row and the column. Rows are counted as a spreadsheet shows
them: the header is row 1 when it is the file's first line.

``read_table(path, columns, required=[...])`` returns a :class:`Table` whose
columns are SI arrays. The quantities a column may hold are the keys of
:data:`UNITS` ("length", "force", "pressure", "volume", "number").
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping

import numpy as np

from .errors import CaseError

#: the units each quantity may be given in, with their factor to SI. "µ" is
#: accepted as the micro sign (U+00B5), the Greek mu (U+03BC) or "u"
UNITS: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "µm": 1e-6, "nm": 1e-9, "km": 1e3},
    "force": {"N": 1.0, "kN": 1e3, "mN": 1e-3, "µN": 1e-6},
    "pressure": {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "N/m²": 1.0,
                 "N/mm²": 1e6},
    "volume": {"m³": 1.0, "cm³": 1e-6, "mm³": 1e-9, "µm³": 1e-18},
    "number": {"": 1.0, "-": 1.0, "1": 1.0},
}
#: the SI unit of each quantity, as error messages name it
SI_UNIT = {"length": "m", "force": "N", "pressure": "Pa", "volume": "m³", "number": ""}

# a unit is the last bracketed group at the end: "Force Reaction (Z) [N]" is the force
# reaction (z) in N (the way ANSYS and COMSOL export tables)
_HEADER = re.compile(r"^(?P<name>.*?)\s*[\[\(](?P<unit>[^\[\]\(\)]*)[\]\)]\s*$")


def normal_unit(text: str) -> str:
    """A unit as :data:`UNITS` spells it: µ for the Greek mu or u, ³ and ² for ^3 and ^2."""
    t = text.strip().replace("\u03bc", "µ").replace("^3", "³").replace("^2", "²")
    t = t.replace("**3", "³").replace("**2", "²")
    if t.startswith("u") and len(t) > 1 and t[1:] in ("m", "N", "m³"):
        t = "µ" + t[1:]
    return t


def unit_factor(unit: str, quantity: str) -> float | None:
    """The factor from ``unit`` to SI for ``quantity``, or None when it is not one of its units."""
    return UNITS[quantity].get(normal_unit(unit))


def split_header(cell: str) -> tuple[str, str | None]:
    """``"force [N]"`` -> ("force", "N"); ``"Force Reaction (Z) [N]"`` -> ("force reaction
    (z)", "N"); ``"s"`` -> ("s", None). Names come out in lower case."""
    text = cell.strip()
    m = _HEADER.match(text)
    if m is None or not m.group("name").strip():
        return text.lower(), None
    return m.group("name").strip().lower(), m.group("unit").strip()


@dataclass
class Table:
    """A table read by :func:`read_table`.

    columns : {name: (n,) float array in SI}, only the columns asked for and found.
    rows : (n,) the spreadsheet row of each entry (the header's row + 1, ...).
    units : {name: the unit as written in the header, or None}.
    ignored : header cells that are not columns asked for (kept aside, unread).
    path : the file.
    """

    columns: dict
    rows: np.ndarray
    units: dict
    ignored: list = field(default_factory=list)
    path: Path | None = None

    def __contains__(self, name) -> bool:
        return name in self.columns

    def __getitem__(self, name) -> np.ndarray:
        return self.columns[name]

    def where(self, i: int, name: str) -> str:
        """'FILE, row R, column 'NAME'' of entry i of column ``name``."""
        return f"{self.path}, row {int(self.rows[i])}, column '{name}'"


def _delimiter(line: str) -> str:
    counts = {d: line.count(d) for d in (",", ";", "\t")}
    best = max(counts, key=counts.get)
    return best if counts[best] else ","


def read_table(path: str | Path, columns: Mapping[str, str], *,
               required: Iterable[str | tuple[str, ...]] = (),
               aliases: Mapping[str, str] | None = None,
               units: Mapping[str, str] | None = None) -> Table:
    """Read a CSV table with a header row; units in the header are converted to SI.

    Parameters
    ----------
    path : the CSV file (UTF-8; comma, semicolon or tab separated; lines
        starting with ``#`` are comments).
    columns : {name: quantity} of the columns to read, quantity a key of
        :data:`UNITS`. Names are matched case-insensitively; a column without
        a unit is taken in SI.
    required : names that must be present; a tuple of names means one of them.
    aliases : {other spelling: name}, e.g. {"ŝ": "s_hat"}, {"force reaction (z)":
        "force"}: a header cell is matched by its name without the unit, or whole.
    units : {name: unit} overriding (or supplying) a column's unit, e.g. {"s": "mm"}
        for a column "Time [s]" that holds the sliding distance in mm, or a force
        column of an Abaqus export (no units) in N.

    Returns
    -------
    Table. An empty cell (or "nan") of a column that is not required alone is NaN.

    Raises
    ------
    CaseError
        one line naming the file, and where it applies the row and the column:
        no header, a missing column, an unknown unit, a cell that is not a
        finite number, a row with fewer cells than the header.
    """
    path = Path(path)
    aliases = {k.strip().lower(): v for k, v in (aliases or {}).items()}
    given_units = dict(units or {})
    if path.is_dir():
        raise CaseError(f"{path}: is a directory, not a CSV file")
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            text = fh.read()
    except FileNotFoundError:
        raise CaseError(f"{path}: file does not exist") from None
    except UnicodeDecodeError as exc:
        raise CaseError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start}); save "
                        "the table as UTF-8") from None
    except OSError as exc:
        raise CaseError(f"{path}: cannot be read: {exc.strerror or exc}") from None
    lines = text.splitlines()
    header_at = next((i for i, line in enumerate(lines)
                      if line.strip() and not line.lstrip().startswith("#")), None)
    if header_at is None:
        raise CaseError(f"{path}: empty (expected a header row naming the columns, e.g. "
                        + ",".join(_example(columns, required)) + ")")
    delim = _delimiter(lines[header_at])
    try:
        header = next(csv.reader([lines[header_at]], delimiter=delim))
    except csv.Error as exc:
        raise CaseError(f"{path}, row {header_at + 1}: cannot be read as CSV: {exc}") from None
    where: dict[str, int] = {}
    units: dict[str, str | None] = {}
    ignored = []
    for j, cell in enumerate(header):
        name, unit = split_header(cell)
        whole = cell.strip().lower()
        if name in aliases:
            name = aliases[name]
        elif whole in aliases:
            # the cell named whole: its last bracket is its unit only when it is one
            # ("Force Reaction (Z)": the (Z) belongs to the name)
            name = aliases[whole]
            if unit is not None and name in columns and unit_factor(unit, columns[name]) is None:
                unit = None
        if name in given_units:
            unit = given_units[name]
        if name not in columns:
            if cell.strip():
                ignored.append(cell.strip())
            continue
        if name in where:
            raise CaseError(f"{path}, row {header_at + 1}: column '{name}' appears twice "
                            f"(columns {where[name] + 1} and {j + 1})")
        quantity = columns[name]
        if unit is not None and unit_factor(unit, quantity) is None:
            allowed = ", ".join(u or "(none)" for u in UNITS[quantity] if u not in ("-", "1"))
            raise CaseError(f"{path}, row {header_at + 1}, column '{cell.strip()}': unknown "
                            f"unit '{unit}' for a {quantity}; allowed: {allowed}")
        where[name] = j
        units[name] = unit
    if not where and _numeric(header):
        raise CaseError(f"{path}, row {header_at + 1}: no header row (the first row holds "
                        "numbers); add one naming the columns, e.g. "
                        + ",".join(_example(columns, required)))
    for need in required:
        options = (need,) if isinstance(need, str) else tuple(need)
        if not any(o in where for o in options):
            said = " or ".join(f"'{o}'" for o in options) if len(options) < 3 else \
                ", ".join(f"'{o}'" for o in options[:-1]) + f" or '{options[-1]}'"
            found = ", ".join(f"'{c.strip()}'" for c in header if c.strip()) or "none"
            raise CaseError(f"{path}: no column {said} (columns found: {found})")
    values = {name: [] for name in where}
    rows = []
    reader = csv.reader(lines[header_at + 1:], delimiter=delim)
    try:
        for offset, cells in enumerate(reader):
            row = header_at + 2 + offset
            if not cells or not any(c.strip() for c in cells) or cells[0].lstrip().startswith("#"):
                continue
            for name, j in where.items():
                if j >= len(cells):
                    raise CaseError(f"{path}, row {row}, column '{header[j].strip()}': missing "
                                    f"(the row has {len(cells)} cells, the header {len(header)})")
                cell = cells[j].strip()
                if cell.lower() == "nan" and not _is_required(name, required):
                    cell = ""              # written for "no value" (wearcheck writes it too)
                if not cell:
                    if _is_required(name, required):
                        raise CaseError(f"{path}, row {row}, column '{header[j].strip()}': "
                                        "empty")
                    values[name].append(math.nan)
                    continue
                try:
                    v = float(cell)
                except ValueError:
                    hint = (" (a decimal comma? write 1.5, not 1,5)"
                            if delim == ";" and re.fullmatch(r"-?\d+,\d+", cell) else "")
                    raise CaseError(f"{path}, row {row}, column '{header[j].strip()}': "
                                    f"'{cell}' is not a number{hint}") from None
                if not math.isfinite(v):
                    raise CaseError(f"{path}, row {row}, column '{header[j].strip()}': "
                                    f"'{cell}' is not a finite number")
                values[name].append(v)
            rows.append(row)
    except csv.Error as exc:
        raise CaseError(f"{path}: cannot be read as CSV: {exc}") from None
    if not rows:
        raise CaseError(f"{path}: the header row is followed by no data rows")
    out = {}
    for name, vals in values.items():
        unit = units[name]
        factor = 1.0 if unit is None else unit_factor(unit, columns[name])
        out[name] = np.asarray(vals, float) * factor
    return Table(columns=out, rows=np.asarray(rows), units=units, ignored=ignored, path=path)


def _is_required(name: str, required) -> bool:
    """A column named alone in ``required`` has no empty cells (a column of a group, one
    of which must be present, may: the caller checks the one it uses)."""
    return any(name == need for need in required if isinstance(need, str))


def _numeric(cells) -> bool:
    try:
        [float(c) for c in cells if c.strip()]
    except ValueError:
        return False
    return True


def _example(columns, required) -> list[str]:
    names = []
    for need in required:
        name = need if isinstance(need, str) else need[0]
        unit = SI_UNIT[columns[name]]
        names.append(f"{name} [{unit}]" if unit else name)
    return names or list(columns)[:2]


def parse_quantity(text: str, quantity: str, what: str) -> tuple[str, float]:
    """``"p [MPa]"`` -> ("p", 1e6): a name with an optional unit of ``quantity``.

    ``what`` names the source in the error (e.g. "--map 'p [MPa]=CPRESS'").
    """
    name, unit = split_header(text)
    if unit is None:
        return name, 1.0
    factor = unit_factor(unit, quantity)
    if factor is None:
        allowed = ", ".join(u or "(none)" for u in UNITS[quantity] if u not in ("-", "1"))
        raise CaseError(f"{what}: unknown unit '{unit}' for a {quantity}; allowed: {allowed}")
    return name, factor
