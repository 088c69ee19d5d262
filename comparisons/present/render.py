"""Off-screen pictures of a run directory (pyvista, no display needed).

``render_run(run_dir)`` writes ``RUN_DIR/render/`` atomically and returns the
PNG paths:

``von_mises_stageKKK.png``  FEM runs: von Mises stress near the contact at the
                            first and the last stage (one picture if they are
                            the same), each coloured from 0 to its own maximum
                            in the picture.
``worn_surface.png``        the worn indenter surface at the last stage, its
                            height exaggerated (the factor is in the title).

VTK draws in a process of its own (:func:`draw_in_child`): a render window
that cannot start (e.g. ``VTK_DEFAULT_OPENGL_WINDOW=vtkOSOpenGLRenderWindow``
without OSMesa) crashes that process, not the one holding the results, and is
reported as one line (:class:`RenderError`). The data are checked here first.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np

from wearcheck.cases import WearcheckError
from wearcheck.outputs import atomic_directory
from wearcheck.rundir import Run
from wearcheck.extras import need
from wearcheck.comparisons.present.vtk import (SURFACE_SEGMENTS, VTK_QUADRATIC_TRIANGLE,
                  VTK_TRIANGLE, check_fields, grid, nice_factor, orient_triangles, revolve_curve, section_data, unworn_profile)


class RenderError(WearcheckError):
    """VTK could not draw the pictures (its process crashed or failed); nothing written."""


#: seconds the drawing process may take before it is stopped
RENDER_TIMEOUT = 600.0

#: size (width, height) of every picture, pixels
WINDOW_SIZE = (1200, 800)
#: half-width of the von Mises window, and its extent into the body, in a0
ZOOM_HALF_WIDTH = 3.0
ZOOM_DEPTH = 3.5
#: rings and segments of the unworn surface's reference wireframe
REFERENCE_RINGS, REFERENCE_SEGMENTS = 13, 36


def _plotter():
    """An off-screen plotter through VTK's EGL window (no X server)."""
    # read when the render window is created; must precede any window
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    pv = need("pyvista", "rendering")
    pv.OFF_SCREEN = True
    plotter = pv.Plotter(off_screen=True, window_size=list(WINDOW_SIZE))
    plotter.set_background("white")
    return plotter


def zoom_window(points, contact_nodes, a0):
    """(r_max, z_low, z_high) of the picture: a few a0 around the pole, into the body."""
    tip = contact_nodes[np.argmin(points[contact_nodes, 0])]
    z_tip = points[tip, 1]
    into_body = 1.0 if np.mean(points[:, 1]) >= z_tip else -1.0
    z_ends = sorted([z_tip - 0.5 * a0 * into_body, z_tip + ZOOM_DEPTH * a0 * into_body])
    return ZOOM_HALF_WIDTH * a0, z_ends[0], z_ends[1]


