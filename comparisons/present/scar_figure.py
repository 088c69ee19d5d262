"""The experimenter's figure: scar diameter and worn volume against cycles, log axes."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.extras import need


def scar_figure(path, tables: dict, *, title: str = "") -> Path:
    """Scar diameter and worn volume against cycles (or s), log axes, with the asymptote.

    ``tables``: label -> :func:`scar_table` output (e.g. one per solver).
    Writes ``path`` (PNG or PDF by its suffix) and returns it.
    """
    matplotlib = need("matplotlib", "drawing figures")
    matplotlib.use("Agg")
    # lazy (a): matplotlib, the optional "plot" extra
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    styles = ["-", "--", ":", "-."]
    first = None
    for k, (label, t) in enumerate(tables.items()):
        x = t["cycles"] if np.all(np.isfinite(t["cycles"])) else t["s"]
        ls = styles[k % len(styles)]
        ax1.loglog(x, t["scar_diameter"] * 1e3, ls, label=f"{label}: scar diameter")
        ax2.loglog(x, t["wear_volume"] * 1e9, ls, label=f"{label}: worn volume")
        ax2.loglog(x, t["lab_volume"] * 1e9, ls, alpha=0.6, label=f"{label}: π D⁴/64R (lab)")
        first = first or (x, t)
    if first is not None:
        x, t = first
        if "asymptote_diameter" in t:
            ax1.loglog(x, t["asymptote_diameter"] * 1e3, "k:", lw=1,
                       label="asymptote 2(4RKFs/π)^(1/4)")
            ax2.loglog(x, t["archard_volume"] * 1e9, "k:", lw=1, label="K F s")
    xlabel = "cycles" if first is not None and np.all(np.isfinite(first[1]["cycles"])) \
        else "sliding distance s [m]"
    ax1.set(xlabel=xlabel, ylabel="scar diameter [mm]")
    ax2.set(xlabel=xlabel, ylabel="worn volume [mm³]")
    for ax in (ax1, ax2):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=150 if path.suffix == ".png" else None, bbox_inches="tight")
    plt.close(fig)
    return path
