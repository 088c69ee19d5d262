"""``wearcheck fit``: wear coefficients of a ball from a measurement sheet, against the MDR.

Reads the measurements (:data:`MEASUREMENTS`, through :mod:`wearcheck.user_tables`),
checks the case and the keys to fit, runs the model (one MDR run with the
exponent n fixed; one per n on a grid, on Dask, with n free), fits by least
squares (:mod:`comparisons.analysis.fitting`), and writes the result as a
``fit`` output directory. Why one run suffices at a fixed n, and which
statistics give the intervals: ``comparisons.analysis.fitting`` and
``docs/fitting.md``.
"""

from __future__ import annotations

import hashlib
import json
import math
import shutil
import tempfile
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wearcheck import cases, layout, registry
from wearcheck.cases import CaseError, RunWarning, SolverError, reference, validity
from wearcheck.comparisons.analysis import fitting
from wearcheck.comparisons.present.fit_report import figure
from wearcheck.comparisons.present.progress import ProgressBar
from wearcheck.mdr import resolution
from wearcheck.outputs import atomic_directory
from wearcheck.rundir import jsonable, provenance
from wearcheck.studies.distributed import Task, run_cases
from wearcheck.numerics.stepping import ADAPTIVE_MAX_S_HAT
from wearcheck.user_tables import Quantity, from_columns, read_table

#: the keys ``fit`` can fit, with their unit
FIT_KEYS = {"wear.specific_rate": "m^3/(N m)", "wear.pressure_exponent": "1",
            "counterface.specific_rate": "m^3/(N m)"}
#: keys refused with a reason
REFUSED_KEYS = {"wear.k": "fit wear.specific_rate, the lab's K; k follows as K·σ0/μ",
                "counterface.k": "fit counterface.specific_rate, the lab's K of the "
                                 "counterface; k follows as K·σ0/μ"}

#: the columns a measurement sheet may hold (the track's need a counterface that wears)
MEASUREMENTS = (
    Quantity("cycles", "count", ("cycle", "n", "number of cycles", "N cycles"),
             "number of cycles (needs sliding.stroke: s = 2·stroke·cycles)"),
    Quantity("s", "length", ("sliding distance", "distance"), "sliding distance"),
    Quantity("scar_diameter", "length", ("D", "scar diameter", "ball scar diameter",
                                         "wear scar diameter", "ball scar"),
             "ball scar diameter"),
    Quantity("ball_volume", "volume", ("V", "ball volume", "volume", "worn volume",
                                       "wear volume", "ball wear volume"),
             "ball worn volume"),
    Quantity("wear_center", "length", ("h", "central wear depth", "wear depth",
                                       "central wear", "ball wear depth"),
             "central wear depth of the ball"),
    Quantity("track_width", "length", ("track width", "w"), "track width"),
    Quantity("track_depth", "length", ("track depth",), "track depth"),
    Quantity("track_area", "area", ("track cross-section area", "track cross section area",
                                    "track area", "cross-section area", "A"),
             "track cross-section area"),
    Quantity("track_volume", "volume", ("track volume", "flat volume", "disc volume",
                                        "counterface volume"), "track volume"),
)

#: the sliding distances [m] a measurement may have: from a nanometre (less is no sliding)
#: to 1e12 m (a bearing at 10 m/s for 30 years slides 1e10 m); beyond, ŝ = K E* s/a0
#: leaves the floating-point range of the fit's search over K
SLIDING_RANGE = (1e-9, 1e12)
#: the first stage of a forward run, in ŝ, at most: below it a measurement is read as
#: the start of wear (the scar the unworn contact, volume and depth ∝ ŝ:
#: ``fitting.Curves``)
S_HAT_START = 1e-3
#: and at least this fraction of the ŝ of the first guess of K at the first measurement
#: (the guess overstates K: the true ŝ lie above, and the decades below cost steps)
START_BELOW_GUESS = 1e-3
#: stages per decade of ŝ in a forward run: the steps land on them, so no gap of the
#: curve spans more than a factor 10^(1/2) in ŝ. The adaptive steps are far denser
#: (20-40 per decade); 8 stages per decade changed the curves by less than the scar's
#: grid reading (docs/fitting.md)
STAGES_PER_DECADE = 2
#: a forward run reaches MARGIN times the ŝ of the first guess of K at the last measurement
#: (and at most half the MDR's cap on ŝ)
MARGIN = 2.0
#: and at most the ŝ at which the long-run scar reaches this fraction of R (the sphere's
#: equator, where the model's body ends)
MOST_B_OVER_R = 0.9
#: forward runs at most (a first one, and two longer ones when the fit needs more)
MOST_RUNS = 3
#: the exponents of the scan with n free: the key's range [1, 4] in steps of 0.25
EXPONENTS = tuple(np.round(np.arange(1.0, 4.0 + 1e-9, 0.25), 2))


