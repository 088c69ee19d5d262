"""``solve(case)``: CalculiX's sphere, from case to RunResult; ``supports(case)``."""

from __future__ import annotations

import math
import time

import numpy as np
from threadpoolctl import threadpool_limits

from wearcheck import meshes
from wearcheck.cases import CaseError, SolverError, programme, reference, validity
from wearcheck.cases.profiles import height
from wearcheck.numerics import stepping, superelement

from . import compliance as compliance_mod
from . import deck, in_loop, run
from .model import cax6_sphere
from .output import dat_blocks, select, stage_fields

#: implicit Euler's and BDF2's step in ŝ when sliding.step_hat = "auto": the FEM's
#: (fem/solver.py; docs/performance.md, "Measurements behind the code"), since the
#: mesh and the superelement are the same
IMPLICIT_AUTO_STEP_HAT = 0.02
BDF2_AUTO_STEP_HAT = 0.01
#: fewest arc nodes required inside the unworn contact radius
MIN_NODES_IN_CONTACT = 5
#: most CalculiX jobs an in-loop run may take (one per step, each seconds long:
#: docs/performance.md, "Measurements behind the code")
MAX_IN_LOOP_STEPS = 2000
#: largest Poisson ratio before volumetric locking shows (as the FEM's quadratic elements)
MAX_POISSON_RATIO = 0.495


def supports(case) -> str | None:
    """None when CalculiX's sphere can run ``case`` here, else the reason it cannot.

    The model's limits (those of the FEM: an elastic sphere against a rigid
    plane) come first, then the mode's, then the ``ccx`` executable.
    """
    if getattr(case, "fretting", None) is not None:
        return ("fretting (partial slip) needs a one-directional tangential load, which the "
                "axisymmetric CalculiX model cannot carry; use the MDR solver")
    ind, cf = case.indenter, case.counterface
    if ind.profile == "ellipsoid":
        return ("indenter.profile = \"ellipsoid\": the CalculiX model is axisymmetric; use "
                "the BEM (or the MDR, approximately)")
    if ind.radius is None:
        return (f"CalculiX needs 'indenter.radius' (the radius of its sphere) for profile "
                f"\"{ind.profile}\"; it is not given")
    if cf.wears:
        return ("counterface.wears = true: the CalculiX model wears the sphere only (a wear "
                "track on the flat needs the BEM's both-bodies models, docs/both-bodies.md)")
    if not cf.rigid:
        return ("counterface.rigid = false: the CalculiX model is an elastic sphere against "
                "a rigid plane; set counterface.rigid = true or use the MDR solver")
    if ind.rigid:
        return ("indenter.rigid = true: the CalculiX body is the elastic sphere; a rigid "
                "indenter has nothing to deform (use the MDR solver)")
    if ind.poisson_ratio > MAX_POISSON_RATIO:
        return (f"key 'indenter.poisson_ratio' = {ind.poisson_ratio!r}: CalculiX's CAX6 "
                f"displacement elements lock beyond ν = {MAX_POISSON_RATIO}; use the MDR solver")
    if case.ccx.mode == "in_loop" and case.sliding.scheme != "explicit":
        return (f"ccx.mode = \"in_loop\" steps by explicit Euler (one CalculiX solve per "
                f"step); key 'sliding.scheme' = \"{case.sliding.scheme}\": set it to "
                "\"explicit\", or use ccx.mode = \"superelement\"")
    return run.unavailable(case.ccx.executable)


def mesh_parameters(case) -> meshes.SphereMeshParameters:
    """The gmsh mesh of a case (the FEM's recipe: P2 grading, the arc sized for the
    predicted final contact radius), after checking the run stays on the sphere and the
    arc resolves the contact."""
    validity.check_planned(case, fem_sphere=True)
    # quadratic elements: the FEM's P2 mesh (growth meshes.GROWTH, its GROWTH[2])
    return meshes.contact_arc(case, "ccx", 2, meshes.GROWTH, MIN_NODES_IN_CONTACT)


