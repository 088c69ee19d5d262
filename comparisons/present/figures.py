"""Drawing primitives that the figures of every output share (matplotlib, Agg
backend, imported only when drawing); which figures an output has is decided
by its own module (``compare_figures``, ``study_figures``, ...).

Every function takes dimensionless arrays and writes the files it is given.
Each solver is drawn in the style of its registry entry (MDR lines, FEM
markers, ...), the same colour per stage.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.extras import need

#: at most this many FEM markers per curve, so that MDR's line stays visible
MAX_MARKERS = 70


def _pyplot():
    matplotlib = need("matplotlib", "drawing figures")
    matplotlib.use("Agg")
    # lazy (a): matplotlib, the optional "plot" extra
    import matplotlib.pyplot as plt
    return plt


def _save(fig, stem: Path, formats) -> list[Path]:
    out = []
    for ext in formats:
        path = Path(stem).with_suffix("." + ext)
        fig.savefig(path, dpi=150 if ext == "png" else None, bbox_inches="tight")
        out.append(path)
    return out


def _thin(x, y, n=MAX_MARKERS):
    step = max(1, int(np.ceil(len(x) / n)))
    return np.asarray(x)[::step], np.asarray(y)[::step]


def _colours(n):
    plt = _pyplot()
    return [plt.get_cmap("viridis")(v) for v in np.linspace(0.0, 0.9, max(n, 1))]


def _series_style(style: dict, colour) -> dict:
    """Matplotlib arguments of one solver's curve from its registry style."""
    st = dict(style)
    st.setdefault("lw", 1.3)
    st["color"] = colour
    return st


