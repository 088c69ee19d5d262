"""A ParaView series (``.pvd`` of ``.vtu`` files) or a single ``.vtu`` with the contact
surface's point data, read through meshio.

Each ``.vtu`` is one stage. Its points are the contact surface (a line in the
r–z section of an axisymmetric model, or the surface itself in 3D); the
radius is the distance from the symmetry axis (``--map axis=y``, the default as
in ParaView and wearcheck's export; ``x`` or ``z``). Point data: ``f`` (worn
profile) or ``wear_depth`` (wear depth), and ``pressure``, or the arrays named
by ``--map f=NAME``, ``--map wear=NAME``, ``--map p=NAME`` (a component of a
vector array as ``NAME.2``). Where several points share a radius (a surface of
revolution) their values are averaged; a 3D surface whose points scatter in
radius is averaged over rings (√n of them, n the points).

The stage's distance: the ``.pvd``'s ``timestep`` (``--map s=time``, the
default; ``--map s_hat=time``, ``--map cycles=time``, or a field-data name
instead of ``time``; a unit as ``--map 's [mm]=time'``); a single ``.vtu``
without a time reads the field data ``s`` or ``TimeValue``. Coordinates in
other units: ``--map 'r [mm]=points'``.

The history: ``history.csv`` beside the file when there is one
(:mod:`.tables_dir`), else the field data ``force``, ``contact_radius``,
``wear_center``, ``wear_volume``, ``depth`` of each file (``--map force=NAME``).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from wearcheck.cases import CaseError
from wearcheck.cases.tables import parse_quantity, split_header
from wearcheck.extras import need

from . import (AXES, DISTANCES, HISTORY_QUANTITIES, External, Stage, check_unused,
               geometry_line, geometry_mapping, map_item, unit_words)
from .tables_dir import read as read_dir

DEFAULT_ARRAYS = {"f": "f", "wear": "wear_depth", "p": "pressure"}
KINDS = {"f": "length", "wear": "length", "p": "pressure"}


def series(path: Path) -> list[tuple[float | None, Path]]:
    """(time, file) of each data set of a .pvd (time None when absent), or of one .vtu."""
    if path.suffix.lower() == ".vtu":
        return [(None, path)]
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError) as exc:
        raise CaseError(f"{path}: not a readable .pvd file ({exc})") from None
    out = []
    for i, ds in enumerate(root.iter("DataSet"), start=1):
        file = ds.get("file")
        if file is None:
            raise CaseError(f"{path}: DataSet {i} has no 'file' attribute")
        t = ds.get("timestep")
        try:
            time = float(t) if t is not None else None
        except ValueError:
            raise CaseError(f"{path}: DataSet {i} ('{file}') has timestep '{t}', not a "
                            "number") from None
        out.append((time, (path.parent / file)))
    if not out:
        raise CaseError(f"{path}: no DataSet in the collection")
    return out


def _array(mesh, name: str, where: str):
    """Point data ``name`` (or ``name.k``, a component) of a mesh, as (n,) floats, or None."""
    base, _, comp = name.partition(".")
    data = mesh.point_data.get(name)
    if data is None and comp.isdigit():
        data = mesh.point_data.get(base)
        if data is not None:
            data = np.asarray(data)
            if data.ndim != 2 or int(comp) >= data.shape[1]:
                raise CaseError(f"{where}: point data '{base}' has no component {comp}")
            return np.asarray(data[:, int(comp)], float)
    if data is None:
        return None
    data = np.asarray(data, float)
    if data.ndim == 2 and data.shape[1] == 1:
        data = data[:, 0]
    if data.ndim != 1:
        raise CaseError(f"{where}: point data '{name}' has {data.shape[1]} components; "
                        f"name one as '{name}.0', '{name}.1', ...")
    return data


def _check_holes(r, finite, file: Path, notes: list) -> None:
    """Points without a finite value (NaN, inf) between points with values in radius
    are a hole in the data, which judging the points left would hide: refused. Those
    beyond the last point with values (a field on the contact's selection only) are
    left out, with a note; so are those inside the first (a field off the axis)."""
    missing = ~finite
    if not missing.any():
        return
    if not finite.any():
        raise CaseError(f"{file}: no point has a finite value of the arrays read")
    lo, hi = r[finite].min(), r[finite].max()
    hole = missing & (r > lo) & (r < hi)
    if hole.any():
        raise CaseError(f"{file}: {int(hole.sum())} point(s) without a finite value at radii "
                        f"{r[hole].min():.4g} to {r[hole].max():.4g} m, between points with "
                        f"values ({lo:.4g} to {hi:.4g} m): a hole in the results, which "
                        "wearcheck does not judge around; export the field on every point")
    notes.append(f"{file.name}: {int(missing.sum())} point(s) without a finite value, outside "
                 f"the radii {lo:.4g} to {hi:.4g} m of the others, left out")


def _field(mesh, name: str):
    v = mesh.field_data.get(name)
    if v is None:
        return None
    v = np.ravel(np.asarray(v, float))
    return float(v[0]) if v.size else None


def radial_average(r, values: dict, where: str, notes: list) -> tuple[np.ndarray, dict]:
    """Values sorted by radius; points that share a radius averaged, or (3D scatter)
    averaged over √n rings of equal width."""
    r = np.asarray(r, float)
    scale = float(np.max(r)) if r.size else 1.0
    key = np.round(r / (scale or 1.0) * 1e9)
    uniq, inverse = np.unique(key, return_inverse=True)
    if len(uniq) < 0.9 * len(r):
        groups = inverse
        notes.append(f"{where}: values averaged over the points that share a radius "
                     f"({len(r)} points, {len(uniq)} radii)")
    else:
        return _sorted(r, values)
    n = int(groups.max()) + 1
    count = np.bincount(groups, minlength=n)
    rr = np.bincount(groups, r, minlength=n) / count
    out = {k: (np.bincount(groups, v, minlength=n) / count if v is not None else None)
           for k, v in values.items()}
    return _sorted(rr, out)


def _sorted(r, values):
    order = np.argsort(r, kind="stable")
    return r[order], {k: (v[order] if v is not None else None) for k, v in values.items()}


def ring_bins(r, values: dict, where: str, notes: list) -> tuple[np.ndarray, dict]:
    """Averages over √n rings of equal width (a 3D surface scattered in radius)."""
    r = np.asarray(r, float)
    bins = max(10, int(math.sqrt(len(r))))
    edges = np.linspace(0.0, float(np.max(r)) * (1 + 1e-12), bins + 1)
    idx = np.clip(np.searchsorted(edges, r, side="right") - 1, 0, bins - 1)
    count = np.bincount(idx, minlength=bins)
    keep = count > 0
    rr = (np.bincount(idx, r, minlength=bins) / np.maximum(count, 1))[keep]
    out = {k: ((np.bincount(idx, v, minlength=bins) / np.maximum(count, 1))[keep]
               if v is not None else None) for k, v in values.items()}
    notes.append(f"{where}: a 3D surface ({len(r)} points) averaged over {int(keep.sum())} "
                 "rings of equal width")
    return rr, out


def read(path: Path, mapping: dict) -> External:
    """The series at ``path`` (see the module docstring)."""
    meshio = need("meshio", "reading .pvd/.vtu results")
    path = Path(path)
    known = {"f", "wear", "p", "axis", "r"} | set(DISTANCES) | set(HISTORY_QUANTITIES)
    check_unused(mapping, known, "VTK")
    names, factors = dict(DEFAULT_ARRAYS), {"f": 1.0, "wear": 1.0, "p": 1.0, "r": 1.0}
    time_kind, time_source, time_factor = "s", "time", 1.0
    fields = {q: q for q in HISTORY_QUANTITIES}
    field_factor = {q: 1.0 for q in HISTORY_QUANTITIES}
    axis = "y"
    given = {}     # wearcheck's name -> the --map item that named its array or field
    for key, value in mapping.items():
        name, _ = split_header(key)
        where = f"--map '{key}={value}'"
        given[name] = map_item(key, value)
        if name in ("axis", "r"):
            what, got = geometry_mapping(name, key, value, where)
            if what == "axis":
                axis = got
            else:
                factors["r"] = got
        elif name in KINDS:
            names[name] = value
            factors[name] = parse_quantity(key, KINDS[name], where)[1]
        elif name in DISTANCES:
            time_kind, time_source = name, value
            time_factor = parse_quantity(key, DISTANCES[name], where)[1]
        else:
            fields[name] = value
            field_factor[name] = parse_quantity(key, HISTORY_QUANTITIES[name], where)[1]
    notes = []
    stages, hist_rows = [], []
    beside = path.parent / "history.csv"
    arrays = set()      # the point data of every file, for what a --map displaced
    for time, file in series(path):
        where = str(file)
        if not file.is_file():
            raise CaseError(f"{path}: data set '{file.name}' does not exist")
        try:
            mesh = meshio.read(file)
        except Exception as exc:  # meshio raises many kinds for a bad file
            raise CaseError(f"{file}: cannot be read as VTK ({type(exc).__name__}: "
                            f"{str(exc).splitlines()[0] if str(exc) else ''})") from None
        if time_source != "time":
            time = _field(mesh, time_source)
            if time is None:
                raise CaseError(f"{file}: no field data '{time_source}' for the distance "
                                f"({given[time_kind]}); its field data: "
                                f"{', '.join(mesh.field_data) or 'none'}")
        elif time is None:
            time = _field(mesh, "s") if time_kind == "s" else None
            time = _field(mesh, "TimeValue") if time is None else time
        if time is None:
            raise CaseError(f"{file}: no time: give a .pvd with timesteps, field data 's', "
                            "or --map s=NAME of a field-data value")
        time *= time_factor
        pts = np.asarray(mesh.points, float) * factors["r"]
        if pts.shape[1] == 2:
            pts = np.column_stack([pts, np.zeros(len(pts))])
        off = [i for i in range(3) if i != AXES[axis]]
        r = np.hypot(pts[:, off[0]], pts[:, off[1]])
        arrays |= set(mesh.point_data)
        vals = {}
        for q in ("f", "wear", "p"):
            a = _array(mesh, names[q], where)
            if a is None and q in given:
                # an array the user named is never silently left out (a typo would
                # leave the stage unjudged in that quantity)
                raise CaseError(f"{file}: no point data '{names[q]}' ({given[q]}); its "
                                f"point data: {', '.join(mesh.point_data) or 'none'}")
            vals[q] = None if a is None else a * factors[q]
        if vals["f"] is not None:
            vals["wear"] = None
        if all(v is None for v in vals.values()):
            raise CaseError(f"{file}: no point data '{names['f']}', '{names['wear']}' or "
                            f"'{names['p']}' (found: {', '.join(mesh.point_data) or 'none'}); "
                            "name them with --map f=NAME, wear=NAME, p=NAME")
        finite = np.ones(len(r), bool)
        for v in vals.values():
            if v is not None:
                finite &= np.isfinite(v)
        _check_holes(r, finite, file, notes)
        r, vals = r[finite], {k: (v[finite] if v is not None else None) for k, v in vals.items()}
        spread = np.ptp(pts[finite][:, off], axis=0) if finite.any() else np.zeros(2)
        if np.all(spread > 0) and len(np.unique(np.round(r / max(r.max(), 1e-300) * 1e9))) \
                >= 0.9 * len(r):
            r, vals = ring_bins(r, vals, file.name, notes)
        else:
            r, vals = radial_average(r, vals, file.name, notes)
        if len(r) < 2:
            raise CaseError(f"{file}: fewer than two surface points with data")
        stages.append(Stage(time=float(time), r=r, f=vals["f"], p=vals["p"],
                            wear=vals["wear"], origin=file.name))
        row = {}
        for q in HISTORY_QUANTITIES:
            v = _field(mesh, fields[q])
            if v is None and q in given and not beside.is_file():
                raise CaseError(f"{file}: no field data '{fields[q]}' ({given[q]}); its "
                                f"field data: {', '.join(mesh.field_data) or 'none'}")
            row[q] = math.nan if v is None else v * field_factor[q]
        hist_rows.append((float(time), row, f"{file.name} field data"))
    stages.sort(key=lambda st: st.time)
    times = [st.time for st in stages]
    if len(set(times)) != len(times):
        raise CaseError(f"{path}: two data sets at the same time {times}")
    if beside.is_file():
        # a history quantity named with --map is a column of that history.csv
        hist = read_dir(path.parent, {k: v for k, v in mapping.items()
                                      if split_header(k)[0] in HISTORY_QUANTITIES})
        notes.append(f"history from {beside.name} beside {path.name}")
        return External(kind=hist.kind, history=hist.history, history_origin=hist.history_origin,
                        stages=stages, source=str(path), format="vtk", stage_kind=time_kind,
                        notes=notes + hist.notes,
                        mapped=_mapped_lines(path, mapping, arrays, hist.mapped))
    hist_rows.sort(key=lambda t: t[0])
    history = {"time": np.array([t for t, _, _ in hist_rows])}
    origin = [o for _, _, o in hist_rows]
    for q in HISTORY_QUANTITIES:
        v = np.array([row[q] for _, row, _ in hist_rows])
        if np.any(np.isfinite(v)):
            history[q] = v
    return External(kind=time_kind, history=history, history_origin=origin, stages=stages,
                    source=str(path), format="vtk", stage_kind=time_kind, notes=notes,
                    mapped=_mapped_lines(path, mapping, arrays, None))


def _mapped_lines(path: Path, mapping: dict, arrays: set, csv_lines) -> list[str]:
    """One line per --map item: the point data, field data, timesteps or coordinates
    it read, in which unit, and the default array it displaced. ``csv_lines``: the
    lines of a history.csv beside the series (which the history quantities name)."""
    out = []
    for key, value in mapping.items():
        name, item, unit = split_header(key)[0], map_item(key, value), unit_words(key)
        if name in ("axis", "r"):
            out.append(geometry_line(path.name, name, key, value))
        elif name in KINDS:
            default = DEFAULT_ARRAYS[name]
            out.append(f"{path.name}: {name} read from point data '{value}'{unit} ({item})"
                       + (f"; point data '{default}' not read"
                          if default != value and default in arrays else ""))
        elif name in DISTANCES:
            what = ("the .pvd timesteps" if value == "time"
                    else f"field data '{value}' of each file")
            out.append(f"{path.name}: {name} read from {what}{unit} ({item})")
        elif csv_lines is None:
            out.append(f"{path.name}: {name} read from field data '{value}' of each "
                       f"file{unit} ({item})")
        else:
            out += [line for line in csv_lines if f"({item})" in line]
    return out
