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
    run_report="wearcheck.comparisons.present.track_report:write",
    history_columns=(Item("max_pressure", "Pa", "largest pixel pressure"),
                     Item("cg_iterations", "", "conjugate-gradient iterations of the step's "
                                               "contact solve"),
                     Item("complementarity_residual", "", "max |min(p/p0, gap/d)| at the "
                                                          "step's converged solve"),
                     Item("scar_radius", "m", "outer radius of the worn region: the largest r "
                                              "with ring-averaged wear >= 1e-3 of its largest"),
                     Item("s_hat", "", "dimensionless sliding ŝ"),
                     Item("cycles", "", "reciprocating cycles s/(2·sliding.stroke); NaN "
                                        "without a stroke"),
                     # both bodies wearing (counterface.wears)
                     Item("wear_volume_counterface", "m^3", "worn volume of the counterface"),
                     Item("track_width", "m", "width of the track where its depth is at "
                                              "least 1e-3 of its largest"),
                     Item("track_depth", "m", "largest depth of the track's cross-section"),
                     Item("track_area", "m^2", "area of the track's cross-section (middle)"),
                     Item("scar_length", "m", "both bodies: the ball's scar along the "
                                              "sliding (wear >= 1e-3 of its largest)"),
                     Item("scar_width", "m", "both bodies: the ball's scar across the "
                                             "sliding")),
    fields=(Item("x", "m", "pixel-centre x coordinates (N,), first array axis"),
            Item("y", "m", "pixel-centre y coordinates (N,), second array axis"),
            Item("profile", "m", "worn profile f(x, y) per stage (K, N, N)"),
            Item("wear_depth", "m", "wear depth per stage (K, N, N)"),
            Item("pressure", "Pa", "pixel pressure per stage (K, N, N)"),
            Item("gap", "m", "gap f - d + u per stage (K, N, N)"),
            Item("track_depth", "m", "counterface.wears: the track's cross-section (depth "
                                     "along y) per stage (K, N)"),
            Item("flat_wear", "m", "bem.track_model = moving: the counterface's wear on its "
                                   "own grid per stage (K, rows, N)"),
            Item("flat_x", "m", "bem.track_model = moving: the flat grid's x along the track "
                                "(rows,)")))
