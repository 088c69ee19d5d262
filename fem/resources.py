"""Memory the FEM solver needs for a case, estimated before the run (pure)."""

from __future__ import annotations

#: the key whose value the estimate mostly depends on (named in refusals)
RESOURCE_KEY = "fem.contact_nodes"


def section_points(case, contact_nodes: int | None = None) -> float:
    """Nodes of the r–z section (with midside nodes for P2), estimated.

    gmsh's graded mesh of the sphere (meshes.sphere_mesh) at 60 / 250 / 1000 /
    4000 contact nodes has 436 / 1089 / 3468 / 12742 vertices with P2 (about
    4 nodes per vertex with the midside nodes) and 4877 / 11278 / 32620 /
    114906 with P1.
    """
    n = float(case.fem.contact_nodes if contact_nodes is None else contact_nodes)
    if case.fem.element_order == 2:
        return 4.0 * (3.2 * n + 400.0)
    return 30.0 * n + 5000.0


#: dense (contact nodes)² matrices a run keeps at once, by time scheme (the
#: compliance and its copies; adaptive stepping keeps factors for several steps)
DENSE_MATRICES = {"adaptive": 40.0, "implicit": 8.0, "bdf2": 8.0, "explicit": 8.0}


def memory_bytes(case, contact_nodes: int | None = None) -> float:
    """Peak memory [bytes] of an FEM run of ``case``.

    The model, an upper bound of the peak resident memory measured less the
    interpreter's (docs/performance.md, "Measurements behind the code"): 30 MB
    fixed, 8 kB per DOF (the sparse factor), DENSE_MATRICES[scheme] doubles per
    contact node², and the stored fields (displacement and stress, 48 bytes per
    node and stage).
    """
    n = float(case.fem.contact_nodes if contact_nodes is None else contact_nodes)
    points = section_points(case, n)
    dofs = 2.0 * points
    stages = 48.0 * points * len(case.stages.s_hat)
    per = DENSE_MATRICES.get(case.sliding.scheme, max(DENSE_MATRICES.values()))
    return 30e6 + 8e3 * dofs + per * 8.0 * n * n + stages


def profile_points(case) -> int:
    """Points of the stored profiles (the contact nodes)."""
    return int(case.fem.contact_nodes)
