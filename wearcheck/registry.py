"""The solver registry, public: ``from wearcheck.registry import Solver, register``.

See :mod:`wearcheck.comparisons.registry` for what an entry declares.
"""

from wearcheck.comparisons.registry import (Solver, get, names, register, solve, supporting,
                                            unregister)

__all__ = ["Solver", "register", "unregister", "get", "names", "supporting", "solve"]
