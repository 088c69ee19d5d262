"""``wearcheck fit`` with both bodies wearing: K of the ball and of the counterface, against
the BEM's long-stroke model (:mod:`bem.track`).

The structure used (docs/fitting.md, "Both bodies"): under force control with
n = 1, each body wears by K_body ∫ p ds from the same contact, so scaling both
rates by c is scaling the sliding distance by c. At a fixed ratio
ρ = K_flat/K_ball one run therefore gives every measured quantity against
ŝ = K_ball E* s/a0 for every overall scale, and a fit is a scan over ρ — one
BEM run per ratio, on Dask when a scheduler (or workers) is given — read
between the ratios by a spline across ln ρ (:class:`fitting.RatioCurves`).
The scan starts from the lab formulas' rates and grows (one ratio at a time,
at most :data:`MOST_RATIOS`) until the estimate and every interval end lie
inside it. ``tests/test_fit_track.py`` checks the scaling on the BEM itself.
"""

from __future__ import annotations

import math
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from wearcheck import cases
from wearcheck.cases import CaseError, SolverError, both_bodies, reference
from wearcheck.comparisons.analysis import fitting

from . import fit as ball_fit
from .distributed import Task, run_cases

FLAT = "counterface.specific_rate"
BALL = "wear.specific_rate"
#: the spacing of the ratio scan in ln ρ: a factor 2. The spline across ln ρ then
#: reads the track's depth and the ball's central wear between two runs within
#: 0.7 % (0.2 % past the first stages), measured on ball_on_flat_steel at 80²
#: against runs at the midpoints (docs/fitting.md); a factor 4 doubles that
RATIO_STEP = math.log(2.0)
#: the ratios of the first scan: the lab formulas' ratio and two steps each side
FIRST_RATIOS = 5
#: runs at most (the scan grows by one ratio where the fit reaches its ends)
MOST_RATIOS = 11
#: with K_ball held, the runs reach this factor past the last measurement's ŝ
HELD_MARGIN = 1.05
#: the widths' resolution check runs the ratio nearest the estimate again on this many
#: times the pixels along each side (a finer grid: the widths' reading converges as the
#: pixel shrinks, and it is biased wide on coarse pixels)
FINER_GRID = 1.5
#: the widths' estimated discretisation error, over their smallest relative uncertainty
#: (or scatter), beyond which a note says the resolution matters
WIDTH_ERROR_SHARE = 0.2


def check(case: cases.Case, keys: tuple, data: fitting.Data, source: str) -> tuple[str, ...]:
    """The rates fitted ("ball", "flat"), checked against the case and the data."""
    if case.counterface_wear_rate is None:
        raise CaseError(f"--fit {FLAT}: the case's counterface does not wear; set "
                        "[counterface] wears = true with its specific_rate (the both-bodies "
                        "model, docs/both-bodies.md)")
    if "wear.pressure_exponent" in keys:
        raise CaseError("--fit wear.pressure_exponent: the counterface wears, and the BEM wears "
                        "both bodies by Reye–Archard's law (n = 1) only")
    if case.wear.pressure_exponent != 1.0:
        raise CaseError(f"key 'wear.pressure_exponent' = {case.wear.pressure_exponent!r}: the "
                        "BEM wears both bodies by Reye–Archard's law (n = 1) only")
    if case.bem.track_model != "long_stroke":
        raise CaseError(f"key 'bem.track_model' = \"{case.bem.track_model}\": wearcheck fit runs "
                        "the long-stroke model (the moving contact costs a contact solve per "
                        "pixel of sliding); set bem.track_model = \"long_stroke\"")
    names = set(str(q) for q in data.quantity)
    free = tuple(b for b, key in (("ball", BALL), ("flat", FLAT)) if key in keys)
    if "ball" in free and not names & set(fitting.BALL_QUANTITIES):
        raise CaseError(f"{source}: --fit {BALL} needs a measurement of the ball (scar "
                        "diameter 'D [um]', volume 'V [mm^3]' or central wear 'h [um]'); "
                        "the sheet has only the track's")
    if "flat" in free and not names & set(fitting.TRACK_QUANTITIES):
        raise CaseError(f"{source}: --fit {FLAT} needs a measurement of the track (width "
                        "'track width [um]', depth 'track depth [um]', cross-section "
                        "'track area [um^2]' or volume 'track volume [mm^3]'); the sheet has "
                        "only the ball's")
    return free


