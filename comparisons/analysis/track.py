"""What a wear rig measures when both bodies wear, beside the laboratory formulas.

Pure functions of a both-bodies run's history (arrays in, arrays out). A lab
measures the ball's (pin's) scar diameter D and the track's width w on the
flat (disc), and computes the volumes from them by rigid geometry, as if the
other body had not worn:

* ball (ASTM G133) and pin (ASTM G99): the spherical cap of base diameter D,
  V = π D⁴/(64 R) to leading order (:func:`comparisons.analysis.scar.lab_volume`;
  G99 writes the exact cap, :func:`comparisons.analysis.scar.cap_volume`);
* disc (G99): the track as a ring of the circular segment the unworn pin of
  radius r cuts to width w, V = 2π R_track [r² asin(w/2r) − (w/4)√(4r² − w²)];
* reciprocating flat (G133 asks for the mean cross-section × stroke from
  profilometry; from the width alone the same segment over the stroke, plus
  the two half-caps of the ends): V = L·A_seg(w, R) + cap(w, R).

:func:`track_table` puts them beside the true volumes, with the profilometer's
reading L × (cross-section area of the track's middle).
"""

from __future__ import annotations

import math

import numpy as np

from wearcheck.cases import both_bodies

from .scar import cap_volume, lab_volume


def segment_area(width, radius):
    """Area [m²] of the circular segment of chord ``width`` cut from a circle of ``radius``."""
    w = np.asarray(width, dtype=float)
    half = 0.5 * w
    return radius**2 * np.arcsin(np.minimum(half / radius, 1.0)) \
        - half * np.sqrt(np.maximum(radius**2 - half**2, 0.0))


def disc_volume(width, pin_radius, track_radius):
    """ASTM G99's disc volume [m³]: 2π R_track · A_seg(w, r_pin)."""
    return 2.0 * math.pi * track_radius * segment_area(width, pin_radius)


def flat_volume(width, ball_radius, stroke):
    """A reciprocating flat's volume [m³] from the track width: stroke·A_seg(w, R) plus the
    two half-caps of the ends (one spherical cap of base w)."""
    return stroke * segment_area(width, ball_radius) + cap_volume(width, ball_radius)


def stage_rows(history: dict, stage_s) -> np.ndarray:
    """The history rows of the stored stages (the row at each stage's s)."""
    s = np.asarray(history["s"], dtype=float)
    return np.array([int(np.argmin(np.abs(s - t))) for t in np.asarray(stage_s, float)],
                    dtype=int)


def track_table(history: dict, case, rows=None) -> dict:
    """Both bodies' true volumes beside the laboratory's formula volumes.

    Parameters
    ----------
    history : a both-bodies run's history (``s``, ``scar_length``, ``scar_width``,
        ``wear_volume``, ``wear_volume_counterface``, ``track_width``,
        ``track_depth``, ``track_area``; ``cycles``).
    case : the run's case (ball radius, motion, stroke or track radius).
    rows : the history rows to tabulate (default: all with s > 0).

    Returns
    -------
    dict of arrays: ``cycles``, ``s``, ``scar_diameter`` (the mean of the ball's
    scar along and across the sliding, ``scar_length`` and ``scar_width``), ``ball_volume``,
    ``ball_formula``, ``ball_deviation`` (formula/true − 1), ``track_width``,
    ``track_depth``, ``flat_volume``, ``flat_formula``, ``flat_deviation``,
    ``flat_profilometer`` (pass length × the middle's cross-section),
    ``archard_ball``, ``archard_flat`` (K·F·s, force control only).
    """
    s = np.asarray(history["s"], dtype=float)
    rows = np.flatnonzero(s > 0) if rows is None else np.asarray(rows, dtype=int)
    R = case.indenter.radius
    sl = case.sliding
    get = {k: np.asarray(history[k], dtype=float)[rows] for k in
           ("s", "scar_length", "scar_width", "wear_volume", "wear_volume_counterface",
            "track_width", "track_depth", "track_area")}
    # an elongated scar is read as the mean of its two diameters
    D = 0.5 * (get["scar_length"] + get["scar_width"])
    w = get["track_width"]
    if sl.motion == "unidirectional":
        ball = cap_volume(D, R)
        flat = disc_volume(w, R, sl.track_radius)
    else:
        ball = lab_volume(D, R)
        flat = flat_volume(w, R, sl.stroke)
    Vb, Vf = get["wear_volume"], get["wear_volume_counterface"]
    with np.errstate(divide="ignore", invalid="ignore"):
        out = dict(cycles=np.asarray(history.get("cycles", np.full(len(s), np.nan)),
                                     float)[rows],
                   s=get["s"], scar_diameter=D, scar_length=get["scar_length"],
                   scar_width=get["scar_width"], ball_volume=Vb, ball_formula=ball,
                   ball_deviation=np.where(Vb > 0, ball / Vb - 1.0, np.nan),
                   track_width=w, track_depth=get["track_depth"], flat_volume=Vf,
                   flat_formula=flat,
                   flat_deviation=np.where(Vf > 0, flat / Vf - 1.0, np.nan),
                   flat_profilometer=both_bodies.pass_length(sl) * get["track_area"])
    if case.loading.control == "force":
        out["archard_ball"] = case.wear_rate * case.loading.force * get["s"]
        out["archard_flat"] = case.counterface_wear_rate * case.loading.force * get["s"]
    return out
