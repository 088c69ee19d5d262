"""``wearcheck compare``: MDR and FEM on one case, figures, metrics, report.

Everything is computed first; the output directory is then written in one
piece with ``runio.atomic_directory``:

    DIR/mdr/, DIR/fem/          run directories (as ``wearcheck run`` writes them)
    DIR/fig2_profiles.png|pdf   f/d against r/a0 at the stages (paper Fig. 2a)
    DIR/fig2_pressure.png|pdf   p/p0 against r/a0 (paper Fig. 2b; Fig. 3b for the
                                truncated paraboloid, with the reference)
    DIR/force_vs_sliding.png|pdf F/F0 and a/a0 against ŝ
    DIR/metrics.json            per-stage and overall differences and the verdict
    DIR/report.md, report.html  the page a reviewer reads
    DIR/edge_study/             (--edge-study) runs at other resolutions, edge_peak.png
    DIR/finite_sphere.png       (--sphere-sweep) FEM force against half-space force
"""

from __future__ import annotations

import dataclasses
import math
import sys
import time
from pathlib import Path

import numpy as np

from wearcheck import cases
from wearcheck.cases import reference

from . import edge_peak, metrics, report, runio
from .solvers import solve as solve_case

#: a0/R of the finite-sphere sweep (physics.md §7)
SPHERE_RATIOS = (0.005, 0.01, 0.02, 0.05, 0.1)
#: grid refinement factors of the edge study, relative to the case
EDGE_GRID_FACTORS = (0.5, 2.0)
#: step factor of the edge study, relative to the step the case's run used
EDGE_STEP_FACTOR = 0.5


# -- running ---------------------------------------------------------------

def _progress(label, quiet):
    from .progress import ProgressBar
    return ProgressBar(label, quiet=quiet)


def run_both(case, *, solve=None, quiet=True, label="") -> dict:
    """Run MDR and FEM on ``case``: {"mdr": RunResult, "fem": RunResult}."""
    solve = solve or solve_case
    out = {}
    for name in ("mdr", "fem"):
        bar = _progress(f"{name}{label}", quiet)
        try:
            out[name] = solve(case, name, progress=bar)
        finally:
            bar.close()
    return out


def profile_scale(case, scales) -> float:
    """The depth d that profiles are measured in: the held depth, or d0 under force control."""
    if case.loading.control == "depth":
        return case.loading.depth
    return scales["d0"]


def step_hat_used(result, s_hat_per_m) -> float:
    """The median sliding step of a run, in ŝ (NaN when it did not slide)."""
    ds = np.diff(np.asarray(result.history["s"], float))
    ds = ds[ds > 0]
    return float(np.median(ds) * s_hat_per_m) if ds.size else math.nan


def grid_spacing(result, a0) -> float:
    """Median spacing of a result's radii, relative to a0."""
    return float(np.median(np.diff(np.asarray(result.r, float))) / a0)


# -- analysis --------------------------------------------------------------

def truncated_reference(case, results, scales) -> dict | None:
    """Paper Fig. 3: each solver's unworn pressure against the quadrature reference.

    Only for a truncated paraboloid at a stage with ŝ = 0. The pressure is
    compared away from the edge (edge_band) and away from the singularity at
    r = b (|r - b| < edge_band · a).
    """
    ind = case.indenter
    if ind.profile != "truncated_paraboloid":
        return None
    E, R, b = case.E_star, ind.radius, ind.flat_radius
    load = {case.loading.control: getattr(case.loading, case.loading.control)}
    ref = reference.truncated_paraboloid(E, R, b, **load)
    a = ref["contact_radius"]
    cmp = case.compare
    out = dict(flat_radius_over_a0=b / scales["a0"], contact_radius=a / scales["a0"],
               force=ref["force"] / scales["F0"], solvers={})
    for name, res in results.items():
        if len(res.stage_s) == 0 or res.stage_s[0] != 0.0:
            continue
        r = np.asarray(res.r, float)
        p_ref = reference.truncated_paraboloid_pressure(r, E, R, b, a)
        a_run = float(metrics.at_stages(res.history["s"], res.history["contact_radius"],
                                        res.stage_s[:1])[0])
        F_run = float(metrics.at_stages(res.history["s"], res.history["force"],
                                        res.stage_s[:1])[0])
        interior, edge = metrics.edge_masks(r, a, a_run, cmp.edge_band)
        near_b = np.abs(r - b) < cmp.edge_band * a
        dp = (np.asarray(res.p[0], float) - p_ref) / scales["p0"]
        row = dict(force=abs(F_run - ref["force"]) / scales["F0"],
                   contact_radius=abs(a_run - a) / scales["a0"])
        row["pressure_interior_max"], row["pressure_interior_rms"], _ = \
            metrics.max_rms(dp[interior & ~near_b])
        row["pressure_near_b_max"], _, _ = metrics.max_rms(dp[near_b])
        row["pressure_edge_max"], _, _ = metrics.max_rms(dp[edge])
        tol = metrics.verdict(dict(row, profile_max=0.0), dataclasses.asdict(cmp))
        tol.pop("profile_max")
        row["checks"] = tol
        row["passed"] = all(c["passed"] for c in tol.values())
        out["solvers"][name] = row
    out["passed"] = bool(out["solvers"]) and all(v["passed"] for v in out["solvers"].values())
    return out


