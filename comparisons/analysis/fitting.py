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

from wearcheck.cases import reference
from wearcheck.comparisons.analysis import scar

#: the quantities a ball's measurements may hold, and the long-run growth of each
#: with sliding (worn sphere under a constant force: b ∝ s^(1/(2(n+1)))):
#: exponents of b in D = 2b, V = π b⁴/4R, h = b²/2R
QUANTITIES = ("scar_diameter", "ball_volume", "wear_center")
#: how each quantity is named in tables, and its SI unit
LABELS = {"scar_diameter": ("scar diameter D", "m"), "ball_volume": ("ball volume V", "m^3"),
          "wear_center": ("central wear depth h", "m")}
_B_POWER = {"scar_diameter": 1.0, "ball_volume": 4.0, "wear_center": 2.0}
#: the 95 % level of every interval
LEVEL = 0.95
#: the level below which a goodness-of-fit p-value says the model does not fit
MISFIT_P = 0.01


# -- the model's curves --------------------------------------------------------

@dataclass(frozen=True)
class Curves:
    """The measured quantities against ŝ from one forward run at exponent n.

    ``s_hat`` (M,) increasing and positive; ``values[name]`` (M,) positive.
    Read with :meth:`__call__`: inside the run a monotone cubic (PCHIP) in
    ln ŝ – ln y; below it the start of wear (the scar the unworn contact,
    volume and depth ∝ ŝ); beyond it the long-run power law
    y ∝ ŝ^(p/(2(n+1))) (p = 1, 4, 2 for D, V, h).
    """

    s_hat: np.ndarray
    values: dict
    exponent: float

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
        if name != "scar_diameter":   # V, h ∝ ŝ at the start of wear
            y = np.where(below, y + (x - lo), y)
        slope = _B_POWER[name] / (2.0 * (self.exponent + 1.0))
        y = np.where(above, y + slope * (x - hi), y)
        return np.exp(y)


@dataclass(frozen=True)
class ExponentCurves:
    """Curves at several exponents n (increasing, at least 4), read between them by a
    cubic spline across n of ln y (:func:`predict_between`)."""

    exponents: np.ndarray
    curves: tuple


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
    """The χ² test: p = P(χ²_dof ≥ χ²)."""
    p = float(scipy.stats.chi2.sf(chi2, dof)) if dof > 0 else float("nan")
    return dict(test="chi2", statistic=chi2, dof=dof, p_value=p,
                reduced_chi2=chi2 / dof if dof > 0 else float("nan"),
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
                    fits=True, note=f"needs at least {n_parameters + 3} measurements")
    F = max(rss_model - rss_trend, 0.0) / 2.0 / (rss_trend / dof) if rss_trend > 0 else math.inf
    p = float(scipy.stats.f.sf(F, 2, dof))
    return dict(test="trend", statistic=F, dof=[2, dof], p_value=p, fits=not (p < MISFIT_P))


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
                goodness_of_fit=_goodness(data, s_min, trend, 1))


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
                goodness_of_fit=_goodness(data, s_min, trend, 2))


def _goodness(data: Data, s_min: float, trend, n_parameters: int) -> dict:
    """χ² test with uncertainties; the trend F-test (``trend()`` its RSS) without."""
    if data.weighted:
        return chi2_test(s_min, len(data) - n_parameters)
    if len(data) - n_parameters - 2 <= 0:
        return trend_test(data, s_min, s_min, n_parameters)
    return trend_test(data, s_min, min(trend(), s_min), n_parameters)
