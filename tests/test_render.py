"""Off-screen pictures (comparisons.render) of synthetic and real runs."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from wearcheck.outputs import OUTPUT_MARKER

from wearcheck import cases
from wearcheck.cases import WearcheckError
from wearcheck.comparisons.present import render
from wearcheck.rundir import Run, write_run

sys.path.insert(0, str(Path(__file__).parent))
from test_vtk_export import cylinder_run  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def read_png(path):
    import matplotlib.image
    return matplotlib.image.imread(path)[..., :3]


def assert_picture(path):
    """A PNG of the plotter's size that shows something besides the background."""
    img = read_png(path)
    assert img.shape == (render.WINDOW_SIZE[1], render.WINDOW_SIZE[0], 3)
    drawn = np.any(img < 0.95, axis=2)
    # the white background covers at most ~90 % (text, axes, the field and a
    # colour bar of 256 shades cover the rest); a blank image fails both
    assert drawn.mean() > 0.05
    assert len(np.unique((img[drawn] * 255).round().astype(int), axis=0)) > 64
    return img


def test_nice_factor():
    assert [render.nice_factor(x) for x in (1.0, 57.0, 0.3, 199.0, 5.0)] == [1, 50, 0.2, 100, 5]


def test_render_synthetic_fem_run(tmp_path):
    run, _ = cylinder_run(tmp_path / "run", s_hat=(0.0, 1.0, 4.0))
    paths = render.render_run(run.path)
    assert [p.name for p in paths] == ["von_mises_stage000.png", "von_mises_stage002.png",
                                       "worn_surface.png"]
    # the pictures and the ownership marker (kind "render") only
    assert sorted(p.name for p in (run.path / "render").iterdir()) == sorted(
        [OUTPUT_MARKER] + [p.name for p in paths])
    for path in paths:
        assert_picture(path)
    # the run itself is untouched
    assert Run(run.path).meta == run.meta


def test_render_run_without_fields_draws_the_surface_only(tmp_path):
    run, _ = cylinder_run(tmp_path / "mdr", s_hat=(0.0, 2.0), with_fields=False)
    paths = render.render_run(run.path)
    assert [p.name for p in paths] == ["worn_surface.png"]
    assert_picture(paths[0])


def test_failed_render_keeps_the_previous_pictures(tmp_path):
    run, _ = cylinder_run(tmp_path / "run", s_hat=(0.0,))
    paths = render.render_run(run.path)
    assert [p.name for p in paths] == ["von_mises_stage000.png", "worn_surface.png"]
    before = {p.name: p.read_bytes() for p in paths}
    fields = dict(np.load(run.path / "fields.npz"))
    fields["stress"] = fields["stress"][..., :3]
    np.savez(run.path / "fields.npz", **fields)
    with pytest.raises(WearcheckError, match="stress"):
        render.render_run(run.path)
    assert {p.name: p.read_bytes() for p in (run.path / "render").iterdir()
            if p.name != OUTPUT_MARKER} == before
    assert [p.name for p in run.path.iterdir() if p.name.startswith(".")
            and p.name != OUTPUT_MARKER] == []


def test_render_fem_run_colours_the_hertz_field(tmp_path):
    """A real FEM run: the picture spans the colour map, brightest below the pole."""
    from wearcheck import fem
    case = cases.load(cases.shipped("hertz"), ["fem.contact_nodes=30"])
    path = write_run(tmp_path / "run", case, fem.solve(case), "fem", argv=["test"])
    paths = render.render_run(path)
    assert [p.name for p in paths] == ["von_mises_stage000.png", "worn_surface.png"]
    img = assert_picture(paths[0])
    import matplotlib
    top = np.array(matplotlib.colormaps["viridis"](1.0)[:3])
    near_top = np.linalg.norm(img - top, axis=2) < 0.08
    near_top[:, int(0.8 * img.shape[1]):] = False  # the colour bar
    assert near_top.any()
    # Hertz: von Mises peaks on the axis at z = 0.48 a (Johnson 1985), so the
    # brightest pixels sit on the picture's axis of symmetry, in the lower
    # half. The axis is at 44 % of the width (render's layout); ±5 % of the
    # width allows for the extent of the peak region (about ±0.5 a0 = ±6 %).
    rows, cols = np.nonzero(near_top)
    assert abs(np.median(cols) / img.shape[1] - 0.44) < 0.05
    assert np.median(rows) > 0.5 * img.shape[0]
    assert_picture(paths[1])


