"""The edge-peak study (paper Section 4): is a pressure maximum near the border of the
worn contact converged, or does it move with the grid and the step?

Each solver runs again at a coarser and a finer grid (its registry entry's
resolution key) and at half its step; ``analysis.edge_peak`` finds and judges
the peaks (docs/theory.md, the edge peak).
"""

from __future__ import annotations

import math

from wearcheck import cases
from wearcheck.cases import reference
from wearcheck import registry
from wearcheck.comparisons.analysis import edge_peak
from wearcheck.comparisons.analysis.diagnosis import grid_spacing, step_hat_used
from wearcheck.comparisons.present.progress import ProgressBar

#: grid refinement factors of the edge study, relative to the case
EDGE_GRID_FACTORS = (0.5, 2.0)
#: step factor of the edge study, relative to the step the case's run used
EDGE_STEP_FACTOR = 0.5


def resolution_of(case, key: str):
    """The value of a dotted case key, e.g. ``resolution_of(case, "mdr.elements")``."""
    section, name = key.split(".")
    return getattr(getattr(case, section), name)


def edge_levels(case, results, sc) -> dict:
    """Per solver, the (label, changes) of the extra runs of the edge study: the keys each
    changes in the case, typed (``{"mdr.elements": 400}``)."""
    out = {}
    for name in results:
        key = registry.get(name).resolution_key
        if key is None:
            continue
        n = resolution_of(case, key)
        levels = [(f"grid x{g:g} ({key}={max(2, round(g * n))})",
                   {key: max(2, round(g * n))}) for g in EDGE_GRID_FACTORS]
        h = step_hat_used(results[name], sc["s_hat_per_m"])
        if math.isfinite(h):
            hs = EDGE_STEP_FACTOR * h
            levels.append((f"step x{EDGE_STEP_FACTOR:g} (sliding.step_hat={hs:.4g})",
                           {"sliding.step_hat": hs}))
        out[name] = levels
    return out


def edge_study(case, results, *, solve=None, quiet=True) -> dict:
    """Edge peaks of every solver at the case's resolution and at coarser/finer grids and steps.

    Returns the study as written to metrics.json, with the extra runs under
    ``runs`` (label -> (solver, case, RunResult or error text)).
    """
    solve = solve or registry.solve
    sc = reference.scales(case)
    out = dict(solvers={}, runs={})
    for name, levels in edge_levels(case, results, sc).items():
        lv = [dict(label="case", changes={}, spacing=grid_spacing(results[name], sc["a0"]),
                   step_hat=step_hat_used(results[name], sc["s_hat_per_m"]),
                   seconds=float(results[name].solve_seconds),
                   peaks=edge_peak.peaks_of(results[name], sc))]
        failed = []
        for label, changes in levels:
            c = case.derive(changes)
            bar = ProgressBar(f"edge {name} {label}", quiet=quiet)
            try:
                res = solve(c, name, progress=bar)
            except cases.SolverError as exc:
                failed.append(dict(label=label, changes=changes, error=str(exc)))
                continue
            finally:
                bar.close()
            out["runs"][f"{name}-{_slug(label)}"] = (name, c, res)
            lv.append(dict(label=label, changes=changes,
                           spacing=grid_spacing(res, sc["a0"]),
                           step_hat=step_hat_used(res, sc["s_hat_per_m"]),
                           seconds=float(res.solve_seconds),
                           peaks=edge_peak.peaks_of(res, sc)))
        out["solvers"][name] = dict(levels=[{k: v for k, v in d.items() if k != "peaks"}
                                            for d in lv],
                                    failed=failed, stages=edge_peak.assess(lv))
    out["summary"] = summarise_edge_study(out)
    return out


def _slug(text):
    return "".join(c if c.isalnum() or c in ".=" else "_" for c in text.split(" (")[0]
                   ).strip("_")


def summarise_edge_study(es) -> str:
    """One plain sentence per solver: converged peak, numerical peak, or none."""
    parts = []
    for name, sol in es["solvers"].items():
        verdicts = [st["verdict"] for st in sol["stages"]]
        worn = [st for st in sol["stages"] if st["stage"] > 0] or sol["stages"]
        conv = [st["stage"] for st in worn if st["verdict"] == "converged"]
        dep = [st["stage"] for st in worn if st["verdict"] == "resolution-dependent"]
        none = [st["stage"] for st in worn if st["verdict"] == "no peak"]
        text = f"{registry.get(name).title}: "
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


