"""The MDR's registry entry: what wearcheck needs to know to run it and read its outputs.

Imported by the registry at its first use; it imports nothing of the solver's
numerics (``module`` is imported when a case is solved).
"""

from wearcheck.registry import Item, Solver

SOLVER = Solver(
    name="mdr", title="MDR", module="wearcheck.mdr", section="mdr",
    run_report="wearcheck.comparisons.present.fretting_report:write",
    resolution_key="mdr.elements", default_levels=(100, 200, 400, 800, 1600, 3200),
    resolution_label="N",
    description="Method of Dimensionality Reduction: 1D springs, exact for axisymmetric "
                "half-space contact",
    style=dict(ls="-", lw=1.4),
    history_columns=(Item("scar_radius", "m", "outer radius of the worn region: the largest r "
                                              "with wear >= 1e-3 of the largest wear"),
                     Item("max_pressure", "Pa", "largest contact pressure"),
                     Item("s_hat", "", "dimensionless sliding ŝ"),
                     Item("cycles", "", "gross slip: reciprocating cycles s/(2·sliding.stroke), "
                                        "NaN without a stroke; fretting: cycles done (0: after "
                                        "the first quarter cycle)"),
                     # fretting runs ([fretting]): one row per simulated cycle
                     Item("tangential_force_amplitude", "N", "fretting: largest |Q| in the "
                                                             "cycle"),
                     Item("displacement_amplitude", "m", "fretting: half the indenter's "
                                                         "tangential travel in the cycle"),
                     Item("stick_radius", "m", "fretting: radius of the zone that did not "
                                               "slip in the cycle's last stroke"),
                     Item("dissipated_energy", "J", "fretting: energy dissipated by friction "
                                                    "so far, ∫|τ||Δslip| dA"),
                     Item("dissipated_energy_1d", "J", "fretting: the same from the 1D "
                                                       "springs, Σ|q_x||Δw|"),
                     Item("energy_per_cycle", "J", "fretting: energy dissipated in the "
                                                   "simulated cycle")),
    fields=(Item("loop_cycles", "", "fretting: cycles whose loop Q(u_x) is kept (L,)"),
            Item("loop_displacement", "m", "fretting: indenter displacement u_x along each "
                                           "kept cycle (L, increments + 1)"),
            Item("loop_tangential_force", "N", "fretting: tangential force Q along each kept "
                                               "cycle (L, increments + 1)")))
