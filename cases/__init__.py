"""The one case definition that every wearcheck solver and command reads.

``cases.load(path, overrides)`` returns a validated, frozen :class:`Case`.
The shipped cases (``hertz.toml``, ``truncated.toml``, ``paper.toml``) live
beside this file; :func:`shipped` returns the path of one.
"""

from pathlib import Path

from .case import (Case, dundurs_beta, effective_moduli, from_dict, key_reference, load, to_dict,
                   to_toml)
from .errors import CaseError, SolverError, WearcheckError
from .result import HISTORY_COLUMNS, RunResult

__all__ = ["Case", "CaseError", "SolverError", "WearcheckError", "RunResult",
           "HISTORY_COLUMNS", "load", "from_dict", "to_dict", "to_toml", "key_reference",
           "effective_moduli", "dundurs_beta", "shipped"]


def shipped(name: str) -> Path:
    """Path of a shipped case file, e.g. ``shipped("paper")``."""
    path = Path(__file__).parent / f"{name.removesuffix('.toml')}.toml"
    if not path.is_file():
        raise CaseError(f"no shipped case '{name}'")
    return path
