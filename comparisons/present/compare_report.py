"""The report of a comparison: verdict, case, per-solver metrics, figures, edge peak,
finite sphere, renders and provenance, as ``present.report`` blocks.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

from wearcheck import cases
from wearcheck import registry
from wearcheck.comparisons.analysis import diagnosis, edge_peak, metrics
from wearcheck.comparisons.present import report


def title(name: str) -> str:
    """A solver's name as reports show it ("MDR"); unregistered names upper-cased."""
    try:
        return registry.get(name).title
    except cases.CaseError:
        return name.upper()


#: the caption of each figure a comparison may draw ({styles}: each solver's line or marker)
CAPTIONS = {
    "fig2_profiles.png": "Worn profiles f/d against r/a0 (paper Fig. 2a): {styles}.",
    "fig2_pressure.png": "Contact pressure p/p0 against r/a0 (paper Fig. 2b): {styles}.",
    "force_vs_sliding.png": "Normal force F/F0 and contact radius a/a0 against ŝ.",
    "scar.png": "Scar diameter and worn volume against cycles (log axes), each solver's, "
                "with the volume a laboratory computes from the diameter (π D⁴/64R) and "
                "the constant-force asymptotes.",
}


def build_report(case, m, figure_names, renders, render_notes, prov) -> list:
    """The report's blocks (see ``present.report``)."""
    R = report
    sc = m["scales"]
    fmt = R.fmt
    blocks = []
    K = m["stages_compared"]
    verdict_text = (f"{K} stage(s) compared; every check within its tolerance, each stage "
                    "judged against its own force, peak pressure, depth and contact radius."
                    if m["passed"] else _failure_text(m))
    blocks.append(R.verdict_block(m["passed"], verdict_text))
    if not m["passed"] and m.get("diagnosis"):
        blocks.append(R.para("Most likely fix: " + diagnosis.sentence(m["diagnosis"])))
    blocks += _skipped_blocks(m)
    ind = case.indenter
    blocks += [R.heading("Case"),
               R.para(f"Case file: {case.source}. Profile: {ind.profile}"
                      + (f", R = {ind.radius:g} m" if ind.radius else "")
                      + (f", b = {ind.flat_radius:g} m" if ind.flat_radius else "")
                      + f"; {case.loading.control} control; E* = {sc['E_star']:.4g} Pa."),
               R.table(["scale", "value"],
                       [["a0 [m]", fmt(sc["a0"], 5)], ["d0 [m]", fmt(sc["d0"], 5)],
                        ["F0 [N]", fmt(sc["F0"], 5)], ["p0 [Pa]", fmt(sc["p0"], 5)],
                        ["profile scale d [m]", fmt(m["profile_scale_depth"], 5)],
                        ["a0/R", fmt(sc["a0"] / ind.radius, 4) if ind.radius else "—"],
                        ["ŝ per metre of sliding", fmt(sc["s_hat_per_m"], 5)]]),
               R.para(f"Method: every solver is compared with the reference, "
                      f"{title(m['reference'])}. Stage k of each solver is the k-th requested "
                      "ŝ; the stages both reached are compared. The reference's fields are "
                      "interpolated linearly onto the other solver's radii and the differences "
                      "taken there. "
                      "The tables report profiles relative to d, pressures to p0, forces to "
                      "F0, contact radii to a0; the verdict judges each stage against its "
                      "own scale (below). Force, contact radius and depth of a stage are read "
                      "from the run's history at the stage's sliding distance. The pressure "
                      "is compared "
                      f"in the interior r < (1 − {case.compare.edge_band:g})·a (a: the smaller "
                      "of the two contact radii) and reported separately in the edge band up "
                      f"to (1 + {case.compare.edge_band:g})·a of the larger one. F0 and a0 are "
                      "the analytic half-space values of the unworn contact, so at ŝ = 0 the "
                      "columns F/F0 and a/a0 measure each solver against that solution."),
               R.para(f"Stages requested (ŝ): {', '.join(f'{s:g}' for s in case.stages.s_hat)}; "
                      "reached: " + ", ".join(f"{title(n)} {k}" for n, k in
                                              m["stages_reached"].items())
                      + f"; compared: {K}. Runs ended at "
                      + ", ".join(f"ŝ = {e['s_hat']:.4g} with F/F0 = {e['force']:.4g} ({title(n)})"
                                  for n, e in m["run_end"].items()) + ".")]
    for w in case.warnings:
        blocks.append(R.para(f"Note: {w}"))
    for n, text in m.get("approximate", {}).items():
        blocks.append(R.para(f"Approximate: {title(n)} — {text}"))
    approximate = m.get("approximate", {})
    for names, t in _shared_remarks(m.get("run_warnings", {})):
        names = [n for n in names if t != approximate.get(n)]
        if names:
            blocks.append(R.para(f"Note: {', '.join(map(title, names))} — {t}"))
    if m.get("reference_note"):
        blocks.append(R.para(f"Reference: {m['reference_note']}."))
    blocks += _checks_blocks(m)
    for name, pair in m["pairs"].items():
        blocks += _pair_blocks(m, name, pair)
    blocks.append(R.para("Solve time: " + ", ".join(
        f"{title(n)} {v:.3g} s" for n, v in m["solve_seconds"].items())
        + ". Grid spacing / a0: " + ", ".join(
        f"{title(n)} {fmt(v)}" for n, v in m["grid_spacing_over_a0"].items())
        + ". Step Δŝ (median): " + ", ".join(
        f"{title(n)} {fmt(v)}" for n, v in m["step_hat"].items()) + "."))
    blocks.append(R.heading("Figures"))
    styles = ", ".join(f"{title(n)} {'markers' if registry.get(n).style.get('marker') else 'lines'}"
                       for n in m["solvers"])
    captions = {name: text.format(styles=styles) for name, text in CAPTIONS.items()}
    for name in figure_names:
        blocks.append(R.image(name, captions.get(name, name)))
    tr = m.get("truncated_reference")
    if tr is not None:
        blocks += [R.heading("Flattened sphere against the reference (paper Fig. 3)"),
                   R.para(f"Truncated paraboloid, b/a0 = {tr['flat_radius_over_a0']:.4g}; "
                          f"reference contact radius a/a0 = {tr['contact_radius']:.5g}, force "
                          f"F/F0 = {tr['force']:.5g}. Pressure differences relative to p0, "
                          f"away from the edge and from the singularity "
                          f"(|r − b| ≥ {case.compare.edge_band:g}·a)."),
                   R.table(["solver", "|ΔF|/F0", "|Δa|/a0", "max|Δp|/p0 away", "rms",
                            "max|Δp|/p0 near b", "max|Δp|/p0 edge", "verdict"],
                           [[title(n), fmt(v["force"]), fmt(v["contact_radius"]),
                             fmt(v["pressure_interior_max"]), fmt(v["pressure_interior_rms"]),
                             fmt(v["pressure_near_b_max"]), fmt(v["pressure_edge_max"]),
                             "pass" if v["passed"] else "FAIL"]
                            for n, v in tr["solvers"].items()])]
    blocks += _scar_blocks(m)
    blocks += _anisotropy_blocks(m)
    blocks += _edge_blocks(m)
    if "sphere_sweep" in m:
        blocks += _sphere_blocks(m["sphere_sweep"])
    blocks.append(R.heading("Renders of the fields"))
    if renders:
        for name in renders:
            solver, stem = name.split("/")[0], Path(name).stem
            blocks.append(R.image(name, f"{title(solver)} run, rendered off-screen: "
                                        f"{stem.replace('_', ' ')} ({name})."))
    else:
        blocks.append(R.para("No renders in the run directories."))
    for note in render_notes:
        blocks.append(R.para(note))
    blocks += [R.heading("Provenance"),
               R.para(f"Command: {prov['command']}"),
               R.para(f"Working directory: {prov['cwd']}; git revision: {prov['git_revision']}; "
                      f"created {prov['created']} on {prov['host']}."),
               R.table(["package", "version"],
                       [[k, v or "—"] for k, v in prov["versions"].items()]),
               R.heading("Resolved case", 3), R.code(cases.to_toml(case))]
    return blocks


