"""Writers of results in the formats ``wearcheck verify`` reads, for the tests: a run's
history and stages as a user's FE code would hand them over (CSV tables with units,
a VTK series with foreign names and units, CalculiX's .frd and .dat).

Each takes ``scale``: the sliding distance written is scale × the true one (1.05:
the results of a model that reaches each state only after 5 % more sliding, i.e.
whose wear coefficient is 1/1.05 of the case's, 4.8 % too low).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def csv_dir(directory, result, *, scale=1.0, time="s", stages=True) -> Path:
    """history.csv (columns shuffled, units mm/kN/mm³, an extra column) and stages.csv
    (long form, s_hat, r in µm, p in MPa, the wear depth instead of f)."""
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    h, st = result.history, result.stages
    per_m = result.scales["s_hat_per_m"]
    head = {"s": "s [mm]", "s_hat": "s_hat", "cycles": "cycles"}[time]
    lines = [f"step,force [kN],contact_radius [mm],{head},wear_volume [mm^3],wear_center [µm],"
             "depth"]
    fretting = result.case.fretting is not None
    for i in range(len(h["s"])):
        s = h["s"][i] * scale
        if time == "cycles":   # a fretting run counts its own cycles; else s/(2·stroke)
            t = h["cycles"][i] * scale if fretting else s * result.case.cycles_per_metre
        else:
            t = {"s": s * 1e3, "s_hat": s * per_m}[time]
        lines.append(f"{i},{h['force'][i] / 1e3:.17g},{h['contact_radius'][i] * 1e3:.17g},"
                     f"{t:.17g},{h['wear_volume'][i] * 1e9:.17g},"
                     f"{h['wear_center'][i] * 1e6:.17g},{h['depth'][i]:.17g}")
    (d / "history.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    if stages:
        from wearcheck.references.certified import unworn_profile
        # the stages' distance as ŝ, or in cycles with a history in cycles (a fretting
        # run's cycles are not proportional to its s: both tables count alike)
        if time == "cycles":
            column = "cycles"
            when = (np.asarray(result.info["stage_cycles"], float)[:len(st["s"])]
                    if fretting else np.asarray(st["s"]) * result.case.cycles_per_metre)
        else:
            column, when = "s_hat", np.asarray(st["s_hat"])
        lines = [f"r [µm],wear [m],{column},p [MPa]"]
        f0 = unworn_profile(result.case, st["r"])
        for k, t in enumerate(when):
            for j, r in enumerate(st["r"]):
                lines.append(f"{r * 1e6:.17g},{st['f'][k, j] - f0[j]:.17g},"
                             f"{t * scale:.17g},{st['p'][k, j] / 1e6:.17g}")
        (d / "stages.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return d


def fe_export(directory, result, *, scale=1.0) -> Path:
    """history.csv and stages.csv as FE post-processors export tables (ANSYS Mechanical,
    COMSOL): tab-separated, quoted names with spaces and brackets, units in the header,
    the sliding distance in the model's pseudo-time column "Time [s]" (in mm), a step
    counter; and an Abaqus-style wear column without a unit (Abaqus has none)."""
    from wearcheck.references.certified import unworn_profile
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    h, st = result.history, result.stages
    rows = ['"Steps"\t"Time [s]"\t"Force Reaction (Y) [N]"\t"Contact Radius [mm]"\t'
            '"Worn Volume [mm³]"\t"WEAR_DEPTH N: 1"']
    for i in range(len(h["s"])):
        rows.append(f"{i + 1}\t{h['s'][i] * scale * 1e3:.10E}\t{-h['force'][i]:.10E}\t"
                    f"{h['contact_radius'][i] * 1e3:.10E}\t{h['wear_volume'][i] * 1e9:.10E}\t"
                    f"{h['wear_center'][i] * 1e3:.10E}")
    (d / "history.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    f0 = unworn_profile(result.case, st["r"])
    rows = ['"Time [s]"\t"X [mm]"\t"Contact Pressure [MPa]"\t"Wear Depth (Y) [µm]"']
    for k, s in enumerate(st["s"]):
        for j, r in enumerate(st["r"]):
            rows.append(f"{s * scale * 1e3:.10E}\t{r * 1e3:.10E}\t{st['p'][k, j] / 1e6:.10E}\t"
                        f"{(st['f'][k, j] - f0[j]) * 1e6:.10E}")
    (d / "stages.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    return d


#: what tells wearcheck which column is which (the distance's unit given, as the
#: pseudo-time's header says seconds; the Abaqus-style column's unit supplied)
FE_EXPORT_MAP = ["s [mm]=Time", "force=Force Reaction (Y)", "contact_radius=Contact Radius",
                 "wear_volume=Worn Volume", "wear_center [mm]=WEAR_DEPTH N: 1", "r=X",
                 "p=Contact Pressure", "wear=Wear Depth (Y)"]


def vtk_series(directory, result, *, scale=1.0) -> Path:
    """A .pvd of .vtu surfaces as another code writes them: the profile revolved about z
    (16 segments), coordinates in mm, the pressure 'CPRESS' in MPa, the worn profile
    'PROFILE' in mm; timesteps s in mm."""
    import meshio
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    st = result.stages
    r = np.asarray(st["r"])
    theta = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
    entries = []
    for k, s in enumerate(st["s"]):
        R, T = np.meshgrid(r, theta, indexing="ij")
        F = np.repeat(st["f"][k][:, None], len(theta), axis=1)
        P = np.repeat(st["p"][k][:, None], len(theta), axis=1)
        pts = np.column_stack([(R * np.cos(T)).ravel(), (R * np.sin(T)).ravel(), F.ravel()])
        name = f"surf_{k:03d}.vtu"
        meshio.write(d / name, meshio.Mesh(pts * 1e3, [("vertex", np.arange(len(pts))[:, None])],
                                           point_data={"CPRESS": P.ravel() / 1e6,
                                                       "PROFILE": F.ravel() * 1e3}))
        entries.append(f'<DataSet timestep="{s * scale * 1e3:.17g}" part="0" file="{name}"/>')
    (d / "surf.pvd").write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" '
                                'version="0.1">\n<Collection>\n' + "\n".join(entries)
                                + "\n</Collection>\n</VTKFile>\n", encoding="utf-8")
    return d / "surf.pvd"


VTK_MAP = ["p [MPa]=CPRESS", "f [mm]=PROFILE", "axis=z", "r [mm]=points", "s [mm]=time"]


def _e(v: float) -> str:
    return f"{v:12.5E}"


def calculix(directory, result, *, scale=1.0, name="wear") -> Path:
    """wear.frd (nodes of the contact surface in an axisymmetric model, mm; per result
    time a CONTACT block with CPRESS in MPa and a user block WEAR with the wear depth
    in mm) and wear.dat (the total force of set TOP per 2° segment, the displacements
    of set TIP), result times = s in mm."""
    from wearcheck.references.certified import unworn_profile
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    st, h = result.stages, result.history
    r = np.asarray(st["r"])
    ids = np.arange(1, len(r) + 1)
    f0 = unworn_profile(result.case, r)
    lines = ["    1C", "    1UUSER", f"    2C{len(r):30d}{'':37s}1"]
    lines += [f" -1{i:10d}{_e(ri * 1e3)}{_e(f0[i - 1] * 1e3)}{_e(0.0)}" for i, ri in zip(ids, r)]
    lines.append(" -3")
    for k, s in enumerate(st["s"]):
        t = s * scale * 1e3
        for block, comps, values in (
                ("CONTACT", ("COPEN", "CSLIP1", "CSLIP2", "CPRESS", "CSHEAR1", "CSHEAR2"),
                 np.column_stack([np.zeros((len(r), 3)), st["p"][k] / 1e6,
                                  np.zeros((len(r), 2))])),
                ("WEAR", ("W",), ((st["f"][k] - f0) * 1e3)[:, None])):
            lines.append(f"    1PSTEP{k + 1:25d}{1:12d}{1:12d}")
            lines.append(f"  100CL  101{_e(t)}{len(r):12d}{'':21s}0{k + 1:5d}{1:12d}")
            lines.append(f" -4  {block:8s}{len(comps):4d}    1")
            lines += [f" -5  {c:8s}    1    4    1    1" for c in comps]
            lines += [f" -1{i:10d}" + "".join(_e(v) for v in values[i - 1]) for i in ids]
            lines.append(" -3")
    lines.append(" 9999")
    (d / f"{name}.frd").write_text("\n".join(lines) + "\n", encoding="utf-8")
    out = []
    for i in range(len(h["s"])):
        t = h["s"][i] * scale * 1e3
        out += ["", f" total force (fx,fy,fz) for set TOP and time  {t:.7E}", "",
                f"       {0.0: .6E} {-h['force'][i] / 180:.6E}  {0.0:.6E}", "",
                f" displacements (vx,vy,vz) for set TIP and time  {t:.7E}", "",
                f"         1  {0.0:.6E} {-h['depth'][i] * 1e3:.6E}  {0.0:.6E}"]
    (d / f"{name}.dat").write_text("\n".join(out) + "\n", encoding="utf-8")
    return d / f"{name}.frd"


CALCULIX_MAP = ["s [mm]=time", "r [mm]=points", "p [MPa]=CONTACT.CPRESS", "wear [mm]=WEAR.W",
                "force=TOP*180", "depth [mm]=TIP"]
