"""The case definition: typed, frozen sections read from one TOML file.

Every key is declared once, as a dataclass field whose metadata holds its unit,
its check and its documentation. Reading, validation, ``--set`` overrides, the
resolved ``case.toml`` and the documentation's key reference all derive from these
declarations.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from dataclasses import dataclass, field
from typing import Any

from .errors import CaseError

REQUIRED = object()


def key(default=REQUIRED, *, unit="", doc="", choices=None, positive=False,
        minimum=None, maximum=None, open_minimum=False, open_maximum=False,
        multiple_of=None, why=""):
    """Declare one case key as a dataclass field.

    The key's own constraints (type, range, choices, ``multiple_of``, for a list
    each entry's) are declared here; ``why`` is said with a value that breaks
    ``multiple_of``. Rules between keys: ``cases/rules.py``.
    """
    meta = dict(unit=unit, doc=doc, choices=choices, positive=positive,
                minimum=minimum, maximum=maximum, open_minimum=open_minimum,
                open_maximum=open_maximum, multiple_of=multiple_of, why=why,
                required=default is REQUIRED)
    if default is REQUIRED:
        return field(default=None, metadata=meta)
    return field(default=default, metadata=meta)


# --------------------------------------------------------------------------
# Sections.  Order of fields is the order of the resolved case file.

PROFILES = ("paraboloid", "sphere", "truncated_paraboloid", "cone", "power_law", "table",
            "ellipsoid")
#: profiles that are not bodies of revolution
NON_AXISYMMETRIC = ("ellipsoid",)

# which geometry keys each profile takes and needs: cases/rules.py (PROFILE_KEYS)


@dataclass(frozen=True)
class Indenter:
    """The worn body: a body of revolution z = f(r), f(0) = 0 unworn (or an ellipsoid)."""

    profile: str = key(doc="shape of the unworn profile f(r)", choices=PROFILES)
    radius: float | None = key(None, unit="m", positive=True,
                               doc="radius of curvature R (paraboloid f = r^2/2R, sphere, "
                                   "truncated paraboloid); ellipsoid: the principal radius "
                                   "R1 along x; for other profiles the radius of the FEM body")
    radius_y: float | None = key(None, unit="m", positive=True,
                                 doc="ellipsoid: the principal radius R2 along y, f = x²/2R1 + "
                                     "y²/2R2 (R1 = radius); solved as it is by the BEM, with the "
                                     "equivalent radius √(R1 R2) (approximately) by the MDR")
    flat_radius: float | None = key(None, unit="m", positive=True,
                                    doc="radius b of the flat tip of a truncated paraboloid "
                                        "(paper Eq. 17)")
    slope_angle: float | None = key(None, unit="rad", minimum=0.0, maximum=math.pi / 2,
                                    open_minimum=True, open_maximum=True,
                                    doc="cone: angle θ between its flank and the plane, f = r tan θ")
    coefficient: float | None = key(None, unit="m^(1-n)", positive=True,
                                    doc="power law f = coefficient * r^exponent")
    exponent: float | None = key(None, positive=True, doc="power law exponent n")
    file: str | None = key(None,
                           doc="CSV with columns r, f in metres (header optional), r sorted, "
                               "starting at 0; relative to the case file")
    rigid: bool = key(False, doc="the indenter does not deform (1/E = 0)")
    youngs_modulus: float | None = key(None, unit="Pa", positive=True, doc="Young's modulus E1")
    poisson_ratio: float | None = key(None, minimum=-1.0, maximum=0.5, open_minimum=True,
                                      doc="Poisson ratio ν1, in (-1, 0.5]")


@dataclass(frozen=True)
class Counterface:
    """The flat counter-body (half-space in MDR, rigid plane in FEM)."""

    rigid: bool = key(True, doc="the counterface does not deform (1/E = 0)")
    youngs_modulus: float | None = key(None, unit="Pa", positive=True, doc="Young's modulus E2")
    poisson_ratio: float | None = key(None, minimum=-1.0, maximum=0.5, open_minimum=True,
                                      doc="Poisson ratio ν2, in (-1, 0.5]")
    wears: bool = key(False, doc="the counterface wears too, along the track (both bodies "
                                 "wearing, as in ASTM G133 and G99; BEM only, needs "
                                 "sliding.motion): give its specific_rate or k (with hardness)")
    specific_rate: float | None = key(None, unit="m^3/(N m)", positive=True,
                                      doc="counterface.wears: the counterface's specific wear "
                                          "rate K_flat, V_flat = K_flat·F·s; give this or "
                                          "counterface.k")
    k: float | None = key(None, unit="1", positive=True,
                          doc="counterface.wears: its dimensionless wear coefficient, "
                              "K_flat = k·μ/counterface.hardness (μ = wear.mu); give this or "
                              "counterface.specific_rate")
    hardness: float | None = key(None, unit="Pa", positive=True,
                                 doc="counterface.wears: hardness of the counterface (needed "
                                     "with counterface.k)")


@dataclass(frozen=True)
class Loading:
    control: str = key(doc="hold the indentation depth or the normal force fixed",
                       choices=("depth", "force"))
    depth: float | None = key(None, unit="m", positive=True,
                              doc="indentation depth d (control = depth), measured from "
                                  "first touch of the unworn profile")
    force: float | None = key(None, unit="N", positive=True,
                              doc="normal force F (control = force)")


@dataclass(frozen=True)
class Wear:
    k: float | None = key(None, unit="1", positive=True,
                          doc="dimensionless wear coefficient k_wear (paper Eq. 1), per unit "
                              "friction work; give this or wear.specific_rate (k = K·σ0/μ), "
                              "the other is derived")
    specific_rate: float | None = key(None, unit="m^3/(N m)", positive=True,
                                      doc="the laboratory's specific wear rate K of the worn "
                                          "body, V = K·F·s for n = 1; K = k μ/σ0, the "
                                          "dimensional coefficient of the wear law; give this "
                                          "or wear.k, the other is derived")
    mu: float = key(unit="1", positive=True, doc="coefficient of friction μ, τ = μ p (paper Eq. 14)")
    hardness: float = key(unit="Pa", positive=True, doc="hardness σ0 of the worn indenter")
    tangential_correction: bool = key(False,
                                      doc="reciprocating sliding: take off the slip the "
                                          "tangential springs lose at each stroke end while "
                                          "they reverse (2μq/G* per stroke, paper Eqs. 15-16; "
                                          "MDR only); needs sliding.stroke")
    pressure_exponent: float = key(1.0, minimum=1.0, maximum=4.0,
                                   doc="exponent n of the wear law dw/ds = (k μ/σ0)·σ0·(p/σ0)^n "
                                       "(1: Reye–Archard, the paper); in [1, 4] (below 1 the "
                                       "rate's derivative is infinite where p -> 0)")


@dataclass(frozen=True)
class Sliding:
    until: str = key("force_fraction", choices=("force_fraction", "distance", "cycles"),
                     doc="stop when the force has fallen below a fraction of its start, "
                         "after a total sliding distance, or after a number of reciprocating "
                         "cycles (s = 2·stroke·cycles, gross slip; revolutions of a "
                         "disc, s = 2π·track_radius·cycles, with sliding.motion = "
                         "\"unidirectional\")")
    force_fraction: float = key(0.01, minimum=0.0, maximum=1.0, open_minimum=True,
                                open_maximum=True,
                                doc="until = force_fraction: stop once F < force_fraction * F(0)")
    distance: float | None = key(None, unit="m", minimum=0.0,
                                 doc="until = distance: total sliding distance s (0: no sliding, "
                                     "the unworn contact only)")
    stroke: float | None = key(None, unit="m", positive=True,
                               doc="reciprocating stroke (one way); one cycle slides 2·stroke. "
                                   "Required by until = cycles and stages.cycles; without it "
                                   "history.csv's column `cycles` is NaN")
    motion: str | None = key(None, choices=("reciprocating", "unidirectional"),
                             doc="the test's motion, for a counterface that wears along its "
                                 "track: reciprocating (ASTM G133, the ball slides to and fro "
                                 "over sliding.stroke) or unidirectional (ASTM G99 pin-on-disc, "
                                 "a circular track of sliding.track_radius; a cycle is one "
                                 "revolution)")
    track_radius: float | None = key(None, unit="m", positive=True,
                                     doc="motion = unidirectional: radius of the wear track on "
                                         "the disc (G99's R); one revolution slides "
                                         "2π·track_radius")
    cycles: float | None = key(None, minimum=0.0,
                               doc="until = cycles: number of cycles to run (0: the unworn "
                                   "contact only)")
    scheme: str = key("adaptive", choices=("adaptive", "implicit", "bdf2", "explicit"),
                      doc="time scheme: adaptive, backward Euler with step doubling and "
                          "Richardson extrapolation, the step controlled by "
                          "sliding.tolerance; implicit (backward) Euler at a fixed step, "
                          "unconditionally stable, first order; bdf2, the variable-step "
                          "second-order backward differentiation formula, L-stable; or "
                          "explicit (forward) Euler as in the paper, stable below a step limit")
    # floor 1e-10: the step-doubling estimate is the difference of two O(1) solutions
    # (force /F0, depth /d0) each carrying the round-off of its solves (~N·eps, 1e-13 to
    # 1e-12 at N = 1e3-1e4); a tolerance near that is never met and the step shrinks
    # without end (1e-15 ran for minutes). The smallest used anywhere is 1e-6 (references/derive.py).
    tolerance: float = key(1e-4, minimum=1e-10, maximum=0.1,
                           doc="scheme = adaptive: local error allowed per step, estimated "
                               "by step doubling (force /F0; depth and central wear /max(d0, "
                               "value)); the global time error of the history comes out about "
                               "this size and is recorded in meta.json info.time_error; at "
                               "least 1e-10 (below it float64 round-off in the estimate is "
                               "never met)")
    step_hat: float | str = key("auto", positive=True,
                                doc="sliding step in units of the dimensionless sliding "
                                    "ŝ = k μ E* s / (σ0 a0), or \"auto\": the solver's "
                                    "default (explicit: half its stability limit; implicit "
                                    "and bdf2: MDR and BEM 0.1, FEM 0.02 and 0.01; adaptive: the "
                                    "largest step allowed, auto = no limit), recorded in "
                                    "meta.json info.step_hat")


@dataclass(frozen=True)
class Stages:
    s_hat: tuple[float, ...] = key((0.0,), minimum=0.0,
                                   doc="dimensionless sliding distances ŝ at which profiles "
                                       "and pressures are kept (increasing); stages after "
                                       "the end of the run are not reached")
    s: tuple[float, ...] | None = key(None, unit="m", minimum=0.0,
                                      doc="the stages as sliding distances instead (not "
                                          "together with s_hat or cycles; s_hat is then "
                                          "derived from them)")
    cycles: tuple[float, ...] | None = key(None, minimum=0.0,
                                           doc="the stages as numbers of cycles instead "
                                               "(needs sliding.stroke, with any "
                                               "sliding.until; not together with s_hat or s, "
                                               "s_hat is then derived from them)")


@dataclass(frozen=True)
class MDRSettings:
    elements: int = key(800, minimum=2, doc="number N of 1D springs (elements) on 0 <= x <= domain")
    domain_factor: float = key(1.25, minimum=1.0, open_minimum=True,
                               doc="radius of the initial simulated domain as a multiple of "
                                   "√2·a0, the contact radius reached at complete wear under "
                                   "depth control; the domain grows (the grid is remapped) "
                                   "when a worn contact nears its edge")
    linear_solver: str = key("auto", choices=("auto", "direct", "iterative"),
                             doc="how the implicit wear steps are solved: direct (a nested LU "
                                 "of the compliance per step size, 8 (N+1)² bytes each; "
                                 "adaptive steps keep to the ladder 2^k ŝ so that each serves "
                                 "many steps), iterative (FFT products and GMRES with a "
                                 "coarse-grid preconditioner, memory O(N); adaptive steps are "
                                 "set continuously), or auto: direct up to N = 2048. Both "
                                 "solve the same equations (to GMRES's tolerance)")
    krylov_precision: str = key("float32", choices=("float32", "float64"),
                                doc="iterative solves: the GMRES iterations in float32 inside an "
                                    "iterative refinement with float64 residuals (the answer "
                                    "meets the float64 tolerance, 10-15 % faster at N = 102400), "
                                    "or in float64 throughout (docs/mixed-precision.md)")


@dataclass(frozen=True)
class FEMSettings:
    contact_nodes: int = key(250, minimum=2,
                             doc="number of nodes on the candidate contact arc")
    contact_factor: float = key(1.25, minimum=0.0, open_minimum=True,
                                doc="extent of the candidate contact arc as a multiple of the "
                                    "predicted final contact radius (√2·a0 under depth "
                                    "control; under force control the long-run scar radius "
                                    "at the end of the run, started from a0: "
                                    "(a0⁴ + 4 R K F s/π)^(1/4) for n = 1)")
    element_order: int = key(2, minimum=1, maximum=2, doc="1: linear, 2: quadratic triangles")
    pressure_recovery: str = key("lumped", choices=("lumped", "consistent"),
                                 doc="nodal pressure = nodal force / lumped 2πr-weighted area, "
                                     "or a consistent boundary-mass recovery")


@dataclass(frozen=True)
class BEMSettings:
    grid: int = key(128, minimum=8, maximum=4096,
                    doc="pixels per side of the square surface grid")
    box: float = key(2.5, minimum=2.0, open_minimum=True,
                     doc="side of the square box as a multiple of the largest expected "
                         "contact radius: √2·a0 for a paraboloid under depth control (the "
                         "radius where f = d, complete wear), the predicted wear-scar radius "
                         "under force control; the long semi-axis for the ellipsoid")
    track_model: str = key("long_stroke", choices=("long_stroke", "moving"),
                           doc="counterface.wears: the long-stroke model (a groove h(y) "
                               "along the track, steady in the ball's frame; one contact "
                               "solve per step) or the moving-contact model (the ball "
                               "travels over a grid fixed to the flat, turnarounds "
                               "included; one contact solve per pixel of sliding: short "
                               "runs)")
    jump_tolerance: float = key(0.01, unit="1", minimum=0.0, maximum=1.0, open_maximum=True,
                                doc="bem.track_model = \"moving\": cycle jumping (ROS2 on "
                                    "the wear per simulated cycle, docs/both-bodies.md): "
                                    "the estimated error of both bodies' wear against the "
                                    "run that simulates every cycle, held at this fraction "
                                    "of the largest wear; 0 simulates every cycle (at most "
                                    "200 000 moves)")
    tolerance: float = key(1e-6, positive=True, maximum=1e-2,
                           doc="complementarity tolerance of each contact solve: "
                               "max |min(p/p0, gap/d)| over the pixels (1e-6: on the paper "
                               "case at 128², 3e-5 p0 and 2e-6 F0 from 1e-7, far inside the "
                               "pixel error, at 2/3 of the iterations)")
    coupling: bool = key(False,
                         doc="couple the normal and tangential problems (bodies not "
                             "elastically similar, Dundurs' β ≠ 0): the friction traction "
                             "μp along the sliding direction moves the surface normally, "
                             "which moves the pressure against it (docs/bem-tangential.md "
                             "§6); one sliding direction, or reciprocating strokes when "
                             "sliding.stroke is given; no effect when β = 0")


@dataclass(frozen=True)
class CCXSettings:
    mode: str = key("superelement", choices=("superelement", "in_loop"),
                    doc="superelement: CalculiX computes the contact nodes' compliance once "
                        "(cached), wearcheck's contact and time schemes run the wear; in_loop: "
                        "one CalculiX contact solve (gap elements) per explicit Euler step, a "
                        "cross-check for short runs on coarse meshes (docs/ccx.md)")
    contact_nodes: int = key(250, minimum=2,
                             doc="number of nodes on the candidate contact arc of the CAX6 "
                                 "sphere (the FEM's mesh at the same fem.contact_nodes)")
    contact_factor: float = key(1.25, minimum=0.0, open_minimum=True,
                                doc="extent of the candidate contact arc as a multiple of the "
                                    "predicted final contact radius (as fem.contact_factor)")
    executable: str = key("ccx", doc="the CalculiX solver: a command on PATH or a path to "
                                     "it (version 2.20 or later)")


@dataclass(frozen=True)
class CompareSettings:
    """What ``wearcheck compare`` accepts as agreement.

    Each stage is judged against its own magnitudes: a difference is divided by
    the reference's value at that stage (its force, peak pressure, depth, contact
    radius), floored at a small fraction of the unworn scale so that a quantity
    near zero is not judged relative to itself.
    """

    profile_tolerance: float = key(0.01, positive=True,
                                   doc="max profile difference allowed, relative to the "
                                       "stage's depth (the approach of the unworn tip, "
                                       "which includes the central wear)")
    force_tolerance: float = key(0.03, positive=True,
                                 doc="max force difference allowed, relative to the stage's "
                                     "force")
    pressure_tolerance: float = key(0.03, positive=True,
                                    doc="max pressure difference allowed away from the contact "
                                        "edge, relative to the stage's peak pressure")
    contact_radius_tolerance: float = key(0.02, positive=True,
                                          doc="max contact-radius difference allowed, relative "
                                              "to the stage's contact radius")
    profile_floor: float = key(0.01, positive=True,
                               doc="smallest profile scale of a stage, relative to the depth d "
                                   "(d0 under force control)")
    force_floor: float = key(0.01, positive=True,
                             doc="smallest force scale of a stage, relative to F0")
    pressure_floor: float = key(0.001, positive=True,
                                doc="smallest pressure scale of a stage, relative to p0")
    contact_radius_floor: float = key(0.1, positive=True,
                                      doc="smallest contact-radius scale of a stage, relative "
                                          "to a0")
    edge_band: float = key(0.1, minimum=0.0, maximum=1.0, open_maximum=True,
                           doc="width of the band at the contact edge, as a fraction of the "
                               "contact radius, whose pressure is reported separately")


@dataclass(frozen=True)
class Fretting:
    """Partial-slip (fretting) wear: a tangential oscillation under the normal load.

    Optional section; when present the run is a fretting run (MDR only) and
    replaces [sliding] and [stages].
    """

    amplitude: float | None = key(None, unit="m", positive=True,
                                  doc="tangential displacement amplitude u0 of the indenter "
                                      "(triangle wave between +u0 and -u0); give this or "
                                      "force_amplitude (an override of one replaces the "
                                      "other)")
    force_amplitude: float | None = key(None, unit="N", positive=True,
                                        doc="tangential force amplitude Q* (triangle wave "
                                            "between +Q* and -Q*), below μF; give this or "
                                            "amplitude (an override of one replaces the "
                                            "other)")
    cycles: int = key(unit="1", minimum=1, doc="number of fretting cycles (+U -> -U -> +U)")
    increments: int = key(40, unit="1", minimum=4, multiple_of=4,
                          why="a quarter cycle ramps from 0 to the amplitude",
                          doc="load increments per cycle, a multiple of 4 (the first "
                              "quarter cycle from 0 to +U takes a quarter of them); a run "
                              "they do not resolve (increment wear number past 1.3, "
                              "docs/fretting.md §5) is refused, naming the number that "
                              "would do")
    jump_tolerance: float = key(0.02, unit="1", minimum=0.0, maximum=1.0, open_maximum=True,
                                doc="cycle jumping (ROS2 on the wear per simulated cycle, "
                                    "docs/fretting.md §4): the estimated error of the worn "
                                    "profile against the run that simulates every cycle, "
                                    "held at this fraction of the largest wear and reported "
                                    "in meta.json (info.cycle_jumping.error_estimate); 0 "
                                    "simulates every cycle (refused when that would take "
                                    "more than ten minutes)")
    stage_cycles: tuple[float, ...] | None = key(None, unit="1", minimum=0.0, multiple_of=1,
                                                 why="cycle numbers",
                                                 doc="cycle numbers (increasing integers) at "
                                                     "which profile, pressure and shear "
                                                     "traction are kept (0: after the first "
                                                     "quarter cycle); stages after the last "
                                                     "cycle are not reached; default 0, 1, "
                                                     "10, 100, ... and the last cycle")


SECTIONS: dict[str, type] = {
    "indenter": Indenter,
    "counterface": Counterface,
    "loading": Loading,
    "wear": Wear,
    "sliding": Sliding,
    "stages": Stages,
    "mdr": MDRSettings,
    "fem": FEMSettings,
    "bem": BEMSettings,
    "ccx": CCXSettings,
    "compare": CompareSettings,
    "fretting": Fretting,
}
REQUIRED_SECTIONS = ("indenter", "loading", "wear")
#: sections that are None in a Case unless the file has them
OPTIONAL_SECTIONS = ("fretting",)


# --------------------------------------------------------------------------
# Key conversion and checks.

def _type_name(tp) -> str:
    if tp is float:
        return "a number"
    if tp is int:
        return "an integer"
    if tp is bool:
        return "true or false"
    if tp is str:
        return "a string"
    return str(tp)


def base_types(annotation) -> tuple:
    """The non-None types a field's annotation allows."""
    tp = eval(annotation, vars(typing)) if isinstance(annotation, str) else annotation
    if isinstance(tp, types.UnionType) or typing.get_origin(tp) is typing.Union:
        return tuple(t for t in typing.get_args(tp) if t is not type(None))
    return (tp,)


