"""Both bodies wearing: the counterface's wear keys and the motion along its track.

A laboratory test wears the ball *and* the flat (ASTM G133, reciprocating
ball-on-flat) or the pin *and* the disc (ASTM G99). The counterface wears by
the same Reye–Archard law as the ball, with its own coefficient
K_flat = ``counterface.specific_rate`` (or ``counterface.k``·μ/``counterface.hardness``),
along the track the ball traces on it: a stroke of ``sliding.stroke``
(``sliding.motion = "reciprocating"``) or a circle of ``sliding.track_radius``
(``"unidirectional"``). The rules that tie these keys together are in the
rule table (``cases/rules.py``); here are the quantities derived from them.
"""

from __future__ import annotations

import math

MOTIONS = ("reciprocating", "unidirectional")


def cycle_length(sliding) -> float | None:
    """Sliding distance of one cycle [m]: 2·stroke (reciprocating), one revolution
    2π·track_radius (unidirectional); None when neither is given."""
    if sliding.motion == "unidirectional":
        return None if sliding.track_radius is None else 2.0 * math.pi * sliding.track_radius
    return None if sliding.stroke is None else 2.0 * sliding.stroke


def pass_length(sliding) -> float:
    """Sliding distance between two passes of the ball over one point of the track [m].

    Reciprocating: the stroke (each stroke passes every point of the track's
    middle once); unidirectional: the circumference 2π·track_radius.
    """
    if sliding.motion == "unidirectional":
        return 2.0 * math.pi * sliding.track_radius
    return sliding.stroke


def counterface_wear_rate(counterface, wear) -> float | None:
    """K_flat [m³/(N·m)] of a counterface that wears (``specific_rate``, or k·μ/hardness
    with μ = ``wear.mu``); None when it does not wear."""
    if not counterface.wears:
        return None
    if counterface.specific_rate is not None:
        return counterface.specific_rate
    return counterface.k * wear.mu / counterface.hardness