def _von_mises_picture(run: Run, k: int, window, clim, path: Path) -> None:
    fields = run.fields
    a0 = run.scales["a0"]
    points = np.asarray(fields["points"], dtype=float)
    cells = orient_triangles(points, fields["cells"])
    kind = VTK_TRIANGLE if cells.shape[1] == 3 else VTK_QUADRATIC_TRIANGLE
    # in units of a0, mirrored about the axis for a full cross-section
    xyz = np.column_stack([points / a0, np.zeros(len(points))])
    vm = section_data(fields, k)["von_mises"] / 1e6
    r_max, z_lo, z_hi = (w / a0 for w in window)
    whole = grid(xyz, {kind: cells})
    whole.point_data["von Mises [MPa]"] = vm
    right = whole.clip_box((0.0, r_max, z_lo, z_hi, -1.0, 1.0), invert=False)
    left = right.reflect((1.0, 0.0, 0.0), point=(0.0, 0.0, 0.0))
    plotter = _plotter()
    for half in (right, left):
        # unlit: the colours are the colour bar's
        plotter.add_mesh(half, scalars="von Mises [MPa]", cmap="viridis", clim=clim,
                         lighting=False, show_scalar_bar=half is right,
                         scalar_bar_args=dict(title="von Mises [MPa]", color="black",
                                              vertical=True, position_x=0.86, position_y=0.15,
                                              height=0.7, fmt="%.3g"))
    plotter.add_text(f"von Mises stress near the contact, stage {k}: "
                     f"s^ = {run.stages['s_hat'][k]:.3g}, s = {run.stages['s'][k]:.3g} m\n"
                     f"undeformed r-z section, lengths in a0 = {a0:.3g} m; "
                     "colours from 0 to this picture's maximum",
                     font_size=11, color="black", position="upper_left")
    # (the hidden z axis still needs a non-empty title: VTK errors on "")
    plotter.show_bounds(bounds=(-r_max, r_max, z_lo, z_hi, 0.0, 0.0), xtitle="r / a0",
                        ytitle="z / a0", ztitle="y", color="black", location="outer",
                        show_zaxis=False, grid=False, font_size=12, use_2d=True)
    plotter.view_xy()
    plotter.enable_parallel_projection()
    # the window fills 72 % of the width, left of the colour bar
    width = 2.0 * r_max / 0.72
    height = width * WINDOW_SIZE[1] / WINDOW_SIZE[0]
    centre = (0.06 * width, 0.5 * (z_lo + z_hi) + 0.03 * height, 0.0)
    plotter.camera.focal_point = centre
    plotter.camera.position = (centre[0], centre[1], 10.0 * r_max)
    plotter.camera.parallel_scale = 0.5 * height
    plotter.screenshot(str(path))
    plotter.close()


def _surface_picture(run: Run, path: Path) -> None:
    a0 = run.scales["a0"]
    st = run.stages
    k = len(st["s"]) - 1
    r, f = st["r"], st["f"][k]
    f0 = unworn_profile(run, r)
    span = float(np.ptp(f)) or float(np.ptp(f0))
    # heights drawn at about half the surface's radius
    scale = nice_factor(0.5 * (r[-1] - r[0]) / span) if span > 0 else 1.0
    xyz, cells, source = revolve_curve(r / a0, f * scale / a0, SURFACE_SEGMENTS)
    worn = grid(xyz, cells)
    worn.point_data["wear depth [um]"] = ((f - f0) * 1e6)[source]
    # a coarse wireframe of the unworn surface for reference (a fine one
    # would alias, and would lie on the worn surface outside the wear scar)
    r_ref = np.linspace(r[0], r[-1], REFERENCE_RINGS)
    ref_xyz, ref_cells, _ = revolve_curve(r_ref / a0, unworn_profile(run, r_ref) * scale / a0,
                                          REFERENCE_SEGMENTS)
    unworn = grid(ref_xyz, ref_cells)
    plotter = _plotter()
    plotter.add_mesh(worn, scalars="wear depth [um]", cmap="plasma", smooth_shading=True,
                     ambient=0.4,
                     scalar_bar_args=dict(title="wear depth [um]", color="black",
                                          vertical=True, position_x=0.86, position_y=0.15,
                                          height=0.7, fmt="%.3g"))
    plotter.add_mesh(unworn.extract_all_edges(), color="gray", opacity=0.5, line_width=1)
    plotter.add_text(f"worn indenter surface, stage {k}: s^ = {st['s_hat'][k]:.3g}, "
                     f"s = {st['s'][k]:.3g} m ({run.solver})\n"
                     f"vertical scale x{scale:g}; lengths in a0 = {a0:.3g} m; "
                     "grey: unworn surface",
                     font_size=11, color="black", position="upper_left")
    # from below and aside: the indenter's face, worn scar at the pole
    R = r[-1] / a0
    plotter.camera_position = [(2.4 * R, -0.8 * R, 2.4 * R), (0.0, 0.3 * R, 0.0), (0.0, 1.0, 0.0)]
    plotter.reset_camera()
    plotter.camera.zoom(1.15)
    plotter.screenshot(str(path))
    plotter.close()


