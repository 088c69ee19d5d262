"""Tables a user brings: CSV files whose header names each column and its unit.

A measurement sheet, a force history, an external solver's result: a CSV with
one header row naming each column and its unit in brackets, e.g. ::

    cycles, D [um], ± D [um], V [mm^3]
    1000,   212.0,  3.0,
    10000,  381.5,  3.0,      0.0128

Each column is one of the quantities the caller declares (:class:`Quantity`,
with the names it answers to); the values are converted to SI. A column may
have an uncertainty column beside it, headed ``± NAME`` (or ``+- NAME``), in
the same unit unless it names its own. An empty cell is a value not measured
in that row. Lines that start with ``#`` and blank lines are skipped.

Every fault (a unit unknown for its quantity, a cell that is not a number, an
uncertainty without its value) is a :class:`CaseError` of one line naming the
file, the row (the file's line number, as a spreadsheet numbers it) and the
column. Used by ``wearcheck fit`` and meant for every reader of user tables.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping

import numpy as np

from wearcheck.cases import CaseError
from wearcheck.cases import tables as shared

_PREFIXES = {"": 1.0, "c": 1e-2, "m": 1e-3, "u": 1e-6, "µ": 1e-6, "μ": 1e-6, "n": 1e-9}
#: the units each dimension accepts here, with their factor to SI: the shared table
#: (:data:`wearcheck.cases.tables.UNITS`) without kilometres and their squares and cubes
#: (no lab measures a scar or a track in them: a km there is a slip of the unit).
#: Spellings as :func:`wearcheck.cases.tables.normal_unit` reads them: ``um``, ``µm``,
#: ``μm``; ``mm^3``, ``mm3``, ``mm³``
UNITS: dict[str, dict[str, float]] = {
    dim: {u: f for u, f in shared.UNITS[dim].items() if not u.startswith("km")}
    for dim in ("length", "area", "volume", "force")}
UNITS["count"] = dict(shared.UNITS["number"])
#: how each dimension's SI unit is written in messages
SI = {"length": "m", "area": "m^2", "volume": "m^3", "force": "N", "count": "1"}


@dataclass(frozen=True)
class Quantity:
    """A quantity a table may hold: its name, dimension and the headers it answers to.

    ``names`` are matched ignoring case, spaces, underscores and hyphens;
    ``refused`` (when set) is the one-line reason why the caller cannot use the
    column yet, said when the file has it.
    """

    name: str
    dimension: str
    names: tuple[str, ...]
    meaning: str = ""
    refused: str | None = None


@dataclass
class Column:
    """One column of a table read: values in SI (NaN where not measured)."""

    quantity: Quantity
    header: str
    unit: str
    values: np.ndarray
    #: the ± column in SI, or None
    uncertainty: np.ndarray | None = None
    uncertainty_header: str | None = None


@dataclass
class Table:
    """A table read: its columns by quantity name, and the file's line of each row."""

    source: str
    columns: dict[str, Column]
    rows: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    def __contains__(self, name: str) -> bool:
        return name in self.columns

    def __getitem__(self, name: str) -> Column:
        return self.columns[name]

    def where(self, i: int, column: str | None = None) -> str:
        """"file 'x.csv', row 5, column 'D [um]'": where the ``i``-th data row is."""
        text = f"{self.source}, row {int(self.rows[i])}"
        if column is not None:
            text += f", column '{self.columns[column].header}'"
        return text


def _key(text: str) -> str:
    return re.sub(r"[\s_\-]+", "", text).lower()


def _lookup(name: str, quantities: Iterable[Quantity]) -> Quantity | None:
    k = _key(name)
    for q in quantities:
        if k in {_key(n) for n in (q.name, *q.names)}:
            return q
    return None


def _parse_header(cells: list[str], quantities: list[Quantity], where: str):
    """[(column index, quantity, is_uncertainty, unit text, factor, header text)]."""
    out, seen = [], {}
    for j, text in enumerate(cells):
        h = shared.parse_header(text)
        at = f"{where}, column {j + 1} '{h.text}'"
        if not h.name:
            raise CaseError(f"{at}: a header must be a quantity and its unit, e.g. 'D [um]'; "
                            "known: " + _known(quantities))
        q = _lookup(h.name, quantities)
        if q is None:
            raise CaseError(f"{at}: unknown column '{h.name}'; known: " + _known(quantities))
        if q.refused:
            raise CaseError(f"{at}: {q.refused}")
        pm, unit = h.uncertainty, h.unit
        if unit is None and not pm and q.dimension != "count":
            raise CaseError(f"{at}: no unit; write it in brackets, e.g. '{h.name} "
                            f"[{_example_unit(q.dimension)}]' (allowed: "
                            f"{_allowed(q.dimension)})")
        factor = None
        if unit is not None:
            factor = shared.unit_factor(unit, q.dimension, UNITS)
            if factor is None:
                raise CaseError(f"{at}: unknown unit '{unit}' for {q.meaning or q.name} "
                                f"({q.dimension}); allowed: {_allowed(q.dimension)}")
        slot = (q.name, pm)
        if slot in seen:
            raise CaseError(f"{at}: {'an uncertainty of ' if pm else ''}'{q.name}' is also "
                            f"column {seen[slot] + 1}; give each column once")
        seen[slot] = j
        out.append((j, q, pm, unit, factor, h.text))
    for j, q, pm, unit, factor, header in out:
        if pm and (q.name, False) not in seen:
            raise CaseError(f"{where}, column {j + 1} '{header}': an uncertainty without its "
                            f"value column '{q.name}'")
    return out