def analyse(case, results) -> dict:
    """All differences of one MDR/FEM pair, as written to metrics.json."""
    sc = reference.scales(case)
    depth = profile_scale(case, sc)
    cmp = case.compare
    exclude = {}
    ind = case.indenter
    if ind.profile == "truncated_paraboloid":
        # both solvers resolve the log singularity at r = b differently: leave it out
        exclude = dict(exclude_radius=ind.flat_radius, exclude_width=cmp.edge_band * sc["a0"])
    elif ind.profile == "cone" or (ind.profile == "power_law" and ind.exponent <= 1.0):
        # p is infinite at a sharp tip (log for the cone): no grid value of it is comparable
        exclude = dict(exclude_radius=0.0, exclude_width=cmp.edge_band * sc["a0"])
    m = metrics.compare_results(results["mdr"], results["fem"], s_hat_per_m=sc["s_hat_per_m"],
                                a0=sc["a0"], F0=sc["F0"], p0=sc["p0"], depth=depth,
                                tolerances=dataclasses.asdict(cmp), edge_band=cmp.edge_band,
                                **exclude)
    m["scales"] = sc
    m["profile_scale_depth"] = depth
    m["tolerances"] = dataclasses.asdict(cmp)
    m["stages_requested_s_hat"] = list(case.stages.s_hat)
    m["solve_seconds"] = {k: float(v.solve_seconds) for k, v in results.items()}
    m["grid_spacing_over_a0"] = {k: grid_spacing(v, sc["a0"]) for k, v in results.items()}
    m["step_hat"] = {k: step_hat_used(v, sc["s_hat_per_m"]) for k, v in results.items()}
    m["run_end"] = {k: dict(s_hat=float(v.history["s"][-1] * sc["s_hat_per_m"]),
                            force=float(v.history["force"][-1] / sc["F0"]))
                    for k, v in results.items()}
    ref = truncated_reference(case, results, sc)
    if ref is not None:
        m["truncated_reference"] = ref
        m["passed"] = bool(m["passed"] and ref["passed"])
    m["edge_peaks"] = {k: peaks_of(v, sc) for k, v in results.items()}
    return m


def peaks_of(result, sc) -> list[dict]:
    """The edge peak of each stage of one run (contact radius from its history)."""
    a = metrics.at_stages(result.history["s"], result.history["contact_radius"],
                          result.stage_s)
    peaks = edge_peak.stage_peaks(result.r, np.asarray(result.p), a)
    for q, s in zip(peaks, result.stage_s):
        q["s_hat"] = float(s * sc["s_hat_per_m"])
    return peaks


# -- the edge study (paper Section 4) ------------------------------------------

def edge_levels(case, results, sc) -> dict:
    """Per solver, the (label, overrides) of the extra runs of the edge study."""
    out = {}
    for name, key, n in (("mdr", "mdr.elements", case.mdr.elements),
                         ("fem", "fem.contact_nodes", case.fem.contact_nodes)):
        levels = [(f"grid x{g:g} ({key}={max(2, round(g * n))})",
                   [f"{key}={max(2, round(g * n))}"]) for g in EDGE_GRID_FACTORS]
        h = step_hat_used(results[name], sc["s_hat_per_m"])
        if math.isfinite(h):
            hs = EDGE_STEP_FACTOR * h
            levels.append((f"step x{EDGE_STEP_FACTOR:g} (sliding.step_hat={hs:.4g})",
                           [f"sliding.step_hat={hs!r}"]))
        out[name] = levels
    return out


def edge_study(case, results, *, solve=None, quiet=True) -> dict:
    """Edge peaks of MDR and FEM at the case's resolution and at coarser/finer grids and steps.

    Returns the study as written to metrics.json, with the extra runs under
    ``runs`` (label -> (solver, case, RunResult or error text)).
    """
    solve = solve or solve_case
    sc = reference.scales(case)
    toml = cases.to_toml(case)
    out = dict(solvers={}, runs={})
    for name, levels in edge_levels(case, results, sc).items():
        lv = [dict(label="case", overrides=[], spacing=grid_spacing(results[name], sc["a0"]),
                   step_hat=step_hat_used(results[name], sc["s_hat_per_m"]),
                   seconds=float(results[name].solve_seconds),
                   peaks=peaks_of(results[name], sc))]
        failed = []
        for label, overrides in levels:
            c = cases.from_dict(_raw(toml), source=case.source, overrides=overrides)
            bar = _progress(f"edge {name} {label}", quiet)
            try:
                res = solve(c, name, progress=bar)
            except cases.SolverError as exc:
                failed.append(dict(label=label, overrides=overrides, error=str(exc)))
                continue
            finally:
                bar.close()
            out["runs"][f"{name}-{_slug(label)}"] = (name, c, res)
            lv.append(dict(label=label, overrides=overrides,
                           spacing=grid_spacing(res, sc["a0"]),
                           step_hat=step_hat_used(res, sc["s_hat_per_m"]),
                           seconds=float(res.solve_seconds), peaks=peaks_of(res, sc)))
        out["solvers"][name] = dict(levels=[{k: v for k, v in d.items() if k != "peaks"}
                                            for d in lv],
                                    failed=failed, stages=edge_peak.assess(lv))
    return out


