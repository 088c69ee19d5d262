"""Memory the MDR solver needs for a case, estimated before the run (pure)."""

from __future__ import annotations

#: the key whose value the estimate mostly depends on (named in refusals)
RESOURCE_KEY = "mdr.elements"
#: the solver's dense-factorisation limit (mdr.wear.DENSE_MAX), repeated to stay import-free
_DENSE_MAX = 2048


def memory_bytes(case, elements: int | None = None) -> float:
    """Peak memory [bytes] of an MDR run of ``case`` (with ``elements`` springs if given).

    Measured on paper.toml (peak RSS less the interpreter's, implicit scheme):
    N = 1000: 24 MB, 2000: 75 MB (dense nested LU, about 2.3 N² doubles),
    4000: 11 MB, 16000: 23 MB (FFT and GMRES, O(N)). The model below bounds
    these: 40 MB fixed, 3 N² doubles up to the dense limit, 2 kB per node,
    and the stored stages (profile and pressure, 16 bytes per node and stage).
    """
    n = float(case.mdr.elements if elements is None else elements) + 1.0
    dense = 3.0 * 8.0 * n * n if n <= _DENSE_MAX + 1 else 0.0
    stages = 16.0 * n * len(case.stages.s_hat)
    return 40e6 + dense + 2e3 * n + stages


def profile_points(case) -> int:
    """Points of the stored profiles (what ``export`` revolves)."""
    return int(case.mdr.elements) + 1
