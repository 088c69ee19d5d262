"""Least-squares fits of wear coefficients to measurements, with profile-likelihood intervals.

Pure numerics, arrays in and out (``wearcheck.studies.fit`` runs the model
and reads the measurements).

**The structure used.** The wear law dw/ds = K σ0 (p/σ0)ⁿ with a quasi-static
contact makes the worn state a function of K·s alone at a fixed exponent n:
w(s; K) = W(K·s). One forward run in the dimensionless sliding
ŝ = K E* s/a0 therefore gives every measured quantity as a function of ŝ
(:class:`Curves`), and the prediction for any K is that curve read at
ŝᵢ = K E* sᵢ/a0: a fit over K needs one run. With n free, one run per n on a
grid, the predictions interpolated across n (:class:`ExponentCurves`).

**The statistics.** With uncertainties σᵢ the misfit is χ² = Σ((yᵢ − mᵢ)/σᵢ)²,
the interval of a parameter {θ: χ²_profile(θ) − χ²_min ≤ 3.84} (the profile
likelihood, Wilks) and the goodness of fit the χ² test with N − P degrees of
freedom. Without them the errors are taken as relative, with one unknown
scatter: rᵢ = ln yᵢ − ln mᵢ, and the interval is the profile-t interval of
nonlinear regression, {θ: RSS_profile(θ) ≤ RSS_min (1 + F₁,ν(0.95)/ν)},
ν = N − P (Bates & Watts 1988, §6.1; exact for a model linear in θ); the
goodness of fit is the F-test of the nested model with a trend
ln yᵢ = ln mᵢ + β0 + β1 ln sᵢ (a wrong wear law shows as a trend of the
residuals with sliding distance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy

from wearcheck.cases import both_bodies, reference
from wearcheck.comparisons.analysis import scar, track

#: the quantities a ball's measurements may hold, and the long-run growth of each
#: with sliding (worn sphere under a constant force: b ∝ s^(1/(2(n+1)))):
#: exponents of b in D = 2b, V = π b⁴/4R, h = b²/2R
BALL_QUANTITIES = ("scar_diameter", "ball_volume", "wear_center")
#: the counterface's track (both bodies wearing: the BEM's long-stroke model)
TRACK_QUANTITIES = ("track_width", "track_depth", "track_area", "track_volume")
QUANTITIES = BALL_QUANTITIES + TRACK_QUANTITIES
#: how each quantity is named in tables, and its SI unit
LABELS = {"scar_diameter": ("scar diameter D", "m"), "ball_volume": ("ball volume V", "m^3"),
          "wear_center": ("central wear depth h", "m"),
          "track_width": ("track width w", "m"), "track_depth": ("track depth", "m"),
          "track_area": ("track cross-section A", "m^2"),
          "track_volume": ("track volume", "m^3")}
_B_POWER = {"scar_diameter": 1.0, "ball_volume": 4.0, "wear_center": 2.0}
#: the widths: at the start of wear the unworn contact's (constant in ŝ); every other
#: quantity grows ∝ ŝ there (the unworn contact's pressure wears both bodies)
_WIDTHS = ("scar_diameter", "track_width")
#: the 95 % level of every interval
LEVEL = 0.95
#: the level below which a goodness-of-fit p-value says the model does not fit
MISFIT_P = 0.01
#: the false-alarm rate of the outlier check over all the measurements together: each
#: one's studentized residual is tested two-sided at OUTLIER_P/N (Bonferroni)
OUTLIER_P = 0.01
#: and a measurement within 2 % of the model is never called an outlier: the model reads
#: the scar's edge between nodes (0.2-1 % of D on the shipped grids), so noise-free data
#: leave residuals of that size whose studentized values mean nothing; a microscope
#: reads a scar to 2-3 %
OUTLIER_FLOOR = 0.02


# -- the model's curves --------------------------------------------------------

@dataclass(frozen=True)
class Curves:
    """The measured quantities against ŝ from one forward run at exponent n.

    ``s_hat`` (M,) increasing and positive; ``values[name]`` (M,) positive.
    Read with :meth:`__call__`: inside the run a monotone cubic (PCHIP) in
    ln ŝ – ln y; below it the start of wear (the widths the unworn contact's,
    volumes, depths and areas ∝ ŝ); beyond it, with ``tail = "law"`` (the
    ball alone), the long-run power law y ∝ ŝ^(p/(2(n+1))) (p = 1, 4, 2 for D,
    V, h); with ``tail = "local"`` (both bodies wearing, no such law) the
    power law of the run's last step.
    """

    s_hat: np.ndarray
    values: dict
    exponent: float
    tail: str = "law"

    def __post_init__(self):
        s = np.asarray(self.s_hat, float)
        if s.ndim != 1 or len(s) < 4 or not np.all(s > 0) or not np.all(np.diff(s) > 0):
            raise ValueError("s_hat must hold at least 4 increasing positive values")
        for name, y in self.values.items():
            if name not in QUANTITIES or np.shape(y) != s.shape or not np.all(np.asarray(y) > 0):
                raise ValueError(f"values[{name!r}] must be positive, one per s_hat")
        object.__setattr__(self, "_fits", {
            name: scipy.interpolate.PchipInterpolator(np.log(s), np.log(np.asarray(y, float)))
            for name, y in self.values.items()})

    @property
    def top(self) -> float:
        """The largest ŝ the run reached."""
        return float(self.s_hat[-1])

    def __call__(self, name: str, s_hat) -> np.ndarray:
        """``name`` at dimensionless sliding ``s_hat`` (> 0)."""
        s_hat = np.asarray(s_hat, float)
        x = np.log(s_hat)
        lo, hi = math.log(self.s_hat[0]), math.log(self.s_hat[-1])
        y = self._fits[name](np.clip(x, lo, hi))
        below, above = x < lo, x > hi
        if name not in _WIDTHS:   # V, h, the track's depth and area ∝ ŝ at the start of wear
            y = np.where(below, y + (x - lo), y)
        if self.tail == "law":
            slope = _B_POWER[name] / (2.0 * (self.exponent + 1.0))
        else:
            ln_s, ln_y = np.log(self.s_hat[-2:]), np.log(np.asarray(self.values[name][-2:], float))
            slope = float((ln_y[1] - ln_y[0]) / (ln_s[1] - ln_s[0]))
        y = np.where(above, y + slope * (x - hi), y)
        return np.exp(y)


@dataclass(frozen=True)
class ExponentCurves:
    """Curves at several exponents n (increasing, at least 4), read between them by a
    cubic spline across n of ln y (:func:`predict_between`)."""

    exponents: np.ndarray
    curves: tuple


@dataclass(frozen=True)
class RatioCurves:
    """Both bodies wearing (n = 1, a constant force): curves at several ratios
    ρ = K_flat/K_ball (``log_ratios`` ln ρ, increasing, at least 4), each against
    ŝ = K_ball E* s/a0, read between them by a cubic spline across ln ρ of ln y
    (:func:`predict_rates`).

    Scaling both rates by c is scaling s by c (each body wears by K_body ∫ p ds
    from the same contact), so at a fixed ratio the worn state is a function of
    K_ball·s: one run per ratio serves every overall scale.
    """

    log_ratios: np.ndarray
    curves: tuple

    def __post_init__(self):
        # the spline is linear in the values it interpolates: its cardinal functions,
        # built once, give it at any ln ρ as weights on the runs' values
        object.__setattr__(self, "_cardinal", scipy.interpolate.CubicSpline(
            np.asarray(self.log_ratios, float), np.eye(len(self.curves)), axis=0))

    def weights(self, log_ratio: float) -> np.ndarray:
        """The spline's weights on the runs at ln ρ = log_ratio: Σ_j w_j y_j is the
        not-a-knot cubic spline through (ln ρ_j, y_j) there."""
        return self._cardinal(log_ratio)


# -- the misfit -----------------------------------------------------------------

@dataclass(frozen=True)
class Data:
    """Measurements: sliding distance s [m], quantity name, value y and uncertainty σ
    (NaN for none; either all or none), in SI."""

    s: np.ndarray
    quantity: np.ndarray
    y: np.ndarray
    sigma: np.ndarray

    def __post_init__(self):
        # which entries hold which quantity, once (predict reads them at every call)
        names = np.asarray(self.quantity)
        object.__setattr__(self, "groups", tuple((str(q), names == q) for q in np.unique(names)))

    @property
    def weighted(self) -> bool:
        return bool(np.all(np.isfinite(self.sigma)))

    def __len__(self) -> int:
        return len(self.y)


def predict(curves: Curves, data: Data, log_K: float, s_hat_per_K_m: float) -> np.ndarray:
    """The model's value of each measurement at K = exp(log_K).

    ``s_hat_per_K_m`` = E*/a0: ŝ per unit K·s [1/(m·(m³/(N m)))].
    """
    s_hat = math.exp(log_K) * s_hat_per_K_m * data.s
    out = np.empty(len(data))
    for name, at in data.groups:
        out[at] = curves(name, s_hat[at])
    return out


def predict_between(family: ExponentCurves, data: Data, log_K: float, n: float,
                    s_hat_per_K_m: float) -> np.ndarray:
    """The prediction at an exponent between the runs': a cubic spline across n of
    ln m (not-a-knot), from each run's prediction at the same K."""
    logs = np.array([np.log(predict(c, data, log_K, s_hat_per_K_m)) for c in family.curves])
    return np.exp(scipy.interpolate.CubicSpline(family.exponents, logs, axis=0)(n))


