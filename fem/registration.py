"""The FEM's registry entry: what wearcheck needs to know to run it and read its outputs.

Imported by the registry at its first use; it imports nothing of the solver's
numerics (``module`` is imported when a case is solved).
"""

from wearcheck.registry import Item, Solver

SOLVER = Solver(
    name="fem", title="FEM", module="wearcheck.fem", section="fem",
    resolution_key="fem.contact_nodes", default_levels=(60, 125, 250, 500, 1000),
    resolution_label="contact nodes",
    description="axisymmetric elastic sphere (scikit-fem), condensed onto its contact nodes, "
                "against a rigid plane",
    style=dict(ls="none", marker="o", ms=3.5, mfc="none", mew=0.9),
    export_vtk="wearcheck.comparisons.present.vtk:write_fem_fields",
    history_columns=(Item("scar_radius", "m", "outer radius of the worn region: the largest r "
                                              "with wear >= 1e-3 of the largest wear"),
                     Item("s_hat", "", "dimensionless sliding ŝ"),
                     Item("cycles", "", "reciprocating cycles s/(2·sliding.stroke); NaN "
                                        "without a stroke")),
    fields=(Item("points", "m", "r, z of the mesh nodes, undeformed (Np, 2); P2 with midside "
                                "nodes"),
            Item("cells", "", "triangles, counter-clockwise, meshio triangle/triangle6 order "
                              "(Nt, 3 or 6)"),
            Item("displacement", "m", "u_r, u_z per stage (K, Np, 2); the top face has "
                                      "u_z = -d"),
            Item("stress", "Pa", "σ_rr, σ_zz, σ_θθ, σ_rz per stage, L2-projected to the "
                                 "nodes (K, Np, 4)"),
            Item("contact_nodes", "", "indices into points of the candidate contact nodes, "
                                      "by increasing r (Nc,)"),
            Item("contact_pressure", "Pa", "nodal contact pressure per stage (K, Nc)"),
            Item("wear_depth", "m", "nodal wear depth per stage (K, Nc)")))
