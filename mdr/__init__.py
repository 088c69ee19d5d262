"""MDR solver of gross-slip Reye–Archard wear (paper Sections 2 and 4).

``supports(case)`` is None for every case (the ellipsoid runs as the
paraboloid of the equivalent radius √(R1 R2), its result marked
``info["approximate"]`` with ``info["warning"]``).
``solve(case, progress=None) -> cases.RunResult`` runs a case: N springs on
0 <= x <= L = domain_factor·√2·a0, nodes uniform in t = x² (the 3D radii r
share them), paper Eqs. 2, 3, 12, 13 integrated exactly over each segment,
wear Δf = (k μ/σ0) σ0 (p/σ0)^n · slip (docs/theory.md §4) by the adaptive scheme
(default: backward Euler with step doubling, error-controlled, Richardson's
correction carried into the next step; docs/time-stepping.md), explicit
Euler (the paper's; stable below a step limit it estimates and enforces),
implicit Euler (unconditionally stable, first order) or the variable-step
BDF2 (L-stable, second order). The domain grows with the contact (t = r²
doubled, every other node kept). BLAS runs
single-threaded during a solve.

Modules: :mod:`mdr.transforms` (the MDR transforms, pure functions),
:mod:`mdr.contact` (normal contact), :mod:`mdr.wear` (the wear steps),
:mod:`mdr.linalg` (nested-block Cholesky, GMRES), :mod:`mdr.solver` (the run: the
implicit step and the growing grid as :mod:`numerics.stepping` steps them).

A case with a [fretting] section is a partial-slip run: :mod:`mdr.fretting`
(tangential springs with Coulomb memory in :mod:`mdr.tangential`, cycle
jumping).
"""

from wearcheck.registry import lazy_attributes

__all__ = ["solve", "supports"]


def supports(case) -> str | None:
    """None: the MDR runs every axisymmetric case the schema accepts (fretting too),
    and the ellipsoid approximately (as the paraboloid of radius √(R1 R2), its
    result marked by the reason in ``info["approximate"]``); not a counterface that wears."""
    if case.counterface.wears:
        return ("counterface.wears = true: the MDR wears the indenter only (a wear track "
                "on the counterface is not axisymmetric); use the BEM")
    return None


# solve and the submodules are imported on first use: the registry imports
# this package for its registration.py, which must not pull in the numerics
__getattr__ = lazy_attributes(__name__, {"solve": ".solver"})
