"""The comparison's figures (matplotlib, Agg backend, imported only when drawing).

Every function takes dimensionless arrays and writes the files it is given.
MDR is drawn as lines, FEM as markers, the same colour per stage.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: at most this many FEM markers per curve, so that MDR's line stays visible
MAX_MARKERS = 70


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
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


def stage_figure(stem, stages, *, ylabel, title="", reference=(), vlines=(), xlim=None,
                 ylim=None, formats=("png", "pdf")) -> list[Path]:
    """Curves per stage: MDR as a line, FEM as markers (paper Fig. 2).

    Parameters
    ----------
    stem : output path without suffix.
    stages : list of dicts with ``label`` and optional ``mdr`` / ``fem`` = (x, y)
        (and optional ``mdr_label`` / ``fem_label`` for the legend).
    reference : list of dicts with ``label``, ``x``, ``y`` (a wide grey band beneath).
    vlines : list of (x, label) vertical markers (e.g. a singularity).
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 4.6))
    for colour, st in zip(_colours(len(stages)), stages):
        if st.get("mdr") is not None:
            ax.plot(*st["mdr"], "-", color=colour, lw=1.3,
                    label=st.get("mdr_label", f"MDR {st['label']}"))
        if st.get("fem") is not None:
            ax.plot(*_thin(*st["fem"]), "o", color=colour, ms=3.5, mfc="none", mew=0.9,
                    label=st.get("fem_label", f"FEM {st['label']}"))
    for ref in reference:
        # a wide grey band beneath: visible even where a solver's line covers it
        ax.plot(ref["x"], ref["y"], "-", color="0.75", lw=5, label=ref["label"], zorder=0)
    for x, label in vlines:
        ax.axvline(x, color="0.5", lw=0.8, ls=":", label=label)
    ax.set_xlabel("r / a0")
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    if xlim is not None:
        ax.set_xlim(*xlim)
    if ylim is not None:
        ax.set_ylim(*ylim)
    ax.grid(alpha=0.3)
    # outside the axes: with many stages a legend inside hides the curves
    ax.legend(fontsize=7, ncol=1, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    out = _save(fig, stem, formats)
    plt.close(fig)
    return out


def history_figure(stem, curves, *, stage_s_hat=(), formats=("png", "pdf")) -> list[Path]:
    """F/F0 and a/a0 against ŝ for each solver.

    curves : dict solver -> (s_hat, F/F0, a/a0); stage_s_hat : stages to mark.
    """
    plt = _pyplot()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10.0, 4.0))
    styles = {"mdr": dict(ls="-", color="C0", lw=1.4), "fem": dict(ls="--", color="C3", lw=1.4)}
    for name, (s, F, a) in curves.items():
        st = styles.get(name, dict(ls=":", lw=1.0))
        ax1.plot(s, F, label=name.upper(), **st)
        ax2.plot(s, a, label=name.upper(), **st)
    for s in stage_s_hat:
        for ax in (ax1, ax2):
            ax.axvline(s, color="0.8", lw=0.6, zorder=0)
    ax1.set_xlabel("ŝ")
    ax1.set_ylabel("F / F0")
    ax2.set_xlabel("ŝ")
    ax2.set_ylabel("a / a0")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        ax.legend()
    out = _save(fig, stem, formats)
    plt.close(fig)
    return out


def edge_study_figure(stem, panels, formats=("png",)) -> list[Path]:
    """Pressure near the edge at several resolutions, one panel per stage.

    panels : list of dicts with ``title`` and ``curves``: list of (label, r/a, p/p(0), solver);
    MDR levels are drawn as blue lines, FEM levels as red markers, darker = finer/first.
    """
    plt = _pyplot()
    n = len(panels)
    fig, axes = plt.subplots(1, n, figsize=(4.3 * n, 4.0), squeeze=False)
    for ax, panel in zip(axes[0], panels):
        by_solver = {}
        for curve in panel["curves"]:
            by_solver.setdefault(curve[3], []).append(curve)
        for solver, curves in by_solver.items():
            cmap = plt.get_cmap("Reds" if solver == "fem" else "Blues")
            shades = np.linspace(0.95, 0.45, len(curves))
            for shade, (label, x, y, _) in zip(shades, curves):
                if solver == "fem":
                    ax.plot(x, y, "o", ms=2.8, mfc="none", mew=0.8, color=cmap(shade),
                            label=label)
                else:
                    ax.plot(x, y, "-", lw=1.1, color=cmap(shade), label=label)
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


def sphere_sweep_figure(stem, ratio, rel_force, *, tolerance, shipped=(),
                        formats=("png",)) -> list[Path]:
    """FEM force / half-space force - 1 against a0/R, with the tolerance band."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.0, 4.0))
    ax.plot(ratio, 100 * np.asarray(rel_force), "o-", color="C3", label="FEM vs half-space")
    ax.axhspan(-100 * tolerance, 100 * tolerance, color="C2", alpha=0.15,
               label="force tolerance")
    for x, label in shipped:
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
