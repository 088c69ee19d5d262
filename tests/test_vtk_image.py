"""BEM surface fields as ParaView ImageData series, read back with pyvista."""

import numpy as np
import pytest

from wearcheck import bem, cases
from wearcheck.cases import WearcheckError, reference
from wearcheck import rundir
from wearcheck.comparisons.present import vtk_image
from wearcheck.comparisons.present.vtk import export_run, read_units

import pyvista as pv  # noqa: E402


@pytest.fixture(scope="module")
def bem_run(tmp_path_factory):
    case = cases.load(cases.shipped("paper"),
                      ["bem.grid=24", 'sliding.until="distance"', "sliding.distance=0.02",
                       "sliding.step_hat=0.1", "stages.s_hat=[0.0, 0.2, 0.5]"])
    res = bem.solve(case)
    out = rundir.write_run(tmp_path_factory.mktemp("runs") / "paper-bem", case, res, "bem")
    return out, res, case


def test_images_read_back(bem_run):
    out, res, case = bem_run
    # through the generic exporter, which asks the registry for the BEM's writer
    target = export_run(out)
    K = len(res.stage_s)
    assert K == 3
    series = pv.PVDReader(target / "surface_fields.pvd")
    assert np.allclose(series.time_values, res.stage_s, rtol=1e-15, atol=0)
    x = res.fields["x"]
    dx = x[1] - x[0]
    p0 = reference.scales(case)["p0"]
    for k in range(K):
        img = pv.read(target / f"surface_fields_{k:03d}.vti")
        # one point per pixel centre: Warp By Scalar applies without Cell Data to Point Data
        assert img.dimensions == (len(x), len(x), 1)
        assert np.allclose(img.spacing[:2], (dx, dx), rtol=1e-12)
        assert np.allclose(img.origin[:2], (x[0], x[0]), rtol=1e-12)
        assert img.n_cells == (len(x) - 1) ** 2 and not img.cell_data.keys()
        for key in vtk_image.IMAGE_FIELDS:
            back = np.asarray(img.point_data[key]).reshape(len(x), len(x), order="F")
            assert np.array_equal(back, res.fields[key][k])
        # the points are the pixel centres: the pressure's centre of load sits on the
        # tip (x = y = 0) for this axisymmetric case
        p = np.asarray(img.point_data["pressure"])
        if p.sum() > 0:
            assert np.allclose(img.points.T[:2] @ p / p.sum(), 0.0, atol=1e-3 * dx)
        assert np.allclose(img.point_data["p_over_p0"], p / p0)
        assert float(img.field_data["s"][0]) == res.stage_s[k]
        assert float(img.field_data["TimeValue"][0]) == res.stage_s[k]
        units = read_units(img.field_data["units"])
        assert units == dict(profile="m", wear_depth="m", pressure="Pa", gap="m", p_over_p0="")
        # the warp factor draws the relief at half the grid's width: within the 1-2-5
        # rounding (a factor 2.5 at most) of that
        warp = float(img.field_data["warp_scale"][0])
        relief = np.ptp(res.fields["profile"]) * warp / (x[-1] - x[0])
        assert 0.5 / 2.5 <= relief <= 0.5
    # the ring-averaged series of the axisymmetric exporter come along
    for name in ("profile", "pressure", "surface"):
        assert (target / f"{name}.pvd").is_file()


def test_fields_of_another_solver_are_refused(tmp_path):
    with pytest.raises(WearcheckError, match="lacks"):
        vtk_image.write_image_series(tmp_path, {"points": np.zeros((3, 2))}, [0.0])