def predict_rates(family: RatioCurves, data: Data, log_K_ball: float, log_K_flat: float,
                  s_hat_per_K_m: float) -> np.ndarray:
    """Both bodies wearing: the prediction at K_ball = exp(log_K_ball) and K_flat =
    exp(log_K_flat), a cubic spline across ln ρ (not-a-knot) of ln m, from each run's
    prediction at the same K_ball."""
    return _across_ratios(family, data, log_K_ball, s_hat_per_K_m)(log_K_flat - log_K_ball)


def _across_ratios(family: RatioCurves, data: Data, log_K_ball: float, s_hat_per_K_m: float):
    """r -> the prediction at ln ρ = r and this K_ball (the runs read once)."""
    logs = np.array([np.log(predict(c, data, log_K_ball, s_hat_per_K_m))
                     for c in family.curves])
    return lambda r: np.exp(family.weights(r) @ logs)


def residuals(data: Data, model: np.ndarray) -> np.ndarray:
    """(y − m)/σ with uncertainties, ln y − ln m without."""
    if data.weighted:
        return (data.y - model) / data.sigma
    return np.log(data.y) - np.log(model)


def misfit(data: Data, model: np.ndarray) -> float:
    """χ² (with uncertainties) or the residual sum of squares of ln y (without)."""
    r = residuals(data, model)
    return float(r @ r)


