"""wearcheck: verification suite for Reye–Archard wear of contacts."""

from wearcheck.cases import Case, CaseError, RunResult, SolverError, WearcheckError

__all__ = ["Case", "CaseError", "RunResult", "SolverError", "WearcheckError"]
