"""The report of a verification: verdict, what was read, the reference and its band,
the checks, per-stage metrics, figures and provenance, as ``present.report`` blocks."""

from __future__ import annotations

import math
import sys

from wearcheck import cases
from wearcheck.comparisons.analysis import metrics
from wearcheck.comparisons.present import report

_UNIT_WORDS = {"d": "d", "F0": "F0", "p0": "p0", "a0": "a0", "V": "π a0² d"}


def _label(column: str) -> str:
    return metrics.CHECK_BY_COLUMN[column].label


def failures(m) -> list[str]:
    """Each failed stage as 'stage k (ŝ = x; where it was read): label value > tolerance
    (of the stage's scale), ...'."""
    out = []
    pair = m["pairs"]["results"]
    for st in pair["stages"]:
        bad = []
        for name, c in st["checks"].items():
            if c["passed"]:
                continue
            of = " (floor)" if c["scale_from"] == "floor" else ""
            bad.append(f"{_label(name)} {report.fmt(c['value'])} > {c['tolerance']:g} of "
                       f"{report.fmt(c['scale'], 4)}·{_UNIT_WORDS[c['unit']]}{of}")
        if bad:
            out.append(f"stage {st['index']} (ŝ = {st['s_hat_reference']:.4g}; {st['origin']}): "
                       + ", ".join(bad))
    reach = pair.get("reach")
    if reach is not None and not reach["passed"]:
        per_m = m["scales"]["s_hat_per_m"]
        late = ", ".join(f"{s * per_m:.4g}" for s in reach["not_reached"])
        end = reach["end_s"]
        ends = (f"your results end at ŝ = {end * per_m:.4g} (s = {end:.4g} m)"
                if math.isfinite(end) else "your results hold no sliding distance")
        out.append(f"the case's stage(s) at ŝ = {late} not reached: {ends}, before the "
                   f"case's last stage at ŝ = {reach['not_reached'][-1] * per_m:.4g} "
                   f"(s = {reach['not_reached'][-1]:.4g} m)")
    last = pair.get("last_stage")
    if last is not None and not last["passed"] and (reach is None or reach["passed"]):
        per_m = m["scales"]["s_hat_per_m"]
        rows = " and ".join(f"ŝ = {s * per_m:.4g} (s = {s:.4g} m)"
                            for s in (last["below_s"], last["above_s"]) if math.isfinite(s))
        out.append(f"no row of your results near the case's last stage at ŝ = "
                   f"{last['last_s'] * per_m:.4g} (none judged from ŝ = "
                   f"{last['from_s'] * per_m:.4g} up to the reference's end): the nearest are "
                   f"at {rows}; check the unit of the sliding distance (a column without "
                   "one is in metres: 's [mm]', 's [um]')")
    rows = pair.get("rows")
    if rows is not None and not rows["passed"]:
        per_m = m["scales"]["s_hat_per_m"]
        out.append(f"{rows['failed']} of {rows['judged']} history row(s) between the stages "
                   "beyond a tolerance: " + ", ".join(
                       f"{_label(name)} {report.fmt(w['value'])} > {w['tolerance']:g} of "
                       f"{report.fmt(w['scale'], 4)} at ŝ = {w['s'] * per_m:.4g} ({w['origin']})"
                       for name, w in rows["worst"].items() if not w["passed"]))
    if not pair["stages"]:
        out.append("no stage could be judged" + (": " + "; ".join(pair["not_judged"])
                                                 if pair["not_judged"] else ""))
    return out


def verdict_text(m) -> str:
    pair = m["pairs"]["results"]
    if m["passed"]:
        return (f"{pair['stages_compared']} stage(s) judged against {m['reference_title']}; "
                "every check within its tolerance, each stage judged against its own scale.")
    return "failed: " + "; ".join(failures(m))


