"""The MDR's history recording: columns derived for many rows at once, the body
watched on them, with the values and verdicts of one row at a time.

The recorder holds its rows' profiles and derives the worn volume, scar radius
and maximum pressure of up to ``solver.FLUSH_ROWS`` rows at once; the body watch
sees them afterwards. Each test compares with the row-by-row computation
(``cases.result.scar_radius``, ``transforms.volume`` of one profile, one
``BodyWatch`` call per row), with a closed form, or with the run's own history
read without the watch.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

from wearcheck import cases
from wearcheck.cases import CaseError, RunWarning, SolverError, profiles, programme, validity
from wearcheck.cases.result import scar_radii, scar_radius
from wearcheck.mdr import solver, transforms

#: a paraboloid (R = 10 mm) tabulated to 1.2 a0 (a0 = 0.1 mm) under the paper case's
#: depth: the worn contact grows towards √2 a0 and leaves the table at ŝ ≈ 0.94
TABLE_END = 1.2e-4


def _table_case(tmp_path, elements=200):
    r = np.linspace(0.0, TABLE_END, 241)
    path = tmp_path / "table.csv"
    path.write_text("r,f\n" + "".join(f"{a:.17g},{a * a / 0.02:.17g}\n" for a in r))
    return cases.load(cases.shipped("paper"), [
        'indenter.profile="table"', f'indenter.file="{path}"', f"mdr.elements={elements}"])


def _run(case, model=None, watch=None, unworn=True):
    built, sc = solver.build_model(case)
    plan, _ = programme.stepping_plan(case, math.inf, sc, control="ladder")
    profile = (lambda x: profiles.height(case.indenter, x, case.table)) if unworn else None
    return solver.run(model or built, plan, profile=profile, watch=watch), sc


def test_scar_radii_are_the_scar_radius_of_each_row_and_the_worn_spheres():
    """Rows w = (b² − r²)/2R worn to radii b (a worn sphere's cap), an unworn row, a
    row worn to the last node and a NaN row: each row's scar_radius exactly, and the
    closed form b √(1 − 1e-3) (where w falls to 1e-3 of its maximum b²/2R) within
    the node spacing there, dt/2b (the level lies in the cell where w meets zero,
    and the scar's edge is interpolated linearly across that cell)."""
    R, n = 0.01, 801
    r = np.sqrt(np.linspace(0.0, 4e-8, n))          # nodes uniform in r², as the MDR's
    b = np.array([0.3, 0.55, 0.71, 0.9, 1.3]) * 1e-4
    rows = np.maximum(b[:, None] ** 2 - r**2, 0.0) / (2 * R)
    rows = np.vstack([rows, np.zeros(n), np.full(n, 2e-9), np.full(n, np.nan)])
    got = scar_radii(r, rows)
    assert np.array_equal(got, [scar_radius(r, w) for w in rows])   # bitwise
    spacing = (r[1] ** 2 - r[0] ** 2) / (2 * b)
    assert np.all(np.abs(got[:5] - b * math.sqrt(1 - 1e-3)) <= spacing)
    assert got[5] == 0.0 and got[6] == r[-1] and got[7] == 0.0


def test_volumes_of_rows_are_those_of_each_row():
    """transforms.volume of rows = of each row (bitwise), and π b⁴/(4R) for the cap
    (b² − r²)/2R, exact for w linear in t = r² as the MDR's grid makes it."""
    R, t = 0.01, np.linspace(0.0, 4e-8, 801)
    b2 = np.array([0.5, 1.0, 3.7]) * 1e-8
    w = np.maximum(b2[:, None] - t, 0.0) / (2 * R)
    dt = t[1] - t[0]
    v = transforms.volume(w, dt)
    assert np.array_equal(v, [transforms.volume(row, dt) for row in w])
    # b² on a node: the integral of the piecewise linear w is the cap's, to round-off
    on_node = np.array([0.5e-8, 1e-8]) / dt
    assert np.allclose(on_node, np.round(on_node), atol=1e-6)
    assert np.allclose(v[:2], math.pi * b2[:2] ** 2 / (4 * R), rtol=1e-12, atol=0)


def test_the_watch_on_rows_gives_the_verdicts_of_one_call_per_row():
    """On the 5 mm ball (slope 0.1 at r = 0.0995 R): rows inside, past the slope
    (one warning), further, past the equator (the refusal): the same remarks,
    the same last step inside and the same refusal as BodyWatch called row by row;
    the rows after the refusal are never seen."""
    case = cases.load(cases.shipped("ball_on_flat"))
    R = case.indenter.radius
    s = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    contact = np.array([0.05, 0.09, 0.0996, 0.3, np.nan, 0.99, 0.2]) * R
    scar = np.array([0.0, 0.05, 0.0, 0.35, 0.6, 1.0002, 0.2]) * R
    verdicts = []
    for by_rows in (False, True):
        watch = validity.BodyWatch(case)
        with warnings.catch_warnings(record=True) as caught, pytest.raises(CaseError) as err:
            warnings.simplefilter("always")
            if by_rows:
                watch.rows(s, contact, scar)
            else:
                for row in zip(s, contact, scar):
                    watch(*row)
        verdicts.append((str(err.value), watch.remarks, watch.inside,
                         [str(w.message) for w in caught if w.category is RunWarning]))
    assert verdicts[0] == verdicts[1]
    assert "from ŝ = " in verdicts[0][1][-1] and verdicts[0][2][0] == 4.0
    assert "cycle 2500" in verdicts[0][0]                 # the row at s = 5 m (1 mm stroke)


@pytest.mark.parametrize("table", [False, True])
def test_the_watch_on_rows_reads_the_slope_as_one_call_does(tmp_path, table):
    """The slope test on many radii at once against one radius at a time, at radii
    spread across the slope's limit (a table's PCHIP derivative and the sphere's)."""
    case = _table_case(tmp_path) if table else cases.load(cases.shipped("ball_on_flat"))
    edge = case.indenter.radius * 0.0995 if not table else 1.0e-4
    radii = edge * (1.0 + np.linspace(-1e-3, 1e-3, 41))
    many = profiles.slope(case.indenter, radii, case.table)
    one = [float(profiles.slope(case.indenter, np.array([a]), case.table)[0]) for a in radii]
    assert np.array_equal(many, one)


@pytest.mark.parametrize("rows", [1, 5, solver.FLUSH_ROWS, 10**6])
def test_a_table_left_mid_run_is_refused_at_the_step_that_leaves_it(tmp_path, monkeypatch,
                                                                     rows):
    """The run refuses naming the first recorded step whose contact or scar passes
    the table's end, and the step before as the last inside, as read from the same
    run's history without the watch: rows watched one at a time (1), in chunks,
    or all at the end of the run (10⁶)."""
    case = _table_case(tmp_path)
    free, sc = _run(case)
    h = free["history"]
    edge = np.maximum(h["contact_radius"], h["scar_radius"])
    k = int(np.argmax(edge > TABLE_END * (1 + validity.END_MARGIN)))
    assert 10 < k < len(edge) - 1            # mid-run: steps inside, steps after
    monkeypatch.setattr(solver, "FLUSH_ROWS", rows)
    with pytest.raises(CaseError) as err:
        _run(case, watch=validity.BodyWatch(case))
    text = str(err.value)
    assert f"at ŝ = {h['s'][k] * sc['s_hat_per_m']:.4g} (s = {h['s'][k]:.4g} m)" in text
    assert f"reaches r = {edge[k]:.4g} m" in text
    assert f"still inside (sliding.distance <= {h['s'][k - 1]:.4g} m" in text


def test_the_watch_refuses_before_the_stepper_fails(tmp_path, monkeypatch):
    """A domain ending at 1.25e-4 m without the unworn profile to grow it: the stepper
    fails when the contact reaches the domain's edge, after the table's end, which
    is the refusal, also when the rows past it were not yet watched."""
    case = _table_case(tmp_path)
    model, _ = solver.build_model(case)
    x = transforms.grid(len(model.x) - 1, 1.25e-4)
    short = dataclasses.replace(model, x=x, f0=profiles.height(case.indenter, x, case.table))
    with pytest.raises(SolverError, match="reached the edge of the MDR domain"):
        _run(case, model=short, unworn=False)
    monkeypatch.setattr(solver, "FLUSH_ROWS", 10**6)
    with pytest.raises(CaseError, match="past the last radius of the profile table"):
        _run(case, model=short, watch=validity.BodyWatch(case), unworn=False)


def test_the_history_is_that_of_one_row_at_a_time(monkeypatch):
    """ball_on_flat at N = 200 to 3000 cycles grows its domain twice (the rows change
    grid within a chunk): with 3 or FLUSH_ROWS rows held, the history's columns are,
    bitwise, those of each recorded state computed alone (the volume and scar radius
    of its wear f - f0, its largest pressure, its central wear)."""
    case = cases.load(cases.shipped("ball_on_flat"), ["mdr.elements=200", "sliding.cycles=3000"])
    seen = []
    record = solver._Recorder.__call__

    def spy(self, model, st, s, stages):
        seen.append((model, st, s))
        record(self, model, st, s, stages)

    monkeypatch.setattr(solver._Recorder, "__call__", spy)
    for rows in (3, solver.FLUSH_ROWS):
        monkeypatch.setattr(solver, "FLUSH_ROWS", rows)
        seen.clear()
        out, _ = _run(case)
        assert out["counters"]["domain_growths"] >= 2
        h = out["history"]
        assert len(seen) == len(h["s"])
        for i, (model, st, s) in enumerate(seen):
            w = st.f - model.f0
            assert (h["s"][i], h["force"][i], h["depth"][i], h["contact_radius"][i]) == \
                (s, st.force, st.depth, st.contact_radius)
            assert h["wear_volume"][i] == transforms.volume(w, model.dt)
            assert h["scar_radius"][i] == scar_radius(model.x, w)
            assert h["max_pressure"][i] == np.max(st.p) and h["wear_center"][i] == w[0]