def _raw(toml_text):
    import tomllib
    return tomllib.loads(toml_text)


def _slug(text):
    return "".join(c if c.isalnum() or c in ".=" else "_" for c in text.split(" (")[0]
                   ).strip("_")


# -- the finite sphere (physics.md §7) ---------------------------------------

def sphere_case(case, ratio):
    """The case's body pressed (unworn, no sliding) to the depth whose half-space a0/R is ratio."""
    ind = case.indenter
    if ind.profile not in ("sphere", "paraboloid"):
        raise cases.CaseError(f"--sphere-sweep needs indenter.profile = \"sphere\" or "
                              f"\"paraboloid\", got \"{ind.profile}\"")
    R, a = ind.radius, ratio * ind.radius
    depth = a * math.atanh(a / R) if ind.profile == "sphere" else a * a / R
    return case.replace(
        loading=dataclasses.replace(case.loading, control="depth", depth=depth, force=None),
        sliding=dataclasses.replace(case.sliding, until="distance", distance=0.0),
        stages=dataclasses.replace(case.stages, s_hat=(0.0,)))


def sphere_sweep(case, ratios=SPHERE_RATIOS, *, solve=None, quiet=True) -> dict:
    """FEM force and contact radius at given approach against the half-space values."""
    solve = solve or solve_case
    rows = []
    for ratio in ratios:
        c = sphere_case(case, ratio)
        hs = reference.unworn_contact(c)
        bar = _progress(f"sphere a0/R={ratio:g}", quiet)
        try:
            res = solve(c, "fem", progress=bar)
        except cases.SolverError as exc:
            rows.append(dict(a0_over_R=ratio, depth=c.loading.depth, error=str(exc)))
            continue
        finally:
            bar.close()
        F, a = float(res.history["force"][0]), float(res.history["contact_radius"][0])
        rows.append(dict(a0_over_R=ratio, depth=c.loading.depth,
                         force_fem=F, force_half_space=hs["force"],
                         force_rel=F / hs["force"] - 1.0,
                         contact_radius_rel=a / hs["contact_radius"] - 1.0,
                         seconds=float(res.solve_seconds)))
    tol = case.compare.force_tolerance
    ok = [r["a0_over_R"] for r in rows if "force_rel" in r and abs(r["force_rel"]) <= tol]
    # the largest ratio below which every swept ratio stays within the tolerance
    limit = None
    for r in rows:
        if "force_rel" not in r or abs(r["force_rel"]) > tol:
            break
        limit = r["a0_over_R"]
    # ΔF/F ≈ c · a0/R for small a0/R; physics.md §7's approach shift (4/(3π)) a/R
    # with F ∝ d^(3/2) gives c = 2/π
    small = [(r["a0_over_R"], r["force_rel"]) for r in rows
             if "force_rel" in r and r["a0_over_R"] <= 0.02]
    slope = None
    if small:
        x, y = np.array(small).T
        slope = float(np.sum(x * y) / np.sum(x * x))
    shipped = {}
    for name in ("hertz", "paper", "truncated"):
        try:
            c = cases.load(cases.shipped(name))
            a0 = reference.scales(c)["a0"]
            shipped[name] = dict(a0_over_R=a0 / c.indenter.radius,
                                 worn_max_over_R=math.sqrt(2) * a0 / c.indenter.radius)
        except cases.CaseError:
            continue
    return dict(profile=case.indenter.profile, rows=rows, force_tolerance=tol,
                within_tolerance=ok, largest_ratio_within_tolerance=limit, shipped=shipped,
                slope=slope, ratio_at_tolerance=(tol / abs(slope) if slope else None))


# -- figures -----------------------------------------------------------------