def build_report(case, m, figure_names, prov) -> list:
    """The report's blocks."""
    R, fmt = report, report.fmt
    pair = m["pairs"]["results"]
    res = m["results"]
    blocks = [R.verdict_block(m["passed"], verdict_text(m))]
    if m.get("diagnosis"):
        blocks.append(R.para("Most likely cause: " + m["diagnosis"]["reason"] + "."))
    blocks += [R.heading("What was read"),
               R.para(f"Results: {res['source']} ({res['format']}); sliding distance given as "
                      f"'{res['distance']}' (stages: '{res['stage_distance']}'); "
                      f"{res['history_rows']} history row(s), {res['stages']} stage(s)."
                      + (f" Mapping: {', '.join(f'{k}={v}' for k, v in res['mapping'].items())}."
                         if res["mapping"] else ""))]
    mapped = res.get("mapped", [])
    for line in mapped:
        blocks.append(R.para(f"Mapped: {line}."))
    if res["not_given"]:
        blocks.append(R.para("Not given, so not judged: " + ", ".join(res["not_given"]) + "."))
    for note in res["notes"]:
        if note not in mapped:
            blocks.append(R.para(f"Read: {note}."))
    for note in pair["not_judged"]:
        blocks.append(R.para(f"Not judged: {note}."))
    band = m.get("reference_band") or {}
    blocks.append(R.heading("The reference"))
    text = f"Reference: {m['reference_title']}. Method: {band.get('method') or '—'}."
    share = band.get("largest_share")
    if share:
        text += (f" Its estimated error uses at most {100 * share['share']:.2g} % of a "
                 f"tolerance ({_label(share['check'])} at stage {share['stage']}, ŝ = "
                 f"{share['s_hat']:.4g}).")
    elif band.get("time_error") is not None:
        text += f" Its time-error estimate: {band['time_error']:.2g}."
    blocks.append(R.para(text))
    sc = m["scales"]
    ind = case.indenter
    blocks += [R.heading("Case"),
               R.para(f"Case file: {case.source}. Profile: {ind.profile}; "
                      f"{case.loading.control} control; E* = {sc['E_star']:.4g} Pa; "
                      f"K = kμ/σ0 = {case.wear_rate:.4g} 1/Pa."),
               R.table(["scale", "value"],
                       [["a0 [m]", fmt(sc["a0"], 5)], ["d0 [m]", fmt(sc["d0"], 5)],
                        ["F0 [N]", fmt(sc["F0"], 5)], ["p0 [Pa]", fmt(sc["p0"], 5)],
                        ["profile scale d [m]", fmt(m["profile_scale_depth"], 5)],
                        ["ŝ per metre of sliding", fmt(sc["s_hat_per_m"], 5)]])]
    tol = m["tolerances"]
    rows = []
    for column in m["checks"]:
        c = metrics.CHECK_BY_COLUMN[column]
        rows.append([c.label, c.difference, c.scale, f"{tol[c.floor]:g}·{_UNIT_WORDS[c.unit]}",
                     f"{tol[c.tolerance]:g}", f"{c.tolerance}, {c.floor}"])
    blocks += [R.heading("Metrics per stage"),
               R.para("Each stage is judged at your distance and on your radii, the reference "
                      "evaluated there (your data are never interpolated). A check divides "
                      "the difference by the stage's own scale, or the floor where that is "
                      "smaller, and must not exceed the tolerance ([compare] keys of the "
                      "case). 'band' is the reference's own estimated error at the stage, "
                      "in the same relative units. A failed check is marked ✗; '—': not "
                      "judged at that stage."),
               R.table(["check", "difference", "judged against", "floor", "tolerance",
                        "[compare] keys"], rows)]
    header = ["stage", "ŝ", "read from"]
    for column in m["checks"]:
        header += [f"{_label(column)} / scale", "band"]
    table, values = [], []
    for st in pair["stages"]:
        row = [st["index"], fmt(st["s_hat_reference"], 4), st["origin"]]
        for column in m["checks"]:
            c = st["checks"].get(column)
            if c is None:
                row += ["—", "—"]
                continue
            row += [fmt(c["value"]) + ("" if c["passed"] else " ✗"),
                    fmt(st.get("band", {}).get(column))]
        table.append(row + ["pass" if st["passed"] else "FAIL"])
        ref, mine = st["reference"], st["results"]
        values.append([st["index"], fmt(st["s_hat_reference"], 4)]
                      + [f"{fmt(ref[q] / _unit(q, m), 5)} / {fmt(mine.get(q, float('nan')) / _unit(q, m), 5)}"
                         for q in ("force", "contact_radius", "wear_center", "wear_volume",
                                   "depth")]
                      + [fmt(st.get("profile_contact_max")), fmt(st.get("pressure_interior_max")),
                         fmt(st.get("pressure_edge_max"))])
    blocks.append(R.table(header + ["verdict"], table))
    blocks.append(R.para("Largest share of each tolerance used: " + "; ".join(
        f"{_label(check)} {100 * w['used']:.0f} % (stage {w['stage']})"
        for check, w in pair["worst"].items() if w["stage"] is not None) + "."))
    blocks.append(R.table(["stage", "ŝ", "F/F0 ref / yours", "a/a0 ref / yours",
                           "w(0)/d ref / yours", "V/(π a0² d) ref / yours", "d/d ref / yours",
                           "max|Δf|/d contact", "max|Δp|/p0 interior", "max|Δp|/p0 edge"],
                          values))
    h = pair["history"]
    rows = pair.get("rows") or dict(judged=0, failed=0)
    blocks.append(R.para(f"Over all {h['rows']} history rows the reference covers "
                         f"({rows['judged']} judged between the stages as the stages are, "
                         f"{rows['failed']} beyond a tolerance): " + ", ".join(
                             f"max |Δ{q}| = {fmt(h[q])}·{_unit_word(q)}"
                             for q in ("force", "contact_radius", "wear_center",
                                       "wear_volume", "depth") if q in h)
                         + (f"; {h['rows_beyond']} row(s) beyond it" if h["rows_beyond"]
                            else "") + "."))
    blocks.append(R.heading("Figures"))
    captions = {"fig_profiles.png": "Worn profiles f/d against r/a0: the reference (lines) and "
                                    "your results (markers) at each judged stage.",
                "fig_pressure.png": "Contact pressure p/p0 against r/a0: the reference (lines) "
                                    "and your results (markers).",
                "history.png": "Force, contact radius, central wear and worn volume (and "
                               "depth) against ŝ: the reference (line) and your history "
                               "rows (markers); below each, every row's difference relative "
                               "to the scale its check judges it against, in %, with the "
                               "tolerance as a band and the failed rows as red crosses."}
    for name in figure_names:
        blocks.append(R.image(name, captions.get(name, name)))
    blocks += [R.heading("Provenance"),
               R.para(f"Command: {prov['command']}"),
               R.para(f"Working directory: {prov['cwd']}; git revision: {prov['git_revision']}; "
                      f"created {prov['created']} on {prov['host']}."),
               R.table(["package", "version"], [[k, v or "—"] for k, v in
                                                prov["versions"].items()])]
    ref_prov = (band.get("provenance") or {})
    if ref_prov:
        blocks.append(R.para(f"The certified reference was made by: {ref_prov.get('command')} "
                             f"(wearcheck {ref_prov.get('wearcheck_version')}, revision "
                             f"{ref_prov.get('git_revision')}, {ref_prov.get('created')})."))
    blocks += [R.heading("Resolved case", 3), R.code(cases.to_toml(case))]
    return blocks


