"""MDR solver of gross-slip Reye–Archard wear (paper Sections 2 and 4).

``solve(case)`` runs a case; :mod:`mdr.transforms` holds the MDR transforms
(paper Eqs. 2, 3, 12, 13) as pure functions, :mod:`mdr.contact` the normal
contact, :mod:`mdr.wear` the explicit and implicit wear steps.
"""

from .solver import solve

__all__ = ["solve"]
