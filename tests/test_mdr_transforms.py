"""MDR transforms (paper Eqs. 2, 3, 12, 13) against closed forms."""

import math

import numpy as np
import pytest

from wearcheck.cases import reference
from wearcheck.mdr import transforms

R = 0.01
L = 2e-4


def test_paraboloid_to_1d_is_exact():
    # f = r²/2R is linear in t = r², which the segment-exact Eq. 2 integrates
    # exactly: only round-off remains
    x = transforms.grid(300, L)
    g = transforms.to_1d(x**2 / (2 * R))
    np.testing.assert_allclose(g, x**2 / R, rtol=1e-12, atol=1e-12 * L**2 / R)


def test_tip_offset_is_kept():
    # docs/theory.md §2: a worn tip f(0) != 0 shifts g by the same constant
    x = transforms.grid(200, L)
    f = x**2 / (2 * R)
    offset = 3e-7
    np.testing.assert_allclose(transforms.to_1d(f + offset), transforms.to_1d(f) + offset,
                               rtol=0, atol=1e-15)


def test_cone_pair_converges_at_rate_one_half():
    # r tanθ <-> (π/2)|x| tanθ. Linear interpolation in t of f ~ sqrt(t)
    # misses the cone's tip on the first segment by O(sqrt(Δt)) = O(N^-1/2),
    # and the Abel transforms carry that error everywhere: both directions
    # converge at rate 1/2 (measured 0.50), with max errors 1.1 % (Eq. 2)
    # and 0.54 % (Eq. 3) of the cone height at N = 1600.
    theta = 0.2
    Ns = np.array([200, 400, 800, 1600])
    err2, err3 = [], []
    for N in Ns:
        x = transforms.grid(N, L)
        f, g = x * math.tan(theta), 0.5 * math.pi * x * math.tan(theta)
        err2.append(np.max(np.abs(transforms.to_1d(f) - g)) / f[-1])
        err3.append(np.max(np.abs(transforms.to_3d(g) - f)) / f[-1])
    for err, at_1600 in ((err2, 0.012), (err3, 0.006)):
        rate = -np.polyfit(np.log(Ns), np.log(err), 1)[0]
        assert 0.45 < rate < 0.6
        assert err[-1] < at_1600


def test_paraboloid_to_3d_converges():
    # Eq. 3 takes g/sqrt(t) linear per segment, which sqrt(t)/R is not near
    # t = 0: first-order convergence (measured error 1.5e-5 of f(L) at N = 800)
    errs = []
    Ns = np.array([200, 400, 800])
    for N in Ns:
        x = transforms.grid(N, L)
        f = transforms.to_3d(x**2 / R)
        errs.append(np.max(np.abs(f - x**2 / (2 * R))) / (L**2 / (2 * R)))
    rate = -np.polyfit(np.log(Ns), np.log(errs), 1)[0]
    assert rate > 0.9
    assert errs[-1] < 2e-5


def test_round_trip_sphere():
    # Eq. 2 then Eq. 3 (independent discretisations) on the exact sphere:
    # error 1.5e-5 of the largest height at N = 800, converging at first order
    R0 = 1e-4
    errs = []
    Ns = np.array([200, 400, 800])
    for N in Ns:
        x = transforms.grid(N, 0.9 * R0)
        f = R0 - np.sqrt(R0**2 - x**2)
        errs.append(np.max(np.abs(transforms.to_3d(transforms.to_1d(f)) - f)) / f[-1])
    rate = -np.polyfit(np.log(Ns), np.log(errs), 1)[0]
    assert rate > 0.9
    assert errs[-1] < 3e-5


def test_exact_inverse_inverts_to_1d():
    # the triangular Toeplitz inverse (power series by Newton's iteration)
    # must undo Eq. 2 to round-off on any profile, and on leading blocks
    rng = np.random.default_rng(1)
    f = np.cumsum(rng.random(3001))
    g = transforms.to_1d(f)
    np.testing.assert_allclose(transforms.from_1d_exact(g), f, rtol=1e-11)
    np.testing.assert_allclose(transforms.from_1d_exact(g[:1234]), f[:1234], rtol=1e-11)