@dataclass
class FitResult:
    """What :func:`fit` found.

    Attributes
    ----------
    case : the resolved case as given; ``fitted_case``: the same with the fitted values.
    parameters : {key: {"value", "ci95": [lo, hi], "unit", "note"}} (an open end of an
        interval: 0 below or None above for K, the end of the scan for n, with a note).
    measurements : one dict per measurement: row, cycles, s, quantity, measured,
        uncertainty, model, residual, lab_K.
    lab : per quantity, the lab formula's K (V = K F s through the origin).
    goodness_of_fit : the test, its statistic, p-value and verdict (``fits``).
    model : the model's runs and settings; ``interval_method``: how the intervals are made.
    warnings : remarks (the model does not fit, an interval open or extrapolated).
    """

    case: cases.Case
    fitted_case: cases.Case
    keys: tuple
    parameters: dict
    measurements: list
    lab: dict
    goodness_of_fit: dict
    model: dict
    interval_method: str
    source: str
    seconds: float
    warnings: list = field(default_factory=list)
    path: Path | None = None
    #: for the figure: (s [m], {quantity: model values}) along the measured range
    curve: tuple = field(default=None, repr=False)

    def to_dict(self) -> dict:
        """The JSON of ``wearcheck fit --json`` and of ``fit.json``."""
        return dict(parameters=self.parameters, lab_formula=self.lab,
                    goodness_of_fit=self.goodness_of_fit, measurements=self.measurements,
                    interval_method=self.interval_method, model=self.model,
                    warnings=self.warnings, source=self.source, seconds=self.seconds)


# -- input -------------------------------------------------------------------------

def check_keys(keys) -> tuple[str, ...]:
    """The keys to fit, checked: wear.specific_rate (optionally with wear.pressure_exponent),
    counterface.specific_rate, or both rates."""
    if isinstance(keys, str):
        keys = [keys]
    keys = tuple(dict.fromkeys(str(k) for k in keys))
    for key in keys:
        if key in REFUSED_KEYS:
            raise CaseError(f"--fit {key}: {REFUSED_KEYS[key]}")
        if key not in FIT_KEYS:
            raise CaseError(f"--fit {key}: not a key wearcheck fit can fit; allowed: "
                            + ", ".join(FIT_KEYS))
    if "wear.pressure_exponent" in keys and "counterface.specific_rate" in keys:
        raise CaseError("--fit wear.pressure_exponent with counterface.specific_rate: both "
                        "bodies wear by Reye–Archard's law (n = 1) in the BEM; fit the rates "
                        "with n held")
    if "wear.specific_rate" not in keys and "counterface.specific_rate" not in keys:
        raise CaseError("--fit: wear.specific_rate must be among the keys fitted (the "
                        "exponent alone does not set the wear), or counterface.specific_rate")
    return keys


def check_case(case: cases.Case) -> None:
    """A ball test: a sphere or paraboloid under a constant force, gross slip."""
    if case.fretting is not None:
        raise CaseError("wearcheck fit fits a gross-slip test; the case has [fretting] "
                        "(partial slip)")
    if case.indenter.profile not in ("sphere", "paraboloid"):
        raise CaseError(f"key 'indenter.profile' = \"{case.indenter.profile}\": wearcheck fit "
                        "fits a ball: profile \"sphere\" or \"paraboloid\" (the lab formulas "
                        "take its radius)")
    if case.loading.control != "force":
        raise CaseError("key 'loading.control' = \"depth\": wearcheck fit fits a test under a "
                        "constant normal force (the lab's K is V/(F s)); use control = "
                        "\"force\" with loading.force")


