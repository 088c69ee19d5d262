"""VTK export (comparisons.vtk) on synthetic run directories with exact fields.

The synthetic FEM run is a circular cylinder (radius Rc, height H, top held)
whose flat base is pressed by a rigid frictionless plane raised by d and worn
in gross slip, with a uniform pressure q on its mantle. Its field is exactly
homogeneous: ε_zz = -e with e = (d - w)/H, u_r = α r, σ_rr = σ_θθ = -q,
σ_rz = 0, p = -σ_zz = E e + 2ν q, and Reye–Archard wear dw/ds = k p gives
w(s) = (d + 2ν q H/E)(1 - exp(-k E s/H)). Linear fields are exact on P1 and
P2 meshes, so every exported value has a closed form to compare with.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import cases
from cases import RunResult, WearcheckError
from comparisons import vtk
from comparisons.runio import Run, write_run

SEGMENTS = 12


# -- synthetic run directories -----------------------------------------------

def cylinder_case(s_hat=(0.0, 1.0, 4.0)):
    """The shipped truncated paraboloid with a flat tip as wide as the cylinder."""
    return cases.load(cases.shipped("truncated"), [
        "indenter.flat_radius=2e-4", "sliding.distance=1.0",
        "stages.s_hat=[" + ", ".join(map(repr, s_hat)) + "]"])


def rectangle_mesh(Rc, H, nr, nz, order, rng):
    """Triangles of [0, Rc] x [0, H] in random orientation; order 2 adds midside nodes."""
    from skfem import MeshTri
    mesh = MeshTri.init_tensor(np.linspace(0.0, Rc, nr + 1), np.linspace(0.0, H, nz + 1))
    points, tri = mesh.p.T.copy(), mesh.t.T.copy()
    flip = rng.random(len(tri)) < 0.5
    tri[flip] = tri[flip][:, [0, 2, 1]]
    if order == 1:
        return points, tri
    mids, extra = {}, []
    six = np.empty((len(tri), 6), dtype=np.int64)
    six[:, :3] = tri
    for t, (a, b, c) in enumerate(tri):
        for slot, (i, j) in zip((3, 4, 5), ((a, b), (b, c), (c, a))):
            key = (min(i, j), max(i, j))
            if key not in mids:
                mids[key] = len(points) + len(extra)
                extra.append(0.5 * (points[i] + points[j]))
            six[t, slot] = mids[key]
    return np.vstack([points, extra]), six


class Cylinder:
    """Closed forms of the synthetic cylinder (see module docstring)."""

    def __init__(self, case, Rc=2e-4, H=1e-3, q=50e6):
        self.case, self.Rc, self.H, self.q = case, Rc, H, q
        self.E, self.nu = case.indenter.youngs_modulus, case.indenter.poisson_ratio
        self.d = case.loading.depth
        self.k = case.wear_rate
        lam = self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu))
        self.lam, self.mu = lam, self.E / (2 * (1 + self.nu))

    def wear(self, s):
        E, nu, H = self.E, self.nu, self.H
        return (self.d + 2 * nu * self.q * H / E) * (1 - np.exp(-self.k * E * s / H))

    def strain(self, s):
        """(e, α): axial shortening strain and radial strain."""
        e = (self.d - self.wear(s)) / self.H
        return e, (self.lam * e - self.q) / (2 * (self.lam + self.mu))

    def pressure(self, s):
        e, _ = self.strain(s)
        return self.E * e + 2 * self.nu * self.q

    def displacement(self, s, r, z):
        e, alpha = self.strain(s)
        return alpha * r, (self.d - self.wear(s)) * (1 - z / self.H)

    def stress(self, s):
        """σ_rr, σ_zz, σ_θθ, σ_rz (uniform)."""
        return -self.q, -self.pressure(s), -self.q, 0.0


def cylinder_run(path, order=2, nr=5, nz=8, s_hat=(0.0, 1.0, 4.0), with_fields=True, seed=0):
    """Write a synthetic run directory; returns (Run, Cylinder)."""
    case = cylinder_case(s_hat)
    cyl = Cylinder(case)
    s = np.asarray(s_hat) / (case.wear_rate * case.E_star / _a0(case))
    points, cells = rectangle_mesh(cyl.Rc, cyl.H, nr, nz, order, np.random.default_rng(seed))
    r, z = points.T
    contact = np.flatnonzero(z == 0.0)
    contact = contact[np.argsort(r[contact])]
    u = np.stack([np.column_stack(cyl.displacement(si, r, z)) for si in s])
    stress = np.stack([np.tile(cyl.stress(si), (len(points), 1)) for si in s])
    fields = dict(points=points, cells=cells, displacement=u, stress=stress,
                  contact_nodes=contact,
                  contact_pressure=np.stack([np.full(len(contact), cyl.pressure(si)) for si in s]),
                  wear_depth=np.stack([np.full(len(contact), cyl.wear(si)) for si in s]))
    steps = np.linspace(0.0, s[-1], 9)
    rs = np.linspace(0.0, cyl.Rc, 21)
    history = dict(s=steps, force=cyl.pressure(steps) * math.pi * cyl.Rc**2,
                   depth=np.full_like(steps, cyl.d), contact_radius=np.full_like(steps, cyl.Rc),
                   wear_center=cyl.wear(steps), wear_volume=cyl.wear(steps) * math.pi * cyl.Rc**2)
    result = RunResult(history=history, stage_s=s, r=rs,
                       f=np.stack([np.full_like(rs, cyl.wear(si)) for si in s]),
                       p=np.stack([np.full_like(rs, cyl.pressure(si)) for si in s]),
                       solve_seconds=0.0, info={"synthetic": "cylinder"},
                       fields=fields if with_fields else None)
    write_run(path, case, result, "fem" if with_fields else "mdr", argv=["test"])
    return Run(path), cyl


def _a0(case):
    from cases import reference
    return reference.scales(case)["a0"]


def quarter_disc_mesh(R, n, rng):
    """Triangles of the quarter disc r, w >= 0, r² + w² <= R² (w = R - z), randomly oriented.

    The unit square is mapped by (x sqrt(1 - y²/2), y sqrt(1 - x²/2)), which
    puts its edges x = 1 and y = 1 on the circle and keeps the axes.
    """
    from skfem import MeshTri
    mesh = MeshTri.init_tensor(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    x, y = mesh.p
    points = R * np.column_stack([x * np.sqrt(1 - y**2 / 2), 1 - y * np.sqrt(1 - x**2 / 2)])
    tri = mesh.t.T.copy()
    flip = rng.random(len(tri)) < 0.5
    tri[flip] = tri[flip][:, [0, 2, 1]]
    return points, tri


def read_pvd(path):
    """(times, files) of a .pvd, by the standard library's XML parser."""
    sets = ET.parse(path).getroot().find("Collection").findall("DataSet")
    return (np.array([float(d.get("timestep")) for d in sets]),
            [path.parent / d.get("file") for d in sets])


