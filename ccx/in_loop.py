"""The cross-check mode: one CalculiX contact solve per explicit Euler step.

Each step writes a deck (:func:`ccx.deck.gap_step`) whose gap elements have
the clearance initial gap + wear, runs CalculiX on it and reads back the
contact forces (the reactions of the gap elements' fixed nodes, ×180 for the
ring), the contact nodes' displacements and the depth. The wear then grows
by forward Euler, w += Δs K σ0 (p/σ0)^n with p = f/A (the lumped areas of
:mod:`ccx.model`). CalculiX cannot restart an axisymmetric model
(``*RESTART,READ`` crashes), so every step is a fresh job; the mode is meant
for short runs on coarse meshes (docs/ccx.md).

The steps are :mod:`numerics.stepping`'s explicit Euler (:class:`InLoop`
supplies the step), the history is recorded as the superelement's
(:class:`numerics.superelement.WearRun`).

The gap elements are penalty springs: a loaded node sinks by f/k into the
plane. :func:`gap_stiffness` makes that at most :data:`PENETRATION` of the
depth scale at twice the Hertz pressure on the largest node; each solve's
largest penetration is recorded and must stay below :data:`PENETRATION_LIMIT`,
and the forces must balance the top face's reaction
(:data:`EQUILIBRIUM_TOLERANCE`): either failing is a SolverError.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wearcheck.cases import CaseError, SolverError, wear_law
from wearcheck.numerics import stepping
from wearcheck.numerics.superelement import WearRun

from . import deck
from .output import dat_blocks, select

#: the penalty's largest sinking into the plane, relative to the depth scale d0
PENETRATION = 1e-6
#: an open gap element's pull at infinite opening, relative to F0/180 (CalculiX's
#: default of 1e-3 N pulls every open node and lowers the force: docs/performance.md,
#: "Measurements behind the code", ``ccx/in_loop.py`` ``TENSION``)
TENSION = 1e-12
#: |Σ f - top reaction| allowed, relative to F0 (the .dat's seven digits allow ~1e-6)
EQUILIBRIUM_TOLERANCE = 1e-5
#: a node sunk deeper than this (relative to d0) into the plane means the gap elements did
#: not act (100 times the penalty's design value; a linear step ignores them silently)
PENETRATION_LIMIT = 1e-4


def gap_stiffness(area, pressure_scale: float, depth_scale: float) -> float:
    """Gap stiffness [N/m on the wedge]: penetration <= PENETRATION·d0 at 2 p0 on the largest area."""
    return 2.0 * pressure_scale * float(np.max(area)) / (deck.WEDGES * PENETRATION * depth_scale)


@dataclass
class GapSolution:
    """One CalculiX contact solve: ring forces f [N] and gaps [m] of the loaded nodes
    (the contact nodes off the axis), the depth [m], the top face's reaction [N],
    the deepest node's sinking into the plane [d0], |Σ f − top reaction| [F0], the
    .frd file's nodal results when fields were asked for."""

    f: np.ndarray
    gap: np.ndarray
    depth: float
    top_force: float
    penetration: float
    equilibrium_error: float
    frd: object = None


