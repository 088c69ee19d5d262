"""Both bodies wearing, long-stroke model: the ball and a groove h(y) along its track.

When the stroke (or the pin-on-disc circumference) is many contact lengths
long, the contact is steady in the ball's frame over most of it, and the
counterface's wear varies only across the sliding direction x: a groove
h(y). Each step is one contact solve in the ball's frame on the pixels,

    gap = f(x, y) + h(y) - d + G p >= 0,   p >= 0,   p·gap = 0,

f the ball's worn profile, which wears as the ball-only BEM's (df/ds = K_ball p
at each pixel), while every pass over a point of the track's middle wears the
counterface there by K_flat ∫ p dx, so per metre of sliding

    dh/ds (y) = K_flat/L · ∫ p(x, y) dx,

L the sliding between two passes over a point (:func:`cases.both_bodies.pass_length`:
the stroke, or the circumference 2π·track_radius). Each body then loses
K_body·F·s: V_ball = Δ² Σ w, V_flat = L·Δ Σ h.

The implicit (backward Euler) step of length eff = c·h couples the two: the
ball's wear compliance eff·K_ball·I and the groove's eff·K_flat·Δ/L·B, B the sum
along x of a pixel column, (B p)_ij = Σ_i' p_i'j — symmetric positive
semi-definite, so the contact problem stays a convex quadratic programme and
:func:`bem.contact.solve` solves it unchanged on the operator
:class:`TrackOperator` = G + σ_flat B. Ball and groove wear from the same
pressures, so V_ball/V_flat = K_ball/K_flat holds at every step to round-off.

Not modelled here: the turnaround ends of the track (:mod:`bem.moving` has them),
the track's curvature on a disc (radius ≫ contact), the wear within one pass
(the per-pass wear K_flat ∫ p dx must be small beside the elastic approach; its
largest value is recorded), a pressure exponent n ≠ 1.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.fft as sfft

from wearcheck.cases import CaseError, RunResult, SolverError, both_bodies, programme
from wearcheck.cases import profiles, reference, validity
from wearcheck.cases.result import SCAR_THRESHOLD, scar_radius
from wearcheck.numerics import stepping

from .wear import ring_scar_radius

from . import contact
from .operator import HalfSpace

#: fixed-step schemes' default step in ŝ (as the ball-only BEM's)
DEFAULT_STEP_HAT = 0.1
#: the wear of one pass (or move), over d0, beyond which a run says that its
#: model's continuous wear is coarse
COARSE_PASS = 0.05
#: the shortest stroke, in unworn contact diameters 2a0, for which the run does not
#: warn: from 3 diameters on the long-stroke model's groove and ball wear agree with
#: the moving-contact model's within about 3 % of their largest (the model leaves out
#: the track's ends, a share ~a/L of it); below, the difference grows fast
#: (docs/both-bodies.md, "Range"; tests/test_bem_moving.py)
SHORT_STROKE_DIAMETERS = 3.0
#: the largest ratio a0/track_radius of a pin-on-disc run that does not warn. A disc's
#: track has no ends (the stroke criterion above would warn only below a0/R_t = π/3,
#: which the loader refuses: a track radius below a0), but both models lay the track
#: straight: across the contact the sliding per revolution varies as r/R_t, by ±a0/R_t
#: at the contact's edges. Past 3 % (the agreement the stroke criterion accepts) the
#: local wear of both bodies is skewed by more than that toward the outer edge; the
#: volumes hold (the pressure-weighted mean radius is R_t).
CURVED_TRACK_RATIO = 0.03


class TrackOperator:
    """p -> G p + σ_flat·B p: the half-space and the groove's wear compliance.

    ``B`` sums a pixel column along x (the first axis) and spreads the sum
    over it: the groove under a column deepens by the pressure's integral
    along the sliding direction. Offers what :func:`bem.contact.solve` uses of
    an operator (``spacing``, call, ``single``, ``preconditioner``,
    ``add_point_loads``).
    """

    def __init__(self, op: HalfSpace, sigma_flat: float):
        self.op, self.sigma_flat = op, float(sigma_flat)
        self.spacing, self.n = op.spacing, op.n

    def __call__(self, p: np.ndarray) -> np.ndarray:
        u = self.op(p)
        if self.sigma_flat:
            u += self.sigma_flat * np.sum(p, axis=0)[None, :]
        return u

    def single(self, p: np.ndarray) -> np.ndarray:
        """:meth:`__call__` with the half-space's transforms in single precision
        (:meth:`HalfSpace.single`, whose error bound the contact solve carries); the
        groove's column sums stay in double."""
        u = self.op.single(p)
        if self.sigma_flat:
            u = u + self.sigma_flat * np.sum(p, axis=0)[None, :]
        return u

    def preconditioner(self, sigma: float = 0.0):
        """v -> C⁻¹ v, C the n-periodic circulant of G + σI + σ_flat B.

        B is n times the projection onto the zero frequency along x, so it
        adds n·σ_flat to the circulant's eigenvalues on that row.
        """
        op, n = self.op, self.n
        eig = op.kernel_hat[::2, ::2] + sigma
        eig[0, :] += n * self.sigma_flat
        inv = 1.0 / eig

        def apply(v):
            return sfft.irfft2(sfft.rfft2(v, workers=op.workers) * inv, s=(n, n),
                               workers=op.workers)
        return apply

    def add_point_loads(self, u, idx, values) -> None:
        self.op.add_point_loads(u, idx, values)
        if self.sigma_flat:
            np.add.at(u.T, idx[1], self.sigma_flat * np.asarray(values)[:, None])

    @property
    def applications(self) -> int:
        return self.op.applications


