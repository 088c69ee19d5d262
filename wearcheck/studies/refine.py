"""Refinement studies on Dask (``wearcheck refine``): one solver at several resolutions.

Runs the case at a sequence of resolutions (and optionally sliding steps),
one run directory per level in DIR, and writes ``refinement-<solver>.csv`` and
``.json`` (differences to the finest level, observed order, Richardson's
estimate, coarsest converged level) and the figures ``fig4_profiles.png``,
``fig4_force.png``, ``convergence.png`` and ``cost.png``. Studies of several solvers
run into the same DIR coexist: ``refinement.csv`` holds every study found there
(a ``solver`` column first), and the figures show them all.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from wearcheck import cases
from wearcheck import registry
from wearcheck.comparisons.analysis import convergence as rf
from wearcheck.studies.distributed import Task, fmt as _fmt, record_study, run_cases
from wearcheck.studies.sweep import refuse_unsupported
from wearcheck import csv_metadata
from wearcheck.csv_metadata import describer, sidecar_name, write_table
from wearcheck.layout import REFINEMENT_COLUMNS
from wearcheck.outputs import study_lock, write_study_text

#: the sidecars' column descriptions
describe = describer(REFINEMENT_COLUMNS, [("F/F0 at s_hat=", next(
    c for c in REFINEMENT_COLUMNS if c.name.startswith("F/F0 at s_hat=")))])
from wearcheck.comparisons.present.study_figures import FIGURES
from wearcheck.rundir import jsonable, provenance


def refine(case: cases.Case, solver: str, out, *, levels=None, steps=None, tolerance=0.01,
           stage=None, scheduler=None, workers=None, quiet=False, solve=None) -> dict:
    """Run a refinement study of ``case`` into ``out``; return its summary (as in the JSON).

    ``levels``: resolutions (the solver's resolution key; default its registry
    levels); ``steps``: ``sliding.step_hat`` per level (one: all); ``stage``: the
    stage ŝ of the profile figure and Richardson's estimate. ``solve`` replaces
    the solver (tests inject one with a known order).
    """
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float)) \
            or not tolerance > 0:
        raise cases.ArgumentError("tolerance", "must be a number > 0", value=tolerance)
    if stage is not None and stage not in case.stages.s_hat:
        raise cases.ArgumentError("stage", "not a stage of the case; stages.s_hat = "
                                  f"{list(case.stages.s_hat)}", value=stage)
    lvls = rf.levels(solver, levels, steps)
    for lv in lvls:  # a level the case cannot take is refused before any run starts
        try:
            case.derive(lv.changes)
        except cases.CaseError as exc:
            named = "steps" if "sliding.step_hat" in str(exc) else "levels"
            raise cases.ArgumentError(named, str(exc)) from None
    refuse_unsupported(case, solver, [lv.changes for lv in lvls], every=True)
    varied = rf.refined_parameter(lvls)
    tasks = [Task(lv.name, solver, lv.changes) for lv in lvls]
    out = Path(out)
    prov = provenance()
    # finest (longest) levels first, so that the short ones fill in around them
    outcomes = run_cases(case, tasks[::-1], out, scheduler=scheduler,
                         workers=workers, quiet=quiet, solve=solve,
                         extra_meta=dict(study=f"refine-{solver}"),
                         study_files=("meta.json", f"refinement-{solver}.json",
                                      f"refinement-{solver}.csv", "refinement.csv",
                                      sidecar_name(f"refinement-{solver}.csv"),
                                      sidecar_name("refinement.csv"),
                                      *FIGURES))[::-1]
    summary = summarize(case, solver, lvls, outcomes, varied, tolerance, stage)
    summary.update(case=str(case.source), provenance=prov)
    written = False
    try:
        # one study at a time: refinement.csv and the figures combine every
        # study in the directory, meta.json records each
        with study_lock(out):
            record_study(out, f"refine-{solver}", case, prov,
                         dict(solver=solver, levels=levels, steps=steps, tolerance=tolerance,
                              stage=stage))
            write_study_text(out, f"refinement-{solver}.json",
                             json.dumps(jsonable(summary), indent=2) + "\n")
            written = True
            command = prov["command"]
            write_table(out, f"refinement-{solver}.csv", csv_text(summary),
                        title=f"wearcheck refine, solver {solver}", command=command,
                        notes=csv_notes(summary), describe=describe)
            write_table(out, "refinement.csv", combined_csv_text(out),
                        title="wearcheck refine: every study in the directory",
                        command=command, notes=combined_notes(out), describe=describe)
            from wearcheck.comparisons.present.study_figures import write_figures
            write_figures(out)
    except KeyboardInterrupt as exc:
        exc.summary_written = written  # for the CLI's message: what is on disk
        raise
    return summary


def summarize(case, solver, lvls, outcomes, varied, tolerance, stage) -> dict:
    """Differences to the finest level, orders, Richardson, converged level."""
    from wearcheck.cases.reference import scales as case_scales
    sols = [rf.scaled(o.result, case_scales(o.case)) if o.ok else None for o in outcomes]
    ok = [i for i, s in enumerate(sols) if s is not None]
    stages = list(case.stages.s_hat)
    rows = []
    for lv, o, sol in zip(lvls, outcomes, sols):
        rows.append(dict(
            name=lv.name, resolution=lv.resolution, step_hat=lv.step_hat,
            h=rf.refinement_h(lv, varied), status=o.status, wall_seconds=o.wall_seconds,
            cpu_seconds=o.cpu_seconds,
            solve_seconds=o.result.solve_seconds if o.ok else math.nan,
            peak_rss_mb=o.peak_rss_mb, start_rss_mb=o.start_rss_mb,
            steps=len(sol.s_hat) - 1 if sol else None,
            final_s_hat=float(sol.s_hat[-1]) if sol else math.nan,
            stage_force=dict(zip(stages, rf.stage_forces(sol, stages).tolist()))
            if sol else dict.fromkeys(stages, math.nan),
            run_dir=o.task.name if o.ok else None,
            traceback=o.traceback or None))
    summary = dict(study="refine", solver=solver, resolution_key=registry.get(solver).resolution_key,
                   refined=varied, tolerance=tolerance, levels=rows, finest=None,
                   stage_s_hat=stage, observed_order={}, richardson=None, converged=None)
    for row in rows:
        row["differences"] = dict.fromkeys(rf.MEASURES, math.nan)
    if not ok:
        return summary
    finest = ok[-1]
    summary["finest"] = rows[finest]["name"]
    edge = case.compare.edge_band
    for i in ok:
        rows[i]["differences"] = rf.differences(sols[i], sols[finest], edge)
    # the order from differences between successive levels: for e = C h^p and a
    # constant ratio they are exactly ∝ h^p, where differences to the finest
    # level, C (h^p - h_f^p), bend the log-log line near the finest level
    for i, j in zip(ok, ok[1:]):
        rows[i]["successive"] = rf.differences(sols[i], sols[j], edge)
    fit = ok[:-1]
    for m in rf.MEASURES:
        p, c = rf.observed_order([rows[i]["h"] for i in fit],
                                 [rows[i]["successive"][m] for i in fit])
        summary["observed_order"][m] = dict(order=p, constant=c, levels=len(fit) + 1)
    # the stage shown and extrapolated: the last one every successful level reached
    if stage is None:
        reached = [s for s in stages if all(math.isfinite(rows[i]["stage_force"][s]) for i in ok)]
        stage = reached[-1] if reached else stages[0]
    summary["stage_s_hat"] = stage
    if len(ok) >= 3:
        three = ok[-3:]
        h = [rows[i]["h"] for i in three]
        by_stage = {}
        for st in stages:
            q = [rows[i]["stage_force"][st] for i in three]
            p, q_star = rf.richardson(h, q)
            by_stage[st] = dict(values=q, order=p, estimate=q_star,
                                finest_error=abs(q[-1] - q_star))
        summary["richardson"] = dict(quantity=f"F/F0 at stage ŝ = {stage:g}",
                                     levels=[rows[i]["name"] for i in three],
                                     **by_stage[stage], by_stage=by_stage)
    worst = [max(r["differences"]["profile"], r["differences"]["force"]) for r in rows]
    i = rf.coarsest_converged(worst, tolerance)
    summary["converged"] = dict(
        tolerance=tolerance, measures=["profile (rel. d0)", "force (rel. F0)"],
        level=rows[i]["name"] if i is not None else None,
        resolution=rows[i]["resolution"] if i is not None else None,
        step_hat=rows[i]["step_hat"] if i is not None else None)
    return summary


def csv_notes(summary: dict) -> list[str]:
    """refinement-<solver>.csv's notes (its sidecar's): the summary in sentences."""
    prov = summary["provenance"]
    notes = [f"wearcheck refine, solver {summary['solver']}: differences to the finest "
             f"level {summary['finest']}.",
             f"Command: {prov['command']}.",
             f"Git revision: {prov['git_revision']}; versions and resolved case: meta.json.",
             "Profile rel. d0, pressure rel. p0 (interior: without the edge band), force "
             "rel. F0; wall/cpu_seconds: the task in its worker (case, solve; not writing), "
             "peak_rss_mb: worker process RSS sampled every 10 ms during the task."]
    for m, fit in summary["observed_order"].items():
        notes.append(f"Observed order {m}: {_fmt(fit['order'], '.3f')} (log-log fit of the "
                     f"differences between successive levels, {fit['levels']} levels).")
    rich = summary["richardson"]
    if rich:
        notes.append(f"Richardson ({', '.join(rich['levels'])}), F/F0 at each stage "
                     "(order -> estimate; nan: not monotone): "
                     + "; ".join(f"s_hat={float(st):g}: {_fmt(r['order'], '.3f')} -> "
                                 f"{_fmt(r['estimate'], '.7g')}"
                                 for st, r in rich["by_stage"].items()) + ".")
    conv = summary["converged"]
    if conv:
        notes.append(f"Coarsest converged level within {conv['tolerance']:g}: "
                     f"{conv['level'] or 'none coarser than the finest'}.")
    return notes


def csv_text(summary: dict) -> str:
    """refinement-<solver>.csv: one row per level (its notes: :func:`csv_notes`)."""
    stages = list(summary["levels"][0]["stage_force"]) if summary["levels"] else []
    cols = (["level", "resolution", "step_hat", "status", "wall_seconds", "cpu_seconds",
             "solve_seconds",
             "peak_rss_mb", "steps", "final_s_hat"]
            + [f"F/F0 at s_hat={s:g}" for s in stages]
            + [f"{m}_difference" for m in rf.MEASURES])
    lines = [",".join(cols)]
    for r in summary["levels"]:
        d = r["differences"]
        vals = ([r["name"], r["resolution"], r["step_hat"],
                 '"' + r["status"].replace('"', "'") + '"',
                 r["wall_seconds"], r["cpu_seconds"], r["solve_seconds"], r["peak_rss_mb"],
                 r["steps"],
                 r["final_s_hat"]]
                + [r["stage_force"][s] for s in stages] + [d[m] for m in rf.MEASURES])
        lines.append(",".join(_fmt(v, ".10g") for v in vals))
    return "\n".join(lines) + "\n"


def combined_csv_text(out: Path) -> str:
    """refinement.csv: every study in ``out`` in one table, a ``solver`` column first.

    Built from the per-solver CSV files (so the two never disagree), also those an
    earlier version wrote with ``#`` lines above the header; columns a study lacks
    (e.g. stages of another case) stay empty.
    """
    rows, columns = [], ["solver"]
    for path in _per_solver_tables(out):
        solver = path.stem.removeprefix("refinement-")
        table = csv_metadata.read_rows(path)
        columns += [c for r in table[:1] for c in r if c not in columns]
        if not table:
            columns += [c for c in csv_metadata.header(path.read_text(encoding="utf-8"))
                        if c not in columns]
        rows += [dict(row, solver=solver) for row in table]
    return csv_metadata.rows_text(columns, rows)


def combined_notes(out: Path) -> list[str]:
    """refinement.csv's notes: those of every per-solver table, in its order."""
    return [n for path in _per_solver_tables(out) for n in csv_metadata.read_notes(path)]


