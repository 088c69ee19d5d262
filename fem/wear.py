"""Gap-based Reye–Archard wear on the condensed sphere (pure arrays).

Each contact node i carries a wear depth w_i that widens its gap,
gap_i = z_i + w_i − d + (C f)_i, and grows as w_i += (k μ/σ0) p_i Δs with the
nodal pressure p_i = f_i / A_i (A_i: lumped 2πr-weighted area).

* explicit (forward) Euler: p from the contact at the start of the step;
  stable for Δs < 2 / (rate · λ_max(A⁻¹ C⁻¹)) (:func:`explicit_limit`);
* implicit (backward) Euler: w_{n+1} = w_n + D f_{n+1}, D = rate Δs / A, so
  one LCP with compliance C + D per step, no stability limit (docs/theory.md §7, §12);
* adaptive: backward Euler with step doubling (one step of Δs, two of
  Δs/2); the difference estimates the local error and sets the step (a
  ladder of doublings and halvings); the two half steps are kept (monotone
  at the moving contact edge) and Richardson's correction, their difference
  to the full step, is added to the start of the next step (second order);
* bdf2: the variable-step second-order backward differentiation formula,
  w_{n+1} = a w_n + b w_{n−1} + c D f_{n+1} with ω = Δs_n/Δs_{n−1},
  a = (1+ω)²/(1+2ω), b = −ω²/(1+2ω), c = (1+ω)/(1+2ω): the implicit step
  with compliance C + c D and the previous wear a w_n + b w_{n−1}; the first
  step is backward Euler. L-stable; zero-stable while ω < 1 + √2, so steps
  grow by at most a factor 2 and the last two steps before a stage or the
  end share the remaining distance when it is less than two steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import linalg

from wearcheck.cases import SolverError, wear_law
from wearcheck.cases.result import scar_radius

from .contact import PrefixCholesky, solve_lcp

#: relative tolerance on the complementarity residual of every contact solve
LCP_TOL = 1e-9


def explicit_limit(C: np.ndarray, area: np.ndarray, rate: float) -> float:
    """Largest stable explicit Euler step Δs [m].

    The wear map δw ← (I − rate Δs A⁻¹ S) δw with S = C_AA⁻¹ is stable while
    rate Δs λ_max(A⁻¹ S) < 2. Over the whole candidate arc λ_max is an upper
    bound for any active subset (Schur complement), so the limit is safe.
    λ_max(A⁻¹ C⁻¹) = 1 / λ_min(A^½ C A^½), of order E*/h for node spacing h:
    measured Δŝ_max = (1.05-1.18) h/a0 with P2 and 1.46 h/a0 with P1, i.e.
    Δs_max ≈ 1.1 h σ0 / (k μ E*) (docs/theory.md §7 with C = O(1)).
    """
    sa = np.sqrt(area)
    lam_min = linalg.eigvalsh(sa[:, None] * C * sa[None, :], subset_by_index=[0, 0])[0]
    return 2.0 * lam_min / rate


@dataclass
class WearRun:
    s: list = field(default_factory=list)
    force: list = field(default_factory=list)
    depth: list = field(default_factory=list)
    contact_radius: list = field(default_factory=list)
    wear_center: list = field(default_factory=list)
    wear_volume: list = field(default_factory=list)
    scar_radius: list = field(default_factory=list)
    stages: list = field(default_factory=list)  # (s, f, w, depth, gap)
    lcp_iterations: int = 0
    max_residual: float = 0.0
    refactorisations: int = 0
    borderings: int = 0
    steps: int = 0
    rejected_steps: int = 0
    time_error: float = 0.0
    largest_step: float = 0.0


def contact_radius(r: np.ndarray, f: np.ndarray, gap: np.ndarray) -> float:
    """Contact radius to sub-node accuracy.

    Between the last loaded node i and the next node the edge is found from
    the gaps of the first two free nodes j, j+1: near a smooth contact edge
    the gap grows like (r − a)^{3/2}, so gap^{2/3} is extrapolated linearly to
    zero; the result is clamped to [r_i, r_j].
    """
    loaded = np.flatnonzero(f > 0)
    if len(loaded) == 0:
        return 0.0
    i = loaded[-1]
    j = i + 1
    if j >= len(r):
        return float(r[i])
    if j + 1 >= len(r):
        return float(r[i])
    t1, t2 = np.cbrt(max(gap[j], 0.0)) ** 2, np.cbrt(max(gap[j + 1], 0.0)) ** 2
    if t2 <= t1:
        return float(r[i])
    a = r[j] - t1 * (r[j + 1] - r[j]) / (t2 - t1)
    return float(min(max(a, r[i]), r[j]))


def run(C, z, r, area, rate, *, control, value, step, scheme, stage_s, until,
        distance=None, force_fraction=None, gap_scale, force_scale, pressure_scale,
        center=None, progress=None, max_steps=2_000_000, oscillation_steps=5,
        tolerance=None, depth_scale=None, exponent=1.0, hardness=1.0,
        first_step=None, watch=None) -> WearRun:
    """Slide and wear; return history and the states at the stored stages.

    Parameters
    ----------
    C : (n, n) compliance [m/N]; z : (n,) unworn heights [m]; r, area : (n,)
    radii [m] and lumped areas [m²]; rate : k μ / σ0 [1/Pa]; control : "depth"
    or "force" with its ``value``; step : Δs [m] (adaptive: the largest step,
    inf for none); scheme : "explicit", "implicit", "bdf2" or "adaptive";
    stage_s : increasing stage distances [m]; until : "distance"
    (stop exactly at ``distance``) or "force_fraction" (stop at the first step
    with F < force_fraction · F(0)); center : (n,) weights giving the wear at
    r = 0 as center @ w (default: node 0). Adaptive: ``tolerance`` on the
    step-doubling error estimate (force /force_scale, depth and central wear
    /max(depth_scale, value)), ``first_step`` [m]. ``exponent`` n and
    ``hardness`` σ0: wear speed rate σ0 (p/σ0)^n (implicit steps linearise it,
    Newton). ``watch(s, contact_radius, scar_radius)`` is called at every
    recorded step (:class:`cases.validity.BodyWatch`).
    """
    n = len(z)
    out = WearRun()
    w = np.zeros(n)
    if center is None:
        center = np.eye(1, n)[0]
    kw = {control: value}
    factors: dict[float, PrefixCholesky] = {}
    adaptive = scheme == "adaptive"

    def speed(p):
        """Wear speed dw/ds at nodal pressures p (:func:`cases.wear_law.speed`)."""
        return wear_law.speed(p, rate, exponent, hardness)

    def factor_for(eff):
        """Factor of C + rate·eff/A (eff: the step times the scheme's c; 0: C).

        A new factor is needed only when c·Δs changes: constant steps share one;
        a stage off the step grid adds at most three under bdf2 (the two
        shared steps before it, the first full step after it). Measured: one
        factor costs 1 ms at 251 nodes, 12 ms at 1001 (benchmarks/bench_fem.py),
        against 0.06-0.5 ms per step. Least recently used out: the running
        step's factor is used every step and must survive a landing's.
        """
        fac = factors.pop(eff, None)
        if fac is None:
            if len(factors) >= 6:
                out.borderings += factors.pop(next(iter(factors))).borderings
            fac = PrefixCholesky(C if eff == 0.0 else C + np.diag(rate * eff / area))
            out.refactorisations += 1
        factors[eff] = fac
        return fac

    def contact(zz, fac, active):
        res = solve_lcp(fac, zz, active=active, gap_scale=gap_scale, force_scale=force_scale,
                        tol=LCP_TOL, **kw)
        out.lcp_iterations += res.iterations
        out.max_residual = max(out.max_residual, res.residual)
        if res.f[-1] > 0:
            raise SolverError(
                f"the contact reached the end of the candidate arc (r = {r[-1]:.4g} m) at "
                f"s = {s:.4g} m: the scar outgrew the radius predicted when the mesh was "
                "built; increase fem.contact_factor")
        return res

    def implicit(base, eff, active):
        """One implicit step from the wear ``base`` with wear compliance eff (= c Δs).

        Returns the contact result and the new wear. n != 1: Newton on the
        linearised wear speed, a fresh factor per iteration.
        """
        if exponent == 1.0:
            res = contact(z + base, factor_for(eff), active)
            return res, base + rate * eff * res.f / area
        p_k = res_prev[0].f / area
        for _ in range(30):
            slope = wear_law.slope(p_k, exponent, hardness)
            shift = eff * (speed(p_k) - rate * slope * p_k)
            fac = PrefixCholesky(C + np.diag(rate * eff * slope / area))
            out.refactorisations += 1
            res = contact(z + base + shift, fac, active)
            p = res.f / area
            change = np.max(np.abs(p - p_k))
            p_k, active = p, res.active
            if change <= 1e-9 * max(np.max(p), 1e-300):
                break
        else:
            raise SolverError("implicit wear step: the Newton iteration of the pressure "
                              "exponent did not converge in 30 iterations")
        return res, base + eff * speed(p_k)

    stages = list(stage_s)
    s = 0.0
    res = contact(z, factor_for(0.0), None)
    res_prev = [res]
    F_start = res.f.sum()
    if not F_start > 0:
        raise SolverError("the unworn sphere carries no force")

    def record(res):
        out.s.append(s)
        out.force.append(res.f.sum())
        out.depth.append(res.depth)
        out.contact_radius.append(contact_radius(r, res.f, res.gap))
        out.wear_center.append(float(center @ w))
        out.wear_volume.append(float(area @ w))
        out.scar_radius.append(scar_radius(r, w))
        if watch is not None:
            watch(s, out.contact_radius[-1], out.scar_radius[-1])
        if stages and abs(s - stages[0]) <= 1e-12 * max(abs(s), step if math.isfinite(step)
                                                         else abs(s)):
            out.stages.append((s, res.f.copy(), w.copy(), res.depth, res.gap.copy()))
            stages.pop(0)

    record(res)
    s_end = distance if until == "distance" else math.inf
    dp_prev = np.zeros(n)
    p_prev = res.f / area
    osc = np.zeros(n, dtype=int)
    bdf2 = scheme == "bdf2"
    ds_prev, w_prev = None, None
    h_cur = min(first_step, step) if adaptive else step
    corr = np.zeros(n)
    while True:
        if until == "distance" and s >= s_end:
            break
        if until == "force_fraction" and out.force[-1] < force_fraction * F_start:
            break
        if out.steps >= max_steps:
            raise SolverError(f"no end after {max_steps} steps (s = {s:.4g} m, "
                              f"F = {out.force[-1]:.4g} N); the step is too small")
        target = min(stages[0] if stages else math.inf, s_end)
        ds = h_cur
        if bdf2 and ds_prev is not None:
            ds = min(ds, 2.0 * ds_prev)  # ω <= 2 < 1 + √2 (zero stability)
        rem = target - s
        land = rem <= ds * (1 + 1e-9)
        if land:
            # a remainder equal to this or the last step up to round-off
            # keeps that step (and its factor); s lands exactly on the target
            same = [h for h in (ds, ds_prev) if h is not None and abs(rem - h) <= 1e-9 * h]
            ds = same[0] if same else rem
        elif (bdf2 or adaptive) and rem < 2.0 * ds * (1 - 1e-9):
            ds = 0.5 * rem  # no sliver step before the target: ω stays in [1/2, 2]
        if scheme == "explicit":
            fac = factor_for(0.0)
            w = w + ds * speed(res.f / area)
            res = contact(z + w, fac, res.active)
        elif adaptive:
            # step doubling: one step of ds and two of ds/2 by backward Euler from
            # the start corrected by the last step's Richardson term (kept out of
            # the recorded state: the recorded one is backward Euler's, monotone)
            start = w + corr
            res_prev[0] = res
            full, w_full = implicit(start, ds, res.active)
            half, w_half = implicit(start, 0.5 * ds, res.active)
            res_prev[0] = half
            two, w_two = implicit(w_half, 0.5 * ds, half.active)
            fs = force_scale
            wc_two = float(center @ w_two)
            err = max(abs(two.f.sum() - full.f.sum()) / fs,
                      abs(two.depth - full.depth) / max(depth_scale, abs(two.depth)),
                      abs(wc_two - float(center @ w_full)) / max(depth_scale, abs(wc_two)))
            if err > tolerance and ds > 1e-12 * max(s, ds):
                out.rejected_steps += 1
                h_cur = 0.5 * ds
                continue
            out.time_error = max(out.time_error, err)
            out.largest_step = max(out.largest_step, ds)
            corr = w_two - w_full
            w_prev, w, res = w, w_two, two
            if err < 0.2 * tolerance and ds == h_cur and 2.0 * ds <= step:
                h_cur = 2.0 * ds
        else:
            if bdf2 and ds_prev is not None:
                om = ds / ds_prev
                c = (1.0 + om) / (1.0 + 2.0 * om)
                # a w_n + b w_{n−1} = w_n − b (w_n − w_{n−1}), since a + b = 1
                base = w + (om * om / (1.0 + 2.0 * om)) * (w - w_prev)
            else:
                c, base = 1.0, w  # backward Euler (and the first bdf2 step)
            res_prev[0] = res
            res, w_new = implicit(base, c * ds, res.active)
            w_prev, w = w, w_new
            # the gap of the new geometry is the LCP's gap (C + c D) f + q
        ds_prev = ds
        s = target if land else s + ds
        out.steps += 1
        record(res)
        if scheme == "explicit":
            p = res.f / area
            dp = p - p_prev
            growing = (dp * dp_prev < 0) & (np.abs(dp) > np.abs(dp_prev)) & \
                (np.abs(dp) > 1e-3 * pressure_scale)
            osc = np.where(growing, osc + 1, 0)
            if np.any(osc >= oscillation_steps):
                i = int(np.argmax(osc))
                raise SolverError(
                    f"explicit wear oscillates: the pressure at r = {r[i]:.4g} m alternates "
                    f"with growing amplitude for {oscillation_steps} steps (s = {s:.4g} m); "
                    "reduce sliding.step_hat or use sliding.scheme = \"implicit\"")
            dp_prev, p_prev = dp, p
        if progress is not None:
            if until == "distance":
                progress(min(s / s_end, 1.0) if s_end > 0 else 1.0, f"s = {s:.3g} m")
            else:
                F = max(out.force[-1], 1e-300)
                progress(min(max(math.log(F / F_start) / math.log(force_fraction), 0.0), 1.0),
                         f"F/F0 = {F / F_start:.3g}")
    out.borderings += sum(f.borderings for f in factors.values())
    return out