def _unit(q, m) -> float:
    sc = m["scales"]
    d = m["profile_scale_depth"]
    return dict(force=sc["F0"], contact_radius=sc["a0"], wear_center=d, depth=d,
                wear_volume=3.141592653589793 * sc["a0"] ** 2 * d)[q]


def _unit_word(q) -> str:
    return dict(force="F0", contact_radius="a0", wear_center="d", depth="d",
                wear_volume="π a0² d")[q]


def print_summary(m, out, stream=None) -> None:
    """A few lines for the terminal (default stderr): one per stage, the verdict, on a
    FAIL the failed checks and the likely cause, then one line per --map item saying
    what it read."""
    stream = sys.stderr if stream is None else stream
    pair = m["pairs"]["results"]
    print(f"results against {m['reference_title']} (differences relative to each stage's "
          "own scale):", file=stream)
    for st in pair["stages"]:
        cells = "  ".join(f"{_label(name)} {100 * c['value']:.2g}%" + ("" if c["passed"] else "!")
                          for name, c in st["checks"].items())
        print(f"  ŝ={st['s_hat_reference']:<7.4g} {cells}  {'ok' if st['passed'] else 'FAIL'}",
              file=stream)
    for note in pair["not_judged"]:
        print(f"  not judged: {note}", file=stream)
    if m["results"]["not_given"]:
        print("  not given: " + ", ".join(m["results"]["not_given"]), file=stream)
    print(f"verify: {'PASS' if m['passed'] else 'FAIL'} -> {out}/report.html", file=stream)
    if not m["passed"]:
        for line in failures(m):
            print(f"  {line}", file=stream)
        if m.get("diagnosis"):
            print(f"most likely cause: {m['diagnosis']['reason']}", file=stream)
    # which column, array or block each --map read: a verdict on a column the user did
    # not mean (a friction force named 'force') must not look like one on theirs
    for line in m["results"].get("mapped", []):
        print(f"  {line}", file=stream)
