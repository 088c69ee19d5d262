"""
From a G133 measurement sheet to K
==================================

A reciprocating ball-on-flat test after ASTM G133, procedure A: a 9.525 mm
(3/8 in) bearing-steel ball on a steel flat, 25 N, 10 mm stroke. The test was
interrupted at 50, 100, 250, 500, 1000 and 2000 cycles and the ball's wear
scar measured under an optical microscope, ± 5 µm. What is the ball's
specific wear rate K [m³/(N·m)], with an honest interval?

The lab's way: the scar taken for a flat cut through a rigid sphere,
V = π D⁴/(64 R), and K = V/(F s). Early in a test much of the scar is the
elastic Hertz contact, which that formula counts as wear: it overstates K.
``wearcheck fit`` fits K against the MDR instead, the ball's elastic contact
and its wear together, and gives a 95 % interval from the profile likelihood,
each measurement's residual and a test of whether the wear law fits at all.
One MDR run serves every K: at a fixed wear law the worn state depends on
K·s only (docs: *Fitting wear coefficients*).
"""

# %%
# The measurement sheet
# ---------------------
# Units go in the header, one column per quantity; ``± D`` is the uncertainty
# of ``D``. Other columns a sheet may have: ``s [m]`` instead of cycles,
# ``V [mm^3]`` (the ball's volume, e.g. by profilometry), ``h [um]`` (its
# central wear depth), each with a ``±`` column.
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import wearcheck

Path("g133_sheet.csv").write_text("""\
# ASTM G133 procedure A, 52100 ball (9.525 mm) on a 52100 flat, 25 N, 10 mm stroke, 5 Hz
cycles, D [um], ± D [um]
50,     295.0,  5
100,    357.0,  5
250,    440.0,  5
500,    517.5,  5
1000,   608.5,  5
2000,   739.5,  5
""", encoding="utf-8")

# %%
# The case: the rig
# -----------------
# Bearing steel on bearing steel (E* from both bodies; only the ball wears in
# this model), μ = 0.6 measured on the rig, hardness 7.8 GPa (about 800 HV).
# ``wear.specific_rate`` is where the fit starts from; any value does.
Path("g133.toml").write_text("""\
[indenter]
profile = "sphere"
radius = 4.7625e-3        # m
youngs_modulus = 210e9    # Pa
poisson_ratio = 0.3

[counterface]
rigid = false
youngs_modulus = 210e9
poisson_ratio = 0.3

[loading]
control = "force"
force = 25.0              # N

[wear]
specific_rate = 1e-15     # m³/(N·m): replaced by the fit
mu = 0.6
hardness = 7.8e9          # Pa

[sliding]
until = "cycles"
stroke = 0.010            # m, one way
cycles = 2000

[mdr]
elements = 400
""", encoding="utf-8")
case = wearcheck.load_case("g133.toml")

# %%
# The fit
# -------
# ``out`` also writes a fit directory: ``fit.json``, ``measurements.csv``,
# ``fit.png`` and the fitted case, with the provenance in ``meta.json``. The
# command line does the same:
# ``wearcheck fit g133.toml g133_sheet.csv --fit wear.specific_rate --out runs/g133-fit``.
result = wearcheck.fit(case, "g133_sheet.csv", "wear.specific_rate", out="runs/g133-fit")
K = result.parameters["wear.specific_rate"]
lab = result.lab["scar_diameter"]
gof = result.goodness_of_fit
print(f"fit:         K = {K['value']:.4g} m³/(N·m), 95 % interval "
      f"[{K['ci95'][0]:.4g}, {K['ci95'][1]:.4g}]")
print(f"lab formula: K = {lab['K']:.4g} m³/(N·m) (π D⁴/64R over F·s, all measurements)")
print(f"goodness of fit: χ² = {gof['statistic']:.3g} for {gof['dof']} degrees of freedom, "
      f"p = {gof['p_value']:.3g}")
check = result.model["resolution"]     # the fit repeated on a coarser model
print(f"model: {len(result.model['runs'])} MDR run(s); "
      + (check["meaning"] if check["error"] is None else
         f"K changes by {100 * check['change']:+.2f} % from mdr.elements = "
         f"{check['elements'][0]} to {check['elements'][1]}"))

# %%
# Measurement by measurement
# --------------------------
# The residual is (measured − model)/±. The lab formula leaves the elastic
# contact out, so its K overestimates most while the scar is not yet twice the
# Hertz contact (2 a_H = 184 µm); in this sheet that shows as the first
# measurements' lab K above the fit, by about as much as their noise, and the
# later ones scattering around it.
print(f"{'cycles':>7} {'D µm':>7} {'model µm':>9} {'residual':>9} {'lab K':>10}")
for m in result.measurements:
    print(f"{m['cycles']:>7.0f} {m['measured'] * 1e6:>7.1f} {m['model'] * 1e6:>9.1f} "
          f"{m['residual']:>+9.2f} {m['lab_K']:>10.3e}")