@dataclass
class TrackModel:
    """A discretised both-bodies case: operator, unworn ball, both wear rates, load."""

    op: HalfSpace
    f0: np.ndarray             # (n, n) unworn ball heights at the pixel centres [m]
    wear_rate: float           # K_ball [1/Pa]
    flat_wear_rate: float      # K_flat [1/Pa]
    pass_length: float         # L: sliding between two passes over a point [m]
    depth: float | None
    force: float | None
    p_scale: float
    g_scale: float
    tol: float = 1e-8
    maxiter: int = 5000
    centre: tuple[int, int] = (0, 0)

    def groove_rate(self) -> float:
        """dh/ds per unit of Σ_i p_ij [m/(Pa·m)]: K_flat·Δ/L."""
        return self.flat_wear_rate * self.op.spacing / self.pass_length


@dataclass
class TrackState:
    f: np.ndarray              # (n, n) ball's worn profile
    groove: np.ndarray         # (n,) groove depth h(y) of the counterface
    p: np.ndarray
    gap: np.ndarray
    depth: float
    force: float
    iterations: int
    residual: float
    extra: dict = field(default_factory=dict)


def contact_state(model: TrackModel, f_base, groove_base, eff: float = 0.0,
                  p_init=None) -> TrackState:
    """The contact of ball ``f_base`` in groove ``groove_base``, with the wear of a
    backward-Euler step of ``eff`` (0: a static solve); returns the worn state."""
    sigma_ball = eff * model.wear_rate
    sigma_flat = eff * model.groove_rate()
    c = contact.solve(TrackOperator(model.op, sigma_flat), f_base + groove_base[None, :],
                      depth=model.depth, force=model.force, sigma=sigma_ball, p_init=p_init,
                      p_scale=model.p_scale, g_scale=model.g_scale, tol=model.tol,
                      maxiter=model.maxiter)
    p = c.pressure
    if np.any(p[0] > 0) or np.any(p[-1] > 0) or np.any(p[:, 0] > 0) or np.any(p[:, -1] > 0):
        raise SolverError("the contact has reached the edge of the BEM box (pressure on its "
                          "outermost pixels); raise bem.box")
    return TrackState(f=f_base + sigma_ball * p, groove=groove_base + sigma_flat * p.sum(axis=0),
                      p=p, gap=c.gap, depth=c.depth, force=c.force, iterations=c.iterations,
                      residual=c.residual)


def explicit_limit(model: TrackModel) -> float:
    """Largest stable explicit Euler step [m]: 2 λ_min(G) / λ_max(W).

    W = K_ball I + K_flat Δ/L · B is the wear-rate operator; λ_max(B) <= n
    (a column of n pixels), so λ_max(W) <= K_ball + K_flat·nΔ/L (sufficient).
    """
    n = model.op.n
    return 2.0 * model.op.smallest_eigenvalue() / (model.wear_rate
                                                   + n * model.groove_rate())


