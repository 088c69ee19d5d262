"""``bem.solve(case)``: the boundary-element wear run of one case."""

from __future__ import annotations

import math
import time

import numpy as np
from scipy import optimize

from wearcheck.cases import (CaseError, RunResult, dundurs_beta, profiles, programme, reference,
                             validity)

from . import moving, track, wear
from .operator import HalfSpace
from .tangential import ShearToNormal

#: implicit Euler's and BDF2's step in ŝ when sliding.step_hat = "auto": the
#: MDR's, because the BEM's time error is the same ODE's (docs/performance.md,
#: "Measurements behind the code")
IMPLICIT_STEP_HAT = 0.1
BDF2_STEP_HAT = 0.1
#: fewest pixels across the unworn contact radius
MIN_PIXELS_IN_CONTACT = 4


def largest_contact_radius(case, sc: dict) -> float:
    """The largest contact radius the run can reach [m] (the box is sized on it).

    Depth control: the radius where the unworn profile reaches the depth d,
    the edge of the completely worn contact max(f, d) (√2·a0 for a
    paraboloid; the long semi-axis √(2 R_max d) for the ellipsoid). Force
    control: the radius of the flat scar that holds the volume worn at the end,
    V = K F s (at least the unworn contact).
    """
    ind, ld = case.indenter, case.loading
    if ind.profile == "ellipsoid":
        r_big = max(ind.radius, ind.radius_y)
        c = reference.hertz_elliptical(case.E_star, ind.radius, ind.radius_y,
                                       **{ld.control: getattr(ld, ld.control)})
        a_long = max(c["semi_axis_x"], c["semi_axis_y"])
        if ld.control == "depth":
            return math.sqrt(2.0 * r_big * ld.depth)
        volume = case.wear_rate * ld.force * (case.end_distance or 0.0)
        # an elliptic paraboloid holds V = π √(R1 R2) h² below the level h
        level = math.sqrt(volume / (math.pi * profiles.equivalent_radius(ind)))
        return max(a_long, math.sqrt(2.0 * r_big * level))

    def f(r):
        return float(profiles.height(ind, r, case.table))

    def beyond(level):
        hi = sc["a0"]
        while f(hi) < level:
            hi *= 2.0
            if hi > 1e6 * sc["a0"]:
                raise CaseError("the profile does not rise to the depth within 10^6 a0; "
                                "the BEM box cannot be sized")
        return optimize.brentq(lambda r: f(r) - level, 0.0, hi, xtol=1e-12 * hi)

    if ld.control == "depth":
        return max(sc["a0"], beyond(ld.depth))
    if case.wear.pressure_exponent != 1.0 and ind.profile in ("sphere", "paraboloid"):
        # V = K F s holds for n = 1 only; the long-run asymptote from a0 sizes the scar
        return max(sc["a0"], reference.predicted_scar_radius(case, case.end_distance or 0.0))
    # n != 1 on other profiles: V = K F s as an estimate (exact for n = 1); a
    # scar that outgrows the box stops the run with a clear error (bem.box)
    volume = case.wear_rate * ld.force * (case.end_distance or 0.0)
    if volume <= 0.0:
        return sc["a0"]

    def held(level):
        rl = beyond(level)
        r = np.linspace(0.0, rl, 2001)
        return float(np.trapezoid(2.0 * np.pi * r * np.maximum(level - profiles.height(
            ind, r, case.table), 0.0), r))
    hi = sc["d0"]
    while held(hi) < volume:
        hi *= 2.0
    level = optimize.brentq(lambda h: held(h) - volume, 0.0, hi, xtol=1e-12 * hi)
    return max(sc["a0"], beyond(level))


