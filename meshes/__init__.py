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

import contextlib
import hashlib
import json
import math
import os
import tempfile
import threading
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from cases import CaseError, SolverError

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


def _generate(params: SphereMeshParameters, path: Path) -> None:
    """Mesh with gmsh (headless) and write ``path`` (.msh 4.1)."""
    import gmsh

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
            gmsh.option.setNumber("General.Verbosity", 2)
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
            for name, tag in zip(GROUPS, (axis, top, surface, contact)):
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
            gmsh.write(str(path))
        except Exception as exc:  # gmsh raises plain Exception with its log text
            raise SolverError(f"gmsh failed to mesh the sphere ({asdict(params)}): {exc}") from None
        finally:
            gmsh.finalize()


def _read(path: Path, params: SphereMeshParameters) -> SphereMesh:
    import meshio

    try:
        m = meshio.read(path)
    except Exception as exc:
        raise SolverError(f"cannot read mesh file '{path}': {exc}") from None
    names = {tag: name for name, (tag, _dim) in
             ((k, tuple(v)) for k, v in m.field_data.items())}
    tri = np.concatenate([c.data for c in m.cells if c.type == "triangle"])
    lines: dict[str, list] = {g: [] for g in GROUPS}
    for block, phys in zip(m.cells, m.cell_data["gmsh:physical"]):
        if block.type != "line":
            continue
        for tag in np.unique(phys):
            name = names.get(int(tag))
            if name in lines:
                lines[name].append(block.data[phys == tag])
    # drop nodes used by no triangle (gmsh keeps none, but be safe) and renumber
    used = np.unique(tri)
    renum = -np.ones(len(m.points), dtype=np.int64)
    renum[used] = np.arange(len(used))
    out_lines = {}
    for name, blocks in lines.items():
        if not blocks:
            raise SolverError(f"mesh file '{path}' lacks the physical group '{name}'")
        out_lines[name] = renum[np.concatenate(blocks)]
    return SphereMesh(points=np.ascontiguousarray(m.points[used, :2]), triangles=renum[tri],
                      lines=out_lines, parameters=params, path=path)


def sphere_mesh(params: SphereMeshParameters, use_cache: bool = True) -> SphereMesh:
    """The mesh for ``params``: read from the cache, or generated and cached."""
    import time

    params.check()
    directory = cache_dir()
    path = directory / f"sphere-{params.key()}.msh"
    if use_cache and path.is_file():
        return _read(path, params)
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SolverError(f"cannot create the mesh cache directory '{directory}' "
                          f"(set WEARCHECK_CACHE): {exc}") from None
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".msh", dir=directory)
    os.close(fd)
    try:
        t0 = time.perf_counter()
        _generate(params, Path(tmp))
        seconds = time.perf_counter() - t0
        mesh = _read(Path(tmp), params)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
    mesh.path = path
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


def parameters_for_case(case) -> SphereMeshParameters:
    """Mesh parameters of a case: the sphere of indenter.radius, the arc to
    fem.contact_factor·√2·a0 with fem.contact_nodes nodes."""
    from cases import reference

    R = case.indenter.radius
    if R is None:
        raise CaseError(f"the FEM needs 'indenter.radius' (the radius of the FEM sphere) for "
                        f"profile \"{case.indenter.profile}\"; it is not given")
    a0 = reference.scales(case)["a0"]
    rc = case.fem.contact_factor * math.sqrt(2.0) * a0
    if rc >= R:
        raise CaseError(f"key 'fem.contact_factor' = {case.fem.contact_factor!r}: the candidate "
                        f"contact arc would reach r = {rc:.4g} m, beyond the sphere's radius "
                        f"indenter.radius = {R:.4g} m")
    return SphereMeshParameters(radius=R, contact_radius=rc,
                                contact_edges=contact_edges_for(case.fem.contact_nodes,
                                                                case.fem.element_order))


__all__ = ["SphereMesh", "SphereMeshParameters", "sphere_mesh", "parameters_for_case",
           "contact_edges_for", "cache_dir", "GROUPS"]
