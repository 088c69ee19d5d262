"""
From a wear rig to a case file
==============================

A reciprocating ball-on-flat test as a laboratory reports it: a 6 mm steel
ball under 5 N on a steel flat, 1 mm stroke, 50 000 cycles, a measured
coefficient of friction μ = 0.6 and a specific wear rate of the ball
K = 1e-15 m³/(N·m) (1e-6 mm³/(N·m)). This tutorial writes the case file,
runs it with the MDR and reads off what the lab measures: the scar diameter
and the worn volume, beside the lab's formulas.

**The lab's K in the case file.** A lab's specific wear rate is per unit
*normal load*, V = K F s; the paper's wear law dw/ds = (k μ/σ0)·p takes a
dimensionless ``wear.k`` per unit *friction work*, V = k μ F s/σ0. The case
file takes either: ``wear.specific_rate = K`` as the lab reports it, and
wearcheck derives

    k = K σ0 / μ

with σ0 = ``wear.hardness`` of the worn ball (typing K into ``wear.k`` would
give wear off by a factor μ/σ0, about 1e-10 here).

**Pin-on-disc.** Only the sliding distance matters in gross slip, so a
unidirectional track of radius r_track is written as a "stroke" of
π·r_track: one cycle then slides 2π·r_track, one revolution, and
``sliding.cycles`` counts revolutions.
"""

# %%
# The lab's numbers, in SI units
# ------------------------------
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import wearcheck

R = 3e-3                  # m, ball radius (6 mm ball)
F = 5.0                   # N, normal load, held constant
stroke = 1e-3             # m, one way
cycles = 5e4
mu = 0.6                  # measured, steady state
sigma0 = 7e9              # Pa, hardness of the ball (hardened bearing steel, about 700 HV)
K = 1e-15                 # m³/(N·m), the lab's specific wear rate of the ball

s_total = 2 * stroke * cycles
print(f"sliding distance s = 2·stroke·cycles = {s_total:.0f} m")

# %%
# The case file
# -------------
# Stages are given in cycles (they need ``sliding.stroke``); the run stops
# after ``sliding.cycles``. The flat is elastic steel like the ball (E* from
# both bodies); only the ball wears. ``wearcheck cases ball_on_flat`` prints a
# shipped case of the same kind with every key commented.
case_text = f"""\
[indenter]
profile = "sphere"
radius = {R}              # m
youngs_modulus = 210e9    # Pa
poisson_ratio = 0.3

[counterface]
rigid = false
youngs_modulus = 210e9
poisson_ratio = 0.3

[loading]
control = "force"
force = {F}               # N

[wear]
specific_rate = {K}       # m³/(N·m), the lab's K (wearcheck derives k = K·σ0/μ)
mu = {mu}
hardness = {sigma0}       # Pa

[sliding]
until = "cycles"
stroke = {stroke}         # m, one way
cycles = {cycles}

[stages]
cycles = [0, 10, 100, 1000, 10000, 50000]

[mdr]
elements = 400
"""
Path("ball_6mm.toml").write_text(case_text, encoding="utf-8")
case = wearcheck.load_case("ball_6mm.toml")   # checked like any case file
print(f"k = K σ0/μ = {case.wear.k:.4g} (derived; the resolved case.toml records it)")

# %%
# Run it
# ------
result = wearcheck.solve(case, "mdr")
scales = result.scales
print(f"Hertz contact: a_H = {scales['a0'] * 1e6:.1f} µm, p0 = {scales['p0'] / 1e9:.2f} GPa; "
      f"{result.info['steps']} steps in {result.solve_seconds:.2f} s")

# %%
# What the lab reads off
# ----------------------
# The scar diameter D = 2·scar_radius (the worn region, down to 1e-3 of the
# central wear). The lab's ball formula V_lab = π D⁴/(64 R) takes the scar
# for a spherical cap cut at D; the true worn volume is K F s (Archard). Once
# the scar is much wider than the Hertz contact, D approaches
# 2 (4 R K F s/π)^¼.
h = result.history
keep = h["s"] > 0
n = h["cycles"][keep]
s = h["s"][keep]
D = 2 * h["scar_radius"][keep]
V = h["wear_volume"][keep]
V_archard = K * F * s
V_lab = math.pi * D**4 / (64 * R)
D_asymptote = 2 * (4 * R * K * F * s / math.pi) ** 0.25

print(f"{'cycles':>8} {'D µm':>8} {'D asymptote µm':>15} {'V mm³':>10} {'K F s mm³':>10} "
      f"{'V_lab/V - 1':>12}")
for c in (10, 100, 1000, 10000, 50000):
    i = int(np.argmin(abs(n - c)))
    print(f"{n[i]:>8.0f} {D[i] * 1e6:>8.1f} {D_asymptote[i] * 1e6:>15.1f} {V[i] * 1e9:>10.3e} "
          f"{V_archard[i] * 1e9:>10.3e} {V_lab[i] / V[i] - 1:>+12.1%}")
print(f"at the end: scar diameter {D[-1] * 1e6:.1f} µm, worn volume {V[-1]:.4e} m³, "
      f"K F s = {V_archard[-1]:.4e} m³, scar radius / R = {D[-1] / 2 / R:.3f}")

# %%
# The figure: scar diameter and volume against cycles
# ---------------------------------------------------
# Early on the scar is mostly the elastic Hertz contact and the ball formula
# overstates the volume many times; it becomes a fair estimate only once the
# scar is several times wider than a_H.
fig, (ax_d, ax_v) = plt.subplots(1, 2, figsize=(9, 3.6))
ax_d.loglog(n, D * 1e6, label="MDR")
ax_d.loglog(n, D_asymptote * 1e6, "--", label="2 (4RKFs/π)^¼")
ax_d.axhline(2 * scales["a0"] * 1e6, color="0.6", lw=0.8, label="Hertz 2a_H")
ax_d.set(xlabel="cycles", ylabel="scar diameter D [µm]")
ax_d.legend()
ax_v.loglog(n, V * 1e9, label="worn volume (MDR)")
ax_v.loglog(n, V_archard * 1e9, ":", label="K F s")
ax_v.loglog(n, V_lab * 1e9, "--", label="lab: π D⁴/64R")
ax_v.set(xlabel="cycles", ylabel="volume [mm³]")
ax_v.legend()
fig.tight_layout()
fig.savefig("lab_rig_to_case.png", dpi=120)
