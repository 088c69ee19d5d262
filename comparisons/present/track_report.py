"""The report of a run in which both bodies wear: the volumes a rig reports beside the
laboratory formulas (ASTM G133, G99), the track's cross-sections, the flat's wear map.

``write(directory, case, result)`` is the BEM's ``run_report`` in the registry:
``wearcheck run`` calls it on every BEM run, and it writes only for a case whose
counterface wears: ``report.md``/``report.html``, ``track_profile.csv`` (the
track's cross-section per stage, profilometer-style), ``track_profiles.png``
and ``counterface_wear.pvd`` with its ``counterface_wear_KKK.vti`` images.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.extras import MissingExtra, need
from wearcheck.cases import both_bodies
from wearcheck.comparisons.analysis import track as analysis
from wearcheck.comparisons.present import report
from wearcheck.comparisons.present.vtk import pvd_text

#: cells along the track of the long-stroke model's map (its groove is uniform along x)
LONG_STROKE_CELLS = 64


def profile_csv_text(stage_s, cycles, y, depth) -> str:
    """``track_profile.csv``: one row per stage and position across the track.

    Columns ``stage``, ``s`` [m], ``cycles``, ``y`` [m] (across the track, 0 at
    the ball's centre), ``depth`` [m] (wear depth of the counterface, positive
    into it) and ``height`` [m] (= −depth, as a profilometer reads the surface).
    """
    lines = ["stage,s,cycles,y,depth,height"]
    for k, (s, c) in enumerate(zip(stage_s, cycles)):
        for yi, d in zip(y, depth[k]):
            lines.append(f"{k},{s:.12e},{c:.12e},{yi:.12e},{d:.12e},{-d:.12e}")
    return "\n".join(lines) + "\n"


def flat_map(case, result):
    """The counterface's wear map per stage: (x (rows,), y (n,), depth (K, rows, n)).

    The moving-contact model's own grid fixed to the flat; the long-stroke
    model's groove extruded along one pass (:data:`LONG_STROKE_CELLS` cells;
    its turnaround ends are not modelled).
    """
    f = result.fields
    y = np.asarray(f["y"], float)
    if "flat_wear" in f:
        return np.asarray(f["flat_x"], float), y, np.asarray(f["flat_wear"], float)
    L = both_bodies.pass_length(case.sliding)
    x = (np.arange(LONG_STROKE_CELLS) + 0.5 - 0.5 * LONG_STROKE_CELLS) * L / LONG_STROKE_CELLS
    groove = np.asarray(f["track_depth"], float)
    return x, y, np.repeat(groove[:, None, :], LONG_STROKE_CELLS, axis=1)


def write_flat_map(directory: Path, case, result) -> Path:
    """``counterface_wear.pvd`` over ``counterface_wear_KKK.vti`` (cell data ``wear_depth``)."""
    pv = need("pyvista", "the counterface's wear map (ParaView files)")
    x, y, depth = flat_map(case, result)
    dx, dy = x[1] - x[0], y[1] - y[0]
    image = pv.ImageData(dimensions=(len(x) + 1, len(y) + 1, 1), spacing=(dx, dy, 1.0),
                         origin=(x[0] - dx / 2, y[0] - dy / 2, 0.0))
    entries = []
    for k, s in enumerate(result.stage_s):
        image.clear_data()
        image.cell_data["wear_depth"] = depth[k].ravel(order="F")
        image.field_data["s"] = np.array([s])
        image.field_data["stage"] = np.array([k])
        name = f"counterface_wear_{k:03d}.vti"
        image.save(directory / name)
        entries.append((float(s), name))
    pvd = directory / "counterface_wear.pvd"
    pvd.write_text(pvd_text(entries), encoding="utf-8")
    return pvd


def _figure(directory: Path, result, cycles) -> str:
    matplotlib = need("matplotlib", "drawing figures")
    matplotlib.use("Agg")
    # lazy (a): matplotlib, the optional "plot" extra
    import matplotlib.pyplot as plt
    y = np.asarray(result.fields["y"], float)
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    for k, s in enumerate(result.stage_s):
        label = f"{cycles[k]:.4g} cycles" if np.isfinite(cycles[k]) else f"s = {s:.3g} m"
        ax.plot(y * 1e3, -result.fields["track_depth"][k] * 1e6, label=label)
    ax.set_xlabel("y across the track [mm]")
    ax.set_ylabel("surface height [µm]")
    ax.set_title("track cross-section (middle of the track)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(directory / "track_profiles.png", dpi=120)
    plt.close(fig)
    return "track_profiles.png"


def blocks(case, result) -> list:
    """The report's blocks: the model, the balance, the table at the stages."""
    R, fmt = report, report.fmt
    info, h = result.info, result.history
    rows = analysis.stage_rows(h, result.stage_s)
    t = analysis.track_table(h, case, rows)
    g99 = case.sliding.motion == "unidirectional"
    std = "ASTM G99 (pin-on-disc)" if g99 else "ASTM G133 (reciprocating ball-on-flat)"
    bal = info.get("archard_balance", {})
    out = [R.heading("Both bodies wearing"),
           R.para(f"Case file: {case.source}. {info.get('model', '')}; {std}; "
                  f"K_ball = {case.wear_rate:.4g}, K_flat = {case.counterface_wear_rate:.4g} "
                  f"m³/(N·m); pixel {info.get('pixel', float('nan')):.3g} m, "
                  f"{info.get('grid', '?')}² pixels."),
           R.para("Global Archard balance (each body loses K_body·F·s): max |V_ball K_flat/"
                  f"(V_flat K_ball) − 1| = {fmt(bal.get('ratio_error'))}"
                  + (f", max |V/(K F s) − 1| = {fmt(bal.get('ball_error'))} (ball), "
                     f"{fmt(bal.get('flat_error'))} (counterface)" if "ball_error" in bal
                     else "") + "."),
           R.heading("Volumes at the stages: true and the laboratory's formulas", 3),
           R.para(("Pin: the spherical cap of the scar diameter D (G99); disc: 2π R_track "
                   "times the segment the unworn pin cuts to the track width w (G99). ")
                  if g99 else
                  ("Ball: π D⁴/(64 R) (G133); flat: the segment the unworn ball cuts to the "
                   "track width w times the stroke, plus the ends' cap. ")
                  + "Each assumes the other body unworn. 'profilometer' is the pass length "
                    "times the cross-section area of the track's middle."),
           R.table(["cycles", "s [m]", "D [mm]", "V ball [mm³]", "formula [mm³]",
                    "formula/V − 1", "w [mm]", "depth [µm]", "V flat [mm³]",
                    "formula [mm³]", "formula/V − 1", "profilometer [mm³]"],
                   [[fmt(t["cycles"][i], 4), fmt(t["s"][i], 4),
                     fmt(t["scar_diameter"][i] * 1e3, 4), fmt(t["ball_volume"][i] * 1e9, 4),
                     fmt(t["ball_formula"][i] * 1e9, 4), _pct(t["ball_deviation"][i]),
                     fmt(t["track_width"][i] * 1e3, 4), fmt(t["track_depth"][i] * 1e6, 4),
                     fmt(t["flat_volume"][i] * 1e9, 4), fmt(t["flat_formula"][i] * 1e9, 4),
                     _pct(t["flat_deviation"][i]), fmt(t["flat_profilometer"][i] * 1e9, 4)]
                    for i in range(len(rows))])]
    return out