def read_measurements(data, case: cases.Case) -> tuple[fitting.Data, list, str]:
    """The measurements as arrays (SI), one entry per measured value.

    ``data``: a CSV file, or a mapping of headers to columns (``{"cycles": [...],
    "D [um]": [...]}``). Returns the data, the rows (file row, cycles, s) of the
    entries, and a description of the source.
    """
    if isinstance(data, (str, Path)):
        table = read_table(data, MEASUREMENTS)
    elif hasattr(data, "keys"):
        table = from_columns(data, MEASUREMENTS)
    else:
        raise CaseError(f"data = {type(data).__name__}: give a CSV file's path or a mapping "
                        "of headers to columns, e.g. {\"cycles\": [...], \"D [um]\": [...]}")
    where = table.source
    given = [q for q in ("cycles", "s") if q in table]
    if len(given) != 1:
        raise CaseError(f"{where}: needs one column of cycles or of sliding distance s (e.g. "
                        "'s [m]'), " + ("not both" if given else "none found"))
    measured = [q for q in fitting.QUANTITIES if q in table]
    if not measured:
        raise CaseError(f"{where}: no measured column; give one or more of scar diameter "
                        "'D [um]', ball volume 'V [mm^3]', central wear depth 'h [um]' (and "
                        "with a counterface that wears track width, depth, area, volume)")
    track = [q for q in measured if q in fitting.TRACK_QUANTITIES]
    if track and case.counterface_wear_rate is None:
        raise CaseError(f"{table.where(0, track[0]).rsplit(', row', 1)[0]}, column "
                        f"'{table[track[0]].header}': a track quantity, but the case's "
                        "counterface does not wear; set [counterface] wears = true with its "
                        "specific_rate (docs/both-bodies.md)")
    weighted = [q for q in measured if table[q].uncertainty is not None]
    if weighted and len(weighted) != len(measured):
        bare = [table[q].header for q in measured if table[q].uncertainty is None]
        raise CaseError(f"{where}: uncertainties (± columns) for some measured columns but not "
                        f"for {', '.join(repr(b) for b in bare)}; give them for all or none")
    x = table[given[0]]
    if given[0] == "cycles" and case.cycle_length is None:
        raise CaseError(f"{where}: the measurements are in cycles; the case needs "
                        "'sliding.stroke' (one cycle slides 2·stroke; a disc's revolution "
                        "2π·sliding.track_radius)")
    s_all = x.values * case.cycle_length if given[0] == "cycles" else x.values
    # a ball worn to its centre is the most there is to measure: a larger value is a unit
    # slip (D in mm written as µm), and the model could only fail to reach it
    R = case.indenter.radius
    ball_bound = dict(scar_diameter=2.0 * R, wear_center=R,
                      ball_volume=2.0 / 3.0 * math.pi * R**3, track_width=2.0 * R,
                      track_depth=R, track_area=math.inf, track_volume=math.inf)
    s, names, y, sigma, rows = [], [], [], [], []
    for i in range(len(table.rows)):
        if not np.isfinite(x.values[i]):
            raise CaseError(f"{table.where(i, given[0])}: empty; every row needs its "
                            f"{x.quantity.meaning}")
        if not x.values[i] > 0:
            raise CaseError(f"{table.where(i, given[0])}: {x.values[i]:g}; the fit needs "
                            "measurements after sliding (> 0)")
        if not SLIDING_RANGE[0] <= s_all[i] <= SLIDING_RANGE[1]:
            raise CaseError(f"{table.where(i, given[0])}: {x.values[i]:g}, a sliding distance "
                            f"of {s_all[i]:g} m; allowed: {SLIDING_RANGE[0]:g} to "
                            f"{SLIDING_RANGE[1]:g} m (check the column's unit)")
        found = False
        for q in measured:
            col = table[q]
            v = col.values[i]
            if not np.isfinite(v):
                continue
            if not v > 0:
                raise CaseError(f"{table.where(i, q)}: {v:g}; a measured {col.quantity.meaning} "
                                "must be > 0")
            if not v <= ball_bound[q]:
                unit = fitting.LABELS[q][1]
                raise CaseError(f"{table.where(i, q)}: {v:g} {unit}; the values imply a scar "
                                f"larger than the ball (indenter.radius R = {R:g} m: a "
                                f"{col.quantity.meaning} is at most {ball_bound[q]:.4g} "
                                f"{unit}); check the column's unit")
            u = col.uncertainty[i] if col.uncertainty is not None else math.nan
            if col.uncertainty is not None and not u > 0:
                raise CaseError(f"{where}, row {int(table.rows[i])}, column "
                                f"'{col.uncertainty_header}': 0; an uncertainty must be > 0")
            s.append(s_all[i])
            names.append(q)
            y.append(v)
            sigma.append(u)
            rows.append(dict(row=int(table.rows[i]),
                             cycles=float(x.values[i]) if given[0] == "cycles" else
                             (float(s_all[i]) * case.cycles_per_metre
                              if case.cycles_per_metre else None),
                             s=float(s_all[i])))
            found = True
        if not found:
            raise CaseError(f"{table.where(i)}: no measured value in this row")
    data = fitting.Data(np.asarray(s), np.asarray(names), np.asarray(y), np.asarray(sigma))
    return data, rows, where


# -- the model ---------------------------------------------------------------------

def forward_changes(case: cases.Case, n: float, s_hat_top: float,
                    s_hat_start: float = S_HAT_START) -> dict:
    """The case changes of one forward run: exponent n, sliding to ŝ = s_hat_top with
    stages (so steps) at STAGES_PER_DECADE per decade from s_hat_start, adaptive steps."""
    per_m = reference.scales(case)["s_hat_per_m"]
    decades = math.log10(s_hat_top / s_hat_start)
    count = max(int(math.ceil(decades * STAGES_PER_DECADE)), 4) + 1
    stages = np.logspace(math.log10(s_hat_start), math.log10(s_hat_top), count)
    return {"wear.pressure_exponent": float(n), "sliding.until": "distance",
            "sliding.distance": float(s_hat_top / per_m), "sliding.scheme": "adaptive",
            "stages.s_hat": [0.0] + [float(v) for v in stages]}


def curves_of(history: dict, n: float) -> fitting.Curves:
    """The model's measured quantities against ŝ from a forward run's history."""
    s_hat = np.asarray(history["s_hat"], float)
    # (a step that lands on a stage a hair after the last one: one point per ŝ)
    keep = (s_hat > 0) & (s_hat > np.maximum.accumulate(np.r_[0.0, s_hat[:-1]]) * (1 + 1e-9))
    values = {"scar_diameter": 2.0 * np.asarray(history["scar_radius"], float)[keep],
              "ball_volume": np.asarray(history["wear_volume"], float)[keep],
              "wear_center": np.asarray(history["wear_center"], float)[keep]}
    return fitting.Curves(s_hat[keep], values, float(n))