def threshold(data: Data, s_min: float, n_parameters: int) -> float:
    """The misfit at the edge of a 95 % interval of one parameter.

    χ²_min + χ²₁(0.95) with uncertainties; RSS_min (1 + F₁,ν(0.95)/ν), ν = N − P,
    without (the profile-t interval).
    """
    if data.weighted:
        return s_min + float(scipy.stats.chi2.ppf(LEVEL, 1))
    dof = len(data) - n_parameters
    return s_min * (1.0 + float(scipy.stats.f.ppf(LEVEL, 1, dof)) / dof)


# -- one-dimensional minimum and profile intervals ------------------------------

def minimise(f, lo: float, hi: float, points: int = 81) -> tuple[float, float]:
    """(x, f(x)) at the smallest f on [lo, hi]: a grid, then Brent's method in the
    best cell (f need not be unimodal across the whole range)."""
    xs = np.linspace(lo, hi, points)
    fs = np.array([f(x) for x in xs])
    i = int(np.argmin(fs))
    a, b = xs[max(i - 1, 0)], xs[min(i + 1, points - 1)]
    if b <= a:
        return float(xs[i]), float(fs[i])
    res = scipy.optimize.minimize_scalar(f, bounds=(a, b), method="bounded",
                                         options=dict(xatol=1e-10 * max(1.0, abs(xs[i]))))
    if res.fun <= fs[i]:
        return float(res.x), float(res.fun)
    return float(xs[i]), float(fs[i])


