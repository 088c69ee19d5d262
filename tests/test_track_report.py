"""What a rig measures when both bodies wear: the laboratory formulas (ASTM G133,
G99) against quadrature, and the both-bodies report's files (issue 24 §5)."""

import math

import numpy as np
import pytest
from scipy import integrate

from wearcheck import bem, cases
from wearcheck.comparisons.analysis import track as analysis
from wearcheck.comparisons.analysis.scar import cap_volume
from wearcheck.comparisons.present import track_report


@pytest.mark.parametrize("w, R", [(1e-4, 5e-3), (2e-3, 5e-3), (9.9e-3, 5e-3)])
def test_segment_area_against_quadrature(w, R):
    below = math.sqrt(R**2 - w**2 / 4)
    area, _ = integrate.quad(lambda y: math.sqrt(R**2 - y**2) - below, -w / 2, w / 2,
                             epsabs=0, epsrel=1e-12)
    assert analysis.segment_area(w, R) == pytest.approx(area, rel=1e-9)
    # G99's disc: the ring of that section
    assert analysis.disc_volume(w, R, 0.016) == pytest.approx(2 * math.pi * 0.016 * area,
                                                              rel=1e-9)


def test_flat_volume_is_the_groove_the_unworn_ball_sweeps():
    # the ball (radius R, lowest point h below the flat) swept over the stroke
    # L: depth(x, y) = h − R + √(R² − y² − e²), e the distance from x to [0, L];
    # its volume by the midpoint rule on a fine grid, within 1e-3
    R, L, w = 5e-3, 2e-3, 1e-3
    h = R - math.sqrt(R**2 - w**2 / 4)
    n = 1200
    x = np.linspace(-w / 2, L + w / 2, n + 1)
    y = np.linspace(-w / 2, w / 2, n + 1)
    xc, yc = 0.5 * (x[1:] + x[:-1]), 0.5 * (y[1:] + y[:-1])
    X, Y = np.meshgrid(xc, yc, indexing="ij")
    e = np.maximum(np.maximum(-X, X - L), 0.0)
    rho2 = Y**2 + e**2
    depth = np.where(rho2 < R**2, h - R + np.sqrt(np.maximum(R**2 - rho2, 0.0)), 0.0)
    V = np.sum(np.maximum(depth, 0.0)) * (x[1] - x[0]) * (y[1] - y[0])
    assert analysis.flat_volume(w, R, L) == pytest.approx(V, rel=1e-3)
    assert analysis.flat_volume(w, R, 0.0) == pytest.approx(cap_volume(w, R), rel=1e-15)


@pytest.fixture(scope="module")
def small_run():
    case = cases.load(cases.shipped("ball_on_flat_steel"),
                      ["bem.grid=32", "bem.box=3.0", "sliding.cycles=100",
                       "stages.cycles=[0, 10, 100]"])
    return case, bem.solve(case)


def test_the_report_writes_the_track_files(small_run, tmp_path):
    import pyvista as pv
    case, res = small_run
    written = track_report.write(tmp_path, case, res)
    names = {p.name for p in written}
    assert {"report.md", "report.html", "track_profile.csv", "counterface_wear.pvd",
            "track_profiles.png"} <= names
    # the profile CSV is the groove of each stage (written to 13 digits)
    data = np.genfromtxt(tmp_path / "track_profile.csv", delimiter=",", names=True)
    n = len(res.fields["y"])
    for k in range(len(res.stage_s)):
        rows = data[data["stage"] == k]
        assert np.allclose(rows["depth"], res.fields["track_depth"][k], rtol=1e-12, atol=0)
        assert np.array_equal(rows["height"], -rows["depth"]) and len(rows) == n
    # the flat's map holds the counterface's volume (the groove over one pass)
    image = pv.read(tmp_path / "counterface_wear_002.vti")
    cell = np.prod(np.array(image.spacing[:2]))
    V = float(np.sum(image.cell_data["wear_depth"])) * cell
    assert V == pytest.approx(res.history["wear_volume_counterface"][-1], rel=1e-10)
    text = (tmp_path / "report.md").read_text()
    assert "ASTM G133" in text and "formula/V − 1" in text


def test_the_table_puts_true_volumes_beside_the_formulas(small_run):
    case, res = small_run
    h = res.history
    rows = analysis.stage_rows(h, res.stage_s)
    t = analysis.track_table(h, case, rows)
    assert np.allclose(t["ball_volume"][1:], case.wear_rate * 25.0 * t["s"][1:], rtol=1e-12)
    assert np.allclose(t["flat_volume"][1:],
                       case.counterface_wear_rate * 25.0 * t["s"][1:], rtol=1e-12)
    D = t["scar_diameter"][-1]
    assert t["ball_formula"][-1] == pytest.approx(math.pi * D**4 / (64 * 0.0047625), rel=1e-12)
    # the long-stroke model's profilometer reading is its true volume
    assert np.allclose(t["flat_profilometer"], t["flat_volume"], rtol=1e-12, atol=0)


def test_no_report_when_the_counterface_does_not_wear(tmp_path):
    case = cases.load(cases.shipped("ball_on_flat"), ["bem.grid=32", "sliding.cycles=1",
                                                      "stages.cycles=[0, 1]"])
    assert track_report.write(tmp_path, case, bem.solve(case)) == []
    assert list(tmp_path.iterdir()) == []
