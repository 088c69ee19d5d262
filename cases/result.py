"""The result every solver returns: the same arrays from MDR and from FEM."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: the worn region (the scar) ends where the wear depth falls below this
#: fraction of its largest value (a lab sees the scar's edge where wear is
#: visible). On a worn sphere w ≈ (b² − r²)/2R near the edge, so 1e-3 of the
#: central wear is reached 0.05 % inside the true edge b (1 % would be 0.5 %
#: inside, and the lab's D⁴ volume formula 2 % low for that alone)
SCAR_THRESHOLD = 1e-3


def scar_radius(r, wear_depth, threshold: float = SCAR_THRESHOLD) -> float:
    """Outer radius of the worn region: the largest r with w >= threshold·max w.

    Linear interpolation between the last node above the level and the next;
    0 when nothing is worn. ``r`` increasing [m], ``wear_depth`` at r [m].
    """
    w = np.asarray(wear_depth, dtype=float)
    r = np.asarray(r, dtype=float)
    wmax = float(np.max(w)) if w.size else 0.0
    if not wmax > 0.0:
        return 0.0
    level = threshold * wmax
    i = int(np.flatnonzero(w >= level)[-1])
    if i + 1 >= len(w):
        return float(r[i])
    frac = (w[i] - level) / (w[i] - w[i + 1])
    return float(r[i] + frac * (r[i + 1] - r[i]))


def scar_radii(r, wear_depths, threshold: float = SCAR_THRESHOLD) -> np.ndarray:
    """:func:`scar_radius` of each row of ``wear_depths`` (rows × len(r)), at once."""
    w = np.asarray(wear_depths, dtype=float)
    r = np.asarray(r, dtype=float)
    out = np.zeros(len(w))
    if not w.size:
        return out
    wmax = w.max(axis=1)
    worn = wmax > 0.0
    if not worn.any():
        return out
    w, wmax = w[worn], wmax[worn]
    level = threshold * wmax
    n = w.shape[1]
    # the last node at or above the level (a worn row has one: its maximum)
    i = n - 1 - np.argmax((w >= level[:, None])[:, ::-1], axis=1)
    inner = i + 1 < n
    radius = r[i]
    rows, j = np.flatnonzero(inner), i[inner]
    wi, wn = w[rows, j], w[rows, j + 1]
    frac = (wi - level[inner]) / (wi - wn)
    radius[inner] = r[j] + frac * (r[j + 1] - r[j])
    out[worn] = radius
    return out


@dataclass(frozen=True)
class Item:
    """One output file, column, array or field: its name, unit ("" when
    dimensionless) and meaning (``wearcheck.layout`` and the solvers'
    registrations describe their outputs with it)."""

    name: str
    unit: str
    meaning: str

    def as_dict(self) -> dict:
        return dict(unit=self.unit, meaning=self.meaning)


#: the history columns every solver provides, in this order: the one declaration
#: (``RunResult`` checks them, ``rundir`` writes them first, ``wearcheck.layout``
#: documents them; a solver declares its extra columns in its own registration)
HISTORY = (
    Item("s", "m", "sliding distance"),
    Item("force", "N", "normal force F"),
    Item("depth", "m", "indentation depth d (approach of the unworn profile's tip)"),
    Item("contact_radius", "m", "contact radius a (BEM: radius of the circle of equal area)"),
    Item("wear_center", "m", "wear depth at r = 0"),
    Item("wear_volume", "m^3", "worn volume"),
)
#: their names
HISTORY_COLUMNS = tuple(i.name for i in HISTORY)
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
        depth at r = 0 [m], worn volume [m³]. More columns may follow;
        both solvers add ``scar_radius`` [m] (:func:`scar_radius`) and
        ``cycles`` (NaN when the case gives no stroke).
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
            if K == 0 and len(shape) >= 1 and shape[0] == 0:
                # no stage reached (every requested one lies after the run's end): any
                # empty array is the empty (0, M) table
                setattr(self, name, np.zeros((0, M)))
                continue
            if shape != (K, M):
                raise ValueError(f"{name} has shape {shape}, expected {(K, M)}")
        for name, arr in (self.stage_extra or {}).items():
            if name in STAGE_KEYS:
                raise ValueError(f"stage_extra '{name}' would overwrite a stages.npz array")
            if np.shape(arr) != (K, M):
                raise ValueError(f"stage_extra '{name}' has shape {np.shape(arr)}, "
                                 f"expected {(K, M)}")