def crossing(f, x_best: float, level: float, bound: float, steps: int = 60) -> float | None:
    """Where ``f`` first rises past ``level`` going from ``x_best`` to ``bound``; None
    when it stays below up to the bound (an open interval)."""
    xs = np.linspace(x_best, bound, steps + 1)
    prev = x_best
    for x in xs[1:]:
        if f(x) > level:
            return float(scipy.optimize.brentq(lambda t: f(t) - level, prev, x,
                                               xtol=1e-10 * max(1.0, abs(x))))
        prev = x
    return None


def interval(f, x_best: float, level: float, lo: float, hi: float):
    """The 95 % interval [a, b] of a profile ``f`` around its minimum; an end that
    the profile does not reach within [lo, hi] is None."""
    return crossing(f, x_best, level, lo), crossing(f, x_best, level, hi)


# -- goodness of fit -------------------------------------------------------------

def chi2_test(chi2: float, dof: int) -> dict:
    """The χ² test: p = P(χ²_dof ≥ χ²); not made (``fits`` None) without a degree of
    freedom."""
    if dof <= 0:
        return dict(test="chi2", statistic=chi2, dof=dof, p_value=float("nan"),
                    reduced_chi2=float("nan"), fits=None, note="needs more measurements "
                    "than parameters")
    p = float(scipy.stats.chi2.sf(chi2, dof))
    return dict(test="chi2", statistic=chi2, dof=dof, p_value=p, reduced_chi2=chi2 / dof,
                fits=not (p < MISFIT_P))


def trend_test(data: Data, rss_model, rss_trend, n_parameters: int) -> dict:
    """F-test of the nested model ln y = ln m + β0 + β1 ln s against the model.

    ``rss_model`` and ``rss_trend`` are the residual sums of squares of the two
    fits (each minimised over the model's parameters); F = ((RSS0 − RSS1)/2) /
    (RSS1/(N − P − 2)) ~ F(2, N − P − 2) when the model holds.
    """
    dof = len(data) - n_parameters - 2
    if dof <= 0:
        return dict(test="trend", statistic=float("nan"), dof=[2, dof], p_value=float("nan"),
                    fits=None, note=f"needs at least {n_parameters + 3} measurements")
    F = max(rss_model - rss_trend, 0.0) / 2.0 / (rss_trend / dof) if rss_trend > 0 else math.inf
    p = float(scipy.stats.f.sf(F, 2, dof))
    return dict(test="trend", statistic=F, dof=[2, dof], p_value=p, fits=not (p < MISFIT_P))


def leverages(data: Data, model_at, theta) -> np.ndarray:
    """The diagonal of the hat matrix J (JᵀJ)⁻¹ Jᵀ of the fit linearised at ``theta``:
    J the derivatives of the residuals by central differences (step 1e-4), ``model_at``
    the model's values at a parameter vector."""
    theta = np.asarray(theta, float)
    h = 1e-4
    cols = []
    for k in range(len(theta)):
        e = np.zeros_like(theta)
        e[k] = h
        up, down = model_at(theta + e), model_at(theta - e)
        cols.append((up - down) / data.sigma / (2 * h) if data.weighted else
                    (np.log(up) - np.log(down)) / (2 * h))
    J = np.column_stack(cols)
    Q, _ = np.linalg.qr(J)
    return np.clip(np.sum(Q**2, axis=1), 0.0, 1.0 - 1e-12)


