"""``wearcheck fit`` with both bodies wearing (issue 25 with issue 24's long-stroke BEM).

The measurements come from separate BEM runs at known rates whose steps land on
the measured distances, plus noise; the fit reads its own runs at other ratios.
Checks: the scaling the fit rests on (both rates times c is the sliding times c)
on the BEM itself, and that the check fails where the scaling does not hold;
the recovery of K_flat alone and of both rates; the coverage of the 95 %
intervals over 100 noise draws; the refusals, one line each.

Small and quick: ball_on_flat_steel at 32² pixels, sliding.tolerance 1e-3,
measurements from 10 to 300 cycles (the track then about 2.5 unworn contact
radii wide, which 32 pixels resolve: the BEM refuses fewer than 4 pixels per
unworn contact radius).
"""

import math
import warnings

import numpy as np
import pytest

import wearcheck
from wearcheck.cases import CaseError, reference
from wearcheck import registry
from wearcheck.comparisons.analysis import fitting
from wearcheck.cli import main as cli_main
from wearcheck.studies import fit_track

K_BALL, K_FLAT = 2e-15, 1.3e-14          # the ratio 6.5 is on no scan's grid
CYCLES = np.geomspace(10.0, 300.0, 5)
S = 0.02 * CYCLES                        # a 10 mm stroke: 2 cm a cycle


@pytest.fixture(scope="module")
def case():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return wearcheck.load_case("ball_on_flat_steel", {"bem.grid": 32,
                                                           "sliding.tolerance": 1e-3})


def _solve(case):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return registry.solve(case, "bem")


@pytest.fixture(scope="module")
def truth(case):
    """The measured quantities of a run at (K_BALL, K_FLAT) landing on the distances S."""
    run = _solve(case.derive({"wear.specific_rate": K_BALL, "counterface.specific_rate": K_FLAT,
                              "sliding.until": "distance", "sliding.distance": float(S[-1]),
                              "stages.s": [0.0] + list(S)}))
    h = run.history
    at = [int(np.flatnonzero(np.isclose(h["s"], s, rtol=1e-12))[0]) for s in S]
    curves = fit_track.curves_of({k: np.asarray(v)[at] for k, v in h.items()})
    return {q: curves.values[q] for q in fitting.QUANTITIES}


# -- the structure: both rates times c is the sliding times c ----------------------------

COLUMNS = ("force", "depth", "contact_radius", "wear_center", "wear_volume",
           "wear_volume_counterface", "track_width", "track_depth", "track_area",
           "max_pressure", "scar_radius", "scar_length", "scar_width", "s_hat")


def _histories(case, rates_times, s_times):
    """A run to ŝ = 30 with its stages in ŝ (so both runs step alike), the rates and the
    sliding distance multiplied as asked."""
    kb, kf = (K_BALL * rates_times[0], K_FLAT * rates_times[1])
    per_m = kb * reference.scales(case)["E_star"] / reference.scales(case)["a0"]
    return _solve(case.derive({"wear.specific_rate": kb, "counterface.specific_rate": kf,
                               "sliding.until": "distance",
                               "sliding.distance": 30.0 / per_m,
                               "stages.s_hat": [0.0, 0.1, 1.0, 10.0, 30.0]})).history


def _largest_difference(h1, h2):
    return {k: float(np.max(np.abs(np.asarray(h1[k]) - np.asarray(h2[k])))
                     / np.max(np.abs(np.asarray(h1[k])))) for k in COLUMNS}


def test_both_rates_times_c_is_the_sliding_times_c(case):
    """The BEM at (3 K_ball, 3 K_flat) over s and at (K_ball, K_flat) over 3 s: the same
    history at the same ŝ (s_hat runs with K_ball·s). Tolerance 1e-7 of each column's
    largest value: the contact solves stop at bem.tolerance = 1e-8 (in p/p0 and
    gap/d), and the two runs, stepping alike in ŝ, differ by round-off amplified to
    that level (measured 4e-9 at most, the peak pressure, on 80²). Scaling the
    ball's rate alone is not the same thing: the same comparison fails (the groove
    then is shallower by 3), which shows the check can fail."""
    c = 3.0
    scaled = _histories(case, (c, c), 1.0)
    longer = _histories(case, (1.0, 1.0), c)
    assert len(scaled["s"]) == len(longer["s"])
    differences = _largest_difference(scaled, longer)
    assert max(differences.values()) < 1e-7, differences
    ball_only = _histories(case, (c, 1.0), 1.0)
    assert _largest_difference(ball_only, longer)["track_depth"] > 0.1


# -- recovery and coverage ------------------------------------------------------------------

