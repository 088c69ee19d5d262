"""What wearcheck writes: the files of a run directory and of a comparison, every
column, array and field with its unit and meaning.

This is the one definition. ``rundir`` writes and reads by it, every
``meta.json`` carries the part that applies to its run (``data_dictionary``),
``metrics.json`` carries the comparison's, and the output tables of the
documentation (``docs/outputs.md``) are generated from it at every docs build
(:func:`doc_tables`). The history columns every solver writes are declared
once, in ``cases.result.HISTORY``; a solver declares its own extra history
columns and ``fields.npz`` arrays in its package's registration
(``mdr/registration.py``, ...).
"""

from __future__ import annotations

from wearcheck.cases.result import HISTORY, Item  # noqa: F401  (HISTORY: part of the layout)

#: files of a run directory (``wearcheck run``, and each solver's folder of a comparison)
RUN_FILES = (
    Item("case.toml", "", "the resolved case, every default filled in"),
    Item("history.csv", "", "one row per step: the history columns, then the solver's extras"),
    Item("stages.npz", "", "the stored stages: the stage arrays"),
    Item("meta.json", "", "scales, solver info, warnings, provenance and this data dictionary"),
    Item("fields.npz", "", "the solver's own arrays per stage, when it has any (its registry "
                           "entry's fields)"),
    Item(".wearcheck-output", "", "ownership marker, JSON: kind (run, comparison, study, vtk, "
                                  "render), complete, writer pid and host; only such a path is "
                                  "ever replaced, and only by the same kind"),
    Item("report.md", "", "fretting runs: loops, stick radius, energy and wear against cycles, "
                          "checked against the closed forms; both bodies wearing: the volumes "
                          "beside the ASTM G133/G99 formulas"),
    Item("report.html", "", "the same, with its figures embedded"),
    Item("fretting_loops.png", "", "fretting runs: Q/μF against u/u* for the kept cycles, "
                                   "with the Mindlin–Deresiewicz loop"),
    Item("fretting_history.png", "", "fretting runs: stick radius, energy per cycle and worn "
                                     "volume against cycles"),
    Item("track_profile.csv", "", "both bodies wearing: the track's cross-section per stage "
                                  "(stage, s, cycles, y, depth, height), profilometer-style"),
    Item("track_profiles.png", "", "both bodies wearing: the track's cross-sections"),
    Item("counterface_wear.pvd", "", "both bodies wearing: the counterface's wear map per "
                                     "stage, ImageData counterface_wear_KKK.vti"),
)

#: history.csv columns every solver writes, in this order: ``HISTORY``, declared
#: once in ``cases.result`` (solvers name them there); each solver's extra columns
#: are declared by its registration (``mdr/registration.py``, ...)

#: stages.npz arrays
STAGES = (
    Item("s", "m", "sliding distance of each stored stage (K,)"),
    Item("s_hat", "", "dimensionless sliding ŝ = k μ E* s / (σ0 a0) of each stage (K,)"),
    Item("r", "m", "radii of the stage fields (M,)"),
    Item("f", "m", "worn profile f(r), measured up from the unworn tip (K, M)"),
    Item("p", "Pa", "contact pressure p(r) (K, M)"),
)
#: stages.npz arrays that only some runs write (``RunResult.stage_extra``)
STAGES_OPTIONAL = (
    Item("tau", "Pa", "shear traction τ(r) (K, M); MDR fretting runs"),
)

#: meta.json keys
META = (
    Item("solver", "", "the solver's registry name"),
    Item("scales", "", "E_star, G_star [Pa], a0, d0 [m], F0 [N], p0 [Pa], s_hat_per_m [1/m]: "
                       "the unworn contact of the case's profile under its load"),
    Item("solve_seconds", "s", "wall-clock time in the solver proper (the machine's load "
                               "counts in it; no CPU time is recorded)"),
    Item("stages_requested_s_hat", "", "the stages the case asked for"),
    Item("stages_reached", "", "how many of them the run stored"),
    Item("warnings", "", "remarks on the case and the run (e.g. elastic similarity violated, "
                         "half-space theory stretched: docs/limits.md)"),
    Item("info", "", "the solver's facts about the run (steps, step used, grid, iterations)"),
    Item("command", "", "the command line that wrote this output"),
    Item("cwd", "", "the working directory of that command"),
    Item("wearcheck_version", "", "the version of wearcheck that wrote this output"),
    Item("git_revision", "", "wearcheck's git revision (with -dirty for local changes) when it "
                             "runs from a git checkout of wearcheck, else null"),
    Item("versions", "", "versions of Python, wearcheck and its dependencies"),
    Item("created", "", "local time of writing, ISO 8601"),
    Item("host", "", "the machine's name"),
    Item("data_dictionary", "", "units and meanings of every file, column, array and key"),
)
#: meta.json keys that only some runs write
META_OPTIONAL = (
    Item("profile_table", "", "indenter.profile = \"table\": the table read: file, sha256 "
                              "(of its bytes), rows, last_radius [m]"),
)