def draw_figures(directory: Path, case, results, m) -> list[str]:
    """The comparison figures; returns their file names (PNG)."""
    from . import figures
    sc = m["scales"]
    a0, p0, d = sc["a0"], sc["p0"], m["profile_scale_depth"]
    K = m["stages_compared"]
    mdr, fem = results["mdr"], results["fem"]
    xmax = max(np.max(mdr.r), np.max(fem.r)) / a0
    prof, pres = [], []
    for k in range(K):
        st = m["stages"][k]
        base = dict(label=f"ŝ={st['s_hat_mdr']:.3g}",
                    mdr_label=f"MDR ŝ={st['s_hat_mdr']:.3g}, F/F0={st['force_mdr']:.3f}",
                    fem_label=f"FEM ŝ={st['s_hat_fem']:.3g}, F/F0={st['force_fem']:.3f}")
        prof.append(dict(base, mdr=(mdr.r / a0, mdr.f[k] / d), fem=(fem.r / a0, fem.f[k] / d)))
        pres.append(dict(base, mdr=(mdr.r / a0, mdr.p[k] / p0), fem=(fem.r / a0, fem.p[k] / p0)))
    names = []
    figures.stage_figure(directory / "fig2_profiles", prof, ylabel="f / d",
                         title="worn profiles (MDR lines, FEM markers)", xlim=(0, xmax))
    names.append("fig2_profiles.png")
    refs, vlines, ylim = [], [], None
    tr = m.get("truncated_reference")
    if tr is not None:
        b = case.indenter.flat_radius
        a = tr["contact_radius"] * a0
        r = np.linspace(0.0, a, 801)
        r = r[np.abs(r - b) > 1e-4 * a]  # the singularity itself is infinite
        p = reference.truncated_paraboloid_pressure(r, case.E_star, case.indenter.radius, b, a)
        refs = [dict(label="reference (quadrature, paper Eq. 13/19)", x=r / a0, y=p / p0)]
        vlines = [(b / a0, "r = b (singular)")]
        finite = [np.nanmax(st["mdr"][1]) for st in pres] + [np.nanmax(st["fem"][1])
                                                              for st in pres]
        ylim = (0.0, 1.15 * max(finite))
    figures.stage_figure(directory / "fig2_pressure", pres, ylabel="p / p0",
                         title="contact pressure (MDR lines, FEM markers)",
                         reference=refs, vlines=vlines, xlim=(0, xmax), ylim=ylim)
    names.append("fig2_pressure.png")
    curves = {}
    for name, res in results.items():
        h = res.history
        curves[name] = (np.asarray(h["s"]) * sc["s_hat_per_m"], np.asarray(h["force"]) / sc["F0"],
                        np.asarray(h["contact_radius"]) / a0)
    figures.history_figure(directory / "force_vs_sliding", curves,
                           stage_s_hat=[st["s_hat_mdr"] for st in m["stages"]])
    names.append("force_vs_sliding.png")
    return names