def contact_solve(jobs, name, sphere, clearance, *, control, value, stiffness, tension,
                  force_scale, depth_scale, depth_guess=None, fields=False) -> GapSolution:
    """Run one gap-element job; ``clearance`` (Nc,) [m] for every contact node.

    Checked: the deepest node sinks at most :data:`PENETRATION_LIMIT` d0 into
    the plane, the forces balance the top face's reaction to
    :data:`EQUILIBRIUM_TOLERANCE` F0; else SolverError.
    """
    text = deck.gap_step(sphere, clearance, control=control, value=value, stiffness=stiffness,
                         tension=tension, fields=fields,
                         depth_guess=depth_scale if depth_guess is None else depth_guess,
                         title=f"wearcheck in-loop contact solve {name}")
    job = jobs.run(name, text, keep_frd=fields)
    blocks = dat_blocks(job.dat, f"{name}.dat")
    try:
        u = select(blocks, "displacements", "CONTACT")[-1]
        rf = select(blocks, "forces", "GROUND")[-1]
        top = select(blocks, "total force", "TOP")[-1]
    except IndexError:
        raise SolverError(f"CalculiX job '{name}': its .dat file lacks the contact "
                          "displacements or forces") from None
    steps = 1 if control == "depth" else 2
    if abs(u.time - steps) > 1e-6:
        raise SolverError(f"CalculiX job '{name}' ended at time {u.time:g}, not {steps} (its "
                          "last step did not finish)")
    n = len(sphere.contact)
    uz = np.full(n, np.nan)
    uz[u.ids - 1] = u.values[:, 1] / deck.MM
    ground = len(sphere.points) + 1
    f = np.full(n - 1, np.nan)
    f[rf.ids - ground] = rf.values[:, 1] * deck.WEDGES
    if np.any(np.isnan(uz)) or np.any(np.isnan(f)):
        raise SolverError(f"CalculiX job '{name}': the .dat file misses contact nodes")
    if control == "depth":
        depth = value
    else:
        ref = select(blocks, "displacements", "TOPREF")[-1]
        depth = -float(ref.values[0, 1]) / deck.MM
    gap = np.asarray(clearance, float)[1:] + uz[1:]
    f = np.maximum(f, 0.0)
    top_force = -float(top.values[0, 1]) * deck.WEDGES
    sunk = float(-np.min(gap)) / depth_scale
    if not sunk <= PENETRATION_LIMIT:
        raise SolverError(f"CalculiX job {name}: a contact node lies {sunk:.3g} d0 inside the "
                          f"plane (the gap elements allow {PENETRATION:g}); they did not act "
                          "(a linear step ignores them)")
    error = abs(f.sum() - top_force) / force_scale
    if not error <= EQUILIBRIUM_TOLERANCE:
        raise SolverError(f"CalculiX job {name}: the gap forces ({f.sum():.7g} N) do not "
                          f"balance the top face's reaction ({top_force:.7g} N)")
    return GapSolution(f=f, gap=gap, depth=depth, top_force=top_force, penetration=sunk,
                       equilibrium_error=error, frd=job.frd)


@dataclass
class State:
    """The wear of the loaded contact nodes and CalculiX's contact solve on it."""

    w: np.ndarray
    contact: GapSolution