#: files of a comparison directory (``wearcheck compare``)
COMPARISON_FILES = (
    Item("<solver>/", "", "one run directory per compared solver"),
    Item("fig2_profiles.png/.pdf", "", "worn profiles f/d against r/a0 at the stages "
                                       "(paper Fig. 2a)"),
    Item("fig2_pressure.png/.pdf", "", "p/p0 against r/a0 (paper Fig. 2b; with the quadrature "
                                       "reference for a truncated paraboloid)"),
    Item("force_vs_sliding.png/.pdf", "", "F/F0 and a/a0 against ŝ for every solver"),
    Item("metrics.json", "", "every solver against the reference: the keys of METRICS"),
    Item("report.md/.html", "", "verdict, case, metrics tables, figures, edge peak, renders, "
                                "provenance (the HTML embeds its images)"),
    Item("case.toml", "", "the resolved case"),
    Item("edge_study/", "", "with --edge-study: runs at other grids and step, edge_peak.png"),
    Item("finite_sphere.png", "", "with --sphere-sweep: FEM force against the half-space's"),
    Item("scar.png", "", "a ball that slides: scar diameter and worn volume against cycles "
                         "(log axes) with the long-run asymptote and the lab's π D⁴/64R"),
)

#: metrics.json keys
METRICS = (
    Item("reference", "", "the solver every other is compared with"),
    Item("solvers", "", "the compared solvers, reference first"),
    Item("pairs", "", "per solver: stages (list of STAGE_METRICS), stages_compared, worst "
                      "(largest share of each tolerance), history (over the common sliding "
                      "range), checks (stages_reached: the same number of stages as the "
                      "reference; sliding_distance: its stages at the requested s), diagnosis (as `diagnosis`, for this solver; null when it "
                      "passed), passed"),
    Item("passed", "", "the verdict: every check of every solver within its tolerance"),
    Item("sliding_distance", "", "per solver (the reference too): its stages at the requested "
                                 "sliding distances (relative tolerance 1e-6) and inside its "
                                 "history's s range; stage, s_solver, s_requested of a mismatch"),
    Item("skipped", "", "per registered solver left out of the comparison: why (the "
                        "reason it cannot run the case or here, opt-in, or not asked for)"),
    Item("diagnosis", "", "null when passed; else for the worst failed check: setting (the "
                          "case key most likely to fix it, or null), value (its current "
                          "value), suggestion, solver, reason, otherwise (the runner-up), "
                          "rule, measures (per solver: points across the stage's contact "
                          "radius, share of the tolerance its time-error estimate uses)"),
    Item("stages_compared", "", "stages reached by every solver"),
    Item("scales", "", "as in meta.json"),
    Item("profile_scale_depth", "m", "the depth d profiles are measured in (held depth, or d0)"),
    Item("tolerances", "", "the [compare] keys"),
    Item("solve_seconds", "s", "per solver"),
    Item("grid_spacing_over_a0", "", "per solver: median spacing of its radii over a0"),
    Item("step_hat", "", "per solver: median sliding step in ŝ"),
    Item("run_end", "", "per solver: ŝ and F/F0 where the run ended"),
    Item("approximate", "", "per solver that solved an approximation of the case: why"),
    Item("run_warnings", "", "per solver, its remarks on its run (e.g. half-space theory "
                             "stretched; docs/limits.md)"),
    Item("anisotropy", "", "per solver with a square grid (BEM), per stage: largest "
                           "deviation of pressure (/p0) and wear (/d) from ring averages"),
    Item("edge_peaks", "", "per solver and stage: the edge-peak detector's finding"),
    Item("truncated_reference", "", "truncated paraboloid: each solver against the quadrature"),
    Item("edge_study", "", "with --edge-study: levels, peaks and verdicts per solver"),
    Item("sphere_sweep", "", "with --sphere-sweep: finite-body force against half-space"),
    Item("reference_note", "", "why the reference is not the default one (e.g. MDR solved "
                               "an approximation of the case)"),
    Item("scar", "", "per solver, at the end of the run: cycles, s, scar_diameter, "
                     "wear_center, wear_volume, lab_volume (π D⁴/64R), lab_volume_deviation, "
                     "and under force control archard_volume and the asymptotes [SI]"),
    Item("stages_requested_s_hat", "", "the stages the case asked for"),
    Item("stages_reached", "", "per solver: how many of them it stored"),
    Item("renders", "", "the pictures rendered into the run directories (relative paths)"),
    Item("render_notes", "", "what went wrong rendering, if anything"),
    Item("case_source", "", "the case file"),
    Item("seconds_total", "s", "wall time of the whole comparison"),
    Item("provenance", "", "command, cwd, git revision, versions, time, host"),
    Item("data_dictionary", "", "units and meanings of every file and key"),
)
#: metrics.json keys present only with their option or profile
METRICS_OPTIONAL = ("truncated_reference", "edge_study", "sphere_sweep", "reference_note",
                    "scar")

