"""Both bodies wearing, moving-contact model: the ball travels over a grid fixed to the flat.

The counterface is a grid of ``rows`` × n pixels in its own frame (x along
the track, the first axis; y across it, the ball's y). The ball's box, n × n
pixels of the same side Δ, sits over the rows k … k+n−1 at offset k and moves
one pixel per move, so ball and flat pixels stay aligned and every move
slides Δ. Reciprocating: the offset runs 0 → M → 0 per cycle (M = stroke/Δ),
turnarounds included; unidirectional (a disc): the flat is periodic along x
(rows = circumference/Δ) and the offset only grows.

Each move is a backward-Euler step of length Δ on the contact at the new
offset: ball pixel (i, j) faces flat pixel (k+i, j), so both wear
compliances are diagonal,

    gap = f + H_window - d + (G + Δ (K_ball + K_flat) I) p,

and then f += Δ K_ball p, H_window += Δ K_flat p: both bodies lose K_body·Δ·F
per move, so V_ball/V_flat = K_ball/K_flat to round-off. A move is the time
step: its wear must be small beside the elastic approach (recorded as
``largest_wear_per_move``). Every move is a contact solve (warm-started from the
last one's pressure, steady in the ball's frame).

Long runs jump over cycles (:func:`run_jumped`, ``bem.jump_tolerance``): a cycle
is one stroke there and back (one revolution of a disc), from offset 0 back to
it; the wear one simulated cycle does from a state, F(y), y the ball's wear and
the flat's map side by side, is integrated in the cycle count by
:mod:`numerics.cycle_jumping` (ROS2, its error against the run that simulates
every cycle held at the tolerance of the largest wear). The problem is stiff:
a pixel worn a little deeper carries less pressure and wears less, at a rate
per cycle of about K·s_cycle·E*/(0.58 Δ) (the half-space's stiffest,
checkerboard, mode), 0.2–0.8 per cycle on the shipped cases at 128², so
explicit steps would be held to a few cycles. ROS2's Jacobian is
:class:`WearJacobian`: per body −K S C, C each pixel's loaded sliding over the
cycle and S the elastic stiffness of the loaded pixels (G restricted to them,
inverted), matrix-free through conjugate gradients on G + a C.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import scipy.fft as sfft

from wearcheck.cases import CaseError, RunResult, SolverError, programme, reference, validity
from wearcheck.numerics import cycle_jumping

from . import track

from . import contact
from .operator import HalfSpace, rectangle_displacement


@dataclass
class MovingModel:
    """A ball of unworn profile ``f0`` on the n × n box over a flat of ``rows`` × n pixels."""

    op: HalfSpace
    f0: np.ndarray
    wear_rate: float           # K_ball [1/Pa]
    flat_wear_rate: float      # K_flat [1/Pa]
    rows: int                  # the flat's pixels along the track
    periodic: bool             # a disc: the track closes on itself
    depth: float | None
    force: float | None
    p_scale: float
    g_scale: float
    tol: float = 1e-8
    maxiter: int = 5000


def reciprocating_offsets(travel: int, cycles: int) -> np.ndarray:
    """The box's offset after each move: 1 … M, M−1 … 0 per cycle (2M moves, M = travel)."""
    one = np.concatenate([np.arange(1, travel + 1), np.arange(travel - 1, -1, -1)])
    return np.tile(one, cycles)


def unidirectional_offsets(rows: int, revolutions: int) -> np.ndarray:
    """The box's offset (mod rows) after each move over ``revolutions`` turns of the disc."""
    return np.arange(1, rows * revolutions + 1) % rows


def window(model: MovingModel, k: int) -> np.ndarray:
    """The flat's rows under the ball's box at offset k."""
    n = model.op.n
    rows = np.arange(k, k + n)
    if model.periodic:
        return rows % model.rows
    if rows[-1] >= model.rows:
        raise ValueError(f"offset {k}: the box passes the flat's {model.rows} rows")
    return rows


def window_rows(model: MovingModel, k: int):
    """The flat's rows under the box at offset k, as a slice when they do not wrap."""
    n = model.op.n
    if model.periodic and k % model.rows + n > model.rows:
        return window(model, k)
    k = k % model.rows if model.periodic else k
    if k + n > model.rows:
        raise ValueError(f"offset {k}: the box passes the flat's {model.rows} rows")
    return slice(k, k + n)


