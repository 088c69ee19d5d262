"""The implicit step's contact check (mdr.wear.FarGap) against the full 1D transform.

The check sums g = to_1d(f) on a window at the contact edge and clears the
nodes beyond by a bound against a reference profile (docs/performance.md, "The
contact iteration"). A node beyond the window that penetrates (d - g_i > tol·d)
but is cleared by the bound would make the step accept a wrong contact set
without a word; these tests look for such a node on adversarial profiles and
depths placed at the threshold, against the transform of the whole grid.
"""

import math
import types
from pathlib import Path

import numpy as np
import pytest

from wearcheck import cases, mdr
from wearcheck.mdr import solver, transforms, wear

TOL = wear.EDGE_TOL


def full_below(f, n, d, tol=TOL):
    """The nodes i >= n that penetrate (as i - n), by the transform of the whole grid."""
    g = transforms.to_1d(f)
    return (d - g[n:] > tol * d).nonzero()[0], g


def reference_profile(rng, N1, kind):
    j = np.arange(N1, dtype=float)
    if kind == "paraboloid":                    # linear in t
        return j / N1
    if kind == "far_dip":                       # non-monotone: dips back far out
        j0, w = rng.uniform(0.4, 0.9) * N1, rng.uniform(0.02, 0.1) * N1
        return j / N1 * (1 - rng.uniform(0.5, 0.99) * np.exp(-((j - j0) / w) ** 2))
    if kind == "flat_far":                      # a flat beyond (a truncated profile's way)
        return np.minimum(j / N1, rng.uniform(0.3, 0.8))
    # a random walk: rises and falls anywhere
    return np.cumsum(rng.standard_normal(N1)) / math.sqrt(N1)


def change(rng, N1, stop, kind, scale):
    """Δ on nodes 0..stop-1: wear-like (a positive cap), signed noise or a step."""
    j = np.arange(N1, dtype=float)
    inside = j < stop
    if kind == "cap":
        shape = np.cos(0.5 * np.pi * j / max(stop, 1))
    elif kind == "noise":
        shape = rng.standard_normal(N1)
    else:
        shape = np.ones(N1)
    return np.where(inside, scale * shape, 0.0)


def test_the_check_finds_every_penetrating_node_on_adversarial_profiles():
    # random reference profiles (monotone, dipping far out, flat, random walks),
    # changes on the contact or up to the window's end, and depths put so that
    # one node from the edge on sits just inside or just outside the threshold
    # (d - g_i = tol·d·(1 + η), η from -1e6, clear by 1e-3 d, to 3), among
    # them the lowest node from the edge or from the window's end on: the
    # nodes the check reports must be those of the transform of the whole
    # grid. Nodes within round-off of the threshold (1e-13 of the largest |g|
    # against tol·|d| ≥ 1e-9 |d|·|η|, η ≥ 0.25) are never made.
    rng = np.random.default_rng(2026)
    cleared = beyond = 0
    for trial in range(400):
        N1 = int(rng.integers(20, 1200))
        far = wear.FarGap()
        f_ref = reference_profile(rng, N1, ["paraboloid", "far_dip", "flat_far", "walk"][trial % 4])
        if trial % 3:
            far.full(f_ref)         # (else: the first check has no reference)
        n = int(rng.integers(1, N1 - 1))
        stop = n if trial % 2 else min(n + int(rng.integers(1, 2 * wear.EDGE_WINDOW)), N1)
        scale = 10.0 ** rng.uniform(-8, 0) * (np.max(np.abs(f_ref)) + 1e-300)
        f = f_ref + change(rng, N1, stop, ["cap", "noise", "step"][trial % 3], scale)
        g = transforms.to_1d(f)
        for pick in range(4):
            if pick < 2:
                # the lowest node from the edge, or from the window's end, on
                first = n if pick == 0 else min(n + wear.EDGE_WINDOW, N1 - 1)
                i = first + int(np.argmin(g[first:]))
            else:
                i = int(rng.integers(n, N1))
            eta = rng.choice([-1e6, -1e3, -3.0, -0.75, -0.25, 0.25, 0.75, 3.0])
            if g[i] == 0.0:
                continue
            d = g[i] / (1.0 - TOL * (1.0 + eta))
            margin = np.abs((d - g[n:]) - TOL * d)
            if np.any(margin < 1e-13 * np.max(np.abs(g)) + 1e-300):
                continue
            expected, _ = full_below(f, n, d)
            below, g_window = far.check(f, n, d, TOL)
            np.testing.assert_array_equal(below, expected, err_msg=f"trial {trial}")
            if g_window is None or len(g_window) < N1 - n + 1:
                cleared += 1
                # what the window sums is the transform there (round-off 1e-13)
                if g_window is not None:
                    np.testing.assert_allclose(g_window, g[n - 1:n - 1 + len(g_window)],
                                               rtol=0, atol=1e-13 * np.max(np.abs(g)))
            beyond += int(np.any(expected >= wear.EDGE_WINDOW))
    # the bound decided many of them, and many had nodes penetrating beyond the
    # window (those the bound must not clear)
    assert cleared > 200 and beyond > 200, (cleared, beyond)


