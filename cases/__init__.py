"""The one case definition that every wearcheck solver and command reads.

``cases.load(path, overrides)`` returns a validated, frozen :class:`Case`.
The shipped cases (``hertz.toml``, ``truncated.toml``, ``paper.toml``) live
beside this file; :func:`shipped` returns the path of one, :func:`resolve` the
file a command line names (a path, or a shipped case's name).
"""

from .case import (Case, dundurs_beta, effective_moduli, from_dict, key_reference, load, to_dict,
                   to_toml)
from .errors import CaseError, RunWarning, SolverError, WearcheckError
from .result import HISTORY_COLUMNS, RunResult
from .catalog import describe, resolve, shipped, shipped_cases

__all__ = ["Case", "CaseError", "SolverError", "WearcheckError", "RunWarning", "RunResult",
           "HISTORY_COLUMNS", "load", "from_dict", "to_dict", "to_toml", "key_reference",
           "effective_moduli", "dundurs_beta", "shipped", "shipped_cases", "resolve", "describe"]

