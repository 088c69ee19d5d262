"""The wear law every solver integrates (cases/wear_law.py)."""

import numpy as np
import pytest

from wearcheck.cases import wear_law


def test_reye_archard_and_the_power_law():
    p = np.array([0.0, 1e8, 2e9, 3e9])
    K, s0 = 1e-15, 2e9
    assert np.array_equal(wear_law.speed(p, K), K * p)
    # n = 2: K σ0 (p/σ0)² = K p²/σ0; equal to Reye–Archard at p = σ0
    assert wear_law.speed(p, K, 2.0, s0) == pytest.approx(K * p**2 / s0, rel=1e-15)
    assert wear_law.speed(np.array([s0]), K, 3.0, s0)[0] == pytest.approx(K * s0, rel=1e-15)
    # a negative round-off pressure wears nothing for n != 1
    assert wear_law.speed(np.array([-1.0]), K, 2.0, s0)[0] == 0.0


@pytest.mark.parametrize("n", [1.0, 1.5, 2.0, 4.0])
def test_the_slope_is_the_derivative(n):
    # against a central difference (relative step 1e-6: error ~1e-12 relative)
    p = np.linspace(0.2e9, 3e9, 7)
    K, s0 = 1e-15, 2e9
    dp = 1e-6 * p
    fd = (wear_law.speed(p + dp, K, n, s0) - wear_law.speed(p - dp, K, n, s0)) / (2 * dp)
    assert K * wear_law.slope(p, n, s0) == pytest.approx(fd, rel=1e-8)
