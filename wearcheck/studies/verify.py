"""``wearcheck verify``: results produced elsewhere against the certified reference (or a
fresh wearcheck run), with the overlays, per-stage metrics, verdict and report of
``compare``.

Verification is a comparison whose second "solver" reads files instead of
solving: the user's results are read (:mod:`wearcheck.external`), the
reference is evaluated at the user's own distances and radii, and each stage
is judged by the verdict's checks (:mod:`comparisons.analysis.verification`).
The output directory (``layout.VERIFICATION_FILES``, written atomically as a
comparison):

    DIR/reference/                 the reference at the judged stages (a run directory)
    DIR/results/history.csv        the user's history as read, in SI (s, s_hat, ...)
    DIR/results/stages.csv         the user's stages as read, long form, in SI
    DIR/fig_profiles.png|pdf       f/d against r/a0: reference lines, the user's markers
    DIR/fig_pressure.png|pdf       p/p0 against r/a0
    DIR/history.png|pdf            F/F0, a/a0, central wear and worn volume against ŝ, and
                                   each row's difference against its tolerance band
    DIR/metrics.json, report.md, report.html, case.toml
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from wearcheck import cases
from wearcheck.cases import CaseError, reference as closed
from wearcheck import external, layout, outputs, registry, rundir
from wearcheck.comparisons.analysis import verification
from wearcheck.studies import compare as compare_mod
from wearcheck.comparisons.present.progress import ProgressBar
from wearcheck.references.certified import unworn_profile
from wearcheck.outputs import check_output
from wearcheck.references import certified
from wearcheck.comparisons.present import report, verify_figures, verify_report

#: the name of the user's results in outputs and reports
RESULTS = "results"


def _solve(case, name, quiet):
    bar = ProgressBar(name, quiet=quiet)
    try:
        return registry.solve(case, name, progress=bar)
    finally:
        bar.close()


def read_results(case, ext, cycles_to_s=None) -> tuple[dict, list]:
    """The user's results (read by ``external.read``) in SI distances: (history
    {"s", quantities, "origin"}, stages [{s, r, f, p, origin}])."""
    sc = closed.scales(case)
    hist = {k: np.asarray(v, float) for k, v in ext.history.items() if k != "time"}
    hist["s"] = verification.to_distance(ext.history["time"], ext.kind, case, sc, cycles_to_s)
    hist["origin"] = list(ext.history_origin)
    stages = []
    for st in ext.stages:
        s = float(verification.to_distance([st.time], ext.stage_kind, case, sc,
                                           cycles_to_s)[0])
        f = st.f
        if f is None and st.wear is not None:
            f = unworn_profile(case, st.r) + st.wear
        stages.append(dict(s=s, r=st.r, f=f, p=st.p, origin=st.origin))
    if any(not np.isfinite(st["s"]) for st in stages) or not np.all(np.isfinite(hist["s"])):
        raise CaseError(f"results '{ext.source}': cycles beyond the reference's cannot be "
                        "turned into sliding distances")
    return hist, stages


def case_stage_cycles(case) -> list[float]:
    """A fretting case's stages in cycles: fretting.stage_cycles, else 0, 1, 10, ... and
    the run's last cycle (as the MDR keeps them)."""
    fr = case.fretting
    if fr.stage_cycles is not None:
        return [float(c) for c in fr.stage_cycles]
    out, c = [0.0], 1
    while c < fr.cycles:
        out.append(float(c))
        c *= 10
    return out + [float(fr.cycles)]


def case_stage_distances(case, cycles_to_s=None) -> list[float]:
    """The case's stages as sliding distances [m]."""
    sc = closed.scales(case)
    if case.fretting is not None:
        return [float(s) for s in cycles_to_s(np.asarray(case_stage_cycles(case)))
                if np.isfinite(s)]
    return [s / sc["s_hat_per_m"] for s in case.stages.s_hat]


