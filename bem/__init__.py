"""3D boundary-element solver of gross-slip Reye–Archard wear on the elastic half-space.

``solve(case, progress=None) -> cases.RunResult``; ``supports(case)``.

A rigid plane against an elastic indenter is a rigid indenter on an elastic
half-space of modulus E* (the bodies' compliances add). The surface is a
square grid of ``bem.grid``² pixels of side Δ = bem.box · a_max / grid,
centred on the tip, a_max the largest contact radius the run can reach
(:func:`bem.solver.largest_contact_radius`). Each pixel carries a uniform
pressure; the displacement at the pixel centres is G p, Love's (1929)
closed-form influence coefficients convolved by a zero-padded FFT
(:mod:`bem.operator`, not periodic). The contact problem p >= 0, gap >= 0,
p·gap = 0 is solved by preconditioned constrained conjugate gradients
(:mod:`bem.contact`), warm-started, to ``bem.tolerance`` in
max |min(p/p0, gap/d)|, under depth or force control; not converging is a
SolverError, as is a contact that reaches the box's outermost pixels.

Wear per pixel Δw = K p Δs (K = k μ/σ0) by explicit Euler (stable below
h = 2 λ_min(G)/K, refused beyond), implicit Euler (the contact problem
with G + hK·I), variable-step BDF2 or the adaptive scheme: :mod:`bem.wear`
supplies the implicit step, :mod:`numerics.stepping` runs the schemes as
for the MDR and FEM.

Outputs: history columns of ``cases.HISTORY_COLUMNS`` (contact_radius is
the equivalent radius √(A/π) of the contact area A, wear_center the wear of
the centre pixel) plus s_hat, max_pressure, cg_iterations,
complementarity_residual; ``r``, ``f``, ``p`` are azimuthal averages on
rings one pixel wide (ring k holds the pixels with round(ρ/Δ) = k), each at
the root-mean-square radius of its pixels (:func:`bem.solver.ring_radii`);
``fields``: ``x``, ``y`` (n,) pixel centres and ``profile``,
``wear_depth``, ``pressure``, ``gap`` (K, n, n) per stage, x along the
first axis; ``info["anisotropy"]``: per stage the largest deviation of the
pressure and of the wear from their ring averages, over p0 and d.
``bem.coupling = true``: the friction traction μp (Cerruti's (1 − 2ν) term,
Dundurs' β) moves the surface normally in every contact solve
(:func:`bem.contact.solve_coupled`); one sliding direction, or reciprocating
strokes when sliding.stroke is given (docs/bem-tangential.md §6).
Not modelled: wear.tangential_correction.
"""

from wearcheck.registry import lazy_attributes

__all__ = ["solve", "supports"]

# solve, supports and the submodules are imported on first use: the registry imports
# this package for its registration.py, which must not pull in the numerics
__getattr__ = lazy_attributes(__name__, {"solve": ".solver", "supports": ".solver"})