def _pct(x) -> str:
    return "—" if not np.isfinite(x) else f"{100 * x:+.2f} %"


def write(directory, case, result) -> list[Path]:
    """Write the both-bodies report and files into a run directory; nothing for a case
    whose counterface does not wear."""
    if not case.counterface.wears or not result.fields or "track_depth" not in result.fields:
        return []
    directory = Path(directory)
    h = result.history
    rows = analysis.stage_rows(h, result.stage_s)
    cycles = np.asarray(h["cycles"], float)[rows] if len(rows) else np.zeros(0)
    csv = directory / "track_profile.csv"
    csv.write_text(profile_csv_text(result.stage_s, cycles, result.fields["y"],
                                    result.fields["track_depth"]), encoding="utf-8")
    written = [csv]
    content = blocks(case, result)
    if len(result.stage_s):
        # the core install has neither pyvista nor matplotlib: the report says so
        try:
            written.append(write_flat_map(directory, case, result))
        except MissingExtra as exc:
            content.append(report.para(f"No ParaView files of the counterface: {exc}."))
        try:
            figure = _figure(directory, result, cycles)
            written.append(directory / figure)
            content.append(report.image(figure, "track cross-sections"))
        except MissingExtra as exc:
            content.append(report.para(f"No figure: {exc}."))
    md, html = report.write(directory, content, f"wearcheck both bodies: {Path(case.source).name}")
    return [md, html] + written