def fresh_reference(case, name, ext, *, quiet=True, solve=None):
    """A run of solver ``name`` with its stages at the user's: (RunReference, the run,
    its case). A fretting case keeps its stages at the user's cycle counts."""
    sc = closed.scales(case)
    if case.fretting is not None:
        times = [st.time for st in ext.stages] if ext.stages else list(ext.history["time"])
        kind = ext.stage_kind if ext.stages else ext.kind
        if kind != "cycles" or any(t != round(t) for t in times):
            raise CaseError("--reference-solver with a fretting case: give the results "
                            "against whole cycles (a column 'cycles'); a fretting run keeps "
                            "its stages at the end of a cycle")
        if not ext.stages:   # the history rows nearest the case's stages
            want = case_stage_cycles(case)
            times = sorted({min(times, key=lambda t: abs(t - c)) for c in want})
        changes = {"fretting.stage_cycles": sorted({int(t) for t in times})}
    else:
        hist, stages = read_results(case, ext)
        s_list = [st["s"] for st in stages] or [
            sel["s"] for sel in verification.select_stages(hist, [],
                                                           case_stage_distances(case))]
        # stages.s_hat replaces stages.cycles (Case.derive drops a key's partner)
        changes = {"stages.s_hat": [s * sc["s_hat_per_m"] for s in sorted(set(s_list))]}
    run_case = case.derive(changes)
    registry.get(name)
    reason = registry.get(name).supports(run_case)
    if reason is not None:
        raise CaseError(f"--reference-solver {name}: it cannot run this case: {reason}")
    result = (solve or (lambda c, n: _solve(c, n, quiet)))(run_case, name)
    return verification.RunReference(result, run_case, name), result, run_case


def verify(case, results, out, *, mapping=None, reference_solver=None, argv=None,
           quiet=True, solve=None) -> dict:
    """Judge the results at ``results`` against the reference; write ``out`` atomically.

    Parameters
    ----------
    case : the case the results claim to solve (a loaded :class:`wearcheck.Case`).
    results : a results directory or file (:func:`wearcheck.external.read`).
    out : the output directory (replaced only if it is a wearcheck comparison).
    mapping : {"name [unit]": "field"} from ``--map``.
    reference_solver : None for the certified reference, else a solver to run.

    Returns the metrics (as in metrics.json); ``["passed"]`` is the verdict.
    """
    t0 = time.perf_counter()
    check_output(out, "comparison")
    sc = closed.scales(case)
    depth = compare_mod.profile_scale(case, sc)
    cmp = case.compare
    if reference_solver is None:
        ref = certified.for_case(case)
        if ref is None:
            raise CaseError("no certified reference solves this case's problem (shipped: "
                            + ", ".join(certified.names()) + "; the physics must match: "
                            "indenter, counterface, loading, wear, fretting); verify against "
                            "a fresh run instead: " + _fresh_run_hint(case))
        ext = external.read(results, mapping)
        hist, stages = read_results(case, ext, ref.cycles_to_s)
        ref_name, ref_title = "reference", f"certified reference '{ref.name}'"
        ref_case = case
    else:
        ext = external.read(results, mapping)
        ref, run, ref_case = fresh_reference(case, reference_solver, ext, quiet=quiet,
                                             solve=solve)
        hist, stages = read_results(case, ext, ref.cycles_to_s)
        ref_name, ref_title = reference_solver, f"a fresh {registry.get(reference_solver).title} run"
    exclude = compare_mod.pressure_exclusion(case, sc)
    pair = verification.judge(ref, hist, stages,
                              case_stage_s=case_stage_distances(case, ref.cycles_to_s),
                              scales=sc, depth=depth, tolerances=dataclasses.asdict(cmp),
                              edge_band=cmp.edge_band, same_distance=ext.time_precision,
                              **exclude)
    factor = verification.distance_factor(ref, hist, sc, depth)
    judged_s = [st["s"] for st in pair["stages"]]
    if reference_solver is None:
        run = ref.run_result(judged_s) if judged_s else ref.run_result([0.0])
    m = dict(reference=ref_name, reference_title=ref_title, solvers=[ref_name, RESULTS],
             pairs={RESULTS: pair}, passed=pair["passed"], scales=sc, profile_scale_depth=depth,
             tolerances=dataclasses.asdict(cmp), checks=pair["checks_used"],
             stages_compared=pair["stages_compared"],
             results=dict(source=str(results), format=ext.format, distance=ext.kind,
                          stage_distance=ext.stage_kind, notes=ext.notes,
                          given=[q for q in list(verification.HISTORY_CHECKS) + ["f", "p"]
                                 if q not in pair["not_given"]],
                          not_given=pair["not_given"], history_rows=len(hist["s"]),
                          stages=len(stages), mapping=dict(mapping or {}),
                          mapped=list(ext.mapped)),
             distance_factor=factor,
             diagnosis=_diagnosis(pair, factor, cmp, ext.kind, verification.stage_unit_slips(
                 ref, stages, lambda r: unworn_profile(case, r), depth, sc["p0"])))
    if reference_solver is None:
        m["reference_band"] = dict(name=ref.name, method=ref.meta.get("method"),
                                   orders=ref.meta.get("orders"),
                                   provenance=ref.meta.get("provenance"),
                                   largest_share=_largest_band_share(pair))
    else:
        err = run.info.get("time_error")
        m["reference_band"] = dict(name=reference_solver, method="a fresh run: no band; its "
                                   "own time-error estimate is info.time_error",
                                   time_error=err.get("estimate") if isinstance(err, dict)
                                   else None)
    # each history row's difference against the tolerance, for the history figure
    judged = verification.row_differences(
        ref, hist, [q for q in verification.HISTORY_CHECKS if q not in pair["not_given"]],
        scales=sc, depth=depth, tolerances=dataclasses.asdict(cmp))
    _write(out, case, m, ref_case, run, ref_name, hist, stages, argv, t0,
           reference_solver is None, judged)
    return m