#: the per-stage entries of metrics.json pairs.<solver>.stages
STAGE_METRICS = (
    Item("s_hat_reference", "", "ŝ of the reference's stage"),
    Item("s_hat_solver", "", "ŝ of the compared solver's stage"),
    Item("force_reference", "", "F/F0 of the reference at the stage"),
    Item("force_solver", "", "F/F0 of the compared solver"),
    Item("force", "", "|ΔF|/F0"),
    Item("contact_radius_reference", "", "a/a0 of the reference"),
    Item("contact_radius_solver", "", "a/a0 of the compared solver"),
    Item("contact_radius", "", "|Δa|/a0"),
    Item("profile_max", "", "max |Δf|/d over the compared solver's radii"),
    Item("profile_rms", "", "RMS Δf/d"),
    Item("profile_contact_max", "", "max |Δf|/d over the contact and its edge band, r <= "
                                    "(1 + edge_band)·a (the larger a of the two)"),
    Item("profile_contact_rms", "", "RMS Δf/d there"),
    Item("pressure_interior_max", "", "max |Δp|/p0 in r < (1 - edge_band)·a"),
    Item("pressure_interior_rms", "", "RMS Δp/p0 there"),
    Item("pressure_edge_max", "", "max |Δp|/p0 in the edge band"),
    Item("pressure_edge_rms", "", "RMS Δp/p0 there"),
    Item("stage_scales", "", "per check, the stage's own scale in the unworn unit: the "
                             "reference's depth (or central wear, if larger) /d, force /F0, "
                             "peak pressure /p0, contact radius /a0"),
    Item("checks", "", "per check: value (the difference over scale), tolerance, scale "
                       "(max(the stage's own scale, the floor), in unit), scale_from ('stage' "
                       "or 'floor'), unit, unworn (the difference in unit), passed"),
    Item("passed", "", "every check of the stage within tolerance"),
)


#: files of a verification directory (``wearcheck verify``)
VERIFICATION_FILES = (
    Item("reference/", "", "the reference at the judged stages, a run directory (solver "
                           "'reference' with meta.json reference: band, method, provenance; or "
                           "the fresh run of --reference-solver)"),
    Item("results/history.csv", "", "the user's history as read, in SI: s [m], s_hat, the "
                                    "quantities given, and the origin (file and row) of each "
                                    "row"),
    Item("results/stages.csv", "", "the user's stages as read, long form, in SI: s, s_hat, r, "
                                   "f, p (NaN: not given)"),
    Item("fig_profiles.png/.pdf", "", "f/d against r/a0: the reference (lines), the results "
                                      "(markers), at each judged stage with a profile"),
    Item("fig_pressure.png/.pdf", "", "p/p0 against r/a0, the same"),
    Item("history.png/.pdf", "", "F/F0, a/a0, w(0)/d and V/(π a0² d) (and the depth) "
                                 "against ŝ; below each, every row's difference relative "
                                 "to its check's scale [%], the tolerance band, failed rows ×"),
    Item("metrics.json", "", "the verdict: the keys of VERIFICATION_METRICS"),
    Item("report.md/.html", "", "verdict, what was read, the reference and its band, the "
                                "checks, per-stage metrics, figures, provenance"),
    Item("case.toml", "", "the resolved case"),
)

