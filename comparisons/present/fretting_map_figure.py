"""The fretting running-condition map as a figure.

The first varied key on the x axis, the second (if any) on the y axis (else
the wear volume per cycle), the marker giving the regime (partial or gross
slip) and its colour the wear volume per cycle; u*(F) = 3μF/(4G*a) is drawn
as the Cattaneo–Mindlin boundary when the map is amplitude against normal
force.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.extras import need

from wearcheck.rundir import provenance


def _label(name: str) -> str:
    """``section.key [unit]`` from the key's declaration."""
    from wearcheck.cases.schema import section_fields
    section, _, key = name.partition(".")
    unit = dict(section_fields(section))[key].metadata["unit"]
    return f"{name} [{unit}]" if unit and unit != "1" else name


def write_figure(rows, names, path: Path) -> Path:
    """The map: regime by marker, wear volume per cycle by colour."""
    matplotlib = need("matplotlib", "drawing figures")
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
