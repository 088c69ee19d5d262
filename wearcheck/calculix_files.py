"""Reading CalculiX's files: the .dat file's prints, the .frd file's nodal results, a deck's nodes.

One reader for both users of CalculiX output: the ``ccx`` solver (its own
jobs; :mod:`wearcheck.ccx.output` reports a damaged file of its own job as a
SolverError) and ``wearcheck verify`` (a user's CalculiX results,
:mod:`wearcheck.external.calculix`). A file that cannot be read is
one :class:`CaseError` naming the file and the line.

The .dat file holds what ``*NODE PRINT``, ``*EL PRINT`` and ``*CONTACT PRINT``
ask for, in blocks::

     displacements (vx,vy,vz) for set CONTACT and time  0.1000000E+01
            2  0.000000E+00  2.071229E-06  0.000000E+00
     total force (fx,fy,fz) for set TOP and time  0.1000000E+01
            2.480972E-02  5.000000E-02 -2.288424E-14
     stresses (elem, integ.pnt.,sxx,syy,szz,sxy,sxz,syz) for set UPPER and time ...
     contact stress (slave node,press,tang1,tang2) for all contact elements and time ...

with seven significant digits (``1p,e13.6``; CalculiX 2.20 has no switch for
more), after an ``E I G E N V A L U E   N U M B E R   k`` line in a
``*GREEN`` step. The ASCII .frd file (``*NODE FILE``, ``*EL FILE``,
``*CONTACT FILE``) holds the nodes (block ``2C``) and per result time nodal
blocks (``100C``: the time in columns 13-24 and the step in 59-63, then ``-4``
name, ``-5`` components, ``-1`` node records of 12-character fields that may
run together, ``-2`` their continuation, ``-3`` end), six significant digits.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wearcheck.cases import CaseError

_HEADER = re.compile(r"^\s*(?P<quantity>[a-z][a-z ]*?)\s*\((?P<components>[^)]*)\)\s+for\s+"
                     r"(?:set\s+(?P<set>\S+)|all contact elements)\s+and time\s+(?P<time>\S+)")
_MODE = re.compile(r"E\s*I\s*G\s*E\s*N\s*V\s*A\s*L\s*U\s*E\s+N\s*U\s*M\s*B\s*E\s*R\s+(\d+)")
# Fortran drops the E of a three-digit exponent: 1.234567-100
_FORTRAN_EXPONENT = re.compile(r"(\d)([-+]\d{3})$")
#: components of a print that identify its row, not values: node, element, integration point
ID_COMPONENTS = ("slave node", "elem", "integ.pnt.")


def to_float(text: str) -> float:
    """A number as CalculiX prints it (also ``1.234567-100``)."""
    try:
        return float(text)
    except ValueError:
        return float(_FORTRAN_EXPONENT.sub(r"\1E\2", text))


@dataclass
class Block:
    """One printed block of a .dat file.

    quantity : "displacements", "forces", "total force", "stresses", "contact
    stress", ...; components : the value columns ("vx", "vy", "vz"); set : the
    node or element set (None for contact prints); time : the step time; ids :
    (n,) node or element numbers (None for totals); values : (n, m) (one row
    for totals; an element print's integration point is its first column);
    mode : the Green function's number in a ``*GREEN`` step, else None.
    """

    quantity: str
    components: tuple
    set: str | None
    time: float
    ids: np.ndarray | None
    values: np.ndarray
    mode: int | None = None


def dat_blocks(text: str, source: str = ".dat file") -> list[Block]:
    """Every print block of a .dat file's ``text``, in order: node prints (a node
    number, then the components), totals (the components), element prints (element,
    integration point, values) and node-to-surface contact prints (slave node,
    values). ``source`` names the file in the CaseError of a malformed line."""
    blocks, current, rows, mode = [], None, [], None

    def close():
        if current is None:
            return
        quantity, comps, name, t, n_ids = current
        if quantity.startswith("total"):
            table = np.array(rows, float).reshape(len(rows), len(comps))
            blocks.append(Block(quantity, comps, name, t, None, table, mode))
            return
        width = len(comps) if n_ids else len(comps) + 1
        table = np.array(rows, float).reshape(len(rows), width)
        # the first identifier is the id; an integration point stays in the values
        blocks.append(Block(quantity, comps[1:] if n_ids else comps, name, t,
                            table[:, 0].astype(np.int64), table[:, 1:], mode))

    for lineno, line in enumerate(text.splitlines(), start=1):
        m = _MODE.search(line)
        if m:
            close()
            current, rows, mode = None, [], int(m.group(1))
            continue
        h = _HEADER.match(line)
        if h:
            close()
            comps = tuple(c.strip() for c in h.group("components").split(","))
            if comps[0] == "slave element+face":
                raise CaseError(f"{source}, line {lineno}: a contact print per element face "
                                "(face-to-face contact); print a node-to-surface contact, "
                                "or give the .frd's CONTACT block")
            n_ids = sum(1 for c in comps if c in ID_COMPONENTS)
            try:
                t = to_float(h.group("time"))
            except ValueError:
                raise CaseError(f"{source}, line {lineno}: time '{h.group('time')}' is not "
                                "a number") from None
            current, rows = (h.group("quantity"), comps, h.group("set"), t, n_ids), []
            continue
        words = line.split()
        if current is None or not words:
            continue
        quantity, comps, name, _, n_ids = current
        expected = len(comps) if (n_ids or quantity.startswith("total")) else len(comps) + 1
        if len(words) != expected:
            raise CaseError(f"{source}, line {lineno}: expected {expected} numbers in the "
                            f"block '{quantity}'" + (f" of set {name}" if name else "")
                            + f", got: {line.strip()}")
        try:
            rows.append([to_float(w) for w in words])
        except ValueError:
            raise CaseError(f"{source}, line {lineno}: not numbers: {line.strip()}") from None
    close()
    return blocks


def select(blocks, quantity: str, node_set: str) -> list[Block]:
    """The blocks of one quantity and set, in order."""
    return [b for b in blocks if b.quantity == quantity and b.set == node_set]


@dataclass
class FrdBlock:
    """One nodal result block of an .frd file: ``name`` ("DISP", "STRESS",
    "CONTACT"), its time, ``components`` and ``values`` (n, m) at node numbers
    ``ids``, and its step (0 when the file does not say)."""

    name: str
    time: float
    components: tuple
    ids: np.ndarray
    values: np.ndarray
    step: int = 0


def _fields(line: str, start: int = 13, width: int = 12) -> list[float]:
    return [to_float(line[k:k + width]) for k in range(start, len(line.rstrip()), width)]


def read_frd(path) -> tuple[dict, list[FrdBlock]]:
    """The nodes {number: (x, y, z)} and the nodal result blocks of an ASCII .frd file."""
    try:
        lines = Path(path).read_text(errors="replace").splitlines()
    except OSError as exc:
        raise CaseError(f"{path}: cannot be read: {exc.strerror or exc}") from None
    nodes, blocks = {}, []
    i = 0
    try:
        while i < len(lines):
            key = lines[i][:6].strip()
            if key == "2C":
                i += 1
                while not lines[i].startswith(" -3"):
                    nodes[int(lines[i][3:13])] = tuple(_fields(lines[i]))
                    i += 1
            elif key.startswith("100C"):
                time = to_float(lines[i][12:24])
                step = int(lines[i][58:63]) if lines[i][58:63].strip() else 0
                i += 1
                name = lines[i].split()[1]
                comps, ids, rows = [], [], []
                i += 1
                while not lines[i].startswith(" -3"):
                    tag = lines[i][:3]
                    if tag == " -5":
                        comps.append(lines[i].split()[1])
                    elif tag == " -1":
                        ids.append(int(lines[i][3:13]))
                        rows.append(_fields(lines[i]))
                    elif tag == " -2":                         # continuation of a record
                        rows[-1].extend(_fields(lines[i]))
                    i += 1
                width = max((len(r) for r in rows), default=0)
                if any(len(r) != width for r in rows):
                    raise ValueError(f"block {name}: records of unequal length")
                blocks.append(FrdBlock(name, time, tuple(comps[:width]),
                                       np.array(ids, np.int64),
                                       np.array(rows, float).reshape(len(rows), width), step))
            i += 1
    except (IndexError, ValueError) as exc:
        raise CaseError(f"{path}, line {i + 1}: not a readable .frd record ({exc})") from None
    if not nodes:
        raise CaseError(f"{path}: no node block (2C); an ASCII .frd is needed "
                        "(CalculiX writes one by default)")
    return nodes, blocks


def inp_nodes(path) -> dict:
    """{number: (x, y, z)} of the ``*NODE`` blocks of a deck, following ``*INCLUDE``."""
    nodes = {}
    try:
        lines = Path(path).read_text(errors="replace").splitlines()
    except OSError as exc:
        raise CaseError(f"{path}: cannot be read: {exc.strerror or exc}") from None
    reading = False
    for lineno, line in enumerate(lines, start=1):
        s = line.strip()
        if not s or s.startswith("**"):
            continue
        if s.startswith("*"):
            word = s.split(",")[0].strip().upper()
            reading = word == "*NODE"
            if word == "*INCLUDE":
                m = re.search(r"INPUT\s*=\s*([^,]+)", s, re.IGNORECASE)
                if m:
                    nodes.update(inp_nodes(Path(path).parent / m.group(1).strip()))
            continue
        if reading:
            parts = [p for p in s.split(",") if p.strip()]
            try:
                values = [float(p) for p in parts[1:4]]
                nodes[int(parts[0])] = tuple(values + [0.0] * (3 - len(values)))
            except (ValueError, IndexError):
                raise CaseError(f"{path}, line {lineno}: not a node record: {s}") from None
    return nodes