# -- the first guesses -----------------------------------------------------------------

def ball_guess(case: cases.Case, data: fitting.Data) -> float:
    """K_ball from the ball's measurements as :func:`fit.first_guess` (the long-run law
    of the ball alone; V = K F s is exact)."""
    keep = np.isin(data.quantity, fitting.BALL_QUANTITIES)
    part = fitting.Data(data.s[keep], data.quantity[keep], data.y[keep], data.sigma[keep])
    return ball_fit.first_guess(case, part, 1.0)


def flat_guess(case: cases.Case, data: fitting.Data) -> float:
    """K_flat from the lab formulas of the track at its last measurement of each quantity,
    their geometric mean: the width's overstates it (the early track is the elastic
    contact's), the depth's understates it (a ball worn flat cuts a shallower groove)."""
    F, R = case.loading.force, case.indenter.radius
    guesses = []
    for q, at in data.groups:
        if q not in fitting.TRACK_QUANTITIES:
            continue
        last = int(np.argmax(np.where(at, data.s, -np.inf)))
        V = float(fitting.lab_track_volume(q, data.y[last:last + 1], R, case.sliding)[0])
        guesses.append(V / (F * data.s[last]))
    return float(np.exp(np.mean(np.log(guesses))))


# -- the model runs ----------------------------------------------------------------------

def forward_changes(case: cases.Case, K_ball: float, log_ratio: float, s_hat_top: float,
                    s_hat_start: float) -> dict:
    """The case changes of the run at ratio exp(log_ratio), K_ball ``K_ball``: sliding to
    ŝ = s_hat_top with stages at :data:`fit.STAGES_PER_DECADE` per decade from
    s_hat_start, adaptive steps."""
    changes = ball_fit.forward_changes(case, 1.0, s_hat_top, s_hat_start)
    del changes["wear.pressure_exponent"]
    sc = reference.scales(case)
    per_m = K_ball * sc["E_star"] / sc["a0"]
    changes.update({BALL: float(K_ball), FLAT: float(K_ball * math.exp(log_ratio)),
                    "sliding.distance": float(s_hat_top / per_m)})
    return changes


def curves_of(history: dict) -> fitting.Curves:
    """Both bodies' measured quantities against ŝ = K_ball E* s/a0 from a run's history."""
    s_hat = np.asarray(history["s_hat"], float)
    keep = (s_hat > 0) & (s_hat > np.maximum.accumulate(np.r_[0.0, s_hat[:-1]]) * (1 + 1e-9))
    column = dict(scar_diameter="scar_radius", ball_volume="wear_volume",
                  wear_center="wear_center", track_width="track_width",
                  track_depth="track_depth", track_area="track_area",
                  track_volume="wear_volume_counterface")
    values = {q: np.asarray(history[c], float)[keep] for q, c in column.items()}
    values["scar_diameter"] = 2.0 * values["scar_diameter"]
    return fitting.Curves(s_hat[keep], values, 1.0, tail="local")