def _skipped_blocks(m) -> list:
    """The registered solvers the comparison left out, each with its reason."""
    skipped = m.get("skipped") or {}
    if not skipped:
        return []
    return [report.para("Skipped: " + "; ".join(f"{title(n)} — {why}"
                                                 for n, why in skipped.items()) + ".")]


def _checks_blocks(m) -> list:
    """What decides the verdict: each check's difference, scale, floor and tolerance."""
    R = report
    tol = m["tolerances"]
    rows = [[c.label, c.difference, c.scale, f"{tol[c.floor]:g}·{c.unit}",
             f"{tol[c.tolerance]:g}", f"{c.tolerance}, {c.floor}"] for c in metrics.CHECKS]
    return [R.heading("Metrics per stage"),
            R.para("Each check divides a stage's difference by that stage's own scale, or by "
                   "the floor where the scale is smaller (so that a quantity near zero is not "
                   "judged relative to itself), and must not exceed the tolerance. The "
                   "second table of each solver gives the same differences in the unworn "
                   "scales (d, F0, p0, a0); those do not decide the verdict. A failed check "
                   "is marked ✗."),
            R.table(["check", "difference", "judged against", "floor", "tolerance",
                     "[compare] keys"], rows)]


def _pair_blocks(m, name, pair) -> list:
    """The verdict table and the metrics table of one solver against the reference."""
    R = report
    fmt = R.fmt
    sc = m["scales"]
    ref, other = title(m["reference"]), title(name)
    blocks = [R.heading(f"{other} against {ref}", 3)]
    verdict_rows, rows = [], []
    for st in pair["stages"]:
        c = st["checks"]

        def judged(check):
            x = c[check.column]
            scale = f"{fmt(x['scale'], 4)}·{x['unit']}" + (" (floor)" if x["scale_from"] ==
                                                           "floor" else "")
            return [fmt(x["value"]) + ("" if x["passed"] else " ✗"), scale]
        verdict_rows.append([st["index"], fmt(st["s_hat_reference"])]
                            + sum((judged(ch) for ch in metrics.CHECKS), [])
                            + ["pass" if st["passed"] else "FAIL"])
        rows.append([st["index"], fmt(st["s_hat_reference"]), fmt(st["s_hat_solver"]),
                     fmt(st["force_reference"], 4), fmt(st["force_solver"], 4),
                     fmt(st["force"]), fmt(st["contact_radius_reference"], 4),
                     fmt(st["contact_radius_solver"], 4), fmt(st["contact_radius"]),
                     fmt(st["profile_contact_max"]), fmt(st["profile_max"]),
                     fmt(st["profile_rms"]), fmt(st["pressure_interior_max"]),
                     fmt(st["pressure_interior_rms"]), fmt(st["pressure_edge_max"]),
                     fmt(st["pressure_edge_rms"])])
    blocks.append(R.para("Largest share of each tolerance used: " + "; ".join(
        f"{metrics.CHECK_BY_COLUMN[check].label} {100 * w['used']:.0f}% (stage {w['stage']}, "
        f"{fmt(w['value'])} of {fmt(w['tolerance'])})" for check, w in pair["worst"].items()
        if w["stage"] is not None) + "."))
    if pair.get("diagnosis"):
        blocks.append(R.para("Most likely fix: " + diagnosis.sentence(pair["diagnosis"])))
    header = ["stage", "ŝ"]
    for ch in metrics.CHECKS:
        header += [f"{ch.label} / scale", f"{ch.label} scale"]
    blocks.append(R.table(header + ["verdict"], verdict_rows))
    blocks.append(R.table(["stage", f"ŝ {ref}", f"ŝ {other}", f"F/F0 {ref}", f"F/F0 {other}",
                           "|ΔF|/F0", f"a/a0 {ref}", f"a/a0 {other}", "|Δa|/a0",
                           "max|Δf|/d contact", "max|Δf|/d all r", "rms Δf/d",
                           "max|Δp|/p0 interior", "rms Δp/p0 interior", "max|Δp|/p0 edge",
                           "rms Δp/p0 edge"], rows))
    h = pair["history"]
    blocks.append(R.para(f"Over the whole common sliding range (ŝ ≤ "
                         f"{fmt(h['s_common_max'] * sc['s_hat_per_m'])}): max |ΔF|/F0 = "
                         f"{fmt(h['force_max'])}, max |Δa|/a0 = {fmt(h['contact_radius_max'])} "
                         f"({other} history interpolated onto {ref}'s steps; not part of the "
                         "verdict)."))
    return blocks


