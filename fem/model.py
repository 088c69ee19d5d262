"""The sphere model: assembly, boundary conditions and the superelement.

The sphere occupies the gmsh mesh of ``meshes`` (pole at the origin, centre
at (0, R), flat top face at z = R). The top face is clamped (u = 0 relative to
the rigid-body approach), the axis has u_r = 0. Static condensation onto the
axial DOFs of the candidate contact nodes gives the compliance C: the top is
held and a unit upward force at contact node j lifts node i by C_ij.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from skfem import (Basis, ElementTriP1, ElementTriP2, ElementVector, FacetBasis, LinearForm,
                   MeshTri, asm)
from skfem.models.poisson import mass

from wearcheck.cases import SolverError

from .axisym import boundary_mass, boundary_weight, stiffness_form, stress_at_quadrature

#: sparse factorisations measured by benchmarks/bench_fem.py (scipy only)
FACTORISATIONS = ("splu-colamd", "splu-mmd_ata", "splu-mmd_at_plus_a", "splu-natural")
DEFAULT_FACTORISATION = "splu-mmd_at_plus_a"


def skfem_mesh(sm) -> MeshTri:
    """scikit-fem mesh with the named boundaries of a ``meshes.SphereMesh``."""
    mesh = MeshTri(np.ascontiguousarray(sm.points.T), np.ascontiguousarray(sm.triangles.T))
    n = mesh.p.shape[1]
    facets = np.sort(mesh.facets, axis=0)
    keys = facets[0].astype(np.int64) * n + facets[1]
    order = np.argsort(keys)
    boundaries = {}
    for name, pairs in sm.lines.items():
        pairs = np.sort(pairs, axis=1)
        want = pairs[:, 0].astype(np.int64) * n + pairs[:, 1]
        pos = np.searchsorted(keys, want, sorter=order)
        idx = order[np.minimum(pos, len(keys) - 1)]
        if not np.array_equal(keys[idx], want):
            raise SolverError(f"mesh boundary '{name}' does not match the triangles' edges")
        boundaries[name] = np.sort(idx)
    return mesh.with_boundaries(boundaries)


def factorise(A, method: str = DEFAULT_FACTORISATION):
    """Sparse LU of a square matrix; returns an object with ``.solve``."""
    kind, _, perm = method.partition("-")
    if kind != "splu" or perm.upper() not in ("COLAMD", "MMD_ATA", "MMD_AT_PLUS_A", "NATURAL"):
        raise ValueError(f"unknown factorisation {method!r}; one of {FACTORISATIONS}")
    symmetric = perm.upper() in ("MMD_AT_PLUS_A", "NATURAL")
    try:
        # for a symmetric ordering, diagonal pivots (stable for SPD K) keep
        # SuperLU a Cholesky in disguise and leave the ordering untouched
        return spla.splu(sp.csc_matrix(A), permc_spec=perm.upper(),
                         diag_pivot_thresh=0.0 if symmetric else 1.0,
                         options=dict(SymmetricMode=symmetric))
    except RuntimeError as exc:
        raise SolverError(f"the stiffness matrix could not be factorised ({exc}); "
                          "is the sphere constrained?") from None


@dataclass
class SphereModel:
    """The assembled sphere and its condensation onto the contact nodes."""

    mesh: MeshTri
    basis: Basis              # vector basis
    scalar: Basis             # scalar basis of the same order (DOF locations)
    E: float
    nu: float
    order: int
    contact: np.ndarray       # scalar DOF indices of the contact nodes, sorted by r
    r: np.ndarray             # their radii [m]
    z: np.ndarray             # their heights (mesh geometry) [m]
    area_rowsum: np.ndarray   # lumped area ∫ φ_i 2πr ds [m²] (0 on the axis for P2)
    boundary_mass: np.ndarray  # consistent ∫ φ_i φ_j 2πr ds on the contact arc [m²]
    free: np.ndarray          # free vector DOFs
    K: sp.csr_matrix
    lu: object = None
    C: np.ndarray | None = None
    timings: dict = field(default_factory=dict)

    def stats(self) -> dict:
        return dict(vertices=int(self.mesh.p.shape[1]), elements=int(self.mesh.t.shape[1]),
                    nodes=int(self.scalar.N), dofs=int(self.basis.N),
                    free_dofs=int(len(self.free)), contact_nodes=int(len(self.contact)),
                    element_order=int(self.order),
                    contact_spacing=float(np.mean(np.diff(self.r))))

    # -- superelement ------------------------------------------------------
    def factorise(self, method: str = DEFAULT_FACTORISATION, contact_last: bool = True) -> None:
        """Sparse LU of the free-DOF stiffness.

        With ``contact_last`` the contact axial DOFs are eliminated last: the
        other DOFs keep the fill-reducing order SuperLU chose for them alone,
        and the trailing nc×nc block of L U is the Schur complement S whose
        inverse is the compliance (:meth:`compliance`).
        """
        t0 = time.perf_counter()
        A = sp.csc_matrix(self.K[self.free][:, self.free])
        self._order = None
        if contact_last:
            rows = self._contact_rows()
            inner = np.setdiff1d(np.arange(A.shape[0]), rows)
            lu_inner = factorise(A[inner][:, inner], method)
            order = np.concatenate([inner[np.argsort(lu_inner.perm_c)], rows])
            del lu_inner
            self.lu = factorise(A[order][:, order], "splu-natural")
            self._order = order
        else:
            self.lu = factorise(A, method)
        self.timings["factorisation"] = time.perf_counter() - t0

    def _solve_free(self, rhs: np.ndarray) -> np.ndarray:
        if self._order is None:
            return self.lu.solve(rhs)
        out = np.empty_like(rhs)
        out[self._order] = self.lu.solve(np.asfortranarray(rhs[self._order]))
        return out

    def _contact_rows(self) -> np.ndarray:
        """Positions of the contact axial DOFs within the free DOFs."""
        pos = np.searchsorted(self.free, 2 * self.contact + 1)
        if not np.array_equal(self.free[pos], 2 * self.contact + 1):
            raise SolverError("a contact node's axial DOF is constrained; the contact arc "
                              "touches the clamped top face")
        return pos

    def _schur_compliance(self):
        """C = S⁻¹ from the trailing block of the contact-last LU, or None if
        SuperLU's own permutations moved the contact DOFs out of the tail."""
        nf = len(self.free)
        nc = len(self.contact)
        tail = np.arange(nf - nc, nf)
        pc, pr = self.lu.perm_c[tail], self.lu.perm_r[tail]
        if not (np.all(pc >= nf - nc) and np.all(pr >= nf - nc)):
            return None
        Lcc = self.lu.L[nf - nc:, nf - nc:].toarray()
        Ucc = self.lu.U[nf - nc:, nf - nc:].toarray()
        # (Pr A Pc)[perm_r[i], perm_c[j]] = A[i, j], so A⁻¹[j, i] = (LU)⁻¹[perm_c[j], perm_r[i]]
        inv = np.linalg.inv(Lcc @ Ucc)
        return inv[np.ix_(pc - (nf - nc), pr - (nf - nc))]

    def compliance(self, method: str = "schur", block: int = 4) -> np.ndarray:
        """Dense C (Nc×Nc) [m/N], the axial compliance of the contact nodes.

        "schur": inverse of the Schur complement read off the contact-last LU
        (one dense nc×nc inverse); "columns": one sparse solve per contact
        node (SuperLU is fastest with blocks of 4 right-hand sides here).
        Measured in benchmarks/bench_fem.py; both agree to round-off.
        """
        if self.lu is None:
            self.factorise()
        t0 = time.perf_counter()
        C = self._schur_compliance() if method == "schur" and self._order is not None else None
        self.timings["compliance_method"] = "schur" if C is not None else "columns"
        if C is None:
            rows = self._contact_rows()
            nf, nc = len(self.free), len(rows)
            C = np.empty((nc, nc))
            for start in range(0, nc, block):
                cols = rows[start:start + block]
                rhs = np.zeros((nf, len(cols)), order="F")
                rhs[cols, np.arange(len(cols))] = 1.0
                C[:, start:start + len(cols)] = self._solve_free(rhs)[rows]
        asym = np.max(np.abs(C - C.T)) / np.max(np.abs(C))
        if not asym < 1e-8:
            raise SolverError(f"the condensed compliance is not symmetric (relative {asym:.2e})")
        self.C = 0.5 * (C + C.T)
        self.timings["compliance"] = time.perf_counter() - t0
        self.timings["compliance_asymmetry"] = float(asym)
        return self.C

    def displacement(self, forces: np.ndarray) -> np.ndarray:
        """Full displacement (vector DOFs, top held) under upward contact forces [N]."""
        rhs = np.zeros(len(self.free))
        rhs[self._contact_rows()] = forces
        u = np.zeros(self.basis.N)
        u[self.free] = self._solve_free(rhs)
        return u

    def nodal_stress(self, u: np.ndarray) -> np.ndarray:
        """(Np, 4) σ_rr, σ_zz, σ_θθ, σ_rz at the scalar DOF locations.

        L2 projection (unweighted area mass matrix) of the quadrature-point
        stresses onto the continuous scalar space of the element order.
        """
        if not hasattr(self, "_mass_lu"):
            self._mass_lu = spla.splu(sp.csc_matrix(asm(mass, self.scalar)))
        sq = stress_at_quadrature(self.basis, u, self.E, self.nu)
        rhs = np.column_stack([asm(_project_form, self.scalar, s=s) for s in sq])
        return self._mass_lu.solve(rhs)


