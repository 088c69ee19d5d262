"""The solver registry, public: ``from wearcheck.registry import Item, Solver, register``.

A solver outside wearcheck (a notebook, a third-party package) registers with
``register(Solver(name=..., title=..., module=... or solve_function=...,
history_columns=(Item(...), ...)))``, the entry a built-in solver keeps in its
package's ``registration.py``. See :mod:`wearcheck.comparisons.registry` for
what an entry declares.
"""

from wearcheck.comparisons.registry import (Item, Solver, get, lazy_attributes, names, register,
                                            solve, supporting, unregister)

__all__ = ["Item", "Solver", "register", "unregister", "get", "names", "supporting", "solve",
           "lazy_attributes"]