def solve(case, progress=None) -> run.CcxResult:
    """Run ``case`` on CalculiX's sphere in the mode ``ccx.mode``; see :mod:`ccx`."""
    reason = supports(case)
    if reason is not None:
        raise CaseError(reason)
    with threadpool_limits(limits=1, user_api="blas"):
        return _solve(case, progress)


def axis_weights(r) -> np.ndarray:
    """Weights of the loaded nodes' values giving the value on the axis: the even
    extrapolation v(0) = (v1 r2² − v2 r1²)/(r2² − r1²) from the first two."""
    w = np.zeros(len(r) - 1)
    r1, r2 = r[1], r[2]
    w[:2] = r2**2 / (r2**2 - r1**2), -r1**2 / (r2**2 - r1**2)
    return w


def step_hat_for(case, limit_hat: float) -> float:
    """The step in ŝ of the case's scheme (``sliding.step_hat``, or its "auto"); an
    explicit step beyond the stability limit ``limit_hat`` is refused naming the key."""
    sl = case.sliding
    if sl.scheme == "adaptive":
        return math.inf if sl.step_hat == "auto" else float(sl.step_hat)
    if sl.step_hat == "auto":
        return {"explicit": 0.5 * limit_hat, "implicit": IMPLICIT_AUTO_STEP_HAT,
                "bdf2": BDF2_AUTO_STEP_HAT}[sl.scheme]
    step_hat = float(sl.step_hat)
    if sl.scheme == "explicit" and step_hat > limit_hat:
        raise CaseError(f"key 'sliding.step_hat' = {sl.step_hat!r}: beyond the explicit Euler "
                        f"stability limit of this mesh, {limit_hat:.4g}; use a step <= "
                        f"{limit_hat:.4g}" + ("" if case.ccx.mode == "in_loop" else
                                              " or sliding.scheme = \"implicit\""))
    return step_hat


