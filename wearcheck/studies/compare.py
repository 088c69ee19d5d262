"""``wearcheck compare``: every solver that supports a case, each against a reference.

Everything is computed first; the output directory is then written in one
piece with ``outputs.atomic_directory`` (the layout is ``layout.COMPARISON_FILES``):

    DIR/<solver>/               one run directory per solver (as ``wearcheck run`` writes)
    DIR/fig2_profiles.png|pdf   f/d against r/a0 at the stages (paper Fig. 2a)
    DIR/fig2_pressure.png|pdf   p/p0 against r/a0 (paper Fig. 2b; Fig. 3b for the
                                truncated paraboloid, with the reference)
    DIR/force_vs_sliding.png|pdf F/F0 and a/a0 against ŝ
    DIR/metrics.json            per solver and stage: differences to the reference, verdict
    DIR/report.md, report.html  the page a reviewer reads
    DIR/edge_study/             (--edge-study) runs at other resolutions, edge_peak.png
    DIR/finite_sphere.png       (--sphere-sweep) FEM force against half-space force
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from wearcheck import cases
from wearcheck.cases import reference
from wearcheck import layout, registry, rundir
from wearcheck.comparisons.analysis import diagnosis, metrics, scar
from wearcheck.comparisons.analysis.diagnosis import grid_spacing, step_hat_used
from wearcheck.comparisons.analysis.edge_peak import peaks_of
from wearcheck.outputs import atomic_directory, check_output
from wearcheck.comparisons.present import compare_figures, compare_report, report
from wearcheck.comparisons.present.progress import ProgressBar
from wearcheck.comparisons.present.scar_figure import scar_figure
from wearcheck.resources import check_memory
from wearcheck.studies import edge_study as edge_mod
from wearcheck.studies import sphere_sweep as sphere_mod
from wearcheck.extras import need

#: how a solver is run; tests replace it with analytic stand-ins
solve_case = registry.solve
#: the default reference solver (exact for axisymmetric half-space contact)
DEFAULT_REFERENCE = "mdr"


def choose_solvers(case, solvers=None, reference_solver=None) -> tuple[str, tuple[str, ...]]:
    """The reference and the solvers of a comparison (reference first).

    ``solvers`` None: every registered solver that supports the case, but for
    opt-in ones (``Solver.default`` False), which run when named. A named
    solver that does not support it is refused with its reason.
    """
    if solvers:
        chosen = tuple(dict.fromkeys(solvers))
        for name in chosen:
            reason = registry.get(name).supports(case)
            if reason is not None:
                raise cases.CaseError(f"solver '{name}' cannot run this case: {reason}")
    else:
        chosen = tuple(n for n in registry.supporting(case) if registry.get(n).default)
    ref = reference_solver or (DEFAULT_REFERENCE if DEFAULT_REFERENCE in chosen else chosen[0]
                               if chosen else DEFAULT_REFERENCE)
    registry.get(ref)
    if ref not in chosen:
        # the reason first when it is the case (the ellipsoid with --reference fem)
        reason = registry.get(ref).supports(case)
        raise cases.CaseError(f"reference solver '{ref}': not among the compared solvers "
                              f"({', '.join(chosen) or 'none'})"
                              + (f"; it cannot run this case: {reason}" if reason else ""))
    if len(chosen) < 2:
        if solvers:
            raise cases.CaseError(f"a comparison needs two solvers; only {chosen[0]} was named "
                                  "(those that can run this case: "
                                  + ", ".join(registry.supporting(case)) + ")")
        why = "; ".join(f"{n}: {reason}" for n, reason in skipped_solvers(case, chosen).items())
        # what is allowed first (the one solver, run alone), then why the others are not
        alone = (f"only {chosen[0]} can: run it alone (wearcheck run --solver {chosen[0]}); "
                 "the others cannot" if chosen else "none can")
        raise cases.CaseError("a comparison needs two solvers that support the case; "
                              f"{alone} ({why})")
    return ref, (ref,) + tuple(n for n in chosen if n != ref)


def run_solvers(case, names, *, solve=None, quiet=True, label="") -> dict:
    """Run each named solver on ``case``: {name: RunResult}, in the order given."""
    solve = solve or solve_case
    out = {}
    for name in names:
        bar = ProgressBar(f"{name}{label}", quiet=quiet)
        try:
            out[name] = solve(case, name, progress=bar)
        finally:
            bar.close()
    return out


def profile_scale(case, scales) -> float:
    """The depth d that profiles are measured in: the held depth, or d0 under force control."""
    if case.loading.control == "depth":
        return case.loading.depth
    return scales["d0"]


# -- analysis --------------------------------------------------------------

def truncated_reference(case, results, scales) -> dict | None:
    """Paper Fig. 3: each solver's unworn pressure against the quadrature reference.

    Only for a truncated paraboloid at a stage with ŝ = 0. The pressure is
    compared away from the edge (edge_band) and away from the singularity at
    r = b (|r - b| < edge_band · a).
    """
    ind = case.indenter
    if ind.profile != "truncated_paraboloid":
        return None
    E, R, b = case.E_star, ind.radius, ind.flat_radius
    load = {case.loading.control: getattr(case.loading, case.loading.control)}
    ref = reference.truncated_paraboloid(E, R, b, **load)
    a = ref["contact_radius"]
    cmp = case.compare
    out = dict(flat_radius_over_a0=b / scales["a0"], contact_radius=a / scales["a0"],
               force=ref["force"] / scales["F0"], solvers={})
    for name, res in results.items():
        if len(res.stage_s) == 0 or res.stage_s[0] != 0.0:
            continue
        r = np.asarray(res.r, float)
        p_ref = reference.truncated_paraboloid_pressure(r, E, R, b, a)
        a_run = float(metrics.at_stages(res.history["s"], res.history["contact_radius"],
                                        res.stage_s[:1])[0])
        F_run = float(metrics.at_stages(res.history["s"], res.history["force"],
                                        res.stage_s[:1])[0])
        interior, edge = metrics.edge_masks(r, a, a_run, cmp.edge_band)
        near_b = np.abs(r - b) < cmp.edge_band * a
        dp = (np.asarray(res.p[0], float) - p_ref) / scales["p0"]
        row = dict(force=abs(F_run - ref["force"]) / scales["F0"],
                   contact_radius=abs(a_run - a) / scales["a0"])
        row["pressure_interior_max"], row["pressure_interior_rms"], _ = \
            metrics.max_rms(dp[interior & ~near_b])
        row["pressure_near_b_max"], _, _ = metrics.max_rms(dp[near_b])
        row["pressure_edge_max"], _, _ = metrics.max_rms(dp[edge])
        # judged as a stage is: against the reference's own force, contact radius and
        # peak pressure (away from the singularity); no profile is compared here
        own = dict(profile_contact_max=1.0, force=out["force"],
                   contact_radius=out["contact_radius"],
                   pressure_interior_max=metrics.peak_pressure(r, p_ref, b, cmp.edge_band * a)
                   / scales["p0"])
        tol = metrics.verdict(dict(row, profile_contact_max=0.0, stage_scales=own),
                              dataclasses.asdict(cmp))
        tol.pop("profile_contact_max")
        row["checks"] = tol
        row["passed"] = all(c["passed"] for c in tol.values())
        out["solvers"][name] = row
    out["passed"] = bool(out["solvers"]) and all(v["passed"] for v in out["solvers"].values())
    return out


def pressure_exclusion(case, scales) -> dict:
    """Where the pressure is infinite, a band left out of the interior pressure check."""
    ind, cmp = case.indenter, case.compare
    if ind.profile == "truncated_paraboloid":
        # the solvers resolve the log singularity at r = b differently: leave it out
        return dict(exclude_radius=ind.flat_radius, exclude_width=cmp.edge_band * scales["a0"])
    if ind.profile == "cone" or (ind.profile == "power_law" and ind.exponent <= 1.0):
        # p is infinite at a sharp tip (log for the cone): no grid value of it is comparable
        return dict(exclude_radius=0.0, exclude_width=cmp.edge_band * scales["a0"])
    return {}


def analyse(case, results, reference_solver=None) -> dict:
    """Every solver against the reference, as written to metrics.json.

    ``results`` maps solver names to results; the reference is
    ``reference_solver`` or the first key.
    """
    ref = reference_solver or next(iter(results))
    sc = reference.scales(case)
    depth = profile_scale(case, sc)
    cmp = case.compare
    exclude = pressure_exclusion(case, sc)
    pairs = {}
    for name, res in results.items():
        if name == ref:
            continue
        pairs[name] = metrics.compare_results(
            results[ref], res, s_hat_per_m=sc["s_hat_per_m"], a0=sc["a0"], F0=sc["F0"],
            p0=sc["p0"], depth=depth, tolerances=dataclasses.asdict(cmp),
            edge_band=cmp.edge_band, **exclude)
    m = dict(reference=ref, solvers=list(results), pairs=pairs)
    m["stages_compared"] = min((p["stages_compared"] for p in pairs.values()), default=0)
    # a stage one solver reached and another did not is a disagreement, not a
    # stage to skip: a solver that stops early must not pass on its first stages
    reached = {k: len(v.stage_s) for k, v in results.items()}
    for name, pair in pairs.items():
        same = reached[name] == reached[ref]
        pair["checks"] = dict(stages_reached=dict(value=reached[name], tolerance=reached[ref],
                                                  passed=same))
        pair["passed"] = bool(pair["passed"] and same)
    # every solver (the reference too) must store its stages at the requested sliding
    # distances: stage k is paired with stage k, so a solver whose s is scaled (a unit
    # slip, a wrong speed) would otherwise be compared at the wrong wear
    requested = np.asarray(case.stages.s_hat, float) / sc["s_hat_per_m"]
    m["sliding_distance"] = {k: metrics.sliding_distance_check(v.stage_s, v.history["s"],
                                                               requested)
                             for k, v in results.items()}
    for name, pair in pairs.items():
        pair["checks"]["sliding_distance"] = m["sliding_distance"][name]
        pair["passed"] = bool(pair["passed"] and m["sliding_distance"][name]["passed"])
    m["passed"] = (bool(pairs) and all(p["passed"] for p in pairs.values())
                   and m["sliding_distance"][ref]["passed"])
    m["scales"] = sc
    m["profile_scale_depth"] = depth
    m["tolerances"] = dataclasses.asdict(cmp)
    m["stages_requested_s_hat"] = list(case.stages.s_hat)
    m["stages_reached"] = {k: len(v.stage_s) for k, v in results.items()}
    m["solve_seconds"] = {k: float(v.solve_seconds) for k, v in results.items()}
    m["grid_spacing_over_a0"] = {k: grid_spacing(v, sc["a0"]) for k, v in results.items()}
    m["step_hat"] = {k: step_hat_used(v, sc["s_hat_per_m"]) for k, v in results.items()}
    m["run_end"] = {k: dict(s_hat=float(v.history["s"][-1] * sc["s_hat_per_m"]),
                            force=float(v.history["force"][-1] / sc["F0"]))
                    for k, v in results.items()}
    m["approximate"] = {k: v.info.get("approximate") for k, v in results.items()
                        if v.info.get("approximate")}
    # each solver's remarks on its run (cases.validity: half-space theory stretched, ...)
    m["run_warnings"] = {k: list(v.info["warnings"]) for k, v in results.items()
                         if v.info.get("warnings")}
    m["anisotropy"] = {k: v.info["anisotropy"] for k, v in results.items()
                       if isinstance(v.info.get("anisotropy"), dict)}
    tr = truncated_reference(case, results, sc)
    if tr is not None:
        m["truncated_reference"] = tr
        m["passed"] = bool(m["passed"] and tr["passed"])
    m["edge_peaks"] = {k: peaks_of(v, sc) for k, v in results.items()}
    diagnose(case, results, m)
    return m


def skipped_solvers(case, chosen) -> dict:
    """The registered solvers a comparison leaves out, each with its reason: why it cannot
    run the case (or here), that it is opt-in (``Solver.default`` False: named to run), or
    that it was not among the solvers asked for."""
    out = {}
    for name in registry.names():
        if name in chosen:
            continue
        entry = registry.get(name)
        reason = entry.supports(case)
        if reason is None:
            reason = ("not among the solvers asked for" if entry.default else
                      "opt-in (an external program): name it to compare it, e.g. --solvers "
                      + ",".join(list(chosen) + [name]))
        out[name] = reason
    return out


def _resolution(case, name, result, stage) -> diagnosis.Resolution:
    """How finely one run resolved its stage ``stage`` (its own contact radius there)."""
    try:
        entry = registry.get(name)
        title, key = entry.title, entry.resolution_key
    except cases.CaseError:      # a result that no registered solver made
        title, key = name.upper(), None
    value = None
    if key is not None:
        section, field = key.split(".")
        value = getattr(getattr(case, section, None), field, None)
    points = math.nan
    if stage < len(result.stage_s):
        a = float(metrics.at_stages(result.history["s"], result.history["contact_radius"],
                                    result.stage_s[stage:stage + 1])[0])
        points = diagnosis.points_across(result.r, a)
    err = result.info.get("time_error")
    err = err.get("estimate") if isinstance(err, dict) else None
    if err is None and case.sliding.scheme in ("implicit", "explicit"):
        sc = cases.reference.scales(case)
        err = diagnosis.first_order_time_error(result.history, sc["F0"], sc["d0"])
    return diagnosis.Resolution(solver=name, title=title, key=key, value=value,
                                points_across=points,
                                time_error=float(err) if err is not None else None,
                                approximate=result.info.get("approximate") or None,
                                step_hat=_number(result.info.get("step_hat")))


def _number(x):
    """``x`` as a float when it is a finite number, else None."""
    try:
        x = float(x)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def diagnose(case, results, m) -> None:
    """Add to each failed pair (and to a failed reference check) the setting most
    likely to fix its worst check; ``m["diagnosis"]``: the worst of them."""
    sl = case.sliding
    found = []

    def advice(failure, names):
        runs = [_resolution(case, n, results[n], failure["stage"]) for n in names]
        return diagnosis.advise(failure, runs, scheme=sl.scheme, tolerance=sl.tolerance,
                                step_hat=sl.step_hat)

    for name, pair in m["pairs"].items():
        failure = diagnosis.worst_failure(pair["stages"])
        pair["diagnosis"] = None
        if failure is not None:
            pair["diagnosis"] = dict(advice(failure, [name, m["reference"]]), pair=name,
                                     used=failure["used"])
            found.append(pair["diagnosis"])
    tr = m.get("truncated_reference")
    for name, row in (tr or {}).get("solvers", {}).items():
        failure = diagnosis.worst_failure([dict(index=0, s_hat_reference=0.0,
                                                checks=row["checks"])])
        if failure is not None:
            row["diagnosis"] = dict(advice(failure, [name]), pair=f"{name} / reference",
                                    used=failure["used"])
            found.append(row["diagnosis"])
    m["diagnosis"] = max(found, key=lambda d: d["used"], default=None)


def scar_tables(case, results) -> dict:
    """Scar diameter, central wear and volume per solver for a ball that wears
    long enough to have a scar (a sphere or paraboloid that slides), else {}."""
    if case.indenter.profile not in ("sphere", "paraboloid") or not case.indenter.radius:
        return {}
    out = {}
    for name, res in results.items():
        if "scar_radius" in res.history and len(res.history["s"]) > 1 \
                and res.history["s"][-1] > 0:
            out[name] = scar.scar_table(res.history, case)
    return out


# -- the whole comparison ---------------------------------------------------

@dataclasses.dataclass
class Runs:
    """What the solvers computed for one comparison: the output of :func:`run`.

    ``results`` maps solver names to results, the reference first;
    ``switched`` is (default reference, reference used) when the default
    reference solved an approximation of the case; ``edge_study`` and
    ``sphere_sweep`` are the sub-studies (None when not asked for), the edge
    study's extra runs in ``edge_runs`` (label -> (solver, case, result)).
    """

    reference: str
    results: dict
    switched: tuple | None = None
    edge_study: dict | None = None
    edge_runs: dict = dataclasses.field(default_factory=dict)
    sphere_sweep: dict | None = None


def run(case, *, solvers=None, reference_solver=None, edge=False, sphere=False,
        sphere_ratios=None, solve=None, quiet=True) -> Runs:
    """Step 1: run the chosen solvers on ``case`` (and the sub-studies asked for).

    Checks each solver's memory need first; nothing is written.
    """
    solve = solve or solve_case
    ref, names = choose_solvers(case, solvers, reference_solver)
    for name in names:
        check_memory(case, name)
    results = run_solvers(case, names, solve=solve, quiet=quiet)
    switched = None
    if reference_solver is None and results[ref].info.get("approximate"):
        # the default reference solved an approximation of this case: the first
        # solver that solved the case itself is the reference instead
        exact = [n for n in names if not results[n].info.get("approximate")]
        if exact:
            switched = (ref, exact[0])
            ref = exact[0]
            results = {ref: results[ref], **{n: r for n, r in results.items() if n != ref}}
    runs = Runs(reference=ref, results=results, switched=switched)
    if edge:
        runs.edge_study = edge_mod.edge_study(case, results, solve=solve, quiet=quiet)
        runs.edge_runs = runs.edge_study.pop("runs")
    if sphere:
        runs.sphere_sweep = sphere_mod.sphere_sweep(
            case, sphere_ratios or sphere_mod.SPHERE_RATIOS, solve=solve, quiet=quiet)
    return runs


def analyse_runs(case, runs: Runs) -> dict:
    """Step 2: the comparison's metrics from its runs (pure: no files, no figures).

    :func:`analyse` of the results, with the solvers left out and why, the
    reference's switch, the scar summary and the sub-studies' results.
    """
    m = analyse(case, runs.results, runs.reference)
    m["skipped"] = skipped_solvers(case, tuple(runs.results))
    if runs.switched:
        old, new = runs.switched
        m["reference_note"] = (f"{registry.get(old).title} solved an approximation "
                               f"of this case, so {registry.get(new).title} is the "
                               "reference")
    scars = scar_tables(case, runs.results)
    if scars:
        m["scar"] = {n: scar.summary(t) for n, t in scars.items()}
    if runs.edge_study is not None:
        m["edge_study"] = dict(runs.edge_study)
    if runs.sphere_sweep is not None:
        m["sphere_sweep"] = dict(runs.sphere_sweep)
    return m


def write(out, case, runs: Runs, m: dict, *, argv=None, render=True, started=None) -> dict:
    """Step 3: write the comparison directory ``out`` atomically: each solver's
    run directory, the figures, metrics.json, case.toml and the report.

    Returns the metrics as written: ``m`` (from :func:`analyse_runs`, not
    changed) with the figures' names, the renders, the provenance and the
    total time (``started``: the ``time.perf_counter()`` of the comparison's
    start) added.
    """
    need("matplotlib", "compare (its figures)")
    m = dict(m)
    names = list(runs.results)
    prov = rundir.provenance(argv)
    with atomic_directory(Path(out), "comparison") as tmp:
        for name, res in runs.results.items():
            (tmp / name).mkdir()
            rundir.write_run_files(tmp / name, case, res, name, argv)
        figure_names = compare_figures.draw_figures(tmp, case, runs.results, m)
        if "edge_study" in m:
            m["edge_study"] = study = dict(m["edge_study"])
            (tmp / "edge_study").mkdir()
            for sub, (name, c, res) in runs.edge_runs.items():
                (tmp / "edge_study" / sub).mkdir()
                rundir.write_run_files(tmp / "edge_study" / sub, c,
                                       dataclasses.replace(res, fields=None), name, argv)
            curves = []
            for n in study["solvers"]:
                curves.append((f"{registry.get(n).title} case", n, runs.results[n]))
                curves += [(f"{registry.get(name).title} {sub.split('-', 1)[1]}", name, res)
                           for sub, (name, c, res) in runs.edge_runs.items() if name == n]
            study["figure"] = compare_figures.draw_edge_study(tmp, curves, m["scales"])
        if "sphere_sweep" in m:
            m["sphere_sweep"] = sweep = dict(m["sphere_sweep"])
            sweep["figure"] = compare_figures.draw_sphere_sweep(tmp, sweep)
        scars = scar_tables(case, runs.results)
        if scars:
            scar_figure(tmp / "scar.png", {registry.get(n).title: t for n, t in scars.items()},
                        title="scar diameter and worn volume")
            figure_names.append("scar.png")
        notes = compare_figures.try_render([tmp / n for n in names])["notes"] if render else []
        renders = compare_figures.find_renders(tmp, names)
        m["renders"] = renders
        m["render_notes"] = notes
        m["provenance"] = prov
        m["case_source"] = case.source
        if started is not None:
            m["seconds_total"] = time.perf_counter() - started
        m["data_dictionary"] = layout.comparison_dictionary()
        rundir.write_json(tmp / "metrics.json", m)
        (tmp / "case.toml").write_text(cases.to_toml(case), encoding="utf-8")
        blocks = compare_report.build_report(case, m, figure_names, renders, notes, prov)
        report.write(tmp, blocks, f"wearcheck compare: {Path(case.source).name}")
    return m


def compare(case, out, *, solvers=None, reference_solver=None, argv=None, edge=False,
            sphere=False, sphere_ratios=None, solve=None, quiet=True, render=True) -> dict:
    """Run the solvers on ``case`` and write the comparison directory ``out`` atomically:
    :func:`run`, :func:`analyse_runs`, :func:`write`.

    Parameters
    ----------
    case : a loaded :class:`wearcheck.Case`.
    out : the comparison directory (replaced only if it is a wearcheck output).
    solvers : names of the solvers to compare (default: every registered solver
        that supports the case); reference_solver : the one the others are
        compared with (default "mdr").
    edge, sphere : also run the edge-peak study and the finite-sphere sweep.

    Returns the metrics (as in metrics.json); ``passed`` is the verdict.
    """
    started = time.perf_counter()
    check_output(out, "comparison")  # before the solves: a path we may not write
    need("matplotlib", "compare (its figures)")    # and an extra it will need
    runs = run(case, solvers=solvers, reference_solver=reference_solver, edge=edge,
               sphere=sphere, sphere_ratios=sphere_ratios, solve=solve, quiet=quiet)
    return write(out, case, runs, analyse_runs(case, runs), argv=argv, render=render,
                 started=started)
