"""The BEM's registry entry: what wearcheck needs to know to run it and read its outputs.

Imported by the registry at its first use; it imports nothing of the solver's
numerics (``module`` is imported when a case is solved).
"""

from wearcheck.registry import Item, Solver

SOLVER = Solver(
    name="bem", title="BEM", module="wearcheck.bem", section="bem",
    resolution_key="bem.grid", default_levels=(32, 64, 128, 256),
    resolution_label="pixels per side",
    description="3D boundary elements on the elastic half-space: pixel grid, DC-FFT, "
                "constrained conjugate gradients; also non-axisymmetric indenters",
    style=dict(ls="none", marker="s", ms=3.0, mfc="none", mew=0.8),
    export_vtk="wearcheck.comparisons.present.vtk_image:write_bem_fields",
    history_columns=(Item("max_pressure", "Pa", "largest pixel pressure"),
                     Item("cg_iterations", "", "conjugate-gradient iterations of the step's "
                                               "contact solve"),
                     Item("complementarity_residual", "", "max |min(p/p0, gap/d)| at the "
                                                          "step's converged solve"),
                     Item("scar_radius", "m", "outer radius of the worn region: the largest r "
                                              "with ring-averaged wear >= 1e-3 of its largest"),
                     Item("s_hat", "", "dimensionless sliding ŝ"),
                     Item("cycles", "", "reciprocating cycles s/(2·sliding.stroke); NaN "
                                        "without a stroke")),
    fields=(Item("x", "m", "pixel-centre x coordinates (N,), first array axis"),
            Item("y", "m", "pixel-centre y coordinates (N,), second array axis"),
            Item("profile", "m", "worn profile f(x, y) per stage (K, N, N)"),
            Item("wear_depth", "m", "wear depth per stage (K, N, N)"),
            Item("pressure", "Pa", "pixel pressure per stage (K, N, N)"),
            Item("gap", "m", "gap f - d + u per stage (K, N, N)")))
