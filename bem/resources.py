"""Memory the BEM solver needs for a case, estimated before the run (pure)."""

from __future__ import annotations

#: the key whose value the estimate mostly depends on (named in refusals)
RESOURCE_KEY = "bem.grid"
#: N × N double arrays alive at once while stepping (CG vectors, gap, profile,
#: warm-start history, the padded transforms counted at their size)
WORKING_ARRAYS = 40.0
#: N × N double arrays kept per stored stage (profile, pressure, gap in the
#: run's stages; profile, wear, pressure, gap in the result's fields)
PER_STAGE = 7.0
#: bem.coupling: the coupling operator's padded (2N)² work array, its complex
#: half-spectrum and the transforms of an application, and the sweeps' lagged
#: displacements (measured on paper.toml at 512²: +44 MB, 21 arrays)
COUPLING_ARRAYS = 22.0


def memory_bytes(case, grid: int | None = None) -> float:
    """Peak memory [bytes] of a BEM run of ``case`` (with ``grid`` pixels per side if given).

    Measured on paper.toml (7 stages, adaptive), peak resident memory less the
    interpreter's 80 MB: 25 MB at 128², 43 MB at 256², 174 MB at 512². The
    model bounds these: 40 MB fixed, WORKING_ARRAYS + PER_STAGE × stages
    doubles per pixel (227 MB at 512²).
    """
    n = float(case.bem.grid if grid is None else grid)
    stages = len(case.stages.s_hat)
    coupling = COUPLING_ARRAYS if case.bem.coupling else 0.0
    return 40e6 + 8.0 * n * n * (WORKING_ARRAYS + coupling + PER_STAGE * stages)
