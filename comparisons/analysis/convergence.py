"""Refinement studies, the pure part: levels, differences to the finest level,
observed order of convergence, Richardson's estimate, coarsest converged level.

Arrays in, arrays out: no I/O, no Dask (resolution keys and default levels come
from each solver's registry entry). Solutions enter in the natural scales
of the case (r/a0, f/d0, p/p0, F/F0, ŝ) so that errors read as fractions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from wearcheck.cases import ArgumentError, CaseError
from wearcheck import registry

#: the error measures of a level, in the order tables show them
MEASURES = ("profile", "pressure", "pressure_interior", "force")


@dataclass(frozen=True)
class Level:
    """One run of a study: a resolution and, optionally, a sliding step ŝ."""

    solver: str
    resolution: int
    step_hat: float | None = None

    @property
    def key(self) -> str:
        return registry.get(self.solver).resolution_key

    @property
    def name(self) -> str:
        """Run directory name, ``<solver>-<key>-<value>[-step-<v>]``."""
        name = f"{self.solver}-{self.key.split('.')[1]}-{self.resolution}"
        return name + (f"-step-{self.step_hat:g}" if self.step_hat is not None else "")

    @property
    def changes(self) -> dict:
        """The keys this level changes in the case, ``{"mdr.elements": 400}``."""
        out = {self.key: self.resolution}
        if self.step_hat is not None:
            out["sliding.step_hat"] = self.step_hat
        return out


def levels(solver: str, resolutions=None, steps=None) -> list[Level]:
    """The levels of a study, coarsest first.

    Resolutions and steps pair up one to one; a single value of either applies
    to every level, so ``steps`` alone refines the step at one resolution.
    """
    entry = registry.get(solver)
    if entry.resolution_key is None:
        raise CaseError(f"solver '{solver}' declares no resolution key to refine")
    res = tuple(resolutions) if resolutions else entry.default_levels
    st = tuple(steps) if steps else (None,)
    if len(st) == 1:
        st = st * len(res)
    elif len(res) == 1:
        res = res * len(st)
    elif len(st) != len(res):
        raise ArgumentError("steps", f"{len(st)} steps for {len(res)} {{levels}}: give one "
                            "step, one level, or as many steps as levels (they pair up)",
                            value=list(steps), also=("levels",))
    bad = [n for n in res if isinstance(n, bool) or not float(n).is_integer()]
    if bad:
        raise ArgumentError("levels", f"{bad[0]!r} is not a whole number of "
                            f"{entry.resolution_key}", value=list(res))
    out = [Level(solver, int(n), None if s is None else float(s)) for n, s in zip(res, st)]
    if len(out) < 2:
        raise ArgumentError("levels", "a refinement study needs at least two levels (three "
                            "for an observed order)", value=[lv.resolution for lv in out])
    if len({lv.name for lv in out}) != len(out):
        raise ArgumentError("levels", "the levels repeat: "
                            + ", ".join(lv.name for lv in out), value=list(res))
    varied = refined_parameter(out)
    return sorted(out, key=lambda lv: -refinement_h(lv, varied))


def refined_parameter(lvls) -> str:
    """"step" when only the step varies across the levels, else "resolution"."""
    steps_only = (len({lv.resolution for lv in lvls}) == 1
                  and len({lv.step_hat for lv in lvls}) > 1)
    return "step" if steps_only else "resolution"


def refinement_h(level: Level, varied: str) -> float:
    """The refinement parameter h (error ∝ h^p): 1/resolution, or the step ŝ."""
    if varied == "resolution":
        return 1.0 / level.resolution
    return level.step_hat if level.step_hat is not None else math.nan


# --------------------------------------------------------------------------
# Solutions in natural scales

@dataclass
class Solution:
    """One level's result in natural scales.

    s_hat, force, radius: history (n,) of ŝ, F/F0 and contact radius a/a0;
    stage_s_hat (K,); r (M,) r/a0; f, p (K, M): worn profile f/d0, pressure p/p0.
    """

    s_hat: np.ndarray
    force: np.ndarray
    radius: np.ndarray
    stage_s_hat: np.ndarray
    r: np.ndarray
    f: np.ndarray
    p: np.ndarray


def scaled(result, scales: dict) -> Solution:
    """A :class:`cases.RunResult` in the natural scales ``cases.reference.scales``."""
    k = scales["s_hat_per_m"]
    return Solution(
        s_hat=np.asarray(result.history["s"], float) * k,
        force=np.asarray(result.history["force"], float) / scales["F0"],
        radius=np.asarray(result.history["contact_radius"], float) / scales["a0"],
        stage_s_hat=np.asarray(result.stage_s, float) * k,
        r=np.asarray(result.r, float) / scales["a0"],
        f=np.asarray(result.f, float) / scales["d0"],
        p=np.asarray(result.p, float) / scales["p0"],
    )


def stage_forces(sol: Solution, stage_s_hat) -> np.ndarray:
    """F/F0 at each requested stage ŝ (linear in the history); NaN past the run's end."""
    s = np.asarray(stage_s_hat, float)
    out = np.interp(s, sol.s_hat, sol.force)
    # a stage is reached when the run got there, up to rounding of the step sum
    out[s > sol.s_hat[-1] * (1 + 1e-9) + 1e-12] = np.nan
    return out