def grid(case, sc: dict, a_max: float | None = None,
         holds: str = "") -> tuple[np.ndarray, float, float]:
    """Pixel-centre coordinates (n,), pixel side Δ and the largest contact radius.

    The pixel n // 2 is centred on the tip, x_i = (i - n//2) Δ, Δ = box·a_max/n.
    ``a_max``: the radius the box must hold (default: the largest contact radius of
    the run); ``holds``: what it holds, for the message (the both-bodies track).
    """
    n = case.bem.grid
    if a_max is None:
        a_max = largest_contact_radius(case, sc)
    dx = case.bem.box * a_max / n
    a_small = sc["a0"]
    if case.indenter.profile == "ellipsoid":
        c = reference.unworn_contact(case)
        a_small = min(c["semi_axis_x"], c["semi_axis_y"])
    if a_small / dx < MIN_PIXELS_IN_CONTACT:
        need = math.ceil(MIN_PIXELS_IN_CONTACT * case.bem.box * a_max / a_small)
        raise CaseError(f"key 'bem.grid' = {n}: only {a_small / dx:.1f} pixels span the unworn "
                        f"contact radius{holds}; at least {MIN_PIXELS_IN_CONTACT} are needed, "
                        f"i.e. bem.grid >= {need}")
    x = (np.arange(n) - n // 2) * dx
    return x, dx, a_max


def ring_average(values: np.ndarray, ring: np.ndarray, rings: int) -> np.ndarray:
    """Mean of ``values`` over the rings (ring index per pixel), for rings 0..rings-1."""
    inside = ring < rings
    total = np.bincount(ring[inside], values[inside], minlength=rings)
    count = np.bincount(ring[inside], minlength=rings)
    return total / np.maximum(count, 1)


def ring_radii(rho: np.ndarray, ring: np.ndarray, rings: int) -> np.ndarray:
    """The radius each ring's average stands for: the root-mean-square ρ of its pixels.

    A ring average of f = c ρ² is c·mean(ρ²), the value at this radius exactly
    (ring 1, the pixels at ρ = Δ and √2 Δ, has mean ρ² = 1.5 Δ²; placed at Δ
    it read 1.5 times the paraboloid there). For a smooth f the offset left is
    (f'' − f'/ρ)·var(ρ)/2, var(ρ) ≈ Δ²/12 within a ring.
    """
    return np.sqrt(ring_average(rho**2, ring, rings))


def coupling(case, n: int, dx: float) -> tuple[wear.Coupling | None, dict | str]:
    """The normal–tangential coupling of ``bem.coupling`` and its description for ``info``.

    None when the key is off or β = 0 (elastically similar: nothing to couple).
    """
    if not case.bem.coupling:
        return None, "off"
    beta = dundurs_beta(case.indenter, case.counterface)
    if beta == 0.0:
        return None, "on, without effect: Dundurs' beta = 0 (elastically similar bodies)"
    reciprocating = case.sliding.stroke is not None
    return (wear.Coupling(shear=ShearToNormal(n, dx, beta, case.E_star), mu=case.wear.mu,
                          reciprocating=reciprocating),
            dict(beta=beta, mu=case.wear.mu, beta_mu=beta * case.wear.mu,
                 sliding="reciprocating: strokes along +x and -x, the wear their mean; the "
                         "stored pressure is the +x stroke's (the -x stroke's is its mirror "
                         "image)" if reciprocating else
                         "one direction: the counterface slides along +x relative to the "
                         "worn body",
                 note="friction traction mu*p along the sliding direction moves the surface "
                      "normally by beta/(pi E*) * (tau_x conv x/rho^2), iterated with the "
                      "contact solve (docs/bem-tangential.md section 6)"))


def supports(case) -> str | None:
    """None when the BEM can run ``case``, else why not.

    It solves every profile (axisymmetric or the ellipsoid) against either
    counterface, in gross slip, with any pressure exponent of the wear law;
    not fretting (partial slip).
    """
    if case.counterface.wears:       # both bodies wearing: bem.track, bem.moving
        return (moving if case.bem.track_model == "moving" else track).supports(case)
    if getattr(case, "fretting", None) is not None:
        return ("the BEM's wear run is gross slip only: its partial-slip solver "
                "(bem.tangential) solves a fretting cycle on a given profile without wear "
                "(benchmarks/bench_fretting_3d.py compares it with the MDR); for a fretting "
                "wear run use the MDR")
    return None


def solve(case, progress=None) -> RunResult:
    """Run the BEM wear simulation of ``case`` (see :mod:`bem`)."""
    if case.counterface.wears:
        return (moving if case.bem.track_model == "moving" else track).solve(case, progress)
    reason = supports(case)
    if reason is not None:
        raise CaseError(reason)
    t0 = time.perf_counter()
    sc = reference.scales(case)
    per_m = sc["s_hat_per_m"]
    sl, bem = case.sliding, case.bem
    validity.check_planned(case)   # before the box is sized on the predicted scar
    x, dx, a_max = grid(case, sc)
    n = len(x)
    X, Y = np.meshgrid(x, x, indexing="ij")
    f0 = profiles.height_xy(case.indenter, X, Y, case.table)
    f0 -= f0[n // 2, n // 2]
    op = HalfSpace(n, dx, case.E_star)
    coupled, coupling_info = coupling(case, n, dx)
    d_scale = case.loading.depth if case.loading.control == "depth" else sc["d0"]
    model = wear.Model(op=op, f0=f0, wear_rate=case.wear_rate, depth=case.loading.depth,
                       force=case.loading.force, p_scale=sc["p0"], g_scale=d_scale,
                       tol=bem.tolerance, centre=(n // 2, n // 2),
                       exponent=case.wear.pressure_exponent, hardness=case.wear.hardness,
                       coupling=coupled)
    limit_hat = wear.explicit_limit(op, case.wear_rate) * per_m
    if model.exponent != 1.0:
        # the rate's derivative n (p/σ0)^(n-1) scales the stiffness; bounded at
        # 1.5 p0 as in the MDR
        limit_hat /= float(wear.wear_speed_slope(model, np.array([1.5 * sc["p0"]]))[0])
    info = dict(solver="bem", grid=n, pixel=dx, box_side=n * dx, largest_contact_radius=a_max,
                scheme=sl.scheme, tolerance=bem.tolerance,
                explicit_limit_step_hat=float(limit_hat),
                operator="own DC-FFT on scipy.fft (Love 1929 pixel coefficients, zero-padded "
                         "to 2N)",
                contact_solver="preconditioned constrained CG (Polonsky-Keer)",
                tangential_correction=("not modelled: wear.tangential_correction = "
                                       f"{str(case.wear.tangential_correction).lower()} ignored")
                if case.wear.tangential_correction else "off",
                coupling=coupling_info)
    if sl.scheme == "explicit":
        step_hat = 0.5 * limit_hat if sl.step_hat == "auto" else float(sl.step_hat)
        if step_hat > limit_hat:
            raise CaseError(
                f"key 'sliding.step_hat' = {sl.step_hat!r}: past the stability limit of "
                f"explicit Euler on this grid; the largest stable step is {limit_hat:.4g} "
                f"(pixel {dx:.3g} m, bem.grid = {n}); use a smaller step or "
                "sliding.scheme = \"implicit\"")
    elif sl.scheme == "adaptive":
        step_hat = math.inf if sl.step_hat == "auto" else float(sl.step_hat)
    else:
        auto = IMPLICIT_STEP_HAT if sl.scheme == "implicit" else BDF2_STEP_HAT
        step_hat = auto if sl.step_hat == "auto" else float(sl.step_hat)
    info["step_hat"] = float(step_hat) if math.isfinite(step_hat) else "unlimited"
    plan, until = programme.stepping_plan(case, step_hat, sc)
    rho = np.hypot(X, Y)
    ring = np.rint(rho / dx).astype(np.int64)
    rings = n // 2                      # whole rings inside the box
    r = ring_radii(rho, ring, rings)
    watch = validity.BodyWatch(case, spacing=dx)
    out = wear.run(model, plan, progress, ring=(ring, rings, r), watch=watch)
    if watch.remarks:
        info["warnings"] = watch.remarks
    hist = programme.finish_history(case, out["history"], until, plan.end, per_m)

    # stages: azimuthal averages on rings one pixel wide, the full fields, anisotropy
    K = len(out["stages"])
    f_avg, p_avg = np.zeros((K, rings)), np.zeros((K, rings))
    fields = {k: np.zeros((K, n, n)) for k in ("profile", "wear_depth", "pressure", "gap")}
    aniso = dict(s_hat=[], pressure=[], pressure_interior=[], wear=[])
    inside = ring < rings
    ring_in = np.where(inside, ring, 0)
    for k, (s, f, p, gap, _d) in enumerate(out["stages"]):
        w = f - f0
        f_avg[k] = ring_average(f, ring, rings)
        p_avg[k] = ring_average(p, ring, rings)
        w_avg = ring_average(w, ring, rings)
        fields["profile"][k], fields["wear_depth"][k] = f, w
        fields["pressure"][k], fields["gap"][k] = p, gap
        aniso["s_hat"].append(s * per_m)
        aniso["pressure"].append(float(np.max(np.abs(p - p_avg[k][ring_in])[inside])) / sc["p0"])
        # rings wholly in contact (the edge rings mix loaded and free pixels)
        full = np.bincount(ring[inside], (p > 0)[inside], minlength=rings) == \
            np.bincount(ring[inside], minlength=rings)
        interior = inside & full[ring_in] & (p > 0)
        aniso["pressure_interior"].append(
            float(np.max(np.abs(p - p_avg[k][ring_in])[interior], initial=0.0)) / sc["p0"])
        aniso["wear"].append(float(np.max(np.abs(w - w_avg[ring_in])[inside])) / d_scale)
    fields["x"] = x.copy()
    fields["y"] = x.copy()
    info["anisotropy"] = dict(
        aniso, note="largest |value - its ring average| over the box per stage: pressure "
                    "over p0 (pressure_interior: on the rings wholly in contact), wear depth "
                    "over d (d0 under force control)")
    counters = out["counters"]
    counters.pop("F_start")
    info.update(counters, operator_applications=op.applications,
                single_precision_applications=op.single_applications,
                max_complementarity_residual=float(np.max(hist["complementarity_residual"])))
    if progress is not None:
        progress(1.0, "done")
    return RunResult(history=hist, stage_s=np.array([st[0] for st in out["stages"]]),
                     r=r, f=f_avg, p=p_avg, solve_seconds=time.perf_counter() - t0, info=info,
                     fields=fields)