def _scar_blocks(m) -> list:
    """What an experimenter reads off at the end of the test, per solver."""
    scars = m.get("scar")
    if not scars:
        return []
    R, fmt = report, report.fmt
    rows = []
    for n, t in scars.items():
        rows.append([title(n), fmt(t.get("cycles"), 4), fmt(t["s"], 4),
                     fmt(t["scar_diameter"] * 1e3, 4), fmt(t["wear_center"] * 1e6, 4),
                     fmt(t["wear_volume"] * 1e9, 4), fmt(t["lab_volume"] * 1e9, 4),
                     f"{100 * t['lab_volume_deviation']:+.2f} %",
                     fmt(t["asymptote_diameter"] * 1e3, 4) if "asymptote_diameter" in t
                     else "—"])
    return [R.heading("The scar (what a wear rig measures)"),
            R.para("At the end of the run: scar diameter D (where the wear exceeds 1e-3 of "
                   "its largest value), central wear depth, true worn volume, and the volume "
                   "a laboratory computes from D by the ball formula π D⁴/(64 R), which "
                   "ignores the elastic recovery of the worn surface. Under constant force "
                   "the scar tends to 2(4 R K F s/π)^(1/4) (docs/time-stepping.md). Figure: "
                   "scar.png."),
            R.table(["solver", "cycles", "s [m]", "D [mm]", "central wear [µm]",
                     "V [mm³]", "V lab [mm³]", "V lab / V − 1", "D asymptote [mm]"], rows)]


