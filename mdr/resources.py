"""Memory the MDR solver needs for a case, estimated before the run (pure)."""

from __future__ import annotations

#: the key whose value the estimate mostly depends on (named in refusals)
RESOURCE_KEY = "mdr.elements"
#: the solver's dense-factorisation limit (mdr.wear.DENSE_MAX), repeated to stay import-free
_DENSE_MAX = 2048


#: dense N x N matrices a run keeps at once, by time scheme (nested LU factors
#: of the implicit step; adaptive stepping keeps several step sizes' factors)
DENSE_MATRICES = {"adaptive": 8.0, "implicit": 8.0, "bdf2": 8.0, "explicit": 1.0}


#: doubles per node and stored stage at the run's end: its grid, profile and pressure
#: as recorded (3), the profile and pressure interpolated onto one grid (2) and stacked
#: into the (K, M) tables (2) while those are alive, and one for the allocator's
#: slack (peak RSS: 57 bytes per node and stage at 20 000 stages and N = 800; the 16
#: bytes assumed before let a run 3x over the estimate pass)
STAGE_DOUBLES = 8.0


def memory_bytes(case, elements: int | None = None) -> float:
    """Peak memory [bytes] of an MDR run of ``case`` (with ``elements`` springs if given).

    Measured on paper.toml at N = 1500 (numpy's allocations, tracemalloc, in
    a fresh process: the first run also builds the unit compliance matrix,
    whose FFTs are its largest transient): adaptive 70 MB (3.9 N² doubles;
    its factorisations start at the contact and grow by bordering; 193 MB,
    10.7 N², when they were sized ahead and packed), implicit and bdf2
    127 MB (7.0 N²: one factorisation of the whole grid, built while the
    compliance's transient is alive); past the dense limit (N > 2048: FFT and
    GMRES, O(N)) 10.5 MB at N = 3000. The model bounds these: 40 MB fixed,
    DENSE_MATRICES[scheme] N² doubles when solved directly (mdr.linear_solver;
    "auto": up to the dense limit), 2 kB per node,
    and the stored stages, STAGE_DOUBLES doubles per node and stage.
    """
    n = float(case.mdr.elements if elements is None else elements) + 1.0
    per = DENSE_MATRICES.get(case.sliding.scheme, max(DENSE_MATRICES.values()))
    if getattr(case, "fretting", None) is not None:
        per = 0.0  # partial slip: no implicit gross-slip step (fretting.toml: 1.6 MB at N = 800)
    solver = case.mdr.linear_solver
    direct = solver == "direct" or (solver == "auto" and n <= _DENSE_MAX + 1)
    dense = per * 8.0 * n * n if direct else 0.0
    stages = 8.0 * STAGE_DOUBLES * n * len(case.stages.s_hat)
    return 40e6 + dense + 2e3 * n + stages


def profile_points(case) -> int:
    """Points of the stored profiles (what ``export`` revolves)."""
    return int(case.mdr.elements) + 1
