"""Memory the MDR solver needs for a case, estimated before the run (pure)."""

from __future__ import annotations

#: the key whose value the estimate mostly depends on (named in refusals)
RESOURCE_KEY = "mdr.elements"
#: the solver's dense-factorisation limit (mdr.wear.DENSE_MAX), repeated to stay import-free
_DENSE_MAX = 2048


#: dense N x N matrices a run keeps at once, by time scheme (nested Cholesky factors
#: of the implicit step; adaptive stepping keeps several step sizes' factors):
#: above the peaks measured (docs/performance.md, "Measurements behind the code",
#: ``mdr/resources.py`` ``memory_bytes``)
DENSE_MATRICES = {"adaptive": 8.0, "implicit": 4.0, "bdf2": 4.0, "explicit": 1.0}


#: doubles per node and stored stage at the run's end: its grid, profile and pressure
#: as recorded (3), the profile and pressure interpolated onto one grid (2) and stacked
#: into the (K, M) tables (2) while those are alive, and one for the allocator's
#: slack (docs/performance.md, "Measurements behind the code", ``mdr/resources.py``)
STAGE_DOUBLES = 8.0


def memory_bytes(case, elements: int | None = None) -> float:
    """Peak memory [bytes] of an MDR run of ``case`` (with ``elements`` springs if given).

    An upper bound of the measured peaks (docs/performance.md, "Measurements
    behind the code", ``mdr/resources.py``): the dense factorisations of the
    implicit step dominate up to the dense limit (adaptive stepping's start at
    the contact and grow by bordering, implicit and bdf2 factor the whole grid
    while the unit compliance's FFT transient is alive); past it (FFT and
    GMRES) the need is O(N). The model: 40 MB fixed,
    DENSE_MATRICES[scheme] N² doubles when solved directly (mdr.linear_solver;
    "auto": up to the dense limit), 2 kB per node,
    and the stored stages, STAGE_DOUBLES doubles per node and stage.
    """
    n = float(case.mdr.elements if elements is None else elements) + 1.0
    per = DENSE_MATRICES.get(case.sliding.scheme, max(DENSE_MATRICES.values()))
    if getattr(case, "fretting", None) is not None:
        per = 0.0  # partial slip: no implicit gross-slip step (its small need: docs/performance.md)
    solver = case.mdr.linear_solver
    direct = solver == "direct" or (solver == "auto" and n <= _DENSE_MAX + 1)
    dense = per * 8.0 * n * n if direct else 0.0
    stages = 8.0 * STAGE_DOUBLES * n * len(case.stages.s_hat)
    return 40e6 + dense + 2e3 * n + stages


def profile_points(case) -> int:
    """Points of the stored profiles (what ``export`` revolves)."""
    return int(case.mdr.elements) + 1