@pytest.fixture(scope="module")
def family(case):
    """The fit's model with K_ball held at K_BALL: five runs at ratios a factor 2 apart
    around 6.5 (not on the grid), to ŝ 5 % past the last measurement."""
    sc = reference.scales(case)
    c = sc["E_star"] / sc["a0"]
    top = 1.05 * K_BALL * c * S[-1]
    start = 1e-3 * K_BALL * c * S[0]
    ratios = np.log(6.5) + np.log(2.0) * (np.arange(5) - 2.3)
    curves = tuple(fit_track.curves_of(_solve(case.derive(
        fit_track.forward_changes(case, K_BALL, r, top, start))).history) for r in ratios)
    return fitting.RatioCurves(ratios, curves), c


def _data(values: dict, sigma=None) -> fitting.Data:
    names = list(values)
    y = np.concatenate([values[q] for q in names])
    return fitting.Data(np.tile(S, len(names)), np.repeat(names, len(S)), y,
                        np.full(len(y), np.nan) if sigma is None else np.asarray(sigma, float))


def test_the_spline_across_ratios_reads_the_runs_between_them(truth, family):
    """The family read at the truth's ratio (between two runs) against the truth's own
    run: the depth, area and volume of the track and the ball's central wear within
    1 % (the spline across ln ρ, measured 0.7 % at most on 80²), the volumes to 1e-3
    (each is K F s exactly; the adaptive stepping's interpolation)."""
    fam, c = family
    for q, tol in (("track_depth", 1e-2), ("wear_center", 1e-2), ("track_area", 1e-3),
                   ("track_volume", 1e-3), ("ball_volume", 1e-3)):
        probe = _data({q: truth[q]})
        model = fitting.predict_rates(fam, probe, math.log(K_BALL), math.log(K_FLAT), c)
        assert model == pytest.approx(truth[q], rel=tol), q
    # the volumes are the Archard balance: V = K F s for each body
    assert truth["ball_volume"] == pytest.approx(K_BALL * 25.0 * S, rel=1e-3)
    assert truth["track_volume"] == pytest.approx(K_FLAT * 25.0 * S, rel=1e-3)


def test_K_flat_intervals_cover_the_truth_95_percent(truth, family):
    """100 draws of the track depth ± 2 %, K_ball held: the profile-likelihood interval
    of K_flat should hold K_FLAT in 95 of them; a correct 95 % method lands in 90-99
    with probability 0.97 (binomial). The runs are the same for every draw (the model
    does not depend on the noise). Fixed seeds: deterministic."""
    fam, c = family
    depth = truth["track_depth"]
    sigma = 0.02 * depth
    covered, estimates = 0, []
    for seed in range(100):
        rng = np.random.default_rng(seed)
        data = _data({"track_depth": depth + sigma * rng.standard_normal(len(S))}, sigma)
        found = fitting.fit_rates(fam, data, c, ("flat",), math.log(K_BALL), 0.0, -50, 0)
        a, b = found["intervals"]["flat"]
        covered += a is not None and b is not None and a <= math.log(K_FLAT) <= b
        estimates.append(found["log_K_flat"])
    print(f"coverage of K_flat: {covered}/100")
    assert 90 <= covered <= 99
    est = np.array(estimates)
    assert abs(est.mean() - math.log(K_FLAT)) < 3 * est.std() / 10


def test_K_flat_intervals_without_uncertainties_cover_the_truth(truth, family):
    """100 draws of the track depth and area with 3 % relative scatter, not given: the
    profile-t interval (the scatter estimated from the 10 values) should hold K_FLAT
    in 95 of them (90-99 with probability 0.97); the goodness of fit is the trend
    test."""
    fam, c = family
    covered = 0
    for seed in range(100):
        rng = np.random.default_rng(1000 + seed)
        values = {q: truth[q] * np.exp(0.03 * rng.standard_normal(len(S)))
                  for q in ("track_depth", "track_area")}
        found = fitting.fit_rates(fam, _data(values), c, ("flat",), math.log(K_BALL), 0.0,
                                  -50, 0)
        a, b = found["intervals"]["flat"]
        covered += a is not None and b is not None and a <= math.log(K_FLAT) <= b
    assert found["goodness_of_fit"]["test"] == "trend"
    print(f"coverage of K_flat without uncertainties: {covered}/100")
    assert 90 <= covered <= 99


def test_a_track_that_deepens_faster_is_flagged_by_the_residuals(truth, family):
    """The verdict can fail: depths ± 2 % made to deepen as (s/s_3)^0.3 faster than the
    model's (a counterface whose wear accelerates, which no constant K_flat gives)
    fail the χ² test; the true depths with the same noise pass it."""
    fam, c = family
    depth = truth["track_depth"]
    rng = np.random.default_rng(3)
    noise = 1 + 0.02 * rng.standard_normal(len(S))
    for values, fits in ((depth, True), (depth * (S / S[2]) ** 0.3, False)):
        data = _data({"track_depth": values * noise}, 0.02 * values)
        gof = fitting.fit_rates(fam, data, c, ("flat",), math.log(K_BALL), 0.0, -50,
                                0)["goodness_of_fit"]
        assert gof["test"] == "chi2" and gof["fits"] is fits, gof


