"""Audit of the implicit step's contact check (mdr.wear.FarGap) against the full transform.

Each case runs twice in this process: with the check as shipped, every call of
``FarGap.check`` also compared with the full transform's answer (the nodes i >= n
with d - g_i > tol·d, g = to_1d(f) of the whole grid), and every state an implicit
step returns checked for penetration beyond its contact on the whole grid; then
with the bound made to fail always (every check does the full transform). The
two histories are compared column by column.

    python benchmarks/audit_contact_check.py [NAME ...]

Prints one line per case: checks, checks the bound cleared (at the edge / beyond
the window), full transforms, disagreements of the check with the full transform,
penetrating accepted states, the largest relative difference of the histories.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from wearcheck import cases, mdr
from wearcheck.cases import reference
from wearcheck.mdr import transforms, wear

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "cases"


class Audit:
    """Wraps FarGap.check and wear.implicit_step for one run."""

    def __init__(self):
        self.checks = self.edge_clears = self.window_clears = self.fulls = 0
        self.far = 0            # checks with penetrating nodes beyond the window
        self.mismatch = []      # (n, d, shipped below, full below)
        self.penetrating = []   # (m, depth, worst (d - g)/d beyond m)
        self.min_margin = np.inf   # smallest (g_i - d)/|d| over cleared nodes
        self._check, self._step, self._full = wear.FarGap.check, wear.implicit_step, \
            wear.FarGap.full

    def install(self, forced_full):
        audit = self

        def full(self, f):
            audit.fulls += 1
            return audit._full(self, f)

        def check(self, f, n, d, tol):
            audit.checks += 1
            below, g = audit._check(self, f, n, d, tol)
            if g is None:
                audit.edge_clears += 1
            elif len(g) < len(f) - n + 1:
                audit.window_clears += 1
            g_all = transforms.to_1d(f)
            below_full = (d - g_all[n:] > tol * d).nonzero()[0]
            audit.far += int(np.any(below_full >= wear.EDGE_WINDOW))
            if not np.array_equal(np.asarray(below), below_full):
                audit.mismatch.append((n, d, list(below)[:5], list(below_full)[:5]))
            if len(below) == 0 and len(g_all) > n:
                audit.min_margin = min(audit.min_margin,
                                       float(np.min(g_all[n:] - d) / abs(d)) if d else np.inf)
            return below, g

        def step(model, state, *args, **kwargs):
            new = audit._step(model, state, *args, **kwargs)
            g = transforms.to_1d(new.f)
            excess = (new.depth - g[new.m + 1:]) / abs(new.depth)
            if excess.size and excess.max() > wear.EDGE_TOL:
                audit.penetrating.append((new.m, new.depth, float(excess.max())))
            return new

        wear.FarGap.check, wear.FarGap.full = check, full
        wear.implicit_step = step
        if forced_full:
            self._clears_saved = wear.FarGap._clears
            wear.FarGap._clears = lambda *a: False

    def remove(self):
        wear.FarGap.check, wear.FarGap.full = self._check, self._full
        wear.implicit_step = self._step
        if hasattr(self, "_clears_saved"):
            wear.FarGap._clears = self._clears_saved


def run(case, forced_full):
    audit = Audit()
    audit.install(forced_full)
    try:
        res = mdr.solve(case)
    except Exception as exc:        # (a refusal is a result here too)
        res = f"{type(exc).__name__}: {str(exc)[:100]}"
    finally:
        audit.remove()
    return res, audit


def history_difference(a, b):
    worst = 0.0
    for k, va in a.history.items():
        va, vb = np.asarray(va, dtype=float), np.asarray(b.history[k], dtype=float)
        if va.shape != vb.shape:
            return np.inf
        ok = np.isfinite(va) & np.isfinite(vb)
        if not np.array_equal(np.isfinite(va), np.isfinite(vb)):
            return np.inf
        scale = np.max(np.abs(va[ok])) if ok.any() else 0.0
        if scale > 0:
            worst = max(worst, float(np.max(np.abs(va[ok] - vb[ok])) / scale))
    return worst


def table_case(directory, name, r, f, **over):
    """A case of the tabulated profile (r, f) beside a TOML file in ``directory``."""
    csv = directory / f"{name}.csv"
    f = np.array(f, dtype=float)
    f[0] = 0.0
    csv.write_text("".join(f"{float(ri)!r},{float(fi)!r}\n" for ri, fi in zip(r, f)))
    raw = dict(indenter=dict(profile="table", file=str(csv), youngs_modulus=210e9,
                             poisson_ratio=0.3),
               loading=dict(control="depth", depth=1e-6),
               wear=dict(k=1e-4, mu=0.3, hardness=2e9),
               sliding=dict(until="force_fraction", force_fraction=0.05,
                            scheme="adaptive", tolerance=1e-4),
               stages=dict(s_hat=[0.0]),
               mdr=dict(elements=400))
    for key, value in over.items():
        section, k = key.split(".")
        if value is None:
            raw[section].pop(k, None)
        else:
            raw.setdefault(section, {})[k] = value
    return cases.from_dict(raw, source=directory / f"{name}.toml")


def adversarial(directory):
    """Table profiles whose far field comes close to the depth: a dip, bumps, noise."""
    R = 0.01
    r = np.linspace(0.0, 4e-4, 2001)
    sphere = r**2 / (2 * R)
    out = {}
    # a sphere whose far field dips back to 5 % of its height around r = 2.2 a0
    # (a0 = 1e-4 m): the 1D profile there comes within a few % of the depth
    dip = sphere * (1 - 0.9 * np.exp(-((r - 2.2e-4) / 4e-5) ** 2))
    dip[0] = 0.0
    out["table_far_dip"] = table_case(directory, "dip", r, np.maximum(dip, 1e-12), **{
        "mdr.domain_factor": 3.0})
    # a dip that comes below the depth later in the run (the worn cap pulls g down)
    for depth_frac, name in ((0.98, "table_dip_grazing"), (0.9, "table_dip_deep")):
        deep = sphere * (1 - depth_frac * np.exp(-((r - 2.5e-4) / 3e-5) ** 2))
        deep[0] = 0.0
        out[name] = table_case(directory, name, r, np.maximum(deep, 1e-13),
                               **{"mdr.domain_factor": 3.0})
    # a bump far outside the contact (raises g far out: must change nothing)
    bump = sphere + 2e-6 * np.exp(-((r - 3e-4) / 2e-5) ** 2)
    out["table_far_bump"] = table_case(directory, "bump", r, bump, **{"mdr.domain_factor": 3.6})
    # random smooth profiles: the sphere times 1 + a random Fourier series
    rng = np.random.default_rng(11)
    for k in range(3):
        mod = 1 + sum(0.3 / (j + 1) * rng.standard_normal() * np.sin((j + 1) * np.pi * r / 4e-4
                                                                    + rng.random() * 6)
                      for j in range(8))
        f = sphere * np.maximum(mod, 0.05)
        f[0] = 0.0
        out[f"table_random_{k}"] = table_case(directory, f"random{k}", r, f, **{
            "mdr.domain_factor": 3.0})
    # a far dip whose 1D profile goes negative (-5 d): contact there from the start
    rw = np.linspace(0.0, 2e-3, 4001)
    sw = rw**2 / (2 * R)
    drop = np.where(rw < 1.5e-4, sw,
                    np.maximum(sw * (1 - 0.999 * np.exp(-((rw - 2e-4) / 2e-5) ** 2)), 1e-10))
    out["table_drop_depth"] = table_case(directory, "drop", rw, drop, **{
        "mdr.domain_factor": 3.0})
    out["table_drop_force"] = table_case(directory, "dropf", rw, drop, **{
        "mdr.domain_factor": 3.0, "loading.control": "force", "loading.force": 10.0,
        "loading.depth": None, "sliding.until": "distance", "sliding.distance": 2e-3,
        "sliding.force_fraction": None})
    # force control on the dip
    out["table_dip_force"] = table_case(directory, "dipf", r, np.maximum(dip, 1e-12), **{
        "mdr.domain_factor": 3.0, "loading.control": "force", "loading.force": 10.0,
        "loading.depth": None, "sliding.until": "distance", "sliding.distance": 2e-3,
        "sliding.force_fraction": None})
    return out


def shipped():
    out = {}
    for name in ("paper", "ball_on_flat", "ball_on_flat_steel", "ellipsoid", "truncated",
                 "hertz", "pin_on_disc"):
        out[name] = cases.load(SHIPPED / f"{name}.toml")
    p = SHIPPED / "paper.toml"
    out["paper_bdf2"] = cases.load(p, ["sliding.scheme=\"bdf2\"", "sliding.step_hat=0.05"])
    out["paper_implicit"] = cases.load(p, ["sliding.scheme=\"implicit\"",
                                           "sliding.step_hat=0.05"])
    out["paper_exponent"] = cases.load(p, ["wear.pressure_exponent=1.5", "mdr.elements=200"])
    per = reference.scales(out["paper"])["s_hat_per_m"]
    out["paper_force"] = cases.load(p, ["loading.control=\"force\"", "loading.force=20.0",
                                        "sliding.until=\"distance\"",
                                        f"sliding.distance={10.0 / per!r}"])
    out["paper_tangential"] = cases.load(p, ["wear.tangential_correction=true",
                                             "sliding.stroke=0.001"])
    out["paper_N3000"] = cases.load(p, ["mdr.elements=3000"])
    out["paper_small_domain"] = cases.load(p, ["mdr.domain_factor=1.2"])
    out["truncated_sliding"] = cases.load(SHIPPED / "truncated.toml", [
        "sliding.until=\"force_fraction\"", "sliding.force_fraction=0.05",
        "sliding.scheme=\"adaptive\"", "sliding.tolerance=1e-4"])
    for name, keys in (("cone", ["indenter.profile=\"cone\"", "indenter.slope_angle=0.01"]),
                       ("power_law", ["indenter.profile=\"power_law\"",
                                      "indenter.coefficient=50.0", "indenter.exponent=2.5"])):
        out[name] = cases.load(p, keys)
    return out


def main(names):
    with tempfile.TemporaryDirectory() as tmp:
        every = {**shipped(), **adversarial(Path(tmp))}
        for name, case in every.items():
            if names and name not in names:
                continue
            t0 = time.process_time()
            (a, audit), (b, forced) = run(case, False), run(case, True)
            if isinstance(a, str) or isinstance(b, str):
                same = "the same" if a == b else "DIFFERENT"
                print(f"{name:22s} refused ({same} with the full transform): "
                      f"{a if isinstance(a, str) else 'ran'} | "
                      f"{b if isinstance(b, str) else 'ran'} | checks {audit.checks} far "
                      f"penetrating {audit.far} mismatches {len(audit.mismatch)} penetrating "
                      f"{len(audit.penetrating)}")
                continue
            diff = history_difference(a, b)
            print(f"{name:22s} checks {audit.checks:5d} cleared edge {audit.edge_clears:5d} "
                  f"window {audit.window_clears:5d} full {audit.fulls:4d} "
                  f"far penetrating {audit.far:3d} | "
                  f"mismatches {len(audit.mismatch)} (forced {len(forced.mismatch)}) "
                  f"penetrating {len(audit.penetrating)} (forced {len(forced.penetrating)}) | "
                  f"history rel diff {diff:.1e} steps {len(a.history['s'])} "
                  f"growths {a.info.get('domain_growths', '?')} | "
                  f"min margin {audit.min_margin:.1e} | {time.process_time() - t0:.1f} s",
                  flush=True)
            for item in audit.mismatch[:3]:
                print("    mismatch", item)
            for item in audit.penetrating[:3]:
                print("    penetrating", item)


if __name__ == "__main__":
    main(sys.argv[1:])
