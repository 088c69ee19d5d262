"""Whether the MDR grid resolves the unworn contact, checked before a run.

The grid has N cells uniform in t = r² on 0 <= r <= L, L = mdr.domain_factor·√2·a0,
so the unworn contact holds N a0²/L² = N/(2·domain_factor²) of them. Below
:data:`MIN_CONTACT_CELLS` the run is refused (docs/limits.md): with fewer
cells the history of F/F0 (depth control) or d/d0 (force control) errs by
more than 1 % somewhere on sphere, cone, truncated paraboloid, power law and
ball-on-flat runs (benchmarks/bench_mdr_resolution.py), where the FEM and
BEM refuse as well (fem.contact_nodes, bem.grid); with 2 cells the paper
case gave F(0)/F0 = 1.25 and F/F0 = 0.47 at ŝ = 3 (0.279) with exit 0.
"""

from __future__ import annotations

import math

from wearcheck.cases import CaseError
from wearcheck.cases.schema import MDRSettings

#: fewest grid cells (in t = r²) inside the unworn contact radius a0
MIN_CONTACT_CELLS = 10
#: fewest elements: a grid that grows (its contact past mdr.solver.GROW_AT =
#: 0.8 of the nodes) keeps every other node, 0.4 N cells in the contact
MIN_ELEMENTS = math.ceil(MIN_CONTACT_CELLS / 0.4)
#: a refusal proposes mdr.elements only up to this (a finer grid is no
#: practical remedy); past it, it proposes mdr.domain_factor alone
MAX_PROPOSED_ELEMENTS = 10_000_000
#: mdr.domain_factor's default
DEFAULT_FACTOR = MDRSettings().domain_factor


def contact_cells(elements: int, domain_factor: float) -> float:
    """Grid cells inside the unworn contact: N a0²/L² = N/(2·domain_factor²)."""
    return elements / (2.0 * domain_factor**2)


def check(case) -> None:
    """CaseError unless ``mdr.elements`` and ``mdr.domain_factor`` resolve the unworn contact."""
    N, factor = case.mdr.elements, case.mdr.domain_factor
    cells = contact_cells(N, factor)
    if cells >= MIN_CONTACT_CELLS and N >= MIN_ELEMENTS:
        return
    need = max(math.ceil(MIN_CONTACT_CELLS * 2.0 * factor**2 * (1.0 - 1e-12)), MIN_ELEMENTS)
    widest = math.sqrt(N / (2.0 * MIN_CONTACT_CELLS))
    remedies = []
    if need <= MAX_PROPOSED_ELEMENTS:
        remedies.append(f"mdr.elements >= {need}")
    if widest > 1.0 and N >= MIN_ELEMENTS:
        remedies.append(f"mdr.domain_factor <= {math.floor(widest * 1000) / 1000:g}")
    if not remedies:   # both far off: the defaults' way
        remedies.append(f"mdr.domain_factor = {DEFAULT_FACTOR:g} with mdr.elements >= "
                        f"{math.ceil(MIN_CONTACT_CELLS * 2.0 * DEFAULT_FACTOR**2)}")
    # name the key the user moved from its default first
    if factor > DEFAULT_FACTOR and len(remedies) == 2:
        remedies.reverse()
    key, value = (("mdr.domain_factor", factor) if remedies[0].startswith("mdr.domain")
                  else ("mdr.elements", N))
    if cells >= MIN_CONTACT_CELLS:
        why = (f"a grid of {N} elements keeps fewer than {MIN_CONTACT_CELLS} cells in the "
               "contact once its domain grows")
    else:
        why = (f"the unworn contact spans {cells:.3g} cells of the MDR grid (N/(2·"
               f"mdr.domain_factor²) with mdr.elements = {N}, mdr.domain_factor = {factor:g}); "
               f"at least {MIN_CONTACT_CELLS} are needed, below which F/F0 (d/d0 under force "
               "control) errs by more than 1 % (docs/limits.md)")
    raise CaseError(f"key '{key}' = {value!r}: {why}; use " + " or ".join(remedies))
