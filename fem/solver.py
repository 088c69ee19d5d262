"""``solve(case)``: the FEM counterpart of the MDR solver, from case to RunResult."""

from __future__ import annotations

import math
import time

import numpy as np
from threadpoolctl import threadpool_limits

from wearcheck import meshes
from wearcheck.cases import CaseError, SolverError, RunResult, programme, reference, validity
from wearcheck.cases.profiles import height
from wearcheck.numerics import stepping, superelement

from .model import build

#: growth of the element size away from the contact arc, per element order:
#: linear triangles need a gentler grading for the same bulk compliance; each
#: value brings the Hertz force near its converged value
#: (docs/performance.md, "Measurements behind the code", ``GROWTH``)
GROWTH = {1: 0.05, 2: 0.25}
#: implicit Euler step in ŝ when sliding.step_hat = "auto": chosen for speed,
#: its time error (first order in Δŝ) stays above the default mesh's spatial
#: error; bdf2 is the accurate choice (docs/performance.md, "Measurements
#: behind the code", ``IMPLICIT_AUTO_STEP_HAT``)
IMPLICIT_AUTO_STEP_HAT = 0.02
#: bdf2 step in ŝ when sliding.step_hat = "auto", chosen for accuracy: its
#: time error is well below the default mesh's spatial error, in little more
#: time than implicit Euler; a larger step would bring the two errors close, a
#: smaller one double the steps for little (docs/performance.md, "Measurements
#: behind the code", ``BDF2_AUTO_STEP_HAT``)
BDF2_AUTO_STEP_HAT = 0.01
#: fewest arc nodes required inside the unworn contact radius
MIN_NODES_IN_CONTACT = 5

#: largest Poisson ratio before volumetric locking shows (see check_case)
MAX_POISSON_RATIO = 0.495


def supports(case) -> str | None:
    """None when this FEM model can represent ``case``, else the reason it cannot."""
    if getattr(case, "fretting", None) is not None:
        return ("fretting (partial slip) needs a one-directional tangential load, which the "
                "axisymmetric FEM cannot carry; use the MDR solver")
    ind, cf = case.indenter, case.counterface
    if cf.wears:
        return ("counterface.wears = true: the FEM wears the sphere only (a wear track on "
                "the counterface is not axisymmetric); use the BEM")
    if ind.profile == "ellipsoid":
        return ("indenter.profile = \"ellipsoid\": the FEM is axisymmetric and cannot "
                "represent an ellipsoid; use the BEM (or the MDR, approximately)")
    if ind.radius is None:
        return (f"the FEM needs 'indenter.radius' (the radius of the FEM sphere) for "
                f"profile \"{ind.profile}\"; it is not given")
    if not cf.rigid:
        return ("counterface.rigid = false: the FEM models an elastic sphere against a "
                "rigid plane (node-to-node contact with the plane); set "
                "counterface.rigid = true or use the MDR solver")
    if ind.rigid:
        return ("indenter.rigid = true: the FEM body is the elastic sphere; a rigid "
                "indenter has nothing to deform (use the MDR solver)")
    if ind.poisson_ratio > MAX_POISSON_RATIO:
        # displacement elements lock volumetrically as ν → 0.5 (0.5 divides by 0); the
        # limit is where the Hertz force still holds (docs/performance.md,
        # "Measurements behind the code", ``MAX_POISSON_RATIO``)
        return (f"key 'indenter.poisson_ratio' = {ind.poisson_ratio!r}: the FEM "
                f"(displacement elements) accepts ν <= {MAX_POISSON_RATIO}; nearly "
                "incompressible material locks (use the MDR solver)")
    return None


def check_case(case) -> None:
    """Reject, with a CaseError, what this FEM model cannot represent."""
    reason = supports(case)
    if reason is not None:
        raise CaseError(reason)


def mesh_parameters(case) -> meshes.SphereMeshParameters:
    """The mesh of a case, after checking that the FEM can represent it."""
    check_case(case)
    validity.check_planned(case, fem_sphere=True)
    order = case.fem.element_order
    return meshes.contact_arc(case, "fem", order, GROWTH[order], MIN_NODES_IN_CONTACT)


def solve(case, progress=None) -> RunResult:
    """Run the FEM superelement model on ``case``; see :mod:`fem`.

    Dense algebra runs on one BLAS thread (threadpoolctl; several times
    faster for these small matrices on a shared machine: docs/performance.md,
    "Measurements behind the code"); the previous thread counts are restored
    on return.
    """
    with threadpool_limits(limits=1, user_api="blas"):
        return _solve(case, progress)


