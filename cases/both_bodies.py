"""Both bodies wearing: the counterface's wear keys and the motion along its track.

A laboratory test wears the ball *and* the flat (ASTM G133, reciprocating
ball-on-flat) or the pin *and* the disc (ASTM G99). The counterface wears by
the same Reye–Archard law as the ball, with its own coefficient
K_flat = ``counterface.specific_rate`` (or ``counterface.k``·μ/``counterface.hardness``),
along the track the ball traces on it: a stroke of ``sliding.stroke``
(``sliding.motion = "reciprocating"``) or a circle of ``sliding.track_radius``
(``"unidirectional"``). :func:`check` is the loader's check of these keys;
the rest are the quantities derived from them.
"""

from __future__ import annotations

import math

from .errors import CaseError

MOTIONS = ("reciprocating", "unidirectional")
_RATE_KEYS = ("specific_rate", "k", "hardness")


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


def check(built: dict) -> None:
    """The combinations of the counterface's wear keys and the motion (one-line CaseErrors)."""
    cf, sl = built["counterface"], built["sliding"]
    if not cf.wears:
        if built["bem"].track_model != "long_stroke":
            raise CaseError(f"key 'bem.track_model' = \"{built['bem'].track_model}\" applies "
                            "to a counterface that wears; set counterface.wears = true or "
                            "remove the key")
        for name in _RATE_KEYS:
            if getattr(cf, name) is not None:
                raise CaseError(f"key 'counterface.{name}' given but 'counterface.wears' = "
                                "false; set counterface.wears = true to wear the counterface "
                                "too, or remove the key")
    else:
        if built.get("fretting") is not None:
            raise CaseError("key 'counterface.wears' = true: the counterface wears along a "
                            "sliding track (sliding.motion), not in fretting; remove "
                            "[fretting] or set counterface.wears = false")
        given = [n for n in ("specific_rate", "k") if getattr(cf, n) is not None]
        if len(given) == 2:
            raise CaseError(f"keys 'counterface.specific_rate' = {cf.specific_rate!r} and "
                            f"'counterface.k' = {cf.k!r} both given; give one (K_flat = "
                            "k·wear.mu/counterface.hardness)")
        if not given:
            raise CaseError("missing key 'counterface.specific_rate' (m^3/(N m)) or "
                            "'counterface.k', required by counterface.wears = true")
        if cf.k is not None and cf.hardness is None:
            raise CaseError(f"key 'counterface.k' = {cf.k!r} needs 'counterface.hardness' "
                            "(Pa): K_flat = k·wear.mu/counterface.hardness")
        if sl.motion is None:
            raise CaseError("missing key 'sliding.motion' (\"reciprocating\" or "
                            "\"unidirectional\"), required by counterface.wears = true: the "
                            "counterface wears along the track the motion traces")
    if sl.motion is None:
        if sl.track_radius is not None:
            raise CaseError(f"key 'sliding.track_radius' = {sl.track_radius!r} needs "
                            "sliding.motion = \"unidirectional\" (a pin-on-disc track)")
        return
    if sl.motion == "reciprocating":
        if sl.track_radius is not None:
            raise CaseError(f"key 'sliding.track_radius' = {sl.track_radius!r} given but "
                            "sliding.motion = \"reciprocating\" (whose track is "
                            "sliding.stroke long); remove it or set sliding.motion = "
                            "\"unidirectional\"")
        if sl.stroke is None:
            raise CaseError("missing key 'sliding.stroke' (m, one way), required by "
                            "sliding.motion = \"reciprocating\"")
    else:
        if sl.stroke is not None:
            raise CaseError(f"key 'sliding.stroke' = {sl.stroke!r} given but sliding.motion = "
                            "\"unidirectional\" (a circular track of sliding.track_radius; a "
                            "cycle is one revolution); remove it or set sliding.motion = "
                            "\"reciprocating\"")
        if sl.track_radius is None:
            raise CaseError("missing key 'sliding.track_radius' (m), required by "
                            "sliding.motion = \"unidirectional\"")
