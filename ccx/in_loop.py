"""The cross-check mode: one CalculiX contact solve per explicit Euler step.

Each step writes a deck (:func:`ccx.deck.gap_step`) whose gap elements have
the clearance initial gap + wear, runs CalculiX on it and reads back the
contact forces (the reactions of the gap elements' fixed nodes, ×180 for the
ring), the contact nodes' displacements and the depth. The wear then grows
by forward Euler, w += Δs K σ0 (p/σ0)^n with p = f/A (the lumped areas of
:mod:`ccx.model`). CalculiX cannot restart an axisymmetric model
(``*RESTART,READ`` crashes), so every step is a fresh job; the mode is meant
for short runs on coarse meshes (docs/ccx.md).

The gap elements are penalty springs: a loaded node sinks by f/k into the
plane. :func:`gap_stiffness` makes that at most :data:`PENETRATION` of the
depth scale at twice the Hertz pressure on the largest node; each solve's
largest penetration is recorded and must stay below :data:`PENETRATION_LIMIT`,
and the forces must balance the top face's reaction
(:data:`EQUILIBRIUM_TOLERANCE`): either failing is a SolverError.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from wearcheck.cases import SolverError, wear_law
from wearcheck.cases.result import scar_radius

from . import deck
from .output import dat_blocks, select

#: the penalty's largest sinking into the plane, relative to the depth scale d0
PENETRATION = 1e-6
#: an open gap element's pull at infinite opening, relative to F0/180 (CalculiX's
#: default of 1e-3 N pulled every open node: measured -5.6 % of the force on the paper case)
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
    .frd file when fields were asked for."""

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
class InLoopRun:
    """History and stage states of an in-loop run (lists, one entry per step)."""

    s: list = field(default_factory=list)
    force: list = field(default_factory=list)
    depth: list = field(default_factory=list)
    contact_radius: list = field(default_factory=list)
    wear_center: list = field(default_factory=list)
    wear_volume: list = field(default_factory=list)
    scar_radius: list = field(default_factory=list)
    stages: list = field(default_factory=list)   # (s, f, w, depth, gap, frd)
    steps: int = 0
    max_penetration: float = 0.0
    max_equilibrium_error: float = 0.0


def contact_radius(r, f, gap) -> float:
    """Contact radius between the last loaded node i and the next, from the gaps of the
    first two free nodes: near a smooth edge gap ∝ (r − a)^{3/2}, so gap^{2/3} is
    extrapolated linearly to zero, clamped to [r_i, r_{i+1}]."""
    loaded = np.flatnonzero(f > 0)
    if len(loaded) == 0:
        return 0.0
    i = loaded[-1]
    j = i + 1
    if j + 1 >= len(r):
        return float(r[i])
    t1, t2 = np.cbrt(max(gap[j], 0.0)) ** 2, np.cbrt(max(gap[j + 1], 0.0)) ** 2
    if t2 <= t1:
        return float(r[i])
    a = r[j] - t1 * (r[j + 1] - r[j]) / (t2 - t1)
    return float(min(max(a, r[i]), r[j]))


def run(jobs, sphere, height, *, control, value, rate, exponent, hardness, step, stage_s,
        until, distance, force_fraction, center, force_scale, depth_scale, stiffness,
        tension, max_steps, progress=None) -> InLoopRun:
    """Slide and wear by forward Euler with one CalculiX solve per step.

    ``height`` (Nc,) initial gaps of the contact nodes [m]; ``step`` Δs [m];
    ``center`` (Nc-1,) weights of the loaded nodes' wear giving the wear at
    r = 0; the rest as :func:`wearcheck.fem.wear.run` takes them. The fields
    (.frd) are written at the stages.
    """
    r = sphere.r[1:]
    area = sphere.area[1:]
    w = np.zeros(len(r))
    out = InLoopRun()
    stages = list(stage_s)
    s = 0.0

    def solve(k, at_stage):
        clearance = np.asarray(height, float) + np.concatenate([[0.0], w])
        sol = contact_solve(jobs, f"step-{k:05d}", sphere, clearance, control=control,
                            value=value, stiffness=stiffness, tension=tension,
                            force_scale=force_scale, depth_scale=depth_scale,
                            depth_guess=out.depth[-1] if out.depth else None, fields=at_stage)
        if sol.f[-1] > 0:
            raise SolverError(f"the contact reached the end of the candidate arc (r = "
                              f"{r[-1]:.4g} m) at s = {s:.4g} m; increase ccx.contact_factor")
        out.max_penetration = max(out.max_penetration, sol.penetration)
        out.max_equilibrium_error = max(out.max_equilibrium_error, sol.equilibrium_error)
        return sol

    def at_stage():
        return bool(stages) and abs(s - stages[0]) <= 1e-12 * max(abs(s), step)

    def record(sol):
        out.s.append(s)
        out.force.append(float(sol.f.sum()))
        out.depth.append(sol.depth)
        out.contact_radius.append(contact_radius(r, sol.f, sol.gap))
        out.wear_center.append(float(center @ w))
        out.wear_volume.append(float(area @ w))
        out.scar_radius.append(scar_radius(r, w))
        if at_stage():
            out.stages.append((s, sol.f.copy(), w.copy(), sol.depth, sol.gap.copy(), sol.frd))
            stages.pop(0)

    sol = solve(0, at_stage())
    F_start = float(sol.f.sum())
    if not F_start > 0:
        raise SolverError("the unworn sphere carries no force")
    record(sol)
    s_end = distance if until == "distance" else math.inf
    while True:
        if until == "distance" and s >= s_end:
            break
        if until == "force_fraction" and out.force[-1] < force_fraction * F_start:
            break
        if out.steps >= max_steps:
            raise SolverError(f"no end after {max_steps} in-loop steps (s = {s:.4g} m, F = "
                              f"{out.force[-1]:.4g} N); use ccx.mode = \"superelement\"")
        target = min(stages[0] if stages else math.inf, s_end)
        land = target - s <= step * (1 + 1e-9)
        ds = target - s if land else step
        w = w + ds * wear_law.speed(sol.f / area, rate, exponent, hardness)
        s = target if land else s + ds
        out.steps += 1
        sol = solve(out.steps, at_stage())
        record(sol)
        if progress is not None:
            if until == "distance":
                progress(min(s / s_end, 1.0) if s_end > 0 else 1.0, f"s = {s:.3g} m")
            else:
                F = max(out.force[-1], 1e-300)
                progress(min(max(math.log(F / F_start) / math.log(force_fraction), 0.0), 1.0),
                         f"F/F0 = {F / F_start:.3g}")
    return out