def differences(sol: Solution, ref: Solution, edge_band: float = 0.1) -> dict:
    """Max differences of a level to the reference (finest) level.

    Compared on the reference's own points: its r grid for the profile f/d0 and
    pressure p/p0 (at every stage both reached, by index), its history ŝ for
    the force F/F0, each restricted to the range both cover; the level is
    interpolated linearly there, as its piecewise-linear plot would show it.
    ``pressure_interior`` leaves out the band ``edge_band * a`` inside the
    reference's contact radius a (its history's, at the stage), where the
    edge peak converges slowest.
    """
    K = min(len(sol.stage_s_hat), len(ref.stage_s_hat))
    lo, hi = max(sol.r[0], ref.r[0]), min(sol.r[-1], ref.r[-1])
    grid = (ref.r >= lo) & (ref.r <= hi)
    r = ref.r[grid]
    prof, pres, inner = [], [], []
    for k in range(K):
        prof.append(np.max(np.abs(np.interp(r, sol.r, sol.f[k]) - ref.f[k, grid])))
        dp = np.abs(np.interp(r, sol.r, sol.p[k]) - ref.p[k, grid])
        pres.append(np.max(dp))
        a = np.interp(ref.stage_s_hat[k], ref.s_hat, ref.radius)
        band = r < (1.0 - edge_band) * a
        if band.any():
            inner.append(np.max(dp[band]))
    upto = ref.s_hat <= min(sol.s_hat[-1], ref.s_hat[-1])
    force = float(np.max(np.abs(np.interp(ref.s_hat[upto], sol.s_hat, sol.force)
                                - ref.force[upto])))

    def largest(values):
        return float(max(values)) if values else math.nan

    return dict(profile=largest(prof), pressure=largest(pres),
                pressure_interior=largest(inner), force=force)


# --------------------------------------------------------------------------
# Convergence

def observed_order(h, error) -> tuple[float, float]:
    """Order p and constant C of error ≈ C h^p: ``np.polyfit`` of log error on log h.

    Points with a zero, negative or non-finite error (the reference level
    itself, failed levels) are left out; fewer than two left give NaN. Fed the
    differences between successive levels (h_i against ||u_i - u_{i+1}||),
    the fit is unbiased: they are C (1 - r^-p) h_i^p for a constant ratio r.
    """
    h, e = np.asarray(h, float), np.asarray(error, float)
    use = np.isfinite(h) & np.isfinite(e) & (h > 0) & (e > 0)
    if use.sum() < 2:
        return math.nan, math.nan
    p, logc = np.polyfit(np.log(h[use]), np.log(e[use]), 1)
    return float(p), float(math.exp(logc))


def richardson(h, q) -> tuple[float, float]:
    """Order p and extrapolated value q* from three levels, q = q* + C h^p.

    ``h`` decreasing; the ratios h1/h2 and h2/h3 may differ (p then solves
    (q1-q2)/(q2-q3) = (h1^p-h2^p)/(h2^p-h3^p)). NaN when the three values do
    not converge monotonically, the premise of the estimate.
    """
    (h1, h2, h3), (q1, q2, q3) = np.asarray(h, float), np.asarray(q, float)
    if not np.all(np.isfinite([h1, h2, h3, q1, q2, q3])) or not h1 > h2 > h3 > 0:
        return math.nan, math.nan
    if q2 == q3 or q1 == q2:
        return math.nan, math.nan
    ratio = (q1 - q2) / (q2 - q3)
    r1, r2 = h1 / h2, h2 / h3

    def excess(p):
        return r2**p * (r1**p - 1.0) / (r2**p - 1.0) - ratio

    # the right side rises from ln r1/ln r2 (p -> 0) without bound
    p_lo, p_hi = 1e-6, 50.0
    if not excess(p_lo) < 0 < excess(p_hi):
        return math.nan, math.nan
    p = optimize.brentq(excess, p_lo, p_hi, xtol=1e-14, rtol=1e-12)
    q_star = q3 + (q3 - q2) * h3**p / (h2**p - h3**p)
    return float(p), float(q_star)


def coarsest_converged(errors, tolerance: float) -> int | None:
    """Index of the coarsest level that, with every finer level, is within tolerance.

    ``errors`` (levels coarsest first, the finest last) holds each level's
    largest relative difference to the finest level, NaN for a failed level
    (left out). None when no level coarser than the finest qualifies.
    """
    e = np.asarray(errors, float)
    found = None
    for i in range(len(e) - 2, -1, -1):
        if math.isnan(e[i]):
            continue
        if e[i] > tolerance:
            break
        found = i
    return found
