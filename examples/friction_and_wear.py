"""
How friction speeds up wear
===========================

The paper's sphere at μ = 0.5 instead of 0.3, in gross slip under a held depth.

Loads the shipped paper case, changes μ (validated like the case file), solves it
with the MDR, prints the force left at the end and plots F/F0 against the
dimensionless sliding distance ŝ (which already contains μ, so both runs end at
the same ŝ: the curves coincide, while the sliding distance in metres does not).
"""

import matplotlib

matplotlib.use("Agg")  # no window needed; the figure goes to a file
import matplotlib.pyplot as plt

import wearcheck

paper = wearcheck.load_case("paper")
rough = paper.derive({"wear.mu": 0.5})

fig, ax = plt.subplots(figsize=(6, 4))
for case, label in ((paper, "μ = 0.3"), (rough, "μ = 0.5")):
    result = wearcheck.solve(case, "mdr")
    F0, s_hat_per_m = result.scales["F0"], result.scales["s_hat_per_m"]
    force = result.history["force"] / F0
    s = result.history["s"]
    print(f"{label}: F/F0 = {force[-1]:.4f} after s = {s[-1] * 1e3:.1f} mm "
          f"(ŝ = {s[-1] * s_hat_per_m:.2f}), {len(s) - 1} steps")
    ax.plot(s * 1e3, force, label=label)
ax.set_xlabel("sliding distance s [mm]")
ax.set_ylabel("F / F0")
ax.legend()
fig.savefig("friction_and_wear.png", dpi=120)
print("figure: friction_and_wear.png")
