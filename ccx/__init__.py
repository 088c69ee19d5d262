"""CalculiX as a solver: a third-party FE code in the paper's own procedure.

``solve(case, progress=None) -> CcxResult`` (a ``cases.RunResult`` that also
carries the CalculiX decks); ``supports(case)`` says why a case cannot run
(the FEM's model limits, ``ccx.mode = "in_loop"`` without explicit Euler, no
CalculiX 2.20 or later at ``ccx.executable``) or returns None.

The body is the FEM's: the elastic sphere of radius indenter.radius meshed
with the project's gmsh recipe (:mod:`meshes`), here as CAX6 elements
(:mod:`ccx.model`), clamped on its flat top face, against a rigid plane; the
initial gap of contact node i is the case's profile f(r_i); the node on the
axis (zero area) carries no contact, its pressure and wear are extrapolated.

``ccx.mode = "superelement"`` (default): CalculiX computes the contact
nodes' compliance in one ``*GREEN`` job (:mod:`ccx.compliance`, cached by
mesh, material and CalculiX version); wearcheck's complementarity solver and
time schemes then run the wear, and one final job recovers the fields at the
stages from the contact forces. ``ccx.mode = "in_loop"``: one CalculiX
contact solve with gap elements per explicit Euler step (:mod:`ccx.in_loop`).

Modules: :mod:`ccx.model` (the CAX6 mesh), :mod:`ccx.deck` (the decks'
text), :mod:`ccx.run` (running CalculiX, failures, the decks kept),
:mod:`ccx.output` (.dat and .frd files), :mod:`ccx.compliance`,
:mod:`ccx.in_loop`, :mod:`ccx.solver`. docs/ccx.md describes the solver,
its pitfalls and the decks.
"""

from wearcheck.registry import lazy_attributes

__all__ = ["solve", "supports"]

# solve, supports and the submodules are imported on first use: the registry imports
# this package for its registration.py, which must not pull in the numerics
__getattr__ = lazy_attributes(__name__, {"solve": ".solver", "supports": ".solver"})
