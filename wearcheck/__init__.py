"""wearcheck: a verification suite for Reye–Archard wear of contacts.

Solvers (MDR, an axisymmetric FEM, ...) read one case definition and return
the same result; comparisons run them against each other and against closed
forms. The Python API in a few lines::

    import wearcheck
    case = wearcheck.load_case("paper", {"wear.mu": 0.5})   # shipped name or a path
    result = wearcheck.solve(case, "mdr", progress=True)
    F = result.history["force"] / result.scales["F0"]
    result.write("runs/mu-0.5")                              # a run directory
    wearcheck.compare(case, "runs/compare-mu-0.5")           # every solver, report

Public names: :func:`load_case`, :func:`shipped_cases`, :func:`solvers`,
:func:`solve`, :class:`Result`, :func:`read_run`, :func:`compare`,
:func:`refine`, :func:`sweep`, :func:`fit`, :func:`export_vtk`, :func:`reference` (a
certified reference solution), :func:`verify` (results produced elsewhere against it),
:class:`Case`,
:class:`CaseError`, :class:`SolverError`, and the solver registry
:mod:`wearcheck.registry` (``register``, ``Solver``). Everything else
(``wearcheck.mdr``, ``wearcheck.comparisons``, ``wearcheck.studies``, ``wearcheck.cli``,
...) is internal.
"""

import os as _os

# A checkout that is not installed (a clone, a notebook started at its root):
# pyproject's package-dir installs cases/ as wearcheck.cases, mdr/ as wearcheck.mdr
# and so on, so the repository root joins this package's search path and the same
# names resolve to the same folders. Only beside the checkout's pyproject.toml: an
# installed wearcheck's parent is site-packages, which must never join it.
_root = _os.path.dirname(_os.path.dirname(_os.path.abspath(__file__)))
if _os.path.isfile(_os.path.join(_root, "pyproject.toml")) \
        and _os.path.isfile(_os.path.join(_root, "cases", "__init__.py")) \
        and _root not in __path__:
    __path__.append(_root)
del _root

from wearcheck.cases import Case, CaseError, RunResult, SolverError, WearcheckError  # noqa: E402
from wearcheck import registry  # noqa: E402
from wearcheck.api import (Result, compare, export_vtk, fit, load_case, read_run,  # noqa: E402
                           reference, refine, shipped_cases, solve, solvers, sweep, verify)

try:
    from importlib.metadata import PackageNotFoundError, version
    __version__ = version("wearcheck")
except PackageNotFoundError:  # running from a checkout that was not installed
    __version__ = "unknown"

__all__ = ["Case", "CaseError", "SolverError", "WearcheckError", "RunResult", "Result",
           "load_case", "shipped_cases", "solvers", "solve", "read_run", "compare", "refine",
           "sweep", "fit", "export_vtk", "reference", "verify", "registry", "__version__"]
