"""The edge-peak detector on pressures with a known shape (closed form, quadrature)."""

import math

import numpy as np
import pytest

from wearcheck.cases import reference
from wearcheck.comparisons.analysis import edge_peak

E_STAR = 2.308e11


def test_hertz_pressure_has_no_peak():
    a = 1e-4
    r = np.linspace(0, 1.5 * a, 600)
    q = edge_peak.find_edge_peak(r, reference.hertz_pressure(r, E_STAR, 0.01, a), a)
    assert not q["present"] and math.isnan(q["r_over_a"])
    # Hertz: p/p(0) = sqrt(1 - 0.98²) at r = 0.98 a; linear interpolation over h = 0.0025 a
    # errs by <= |p''| h²/8 ≈ 127 · 6.3e-6 / 8 ≈ 1e-4, i.e. 5e-4 relative
    assert q["edge_height"] == pytest.approx(math.sqrt(1 - 0.98**2), rel=2e-3)


def test_grid_noise_below_the_prominence_threshold_is_not_a_peak():
    a = 1e-4
    r = np.linspace(0, 1.5 * a, 600)
    p = reference.hertz_pressure(r, E_STAR, 0.01, a)
    # saw-tooth of 1e-5 max p: local maxima everywhere, each far below MIN_PROMINENCE = 1e-3
    p = p * (1 + 1e-5 * (-1.0) ** np.arange(r.size))
    q = edge_peak.find_edge_peak(r, p, a)
    assert not q["present"]
    assert q["prominence_of_max"] < 1e-4


def test_truncated_paraboloid_peak_sits_at_the_flat_radius():
    # paper Eq. 17-19: the pressure is singular at r = b; with b/a ≈ 0.8 the singularity
    # lies in the outer part of the contact, so the detector must find it there
    R, b = 0.01, 8e-5
    ref = reference.truncated_paraboloid(E_STAR, R, b, depth=6e-7)
    a = ref["contact_radius"]
    r = np.linspace(0, 1.3 * a, 397)
    p = reference.truncated_paraboloid_pressure(r, E_STAR, R, b, a)
    q = edge_peak.find_edge_peak(r, p, a)
    h = r[1] - r[0]
    assert q["present"] and not q["at_last_node"]
    # the sampled maximum is a node next to r = b: within one grid spacing
    assert abs(q["r_over_a"] * a - b) <= h
    assert q["height"] > 1.0  # above the centre pressure: a log singularity


def test_flat_punch_maximum_is_on_the_last_node():
    # flat punch p ∝ 1/sqrt(a² - r²) rises to the edge: its maximum is the outermost node
    a = 1e-4
    r = np.linspace(0, 1.2 * a, 241)
    p = np.where(r < a, 1.0 / np.sqrt(np.clip(a**2 - r**2, 1e-30, None)), 0.0)
    q = edge_peak.find_edge_peak(r, p, a)
    assert q["present"] and q["at_last_node"]
    assert q["r_over_a"] == r[r < a][-1] / a


def _level(label, spacing, *peaks):
    return dict(label=label, spacing=spacing, peaks=list(peaks))


def _peak(present, r_over_a=0.9, prom=0.05, last=False):
    return dict(present=present, r_over_a=r_over_a if present else math.nan, height=1.0,
                prominence=prom, prominence_of_max=prom, at_last_node=last, p_center=1.0)


def test_assess_distinguishes_converged_moving_partial_and_absent():
    levels = [
        _level("case", 0.004, _peak(False), _peak(True, 0.90, 0.050), _peak(True, 0.90),
               _peak(True, 0.80), _peak(True, 0.97, last=True)),
        _level("fine", 0.002, _peak(False), _peak(True, 0.901, 0.052), _peak(False),
               _peak(True, 0.95), _peak(True, 0.985, last=True)),
        _level("step", 0.004, _peak(False), _peak(True, 0.899, 0.049), _peak(True, 0.90),
               _peak(True, 0.80), _peak(True, 0.97, last=True)),
    ]
    v = edge_peak.assess(levels)
    assert [s["verdict"] for s in v] == ["no peak", "converged", "resolution-dependent",
                                         "resolution-dependent", "resolution-dependent"]
    assert "fine" not in v[2]["reason"] and "case" in v[2]["reason"]
    assert "moves" in v[3]["reason"]
    assert "outermost node" in v[4]["reason"]


def test_assess_flags_a_prominence_that_changes_with_resolution():
    levels = [_level("case", 0.004, _peak(True, 0.9, 0.05)),
              _level("fine", 0.002, _peak(True, 0.9, 0.02))]
    (v,) = edge_peak.assess(levels)
    assert v["verdict"] == "resolution-dependent" and "prominence" in v["reason"]