def test_hertz_pressure_and_force_from_line_load():
    # q = E*(d - x²/R) is linear in t, so Eq. 13 and Eq. 12 are exact when
    # the contact edge is a node (a² = t_160 here): round-off only
    E = 2e11
    N = 500
    x = transforms.grid(N, L)
    a = x[160]
    d = a**2 / R
    q = E * np.maximum(d - x**2 / R, 0.0)
    dt = L**2 / N
    p = transforms.pressure(q, dt)
    p_ref = reference.hertz_pressure(x, E, R, a)
    np.testing.assert_allclose(p, p_ref, rtol=0, atol=1e-11 * p_ref[0])
    F = transforms.force(q, dt)
    assert F == pytest.approx(reference.hertz(E, R, depth=d)["force"], rel=1e-12)
    # the inverse of Eq. 13 on the contact nodes recovers q
    np.testing.assert_allclose(transforms.line_load(p[:160], dt), q[:160], rtol=0,
                               atol=1e-11 * q[0])


@pytest.mark.parametrize("method", ["product", "fft"])
def test_compliance_matrix_matches_operators(method):
    # the dense leading-block matrix used by the implicit step, built either
    # way, is the same map as the FFT operators (checked on a random pressure)
    n, dt, E = 257, 1e-10, 2e11
    A = transforms.compliance_matrix(n, dt, E, method=method)
    p = np.random.default_rng(2).random(n)
    u = transforms.from_1d_exact(transforms.line_load(p, dt)) / E
    np.testing.assert_allclose(A @ p, u, rtol=1e-12, atol=1e-12 * np.max(np.abs(u)))
    np.testing.assert_allclose(A[:100, :100] @ p[:100],
                               transforms.from_1d_exact(transforms.line_load(p[:100], dt)) / E,
                               rtol=1e-12, atol=1e-12 * np.max(np.abs(u)))


@pytest.mark.parametrize("n", [1, 2, 65, 300])
def test_compliance_split_is_the_matrix_as_symmetric_plus_rank_one(n):
    # S + u vᵀ must be the compliance matrix built as the triangular factors'
    # product (independently: trmm) to round-off (1e-14 of its largest entry:
    # both sum O(n) terms of size 1 in float64), with S symmetric positive
    # definite (what the Cholesky factorisation of the implicit step needs), and
    # a leading block's split the leading block of the split (nested contact sets)
    C = transforms.compliance_matrix(n, 1.0, 1.0, method="product")
    S, u, v = transforms.compliance_split(n)
    full = np.triu(S) + np.triu(S, 1).T
    np.testing.assert_allclose(full + np.outer(u, v), C, rtol=0, atol=1e-14 * np.max(np.abs(C)))
    assert np.linalg.eigvalsh(full).min() > 0.0
    m = (n + 1) // 2
    Sm, um, vm = transforms.compliance_split(m)
    np.testing.assert_allclose(np.triu(Sm), np.triu(S[:m, :m]), rtol=0,
                               atol=1e-14 * np.max(np.abs(C)))
    np.testing.assert_allclose(um, u[:m], rtol=0, atol=1e-14)
    np.testing.assert_allclose(vm, v[:m], rtol=1e-14, atol=0)   # (kernels of two lengths)


@pytest.mark.parametrize("negative", [0, 1, 3, 40, 300])
def test_last_loaded_node_by_sums_from_the_edge(negative):
    # the contact iteration's shrink: the last node with line load q > 0, from
    # sums at the edge (and past LAST_LOADED_SCAN nodes by the transform), must
    # be the last positive node of the whole line load (the FFT product), for a
    # pressure whose last ``negative`` nodes pull (0 when every node pulls)
    rng = np.random.default_rng(11)
    p = 1.0 + rng.random(300)
    if negative:
        p[-negative:] = -5.0 * (1.0 + rng.random(negative))
    q = transforms.line_load(p, 1e-10)
    pos = np.flatnonzero(q > 0.0)
    assert transforms.last_loaded(p) == (int(pos[-1]) if pos.size else 0)