def _anisotropy_blocks(m) -> list:
    """The BEM's square grid against round contacts: deviation from ring averages."""
    rows = []
    for n, info in m.get("anisotropy", {}).items():
        for k, (pi, w) in enumerate(zip(info.get("pressure_interior", []),
                                        info.get("wear", []))):
            rows.append([title(n), k, report.fmt(pi), report.fmt(w)])
    if not rows:
        return []
    return [report.heading("Anisotropy of the grid", 3),
            report.para("Largest deviation of the pressure (on the rings wholly in contact, "
                        "relative to p0) and of the wear depth (relative to d) from their "
                        "azimuthal averages, per stage: what a square grid does to a round "
                        "contact."),
            report.table(["solver", "stage", "max |p − ⟨p⟩|/p0", "max |w − ⟨w⟩|/d"], rows)]


def _failed_check(name, c) -> str:
    """One failed check: its value and tolerance, relative to what."""
    label = metrics.CHECK_BY_COLUMN[name].label if name in metrics.CHECK_BY_COLUMN else name
    if "scale" not in c:
        return f"{label} {report.fmt(c['value'])} > {c['tolerance']:g}"
    of = ("the floor" if c["scale_from"] == "floor" else "the stage's own")
    return (f"{label} {report.fmt(c['value'])} > {c['tolerance']:g} of {of} scale "
            f"{report.fmt(c['scale'], 4)}·{c['unit']}")


def _sliding_distance_text(name, c) -> str:
    """One failed sliding-distance check (metrics.sliding_distance_check) in words."""
    k, s_k, r_k = c["stage"], c["s_solver"], c["s_requested"]
    if c["reason"] == "history":
        return (f"{name} stage {k} at s = {s_k:.6g} m lies outside its history's sliding "
                f"range s = {c['history_s_min']:.6g} to {c['history_s_max']:.6g} m")
    return (f"{name} stage {k} at s = {s_k:.6g} m, the case's stage {k} at s = {r_k:.6g} m "
            f"(relative tolerance {c['tolerance']:g}): its sliding distances are not "
            f"the requested ones")