class TrackWear(stepping.Problem):
    """The long-stroke model's step as :mod:`numerics.stepping` steps it.

    The integrated variable is the ball's profile and the groove side by side
    (f.ravel(), h), so step doubling's Richardson correction and BDF2's
    history carry both. The error estimate reads the force, the approach and
    the total wear at the centre (ball + groove).
    """

    def __init__(self, model: TrackModel, start: TrackState):
        self.model, self.n = model, model.op.n
        self.last = None
        self.cg_iterations = start.iterations

    def _split(self, y):
        n = self.n
        return y[:n * n].reshape(n, n), y[n * n:]

    def _guess(self, state, h):
        if self.last is None:
            return state.p
        guess = np.maximum(state.p + (h / self.last[1]) * (state.p - self.last[0]), 0.0)
        return guess if np.any(guess > 0) else state.p

    def implicit(self, origin, base, h, c, sub):
        p_guess = origin.p if sub.kind == "second" else self._guess(sub.start, sub.length)
        f_base, g_base = self._split(base)
        new = contact_state(self.model, f_base, g_base, c * h, p_guess)
        self.cg_iterations += new.iterations
        return new

    def explicit(self, state, h, sub):
        m = self.model
        new = contact_state(m, state.f + h * m.wear_rate * state.p,
                            state.groove + h * m.groove_rate() * state.p.sum(axis=0), 0.0,
                            state.p)
        self.cg_iterations += new.iterations
        return new

    def profile(self, state):
        return np.concatenate([state.f.ravel(), state.groove])

    def measures(self, state):
        i0, j0 = self.model.centre
        wear = state.f[i0, j0] - self.model.f0[i0, j0] + state.groove[j0]
        return state.force, state.depth, wear

    def accepted(self, old, new, h):
        self.last = (old.p, h)


def track_width(y: np.ndarray, groove: np.ndarray, threshold: float = SCAR_THRESHOLD) -> float:
    """Width of the track [m]: where the groove is at least ``threshold`` of its deepest,
    each side of the deepest point read as :func:`cases.result.scar_radius`."""
    if not np.max(groove) > 0.0:
        return 0.0
    j = int(np.argmax(groove))
    right = scar_radius(y[j:] - y[j], groove[j:], threshold)
    left = scar_radius(y[j] - y[j::-1], groove[j::-1], threshold)
    return right + left


def record_ball(hist: dict, model, s: float, w: np.ndarray, force: float, depth: float,
                p: np.ndarray, iterations: int, y: np.ndarray, i: int, j: int, ring) -> None:
    """Append the ball's history columns (both track models): force, depth, contact
    radius (loaded pixels), central wear w[i, j], worn volume, scar along and across
    the sliding, ring-averaged scar radius, peak pressure, CG iterations."""
    area = model.op.spacing ** 2
    hist["s"].append(s)
    hist["force"].append(force)
    hist["depth"].append(depth)
    loaded = np.count_nonzero(p > model.tol * model.p_scale)
    hist["contact_radius"].append(math.sqrt(loaded * area / math.pi))
    hist["wear_center"].append(float(w[i, j]))
    hist["wear_volume"].append(float(np.sum(w)) * area)
    hist["scar_length"].append(track_width(y, w[:, j]))
    hist["scar_width"].append(track_width(y, w[i, :]))
    hist["scar_radius"].append(ring_scar_radius(ring, w))
    hist["max_pressure"].append(float(np.max(p)))
    hist["cg_iterations"].append(iterations)


