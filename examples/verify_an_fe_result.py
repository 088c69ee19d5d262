"""
Verify a wear result from your own FE model
===========================================

You have a wear model in your own finite-element code (an Abaqus
UMESHMOTION, an ANSYS or COMSOL script, CalculiX) and want to know whether
it is right. Build one of wearcheck's benchmarks in it (here the paper's
case: ``wearcheck cases paper`` prints it; :doc:`../benchmarks`
defines each for another code), export what your post-processor gives you,
and let ``wearcheck verify`` judge it against the certified reference: per
stage, each quantity against the stage's own scale, with the reference's own
error beside it.

The results used here are an FE export of the paper case as it comes out of
an FE code: ``examples/data/paper_fe_export/`` holds the history and the
stage profiles computed by CalculiX 2.20 on a CAX6 sphere of 60 contact nodes
(made by ``benchmarks/make_example_results.py``; its comment lines say how),
written as ANSYS Mechanical or COMSOL export tables: tab-separated, quoted
names with units in brackets, the sliding distance in the model's pseudo-time
column ``Time [s]`` (in mm), a negative reaction force and the central wear
as an Abaqus-style column without a unit.
"""

# %%
# The files as your FE code wrote them
# ------------------------------------
from pathlib import Path

import matplotlib.pyplot as plt

import wearcheck

try:
    HERE = Path(__file__).resolve().parent
except NameError:        # the docs build runs the script in its folder, without __file__
    HERE = Path.cwd()
RESULTS = HERE / "data" / "paper_fe_export"

for name in ("history.csv", "stages.csv"):
    lines = (RESULTS / name).read_text(encoding="utf-8").splitlines()
    print(f"{name}:")
    print("\n".join("    " + line for line in lines[2:5]) + "\n    ...")

# %%
# Which column is which
# ---------------------
# wearcheck reads a history (``s`` or ``s_hat`` or ``cycles``, and ``force``;
# optionally ``contact_radius``, ``wear_center``, ``wear_volume``, ``depth``)
# and stages in long form (the distance, ``r``, and ``f`` or ``wear`` and/or
# ``p``). ``--map name=COLUMN`` names your column for each; a unit in the
# header (``[mm]``, ``[MPa]``, ``[mm³]``, ``[µm]``) is converted, and a unit in
# the mapping overrides the header's: the pseudo-time "Time [s]" holds the
# sliding distance in mm, and the Abaqus-style wear column has no unit at all.
MAP = ["s [mm]=Time", "force=Force Reaction (Y)", "contact_radius=Contact Radius",
       "wear_volume=Worn Volume", "wear_center [mm]=WEAR_DEPTH N: 1",
       "r=X", "p=Contact Pressure", "wear=Wear Depth (Y)"]

m = wearcheck.verify("paper", RESULTS, "runs/verify-fe-export", mapping=MAP)
print("verdict:", "PASS" if m["passed"] else "FAIL")
print("read:", "; ".join(m["results"]["notes"]))


def show(m):
    """Each stage's worst check, as a share of its tolerance."""
    for st in m["pairs"]["results"]["stages"]:
        worst = max(st["checks"], key=lambda c: st["checks"][c]["value"]
                    / st["checks"][c]["tolerance"])
        c = st["checks"][worst]
        print(f"  stage {st['index']} (ŝ = {st['s_hat_reference']:.3g}): worst {worst} "
              f"{c['value']:.3g} of {c['tolerance']:g} allowed"
              + ("" if c["passed"] else "  FAILED"))


show(m)

# %%
# A wrong result fails, and says where
# ------------------------------------
# A model whose wear coefficient is 1/1.05 of the case's (a μ or a hardness
# slightly off, a per-cycle distance miscounted) reaches every state only
# after 5 % more sliding. Its export is the same tables with the distance
# column times 1.05:
WRONG = Path("wrong_fe_export")
WRONG.mkdir(exist_ok=True)
for name in ("history.csv", "stages.csv"):
    lines = (RESULTS / name).read_text(encoding="utf-8").splitlines()
    header = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    column = lines[header].split("\t").index('"Time [s]"')
    for i in range(header + 1, len(lines)):
        cells = lines[i].split("\t")
        cells[column] = f"{float(cells[column]) * 1.05:.8E}"
        lines[i] = "\t".join(cells)
    (WRONG / name).write_text("\n".join(lines) + "\n", encoding="utf-8")

bad = wearcheck.verify("paper", WRONG, "runs/verify-wrong", mapping=MAP)
print("verdict:", "PASS" if bad["passed"] else "FAIL")
show(bad)
print(f"distance factor λ = {bad['diagnosis']['factor']:.4f}: {bad['diagnosis']['reason']}")

# %%
# The report and the figures
# --------------------------
# Each verification is a directory: ``report.html`` (the verdict, what was
# read, the reference and its band, the per-stage table, the figures),
# ``metrics.json``, the reference at your stages as a run directory and your
# data as read, in SI. Its history figure: the reference as lines, your
# results as markers.
fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
for ax, (title, out) in zip(axes, (("right", "runs/verify-fe-export"),
                                   ("distances × 1.05", "runs/verify-wrong"))):
    ax.imshow(plt.imread(Path(out) / "history.png"))
    ax.set_title(title)
    ax.axis("off")
fig.tight_layout()
fig.savefig("verify_an_fe_result.png", dpi=120)

# %%
# On the command line
# -------------------
# The same, with the exit code a CI job can use (0 pass, 1 fail, 2 a bad file
# or mapping, with one line naming the file, row and column)::
#
#     wearcheck verify paper examples/data/paper_fe_export --out runs/verify \
#         --map 's [mm]=Time' --map 'force=Force Reaction (Y)' \
#         --map 'contact_radius=Contact Radius' --map 'wear_volume=Worn Volume' \
#         --map 'wear_center [mm]=WEAR_DEPTH N: 1' --map r=X \
#         --map 'p=Contact Pressure' --map 'wear=Wear Depth (Y)'
#
# Other formats (a ParaView ``.pvd`` series, CalculiX's ``.frd`` and ``.dat``)
# and every rule of the verdict: :doc:`../verify`.