def test_a_bound_too_small_would_be_found(monkeypatch):
    # the comparison above can fail: with the change's bound left out (the
    # reference's g trusted beyond the window), the check clears a node that
    # penetrates. A profile dipping far out (its 1D profile lowest at node 585)
    # and a wear-like cap on the centre that pulls g there below the depth
    N1 = 801
    j = np.arange(N1, dtype=float)
    f_ref = j / N1 * (1 - 0.3 * np.exp(-((j - 600) / 40) ** 2))
    far = wear.FarGap()
    far.full(f_ref)
    f = f_ref + change(None, N1, 100, "cap", 0.05)
    g = transforms.to_1d(f)
    d = float(np.min(g[300:])) * (1 + 2 * TOL)
    expected, _ = full_below(f, 120, d)
    assert list(expected) == [585 - 120]
    np.testing.assert_array_equal(far.check(f, 120, d, TOL)[0], expected)
    far.full(f_ref)         # (the check above made f its reference)
    monkeypatch.setattr(transforms, "far_bound", lambda delta: 0.0)
    assert len(far.check(f, 120, d, TOL)[0]) == 0


@pytest.mark.parametrize("depth", [-1.0, -1e-3, 0.0])
def test_the_check_at_a_negative_or_zero_depth(depth):
    # the threshold tol·d is below 0 for a negative depth: a flat profile just
    # above the depth, by 0.5 tol |d| (g of a constant is that constant), is
    # penetrating (d - g = -0.5 tol|d| > tol·d). The bound cleared it before
    # this was fixed (it compared d - g with +0.5 tol |d|); at d = 0 every node
    # with g < 0 penetrates
    N1 = 501
    f = np.full(N1, depth + 0.5 * TOL * abs(depth) if depth else -1e-12)
    far = wear.FarGap()
    far.full(f.copy())
    expected, _ = full_below(f, 100, depth)
    assert len(expected) == N1 - 100
    np.testing.assert_array_equal(far.check(f, 100, depth, TOL)[0], expected)
    # and a flat profile clear of the threshold by 2 tol |d| is cleared by the bound
    f = np.full(N1, depth + 2 * TOL * abs(depth) if depth else 1e-12)
    far.full(f.copy())
    below, g = far.check(f, 100, depth, TOL)
    assert len(full_below(f, 100, depth)[0]) == 0 and len(below) == 0 and g is None


def table_case(tmp_path, name, r, f, **over):
    """A depth-controlled case of the tabulated profile (r, f), adaptive, N = 200."""
    f = np.array(f, dtype=float)
    f[0] = 0.0
    csv = tmp_path / f"{name}.csv"
    csv.write_text("".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(r, f)))
    raw = dict(indenter=dict(profile="table", file=str(csv), youngs_modulus=210e9,
                             poisson_ratio=0.3),
               counterface=dict(rigid=True),
               loading=dict(control="depth", depth=1e-6),
               wear=dict(k=1e-4, mu=0.3, hardness=2e9),
               sliding=dict(until="force_fraction", force_fraction=0.5, scheme="adaptive",
                            tolerance=1e-3),
               stages=dict(s_hat=[0.0]),
               mdr=dict(elements=200, domain_factor=3.0))
    for key, value in over.items():
        section, k = key.split(".")
        if value is None:
            raw[section].pop(k, None)
        else:
            raw[section][k] = value
    return cases.from_dict(raw, source=tmp_path / f"{name}.toml")


def run_both(monkeypatch, case):
    """The run with the check as shipped and with the full transform in every check;
    every state an implicit step returns is checked on the whole grid."""
    step = wear.implicit_step
    accepted = []

    def checked_step(model, state, *args, **kwargs):
        new = step(model, state, *args, **kwargs)
        g = transforms.to_1d(new.f)
        accepted.append(float(np.max(new.depth - g[new.m + 1:], initial=-np.inf)
                              / abs(new.depth)))
        return new

    monkeypatch.setattr(wear, "implicit_step", checked_step)
    out = []
    for shipped in (True, False):
        if not shipped:
            monkeypatch.setattr(wear.FarGap, "_clears", lambda *args: False)
        res = mdr.solve(case)
        out.append(res)
    # no state beyond its contact set penetrates (the step's own tolerance)
    assert len(accepted) > 40 and max(accepted) <= wear.EDGE_TOL
    return out


