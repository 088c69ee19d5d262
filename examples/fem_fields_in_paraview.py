"""
FEM fields in ParaView
======================

A FEM run written as a run directory, its ParaView files, and reading them back.

Writes ``runs/hertz-fem`` (history.csv, stages.npz, fields.npz, meta.json) and its
``vtk/`` folder: open ``runs/hertz-fem/vtk/section.pvd`` or ``solid.pvd`` in
ParaView. Here pyvista reads the revolved solid back and reports the largest von
Mises stress below the surface, which Hertz's theory puts at 0.62 p0 for ν = 0.3.
"""

import numpy as np
import pyvista as pv

import wearcheck

result = wearcheck.solve("hertz", "fem")
run_dir = result.write("runs/hertz-fem")
vtk_dir = result.export_vtk(revolve=24)
print("ParaView files:", sorted(p.name for p in vtk_dir.glob("*.pvd")))

solid = pv.read(vtk_dir / "solid_000.vtu")
p0 = result.scales["p0"]
von_mises = solid.point_data["von_mises"]
deepest = solid.points[np.argmax(von_mises)]
print(f"max von Mises = {von_mises.max() / p0:.3f} p0 at depth "
      f"{deepest[1] / result.scales['a0']:.3f} a0 (Hertz: 0.62 p0 at 0.48 a0)")
print("history.csv, as its meta.json describes it:")
columns = wearcheck.read_run(run_dir).meta["data_dictionary"]["history_csv"]
for name, item in columns.items():
    print(f"  {name:<15} [{item['unit'] or '-'}] {item['meaning']}")