_TOML_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n",
                 "\f": "\\f", "\r": "\\r"}


def toml_string(text: str) -> str:
    """``text`` as a TOML basic string: quoted, with every character TOML forbids escaped.

    TOML basic strings may not hold ``"``, ``\\``, U+0000-U+001F or U+007F
    unescaped. A lone surrogate (a file name that was not valid UTF-8) has no
    TOML form and becomes U+FFFD.
    """
    out = []
    for ch in text:
        code = ord(ch)
        if ch in _TOML_ESCAPES:
            out.append(_TOML_ESCAPES[ch])
        elif code < 0x20 or code == 0x7F:
            out.append(f"\\u{code:04X}")
        elif 0xD800 <= code <= 0xDFFF:
            out.append("\ufffd")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def format_value(value) -> str:
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value)


def _check_number(name, value, meta):
    try:
        finite = math.isfinite(value)
    except OverflowError:  # an integer beyond the range of a float
        finite = False
    if not finite:
        raise CaseError(f"key '{name}' = {value!r}: must be a finite number")
    unit = f" {meta['unit']}" if meta["unit"] and meta["unit"] != "1" else ""
    if meta["positive"] and not value > 0:
        raise CaseError(f"key '{name}' = {format_value(value)}: must be > 0{unit}")
    lo, hi = meta["minimum"], meta["maximum"]
    if lo is not None and (value < lo or (meta["open_minimum"] and value == lo)):
        lb = "(" if meta["open_minimum"] else "["
        rb = ")" if meta["open_maximum"] else "]"
        allowed = f"in {lb}{lo:g}, {hi:g}{rb}" if hi is not None else \
            f"{'>' if meta['open_minimum'] else '>='} {lo:g}"
        raise CaseError(f"key '{name}' = {format_value(value)}: must be {allowed}{unit}")
    if hi is not None and (value > hi or (meta["open_maximum"] and value == hi)):
        lb = "(" if meta["open_minimum"] else "["
        rb = ")" if meta["open_maximum"] else "]"
        allowed = f"in {lb}{lo:g}, {hi:g}{rb}" if lo is not None else \
            f"{'<' if meta['open_maximum'] else '<='} {hi:g}"
        raise CaseError(f"key '{name}' = {format_value(value)}: must be {allowed}{unit}")
    step = meta["multiple_of"]
    if step is not None and value % step:
        want = "a whole number" if step == 1 else f"a multiple of {step:g}"
        raise CaseError(f"key '{name}' = {format_value(value)}: must be {want}"
                        + (f" ({meta['why']})" if meta["why"] else ""))
    return value


