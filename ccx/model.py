"""The sphere as CalculiX sees it: the project's gmsh mesh with CAX6 midside nodes (pure arrays).

The gmsh mesh (:mod:`meshes`) is of first order; each triangle gets a midside
node at the middle of each straight edge, so the CAX6 elements have the
geometry of the FEM's P2 elements on the same mesh (midside nodes on the
chords of the contact arc, as the FEM places its DOFs). Nodes are numbered for
CalculiX: the contact nodes first, by increasing r (CalculiX node i + 1 is
contact node i, so anything CalculiX sorts by node number comes out by r),
then every other node.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wearcheck.cases import SolverError


@dataclass(frozen=True)
class Cax6Sphere:
    """The CAX6 mesh of the sphere's r–z section, SI units.

    points : (Np, 2) r, z [m]; elements : (Ne, 6) node indices (0-based)
    in CalculiX's CAX6 order (three corners counter-clockwise in (r, z),
    then the midside nodes of edges 1-2, 2-3, 3-1); contact : (Nc,) the
    contact-arc nodes 0 .. Nc-1, by increasing r (the first on the axis);
    top, axis : node indices of the flat top face and of the axis;
    area : (Nc,) lumped 2πr-weighted area ∫ φ_i 2πr ds of each contact node
    [m²] (0 on the axis).
    """

    points: np.ndarray
    elements: np.ndarray
    contact: np.ndarray
    top: np.ndarray
    axis: np.ndarray
    area: np.ndarray

    @property
    def r(self) -> np.ndarray:
        """Radii of the contact nodes [m]."""
        return self.points[self.contact, 0]


def cax6_sphere(sm) -> Cax6Sphere:
    """The CAX6 sphere of a ``meshes.SphereMesh`` (first-order gmsh triangles)."""
    pts = np.asarray(sm.points, float)
    tri = np.asarray(sm.triangles, np.int64).copy()
    p = pts[tri]
    signed = ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
              - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    if np.any(signed == 0.0):
        raise SolverError("the sphere mesh has a triangle of zero area")
    tri[signed < 0] = tri[signed < 0][:, [0, 2, 1]]
    # one midside node per edge, numbered after the vertices
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    inverse = inverse.reshape(3, -1).T                     # (Nt, 3): edges 1-2, 2-3, 3-1
    n_vertices = len(pts)
    points = np.vstack([pts, 0.5 * (pts[unique[:, 0]] + pts[unique[:, 1]])])
    elements = np.column_stack([tri, n_vertices + inverse])

    def group(name):
        """The vertices and midside nodes on a boundary group, and its (a, mid, b) edges."""
        pairs = np.sort(np.asarray(sm.lines[name], np.int64), axis=1)
        pos = np.searchsorted(unique[:, 0] * n_vertices + unique[:, 1],
                              pairs[:, 0] * n_vertices + pairs[:, 1])
        pos = np.minimum(pos, len(unique) - 1)
        if not np.array_equal(unique[pos], pairs):
            raise SolverError(f"mesh boundary '{name}' does not match the triangles' edges")
        mids = n_vertices + pos
        nodes = np.unique(np.concatenate([pairs.ravel(), mids]))
        return nodes, np.column_stack([pairs[:, 0], mids, pairs[:, 1]])

    contact, arc = group("contact")
    top, _ = group("top")
    axis, _ = group("axis")
    contact = contact[np.argsort(points[contact, 0], kind="stable")]
    if points[contact[0], 0] != 0.0:
        raise SolverError("the contact arc does not start on the axis")

    # renumber: contact nodes first, by r
    order = np.concatenate([contact, np.setdiff1d(np.arange(len(points)), contact)])
    new = np.empty(len(points), np.int64)
    new[order] = np.arange(len(points))
    area = np.zeros(len(points))
    np.add.at(area, arc.ravel(), _edge_weights(points, arc).ravel())
    return Cax6Sphere(points=points[order], elements=new[elements],
                      contact=np.arange(len(contact)), top=np.sort(new[top]),
                      axis=np.sort(new[axis]), area=area[contact])


#: three-point Gauss–Legendre rule on [0, 1]: exact for the cubic φ_k(ξ)·r(ξ)
_GAUSS_X = 0.5 + 0.5 * np.array([-math.sqrt(0.6), 0.0, math.sqrt(0.6)])
_GAUSS_W = np.array([5.0, 8.0, 5.0]) / 18.0


def _edge_weights(points, arc) -> np.ndarray:
    """∫ φ_k 2πr ds over each straight quadratic edge (a, mid, b): (Ne, 3)."""
    a, b = points[arc[:, 0]], points[arc[:, 2]]
    length = np.hypot(*(b - a).T)
    x = _GAUSS_X
    shape = np.array([(1 - x) * (1 - 2 * x), 4 * x * (1 - x), x * (2 * x - 1)])  # (3, q)
    r = a[:, 0, None] + (b[:, 0] - a[:, 0])[:, None] * x[None, :]                # (Ne, q)
    return 2.0 * math.pi * length[:, None] * ((r * _GAUSS_W)[:, None, :] * shape[None]).sum(-1)