def _per_solver_tables(out: Path) -> list[Path]:
    return sorted(p for p in Path(out).glob("refinement-*.csv") if p.is_file())


def table(summary: dict) -> str:
    """The printed table: one line per level, then orders and the converged level."""
    key = summary["resolution_key"]
    lines = [f"{'level':<28} {key:>16} {'step':>8} {'wall s':>8} {'cpu s':>8} {'MB':>6} "
             f"{'profile/d0':>11} {'p/p0':>9} {'p/p0 int':>9} {'F/F0':>9}  status"]
    for r in summary["levels"]:
        d = r["differences"]
        lines.append(f"{r['name']:<28} {r['resolution']:>16} {_fmt(r['step_hat']):>8} "
                     f"{_fmt(r['wall_seconds'], '.3g'):>8} {_fmt(r['cpu_seconds'], '.3g'):>8} "
                     f"{_fmt(r['peak_rss_mb'], '.0f'):>6} "
                     + " ".join(f"{_fmt(d[m], '.2e'):>{w}}" for m, w in
                                zip(rf.MEASURES, (11, 9, 9, 9)))
                     + f"  {r['status']}")
    per = "1/resolution" if summary["refined"] == "resolution" else "step"
    for m, fit in summary["observed_order"].items():
        lines.append(f"observed order, {m}: {_fmt(fit['order'], '.2f')} (difference between "
                     f"successive levels ∝ ({per})^p, {fit['levels']} levels)")
    rich = summary["richardson"]
    if rich:
        lines.append(f"Richardson ({', '.join(rich['levels'])}), F/F0 at each stage ŝ "
                     "(NaN: not monotone in the three levels):")
        for st, r in rich["by_stage"].items():
            lines.append(f"  ŝ = {float(st):<6g} order {_fmt(r['order'], '.2f'):>5}, estimate "
                         f"{_fmt(r['estimate'], '.7g'):>10}, finest level off by "
                         f"{_fmt(r['finest_error'], '.2e')}")
    conv = summary["converged"]
    if conv:
        lines.append(f"coarsest level converged within {conv['tolerance']:g} (profile/d0, "
                     f"F/F0): {conv['level'] or 'none coarser than the finest'}")
    return "\n".join(lines)
