"""The figures of a comparison: paper Fig. 2 overlays of every solver, the force
history, the edge study and the finite-sphere sweep; renders of the run directories.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.cases import WearcheckError, reference
from wearcheck import registry
from wearcheck.comparisons.analysis import metrics
from wearcheck.comparisons.present import figures
from wearcheck.extras import MissingExtra


def _style_word(style: dict) -> str:
    return "markers" if style.get("marker") else "lines"


def draw_figures(directory: Path, case, results, m) -> list[str]:
    """The comparison figures; returns their file names (PNG)."""
    sc = m["scales"]
    a0, p0, d = sc["a0"], sc["p0"], m["profile_scale_depth"]
    K = m["stages_compared"]
    ref = m["reference"]
    xmax = max(np.max(res.r) for res in results.values()) / a0
    prof, pres = [], []
    for k in range(K):
        s_ref = results[ref].stage_s[k] * sc["s_hat_per_m"]
        series_f, series_p = [], []
        for name, res in results.items():
            entry = registry.get(name)
            F = metrics.at_stages(res.history["s"], res.history["force"], res.stage_s[k:k + 1])[0]
            label = (f"{entry.title} ŝ={res.stage_s[k] * sc['s_hat_per_m']:.3g}, "
                     f"F/F0={F / sc['F0']:.3f}")
            series_f.append(dict(x=res.r / a0, y=res.f[k] / d, label=label, style=entry.style))
            series_p.append(dict(x=res.r / a0, y=res.p[k] / p0, label=label, style=entry.style))
        prof.append(dict(label=f"ŝ={s_ref:.3g}", series=series_f))
        pres.append(dict(label=f"ŝ={s_ref:.3g}", series=series_p))
    styles = ", ".join(f"{registry.get(n).title} {_style_word(registry.get(n).style)}"
                       for n in results)
    names = []
    figures.stage_figure(directory / "fig2_profiles", prof, ylabel="f / d",
                         title=f"worn profiles ({styles})", xlim=(0, xmax))
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
        finite = [np.nanmax(s["y"]) for st in pres for s in st["series"]]
        ylim = (0.0, 1.15 * max(finite))
    figures.stage_figure(directory / "fig2_pressure", pres, ylabel="p / p0",
                         title=f"contact pressure ({styles})",
                         reference=refs, vlines=vlines, xlim=(0, xmax), ylim=ylim)
    names.append("fig2_pressure.png")
    curves = {}
    for name, res in results.items():
        h = res.history
        curves[registry.get(name).title] = (np.asarray(h["s"]) * sc["s_hat_per_m"],
                                            np.asarray(h["force"]) / sc["F0"],
                                            np.asarray(h["contact_radius"]) / a0)
    figures.history_figure(directory / "force_vs_sliding", curves,
                           stage_s_hat=[s * sc["s_hat_per_m"] for s in results[ref].stage_s[:K]])
    names.append("force_vs_sliding.png")
    return names


def draw_edge_study(directory: Path, study_results, sc) -> str | None:
    """Outer pressure at the first worn, a middle and the last stage, every level.

    study_results : list of (label, solver, RunResult). Writes edge_study/edge_peak.png.
    """
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
                curves.append((label, np.asarray(res.r) / a, p / p[0],
                               registry.get(solver).style))
        s_hat = study_results[0][2].stage_s[k] * sc["s_hat_per_m"]
        panels.append(dict(title=f"ŝ = {s_hat:.3g}", curves=curves))
    if not panels:
        return None
    figures.edge_study_figure(directory / "edge_study" / "edge_peak", panels)
    return "edge_study/edge_peak.png"


# -- renders ------------------------------------------------------------------

RENDER_FUNCTIONS = ("render_run", "render_run_dir", "render")


def try_render(run_dirs) -> dict:
    """Render each run directory with ``comparisons.render`` if it exists; never raises.

    Returns {"images": [relative PNG paths found], "notes": [what went wrong]}.
    """
    notes = []
    try:
        from wearcheck.comparisons.present import render as render_mod
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
        except MissingExtra as exc:   # one note, not one per run directory
            notes.append(f"no renders: {exc}")
            break
        except WearcheckError as exc:  # said in one line, the partial directory's path not
            notes.append(str(exc).replace(f"'{d}'", Path(d).name))
        except Exception as exc:  # noqa: BLE001 - rendering must not fail the comparison
            notes.append(f"rendering {Path(d).name} failed: {type(exc).__name__}: {exc}")
    return dict(notes=notes)


def find_renders(directory: Path, names) -> list[str]:
    """PNG files the renderer wrote into the run directories (relative paths)."""
    out = []
    for sub in names:
        out += sorted(str(p.relative_to(directory)) for p in (directory / sub).rglob("*.png"))
    return out


def draw_sphere_sweep(directory: Path, sweep: dict) -> str | None:
    """finite_sphere.png: the solver's force relative to the half-space against a0/R."""
    good = [r for r in sweep["rows"] if "force_rel" in r]
    if not good:
        return None
    figures.sphere_sweep_figure(
        directory / "finite_sphere", [r["a0_over_R"] for r in good],
        [r["force_rel"] for r in good], tolerance=sweep["force_tolerance"],
        shipped=[(v["a0_over_R"], k) for k, v in sweep["shipped"].items()])
    return "finite_sphere.png"