def s_hat_cap(case: cases.Case, n: float) -> float:
    """The ŝ at which the long-run scar of exponent n reaches MOST_B_OVER_R·R."""
    sc = reference.scales(case)
    R = case.indenter.radius
    K_s = float(fitting.rate_for_scar(MOST_B_OVER_R * R, R, case.loading.force, 1.0, n,
                                      case.wear.hardness))
    return K_s * sc["E_star"] / sc["a0"]


def first_guess(case: cases.Case, data: fitting.Data, n: float) -> float:
    """K from the long-run law (fitting.asymptotic_rate) at the last measurement of each
    quantity, the largest: the scar is then most worn and nearest that law, which
    it approaches from above (so the guess overstates K; earlier measurements, their
    scar mostly the elastic contact, would overstate it far more)."""
    R, F, H = case.indenter.radius, case.loading.force, case.wear.hardness
    guesses = []
    for q, at in data.groups:
        last = int(np.argmax(np.where(at, data.s, -np.inf)))
        guesses.append(float(fitting.asymptotic_rate(q, data.y[last], R, F, data.s[last], n, H)))
    return max(guesses)


def plan(case: cases.Case, data: fitting.Data, c: float, n: float) -> tuple[float, float]:
    """The ŝ range of the forward run at exponent n: (start, end)."""
    guess = first_guess(case, data, n) * c
    top = min(MARGIN * guess * float(np.max(data.s)), s_hat_cap(case, n),
              0.5 * ADAPTIVE_MAX_S_HAT)
    start = min(max(S_HAT_START, START_BELOW_GUESS * guess * float(np.min(data.s))),
                top / 10.0)
    return start, top


def solve_here(case: cases.Case, quiet: bool, label: str, solver: str = "mdr"):
    bar = ProgressBar(label, quiet=quiet)
    try:
        with warnings.catch_warnings():
            # a forward run's remarks are on its own ŝ range, past the measurements;
            # the fit judges the fitted model over the measured range (_validity_remarks)
            warnings.simplefilter("ignore", RunWarning)
            return registry.solve(case, solver, progress=bar)
    finally:
        bar.close()


def _run_info(n, top, result, seconds) -> dict:
    return dict(exponent=float(n), s_hat_end=float(top), steps=int(result.info.get("steps", 0)),
                seconds=float(seconds))


# -- the fit -------------------------------------------------------------------------

def fit(case: cases.Case, data, keys=("wear.specific_rate",), *, exponents=None,
        scheduler: str | None = None, workers: int | None = None,
        quiet: bool = True) -> FitResult:
    """Fit ``keys`` of ``case`` to the measurements ``data`` (see :func:`read_measurements`).

    With ``wear.pressure_exponent`` among the keys, the MDR runs once per exponent
    of ``exponents`` (default :data:`EXPONENTS`) on Dask (``scheduler``, ``workers``
    as for ``wearcheck sweep``); else once, here, at the case's exponent.

    Raises
    ------
    CaseError
        bad keys, a case that is not a ball test under a constant force, bad data.
    SolverError
        a forward run failed.
    """
    t0 = time.perf_counter()
    keys = check_keys(keys)
    check_case(case)
    data, rows, source = read_measurements(data, case)
    if case.counterface_wear_rate is not None or "counterface.specific_rate" in keys:
        # lazy (c): fit_track builds on this module (the ball's fit)
        from . import fit_track     # both bodies wearing: the BEM's long-stroke model
        return fit_track.fit(case, data, rows, source, keys, scheduler=scheduler,
                             workers=workers, quiet=quiet, t0=t0)
    free_n = "wear.pressure_exponent" in keys
    n_parameters = 2 if free_n else 1
    if not data.weighted and len(data) < n_parameters + 1:
        raise CaseError(f"{source}: {len(data)} measurement(s) without uncertainties; the "
                        f"scatter is estimated from them, which needs at least "
                        f"{n_parameters + 1} to fit {n_parameters} parameter(s) (or give ± "
                        "uncertainty columns)")
    if data.weighted and len(data) < n_parameters:
        raise CaseError(f"{source}: {len(data)} measurement(s) for {n_parameters} parameters")
    sc = reference.scales(case)
    c = sc["E_star"] / sc["a0"]       # ŝ per unit K·s
    notes: list[str] = []
    if free_n:
        found, runs, family = _fit_exponent(case, data, c, exponents, scheduler, workers,
                                            quiet, notes)
    else:
        found, runs, family = _fit_rate(case, data, c, quiet, notes)
    return _result(case, keys, data, rows, source, found, runs, family, c, notes,
                   time.perf_counter() - t0)


