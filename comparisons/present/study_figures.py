"""Figures of the refinement studies in one directory (paper Fig. 4 and cost).

Drawn from what the directory holds: every ``refinement-<solver>.json`` and
the run directories it lists, so the MDR and FEM studies run into one
directory share ``cost.png`` and sit side by side in the other figures.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from wearcheck.extras import need

from wearcheck.comparisons.analysis.convergence import MEASURES
from wearcheck.cases import CaseError
from wearcheck import registry
from wearcheck.outputs import remove_study_file, write_study_file
from wearcheck.rundir import Run, provenance

FIGURES = ("fig4_profiles.png", "fig4_force.png", "convergence.png", "cost.png")
LABELS = {"profile": "profile / d0", "pressure": "pressure / p0",
          "pressure_interior": "pressure / p0 (interior)", "force": "force / F0"}


def studies(out: Path) -> list[dict]:
    """The refinement summaries in ``out``, MDR first."""
    found = []
    for path in sorted(Path(out).glob("refinement-*.json")):
        if path.name.endswith(".csv-metadata.json"):   # a CSV's sidecar, not a summary
            continue
        found.append(json.loads(path.read_text(encoding="utf-8")))
    order = {n: i for i, n in enumerate(registry.names())}
    return sorted(found, key=lambda s: order.get(s["solver"], len(order)))


def _save(fig, path: Path) -> None:
    """Save a PNG into its study atomically, the command line in its metadata."""
    write_study_file(path.parent, path.name, lambda tmp: fig.savefig(
        tmp, dpi=130, metadata={"Software": "wearcheck", "Description": provenance()["command"]}))


def _level_label(study, row):
    try:
        n = registry.get(study["solver"]).resolution_label
    except CaseError:
        n = "resolution"
    label = f"{n} = {row['resolution']}"
    return label + (f", Δŝ = {row['step_hat']:g}" if row["step_hat"] is not None else "")


def _with_differences(axes, study, curves):
    """Curves (row, x, y) on the upper axes; each minus the finest level's below."""
    finest = [c for c in curves if c[0]["name"] == study["finest"]]
    for row, x, y in curves:
        line, = axes[0].plot(x, y, label=_level_label(study, row))
        if finest and row["name"] != study["finest"]:
            _, xf, yf = finest[0]
            keep = (xf >= x[0]) & (xf <= x[-1])
            axes[1].plot(xf[keep], np.interp(xf[keep], x, y) - yf[keep], color=line.get_color())
    if curves:
        axes[0].legend(fontsize=8)
    axes[1].axhline(0.0, color="0.6", lw=0.8)