def _solve(case, progress):
    t_start = time.perf_counter()
    sc = reference.scales(case)
    d0, F0, p0, per_m = sc["d0"], sc["F0"], sc["p0"], sc["s_hat_per_m"]
    settings = case.ccx
    in_loop_mode = settings.mode == "in_loop"
    params = mesh_parameters(case)
    if progress:
        progress(0.0, "mesh")
    sm = meshes.sphere_mesh(params)
    sphere = cax6_sphere(sm)
    E, nu = case.indenter.youngs_modulus, case.indenter.poisson_ratio
    executable = run.find(settings.executable)
    version = run.version(executable)
    jobs = run.Jobs(executable=executable,
                    model=deck.model(sphere, E, nu, nonlinear=in_loop_mode,
                                     title=f"wearcheck case {case.source}"))
    if progress:
        progress(0.0, "compliance (CalculiX)")
    C, compliance_info = compliance_mod.compliance(sphere, E, nu, jobs, version)
    r_all = sphere.r
    r, area = r_all[1:], sphere.area[1:]
    z_all = height(case.indenter, r_all, case.table)
    rate, n_exp, hardness = case.wear_rate, case.wear.pressure_exponent, case.wear.hardness
    control = case.loading.control
    center = axis_weights(r_all)
    limit_hat = superelement.explicit_limit(C, area, rate) * per_m
    if n_exp != 1.0:
        # the rate's derivative n (p/σ0)^(n-1) scales the stiffness; bound p by 1.5 p0
        limit_hat /= n_exp * (1.5 * p0 / hardness) ** (n_exp - 1.0)
    step_hat = step_hat_for(case, limit_hat)
    plan, until = programme.stepping_plan(case, step_hat, sc)
    info = dict(mode=settings.mode, scheme=case.sliding.scheme,
                step_hat=step_hat if math.isfinite(step_hat) else "unlimited",
                step=plan.step if math.isfinite(plan.step) else "unlimited",
                explicit_limit_step_hat=float(limit_hat))

    def loop_progress(frac, text):
        if progress:
            progress(0.05 + 0.85 * frac, text)

    watch = validity.BodyWatch(case, fem_sphere=True, spacing=float(np.mean(np.diff(r_all))))
    t0 = time.perf_counter()
    if in_loop_mode:
        if until == "distance" and plan.end / plan.step > MAX_IN_LOOP_STEPS * (1 + 1e-9):
            raise CaseError(f"ccx.mode = \"in_loop\": the run would take "
                            f"{plan.end / plan.step:.3g} steps of Δŝ = {step_hat:.3g} (one "
                            f"CalculiX job each; at most {MAX_IN_LOOP_STEPS}); shorten the run "
                            "or use ccx.mode = \"superelement\"")
        problem = in_loop.InLoop(
            jobs, sphere, z_all, control=control, value=getattr(case.loading, control),
            rate=rate, exponent=n_exp, hardness=hardness, stage_s=plan.stages, center=center,
            force_scale=F0, depth_scale=d0, stiffness=in_loop.gap_stiffness(area, p0, d0),
            tension=in_loop.TENSION * F0 / deck.WEDGES, max_steps=MAX_IN_LOOP_STEPS)
        out, frd_steps = in_loop.run(problem, plan, loop_progress, watch=watch)
        t_loop = time.perf_counter() - t0
        info.update(gap_stiffness=dict(value=problem.stiffness, unit="N/m on the 2° wedge"),
                    gap_tension=dict(value=problem.tension, unit="N on the 2° wedge"),
                    max_penetration=dict(value=problem.max_penetration, unit="d0"),
                    max_equilibrium_error=dict(value=problem.max_equilibrium_error,
                                               unit="F0"))
    else:
        problem = superelement.Superelement(
            C, z_all[1:], r, area, rate, control=control, value=getattr(case.loading, control),
            gap_scale=d0, force_scale=F0, pressure_scale=p0, center=center, exponent=n_exp,
            hardness=hardness, arc_key="ccx.contact_factor")
        out = superelement.run(problem, plan, loop_progress, watch=watch)
        t_loop = time.perf_counter() - t0
        if progress:
            progress(0.9, "fields (CalculiX)")
        frd_steps, recovered = (recover_fields(jobs, sphere, z_all, out.stages, d0)
                                if out.stages else ([], 0.0))
        info.update(lcp_iterations=out.lcp_iterations, lcp_tolerance=superelement.LCP_TOL,
                    max_complementarity_residual=out.max_residual,
                    refactorisations=out.refactorisations, borderings=out.borderings,
                    recovery_gap=dict(value=recovered, unit="d0", meaning=(
                        "largest |gap| of a loaded contact node when CalculiX applies the "
                        "stage's contact forces to the sphere (fields recovery)")))
    info.update(stepping.info(out.outcome, plan))
    if watch.remarks:
        info["warnings"] = watch.remarks
    fields = _fields(sphere, out.stages, frd_steps)
    history = programme.finish_history(case, _history(out), until, plan.end, per_m)
    if progress:
        progress(1.0, "done")
    return _result(case, sphere, out, history, z_all, fields, jobs, version, compliance_info,
                   info, params, sm, t_start, t_loop)


def _history(out) -> dict:
    return {k: np.array(getattr(out, k), float) for k in
            ("s", "force", "depth", "contact_radius", "wear_center", "wear_volume",
             "scar_radius")}


def _fields(sphere, stages, frd_steps) -> dict:
    """Mesh, displacement and nodal stress at the stages, from CalculiX's .frd results."""
    K, Np = len(stages), len(sphere.points)
    disp = np.zeros((K, Np, 2))
    stress = np.zeros((K, Np, 4))
    for k, results in enumerate(frd_steps):
        disp[k], stress[k] = stage_fields(results, Np)
    return dict(points=sphere.points.copy(), cells=sphere.elements.astype(np.int64),
                displacement=disp, stress=stress,
                contact_nodes=sphere.contact.astype(np.int64))


