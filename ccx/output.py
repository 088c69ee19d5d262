"""CalculiX's outputs of the solver's own jobs: the shared reader
(:mod:`wearcheck.calculix_files`), a damaged file reported as a SolverError (a
job of ours that printed what we cannot read is a failure of the run, not of
the case), and the .frd's fields of the sphere at a stage.
"""

from __future__ import annotations

import numpy as np

from wearcheck import calculix_files
from wearcheck.calculix_files import Block, FrdBlock, select, to_float
from wearcheck.cases import CaseError, SolverError

__all__ = ["Block", "FrdBlock", "dat_blocks", "read_frd", "select", "stage_fields",
           "to_float"]


def dat_blocks(text: str, source: str = ".dat file") -> list[Block]:
    """Every print block of a job's .dat text (:func:`wearcheck.calculix_files.dat_blocks`)."""
    try:
        return calculix_files.dat_blocks(text, source)
    except CaseError as exc:
        raise SolverError(str(exc)) from None


def read_frd(path) -> tuple[dict, list[FrdBlock]]:
    """The nodes and nodal result blocks of a job's .frd file
    (:func:`wearcheck.calculix_files.read_frd`)."""
    try:
        return calculix_files.read_frd(path)
    except CaseError as exc:
        raise SolverError(f"CalculiX results: {exc}") from None


def stage_fields(results, n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Displacement (Np, 2) [m] and stress (Np, 4) σ_rr, σ_zz, σ_θθ, σ_rz [Pa] of one step.

    ``results``: the step's :class:`FrdBlock` blocks; CalculiX's x, y, z are
    r, z, θ of the axisymmetric model, the deck's units mm and MPa; nodes
    1 .. ``n_points`` are the sphere's.
    """
    disp = np.zeros((n_points, 2))
    stress = np.zeros((n_points, 4))
    found = set()
    for b in results:
        keep = b.ids <= n_points          # not the gap elements' ground nodes
        if b.name == "DISP":
            disp[b.ids[keep] - 1] = b.values[keep, :2] * 1e-3
            found.add(b.name)
        elif b.name == "STRESS":
            cols = [b.components.index(c) for c in ("SXX", "SYY", "SZZ", "SXY")]
            stress[b.ids[keep] - 1] = b.values[keep][:, cols] * 1e6
            found.add(b.name)
    if found != {"DISP", "STRESS"}:
        raise SolverError("CalculiX's .frd file lacks " + " and ".join(
            sorted({"DISP", "STRESS"} - found)))
    return disp, stress
