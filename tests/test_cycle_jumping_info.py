"""The counts of ``info["cycle_jumping"]`` (meta.json) hold what their names say,
counted here from the calls the integrator makes to the problem, not from its own
counters; ``stage_cycles`` is the key of the stored stages' cycle numbers only (the
case key ``fretting.stage_cycles``, ``info.stage_cycles``), not of a count."""

import numpy as np

from wearcheck.numerics import cycle_jumping as cj


class CountedDecay(cj.Problem):
    """y_{n+1} = y_n + κ (1 − y_n): a linear approach to y = 1, with every cycle the
    integrator asks for counted (``probe``: a second-stage cycle of ROS2) and the
    first ``refuse`` steps refused by :meth:`admissible` (their check cycles are
    simulated and not kept)."""

    kappa = 1e-2

    def __init__(self, refuse=0):
        self.calls = {True: 0, False: 0}
        self.refuse = refuse

    def cycle(self, state, n, probe=False):
        self.calls[bool(probe)] += 1
        rate = np.array([self.kappa * (1.0 - state[0])])
        return cj.Cycle(state=state + rate, rate=rate)

    def advance(self, state, increment, cycles, cycle):
        return state + increment

    def variable(self, state):
        return state

    def admissible(self, before, after):
        if self.refuse:
            self.refuse -= 1
            return False
        return True

    def jacobian(self, cycle):
        return np.array([0]), np.array([[-self.kappa]])


def test_each_count_is_the_cycles_its_name_says():
    for refuse in (0, 3):
        problem = CountedDecay(refuse=refuse)
        kept = []
        out = cj.run(problem, np.array([0.0]), cj.Plan(cycles=5000, tolerance=1e-2),
                     lambda cyc, n: kept.append(n))
        info = out.info()
        assert "stage_cycles" not in info     # (a count named like the stages' cycle list)
        assert info["second_stage_cycles"] == problem.calls[True] > 0
        assert info["simulated_cycles"] == problem.calls[True] + problem.calls[False]
        assert info["recorded_cycles"] == len(kept)
        # one second-stage cycle per step tried; every simulated cycle is one of
        # three kinds: kept, second stage, the end of a step rejected (by its error
        # or, inadmissible_steps of them, by the problem)
        assert info["second_stage_cycles"] == info["steps"] + info["rejected_steps"]
        assert info["inadmissible_steps"] == refuse <= info["rejected_steps"]
        assert info["simulated_cycles"] == (info["recorded_cycles"]
                                            + info["second_stage_cycles"]
                                            + info["rejected_steps"])
        assert info["largest_step"] == max(np.diff([0] + kept))   # cycles between kept rows