class InLoop(stepping.Problem):
    """Forward Euler with one CalculiX contact solve per step, for :func:`numerics.stepping.run`.

    ``height`` (Nc,) initial gaps of the contact nodes [m]; ``stage_s`` the
    distances [m] where the fields (.frd) are written; ``center`` (Nc-1,)
    weights of the loaded nodes' wear giving the wear at r = 0; ``max_steps``
    CalculiX jobs at most (SolverError beyond). Only the explicit scheme:
    there is no implicit step (CalculiX's contact has no wear compliance).
    """

    def __init__(self, jobs, sphere, height, *, control, value, rate, exponent, hardness,
                 stage_s, center, force_scale, depth_scale, stiffness, tension, max_steps):
        self.jobs, self.sphere, self.height = jobs, sphere, np.asarray(height, float)
        self.r, self.area, self.center = sphere.r[1:], sphere.area[1:], center
        self.control, self.value = control, value
        self.rate, self.exponent, self.hardness = rate, exponent, hardness
        self.pending = list(stage_s)
        self.scales = dict(force_scale=force_scale, depth_scale=depth_scale)
        self.stiffness, self.tension, self.max_steps = stiffness, tension, max_steps
        self.solves = 0
        self.max_penetration = 0.0
        self.max_equilibrium_error = 0.0
        self._depth = None

    def _at_stage(self, s) -> bool:
        """Whether ``s`` completes a stage (the stepper's rule), consuming it."""
        hit = False
        while self.pending and self.pending[0] <= s * (1 + 1e-12) + 1e-300:
            self.pending.pop(0)
            hit = True
        return hit

    def solve(self, w, s) -> GapSolution:
        """CalculiX's contact of the sphere worn by ``w`` at sliding distance ``s``."""
        if self.solves > self.max_steps:
            raise SolverError(f"no end after {self.max_steps} in-loop steps (s = {s:.4g} m); "
                              "use ccx.mode = \"superelement\"")
        clearance = self.height + np.concatenate([[0.0], w])
        sol = contact_solve(self.jobs, f"step-{self.solves:05d}", self.sphere, clearance,
                            control=self.control, value=self.value, stiffness=self.stiffness,
                            tension=self.tension, depth_guess=self._depth,
                            fields=self._at_stage(s), **self.scales)
        self.solves += 1
        if sol.f[-1] > 0:
            raise SolverError(f"the contact reached the end of the candidate arc (r = "
                              f"{self.r[-1]:.4g} m) at s = {s:.4g} m; increase "
                              "ccx.contact_factor")
        self._depth = sol.depth
        self.max_penetration = max(self.max_penetration, sol.penetration)
        self.max_equilibrium_error = max(self.max_equilibrium_error, sol.equilibrium_error)
        return sol

    def unworn(self) -> State:
        """The contact of the unworn sphere."""
        w = np.zeros(len(self.r))
        sol = self.solve(w, 0.0)
        if not sol.f.sum() > 0:
            raise SolverError("the unworn sphere carries no force")
        return State(w, sol)

    def implicit(self, origin, base, h, c, sub):
        raise SolverError("ccx.mode = \"in_loop\" steps by explicit Euler only")

    def explicit(self, state, h, sub):
        """Wear by the pressure at the start of the step, then CalculiX's contact."""
        w = state.w + h * wear_law.speed(state.contact.f / self.area, self.rate,
                                         self.exponent, self.hardness)
        return State(w, self.solve(w, sub.s + h))

    def profile(self, state):
        return state.w

    def measures(self, state):
        c = state.contact
        return float(c.f.sum()), c.depth, float(self.center @ state.w)


def run(problem: InLoop, plan: stepping.Plan, progress=None, watch=None
        ) -> tuple[WearRun, list]:
    """Slide and wear ``problem`` as ``plan`` (explicit) says: the history and stages, and
    the .frd results of each stage; ``watch(s, contact_radius, scar_radius)`` is called
    at every recorded step (:class:`cases.validity.BodyWatch`).

    A run stopped by the force is refused after its first step when, projected
    from it, it would take more than ``problem.max_steps`` CalculiX jobs.
    """
    out, frds = WearRun(), []

    def observe(state, s, stages):
        c = state.contact
        out.record(s, c.f, c.gap, c.depth, state.w, stages, r=problem.r, area=problem.area,
                   center=problem.center)
        frds.extend([c.frd] * stages)
        if watch is not None:
            watch(s, out.contact_radius[-1], out.scar_radius[-1])
        if len(out.s) == 2 and plan.force_fraction is not None:
            fallen = (1.0 - out.force[1] / out.force[0]) / (1.0 - plan.force_fraction)
            projected = s / fallen / plan.step if fallen > 0 else math.inf
            if projected > problem.max_steps:
                raise CaseError(f"ccx.mode = \"in_loop\": the run would take about "
                                f"{projected:.3g} steps of Δŝ = {plan.step * plan.per_m:.3g} "
                                f"to F < {plan.force_fraction:g} F0, projected from its first "
                                f"(one CalculiX job each; at most {problem.max_steps}); use "
                                "ccx.mode = \"superelement\" or a coarser mesh")

    outcome = stepping.run(problem, problem.unworn(), plan, observe, progress)
    out.steps, out.outcome = outcome.steps, outcome
    return out, frds
