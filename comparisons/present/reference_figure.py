"""A certified reference at a glance: worn profiles and pressures at some of its stored
stages, and its history (one PNG; the documentation draws one per benchmark)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.comparisons.analysis import verification
from wearcheck.comparisons.present import figures


def draw(ref, path: str | Path, stages: int = 6) -> Path:
    """``path``: the PNG of reference ``ref`` (a ``references.certified.Reference``)."""
    plt = figures._pyplot()
    sc = ref.scales
    case = ref.case
    d = case.loading.depth if case.loading.control == "depth" else sc["d0"]
    units = verification.unit_scales(sc, d)
    per_m = sc["s_hat_per_m"]
    picks = np.unique(np.round(np.linspace(0, len(ref.stage_s) - 1, stages)).astype(int))
    fig, axes = plt.subplots(1, 3, figsize=(14.0, 3.9))
    colours = figures._colours(len(picks))
    r_max = 0.0
    cycles = case.fretting is not None or case.stages.cycles is not None
    for colour, j in zip(colours, picks):
        s = float(ref.stage_s[j])
        r = ref.radii([s])
        f, p = ref.stage_at(s, r)
        if cycles:
            label = f"{float(ref.s_to_cycles(s)):.3g} cycles"
        else:
            label = f"ŝ = {s * per_m:.3g}"
        axes[0].plot(r / sc["a0"], f / d, color=colour, lw=1.3, label=label)
        axes[1].plot(r / sc["a0"], p / sc["p0"], color=colour, lw=1.3, label=label)
        r_max = max(r_max, float(r[-1]))
    for ax, ylabel in ((axes[0], "f / d"), (axes[1], "p / p0")):
        ax.set_xlabel("r / a0")
        ax.set_ylabel(ylabel)
        ax.set_xlim(0, r_max / sc["a0"])
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    h = ref.history
    s = np.asarray(h["s"], float)
    x = ref.s_to_cycles(s) if cycles else s * per_m
    ax = axes[2]
    if len(s) > 1:
        for q, label, colour in (("force", "F / F0", "C0"), ("contact_radius", "a / a0", "C1"),
                                 ("wear_center", "w(0) / d", "C2"),
                                 ("wear_volume", "V / (π a0² d)", "C3")):
            ax.plot(x[x > 0] if cycles else x, (np.asarray(h[q], float) / units[q])[x > 0]
                    if cycles else np.asarray(h[q], float) / units[q], color=colour, lw=1.3,
                    label=label)
        if cycles:
            ax.set_xscale("log")
        ax.set_xlabel("cycles" if cycles else "ŝ")
        ax.legend(fontsize=7)
    else:
        ax.text(0.5, 0.5, "unworn contact: no history", ha="center", va="center",
                transform=ax.transAxes)
        ax.set_xticks([])
        ax.set_yticks([])
    ax.grid(alpha=0.3)
    fig.suptitle(f"certified reference '{ref.name}'", fontsize=10)
    path = Path(path)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path