@LinearForm
def _project_form(v, w):
    return w["s"] * v


def build(sm, E: float, nu: float, order: int) -> SphereModel:
    """Assemble the sphere of mesh ``sm`` (meshes.SphereMesh) with E, ν, order 1|2."""
    t0 = time.perf_counter()
    mesh = skfem_mesh(sm)
    scalar_elem = ElementTriP2() if order == 2 else ElementTriP1()
    intorder = 4 if order == 2 else 2
    basis = Basis(mesh, ElementVector(scalar_elem), intorder=intorder)
    scalar = basis.with_element(scalar_elem)
    K = asm(stiffness_form(E, nu), basis).tocsr()

    fixed = np.unique(np.concatenate([basis.get_dofs("top").all(),
                                      basis.get_dofs("axis").all("u^1")]))
    free = np.setdiff1d(np.arange(basis.N), fixed)

    contact = scalar.get_dofs("contact").all()
    x = scalar.doflocs[:, contact]
    order_r = np.argsort(x[0])
    contact = contact[order_r]
    fb = FacetBasis(mesh, scalar_elem, facets=mesh.boundaries["contact"], intorder=intorder)
    rowsum = asm(boundary_weight, fb)[contact]
    Mb = asm(boundary_mass, fb).tocsr()[contact][:, contact].toarray()
    model = SphereModel(mesh=mesh, basis=basis, scalar=scalar, E=E, nu=nu, order=order,
                        contact=contact, r=scalar.doflocs[0, contact],
                        z=scalar.doflocs[1, contact], area_rowsum=rowsum,
                        boundary_mass=Mb, free=free, K=K)
    model.timings["assembly"] = time.perf_counter() - t0
    return model