def test_the_widths_resolution_check(case, truth, family):
    """The scar diameter is read where the wear falls to 1e-3 of its largest, between
    pixels: the check repeats the run nearest the estimate on 1.5 times the pixels.
    Independent of the code: at the start of wear the scar is the unworn contact,
    2 a0 (Hertz), and the finer grid reads it closer to that than the coarse one;
    the note comes when the estimated error passes a fifth of the uncertainty, not
    when the uncertainty is far larger."""
    fam, c = family
    D = truth["scar_diameter"]
    found = fitting.fit_rates(fam, _data({"scar_diameter": D}, 0.005 * D), c, ("flat",),
                              math.log(K_BALL), 0.0, -50, 0)
    top, start = 1.05 * K_BALL * c * S[-1], 1e-3 * K_BALL * c * S[0]
    check = fit_track.width_resolution(case, _data({"scar_diameter": D}, 0.005 * D), found,
                                       fam, K_BALL, top, start, c, None, None, True)
    assert check["grid"] == [32, 48]
    j = int(np.argmin(np.abs(fam.log_ratios - (found["log_K_flat"] - found["log_K_ball"]))))
    coarse = fam.curves[j]
    fine = fit_track.curves_of(_solve(case.derive(dict(
        fit_track.forward_changes(case, K_BALL, float(fam.log_ratios[j]), top, start),
        **{"bem.grid": 48}))).history)
    two_a0 = 2.0 * reference.scales(case)["a0"]
    assert abs(fine.values["scar_diameter"][0] - two_a0) < \
        abs(coarse.values["scar_diameter"][0] - two_a0)
    precise = _data({"scar_diameter": D}, 1e-4 * D)
    assert "resolution matters for the widths" in fit_track.width_note(check, precise,
                                                                       found["model"])
    loose = _data({"scar_diameter": D}, 0.5 * D)
    assert fit_track.width_note(check, loose, found["model"]) is None


def test_the_scan_grows_to_the_fit(case, truth, monkeypatch):
    """A first guess of K_flat ten times too small puts the truth's ratio (6.5) past the
    first scan's end (0.65 × 2^±2): the scan grows, one run a step, until the estimate
    and the interval are half a step inside it, and the interval holds K_FLAT."""
    monkeypatch.setattr(fit_track, "flat_guess", lambda case, data: K_FLAT / 10.0)
    depth = truth["track_depth"]
    noisy = depth * (1 + 0.02 * np.random.default_rng(9).standard_normal(len(S)))
    result = wearcheck.fit(case.derive({"wear.specific_rate": K_BALL}),
                           {"s [m]": S, "track depth [m]": noisy, "± track depth [m]": 0.02 * depth},
                           "counterface.specific_rate")
    ratios = sorted(r["ratio"] for r in result.model["runs"])
    assert len(ratios) > fit_track.FIRST_RATIOS and ratios[-1] > 6.5 * 2 ** 0.5
    lo, hi = result.parameters["counterface.specific_rate"]["ci95"]
    assert lo <= K_FLAT <= hi


def test_both_rates_are_recovered_from_the_command_line(tmp_path, truth, capsys):
    """Ball central wear and track depth, ± 2 % (one draw): wearcheck fit with both keys
    holds both true rates in its intervals; --json; the runs are a ratio scan."""
    rng = np.random.default_rng(5)
    h, d = truth["wear_center"] * 1e6, truth["track_depth"] * 1e6
    lines = ["# G133: both bodies measured", "cycles, h [um], ± h [um], track depth [um], "
             "± track depth [um]"]
    for n, hi, di in zip(CYCLES, h, d):
        lines.append(f"{n:.6g}, {hi * (1 + 0.02 * rng.standard_normal()):.5g}, {0.02 * hi:.4g}, "
                     f"{di * (1 + 0.02 * rng.standard_normal()):.5g}, {0.02 * di:.4g}")
    sheet = tmp_path / "sheet.csv"
    sheet.write_text("\n".join(lines) + "\n", encoding="utf-8")
    import json
    code = cli_main(["fit", "ball_on_flat_steel", str(sheet), "--fit", "wear.specific_rate",
                     "--fit", "counterface.specific_rate", "--set", "bem.grid=32",
                     "--set", "sliding.tolerance=1e-3", "--json", "--out",
                     str(tmp_path / "fit")])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    # the fit directory: the figure has a panel per quantity and the residuals; the
    # fitted case holds both rates
    assert (tmp_path / "fit" / "fit.png").stat().st_size > 10_000
    fitted = wearcheck.load_case(tmp_path / "fit" / "fitted_case.toml")
    assert fitted.counterface_wear_rate == pytest.approx(
        out["parameters"]["counterface.specific_rate"]["value"], rel=1e-12)
    p = out["parameters"]
    for key, true in (("wear.specific_rate", K_BALL), ("counterface.specific_rate", K_FLAT)):
        lo, hi = p[key]["ci95"]
        assert lo <= true <= hi, (key, p[key])
        assert hi / lo < 1.3                      # ± 2 % on 5 + 5 values pins both
    assert out["model"]["solver"] == "bem" and len(out["model"]["runs"]) >= 5
    print("both rates:", p, [(r["ratio"], r["seconds"]) for r in out["model"]["runs"]])