def outlier_test(data: Data, model: np.ndarray, leverage: np.ndarray,
                 n_parameters: int) -> dict:
    """The externally studentized residuals against the Bonferroni limit.

    With uncertainties zᵢ = rᵢ/√(1 − hᵢ) ~ N(0, 1); without, the scatter estimated
    leaving the measurement out, tᵢ = eᵢ/(s₍ᵢ₎ √(1 − hᵢ)) ~ t(N − P − 1) (exact for a
    model linear in its parameters, Cook & Weisberg 1982). A measurement is flagged
    when |tᵢ| passes the two-sided limit at OUTLIER_P/N (the chance that clean data
    flag any is at most OUTLIER_P) and it is more than OUTLIER_FLOOR from the model. ``tested`` False when there are too few
    measurements (N ≤ P, or N < P + 3 without uncertainties, as the trend test).
    """
    r = residuals(data, model)
    N, dof = len(data), len(data) - n_parameters
    alpha = OUTLIER_P / (2.0 * N)
    if data.weighted:
        if dof < 1:
            return dict(tested=False, note="needs more measurements than parameters")
        t = r / np.sqrt(1.0 - leverage)
        limit = float(scipy.stats.norm.isf(alpha))
    else:
        # (with N − P − 1 = 1 the scatter left out is one residual, and the fit's
        # nonlinearity alone can make it vanish: from 2 on, as the trend test)
        if dof < 3:
            return dict(tested=False, note=f"needs at least {n_parameters + 3} measurements")
        rss = float(r @ r)
        left = np.maximum(rss - r**2 / (1.0 - leverage), 0.0) / (dof - 1)
        with np.errstate(divide="ignore"):
            t = np.where(left > 0, r / np.sqrt(left * (1.0 - leverage)), np.inf * np.sign(r))
        limit = float(scipy.stats.t.isf(alpha, dof - 1))
    gross = np.abs(np.log(data.y) - np.log(model)) > OUTLIER_FLOOR
    flagged = [int(i) for i in np.flatnonzero((np.abs(t) > limit) & gross)]
    return dict(tested=True, statistic="externally studentized residual" if not data.weighted
                else "standardized residual (uncertainties given)",
                values=[float(v) for v in t], limit=limit, false_alarm=OUTLIER_P,
                floor=OUTLIER_FLOOR, flagged=flagged)


def trend_rss(data: Data, model: np.ndarray) -> float:
    """The least residual sum of squares of ln y − ln m − β0 − β1 ln s over β0, β1."""
    r = np.log(data.y) - np.log(model)
    A = np.column_stack([np.ones(len(data)), np.log(data.s)])
    beta, *_ = np.linalg.lstsq(A, r, rcond=None)
    e = r - A @ beta
    return float(e @ e)


# -- the lab's formulas ------------------------------------------------------------

def lab_volume(quantity: str, y, R: float) -> np.ndarray:
    """The ball's worn volume as labs compute it from a rigid sphere cut flat:
    π D⁴/(64 R) from the scar diameter D (ASTM G99/G133, small D/R), π h²(3R − h)/3
    from the cap height h (the central wear), the volume itself when measured."""
    y = np.asarray(y, float)
    if quantity == "scar_diameter":
        return scar.lab_volume(y, R)
    if quantity == "wear_center":
        return math.pi * y**2 * (3.0 * R - y) / 3.0
    return y


def lab_track_volume(quantity: str, y, R: float, sliding) -> np.ndarray:
    """The counterface's worn volume as labs compute it, as if the ball were unworn:
    from the track width w the G133 flat (stroke·A_seg(w, R) plus the ends' cap) or the
    G99 disc (2π R_track·A_seg(w, R)) (:mod:`comparisons.analysis.track`); from the
    depth δ the same groove of sagitta δ over the pass length L; from the
    cross-section A, L·A (a profilometer's reading); the volume itself when measured."""
    y = np.asarray(y, float)
    L = both_bodies.pass_length(sliding)
    if quantity == "track_width":
        if sliding.motion == "unidirectional":
            return track.disc_volume(y, R, sliding.track_radius)
        return track.flat_volume(y, R, sliding.stroke)
    if quantity == "track_depth":
        width = 2.0 * np.sqrt(np.maximum(2.0 * R * y - y**2, 0.0))
        return L * track.segment_area(width, R)
    if quantity == "track_area":
        return L * y
    return y


def lab_rate(V_lab, force: float, s) -> tuple[np.ndarray, float]:
    """The specific wear rates K = V/(F s) of each measurement, and the least-squares
    line V = K·F·s through the origin over all of them."""
    V_lab, Fs = np.asarray(V_lab, float), force * np.asarray(s, float)
    return V_lab / Fs, float(V_lab @ Fs / (Fs @ Fs))