def read_both(path):
    """A VTU read by meshio and by pyvista."""
    import meshio
    import pyvista as pv
    return meshio.read(path), pv.read(path)


# -- numerics ------------------------------------------------------------------

def test_von_mises_is_that_of_the_principal_stresses():
    rng = np.random.default_rng(1)
    s = rng.normal(size=(200, 4)) * 1e8
    rr, zz, tt, rz = s.T
    tensor = np.zeros((200, 3, 3))
    tensor[:, 0, 0], tensor[:, 1, 1], tensor[:, 2, 2] = rr, tt, zz
    tensor[:, 0, 2] = tensor[:, 2, 0] = rz
    p = np.linalg.eigvalsh(tensor)
    expected = np.sqrt(0.5 * ((p[:, 0] - p[:, 1])**2 + (p[:, 1] - p[:, 2])**2
                              + (p[:, 2] - p[:, 0])**2))
    # eigenvalues and the closed form agree to rounding (~1e-15 of |σ|)
    np.testing.assert_allclose(vtk.von_mises(s), expected, rtol=1e-10)
    # the hoop stress counts: a pure hoop stress has von Mises |σ_θθ|
    assert vtk.von_mises([0.0, 0.0, 3.0, 0.0]) == pytest.approx(3.0, rel=1e-15)


