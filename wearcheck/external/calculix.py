"""CalculiX results: the ``.frd`` file's nodal blocks and the ``.dat`` file's prints.

Each result time is a stage, its time the sliding distance (``--map s=time``,
the default; ``s_hat=time`` or ``cycles=time``; a unit as ``'s [mm]=time'``).

Stage fields, from the ``.frd`` (ASCII, ``*NODE FILE``/``*CONTACT FILE``): the
radius from the node coordinates (block ``2C``; the symmetry axis is y as in
CalculiX's axisymmetric elements, ``--map axis=z`` for a 3D model whose axis is
z), the pressure from ``--map p=BLOCK.COMPONENT`` (default ``CONTACT.CPRESS``,
written for the slave nodes), optionally the wear depth or the worn profile
from ``--map wear=BLOCK.COMPONENT`` or ``--map f=BLOCK.COMPONENT`` (a user
field). Or, without an ``.frd``, from the ``.dat``'s ``*CONTACT PRINT`` of
CSTR for a node-to-surface contact (``contact stress (slave node,press,...)``),
the coordinates then from the ``.inp`` deck of the same name (``*NODE``,
following ``*INCLUDE``).

History, from the ``.dat``: the force is the axial component of the ``total
force`` print of the node set ``--map force=SET`` (``*NODE PRINT, NSET=SET,
TOTALS=ONLY`` of RF; default: the only set with totals), its absolute value,
times a factor ``--map 'force=SET*180'`` (CalculiX prints an axisymmetric
model's reaction forces per 2° segment: ×180 for the ring). ``--map
depth=SET``: the depth is the mean axial displacement of that set's nodes
(``*NODE PRINT, NSET=SET`` of U), its absolute value. Model units other than
SI: ``--map 'r [mm]=points'``, ``'p [MPa]=CONTACT.CPRESS'``, ``'force [N]=SET'``,
``'depth [mm]=SET'``.

The files are read by :mod:`wearcheck.calculix_files` (CalculiX 2.20's
formats), the reader the ``ccx`` solver reads its own jobs with.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.calculix_files import dat_blocks, inp_nodes, read_frd
from wearcheck.cases import CaseError
from wearcheck.cases.tables import parse_quantity, split_header

from . import (AXES, DISTANCES, External, Stage, check_unused, geometry_line,
               geometry_mapping, map_item, unit_words)

def _target(value: str, where: str) -> tuple[str, str | None, float]:
    """'BLOCK.COMPONENT*FACTOR' or 'SET*FACTOR' -> (name, component or None, factor)."""
    body, _, factor = value.partition("*")
    try:
        k = float(factor) if factor else 1.0
    except ValueError:
        raise CaseError(f"{where}: factor '{factor}' is not a number") from None
    name, _, comp = body.partition(".")
    return name.strip(), (comp.strip() or None), k


def read(path: Path, mapping: dict) -> External:
    """The CalculiX results at ``path`` (.frd or .dat; the other of the same name too)."""
    path = Path(path)
    known = {"p", "wear", "f", "force", "depth", "axis", "r"} | set(DISTANCES)
    check_unused(mapping, known, "CalculiX")
    frd = path if path.suffix.lower() == ".frd" else path.with_suffix(".frd")
    dat = path if path.suffix.lower() == ".dat" else path.with_suffix(".dat")
    frd = frd if frd.is_file() else None
    dat = dat if dat.is_file() else None
    spec = {"p": ("CONTACT.CPRESS", "pressure", 1.0)}
    kind, time_factor, axis, coord = "s", 1.0, "y", 1.0
    given = {}     # wearcheck's name -> the --map item that named its block or set
    for key, value in mapping.items():
        name, _ = split_header(key)
        where = f"--map '{key}={value}'"
        given[name] = map_item(key, value)
        if name in ("axis", "r"):
            what, got = geometry_mapping(name, key, value, where)
            axis, coord = (got, coord) if what == "axis" else (axis, got)
        elif name in DISTANCES:
            if value != "time":
                raise CaseError(f"{where}: the distance is CalculiX's result time: "
                                f"--map {name}=time")
            kind, time_factor = name, parse_quantity(key, DISTANCES[name], where)[1]
        else:
            quantity = {"p": "pressure", "force": "force"}.get(name, "length")
            spec[name] = (value, quantity, parse_quantity(key, quantity, where)[1])
    notes = []
    source = frd or dat
    # a quantity the user named is read from its file, never silently left out
    for q, (needs, what) in {"wear": (frd, ".frd"), "f": (frd, ".frd"),
                             "force": (dat, ".dat"), "depth": (dat, ".dat")}.items():
        if q in given and needs is None:
            raise CaseError(f"{given[q]}: no {what} file beside {source} (the {q} is read "
                            f"from {path.with_suffix(what).name})")
    stages = []
    if frd is not None:
        nodes, blocks = read_frd(frd)
        _check_blocks(frd, blocks, spec, given)
        stages = _frd_stages(frd, nodes, blocks, spec, axis, coord, time_factor, notes)
    blocks_dat = []
    if dat is not None:
        try:
            text = dat.read_text(errors="replace")
        except OSError as exc:
            raise CaseError(f"{dat}: cannot be read: {exc.strerror or exc}") from None
        blocks_dat = dat_blocks(text, str(dat))
        if not stages:
            stages = _dat_stages(dat, blocks_dat, spec, axis, coord, time_factor, notes)
    history = _dat_history(dat, blocks_dat, spec, axis, time_factor, notes, stages)
    origin = [f"{dat.name if dat else frd.name} time {t:g}" for t in history["time"]]
    # the .frd prints a time with six digits, the .dat with seven: the same time
    return External(kind=kind, history=history, history_origin=origin, stages=stages,
                    source=str(source), format="calculix", stage_kind=kind, notes=notes,
                    time_precision=1e-5, mapped=_mapped_lines(mapping, frd, dat))


def _mapped_lines(mapping: dict, frd, dat) -> list[str]:
    """One line per --map item: the block and component, node set or result times it
    read, in which unit."""
    out = []
    for key, value in mapping.items():
        name, item, unit = split_header(key)[0], map_item(key, value), unit_words(key)
        target, comp, k = _target(value, item)
        times = f" × {k:g}" if k != 1.0 else ""
        if name in ("axis", "r"):
            out.append(geometry_line((frd or dat).name, name, key, value))
        elif name in DISTANCES:
            out.append(f"{(frd or dat).name}: {name} read from the result times{unit} ({item})")
        elif name == "p" and frd is None:
            out.append(f"{dat.name}: p read from the contact prints (CSTR){unit} ({item})")
        elif name in ("p", "wear", "f"):
            out.append(f"{frd.name}: {name} read from block {target} component {comp}{times}"
                       f"{unit} ({item})")
        elif name == "force":
            out.append(f"{dat.name}: force read from the total force of set {target}{times}"
                       f"{unit} ({item})")
        elif name == "depth":
            out.append(f"{dat.name}: depth read from the displacements of set {target}"
                       f"{times}{unit} ({item})")
    return out


def _radius(coords: np.ndarray, axis: str, factor: float) -> np.ndarray:
    off = [i for i in range(3) if i != AXES[axis]]
    return np.hypot(coords[:, off[0]], coords[:, off[1]]) * factor


def _check_blocks(frd, blocks, spec, given) -> None:
    """Each block and component named with --map (p, wear, f) is in the .frd: one line
    naming it and the blocks (or the block's components) the file has."""
    have = {}
    for b in blocks:
        have.setdefault(b.name, b.components)
    for q in ("p", "wear", "f"):
        if q not in given:
            continue
        name, comp, _ = _target(spec[q][0], given[q])
        if name not in have:
            raise CaseError(f"{frd}: no block '{name}' ({given[q]}); its blocks: "
                            f"{', '.join(sorted(have)) or 'none'}")
        if comp is None or comp not in have[name]:
            raise CaseError(f"{frd}: block {name} has no component "
                            + (f"'{comp}'" if comp else "named") + f" ({given[q]}); its "
                            f"components: {', '.join(have[name])}; --map {q}={name}.COMPONENT")


def _frd_stages(frd, nodes, blocks, spec, axis, coord, time_factor, notes) -> list:
    wanted = {q: _target(spec[q][0], f"--map {q}={spec[q][0]}")
              for q in ("p", "wear", "f") if q in spec}
    times = sorted({b.time for b in blocks})
    stages = []
    for t in times:
        at = [b for b in blocks if b.time == t]
        vals, ids = {}, None
        for q, (name, comp, k) in wanted.items():
            found = [b for b in at if b.name == name]
            if not found:
                continue
            b = found[0]
            if comp is None or comp not in b.components:
                raise CaseError(f"{frd}: block {name} at time {t:g} has no component "
                                f"'{comp}' (it has {', '.join(b.components)}); --map "
                                f"{q}={name}.COMPONENT")
            v = b.values[:, b.components.index(comp)] * k * spec[q][2]
            vals[q] = dict(zip(b.ids.tolist(), v))
            ids = b.ids if ids is None else ids
        if not vals:
            continue
        ids = sorted(set().union(*[set(v) for v in vals.values()]))
        missing = [i for i in ids if i not in nodes]
        if missing:
            raise CaseError(f"{frd}: node {missing[0]} of the results at time {t:g} is not "
                            "in the node block")
        coords = np.array([nodes[i] for i in ids], float)
        r = _radius(coords, axis, coord)
        order = np.argsort(r, kind="stable")

        def col(q):
            if q not in vals:
                return None
            return np.array([vals[q].get(i, 0.0) for i in ids], float)[order]
        f, wear = col("f"), col("wear")
        stages.append(Stage(time=t * time_factor, r=r[order], f=f, p=col("p"),
                            wear=wear if f is None else None,
                            origin=f"{frd.name} time {t:g}"))
    if not stages:
        names = sorted({b.name for b in blocks})
        raise CaseError(f"{frd}: no block {spec['p'][0].split('.')[0]} (the contact "
                        f"pressure); blocks: {', '.join(names) or 'none'}; name the pressure "
                        "with --map p=BLOCK.COMPONENT (*CONTACT FILE writes CONTACT.CPRESS)")
    notes.append(f"{frd.name}: {len(stages)} stage(s) at the result times")
    return stages


def _dat_stages(dat, blocks, spec, axis, coord, time_factor, notes) -> list:
    contact = [b for b in blocks if b.quantity == "contact stress"]
    if not contact:
        return []
    inp = dat.with_suffix(".inp")
    if not inp.is_file():
        raise CaseError(f"{dat}: the contact prints need the node coordinates: no "
                        f"{inp.name} (the deck) and no .frd beside it")
    nodes = inp_nodes(inp)
    k = spec["p"][2]
    stages = []
    for b in contact:
        missing = [i for i in b.ids if i not in nodes]
        if missing:
            raise CaseError(f"{dat}: slave node {missing[0]} at time {b.time:g} is not in "
                            f"{inp.name}")
        r = _radius(np.array([nodes[i] for i in b.ids], float), axis, coord)
        order = np.argsort(r, kind="stable")
        stages.append(Stage(time=b.time * time_factor, r=r[order], f=None,
                            p=b.values[order, 0] * k, origin=f"{dat.name} time {b.time:g}"))
    notes.append(f"{dat.name}: the pressure from the contact prints, the radii from {inp.name}")
    return stages


def _dat_history(dat, blocks, spec, axis, time_factor, notes, stages) -> dict:
    comp = AXES[axis]
    totals = [b for b in blocks if b.quantity == "total force"]
    history = {}
    if totals:
        sets = sorted({b.set for b in totals})
        if "force" in spec:
            name, _, k = _target(spec["force"][0], f"--map force={spec['force'][0]}")
            k *= spec["force"][2]
        elif len(sets) == 1:
            name, k = sets[0], 1.0
        else:
            raise CaseError(f"{dat}: total forces of several node sets ({', '.join(sets)}); "
                            "name the one that carries the load: --map force=SET")
        mine = [b for b in totals if b.set == name]
        if not mine:
            raise CaseError(f"{dat}: no total force of set {name} (sets with totals: "
                            f"{', '.join(sets)})")
        history["time"] = np.array([b.time for b in mine]) * time_factor
        history["force"] = np.array([abs(b.values[0, comp]) for b in mine]) * k
        notes.append(f"{dat.name}: the force is |{('fx', 'fy', 'fz')[comp]}| of set {name}'s "
                     f"total" + (f" × {k:g}" if k != 1.0 else ""))
    elif dat is not None and "force" in spec:
        printed = sorted({f"{b.quantity} of set {b.set}" if b.set else b.quantity
                          for b in blocks})
        raise CaseError(f"{dat}: no 'total force' print (*NODE PRINT, NSET=SET, TOTALS=ONLY "
                        f"with RF) for --map force={spec['force'][0]}; it prints: "
                        f"{', '.join(printed) or 'nothing'}")
    if "depth" in spec:
        name, _, k = _target(spec["depth"][0], f"--map depth={spec['depth'][0]}")
        disp = [b for b in blocks if b.quantity == "displacements" and b.set == name]
        if not disp:
            printed = sorted({b.set for b in blocks if b.quantity == "displacements"})
            raise CaseError(f"{dat}: no displacements printed for set {name} (--map depth="
                            f"{spec['depth'][0]}); sets with displacements printed: "
                            f"{', '.join(printed) or 'none'}")
        t = np.array([b.time for b in disp]) * time_factor
        d = np.array([abs(float(np.mean(b.values[:, comp]))) for b in disp]) * k \
            * spec["depth"][2]
        if "time" not in history:
            history["time"] = t
        elif len(t) != len(history["time"]) or not np.allclose(t, history["time"]):
            raise CaseError(f"{dat}: the displacements of set {name} are printed at other "
                            "times than the total force")
        history["depth"] = d
    if "time" not in history:
        # no printed totals: the stages alone, without history quantities
        history["time"] = np.array([st.time for st in stages])
        notes.append("no total force printed: the force is not judged")
    return history