def _failure_text(m) -> str:
    failed = []
    for solver, pair in m["pairs"].items():
        for st in pair["stages"]:
            for name, c in st["checks"].items():
                if not c["passed"]:
                    failed.append(f"{title(solver)} stage {st['index']} "
                                  f"(ŝ={st['s_hat_reference']:.3g}) " + _failed_check(name, c))
    tr = m.get("truncated_reference")
    if tr is not None:
        for n, v in tr["solvers"].items():
            for name, c in v["checks"].items():
                if not c["passed"]:
                    failed.append(f"{title(n)} vs reference " + _failed_check(name, c))
        if not tr["solvers"]:
            failed.append("no solver has an ŝ = 0 stage to compare with the reference")
    for solver, pair in m["pairs"].items():
        c = pair.get("checks", {}).get("stages_reached")
        if c and not c["passed"]:
            failed.append(f"{title(solver)} reached {c['value']} stage(s), "
                          f"{title(m['reference'])} {c['tolerance']}")
    for solver, c in m.get("sliding_distance", {}).items():
        if not c["passed"]:
            failed.append(_sliding_distance_text(title(solver), c))
    if m["stages_compared"] == 0:
        failed.append("no stage reached by every solver")
    return "failed: " + "; ".join(failed)


def _peak_cell(q, with_edge=True) -> str:
    """One peak in a table cell: position, height, prominence (relative to p(0))."""
    if not q["present"]:
        if not with_edge:
            return "none"
        return f"none (p_edge/p(0)={report.fmt(q.get('edge_height'), 3)})"
    text = (f"r/a={report.fmt(q['r_over_a'], 4)}, p/p(0)={report.fmt(q['height'], 4)}, "
            f"prom.={report.fmt(q['prominence'], 2)}")
    return text + (" (last node)" if q["at_last_node"] else "")


def _edge_blocks(m) -> list:
    R = report
    fmt = R.fmt
    blocks = [R.heading("Edge peak (paper Section 4)"),
              R.para(f"An interior local maximum of p(r) in r ≥ {edge_peak.OUTER:g}·a counts as "
                     f"a peak when its prominence (height above the dip inward of it) exceeds "
                     f"{edge_peak.MIN_PROMINENCE:g} of max p. Cells give its position r/a, its "
                     "height p_peak/p(0) and its prominence relative to p(0); \"last node\": "
                     "the maximum is the outermost node in contact (not resolved by the grid). "
                     f"p_edge/p(0): the pressure at r = {edge_peak.EDGE_PROBE:g}·a relative to "
                     "p(0), how abruptly it falls to zero at the edge (Hertz: "
                     f"{math.sqrt(1 - edge_peak.EDGE_PROBE ** 2):.3f}).")]
    peaks = m["edge_peaks"]
    K = max(len(v) for v in peaks.values())
    rows = []
    for k in range(K):
        first = next((v[k] for v in peaks.values() if k < len(v)), None)
        row = [k, fmt(first["s_hat"]) if first else "—"]
        for name in peaks:
            q = peaks[name][k] if k < len(peaks[name]) else None
            row += [_peak_cell(q, False), fmt(q["edge_height"])] if q else ["—", "—"]
        rows.append(row)
    header = ["stage", "ŝ"]
    for name in peaks:
        header += [f"{title(name)} peak", f"{title(name)} p_edge/p(0)"]
    blocks.append(R.table(header, rows))
    es = m.get("edge_study")
    if es is None:
        blocks.append(R.para("Resolution study not run (wearcheck compare --edge-study)."))
        return blocks
    blocks.append(R.heading("Edge peak at other resolutions and steps", 3))
    for name, sol in es["solvers"].items():
        lv = sol["levels"]
        blocks.append(R.para(f"{title(name)} levels: " + "; ".join(
            f"{d['label']}: spacing {fmt(d['spacing'])}·a0, Δŝ {fmt(d['step_hat'])}, "
            f"{d['seconds']:.3g} s" for d in lv)))
        for f in sol["failed"]:
            blocks.append(R.para(f"{title(name)} {f['label']} failed: {f['error']}"))
        rows = []
        for st in sol["stages"]:
            rows.append([st["stage"], fmt(st["levels"][0].get("s_hat"))]
                        + [_peak_cell(d) for d in st["levels"]]
                        + [f"{st['verdict']}: {st['reason']}"])
        labels = [d["label"].split(" (")[0] for d in lv]
        blocks.append(R.table(["stage", "ŝ"] + [f"{title(name)} {x}" for x in labels]
                              + ["verdict"], rows))
    blocks.append(R.para("Answer: " + es["summary"]))
    if es.get("figure"):
        blocks.append(R.image(es["figure"], "p/p(0) against r/a near the edge at every level "
                                            "(each solver in its own colour map)."))
    return blocks