# %%
# The figure
# ----------
# Measured scars with their uncertainty, the fitted model, and the scar the
# lab formula implies for its own K (D = (64 R K F s/π)^¼).
s_model, model = result.curve
cycles = np.array([m["cycles"] for m in result.measurements])
D = np.array([m["measured"] for m in result.measurements])
dD = np.array([m["uncertainty"] for m in result.measurements])
per_cycle = 2 * case.sliding.stroke
R, F = case.indenter.radius, case.loading.force
fig, (ax, ax_r) = plt.subplots(1, 2, figsize=(9, 3.6))
ax.errorbar(cycles, D * 1e6, yerr=dD * 1e6, fmt="o", color="k", label="measured ± 5 µm")
ax.plot(s_model / per_cycle, model["scar_diameter"] * 1e6,
        label=f"MDR, K = {K['value']:.3g}")
ax.plot(s_model / per_cycle, (64 * R * lab["K"] * F * s_model / np.pi) ** 0.25 * 1e6, "--",
        label=f"lab formula, K = {lab['K']:.3g}")
ax.set(xscale="log", yscale="log", xlabel="cycles", ylabel="scar diameter D [µm]")
ax.legend()
ax_r.plot(cycles, [m["residual"] for m in result.measurements], "o")
ax_r.axhline(0, color="0.5", lw=0.8)
ax_r.set(xscale="log", xlabel="cycles", ylabel="(measured − model)/σ",
         title=f"residuals: χ² p = {gof['p_value']:.2g}")
fig.tight_layout()
fig.savefig("g133_sheet_to_K.png", dpi=120)

# %%
# The flat too
# ------------
# G133 asks for the flat's wear as well. A profilometer traced the track's
# cross-section in its middle at the same cycle counts: its depth [µm] and
# its area [µm²], each ± 3 %. With ``[counterface] wears = true`` the fit runs
# the BEM's long-stroke model of both bodies wearing (the ball in its frame,
# a groove along the track) and fits the flat's K_flat, the ball's K held at
# the value fitted above (``wearcheck fit ... --fit counterface.specific_rate``).
# Under a constant force both bodies' wear scales with K·s alike, so one BEM
# run per ratio K_flat/K_ball serves every overall scale: the fit scans that
# ratio, a few runs (docs: *Fitting wear coefficients*, "Both bodies"). The
# ball's K above assumed an unworn flat; ``keys=["wear.specific_rate",
# "counterface.specific_rate"]`` fits both against the BEM together (a sheet
# with the scars and the track), at about the same cost.
Path("g133_track.csv").write_text("""\
# the flat's track, profilometer across its middle, ± 3 %
cycles, track depth [um], ± track depth [um], track area [um^2], ± track area [um^2]
50,     0.104,  0.003,  19,   1
100,    0.170,  0.005,  40,   1
250,    0.368,  0.011,  95,   3
500,    0.600,  0.018,  194,  6
1000,   1.005,  0.030,  382,  12
2000,   1.729,  0.051,  782,  23
""", encoding="utf-8")
both = case.derive({"wear.specific_rate": K["value"], "sliding.motion": "reciprocating",
                    "counterface.wears": True, "counterface.specific_rate": 1e-14,
                    "counterface.hardness": 2e9, "bem.grid": 64})
flat = wearcheck.fit(both, "g133_track.csv", "counterface.specific_rate")
K_flat = flat.parameters["counterface.specific_rate"]
print(f"flat fit:    K_flat = {K_flat['value']:.4g} m³/(N·m), 95 % interval "
      f"[{K_flat['ci95'][0]:.4g}, {K_flat['ci95'][1]:.4g}]")
print(f"lab formula: K_flat = {flat.lab['track_area']['K']:.4g} m³/(N·m) from the area "
      f"(L·A/(F s)), {flat.lab['track_depth']['K']:.4g} from the depth (the unworn ball's "
      "groove)")
print(f"model: {len(flat.model['runs'])} BEM runs at K_flat/K_ball = "
      + ", ".join(f"{r['ratio']:.3g}" for r in flat.model["runs"])
      + f"; {sum(r['seconds'] for r in flat.model['runs']):.0f} s")

# %%
# The area gives K_flat almost directly (the flat loses K_flat·F·s, and the
# model's track volume is the pass length times its cross-section); the depth
# read as the unworn ball's groove understates it, as the ball is worn flat
# and cuts a shallower, wider groove.

# %%
# With the pressure exponent free
# -------------------------------
# ``keys=["wear.specific_rate", "wear.pressure_exponent"]`` fits n of
# dw/ds = K σ0 (p/σ0)ⁿ too: one MDR run per n of a scan (1 to 4 in steps of
# 0.25) on Dask. Those runs cost far more than the one above (see *Fitting
# wear coefficients* for the numbers), so they are not run here; with six
# scar diameters of one test, K and n are also strongly correlated.
