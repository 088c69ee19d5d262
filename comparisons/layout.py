"""What wearcheck writes: the files of a run directory and of a comparison, every
column, array and field with its unit and meaning.

This is the one definition. ``rundir`` writes and reads by it, every
``meta.json`` carries the part that applies to its run (``data_dictionary``),
``metrics.json`` carries the comparison's, and the output tables of the
documentation (``docs/outputs.md``) are generated from it at every docs build
(:func:`doc_tables`). A solver documents its own extra history
columns and ``fields.npz`` arrays in its registry entry.
"""

from __future__ import annotations

from dataclasses import dataclass

from wearcheck.cases.result import HISTORY_COLUMNS


@dataclass(frozen=True)
class Item:
    """One file, column, array or field: its name, unit ("" when dimensionless) and meaning."""

    name: str
    unit: str
    meaning: str

    def as_dict(self) -> dict:
        return dict(unit=self.unit, meaning=self.meaning)


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
                          "checked against the closed forms"),
    Item("report.html", "", "the same, with its figures embedded"),
    Item("fretting_loops.png", "", "fretting runs: Q/μF against u/u* for the kept cycles, "
                                   "with the Mindlin–Deresiewicz loop"),
    Item("fretting_history.png", "", "fretting runs: stick radius, energy per cycle and worn "
                                     "volume against cycles"),
)

#: history.csv columns every solver writes, in this order
HISTORY = (
    Item("s", "m", "sliding distance"),
    Item("force", "N", "normal force F"),
    Item("depth", "m", "indentation depth d (approach of the unworn profile's tip)"),
    Item("contact_radius", "m", "contact radius a (BEM: radius of the circle of equal area)"),
    Item("wear_center", "m", "wear depth at r = 0"),
    Item("wear_volume", "m^3", "worn volume"),
)
assert tuple(i.name for i in HISTORY) == HISTORY_COLUMNS  # cases.result names them for solvers

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
    Item("solve_seconds", "s", "time in the solver proper"),
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
                      "reference), diagnosis (as `diagnosis`, for this solver; null when it "
                      "passed), passed"),
    Item("passed", "", "the verdict: every check of every solver within its tolerance"),
    Item("skipped", "", "per registered solver left out of the comparison: why (the "
                        "reason it cannot run the case, or not asked for)"),
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


def _table(items) -> dict:
    return {i.name: i.as_dict() for i in items}


UNDECLARED = "not declared by the solver's registry entry"


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
    }