def test_render_command_needs_no_display(tmp_path):
    run, _ = cylinder_run(tmp_path / "run", s_hat=(0.0, 1.0))
    env = {k: v for k, v in os.environ.items()
           if k not in ("DISPLAY", "WAYLAND_DISPLAY", "VTK_DEFAULT_OPENGL_WINDOW")}
    done = subprocess.run([sys.executable, "-m", "wearcheck", "render", str(run.path)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "X server" not in done.stderr
    printed = [Path(line) for line in done.stdout.split()]
    assert [p.name for p in printed] == ["von_mises_stage000.png", "von_mises_stage001.png",
                                         "worn_surface.png"]
    for path in printed:
        assert_picture(path)


def _osmesa_missing() -> bool:
    import ctypes.util
    return ctypes.util.find_library("OSMesa") is None


@pytest.mark.skipif(not _osmesa_missing(), reason="OSMesa is installed: the window works")
def test_a_crashing_render_window_is_one_line_and_keeps_the_run(tmp_path):
    """Issue 20: VTK_DEFAULT_OPENGL_WINDOW=vtkOSOpenGLRenderWindow without OSMesa
    segfaulted ``render`` (exit 139, a .partial left). VTK now draws in a process
    of its own: one line, exit 1, the run and its earlier pictures untouched."""
    run, _ = cylinder_run(tmp_path / "run", s_hat=(0.0, 1.0))
    paths = render.render_run(run.path)
    before = {p.name: p.read_bytes() for p in paths}
    env = dict(os.environ, VTK_DEFAULT_OPENGL_WINDOW="vtkOSOpenGLRenderWindow")
    done = subprocess.run([sys.executable, "-m", "wearcheck", "render", str(run.path)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 1, done.stderr
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "SIGSEGV" in lines[0] and "OSMesa" in lines[0], done.stderr
    assert "VTK_DEFAULT_OPENGL_WINDOW" in lines[0]
    assert {p.name: p.read_bytes() for p in (run.path / "render").iterdir()
            if p.name != OUTPUT_MARKER} == before
    assert [p.name for p in run.path.iterdir() if p.name.startswith(".")] == [OUTPUT_MARKER]


@pytest.mark.skipif(not _osmesa_missing(), reason="OSMesa is installed: the window works")
def test_compare_keeps_its_results_when_the_renderer_crashes(tmp_path):
    """The same window under ``compare``: before, exit 139 after both solvers had
    finished, the comparison lost in a .partial. Now the comparison is written,
    its verdict decides the exit code, and the crash is a note (stderr, report)."""
    out = tmp_path / "cmp"
    env = dict(os.environ, VTK_DEFAULT_OPENGL_WINDOW="vtkOSOpenGLRenderWindow")
    done = subprocess.run([sys.executable, "-m", "wearcheck", "compare", "hertz", "--solvers",
                           "mdr,fem", "--set", "mdr.elements=60", "--set",
                           "fem.contact_nodes=30", "--out", str(out)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    notes = [line for line in done.stderr.splitlines() if line.startswith("note: rendering")]
    assert [n.split()[2] for n in notes] == ["mdr", "fem"]
    assert all("SIGSEGV" in n for n in notes)
    assert "SIGSEGV" in (out / "report.md").read_text()
    assert Run(out / "fem").solver == "fem" and Run(out / "mdr").solver == "mdr"
    assert [p.name for p in tmp_path.iterdir()] == ["cmp"]


def test_a_failing_render_process_is_reported_with_vtks_reason(tmp_path, monkeypatch):
    """The parent's reading of a failed child: its exit status and VTK's last
    message (colour codes and the log prefix removed), in one line."""
    run, _ = cylinder_run(tmp_path / "run", s_hat=(0.0,), with_fields=False)
    vtk_log = ("\x1b[0m\x1b[33m2026-11-27 02:20:55.258 (   1.967s) [    7F922F442B80]"
               "vtkXOpenGLRenderWindow.cxx:1234   ERR| bad X server connection. Exiting.\x1b[0m\n")

    def failed(*args, **kwargs):
        return subprocess.CompletedProcess(args, -6, "", vtk_log)
    monkeypatch.setattr(render.subprocess, "run", failed)
    monkeypatch.delenv("VTK_DEFAULT_OPENGL_WINDOW", raising=False)
    with pytest.raises(render.RenderError) as info:
        render.render_run(run.path)
    assert str(info.value) == (f"rendering '{run.path}' failed: VTK's process crashed "
                               "(SIGABRT): bad X server connection")
    assert not (run.path / "render").exists()
