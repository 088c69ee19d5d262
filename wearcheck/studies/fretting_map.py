"""The running-condition map of fretting: partial or gross slip, and wear per cycle.

One MDR fretting run per combination of the varied keys (typically
``fretting.amplitude`` and ``loading.force``) on the Dask runner of
:mod:`wearcheck.studies.distributed`; each run directory is kept. A run is in
partial slip when a stick zone survives its last cycle (stick radius > 0),
else in gross slip. ``fretting_map.csv`` lists every run with its regime,
the amplitude over the unworn gross-slip threshold u* = 3μF/(4G*a), the
worn volume per cycle and the energy dissipated in the last cycle;
``fretting_map.png`` draws the map
(:mod:`wearcheck.comparisons.present.fretting_map_figure`).
"""

from __future__ import annotations

import math
from pathlib import Path

from wearcheck import cases
from wearcheck.cases import reference

from wearcheck.csv_metadata import describer, sidecar_name, write_table
from wearcheck.layout import FRETTING_MAP_COLUMNS
from wearcheck.outputs import write_study_file
from wearcheck.rundir import provenance
from wearcheck.studies.distributed import record_study, run_cases
from wearcheck.studies.sweep import (check_varied, csv_cell, tasks_for,
                                                 varied_column, varied_values)

COLUMNS = tuple(c.name for c in FRETTING_MAP_COLUMNS)

#: the sidecar's column descriptions
describe = describer(FRETTING_MAP_COLUMNS)


def summarise(outcome) -> dict:
    """One map row from a run's outcome (regime, u*, wear per cycle)."""
    row = dict.fromkeys(COLUMNS, math.nan)
    row.update(run=outcome.task.name, status=outcome.status, regime="",
               wall_seconds=outcome.wall_seconds)
    if not outcome.ok:
        return row
    case, h = outcome.case, outcome.result.history
    sc = reference.scales(case)
    u_star = 3.0 * case.wear.mu * sc["F0"] / (4.0 * case.G_star * sc["a0"])
    amp = float(h["displacement_amplitude"][-1])
    row.update(regime="partial slip" if h["stick_radius"][-1] > 0.0 else "gross slip",
               amplitude_over_u_star=amp / u_star, u_star=u_star,
               normal_force=float(h["force"][-1]),
               stick_radius_over_a0=float(h["stick_radius"][-1]) / sc["a0"],
               tangential_force_amplitude=float(h["tangential_force_amplitude"][-1]),
               wear_volume_per_cycle=float(h["wear_volume"][-1]) / max(h["cycles"][-1], 1.0),
               energy_last_cycle=float(h["energy_per_cycle"][-1]))
    return row


def fretting_map(case: cases.Case, vary, out, *, scheduler=None, workers=None,
                 quiet=False, solve=None) -> list[dict]:
    """Run the map of ``case`` into ``out``; write fretting_map.csv and fretting_map.png;
    return the rows.

    ``vary``: one or two case keys and their values, ``{"fretting.amplitude": [1e-7,
    1e-6], "loading.force": [1.0, 2.0]}`` (Python values, as ``Case.derive`` takes them).
    """
    if case.fretting is None:
        raise cases.CaseError(f"case '{case.source}' has no [fretting] section; the running-"
                              "condition map varies a fretting case")
    values = varied_values(vary)
    if not 1 <= len(values) <= 2:
        raise cases.ArgumentError("vary", f"the map takes one or two keys, got {len(values)}",
                                  value=list(values))
    check_varied(case, values)
    names = list(values)
    tasks = tasks_for("fretting", "mdr", values)
    prov = provenance()
    out = Path(out)
    outcomes = run_cases(case, tasks, out, scheduler=scheduler, workers=workers,
                         quiet=quiet, solve=solve, extra_meta=dict(study="fretting-map"),
                         study_files=("meta.json", "fretting_map.csv",
                                      sidecar_name("fretting_map.csv"), "fretting_map.png"))
    rows = []
    for t, o in zip(tasks, outcomes):
        row = summarise(o)
        row.update(t.changes)
        rows.append(row)
    record_study(out, "fretting-map", case, prov, dict(vary=values))
    notes = [f"wearcheck fretting-map: {', '.join(names)}.",
             f"Command: {prov['command']}.",
             "regime: partial slip when a stick zone survives the last cycle; u_star = 3 mu "
             "F0 / (4 G* a0) of the unworn contact; wear_volume_per_cycle = final worn volume "
             "/ cycles [m^3]; energy_last_cycle [J]."]
    head = [",".join(list(names) + list(COLUMNS))]
    body = [",".join(csv_cell(r[k]) for k in list(names) + list(COLUMNS)) for r in rows]
    write_table(out, "fretting_map.csv", "\n".join(head + body) + "\n",
                title="wearcheck fretting-map", command=prov["command"], notes=notes,
                describe=lambda c: varied_column(c) if "." in c else describe(c))
    from wearcheck.comparisons.present.fretting_map_figure import write_figure
    write_study_file(out, "fretting_map.png", lambda tmp: write_figure(rows, names, tmp))
    return rows
