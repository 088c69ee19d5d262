"""Reading CalculiX's outputs: the .dat file's node prints and the .frd file's nodal results.

The .dat file holds what ``*NODE PRINT`` asks for, in blocks::

     displacements (vx,vy,vz) for set CONTACT and time  0.1000000E+01
            2  0.000000E+00  2.071229E-06  0.000000E+00
     total force (fx,fy,fz) for set TOP and time  0.1000000E+01
            2.480972E-02  5.000000E-02 -2.288424E-14

with seven significant digits (``1p,e13.6``; CalculiX 2.20 has no switch for
more), after an ``E I G E N V A L U E   N U M B E R   k`` line in a
``*GREEN`` step. The ASCII .frd file (``*NODE FILE``, ``*EL FILE``) holds the
nodes (block ``2C``) and per step nodal result blocks (``100C``: ``-4`` name,
``-5`` components, ``-1`` node records of 12-character fields that may run
together, ``-3`` end), six significant digits.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wearcheck.cases import SolverError

_HEADER = re.compile(r"^\s*(?P<quantity>[a-z][a-z ]*?)\s*\((?P<components>[^)]*)\)\s+for set\s+"
                     r"(?P<set>\S+)\s+and time\s+(?P<time>\S+)")
_MODE = re.compile(r"E\s*I\s*G\s*E\s*N\s*V\s*A\s*L\s*U\s*E\s+N\s*U\s*M\s*B\s*E\s*R\s+(\d+)")
# Fortran drops the E of a three-digit exponent: 1.234567-100
_FORTRAN_EXPONENT = re.compile(r"(\d)([-+]\d{3})$")


def to_float(text: str) -> float:
    """A number as CalculiX prints it (also ``1.234567-100``)."""
    try:
        return float(text)
    except ValueError:
        return float(_FORTRAN_EXPONENT.sub(r"\1E\2", text))


@dataclass
class Block:
    """One printed block of the .dat file.

    quantity : "displacements", "forces", "total force", ...; components :
    ("vx", "vy", "vz"); set : the node set's name; time : step time; mode :
    the Green function's number in a *GREEN step, else None; ids : (n,)
    node numbers (None for totals); values : (n, m) (one row for totals).
    """

    quantity: str
    components: tuple
    set: str
    time: float
    mode: int | None
    ids: np.ndarray | None
    values: np.ndarray


def dat_blocks(text: str, source: str = ".dat file") -> list[Block]:
    """Every node-print block of a .dat file's ``text``, in order."""
    blocks = []
    mode = None
    current = None
    rows: list = []

    def close():
        if current is None:
            return
        q, comps, name, t = current
        total = q.startswith("total")
        table = np.array(rows, float).reshape(len(rows), len(comps) + (0 if total else 1))
        if total:
            ids, values = None, table
        else:
            ids, values = table[:, 0].astype(np.int64), table[:, 1:]
        blocks.append(Block(q, comps, name, t, mode, ids, values))

    for lineno, line in enumerate(text.splitlines(), start=1):
        m = _MODE.search(line)
        if m:
            close()
            current, rows = None, []
            mode = int(m.group(1))
            continue
        h = _HEADER.match(line)
        if h:
            close()
            comps = tuple(c.strip() for c in h.group("components").split(","))
            current = (h.group("quantity"), comps, h.group("set"), to_float(h.group("time")))
            rows = []
            continue
        words = line.split()
        if current is None or not words:
            continue
        expected = len(current[1]) + (0 if current[0].startswith("total") else 1)
        if len(words) != expected:
            raise SolverError(f"{source}, line {lineno}: expected {expected} numbers in the "
                              f"block '{current[0]}' of set {current[2]}, got: {line.strip()}")
        try:
            rows.append([to_float(w) for w in words])
        except ValueError:
            raise SolverError(f"{source}, line {lineno}: not numbers: {line.strip()}") from None
    close()
    return blocks


def select(blocks, quantity: str, node_set: str) -> list[Block]:
    """The blocks of one quantity and node set, in order."""
    return [b for b in blocks if b.quantity == quantity and b.set == node_set]


@dataclass
class FrdResult:
    """One nodal result block of an .frd file: ``name`` ("DISP", "STRESS"), its
    step and time, ``components`` and ``values`` (n, m) at node numbers ``ids``."""

    name: str
    step: int
    time: float
    components: tuple
    ids: np.ndarray
    values: np.ndarray


def _fields(line: str, start: int = 13, width: int = 12) -> list[float]:
    return [to_float(line[k:k + width]) for k in range(start, len(line.rstrip()), width)]


def read_frd(path) -> tuple[dict, list[FrdResult]]:
    """The nodes {number: (x, y, z)} and nodal result blocks of an ASCII .frd file."""
    path = Path(path)
    try:
        lines = path.read_text(errors="replace").splitlines()
    except OSError as exc:
        raise SolverError(f"cannot read CalculiX results '{path}': {exc}") from None
    nodes: dict = {}
    results: list[FrdResult] = []
    i = 0
    try:
        while i < len(lines):
            line = lines[i]
            key = line[:6].strip()
            if key == "2C":                                   # nodes
                i += 1
                while not lines[i].startswith(" -3"):
                    nodes[int(lines[i][3:13])] = tuple(_fields(lines[i]))
                    i += 1
            elif key.startswith("100C"):                      # a nodal result block
                parts = line.split()
                time = to_float(parts[2])
                step = int(parts[5]) if len(parts) > 5 else 0
                i += 1
                name = lines[i].split()[1]
                comps = []
                ids, rows = [], []
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
                results.append(FrdResult(name=name, step=step, time=time,
                                         components=tuple(comps[:width]),
                                         ids=np.array(ids, np.int64),
                                         values=np.array(rows, float).reshape(len(rows), width)))
            i += 1
    except (IndexError, ValueError) as exc:
        raise SolverError(f"CalculiX results '{path}' are damaged near line {i + 1}: "
                          f"{exc}") from None
    return nodes, results


def stage_fields(results, n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Displacement (Np, 2) [m] and stress (Np, 4) σ_rr, σ_zz, σ_θθ, σ_rz [Pa] of one step.

    ``results``: the step's :class:`FrdResult` blocks; CalculiX's x, y, z are
    r, z, θ of the axisymmetric model, the deck's units mm and MPa; nodes
    1 .. ``n_points`` are the sphere's.
    """
    disp = np.zeros((n_points, 2))
    stress = np.zeros((n_points, 4))
    found = set()
    for b in results:
        keep = b.ids <= n_points          # not the gap elements' ground nodes
        if b.name == "DISP":
            disp[b.ids[keep] - 1] = b.values[keep, :2] * 1e-3
            found.add(b.name)
        elif b.name == "STRESS":
            cols = [b.components.index(c) for c in ("SXX", "SYY", "SZZ", "SXY")]
            stress[b.ids[keep] - 1] = b.values[keep][:, cols] * 1e6
            found.add(b.name)
    if found != {"DISP", "STRESS"}:
        raise SolverError("CalculiX's .frd file lacks " + " and ".join(
            sorted({"DISP", "STRESS"} - found)))
    return disp, stress