def stage_figure(stem, stages, *, ylabel, title="", reference=(), vlines=(), xlim=None,
                 ylim=None, formats=("png", "pdf")) -> list[Path]:
    """Curves per stage, one colour per stage, one style per solver (paper Fig. 2).

    Parameters
    ----------
    stem : output path without suffix.
    stages : list of dicts with ``label`` and ``series``: a list of dicts with
        ``x``, ``y``, ``label`` and ``style`` (the solver's registry style; a
        style with a marker is drawn as at most ``MAX_MARKERS`` markers).
    reference : list of dicts with ``label``, ``x``, ``y`` (a wide grey band beneath).
    vlines : list of (x, label) vertical markers (e.g. a singularity).
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 4.6))
    for colour, st in zip(_colours(len(stages)), stages):
        for series in st["series"]:
            style = _series_style(series["style"], colour)
            x, y = series["x"], series["y"]
            if style.get("marker"):
                x, y = _thin(x, y)
            ax.plot(x, y, label=series["label"], **style)
    for ref in reference:
        ax.plot(ref["x"], ref["y"], "-", color="0.6", lw=4.0, alpha=0.45, zorder=0,
                label=ref["label"])
    for x, label in vlines:
        ax.axvline(x, color="0.4", ls=":", lw=1.0, label=label)
    ax.set_xlabel("r / a0")
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title, fontsize=10)
    if xlim is not None:
        ax.set_xlim(*xlim)
    if ylim is not None:
        ax.set_ylim(*ylim)
    ax.grid(alpha=0.3)
    # beside the axes, not on them: a stage and solver per entry (21 for the paper
    # case's three solvers) covered the curves wherever "best" put them
    entries = len(ax.get_legend_handles_labels()[1])
    ax.legend(fontsize=6.5, ncol=1 if entries <= 24 else 2, loc="upper left",
              bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    out = _save(fig, stem, formats)
    plt.close(fig)
    return out


def history_figure(stem, curves, *, stage_s_hat=(), formats=("png", "pdf")) -> list[Path]:
    """F/F0 and a/a0 against ŝ for each solver.

    curves : dict title -> (s_hat, F/F0, a/a0); stage_s_hat : stages to mark.
    """
    plt = _pyplot()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10.0, 4.0))
    dashes = ("-", "--", "-.", ":")
    for i, (name, (s, F, a)) in enumerate(curves.items()):
        st = dict(ls=dashes[i % len(dashes)], color=f"C{i}", lw=1.4)
        ax1.plot(s, F, label=name, **st)
        ax2.plot(s, a, label=name, **st)
    for s in stage_s_hat:
        for ax in (ax1, ax2):
            ax.axvline(s, color="0.8", lw=0.6, zorder=0)
    ax1.set_xlabel("ŝ")
    ax1.set_ylabel("F / F0")
    ax2.set_xlabel("ŝ")
    ax2.set_ylabel("a / a0")
    lo = min((float(np.min(F)) for _, F, _ in curves.values() if len(F)), default=1.0)
    hi = max((float(np.max(F)) for _, F, _ in curves.values() if len(F)), default=1.0)
    if hi - lo < 1e-6:
        # force control: F/F0 is 1 to round-off; an autoscaled axis would plot the noise
        ax1.set_ylim(0.0, 1.1 * max(hi, 1e-300))
    for ax in (ax1, ax2):
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(alpha=0.3)
        ax.legend()
    out = _save(fig, stem, formats)
    plt.close(fig)
    return out


def edge_study_figure(stem, panels, formats=("png",)) -> list[Path]:
    """Pressure near the edge at several resolutions, one panel per stage.

    panels : list of dicts with ``title`` and ``curves``: list of (label, r/a, p/p(0), style)
    with the solver's registry style; each solver gets its own colour map, darker =
    first level (the case's own resolution).
    """
    plt = _pyplot()
    n = len(panels)
    fig, axes = plt.subplots(1, n, figsize=(4.3 * n, 4.0), squeeze=False)
    for ax, panel in zip(axes[0], panels):
        by_solver = {}
        for curve in panel["curves"]:
            by_solver.setdefault(repr(sorted(curve[3].items())), []).append(curve)
        maps = ("Blues", "Reds", "Greens", "Purples", "Oranges")
        for i, curves in enumerate(by_solver.values()):
            cmap = plt.get_cmap(maps[i % len(maps)])
            shades = np.linspace(0.95, 0.45, len(curves))
            for shade, (label, x, y, style) in zip(shades, curves):
                st = dict(style, color=cmap(shade))
                if st.get("marker"):
                    st.update(ms=2.8, lw=0)
                ax.plot(x, y, label=label, **st)
        ax.set_xlim(OUTER_PLOT, 1.03)
        ax.set_xlabel("r / a")
        ax.set_ylabel("p / p(0)")
        ax.set_title(panel["title"], fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6, loc="lower left")
    out = _save(fig, stem, formats)
    plt.close(fig)
    return out


#: the edge-study panels show the outer part of the contact only
OUTER_PLOT = 0.7


def group_marks(marks, rel=0.02):
    """(x, label) pairs with x within ``rel`` of each other merged into one mark
    whose label lists them ("paper, fretting"): their labels were printed over
    each other."""
    groups = []
    for x, label in sorted(marks):
        if groups and abs(x - groups[-1][0]) <= rel * abs(groups[-1][0]):
            groups[-1][1].append(label)
        else:
            groups.append((x, [label]))
    return [(x, ", ".join(labels)) for x, labels in groups]


def sphere_sweep_figure(stem, ratio, rel_force, *, tolerance, shipped=(),
                        formats=("png",)) -> list[Path]:
    """FEM force / half-space force - 1 against a0/R, with the tolerance band."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.0, 4.0))
    ax.plot(ratio, 100 * np.asarray(rel_force), "o-", color="C3", label="FEM vs half-space")
    ax.axhspan(-100 * tolerance, 100 * tolerance, color="C2", alpha=0.15,
               label="force tolerance")
    for x, label in group_marks(shipped):
        ax.axvline(x, color="0.4", ls=":", lw=0.9)
        ax.annotate(label, (x, 0), rotation=90, fontsize=7, va="bottom")
    ax.set_xscale("log")
    ax.set_xlabel("a0 / R")
    ax.set_ylabel("F_FEM / F_half-space - 1  [%]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    out = _save(fig, stem, formats)
    plt.close(fig)
    return out
