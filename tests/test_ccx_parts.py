"""The CalculiX solver's parts that need no CalculiX: numbers in decks, the CAX6 sphere,
reading .dat and .frd text, failure detection, supports() and the [ccx] keys."""

import math
import stat

import numpy as np
import pytest

from wearcheck import cases, meshes
from wearcheck.cases import CaseError, SolverError, validity
from wearcheck.ccx import deck, model, output, run, solver

PAPER = cases.shipped("paper")


@pytest.fixture(autouse=True)
def _mesh_cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("WEARCHECK_CACHE", str(tmp_path_factory.getbasetemp() / "meshes"))


@pytest.mark.parametrize("x", [0.0, 1.0, -1.2345678901234567e-12, 0.1 + 0.2, 210000.0,
                               6.02214076e23, -1e-300, 1.7976931348623157e308])
def test_numbers_fit_calculix_fields_with_most_digits(x):
    text = deck.number(x)
    # CalculiX refuses a field of more than 20 characters (measured: *NODE and *GAP);
    # 20 characters hold 14-16 significant digits, a relative error below 1e-13
    assert len(text) <= 20
    assert float(text) == pytest.approx(x, rel=1e-13, abs=0.0)


def test_a_number_that_is_not_finite_is_refused():
    with pytest.raises(ValueError, match="cannot write"):
        deck.number(math.nan)


