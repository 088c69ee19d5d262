"""The running-condition map of fretting: partial or gross slip, and wear per cycle.

One MDR fretting run per combination of the varied keys (typically
``fretting.amplitude`` and ``loading.force``) on the Dask runner of
:mod:`comparisons.distributed`; each run directory is kept. A run is in
partial slip when a stick zone survives its last cycle (stick radius > 0),
else in gross slip. ``fretting_map.csv`` lists every run with its regime,
the amplitude over the unworn gross-slip threshold u* = 3μF/(4G*a), the
worn volume per cycle and the energy dissipated in the last cycle;
``fretting_map.png`` draws the map: the first varied key on the x axis, the
second (if any) on the y axis, the marker giving the regime and its colour
the wear volume per cycle, with u*(F) drawn as the Cattaneo–Mindlin boundary
when the map is amplitude against normal force.
"""

from __future__ import annotations

import itertools
import math
import re
from pathlib import Path

import numpy as np

from wearcheck import cases
from wearcheck.cases import reference

from .distributed import Task, fmt, record_study, run_cases
from .runio import provenance, write_text_atomic

COLUMNS = ("run", "status", "regime", "amplitude_over_u_star", "u_star", "normal_force",
           "stick_radius_over_a0", "tangential_force_amplitude", "wear_volume_per_cycle",
           "energy_last_cycle", "wall_seconds")


def _dir_part(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._+-]+", "_", text).strip("_") or "_"


def tasks_for(varied: list[tuple[str, list[str]]]) -> list[Task]:
    """One MDR task per combination of the varied values."""
    names = [n for n, _ in varied]
    out = []
    for combo in itertools.product(*(vals for _, vals in varied)):
        name = "-".join(["fretting"] + [f"{n}-{_dir_part(v)}" for n, v in zip(names, combo)])
        out.append(Task(name, "mdr", tuple(f"{n}={v}" for n, v in zip(names, combo))))
    return out


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


def fretting_map(case_path, overrides, varied, out, *, scheduler=None, workers=None,
                 quiet=False, solve=None) -> list[dict]:
    """Run the map into ``out``; write fretting_map.csv and fretting_map.png; return the rows."""
    case = cases.load(case_path, overrides)
    if case.fretting is None:
        raise cases.CaseError(f"case '{case_path}' has no [fretting] section; the running-"
                              "condition map varies a fretting case")
    if not 1 <= len(varied) <= 2:
        raise cases.CaseError(f"fretting-map takes one or two --vary keys, got {len(varied)}")
    names = [n for n, _ in varied]
    if len(set(names)) != len(names):
        raise cases.CaseError("--vary names a key twice: " + ", ".join(names))
    both = set(names) & {o.partition("=")[0].strip() for o in overrides}
    if both:
        raise cases.CaseError(f"key {sorted(both)[0]} is both in --set and --vary")
    tasks = tasks_for(varied)
    prov = provenance()
    out = Path(out)
    outcomes = run_cases(case_path, overrides, tasks, out, scheduler=scheduler, workers=workers,
                         quiet=quiet, solve=solve, extra_meta=dict(study="fretting-map"))
    rows = []
    for t, o in zip(tasks, outcomes):
        row = summarise(o)
        row.update({n: ov.partition("=")[2] for n, ov in zip(names, t.overrides)})
        rows.append(row)
    record_study(out, "fretting-map", case, overrides, prov)
    head = [f"# wearcheck fretting-map: {', '.join(names)}",
            f"# command: {prov['command']}",
            "# regime: partial slip when a stick zone survives the last cycle; "
            "u_star = 3 mu F0 / (4 G* a0) of the unworn contact; wear_volume_per_cycle = "
            "final worn volume / cycles [m^3]; energy_last_cycle [J]",
            ",".join(list(names) + list(COLUMNS))]
    body = [",".join(_cell(r[k]) for k in list(names) + list(COLUMNS)) for r in rows]
    write_text_atomic(out / "fretting_map.csv", "\n".join(head + body) + "\n")
    write_figure(rows, names, out / "fretting_map.png")
    return rows


def _cell(v):
    if isinstance(v, str):
        return '"' + v.replace('"', "'") + '"'
    return fmt(v, ".10g")


def _label(name: str) -> str:
    """``section.key [unit]`` from the key's declaration."""
    from wearcheck.cases.schema import section_fields
    section, _, key = name.partition(".")
    unit = dict(section_fields(section))[key].metadata["unit"]
    return f"{name} [{unit}]" if unit and unit != "1" else name


def write_figure(rows, names, path: Path) -> Path:
    """The map: regime by marker, wear volume per cycle by colour."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = np.array([float(r[names[0]]) for r in rows])
    if len(names) > 1:
        y = np.array([float(r[names[1]]) for r in rows])
        ylabel = _label(names[1])
    else:
        y = np.array([r["wear_volume_per_cycle"] for r in rows], dtype=float)
        ylabel = "wear volume per cycle [m³]"
    wear = np.array([r["wear_volume_per_cycle"] for r in rows], dtype=float)
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    ok = np.isfinite(wear) & (wear > 0)
    norm = None
    if ok.any():
        norm = matplotlib.colors.LogNorm(vmin=wear[ok].min(), vmax=max(wear[ok].max(),
                                                                       wear[ok].min() * 1.01))
    sc = None
    for regime, marker in (("partial slip", "o"), ("gross slip", "^")):
        sel = np.array([r["regime"] == regime for r in rows]) & ok
        if sel.any():
            sc = ax.scatter(x[sel], y[sel], c=wear[sel], norm=norm, marker=marker, s=70,
                            cmap="viridis", edgecolors="k", label=regime)
    bad = np.array([r["status"] != "ok" for r in rows])
    if bad.any() and len(names) > 1:
        ax.scatter(x[bad], y[bad], marker="x", c="r", s=60, label="failed")
    if sc is not None:
        fig.colorbar(sc, ax=ax, label="wear volume per cycle [m³]")
    if names[0] == "fretting.amplitude" and len(names) > 1 and names[1] == "loading.force":
        # the Cattaneo–Mindlin boundary u*(F) of the unworn contacts
        pts = sorted({(float(r["normal_force"]), r["u_star"]) for r in rows
                      if r["status"] == "ok"})
        if pts:
            ax.plot([p[1] for p in pts], [p[0] for p in pts], "k--",
                    label="u* = 3μF/(4G*a)")
    if np.all(x > 0) and x.max() > 10 * x.min():
        ax.set_xscale("log")
    if len(names) == 1 and ok.any():
        ax.set_yscale("log")
    ax.set_xlabel(_label(names[0]))
    ax.set_ylabel(ylabel)
    ax.set_title("fretting running-condition map (MDR)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130, metadata={"Software": "wearcheck",
                                         "Description": provenance()["command"]})
    plt.close(fig)
    return path