def assert_same_history(a, b):
    # the window's direct sums against the FFT: round-off, 1e-12 of each column
    assert a.history.keys() == b.history.keys()
    for k in a.history:
        va, vb = np.asarray(a.history[k], dtype=float), np.asarray(b.history[k], dtype=float)
        assert va.shape == vb.shape, k
        scale = np.max(np.abs(va), where=np.isfinite(va), initial=0.0)
        np.testing.assert_allclose(va, vb, rtol=0, atol=1e-12 * scale + 1e-300, err_msg=k)
    assert a.info["contact_iterations"] == b.info["contact_iterations"]


R = 0.01
r_table = np.linspace(0.0, 1e-3, 2001)
sphere = r_table**2 / (2 * R)


@pytest.mark.filterwarnings("ignore::wearcheck.cases.errors.RunWarning")
def test_a_far_dip_of_a_table_profile(monkeypatch, tmp_path):
    # a sphere whose far field dips back to 1/100 of itself around r = 2 a0 (a0 =
    # 1e-4 m), its 1D profile there below the depth (-5 d): contact there from
    # the start, and the wear of the centre pulls it further down
    dip = sphere * (1 - 0.99 * np.exp(-((r_table - 2e-4) / 2e-5) ** 2))
    case = table_case(tmp_path, "dip", r_table, dip)
    model, _ = solver.build_model(case)
    assert transforms.to_1d(model.f0).min() < -1e-6
    a, b = run_both(monkeypatch, case)
    assert_same_history(a, b)


@pytest.mark.filterwarnings("ignore::wearcheck.cases.errors.RunWarning")
def test_regrids_on_the_solver_reference(monkeypatch):
    # the reference the states carry, started by each grid's first state and
    # replaced at each domain growth (the grid √2 wider in r, the same number of
    # nodes: a stale reference would have the right length), on the shipped
    # ball-on-flat case under force control, 300 elements
    case = cases.load(Path(cases.__file__).parent / "ball_on_flat.toml", ["mdr.elements=300"])
    a, b = run_both(monkeypatch, case)
    assert a.info["domain_growths"] >= 2
    assert_same_history(a, b)


@pytest.mark.filterwarnings("ignore::wearcheck.cases.errors.RunWarning")
def test_a_far_ring_that_comes_into_contact(monkeypatch, tmp_path):
    # a sphere dipping to 1/10 of itself around r = 2.5 a0, its 1D profile there
    # above the depth at the start: the wear of the centre pulls it down until
    # nodes far beyond the contact's window penetrate (4 of 342 checks). The
    # check must find them (the full transform of the whole grid decides), and
    # the run end as it does with the full transform in every check (here both
    # refuse alike: the contact set flips between the centre and the ring)
    r = np.linspace(0.0, 4e-4, 2001)
    dip = r**2 / (2 * R) * (1 - 0.9 * np.exp(-((r - 2.5e-4) / 3e-5) ** 2))
    case = table_case(tmp_path, "ring", r, dip, **{"sliding.force_fraction": 0.05})
    check = wear.FarGap.check
    far = []

    def spy(self, f, n, d, tol):
        expected, _ = full_below(f, n, d, tol)
        below, g = check(self, f, n, d, tol)
        np.testing.assert_array_equal(below, expected)
        far.append(bool(np.any(expected >= wear.EDGE_WINDOW)))
        return below, g

    monkeypatch.setattr(wear.FarGap, "check", spy)
    outcomes = []
    for shipped in (True, False):
        if not shipped:
            monkeypatch.setattr(wear.FarGap, "_clears", lambda *args: False)
        try:
            outcomes.append(mdr.solve(case))
        except cases.SolverError as exc:
            outcomes.append(str(exc))
    assert sum(far) >= 1 and len(far) > 100, (sum(far), len(far))
    a, b = outcomes
    if isinstance(a, str) or isinstance(b, str):
        assert a == b
        # the refusal says why (two regions of contact), not "reduce the step"
        assert "two separate regions" in a and "--solver bem" in a, a
    else:
        assert_same_history(a, b)


def test_an_unsettled_edge_of_a_node_or_two_asks_for_a_shorter_step():
    # the edge moving by a node or two (a step too long for nodal contact
    # conditions) against jumping across a third of the contact (two regions)
    model = types.SimpleNamespace(x=np.linspace(0.0, 1e-4, 401))
    assert wear._unsettled(model, 200, 202).endswith("reduce sliding.step_hat")
    far = wear._unsettled(model, 200, 60)
    assert "two separate regions" in far and "r = 1.5e-05 m and 5e-05 m" in far