#: metrics.json keys of a verification
VERIFICATION_METRICS = (
    Item("passed", "", "the verdict: every check of every judged stage within its tolerance"),
    Item("reference", "", "'reference' (certified) or the solver of --reference-solver"),
    Item("reference_title", "", "the reference in words"),
    Item("reference_band", "", "name, method, orders, provenance of the certified reference "
                               "and the largest share of a tolerance its band uses; or the "
                               "fresh run's time-error estimate"),
    Item("pairs", "", "results: stages (each with s, s_hat_reference, origin, reference and "
                      "results values [SI], the differences of STAGE_METRICS and of the wear "
                      "checks, stage_scales, checks, band (the reference's error relative to "
                      "each check's scale), passed), worst, checks_used, not_given, "
                      "not_judged (stages beyond the reference, stages without a history "
                      "row), history (largest differences over all rows), rows (the rows "
                      "between the stages: judged, failed, failed_rows {quantity: row "
                      "indices from 0}, worst), passed; a stage's row is the history row "
                      "judged at it (from 0, null when none)"),
    Item("checks", "", "the checks made (those of compare and wear_center, wear_volume, "
                       "depth, where given)"),
    Item("results", "", "source, format, distance (s, s_hat or cycles), given, not_given, "
                        "history_rows, stages, mapping, mapped (one line per --map item: what it "
                        "read), notes (what the reader decided)"),
    Item("distance_factor", "", "factor (the λ on the user's distances that fits the "
                                "reference best, within bounds), misfit, misfit_at_one, "
                                "quantities, bounds, unit_misfits (the misfit at 1e-3, "
                                "1e-6 and 1e3 × the distances: a unit slip)"),
    Item("diagnosis", "", "null, or on a FAIL the most likely cause: factor (the "
                          "distance factor that fits, or null), reason (unit slips of "
                          "the pressure or the profile, the distance factor, or the "
                          "units to check)"),
    Item("scales", "", "as in meta.json"),
    Item("profile_scale_depth", "m", "the depth d profiles are measured in"),
    Item("tolerances", "", "the [compare] keys"),
    Item("stages_compared", "", "stages judged"),
    Item("case_source", "", "the case file"),
    Item("seconds_total", "s", "wall time"),
    Item("provenance", "", "command, cwd, git revision, versions, time, host"),
    Item("data_dictionary", "", "units and meanings of every file and key"),
)

#: files of a fit directory (``wearcheck fit --out``)
FIT_FILES = (
    Item("case.toml", "", "the resolved case as given"),
    Item("fitted_case.toml", "", "the same with the fitted values (wear.specific_rate, "
                                 "wear.pressure_exponent)"),
    Item("fit.json", "", "what --json prints: parameters with their 95 % intervals, the lab "
                         "formula's K, the goodness of fit, the measurements, the model's runs"),
    Item("measurements.csv", "", "one row per measured value: the columns of FIT_COLUMNS"),
    Item("fit.png", "", "measured values and the fitted model against sliding, the lab "
                        "formula's line, and the residual of each measurement"),
    Item("meta.json", "", "resolved and fitted case, the measurement file (path, SHA-256), "
                          "warnings, provenance and this data dictionary"),
)
#: columns of a fit's measurements.csv (SI)
FIT_COLUMNS = (
    Item("row", "", "the row of the measurement file (its line number)"),
    Item("cycles", "", "cycles (empty when neither the sheet nor the stroke gives them)"),
    Item("s", "m", "sliding distance"),
    Item("quantity", "", "scar_diameter, ball_volume, wear_center, track_width, track_depth, "
                         "track_area or track_volume"),
    Item("unit", "", "the unit of measured, uncertainty and model: m, m^2 or m^3"),
    Item("measured", "(unit)", "the measured value"),
    Item("uncertainty", "(unit)", "its ± uncertainty (empty when the sheet gives none)"),
    Item("model", "(unit)", "the fitted model's value"),
    Item("residual", "", "(measured − model)/uncertainty, or ln(measured/model) without "
                         "uncertainties"),
    Item("lab_K", "m^3/(N m)", "the lab formula's K = V_lab/(F s) of this measurement (the "
                               "counterface's for a track quantity)"),
)