@pytest.mark.parametrize("order", [1, 2])
def test_orient_triangles_keeps_nodes_and_midsides(order):
    points, cells = rectangle_mesh(1.0, 2.0, 3, 4, order, np.random.default_rng(2))
    assert np.any(vtk.signed_areas(points, cells) < 0)  # the input is mixed
    out = vtk.orient_triangles(points, cells)
    assert np.all(vtk.signed_areas(points, out) > 0)
    np.testing.assert_array_equal(np.sort(out, axis=1), np.sort(cells, axis=1))
    if order == 2:
        for m, (i, j) in zip((3, 4, 5), ((0, 1), (1, 2), (2, 0))):
            np.testing.assert_allclose(points[out[:, m]],
                                       0.5 * (points[out[:, i]] + points[out[:, j]]), atol=1e-15)
        sub = vtk.linear_subtriangles(out)
        assert sub.shape == (4 * len(out), 3)
        assert np.all(vtk.signed_areas(points, sub) > 0)
        # the four sub-triangles tile their parent
        np.testing.assert_allclose(vtk.signed_areas(points, sub).reshape(4, -1).sum(axis=0),
                                   vtk.signed_areas(points, out), rtol=1e-12)


@pytest.mark.parametrize("segments", [3, 8, 64])
def test_revolved_quarter_disc_is_a_valid_solid_of_the_hemisphere_volume(segments):
    import pyvista as pv
    R = 2.0
    points, tri = quarter_disc_mesh(R, 6, np.random.default_rng(3))
    tri = vtk.orient_triangles(points, tri)
    xyz, source, theta, cells = vtk.revolve_mesh(points, tri, segments)
    on_axis = (points[:, 0] == 0)[tri].sum(axis=1)
    assert len(cells[vtk.VTK_WEDGE]) == segments * np.sum(on_axis == 0)
    assert len(cells[vtk.VTK_PYRAMID]) == segments * np.sum(on_axis == 1)
    assert len(cells[vtk.VTK_TETRA]) == segments * np.sum(on_axis == 2)
    mesh = vtk.grid(xyz, cells)
    # VTK's own verdict: every cell has positive volume, no inverted faces
    volume = mesh.compute_cell_sizes().cell_data["Volume"]
    assert np.all(volume > 0)
    assert mesh.validate_mesh().is_valid
    # a closed solid: no free faces
    assert mesh.extract_surface(algorithm="dataset_surface").n_open_edges == 0
    # The polygonal revolution has exactly N sin(2π/N)/(2π) times the volume
    # 2π ∫ r dA of the revolved r–z mesh (Pappus; x = r((1-t) e_j + t e_j+1)
    # has Jacobian r sin(2π/N)): agreement to rounding, 1e-12.
    area = vtk.signed_areas(points, tri)
    pappus = 2 * np.pi * np.sum(area * points[tri, 0].mean(axis=1))
    factor = segments * np.sin(2 * np.pi / segments) / (2 * np.pi)
    assert volume.sum() == pytest.approx(factor * pappus, rel=1e-12)
    # Against the hemisphere 2πR³/3: the chords of angle δ on the arc cut off
    # at most a layer R δ²/8 thick over the curved area 2πR², i.e. 3δ²/8
    # relative, on top of the polygonal factor.
    arc = np.isclose(np.hypot(points[:, 0], R - points[:, 1]), R)
    angles = np.sort(np.arctan2(R - points[arc, 1], points[arc, 0]))
    delta = np.max(np.diff(angles))
    hemisphere = 2 * np.pi * R**3 / 3
    deficit = 1 - volume.sum() / hemisphere
    assert 1 - factor <= deficit <= 1 - factor + 3 * delta**2 / 8
    # points sit at their node's radius and height, at angle θ
    np.testing.assert_allclose(np.hypot(xyz[:, 0], xyz[:, 2]), points[source, 0], atol=1e-14)
    np.testing.assert_allclose(xyz[:, 1], points[source, 1], atol=0)
    assert isinstance(mesh, pv.UnstructuredGrid)


def test_revolve_vectors_rotates_about_the_axis():
    theta = 2 * np.pi * np.arange(7) / 7
    v = vtk.revolve_vectors(np.tile([1.0, 2.0], (7, 1)), theta)
    # the radial unit vector at θ points to where the node at r = 1 went
    xyz, _, theta_points, _ = vtk.revolve_mesh(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]),
                                               np.array([[0, 1, 2]]), 7)
    np.testing.assert_allclose(theta_points[1:-1], theta, atol=1e-15)
    np.testing.assert_allclose(v[:, [0, 2]], xyz[1:-1, [0, 2]], atol=1e-15)
    np.testing.assert_allclose(v[:, 1], 2.0)