def _rate_range(case, data, c, n, top) -> tuple[float, float]:
    """ln K from where every measurement is in the elastic start of wear (ŝ ≤ 1e-6) to
    where the last one is 100 times past the run's end (the long-run law beyond it)."""
    s_max = float(np.max(data.s))
    return math.log(1e-6 / (c * s_max)), math.log(100.0 * top / (c * s_max))


def _fit_rate(case, data, c, quiet, notes):
    """n fixed: one forward run (longer ones if the fit needs them)."""
    n = case.wear.pressure_exponent
    start, top = plan(case, data, c, n)
    runs = []
    for attempt in range(MOST_RUNS):
        forward = case.derive(forward_changes(case, n, top, start))
        t = time.perf_counter()
        result = solve_here(forward, quiet, f"mdr n = {n:g}")
        runs.append(_run_info(n, top, result, time.perf_counter() - t))
        curves = curves_of(result.history, n)
        lo, hi = _rate_range(case, data, c, n, curves.top)
        found = fitting.fit_rate(curves, data, c, lo, hi)
        need = _reach(found["log_K"], found["interval"][1], data, c)
        ran = top
        if need <= curves.top:
            break
        cap = min(s_hat_cap(case, n), 0.5 * ADAPTIVE_MAX_S_HAT)
        if top >= cap or attempt == MOST_RUNS - 1:
            notes.append(f"the fit reads the model beyond its run's end (ŝ = {curves.top:.4g}"
                         + (f", where the long-run scar reaches {MOST_B_OVER_R:g} R"
                            if top >= cap else "") +
                         "): the upper end is extrapolated by the long-run law")
            break
        top = min(30.0 * need, cap)
    found["resolution"] = _resolution(case, data, c, n, (start, ran), curves, lo, hi, quiet)
    return found, runs, curves


