"""Deriving a certified reference: a benchmark solved at several resolutions, sampled
on common points, and the error of the finest solution estimated.

The finest run (every resolution at its finest) is the reference. Its error is
estimated per stored stage and check, in SI units, as the sum of

- **space** and **time** (and, for fretting, the jump tolerance and the
  increments per cycle): one dimension at a time, three levels coarse to fine
  with the others held; the observed order p from the max-norms of the
  differences, ``p = log(‖Q1 − Q2‖/‖Q2 − Q3‖)/log(ratio)``, and Roache's grid
  convergence index of the finest level, ``1.25 max(|Q3 − Q2|, |Q2 − Q1|/ratio^p)
  /(ratio^p − 1)`` with p clamped to [0.5, 2] (a faster observed order is not
  trusted; a slower or erratic one makes the band up to 3 times the last
  difference);
- **resample**: what the shipped samples cost: the history's PCHIP against
  the finest run's own steps, the stage's linear interpolation in r against
  the run at the midpoints of the samples, and (per interval, ``interval``)
  the cubic interpolation between stored stages against held-out stages
  computed in the same run.

Closed forms (Hertz, the truncated paraboloid) are the reference themselves;
their band is the resampling alone, and the MDR's convergence to them is
recorded. The other solvers, run at the case's own settings, give the
**spread** (not part of the band: it measures them, not the reference).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from wearcheck.cases import reference as closed
from wearcheck import registry

from . import certified

#: Roache's safety factor of the grid convergence index with three levels
SAFETY = 1.25
#: the observed order is clamped to this range before it is used
ORDER_RANGE = (0.5, 2.0)


@dataclass(frozen=True)
class Dimension:
    """One resolution varied over three levels, coarse to fine.

    name : "space", "time", ...; key : the case key ("mdr.elements");
    levels : its values coarse to fine; ratio : the refinement ratio between
    levels (2 for a doubled grid, 10 for a tenfold tighter tolerance);
    at : the other keys while this one is varied.
    """

    name: str
    key: str
    levels: tuple
    ratio: float
    at: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Plan:
    """How one benchmark's reference is made.

    solver : "mdr", "bem" or "closed_form". stages : the stored stages, in
    ``stage_unit`` ("s_hat" or "cycles"). s_hat_ref : None to interpolate in ŝ,
    else in log(1 + ŝ/s_hat_ref). dimensions : the resolutions varied (the
    first one's finest run, at its ``at``, is the reference). rho_* : the
    stage samples r = ρ·a. spread : solvers run at the case's settings.
    """

    name: str
    solver: str
    stages: tuple
    stage_unit: str = "s_hat"
    s_hat_ref: float | None = None
    dimensions: tuple = ()
    rho_f_max: float = 1.2
    rho_p_max: float = 1.2
    points_f: int = 193
    points_p: int = 193
    history_points: int = 300
    spread: tuple = ()
    mdr_check_levels: tuple = ()
    integer_stages: bool = False

    def rho_f(self) -> np.ndarray:
        return np.linspace(0.0, self.rho_f_max, self.points_f)

    def rho_p(self) -> np.ndarray:
        return np.linspace(0.0, self.rho_p_max, self.points_p)


_DEPTH_STAGES = (0.0, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0,
                 3.5, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 10.5)
_DECADES = (0.0, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1e3, 2e3, 5e3, 1e4,
            2e4, 5e4, 1e5, 2e5, 5e5, 1e6)

#: the shipped references (python benchmarks/make_references.py makes them)
PLANS = {
    "hertz": Plan("hertz", "closed_form", (0.0,), spread=("mdr", "fem", "bem"),
                  mdr_check_levels=(800, 1600, 3200)),
    "truncated": Plan("truncated", "closed_form", (0.0,), spread=("mdr", "fem", "bem"),
                      mdr_check_levels=(800, 1600, 3200)),
    "paper": Plan(
        "paper", "mdr", _DEPTH_STAGES, spread=("fem", "bem"),
        dimensions=(Dimension("space", "mdr.elements", (1600, 3200, 6400), 2.0,
                              {"sliding.tolerance": 1e-6}),
                    Dimension("time", "sliding.tolerance", (1e-4, 1e-5, 1e-6), 10.0,
                              {"mdr.elements": 1600}))),
    "ellipsoid": Plan(
        # the BEM's box (2.5 times the final long semi-axis) holds rings to 1.64 a(s) at
        # the end; the worn region and the pressure reach the long semi-axis, 1.44 a(s)
        # at most (b/a = 0.48 unworn, 0.58 at complete wear)
        "ellipsoid", "bem", _DEPTH_STAGES[:-1], spread=("mdr",), rho_f_max=1.55, rho_p_max=1.55,
        points_f=187, points_p=187,
        dimensions=(Dimension("space", "bem.grid", (64, 128, 256), 2.0,
                              {"sliding.tolerance": 1e-5}),
                    Dimension("time", "sliding.tolerance", (1e-3, 1e-4, 1e-5), 10.0,
                              {"bem.grid": 64}))),
    "ball_on_flat": Plan(
        "ball_on_flat", "mdr", _DECADES, stage_unit="cycles", s_hat_ref=0.01,
        spread=("fem", "bem"),
        dimensions=(Dimension("space", "mdr.elements", (400, 800, 1600), 2.0,
                              {"sliding.tolerance": 1e-6}),
                    Dimension("time", "sliding.tolerance", (1e-4, 1e-5, 1e-6), 10.0,
                              {"mdr.elements": 400}))),
    "fretting": Plan(
        "fretting", "mdr", (0, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000,
                            20000, 50000, 100000),
        stage_unit="cycles", s_hat_ref=1e-4, integer_stages=True,
        # (increments per cycle: a multiple of 4, each quarter cycle ramping alike)
        dimensions=(Dimension("space", "mdr.elements", (400, 800, 1600), 2.0,
                              {"fretting.jump_tolerance": 0.005, "fretting.increments": 16}),
                    Dimension("jumps", "fretting.jump_tolerance", (0.02, 0.01, 0.005), 2.0,
                              {"mdr.elements": 400, "fretting.increments": 16}),
                    Dimension("increments", "fretting.increments", (4, 8, 16), 2.0,
                              {"mdr.elements": 400, "fretting.jump_tolerance": 0.005}))),
}


# -- stages --------------------------------------------------------------------

def held_out(plan: Plan) -> tuple:
    """One stage between each pair of stored stages (the middle in τ, or in the
    cycle count's logarithm), computed but not shipped: what interpolating
    between stored stages costs is measured on them."""
    st = np.asarray(plan.stages, float)
    out = []
    for lo, hi in zip(st[:-1], st[1:]):
        if plan.stage_unit == "cycles":
            mid = math.sqrt(lo * hi) if lo > 0 else 0.5 * hi
            if plan.integer_stages:
                mid = float(round(mid))
                mid = mid if lo < mid < hi else None
        else:
            mid = 0.5 * (lo + hi)
        out.append(mid)
    return tuple(out)


def configure(case, plan: Plan, changes: dict):
    """The case with the stored and held-out stages and the resolution ``changes``."""
    stages = sorted(set(plan.stages) | {m for m in held_out(plan) if m is not None})
    keys = dict(changes)
    if case.fretting is not None:
        keys["fretting.stage_cycles"] = [int(c) for c in stages]
    elif plan.stage_unit == "cycles":
        keys["stages.cycles"] = [float(c) for c in stages]
    else:
        keys["stages.s_hat"] = [float(c) for c in stages]
    return case.derive(keys)


def stage_distances(result, plan: Plan) -> dict:
    """{stage value (ŝ or cycles): distance s [m]} of a run configured by :func:`configure`."""
    stages = sorted(set(plan.stages) | {m for m in held_out(plan) if m is not None})
    s = np.asarray(result.stage_s, float)
    if len(s) != len(stages):
        raise RuntimeError(f"{plan.name}: the run kept {len(s)} stages, "
                           f"{len(stages)} were asked for (did it end early?)")
    return dict(zip(stages, s))


# -- sampling a run -------------------------------------------------------------

def wear_on_radii(result, case) -> np.ndarray:
    """(K, M) wear depth on the run's radii: the BEM's ring average of its wear
    field (fields.wear_depth), else f − f0 (f0 exact on the run's radii)."""
    flds = result.fields or {}
    w3 = flds.get("wear_depth")
    if w3 is not None and np.ndim(w3) == 3 and "x" in flds:
        x, y = np.asarray(flds["x"]), np.asarray(flds["y"])
        X, Y = np.meshgrid(x, y, indexing="ij")
        dx = float(x[1] - x[0])
        ring = np.rint(np.hypot(X, Y) / dx).astype(np.int64).ravel()
        rings = len(result.r)
        inside = ring < rings
        count = np.bincount(ring[inside], minlength=rings)
        out = np.zeros((len(w3), rings))
        for k in range(len(w3)):
            total = np.bincount(ring[inside], np.asarray(w3[k]).ravel()[inside],
                                minlength=rings)
            out[k] = total / np.maximum(count, 1)
        return out
    return np.asarray(result.f, float) - certified.unworn_profile(case, result.r)[None, :]


def history_interpolant(result, s_hat_per_m, s_hat_ref):
    """{column: callable(s)}: PCHIP in τ through a run's history (repeated s dropped)."""
    import scipy.interpolate
    s = np.asarray(result.history["s"], float)
    keep = np.concatenate([[True], np.diff(s) > 0])
    t = certified.tau(s[keep] * s_hat_per_m, s_hat_ref)
    out = {}
    for name in certified.HISTORY[1:]:
        y = np.asarray(result.history[name], float)[keep]
        if len(t) == 1:
            out[name] = (lambda v: (lambda q: np.full(np.shape(q), v)))(float(y[0]))
            continue
        spline = scipy.interpolate.PchipInterpolator(t, y)

        def at(q, spline=spline):
            return spline(certified.tau(np.asarray(q, float) * s_hat_per_m, s_hat_ref))
        out[name] = at
    return out


def sample_stages(result, case, dist, stage_a, rho_f, rho_p) -> tuple[dict, dict]:
    """Wear and pressure of a run at r = ρ·a (a: the finest run's stage contact radii),
    linearly in r; {stage value: (Mf,)}, {stage value: (Mp,)}. Beyond the run's radii
    both are zero: the solvers' domains hold the contact and all the wear (the MDR
    grows its domain before the contact reaches 0.9 of it), which
    :func:`_check_support` checks on the finest run."""
    r = np.asarray(result.r, float)
    w = wear_on_radii(result, case)
    p = np.asarray(result.p, float)
    wear, pres = {}, {}
    for k, key in enumerate(dist):
        a = stage_a[key]
        wear[key] = np.interp(rho_f * a, r, w[k], right=0.0)
        pres[key] = np.interp(rho_p * a, r, p[k], right=0.0)
    return wear, pres


# -- error estimates ------------------------------------------------------------

def observed_order(q1, q2, q3, ratio: float) -> float:
    """Order from three levels (max-norms of the two differences); NaN if undefined."""
    e12 = float(np.nanmax(np.abs(np.asarray(q1) - q2))) if np.size(q1) else math.nan
    e23 = float(np.nanmax(np.abs(np.asarray(q2) - q3))) if np.size(q2) else math.nan
    if not (e12 > 0 and e23 > 0):
        return math.nan
    return math.log(e12 / e23) / math.log(ratio)


def gci(q1, q2, q3, ratio: float, order: float):
    """Roache's grid convergence index of the finest level q3 (pointwise, same units)."""
    p = ORDER_RANGE[0] if not np.isfinite(order) else float(np.clip(order, *ORDER_RANGE))
    g = ratio**p
    e23 = np.abs(np.asarray(q3, float) - q2)
    e12 = np.abs(np.asarray(q2, float) - q1) / g
    return SAFETY * np.maximum(e23, e12) / (g - 1.0)


def stage_norms(case, wear: dict, pres: dict, hist: dict, keys, stage_a, rho_f, rho_p,
                edge_band: float) -> dict:
    """Per check, the quantity each stage is judged by (for differencing): the wear
    over the contact and the pressure in the interior as arrays, the history values."""
    out = {c: [] for c in certified.BAND_CHECKS}
    contact = rho_f <= 1.0 + edge_band
    for key in keys:
        a = stage_a[key]
        out["profile_contact_max"].append(wear[key][contact])
        out["pressure_interior_max"].append(pres[key][interior_mask(case, rho_p, a,
                                                                    edge_band)])
        for name in ("force", "contact_radius", "wear_center", "wear_volume", "depth"):
            out[name].append(np.array([hist[name][key]]))
    return out


def interior_mask(case, rho_p, a, edge_band) -> np.ndarray:
    """The interior of the pressure check on the ρ samples: ρ < 1 − edge_band, away
    from a singular band (|r − b| < edge_band·a0 of a truncated paraboloid)."""
    mask = rho_p < 1.0 - edge_band
    if case.indenter.profile == "truncated_paraboloid":
        a0 = closed.scales(case)["a0"]
        mask &= np.abs(rho_p * a - case.indenter.flat_radius) >= edge_band * a0
    return mask


def dimension_band(case, per_level: list, dim: Dimension) -> tuple[dict, dict]:
    """{check: (J,) band} and {check: observed order} of one dimension's three levels.

    ``per_level``: each level's :func:`stage_norms` (coarse to fine)."""
    band, orders = {}, {}
    for check in certified.BAND_CHECKS:
        q = [per_level[i][check] for i in range(3)]
        flat = [np.concatenate(x) if x else np.zeros(0) for x in q]
        order = observed_order(*flat, ratio=dim.ratio)
        orders[check] = order
        band[check] = np.array([float(np.nanmax(gci(q[0][j], q[1][j], q[2][j], dim.ratio,
                                                    order), initial=0.0))
                                for j in range(len(q[0]))])
    return band, orders


# -- the whole derivation -----------------------------------------------------------

def derive(plan: Plan, *, dimensions=None, spread=None, changes=None, quiet=False,
           solve=None) -> dict:
    """Compute a reference and its band; returns what :func:`certified.write` takes.

    ``dimensions`` and ``spread`` replace the plan's, ``changes`` are applied to the
    shipped case first (a shorter run: the tests derive coarse versions);
    ``solve(case, solver)`` defaults to the registry's.
    """
    from wearcheck import cases
    solve = solve or (lambda c, name: registry.solve(c, name))
    case = cases.load(cases.shipped(plan.name))
    if changes:
        case = case.derive(changes)
    dims = plan.dimensions if dimensions is None else dimensions
    say = (lambda *a: None) if quiet else (lambda *a: print(*a, flush=True))
    if plan.solver == "closed_form":
        data = _closed_form(plan, case)
    else:
        data = _from_runs(plan, case, dims, solve, say)
    data["meta"]["spread"] = _spread(plan, case, data, plan.spread if spread is None
                                     else spread, solve, say)
    if plan.mdr_check_levels:
        data["meta"]["mdr_against_closed_form"] = _mdr_check(plan, case, data, solve, say)
    data.pop("closed_pressure", None)
    return data


def _run(case, plan, changes, solver, solve, say):
    c = configure(case, plan, changes)
    t0 = time.perf_counter()
    res = solve(c, solver)
    seconds = time.perf_counter() - t0
    say(f"  {plan.name} {solver} {changes}: {seconds:.1f} s, {len(res.history['s'])} steps")
    return c, res, dict(changes=changes, seconds=seconds, steps=len(res.history["s"]) - 1,
                        info={k: v for k, v in res.info.items()
                              if isinstance(v, (int, float, str))})


def _from_runs(plan, case, dims, solve, say) -> dict:
    sc = closed.scales(case)
    per_m = sc["s_hat_per_m"]
    edge_band = case.compare.edge_band
    rho_f, rho_p = plan.rho_f(), plan.rho_p()
    runs = {}
    log = []

    def level(dim, value):
        changes = dict(dim.at, **{dim.key: value})
        key = tuple(sorted(changes.items()))
        if key not in runs:
            c, res, entry = _run(case, plan, changes, plan.solver, solve, say)
            runs[key] = (c, res)
            log.append(entry)
        return runs[key]

    finest_case, finest = level(dims[0], dims[0].levels[-1])
    dist = stage_distances(finest, plan)
    keys = list(dist)
    a_of = history_interpolant(finest, per_m, plan.s_hat_ref)["contact_radius"]
    stage_a = {k: float(a_of(dist[k])) for k in keys}
    # every level is sampled where the finest one is: the same s, the same radii
    s_end = min(float(res.history["s"][-1]) for _, res in runs.values())

    def sampled(res):
        h = history_interpolant(res, per_m, plan.s_hat_ref)
        d = stage_distances(res, plan)
        hist = {name: {k: float(h[name](dist[k])) for k in keys} for name in h}
        wear, pres = sample_stages(res, finest_case, d, stage_a, rho_f, rho_p)
        return hist, wear, pres

    bands, orders, level_values = {}, {}, {}
    for dim in dims:
        per_level = []
        for value in dim.levels:
            _, res = level(dim, value)
            hist, wear, pres = sampled(res)
            per_level.append(stage_norms(case, wear, pres, hist, keys, stage_a, rho_f, rho_p,
                                         edge_band))
        bands[dim.name], orders[dim.name] = dimension_band(case, per_level, dim)
        level_values[dim.name] = dict(key=dim.key, levels=list(dim.levels), ratio=dim.ratio,
                                      at=dim.at)
    s_end = min(s_end, min(float(res.history["s"][-1]) for _, res in runs.values()))
    hist_f, wear_f, pres_f = sampled(finest)
    stored = [k for k in keys if k in plan.stages]
    extra = [k for k in keys if k not in plan.stages]
    # the history's samples, and what the PCHIP through them costs against the run
    t_end = certified.tau(s_end * per_m, plan.s_hat_ref)
    u = np.linspace(0.0, 1.0, plan.history_points)
    if plan.s_hat_ref is None:
        t_samples = t_end * u**1.5          # denser early, where the force falls fastest
    else:
        t_samples = t_end * u
    s_samples = _s_of_tau(t_samples, per_m, plan.s_hat_ref)
    s_samples[0], s_samples[-1] = 0.0, s_end
    h_f = history_interpolant(finest, per_m, plan.s_hat_ref)
    history = dict(s=s_samples, **{n: h_f[n](s_samples) for n in certified.HISTORY[1:]})
    if case.fretting is not None:
        history["cycles"] = np.interp(s_samples, finest.history["s"],
                                      finest.history["cycles"])
    stored_s = np.array([dist[k] for k in keys if k in plan.stages])
    hist_resample = _history_resample(finest, history, per_m, plan.s_hat_ref, stored_s)
    # the stage samples and what linear interpolation in ρ and cubic in τ cost
    rho_cost = _rho_resample(finest, finest_case, dist, stage_a, rho_f, rho_p, case, edge_band)
    wear_arr = np.array([wear_f[k] for k in stored])
    pres_arr = np.array([pres_f[k] for k in stored])
    for name, arr in (("wear", wear_arr), ("pressure", pres_arr)):
        if not np.all(np.isfinite(arr)):
            raise RuntimeError(f"{plan.name}: the finest run's {name} is not finite")
    _check_support(plan, finest, finest_case, dist, stage_a, sc)
    interval = _held_out_cost(plan, case, stored, extra, dist, stage_a, wear_f, pres_f,
                              hist_f, per_m, rho_f, rho_p, edge_band)
    band = {}
    j_of = {k: i for i, k in enumerate(keys)}
    for check in certified.BAND_CHECKS:
        parts = {}
        for dim in dims:
            parts[dim.name] = np.array([bands[dim.name][check][j_of[k]] for k in stored])
        resample = np.array([(hist_resample[check][j] if check in hist_resample else 0.0)
                             + rho_cost[check][k] for j, k in enumerate(stored)])
        parts["resample"] = resample
        parts["total"] = sum(parts.values())
        parts["interval"] = interval[check]
        band[check] = parts
    meta = dict(method=f"{plan.solver.upper()} at its finest level; band: grid convergence "
                       "index per dimension + resampling (references/derive.py)",
                solver=plan.solver, dimensions=level_values, orders=orders, runs=log,
                stage_unit=plan.stage_unit, stages=list(plan.stages),
                held_out=[k for k in extra], edge_band=edge_band,
                history_resample={k: v.tolist() for k, v in hist_resample.items()})
    return dict(name=plan.name, physics=certified.physics(case), s_hat_ref=plan.s_hat_ref,
                history=history, stage_s=np.array([dist[k] for k in stored]),
                stage_a=np.array([stage_a[k] for k in stored]), rho_f=rho_f, wear=wear_arr,
                rho_p=rho_p, pressure=pres_arr, band=band, meta=meta)


def _s_of_tau(t, per_m, s_hat_ref):
    t = np.asarray(t, float)
    s_hat = t if s_hat_ref is None else s_hat_ref * np.expm1(t)
    return s_hat / per_m


def _history_resample(run, history, per_m, s_hat_ref, stage_s) -> dict:
    """Per history check and stored stage (distances ``stage_s``), the largest |PCHIP of
    the samples − the run| over the run's steps between the neighbouring stored stages:
    the cost of reading the history near that stage. (One maximum over the whole run
    charged the early stages of a run over decades with the error of its late ones,
    a thousand times their worn volume.)"""
    import scipy.interpolate
    s = np.asarray(run.history["s"], float)
    inside = s <= history["s"][-1]
    t_s = certified.tau(history["s"] * per_m, s_hat_ref)
    t_run = certified.tau(s[inside] * per_m, s_hat_ref)
    stage_s = np.asarray(stage_s, float)
    lower = np.concatenate([[0.0], stage_s[:-1]])
    upper = np.concatenate([stage_s[1:], [np.inf]])
    out = {}
    for name in ("force", "contact_radius", "wear_center", "wear_volume", "depth"):
        y = scipy.interpolate.PchipInterpolator(t_s, history[name])(t_run)
        err = np.abs(y - np.asarray(run.history[name], float)[inside])
        out[name] = np.array([float(np.max(err[(s[inside] >= lo) & (s[inside] <= hi)],
                                           initial=0.0)) for lo, hi in zip(lower, upper)])
    return out


def _rho_resample(run, run_case, dist, stage_a, rho_f, rho_p, case, edge_band) -> dict:
    """Per check and stage, what linear interpolation between the ρ samples misses:
    the run at the samples' midpoints against the samples' average there."""
    out = {c: {} for c in certified.BAND_CHECKS}
    r = np.asarray(run.r, float)
    w = wear_on_radii(run, run_case)
    p = np.asarray(run.p, float)
    mid_f, mid_p = 0.5 * (rho_f[1:] + rho_f[:-1]), 0.5 * (rho_p[1:] + rho_p[:-1])
    for k, key in enumerate(dist):
        a = stage_a[key]
        wf = np.interp(rho_f * a, r, w[k])
        pf = np.interp(rho_p * a, r, p[k])
        dw = np.abs(np.interp(mid_f * a, r, w[k]) - 0.5 * (wf[1:] + wf[:-1]))
        dp = np.abs(np.interp(mid_p * a, r, p[k]) - 0.5 * (pf[1:] + pf[:-1]))
        contact = mid_f <= 1.0 + edge_band
        interior = interior_mask(case, mid_p, a, edge_band)
        for c in certified.BAND_CHECKS:
            out[c][key] = 0.0
        out["profile_contact_max"][key] = float(np.max(dw[contact], initial=0.0))
        out["pressure_interior_max"][key] = float(np.max(dp[interior], initial=0.0))
    return out


def _held_out_cost(plan, case, stored, extra, dist, stage_a, wear_f, pres_f, hist_f, per_m,
                   rho_f, rho_p, edge_band) -> dict:
    """Per check, (J − 1,): interpolating the stored stages (cubic in τ at fixed ρ) at
    the held-out stage of each interval, against the run there."""
    out = {c: np.zeros(max(len(stored) - 1, 0)) for c in certified.BAND_CHECKS}
    if not extra:
        return out
    nodes = certified.tau(np.array([dist[k] for k in stored]) * per_m, plan.s_hat_ref)
    W = np.array([wear_f[k] for k in stored])
    P = np.array([pres_f[k] for k in stored])
    contact = rho_f <= 1.0 + edge_band
    for key in extra:
        t = float(certified.tau(dist[key] * per_m, plan.s_hat_ref))
        j = int(np.clip(np.searchsorted(nodes, t) - 1, 0, len(nodes) - 2))
        idx = certified.stencil(t, nodes)
        lw = certified.lagrange_weights(t, nodes[idx])
        a = stage_a[key]
        dw = np.abs(lw @ W[idx] - wear_f[key])[contact]
        dp = np.abs(np.maximum(lw @ P[idx], 0.0) - pres_f[key])[
            interior_mask(case, rho_p, a, edge_band)]
        out["profile_contact_max"][j] = max(out["profile_contact_max"][j],
                                            float(np.max(dw, initial=0.0)))
        out["pressure_interior_max"][j] = max(out["pressure_interior_max"][j],
                                              float(np.max(dp, initial=0.0)))
    return out


def _check_support(plan, run, run_case, dist, stage_a, sc) -> None:
    """The wear is zero beyond ρ_f_max and the pressure beyond ρ_p_max at every stage
    (what the file leaves out), and the run's radii reach beyond the wear and the
    contact (what sampling beyond them takes as zero); else a RuntimeError."""
    r = np.asarray(run.r, float)
    w = wear_on_radii(run, run_case)
    p = np.asarray(run.p, float)
    d = closed.scales(run_case)["d0"]
    for k, key in enumerate(dist):
        a = stage_a[key]
        if np.abs(w[k][-1]) > 1e-9 * d or p[k][-1] > 1e-9 * sc["p0"] or a >= r[-1]:
            raise RuntimeError(f"{plan.name}: wear or pressure at the end of the run's radii "
                               f"at stage {key}")
        beyond_f, beyond_p = r > plan.rho_f_max * a, r > plan.rho_p_max * a
        if np.any(np.abs(w[k][beyond_f]) > 1e-9 * d):
            raise RuntimeError(f"{plan.name}: wear beyond ρ = {plan.rho_f_max} at stage {key}")
        if np.any(p[k][beyond_p] > 1e-9 * sc["p0"]):
            raise RuntimeError(f"{plan.name}: pressure beyond ρ = {plan.rho_p_max} at "
                               f"stage {key}")


def _closed_form(plan, case) -> dict:
    """Hertz or the truncated paraboloid, unworn: the closed forms sampled."""
    ind, E = case.indenter, case.E_star
    load = {case.loading.control: getattr(case.loading, case.loading.control)}
    rho_f, rho_p = plan.rho_f(), plan.rho_p()
    edge_band = case.compare.edge_band
    if ind.profile == "paraboloid":
        c = closed.hertz(E, ind.radius, **load)

        def pressure(r):
            return closed.hertz_pressure(r, E, ind.radius, c["contact_radius"])
        method = "Hertz's closed form (cases/reference.py hertz, hertz_pressure)"
    elif ind.profile == "truncated_paraboloid":
        c = closed.truncated_paraboloid(E, ind.radius, ind.flat_radius, **load)

        def pressure(r):
            r = np.asarray(r, float)
            out = closed.truncated_paraboloid_pressure(r, E, ind.radius, ind.flat_radius,
                                                       c["contact_radius"])
            return np.where(np.isfinite(out), out, 0.0)   # r = b exactly: left out
        method = ("paper Eqs. 17-19, the pressure by adaptive quadrature to 1e-12 "
                  "(cases/reference.py truncated_paraboloid, truncated_paraboloid_pressure)")
    else:
        raise ValueError(f"no closed form for {ind.profile}")
    a = c["contact_radius"]
    p = pressure(rho_p * a)
    mid = 0.5 * (rho_p[1:] + rho_p[:-1])
    dp = np.abs(pressure(mid * a) - 0.5 * (p[1:] + p[:-1]))
    interior = interior_mask(case, mid, a, edge_band)
    resample = {ch: 0.0 for ch in certified.BAND_CHECKS}
    resample["pressure_interior_max"] = float(np.max(dp[interior], initial=0.0))
    band = {ch: dict(resample=np.array([resample[ch]]), total=np.array([resample[ch]]),
                     interval=np.zeros(0)) for ch in certified.BAND_CHECKS}
    history = dict(s=np.array([0.0]), force=np.array([c["force"]]),
                   depth=np.array([c["depth"]]), contact_radius=np.array([a]),
                   wear_center=np.array([0.0]), wear_volume=np.array([0.0]))
    meta = dict(method=method, solver="closed_form", stage_unit="s_hat", stages=[0.0],
                edge_band=edge_band, dimensions={}, orders={}, runs=[])
    return dict(name=plan.name, physics=certified.physics(case), s_hat_ref=None,
                history=history, stage_s=np.array([0.0]), stage_a=np.array([a]),
                rho_f=rho_f, wear=np.zeros((1, len(rho_f))), rho_p=rho_p,
                pressure=p[None, :], band=band, meta=meta, closed_pressure=pressure)


def as_reference(data, case) -> certified.Reference:
    """What :func:`derive` returned, as a :class:`certified.Reference` (not written)."""
    hist = {k: np.asarray(v, float) for k, v in data["history"].items()}
    return certified.Reference(name=data["name"], case=case, s_hat_ref=data["s_hat_ref"],
                               history=hist, stage_s=np.asarray(data["stage_s"], float),
                               stage_a=np.asarray(data["stage_a"], float),
                               rho_f=data["rho_f"], wear=np.asarray(data["wear"], float),
                               rho_p=data["rho_p"], pressure=np.asarray(data["pressure"], float),
                               band=data["band"], meta=data["meta"])


def _spread(plan, case, data, solvers, solve, say) -> dict:
    """Each other solver at the case's own settings against the reference, per stage
    and check (relative to the stage's scale, as the verdict judges)."""
    from wearcheck.studies import compare as cmp
    ref = as_reference(data, case)
    out = {}
    for name in solvers:
        reason = registry.get(name).supports(case)
        if reason is not None:
            out[name] = dict(skipped=reason)
            continue
        c = case
        if case.end_distance is None and case.fretting is None:
            # the stages the reference covers (its last stored one is before the end)
            per_m = ref.scales["s_hat_per_m"]
            c = case.derive({"stages.s_hat": [s for s in case.stages.s_hat
                                              if s / per_m <= ref.last_s * (1 + 1e-9)]})
        t0 = time.perf_counter()
        res = solve(c, name)
        seconds = time.perf_counter() - t0
        say(f"  {plan.name} spread {name}: {seconds:.1f} s")
        stage_s = [s for s in res.stage_s if ref.covers(s)]
        ref_run = ref.run_result(stage_s)
        m = cmp.analyse(c, {"reference": ref_run,
                            name: dataclasses.replace(res, stage_s=np.asarray(stage_s),
                                                      f=np.asarray(res.f)[:len(stage_s)],
                                                      p=np.asarray(res.p)[:len(stage_s)])},
                        "reference")
        pair = m["pairs"][name]
        out[name] = dict(seconds=seconds, settings=_settings(c, name),
                         s_hat=[st["s_hat_reference"] for st in pair["stages"]],
                         checks={ch: [st["checks"][ch]["value"] for st in pair["stages"]]
                                 for ch in pair["stages"][0]["checks"]} if pair["stages"]
                         else {},
                         passed=pair["passed"], approximate=res.info.get("approximate"))
    return out


def _settings(case, solver) -> dict:
    entry = registry.get(solver)
    if entry.resolution_key is None:
        return {}
    section, key = entry.resolution_key.split(".")
    return {entry.resolution_key: getattr(getattr(case, section), key),
            "sliding.scheme": case.sliding.scheme, "sliding.tolerance": case.sliding.tolerance}


def _mdr_check(plan, case, data, solve, say) -> dict:
    """The MDR at growing N against the closed form: force, contact radius and
    interior pressure errors, and their observed orders."""
    ref = as_reference(data, case)
    sc = ref.scales
    rows = []
    for n in plan.mdr_check_levels:
        c = case.derive({"mdr.elements": n})
        res = solve(c, "mdr")
        F = float(res.history["force"][0])
        a = float(res.history["contact_radius"][0])
        r = np.asarray(res.r, float)
        p_ref = data["closed_pressure"](r)     # the closed form itself, not its samples
        mask = interior_mask(case, r / ref.stage_a[0], ref.stage_a[0], case.compare.edge_band)
        rows.append(dict(elements=n, force=abs(F - ref.history["force"][0]) / sc["F0"],
                         contact_radius=abs(a - ref.history["contact_radius"][0]) / sc["a0"],
                         pressure=float(np.max(np.abs(res.p[0] - p_ref)[mask])) / sc["p0"]))
        rows[-1] = {k: float(v) for k, v in rows[-1].items()}
        say(f"  {plan.name} mdr N = {n}: {rows[-1]}")
    orders = {}
    for q in ("force", "contact_radius", "pressure"):
        e = np.array([row[q] for row in rows])
        n = np.array([row["elements"] for row in rows], float)
        good = e > 0
        orders[q] = float(-np.polyfit(np.log(n[good]), np.log(e[good]), 1)[0]) \
            if good.sum() >= 2 else math.nan
    return dict(levels=rows, orders=orders)