def convert(name: str, f: dataclasses.Field, value: Any):
    """Check one raw TOML value against its declaration; return the typed value."""
    meta = f.metadata
    allowed = base_types(f.type)
    origin = [typing.get_origin(t) for t in allowed]
    if tuple in origin:  # list of numbers
        if not isinstance(value, (list, tuple)) or not value:
            hint = ""
            if isinstance(value, str) and "," in value:    # --set stages.s_hat=0,1
                hint = f", written in brackets: [{value.strip('[]() ').replace(',', ', ')}]"
            elif isinstance(value, (int, float)) and not isinstance(value, bool):
                hint = f", written in brackets: [{format_value(value)}]"
            raise CaseError(f"key '{name}' = {format_value(value)}: must be a non-empty list of "
                            f"numbers{hint}")
        out = []
        for v in value:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise CaseError(f"key '{name}' = {format_value(value)}: every entry must be a number")
            out.append(_check_number(name, float(_check_number(name, v, meta)), meta))
        return tuple(out)
    if isinstance(value, bool):
        if bool in allowed:
            return value
    elif isinstance(value, int) and int in allowed:
        return int(_check_number(name, value, meta))
    elif isinstance(value, float) and int in allowed and float not in allowed \
            and math.isfinite(value) and value.is_integer():
        # 1e3 is a float in TOML; an integral one is the integer (as in JSON Schema)
        return int(_check_number(name, int(value), meta))
    elif isinstance(value, (int, float)) and float in allowed:
        return _check_number(name, float(_check_number(name, value, meta)), meta)
    elif isinstance(value, str) and str in allowed:
        choices = meta["choices"]
        if float in allowed and value != "auto":  # a number or "auto"
            raise CaseError(f"key '{name}' = {format_value(value)}: must be a number or \"auto\"")
        if choices is not None and value not in choices:
            raise CaseError(f"key '{name}' = {format_value(value)}: must be one of "
                            + ", ".join(f'"{c}"' for c in choices))
        return value
    want = " or ".join(_type_name(t) for t in allowed)
    if float in allowed and str in allowed:
        want = 'a number or "auto"'
    unit = meta.get("unit") or ""
    if isinstance(value, str) and (float in allowed or int in allowed) and unit not in ("", "1"):
        # "2 GPa", "1 um": the unit goes with the key, the file holds the number alone
        want += f" in {unit} (case files are SI; write the number alone, without a unit)"
    raise CaseError(f"key '{name}' = {format_value(value)}: must be {want}")