def write_figures(out: str | Path) -> list[Path]:
    """Draw the four study figures into ``out``; return their paths."""
    matplotlib = need("matplotlib", "drawing figures")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    out = Path(out)
    found = [s for s in studies(out) if s["finest"]]  # studies with a level that ran
    if not found:
        # figures of an earlier study would pass for this one's (the study
        # directory is ours: its marker was checked before the study ran)
        for name in FIGURES:
            remove_study_file(out, name)
        return []
    paths = []
    runs = {s["solver"]: [(row, Run(out / row["run_dir"])) for row in s["levels"]
                          if row["run_dir"] and (out / row["run_dir"] / "meta.json").is_file()]
            for s in found}

    # Fig. 4a: worn profiles at one stage, one curve per level; below, each
    # level minus the finest (on the finest level's r), where they differ
    fig, axes = plt.subplots(2, len(found), figsize=(5.5 * len(found), 6.4), squeeze=False,
                             sharex="col", gridspec_kw=dict(height_ratios=(2, 1)))
    for col, s in enumerate(found):
        stage = s["stage_s_hat"]
        curves = []
        for row, run in runs[s["solver"]]:
            st, sc = run.stages, run.scales
            k = np.flatnonzero(np.isclose(st["s_hat"], stage, rtol=1e-6, atol=1e-9))
            if k.size:
                curves.append((row, st["r"] / sc["a0"], st["f"][k[0]] / sc["d0"]))
        _with_differences(axes[:, col], s, curves)
        axes[0, col].set(ylabel="f / d0", title=f"{s['solver'].upper()}: worn profile at "
                                                f"ŝ = {stage:g}")
        axes[0, col].set_ylim(bottom=0.0)
        axes[1, col].set(xlabel="r / a0", ylabel="f/d0 − finest")
    fig.tight_layout()
    paths.append(out / "fig4_profiles.png")
    _save(fig, paths[-1])
    plt.close(fig)

    # Fig. 4b: normal force against sliding, one curve per level
    fig, axes = plt.subplots(2, len(found), figsize=(5.5 * len(found), 6.4), squeeze=False,
                             sharex="col", gridspec_kw=dict(height_ratios=(2, 1)))
    for col, s in enumerate(found):
        curves = []
        for row, run in runs[s["solver"]]:
            sc = run.scales
            curves.append((row, run.history["s"] * sc["s_hat_per_m"],
                           run.history["force"] / sc["F0"]))
        _with_differences(axes[:, col], s, curves)
        axes[0, col].set(ylabel="F / F0", title=f"{s['solver'].upper()}: normal force")
        axes[1, col].set(xlabel="ŝ = k μ E* s / (σ0 a0)", ylabel="F/F0 − finest")
    fig.tight_layout()
    paths.append(out / "fig4_force.png")
    _save(fig, paths[-1])
    plt.close(fig)

    # convergence: difference to the finest level against resolution, fitted order
    fig, axes = plt.subplots(1, len(found), figsize=(5.5 * len(found), 4.2), squeeze=False)
    for ax, s in zip(axes[0], found):
        by_res = s["refined"] == "resolution"
        rows = [r for r in s["levels"] if r["name"] != s["finest"] and r["status"] == "ok"]
        x = np.array([r["resolution"] if by_res else r["step_hat"] for r in rows], float)
        for m in MEASURES:
            e = np.array([r["differences"][m] for r in rows], float)
            if not np.any(e > 0) or m not in s["observed_order"]:
                continue
            fit = s["observed_order"][m]
            line, = ax.loglog(x, e, "o", label=f"{LABELS[m]}, p = {fit['order']:.2f}")
            succ = np.array([r.get("successive", {}).get(m, np.nan) for r in rows], float)
            ax.loglog(x, succ, "s", mfc="none", color=line.get_color(), ms=5)
            if math.isfinite(fit["order"]):
                # the fit, e = C h^p with h = 1/resolution (or the step), is to
                # the differences between successive levels (open squares)
                h = 1.0 / x if by_res else x
                ax.loglog(x, fit["constant"] * h ** fit["order"], "--", color=line.get_color())
        xlabel = (f"resolution ({s['resolution_key']})" if by_res else "step Δŝ")
        finest = [r for r in s["levels"] if r["name"] == s["finest"]][0]
        ax.set(xlabel=xlabel, ylabel="max difference",
               title=f"{s['solver'].upper()}: convergence, finest {_level_label(s, finest)}")
        handles, labels = ax.get_legend_handles_labels()
        if handles:
            handles += [Line2D([], [], ls="", marker="o", color="0.3"),
                        Line2D([], [], ls="", marker="s", mfc="none", color="0.3")]
            labels += ["to the finest level", "to the next level (fitted)"]
            ax.legend(handles, labels, fontsize=8)
    fig.tight_layout()
    paths.append(out / "convergence.png")
    _save(fig, paths[-1])
    plt.close(fig)

    # cost: difference to each solver's finest level against wall time
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, m in zip(axes, ("profile", "force")):
        for s in found:
            rows = [r for r in s["levels"] if r["name"] != s["finest"] and r["status"] == "ok"]
            t = [r["wall_seconds"] for r in rows]
            e = [r["differences"][m] for r in rows]
            line, = ax.loglog(t, e, "o-", label=f"{s['solver'].upper()}, wall time")
            # CPU time: what the run costs without other processes competing
            ax.loglog([r["cpu_seconds"] for r in rows], e, "o:", mfc="none",
                      color=line.get_color(), label=f"{s['solver'].upper()}, CPU time")
            for ti, ei, r in zip(t, e, rows):
                ax.annotate(str(r["resolution"]), (ti, ei), fontsize=7,
                            textcoords="offset points", xytext=(3, 3))
        ax.set(xlabel="time per run [s]", ylabel=f"max difference, {LABELS[m]}",
               title=f"cost against accuracy ({m})")
        ax.legend(fontsize=8)
    fig.tight_layout()
    paths.append(out / "cost.png")
    _save(fig, paths[-1])
    plt.close(fig)
    return paths
