"""The fretting run's progress bar follows its cost, not its cycle count.

Review finding: with cycle jumping a run to 10⁸ cycles stood at 0.0 % of the bar for
most of its time (the cost grows with the logarithm of the cycle count,
docs/performance.md "The cost in the cycle count"), and the ETA was meaningless.
The bar now advances in log(1 + n) when cycles are jumped, in n when every cycle
is simulated (then the cost is proportional to n).
"""

import math
import time

import numpy as np

from wearcheck import mdr

from test_fretting_mdr import make


def _reports(case):
    seen = []
    mdr.solve(case, progress=lambda fraction, text="": seen.append(
        (fraction, text, time.process_time())))
    return seen


def _cycle(text):
    return int(text.split()[1])          # "cycle N of M"


def test_the_bar_advances_in_the_logarithm_of_the_cycles_when_jumping():
    cycles = 20000
    case, _, _ = make(N=100, amplitude=0.5, cycles=cycles, k=0.3, jump_tolerance=0.05,
                      increments=20, stage_cycles=[0, cycles])
    seen = _reports(case)
    fractions = [f for f, _, _ in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    reported = [(f, _cycle(t)) for f, t, _ in seen if t.startswith("cycle")]
    assert all(t.endswith(f"of {cycles}") for _, t, _ in seen if t.startswith("cycle"))
    for f, n in reported:
        assert f == math.log1p(n) / math.log1p(cycles)
    # the point of it: the bar is not stuck near 0 for most of the run. Against
    # CPU time the bar's fraction is within a factor of ~2.5 of the time's
    # fraction once a tenth of the time has passed (linear in n it was < 0.05
    # there: the first tenth of the cycles is reached near the run's end).
    t0, t1 = seen[0][2], seen[-1][2]
    for f, _, t in seen:
        share = (t - t0) / (t1 - t0)
        if 0.1 <= share <= 0.9:
            assert f > share / 2.5, (f, share)


def test_the_bar_is_linear_when_every_cycle_is_simulated():
    cycles = 60
    case, _, _ = make(N=60, amplitude=0.5, cycles=cycles, k=0.3, jump_tolerance=0.0,
                      increments=20, stage_cycles=[0, cycles])
    seen = [(f, _cycle(t)) for f, t, _ in _reports(case) if t.startswith("cycle")]
    assert len(seen) >= 20
    for f, n in seen:
        assert f == n / cycles
