"""Tangential (partial-slip) frictional contact on the elastic half-space.

Under a GIVEN normal pressure p on the pixels, the indenter is moved
rigidly in the plane by δ = (δx, δy). Each pixel carries a uniform traction
τ = (τx, τy) exerted on the half-space; its surface displacement at the
pixel centres is u = A τ, the Cerruti solution (Johnson 1985, Eq. 3.86 at
z = 0) integrated over the pixels in closed form:

    u_x = 1/(2πG) ∫∫ [((1-ν)/ρ + ν X²/ρ³) τx + ν XY/ρ³ τy] dA,
    u_y = 1/(2πG) ∫∫ [ν XY/ρ³ τx + ((1-ν)/ρ + ν Y²/ρ³) τy] dA,

on the zero-padded 2n × 2n grid (DC-FFT, not periodic), as the normal
operator of :mod:`bem.operator`. The coupling of normal and tangential
problems ((1-2ν) terms) is left out (Goodman's approximation, as in
Cattaneo–Mindlin and the MDR): p is given and does not change.

The relative displacement of indenter and surface accumulated by slip is w.
In an increment from a previous state (τ⁰, w⁰) to the displacement δ, the
slip increment is Δw = δ - A τ - w⁰, and Coulomb's law with the direction
free in the plane reads, per pixel,

    |τ| <= μ p,   Δw = λ τ/|τ|,  λ >= 0,  λ (μ p - |τ|) = 0,

the optimality conditions of min ½ τ·Aτ - (δ - w⁰)·τ over the friction discs
(A symmetric positive definite). It is solved by an accelerated projected
gradient (FISTA with adaptive restart, Beck & Teboulle 2009; O'Donoghue &
Candès 2015): the projection onto the discs is radial clipping per pixel,
the step 1/λ_max(A) from the symbol of the padded block circulant (an upper
bound of the eigenvalues of A on any set of pixels, by interlacing).
Converged when the natural residual

    max |τ - P(τ + Δw/K₀₀)| / (μ max p)

(K₀₀ the pixel's self-compliance) is below ``tol``: zero exactly when the
conditions hold; in words, the slip left in stick pixels, and the traction
off the disc or against the slip in slip pixels, relative to the pixel's own
response to μ max p. Non-convergence raises SolverError.

The dissipation of an increment is Δ² Σ τ·Δw at its end (the slip of a
pixel under the traction it ends with: exact when directions do not turn
within the increment, the error of a backward-Euler rule otherwise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.fft as sfft

from wearcheck.cases import SolverError

from .operator import _corner


def _corner_xx(X, Y):
    """Y asinh(X/|Y|): the double antiderivative of X²/ρ³ (zero where Y = 0, its limit)."""
    X = np.asarray(X, dtype=float)
    Y = np.asarray(Y, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(Y != 0.0, Y * np.arcsinh(X / np.where(Y != 0.0, np.abs(Y), 1.0)), 0.0)


def _corner_xy(X, Y):
    """-ρ: the double antiderivative of XY/ρ³."""
    return -np.hypot(X, Y)


def _four_corners(F, x, y, a, b):
    return F(x + a, y + b) - F(x - a, y + b) - F(x + a, y - b) + F(x - a, y - b)


def rectangle_integrals(x, y, half_x, half_y):
    """∫∫ of 1/ρ, X²/ρ³, Y²/ρ³, XY/ρ³ over the rectangle |x'| <= half_x, |y'| <= half_y.

    X = x - x', Y = y - y', ρ = √(X² + Y²); in closed form from the double
    antiderivatives at the four corners [m]. X²/ρ³ + Y²/ρ³ = 1/ρ.
    """
    a, b = half_x, half_y
    ones = _four_corners(_corner, x, y, a, b)
    xx = _four_corners(_corner_xx, x, y, a, b)
    yy = _four_corners(lambda X, Y: _corner_xx(Y, X), x, y, a, b)
    xy = _four_corners(_corner_xy, x, y, a, b)
    return ones, xx, yy, xy


def _corner_x_over_rho2(X, Y):
    """Y ln ρ + X atan(Y/X): the double antiderivative of X/ρ² (zero terms at X = 0, ρ = 0).

    ∂/∂Y of it is 1 + ln ρ (continuous off the origin, integrable there), whose
    ∂/∂X is X/ρ², so the four-corner sum is the integral over a rectangle.
    """
    X = np.asarray(X, dtype=float)
    Y = np.asarray(Y, dtype=float)
    rho2 = X * X + Y * Y
    with np.errstate(divide="ignore", invalid="ignore"):
        ty = np.where(rho2 > 0.0, 0.5 * Y * np.log(np.where(rho2 > 0.0, rho2, 1.0)), 0.0)
        tx = np.where(X != 0.0, X * np.arctan(Y / np.where(X != 0.0, X, 1.0)), 0.0)
    return tx + ty


def rectangle_integral_x_over_rho2(x, y, half_x, half_y):
    """∫∫ X/ρ² over the rectangle |x'| <= half_x, |y'| <= half_y (X = x - x') [dimensionless]."""
    return _four_corners(_corner_x_over_rho2, x, y, half_x, half_y)


def padded_size(n):
    """The FFT length of the zero padding: at least 2n, and fast for scipy.fft."""
    return sfft.next_fast_len(2 * n, real=True)


def cerruti_kernels(n, spacing, shear_modulus, poisson, m=None):
    """Influence coefficients K_xx, K_yy, K_xy [m/Pa] of a unit traction on one pixel.

    u_x at pixel offset (i, j) from τx = 1 on pixel (0, 0) is K_xx[i, j],
    u_y from it K_xy[i, j]; u_y from τy is K_yy. On the m × m wrap-around
    grid of the DC-FFT (m >= 2n, default :func:`padded_size`): offset i at
    index i mod m for |i| < n, zero elsewhere, so the circular convolution
    equals the linear one on the n × n box (:func:`bem.operator.influence_kernel`
    with m = 2n).
    """
    m = padded_size(n) if m is None else m
    if m < 2 * n:
        raise ValueError(f"padding {m} < 2n = {2 * n}")
    off = np.arange(m)
    off = np.where(off < n, off, off - m).astype(float)
    far = np.abs(off) >= n
    off[far] = 0.0
    X, Y = np.meshgrid(off * spacing, off * spacing, indexing="ij")
    ones, xx, yy, xy = rectangle_integrals(X, Y, 0.5 * spacing, 0.5 * spacing)
    c = 1.0 / (2.0 * math.pi * shear_modulus)
    kernels = [c * ((1.0 - poisson) * ones + poisson * xx),
               c * ((1.0 - poisson) * ones + poisson * yy),
               c * poisson * xy]
    for K in kernels:
        K[far, :] = 0.0
        K[:, far] = 0.0
    return kernels


def equivalent_half_space(E_star: float, G_star: float) -> tuple[float, float]:
    """Shear modulus G and Poisson ratio ν of the half-space with the same E*, G*.

    A rigid indenter on a half-space (G, ν) has E* = 2G/(1-ν) and
    G* = 4G/(2-ν) (paper Eqs. 5-6); inverted: ν = 2(1-r)/(2-r), r = G*/E*,
    G = E*(1-ν)/2. Exact for a rigid counterface; for two elastic bodies the
    half-space carrying both compliances.
    """
    r = G_star / E_star
    nu = 2.0 * (1.0 - r) / (2.0 - r)
    if not -1.0 < nu <= 0.5:
        raise ValueError(f"G*/E* = {r:g} gives no Poisson ratio in (-1, 0.5]")
    return E_star * (1.0 - nu) / 2.0, nu


class TangentialHalfSpace:
    """u = A τ, (u_x, u_y) from (τx, τy), on an n × n grid of pixels (DC-FFT).

    Parameters
    ----------
    n : pixels per side.
    spacing : pixel side [m].
    shear_modulus : G [Pa].
    poisson : ν; 0 uncouples the components (u_x = (1/(2πG)) ∫∫ τx/ρ).
    workers : threads of scipy.fft.
    """

    def __init__(self, n, spacing, shear_modulus, poisson, workers=1):
        self.n, self.spacing = n, spacing
        self.shear_modulus, self.poisson, self.workers = shear_modulus, poisson, workers
        m = padded_size(n)
        Kxx, Kyy, Kxy = cerruti_kernels(n, spacing, shear_modulus, poisson, m)
        # K_xx, K_yy are even in both offsets, K_xy odd in both: all three
        # transforms are real
        self.hat = [np.ascontiguousarray(sfft.rfft2(K, workers=workers).real)
                    for K in (Kxx, Kyy, Kxy)]
        self.self_compliance = float(Kxx[0, 0])
        a, b, c = self.hat
        # the largest eigenvalue of the 2 × 2 symbol: bounds A on any set of pixels
        self.largest_eigenvalue = float(np.max(0.5 * (a + b)
                                               + np.sqrt(0.25 * (a - b)**2 + c * c)))
        self._pad = np.zeros((m, m))
        self.applications = 0

    def __call__(self, tx, ty):
        """Surface displacements (u_x, u_y) [m] at the pixel centres of the traction [Pa]."""
        n, w = self.n, self.workers
        self._pad[:n, :n] = tx
        fx = sfft.rfft2(self._pad, workers=w)
        self._pad[:n, :n] = ty
        fy = sfft.rfft2(self._pad, workers=w)
        a, b, c = self.hat
        s = self._pad.shape
        ux = sfft.irfft2(a * fx + c * fy, s=s, workers=w)[:n, :n]
        uy = sfft.irfft2(c * fx + b * fy, s=s, workers=w)[:n, :n]
        self.applications += 1
        return ux, uy


def shear_to_normal_kernel(n, spacing, beta, E_star, m=None):
    """Normal displacement [m/Pa] at pixel offset (i, j) of a unit traction τx on one pixel.

    The (1 − 2ν) term of Cerruti's solution: a tangential point force Q_x
    moves the surface normally by (1 − 2ν)/(4πG) Q_x X/ρ² into the solid
    (Betti's theorem with Boussinesq's radial displacement, which points
    towards a normal load, gives the sign: ahead of the force the surface
    sinks; Tamaas's operator agrees, tests/test_bem_coupling.py). For two bodies the relative normal displacement is
    β/(π E*) Q_x X/ρ², β Dundurs' second parameter (rigid counterface:
    β/(πE*) = (1 − 2ν)/(4πG)). Laid out as :func:`cerruti_kernels` on the
    m × m wrap-around grid.
    """
    m = padded_size(n) if m is None else m
    if m < 2 * n:
        raise ValueError(f"padding {m} < 2n = {2 * n}")
    off = np.arange(m)
    off = np.where(off < n, off, off - m).astype(float)
    far = np.abs(off) >= n
    off[far] = 0.0
    X, Y = np.meshgrid(off * spacing, off * spacing, indexing="ij")
    K = beta / (math.pi * E_star) * spacing * rectangle_integral_x_over_rho2(
        X / spacing, Y / spacing, 0.5, 0.5)
    K[far, :] = 0.0
    K[:, far] = 0.0
    return K


class ShearToNormal:
    """u_z = C τx: the normal displacement [m] of a traction along x [Pa] (DC-FFT).

    The coupling of the tangential into the normal problem for bodies that
    are not elastically similar (Dundurs' β ≠ 0); C is odd in x (its
    transform imaginary) and antisymmetric as a matrix, Cᵀ = −C: it does no
    work on the pressure, pᵀ C p = 0.

    Parameters
    ----------
    n : pixels per side.
    spacing : pixel side [m].
    beta : Dundurs' β of the pair (:func:`cases.dundurs_beta`).
    E_star : effective modulus [Pa].
    workers : threads of scipy.fft.
    """

    def __init__(self, n, spacing, beta, E_star, workers=1):
        self.n, self.spacing, self.beta, self.workers = n, spacing, beta, workers
        m = padded_size(n)
        self.hat = sfft.rfft2(shear_to_normal_kernel(n, spacing, beta, E_star, m),
                              workers=workers)
        self._pad = np.zeros((m, m))
        self.applications = 0

    def __call__(self, tx):
        """Normal displacement [m] at the pixel centres of the traction τx [Pa], (n, n)."""
        n = self.n
        self._pad[:n, :n] = tx
        out = sfft.irfft2(sfft.rfft2(self._pad, workers=self.workers) * self.hat,
                          s=self._pad.shape, workers=self.workers)[:n, :n]
        self.applications += 1
        return out


@dataclass
class TangentialState:
    """The tangential contact after an increment.

    traction : (2, n, n) τx, τy on the half-space [Pa].
    slip : (2, n, n) relative displacement w accumulated by slip [m].
    slip_increment : (2, n, n) Δw of the last increment [m].
    stick : (n, n) bool, loaded pixels that did not slip in the increment.
    displacement : (δx, δy) of the indenter [m].
    force : (Qx, Qy) = Δ² Σ τ [N].
    dissipated : Δ² Σ τ·Δw of the increment [J].
    """

    traction: np.ndarray
    slip: np.ndarray
    slip_increment: np.ndarray
    stick: np.ndarray
    displacement: tuple
    force: tuple
    dissipated: float
    iterations: int = 0
    residual: float = 0.0


def zero_state(n) -> TangentialState:
    """The state before any tangential load."""
    z = np.zeros((2, n, n))
    return TangentialState(traction=z, slip=z.copy(), slip_increment=z.copy(),
                           stick=np.zeros((n, n), bool), displacement=(0.0, 0.0),
                           force=(0.0, 0.0), dissipated=0.0)


def _project(tx, ty, bound):
    """Radial clipping of (τx, τy) onto the discs |τ| <= bound, per pixel."""
    mag = np.hypot(tx, ty)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(mag > bound, bound / np.where(mag > 0, mag, 1.0), 1.0)
    return tx * scale, ty * scale


def solve(op: TangentialHalfSpace, pressure, mu, displacement, previous=None, *,
          tol=1e-7, maxiter=20000, check_every=10) -> TangentialState:
    """The increment from ``previous`` to the indenter displacement δ.

    Parameters
    ----------
    op : the half-space's tangential operator.
    pressure : (n, n) normal pressure [Pa], held.
    mu : friction coefficient.
    displacement : (δx, δy) [m], or δx alone.
    previous : the state the increment starts from (None: unloaded).
    tol : tolerance of the natural residual (module docstring).

    Raises
    ------
    SolverError
        When ``maxiter`` iterations do not reach ``tol``.
    """
    n = op.n
    p = np.maximum(np.asarray(pressure, dtype=float), 0.0)
    dx, dy = (float(displacement), 0.0) if np.isscalar(displacement) else map(float, displacement)
    prev = previous if previous is not None else zero_state(n)
    bound = mu * p
    scale = mu * float(np.max(p))
    if not scale > 0.0:
        raise SolverError("tangential solve: no pixel carries pressure")
    loaded = p > 0.0
    bx = np.where(loaded, dx - prev.slip[0], 0.0)
    by = np.where(loaded, dy - prev.slip[1], 0.0)
    L = op.largest_eigenvalue
    k00 = op.self_compliance
    x, y = _project(prev.traction[0], prev.traction[1], bound)
    zx, zy = x.copy(), y.copy()
    t = 1.0
    res = np.inf
    for it in range(1, maxiter + 1):
        ux, uy = op(zx, zy)
        # gradient A z - b; a projected step along it
        xn, yn = _project(zx - (ux - bx) / L, zy - (uy - by) / L, bound)
        # adaptive restart: momentum dropped when it points uphill
        if np.sum((zx - xn) * (xn - x) + (zy - yn) * (yn - y)) > 0.0:
            t = 1.0
            zx, zy = xn, yn
        else:
            t_new = 0.5 * (1.0 + math.sqrt(1.0 + 4.0 * t * t))
            beta = (t - 1.0) / t_new
            zx, zy = xn + beta * (xn - x), yn + beta * (yn - y)
            t = t_new
        x, y = xn, yn
        if it % check_every == 0 or it == maxiter:
            ux, uy = op(x, y)
            wx = np.where(loaded, bx - ux, 0.0)
            wy = np.where(loaded, by - uy, 0.0)
            px, py = _project(x + wx / k00, y + wy / k00, bound)
            res = float(np.max(np.hypot(x - px, y - py))) / scale
            if res < tol:
                return _state(op, prev, x, y, wx, wy, bound, (dx, dy), it, res)
    raise SolverError(f"tangential solve did not converge: natural residual {res:.3g} after "
                      f"{maxiter} iterations (tolerance {tol:g})")


def _state(op, prev, tx, ty, wx, wy, bound, displacement, it, res):
    area = op.spacing**2
    mag = np.hypot(tx, ty)
    # stick: loaded and strictly inside the disc (slip pixels sit on its rim)
    stick = (bound > 0.0) & (mag < bound * (1.0 - 1e-6))
    traction = np.stack([tx, ty])
    inc = np.stack([wx, wy])
    inc[:, stick] = 0.0
    return TangentialState(traction=traction, slip=prev.slip + inc, slip_increment=inc,
                           stick=stick, displacement=tuple(displacement),
                           force=(area * float(np.sum(tx)), area * float(np.sum(ty))),
                           dissipated=area * float(np.sum(tx * inc[0] + ty * inc[1])),
                           iterations=it, residual=res)


def solve_force(op, pressure, mu, force, previous=None, *, tol=1e-7, force_rtol=1e-6,
                max_solves=60, **kw) -> TangentialState:
    """The increment to the tangential force Qx = ``force`` (δy = 0), |Q| < μ Δ² Σ p.

    Qx(δx) is continuous and non-decreasing: δx is bracketed from the
    previous displacement (steps doubling) and found by the Illinois variant
    of regula falsi to |Qx - force| <= force_rtol·μF, each solve warm-started
    from the last.
    """
    prev = previous if previous is not None else zero_state(op.n)
    area = op.spacing**2
    limit = mu * area * float(np.sum(np.maximum(pressure, 0.0)))
    if not abs(force) < limit:
        raise SolverError(f"tangential force {force:g} N is at or beyond μ·F = {limit:g} N: "
                          "gross slip")
    warm = {"state": prev}
    solves = [0]

    def excess(dx):
        if solves[0] >= max_solves:
            raise SolverError(f"tangential force control: {max_solves} solves did not reach "
                              f"Q = {force:g} N to {force_rtol:g} μF")
        solves[0] += 1
        st = solve(op, pressure, mu, (dx, prev.displacement[1]), prev, tol=tol, **kw)
        # warm start of the next solve from this one's traction
        warm["state"] = st
        return st, st.force[0] - force

    ftol = force_rtol * limit
    d0, f0 = prev.displacement[0], prev.force[0] - force
    if abs(f0) <= ftol:
        return excess(d0)[0]
    # the full-stick stiffness bounds Q'(δ) from above: this first step undershoots
    step = -f0 * op.self_compliance / area
    d1 = d0 + step
    st, f1 = excess(d1)
    while f1 * f0 > 0.0 and abs(f1) > ftol:
        d0, f0 = d1, f1
        step *= 2.0
        d1 = d0 + step
        st, f1 = excess(d1)
    while abs(f1) > ftol:
        d = d1 - f1 * (d1 - d0) / (f1 - f0)
        st, fd = excess(d)
        if fd * f1 < 0.0:
            d0, f0 = d1, f1
        else:
            # Illinois: the end kept has its value halved, so the bracket
            # shrinks from both sides
            f0 *= 0.5
        d1, f1 = d, fd
    return st


@dataclass
class Cycle:
    """A reciprocating displacement history 0 -> +u0 -> -u0 -> +u0 ....

    displacement, force : (K,) δx and Qx at every increment's end (the loop).
    dissipated : (K,) dissipation of each increment [J].
    energy_per_cycle : dissipation over the last full cycle (-u0 -> +u0 ... back) [J].
    loop_work : ∮ Q dδ over the last full cycle by the trapezoidal rule [J].
    at_amplitude : the state at the last +u0 (stick mask of the reloading).
    first_loading : the state at the first +u0 (Cattaneo–Mindlin).
    """

    displacement: np.ndarray
    force: np.ndarray
    dissipated: np.ndarray
    energy_per_cycle: float
    loop_work: float
    at_amplitude: TangentialState
    first_loading: TangentialState
    iterations: int = 0
    extra: dict = field(default_factory=dict)


def reciprocating(op, pressure, mu, amplitude, *, increments=8, cycles=1, tol=1e-7,
                  **kw) -> Cycle:
    """Run the history 0 -> +u0, then ``cycles`` times +u0 -> -u0 -> +u0, with memory.

    ``increments`` per quarter cycle (first loading) and twice that per half
    cycle; each increment warm-started from the previous state.
    """
    if increments < 1 or cycles < 1:
        raise ValueError("increments and cycles must be >= 1")
    half = np.linspace(amplitude, -amplitude, 2 * increments + 1)[1:]
    path = list(np.linspace(0.0, amplitude, increments + 1)[1:])
    for _ in range(cycles):
        path += list(half) + list(-half)
    st = zero_state(op.n)
    disp, force, diss = [0.0], [0.0], [0.0]
    first = None
    its = 0
    for k, d in enumerate(path):
        st = solve(op, pressure, mu, (d, 0.0), st, tol=tol, **kw)
        its += st.iterations
        disp.append(d)
        force.append(st.force[0])
        diss.append(st.dissipated)
        if k == increments - 1:
            first = st
    disp, force, diss = map(np.asarray, (disp, force, diss))
    m = 4 * increments          # increments per full cycle
    last = slice(len(path) - m + 1, len(path) + 1)
    energy = float(np.sum(diss[last]))
    ld, lq = disp[len(path) - m:], force[len(path) - m:]
    work = float(np.sum(0.5 * (lq[1:] + lq[:-1]) * np.diff(ld)))
    return Cycle(displacement=disp, force=force, dissipated=diss, energy_per_cycle=energy,
                 loop_work=work, at_amplitude=st, first_loading=first, iterations=its)