def contact_solve(model: MovingModel, gap0: np.ndarray, sigma: float, p_init):
    """One move's contact on the box with the gap ``gap0`` (ball + flat under it)."""
    c = contact.solve(model.op, gap0, depth=model.depth, force=model.force, sigma=sigma,
                      p_init=p_init, p_scale=model.p_scale, g_scale=model.g_scale,
                      tol=model.tol, maxiter=model.maxiter)
    q = c.pressure
    if np.any(q[0] > 0) or np.any(q[-1] > 0) or np.any(q[:, 0] > 0) or np.any(q[:, -1] > 0):
        raise SolverError("the contact has reached the edge of the BEM box (pressure on "
                          "its outermost pixels); raise bem.box")
    if not np.all(np.isfinite(q)):
        raise SolverError("the moving-contact run produced non-finite pressures")
    return c


@dataclass
class Slide:
    """The two bodies after some moves: the ball's profile f, the flat's wear map H,
    the last move's contact (its pressure warm-starts the next), the CG iterations
    and the largest wear of one move on the flat."""

    f: np.ndarray
    H: np.ndarray
    last: contact.Contact
    iterations: int = 0
    largest: float = 0.0
    ball_sliding: np.ndarray | None = None
    flat_sliding: np.ndarray | None = None


def slide(model: MovingModel, f, H, last, offsets, visit=None, sliding=False) -> Slide:
    """Move the ball along ``offsets`` (one pixel each) from the profile ``f`` and the
    flat's wear ``H`` (neither modified); ``last``: the contact before the first move.
    ``visit(move, out)`` after each move (1-based). ``sliding``: also sum, per pixel
    of each body, the sliding under pressure (Δ per loaded move), ``ball_sliding``
    and ``flat_sliding``."""
    dx = model.op.spacing
    sigma = dx * (model.wear_rate + model.flat_wear_rate)
    out = Slide(f=f.copy(), H=H.copy(), last=last)
    if sliding:
        out.ball_sliding, out.flat_sliding = np.zeros_like(f), np.zeros_like(H)
    for move, k in enumerate(offsets, start=1):
        rows = window_rows(model, int(k))
        c = contact_solve(model, out.f + out.H[rows], sigma, out.last.pressure)
        p = c.pressure
        out.last = c
        out.iterations += c.iterations
        out.f += dx * model.wear_rate * p
        out.H[rows] += dx * model.flat_wear_rate * p
        if sliding:
            loaded = dx * (p > 0)
            out.ball_sliding += loaded
            out.flat_sliding[rows] += loaded
        out.largest = max(out.largest, dx * model.flat_wear_rate * float(np.max(p)))
        if visit is not None:
            visit(move, out)
    return out