def asymptotic_rate(quantity: str, y, R: float, force: float, s, n: float,
                    hardness: float) -> np.ndarray:
    """K from the long-run worn-paraboloid law (:func:`reference.worn_sphere_asymptote`
    with ``profile="paraboloid"``: b^(2(n+1)) ∝ K s), b from D = 2b, V = π b⁴/4R or
    h = b²/2R: a first guess that sizes the forward run."""
    y = np.asarray(y, float)
    b = (y / 2.0 if quantity == "scar_diameter" else
         (4.0 * R * y / math.pi) ** 0.25 if quantity == "ball_volume" else
         np.sqrt(2.0 * R * y))
    return rate_for_scar(b, R, force, s, n, hardness)


def rate_for_scar(b, R: float, force: float, s, n: float, hardness: float):
    """The K at which the long-run scar radius is b after sliding s (its K·s over s).

    The paraboloid's law, a power law in K·s (the sphere's exact cap needs a
    larger K·s for the same b: the forward runs sized on it stop earlier, as
    :func:`reference.predicted_scar_radius` predicts their scar)."""
    unit = reference.worn_sphere_asymptote(R, force, 1.0, 1.0, exponent=n, hardness=hardness,
                                           profile="paraboloid")["scar_radius"]
    return (np.asarray(b, float) / float(unit)) ** (2.0 * (n + 1.0)) / np.asarray(s, float)


# -- the fits ----------------------------------------------------------------------

def fit_rate(curves: Curves, data: Data, s_hat_per_K_m: float, lo: float, hi: float) -> dict:
    """Fit K at the curves' exponent: ln K in [lo, hi].

    Returns log_K, its 95 % interval (ends None where open within [lo, hi]), the
    least misfit, the model at the estimate and the goodness of fit.
    """
    def S(u):
        return misfit(data, predict(curves, data, u, s_hat_per_K_m))
    u, s_min = minimise(S, lo, hi)
    level = threshold(data, s_min, 1)
    a, b = interval(S, u, level, lo, hi)

    def trend():   # (the trend moves K little: searched within a factor e³ of the estimate)
        return minimise(lambda v: trend_rss(data, predict(curves, data, v, s_hat_per_K_m)),
                        max(lo, u - 3.0), min(hi, u + 3.0), points=31)[1]
    return dict(log_K=u, interval=(a, b), misfit=s_min, level=level,
                model=predict(curves, data, u, s_hat_per_K_m),
                goodness_of_fit=_goodness(
                    data, s_min, trend, 1,
                    lambda t: predict(curves, data, t[0], s_hat_per_K_m), [u]))


def fit_rate_and_exponent(family: ExponentCurves, data: Data, s_hat_per_K_m: float,
                          lo: float, hi: float) -> dict:
    """Fit K and n together: ln K in [lo, hi], n within the family's exponents.

    Started from the best K at each run's exponent, then Nelder–Mead on the
    spline across n; each interval from the profile of its parameter (the other
    minimised). Returns as :func:`fit_rate`, with exponent and exponent_interval.
    """
    ns = np.asarray(family.exponents, float)
    n_lo, n_hi = float(ns[0]), float(ns[-1])

    def S(u, n):
        return misfit(data, predict_between(family, data, u, n, s_hat_per_K_m))
    starts = [minimise(lambda u: misfit(data, predict(cv, data, u, s_hat_per_K_m)), lo, hi,
                       points=121) for cv in family.curves]
    j = int(np.argmin([f for _, f in starts]))
    best = (starts[j][0], float(ns[j]), starts[j][1])
    res = scipy.optimize.minimize(lambda t: S(t[0], t[1]), [best[0], best[1]],
                                  method="Nelder-Mead", bounds=[(lo, hi), (n_lo, n_hi)],
                                  options=dict(xatol=1e-9, fatol=1e-14, maxiter=4000))
    if res.fun < best[2]:
        best = (float(res.x[0]), float(res.x[1]), float(res.fun))
    u, n, s_min = best
    level = threshold(data, s_min, 2)

    def profile_u(v):     # the least misfit at ln K = v, over n
        return minimise(lambda m: S(v, m), n_lo, n_hi, points=25)[1]

    def profile_n(m):     # the least misfit at n = m, over ln K
        return minimise(lambda v: S(v, m), lo, hi, points=61)[1]
    a, b = interval(profile_u, u, level, lo, hi)
    na, nb = interval(profile_n, n, level, n_lo, n_hi)

    def trend():
        t = scipy.optimize.minimize(
            lambda p: trend_rss(data, predict_between(family, data, p[0], p[1], s_hat_per_K_m)),
            [u, n], method="Nelder-Mead", bounds=[(lo, hi), (n_lo, n_hi)],
            options=dict(xatol=1e-9, fatol=1e-14, maxiter=4000))
        return float(t.fun)
    return dict(log_K=u, exponent=n, interval=(a, b), exponent_interval=(na, nb),
                misfit=s_min, level=level,
                model=predict_between(family, data, u, n, s_hat_per_K_m),
                goodness_of_fit=_goodness(
                    data, s_min, trend, 2,
                    lambda t: predict_between(family, data, t[0], t[1], s_hat_per_K_m), [u, n]))