def _fresh_run_hint(case) -> str:
    """The --reference-solver options that can run ``case`` (as the registry says)."""
    able = registry.supporting(case)
    if not able:
        return ("no registered solver can run this case either (" + "; ".join(
            f"{n}: {registry.get(n).supports(case)}" for n in registry.names()) + ")")
    return " or ".join(f"--reference-solver {n}" for n in able) + \
        (" (the only solver that runs this case)" if len(able) == 1 else "")


def _largest_band_share(pair) -> dict | None:
    """The reference band's largest share of a tolerance over the stages judged."""
    best = None
    for st in pair["stages"]:
        for name, value in st.get("band", {}).items():
            if name not in st["checks"]:      # not judged: beyond a third of the tolerance
                continue
            share = value / st["checks"][name]["tolerance"]
            if best is None or share > best["share"]:
                best = dict(share=share, check=name, stage=st["index"],
                            s_hat=st["s_hat_reference"])
    return best


def _diagnosis(pair, factor, cmp, kind, slips) -> dict | None:
    """On a FAIL, the most likely cause: unit slips in the stages (``slips``, from
    :func:`verification.stage_unit_slips`), then the distance factor λ: "agree" only
    when λ lies strictly inside the searched range and the misfit there is within
    the verdict's tolerance; else a unit factor (mm or µm under a header in metres)
    that fits, else a pointer at the units when the history fits at no factor."""
    if pair["passed"]:
        return None
    reasons, lam = list(slips), None
    if factor is not None:
        lo, hi = factor["bounds"]
        lam, misfit, at_one = factor["factor"], factor["misfit"], factor["misfit_at_one"]
        # the misfit is an RMS relative difference of force, central wear and volume:
        # within the largest of their tolerances it is agreement
        tol = max(cmp.force_tolerance if q == "force" else cmp.profile_tolerance
                  for q in factor["quantities"])
        inside = lo * (1 + 1e-3) < lam < hi * (1 - 1e-3)
        units = [u for u in factor.get("unit_misfits", [])
                 if u["misfit"] is not None and u["misfit"] <= tol]
        if inside and abs(lam - 1.0) >= 1e-3 and misfit <= tol and misfit < 0.25 * at_one:
            reasons.append(
                f"your results agree with the reference at {lam:.4g} × your sliding "
                f"distances (misfit {misfit:.2g} there, {at_one:.2g} as given, over "
                # (your state at s is the reference's at λs: your K s = K_case λ s)
                f"{', '.join(factor['quantities'])}): your model wears {lam:.4g} times as "
                "fast as the case says; check the wear coefficient K = kμ/σ0 (k, μ, σ0) "
                "and the distance slid per step or cycle")
        elif units and kind == "s":
            u = min(units, key=lambda u: u["misfit"])
            said = {1e-3: "mm written under a header in metres (write 's [mm]')",
                    1e-6: "µm written under a header in metres (write 's [um]')",
                    1e3: "metres written under a header in mm"}[u["factor"]]
            reasons.append(f"your history agrees with the reference at {u['factor']:g} × "
                           f"your sliding distances (misfit {u['misfit']:.2g} there, "
                           f"{at_one:.2g} as given): {said}")
            lam = u["factor"]
        elif at_one > tol and not slips:
            at = f"{lam:.4g} ×" + ("" if inside else ", the end of that range")
            lam = None
            reasons.append(
                f"no factor on your sliding distances from {lo:g} to {hi:g} makes your "
                f"history agree with the reference (best misfit {misfit:.2g}, at {at}; "
                f"{at_one:.2g} as given): check the units of your columns: a header "
                "without a unit is SI (m, N, Pa, m³), distances in mm need 's [mm]' (a "
                "factor 1000), a force in kN 'force [kN]'")
    if not reasons:
        return None
    return dict(factor=lam, reason="; ".join(reasons))


