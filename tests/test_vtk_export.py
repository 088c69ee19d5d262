"""VTK export (comparisons.vtk) on synthetic run directories with exact fields.

The synthetic FEM run is a circular cylinder (radius Rc, height H) whose
top face is moved down by d onto a rigid frictionless plane z = 0 (the FEM's
frame, fem/__init__.py), its flat base worn in gross slip, with a uniform
pressure q on its mantle. Its field is exactly homogeneous: ε_zz = -e with
e = (d - w)/H, u_z = (d - w)(1 - z/H) - d, u_r = α r, σ_rr = σ_θθ = -q,
σ_rz = 0, p = -σ_zz = E e + 2ν q, and Reye–Archard wear dw/ds = k p gives
w(s) = (d + 2ν q H/E)(1 - exp(-k E s/H)). Linear fields are exact on P1 and
P2 meshes, so every exported value has a closed form to compare with.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from wearcheck.outputs import OUTPUT_MARKER

from wearcheck import cases
from wearcheck.cases import RunResult, WearcheckError
from wearcheck.comparisons.present import vtk
from wearcheck.rundir import Run, write_run

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
        return alpha * r, (self.d - self.wear(s)) * (1 - z / self.H) - self.d

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
    from wearcheck.cases import reference
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


#: faces of VTK's linear cells by local point number (vtkWedge, vtkPyramid, vtkTetra)
FACES = {13: [(0, 1, 2), (3, 5, 4), (0, 3, 4, 1), (1, 4, 5, 2), (2, 5, 3, 0)],
         14: [(0, 1, 2, 3), (0, 4, 1), (1, 4, 2), (2, 4, 3), (3, 4, 0)],
         10: [(0, 1, 3), (1, 2, 3), (2, 0, 3), (0, 2, 1)]}


def assert_convex_cells(mesh):
    """Every wedge, pyramid and tetrahedron has planar faces and is convex.

    Checked face by face: all the cell's points lie on one side of each face's
    plane, to 1e-9 of the cell's size (rounding). VTK's cell validator does
    this too but takes minutes on the FEM's solids and flags, with absolute
    tolerances, cells that pass this test (see ``assert_vtk_validator``).
    """
    conn = mesh.cell_connectivity
    offsets = mesh.cell_offsets
    for kind, faces in FACES.items():
        sel = np.flatnonzero(mesh.celltypes == kind)
        if not len(sel):
            continue
        n = {13: 6, 14: 5, 10: 4}[kind]
        P = mesh.points[conn[offsets[sel][:, None] + np.arange(n)]]  # (cells, n, 3)
        size = np.max(np.ptp(P, axis=1), axis=1)
        for face in faces:
            a, b, c = (P[:, i] for i in face[:3])
            normal = np.cross(b - a, c - a)
            normal /= np.linalg.norm(normal, axis=1)[:, None]
            d = np.einsum("cnk,ck->cn", P - a[:, None, :], normal) / size[:, None]
            assert np.all((d <= 1e-9).all(axis=1) | (d >= -1e-9).all(axis=1))
            assert np.all(np.abs(d[:, list(face)]) <= 1e-9)


def assert_vtk_validator(mesh):
    """VTK's cell validator (small meshes only: it is slow).

    Run on a copy scaled to unit size, as its tolerances are absolute. Its
    convexity test is left out: it flags wedges that pass
    ``assert_convex_cells``.
    """
    unit = mesh.copy()
    unit.points = mesh.points / np.max(np.ptp(mesh.points, axis=0))
    report = unit.validate_mesh(exclude_fields=["non_convex"])
    assert report.is_valid, report.message


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


@pytest.mark.parametrize("segments", [3, 8, 32])
def test_revolved_quarter_disc_is_a_valid_solid_of_the_hemisphere_volume(segments):
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
    assert_convex_cells(mesh)
    assert_vtk_validator(mesh)
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


def test_revolve_vectors_rotates_about_the_axis():
    theta = 2 * np.pi * np.arange(7) / 7
    v = vtk.revolve_vectors(np.tile([1.0, 2.0], (7, 1)), theta)
    # the radial unit vector at θ points to where the node at r = 1 went
    xyz, _, theta_points, _ = vtk.revolve_mesh(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]),
                                               np.array([[0, 1, 2]]), 7)
    np.testing.assert_allclose(theta_points[1:-1], theta, atol=1e-15)
    np.testing.assert_allclose(v[:, [0, 2]], xyz[1:-1, [0, 2]], atol=1e-15)
    np.testing.assert_allclose(v[:, 1], 2.0)


# -- export of a synthetic FEM run ---------------------------------------------

SECTION_FIELDS = {"displacement", "sigma_rr", "sigma_zz", "sigma_tt", "sigma_rz", "von_mises", "stress",
                  "contact_pressure", "wear_depth", "contact_node"}
SERIES_FIELDS = dict(profile={"f", "wear_depth", "pressure"},
                     pressure={"pressure", "p_over_p0", "r"},
                     surface={"f", "wear_depth", "pressure"},
                     section=SECTION_FIELDS, solid=SECTION_FIELDS)


@pytest.fixture(scope="module", params=[1, 2], ids=["P1", "P2"])
def exported(request, tmp_path_factory):
    run, cyl = cylinder_run(tmp_path_factory.mktemp("vtk") / "run", order=request.param)
    return run, cyl, vtk.export_run(run.path, revolve=SEGMENTS)


def check_series(directory, run, expected):
    """The .pvd files: names, time values (= s of the stages), files present."""
    assert {p.stem for p in directory.glob("*.pvd")} == set(expected)
    import pyvista as pv
    for name in expected:
        times, files = read_pvd(directory / f"{name}.pvd")
        # written with repr(): exact round trip
        np.testing.assert_array_equal(times, run.stages["s"])
        assert all(f.is_file() for f in files)
        reader = pv.get_reader(directory / f"{name}.pvd")
        np.testing.assert_allclose(reader.time_values, run.stages["s"], rtol=1e-15, atol=0)
        assert len(reader.time_values) == len(run.stages["s"])


def test_series_and_time_values(exported):
    run, _, directory = exported
    check_series(directory, run, SERIES_FIELDS)


def test_every_vtu_reads_back_with_meshio_and_pyvista(exported):
    run, _, directory = exported
    K = len(run.stages["s"])
    Np = len(run.fields["points"])
    for name, names in SERIES_FIELDS.items():
        files = sorted(directory.glob(f"{name}_*.vtu"))
        assert len(files) == K
        for k, file in enumerate(files):
            m, g = read_both(file)
            assert set(m.point_data) == names == set(g.point_data)
            assert len(m.points) == g.n_points
            for key in names:
                want = {"displacement": (g.n_points, 3), "stress": (g.n_points, 9)}.get(
                    key, (g.n_points,))
                assert m.point_data[key].shape == want == g.point_data[key].shape
            for data in (m.field_data, g.field_data):
                assert float(np.ravel(data["s"])[0]) == run.stages["s"][k]
                assert float(np.ravel(data["TimeValue"])[0]) == run.stages["s"][k]
                assert float(np.ravel(data["s_hat"])[0]) == pytest.approx(
                    run.stages["s_hat"][k], rel=1e-15)
                assert int(np.ravel(data["stage"])[0]) == k
            # every point array's unit, as the layout and the docs give it
            for data in (m.field_data, g.field_data):
                assert vtk.read_units(data["units"]) == {n: vtk.UNITS[n] for n in names}
                assert float(np.ravel(data["warp_scale"])[0]) >= 1.0
            if name == "section":
                assert g.n_points == Np
                kind = "triangle" if run.fields["cells"].shape[1] == 3 else "triangle6"
                assert [c.type for c in m.cells] == [kind]


def test_section_fields_are_the_exact_solution(exported):
    run, cyl, directory = exported
    r, z = run.fields["points"].T
    contact = run.fields["contact_nodes"]
    for k, s in enumerate(run.stages["s"]):
        m, g = read_both(directory / f"section_{k:03d}.vtu")
        np.testing.assert_array_equal(m.points[:, :2], run.fields["points"])
        assert np.all(m.points[:, 2] == 0)
        u_r, u_z = cyl.displacement(s, r, z)
        # fields pass through float64 unchanged: rounding only
        np.testing.assert_allclose(m.point_data["displacement"],
                                   np.column_stack([u_r, u_z, 0 * r]), rtol=0, atol=1e-22)
        srr, szz, stt, srz = cyl.stress(s)
        for key, value in (("sigma_rr", srr), ("sigma_zz", szz), ("sigma_tt", stt),
                           ("sigma_rz", srz)):
            np.testing.assert_allclose(g.point_data[key], value, rtol=1e-14)
        # σ_rr = σ_θθ, σ_rz = 0: von Mises is |σ_zz - σ_rr| (and not the
        # plane value, which would ignore the hoop stress)
        np.testing.assert_allclose(g.point_data["von_mises"], abs(szz - srr), rtol=1e-12)
        marker = np.zeros(len(r))
        marker[contact] = 1
        np.testing.assert_array_equal(g.point_data["contact_node"], marker)
        np.testing.assert_allclose(g.point_data["contact_pressure"],
                                   marker * cyl.pressure(s), rtol=1e-14)
        np.testing.assert_allclose(g.point_data["wear_depth"], marker * cyl.wear(s), rtol=1e-14)


def check_contact_against_run(run, directory, gap_tol, field_tol, skip=()):
    """The exported fields against the run's own contact results.

    FEM convention (fem/__init__.py): displacements in the frame of the rigid
    plane z = 0, the top face moved down by the depth d; contact node i has
    the initial gap f0(r_i) (the case's unworn profile), so a node in
    contact closes its gap, f0 + w + u_z = 0, and the top face has u_z = -d.
    Its wear and pressure are those of the run's stages at its radius.
    Tolerances: ``gap_tol`` relative to d on the closed gap and the top
    face's displacement, ``field_tol`` relative to the largest stage value
    of wear and pressure. ``skip``: contact node positions left out of the
    gap check.
    """
    contact = run.fields["contact_nodes"]
    st = run.stages
    f0 = vtk.unworn_profile(run, st["r"])
    for k, s in enumerate(st["s"]):
        g = pv_read(directory / f"section_{k:03d}.vtu")
        r = g.points[contact, 0]
        u_z = g.point_data["displacement"][contact, 1]
        w = g.point_data["wear_depth"][contact]
        p = g.point_data["contact_pressure"][contact]
        depth = np.interp(s, run.history["s"], run.history["depth"])
        touching = p > 0
        touching[list(skip)] = False
        assert touching.any()
        gap = vtk.unworn_profile(run, r) + w + u_z
        np.testing.assert_allclose(gap[touching], 0.0, rtol=0, atol=gap_tol * depth)
        top = g.points[:, 1] == np.max(g.points[:, 1])
        np.testing.assert_allclose(g.point_data["displacement"][top, 1], -depth, rtol=gap_tol)
        wear = np.interp(r, st["r"], st["f"][k] - f0)
        pressure = np.interp(r, st["r"], st["p"][k])
        scale_w = max(np.max(np.abs(st["f"] - f0)), 1e-300)
        np.testing.assert_allclose(w, wear, rtol=0, atol=field_tol * scale_w)
        np.testing.assert_allclose(p, pressure, rtol=0, atol=field_tol * np.max(st["p"]))


def pv_read(path):
    import pyvista as pv
    return pv.read(path)


def test_contact_nodes_against_the_runs_contact_results(exported):
    run, cyl, directory = exported
    # exact synthetic data: rounding only
    check_contact_against_run(run, directory, gap_tol=1e-12, field_tol=1e-12)


def test_revolved_solid(exported):
    run, cyl, directory = exported
    N = SEGMENTS
    factor = N * np.sin(2 * np.pi / N) / (2 * np.pi)
    for k, s in enumerate(run.stages["s"]):
        m, g = read_both(directory / f"solid_{k:03d}.vtu")
        assert {c.type for c in m.cells} == {"wedge", "pyramid", "tetra"}
        volume = g.compute_cell_sizes().cell_data["Volume"]
        assert np.all(volume > 0)
        assert_convex_cells(g)
        if k == 0:  # slow; the same cells in every stage
            assert_vtk_validator(g)
        # the N-gon prism inscribed in the cylinder: (N/2) sin(2π/N) Rc² H
        # exactly (straight r–z boundaries), rounding only; the cylinder's
        # πRc²H is larger by the polygonal revolution factor
        assert volume.sum() == pytest.approx(factor * np.pi * cyl.Rc**2 * cyl.H, rel=1e-12)
        assert 1 - volume.sum() / (np.pi * cyl.Rc**2 * cyl.H) == pytest.approx(1 - factor,
                                                                               rel=1e-9)
        # Cartesian displacement of the homogeneous field at each 3D point
        x, y, zc = g.points.T
        e, alpha = cyl.strain(s)
        want = np.column_stack([alpha * x, cyl.displacement(s, 0.0, y)[1], alpha * zc])
        np.testing.assert_allclose(m.point_data["displacement"], want, rtol=0, atol=1e-21)
        np.testing.assert_allclose(g.point_data["sigma_zz"], cyl.stress(s)[1], rtol=1e-14)


def test_profile_pressure_and_surface(exported):
    run, cyl, directory = exported
    st = run.stages
    M = len(st["r"])
    for k, s in enumerate(st["s"]):
        m, g = read_both(directory / f"profile_{k:03d}.vtu")
        np.testing.assert_array_equal(m.points,
                                      np.column_stack([st["r"], st["f"][k], 0 * st["r"]]))
        assert [c.type for c in m.cells] == ["line"] and len(m.cells[0].data) == M - 1
        # the case's unworn profile is flat out to the cylinder's radius
        np.testing.assert_allclose(g.point_data["wear_depth"], cyl.wear(s), rtol=1e-14)
        m, g = read_both(directory / f"pressure_{k:03d}.vtu")
        np.testing.assert_array_equal(m.points[:, 0], st["r"])
        assert np.all(m.points[:, 1:] == 0)
        np.testing.assert_allclose(g.point_data["p_over_p0"],
                                   cyl.pressure(s) / run.scales["p0"], rtol=1e-14)
        m, g = read_both(directory / f"surface_{k:03d}.vtu")
        # r[0] = 0 is on the axis: one point there, N on every other ring
        assert g.n_points == 1 + (M - 1) * SEGMENTS
        ring = np.hypot(g.points[:, 0], g.points[:, 2])
        assert np.all(np.min(np.abs(ring[:, None] - st["r"][None, :]), axis=1) < 1e-15)
        np.testing.assert_allclose(g.points[:, 1], cyl.wear(s), rtol=1e-14)
        area = g.compute_cell_sizes().cell_data["Area"].sum()
        # flat disc, an inscribed N-gon: (N/2) sin(2π/N) Rc²
        assert area == pytest.approx(SEGMENTS / 2 * np.sin(2 * np.pi / SEGMENTS) * cyl.Rc**2,
                                     rel=1e-12)


def test_run_without_fields_gets_profiles_only(tmp_path):
    run, _ = cylinder_run(tmp_path / "mdr", with_fields=False)
    directory = vtk.export_run(run.path, revolve=SEGMENTS)
    check_series(directory, run, ("profile", "pressure", "surface"))


def test_export_replaces_atomically_and_a_failure_keeps_the_old_files(tmp_path):
    run, _ = cylinder_run(tmp_path / "run", s_hat=(0.0, 1.0))
    directory = vtk.export_run(run.path)
    before = {p.name: p.read_bytes() for p in directory.iterdir()}
    assert "solid.pvd" not in before
    directory = vtk.export_run(run.path, revolve=4)
    assert (directory / "solid.pvd").is_file()
    before = {p.name: p.read_bytes() for p in directory.iterdir()}
    # break fields.npz: the export fails and leaves the previous vtk/ alone
    fields = dict(np.load(run.path / "fields.npz"))
    del fields["stress"]
    np.savez(run.path / "fields.npz", **fields)
    with pytest.raises(WearcheckError, match="stress"):
        vtk.export_run(run.path, revolve=4)
    assert {p.name: p.read_bytes() for p in directory.iterdir()} == before
    assert sorted(p.name for p in run.path.iterdir() if p.name.startswith(".")
            and p.name != OUTPUT_MARKER) == []


def test_export_command(tmp_path, capsys):
    from wearcheck.cli import main
    run, _ = cylinder_run(tmp_path / "run", s_hat=(0.0, 2.0))
    assert main(["export", str(run.path), "--revolve", "5"]) == 0
    check_series(run.path / "vtk", run, SERIES_FIELDS)
    # the rest of the run directory is untouched
    assert Run(run.path).meta == run.meta
    assert main(["export", str(tmp_path / "nothing")]) != 0
    assert "does not exist" in capsys.readouterr().err
    assert main(["export", str(run.path), "--revolve", "2"]) != 0
    assert "at least 3 segments" in capsys.readouterr().err


def test_run_that_stored_no_stage_exports_nothing(tmp_path):
    from wearcheck.comparisons.present.render import render_run
    run, _ = cylinder_run(tmp_path / "run", s_hat=(0.0,))
    F = run.fields
    empty = RunResult(history=run.history, stage_s=np.zeros(0), r=run.stages["r"],
                      f=np.zeros((0, len(run.stages["r"]))),
                      p=np.zeros((0, len(run.stages["r"]))), solve_seconds=0.0,
                      fields=dict(F, **{k: F[k][:0] for k in ("displacement", "stress",
                                                               "contact_pressure",
                                                               "wear_depth")}))
    path = write_run(tmp_path / "empty", run.case, empty, "fem", argv=["test"])
    assert [p.name for p in vtk.export_run(path, revolve=4).iterdir()] == [OUTPUT_MARKER]
    assert render_run(path) == []


def test_the_unworn_reference_of_an_ellipsoid_is_the_one_its_run_holds(tmp_path):
    """Wear depth f - f0 of an unworn run is zero. The BEM stores the ellipsoid as
    ring averages, x²/2R1 + y²/2R2 averaged over the angle = r²(1/R1 + 1/R2)/4; the
    reference was the paraboloid of the equivalent radius √(R1 R2), so the rendered
    and exported wear depth showed 0.4 µm (40 % of d) at the rim, where nothing wore.
    The MDR solves that equivalent paraboloid (its info says so): its reference."""
    import wearcheck
    from wearcheck.comparisons.present.vtk import unworn_profile
    case = wearcheck.load_case("ellipsoid", {"bem.grid": 48, "mdr.elements": 100,
                                             "sliding.until": "distance",
                                             "sliding.distance": 0.0, "stages.s_hat": [0.0]})
    R1, R2 = case.indenter.radius, case.indenter.radius_y
    for solver in ("bem", "mdr"):
        run = Run(wearcheck.solve(case, solver).write(tmp_path / solver))
        r, f = run.stages["r"], run.stages["f"][0]
        wear = f - unworn_profile(run, r)
        # BEM: a ring is the pixels nearest to it, which sample the angle unevenly, so
        # their mean misses the anisotropic part r²(1/R1 - 1/R2)cos2θ/4 by a little
        # (measured 1.9 % of d at 48²); the old reference was off by 40 % of d.
        # MDR: round-off.
        d = case.loading.depth
        tol = 0.05 * d if solver == "bem" else 1e-9 * d
        assert np.max(np.abs(wear)) <= tol, (solver, np.max(np.abs(wear)), tol)
    # the two references: the ring average and the equivalent paraboloid
    bem, mdr = Run(tmp_path / "bem"), Run(tmp_path / "mdr")
    r = np.array([1e-4])
    assert unworn_profile(bem, r) == pytest.approx(r**2 * (1 / R1 + 1 / R2) / 4, rel=1e-12)
    assert unworn_profile(mdr, r) == pytest.approx(r**2 / (2 * np.sqrt(R1 * R2)), rel=1e-12)