def _run_all(case, tasks, scheduler, workers, quiet) -> list:
    """[(history, info, seconds, worker)] of each (name, changes): on Dask when a
    scheduler or workers are given, else one after another here."""
    if scheduler is None and workers is None:
        out = []
        for name, changes in tasks:
            t = time.perf_counter()
            try:
                result = ball_fit.solve_here(case.derive(changes), quiet, f"bem {name}", "bem")
            except CaseError as exc:
                raise CaseError(f"the fit's model run at K_flat/K_ball = {name[6:]}, to s = "
                                f"{changes['sliding.distance']:.4g} m (past the last "
                                f"measurement, on the first guess of the rates): {exc}") from None
            out.append((result.history, result.info, time.perf_counter() - t, None))
        return out
    scratch = Path(tempfile.mkdtemp(prefix="wearcheck-fit-"))
    try:
        outcomes = run_cases(case, [Task(name=n, solver="bem", changes=c) for n, c in tasks],
                             scratch / "runs", scheduler=scheduler, workers=workers,
                             quiet=quiet, study_files=())
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    failed = [o for o in outcomes if not o.ok]
    if failed:
        raise SolverError(f"the forward run {failed[0].task.name} failed: {failed[0].message}")
    return [(o.result.history, o.result.info, o.wall_seconds, o.worker) for o in outcomes]


# -- the fit -------------------------------------------------------------------------------

