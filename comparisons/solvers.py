"""Dispatch a case to one of the independent solvers."""

from __future__ import annotations

from wearcheck.cases import Case, CaseError, RunResult

SOLVERS = ("mdr", "fem", "bem")


def solve(case: Case, solver: str, progress=None) -> RunResult:
    """Run ``solver`` ("mdr", "fem" or "bem") on ``case``."""
    if solver == "mdr":
        from wearcheck import mdr
        return mdr.solve(case, progress=progress)
    if solver == "fem":
        from wearcheck import fem
        return fem.solve(case, progress=progress)
    if solver == "bem":
        from wearcheck import bem
        return bem.solve(case, progress=progress)
    raise CaseError(f"solver '{solver}': must be one of " + ", ".join(SOLVERS))