def _result(case, sphere, out, history, z_all, fields, jobs, version, compliance_info, info,
            params, sm, t_start, t_loop) -> run.CcxResult:
    """The RunResult of either mode from its history and stage states."""
    area = sphere.area[1:]
    K, nc = len(out.stages), len(sphere.contact)
    f_nodes, w_nodes = np.zeros((K, nc)), np.zeros((K, nc))
    for k, stage in enumerate(out.stages):
        f_nodes[k, 1:], w_nodes[k, 1:] = stage[1], stage[2]
    p = np.zeros((K, nc))
    p[:, 1:] = f_nodes[:, 1:] / area
    center = axis_weights(sphere.r)
    for arr in (p, w_nodes):
        arr[:, 0] = arr[:, 1:] @ center
    fields.update(contact_pressure=p, wear_depth=w_nodes)
    info.update(
        solver="ccx", ccx=dict(executable=jobs.executable, version=".".join(map(str, version)),
                               jobs=len(jobs.seconds), seconds=sum(jobs.seconds.values()),
                               threads=1),
        pressure_exponent=case.wear.pressure_exponent,
        compliance=compliance_info,
        mesh=dict(contact_nodes=nc, nodes=len(sphere.points), elements=len(sphere.elements),
                  element="CAX6", growth=params.growth,
                  contact_arc_radius=params.contact_radius, cache_file=str(sm.path)),
        timings=dict(wear_loop=t_loop, ccx=dict(jobs.seconds) if len(jobs.seconds) <= 20
                     else dict(total=sum(jobs.seconds.values()))),
        decks="ccx/ in the run directory: sphere.inp (the model) and one deck per CalculiX job",
        axis_node=("the axis node has zero 2πr-weighted area: no contact there, its pressure "
                   "and wear are the even extrapolation from the next two nodes"),
        tangential_correction=("not modelled: frictionless normal contact, "
                               f"wear.tangential_correction = "
                               f"{str(case.wear.tangential_correction).lower()} ignored"),
        body=("elastic sphere of radius indenter.radius (CAX6, the FEM's mesh) clamped on "
              "its flat top face, against a rigid plane; the initial gap is the case's "
              "profile f(r_i)"),
        predicted_scar_radius=reference.predicted_scar_radius(case, case.end_distance or 0.0))
    decks = {deck.MODEL_FILE: jobs.model, **jobs.decks}
    return run.CcxResult(history=history, stage_s=np.array([st[0] for st in out.stages]),
                         r=sphere.r.copy(), f=z_all[None, :] + w_nodes, p=p,
                         solve_seconds=time.perf_counter() - t_start, info=info,
                         fields=fields, decks=decks)


#: recovered gaps of loaded nodes allowed, relative to d0: the fields come from a fresh
#: static solve with the contact forces; a loaded node must come out on the plane
RECOVERY_TOLERANCE = 1e-4


def recover_fields(jobs, sphere, height, stages, depth_scale) -> tuple[list, float]:
    """The .frd results of each stage, from one CalculiX job applying its contact forces.

    ``stages``: (s, f (Nc-1,), w (Nc-1,), depth, gap) per stage, as the wear
    run stored them; ``height`` (Nc,) the initial gaps. Returns the results
    per stage and the largest |gap| of a loaded node in the recovered state,
    relative to ``depth_scale`` (SolverError above :data:`RECOVERY_TOLERANCE`:
    the compliance does not belong to this sphere).
    """
    forces = [(st[3], np.concatenate([[0.0], st[1]])) for st in stages]
    job = jobs.run("recovery", deck.recovery(sphere, forces, title="wearcheck: the fields at "
                                                                   "the stages"), keep_frd=True)
    per_stage = [[b for b in job.frd if b.step == k + 1] for k in range(len(stages))]
    blocks = select(dat_blocks(job.dat, "recovery.dat"), "displacements", "CONTACT")
    if len(blocks) != len(stages):
        raise SolverError(f"CalculiX job 'recovery': {len(blocks)} steps printed for "
                          f"{len(stages)} stages")
    worst = 0.0
    for st, b in zip(stages, blocks):
        uz = b.values[np.argsort(b.ids), 1] / deck.MM
        gap = height[1:] + st[2] + uz[1:]
        loaded = st[1] > 0
        if np.any(loaded):
            worst = max(worst, float(np.max(np.abs(gap[loaded]))) / depth_scale)
    if not worst <= RECOVERY_TOLERANCE:
        raise SolverError(f"CalculiX's recovery of the stages leaves loaded contact nodes "
                          f"{worst:.3g} d0 off the plane: the cached compliance does not "
                          "belong to this sphere (delete it from the cache)")
    return per_stage, worst
