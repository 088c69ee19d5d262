"""MDR transforms on a grid uniform in t = r² (paper Eqs. 2, 3, 12, 13).

Functions are represented by their values at the nodes ``x_i = L sqrt(i/N)``,
i = 0..N, and taken piecewise linear in t = x² between them. In t the
weakly singular kernels of the MDR are Abel kernels 1/sqrt(t - τ): every
segment integral is done in closed form (segment-exact) and depends only on
the index difference, so each transform is a triangular Toeplitz convolution,
applied by FFT in O(N log N) without forming a matrix.

Paper Eq. 2 (with the tip offset f(0) kept, docs/theory.md §2)::

    g(x) = f(0) + x ∫_0^x f'(r) / sqrt(x² - r²) dr = f(0) + sqrt(t) ∫_0^t f_τ / sqrt(t - τ) dτ

Paper Eq. 3::

    f(r) = (2/π) ∫_0^r g(x) / sqrt(r² - x²) dx = (1/π) ∫_0^τ g(t) / (sqrt(t) sqrt(τ - t)) dt

Paper Eq. 13::

    p(r) = -(1/π) ∫_r^∞ q'(x) / sqrt(x² - r²) dx = -(1/π) ∫_τ^∞ q_t / sqrt(t - τ) dt
"""

from __future__ import annotations

import math
import threading
from functools import lru_cache

import numpy as np
from scipy import fft as _fft


def grid(elements: int, length: float) -> np.ndarray:
    """Nodes x_i = L sqrt(i/N), i = 0..N: uniform in t = x², N segments (springs)."""
    return length * np.sqrt(np.arange(elements + 1) / elements)


# -- triangular Toeplitz convolutions ----------------------------------------

_SPECTRA: dict = {}


def _real(x) -> np.ndarray:
    """x as a real array: float32 kept (the low-precision Krylov iterations of
    the implicit step, mdr/linalg.py), anything else as float64."""
    x = np.asarray(x)
    return x if x.dtype == np.float32 else np.asarray(x, dtype=float)