@pytest.mark.parametrize("backend", ["fftw", "pocketfft", "scipy.fft"])
def test_toeplitz_products_against_the_direct_sum(backend, monkeypatch):
    # the FFT convolutions (FFTW through pyFFTW from FFTW_FROM points on;
    # scipy's pocketfft called directly, or through scipy.fft where that
    # entry point is missing) against the O(n²) sum, on sizes through the
    # small-vector branch, odd FFT lengths and FFTW's ladder of lengths;
    # round-off of a few 1e-16 of the sum of |terms|
    if backend == "fftw":
        pytest.importorskip("pyfftw")           # installed with the test extra
        monkeypatch.setattr(transforms, "FFT", "fftw")
    else:
        monkeypatch.setattr(transforms, "FFT", "pocketfft")
    if backend == "scipy.fft":
        monkeypatch.setattr(transforms, "_POCKETFFT", None)
    elif backend == "pocketfft":
        assert transforms._POCKETFFT is not None   # this scipy has it
    used = []
    plan = transforms._fftw_plan
    monkeypatch.setattr(transforms, "_fftw_plan", lambda nfft: used.append(nfft) or plan(nfft))
    rng = np.random.default_rng(3)
    kernel = transforms.abel_kernel(8192)
    for n in (1, 64, 65, 333, 1000, 2049, 4500):
        x = rng.standard_normal(n)
        ref = np.array([kernel[i::-1] @ x[:i + 1] for i in range(n)])
        scale = np.array([np.abs(kernel[i::-1]) @ np.abs(x[:i + 1]) for i in range(n)])
        for key in (None, "c"):
            y = transforms.lower(kernel, x, key=key)
            assert np.all(np.abs(y - ref) <= 1e-13 * scale), n
        up = transforms.upper(kernel, x, key="c")
        ref_up = np.array([kernel[:n - i] @ x[i:] for i in range(n)])
        assert np.allclose(up, ref_up, rtol=0, atol=1e-13 * np.max(np.abs(ref_up)) + 1e-300)
    # FFTW served exactly the products from FFTW_FROM points on
    assert bool(used) == (backend == "fftw")
    assert all(nfft >= transforms.FFTW_FROM for nfft in used)


def test_fftw_lengths_and_threads():
    # the ladder of FFTW lengths: at least the points asked, at most 1/8 above
    # a length of the ladder 2^k·{1, 9/8, 5/4, 3/2, 7/4}
    for n in range(65, 70000, 997):
        m = transforms._fftw_size(n)
        assert n <= m <= 1.25 * n
    pytest.importorskip("pyfftw")
    # plans and buffers are per thread: products in two threads at once are
    # each the direct sum's
    import threading
    kernel = transforms.abel_kernel(8192)
    rng = np.random.default_rng(5)
    xs = [rng.standard_normal(3000) for _ in range(2)]
    refs = [np.array([kernel[i::-1] @ x[:i + 1] for i in range(len(x))]) for x in xs]
    errors = []

    def work(x, ref):
        for _ in range(30):
            y = transforms.lower(kernel, x, key="c")
            errors.append(np.max(np.abs(y - ref)) / np.max(np.abs(ref)))

    old = transforms.FFT
    transforms.FFT = "fftw"
    try:
        threads = [threading.Thread(target=work, args=(x, r)) for x, r in zip(xs, refs)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        transforms.FFT = old
    assert len(errors) == 60 and max(errors) < 1e-13


def test_a_broken_pyfftw_falls_back_to_pocketfft(monkeypatch):
    # pyFFTW found at import but failing to import when first needed: the
    # product is pocketfft's, and pocketfft serves from then on
    import sys
    monkeypatch.setattr(transforms, "FFT", "fftw")
    monkeypatch.setattr(transforms, "_LOCAL", __import__("threading").local())
    monkeypatch.setitem(sys.modules, "pyfftw", None)       # import raises ImportError
    kernel = transforms.abel_kernel(8192)
    x = np.random.default_rng(2).standard_normal(3000)
    ref = np.array([kernel[i::-1] @ x[:i + 1] for i in range(len(x))])
    y = transforms.lower(kernel, x, key="c")
    assert np.max(np.abs(y - ref)) < 1e-13 * np.max(np.abs(ref))
    assert transforms.FFT == "pocketfft"