def fit(case: cases.Case, data: fitting.Data, rows: list, source: str, keys: tuple, *,
        scheduler=None, workers=None, quiet=True, t0=None) -> "ball_fit.FitResult":
    """Fit K_ball, K_flat or both to ball and track measurements (see the module)."""
    t0 = time.perf_counter() if t0 is None else t0
    free = check(case, keys, data, source)
    P = len(free)
    if not data.weighted and len(data) < P + 1:
        raise CaseError(f"{source}: {len(data)} measurement(s) without uncertainties; the "
                        f"scatter is estimated from them, which needs at least {P + 1} to fit "
                        f"{P} parameter(s) (or give ± uncertainty columns)")
    if data.weighted and len(data) < P:
        raise CaseError(f"{source}: {len(data)} measurement(s) for {P} parameters")
    sc = reference.scales(case)
    c = sc["E_star"] / sc["a0"]
    K_ball = ball_guess(case, data) if "ball" in free else case.wear_rate
    K_flat = flat_guess(case, data) if "flat" in free else case.counterface_wear_rate
    s_min, s_max = float(np.min(data.s)), float(np.max(data.s))
    if "ball" in free:
        top = ball_fit.MARGIN * K_ball * c * s_max
    else:
        top = HELD_MARGIN * K_ball * c * s_max
    start = min(max(ball_fit.S_HAT_START, ball_fit.START_BELOW_GUESS * K_ball * c * s_min),
                top / 10.0)
    centre = math.log(K_flat / K_ball)
    ratios = list(centre + RATIO_STEP * (np.arange(FIRST_RATIOS) - FIRST_RATIOS // 2))
    lo = math.log(1e-6 / (c * s_max))          # ln K_ball searched (when free): as the ball's
    hi = math.log(100.0 * top / (c * s_max))
    curves, runs, notes = {}, [], []
    while True:
        todo = [r for r in ratios if r not in curves]
        tasks = [(f"ratio-{math.exp(r):.4g}", forward_changes(case, K_ball, r, top, start))
                 for r in todo]
        for r, (history, info, seconds, worker) in zip(
                todo, _run_all(case, tasks, scheduler, workers, quiet)):
            curves[r] = curves_of(history)
            runs.append(dict(ratio=math.exp(r), s_hat_end=float(top),
                             steps=int(info.get("steps", 0)), pixel=float(info["pixel"]),
                             seconds=float(seconds), worker=worker))
        grid = sorted(curves)
        family = fitting.RatioCurves(np.array(grid), tuple(curves[r] for r in grid))
        found = fitting.fit_rates(family, data, c, free, math.log(case.wear_rate),
                                  math.log(case.counterface_wear_rate), lo, hi)
        # the estimate and the interval ends half a step inside the scan, or one more run
        below = min(found["log_ratios"]) < grid[0] + 0.5 * RATIO_STEP
        above = max(found["log_ratios"]) > grid[-1] - 0.5 * RATIO_STEP
        if not (below or above):
            break
        if len(curves) >= MOST_RATIOS:
            notes.append(f"the ratio scan stopped at {MOST_RATIOS} runs, K_flat/K_ball in "
                         f"[{math.exp(grid[0]):.4g}, {math.exp(grid[-1]):.4g}], with the fit "
                         "at its end: an interval end there is open")
            break
        if below:
            ratios.append(grid[0] - RATIO_STEP)
        if above and len(curves) + below < MOST_RATIOS:
            ratios.append(grid[-1] + RATIO_STEP)
    resolution = None
    widths = [q for q in WIDTHS if np.any(data.quantity == q)]
    if widths:
        resolution = width_resolution(case, data, found, family, K_ball, top, start, c,
                                      scheduler, workers, quiet)
    reach = max(found["log_K_ball"], (found["intervals"].get("ball") or (0, None))[1]
                or found["log_K_ball"])
    if math.exp(reach) * c * s_max > top * (1 + 1e-9):
        notes.append(f"the fit reads the model beyond its runs' end (ŝ = {top:.4g}): extended "
                     "by the power law of each run's last step")
    return _result(case, keys, free, data, rows, source, found, family, runs, c, notes,
                   resolution, time.perf_counter() - t0)


def _parameter(log_value, interval, key, notes) -> dict:
    a, b = interval
    entry = dict(value=math.exp(log_value), ci95=[math.exp(a) if a is not None else 0.0,
                                                  math.exp(b) if b is not None else None],
                 unit=ball_fit.FIT_KEYS[key])
    if a is None or b is None:
        side = "below" if a is None else "above"
        entry["note"] = (f"the data do not bound it from {side} within the ratio scan "
                         "and the searched range")
        notes.append(f"{key}: {entry['note']}")
    return entry


def _result(case, keys, free, data, rows, source, found, family, runs, c, notes, resolution,
            seconds):
    parameters = {}
    if "ball" in free:
        parameters[BALL] = _parameter(found["log_K_ball"], found["intervals"]["ball"], BALL,
                                      notes)
    if "flat" in free:
        parameters[FLAT] = _parameter(found["log_K_flat"], found["intervals"]["flat"], FLAT,
                                      notes)
    K_ball, K_flat = math.exp(found["log_K_ball"]), math.exp(found["log_K_flat"])
    fitted = case.derive({BALL: K_ball, FLAT: K_flat})
    lab, lab_K = ball_fit.lab_formulas(case, data)
    measurements = ball_fit.measurement_rows(data, rows, found["model"], lab_K)
    gof = found["goodness_of_fit"]
    warning = ball_fit.misfit_warning(gof, rows)
    if warning:
        notes.insert(0, warning)
    if resolution is not None:
        note = width_note(resolution, data, found["model"])
        if note:
            notes.append(note)
    s = np.geomspace(float(np.min(data.s)) / 3.0, float(np.max(data.s)) * 3.0, 200)
    curve = (s, {q: fitting.predict_rates(family, _probe(q, s), found["log_K_ball"],
                                          found["log_K_flat"], c)
                 for q in np.unique(data.quantity).astype(str)})
    model = dict(solver="bem", body="both bodies wearing: the BEM's long-stroke model "
                                    "(bem/track.py), the ball and a groove along its track",
                 grid=case.bem.grid, scheme="adaptive", tolerance=case.sliding.tolerance,
                 runs=runs, ratios=[math.exp(r) for r in family.log_ratios],
                 structure="under force control with n = 1, scaling both K by c is scaling s "
                           "by c: one run per ratio K_flat/K_ball in ŝ = K_ball E* s/a0 gives "
                           "the prediction for every overall scale; between the ratios a "
                           "cubic spline across ln(K_flat/K_ball)",
                 s_hat_per_K_s=c, pass_length=both_bodies.pass_length(case.sliding),
                 held={k: v for k, v in ((BALL, case.wear_rate), (FLAT,
                       case.counterface_wear_rate)) if k not in keys},
                 resolution=resolution if resolution is not None else
                 "the depths, areas and volumes: not checked (they converge at second "
                 "order in the pixel, docs/both-bodies.md); the widths: checked when measured")
    return ball_fit.FitResult(case=case, fitted_case=fitted, keys=keys, parameters=parameters,
                              measurements=measurements, lab=lab, goodness_of_fit=gof,
                              model=model, interval_method=ball_fit.interval_method(data),
                              source=source, seconds=seconds, warnings=notes, curve=curve)


def _probe(quantity: str, s) -> fitting.Data:
    return fitting.Data(s, np.full(len(s), quantity), np.ones(len(s)), np.full(len(s), np.nan))


#: the quantities read as widths (where the wear falls to 10⁻³ of its largest, between
#: pixels): first order in the pixel
WIDTHS = ("scar_diameter", "track_width")


def width_resolution(case, data, found, family, K_ball, top, start, c, scheduler, workers,
                     quiet) -> dict:
    """The widths' reading on a finer grid: the run at the scanned ratio nearest the
    estimate repeated on :data:`FINER_GRID` times the pixels, both read at the
    estimate's K_ball at each measured width. Returns the grids, the ratio, the
    largest relative change of a width and the first-order error estimate
    change/(M/N − 1) (the reading converges at first order in the pixel)."""
    j = int(np.argmin(np.abs(family.log_ratios - (found["log_K_flat"] - found["log_K_ball"]))))
    r = float(family.log_ratios[j])
    N = case.bem.grid
    M = 2 * int(round(FINER_GRID * N / 2))
    changes = dict(forward_changes(case, K_ball, r, top, start), **{"bem.grid": M})
    (history, info, seconds, _), = _run_all(case, [(f"ratio-{math.exp(r):.4g}-grid-{M}",
                                                    changes)], scheduler, workers, quiet)
    fine = curves_of(history)
    widths = np.isin(data.quantity, WIDTHS)
    part = fitting.Data(data.s[widths], data.quantity[widths], data.y[widths],
                        data.sigma[widths])
    coarse_w = fitting.predict(family.curves[j], part, found["log_K_ball"], c)
    fine_w = fitting.predict(fine, part, found["log_K_ball"], c)
    change = fine_w / coarse_w - 1.0
    k = int(np.argmax(np.abs(change)))
    return dict(grid=[N, M], ratio=math.exp(r), seconds=float(seconds),
                largest_change=float(change[k]), at_s=float(part.s[k]),
                quantity=str(part.quantity[k]), error=float(change[k] / (M / N - 1.0)),
                meaning="the widths read at the estimate on the run nearest its ratio, on N "
                        "and on M pixels a side: error = change/(M/N − 1) estimates their "
                        "discretisation error at N (first order); the intervals do not "
                        "include it")


def width_note(resolution: dict, data: fitting.Data, model) -> str | None:
    """A note when the widths' estimated discretisation error passes
    :data:`WIDTH_ERROR_SHARE` of their smallest relative uncertainty (without
    uncertainties: of the residuals' relative scatter, ``model`` the fitted
    model's values), else None."""
    widths = np.isin(data.quantity, WIDTHS)
    if data.weighted:
        scale = float(np.min(data.sigma[widths] / data.y[widths]))
        what = "measured uncertainty"
    else:
        r = fitting.residuals(data, np.asarray(model, float))
        scale = float(np.sqrt(np.mean(r**2)))
        what = "residuals' scatter"
    error = abs(resolution["error"])
    if error <= WIDTH_ERROR_SHARE * scale:
        return None
    N, M = resolution["grid"]
    said = f" against a {what} of {100 * scale:.2g} %"
    return (f"the model's resolution matters for the widths: {resolution['quantity']} moves by "
            f"{100 * resolution['largest_change']:+.2g} % from bem.grid = {N} to {M}, an "
            f"estimated error at {N} of {100 * error:.2g} %{said}, which the intervals do not "
            f"include; raise bem.grid (e.g. --set bem.grid={2 * N}) or fit the depths, "
            "areas and volumes without the width columns")
