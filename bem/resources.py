"""Memory the BEM solver needs for a case, estimated before the run (pure)."""

from __future__ import annotations

#: the key whose value the estimate mostly depends on (named in refusals)
RESOURCE_KEY = "bem.grid"
#: N × N double arrays alive at once while stepping (CG vectors, gap, profile,
#: warm-start history, the padded transforms counted at their size), and
#: the displacement G p kept with each live state (five) and the operator's
#: single-precision kernel (one)
WORKING_ARRAYS = 46.0
#: N × N double arrays kept per stored stage (profile, pressure, gap in the
#: run's stages; profile, wear, pressure, gap in the result's fields)
PER_STAGE = 7.0
#: bem.coupling: the coupling operator's padded (2N)² work array, its complex
#: half-spectrum and the transforms of an application, and the sweeps' lagged
#: displacements (docs/performance.md, "Measurements behind the code")
COUPLING_ARRAYS = 22.0


def memory_bytes(case, grid: int | None = None) -> float:
    """Peak memory [bytes] of a BEM run of ``case`` (with ``grid`` pixels per side if given).

    The model bounds the peak resident memory measured less the interpreter's
    (docs/performance.md, "Measurements behind the code"): 40 MB fixed,
    WORKING_ARRAYS + PER_STAGE × stages doubles per pixel.
    """
    n = float(case.bem.grid if grid is None else grid)
    stages = len(case.stages.s_hat)
    coupling = COUPLING_ARRAYS if case.bem.coupling else 0.0
    return 40e6 + 8.0 * n * n * (WORKING_ARRAYS + coupling + PER_STAGE * stages)
