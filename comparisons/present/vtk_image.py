"""ParaView files of the BEM's surface fields: ImageData (.vti) per stage in a PVD series.

``write_image_series(directory, fields, stage_s, ...)`` writes
``NAME_KKK.vti`` for every stored stage K and ``NAME.pvd`` over them (time
values: the sliding distances s [m]). Each image is the BEM's pixel grid as
points at the pixel centres (so that Warp By Scalar and Contour apply at once,
without Cell Data to Point Data; the pressure is the pixel's mean), origin and
spacing in metres, x along the first array axis; point data ``profile``,
``wear_depth``, ``pressure``, ``gap`` [m, m, Pa, m] (and ``p_over_p0`` when
p0 is given); field data ``s``, ``stage``, ``TimeValue`` (= s), ``units`` (the point
arrays' units, JSON in UTF-8 bytes: ``vtk.read_units``), ``warp_scale`` (Warp By Scalar's factor that
draws the relief at about half the grid's width), and ``s_hat``.

``write_bem_fields(directory, run, revolve=0)`` is the BEM's registry
``export_vtk``: ``wearcheck run --solver bem --vtk`` (and ``wearcheck
export``) write the ring-averaged series of :mod:`comparisons.present.vtk`
(``profile``, ``pressure``, ``surface``) and this ``surface_fields`` series.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.extras import need
from wearcheck.cases import WearcheckError

from wearcheck.comparisons.present.vtk import pvd_text, units_of, warp_scale
from wearcheck.rundir import Run

#: the per-stage surface fields of a BEM run (``RunResult.fields``)
IMAGE_FIELDS = ("profile", "wear_depth", "pressure", "gap")


def check_image_fields(fields, n_stages: int) -> None:
    """Raise ``WearcheckError`` unless ``fields`` holds the BEM's x, y and (K, nx, ny) fields."""
    missing = [k for k in ("x", "y", *IMAGE_FIELDS) if k not in fields]
    if missing:
        raise WearcheckError(f"fields.npz lacks {missing} (not a BEM run?)")
    shape = (n_stages, len(fields["x"]), len(fields["y"]))
    for key in IMAGE_FIELDS:
        if np.shape(fields[key]) != shape:
            raise WearcheckError(f"fields.npz: '{key}' has shape {np.shape(fields[key])}, "
                                 f"expected {shape}")
    for axis in ("x", "y"):
        step = np.diff(np.asarray(fields[axis], dtype=float))
        if len(step) == 0 or not np.allclose(step, step[0], rtol=1e-9, atol=0) or step[0] <= 0:
            raise WearcheckError(f"fields.npz: '{axis}' is not an increasing uniform grid")


def write_image_series(directory, fields, stage_s, *, s_hat_per_m: float | None = None,
                       p0: float | None = None, name: str = "surface_fields") -> Path:
    """Write the surface fields per stage as ImageData files plus their PVD; returns the .pvd.

    Parameters
    ----------
    directory : existing output directory.
    fields : mapping with ``x`` (nx,), ``y`` (ny,) pixel centres [m] and
        ``profile``, ``wear_depth``, ``pressure``, ``gap`` (K, nx, ny).
    stage_s : (K,) sliding distances [m] of the stages (the PVD time values).
    s_hat_per_m, p0 : optional scales for ``s_hat`` and ``p_over_p0``.
    """
    pv = need("pyvista", "writing ParaView files")
    directory = Path(directory)
    stage_s = np.asarray(stage_s, dtype=float)
    check_image_fields(fields, len(stage_s))
    x = np.asarray(fields["x"], dtype=float)
    y = np.asarray(fields["y"], dtype=float)
    dx, dy = x[1] - x[0], y[1] - y[0]
    # one point per pixel, at its centre
    image = pv.ImageData(dimensions=(len(x), len(y), 1), spacing=(dx, dy, 1.0),
                         origin=(x[0], y[0], 0.0))
    warp = warp_scale(x, np.asarray(fields["profile"], float))
    entries = []
    for k, s in enumerate(stage_s):
        image.clear_data()
        for key in IMAGE_FIELDS:
            # VTK orders points with x fastest: Fortran order of the (x, y) array
            image.point_data[key] = np.asarray(fields[key][k], dtype=float).ravel(order="F")
        if p0 is not None:
            image.point_data["p_over_p0"] = image.point_data["pressure"] / p0
        image.field_data["s"] = np.array([s])
        image.field_data["TimeValue"] = np.array([s])
        image.field_data["stage"] = np.array([k])
        image.field_data["warp_scale"] = np.array([warp])
        image.field_data["units"] = units_of(image.point_data.keys())
        if s_hat_per_m is not None:
            image.field_data["s_hat"] = np.array([s * s_hat_per_m])
        file = f"{name}_{k:03d}.vti"
        image.save(directory / file)
        entries.append((s, file))
    pvd = directory / f"{name}.pvd"
    pvd.write_text(pvd_text(entries), encoding="utf-8")
    return pvd


def write_bem_fields(directory, run: Run, revolve: int = 0) -> list[Path]:
    """The BEM's own series (registry ``export_vtk``): ``surface_fields``; its .pvd path.

    ``revolve`` is ignored: the surface is already three-dimensional.
    """
    fields, stage_s = run.fields, run.stages["s"]
    check_image_fields(fields, len(stage_s))
    if not len(stage_s):
        return []
    return [write_image_series(directory, fields, stage_s,
                               s_hat_per_m=run.scales["s_hat_per_m"], p0=run.scales["p0"])]