@pytest.fixture(scope="module")
def sphere(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("WEARCHECK_CACHE", str(tmp_path_factory.getbasetemp() / "meshes"))
    case = cases.load(PAPER, ["ccx.contact_nodes=21"])
    sm = meshes.sphere_mesh(solver.mesh_parameters(case))
    yield sm, model.cax6_sphere(sm)
    mp.undo()


def test_cax6_sphere_numbers_the_contact_nodes_first_by_radius(sphere):
    sm, sp = sphere
    nc = len(sp.contact)
    assert nc == 21 and np.array_equal(sp.contact, np.arange(nc))
    assert sp.r[0] == 0.0 and np.all(np.diff(sp.r) > 0)
    # every contact node lies on the arc's chords: vertices on the sphere, midside nodes
    # on the chord midpoints (the FEM's P2 geometry on the same mesh)
    R = 0.01
    dist = np.hypot(sp.points[sp.contact, 0], sp.points[sp.contact, 1] - R)
    assert np.allclose(dist[::2], R, rtol=1e-12)
    assert np.allclose(sp.points[sp.contact[1::2]],
                       0.5 * (sp.points[sp.contact[:-1:2]] + sp.points[sp.contact[2::2]]))
    # the corners of each CAX6 element counter-clockwise, midside nodes on the edges
    p = sp.points[sp.elements]
    signed = ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
              - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    assert np.all(signed > 0)
    assert np.allclose(p[:, 3], 0.5 * (p[:, 0] + p[:, 1]))
    assert np.allclose(p[:, 4], 0.5 * (p[:, 1] + p[:, 2]))
    assert np.allclose(p[:, 5], 0.5 * (p[:, 2] + p[:, 0]))
    assert len(sp.points) == len(sm.points) + len(np.unique(
        np.sort(np.concatenate([sm.triangles[:, [0, 1]], sm.triangles[:, [1, 2]],
                                sm.triangles[:, [2, 0]]]), axis=1), axis=0))


def test_lumped_areas_add_up_to_the_revolved_chords(sphere):
    _, sp = sphere
    # Σ_i ∫ φ_i 2πr ds = ∫ 2πr ds (the shape functions sum to one): the surface of the
    # chords revolved about the axis, π (r_a + r_b) L per chord (a frustum), exactly
    corners = sp.points[sp.contact[::2]]
    L = np.hypot(*np.diff(corners, axis=0).T)
    frusta = np.sum(math.pi * (corners[:-1, 0] + corners[1:, 0]) * L)
    assert np.sum(sp.area) == pytest.approx(frusta, rel=1e-13)
    # the node on the axis has none (r = 0 where its shape function lives): round-off only
    assert abs(sp.area[0]) < 1e-12 * sp.area.max() and np.all(sp.area[1:] > 0)
    # a corner node between two equal chords far from the axis: its weight is 1/3 of the
    # two chords' ring areas (Simpson's weights 1/6, 4/6, 1/6 of each quadratic edge)
    i = 10
    assert sp.area[i] == pytest.approx(2 * math.pi * sp.r[i] * L[i // 2] / 3, rel=2e-3)


DAT = """
                    E I G E N V A L U E    N U M B E R     1


 displacements (vx,vy,vz) for set LOADED and time  0.1000000E+01

         2  0.000000E+00  2.071229E-06  0.000000E+00
         3 -9.175516E-08  4.778793-100  0.000000E+00

 total force (fx,fy,fz) for set TOP and time  0.1000000E+01

        2.480972E-02  5.000000E-02 -2.288424E-14
"""


def test_dat_blocks_read_prints_green_functions_and_fortran_exponents():
    blocks = output.dat_blocks(DAT)
    assert [(b.quantity, b.set, b.mode) for b in blocks] == [("displacements", "LOADED", 1),
                                                            ("total force", "TOP", 1)]
    u = blocks[0]
    assert u.components == ("vx", "vy", "vz") and u.time == 1.0
    assert np.array_equal(u.ids, [2, 3])
    # Fortran drops the E of a three-digit exponent: 4.778793-100 is 4.778793e-100
    assert u.values[1, 1] == 4.778793e-100 and u.values[0, 1] == 2.071229e-06
    assert blocks[1].ids is None and blocks[1].values.tolist() == [[2.480972e-02, 5e-02,
                                                                    -2.288424e-14]]


def test_a_damaged_dat_line_is_named():
    with pytest.raises(SolverError, match=r"job.dat, line 7: expected 4 numbers"):
        output.dat_blocks(DAT.replace("  0.000000E+00\n         3", "\n         3"), "job.dat")


FRD = (
    "    1C\n"
    "    2C                             2                                     1\n"
    " -1         1 1.00000E+00 2.00000E+00 0.00000E+00\n"
    " -1         2 3.00000E+00-4.00000E+00 0.00000E+00\n"
    " -3\n"
    "    1PSTEP                         1           1           1\n"
    "  100CL  101 1.000000000           2                     0    1           1\n"
    " -4  DISP        4    1\n"
    " -5  D1          1    2    1    0\n"
    " -5  D2          1    2    2    0\n"
    " -5  D3          1    2    3    0\n"
    " -5  ALL         1    2    0    0    1ALL\n"
    " -1         1-1.00000E-03 2.00000E-03 0.00000E+00\n"
    " -1         2 4.00000E-03-5.00000E-03 0.00000E+00\n"
    " -3\n"
    "  100CL  101 1.000000000           2                     0    1           1\n"
    " -4  STRESS      6    1\n"
    " -5  SXX         1    4    1    1\n -5  SYY         1    4    2    2\n"
    " -5  SZZ         1    4    3    3\n -5  SXY         1    4    1    2\n"
    " -5  SYZ         1    4    2    3\n -5  SZX         1    4    3    1\n"
    " -1         1 1.00000E+00 2.00000E+00 3.00000E+00 4.00000E+00 5.00000E+00 6.00000E+00\n"
    " -1         2-1.00000E+00-2.00000E+00-3.00000E+00-4.00000E+00-5.00000E+00-6.00000E+00\n"
    " -3\n"
    " 9999\n")


def test_frd_nodal_results_with_fields_that_run_together(tmp_path):
    path = tmp_path / "job.frd"
    path.write_text(FRD)
    nodes, results = output.read_frd(path)
    assert nodes == {1: (1.0, 2.0, 0.0), 2: (3.0, -4.0, 0.0)}
    assert [(b.name, b.step, b.time) for b in results] == [("DISP", 1, 1.0), ("STRESS", 1, 1.0)]
    assert results[0].components == ("D1", "D2", "D3")
    assert results[0].values.tolist() == [[-1e-3, 2e-3, 0.0], [4e-3, -5e-3, 0.0]]
    # into wearcheck's fields: mm -> m, MPa -> Pa, (x, y, z) = (r, z, θ): σ_rr σ_zz σ_θθ σ_rz
    disp, stress = output.stage_fields(results, 2)
    assert disp.tolist() == [[-1e-6, 2e-6], [4e-6, -5e-6]]
    assert stress.tolist() == [[1e6, 2e6, 3e6, 4e6], [-1e6, -2e6, -3e6, -4e6]]
    with pytest.raises(SolverError, match="lacks STRESS"):
        output.stage_fields(results[:1], 2)
    path.write_text(FRD.replace(" -3\n 9999", ""))
    with pytest.raises(SolverError, match=r"job.frd, line 2\d: not a readable .frd record"):
        output.read_frd(path)


def test_failure_of_reads_calculix_s_inconsistent_signals():
    # an input file it cannot open: return code 0 with an *ERROR line (measured, 2.20)
    assert "cannot open file" in run.failure_of(0, " *ERROR in readinput: cannot open file "
                                                   "job.inp\n")
    assert "return code 201" in run.failure_of(201, " *ERROR: too many cutbacks\n best so far\n")
    assert "best so far" in run.failure_of(201, " *ERROR: too many cutbacks\n best so far\n")
    # a crash (the singular matrix of an unconstrained node: 255; *RESTART,READ: 139)
    assert "crash" in run.failure_of(139, "no error printed\n")
    assert run.failure_of(0, " Job finished\n") is None


def _fake_ccx(tmp_path, version):
    exe = tmp_path / "ccx"
    exe.write_text(f"#!/bin/sh\necho\necho 'This is Version {version}'\nexit 201\n")
    exe.chmod(exe.stat().st_mode | stat.S_IXUSR)
    return str(exe)


def test_supports_names_why_calculix_cannot_run(tmp_path):
    case = cases.load(PAPER)
    missing = case.derive({"ccx.executable": str(tmp_path / "nowhere" / "ccx")})
    reason = solver.supports(missing)
    assert "'ccx.executable'" in reason and "apt-get install calculix-ccx" in reason
    old = case.derive({"ccx.executable": _fake_ccx(tmp_path, "2.17")})
    assert "CalculiX 2.17; wearcheck needs 2.20 or later" in solver.supports(old)
    (tmp_path / "new").mkdir()
    assert solver.supports(case.derive({"ccx.executable": _fake_ccx(tmp_path / "new",
                                                                    "2.21")})) is None
    in_loop = case.derive({"ccx.mode": "in_loop"})
    assert "'sliding.scheme' = \"adaptive\"" in solver.supports(in_loop)
    elastic = case.derive({"counterface.rigid": False, "counterface.youngs_modulus": 1e11,
                           "counterface.poisson_ratio": 0.3})
    assert "rigid plane" in solver.supports(elastic)


@pytest.mark.parametrize("key, value, message", [
    ("ccx.mode", "loop", 'must be one of "superelement", "in_loop"'),
    ("ccx.contact_nodes", 1, "must be >= 2"),
    ("ccx.contact_factor", 0, "must be > 0"),
    ("ccx.executable", 3, "must be a string"),
    ("ccx.nodes", 3, "unknown key 'ccx.nodes'"),
])
def test_bad_ccx_keys_are_named(key, value, message):
    with pytest.raises(CaseError, match=f"'{key}'.*{message}|{message}"):
        cases.load(PAPER).derive({key: value})


def test_a_contact_arc_too_coarse_is_refused_with_the_count_that_would_do():
    case = cases.load(PAPER, ["ccx.contact_nodes=5"])
    with pytest.raises(CaseError, match=r"'ccx.contact_nodes' = 5: .* ccx.contact_nodes >= "):
        solver.mesh_parameters(case)


def test_a_run_past_the_ball_s_equator_is_refused_as_by_the_other_solvers():
    # cases.validity.check_planned, the refusal every solver makes before its run
    # (tests/test_validity.py), before CalculiX is looked for or a mesh is made
    case = cases.load(cases.shipped("ball_on_flat"), ["loading.force=500", "wear.k=6e-3"])
    with pytest.raises(CaseError) as err:
        solver.mesh_parameters(case)
    with pytest.raises(CaseError) as fem_err:
        validity.check_planned(case, fem_sphere=True)
    assert str(err.value) == str(fem_err.value)
    assert str(err.value).startswith("key 'sliding.cycles' = 1000000.0: the run would wear "
                                     "the sphere past its equator")
