"""The condensed sphere: compliance, areas, exported fields; bad FEM input."""

import math

import numpy as np
import pytest

from wearcheck import cases
from wearcheck import fem
from wearcheck import meshes
from wearcheck.cases import CaseError, reference
from wearcheck.fem.model import build

R, E, NU = 0.01, 210e9, 0.3


@pytest.fixture(autouse=True)
def _mesh_cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("WEARCHECK_CACHE", str(tmp_path_factory.getbasetemp() / "meshes"))


@pytest.fixture(scope="module", params=[1, 2])
def model(request, tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("WEARCHECK_CACHE", str(tmp_path_factory.getbasetemp() / "meshes"))
    order = request.param
    params = meshes.SphereMeshParameters(radius=R, contact_radius=1.77e-4, contact_edges=20,
                                         growth=fem.solver.GROWTH[order])
    m = build(meshes.sphere_mesh(params), E, NU, order)
    m.compliance()
    yield m
    mp.undo()


def test_compliance_is_symmetric_positive_definite(model):
    # Maxwell-Betti: the condensed compliance is symmetric before the solver
    # symmetrises it (asymmetry = round-off of the sparse solves, < 1e-10);
    # strain energy > 0 for any load: all eigenvalues positive.
    assert model.timings["compliance_asymmetry"] < 1e-10
    assert np.array_equal(model.C, model.C.T)
    assert np.linalg.eigvalsh(model.C).min() > 0


def test_compliance_matches_boussinesq_ring_load(model):
    # Half-space: a ring load F of radius ρ lifts the centre by
    # (1-ν²) F / (π E ρ). The clamped finite sphere lowers that by a nearly
    # uniform O(1/(E R)) (measured 0.3/(E R) far out); the discretisation
    # of the point-like load matters within a few node spacings (measured
    # 1.5 % at ρ = 4h). Require 2 % for ρ >= 4h, and agreement within
    # 0.5/(E R) (~2 % of the ring compliance at ρ = a0) for ρ >= 10h.
    r = model.r
    h = np.mean(np.diff(r))
    ring = (1 - NU**2) / (math.pi * E * np.where(r > 0, r, np.inf))
    near, far = r >= 4 * h, r >= 10 * h
    assert np.max(np.abs(model.C[0, near] / ring[near] - 1)) < 0.02
    assert np.max(np.abs(model.C[0, far] - ring[far])) < 0.5 / (E * R)


def test_lumped_areas(model):
    # Σ ∫φ_i 2πr ds = ∫ 2πr ds over the arc = area of the spherical cap
    # 2πR(R - sqrt(R² - rc²)); the revolved chord polygon differs by
    # O((h/R)²) relative (h: element length; 8.9e-6 m here, (h/R)² = 8e-7).
    rc = model.r[-1]
    h = rc / 20
    cap = 2 * math.pi * R * (R - math.sqrt(R**2 - rc**2))
    assert abs(model.area_rowsum.sum() - cap) < 2 * (h / R) ** 2 * cap
    if model.order == 2:
        # the documented fact: the P2 node on the axis has zero r-weighted area
        assert abs(model.area_rowsum[0]) < 1e-12 * model.area_rowsum[1]
    assert np.all(model.area_rowsum[model.order - 1:] > 0)


def test_fields_for_export():
    case = cases.load(cases.shipped("hertz"), ["fem.contact_nodes=41"])
    res = fem.solve(case)
    fl = res.fields
    assert set(fl) == {"points", "cells", "displacement", "stress", "contact_nodes",
                       "contact_pressure", "wear_depth"}
    pts, cells = fl["points"], fl["cells"]
    K, Np, Nc = len(res.stage_s), len(pts), len(res.r)
    assert cells.shape[1] == 6 and fl["displacement"].shape == (K, Np, 2)
    assert fl["stress"].shape == (K, Np, 4) and fl["contact_pressure"].shape == (K, Nc)
    assert fl["wear_depth"].shape == (K, Nc)
    # counter-clockwise triangles; midside nodes at the edge midpoints in
    # meshio triangle6 order (01, 12, 20)
    p = pts[cells]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    assert np.all(area > 0)
    for k, (i, j) in enumerate([(0, 1), (1, 2), (2, 0)]):
        assert np.allclose(p[:, 3 + k], 0.5 * (p[:, i] + p[:, j]), rtol=0, atol=1e-15)
    # contact nodes: on the sphere, by increasing r, the radii of the stages
    cn = pts[fl["contact_nodes"]]
    assert np.allclose(cn[:, 0], res.r) and np.all(np.diff(res.r) > 0)
    assert np.allclose(np.hypot(cn[:, 0], cn[:, 1] - R), R, rtol=0, atol=1e-9)
    # the top face moved down by the approach
    top = np.isclose(pts[:, 1], R)
    assert np.allclose(fl["displacement"][0, top, 1], -case.loading.depth, rtol=1e-12)
    assert np.allclose(fl["displacement"][0, top, 0], 0.0)
    # surface stress at the pole against Hertz (Johnson 1985, §4.2):
    # σ_zz = -p0, σ_rr = σ_θθ = -(1+2ν)/2 p0. Nodal L2 projection of
    # piecewise-linear stresses at a boundary node: within 5 % p0.
    sc = reference.scales(case)
    p0 = 2 * sc["E_star"] * sc["a0"] / (math.pi * R)
    pole = np.flatnonzero(np.all(pts == 0.0, axis=1))[0]
    s = fl["stress"][0, pole]
    assert abs(s[1] + p0) < 0.05 * p0
    assert abs(s[0] + (1 + 2 * NU) / 2 * p0) < 0.05 * p0
    assert abs(s[2] - s[0]) < 0.01 * p0


@pytest.mark.parametrize("overrides,match", [
    (["fem.contact_nodes=0"], r"fem\.contact_nodes.*>= 2"),
    (["fem.contact_nodes=5"], r"fem\.contact_nodes.*= 5.*at least"),
    (["fem.contact_factor=0.5"], r"fem\.contact_factor.*= 0\.5.*inside the unworn contact"),
    (["counterface.rigid=false", "counterface.youngs_modulus=2e11",
      "counterface.poisson_ratio=0.3"], r"counterface\.rigid.*rigid plane"),
    (["indenter.rigid=true", "counterface.rigid=false", "counterface.youngs_modulus=2e11",
      "counterface.poisson_ratio=0.3"], r"counterface\.rigid|indenter\.rigid"),
    (["indenter.poisson_ratio=0.5"], r"indenter\.poisson_ratio.*= 0\.5.*<= 0\.495"),
    (["sliding.distance=1e300"], r"sliding\.distance.*1e\+300.*cap"),
])
def test_bad_fem_input_is_rejected(overrides, match):
    case_path = cases.shipped("hertz")
    if any(o.startswith("indenter.rigid") for o in overrides):
        # a rigid indenter must not carry elastic constants
        raw = {"indenter": {"profile": "sphere", "radius": R, "rigid": True},
               "counterface": {"rigid": False, "youngs_modulus": 2e11, "poisson_ratio": 0.3},
               "loading": {"control": "depth", "depth": 1e-6},
               "wear": {"k": 1e-4, "mu": 0.3, "hardness": 2e9},
               "sliding": {"until": "distance", "distance": 0.0}}
        with pytest.raises(CaseError, match=match):
            fem.solve(cases.from_dict(raw))
        return
    with pytest.raises(CaseError, match=match):
        fem.solve(cases.load(case_path, overrides))


def test_rigid_indenter_and_missing_radius_are_rejected():
    raw = {"indenter": {"profile": "sphere", "radius": R, "rigid": True},
           "counterface": {"rigid": False, "youngs_modulus": 2e11, "poisson_ratio": 0.3},
           "loading": {"control": "depth", "depth": 1e-6},
           "wear": {"k": 1e-4, "mu": 0.3, "hardness": 2e9},
           "sliding": {"until": "distance", "distance": 0.0}}
    # both faults are reported; the counterface is checked first
    with pytest.raises(CaseError, match=r"counterface\.rigid"):
        fem.solve(cases.from_dict(raw))
    raw["counterface"] = {"rigid": True}
    raw["indenter"] = {"profile": "sphere", "radius": R, "rigid": True}
    with pytest.raises(CaseError, match=r"indenter\.rigid"):
        fem.solve(cases.from_dict(raw))
    raw["indenter"] = {"profile": "cone", "slope_angle": 0.01, "youngs_modulus": E,
                       "poisson_ratio": NU}
    with pytest.raises(CaseError, match=r"indenter\.radius"):
        fem.solve(cases.from_dict(raw))


def test_schur_and_column_compliance_agree(model):
    # The Schur complement read off the contact-last LU and one sparse solve
    # per contact node are two routes to the same matrix: round-off (1e-12).
    assert model.timings["compliance_method"] == "schur"
    other = build(meshes.sphere_mesh(meshes.SphereMeshParameters(
        radius=R, contact_radius=1.77e-4, contact_edges=20,
        growth=fem.solver.GROWTH[model.order])), E, NU, model.order)
    other.factorise(contact_last=False)
    C = other.compliance("columns")
    assert other.timings["compliance_method"] == "columns"
    assert np.max(np.abs(C - model.C)) < 1e-12 * np.max(model.C)


def _blas_threads():
    from threadpoolctl import threadpool_info

    return [(m["filepath"], m["num_threads"]) for m in threadpool_info()
            if m["user_api"] == "blas"]


def test_solve_runs_single_threaded_blas_and_restores_thread_counts():
    # fem.solve limits BLAS to one thread (threadpoolctl) while it runs and
    # restores every library's count afterwards, also when it fails. The
    # outer limit of 2 makes "before" differ from 1 on any machine that lets
    # OpenBLAS use 2 threads, so that a restore to 1 would be caught.
    from threadpoolctl import threadpool_limits

    case = cases.load(cases.shipped("hertz"), ["fem.contact_nodes=41"])
    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        assert before, "no BLAS library found by threadpoolctl"
        inside = []
        fem.solve(case, progress=lambda frac, text: inside.append(_blas_threads()))
        assert _blas_threads() == before
        assert inside and all(n == 1 for seen in inside for _path, n in seen)
        with pytest.raises(CaseError):
            fem.solve(cases.load(cases.shipped("hertz"), ["fem.contact_nodes=5"]))
        assert _blas_threads() == before