def draw_edge_study(directory: Path, study_results, sc) -> str | None:
    """Outer pressure at the first worn, a middle and the last stage, every level.

    study_results : list of (label, solver, RunResult). Writes edge_study/edge_peak.png.
    """
    from . import figures
    K = min(len(res.stage_s) for _, _, res in study_results)
    worn = list(range(1, K)) or list(range(K))
    ks = sorted({worn[0], worn[len(worn) // 2], worn[-1]}) if worn else []
    panels = []
    for k in ks:
        curves = []
        for label, solver, res in study_results:
            a = metrics.at_stages(res.history["s"], res.history["contact_radius"],
                                  res.stage_s[k:k + 1])[0]
            p = np.asarray(res.p[k])
            if p[0] > 0:
                curves.append((label, np.asarray(res.r) / a, p / p[0], solver))
        s_hat = study_results[0][2].stage_s[k] * sc["s_hat_per_m"]
        panels.append(dict(title=f"ŝ = {s_hat:.3g}", curves=curves))
    if not panels:
        return None
    figures.edge_study_figure(directory / "edge_study" / "edge_peak", panels)
    return "edge_study/edge_peak.png"


# -- renders (comparisons.render, another engineer's module) ------------------

RENDER_FUNCTIONS = ("render_run", "render_run_dir", "render")


def try_render(run_dirs) -> dict:
    """Render each run directory with ``comparisons.render`` if it exists; never raises.

    Returns {"images": [relative PNG paths found], "notes": [what went wrong]}.
    """
    notes = []
    try:
        from . import render as render_mod
    except Exception as exc:  # noqa: BLE001 - a missing or broken renderer is a note
        render_mod = None
        notes.append(f"no renders: comparisons.render not importable ({exc})")
    fn = None
    if render_mod is not None:
        fn = next((getattr(render_mod, n) for n in RENDER_FUNCTIONS
                   if callable(getattr(render_mod, n, None))), None)
        if fn is None:
            notes.append("no renders: comparisons.render has none of "
                         + ", ".join(RENDER_FUNCTIONS))
    for d in run_dirs:
        if fn is None:
            break
        try:
            fn(d)
        except Exception as exc:  # noqa: BLE001 - rendering must not fail the comparison
            notes.append(f"rendering {Path(d).name} failed: {type(exc).__name__}: {exc}")
    return dict(notes=notes)


def find_renders(directory: Path) -> list[str]:
    """PNG files the renderer wrote into the run directories (relative paths)."""
    out = []
    for sub in ("fem", "mdr"):
        out += sorted(str(p.relative_to(directory)) for p in (directory / sub).rglob("*.png"))
    return out


# -- report ------------------------------------------------------------------

def build_report(case, m, figure_names, renders, render_notes, prov) -> list:
    """The report's blocks (see comparisons.report)."""
    R = report
    sc = m["scales"]
    fmt = R.fmt
    blocks = []
    K = m["stages_compared"]
    verdict_text = (f"{K} stage(s) compared; every check within its tolerance."
                    if m["passed"] else _failure_text(m))
    blocks.append(R.verdict_block(m["passed"], verdict_text))
    ind = case.indenter
    blocks += [R.heading("Case"),
               R.para(f"Case file: {case.source}. Profile: {ind.profile}"
                      + (f", R = {ind.radius:g} m" if ind.radius else "")
                      + (f", b = {ind.flat_radius:g} m" if ind.flat_radius else "")
                      + f"; {case.loading.control} control; E* = {sc['E_star']:.4g} Pa."),
               R.table(["scale", "value"],
                       [["a0 [m]", fmt(sc["a0"], 5)], ["d0 [m]", fmt(sc["d0"], 5)],
                        ["F0 [N]", fmt(sc["F0"], 5)], ["p0 [Pa]", fmt(sc["p0"], 5)],
                        ["profile scale d [m]", fmt(m["profile_scale_depth"], 5)],
                        ["a0/R", fmt(sc["a0"] / ind.radius, 4) if ind.radius else "—"],
                        ["ŝ per metre of sliding", fmt(sc["s_hat_per_m"], 5)]]),
               R.para("Method: stage k of each solver is the k-th requested ŝ; the stages both "
                      "solvers reached are compared. The MDR fields are interpolated linearly "
                      "onto the FEM contact-node radii and the differences taken there. "
                      "Profiles are relative to d, pressures to p0, forces to F0, contact "
                      "radii to a0; force and contact radius of a stage are read from the "
                      "run's history at the stage's sliding distance. The pressure is compared "
                      f"in the interior r < (1 − {case.compare.edge_band:g})·a (a: the smaller "
                      "of the two contact radii) and reported separately in the edge band up "
                      f"to (1 + {case.compare.edge_band:g})·a of the larger one. F0 and a0 are "
                      "the analytic half-space values of the unworn contact, so at ŝ = 0 the "
                      "columns F/F0 and a/a0 measure each solver against that solution."),
               R.para(f"Stages requested (ŝ): {', '.join(f'{s:g}' for s in case.stages.s_hat)}; "
                      f"reached: MDR {m['stages_reached']['mdr']}, "
                      f"FEM {m['stages_reached']['fem']}; compared: {K}. Runs ended at "
                      + ", ".join(f"ŝ = {e['s_hat']:.4g} with F/F0 = {e['force']:.4g} ({n.upper()})"
                                  for n, e in m["run_end"].items()) + ".")]
    for w in case.warnings:
        blocks.append(R.para(f"Note: {w}"))
    tol = m["tolerances"]
    blocks += [R.heading("Metrics per stage"),
               R.para(f"Tolerances: profile {tol['profile_tolerance']:g}·d, force "
                      f"{tol['force_tolerance']:g}·F0, pressure (interior) "
                      f"{tol['pressure_tolerance']:g}·p0, contact radius "
                      f"{tol['contact_radius_tolerance']:g}·a0. A failed check is marked ✗.")]
    rows = []
    for st in m["stages"]:
        c = st["checks"]

        def mark(name, value):
            return fmt(value) + ("" if c[name]["passed"] else " ✗")
        rows.append([st["index"], fmt(st["s_hat_mdr"]), fmt(st["s_hat_fem"]),
                     fmt(st["force_mdr"], 4), fmt(st["force_fem"], 4), mark("force", st["force"]),
                     fmt(st["contact_radius_mdr"], 4), fmt(st["contact_radius_fem"], 4),
                     mark("contact_radius", st["contact_radius"]),
                     mark("profile_max", st["profile_max"]), fmt(st["profile_rms"]),
                     mark("pressure_interior_max", st["pressure_interior_max"]),
                     fmt(st["pressure_interior_rms"]), fmt(st["pressure_edge_max"]),
                     fmt(st["pressure_edge_rms"]), "pass" if st["passed"] else "FAIL"])
    blocks.append(R.para("Largest share of each tolerance used: " + "; ".join(
        f"{name} {100 * w['used']:.0f}% (stage {w['stage']}, {fmt(w['value'])} of "
        f"{fmt(w['tolerance'])})" for name, w in m["worst"].items()
        if w["stage"] is not None) + "."))
    blocks.append(R.table(["stage", "ŝ MDR", "ŝ FEM", "F/F0 MDR", "F/F0 FEM", "|ΔF|/F0",
                           "a/a0 MDR", "a/a0 FEM", "|Δa|/a0", "max|Δf|/d", "rms Δf/d",
                           "max|Δp|/p0 interior", "rms Δp/p0 interior", "max|Δp|/p0 edge",
                           "rms Δp/p0 edge", "verdict"], rows))
    h = m["history"]
    blocks.append(R.para(f"Over the whole common sliding range (ŝ ≤ "
                         f"{fmt(h['s_common_max'] * sc['s_hat_per_m'])}): max |ΔF|/F0 = "
                         f"{fmt(h['force_max'])}, max |Δa|/a0 = {fmt(h['contact_radius_max'])} "
                         "(FEM history interpolated onto MDR's steps; not part of the verdict)."))
    blocks.append(R.para(f"Solve time: MDR {m['solve_seconds']['mdr']:.3g} s, FEM "
                         f"{m['solve_seconds']['fem']:.3g} s. Grid spacing / a0: MDR "
                         f"{fmt(m['grid_spacing_over_a0']['mdr'])}, FEM "
                         f"{fmt(m['grid_spacing_over_a0']['fem'])}. Step Δŝ (median): MDR "
                         f"{fmt(m['step_hat']['mdr'])}, FEM {fmt(m['step_hat']['fem'])}."))
    blocks.append(R.heading("Figures"))
    captions = {"fig2_profiles.png": "Worn profiles f/d against r/a0 (paper Fig. 2a): MDR "
                                     "lines, FEM markers.",
                "fig2_pressure.png": "Contact pressure p/p0 against r/a0 (paper Fig. 2b): MDR "
                                     "lines, FEM markers.",
                "force_vs_sliding.png": "Normal force F/F0 and contact radius a/a0 against ŝ."}
    for name in figure_names:
        blocks.append(R.image(name, captions.get(name, name)))
    tr = m.get("truncated_reference")
    if tr is not None:
        blocks += [R.heading("Flattened sphere against the reference (paper Fig. 3)"),
                   R.para(f"Truncated paraboloid, b/a0 = {tr['flat_radius_over_a0']:.4g}; "
                          f"reference contact radius a/a0 = {tr['contact_radius']:.5g}, force "
                          f"F/F0 = {tr['force']:.5g}. Pressure differences relative to p0, "
                          f"away from the edge and from the singularity "
                          f"(|r − b| ≥ {case.compare.edge_band:g}·a)."),
                   R.table(["solver", "|ΔF|/F0", "|Δa|/a0", "max|Δp|/p0 away", "rms",
                            "max|Δp|/p0 near b", "max|Δp|/p0 edge", "verdict"],
                           [[n.upper(), fmt(v["force"]), fmt(v["contact_radius"]),
                             fmt(v["pressure_interior_max"]), fmt(v["pressure_interior_rms"]),
                             fmt(v["pressure_near_b_max"]), fmt(v["pressure_edge_max"]),
                             "pass" if v["passed"] else "FAIL"]
                            for n, v in tr["solvers"].items()])]
    blocks += _edge_blocks(m)
    if "sphere_sweep" in m:
        blocks += _sphere_blocks(m["sphere_sweep"])
    blocks.append(R.heading("Renders of the fields"))
    if renders:
        for name in renders:
            solver, stem = name.split("/")[0], Path(name).stem
            blocks.append(R.image(name, f"{solver.upper()} run, rendered by comparisons.render: "
                                        f"{stem.replace('_', ' ')} ({name})."))
    else:
        blocks.append(R.para("No renders in the run directories."))
    for note in render_notes:
        blocks.append(R.para(note))
    blocks += [R.heading("Provenance"),
               R.para(f"Command: {prov['command']}"),
               R.para(f"Working directory: {prov['cwd']}; git revision: {prov['git_revision']}; "
                      f"created {prov['created']} on {prov['host']}."),
               R.table(["package", "version"],
                       [[k, v or "—"] for k, v in prov["versions"].items()]),
               R.heading("Resolved case", 3), R.code(cases.to_toml(case))]
    return blocks


def _failure_text(m) -> str:
    failed = []
    for st in m["stages"]:
        for name, c in st["checks"].items():
            if not c["passed"]:
                failed.append(f"stage {st['index']} (ŝ={st['s_hat_mdr']:.3g}) {name} "
                              f"{report.fmt(c['value'])} > {c['tolerance']:g}")
    tr = m.get("truncated_reference")
    if tr is not None:
        for n, v in tr["solvers"].items():
            for name, c in v["checks"].items():
                if not c["passed"]:
                    failed.append(f"{n.upper()} vs reference {name} {report.fmt(c['value'])} > "
                                  f"{c['tolerance']:g}")
        if not tr["solvers"]:
            failed.append("no solver has an ŝ = 0 stage to compare with the reference")
    if m["stages_compared"] == 0:
        failed.append("no stage reached by both solvers")
    return "failed: " + "; ".join(failed)


def _peak_cell(q, with_edge=True) -> str:
    """One peak in a table cell: position, height, prominence (relative to p(0))."""
    if not q["present"]:
        if not with_edge:
            return "none"
        return f"none (p_edge/p(0)={report.fmt(q.get('edge_height'), 3)})"
    text = (f"r/a={report.fmt(q['r_over_a'], 4)}, p/p(0)={report.fmt(q['height'], 4)}, "
            f"prom.={report.fmt(q['prominence'], 2)}")
    return text + (" (last node)" if q["at_last_node"] else "")


def _edge_blocks(m) -> list:
    R = report
    fmt = R.fmt
    blocks = [R.heading("Edge peak (paper Section 4)"),
              R.para(f"An interior local maximum of p(r) in r ≥ {edge_peak.OUTER:g}·a counts as "
                     f"a peak when its prominence (height above the dip inward of it) exceeds "
                     f"{edge_peak.MIN_PROMINENCE:g} of max p. Cells give its position r/a, its "
                     "height p_peak/p(0) and its prominence relative to p(0); \"last node\": "
                     "the maximum is the outermost node in contact (not resolved by the grid). "
                     f"p_edge/p(0): the pressure at r = {edge_peak.EDGE_PROBE:g}·a relative to "
                     "p(0), how abruptly it falls to zero at the edge (Hertz: "
                     f"{math.sqrt(1 - edge_peak.EDGE_PROBE ** 2):.3f}).")]
    peaks = m["edge_peaks"]
    K = max(len(v) for v in peaks.values())
    rows = []
    for k in range(K):
        row = [k]
        for name in ("mdr", "fem"):
            q = peaks[name][k] if k < len(peaks[name]) else None
            if name == "mdr":
                row.append(fmt(q["s_hat"]) if q else "—")
            row += [_peak_cell(q, False), fmt(q["edge_height"])] if q else ["—", "—"]
        rows.append(row)
    blocks.append(R.table(["stage", "ŝ", "MDR peak", "MDR p_edge/p(0)", "FEM peak",
                           "FEM p_edge/p(0)"], rows))
    es = m.get("edge_study")
    if es is None:
        blocks.append(R.para("Resolution study not run (wearcheck compare --edge-study)."))
        return blocks
    blocks.append(R.heading("Edge peak at other resolutions and steps", 3))
    for name, sol in es["solvers"].items():
        lv = sol["levels"]
        blocks.append(R.para(f"{name.upper()} levels: " + "; ".join(
            f"{d['label']}: spacing {fmt(d['spacing'])}·a0, Δŝ {fmt(d['step_hat'])}, "
            f"{d['seconds']:.3g} s" for d in lv)))
        for f in sol["failed"]:
            blocks.append(R.para(f"{name.upper()} {f['label']} failed: {f['error']}"))
        rows = []
        for st in sol["stages"]:
            rows.append([st["stage"], fmt(st["levels"][0].get("s_hat"))]
                        + [_peak_cell(d) for d in st["levels"]]
                        + [f"{st['verdict']}: {st['reason']}"])
        labels = [d["label"].split(" (")[0] for d in lv]
        blocks.append(R.table(["stage", "ŝ"] + [f"{name.upper()} {x}" for x in labels]
                              + ["verdict"], rows))
    blocks.append(R.para("Answer: " + es["summary"]))
    if es.get("figure"):
        blocks.append(R.image(es["figure"], "p/p(0) against r/a near the edge at every level "
                                            "(MDR lines, FEM markers)."))
    return blocks


def summarise_edge_study(es) -> str:
    """One plain sentence per solver: converged peak, numerical peak, or none."""
    parts = []
    for name, sol in es["solvers"].items():
        verdicts = [st["verdict"] for st in sol["stages"]]
        worn = [st for st in sol["stages"] if st["stage"] > 0] or sol["stages"]
        conv = [st["stage"] for st in worn if st["verdict"] == "converged"]
        dep = [st["stage"] for st in worn if st["verdict"] == "resolution-dependent"]
        none = [st["stage"] for st in worn if st["verdict"] == "no peak"]
        text = f"{name.upper()}: "
        if conv:
            text += f"a converged edge peak at stage(s) {conv}"
        if dep:
            text += ("; " if conv else "") + f"a resolution-dependent (numerical) peak at " \
                                               f"stage(s) {dep}"
        if none:
            text += ("; " if conv or dep else "") + f"no peak at stage(s) {none}"
        if not verdicts:
            text += "no stage"
        last = sol["stages"][-1]["levels"] if sol["stages"] else []
        edge = [d["edge_height"] for d in last if math.isfinite(d.get("edge_height", math.nan))]
        if edge:
            text += (f"; at the last stage p(r = {edge_peak.EDGE_PROBE:g} a)/p(0) = "
                     f"{min(edge):.3g} to {max(edge):.3g} over the levels")
        parts.append(text)
    return ". ".join(parts) + "."


def _sphere_blocks(sw) -> list:
    R = report
    fmt = R.fmt
    rows = []
    for r in sw["rows"]:
        if "error" in r:
            rows.append([fmt(r["a0_over_R"]), fmt(r["depth"], 4), "failed: " + r["error"], "",
                         "", ""])
        else:
            rows.append([fmt(r["a0_over_R"]), fmt(r["depth"], 4), fmt(r["force_fem"], 5),
                         fmt(r["force_half_space"], 5), f"{100 * r['force_rel']:+.3f}%",
                         f"{100 * r['contact_radius_rel']:+.3f}%"])
    shipped = "; ".join(f"{k}: a0/R = {v['a0_over_R']:.4g} (worn up to √2·a0: "
                        f"{v['worn_max_over_R']:.4g})" for k, v in sw["shipped"].items())
    lim = sw["largest_ratio_within_tolerance"]
    return [R.heading("Finite sphere against the half-space"),
            R.para(f"FEM ({sw['profile']}) pressed without sliding to the depth whose "
                   "half-space contact radius is a0; force compared with the half-space value "
                   "(cases.reference.unworn_contact). The difference includes the FEM's own "
                   "discretisation error."),
            R.table(["a0/R", "depth [m]", "F FEM [N]", "F half-space [N]", "ΔF/F",
                     "Δa/a"], rows),
            R.para(f"Within the force tolerance {sw['force_tolerance']:g}: a0/R ≤ "
                   f"{fmt(lim)} (every swept ratio up to it). Fit over a0/R ≤ 0.02: ΔF/F ≈ "
                   f"{fmt(sw['slope'])}·a0/R (physics.md §7 estimate: 2/π ≈ 0.637), so the "
                   f"finite sphere alone uses the whole force tolerance at a0/R ≈ "
                   f"{fmt(sw['ratio_at_tolerance'])}. Shipped cases: {shipped}."),
            ] + ([R.image(sw["figure"], "FEM force relative to the half-space force against "
                                        "a0/R.")] if sw.get("figure") else [])


# -- the whole comparison ---------------------------------------------------

def compare(case, out, *, argv=None, edge=False, sphere=False, sphere_ratios=SPHERE_RATIOS,
            solve=None, quiet=True, render=True) -> dict:
    """Run both solvers on ``case`` and write the comparison directory ``out`` atomically.

    Returns the metrics (as in metrics.json); ``passed`` is the verdict.
    """
    t0 = time.perf_counter()
    from .outputs import check_output
    check_output(out, "comparison")  # before the solves
    from .resources import check_memory
    for name in ("mdr", "fem"):
        check_memory(case, name)
    solve = solve or solve_case
    results = run_both(case, solve=solve, quiet=quiet)
    m = analyse(case, results)
    study = None
    if edge:
        study = edge_study(case, results, solve=solve, quiet=quiet)
        study["summary"] = summarise_edge_study(study)
    sweep = sphere_sweep(case, sphere_ratios, solve=solve, quiet=quiet) if sphere else None
    prov = runio.provenance(argv)
    out = Path(out)
    with runio.atomic_directory(out, "comparison") as tmp:
        for name, res in results.items():
            (tmp / name).mkdir()
            runio.write_run_files(tmp / name, case, res, name, argv)
        figure_names = draw_figures(tmp, case, results, m)
        if study is not None:
            runs = study.pop("runs")
            (tmp / "edge_study").mkdir()
            for sub, (name, c, res) in runs.items():
                (tmp / "edge_study" / sub).mkdir()
                runio.write_run_files(tmp / "edge_study" / sub, c,
                                      dataclasses.replace(res, fields=None), name, argv)
            curves = []
            for n in ("mdr", "fem"):
                curves.append((f"{n.upper()} case", n, results[n]))
                curves += [(f"{name.upper()} {sub.split('-', 1)[1]}", name, res)
                           for sub, (name, c, res) in runs.items() if name == n]
            study["figure"] = draw_edge_study(tmp, curves, m["scales"])
            m["edge_study"] = study
        if sweep is not None:
            from . import figures
            good = [r for r in sweep["rows"] if "force_rel" in r]
            if good:
                figures.sphere_sweep_figure(
                    tmp / "finite_sphere", [r["a0_over_R"] for r in good],
                    [r["force_rel"] for r in good], tolerance=sweep["force_tolerance"],
                    shipped=[(v["a0_over_R"], k) for k, v in sweep["shipped"].items()])
                sweep["figure"] = "finite_sphere.png"
            m["sphere_sweep"] = sweep
        notes = try_render([tmp / "fem", tmp / "mdr"])["notes"] if render else []
        renders = find_renders(tmp)
        m["renders"] = renders
        m["render_notes"] = notes
        m["provenance"] = prov
        m["case_source"] = case.source
        m["seconds_total"] = time.perf_counter() - t0
        runio.write_json(tmp / "metrics.json", m)
        (tmp / "case.toml").write_text(cases.to_toml(case), encoding="utf-8")
        blocks = build_report(case, m, figure_names, renders, notes, prov)
        report.write(tmp, blocks, f"wearcheck compare: {Path(case.source).name}")
    return m


def print_summary(m, out, stream=sys.stderr) -> None:
    """A few lines for the terminal."""
    for st in m["stages"]:
        print(f"  ŝ={st['s_hat_mdr']:<6.3g} F/F0 {st['force_mdr']:.4f}/{st['force_fem']:.4f}  "
              f"|Δf|/d {st['profile_max']:.2e}  |Δp|/p0 {st['pressure_interior_max']:.2e} "
              f"(edge {st['pressure_edge_max']:.2e})  |Δa|/a0 {st['contact_radius']:.2e}  "
              f"{'ok' if st['passed'] else 'FAIL'}", file=stream)
    print(f"compare: {'PASS' if m['passed'] else 'FAIL'} -> {out}/report.html", file=stream)
