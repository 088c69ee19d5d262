"""FEM counterpart of the MDR solver: an axisymmetric elastic sphere in
scikit-fem, condensed onto its candidate contact nodes, against a rigid plane.

``solve(case, progress=None) -> cases.RunResult``; ``supports(case)`` says
why a case cannot run (elastic counterface, rigid indenter, ellipsoid,
ν > 0.495, no indenter.radius) or returns None.

Geometry and conventions (SI units): r–z plane, the sphere's pole at the
origin, the sphere above it (centre at (0, R), R = indenter.radius), its flat
top face z = R clamped and moved rigidly down by the approach d, u_r = 0 on
the axis; the rigid plane is z = 0. The initial gap of contact node i is the
case's profile f(r_i) (exactly the mesh surface for profile "sphere"; for the
paraboloid and truncated paraboloid the elastic body is still the sphere,
whose compliance differs negligibly at a0/R <= 0.01). Only the sphere's E1,
ν1 enter: the counterface must be rigid.

The stiffness (:mod:`fem.axisym`, :mod:`fem.model`) is factorised once, with
the contact nodes' axial DOFs eliminated last, so that the compliance C of
those DOFs is the inverse of the trailing Schur block; the wear loop only
touches C. Full fields are recovered for the stored stages only.

Contact is node-to-node: gap_i = z_i + w_i − d + (C f)_i >= 0, f_i >= 0,
f_i gap_i = 0, solved by a warm-started active-set method
(:mod:`numerics.superelement`, shared with any solver that condenses a body)
to a complementarity residual below 1e-9 (forces over F0, gaps over d);
depth or force control (then d is the extra unknown).
Nodal pressure p_i = f_i / A_i with A_i = ∫ φ_i 2πr ds (row-sum lumping).
With quadratic elements the node on the axis has A = 0 exactly and carries
no force; it is left out of the contact problem and its pressure and wear
are reported as the even extrapolation v(0) = (v1 r2² − v2 r1²)/(r2² − r1²).
(HRZ lumping gives that node an area, but its force stays zero unworn, so
p(0) = 0, and a bump of ~0.25 % d grows there under wear: measured, not used.)
``fem.pressure_recovery = "consistent"`` reports p = M⁻¹ f with the
consistent 2πr-weighted boundary mass instead; it ripples odd-even (0.7 % p0
unworn, up to 7 % p0 and negative values near a worn edge) and does not
drive the wear, which always uses the lumped p.
Wear dw_i/ds = (k μ/σ0) σ0 (p_i/σ0)^n by the adaptive scheme (default; step
doubling with a deferred Richardson correction), explicit or implicit Euler
or variable-step BDF2 (:mod:`numerics.stepping`); the candidate contact arc is sized
for the predicted final contact radius (√2·a0 under depth control, the
long-run scar radius under force control);
the contact radius is interpolated between the last loaded and the first
free node from the free nodes' gaps (gap^{2/3} linear near a smooth edge).
Not modelled: wear.tangential_correction (frictionless normal FEM).

``RunResult.fields`` (for export): ``points`` (Np, 2) undeformed r, z of the
DOF locations (P2: with midside nodes); ``cells`` (Nt, 3|6), counter-clockwise,
meshio ``triangle``/``triangle6`` order; ``displacement`` (K, Np, 2) u_r, u_z
in the plane's frame (the top face has u_z = −d); ``stress`` (K, Np, 4) σ_rr,
σ_zz, σ_θθ, σ_rz, L2-projected onto the continuous nodal space;
``contact_nodes`` (Nc,) indices into points, by increasing r;
``contact_pressure`` and ``wear_depth`` (K, Nc).
"""

from wearcheck.registry import lazy_attributes

__all__ = ["solve", "supports"]

# solve, supports and the submodules are imported on first use: the registry imports
# this package for its registration.py, which must not pull in the numerics
__getattr__ = lazy_attributes(__name__, {"solve": ".solver", "supports": ".solver"})
