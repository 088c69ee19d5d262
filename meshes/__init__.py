"""gmsh meshes of the axisymmetric sphere, cached by their parameters.

The r–z domain is the lower half of the meridian section of a sphere of radius
R whose pole touches the plane z = 0 and whose centre is at (0, R)::

    top      z = R, 0 <= r <= R      (flat face, clamped by the FEM)
    axis     r = 0, 0 <= z <= R      (symmetry axis)
    contact  the arc from the pole (0, 0) out to r = r_contact
    surface  the rest of the arc, from r_contact to the equator (R, R)

The contact arc carries ``contact_edges`` equal elements (so equally spaced
nodes, placed exactly on the circle); away from it the element size grows
linearly with the distance from the arc (a gmsh Distance + MathEval size
field), capped at ``size_max``. Meshes are first order: scikit-fem keeps the
boundary tags of order-1 gmsh meshes only, and the FEM uses them with
quadratic elements when asked.

Meshes are written to a cache directory (``$WEARCHECK_CACHE`` or
``~/.cache/wearcheck/meshes``) under a hash of their parameters, atomically.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import threading
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from wearcheck.cases import CaseError, SolverError, reference
from wearcheck.extras import need
from wearcheck import temporaries

#: bump when the geometry or meshing recipe changes (invalidates the cache)
RECIPE = 1
GROUPS = ("axis", "top", "surface", "contact")
#: default growth of the element size with the distance from the contact arc
GROWTH = 0.25

_gmsh_lock = threading.Lock()


@dataclass(frozen=True)
class SphereMeshParameters:
    """Everything that defines one mesh (and its cache key); lengths in m."""

    radius: float
    contact_radius: float
    contact_edges: int
    growth: float = GROWTH
    size_max: float | None = None  # default: radius / 10

    def key(self) -> str:
        data = dict(asdict(self), recipe=RECIPE)
        text = json.dumps(data, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:20]

    def check(self) -> None:
        if not self.contact_edges >= 1:
            raise CaseError(f"the contact arc needs at least one element, got {self.contact_edges}")
        if not 0.0 < self.contact_radius < self.radius:
            raise CaseError(f"contact arc radius {self.contact_radius:.6g} m must lie in "
                            f"(0, indenter.radius = {self.radius:.6g} m)")
        if not self.growth > 0:
            raise CaseError(f"mesh growth rate must be > 0, got {self.growth!r}")


@dataclass
class SphereMesh:
    """A first-order triangle mesh of the sphere's r–z section.

    points : (N, 2) r, z [m]; triangles : (Nt, 3) node indices;
    lines : name -> (Ne, 2) node pairs of the boundary edges of each group.
    """

    points: np.ndarray
    triangles: np.ndarray
    lines: dict
    parameters: SphereMeshParameters
    path: Path | None = None
    generate_seconds: float = 0.0  # 0 when read from the cache


def cache_dir() -> Path:
    """Where meshes are cached: $WEARCHECK_CACHE or ~/.cache/wearcheck/meshes."""
    env = os.environ.get("WEARCHECK_CACHE")
    base = Path(env) if env else Path.home() / ".cache" / "wearcheck" / "meshes"
    return base


def _generate(params: SphereMeshParameters, msh_path: Path) -> dict:
    """Mesh with gmsh (headless), write ``msh_path`` (.msh 4.1), return the arrays."""
    gmsh = need("gmsh", "meshing the FEM's sphere")

    R, rc, n = params.radius, params.contact_radius, params.contact_edges
    # element length along the contact arc
    theta_c = math.asin(rc / R)
    h_c = R * theta_c / n
    size_max = params.size_max if params.size_max is not None else R / 10.0
    size_max = max(size_max, h_c)
    with _gmsh_lock:  # gmsh has one global state per process
        gmsh.initialize(["wearcheck", "-nopopup"], readConfigFiles=False, interruptible=False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.model.add("sphere")
            geo = gmsh.model.geo
            zc = R - math.sqrt(R * R - rc * rc)
            centre = geo.addPoint(0.0, R, 0.0)
            pole = geo.addPoint(0.0, 0.0, 0.0)
            edge = geo.addPoint(rc, zc, 0.0)
            equator = geo.addPoint(R, R, 0.0)
            contact = geo.addCircleArc(pole, centre, edge)
            surface = geo.addCircleArc(edge, centre, equator)
            top = geo.addLine(equator, centre)
            axis = geo.addLine(centre, pole)
            loop = geo.addCurveLoop([contact, surface, top, axis])
            body = geo.addPlaneSurface([loop])
            geo.mesh.setTransfiniteCurve(contact, n + 1)
            geo.synchronize()
            curves = dict(zip(GROUPS, (axis, top, surface, contact)))
            for name, tag in curves.items():
                gmsh.model.addPhysicalGroup(1, [tag], name=name)
            gmsh.model.addPhysicalGroup(2, [body], name="sphere")

            fields = gmsh.model.mesh.field
            dist = fields.add("Distance")
            fields.setNumbers(dist, "CurvesList", [contact])
            fields.setNumber(dist, "Sampling", max(4 * n, 100))
            grow = fields.add("MathEval")
            fields.setString(grow, "F", f"{h_c!r} + {params.growth!r} * F{dist}")
            cap = fields.add("MathEval")
            fields.setString(cap, "F", f"{size_max!r}")
            size = fields.add("Min")
            fields.setNumbers(size, "FieldsList", [grow, cap])
            fields.setAsBackgroundMesh(size)
            gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
            gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
            gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
            gmsh.option.setNumber("Mesh.Algorithm", 5)  # Delaunay: quick for graded sizes
            gmsh.option.setNumber("Mesh.ElementOrder", 1)
            gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
            gmsh.model.mesh.generate(2)
            gmsh.write(str(msh_path))

            tags, coords, _ = gmsh.model.mesh.getNodes()
            index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
            index[tags.astype(np.int64)] = np.arange(len(tags))
            points = coords.reshape(-1, 3)[:, :2]
            types, _, nodes = gmsh.model.mesh.getElements(2, body)
            if list(types) != [2]:
                raise SolverError(f"gmsh produced element types {list(types)}, expected "
                                  "3-node triangles only")
            triangles = index[nodes[0].astype(np.int64)].reshape(-1, 3)
            lines = {}
            for name, tag in curves.items():
                types, _, nodes = gmsh.model.mesh.getElements(1, tag)
                lines[name] = index[nodes[0].astype(np.int64)].reshape(-1, 2)
        except SolverError:
            raise
        except Exception as exc:  # gmsh raises plain Exception with its log text
            raise SolverError(f"gmsh failed to mesh the sphere ({asdict(params)}): {exc}") from None
        finally:
            gmsh.finalize()
    # drop nodes used by no triangle (gmsh keeps none, but be safe) and renumber
    used = np.unique(triangles)
    renum = -np.ones(len(points), dtype=np.int64)
    renum[used] = np.arange(len(used))
    arrays = dict(points=np.ascontiguousarray(points[used]), triangles=renum[triangles])
    for name, pairs in lines.items():
        if len(pairs) == 0 or np.any(renum[pairs] < 0):
            raise SolverError(f"gmsh mesh lacks a proper boundary group '{name}'")
        arrays[f"line_{name}"] = renum[pairs]
    return arrays


def atomic_save(path: Path, write) -> None:
    """Write ``path`` through a temporary file in its directory, then rename (caches use
    it). The temporary's name says which process writes it: what a killed writer left
    anywhere in the cache is removed first (:mod:`wearcheck.temporaries`)."""
    temporaries.atomic_write(path, write, mode=0o644, clean="all")


def _from_arrays(arrays, params, path) -> SphereMesh:
    return SphereMesh(points=arrays["points"], triangles=arrays["triangles"],
                      lines={g: arrays[f"line_{g}"] for g in GROUPS}, parameters=params,
                      path=path)


def _file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def entry_checksum(arrays: dict, key: str, msh_sha256: str) -> str:
    """SHA-256 of a cache entry: its parameters' key, the .msh file's SHA-256 and every
    array (name, dtype, shape, bytes). Written into the .npz, checked when read."""
    h = hashlib.sha256(f"{key}\n{msh_sha256}\n".encode())
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name} {a.dtype.str} {a.shape}\n".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _read_entry(npz: Path, msh: Path, params) -> dict | None:
    """The arrays of a cache entry, or None when it is damaged: unreadable, or
    anything in it (an array, the .msh) changed since it was written (its checksum),
    or written by a wearcheck that kept no checksum. Such an entry would give a
    mesh that is not the one its parameters name, and a solve failing in ways
    that point elsewhere ("the stiffness matrix could not be factorised")."""
    try:
        with np.load(npz, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        recorded = str(arrays.pop("checksum"))
        if recorded != entry_checksum(arrays, params.key(), _file_sha256(msh)):
            return None
        _from_arrays(arrays, params, msh)   # every array there
        return arrays
    except Exception:  # zipfile.BadZipFile, EOFError, OSError, ValueError, KeyError
        return None


def sphere_mesh(params: SphereMeshParameters, use_cache: bool = True) -> SphereMesh:
    """The mesh for ``params``: read from the cache, or generated and cached.

    The cache holds ``sphere-<hash>.msh`` (gmsh's file, for users and
    ``wearcheck mesh``) and ``sphere-<hash>.npz`` (the arrays, read back
    without meshio, and the entry's checksum); the .npz is written last, so its
    presence marks a complete entry. A damaged entry (truncated, or changed
    since: :func:`entry_checksum`) is generated again.
    """
    import time

    params.check()
    directory = cache_dir()
    stem = f"sphere-{params.key()}"
    msh, npz = directory / f"{stem}.msh", directory / f"{stem}.npz"
    if use_cache and npz.is_file() and msh.is_file():
        arrays = _read_entry(npz, msh, params)
        if arrays is not None:
            return _from_arrays(arrays, params, msh)
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SolverError(f"cannot create the mesh cache directory '{directory}' "
                          f"(set WEARCHECK_CACHE): {exc}") from None
    t0 = time.perf_counter()
    arrays = {}

    def write_msh(tmp):
        arrays.update(_generate(params, tmp))

    atomic_save(msh, write_msh)
    seconds = time.perf_counter() - t0
    checksum = entry_checksum(arrays, params.key(), _file_sha256(msh))
    atomic_save(npz, lambda tmp: np.savez(tmp, checksum=np.array(checksum), **arrays))
    mesh = _from_arrays(arrays, params, msh)
    mesh.generate_seconds = seconds
    return mesh


def contact_edges_for(contact_nodes: int, element_order: int) -> int:
    """Elements on the contact arc giving at least ``contact_nodes`` nodes there.

    With quadratic elements each edge carries a midside node, so the arc has
    2·edges + 1 nodes: an even request is raised by one.
    """
    if element_order == 2:
        return max(1, math.ceil((contact_nodes - 1) / 2))
    return max(1, contact_nodes - 1)


def contact_arc(case, section: str, element_order: int, growth: float,
                min_nodes_in_contact: int) -> SphereMeshParameters:
    """The sphere mesh of a case for the solver whose keys are ``section``
    (``fem`` or ``ccx``: its ``contact_nodes`` and ``contact_factor``).

    The candidate contact arc reaches ``contact_factor`` times the predicted
    final contact radius (√2·a0 under depth control, the long-run scar radius
    under force control). Refused, naming the key: an arc ending inside the
    unworn contact, fewer than ``min_nodes_in_contact`` nodes inside it, an
    arc past the sphere's equator.
    """
    keys, R = getattr(case, section), case.indenter.radius
    factor, nodes = keys.contact_factor, keys.contact_nodes
    a0 = reference.scales(case)["a0"]
    predicted = reference.predicted_scar_radius(case, case.end_distance or 0.0)
    rc = factor * predicted
    if rc <= a0:
        raise CaseError(f"key '{section}.contact_factor' = {factor!r}: the candidate contact "
                        f"arc ends at r = {rc:.4g} m, inside the unworn contact radius a0 = "
                        f"{a0:.4g} m; must be > {a0 / predicted:.4f} (>= 1 to reach the "
                        f"predicted final contact radius {predicted:.4g} m)")
    edges = contact_edges_for(nodes, element_order)
    inside = int(a0 / (rc / (edges * element_order))) + 1
    if inside < min_nodes_in_contact:
        need = math.ceil((min_nodes_in_contact - 1) * rc / a0) + 1
        raise CaseError(f"key '{section}.contact_nodes' = {nodes}: only {inside} nodes would "
                        f"lie inside the unworn contact (a0 = {a0:.4g} m); at least "
                        f"{min_nodes_in_contact} are needed, i.e. {section}.contact_nodes >= "
                        f"{need}")
    if rc >= R:
        # (a predicted scar past R itself is refused by cases.validity.check_planned, as
        # by every solver: here only the arc's margin beyond it does not fit)
        raise CaseError(f"key '{section}.contact_factor' = {factor!r}: the candidate arc "
                        f"would reach r = {rc:.4g} m, beyond indenter.radius = {R:.4g} m "
                        f"(predicted final scar radius {predicted:.4g} m); use "
                        f"{section}.contact_factor < {math.floor(R / predicted * 1000) / 1000:g}"
                        " (>= 1 reaches the predicted scar), or shorten the run or lower the "
                        "load")
    return SphereMeshParameters(radius=R, contact_radius=rc, contact_edges=edges, growth=growth)


__all__ = ["SphereMesh", "SphereMeshParameters", "sphere_mesh", "contact_edges_for",
           "contact_arc", "cache_dir",
           "atomic_save",
           "GROUPS"]
