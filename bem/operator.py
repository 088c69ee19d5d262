"""The elastic half-space as a linear operator on a square grid of pixels.

Each pixel carries a uniform pressure; the surface displacement at every
pixel centre is the sum of the closed-form displacements of uniformly loaded
rectangles (Love 1929), a discrete convolution. The half-space is not
periodic: the convolution is done by FFT on a grid zero-padded to 2N × 2N
("DC-FFT", Liu, Wang & Liu 2000), which is exact for the N × N box.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft


def _corner(X, Y):
    """Φ(X, Y) = X asinh(Y/|X|) + Y asinh(X/|Y|): the double antiderivative of 1/√(X²+Y²).

    X ln(Y + ρ) + Y ln(X + ρ) less X ln|X| + Y ln|Y|, which cancel in the
    four-corner sum; asinh has no cancellation for negative arguments. Zero
    terms where X or Y is zero (their limit).
    """
    X = np.asarray(X, dtype=float)
    Y = np.asarray(Y, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(X != 0.0, X * np.arcsinh(Y / np.where(X != 0.0, np.abs(X), 1.0)), 0.0)
        ty = np.where(Y != 0.0, Y * np.arcsinh(X / np.where(Y != 0.0, np.abs(Y), 1.0)), 0.0)
    return tx + ty


def rectangle_displacement(x, y, half_x, half_y, E_star):
    """Normal surface displacement at (x, y) of a unit pressure on |x'| <= half_x, |y'| <= half_y.

    Love (1929): u = (1/(π E*)) ∫∫ dx' dy' / √((x-x')² + (y-y')²), in closed
    form through :func:`_corner` at the four corners. Units: m per Pa.
    """
    a, b = half_x, half_y
    s = (_corner(x + a, y + b) - _corner(x - a, y + b)
         - _corner(x + a, y - b) + _corner(x - a, y - b))
    return s / (np.pi * E_star)


def influence_kernel(n, spacing, E_star):
    """Influence coefficients K[i, j] = u at pixel offset (i, j) of a unit pressure on one pixel.

    Returned on the 2n × 2n wrap-around grid of the DC-FFT: offset i sits at
    index i mod 2n for |i| < n; the row and column at index n (offset ±n,
    never needed inside the box) are zero, which is what makes the circular
    convolution equal to the linear one on the n × n box. K is even in both
    offsets: the closed form is evaluated on the quadrant of offsets 0..n-1
    and mirrored (a quarter of the evaluations).
    """
    off = np.arange(n) * spacing
    X, Y = np.meshgrid(off, off, indexing="ij")
    quadrant = rectangle_displacement(X, Y, 0.5 * spacing, 0.5 * spacing, E_star)
    K = np.zeros((2 * n, 2 * n))
    K[:n, :n] = quadrant
    K[n + 1:, :n] = quadrant[:0:-1, :]
    K[:, n + 1:] = K[:, n - 1:0:-1]
    return K


class HalfSpace:
    """u = G p on an n × n grid of square pixels of side ``spacing`` (m), DC-FFT.

    Parameters
    ----------
    n : pixels per side.
    spacing : pixel side [m].
    E_star : effective modulus [Pa].
    workers : threads of scipy.fft.
    """

    def __init__(self, n: int, spacing: float, E_star: float, workers: int = 1):
        self.n, self.spacing, self.E_star, self.workers = n, spacing, E_star, workers
        # the kernel is even in both offsets: its transform is real
        self.kernel_hat = np.ascontiguousarray(
            sfft.rfft2(influence_kernel(n, spacing, E_star), workers=workers).real)
        self.applications = 0
        self.single_applications = 0
        self._kernel_hat_single = None

    def __call__(self, p: np.ndarray) -> np.ndarray:
        """Displacement [m] at the pixel centres of the pressure field p [Pa], (n, n).

        The padded transform is pruned: the rows of zeros are not transformed
        along the second axis, and only the box's rows are transformed back
        (a quarter fewer 1D transforms than rfft2/irfft2 of the padded grid;
        docs/performance.md, "Measurements behind the code").
        """
        n = self.n
        self.applications += 1
        a = sfft.rfft(p, n=2 * n, axis=1, workers=self.workers)
        a = sfft.fft(a, n=2 * n, axis=0, overwrite_x=True, workers=self.workers)
        a *= self.kernel_hat
        a = sfft.ifft(a, axis=0, overwrite_x=True, workers=self.workers)[:n]
        return sfft.irfft(a, n=2 * n, axis=1, workers=self.workers)[:, :n]

    def single(self, p: np.ndarray) -> np.ndarray:
        """G p as :meth:`__call__`, with the transforms in single precision (float32).

        Its error is near float32's rounding, relative to max |G p|
        (docs/performance.md, "Measurements behind the code"): for the
        search directions of the contact solve, whose
        displacements are increments of a displacement computed in double
        precision (:func:`contact.solve`). Returned as float64.
        """
        n = self.n
        self.single_applications += 1
        if self._kernel_hat_single is None:
            self._kernel_hat_single = self.kernel_hat.astype(np.float32)
        a = sfft.rfft(p.astype(np.float32), n=2 * n, axis=1, workers=self.workers)
        a = sfft.fft(a, n=2 * n, axis=0, overwrite_x=True, workers=self.workers)
        a *= self._kernel_hat_single
        a = sfft.ifft(a, axis=0, overwrite_x=True, workers=self.workers)[:n]
        return sfft.irfft(a, n=2 * n, axis=1, workers=self.workers)[:, :n].astype(np.float64)

    def preconditioner(self, sigma: float = 0.0):
        """v -> C⁻¹ v with C the n-periodic circulant of G + σ I: a preconditioner.

        C's kernel is the padded kernel folded onto the n × n box, so its
        eigenvalues are the padded ones at even frequencies, Ĝ[2m]; they are
        positive, so C⁻¹ is symmetric positive definite. It costs an n × n
        FFT pair, a quarter of :meth:`__call__`, done in single precision: a
        preconditioner's rounding at 1e-7 changes the search directions, not
        the solution (the residual is the operator's).
        """
        n = self.n
        inv = (1.0 / (self.kernel_hat[::2, ::2] + sigma)).astype(np.float32)

        def apply(v):
            return sfft.irfft2(sfft.rfft2(v.astype(np.float32), workers=self.workers) * inv,
                               s=(n, n), workers=self.workers).astype(np.float64)
        return apply

    def window(self, m: int) -> "HalfSpace":
        """The same half-space on an m × m box (a window of this one), cached.

        G's coefficients depend on the pixel offset only, so G restricted to
        a window equals the window's own operator: a contact solve on a
        window that holds all the pressure is exact there
        (:func:`contact.solve`).
        """
        cache = self.__dict__.setdefault("_windows", {})
        if m not in cache:
            cache[m] = HalfSpace(m, self.spacing, self.E_star, self.workers)
        return cache[m]

    def add_point_loads(self, u: np.ndarray, idx, values) -> None:
        """u += G applied to pressures ``values`` on the pixels ``idx`` (direct sum).

        Cheaper than a convolution for a few pixels (n² per pixel).
        """
        n = self.n
        if not hasattr(self, "_kernel_shifted"):
            self._kernel_shifted = np.fft.fftshift(influence_kernel(n, self.spacing,
                                                                    self.E_star))
        Ks = self._kernel_shifted
        for (i, j), v in zip(zip(*idx), values):
            u += v * Ks[n - i:2 * n - i, n - j:2 * n - j]

    @property
    def self_compliance(self) -> float:
        """Displacement of a pixel under its own unit pressure, K[0, 0] [m/Pa]."""
        return float(rectangle_displacement(0.0, 0.0, 0.5 * self.spacing, 0.5 * self.spacing,
                                            self.E_star))

    def smallest_eigenvalue(self) -> float:
        """A lower bound of G's eigenvalues on any set of pixels [m/Pa].

        G restricted to any set of pixels is a principal submatrix of the
        infinite Toeplitz operator; its eigenvalues lie above the minimum of
        that operator's symbol, which for this kernel is reached at the
        checkerboard frequency (π, π): Σ K[i, j] (-1)^(i+j) over the whole
        lattice, :data:`CHECKERBOARD` · Δ/E*.
        """
        return checkerboard_symbol() * self.spacing / self.E_star


def _checkerboard_partial(m: int) -> float:
    """Σ K[i, j] (-1)^(i+j) over |i|, |j| < m, for Δ = E* = 1."""
    off = np.arange(-m + 1, m, dtype=float)
    X, Y = np.meshgrid(off, off, indexing="ij")
    sign = (-1.0) ** np.add.outer(np.arange(2 * m - 1), np.arange(2 * m - 1))
    sign *= sign[m - 1, m - 1]
    return float(np.sum(rectangle_displacement(X, Y, 0.5, 0.5, 1.0) * sign))


_CHECKERBOARD: list[float] = []


def checkerboard_symbol() -> float:
    """The symbol of the pixel operator at (π, π), for Δ = E* = 1 (about 0.5807).

    The partial sums over growing squares converge as 1/m (alternating
    tail); Richardson's extrapolation of m = 128 and 256 removes that term
    (the m = 8, 16, 24 sums 0.6107, 0.5952, 0.5903 extrapolate to the same;
    m = 256 and 512 give 0.580692, 128 and 256 0.580679: converged to 2e-5).
    """
    if not _CHECKERBOARD:
        _CHECKERBOARD.append(2.0 * _checkerboard_partial(256) - _checkerboard_partial(128))
    return _CHECKERBOARD[0]