def _write(out, case, m, ref_case, run, ref_name, hist, stages, argv, t0, certified_ref,
           judged=None):
    prov = rundir.provenance(argv)
    out = Path(out)
    with outputs.atomic_directory(out, "comparison") as tmp:
        (tmp / "reference").mkdir()
        extra = {"reference": m["reference_band"]} if certified_ref else None
        rundir.write_run_files(tmp / "reference", ref_case, run, ref_name, argv,
                               extra_meta=extra)
        (tmp / RESULTS).mkdir()
        write_results(tmp / RESULTS, hist, stages, m["scales"]["s_hat_per_m"])
        names = verify_figures.draw(tmp, case, m, run, hist, stages, judged)
        m["provenance"] = prov
        m["case_source"] = case.source
        m["seconds_total"] = time.perf_counter() - t0
        m["data_dictionary"] = layout.verification_dictionary()
        rundir.write_json(tmp / "metrics.json", m)
        (tmp / "case.toml").write_text(cases.to_toml(case), encoding="utf-8")
        blocks = verify_report.build_report(case, m, names, prov)
        report.write(tmp, blocks, f"wearcheck verify: {Path(case.source).name}")


def write_results(directory: Path, hist, stages, per_m) -> None:
    """The user's data as read, in SI: history.csv and stages.csv (long form)."""
    cols = ["s"] + [q for q in verification.HISTORY_CHECKS if q in hist]
    lines = [",".join(["s", "s_hat"] + cols[1:] + ["origin"])]
    for i in range(len(hist["s"])):
        vals = [hist["s"][i], hist["s"][i] * per_m] + [hist[q][i] for q in cols[1:]]
        # quoted: a file name in the origin may hold a comma
        origin = '"' + str(hist["origin"][i]).replace('"', '""') + '"'
        lines.append(",".join(f"{v:.12e}" for v in vals) + f",{origin}")
    (directory / "history.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    lines = ["s,s_hat,r,f,p"]
    for st in stages:
        f = st["f"] if st["f"] is not None else np.full(len(st["r"]), math.nan)
        p = st["p"] if st["p"] is not None else np.full(len(st["r"]), math.nan)
        for ri, fi, pi in zip(st["r"], f, p):
            lines.append(",".join(f"{v:.12e}" for v in (st["s"], st["s"] * per_m, ri, fi, pi)))
    (directory / "stages.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