def _spectrum(kernel: np.ndarray, nfft: int, key) -> np.ndarray:
    """rFFT of kernel[:nfft//2], cached per (kernel, size): kernels are fixed per grid.

    With len(x) <= nfft/2, a kernel truncated to nfft/2 terms gives the exact
    leading outputs without wrap-around, so one spectrum serves every length.
    """
    k = (key, nfft)
    spec = _SPECTRA.get(k)
    if spec is None:
        if len(_SPECTRA) > 32:
            _SPECTRA.clear()
        spec = _fft.rfft(kernel[:nfft // 2], nfft)  # zero-padded if shorter
        _SPECTRA[k] = spec
    return spec


def _pocketfft():
    """scipy's own pocketfft entry points (r2c, c2r), or None.

    scipy.fft's wrappers check and pad their arguments in Python, most of the
    time of a small convolution (docs/performance.md, "Measurements behind the code";
    most of an implicit step's to_1d at N = 800 is such convolutions). A private module,
    so it is used only when it reproduces scipy.fft on a test convolution;
    otherwise scipy.fft serves (both paths are tested).
    """
    try:
        from scipy.fft._pocketfft import pypocketfft as pp
        rng = np.random.default_rng(0)
        a, b = rng.random(37), rng.random(37)
        ref = _fft.irfft(_fft.rfft(a, 80) * _fft.rfft(b, 80), 80)
        got = pp.c2r(pp.r2c(np.r_[a, np.zeros(43)], (0,), True, 0, None, 1)
                     * _fft.rfft(b, 80), (0,), 80, False, 2, None, 1)
        if got.shape == ref.shape and np.allclose(got, ref, rtol=0, atol=1e-12):
            return pp.r2c, pp.c2r
    except Exception:       # another scipy: its public interface below
        pass
    return None


_POCKETFFT = _pocketfft()


def _has_pyfftw() -> bool:
    # (found, not imported: importing pyFFTW is slow, most of it dask.array
    # for its interfaces; it is imported by the first large product;
    # docs/performance.md, "Measurements behind the code")
    import importlib.util
    return importlib.util.find_spec("pyfftw") is not None


#: the FFT library of the larger convolutions: "fftw" (pyFFTW, installed with
#: the ``fftw`` extra; FFTW is GPL, so it is optional) or "pocketfft" (scipy's).
#: FFTW when installed: its real transforms are several times faster than
#: pocketfft's at large sizes, for the same iterations and history to round-off
#: (docs/performance.md, "Measurements behind the code")
FFT = "fftw" if _has_pyfftw() else "pocketfft"
#: FFT lengths below this stay with pocketfft: FFTW's planning of each size
#: costs more than the small products of coarse grids gain (a cold run is slower
#: with FFTW; docs/performance.md, "Measurements behind the code")
FFTW_FROM = 4096
#: plans kept per thread (each holds its sizes' aligned buffers: 16 bytes a point)
FFTW_PLANS = 8
_LOCAL = threading.local()


def _fftw_size(n: int) -> int:
    """The FFT length used for at least n points: 2^k times 1, 9/8, 5/4, 3/2 or 7/4.

    A coarse ladder, so that a run's changing contact sets share a few plans
    (each is costly to make); at most 1/8 of padding beyond the
    next size that FFTW transforms fast.
    """
    if n <= 64:
        return 64
    k = 1 << (int(n - 1).bit_length() - 1)        # the power of 2 below n
    for f in (1.0, 1.125, 1.25, 1.5, 1.75, 2.0):
        if f * k >= n:
            return int(f * k)
    return 2 * k


def _fftw_plan(nfft: int, single: bool = False):
    """(real buffer, complex buffer, forward plan, backward plan) of one size, per thread.

    ``single``: float32 buffers (FFTW's single precision, the implicit step's
    inner solves).
    """
    plans = getattr(_LOCAL, "plans", None)
    if plans is None:
        plans = _LOCAL.plans = {}
    plan = plans.pop((nfft, single), None)
    if plan is None:
        try:
            # lazy (a): pyFFTW, the optional "fftw" extra
            import pyfftw
        except ImportError:         # found but broken: pocketfft from now on
            global FFT
            FFT = "pocketfft"
            return None
        real = pyfftw.empty_aligned(nfft, dtype="float32" if single else "float64")
        spectrum = pyfftw.empty_aligned(nfft // 2 + 1,
                                        dtype="complex64" if single else "complex128")
        # FFTW_ESTIMATE: FFTW_MEASURE's faster transforms do not repay its planning
        # time (docs/performance.md, "Measurements behind the code")
        forward = pyfftw.FFTW(real, spectrum, flags=("FFTW_ESTIMATE",), threads=1)
        backward = pyfftw.FFTW(spectrum, real, direction="FFTW_BACKWARD",
                               flags=("FFTW_ESTIMATE", "FFTW_DESTROY_INPUT"), threads=1)
        plan = (real, spectrum, forward, backward)
        if len(plans) >= FFTW_PLANS:
            plans.pop(next(iter(plans)))
    plans[(nfft, single)] = plan
    return plan


def _fftw_convolve(plan, spec: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The leading len(x) outputs of the product with spec, through one size's FFTW plan
    (in the plan's precision)."""
    real, spectrum, forward, backward = plan
    n = len(x)
    real[:n] = x
    real[n:] = 0.0
    forward.execute()
    spectrum *= spec
    backward.execute()
    # FFTW's backward transform is unnormalised
    return real[:n] * real.dtype.type(1.0 / len(real))


_FFT_LENGTHS: dict = {}


def _fft_length(n: int) -> int:
    """The FFT length of a product whose leading n outputs are wanted (at least 2n).

    Cached per n: asked for at every transform, and the few lengths of a run
    repeat (a lookup instead of next_fast_len's search in the implicit
    step's contact iterations)."""
    key = (n, FFT)        # (FFT may change: an FFTW found broken, tests)
    nfft = _FFT_LENGTHS.get(key)
    if nfft is None:
        if FFT == "fftw" and 2 * n >= FFTW_FROM:
            nfft = _fftw_size(2 * n)
        else:
            nfft = _fft.next_fast_len(2 * n, real=True)
        if len(_FFT_LENGTHS) > 4096:
            _FFT_LENGTHS.clear()
        _FFT_LENGTHS[key] = nfft
    return nfft


def _convolve(spec: np.ndarray, x: np.ndarray, nfft: int) -> np.ndarray:
    """The leading len(x) outputs of irfft(spec · rfft(x, nfft))."""
    n = len(x)
    plan = _fftw_plan(nfft) if FFT == "fftw" and nfft >= FFTW_FROM else None
    if plan is not None:
        return _fftw_convolve(plan, spec, x)
    if _POCKETFFT is None:
        return _fft.irfft(spec * _fft.rfft(x, nfft), nfft)[:n]
    r2c, c2r = _POCKETFFT
    padded = np.empty(nfft)
    padded[:n] = x
    padded[n:] = 0.0
    X = r2c(padded, (0,), True, 0, None, 1)
    X *= spec
    return c2r(X, (0,), nfft, False, 2, None, 1)[:n]


def _half_factors(kernel: np.ndarray, m: int, key) -> tuple[np.ndarray, np.ndarray]:
    """P, Q with FFT_2m-convolution = IFFT_m(P Z + Q conj(Z[-k])), Z = FFT_m of x packed complex.

    A real signal x of 2m points packed as m complex ones z_j = x_2j + i x_2j+1
    has the real spectrum X_k = A_k Z_k + B_k conj(Z_{m-k}) (A, B = (1 ∓ i W^k)/2,
    W = exp(-2πi/2m)); the inverse real transform of Y = S X is the inverse
    complex one of C_k Y_k + D_k conj(Y_{m-k}) read as 2m reals (C, D = (1 ± i
    W^-k)/2). Both steps and the kernel's spectrum S fold into P and Q
    (float64, rounded to complex64 once), cached per (kernel, m).
    """
    k = (key, m, "half")
    out = _SPECTRA.get(k)
    if out is None:
        if len(_SPECTRA) > 32:
            _SPECTRA.clear()
        S = _fft.rfft(kernel[:m], 2 * m)             # m + 1 terms
        W = np.exp(-1j * np.pi * np.arange(m + 1) / m)
        SA, SB = S * 0.5 * (1 - 1j * W), S * 0.5 * (1 + 1j * W)
        C, D = 0.5 * (1 + 1j * np.conj(W[:m])), 0.5 * (1 - 1j * np.conj(W[:m]))
        rev = m - np.arange(m)
        out = ((C * SA[:m] + D * np.conj(SB[rev])).astype(np.complex64),
               (C * SB[:m] + D * np.conj(SA[rev])).astype(np.complex64))
        _SPECTRA[k] = out
    return out


def _spectrum32(kernel: np.ndarray, nfft: int, key) -> np.ndarray:
    """:func:`_spectrum` rounded to complex64, cached beside it."""
    k = (key, nfft, "single")
    spec = _SPECTRA.get(k)
    if spec is None:
        spec = _spectrum(kernel, nfft, key).astype(np.complex64)
        _SPECTRA[k] = spec
    return spec


def _lower_float32(kernel: np.ndarray, x: np.ndarray, key) -> np.ndarray:
    """:func:`lower` of a float32 x by two complex FFTs of half the length.

    scipy's float32 real transforms (pocketfft r2c) are no faster than its
    float64 ones inside a run (it vectorises across transforms, not within
    one), its complex transform of half the length is: with the real/complex
    split folded into the kernel's factors, a convolution is faster than by
    r2c and c2r (docs/performance.md, "Measurements behind the code";
    docs/mixed-precision.md).
    """
    n = len(x)
    if FFT == "fftw" and 2 * n >= FFTW_FROM:
        # FFTW's single-precision real transforms (SIMD within one transform)
        nfft = _fftw_size(2 * n)
        plan = _fftw_plan(nfft, single=True)
        if plan is not None:
            return _fftw_convolve(plan, _spectrum32(kernel, nfft, (key, len(kernel))), x)
    # 5-smooth: the complex default admits factors 7 and 11, far slower here
    # (docs/performance.md, "Measurements behind the code")
    m = _fft.next_fast_len(n, real=True)
    P, Q = _half_factors(kernel, m, (key, len(kernel)))
    buf = np.zeros(2 * m, np.float32)
    buf[:n] = x
    Z = _fft.fft(buf.view(np.complex64), overwrite_x=True)
    Zc = np.empty_like(Z)           # conj(Z[(m - k) mod m])
    Zc[0] = Z[0]
    Zc[1:] = Z[:0:-1]
    np.conjugate(Zc, out=Zc)
    Z *= P
    Zc *= Q
    Z += Zc
    return _fft.ifft(Z, overwrite_x=True).view(np.float32)[:n]


def lower(kernel: np.ndarray, x: np.ndarray, key=None) -> np.ndarray:
    """y_i = Σ_{j<=i} kernel[i-j] x_j (lower-triangular Toeplitz), i < len(x)."""
    n = len(x)
    if n == 0:
        return x.copy()
    if n <= 64:  # a direct sum beats the FFT's overhead on tiny vectors
        return np.convolve(kernel[:n].astype(x.dtype, copy=False), x)[:n]
    if x.dtype == np.float32 and key is not None:
        return _lower_float32(kernel, x, key)
    nfft = _fft_length(n)
    if key is None:
        spec = _fft.rfft(kernel[:n], nfft)
    else:
        # any truncation between n and nfft/2 terms gives the same leading outputs
        spec = _spectrum(kernel, nfft, (key, len(kernel)))
    return _convolve(spec, np.asarray(x, dtype=float), nfft)


def upper(kernel: np.ndarray, x: np.ndarray, key=None) -> np.ndarray:
    """y_i = Σ_{j>=i} kernel[j-i] x_j (upper-triangular Toeplitz)."""
    return lower(kernel, x[::-1], key)[::-1]


# -- kernels -------------------------------------------------------------------

@lru_cache(maxsize=4)
def abel_kernel(n: int) -> np.ndarray:
    """c[k] = sqrt(k+1) - sqrt(k): (1/(2 sqrt Δt)) ∫ over segment k of dt/sqrt(t) - like weights.

    ∫_{t_j}^{t_{j+1}} dτ / sqrt(t_i - τ) = 2 sqrt(Δt) c[i-j-1].
    """
    k = np.arange(n, dtype=float)
    # sqrt(k+1) - sqrt(k) written without cancellation
    c = 1.0 / (np.sqrt(k + 1.0) + np.sqrt(k))
    c.flags.writeable = False
    return c


@lru_cache(maxsize=4)
def abel_kernel_inverse(n: int) -> np.ndarray:
    """Coefficients b of the power series 1/c(z), c(z) = Σ c[k] z^k (c[0] = 1).

    The inverse of a triangular Toeplitz matrix is triangular Toeplitz with
    these entries; Newton's iteration b <- b (2 - c b) doubles the number of
    correct terms per pass, O(n log n) in all.
    """
    c = abel_kernel(n)
    b = np.ones(1)
    m = 1
    while m < n:
        m = min(2 * m, n)
        cb = _fft.irfft(_fft.rfft(c[:m], 2 * m) * _fft.rfft(b, 2 * m), 2 * m)[:m]
        corr = _fft.irfft(_fft.rfft(b, 2 * m) * _fft.rfft(cb, 2 * m), 2 * m)[:m]
        b = np.concatenate([b, np.zeros(m - len(b))])
        b = 2.0 * b - corr
    b.flags.writeable = False
    return b


@lru_cache(maxsize=4)
def abel_kernel_inverse_sum(n: int) -> np.ndarray:
    """Partial sums B[k] = b[0] + ... + b[k] of :func:`abel_kernel_inverse`.

    A cumulative sum after a Toeplitz product is the Toeplitz product with
    the summed kernel, so :func:`line_load` and :func:`from_1d_exact` are one
    convolution each (B[k] ~ k^(-1/2): no growth, no cancellation).
    """
    B = np.cumsum(abel_kernel_inverse(n))
    B.flags.writeable = False
    return B


@lru_cache(maxsize=8)
def _eq3_kernels(n: int):
    """Product-integration weights of ∫ ψ(t) / sqrt(τ - t) dt for ψ linear per segment.

    With v = (t - t_j)/Δt and k = i - j >= 1: α_k = ∫_0^1 (1-v)/sqrt(k-v) dv,
    β_k = ∫_0^1 v/sqrt(k-v) dv (times sqrt(Δt)).
    """
    k = np.arange(1, n + 1, dtype=float)
    i0 = 2.0 / (np.sqrt(k) + np.sqrt(k - 1.0))                  # ∫ dv/sqrt(k-v)
    # (2/3)(k^{3/2} - (k-1)^{3/2}) without cancellation
    i1 = (2.0 / 3.0) * (3.0 * k * k - 3.0 * k + 1.0) / (k**1.5 + (k - 1.0) ** 1.5)
    beta = k * i0 - i1
    alpha = i0 - beta
    a = np.concatenate([[0.0], alpha])          # a[k] = α_k, a[0] unused (0)
    b = beta                                     # b[k] = β_{k+1}
    return a, b


@lru_cache(maxsize=8)
def _force_weights(n: int) -> np.ndarray:
    """Nodal weights w with ∫_0^{t_n} q(t)/sqrt(t) dt = sqrt(Δt) Σ w_i q_i, q linear in t."""
    j = np.arange(n, dtype=float)
    i0 = 2.0 / (np.sqrt(j + 1.0) + np.sqrt(j))
    i1 = (2.0 / 3.0) * (3.0 * j * j + 3.0 * j + 1.0) / ((j + 1.0) ** 1.5 + j**1.5)
    w = np.zeros(n + 1)
    w[:-1] += (j + 1.0) * i0 - i1
    w[1:] += i1 - j * i0
    w.flags.writeable = False
    return w


@lru_cache(maxsize=8)
def _node_roots(n: int, dtype=np.float64) -> tuple[np.ndarray, np.ndarray]:
    """2 sqrt(i) and 1/(2 sqrt(i)), i = 1..n-1 (computed per call, they cost as much
    as a small transform); float32 ones for float32 vectors (no upcast)."""
    r = 2.0 * np.sqrt(np.arange(1, n, dtype=float))
    inv = 1.0 / r
    r, inv = r.astype(dtype), inv.astype(dtype)
    r.flags.writeable = inv.flags.writeable = False
    return r, inv


def _two_sqrt(n: int) -> np.ndarray:
    """2 sqrt(i) for i = 1..n-1."""
    return _node_roots(1 << max(int(n - 1).bit_length(), 6))[0][:n - 1]


def _half_rsqrt(n: int, dtype=np.float64) -> np.ndarray:
    """1/(2 sqrt(i)) for i = 1..n-1."""
    return _node_roots(1 << max(int(n - 1).bit_length(), 6), np.dtype(dtype).type)[1][:n - 1]


def _kernel(fn, n: int) -> np.ndarray:
    """A cached kernel with at least n terms (lengths rounded up to powers of 2)."""
    return fn(1 << max(int(n - 1).bit_length(), 6))


# -- the transforms ----------------------------------------------------------

def to_1d(f: np.ndarray) -> np.ndarray:
    """Paper Eq. 2 on the t-uniform grid, keeping the tip offset f(0).

    g_i = f_0 + 2 sqrt(i) Σ_{j<i} c[i-j-1] (f_{j+1} - f_j); exact for f linear
    in t (paraboloid r²/2R -> x²/R). Independent of the grid length.
    """
    f = np.asarray(f, dtype=float)
    n = len(f)
    g = np.empty(n)
    g[0] = f[0]
    if n > 1:
        plan = _TO_1D.get(n) if _POCKETFFT is not None else None
        if plan is not None and (FFT == "pocketfft" or plan[1] < FFTW_FROM):
            # the same product as lower()'s, its lookups done once per size: the
            # implicit step checks its contact by a to_1d of the whole grid per
            # contact iteration, where those lookups were a visible share
            spec, nfft, two_sqrt = plan
            r2c, c2r = _POCKETFFT
            padded = np.empty(nfft)
            np.subtract(f[1:], f[:-1], out=padded[:n - 1])
            padded[n - 1:] = 0.0
            X = r2c(padded, (0,), True, 0, None, 1)
            X *= spec
            np.multiply(two_sqrt, c2r(X, (0,), nfft, False, 2, None, 1)[:n - 1], out=g[1:])
        else:
            # (the differences by slicing: np.diff's checks cost as much as the
            # subtraction on a grid of 800)
            kernel = _kernel(abel_kernel, n - 1)
            s = lower(kernel, f[1:] - f[:-1], key="c")
            np.multiply(_two_sqrt(n), s, out=g[1:])
            if n - 1 > 64:
                if len(_TO_1D) > 64:
                    _TO_1D.clear()
                nfft = _fft_length(n - 1)
                _TO_1D[n] = (_spectrum(kernel, nfft, ("c", len(kernel))), nfft, _two_sqrt(n))
        g[1:] += f[0]
    return g


#: per grid size: to_1d's kernel spectrum, FFT length and node factors 2 sqrt(i)
_TO_1D: dict = {}


@lru_cache(maxsize=4)
def _direct_rows(L: int):
    """Rows of :func:`to_1d`'s sum for nodes up to L, as views of one reversed kernel.

    Returns V with V[L - i, j] = c[i-1-j] for j < i and 0 for j >= i (a
    sliding-window view: no L×L matrix is stored), 2 sqrt(i) for i = 0..L,
    and the kernel's differences reversed, Dr[L-1-m] = c[m-1] - c[m] (m >= 1).
    """
    c = abel_kernel(L)
    e = np.zeros(2 * L)
    e[:L] = c[::-1]
    V = np.lib.stride_tricks.sliding_window_view(e, L)
    two_sqrt = 2.0 * np.sqrt(np.arange(L + 1, dtype=float))
    D = np.zeros(L)
    D[1:] = c[:-1] - c[1:]
    Dr = D[::-1].copy()
    for a in (two_sqrt, Dr):
        a.flags.writeable = False
    return V, two_sqrt, Dr


def to_1d_rows(f: np.ndarray, first: int, stop: int) -> np.ndarray:
    """:func:`to_1d` of f on the nodes first..stop-1 alone, by direct sums.

    O((stop - first) · stop) operations, no transform: the implicit step's
    contact check needs the 1D profile on a few nodes at the contact edge
    (``f``: float64, at least ``stop`` nodes).
    """
    L = 1 << max(int(stop).bit_length(), 6)
    V, two_sqrt, _ = _direct_rows(L)
    J = stop - 1
    if J <= 0:
        return f[first:stop].copy()
    df = f[1:stop] - f[:J]
    # rows of the nodes stop-1 down to first
    s = np.dot(V[L - J:L - first + 1, :J], df)
    g = two_sqrt[first:stop] * s[::-1]
    g += f[0]
    return g


def far_bound(delta: np.ndarray) -> float:
    """A bound b with |to_1d(Δ)_i| <= b for every node i >= M, where Δ is ``delta``
    (M = len(delta) nodes) followed by zeros.

    Summation by parts of to_1d's sum: for i >= M,
    to_1d(Δ)_i = -Δ_0 (w_0 - 1) - Σ_{1<=k<M} a_k Δ_k with w_0 = 2 sqrt(i) c[i-1]
    (w_0 - 1 = c[i-1]²) and a_k = 2 sqrt(i) (c[i-1-k] - c[i-k]) >= 0. Every
    one of these weights decreases with i (c is the second difference of
    sqrt; docs/performance.md, "The paper case as users run it"), so their
    values at i = M weighting |Δ| bound every node beyond; Δ_0's is taken as
    a_0 = 2 sqrt(M) (c[M-1] - c[M]) >= c[M-1]² (about twice it), which makes
    the bound one dot product.
    """
    M = len(delta)
    if M == 0:
        return 0.0
    L = 1 << max(int(M).bit_length(), 6)
    _, _, Dr = _direct_rows(L)
    return 2.0 * math.sqrt(M) * float(np.dot(Dr[L - M - 1:L - 1], np.abs(delta)))


def from_1d_exact(g: np.ndarray) -> np.ndarray:
    """The exact inverse of :func:`to_1d` (a discrete Eq. 3).

    Triangular, so the inverse on nodes 0..m needs g on 0..m only: used by
    the implicit wear step, where it must invert to_1d to round-off. A
    float32 g is transformed in float32 (the implicit step's inner solves).
    """
    g = _real(g)
    n = len(g)
    f = np.full(n, g[0], dtype=g.dtype)
    if n > 1:
        s = (g[1:] - g[0]) * _half_rsqrt(n, g.dtype)
        # the cumulative sum of the increments, folded into the kernel
        f[1:] += lower(_kernel(abel_kernel_inverse_sum, n - 1), s, key="B")
    return f


def to_3d(g: np.ndarray) -> np.ndarray:
    """Paper Eq. 3 by segment-exact product integration on the t-uniform grid.

    On the first segment g is linear in t and the kernel 1/(sqrt(t) sqrt(τ-t))
    is integrated exactly; beyond it ψ = g/sqrt(t) is taken linear in t per
    segment and 1/sqrt(τ - t) integrated exactly. Independent of :func:`to_1d`
    (the round trip is a test of both).
    """
    g = np.asarray(g, dtype=float)
    n = len(g)
    f = np.empty(n)
    f[0] = g[0]
    if n == 1:
        return f
    i = np.arange(1, n, dtype=float)
    phi = np.arcsin(1.0 / np.sqrt(i))
    first = g[0] * 2.0 * phi + (g[1] - g[0]) * (i * phi - np.sqrt(i - 1.0))
    a, b = _eq3_kernels(1 << max(int(n - 2).bit_length(), 6))
    h = np.zeros(n)
    h[1:] = g[1:] / np.sqrt(np.arange(1, n))
    rest = lower(a, h, key="eq3a")[1:]
    h2 = h.copy()
    h2[:2] = 0.0
    # Σ_{j=2}^{i} β_{i-j+1} h_j = Σ_{j<=i} b[i-j] h2_j, b[k] = β_{k+1}
    rest += lower(b, h2, key="eq3b")[1:]
    f[1:] = (first + rest) / math.pi
    return f


def pressure(q: np.ndarray, dt: float) -> np.ndarray:
    """Paper Eq. 13: p at the nodes from the line load q (Pa·m/m), q linear in t.

    q must vanish at the last node (the contact lies inside the grid).
    p_i = -(2/(π sqrt Δt)) Σ_{j>=i} c[j-i] (q_{j+1} - q_j).
    """
    q = np.asarray(q, dtype=float)
    n = len(q)
    p = np.zeros(n)
    if n > 1:
        p[:-1] = upper(_kernel(abel_kernel, n - 1), np.diff(q), key="c")
        p[:-1] *= -2.0 / (math.pi * math.sqrt(dt))
        # beyond the last loaded node p is exactly 0: clear the FFT's round-off there
        loaded = np.flatnonzero(q)
        p[(loaded[-1] + 1) if loaded.size else 0:] = 0.0
    return p


def line_load(p: np.ndarray, dt: float) -> np.ndarray:
    """Inverse of :func:`pressure` for a contact ending at the node after the last.

    Given p on nodes 0..m, returns q on 0..m with q_{m+1} = 0 (upper
    triangular, so the contact set's block is inverted on its own). A
    float32 p is transformed in float32.
    """
    p = _real(p)
    # q_i = -Σ_{k>=i} Δq_k, the sum folded into the kernel
    return upper(_kernel(abel_kernel_inverse_sum, len(p)), p, key="B") * (0.5 * math.pi * math.sqrt(dt))


#: :func:`last_loaded` sums this many nodes in from the edge before it transforms
LAST_LOADED_SCAN = 32


def last_loaded(p: np.ndarray) -> int:
    """The last node i with line load q_i > 0 of the pressure p (``line_load(p, dt)``;
    0 if none), found from the edge inwards.

    q_i is (π/2) sqrt(Δt) Σ_{k>=0} B[k] p[i+k]: a node at the edge needs a
    sum of a few terms, where the whole line load is a transform of the grid.
    The contact iteration asks it of a set too large by a node or two.
    """
    n = len(p)
    p = np.asarray(p, dtype=float)
    B = _kernel(abel_kernel_inverse_sum, n)
    for i in range(n - 1, max(n - 1 - LAST_LOADED_SCAN, -1), -1):
        if float(B[:n - i] @ p[i:]) > 0.0:
            return i
    pos = np.flatnonzero(line_load(p, 1.0) > 0.0)
    return int(pos[-1]) if pos.size else 0


def force(q: np.ndarray, dt: float) -> float:
    """Paper Eq. 12: F = 2 ∫_0^∞ q dx = ∫ q / sqrt(t) dt, exact for q linear in t."""
    q = np.asarray(q, dtype=float)
    n = len(q) - 1
    return float(math.sqrt(dt) * (_force_weights(n) @ q)) if n > 0 else 0.0


def force_weights(n: int, dt: float) -> np.ndarray:
    """Nodal weights w (N+1) with F = w · q (paper Eq. 12, exact for q linear in t)."""
    return math.sqrt(dt) * _force_weights(n)


@lru_cache(maxsize=8)
def pressure_force_weights(n: int) -> np.ndarray:
    """Nodal weights v (N+1 = n+1) with Δt v[:k] · p = force(line_load(p, Δt), Δt) for
    a pressure p on the nodes 0..k-1 (k <= N): Eq. 12 of :func:`line_load`
    without forming the line load (the line load is positive where p >= 0 on
    nodes i..k-1: :func:`line_load`'s kernel B is positive)."""
    # F = sqrt(Δt) w·q with q_i = (π/2) sqrt(Δt) Σ_{k>=i} B[k-i] p_k:
    # v_k = (π/2) Σ_{i<=k} w_i B[k-i]
    v = (0.5 * math.pi) * lower(_kernel(abel_kernel_inverse_sum, n + 1), _force_weights(n),
                                key="B")
    v.flags.writeable = False
    return v


def volume(w: np.ndarray, dt: float):
    """∫ 2π r w dr = π ∫ w dt, exact for w linear in t.

    ``w`` at the nodes, or one profile per row (2D): a float, or the rows' volumes.
    """
    w = np.asarray(w, dtype=float)
    v = math.pi * dt * (w.sum(axis=-1) - 0.5 * (w[..., 0] + w[..., -1]))
    return float(v) if w.ndim == 1 else v


#: up to this size the compliance matrix is the product of its two dense
#: triangular factors (BLAS trmm), beyond it the FFT's O(n² log n) is faster
#: (docs/performance.md, "Measurements behind the code")
DENSE_PRODUCT_MAX = 1000


def compliance_matrix(n: int, dt: float, E_star: float, method: str | None = None) -> np.ndarray:
    """Dense n×n matrix of p -> T⁻¹[P⁻¹ p]/E*: 3D surface displacement from pressure.

    The exact composition of :func:`line_load` and :func:`from_1d_exact` on
    nodes 0..n-1 (contact ending at node n), built from their Toeplitz
    kernels. Its leading blocks are the same map on smaller contact sets.
    ``method``: "product" (the triangular factors multiplied) or "fft" (T⁻¹
    applied to P⁻¹'s columns by FFT); by default the faster for n.
    """
    from scipy.linalg import toeplitz

    B = np.cumsum(_kernel(abel_kernel_inverse, n)[:n])          # kernel of both triangular maps
    if (method or ("product" if n <= DENSE_PRODUCT_MAX else "fft")) == "product":
        from scipy.linalg.blas import dtrmm

        # both factors built as their transposes in C order, so that BLAS
        # gets them in Fortran order without the wrapper's copies (about
        # half the time; docs/performance.md, "Measurements behind the code")
        # P⁻¹ (upper Toeplitz): its transpose is lower
        Qt = toeplitz(B, np.zeros(n)) * (0.5 * math.pi * math.sqrt(dt))
        # T⁻¹ as a matrix: f_i = g_0 + Σ_{1<=j<=i} B[i-j] (g_j - g_0)/(2 sqrt j);
        # its transpose holds column j of T⁻¹ in row j
        Lt = toeplitz(np.r_[B[0], np.zeros(n - 1)], B)
        Lt *= np.r_[0.0, 1.0 / (2.0 * np.sqrt(np.arange(1, n)))][:, None]
        Lt[0, :] = 1.0 - Lt.sum(axis=0)
        return dtrmm(1.0 / E_star, Lt.T, Qt.T, lower=1, overwrite_b=1)
    Q = toeplitz(np.r_[B[0], np.zeros(n - 1)], B) * (0.5 * math.pi * math.sqrt(dt))
    # T⁻¹ = [[1, 0], [1 - L d, L D]] with L lower Toeplitz (kernel B) and
    # D = diag(d), d_i = 1/(2 sqrt i); applied to Q through one 2D FFT along
    # the rows (O(n² log n), where the dense product was O(n³))
    out = np.empty((n, n))
    out[0] = Q[0]
    if n > 1:
        d = 1.0 / (2.0 * np.sqrt(np.arange(1, n)))
        m = n - 1
        nfft = _fft.next_fast_len(2 * m, real=True)
        spec = _fft.rfft(B[:m], nfft)
        # rows of the transposed block are contiguous: transform along the last axis
        DQt = np.ascontiguousarray((d[:, None] * Q[1:]).T)
        LDQ = _fft.irfft(spec[None, :] * _fft.rfft(DQt, nfft, axis=1), nfft, axis=1)[:, :m].T
        Ld = np.convolve(B[:m], d)[:m]
        out[1:] = LDQ + (1.0 - Ld)[:, None] * Q[0][None, :]
    return out / E_star


#: the tip node's weight in the symmetric part of :func:`compliance_split`: any
#: positive value splits the matrix exactly; this one, the next node's 1/(2 sqrt 1),
#: keeps the symmetric part as well conditioned as the whole matrix and the
#: rank-one term's Sherman–Morrison denominator near 1 (1.1-1.9 on the paper case)
SPLIT_TIP_WEIGHT = 0.5


def compliance_split(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The unit compliance matrix (dt = E* = 1) of n nodes as S + u vᵀ, S symmetric
    positive definite: (S_upper, u, v).

    :func:`compliance_matrix` is T⁻¹ P⁻¹ with P⁻¹ = (π/2) Lᵀ and
    T⁻¹ = L D + a e₀ᵀ
    (L lower Toeplitz of kernel B, D = diag(δ, 1/(2 sqrt i)) with δ =
    SPLIT_TIP_WEIGHT, a its first column less δ B), so it is (π/2)(L D Lᵀ + a Bᵀ):
    S = (π/2) W Wᵀ with W = L D^½ lower triangular, u = (π/2) a, v = B. Its leading
    blocks are the same split of the leading blocks. Only S's upper triangle is
    formed (``S_upper``, a reversed view of a Fortran-ordered array; below the
    diagonal it holds other values), by LAPACK's ``lauum`` (n³/3 operations against the n³ of the
    product of the two triangular factors) on the index-reversed W, which is
    upper triangular.
    """
    from scipy.linalg import toeplitz
    from scipy.linalg.lapack import dlauum

    B = np.cumsum(_kernel(abel_kernel_inverse, n)[:n])
    d = np.r_[SPLIT_TIP_WEIGHT, 1.0 / (2.0 * np.sqrt(np.arange(1, n)))]
    # V = J W J (J the reversal): V[i, j] = B[j - i] sqrt(d[n-1-j]) for j >= i
    V = toeplitz(np.r_[B[0], np.zeros(n - 1)], B)
    V *= np.sqrt(d[::-1])[None, :]
    # V.T (lower, Fortran-ordered: no copy): lauum's (V.T)ᵀ V.T = V Vᵀ = J S J
    # in its lower triangle, which reversed is S's upper triangle
    VVt, info = dlauum(V.T, lower=1, overwrite_c=1)
    if info != 0:
        raise ArithmeticError(f"LAPACK dlauum failed (info {info})")
    VVt *= 0.5 * math.pi
    S = VVt[::-1, ::-1]             # (a view: no copy of n² numbers)
    # a = T⁻¹'s first column less δ B: 1 - Σ_{1<=j<=i} B[i-j] d_j - δ B_i
    first = np.ones(n)
    if n > 1:
        first[1:] -= np.convolve(B, d[1:])[:n - 1]
    u = (0.5 * math.pi) * (first - d[0] * B)
    return S, u, B
