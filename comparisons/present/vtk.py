"""ParaView files of a run directory: VTU snapshots in PVD time series.

``export_run(run_dir, revolve=0)`` writes ``RUN_DIR/vtk/`` atomically. Every
series is a ``NAME.pvd`` collection of ``NAME_KKK.vtu`` files, one per stored
stage K, whose time values are the sliding distances s [m]; each VTU also
holds the field data ``s``, ``s_hat``, ``stage``, ``TimeValue`` (= s), ``units``
(the point arrays' units as UTF-8 JSON text in bytes, ``{"pressure": "Pa", ...}``:
VTK string arrays would stop meshio reading the file) and ``warp_scale`` (the factor
that draws the worn relief at about half the surface's radius: heights are
microns over radii of a tenth of a millimetre).

Coordinates: the r–z section lies in the x–y plane (x = r, y = z, the axis of
symmetry is the y axis, ParaView's default "up"); a revolved point at angle θ
is (r cos θ, z, -r sin θ), so (r, θ, z) stays right-handed.

Series (all runs):

``profile``   worn profile y = f(r), a polyline; point data ``f``,
              ``wear_depth`` (f minus the unworn profile), ``pressure``.
``pressure``  contact pressure on the line y = 0, a polyline; point data
              ``pressure`` [Pa], ``p_over_p0``, ``r``.
``surface``   the worn indenter surface y = f(r) revolved; point data ``f``,
              ``wear_depth``, ``pressure``.

Series (FEM runs, from ``fields.npz``):

``section``   the r–z mesh (triangles or quadratic triangles as in the FEM),
              undeformed; point data ``displacement`` (u_r, u_z, 0),
              ``sigma_rr``, ``sigma_zz``, ``sigma_tt`` (hoop, σ_θθ),
              ``sigma_rz``, ``von_mises``, ``stress`` (the full symmetric tensor,
              9 components row by row, in the section's x, y, z frame), ``contact_pressure`` and
              ``wear_depth`` (zero off the contact nodes) and ``contact_node``
              (1 on the candidate contact nodes).
``solid``     (``revolve=N``) the same fields on the section revolved in N
              segments into a closed solid; ``displacement`` and ``stress`` are
              Cartesian (ParaView's tensor filters apply).
              Quadratic triangles are revolved as their four linear
              sub-triangles; cells are linear wedges, collapsing to pyramids
              (one node on the axis) and tetrahedra (an edge on the axis).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.extras import need
from wearcheck.cases import CaseError, WearcheckError
from wearcheck.cases.profiles import height, height_xy
from wearcheck.cases.schema import NON_AXISYMMETRIC

from wearcheck.outputs import atomic_directory
from wearcheck.rundir import Run

FIELD_KEYS = ("points", "cells", "displacement", "stress", "contact_nodes",
              "contact_pressure", "wear_depth")
#: segments of the revolved worn surface when no --revolve is given
SURFACE_SEGMENTS = 72

# VTK cell type ids (vtkCellType.h), so that the numerics need no VTK import
VTK_LINE, VTK_TRIANGLE, VTK_QUAD, VTK_TETRA, VTK_WEDGE, VTK_PYRAMID = 3, 5, 9, 10, 13, 14
VTK_QUADRATIC_TRIANGLE = 22


# -- numerics: arrays in, arrays out ---------------------------------------

def von_mises(stress):
    """Von Mises stress of axisymmetric stresses, hoop stress included.

    Parameters
    ----------
    stress : (..., 4) σ_rr, σ_zz, σ_θθ, σ_rz.
    """
    rr, zz, tt, rz = np.moveaxis(np.asarray(stress, dtype=float), -1, 0)
    return np.sqrt(0.5 * ((rr - zz) ** 2 + (zz - tt) ** 2 + (tt - rr) ** 2) + 3.0 * rz**2)


def signed_areas(points, triangles):
    """Signed areas in the (r, z) plane of the corner triangles (first three nodes)."""
    p = np.asarray(points, dtype=float)
    a, b, c = (p[triangles[:, i]] for i in range(3))
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
                  - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def orient_triangles(points, cells):
    """Reorder (Nt, 3) or (Nt, 6) triangles to be counter-clockwise in (r, z).

    A quadratic triangle (corners, then midsides 01, 12, 20) is reversed as
    (0, 2, 1, 20, 12, 01). Raises ``WearcheckError`` on a degenerate triangle.
    """
    cells = np.array(cells, dtype=np.int64)
    area = signed_areas(points, cells)
    if np.any(area == 0.0):
        raise WearcheckError(f"fields.npz: {np.count_nonzero(area == 0)} triangles of zero area")
    reverse = [0, 2, 1] if cells.shape[1] == 3 else [0, 2, 1, 5, 4, 3]
    flip = area < 0
    cells[flip] = cells[flip][:, reverse]
    return cells


def linear_subtriangles(cells):
    """The linear triangles of a mesh: (Nt, 3) as is, (Nt, 6) split into four each.

    The sub-triangles keep their parent's orientation.
    """
    cells = np.asarray(cells, dtype=np.int64)
    if cells.shape[1] == 3:
        return cells
    c0, c1, c2, m01, m12, m20 = cells.T
    return np.concatenate([np.column_stack(t) for t in
                           ((c0, m01, m20), (m01, c1, m12), (m20, m12, c2), (m01, m12, m20))])


def _rings(points, segments):
    """Numbering of the revolved points: node i, segment j -> start[i] + stride[i] j.

    stride is 1, or 0 for a node on the axis.

    Nodes with r <= 1e-12 max(r) are on the axis and appear once.
    Returns start, stride, xyz (P, 3), source (P,), theta (P,).
    """
    r, z = points[:, 0], points[:, 1]
    axis = r <= 1e-12 * np.max(np.abs(r))
    N = int(segments)
    stride = np.where(axis, 0, 1)
    count = np.where(axis, 1, N)
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    source = np.repeat(np.arange(len(points)), count)
    theta = 2.0 * np.pi * (np.arange(len(source)) - start[source]) / N
    rr = np.where(axis[source], 0.0, r[source])
    xyz = np.column_stack([rr * np.cos(theta), z[source], -rr * np.sin(theta)])
    return start, stride, xyz, source, theta


def _at(start, stride, nodes, jj):
    """Revolved point numbers of r–z nodes (n,) at segments jj (N,): (n, N)."""
    return start[nodes][:, None] + stride[nodes][:, None] * jj[None, :]


def revolve_mesh(points, triangles, segments):
    """Revolve counter-clockwise r–z triangles about the axis into a closed solid.

    Parameters
    ----------
    points : (Np, 2) r, z; nodes with r <= 1e-12 max(r) count as on the axis.
    triangles : (Nt, 3) linear triangles, counter-clockwise in (r, z).
    segments : number N >= 3 of equal angular segments.

    Returns
    -------
    xyz : (P, 3) points (r cos θ, z, -r sin θ); an axis node appears once,
        every other node N times.
    source : (P,) index of the r–z node each point comes from.
    theta : (P,) its angle θ (0 on the axis).
    cells : dict VTK cell type -> (n, k) connectivity: wedges, collapsing to
        pyramids (one node of the triangle on the axis) and tetrahedra (an
        edge on the axis); all of positive volume in VTK's convention.
    """
    if segments < 3:
        raise WearcheckError(f"revolving needs at least 3 segments, got {segments}")
    points = np.asarray(points, dtype=float)
    triangles = np.asarray(triangles, dtype=np.int64)
    start, stride, xyz, source, theta = _rings(points, segments)
    j = np.arange(segments)
    jn = (j + 1) % segments

    def at(nodes, jj):
        return _at(start, stride, nodes, jj)

    on = (stride == 0)[triangles]
    n_on = on.sum(axis=1)
    if np.any(n_on == 3):
        raise WearcheckError("a triangle lies entirely on the axis")
    cells = {}
    # turning towards -z puts the next segment behind a counter-clockwise
    # triangle (normal +z); VTK wants a wedge's first face to face its
    # second, hence (a, c, b)
    a, b, c = triangles[n_on == 0].T
    if len(a):
        cells[VTK_WEDGE] = np.stack([at(a, j), at(c, j), at(b, j),
                                     at(a, jn), at(c, jn), at(b, jn)], axis=-1).reshape(-1, 6)
    # rolling a triangle's nodes keeps its orientation: axis node first for
    # the pyramid (its apex), off-axis node last for the tetrahedron
    for n, kind in ((1, VTK_PYRAMID), (2, VTK_TETRA)):
        t = triangles[n_on == n]
        if not len(t):
            continue
        first = np.argmax(on[n_on == n], axis=1) if n == 1 else \
            (np.argmin(on[n_on == n], axis=1) + 1) % 3
        A, B, C = np.take_along_axis(t, (first[:, None] + np.arange(3)) % 3, axis=1).T
        if n == 1:
            nodes = [at(B, j), at(C, j), at(C, jn), at(B, jn), at(A, j)]
        else:
            nodes = [at(A, j), at(B, j), at(C, jn), at(C, j)]
        cells[kind] = np.stack(nodes, axis=-1).reshape(-1, len(nodes))
    return xyz, source, theta, cells


def revolve_vectors(v_rz, theta):
    """Cylindrical (v_r, v_z) at angles θ as Cartesian (v_r cos θ, v_z, -v_r sin θ)."""
    v_rz = np.asarray(v_rz, dtype=float)
    return np.column_stack([v_rz[:, 0] * np.cos(theta), v_rz[:, 1], -v_rz[:, 0] * np.sin(theta)])


def revolve_stress(stress, theta):
    """Axisymmetric stress (σ_rr, σ_zz, σ_θθ, σ_rz) at angles θ as Cartesian 3×3 tensors.

    With a point at (r cos θ, z, -r sin θ): e_r = (cos θ, 0, -sin θ), e_z = (0, 1, 0),
    e_θ = (-sin θ, 0, -cos θ), and σ = σ_rr e_r e_r + σ_zz e_z e_z + σ_θθ e_θ e_θ
    + σ_rz (e_r e_z + e_z e_r). At θ = 0 this is the section's own frame.
    """
    stress = np.asarray(stress, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    srr, szz, stt, srz = stress.T
    out = np.zeros((len(stress), 3, 3))
    out[:, 0, 0] = srr * c * c + stt * s * s
    out[:, 1, 1] = szz
    out[:, 2, 2] = srr * s * s + stt * c * c
    out[:, 0, 1] = out[:, 1, 0] = srz * c
    out[:, 1, 2] = out[:, 2, 1] = -srz * s
    out[:, 0, 2] = out[:, 2, 0] = -c * s * (srr - stt)
    return out.reshape(len(stress), 9)


def polyline(r, y):
    """Points (r, y, 0) and the line segments joining them in order."""
    r = np.asarray(r, dtype=float)
    xyz = np.column_stack([r, y, np.zeros_like(r)])
    n = len(r)
    return xyz, {VTK_LINE: np.column_stack([np.arange(n - 1), np.arange(1, n)])}


def revolve_curve(r, y, segments):
    """Surface of revolution of the curve (r, y), r >= 0 increasing.

    Returns points, cells (quads; triangles at a point on the axis) and
    ``source`` (P,), the curve index of each point.
    """
    start, stride, xyz, source, _ = _rings(np.column_stack([r, y]), segments)
    j = np.arange(segments)
    jn = (j + 1) % segments
    i0, i1 = np.arange(len(r) - 1), np.arange(1, len(r))
    axis = stride == 0
    quad = ~axis[i0] & ~axis[i1]
    tri = axis[i0] & ~axis[i1]

    def at(nodes, jj):
        return _at(start, stride, nodes, jj)

    # ordered so that the normals point to -y for a rising curve: out of
    # the indenter, whose material lies above its profile
    cells = {}
    if quad.any():
        cells[VTK_QUAD] = np.stack([at(i0[quad], j), at(i0[quad], jn), at(i1[quad], jn),
                                    at(i1[quad], j)], axis=-1).reshape(-1, 4)
    if tri.any():
        cells[VTK_TRIANGLE] = np.stack([at(i0[tri], j), at(i1[tri], jn), at(i1[tri], j)],
                                       axis=-1).reshape(-1, 3)
    return xyz, cells, source


# -- fields of a run -------------------------------------------------------

def check_fields(fields, n_stages):
    """Raise ``CaseError`` (a damaged run, exit 2) unless ``fields`` has the FEM keys and
    shapes, and finite values."""
    missing = [k for k in FIELD_KEYS if k not in fields]
    if missing:
        raise CaseError(f"fields.npz lacks {missing}")
    Np = len(fields["points"])
    Nc = len(fields["contact_nodes"])
    want = dict(points=(Np, 2), displacement=(n_stages, Np, 2), stress=(n_stages, Np, 4),
                contact_pressure=(n_stages, Nc), wear_depth=(n_stages, Nc))
    for key, shape in want.items():
        if np.shape(fields[key]) != shape:
            raise CaseError(f"fields.npz: '{key}' has shape {np.shape(fields[key])}, "
                            f"expected {shape}")
        bad = int(np.size(fields[key]) - np.count_nonzero(np.isfinite(fields[key])))
        if bad:  # a run never stores one: damage, which would draw as nothing
            raise CaseError(f"fields.npz is damaged: '{key}' holds {bad} values that are not "
                            "finite (NaN or infinite)")
    cells = fields["cells"]
    if np.ndim(cells) != 2 or np.shape(cells)[1] not in (3, 6):
        raise CaseError(f"fields.npz: 'cells' has shape {np.shape(cells)}, "
                        "expected (Nt, 3) or (Nt, 6)")
    for key in ("cells", "contact_nodes"):
        index = np.asarray(fields[key])
        if index.size and not (index.min() >= 0 and index.max() < Np):
            raise CaseError(f"fields.npz: '{key}' refers to nodes outside 0..{Np - 1}")


def section_data(fields, k):
    """Point data of stage k on the r–z mesh (arrays named as in the VTU files)."""
    Np = len(fields["points"])
    nodes = fields["contact_nodes"]
    stress = np.asarray(fields["stress"][k], dtype=float)
    u = np.asarray(fields["displacement"][k], dtype=float)
    data = dict(displacement=np.column_stack([u, np.zeros(Np)]),
                sigma_rr=stress[:, 0], sigma_zz=stress[:, 1], sigma_tt=stress[:, 2],
                sigma_rz=stress[:, 3], von_mises=von_mises(stress),
                stress=revolve_stress(stress, np.zeros(Np)))
    for key in ("contact_pressure", "wear_depth"):
        full = np.zeros(Np)
        full[nodes] = fields[key][k]
        data[key] = full
    marker = np.zeros(Np, dtype=np.uint8)
    marker[nodes] = 1
    data["contact_node"] = marker
    return data


def unworn_profile(run: Run, r):
    """The case's unworn profile f0(r) [m], as the run's stages hold it.

    A body of revolution is f(r). A non-axisymmetric one (the ellipsoid) is
    stored as ring averages over the angle by a solver that solves it as it is,
    and as the equivalent body of revolution by one that solved an
    approximation (``info["approximate"]``, the MDR): the unworn reference must
    be the same, or the wear depth (f - f0) shows wear where there is none
    (0.4 µm, 40 % of d, at the rim of the ellipsoid's BEM picture).
    """
    ind = run.case.indenter
    r = np.asarray(r, dtype=float)
    if ind.profile not in NON_AXISYMMETRIC or run.meta.get("info", {}).get("approximate"):
        return height(ind, r, run.case.table)
    theta = np.linspace(0.0, 2.0 * np.pi, 720, endpoint=False)
    x, y = np.multiply.outer(r, np.cos(theta)), np.multiply.outer(r, np.sin(theta))
    return height_xy(ind, x, y, run.case.table).mean(axis=-1)


#: units of the point arrays the series write ("" dimensionless)
UNITS = dict(f="m", wear_depth="m", pressure="Pa", p_over_p0="", r="m", shear_traction="Pa",
             displacement="m", sigma_rr="Pa", sigma_zz="Pa", sigma_tt="Pa", sigma_rz="Pa",
             von_mises="Pa", stress="Pa", contact_pressure="Pa", contact_node="",
             profile="m", gap="m")


def nice_factor(x: float) -> float:
    """The largest of 1, 2, 5 times a power of ten not above x (x > 0)."""
    e = np.floor(np.log10(x))
    m = x / 10.0**e
    return float((5.0 if m >= 5 else 2.0 if m >= 2 else 1.0) * 10.0**e)


def warp_scale(r, f) -> float:
    """A round factor that draws heights ``f`` (K, M) over radii ``r`` at about half
    the radius span (1 when the surface has no relief)."""
    span = float(np.ptp(np.asarray(f, float)))
    extent = float(np.ptp(np.asarray(r, float)))
    return nice_factor(0.5 * extent / span) if span > 0 and extent > 0 else 1.0


def units_of(names) -> np.ndarray:
    """The units of the arrays ``names`` (``UNITS``; "?" for one it does not know) as
    UTF-8 bytes of a JSON object, the field data ``units``: read it back with
    ``json.loads(bytes(array))``."""
    import json
    text = json.dumps({n: UNITS.get(n, "?") for n in names}, ensure_ascii=False)
    return np.frombuffer(text.encode("utf-8"), dtype=np.uint8).copy()


def read_units(array) -> dict:
    """The ``units`` field data of a file written here, as a dict."""
    import json
    return json.loads(bytes(np.asarray(array, dtype=np.uint8).ravel()).decode("utf-8"))


def stage_field_data(run: Run, k):
    s = float(run.stages["s"][k])
    return dict(s=[s], s_hat=[float(run.stages["s_hat"][k])], stage=[k], TimeValue=[s],
                warp_scale=[warp_scale(run.stages["r"], run.stages["f"])])


# -- writing ---------------------------------------------------------------

def grid(xyz, cells):
    """pyvista UnstructuredGrid from points and {VTK cell type: connectivity}."""
    pv = need("pyvista", "writing ParaView files")
    return pv.UnstructuredGrid({int(t): np.asarray(c, dtype=np.int64) for t, c in cells.items()},
                               np.asarray(xyz, dtype=float))


def _save(mesh, path, point_data, field_data):
    mesh.clear_data()
    for name, values in point_data.items():
        mesh.point_data[name] = values
    for name, values in field_data.items():
        mesh.field_data[name] = np.asarray(values)
    mesh.field_data["units"] = units_of(point_data)
    mesh.save(path)


def pvd_text(entries):
    """XML of a ParaView collection; entries are (time, file name) pairs."""
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    lines += [f'    <DataSet timestep="{float(t)!r}" group="" part="0" file="{name}"/>'
              for t, name in entries]
    lines += ["  </Collection>", "</VTKFile>", ""]
    return "\n".join(lines)


def _series(directory, name, mesh, run, data_of_stage):
    entries = []
    for k in range(len(run.stages["s"])):
        file = f"{name}_{k:03d}.vtu"
        _save(mesh, directory / file, data_of_stage(k), stage_field_data(run, k))
        entries.append((run.stages["s"][k], file))
    # plain writes: the caller builds the whole directory before renaming it
    (directory / f"{name}.pvd").write_text(pvd_text(entries), encoding="utf-8")
    return directory / f"{name}.pvd"


def write_vtk_files(directory, run: Run, revolve: int = 0) -> list[Path]:
    """Write every series of ``run`` into ``directory``; returns the .pvd paths."""
    directory = Path(directory)
    st = run.stages
    if not len(st["s"]):
        return []  # an empty collection would be a time series without times
    r, f, p = st["r"], st["f"], st["p"]
    f0 = unworn_profile(run, r)
    p0 = run.scales["p0"]
    out = []

    xyz, cells = polyline(r, np.zeros_like(r))
    mesh = grid(xyz, cells)

    tau = st.get("tau")  # shear traction of a fretting run

    def with_tau(data, k, index=slice(None)):
        if tau is not None:
            data["shear_traction"] = tau[k][index]
        return data

    def profile(k):
        mesh.points = np.column_stack([r, f[k], np.zeros_like(r)])
        return with_tau(dict(f=f[k], wear_depth=f[k] - f0, pressure=p[k]), k)

    out.append(_series(directory, "profile", mesh, run, profile))
    mesh = grid(xyz, cells)
    out.append(_series(directory, "pressure", mesh, run,
                       lambda k: dict(pressure=p[k], p_over_p0=p[k] / p0, r=r)))

    segments = revolve if revolve > 0 else SURFACE_SEGMENTS
    xyz, cells, source = revolve_curve(r, np.zeros_like(r), segments)
    mesh = grid(xyz, cells)

    def surface(k):
        mesh.points = np.column_stack([xyz[:, 0], f[k][source], xyz[:, 2]])
        return with_tau(dict(f=f[k][source], wear_depth=(f[k] - f0)[source],
                             pressure=p[k][source]), k, source)

    out.append(_series(directory, "surface", mesh, run, surface))

    export = _solver_export(run.solver)
    if export is not None and run.fields is not None:
        out += export(directory, run, revolve=revolve)
    return out


def _solver_export(name: str):
    """The registry's VTK writer for a solver's own fields (None: none)."""
    import importlib

    from wearcheck import registry
    try:
        target = registry.get(name).export_vtk
    except CaseError:
        return None
    if target is None:
        return None
    module, _, function = target.partition(":")
    return getattr(importlib.import_module(module), function)


def write_fem_fields(directory, run: Run, revolve: int = 0) -> list[Path]:
    """The FEM's own series: ``section`` (and ``solid`` with ``revolve``); .pvd paths."""
    fields = run.fields
    check_fields(fields, len(run.stages["s"]))
    out = []
    points = np.asarray(fields["points"], dtype=float)
    cells = orient_triangles(points, fields["cells"])
    kind = VTK_TRIANGLE if cells.shape[1] == 3 else VTK_QUADRATIC_TRIANGLE
    mesh = grid(np.column_stack([points, np.zeros(len(points))]), {kind: cells})
    out.append(_series(directory, "section", mesh, run, lambda k: section_data(fields, k)))
    if revolve > 0:
        xyz, source, theta, cells3 = revolve_mesh(points, linear_subtriangles(cells), revolve)
        mesh = grid(xyz, cells3)

        def solid(k):
            data = {name: v[source] for name, v in section_data(fields, k).items()}
            data["displacement"] = revolve_vectors(fields["displacement"][k][source], theta)
            data["stress"] = revolve_stress(fields["stress"][k][source], theta)
            return data

        out.append(_series(directory, "solid", mesh, run, solid))
    return out


def export_run(run_dir, revolve: int = 0) -> Path:
    """Write ``RUN_DIR/vtk/`` for a run directory, atomically; returns its path.

    Parameters
    ----------
    run_dir : a complete run directory (``wearcheck.rundir.Run`` reads it).
    revolve : N > 0 also writes the FEM fields revolved in N segments
        (``solid`` series); ignored for runs without fields. N is also the
        number of segments of the worn surface (default ``SURFACE_SEGMENTS``).
    """
    if revolve < 0 or 0 < revolve < 3:
        raise CaseError(f"--revolve {revolve}: need 0 (no solid) or at least 3 segments")
    need("pyvista", "writing ParaView files")
    run = Run(run_dir)
    target = run.path / "vtk"
    from wearcheck.resources import check_export
    # the FEM's section mesh is what a revolution multiplies; other fields are small
    check_export(len(run.fields["points"]) if run.fields and "points" in run.fields else 0,
                 len(run.stages["r"]), revolve or SURFACE_SEGMENTS, len(run.stages["s"]),
                 run.path)
    with atomic_directory(target, "vtk") as tmp:
        write_vtk_files(tmp, run, revolve)
    return target