#: files a study writes into its directory (``wearcheck sweep``, ``refine``, ``fretting-map``);
#: each table ``NAME.csv`` is header and rows only, its metadata in ``NAME.csv-metadata.json``
STUDY_FILES = (
    Item("meta.json", "", "every study run into the directory: resolved base case, its "
                          "arguments, provenance"),
    Item("sweep.csv", "", "wearcheck sweep: one row per run, the columns of SWEEP_COLUMNS"),
    Item("refinement-<solver>.csv", "", "wearcheck refine: one row per level, the columns of "
                                        "REFINEMENT_COLUMNS"),
    Item("refinement.csv", "", "every refine study in the directory in one table, a solver "
                               "column first"),
    Item("refinement-<solver>.json", "", "the refine summary: levels, observed orders, "
                                         "Richardson's estimate, converged level"),
    Item("fretting_map.csv", "", "wearcheck fretting-map: one row per run, the varied keys "
                                 "then the columns of FRETTING_MAP_COLUMNS"),
    Item("NAME.csv-metadata.json", "", "beside each CSV above: W3C CSV on the Web metadata "
                                       "(dc:title, dc:source = the command line, notes, and "
                                       "each column's name, titles, dc:description and unit)"),
)

#: columns every study table shares
_TASK_COLUMNS = (
    Item("status", "", "ok, or the run's error"),
    Item("wall_seconds", "s", "wall time of the task in its worker (case, solve; not writing)"),
    Item("cpu_seconds", "s", "CPU time of the task in its worker"),
    Item("solve_seconds", "s", "wall-clock time in the solver proper"),
    Item("peak_rss_mb", "MB", "worker process RSS, sampled every 10 ms during the task"),
    Item("steps", "", "steps the run took"),
)

#: sweep.csv columns (after ``run``, one column per varied case key, in the case's units)
SWEEP_COLUMNS = (
    Item("run", "", "the run's directory in the study"),
    *_TASK_COLUMNS,
    Item("final_s", "m", "sliding distance at the end of the run"),
    Item("final_s_hat", "", "dimensionless sliding ŝ at the end of the run"),
    Item("final_F_over_F0", "", "normal force at the end over F0 of the run's unworn contact"),
    Item("final_wear_center_over_d0", "", "wear depth at the centre at the end over d0"),
    Item("final_contact_radius_over_a0", "", "contact radius at the end over a0"),
)

#: refinement-<solver>.csv columns (refinement.csv: ``solver`` first, then these)
REFINEMENT_COLUMNS = (
    Item("solver", "", "refinement.csv: the study's solver"),
    Item("level", "", "the level's run directory"),
    Item("resolution", "", "the refined resolution (elements, mesh size, ...) of the level"),
    Item("step_hat", "", "the level's step in ŝ"),
    *_TASK_COLUMNS,
    Item("final_s_hat", "", "dimensionless sliding ŝ at the end of the run"),
    Item("F/F0 at s_hat=<stage>", "", "normal force over F0 at each stage of the case"),
    Item("profile_difference", "", "largest difference of the worn profile to the finest "
                                   "level, over d0"),
    Item("pressure_difference", "", "largest difference of the pressure to the finest level, "
                                    "over p0"),
    Item("pressure_interior_difference", "", "the same without the edge band "
                                             "(compare.edge_band)"),
    Item("force_difference", "", "largest difference of the force to the finest level, "
                                 "over F0"),
)

#: fretting_map.csv columns (after one column per varied case key)
FRETTING_MAP_COLUMNS = (
    Item("run", "", "the run's directory in the study"),
    Item("status", "", "ok, or the run's error"),
    Item("regime", "", "partial slip when a stick zone survives the last cycle, else gross "
                       "slip"),
    Item("amplitude_over_u_star", "", "displacement amplitude over u* = 3 μ F0/(4 G* a0) of "
                                      "the unworn contact"),
    Item("u_star", "m", "u* = 3 μ F0/(4 G* a0), the amplitude of full sliding"),
    Item("normal_force", "N", "normal force at the end"),
    Item("stick_radius_over_a0", "", "stick radius of the last cycle over a0"),
    Item("tangential_force_amplitude", "N", "tangential force amplitude of the last cycle"),
    Item("wear_volume_per_cycle", "m^3", "final worn volume over cycles"),
    Item("energy_last_cycle", "J", "energy dissipated in the last cycle"),
    Item("wall_seconds", "s", "wall time of the task in its worker"),
)