def fit_rates(family: RatioCurves, data: Data, s_hat_per_K_m: float, free: tuple,
              log_K_ball: float, log_K_flat: float, lo: float, hi: float) -> dict:
    """Fit the rates of both bodies wearing, or one of them with the other held.

    Parameters
    ----------
    family : the runs at several ratios ρ = K_flat/K_ball.
    free : the rates fitted, a non-empty subset of ("ball", "flat").
    log_K_ball, log_K_flat : ln K of each (the value of a held one; a free one's is unused).
    lo, hi : the range of ln K_ball searched (when it is free).

    The ratio stays within the family's: ln ρ in [r0, r1]. Each interval is the
    profile of its parameter (the other minimised where free). Returns log_K_ball,
    log_K_flat, intervals {"ball"/"flat": (a, b)} of the free ones (an end None
    where the profile stays below the level within the range: at the end of the
    ratio scan, or of [lo, hi]), ``log_ratios`` (ln ρ at the estimate and at each
    interval end: the study extends its scan where they reach its ends), the least
    misfit, the model at the estimate and the goodness of fit.
    """
    free = tuple(f for f in ("ball", "flat") if f in free)
    if not free:
        raise ValueError("free: at least one of 'ball', 'flat'")
    r0, r1 = float(family.log_ratios[0]), float(family.log_ratios[-1])

    def S(u, r):
        return misfit(data, predict_rates(family, data, u, u + r, s_hat_per_K_m))
    intervals, reached = {}, []
    if free == ("flat",):
        u = log_K_ball
        at_u = _across_ratios(family, data, u, s_hat_per_K_m)

        def S_r(r):
            return misfit(data, at_u(r))
        r, s_min = minimise(S_r, r0, r1)
        level = threshold(data, s_min, 1)
        a, b = interval(S_r, r, level, r0, r1)
        intervals["flat"] = (None if a is None else u + a, None if b is None else u + b)
        reached = [r] + [e if e is not None else (r0 if k == 0 else r1)
                         for k, e in enumerate((a, b))]

        def trend():
            return minimise(lambda x: trend_rss(data, at_u(x)), r0, r1, points=41)[1]

        def model_at(t):
            return at_u(t[0])
        theta = [r]
    elif free == ("ball",):
        v = log_K_flat
        u_lo, u_hi = max(lo, v - r1), min(hi, v - r0)
        if not u_lo < u_hi:
            raise ValueError("the held K_flat leaves no K_ball within the ratio scan")

        def S_u(x):
            return S(x, v - x)
        u, s_min = minimise(S_u, u_lo, u_hi)
        r = v - u
        level = threshold(data, s_min, 1)
        a, b = interval(S_u, u, level, u_lo, u_hi)
        intervals["ball"] = (a, b)
        reached = [r, v - (b if b is not None else u_hi), v - (a if a is not None else u_lo)]

        def trend():
            return minimise(lambda x: trend_rss(data, predict_rates(
                family, data, x, v, s_hat_per_K_m)), max(u_lo, u - 3.0), min(u_hi, u + 3.0),
                points=31)[1]

        def model_at(t):
            return predict_rates(family, data, t[0], v, s_hat_per_K_m)
        theta = [u]
    else:
        starts = []
        for j, cv in enumerate(family.curves):
            x, f = minimise(lambda y: misfit(data, predict(cv, data, y, s_hat_per_K_m)), lo, hi,
                            points=121)
            starts.append((f, x, float(family.log_ratios[j])))
        f0, u, r = min(starts)
        res = scipy.optimize.minimize(lambda t: S(t[0], t[1]), [u, r], method="Nelder-Mead",
                                      bounds=[(lo, hi), (r0, r1)],
                                      options=dict(xatol=1e-9, fatol=1e-14, maxiter=4000))
        s_min = f0
        if res.fun < f0:
            u, r, s_min = float(res.x[0]), float(res.x[1]), float(res.fun)
        level = threshold(data, s_min, 2)

        def profile_ball(x):          # (ln ρ, the least misfit) at ln K_ball = x, over ln ρ
            at_x = _across_ratios(family, data, x, s_hat_per_K_m)
            return minimise(lambda y: misfit(data, at_x(y)), r0, r1, points=25)

        def profile_flat(w):          # (ln ρ, the least misfit) at ln K_flat = w, over K_ball
            a_, b_ = max(lo, w - r1), min(hi, w - r0)
            if not a_ < b_:
                return r0, math.inf
            x, f = minimise(lambda y: S(y, w - y), a_, b_, points=25)
            return w - x, f
        a, b = interval(lambda x: profile_ball(x)[1], u, level, lo, hi)
        intervals["ball"] = (a, b)
        v = u + r
        c_, d_ = interval(lambda w: profile_flat(w)[1], v, level, lo + r0, hi + r1)
        intervals["flat"] = (c_, d_)
        reached = [r]
        for end, edge in ((a, r0), (b, r1)):
            reached.append(profile_ball(end)[0] if end is not None else edge)
        for end, edge in ((c_, r0), (d_, r1)):
            reached.append(profile_flat(end)[0] if end is not None else edge)

        def trend():
            t = scipy.optimize.minimize(
                lambda p: trend_rss(data, predict_rates(family, data, p[0], p[0] + p[1],
                                                        s_hat_per_K_m)),
                [u, r], method="Nelder-Mead", bounds=[(lo, hi), (r0, r1)],
                options=dict(xatol=1e-9, fatol=1e-14, maxiter=4000))
            return float(t.fun)

        def model_at(t):
            return predict_rates(family, data, t[0], t[0] + t[1], s_hat_per_K_m)
        theta = [u, r]
    log_K_flat = u + r
    return dict(log_K_ball=u, log_K_flat=log_K_flat, intervals=intervals,
                log_ratios=[float(x) for x in reached], misfit=s_min, level=level,
                model=predict_rates(family, data, u, log_K_flat, s_hat_per_K_m),
                goodness_of_fit=_goodness(data, s_min, trend, len(free), model_at, theta))


