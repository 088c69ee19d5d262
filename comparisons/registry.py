"""The solver registry: everything wearcheck knows about each solver, in one place.

A solver is a package that exports ``solve(case, progress=None) -> RunResult``
and ``supports(case) -> str | None`` (None when it can run the case, else the
reason it cannot). It is registered once, here, with a :class:`Solver` entry;
``run``, ``compare``, ``refine``, ``sweep`` and the studies ask the registry
and never name a solver. Adding a solver is: a new top-level package, its
case section in ``cases/schema.py``, one ``register(Solver(...))`` call.

Solver packages are imported only when a solver is used, so ``import
wearcheck`` stays light and a broken optional solver cannot break the others.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from wearcheck import extras
from wearcheck.cases import Case, CaseError, RunResult, SolverError
from wearcheck.comparisons.layout import Item


@dataclass(frozen=True)
class Solver:
    """One registered solver.

    Parameters
    ----------
    name : short name used on the command line and as a key in outputs ("mdr").
        The solve function is called as ``solve(case, progress=None)`` with
        ``progress(fraction, text)`` or None, and returns a ``RunResult``.
    title : name in figures and reports ("MDR").
    module : import path of the package with ``solve`` and ``supports``.
    section : its case section ("mdr"), whose keys only it reads.
    resolution_key : the case key its refinement studies vary ("mdr.elements").
    default_levels : resolutions of a default refinement study, coarsest first.
    resolution_label : the resolution in words, for figures ("N", "contact nodes").
    description : one line for ``wearcheck solvers`` and the help texts.
    style : matplotlib keyword arguments of its curves in comparison figures.
    export_vtk : "module:function" that writes ParaView files of the solver's own
        ``fields.npz``, ``function(directory, run, revolve=0) -> list[Path]`` (the
        .pvd files; ``run`` a ``rundir.Run``); None: the generic profile,
        pressure and surface series only.
    run_report : "module:function" that adds a report to its run directories,
        ``function(directory, case, result) -> list[Path]`` (it may write nothing).
    history_columns : its extra ``history.csv`` columns, ``layout.Item`` each.
    fields : its ``fields.npz`` arrays, ``layout.Item`` each.
    solve_function, supports_function : for solvers that are not packages
        (tests, notebooks): callables used instead of ``module``.
    default : whether ``compare`` runs it when no solvers are named; False for
        an opt-in solver (ccx: an external program), which runs when named.
    """

    name: str
    title: str
    module: str | None = None
    section: str | None = None
    resolution_key: str | None = None
    default_levels: tuple[int, ...] = ()
    resolution_label: str = "resolution"
    description: str = ""
    style: dict = field(default_factory=dict)
    export_vtk: str | None = None
    run_report: str | None = None
    history_columns: tuple = ()
    fields: tuple = ()
    solve_function: Callable | None = None
    supports_function: Callable | None = None
    default: bool = True

    def _package(self):
        try:
            return importlib.import_module(self.module)
        except ModuleNotFoundError as exc:
            # an optional module the solver needs (the FEM's scikit-fem): one line
            # naming the extra, which supports() gives as its reason
            found = extras.missing(f"the {self.title}", exc)
            if found is None:
                raise
            raise found from None

    def solve(self, case: Case, progress=None) -> RunResult:
        """Run this solver on ``case`` (refused with a CaseError when unsupported)."""
        fn = self.solve_function or self._package().solve   # a missing extra said first
        reason = self.supports(case)
        if reason is not None:
            raise CaseError(f"solver '{self.name}' cannot run this case: {reason}")
        try:
            result = fn(case, progress=progress)
        except (ArithmeticError, np.linalg.LinAlgError) as exc:
            # a float overflow, a NaN in an integer, a factorisation or least-squares
            # solve that broke down: the numbers went out of range, a numerical
            # failure (exit 3) rather than a bug (exit 70)
            text = str(exc).splitlines()[0] if str(exc) else ""
            raise SolverError(f"solver '{self.name}': numerical failure ({type(exc).__name__}"
                              f"{': ' + text if text else ''}); the case's numbers (moduli, "
                              "load, wear keys) may lie outside what it can represent") \
                from exc
        if not isinstance(result, RunResult):
            raise TypeError(f"solver '{self.name}' returned {type(result).__name__}, "
                            "not a wearcheck RunResult")
        return result

    def supports(self, case: Case) -> str | None:
        """None when this solver can run ``case``, else the reason it cannot."""
        fn = self.supports_function
        if fn is None and self.module is not None:
            try:
                fn = getattr(self._package(), "supports", None)
            except extras.MissingExtra as exc:
                return str(exc)
        return fn(case) if fn is not None else None


_REGISTRY: dict[str, Solver] = {}


def register(solver: Solver, *, replace: bool = False) -> Solver:
    """Add a solver to the registry; returns it.

    The name becomes a directory and a key in outputs: lower-case letters,
    digits, "_" and "-". ``section``, if given, must be a section declared in
    ``cases/schema.py`` (a solver defined in a notebook has none).
    """
    import re

    from wearcheck.cases.schema import SECTIONS
    if not re.fullmatch(r"[a-z][a-z0-9_-]*", solver.name or ""):
        raise ValueError(f"solver name '{solver.name}': use lower-case letters, digits, '_' "
                         "and '-', starting with a letter (it names directories and keys)")
    if solver.section is not None and solver.section not in SECTIONS:
        raise ValueError(f"solver '{solver.name}': section '{solver.section}' is not declared "
                         "in cases/schema.py (SECTIONS); a notebook solver has none")
    if solver.name in _REGISTRY and not replace:
        raise ValueError(f"a solver named '{solver.name}' is registered already")
    if solver.module is None and solver.solve_function is None:
        raise ValueError(f"solver '{solver.name}': give module or solve_function")
    _REGISTRY[solver.name] = solver
    return solver


def unregister(name: str) -> None:
    """Remove a solver (tests and notebooks that registered their own)."""
    _REGISTRY.pop(name, None)


def names() -> tuple[str, ...]:
    """Names of the registered solvers, in registration order."""
    return tuple(_REGISTRY)


def get(name: str) -> Solver:
    """The registered solver ``name``; a CaseError naming the choices otherwise."""
    try:
        return _REGISTRY[name]
    except KeyError:
        raise CaseError(f"solver '{name}': must be one of " + ", ".join(_REGISTRY)) from None


def supporting(case: Case) -> tuple[str, ...]:
    """Names of the solvers that can run ``case``."""
    return tuple(n for n, s in _REGISTRY.items() if s.supports(case) is None)


def solve(case: Case, solver: str, progress=None) -> RunResult:
    """Run the registered solver named ``solver`` on ``case``."""
    return get(solver).solve(case, progress=progress)


# -- the built-in solvers ----------------------------------------------------

register(Solver(
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
                                               "cycle (L, increments + 1)"))))

register(Solver(
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
            Item("wear_depth", "m", "nodal wear depth per stage (K, Nc)"))))

register(Solver(
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
                                "(rows,)"))))

register(Solver(
    name="ccx", title="CalculiX", module="wearcheck.ccx", section="ccx",
    resolution_key="ccx.contact_nodes", default_levels=(60, 125, 250, 500),
    resolution_label="contact nodes",
    description="CalculiX (third-party FE code, external ccx 2.20+): the FEM's sphere as CAX6 "
                "elements; its compliance drives wearcheck's wear loop, or ccx.mode = in_loop "
                "solves gap-element contact in every explicit step",
    style=dict(ls="none", marker="^", ms=3.5, mfc="none", mew=0.9),
    export_vtk="wearcheck.comparisons.present.vtk:write_fem_fields",
    run_report="wearcheck.ccx.run:write_decks",
    history_columns=get("fem").history_columns,   # the FEM's sphere, the same columns
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
    default=False))