def _known(quantities) -> str:
    return ", ".join(q.name for q in quantities)


def _allowed(dimension: str) -> str:
    """The units of a dimension as messages list them (``m^3``; ``m3`` and ``m³`` also work)."""
    power = {"length": 1, "area": 2, "volume": 3}.get(dimension)
    if power is not None:
        return ", ".join(f"{p}m" + (f"^{power}" if power > 1 else "")
                         for p in _PREFIXES if p != "k")
    if dimension == "count":
        return "none, or 1"
    return ", ".join(UNITS[dimension])


def _example_unit(dimension: str) -> str:
    return {"length": "um", "area": "um^2", "volume": "mm^3", "force": "N"}.get(dimension, "")


def read_table(path: str | Path, quantities: Iterable[Quantity]) -> Table:
    """Read a CSV whose header names each column as a quantity and its unit.

    Parameters
    ----------
    path : the CSV file (UTF-8, commas between columns).
    quantities : the quantities the table may hold.

    Returns
    -------
    Table
        the columns in SI (NaN for empty cells), with their ± columns.

    Raises
    ------
    CaseError
        one line naming the file, the row and the column of the fault.
    """
    where = f"file '{path}'"
    numbered = shared.data_lines(shared.read_lines(path, where))
    head = numbered[:1]
    if head and any(sep in head[0][1] for sep in (";", "\t")) and "," not in head[0][1]:
        sep = "semicolons" if ";" in head[0][1] else "tabs"
        raise CaseError(f"{where}, row {head[0][0]}: columns are separated by commas, not {sep}")
    return _table(where, shared.split_cells(numbered, ",", where), list(quantities))


def from_columns(data: Mapping[str, Iterable], quantities: Iterable[Quantity],
                 source: str = "the data") -> Table:
    """A table given in Python: ``{"cycles": [...], "D [um]": [...]}`` (headers as in a
    CSV file; pandas DataFrames work as mappings of their columns)."""
    headers = [str(h) for h in data.keys()]
    try:
        cols = [np.asarray(list(data[h]) if not isinstance(data[h], np.ndarray) else data[h],
                           dtype=object).ravel() for h in data.keys()]
    except TypeError:
        raise CaseError(f"{source}: each column must be a sequence of numbers") from None
    lengths = {len(c) for c in cols}
    if len(lengths) > 1:
        raise CaseError(f"{source}: the columns differ in length ("
                        + ", ".join(f"'{h}': {len(c)}" for h, c in zip(headers, cols)) + ")")
    n = lengths.pop() if lengths else 0
    rows = [(1, headers)]
    for i in range(n):
        rows.append((i + 2, ["" if v is None or (isinstance(v, float) and math.isnan(v))
                             else str(v) for v in (c[i] for c in cols)]))
    return _table(source, rows, list(quantities))


def _table(where: str, numbered: list, quantities: list[Quantity]) -> Table:
    if not numbered:
        raise CaseError(f"{where} is empty: it needs a header row and at least one row of "
                        "numbers")
    head_line, head = numbered[0]
    spec = _parse_header(head, quantities, f"{where}, row {head_line}")
    width = len(head)
    values = {j: [] for j, *_ in spec}
    rows = []
    for line, row in numbered[1:]:
        cells = [c.strip() for c in row]
        while len(cells) > width and not cells[-1]:
            cells.pop()   # a trailing comma
        if len(cells) > width:
            raise CaseError(f"{where}, row {line}: {len(cells)} cells for {width} columns")
        cells += [""] * (width - len(cells))
        for j, q, pm, unit, factor, header in spec:
            text = cells[j]
            at = f"{where}, row {line}, column '{header}'"
            if not text:
                values[j].append(math.nan)
                continue
            value = shared.number(text, at)
            if value < 0:
                raise CaseError(f"{at}: {text} is negative; {q.meaning or q.name} "
                                f"{'uncertainties are' if pm else 'is'} at least 0")
            values[j].append(value)
        rows.append(line)
    if not rows:
        raise CaseError(f"{where} has a header but no rows of numbers")
    columns: dict[str, Column] = {}
    for j, q, pm, unit, factor, header in spec:
        if not pm:
            columns[q.name] = Column(q, header, unit or "",
                                     np.asarray(values[j], float) * (factor or 1.0))
    for j, q, pm, unit, factor, header in spec:
        if pm:
            col = columns[q.name]
            scale = factor if factor is not None else (
                shared.unit_factor(col.unit, q.dimension, UNITS) or 1.0)
            u = np.asarray(values[j], float) * scale
            col.uncertainty, col.uncertainty_header = u, header
    table = Table(where, columns, np.asarray(rows, int))
    for name, col in columns.items():
        if col.uncertainty is None:
            continue
        for i in range(len(rows)):
            has_value, has_u = not math.isnan(col.values[i]), not math.isnan(col.uncertainty[i])
            if has_value != has_u:
                missing = col.uncertainty_header if has_value else col.header
                raise CaseError(f"{table.where(i)}: '{col.header}' and '{col.uncertainty_header}' "
                                f"go together; '{missing}' is empty")
    return table