@pytest.mark.slow
def test_the_scan_on_dask(case, truth):
    """The runs on a Dask cluster (--workers 2; a cluster's start costs more than these
    small runs, hence slow): the same scan and K_flat as run here, one after another."""
    depth = truth["track_depth"]
    noisy = depth * (1 + 0.02 * np.random.default_rng(4).standard_normal(len(S)))
    data = {"s [m]": S, "track depth [m]": noisy, "± track depth [m]": 0.02 * depth}
    held = case.derive({"wear.specific_rate": K_BALL})
    here = wearcheck.fit(held, data, "counterface.specific_rate")
    dask = wearcheck.fit(held, data, "counterface.specific_rate", workers=2)
    assert all(r["worker"] for r in dask.model["runs"])
    assert [r["ratio"] for r in dask.model["runs"]] == [r["ratio"] for r in here.model["runs"]]
    # the same runs in another process: the same numbers (the BEM is deterministic; 1e-9
    # leaves room for a different FFT plan there)
    assert dask.parameters["counterface.specific_rate"]["value"] == pytest.approx(
        here.parameters["counterface.specific_rate"]["value"], rel=1e-9)


# -- refusals -------------------------------------------------------------------------------

BALL_ONLY = "cycles, D [um]\n100, 300\n300, 320\n"


@pytest.mark.parametrize("case_name, sheet, keys, pattern", [
    ("ball_on_flat", BALL_ONLY, ["counterface.specific_rate"],
     r"--fit counterface\.specific_rate: the case's counterface does not wear"),
    ("ball_on_flat", "cycles, track depth [um]\n10, 1\n20, 2\n", ["wear.specific_rate"],
     r"column 'track depth \[um\]': a track quantity, but the case's counterface does not wear"),
    ("ball_on_flat_steel", BALL_ONLY, ["counterface.specific_rate"],
     r"--fit counterface\.specific_rate needs a measurement of the track"),
    ("ball_on_flat_steel", "cycles, track depth [um]\n10, 1\n20, 2\n", ["wear.specific_rate"],
     r"--fit wear\.specific_rate needs a measurement of the ball"),
    ("ball_on_flat_steel", BALL_ONLY, ["wear.specific_rate", "wear.pressure_exponent"],
     r"the counterface wears, and the BEM wears both bodies by Reye–Archard's law"),
    ("ball_on_flat_steel", BALL_ONLY, ["counterface.specific_rate", "wear.pressure_exponent"],
     r"--fit wear\.pressure_exponent with counterface\.specific_rate"),
    ("ball_on_flat_steel", BALL_ONLY, ["counterface.k"], r"--fit counterface\.k: fit "
                                                         r"counterface\.specific_rate"),
])
def test_refusals_are_one_line(tmp_path, capsys, case_name, sheet, keys, pattern):
    path = tmp_path / "sheet.csv"
    path.write_text(sheet, encoding="utf-8")
    args = ["fit", case_name, str(path), "--quiet"]
    for key in keys:
        args += ["--fit", key]
    code = cli_main(args)
    err = capsys.readouterr().err
    assert code == 2, err
    lines = [line for line in err.splitlines() if line.startswith("wearcheck fit: error")]
    assert len(lines) == 1 and "Traceback" not in err
    import re
    assert re.search(pattern, lines[0]), lines[0]


def test_the_moving_contact_model_is_refused(tmp_path):
    path = tmp_path / "sheet.csv"
    path.write_text("cycles, track depth [um]\n10, 1\n20, 2\n", encoding="utf-8")
    with pytest.raises(CaseError, match=r"bem\.track_model.*long-stroke"):
        wearcheck.fit(wearcheck.load_case("ball_on_flat_steel",
                                          {"bem.track_model": "moving",
                                           "sliding.stroke": 1e-3}),
                      path, "counterface.specific_rate")