def _solve(case, progress=None) -> RunResult:
    t_start = time.perf_counter()
    params = mesh_parameters(case)
    sc = reference.scales(case)
    d0, F0, p0, per_m = sc["d0"], sc["F0"], sc["p0"], sc["s_hat_per_m"]
    fem, sl = case.fem, case.sliding
    order = fem.element_order
    rc = params.contact_radius
    if progress:
        progress(0.0, "mesh")
    t0 = time.perf_counter()
    sm = meshes.sphere_mesh(params)
    t_mesh = time.perf_counter() - t0
    if progress:
        progress(0.0, "assembly")
    model = build(sm, case.indenter.youngs_modulus, case.indenter.poisson_ratio, order)
    model.factorise()
    if progress:
        progress(0.0, "compliance")
    C_all = model.compliance()

    # P2: the node on the axis has ∫φ 2πr ds = 0; it cannot carry a pressure
    # (the consistent load of a smooth pressure on it is <= 0), so it takes
    # no part in the contact problem; its pressure and wear are reported as
    # the even extrapolation v(0) from the next two nodes.
    first = 1 if order == 2 else 0
    idx = np.arange(first, len(model.contact))
    C = C_all[np.ix_(idx, idx)]
    r_all = model.r
    z_all = height(case.indenter, r_all, case.table)
    r, z, area = r_all[idx], z_all[idx], model.area_rowsum[idx]
    rate = case.wear_rate
    # wear at r = 0 as a combination of the nodal wear (even extrapolation for P2)
    center = np.zeros(len(idx))
    if first:
        r1, r2 = r_all[1], r_all[2]
        center[:2] = r2**2 / (r2**2 - r1**2), -r1**2 / (r2**2 - r1**2)
    else:
        center[0] = 1.0

    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        limit = superelement.explicit_limit(C, area, rate) if np.all(np.isfinite(C)) else math.nan
        n_exp = case.wear.pressure_exponent
        if n_exp != 1.0:
            # the rate's derivative n (p/σ0)^(n-1) scales the stiffness; bound p by 1.5 p0
            limit /= n_exp * (1.5 * p0 / case.wear.hardness) ** (n_exp - 1.0)
        limit_hat = limit * per_m
    if not (math.isfinite(limit_hat) and limit_hat > 0 and np.all(np.isfinite(C))):
        # extreme moduli (e.g. E1 = 1e-300 Pa): the compliance or the wear rate
        # leaves floating point, and every later step would be meaningless
        raise SolverError(f"the contact compliance of this case is not representable in "
                          f"floating point (indenter.youngs_modulus = "
                          f"{case.indenter.youngs_modulus!r} Pa, stability limit "
                          f"{float(limit_hat)!r} in ŝ); the FEM cannot run it")
    adaptive = sl.scheme == "adaptive"
    if adaptive:
        step_hat = math.inf if sl.step_hat == "auto" else float(sl.step_hat)
    elif sl.step_hat == "auto":
        step_hat = {"explicit": 0.5 * limit_hat, "implicit": IMPLICIT_AUTO_STEP_HAT,
                    "bdf2": BDF2_AUTO_STEP_HAT}[sl.scheme]
    else:
        step_hat = float(sl.step_hat)
        if sl.scheme == "explicit" and step_hat > limit_hat:
            raise CaseError(f"key 'sliding.step_hat' = {sl.step_hat!r}: beyond the explicit "
                            f"Euler stability limit of this mesh, {limit_hat:.4g} (node spacing "
                            f"{model.stats()['contact_spacing']:.3g} m); use a step <= "
                            f"{limit_hat:.4g} or sliding.scheme = \"implicit\"")
    plan, until = programme.stepping_plan(case, step_hat, sc)
    step, s_end = plan.step, plan.end
    control = case.loading.control
    problem = superelement.Superelement(
        C, z, r, area, rate, control=control, value=getattr(case.loading, control),
        gap_scale=d0, force_scale=F0, pressure_scale=p0, center=center, exponent=n_exp,
        hardness=case.wear.hardness, arc_key="fem.contact_factor")

    def loop_progress(frac, text):
        if progress:
            progress(0.05 + 0.9 * frac, text)

    t0 = time.perf_counter()
    watch = validity.BodyWatch(case, fem_sphere=True,
                               spacing=model.stats()["contact_spacing"])
    out = superelement.run(problem, plan, loop_progress, watch=watch)
    t_loop = time.perf_counter() - t0

    # stages: full arc values (with the axis node for P2)
    t0 = time.perf_counter()
    K = len(out.stages)
    nc = len(r_all)
    f_nodes = np.zeros((K, nc))
    w_nodes = np.zeros((K, nc))
    for k, (_s, fk, wk, _d, _g) in enumerate(out.stages):
        f_nodes[k, first:] = fk
        w_nodes[k, first:] = wk
    p_lumped = np.zeros((K, nc))
    p_lumped[:, first:] = f_nodes[:, first:] / area
    if first:
        r1, r2 = r_all[1], r_all[2]
        for arr in (p_lumped, w_nodes):
            arr[:, 0] = (arr[:, 1] * r2**2 - arr[:, 2] * r1**2) / (r2**2 - r1**2)
    if fem.pressure_recovery == "consistent":
        # p = M⁻¹ f with the consistent 2πr-weighted boundary mass of the arc
        p_out = np.linalg.solve(model.boundary_mass, f_nodes.T).T
    else:
        p_out = p_lumped
    profile = z_all[None, :] + w_nodes
    fields = _fields(model, out, f_nodes, first, p_out, w_nodes)
    t_fields = time.perf_counter() - t0

    history = dict(s=np.array(out.s), force=np.array(out.force), depth=np.array(out.depth),
                   contact_radius=np.array(out.contact_radius),
                   wear_center=np.array(out.wear_center), wear_volume=np.array(out.wear_volume),
                   scar_radius=np.array(out.scar_radius))
    history = programme.finish_history(case, history, until, s_end, per_m)
    info = dict(
        solver="fem", scheme=sl.scheme,
        step_hat=step_hat if math.isfinite(step_hat) else "unlimited",
        step=step if math.isfinite(step) else "unlimited",
        pressure_exponent=n_exp,
        explicit_limit_step_hat=float(limit_hat),
        lcp_iterations=out.lcp_iterations, lcp_tolerance=superelement.LCP_TOL,
        max_complementarity_residual=out.max_residual,
        refactorisations=out.refactorisations, borderings=out.borderings,
        compliance_route=model.timings["compliance_method"],
        mesh=dict(model.stats(), growth=params.growth, contact_arc_radius=rc,
                  cache_file=str(sm.path), generated=sm.generate_seconds > 0),
        timings=dict(mesh=t_mesh, assembly=model.timings["assembly"],
                     factorisation=model.timings["factorisation"],
                     compliance=model.timings["compliance"], wear_loop=t_loop,
                     fields=t_fields),
        pressure_recovery=fem.pressure_recovery,
        axis_node=("P2: the axis node has zero 2πr-weighted area; excluded from the contact "
                   "problem, its pressure and wear are the even extrapolation from the next "
                   "two nodes") if first else "P1: included (row-sum area)",
        tangential_correction=("not modelled: frictionless normal FEM, wear.tangential_correction"
                               f" = {str(case.wear.tangential_correction).lower()} ignored"),
        body=("elastic sphere of radius indenter.radius clamped on its flat top face, against "
              "a rigid plane; the initial gap is the case's profile f(r_i)"),
    )
    info.update(stepping.info(out.outcome, plan))
    info["predicted_scar_radius"] = reference.predicted_scar_radius(case, case.end_distance or 0.0)
    if watch.remarks:
        info["warnings"] = watch.remarks
    if progress:
        progress(1.0, "done")
    return RunResult(history=history, stage_s=np.array([st[0] for st in out.stages]),
                     r=r_all.copy(), f=profile, p=p_out,
                     solve_seconds=time.perf_counter() - t_start, info=info, fields=fields)


def _fields(model, out, f_nodes, first, p_out, w_nodes) -> dict:
    """Mesh, displacement and nodal stress at the stored stages (SI)."""
    scalar = model.scalar
    points = scalar.doflocs.T.copy()
    cells = scalar.element_dofs.T.copy()
    # counter-clockwise in (r, z); for triangle6 swap vertices 1, 2 and edges 01, 20
    p = points[cells[:, :3]]
    signed = ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
              - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    flip = signed < 0
    swap = [0, 2, 1] if cells.shape[1] == 3 else [0, 2, 1, 5, 4, 3]
    cells[flip] = cells[flip][:, swap]
    K, Np = len(out.stages), len(points)
    disp = np.zeros((K, Np, 2))
    stress = np.zeros((K, Np, 4))
    for k, (_s, _f, _w, depth, _g) in enumerate(out.stages):
        u = model.displacement(f_nodes[k])
        stress[k] = model.nodal_stress(u)
        disp[k] = u.reshape(-1, 2)
        disp[k, :, 1] -= depth  # the top face moved down by the approach
    return dict(points=points, cells=cells.astype(np.int64), displacement=disp, stress=stress,
                contact_nodes=model.contact.astype(np.int64), contact_pressure=p_out,
                wear_depth=w_nodes)