def observer(model: MovingModel, middle: int, ring=None):
    """The history's columns and ``add(s, f, H, contact)``, which appends one row."""
    n, dx = model.op.n, model.op.spacing
    area = dx * dx
    y = (np.arange(n) - n // 2) * dx
    i0 = n // 2
    hist = {k: [] for k in ("s", "force", "depth", "contact_radius", "wear_center",
                            "wear_volume", "wear_volume_counterface", "track_width",
                            "track_depth", "track_area", "max_pressure", "cg_iterations",
                            "scar_radius", "scar_length", "scar_width")}

    def add(s, f, H, c):
        w = f - model.f0
        track.record_ball(hist, model, s, w, c.force, c.depth, c.pressure, c.iterations, y,
                          i0, i0, ring)
        hist["wear_volume_counterface"].append(float(np.sum(H)) * area)
        hist["track_width"].append(track.track_width(y, H[middle]))
        hist["track_depth"].append(float(np.max(H[middle])))
        hist["track_area"].append(float(np.sum(H[middle])) * dx)
    return hist, add


def start(model: MovingModel) -> contact.Contact:
    """The unworn contact at offset 0 (SolverError if it carries no load)."""
    c = contact_solve(model, model.f0 + 0.0, 0.0, None)
    if not c.force > 0.0:
        raise SolverError("the unworn indenter carries no load")
    return c


def run(model: MovingModel, offsets, *, record=None, keep=None, middle=None, ring=None,
        progress=None) -> dict:
    """Slide the ball along ``offsets`` (one pixel per move) from offset 0 at rest.

    ``record``: move numbers (0 = the unworn start) that enter the history
    (None: every move); ``keep``: those whose whole state is kept (None: the
    recorded ones); ``middle``: the flat's row read as the track's cross-section
    (default: the middle row). Returns the history (``s``, ``force``,
    ``depth``, ``contact_radius``, ``wear_center``, ``wear_volume``,
    ``wear_volume_counterface``, ``track_width``, ``track_depth``,
    ``track_area`` (of the row ``middle``), ``scar_length``, ``scar_width`` (the
    ball's scar along and across the sliding), ``max_pressure``,
    ``cg_iterations``), the kept states (``ball_wear`` (K, n, n), ``flat_wear``
    (K, rows, n), ``pressure``, ``gap``, ``move``), counters and the largest wear of
    one move. ``ring`` = (ring index per pixel, rings, radii) adds ``scar_radius``
    (of the ring-averaged ball wear), as :func:`bem.track.run`.
    """
    dx = model.op.spacing
    offsets = np.asarray(offsets, dtype=int)
    record = set(range(len(offsets) + 1) if record is None else record)
    keep = record if keep is None else set(keep)
    middle = model.rows // 2 if middle is None else middle
    hist, add = observer(model, middle, ring)
    kept = dict(ball_wear=[], flat_wear=[], pressure=[], gap=[], move=[])

    def observe(move, f, H, c):
        if move in record:
            add(move * dx, f, H, c)
        if move in keep:
            kept["ball_wear"].append(f - model.f0)
            kept["flat_wear"].append(H.copy())
            kept["pressure"].append(c.pressure.copy())
            kept["gap"].append(c.gap.copy())
            kept["move"].append(move)

    def visit(move, out):
        if move in record or move in keep:
            observe(move, out.f, out.H, out.last)
        if progress is not None and move % 1000 == 0:
            progress(move / len(offsets), f"move {move} of {len(offsets)}")

    c = start(model)
    H = np.zeros((model.rows, model.op.n))
    observe(0, model.f0, H, c)
    out = slide(model, model.f0, H, c, offsets, visit)
    return dict(history={k: np.asarray(v) for k, v in hist.items()},
                states={k: np.asarray(v) for k, v in kept.items()},
                counters=dict(moves=len(offsets), cg_iterations=out.iterations,
                              largest_wear_per_move=out.largest))


def run_jumped(model: MovingModel, cycle_offsets, moves: int, *, tolerance: float,
               keep=(), middle=None, ring=None, progress=None,
               max_simulated_moves: int | None = None) -> dict:
    """Slide the ball ``moves`` moves by cycles of ``cycle_offsets`` (one stroke there and
    back, or one revolution, from offset 0 back to it), jumping over cycles.

    The whole cycles are integrated in the cycle count by
    :func:`numerics.cycle_jumping.run` (ROS2 on the wear per simulated cycle, the
    Jacobian :class:`WearJacobian`), its global error estimate held at
    ``tolerance`` of the largest wear (0: every cycle simulated); the moves past
    the last whole cycle are simulated. The history has a row at the start and at
    the end of every simulated cycle that is kept; ``keep``: move numbers whose
    whole state is kept (a stage inside a cycle: that cycle is simulated and the
    state taken at the move). Returns as :func:`run`, with ``jumping``
    (:meth:`numerics.cycle_jumping.Outcome.info`).
    """
    dx = model.op.spacing
    cycle_offsets = np.asarray(cycle_offsets, dtype=int)
    P = len(cycle_offsets)
    whole, rest = divmod(int(moves), P)
    middle = model.rows // 2 if middle is None else middle
    hist, add = observer(model, middle, ring)
    kept = dict(ball_wear=[], flat_wear=[], pressure=[], gap=[], move=[])

    def keep_state(move, f, H, c):
        kept["ball_wear"].append(f - model.f0)
        kept["flat_wear"].append(H.copy())
        kept["pressure"].append(c.pressure.copy())
        kept["gap"].append(c.gap.copy())
        kept["move"].append(move)

    keep = sorted({int(m) for m in keep})
    stops = {}
    for m in keep:
        if 0 < m <= whole * P:
            count = -(-m // P)
            stops.setdefault(count, []).append(m - (count - 1) * P)
    counters = dict(moves=0, cg_iterations=0, largest_wear_per_move=0.0,
                    jacobian_cg_iterations=0, jacobian_seconds=0.0)
    problem = Cycles(model, cycle_offsets, counters, stops)
    c = start(model)
    state = Between(model.f0.copy(), np.zeros((model.rows, model.op.n)), c)
    add(0.0, state.f, state.H, c)
    if 0 in keep:
        keep_state(0, state.f, state.H, c)
    info = None
    if whole:
        guard = (max(1, max_simulated_moves // P) if max_simulated_moves is not None
                 else 10 * whole + 10)
        plan = cycle_jumping.Plan(cycles=whole, tolerance=tolerance,
                                  landings=tuple(sorted(stops)), max_simulated=guard,
                                  tolerance_key="bem.jump_tolerance")

        def observe(cyc, count):
            for move, f, H, last in cyc.record["stops"]:
                keep_state((count - 1) * P + move, f, H, last)
            st = cyc.state
            add(count * P * dx, st.f, st.H, st.last)
        outcome = cycle_jumping.run(problem, state, plan, observe, progress)
        state, info = outcome.state, outcome.info()
    if rest:
        tail = [m - whole * P for m in keep if m > whole * P]

        def visit(move, out):
            if move in tail:
                keep_state(whole * P + move, out.f, out.H, out.last)
        out = slide(model, state.f, state.H, state.last, cycle_offsets[:rest], visit)
        counters["moves"] += rest
        counters["cg_iterations"] += out.iterations
        counters["largest_wear_per_move"] = max(counters["largest_wear_per_move"],
                                                out.largest)
        add(moves * dx, out.f, out.H, out.last)
    return dict(history={k: np.asarray(v) for k, v in hist.items()},
                states={k: np.asarray(v) for k, v in kept.items()},
                counters=counters, jumping=info)


def track_rows(stroke: float, spacing: float) -> tuple[int, float]:
    """The stroke in whole pixels M >= 1 and the pixel side Δ' <= ``spacing`` with M Δ' = stroke."""
    M = max(1, math.ceil(stroke / spacing * (1 - 1e-12)))
    return M, stroke / M


# -- the case adapter ----------------------------------------------------------

#: the most moves (contact solves) a moving-contact run may take without cycle jumping
MAX_MOVES = 200_000
#: with cycle jumping: the runaway guard on the moves simulated (all cycles: kept,
#: stages of the integrator, rejected steps): the scale of the shipped runs simulated
#: every move (1e7–1e8), 14–33 h at 5–12 ms per move: a guard, not a budget
MAX_SIMULATED_MOVES = 10_000_000
#: relative residual and iteration cap of the wear Jacobian's solves (cycle jumping)
SOLVE_TOL = 1e-8
SOLVE_MAXITER = 2000
#: the most history rows (pass ends, thinned evenly beyond)
MAX_HISTORY_ROWS = 2000


def supports(case) -> str | None:
    """None when the moving-contact model can run ``case``, else why not."""
    reason = track.supports(case)
    if reason is None and case.sliding.until == "force_fraction":
        reason = ("the moving-contact model (bem.track_model = \"moving\") slides a given "
                  "distance: set sliding.until = \"cycles\" or \"distance\"")
    return reason


def solve(case, progress=None):
    """The BEM run of a case whose counterface wears: the moving-contact model."""
    # lazy (c): bem.solver imports this module
    from .solver import ring_average
    reason = supports(case)
    if reason is not None:
        raise CaseError(reason)
    t0 = time.perf_counter()
    sc = reference.scales(case)
    per_m = sc["s_hat_per_m"]
    validity.check_planned(case)
    sl = case.sliding
    base, _ = track.setup(case, sc)
    n = base.op.n
    if sl.motion == "reciprocating":
        travel, dx = track_rows(sl.stroke, base.op.spacing)
        rows, periodic, per_pass = travel + n, False, travel
    else:
        circumference = 2.0 * math.pi * sl.track_radius
        rows, dx = track_rows(circumference, base.op.spacing)
        periodic, per_pass = True, rows
        if rows < n:
            raise CaseError(f"key 'sliding.track_radius' = {sl.track_radius!r}: the track's "
                            f"circumference holds {rows} pixels, fewer than the box's {n}; "
                            "the moving-contact model needs a track longer than its box")
    model_t, x = track.setup(case, sc, spacing=dx)
    s_end = case.end_distance
    moves = int(round(s_end / dx))
    tol = case.bem.jump_tolerance
    if moves > MAX_MOVES and tol == 0:
        raise CaseError(f"key 'bem.jump_tolerance' = 0: the run would take {moves} "
                        f"contact solves (one per pixel of sliding, {dx:.3g} m; at most "
                        f"{MAX_MOVES} without cycle jumping); give bem.jump_tolerance > 0, "
                        "shorten the run or use bem.track_model = \"long_stroke\"")
    if periodic:
        cycle_offsets = unidirectional_offsets(rows, 1)
    else:
        cycle_offsets = reciprocating_offsets(travel, 1)
    keep = sorted({min(moves, int(round(s / dx))) for s in
                   (sh / per_m for sh in case.stages.s_hat) if s <= s_end * (1 + 1e-12)})
    model = MovingModel(op=model_t.op, f0=model_t.f0, wear_rate=model_t.wear_rate,
                        flat_wear_rate=model_t.flat_wear_rate, rows=rows, periodic=periodic,
                        depth=model_t.depth, force=model_t.force, p_scale=model_t.p_scale,
                        g_scale=model_t.g_scale, tol=model_t.tol)
    X, Y = np.meshgrid(x, x, indexing="ij")
    ring = np.rint(np.hypot(X, Y) / dx).astype(np.int64)
    rings = n // 2
    r = np.arange(rings) * dx
    middle = (travel // 2 + n // 2) if not periodic else rows // 2
    if tol > 0:
        out = run_jumped(model, cycle_offsets, moves, tolerance=tol, keep=keep,
                         middle=middle, ring=(ring, rings, r), progress=progress,
                         max_simulated_moves=MAX_SIMULATED_MOVES)
    else:
        offsets = np.tile(cycle_offsets, -(-moves // len(cycle_offsets)))[:moves]
        ends = list(range(0, moves + 1, per_pass)) + [moves]
        if len(ends) > MAX_HISTORY_ROWS:
            ends = [ends[i] for i in np.linspace(0, len(ends) - 1,
                                                 MAX_HISTORY_ROWS).astype(int)]
        out = run(model, offsets, record=set(ends), keep=set(keep), middle=middle,
                  ring=(ring, rings, r), progress=progress)
    hist = programme.finish_history(case, out["history"], "distance", s_end, per_m)
    st = out["states"]
    K = len(st["move"])
    f_avg, p_avg = np.zeros((K, rings)), np.zeros((K, rings))
    fields = dict(x=x.copy(), y=x.copy(), profile=model.f0[None] + st["ball_wear"],
                  wear_depth=st["ball_wear"], pressure=st["pressure"], gap=st["gap"],
                  track_depth=st["flat_wear"][:, middle, :], flat_wear=st["flat_wear"],
                  flat_x=(np.arange(rows) - n // 2) * dx)
    for k in range(K):
        f_avg[k] = ring_average(fields["profile"][k], ring, rings)
        p_avg[k] = ring_average(st["pressure"][k], ring, rings)
    counters = out["counters"]
    info = dict(solver="bem", model="both bodies wearing, moving contact (a grid fixed to the "
                                    "flat, one pixel per move)",
                grid=n, pixel=dx, box_side=n * dx, flat_rows=rows, periodic=periodic,
                middle_row=middle, counterface_wear_rate=model.flat_wear_rate,
                motion=sl.motion, tolerance=case.bem.tolerance,
                archard_balance=track.balance(hist, model.wear_rate, model.flat_wear_rate,
                                              case.loading.force),
                jump_tolerance=tol, run_moves=moves, **counters)
    if out.get("jumping") is not None:
        info["cycle_jumping"] = out["jumping"]
    remarks = [r for r in (track.curved_track_remark(sl, sc["a0"]) if periodic else None,
                           track.coarse_wear_remark(counters["largest_wear_per_move"],
                                                    sc["d0"], "move")) if r]
    if remarks:
        info["warnings"] = remarks
    if progress is not None:
        progress(1.0, "done")
    return RunResult(history=hist, stage_s=np.asarray(st["move"], float) * dx, r=r, f=f_avg,
                     p=p_avg, solve_seconds=time.perf_counter() - t0, info=info, fields=fields)


# -- cycle jumping -------------------------------------------------------------

@dataclass
class Between:
    """The run between two cycles, the ball back at offset 0: its profile f, the
    flat's wear map H and the last contact (which warm-starts the next move)."""

    f: np.ndarray
    H: np.ndarray
    last: contact.Contact


class Cycles(cycle_jumping.Problem):
    """The moving-contact run as :mod:`numerics.cycle_jumping` sees it: a cycle is one
    stroke there and back (one revolution of a disc), simulated move by move from
    offset 0 back to it; the integrated variable is the ball's wear and the flat's
    wear map side by side."""

    def __init__(self, model: MovingModel, offsets, counters: dict, stops=None):
        self.model = model
        self.offsets = np.asarray(offsets, dtype=int)
        self.counters = counters
        #: cycle count -> the moves within that cycle whose state is kept
        self.stops = stops or {}

    def cycle(self, state, n, probe=False):
        stops = () if probe else self.stops.get(n, ())
        snaps = []

        def visit(move, out):
            if move in stops:
                snaps.append((move, out.f.copy(), out.H.copy(), out.last))
        out = slide(self.model, state.f, state.H, state.last, self.offsets,
                    visit if stops else None, sliding=not probe)
        self.counters["moves"] += len(self.offsets)
        self.counters["cg_iterations"] += out.iterations
        self.counters["largest_wear_per_move"] = max(self.counters["largest_wear_per_move"],
                                                     out.largest)
        rate = np.concatenate([(out.f - state.f).ravel(), (out.H - state.H).ravel()])
        return cycle_jumping.Cycle(state=Between(out.f, out.H, out.last), rate=rate,
                                   record=dict(stops=snaps, ball_sliding=out.ball_sliding,
                                               flat_sliding=out.flat_sliding))

    def advance(self, state, increment, cycles, cycle):
        nb = state.f.size
        f = state.f + increment[:nb].reshape(state.f.shape)
        H = state.H + increment[nb:].reshape(state.H.shape)
        if not (np.all(np.isfinite(f)) and np.all(np.isfinite(H))):
            raise SolverError("cycle jumping produced non-finite wear; lower "
                              "bem.jump_tolerance")
        return Between(f, H, cycle.state.last if cycle is not None else state.last)

    def variable(self, state):
        return np.concatenate([(state.f - self.model.f0).ravel(), state.H.ravel()])

    def jacobian(self, cycle):
        m = self.model
        rec = cycle.record
        kernels = self.__dict__.setdefault("_kernels", {})
        bodies = []
        for rate, sliding in ((m.wear_rate, rec["ball_sliding"]),
                              (m.flat_wear_rate, rec["flat_sliding"])):
            if sliding.shape not in kernels:
                kernels[sliding.shape] = half_space_transform(sliding.shape, m.op.spacing,
                                                              m.op.E_star)
            bodies.append(Body(rate, sliding, *kernels[sliding.shape]))
        return WearJacobian(bodies, force_control=m.force is not None,
                            counters=self.counters)


def half_space_transform(shape, spacing, E_star):
    """G on a rows × cols grid of pixels by DC-FFT (zero-padded, exact on the grid):
    the padded kernel's transform, and a pixel's own compliance."""
    rows, cols = shape
    di = np.arange(2 * rows)
    di = np.where(di < rows, di, di - 2 * rows).astype(float)
    dj = np.arange(2 * cols)
    dj = np.where(dj < cols, dj, dj - 2 * cols).astype(float)
    X, Y = np.meshgrid(di * spacing, dj * spacing, indexing="ij")
    kernel = rectangle_displacement(X, Y, 0.5 * spacing, 0.5 * spacing, E_star)
    kernel[rows, :] = 0.0
    kernel[:, cols] = 0.0
    return sfft.rfft2(kernel), float(kernel[0, 0])


class Body:
    """One body's block of the wear Jacobian, J ≈ −K S C on its loaded pixels.

    C: each pixel's sliding under pressure over the cycle (m); S: the elastic
    stiffness of those pixels together, the inverse of G restricted to them,
    under force control projected so that a uniform wear of all of them
    changes no pressure (S 1 = 0: the approach takes it up). A pixel's wear
    per cycle is K·∫p ds over its loaded sliding, and worn by δ it carries
    S δ less pressure, so ∂F/∂y ≈ −K C S for a contact that stays put; the
    transpose −K S C is taken instead, which has 1ᵀJ = 0: the solves of ROS2
    keep each body's summed wear, so V_ball/V_flat = K_ball/K_flat stays exact
    through the jumps.
    """

    def __init__(self, rate, sliding, kernel_hat, self_compliance):
        self.rate = rate
        self.shape = sliding.shape
        self.support = np.flatnonzero(sliding.ravel() > 0.0)
        self.c = sliding.ravel()[self.support]
        self.kernel_hat = kernel_hat           # :func:`half_space_transform`
        self.self_compliance = self_compliance
        self._unit = {}
        self.iterations = 0

    def G(self, v):
        """G restricted to the loaded pixels, applied to ``v`` on them."""
        rows, cols = self.shape
        full = np.zeros(rows * cols)
        full[self.support] = v
        u = sfft.irfft2(sfft.rfft2(full.reshape(rows, cols), s=(2 * rows, 2 * cols))
                        * self.kernel_hat, s=(2 * rows, 2 * cols))[:rows, :cols]
        return u.ravel()[self.support]

    def _solve_A(self, a, b):
        """(G + a C)⁻¹ b on the loaded pixels: conjugate gradients, Jacobi-preconditioned."""
        diag = self.self_compliance + a * self.c
        x = b / diag
        r = b - (self.G(x) + a * self.c * x)
        z = r / diag
        d = z.copy()
        rz = float(r @ z)
        scale = float(np.linalg.norm(b))
        for _ in range(SOLVE_MAXITER):
            if not float(np.linalg.norm(r)) > SOLVE_TOL * scale:
                return x
            self.iterations += 1
            q = self.G(d) + a * self.c * d
            alpha = rz / float(d @ q)
            x += alpha * d
            r -= alpha * q
            z = r / diag
            rz, rz_old = float(r @ z), rz
            d = z + (rz / rz_old) * d
        raise SolverError("cycle jumping: the wear Jacobian's solve did not converge")

    def solve(self, gh, x, force_control):
        """(I − gh J)⁻¹ x on this body's variable (its loaded pixels; the rest as x)."""
        out = np.array(x, dtype=float, copy=True)
        if not len(self.support):
            return out
        a = gh * self.rate
        xs = out[self.support]
        u = self._solve_A(a, self.c * xs)
        if force_control:
            if a not in self._unit:
                self._unit = {a: self._solve_A(a, np.ones_like(xs))}
            unit = self._unit[a]
            u -= (np.sum(u) / np.sum(unit)) * unit
        out[self.support] = xs - a * u
        return out


class WearJacobian(cycle_jumping.SolveJacobian):
    """The wear Jacobian of a cycle, ball and flat blocks (their coupling through
    the contact left out: a W-method's J need only be near the stiff part)."""

    def __init__(self, bodies, force_control, counters=None):
        self.bodies = bodies
        self.force_control = force_control
        self.sizes = np.cumsum([0] + [int(np.prod(b.shape)) for b in bodies])
        self.counters = counters if counters is not None else {}

    def filter(self, gh, x):
        t = time.perf_counter()
        out = np.empty_like(x, dtype=float)
        for b, lo, hi in zip(self.bodies, self.sizes[:-1], self.sizes[1:]):
            out[lo:hi] = b.solve(gh, x[lo:hi], self.force_control)
        c = self.counters
        c["jacobian_cg_iterations"] = (c.get("jacobian_cg_iterations", 0)
                                       + sum(b.iterations for b in self.bodies))
        for b in self.bodies:
            b.iterations = 0
        c["jacobian_seconds"] = c.get("jacobian_seconds", 0.0) + time.perf_counter() - t
        return out
