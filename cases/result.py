"""The result every solver returns: the same arrays from MDR and from FEM."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: history columns every solver provides, in this order (SI units)
HISTORY_COLUMNS = ("s", "force", "depth", "contact_radius", "wear_center", "wear_volume")
#: arrays of stages.npz that every run has
STAGE_KEYS = ("s", "s_hat", "r", "f", "p")


@dataclass
class RunResult:
    """Output of one solver run.

    Attributes
    ----------
    history : dict of 1D arrays, one entry per step (including the start),
        with at least the keys of ``HISTORY_COLUMNS``: sliding distance s [m],
        normal force [N], indentation depth [m], contact radius [m], wear
        depth at r = 0 [m], worn volume [m³]. More columns may follow.
    stage_s : (K,) sliding distances [m] of the stored stages.
    r : (M,) radii [m] at which stage profiles and pressures are given.
    f : (K, M) worn profile heights f(r) [m] (unworn profile plus wear).
    p : (K, M) contact pressure [Pa].
    solve_seconds : time spent in the solver proper.
    info : JSON-serialisable solver facts (steps taken, step used, grid...).
    fields : optional solver-specific arrays for export (e.g. FEM mesh and
        displacements per stage); written to ``fields.npz`` when present.
    stage_extra : optional further (K, M) arrays per stage (e.g. the shear
        traction ``tau`` [Pa] of a fretting run); written into ``stages.npz``.
    """

    history: dict[str, np.ndarray]
    stage_s: np.ndarray
    r: np.ndarray
    f: np.ndarray
    p: np.ndarray
    solve_seconds: float
    info: dict = field(default_factory=dict)
    fields: dict[str, np.ndarray] | None = None
    stage_extra: dict[str, np.ndarray] | None = None

    def __post_init__(self):
        missing = [c for c in HISTORY_COLUMNS if c not in self.history]
        if missing:
            raise ValueError(f"history lacks columns {missing}")
        K, M = len(self.stage_s), len(self.r)
        for name in ("f", "p"):
            shape = np.shape(getattr(self, name))
            if shape != (K, M):
                raise ValueError(f"{name} has shape {shape}, expected {(K, M)}")
        for name, arr in (self.stage_extra or {}).items():
            if name in STAGE_KEYS:
                raise ValueError(f"stage_extra '{name}' would overwrite a stages.npz array")
            if np.shape(arr) != (K, M):
                raise ValueError(f"stage_extra '{name}' has shape {np.shape(arr)}, "
                                 f"expected {(K, M)}")
