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
last one's pressure, steady in the ball's frame), so the cost grows with the
sliding distance in pixels: short runs and short strokes, and the check of the
long-stroke model (:mod:`bem.track`) in the middle of a long track. No cycle
jumping here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wearcheck.cases import SolverError

from . import contact
from .operator import HalfSpace


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
    from wearcheck.cases.result import scar_radius
    from .track import track_width
    op, n = model.op, model.op.n
    dx = op.spacing
    area = dx * dx
    offsets = np.asarray(offsets, dtype=int)
    record = set(range(len(offsets) + 1) if record is None else record)
    keep = record if keep is None else set(keep)
    middle = model.rows // 2 if middle is None else middle
    y = (np.arange(n) - n // 2) * dx
    f = model.f0.copy()
    H = np.zeros((model.rows, n))
    sigma = dx * (model.wear_rate + model.flat_wear_rate)
    i0 = n // 2
    hist = {k: [] for k in ("s", "force", "depth", "contact_radius", "wear_center",
                            "wear_volume", "wear_volume_counterface", "track_width",
                            "track_depth", "track_area", "max_pressure", "cg_iterations",
                            "scar_radius", "scar_length", "scar_width")}
    kept = dict(ball_wear=[], flat_wear=[], pressure=[], gap=[], move=[])
    p, iterations, largest = None, 0, 0.0

    def solve(k, sig):
        c = contact.solve(op, f + H[window(model, k)], depth=model.depth, force=model.force,
                          sigma=sig, p_init=p, p_scale=model.p_scale, g_scale=model.g_scale,
                          tol=model.tol, maxiter=model.maxiter)
        q = c.pressure
        if np.any(q[0] > 0) or np.any(q[-1] > 0) or np.any(q[:, 0] > 0) or np.any(q[:, -1] > 0):
            raise SolverError("the contact has reached the edge of the BEM box (pressure on "
                              "its outermost pixels); raise bem.box")
        return c

    def observe(move, c):
        if move in record:
            hist["s"].append(move * dx)
            hist["force"].append(c.force)
            hist["depth"].append(c.depth)
            loaded = np.count_nonzero(c.pressure > model.tol * model.p_scale)
            hist["contact_radius"].append(math.sqrt(loaded * area / math.pi))
            hist["wear_center"].append(float(f[i0, i0] - model.f0[i0, i0]))
            hist["wear_volume"].append(float(np.sum(f - model.f0)) * area)
            hist["wear_volume_counterface"].append(float(np.sum(H)) * area)
            hist["track_width"].append(track_width(y, H[middle]))
            hist["track_depth"].append(float(np.max(H[middle])))
            hist["track_area"].append(float(np.sum(H[middle])) * dx)
            hist["scar_length"].append(track_width(y, f[:, i0] - model.f0[:, i0]))
            hist["scar_width"].append(track_width(y, f[i0, :] - model.f0[i0, :]))
            hist["max_pressure"].append(float(np.max(c.pressure)))
            hist["cg_iterations"].append(c.iterations)
            if ring is not None:
                index, rings, radii = ring
                inside = index < rings
                w = (f - model.f0)[inside]
                total = np.bincount(index[inside], w, minlength=rings)
                count = np.maximum(np.bincount(index[inside], minlength=rings), 1)
                hist["scar_radius"].append(scar_radius(radii, total / count))
            else:
                hist["scar_radius"].append(math.nan)
        if move not in keep:
            return
        kept["ball_wear"].append(f - model.f0)
        kept["flat_wear"].append(H.copy())
        kept["pressure"].append(c.pressure.copy())
        kept["gap"].append(c.gap.copy())
        kept["move"].append(move)

    c = solve(0, 0.0)
    p = c.pressure
    if not c.force > 0.0:
        raise SolverError("the unworn indenter carries no load")
    observe(0, c)
    for move, k in enumerate(offsets, start=1):
        c = solve(int(k), sigma)
        p = c.pressure
        iterations += c.iterations
        f += dx * model.wear_rate * p
        H[window(model, int(k))] += dx * model.flat_wear_rate * p
        if not np.all(np.isfinite(p)):
            raise SolverError("the moving-contact run produced non-finite pressures")
        largest = max(largest, dx * model.flat_wear_rate * float(np.max(p)))
        if move in record or move in keep:
            observe(move, c)
        if progress is not None and move % 1000 == 0:
            progress(move / len(offsets), f"move {move} of {len(offsets)}")
    return dict(history={k: np.asarray(v) for k, v in hist.items()},
                states={k: np.asarray(v) for k, v in kept.items()},
                counters=dict(moves=len(offsets), cg_iterations=iterations,
                              largest_wear_per_move=largest))


def track_rows(stroke: float, spacing: float) -> tuple[int, float]:
    """The stroke in whole pixels M >= 1 and the pixel side Δ' <= ``spacing`` with M Δ' = stroke."""
    M = max(1, math.ceil(stroke / spacing * (1 - 1e-12)))
    return M, stroke / M


# -- the case adapter ----------------------------------------------------------

#: the most moves (contact solves) a moving-contact run may take
MAX_MOVES = 200_000
#: the most history rows (pass ends, thinned evenly beyond)
MAX_HISTORY_ROWS = 2000


def supports(case) -> str | None:
    """None when the moving-contact model can run ``case``, else why not."""
    from .track import supports as track_supports
    reason = track_supports(case)
    if reason is None and case.sliding.until == "force_fraction":
        reason = ("the moving-contact model (bem.track_model = \"moving\") slides a given "
                  "distance: set sliding.until = \"cycles\" or \"distance\"")
    return reason


def solve(case, progress=None):
    """The BEM run of a case whose counterface wears: the moving-contact model."""
    import time

    from wearcheck.cases import CaseError, RunResult, programme, reference, validity

    from . import track
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
    if moves > MAX_MOVES:
        raise CaseError(f"key 'bem.track_model' = \"moving\": the run would take {moves} "
                        f"contact solves (one per pixel of sliding, {dx:.3g} m; at most "
                        f"{MAX_MOVES}); shorten the run or use bem.track_model = "
                        "\"long_stroke\"")
    if periodic:
        offsets = unidirectional_offsets(rows, -(-moves // rows))[:moves]
    else:
        offsets = reciprocating_offsets(travel, -(-moves // (2 * travel)))[:moves]
    ends = list(range(0, moves + 1, per_pass)) + [moves]
    if len(ends) > MAX_HISTORY_ROWS:
        ends = [ends[i] for i in np.linspace(0, len(ends) - 1, MAX_HISTORY_ROWS).astype(int)]
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
                **counters)
    remark = track.coarse_wear_remark(counters["largest_wear_per_move"], sc["d0"], "move")
    if remark:
        info["warnings"] = [remark]
    if progress is not None:
        progress(1.0, "done")
    return RunResult(history=hist, stage_s=np.asarray(st["move"], float) * dx, r=r, f=f_avg,
                     p=p_avg, solve_seconds=time.perf_counter() - t0, info=info, fields=fields)