def _goodness(data: Data, s_min: float, trend, n_parameters: int, model_at, theta) -> dict:
    """χ² test with uncertainties; the trend F-test (``trend()`` its RSS) without; and
    with either the outlier test (:func:`outlier_test`; ``model_at`` the model at a
    parameter vector, ``theta`` the estimate).

    ``fits``: False when a test fails, True when the χ² or trend test was made and both
    pass, None when the χ² or trend test could not be made (``fit_tested`` False: too
    few measurements for the parameters) and no outlier was found.
    """
    if data.weighted:
        gof = chi2_test(s_min, len(data) - n_parameters)
    elif len(data) - n_parameters - 2 <= 0:
        gof = trend_test(data, s_min, s_min, n_parameters)
    else:
        gof = trend_test(data, s_min, min(trend(), s_min), n_parameters)
    model = model_at(np.asarray(theta, float))
    out = outlier_test(data, model, leverages(data, model_at, theta), n_parameters)
    gof["outliers"] = out
    # the outlier test where the χ² test is not made (never, as both need N > P) can
    # condemn a fit but not pass one
    gof["fit_tested"] = gof["fits"] is not None
    if out["tested"] and out["flagged"]:
        gof["fits"] = False
    gof["measurements"], gof["parameters"] = len(data), n_parameters
    return gof