def run(model: TrackModel, plan: stepping.Plan, progress=None, *, y=None, ring=None,
        watch=None) -> dict:
    """Step both bodies' wear from the unworn state as ``plan`` says.

    Returns the history (the ball-only BEM's columns plus
    ``wear_volume_counterface``, ``track_width``, ``track_depth``,
    ``track_area``, and the ball's scar along and across the sliding,
    ``scar_length`` and ``scar_width``, read as :func:`track_width`), the stages (s, f, p, gap, depth, groove) and counters.
    """
    n = model.op.n
    dy = model.op.spacing
    y = np.arange(n) * dy if y is None else y
    i0, j0 = model.centre
    state = contact_state(model, model.f0.copy(), np.zeros(n))
    if not state.force > 0.0:
        raise SolverError("the unworn indenter carries no load")
    names = ("s", "force", "depth", "contact_radius", "wear_center", "wear_volume",
             "wear_volume_counterface", "track_width", "track_depth", "track_area",
             "max_pressure", "cg_iterations", "complementarity_residual", "scar_radius",
             "scar_length", "scar_width")
    hist = {k: [] for k in names}
    stages = []
    column = [0.0]      # the largest Σ_i p_ij seen: one pass wears K_flat·Δ times it

    def record(st, s, reached):
        w = st.f - model.f0
        record_ball(hist, model, s, w, st.force, st.depth, st.p, st.iterations, y, i0, j0, ring)
        section = float(np.sum(st.groove)) * dy
        hist["wear_volume_counterface"].append(section * model.pass_length)
        hist["track_area"].append(section)
        hist["track_width"].append(track_width(y, st.groove))
        hist["track_depth"].append(float(np.max(st.groove)))
        column[0] = max(column[0], float(np.max(st.p.sum(axis=0))))
        hist["complementarity_residual"].append(st.residual)
        if watch is not None:
            watch(s, hist["contact_radius"][-1], hist["scar_radius"][-1])
        for _ in range(reached):
            stages.append((s, st.f.copy(), st.p.copy(), st.gap.copy(), st.depth,
                           st.groove.copy()))

    problem = TrackWear(model, state)
    outcome = stepping.run(problem, state, plan, record, progress)
    counters = dict(stepping.info(outcome, plan), cg_iterations=problem.cg_iterations,
                    largest_wear_per_pass=model.flat_wear_rate * model.op.spacing * column[0])
    return dict(history={k: np.asarray(v) for k, v in hist.items()}, stages=stages,
                counters=counters)


# -- the case adapter ----------------------------------------------------------

def supports(case) -> str | None:
    """None when the long-stroke model can run ``case`` (a counterface that wears)."""
    if case.wear.pressure_exponent != 1.0:
        return (f"key 'wear.pressure_exponent' = {case.wear.pressure_exponent!r}: the BEM wears "
                "the counterface by Reye–Archard's law (n = 1) only")
    if getattr(case, "fretting", None) is not None:
        return "a counterface that wears needs gross sliding ([sliding]), not [fretting]"
    if getattr(case.bem, "coupling", False):
        return ("key 'bem.coupling' = true: the friction coupling is not modelled with a "
                "counterface that wears; set bem.coupling = false")
    return None


def largest_track_radius(case, sc: dict) -> float:
    """The largest contact radius the run can reach [m] (the box is sized on it).

    Under force control, for a sphere or paraboloid: √(b² + w²/4), b the
    ball-only BEM's (:func:`bem.solver.largest_contact_radius`, the ball's wear
    alone) and w the width of a groove cut by the unworn ball that holds
    V_flat = K_flat F s (parabolic section w³/(12R) = V_flat/L). Under depth
    control the contact never passes f = d, as for the ball alone."""
    # lazy (c): bem.solver imports this module
    from .solver import largest_contact_radius
    a_ball = largest_contact_radius(case, sc)
    ind, ld = case.indenter, case.loading
    if ld.control == "depth" or ind.profile not in ("sphere", "paraboloid"):
        return a_ball
    section = case.counterface_wear_rate * ld.force * (case.end_distance or 0.0) \
        / both_bodies.pass_length(case.sliding)
    # the two closures add at the centre (cap b²/2R, groove w²/8R): the unworn
    # ball reaches their sum at √(b² + w²/4)
    return math.hypot(a_ball, 0.5 * (12.0 * ind.radius * section) ** (1.0 / 3.0))


