"""Normal contact on the pixel grid by constrained conjugate gradients.

Solves, for pressures p >= 0 on the pixels,

    gap = h - d + (G + σ I) p >= 0,   p >= 0,   p · gap = 0,

under depth control (d given) or force control (Δ² Σ p = W given, d the
unknown), with Polonsky & Keer's (2000) constrained conjugate gradients: CG
on the pixels in contact, a projection onto p >= 0, a restart (steepest
descent) whenever pixels out of contact overlap, and, under force control,
the mean gap over the contact subtracted (it is the approach d) and p
rescaled to the force. σ I is the wear compliance of an implicit wear step
(σ = h K for backward Euler); σ = 0 is the static problem.

The search directions are preconditioned (Vollebregt 2014) by the inverse
of the padded circulant, 1/(Ĝ + σ) in Fourier space, applied to the gap on
the contact and restricted to it again: symmetric positive definite on the
contact set, and close to the inverse of G + σI away from the contact edge,
which removes most of the iterations that grow with the grid.

Converged when the natural residual max |min(p/p_scale, gap/g_scale)| is
below ``tol``: it is zero exactly when the three conditions hold.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.fft as sfft

from wearcheck.cases import SolverError


#: pixels clipped in one iteration up to which their displacement is summed
#: directly (n² each) rather than by a full convolution
MAX_DIRECT = 32
#: iterations between fresh convolutions of the whole pressure (rounding drift)
REFRESH = 50
#: relative error of a single-precision operator application (measured
#: 3.2e-7-3.9e-7 of max |G t|, :meth:`HalfSpace.single`), times 5: the bound
#: on what each single-precision search direction adds to the displacement's error
SINGLE_ERROR = 2e-6
#: single-precision directions only for tolerances from this up (the
#: iteration stagnates near 2e-7 with them), and only while the residual
#: halves at least once in SINGLE_STALL iterations; then double precision
SINGLE_MIN_TOL = 1e-7
SINGLE_STALL = 6
#: the contact is solved on a square window of the box around the pixels
#: that may touch (:func:`solve`) when its side is at most this fraction of
#: the box's; pixels added around them (at least; an eighth of their extent
#: when more); enlargements before solving on the whole box
WINDOW_MAX_FRACTION = 0.85
WINDOW_MARGIN = 4
WINDOW_TRIES = 3


@dataclass
class Contact:
    """A converged contact: pressure [Pa], gap [m], approach d [m], force [N].

    ``displacement`` is G p (without the wear compliance) as the solve
    tracked it, within ``displacement_error`` [m]: a later solve that starts
    from this pressure (or from a combination of such) needs no convolution
    to start.
    """

    pressure: np.ndarray
    gap: np.ndarray
    depth: float
    force: float
    iterations: int
    residual: float
    displacement: np.ndarray | None = None
    displacement_error: float = 0.0


def complementarity_residual(p, gap, p_scale, g_scale) -> float:
    """max |min(p/p_scale, gap/g_scale)|: zero iff p >= 0, gap >= 0, p·gap = 0."""
    m = np.minimum(p, gap * (p_scale / g_scale))
    return float(max(m.max(), -m.min())) / p_scale


def initial_pressure(h, depth=None, force=None):
    """A starting pressure when no warm start is given."""
    if force is not None:
        # a paraboloid-like guess over the lowest 2 % of the pixels (the box
        # is sized to the contact, so this is its right order)
        level = np.quantile(h, 0.02)
        p = np.sqrt(np.maximum(level - h, 0.0))
        return p if np.any(p > 0) else (h == np.min(h)).astype(float)
    p = np.where(h < depth, depth - h, 0.0)
    if not np.any(p > 0):
        raise SolverError("no pixel of the profile reaches the approach d: no contact")
    return p


def mirror_x(field: np.ndarray) -> np.ndarray:
    """The field's mirror image x -> -x about the tip (pixel n//2 of the first axis).

    Pixel i goes to 2·(n//2) - i; for even n pixel 0 has no image in the box
    and keeps its own value (the n-periodic reflection, which commutes with
    the circulant preconditioner).
    """
    n = field.shape[0]
    lo = 2 * (n // 2) - (n - 1)
    out = field.copy()
    out[lo:] = field[lo:][::-1]
    return out


def _mirror_index(i: np.ndarray, n: int) -> np.ndarray:
    """Row index of the mirror image of rows ``i`` (see :func:`mirror_x`)."""
    j = 2 * (n // 2) - i
    return np.where(j < n, j, i)


def contact_window(candidates: np.ndarray, margin: int):
    """The square window (rows, columns as slices) holding ``candidates`` with ``margin``.

    Its side is a fast FFT length (its padded operator's is twice that);
    None when it would exceed :data:`WINDOW_MAX_FRACTION` of the box.
    """
    n = candidates.shape[0]
    rows = np.nonzero(candidates.any(axis=1))[0]
    cols = np.nonzero(candidates.any(axis=0))[0]
    if not len(rows):
        return None
    need = max(rows[-1] - rows[0], cols[-1] - cols[0]) + 1 + 2 * margin
    m = sfft.next_fast_len(int(need), real=True)
    if m > WINDOW_MAX_FRACTION * n:
        return None

    def place(first, last):
        start = (first + last + 1 - m) // 2
        return slice(int(min(max(start, 0), n - m)), int(min(max(start, 0), n - m)) + m)
    return place(rows[0], rows[-1]), place(cols[0], cols[-1])


def solve(op, h, *, depth=None, force=None, sigma=0.0, p_init=None, p_scale=1.0,
          g_scale=1.0, tol=1e-8, maxiter=5000, precondition=True,
          stroke_mean=False, single=True, displacement=None,
          displacement_error=0.0, window=True, whole_box=True) -> Contact:
    """Constrained CG contact solve (Polonsky–Keer), warm-started from ``p_init``.

    With ``window`` (and an operator that has windows, :meth:`bem.operator.
    HalfSpace.window`) the CG runs on a square window of the box. G's
    coefficients depend on the offset only, so with all the pressure inside,
    the window's solve is the box's. No pixel with h >= d can touch (G and σ
    are non-negative, so is the displacement of p >= 0): under depth control
    the window holds every pixel with h < d when it can
    (:data:`WINDOW_MAX_FRACTION`), and nothing outside it needs checking.
    Otherwise (force control, or a reach too wide) it holds the starting
    pressure's pixels with a margin (an eighth of their extent, at least
    :data:`WINDOW_MARGIN`; without a start, the first guess's); after the
    solve the pixels outside with h < d at the solved approach are checked
    on the whole box's displacement (the last one plus one convolution of
    the change of pressure), and one that overlaps joins the window and the
    solve is repeated (:data:`WINDOW_TRIES` times, then on the whole box).

    ``whole_box``: the returned gap and displacement cover the whole box.
    False: when no pixel outside the window may touch, they are NaN outside
    it (the displacement there is not computed; a later solve given it
    convolves where it is NaN); the gap there is h - d + G p, as p = 0. The
    pressure, approach, force and residual are the box's in either case.
    Parameters and result otherwise as :func:`solve_box`.
    """
    if (depth is None) == (force is None):
        raise ValueError("give depth or force")
    if not (window and not stroke_mean and hasattr(op, "window") and h.shape == (op.n, op.n)):
        return solve_box(op, h, depth=depth, force=force, sigma=sigma, p_init=p_init,
                         p_scale=p_scale, g_scale=g_scale, tol=tol, maxiter=maxiter,
                         precondition=precondition, stroke_mean=stroke_mean, single=single,
                         displacement=_known(displacement), displacement_error=displacement_error)
    per_pixel = np.ndim(sigma) > 0
    sigma = np.asarray(sigma, dtype=float) if per_pixel else float(sigma)
    p = None
    if p_init is not None and np.any(p_init > 0):
        p = np.maximum(np.asarray(p_init, dtype=float), 0.0)
    if p is None:
        displacement = None
    settings = dict(p_scale=p_scale, g_scale=g_scale, tol=tol, maxiter=maxiter,
                    precondition=precondition, single=single)
    box = contact_window(h < depth, 0) if depth is not None else None
    if box is not None:
        # every pixel that may touch is inside: the window's solve is the box's
        c = _solve_window(op, h, box, depth, force, sigma, p, displacement,
                          displacement_error, settings)
        result = _on_box(op, h, box, c, p, displacement, displacement_error, sigma, tol,
                         single, g_scale, p_scale, whole_box, False)[0]
        # nothing outside may touch: the window's residual is the box's (the
        # box's gap adds the rounding of the displacement's update there)
        result.residual = c.residual
        return result
    if p is not None:
        candidates = p > 0
    elif depth is not None:
        candidates = h < depth
    else:
        candidates = initial_pressure(h, force=force) > 0
    rows = np.nonzero(candidates.any(axis=1))[0]
    cols = np.nonzero(candidates.any(axis=0))[0]
    if not len(rows):
        raise SolverError("no pixel of the profile reaches the approach d: no contact")
    extent = max(rows[-1] - rows[0], cols[-1] - cols[0]) + 1
    margin = max(WINDOW_MARGIN, int(extent) // 8)
    iterations = 0
    for _ in range(WINDOW_TRIES):
        box = contact_window(candidates, margin)
        if box is None:
            break
        c = _solve_window(op, h, box, depth, force, sigma, p, displacement,
                          displacement_error, settings)
        iterations += c.iterations
        c.iterations = iterations
        outside = np.ones(h.shape, dtype=bool)
        outside[box] = False
        reach = outside & (h < c.depth)
        if not whole_box and not np.any(reach):
            return _on_box(op, h, box, c, p, displacement, displacement_error, sigma, tol,
                           single, g_scale, p_scale, False, False)[0]
        result, drift = _on_box(op, h, box, c, p, displacement, displacement_error, sigma,
                                tol, single, g_scale, p_scale, True, force is not None)
        p, displacement, displacement_error = (result.pressure, result.displacement,
                                               result.displacement_error)
        if result.residual + 2.0 * drift / g_scale < tol:
            return result
        overlap = reach & (result.gap < 0.0)
        if not np.any(overlap):
            break       # the window's solve and the box's residual differ at rounding
        candidates = candidates | overlap | (p > 0.0)
    c = solve_box(op, h, depth=depth, force=force, sigma=sigma, p_init=p, p_scale=p_scale,
                  g_scale=g_scale, tol=tol, maxiter=maxiter, precondition=precondition,
                  single=single, displacement=_known(displacement),
                  displacement_error=displacement_error)
    c.iterations += iterations
    return c


def _known(displacement, box=None):
    """The displacement (on ``box``) when it is known there (no NaN), else None."""
    if displacement is None:
        return None
    part = displacement if box is None else displacement[box]
    return part if np.isfinite(part).all() else None


def _solve_window(op, h, box, depth, force, sigma, p, displacement, displacement_error,
                  settings) -> Contact:
    """:func:`solve_box` on the window ``box`` (its own operator; applications counted as the box's)."""
    sub = op.window(box[0].stop - box[0].start)
    counts = sub.applications, sub.single_applications
    try:
        return solve_box(sub, h[box], depth=depth, force=force,
                         sigma=sigma[box] if np.ndim(sigma) else sigma,
                         p_init=None if p is None else p[box],
                         displacement=None if p is None else _known(displacement, box),
                         displacement_error=displacement_error, **settings)
    finally:
        op.applications += sub.applications - counts[0]
        op.single_applications += sub.single_applications - counts[1]


def _on_box(op, h, box, c, p, displacement, displacement_error, sigma, tol, single, g_scale,
            p_scale, whole_box, force_control):
    """The window's contact ``c`` on the whole box, and the bound on its displacement's error.

    ``whole_box``: the displacement on the box is the last one plus that of
    the change of pressure (in single precision under the running bound
    while that stays small against the tolerance, else one double
    convolution); the gap and residual are the box's (under force control
    with the approach recomputed on it). Otherwise the window's displacement
    and gap, NaN outside it.
    """
    p_new = np.zeros_like(h)
    p_new[box] = c.pressure
    if not whole_box:
        u = np.full_like(h, np.nan)
        u[box] = c.displacement
        gap = np.full_like(h, np.nan)
        gap[box] = c.gap
        return Contact(pressure=p_new, gap=gap, depth=c.depth, force=c.force,
                       iterations=c.iterations, residual=c.residual, displacement=u,
                       displacement_error=c.displacement_error), c.displacement_error
    u, drift = None, 0.0
    if displacement is not None and p is not None and single and tol >= SINGLE_MIN_TOL:
        change = op.single(p_new - p)
        drift = displacement_error + SINGLE_ERROR * float(np.max(np.abs(change)))
        if 2.0 * drift / g_scale < 0.5 * tol:
            u = displacement + change
            if not np.isfinite(u).all():
                u = None
    if u is None:
        u, drift = op(p_new), 0.0
    on = p_new > 0.0
    d = float(np.mean((h + u + sigma * p_new)[on])) if force_control else c.depth
    gap = h - d + u + sigma * p_new
    res = complementarity_residual(p_new, gap, p_scale, g_scale)
    return Contact(pressure=p_new, gap=gap, depth=d, force=c.force, iterations=c.iterations,
                   residual=res, displacement=u, displacement_error=drift), drift


def solve_box(op, h, *, depth=None, force=None, sigma=0.0, p_init=None, p_scale=1.0,
              g_scale=1.0, tol=1e-8, maxiter=5000, precondition=True,
              stroke_mean=False, single=True, displacement=None,
              displacement_error=0.0) -> Contact:
    """Constrained CG contact solve (Polonsky–Keer) on the whole box, warm-started from ``p_init``.

    Parameters
    ----------
    op : :class:`bem.operator.HalfSpace`, p -> G p (m per Pa).
    h : (n, n) height of the (worn) profile [m].
    depth, force : give one: the approach d [m] (depth control) or the
        normal force W [N] (force control).
    sigma : wear compliance σ [m/Pa] added to G (implicit wear step): a
        number, or one per pixel (the linearised wear law of a pressure
        exponent n != 1); the preconditioner then takes its mean over the
        loaded pixels.
    stroke_mean : the wear compliance acts on the mean of p and its mirror
        image x -> -x, σ (p + M p)/2 (reciprocating strokes with coupling,
        :mod:`bem.wear`): symmetric positive semi-definite as σ I, for σ
        symmetric in x. The preconditioner stays 1/(Ĝ + σ): one exact on
        the periodic box, (Ĝ + σ)⁻¹ on the symmetric part and Ĝ⁻¹ on the
        antisymmetric part, did not converge in 5000 iterations at
        σ = 10⁵ Δ/E* (sliding Hertz contact, 128², depth control; the plain
        one: 210 over the coupling's sweeps): the contact set is not
        symmetric, and a pixel whose image is out of contact sees σ/2, which
        the split weighs as σ or 0.
    p_init : starting pressure (clipped to >= 0), e.g. the last step's.
    p_scale, g_scale : pressure and gap scales of the residual [Pa], [m].
    tol : complementarity tolerance (see module docstring).
    precondition : use the Fourier preconditioner (False: plain PK).
    single : the search directions' displacements in single precision
        (:meth:`HalfSpace.single`), the displacement of the pressure itself in
        double: each single-precision increment adds at most
        :data:`SINGLE_ERROR` of its size to the displacement's error, and
        the solve ends only when the residual plus that bound (over
        ``g_scale``) is below ``tol``, else the displacement is recomputed in
        double and the solve continues in double precision (as it does when
        the residual stops falling, and throughout for ``tol`` below
        :data:`SINGLE_MIN_TOL`).
    displacement, displacement_error : G p_init when known (a returned
        :class:`Contact`'s, or a linear combination of them) and the bound
        on its error [m]: the solve starts from it instead of a convolution;
        the error bound is carried on as the single-precision one.

    Raises
    ------
    SolverError
        When ``maxiter`` iterations do not reach ``tol``, or the profile
        does not reach the approach.
    """
    if (depth is None) == (force is None):
        raise ValueError("give depth or force")
    area = op.spacing**2
    per_pixel = np.ndim(sigma) > 0
    sigma = np.asarray(sigma, dtype=float) if per_pixel else float(sigma)
    if p_init is None or not np.any(p_init > 0):
        p = initial_pressure(h, depth, force)
        displacement = None
    else:
        p = np.maximum(np.asarray(p_init, dtype=float), 0.0)
    if force is not None:
        scale = force / (area * np.sum(p))
        p = p * scale
        if displacement is not None:
            displacement, displacement_error = scale * displacement, scale * displacement_error
    sigma_bar = float(np.mean(sigma[p > 0])) if per_pixel else sigma
    precond = op.preconditioner(sigma_bar) if precondition else None

    def compliance(v):
        """The wear compliance applied to v: σ v, or σ (v + M v)/2."""
        return sigma * (0.5 * (v + mirror_x(v)) if stroke_mean else v)

    # Each CG iteration's elementwise work is a few dozen passes over the
    # box; those below are skipped or fused where the result is the same:
    # no wear compliance for σ = 0, h - d once under depth control, the
    # inner products in one pass each (einsum), and every array of the
    # iteration written into one allocated before it: a fresh array of a
    # window's size is mapped from the system and faulted in page by page
    # (measured: twice the time of the pass itself, docs/performance.md)
    has_compliance = stroke_mean or per_pixel or sigma != 0.0
    h_minus_d = h - depth if depth is not None else None

    t = np.zeros_like(p)
    gap, g, z, work = (np.empty_like(p) for _ in range(4))
    on, free, free_old = (np.empty(p.shape, dtype=bool) for _ in range(3))
    gz_old = 1.0
    restart = True
    d = depth
    res = np.inf
    u = None
    drift = 0.0          # bound on the error single-precision increments left in u [m]
    single = single and tol >= SINGLE_MIN_TOL
    best, since = np.inf, 0
    ratio = p_scale / g_scale
    if displacement is not None:
        u = displacement + compliance(p)
        drift = displacement_error
    for it in range(1, maxiter + 1):
        if u is None or it % REFRESH == 0:
            u = op(p) + compliance(p)
            drift = 0.0
            # the gap jumps by the error the recomputation removed: the
            # conjugate directions' recurrence no longer holds (after a
            # displacement off by 2e-5 d the iteration stalled for hundreds
            # of iterations without this restart)
            restart = True
        np.greater(p, 0.0, out=on)
        if force is not None:
            # the approach: the mean of h + u over the contact (zero gap there)
            d = float(np.mean((h + u)[on]))
            np.subtract(h, d, out=gap)
            gap += u
        else:
            np.add(u, h_minus_d, out=gap)
        # the complementarity residual (:func:`complementarity_residual`)
        np.multiply(gap, ratio, out=work)
        np.minimum(p, work, out=work)
        res = float(max(work.max(), -work.min())) / p_scale
        if res < tol:
            if res + 2.0 * drift / g_scale < tol:
                return Contact(pressure=p, gap=gap, depth=float(d),
                               force=float(area * np.sum(p)), iterations=it - 1, residual=res,
                               displacement=u - compliance(p), displacement_error=drift)
            # the single-precision increments may hide a residual above tol
            # (2·drift: the approach under force control is a mean of u too)
            u, single = None, False
            continue
        if single:
            if res < 0.5 * best:
                best, since = res, 0
            else:
                since += 1
                if since >= SINGLE_STALL:
                    # stagnating at single precision's resolution: on in double
                    u, single = None, False
                    continue
        # the free pixels of the bound-constrained problem: loaded, or
        # unloaded and overlapping (their gradient points into p > 0)
        np.less(gap, 0.0, out=free)
        free |= on
        np.multiply(gap, free, out=g)
        if force is not None:
            # the force is held: directions of zero mean on the free pixels
            g[free] -= np.mean(g[free])
        if precond is not None:
            np.multiply(precond(g), free, out=z)
            if force is not None:
                z[free] -= np.mean(z[free])
        else:
            np.copyto(z, g)
        gz = float(np.einsum("ij,ij->", g, z))
        # conjugate directions while the free set stays; restart when it changes
        if restart or not np.array_equal(free, free_old):
            np.copyto(t, z)
        else:
            t *= gz / gz_old
            t += z
        restart = False
        free, free_old = free_old, free
        gz_old = gz
        r = op.single(t) if single else op(t)
        if has_compliance:
            r += compliance(t)
        rt = float(np.einsum("ij,ij->", r, t))
        if not rt > 0.0:
            raise SolverError("contact solve: the search direction has no positive curvature "
                              f"(residual {res:.3g}); the operator is not positive definite")
        tau = gz / rt
        np.multiply(t, tau, out=work)
        p -= work
        np.multiply(r, tau, out=work)
        u -= work
        if single:
            drift += SINGLE_ERROR * abs(tau) * float(max(r.max(), -r.min()))
        # the projection onto p >= 0: its (few) pixels enter u by direct sum
        clipped = np.nonzero(p < 0.0) if p.min() < 0.0 else ((),)
        if len(clipped[0]) > MAX_DIRECT:
            np.maximum(p, 0.0, out=p)
            u = None
        elif len(clipped[0]):
            values = -p[clipped]
            p[clipped] = 0.0
            op.add_point_loads(u, clipped, values)
            weight = (sigma[clipped] if per_pixel else sigma) * values
            if stroke_mean:
                # σ (δ + M δ)/2 of the clipped pixels δ (σ symmetric in x)
                image = (_mirror_index(clipped[0], p.shape[0]), clipped[1])
                np.add.at(u, clipped, 0.5 * weight)
                np.add.at(u, image, 0.5 * weight)
            else:
                u[clipped] += weight
        if force is not None:
            total = area * np.sum(p)
            if not total > 0.0:
                raise SolverError("contact solve: the pressure vanished under force control")
            p *= force / total
            if u is not None:
                u *= force / total
                drift *= force / total
    raise SolverError(f"contact solve did not converge: complementarity residual {res:.3g} "
                      f"after {maxiter} iterations (tolerance {tol:g}); raise bem.tolerance "
                      "or check the case")


#: normal–tangential coupling: most sweeps, and the sweep after which the
#: iteration must have contracted (rate about βμ, measured 0.05-0.09 per sweep)
COUPLED_MAX_SWEEPS = 40
COUPLED_CHECK_AFTER = 4


def solve_coupled(op, shear, h, traction_factor, *, depth=None, force=None, sigma=0.0,
                  p_init=None, p_scale=1.0, g_scale=1.0, tol=1e-8, maxiter=5000,
                  precondition=True, stroke_mean=False, displacement=None,
                  displacement_error=0.0) -> Contact:
    """The contact in gross slip with the friction traction moving the surface normally.

    Solves p >= 0, gap >= 0, p·gap = 0 with

        gap = h - d + (G + σ I) p + C(t p),

    C the normal displacement of a traction along x (:class:`bem.tangential.
    ShearToNormal`) and t = ±μ the traction per unit pressure (τx = μp
    along the sliding direction). C is antisymmetric, so the operator
    G + tC is not symmetric and constrained CG does not apply to it as a
    whole; the coupling is iterated instead (Picard): each sweep is a
    contact solve (:func:`solve`, warm-started) on the profile
    h + C(t p_prev). The iteration contracts by about |t| β per sweep (the
    symbol of tC over that of G is tβ k_x/|k|, at most |t| β). Converged
    when the complementarity residual of the coupled problem, with the gap
    recomputed from the new pressure (and, under force control, the approach
    shifted by the mean change over the contact), is below ``tol``.
    ``sigma``, ``stroke_mean``, ``displacement`` as :func:`solve` (the wear
    compliance is implicit in each sweep, only the coupling is lagged).

    Returns the :class:`Contact`, its ``iterations`` summed over the sweeps.

    Raises
    ------
    SolverError
        When a sweep's solve fails, or the sweeps do not converge (no
        contraction after :data:`COUPLED_CHECK_AFTER` sweeps, or more than
        :data:`COUPLED_MAX_SWEEPS`).
    """
    p = p_init
    u_c = shear(traction_factor * p) if p is not None and np.any(p > 0) else np.zeros_like(h)
    iterations, history = 0, []
    for sweep in range(1, COUPLED_MAX_SWEEPS + 1):
        c = solve(op, h + u_c, depth=depth, force=force, sigma=sigma, p_init=p,
                  p_scale=p_scale, g_scale=g_scale, tol=tol, maxiter=maxiter,
                  precondition=precondition, stroke_mean=stroke_mean,
                  displacement=displacement, displacement_error=displacement_error)
        displacement, displacement_error = c.displacement, c.displacement_error
        iterations += c.iterations
        u_new = shear(traction_factor * c.pressure)
        change = u_new - u_c
        d = c.depth
        if force is not None:
            on = c.pressure > 0.0
            shift = float(np.mean(change[on]))
            change -= shift
            d += shift
        gap = c.gap + change
        res = complementarity_residual(c.pressure, gap, p_scale, g_scale)
        if res < tol:
            return Contact(pressure=c.pressure, gap=gap, depth=float(d), force=c.force,
                           iterations=iterations, residual=res, displacement=displacement,
                           displacement_error=displacement_error)
        history.append(res)
        if sweep > COUPLED_CHECK_AFTER and res >= history[0]:
            break
        p, u_c = c.pressure, u_new
    raise SolverError(f"contact solve with normal-tangential coupling (bem.coupling) did not "
                      f"converge: complementarity residual {history[-1]:.3g} after "
                      f"{len(history)} sweeps (tolerance {tol:g}; the first sweep left "
                      f"{history[0]:.3g}); the sweeps contract by about Dundurs' beta times "
                      f"mu = {abs(shear.beta * traction_factor):.3g} and cannot converge near "
                      "or above 1")