def _sphere_blocks(sw) -> list:
    R = report
    fmt = R.fmt
    rows = []
    for r in sw["rows"]:
        if "error" in r:
            rows.append([fmt(r["a0_over_R"]), fmt(r["depth"], 4), "failed: " + r["error"], "",
                         "", ""])
        else:
            rows.append([fmt(r["a0_over_R"]), fmt(r["depth"], 4), fmt(r["force_solver"], 5),
                         fmt(r["force_half_space"], 5), f"{100 * r['force_rel']:+.3f}%",
                         f"{100 * r['contact_radius_rel']:+.3f}%"])
    shipped = "; ".join(f"{k}: a0/R = {v['a0_over_R']:.4g} (worn up to √2·a0: "
                        f"{v['worn_max_over_R']:.4g})" for k, v in sw["shipped"].items())
    lim = sw["largest_ratio_within_tolerance"]
    return [R.heading("Finite sphere against the half-space"),
            R.para(f"{title(sw['solver'])} ({sw['profile']}) pressed without sliding to the depth whose "
                   "half-space contact radius is a0; force compared with the half-space value "
                   "(cases.reference.unworn_contact). The difference includes the FEM's own "
                   "discretisation error."),
            R.table(["a0/R", "depth [m]", f"F {title(sw['solver'])} [N]", "F half-space [N]", "ΔF/F",
                     "Δa/a"], rows),
            R.para(f"Within the force tolerance {sw['force_tolerance']:g}: a0/R ≤ "
                   f"{fmt(lim)} (every swept ratio up to it). Fit over a0/R ≤ 0.02: ΔF/F ≈ "
                   f"{fmt(sw['slope'])}·a0/R (docs/theory.md §13: a0/R scaling, constant measured), so the "
                   f"finite sphere alone uses the whole force tolerance at a0/R ≈ "
                   f"{fmt(sw['ratio_at_tolerance'])}. Shipped cases: {shipped}."),
            ] + ([R.image(sw["figure"], f"{title(sw['solver'])} force relative to the half-space force against "
                                        "a0/R.")] if sw.get("figure") else [])


def _shared_remarks(run_warnings: dict) -> list[tuple[list[str], str]]:
    """Each solver's remarks, a text that several solvers made (a remark on the case's
    unworn contact, e.g. the yield estimate) once with their names, in first-seen order."""
    said: dict[str, list[str]] = {}
    for name, texts in run_warnings.items():
        for text in texts:
            said.setdefault(text, []).append(name)
    return [(names, text) for text, names in said.items()]


def print_summary(m, out, stream=None) -> None:
    """A few lines for the terminal: one per compared solver and stage (default: stderr),
    the solvers skipped and why, and on a FAIL the setting most likely to fix it.

    The default is looked up at the call: a stream bound at import time may be
    one that was replaced and closed since (a notebook's, a test's capture).
    """
    stream = sys.stderr if stream is None else stream
    ref = title(m["reference"])
    for name, why in (m.get("skipped") or {}).items():
        print(f"skipped {title(name)}: {why}", file=stream)
    for names, text in _shared_remarks(m.get("run_warnings", {})):
        print(f"note: {', '.join(map(title, names))}: {text}", file=stream)
    for name, pair in m["pairs"].items():
        print(f"{title(name)} against {ref} (differences relative to each stage's own scale):",
              file=stream)
        for st in pair["stages"]:
            c = st["checks"]
            cells = "  ".join(f"{ch.label} {100 * c[ch.column]['value']:.2g}%"
                              + ("" if c[ch.column]["passed"] else "!")
                              for ch in metrics.CHECKS)
            print(f"  ŝ={st['s_hat_reference']:<6.3g} F/F0 {st['force_reference']:.4f}/"
                  f"{st['force_solver']:.4f}  {cells}  {'ok' if st['passed'] else 'FAIL'}",
                  file=stream)
    print(f"compare: {'PASS' if m['passed'] else 'FAIL'} -> {out}/report.html", file=stream)
    if not m["passed"] and m.get("diagnosis"):
        print(f"most likely fix: {diagnosis.sentence(m['diagnosis'])}", file=stream)