def setup(case, sc: dict, spacing: float | None = None) -> tuple[TrackModel, np.ndarray]:
    """The model of ``case`` on its grid, and the pixel-centre coordinates (n,).

    ``spacing``: a pixel side at most the case's (the moving-contact model's,
    which divides the stroke), instead of the case's.
    """
    # lazy (c): bem.solver imports this module
    from .solver import grid
    n = case.bem.grid
    x, dx, a_max = grid(case, sc, largest_track_radius(case, sc),
                        " in a box that holds the worn track")
    if spacing is not None and spacing < dx:
        dx = spacing
        x = (np.arange(n) - n // 2) * dx
    X, Y = np.meshgrid(x, x, indexing="ij")
    f0 = profiles.height_xy(case.indenter, X, Y, case.table)
    f0 -= f0[n // 2, n // 2]
    d_scale = case.loading.depth if case.loading.control == "depth" else sc["d0"]
    model = TrackModel(op=HalfSpace(n, dx, case.E_star), f0=f0, wear_rate=case.wear_rate,
                       flat_wear_rate=case.counterface_wear_rate,
                       pass_length=both_bodies.pass_length(case.sliding),
                       depth=case.loading.depth, force=case.loading.force, p_scale=sc["p0"],
                       g_scale=d_scale, tol=case.bem.tolerance, centre=(n // 2, n // 2))
    return model, x


def step_hat_of(case, limit_hat: float) -> float:
    """The step in ŝ of the case's scheme (adaptive: the largest, inf for none)."""
    sl = case.sliding
    if sl.scheme == "explicit":
        step = 0.5 * limit_hat if sl.step_hat == "auto" else float(sl.step_hat)
        if step > limit_hat:
            raise CaseError(f"key 'sliding.step_hat' = {sl.step_hat!r}: past the stability "
                            f"limit of explicit Euler with both bodies wearing; the largest "
                            f"stable step is {limit_hat:.4g}; use a smaller step or "
                            "sliding.scheme = \"implicit\"")
        return step
    if sl.step_hat == "auto":
        return math.inf if sl.scheme == "adaptive" else DEFAULT_STEP_HAT
    return float(sl.step_hat)


def coarse_wear_remark(largest: float, d0: float, unit: str) -> str | None:
    """The remark when one pass (move) wears the counterface by more than
    :data:`COARSE_PASS` of d0, else None."""
    if not largest > COARSE_PASS * d0:
        return None
    return (f"one {unit} wears the counterface by up to {largest / d0:.3g} d0 (more than "
            f"{COARSE_PASS:g}): the {'long-stroke' if unit == 'pass' else 'moving-contact'} "
            f"model takes that wear as continuous, which it no longer is; "
            + ("a short run is better solved with bem.track_model = \"moving\""
               if unit == "pass" else "refine bem.grid (a move is one pixel)"))


def short_stroke_remark(sliding, a0: float) -> str | None:
    """The remark when a reciprocating stroke is shorter than
    :data:`SHORT_STROKE_DIAMETERS` unworn contact diameters ``2·a0``, or a disc's
    track radius below a0/:data:`CURVED_TRACK_RATIO`; else None."""
    if sliding.motion == "unidirectional":
        return curved_track_remark(sliding, a0)
    if not sliding.stroke:
        return None
    diameters = sliding.stroke / (2.0 * a0)
    if diameters >= SHORT_STROKE_DIAMETERS:
        return None
    return (f"key 'sliding.stroke' = {sliding.stroke!r}: the stroke is {diameters:.3g} unworn "
            f"contact diameters (2a0 = {2.0 * a0:.4g} m), below the {SHORT_STROKE_DIAMETERS:g} "
            "from which the long-stroke model (a groove along the whole track) agrees with "
            "the moving contact within about 3 %; it leaves out the track's ends, which "
            "make up much of so short a track (at 1 diameter the groove differs by 26 %): "
            "solve it with bem.track_model = \"moving\" (docs/both-bodies.md, \"Range\")")


def curved_track_remark(sliding, a0: float) -> str | None:
    """The remark when a disc's track is curved on the contact's scale (a0/R_t past
    :data:`CURVED_TRACK_RATIO`), else None."""
    R_t = sliding.track_radius
    if not R_t or a0 / R_t <= CURVED_TRACK_RATIO:
        return None
    return (f"key 'sliding.track_radius' = {R_t!r}: the track radius is {R_t / a0:.3g} unworn "
            f"contact radii (a0 = {a0:.4g} m; its circumference {math.pi * R_t / a0:.3g} "
            f"contact diameters), below the {1.0 / CURVED_TRACK_RATIO:.3g} from which the "
            "straight track both BEM models take is within "
            f"{100 * CURVED_TRACK_RATIO:g} %: the sliding per revolution varies by "
            f"±{100 * a0 / R_t:.2g} % across the contact, which skews both bodies' wear "
            "toward the track's outer edge (the volumes hold); results are approximate "
            "(docs/both-bodies.md, \"Range\")")


def balance(history: dict, K_ball: float, K_flat: float, force=None) -> dict:
    """The global Archard balance of a run: each body loses K_body·F·s.

    ``ratio_error``: max over the steps with wear of |V_ball K_flat/(V_flat K_ball) − 1|;
    under force control (``force`` given) also ``ball_error`` and ``flat_error``,
    max |V/(K F s) − 1|.
    """
    Vb = np.asarray(history["wear_volume"], float)
    Vf = np.asarray(history["wear_volume_counterface"], float)
    s = np.asarray(history["s"], float)
    worn = (s > 0) & (Vf > 0)
    out = dict(ratio_error=float(np.max(np.abs(Vb[worn] * K_flat / (Vf[worn] * K_ball) - 1.0),
                                        initial=0.0)))
    if force is not None:
        out["ball_error"] = float(np.max(np.abs(Vb[worn] / (K_ball * force * s[worn]) - 1.0),
                                         initial=0.0))
        out["flat_error"] = float(np.max(np.abs(Vf[worn] / (K_flat * force * s[worn]) - 1.0),
                                         initial=0.0))
    return out


def solve(case, progress=None) -> RunResult:
    """The BEM run of a case whose counterface wears: the long-stroke model."""
    # lazy (c): bem.solver imports this module
    from .solver import ring_average
    reason = supports(case)
    if reason is not None:
        raise CaseError(reason)
    t0 = time.perf_counter()
    sc = reference.scales(case)
    per_m = sc["s_hat_per_m"]
    validity.check_planned(case)
    model, x = setup(case, sc)
    n, dx = len(x), model.op.spacing
    limit_hat = explicit_limit(model) * per_m
    step_hat = step_hat_of(case, limit_hat)
    plan, until = programme.stepping_plan(case, step_hat, sc)
    X, Y = np.meshgrid(x, x, indexing="ij")
    ring = np.rint(np.hypot(X, Y) / dx).astype(np.int64)
    rings = n // 2
    r = np.arange(rings) * dx
    watch = validity.BodyWatch(case, spacing=dx)
    short = short_stroke_remark(case.sliding, sc["a0"])
    if short:
        validity.remark(watch.remarks, short)
    out = run(model, plan, progress, y=x, ring=(ring, rings, r), watch=watch)
    hist = programme.finish_history(case, out["history"], until, plan.end, per_m)
    K = len(out["stages"])
    f_avg, p_avg = np.zeros((K, rings)), np.zeros((K, rings))
    fields = {k: np.zeros((K, n, n)) for k in ("profile", "wear_depth", "pressure", "gap")}
    fields["track_depth"] = np.zeros((K, n))
    for k, (_s, f, p, gap, _d, groove) in enumerate(out["stages"]):
        f_avg[k], p_avg[k] = ring_average(f, ring, rings), ring_average(p, ring, rings)
        fields["profile"][k], fields["wear_depth"][k] = f, f - model.f0
        fields["pressure"][k], fields["gap"][k] = p, gap
        fields["track_depth"][k] = groove
    fields["x"], fields["y"] = x.copy(), x.copy()
    info = dict(solver="bem", model="both bodies wearing, long-stroke (groove h(y))",
                grid=n, pixel=dx, box_side=n * dx, scheme=case.sliding.scheme,
                tolerance=case.bem.tolerance, explicit_limit_step_hat=float(limit_hat),
                step_hat=float(step_hat) if math.isfinite(step_hat) else "unlimited",
                counterface_wear_rate=model.flat_wear_rate, pass_length=model.pass_length,
                motion=case.sliding.motion,
                archard_balance=balance(hist, model.wear_rate, model.flat_wear_rate,
                                        case.loading.force),
                not_modelled="the track's turnaround ends and curvature, the wear within "
                             "one pass (largest_wear_per_pass, K_flat ∫ p dx at its largest, "
                             "against the approach: the model wants it small)")
    remarks = list(watch.remarks)
    remark = coarse_wear_remark(out["counters"]["largest_wear_per_pass"], sc["d0"], "pass")
    if remark:
        remarks.append(remark)
    if remarks:
        info["warnings"] = remarks
    info.update(out["counters"], operator_applications=model.op.applications,
                max_complementarity_residual=float(np.max(hist["complementarity_residual"])))
    if progress is not None:
        progress(1.0, "done")
    return RunResult(history=hist, stage_s=np.array([st[0] for st in out["stages"]]),
                     r=r, f=f_avg, p=p_avg, solve_seconds=time.perf_counter() - t0, info=info,
                     fields=fields)
