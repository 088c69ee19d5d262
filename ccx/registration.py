"""CalculiX's registry entry: what wearcheck needs to know to run it and read its outputs.

Imported by the registry at its first use; it imports nothing of the solver's
numerics (``module`` is imported when a case is solved). Opt-in (``default``
False): ``compare`` runs it only when it is named, as it needs the external
``ccx`` program.
"""

from wearcheck.registry import Item, Solver

SOLVER = Solver(
    name="ccx", title="CalculiX", module="wearcheck.ccx", section="ccx",
    resolution_key="ccx.contact_nodes", default_levels=(60, 125, 250, 500),
    resolution_label="contact nodes",
    description="CalculiX (third-party FE code, external ccx 2.20+): the FEM's sphere as CAX6 "
                "elements; its compliance drives wearcheck's wear loop, or ccx.mode = in_loop "
                "solves gap-element contact in every explicit step",
    style=dict(ls="none", marker="^", ms=3.5, mfc="none", mew=0.9),
    export_vtk="wearcheck.comparisons.present.vtk:write_fem_fields",
    run_report="wearcheck.ccx.run:write_decks",
    # the columns numerics.superelement's wear run records, as for the FEM's sphere
    history_columns=(Item("scar_radius", "m", "outer radius of the worn region: the largest r "
                                              "with wear >= 1e-3 of the largest wear"),
                     Item("s_hat", "", "dimensionless sliding ŝ"),
                     Item("cycles", "", "reciprocating cycles s/(2·sliding.stroke); NaN "
                                        "without a stroke")),
    fields=(Item("points", "m", "r, z of the CAX6 mesh nodes, undeformed (Np, 2); CalculiX "
                                "node i + 1 is row i"),
            Item("cells", "", "CAX6 triangles, counter-clockwise, meshio triangle6 order (Nt, 6)"),
            Item("displacement", "m", "u_r, u_z per stage from CalculiX's .frd (K, Np, 2); the "
                                      "top face has u_z = -d"),
            Item("stress", "Pa", "σ_rr, σ_zz, σ_θθ, σ_rz per stage, CalculiX's nodal values "
                                 "from its .frd (K, Np, 4)"),
            Item("contact_nodes", "", "indices into points of the candidate contact nodes, "
                                      "by increasing r (Nc,)"),
            Item("contact_pressure", "Pa", "nodal contact pressure per stage (K, Nc)"),
            Item("wear_depth", "m", "nodal wear depth per stage (K, Nc)")),
    default=False)