def did_you_mean(name: str, allowed) -> str:
    """" (did you mean 'mu'?)" for a near miss of one of ``allowed``, else ""."""
    import difflib
    close = difflib.get_close_matches(str(name), list(allowed), n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


def key_problem(name) -> str | None:
    """What is wrong with ``name`` as a dotted case key (``"wear.mu"``), or None if declared."""
    section, _, key = str(name).partition(".")
    if not isinstance(name, str) or not key or "." in key:
        return "a key must be section.key, e.g. wear.mu"
    if section not in SECTIONS:
        return (f"unknown section '{section}'{did_you_mean(section, SECTIONS)}; allowed: "
                + ", ".join(SECTIONS))
    names = [f.name for f in dataclasses.fields(SECTIONS[section])]
    if key not in names:
        return (f"unknown key '{name}'{did_you_mean(key, names)}; allowed in [{section}]: "
                + ", ".join(names))
    return None


def build_section(section: str, raw: dict) -> Any:
    """Build one section from its raw TOML table; unknown and missing keys are errors."""
    cls = SECTIONS[section]
    fields = {f.name: f for f in dataclasses.fields(cls)}
    if not isinstance(raw, dict):
        raise CaseError(f"'{section}' must be a table [{section}], got {format_value(raw)}")
    unknown = sorted(set(raw) - set(fields))
    if unknown:
        hint = did_you_mean(unknown[0], fields)
        elsewhere = [other for other, c in SECTIONS.items() if other != section
                     and unknown[0] in {f.name for f in dataclasses.fields(c)}]
        if elsewhere and not hint:     # mu under [sliding]: a key of another section
            hint = f" ('{unknown[0]}' is a key of [{elsewhere[0]}])"
        raise CaseError(f"unknown key '{section}.{unknown[0]}'"
                        f"{hint}; allowed in [{section}]: "
                        + ", ".join(fields))
    values = {}
    for name, f in fields.items():
        full = f"{section}.{name}"
        if name in raw:
            values[name] = convert(full, f, raw[name])
        elif f.metadata["required"]:
            raise CaseError(f"missing key '{full}' ({f.metadata['doc']})")
    return cls(**values)


def section_fields(section: str):
    """(name, Field) pairs of a section, in declaration order."""
    return [(f.name, f) for f in dataclasses.fields(SECTIONS[section])]