def coarse_elements(case: cases.Case) -> int:
    """The elements of the resolution check's model: N/2, or the fewest the MDR accepts
    (:mod:`wearcheck.mdr.resolution`) when N/2 is below them."""
    factor = case.mdr.domain_factor
    fewest = max(math.ceil(resolution.MIN_CONTACT_CELLS * 2.0 * factor**2 * (1.0 - 1e-12)),
                 resolution.MIN_ELEMENTS)
    return max(case.mdr.elements // 2, fewest)


def _resolution(case, data, c, n, span, curves, lo, hi, quiet) -> dict:
    """The fit at exponent n repeated with the model on M = N/2 elements (or the fewest
    the MDR accepts).

    The scar's edge converges at first order in the element size (it is read
    between nodes), so K_N − K_M, over N/M − 1, estimates the error of K at N;
    the intervals do not include it. Not checked when N is already the fewest.
    """
    N = case.mdr.elements
    M = coarse_elements(case)
    K = math.exp(fitting.fit_rate(curves, data, c, lo, hi)["log_K"])
    if M >= N:
        return dict(exponent=float(n), elements=[N], specific_rate=[K], error=None,
                    seconds=0.0, meaning=f"not checked: mdr.elements = {N} is the fewest the "
                                         "MDR accepts for this case")
    changes = dict(forward_changes(case, n, span[1], span[0]), **{"mdr.elements": M})
    t = time.perf_counter()
    coarse = solve_here(case.derive(changes), quiet, f"mdr N = {M}")
    seconds = time.perf_counter() - t
    K_M = math.exp(fitting.fit_rate(curves_of(coarse.history, n), data, c, lo, hi)["log_K"])
    return dict(exponent=float(n), elements=[M, N], specific_rate=[K_M, K],
                change=K / K_M - 1.0, error=(K - K_M) / (N / M - 1.0), seconds=seconds,
                meaning="K fitted with the model on M and on N elements at this exponent: "
                        "error = (K_N − K_M)/(N/M − 1) estimates the discretisation error "
                        "of K at N (first order)")


def _resolution_note(resolution: dict, parameters: dict) -> str | None:
    """A note when the model's estimated discretisation error of K passes a fifth of the
    interval's half-width, or when it was not checked."""
    N = resolution["elements"][-1]
    if resolution["error"] is None:
        return (f"the model's resolution is not checked: mdr.elements = {N} is the fewest the "
                f"MDR accepts here, so no coarser model exists to compare with; the intervals "
                f"do not include its error (--set mdr.elements={2 * N} checks it)")
    p = parameters["wear.specific_rate"]
    lo, hi = p["ci95"]
    half_width = 0.5 * (hi - lo) if hi is not None else math.inf
    error = abs(resolution["error"])
    if error <= 0.2 * half_width:
        return None
    K_M, K = resolution["specific_rate"]
    return (f"the model's resolution matters: K moves by {100 * (K / K_M - 1):+.2g} % from "
            f"mdr.elements = {resolution['elements'][0]} to {N}, an estimated error at {N} "
            f"of {error / half_width:.2g} of the interval's half-width, which does not "
            f"include it; raise mdr.elements (e.g. --set mdr.elements={2 * N})")


def _reach(log_K, upper, data, c) -> float:
    """The largest ŝ the fit read: at the estimate and at the interval's upper end."""
    top_log_K = upper if upper is not None else log_K
    return math.exp(max(log_K, top_log_K)) * c * float(np.max(data.s))


def _fit_exponent(case, data, c, exponents, scheduler, workers, quiet, notes):
    """n free: one forward run per exponent, on Dask."""
    exponents = np.asarray(EXPONENTS if exponents is None else sorted(set(map(float, exponents))),
                           float)
    if len(exponents) < 4 or exponents[0] < 1.0 or exponents[-1] > 4.0:
        raise CaseError(f"exponents = {list(exponents)}: at least 4 values in [1, 4] (the "
                        "range of wear.pressure_exponent)")
    spans = [plan(case, data, c, n) for n in exponents]
    tasks = []
    for n, (start, top) in zip(exponents, spans):
        tasks.append(Task(name=f"n-{n:g}", solver="mdr",
                          changes=forward_changes(case, n, top, start)))
    scratch = Path(tempfile.mkdtemp(prefix="wearcheck-fit-"))
    try:
        outcomes = run_cases(case, tasks, scratch / "runs", scheduler=scheduler,
                             workers=workers, quiet=quiet, study_files=())
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    failed = [o for o in outcomes if not o.ok]
    if failed:
        raise SolverError(f"the forward run at n = {failed[0].task.name[2:]} failed: "
                          f"{failed[0].message}")
    curves = tuple(curves_of(o.result.history, n) for o, n in zip(outcomes, exponents))
    runs = [dict(_run_info(n, span[1], o.result, o.wall_seconds), worker=o.worker)
            for n, span, o in zip(exponents, spans, outcomes)]
    family = fitting.ExponentCurves(exponents, curves)
    lo = min(_rate_range(case, data, c, n, cv.top)[0] for n, cv in zip(exponents, curves))
    hi = max(_rate_range(case, data, c, n, cv.top)[1] for n, cv in zip(exponents, curves))
    found = fitting.fit_rate_and_exponent(family, data, c, lo, hi)
    # the runs that carry the spline at the estimate must reach the ŝ it reads
    j = int(np.argmin(abs(exponents - found["exponent"])))
    need = _reach(found["log_K"], None, data, c)
    if need > curves[j].top:
        notes.append(f"at the fitted n the model is read beyond its run's end (ŝ = "
                     f"{curves[j].top:.4g}): extrapolated by the long-run law")
    # the resolution check at the scanned exponent nearest the estimate
    lo_j, hi_j = _rate_range(case, data, c, exponents[j], curves[j].top)
    found["resolution"] = _resolution(case, data, c, exponents[j], spans[j], curves[j], lo_j,
                                      hi_j, quiet)
    return found, runs, family


def _result(case, keys, data, rows, source, found, runs, family, c, notes, seconds):
    K = math.exp(found["log_K"])
    lo, hi = found["interval"]
    parameters = {"wear.specific_rate": dict(
        value=K, ci95=[math.exp(lo) if lo is not None else 0.0,
                       math.exp(hi) if hi is not None else None],
        unit=FIT_KEYS["wear.specific_rate"])}
    if lo is None:
        parameters["wear.specific_rate"]["note"] = (
            "the data do not bound K from below: the scars are no larger than the unworn "
            "contact's")
        notes.append(f"wear.specific_rate: {parameters['wear.specific_rate']['note']}")
    if hi is None:
        parameters["wear.specific_rate"]["note"] = "the data do not bound K from above"
        notes.append("wear.specific_rate: the data do not bound K from above")
    n = found.get("exponent", case.wear.pressure_exponent)
    if "wear.pressure_exponent" in keys:
        nlo, nhi = found["exponent_interval"]
        exps = family.exponents
        entry = dict(value=n, ci95=[nlo if nlo is not None else float(exps[0]),
                                    nhi if nhi is not None else float(exps[-1])], unit="1")
        if nlo is None or nhi is None:
            entry["note"] = (f"the interval reaches the end of the scan "
                             f"[{exps[0]:g}, {exps[-1]:g}] (the key's range is [1, 4])")
            notes.append(f"wear.pressure_exponent: {entry['note']}")
        parameters["wear.pressure_exponent"] = entry
    note = _resolution_note(found["resolution"], parameters)
    if note:
        notes.append(note)
    fitted = case.derive({"wear.specific_rate": K, "wear.pressure_exponent": float(n)})
    lab, lab_K = lab_formulas(case, data)
    measurements = measurement_rows(data, rows, found["model"], lab_K)
    gof = found["goodness_of_fit"]
    warning = misfit_warning(gof, rows)
    if warning:
        notes.insert(0, warning)
    notes += below_hertz_notes(case, data, rows)
    method = interval_method(data)
    curve = _curve(family, data, found, c)
    notes += _validity_remarks(fitted, family, data, found, c)
    model_info = dict(solver="mdr", body="the ball alone (the flat does not wear)",
                      elements=case.mdr.elements, scheme="adaptive",
                      tolerance=case.sliding.tolerance, runs=runs,
                      structure="at a fixed n the worn state is a function of K·s: one run "
                                "in ŝ = K E* s/a0 gives the prediction for every K",
                      s_hat_per_K_s=c, resolution=found["resolution"])
    return FitResult(case=case, fitted_case=fitted, keys=keys, parameters=parameters,
                     measurements=measurements, lab=lab, goodness_of_fit=gof, model=model_info,
                     interval_method=method, source=source, seconds=seconds, warnings=notes,
                     curve=curve)


#: the lab's formula of each quantity's volume (the ball's, or the counterface's)
LAB_FORMULAS = {"scar_diameter": "V = π D⁴/(64 R)", "ball_volume": "V measured",
                "wear_center": "V = π h² (3R − h)/3",
                "track_width": "the unworn ball's groove of width w, G133's flat: "
                               "stroke·A_seg(w, R) + the ends' cap",
                "track_width_disc": "the unworn pin's groove of width w, G99's disc: "
                                    "2π R_track·A_seg(w, R)",
                "track_depth": "L·A_seg of the unworn ball's groove of depth δ",
                "track_area": "V = L·A (profilometer)", "track_volume": "V measured"}


def lab_formulas(case: cases.Case, data: fitting.Data) -> tuple[dict, np.ndarray]:
    """The lab formula's K per quantity (V = K F s, least squares through the origin) and
    each measurement's own V_lab/(F s); the track's K is the counterface's."""
    R, F = case.indenter.radius, case.loading.force
    lab, lab_K = {}, np.full(len(data), np.nan)
    for q in fitting.QUANTITIES:
        at = data.quantity == q
        if not np.any(at):
            continue
        if q in fitting.TRACK_QUANTITIES:
            V = fitting.lab_track_volume(q, data.y[at], R, case.sliding)
        else:
            V = fitting.lab_volume(q, data.y[at], R)
        per, pooled = fitting.lab_rate(V, F, data.s[at])
        lab_K[at] = per
        body = "K_flat" if q in fitting.TRACK_QUANTITIES else "K"
        disc = q == "track_width" and case.sliding.motion == "unidirectional"
        formula = LAB_FORMULAS["track_width_disc" if disc else q]
        lab[q] = dict(K=pooled, formula=f"{formula}; {body} = V/(F s), least squares "
                                        "through the origin over the measurements (n = 1)")
    return lab, lab_K


def measurement_rows(data: fitting.Data, rows: list, model, lab_K) -> list[dict]:
    """One dict per measurement: its row, quantity, value, the model's, residual, lab K."""
    r = fitting.residuals(data, model)
    out = []
    for i in range(len(data)):
        out.append(dict(rows[i], quantity=str(data.quantity[i]),
                        unit=fitting.LABELS[str(data.quantity[i])][1],
                        measured=float(data.y[i]),
                        uncertainty=float(data.sigma[i]) if data.weighted else None,
                        model=float(model[i]), residual=float(r[i]), lab_K=float(lab_K[i])))
    return out


#: how the remarks that are warnings (not notes) begin: the model does not fit, its fit
#: could not be tested, a scar no K gives
WARNING_STARTS = ("the residuals", "too few measurements", "scar diameter below")


def misfit_warning(gof: dict, rows: list | None = None) -> str | None:
    """The warning when the goodness of fit says the model does not fit, or that it
    could not be tested; None when the tests made pass. ``rows``: each measurement's
    row (a dict with "row"), to name an outlier's."""
    if gof["fits"] is None:
        return (f"too few measurements to test the model's fit: {gof['measurements']} "
                f"points, {gof['parameters']} parameter(s); the values are the best fit, "
                "but nothing here says the model describes the measurements")
    if gof["fits"]:
        return None
    said = []
    p = gof["p_value"]
    if p < fitting.MISFIT_P:
        what = (f"χ² = {gof['statistic']:.4g} for {gof['dof']} degrees of freedom"
                if gof["test"] == "chi2" else
                f"a trend of the residuals with ln s, F = {gof['statistic']:.4g} on "
                f"{gof['dof'][0]} and {gof['dof'][1]} degrees of freedom")
        said.append(f"{what}, p = {p:.3g} < {fitting.MISFIT_P:g}")
    out = gof["outliers"]
    if out.get("flagged"):
        names = [f"row {rows[i]['row']}" if rows else f"measurement {i + 1}"
                 for i in out["flagged"]]
        worst = max(abs(out["values"][i]) for i in out["flagged"])
        said.append(f"an outlier at {', '.join(names)} (|{out['statistic']}| = {worst:.3g} > "
                    f"{out['limit']:.3g}, the limit at a false-alarm rate of "
                    f"{out['false_alarm']:g} over all points)")
    return (f"the residuals say the model does not fit: {'; '.join(said)}; the wear law (or "
            "the uncertainties) do not describe these measurements, and the intervals are "
            "then too narrow")


def below_hertz_notes(case: cases.Case, data: fitting.Data, rows: list) -> list[str]:
    """One remark naming the rows whose scar diameter is below the unworn Hertz contact's
    2a0: wear only widens the contact under a constant force, so no K ≥ 0 gives them
    (a scar read too small, or a load or radius in the case that is not the test's)."""
    two_a0 = 2.0 * reference.scales(case)["a0"]
    below = [i for i in range(len(data))
             if data.quantity[i] == "scar_diameter" and data.y[i] < two_a0]
    if not below:
        return []
    shown = ", ".join(f"row {rows[i]['row']} ({data.y[i]:.4g} m)" for i in below)
    return [f"scar diameter below the unworn Hertz contact's 2a0 = {two_a0:.4g} m at {shown}: "
            "the model cannot give a scar smaller than the unworn contact at any K ≥ 0; "
            "check the reading, the load and the ball's radius"]


def interval_method(data: fitting.Data) -> str:
    """How the intervals were made (with or without the uncertainties)."""
    return ("profile likelihood: {θ: χ²_profile(θ) − χ²_min ≤ 3.84} (χ²₁ at 95 %), with the "
            "uncertainties given" if data.weighted else
            "profile t (nonlinear regression, Bates & Watts 1988 §6.1): relative errors of "
            "one unknown scatter, {θ: RSS_profile(θ) ≤ RSS_min (1 + F₁,ν(0.95)/ν)}, ν = N − P")


def _model_at(family, found, quantity: str, s, c) -> np.ndarray:
    """The fitted model's ``quantity`` after sliding s [m]."""
    probe = fitting.Data(s, np.full(len(s), quantity), np.ones(len(s)), np.full(len(s), np.nan))
    if isinstance(family, fitting.ExponentCurves):
        return fitting.predict_between(family, probe, found["log_K"], found["exponent"], c)
    return fitting.predict(family, probe, found["log_K"], c)


def _curve(family, data, found, c):
    """The fitted model along the measured range, for the figure."""
    s = np.geomspace(float(np.min(data.s)) / 3.0, float(np.max(data.s)) * 3.0, 200)
    return s, {str(q): _model_at(family, found, str(q), s, c) for q in np.unique(data.quantity)}


def _validity_remarks(fitted: cases.Case, family, data, found, c) -> list[str]:
    """The remarks a run of the fitted case makes over the measured range.

    :class:`cases.validity.BodyWatch`, as every solver calls it, at the fitted
    model's scar at each measured sliding distance: the yield estimate, and
    half-space theory from the first measurement whose scar passes b/R = 0.1
    (one RunWarning each). A scar past the ball's equator is not handed to it
    (the watch would stop a run; the fit says so in its own note on reading
    the model beyond its run).
    """
    s = np.unique(data.s)
    b = 0.5 * _model_at(family, found, "scar_diameter", s, c)
    watch = validity.BodyWatch(fitted)
    for s_i, b_i in zip(s, b):
        if not b_i < fitted.indenter.radius:
            break
        watch(float(s_i), None, float(b_i))
    return watch.remarks


def file_digest(path) -> str | None:
    """SHA-256 of a measurement file (recorded in meta.json)."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return None


def write(result: FitResult, out, data_path=None, argv=None) -> Path:
    """Write the fit directory ``out`` atomically: case.toml, fitted_case.toml, fit.json,
    measurements.csv, fit.png and meta.json (provenance)."""
    with atomic_directory(out, "fit") as tmp:
        (tmp / "case.toml").write_text(cases.to_toml(result.case), encoding="utf-8")
        (tmp / "fitted_case.toml").write_text(cases.to_toml(result.fitted_case),
                                              encoding="utf-8")
        (tmp / "fit.json").write_text(json.dumps(jsonable(result.to_dict()), indent=2) + "\n",
                                      encoding="utf-8")
        (tmp / "measurements.csv").write_text(measurements_csv(result.measurements),
                                              encoding="utf-8")
        figure(result, tmp / "fit.png")
        meta = dict(kind="fit", resolved_case=cases.to_toml(result.case),
                    fitted_case=cases.to_toml(result.fitted_case), keys=list(result.keys),
                    measurements=dict(source=result.source,
                                      path=str(Path(data_path).resolve()) if data_path else None,
                                      sha256=file_digest(data_path) if data_path else None),
                    warnings=list(result.case.warnings) + result.warnings,
                    data_dictionary=layout.fit_dictionary())
        meta.update(provenance(argv))
        (tmp / "meta.json").write_text(json.dumps(jsonable(meta), indent=2, allow_nan=True)
                                       + "\n", encoding="utf-8")
    result.path = Path(out)
    return result.path


def measurements_csv(rows: list) -> str:
    """measurements.csv: one row per measurement (SI; ``pandas.read_csv`` reads it as is)."""
    names = [c.name for c in layout.FIT_COLUMNS]
    lines = [",".join(names)]
    for row in rows:
        cells = []
        for name in names:
            v = row.get(name)
            cells.append("" if v is None else (v if isinstance(v, str) else f"{v:.10g}"))
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"