def plan(run: Run) -> list[dict]:
    """The pictures of ``run``, their data checked: [{"name", "kind", and for the von
    Mises pictures "stage", "window", "clim"}]; [] when it stored no stage."""
    if not len(run.stages["s"]):
        return []
    pictures = []
    if run.fields is not None and "cells" in run.fields:  # a section mesh (FEM)
        fields = run.fields
        K = len(run.stages["s"])
        check_fields(fields, K)
        points = np.asarray(fields["points"], dtype=float)
        window = zoom_window(points, fields["contact_nodes"], run.scales["a0"])
        r_max, z_lo, z_hi = window
        inside = ((np.abs(points[:, 0]) <= r_max) & (points[:, 1] >= z_lo)
                  & (points[:, 1] <= z_hi))
        for k in sorted({0, K - 1}):
            # each its own colour range: the force, and with it the
            # stress, falls by orders of magnitude as the tip wears flat
            vmax = float(np.max(section_data(fields, k)["von_mises"][inside])) / 1e6
            pictures.append(dict(name=f"von_mises_stage{k:03d}.png", kind="von_mises", stage=k,
                                 window=[float(w) for w in window], clim=[0.0, vmax or 1.0]))
    pictures.append(dict(name="worn_surface.png", kind="surface"))
    return pictures


def draw(run_dir, directory, pictures) -> None:
    """Draw ``pictures`` (from :func:`plan`) of the run into ``directory``, here."""
    run = Run(run_dir)
    for p in pictures:
        if p["kind"] == "von_mises":
            _von_mises_picture(run, p["stage"], tuple(p["window"]), tuple(p["clim"]),
                               Path(directory) / p["name"])
        else:
            _surface_picture(run, Path(directory) / p["name"])


_ANSI = re.compile(r"\x1b\[[0-9;]*m")


def _reason(stderr: str) -> str:
    """The last message VTK (or Python) gave on ``stderr``, as one short line."""
    lines = [_ANSI.sub("", line).strip() for line in stderr.splitlines()]
    lines = [line for line in lines if line]
    vtk = [line.split("|", 1)[1].strip() for line in lines
           if re.search(r"\b(WARN|ERR)\|", line)]
    text = (vtk or lines or [""])[-1]
    return text.split(". ")[0][:200]     # its first sentence


def draw_in_child(run_dir, directory, pictures) -> None:
    """:func:`draw` in a process of its own; its crash or failure is a :class:`RenderError`."""
    if not sys.executable:          # an embedded interpreter that cannot start another
        draw(run_dir, directory, pictures)
        return
    code = ("import json, sys; from wearcheck.comparisons.present.render import draw; "
            "draw(sys.argv[1], sys.argv[2], json.load(sys.stdin))")
    try:
        done = subprocess.run([sys.executable, "-c", code, str(run_dir), str(directory)],
                              input=json.dumps(pictures), capture_output=True, text=True,
                              timeout=RENDER_TIMEOUT)
    except subprocess.TimeoutExpired:
        raise RenderError(f"rendering '{run_dir}' did not finish within {RENDER_TIMEOUT:g} s; "
                          "its process was stopped") from None
    if done.returncode == 0:
        return
    rc = done.returncode
    try:
        what = f"crashed ({signal.Signals(-rc).name})" if rc < 0 else f"failed (exit {rc})"
    except ValueError:
        what = f"was stopped by signal {-rc}"
    reason = _reason(done.stderr)
    window = os.environ.get("VTK_DEFAULT_OPENGL_WINDOW")
    hint = (f"; VTK_DEFAULT_OPENGL_WINDOW={window} is set: unset it to draw through EGL"
            if window and window != "vtkEGLRenderWindow" else "")
    raise RenderError(f"rendering '{run_dir}' failed: VTK's process {what}"
                      + (f": {reason}" if reason else "") + hint)


def render_run(run_dir) -> list[Path]:
    """Write the PNGs of a run into ``RUN_DIR/render/`` atomically; returns their paths.

    A run that stored no stage has nothing to draw: no directory, no paths. A
    renderer that fails or crashes is a :class:`RenderError`; the run, and
    pictures rendered before, are left as they were.
    """
    need("pyvista", "rendering")
    run = Run(run_dir)
    target = run.path / "render"
    pictures = plan(run)
    if not pictures:
        return []
    with atomic_directory(target, "render") as tmp:
        draw_in_child(run.path, tmp, pictures)
        missing = [p["name"] for p in pictures if not (tmp / p["name"]).is_file()]
        if missing:
            raise RenderError(f"rendering '{run.path}' wrote no {', '.join(missing)}")
    return [target / p["name"] for p in pictures]
