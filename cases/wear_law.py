"""The local wear law every solver integrates (docs/theory.md §4; issue 11 §4).

    dw/ds = K σ0 (p/σ0)^n,     K = k μ/σ0,

n = 1 is Reye–Archard (paper Eq. 1, gross slip): dw/ds = K p. Pure
functions of nodal (or pixel) pressures; the implicit schemes linearise the
law with :func:`slope`.
"""

from __future__ import annotations

import numpy as np


def speed(p, rate: float, exponent: float = 1.0, hardness: float = 1.0):
    """Wear speed dw/ds [m/m] at pressures p [Pa]; ``rate`` is K [1/Pa], ``hardness`` σ0 [Pa].

    Negative pressures (round-off outside a contact) wear nothing for n != 1.
    """
    if exponent == 1.0:
        return rate * p
    return rate * p * (np.maximum(p, 0.0) / hardness) ** (exponent - 1.0)


def slope(p, exponent: float = 1.0, hardness: float = 1.0):
    """d(dw/ds)/dp divided by K: n (p/σ0)^(n-1) (1 for n = 1)."""
    if exponent == 1.0:
        return np.ones_like(np.asarray(p, dtype=float))
    return exponent * (np.maximum(p, 0.0) / hardness) ** (exponent - 1.0)