def _table(items) -> dict:
    return {i.name: i.as_dict() for i in items}


UNDECLARED = "not declared by the solver's registration"


def run_dictionary(solver=None, history_names=(), field_names=(), stage_names=(),
                   meta_names=()) -> dict:
    """The data dictionary of one run directory (written into its meta.json).

    ``solver`` is its registry entry (or None): its extra history columns and
    fields that the run wrote are added (a solver may write different extras
    by mode, e.g. the MDR's fretting runs); written columns and fields it does
    not declare are listed as undeclared, never left out. ``stage_names``: the
    optional stages.npz arrays written (``STAGES_OPTIONAL``); ``meta_names``:
    the optional meta.json keys written (``META_OPTIONAL``).
    """
    history = _table(HISTORY)
    fields = {}
    info = ""
    if solver is not None:
        history.update({k: v for k, v in _table(solver.history_columns).items()
                        if k in history_names})
        fields = {k: v for k, v in _table(solver.fields).items() if k in field_names}
        info = solver.description
    stages = _table(STAGES)
    optional = _table(STAGES_OPTIONAL)
    for name in stage_names:
        stages[name] = optional.get(name, dict(unit="?", meaning="not declared in layout.py"))
    for name in history_names:
        history.setdefault(name, dict(unit="?", meaning=UNDECLARED))
    for name in field_names:
        fields.setdefault(name, dict(unit="?", meaning=UNDECLARED))
    meta = _table(META)
    meta.update({k: v for k, v in _table(META_OPTIONAL).items() if k in meta_names})
    return dict(files=_table(RUN_FILES), history_csv=history, stages_npz=stages,
                fields_npz=fields, meta_json=meta, solver=info)


def comparison_dictionary() -> dict:
    """The data dictionary of a comparison directory (written into metrics.json)."""
    return dict(files=_table(COMPARISON_FILES), metrics_json=_table(METRICS),
                stage_metrics=_table(STAGE_METRICS))


def verification_dictionary() -> dict:
    """The data dictionary of a verification directory (written into metrics.json)."""
    return dict(files=_table(VERIFICATION_FILES), metrics_json=_table(VERIFICATION_METRICS),
                stage_metrics=_table(STAGE_METRICS))


def fit_dictionary() -> dict:
    """The data dictionary of a fit directory (written into its meta.json)."""
    return dict(files=_table(FIT_FILES), measurements_csv=_table(FIT_COLUMNS))


def markdown(items, first="name") -> str:
    """A Markdown table of items (the documentation's output tables)."""
    rows = [f"| {first} | unit | meaning |", "|---|---|---|"]
    rows += [f"| `{i.name}` | {i.unit} | {i.meaning} |" for i in items]
    return "\n".join(rows)


def doc_tables() -> dict[str, str]:
    """The documentation's output tables, by name (``docs/outputs.md`` includes
    each as ``_generated/layout-NAME.md``, written at every docs build)."""
    return {
        "run-files": markdown(RUN_FILES, "file"),
        "history": markdown(HISTORY, "column"),
        "stages": markdown(STAGES + STAGES_OPTIONAL, "array"),
        "meta": markdown(META + META_OPTIONAL, "key"),
        "comparison-files": markdown(COMPARISON_FILES, "file"),
        "metrics": markdown(METRICS, "key"),
        "stage-metrics": markdown(STAGE_METRICS, "key"),
        "verification-files": markdown(VERIFICATION_FILES, "file"),
        "verification-metrics": markdown(VERIFICATION_METRICS, "key"),
        "fit-files": markdown(FIT_FILES, "file"),
        "fit-columns": markdown(FIT_COLUMNS, "column"),
        "study-files": markdown(STUDY_FILES, "file"),
        "sweep-columns": markdown(SWEEP_COLUMNS, "column"),
        "refinement-columns": markdown(REFINEMENT_COLUMNS, "column"),
        "fretting-map-columns": markdown(FRETTING_MAP_COLUMNS, "column"),
    }
