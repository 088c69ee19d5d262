"""Reading a user's CSV table with units in its header: ``force [N]``, ``s [mm]``, ``± D [um]``.

The one parser of the tables users bring, in two parts:

* what every such table shares (used by :func:`read_table` here and by
  :mod:`wearcheck.user_tables`, the measurement sheets of ``wearcheck fit``):
  the units of each dimension and their spellings (:func:`unit_factor`), a
  header cell as name, unit and ± (:func:`parse_header`), the file read as
  numbered lines with comments and blank lines skipped (:func:`read_lines`,
  :func:`data_lines`, :func:`split_cells`), a cell as a finite number
  (:func:`number`), and every fault one :class:`CaseError` naming the file, the
  row and the column (rows counted as a spreadsheet shows them: the file's line
  numbers);
* :func:`read_table`, the reader of an FE program's results for ``wearcheck
  verify``: the header row names the columns in any order (extra columns kept
  aside, unread); comma, semicolon or tab separated; aliases and units the
  caller supplies (FE exports name columns their own way).

``read_table(path, columns, required=[...])`` returns a :class:`Table` whose
columns are SI arrays. The dimensions a column may have are the keys of
:data:`UNITS` ("length", "area", "volume", "force", "pressure", "number").
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

#: the units each dimension may be given in, with their factor to SI, as
#: :func:`normal_unit` spells them ("µ" the micro sign, "²" and "³" superscripts)
UNITS: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "µm": 1e-6, "nm": 1e-9, "km": 1e3},
    "area": {"m²": 1.0, "cm²": 1e-4, "mm²": 1e-6, "µm²": 1e-12, "nm²": 1e-18},
    "volume": {"m³": 1.0, "cm³": 1e-6, "mm³": 1e-9, "µm³": 1e-18, "nm³": 1e-27},
    "force": {"N": 1.0, "kN": 1e3, "mN": 1e-3, "µN": 1e-6},
    "pressure": {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "N/m²": 1.0,
                 "N/mm²": 1e6},
    "number": {"": 1.0, "-": 1.0, "1": 1.0},
}
#: the SI unit of each dimension, as error messages name it
SI_UNIT = {"length": "m", "area": "m²", "volume": "m³", "force": "N", "pressure": "Pa",
           "number": ""}


def normal_unit(text: str) -> str:
    """A unit as :data:`UNITS` spells it: µ for the Greek mu or a leading u (``um``,
    ``uN``), ² and ³ for ``^2``, ``**2`` or a trailing 2 after a letter (``mm3``)."""
    t = text.strip().replace("\u03bc", "µ")
    for power, sup in (("3", "³"), ("2", "²")):
        t = t.replace(f"**{power}", sup).replace(f"^{power}", sup)
        t = re.sub(rf"(?<=[A-Za-zµ]){power}$", sup, t)
    if t.startswith("u") and len(t) > 1 and any("µ" + t[1:] in units for units in UNITS.values()):
        t = "µ" + t[1:]
    return t


def unit_factor(unit: str, quantity: str,
                units: Mapping[str, Mapping[str, float]] = UNITS) -> float | None:
    """The factor from ``unit`` to SI for the dimension ``quantity`` (of ``units``: a
    caller may allow fewer), or None when it is not one of its units."""
    return units[quantity].get(normal_unit(unit))


# a unit is the last bracketed group at the end: "Force Reaction (Z) [N]" is the force
# reaction (z) in N (the way ANSYS and COMSOL export tables)
_HEADER = re.compile(r"^(?P<name>.*?)\s*[\[\(](?P<unit>[^\[\]\(\)]*)[\]\)]\s*$")
# an uncertainty column: "± D [um]", "+- D", "+/- D"
_UNCERTAINTY = re.compile(r"^(±|\+/-|\+-)\s*")


@dataclass(frozen=True)
class Header:
    """A header cell: ``text`` as written (stripped), ``name`` without the unit and the ±
    (its case kept), ``unit`` as written or None, ``uncertainty`` for a ± column."""

    text: str
    name: str
    unit: str | None
    uncertainty: bool = False


def parse_header(cell: str) -> Header:
    """``"± D [um]"`` -> Header("± D [um]", "D", "um", True); ``"Force Reaction (Z) [N]"`` ->
    name "Force Reaction (Z)", unit "N"; ``"s"`` -> name "s", no unit."""
    text = cell.strip()
    m = _UNCERTAINTY.match(text)
    rest = text[m.end():] if m else text
    h = _HEADER.match(rest)
    if h is None or not h.group("name").strip():
        return Header(text, rest.strip(), None, m is not None)
    return Header(text, h.group("name").strip(), h.group("unit").strip(), m is not None)


def split_header(cell: str) -> tuple[str, str | None]:
    """``"force [N]"`` -> ("force", "N"); ``"Force Reaction (Z) [N]"`` -> ("force reaction
    (z)", "N"); ``"s"`` -> ("s", None). Names come out in lower case (a ± stays in it)."""
    text = cell.strip()
    m = _HEADER.match(text)
    if m is None or not m.group("name").strip():
        return text.lower(), None
    return m.group("name").strip().lower(), m.group("unit").strip()


def read_lines(path: str | Path, where: str) -> list[str]:
    """The lines of a UTF-8 text file (a byte-order mark dropped); a directory, a file
    that does not exist or cannot be read, or bytes that are not UTF-8: one line
    starting with ``where`` (e.g. "file 'x.csv'")."""
    path = Path(path)
    if path.is_dir():
        raise CaseError(f"{where} is a directory, not a CSV file")
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            return fh.read().splitlines()
    except FileNotFoundError:
        raise CaseError(f"{where} does not exist") from None
    except UnicodeDecodeError as exc:
        raise CaseError(f"{where} is not UTF-8 text ({exc.reason} at byte {exc.start}); save "
                        "it as UTF-8") from None
    except OSError as exc:
        raise CaseError(f"{where} cannot be read: {exc.strerror or exc}") from None


def data_lines(lines: list[str]) -> list[tuple[int, str]]:
    """(line number from 1, text) of the lines that are neither blank nor comments (#)."""
    return [(i, line) for i, line in enumerate(lines, start=1)
            if line.strip() and not line.lstrip().startswith("#")]


def split_cells(numbered: list[tuple[int, str]], delimiter: str,
                where: str) -> list[tuple[int, list[str]]]:
    """Each numbered line split into its cells (CSV quoting; spaces after a delimiter
    skipped)."""
    out = []
    for line, text in numbered:
        try:
            out.append((line, next(csv.reader([text], delimiter=delimiter,
                                              skipinitialspace=True), [])))
        except csv.Error as exc:
            raise CaseError(f"{where}, row {line}: cannot be read as CSV: {exc}") from None
    return out


def sniff_delimiter(line: str) -> str:
    """The most frequent of comma, semicolon and tab in a header line (comma if none)."""
    counts = {d: line.count(d) for d in (",", ";", "\t")}
    best = max(counts, key=counts.get)
    return best if counts[best] else ","


def number(text: str, at: str, comma_hint: bool = True) -> float:
    """A cell as a finite number; else one line starting with ``at`` (file, row,
    column). ``comma_hint``: say "a decimal comma?" of a cell like 1,5."""
    try:
        value = float(text)
    except ValueError:
        hint = (" (a decimal comma? write 1.5, not 1,5)"
                if comma_hint and re.fullmatch(r"[+-]?\d+,\d+", text.strip()) else "")
        raise CaseError(f"{at}: '{text}' is not a number{hint}") from None
    if not math.isfinite(value):
        raise CaseError(f"{at}: '{text}' is not a finite number")
    return value


# -- the FE results' reader -------------------------------------------------------------

@dataclass
class Table:
    """A table read by :func:`read_table`.

    columns : {name: (n,) float array in SI}, only the columns asked for and found.
    rows : (n,) the spreadsheet row of each entry (the header's row + 1, ...).
    units : {name: the unit as written in the header, or None}.
    ignored : header cells that are not columns asked for (kept aside, unread).
    path : the file.
    headers : {name: the header cell it was read from, as written}.
    """

    columns: dict
    rows: np.ndarray
    units: dict
    ignored: list = field(default_factory=list)
    path: Path | None = None
    headers: dict = field(default_factory=dict)

    def __contains__(self, name) -> bool:
        return name in self.columns

    def __getitem__(self, name) -> np.ndarray:
        return self.columns[name]

    def where(self, i: int, name: str) -> str:
        """'FILE, row R, column 'NAME'' of entry i of column ``name``."""
        return f"file '{self.path}', row {int(self.rows[i])}, column '{name}'"


def read_table(path: str | Path, columns: Mapping[str, str], *,
               required: Iterable[str | tuple[str, ...]] = (),
               aliases: Mapping[str, str] | None = None,
               units: Mapping[str, str] | None = None,
               groups: Iterable[Iterable[str]] = ()) -> Table:
    """Read a CSV table with a header row; units in the header are converted to SI.

    Parameters
    ----------
    path : the CSV file (UTF-8; comma, semicolon or tab separated; lines
        starting with ``#`` are comments).
    columns : {name: quantity} of the columns to read, quantity a key of
        :data:`UNITS`. Names are matched case-insensitively; a column without
        a unit is taken in SI.
    required : names that must be present; a tuple of names means one of them.
    aliases : {the user's column: name}, e.g. {"Fz": "force"}, {"force reaction (z)":
        "force"} (``--map``): a header cell is matched by its name without the unit,
        or whole. An alias of a name in ``columns`` must match a header cell (else an
        error naming the columns there are), and it wins: a cell named ``name``
        itself (or another name of its group) is then not read (in ``ignored``).
    units : {name: unit} overriding (or supplying) a column's unit, e.g. {"s": "mm"}
        for a column "Time [s]" that holds the sliding distance in mm, or a force
        column of an Abaqus export (no units) in N.
    groups : names that give one quantity (the distance as s, s_hat or cycles; the
        profile as f or wear): an alias of one displaces the others' columns.

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
    where_file = f"file '{path}'"
    given_aliases = {k.strip(): v for k, v in (aliases or {}).items()}
    aliases = {k.lower(): v for k, v in given_aliases.items()}
    given_units = dict(units or {})
    numbered = data_lines(read_lines(path, where_file))
    if not numbered:
        raise CaseError(f"{where_file} is empty (expected a header row naming the columns, "
                        "e.g. " + ",".join(_example(columns, required)) + ")")
    header_at, header_text = numbered[0]
    delim = sniff_delimiter(header_text)
    header = split_cells([numbered[0]], delim, where_file)[0][1]
    _check_aliases(given_aliases, header, columns, where_file)
    # a name mapped by an alias (and the rest of its group) is read from the alias's
    # column only: "--map force=Fn" beside a column "force [N]" (a friction force)
    displaced = set()
    for name in {v for v in aliases.values() if v in columns}:
        displaced |= {name}.union(*(set(g) for g in groups if name in g))
    where: dict[str, int] = {}
    units: dict[str, str | None] = {}
    ignored = []
    for j, cell in enumerate(header):
        name, unit = split_header(cell)
        whole = cell.strip().lower()
        if name in displaced and name not in aliases and whole not in aliases:
            if cell.strip():
                ignored.append(cell.strip())
            continue
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
            raise CaseError(f"{where_file}, row {header_at}: column '{name}' appears twice "
                            f"(columns {where[name] + 1} and {j + 1})")
        quantity = columns[name]
        if unit is not None and unit_factor(unit, quantity) is None:
            allowed = ", ".join(u or "(none)" for u in UNITS[quantity] if u not in ("-", "1"))
            raise CaseError(f"{where_file}, row {header_at}, column '{cell.strip()}': unknown "
                            f"unit '{unit}' for a {quantity}; allowed: {allowed}")
        where[name] = j
        units[name] = unit
    if not where and _numeric(header):
        raise CaseError(f"{where_file}, row {header_at}: no header row (the first row holds "
                        "numbers); add one naming the columns, e.g. "
                        + ",".join(_example(columns, required)))
    for need in required:
        options = (need,) if isinstance(need, str) else tuple(need)
        if not any(o in where for o in options):
            said = " or ".join(f"'{o}'" for o in options) if len(options) < 3 else \
                ", ".join(f"'{o}'" for o in options[:-1]) + f" or '{options[-1]}'"
            found = ", ".join(f"'{c.strip()}'" for c in header if c.strip()) or "none"
            raise CaseError(f"{where_file}: no column {said} (columns found: {found})")
    values = {name: [] for name in where}
    rows = []
    for row, cells in split_cells(numbered[1:], delim, where_file):
        for name, j in where.items():
            at = f"{where_file}, row {row}, column '{header[j].strip()}'"
            if j >= len(cells):
                raise CaseError(f"{at}: missing (the row has {len(cells)} cells, the header "
                                f"{len(header)})")
            cell = cells[j].strip()
            if cell.lower() == "nan" and not _is_required(name, required):
                cell = ""              # written for "no value" (wearcheck writes it too)
            if not cell:
                if _is_required(name, required):
                    raise CaseError(f"{at}: empty")
                values[name].append(math.nan)
                continue
            values[name].append(number(cell, at, comma_hint=delim == ";"))
        rows.append(row)
    if not rows:
        raise CaseError(f"{where_file}: the header row is followed by no data rows")
    out = {}
    for name, vals in values.items():
        unit = units[name]
        factor = 1.0 if unit is None else unit_factor(unit, columns[name])
        out[name] = np.asarray(vals, float) * factor
    return Table(columns=out, rows=np.asarray(rows), units=units, ignored=ignored,
                 path=Path(path), headers={name: header[j].strip() for name, j in where.items()})


def _check_aliases(aliases: Mapping[str, str], header, columns, where_file) -> None:
    """Each alias of a name this table reads names one of the header's cells (by its
    name without the unit, or whole, in any case)."""
    names = {split_header(c)[0] for c in header} | {c.strip().lower() for c in header}
    for column, name in aliases.items():
        if name in columns and column.lower() not in names:
            found = ", ".join(f"'{c.strip()}'" for c in header if c.strip()) or "none"
            raise CaseError(f"no column '{column}' in {where_file} (--map {name}={column}); "
                            f"its columns are {found}")


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
