"""The solver registry: what wearcheck knows about each solver, asked by name.

A solver is a package that exports ``solve(case, progress=None) -> RunResult``
and ``supports(case) -> str | None`` (None when it can run the case, else the
reason it cannot). It describes itself in its own package, as meshio's formats
do: its ``registration.py`` holds ``SOLVER = Solver(...)`` with its case
section, resolution key, history columns and fields, and the registry registers
it. ``run``, ``compare``, ``refine``,
``sweep`` and the studies ask the registry and never name a solver. The
history columns every solver writes are declared once, ``cases.result.HISTORY``.

The built-in registrations (:data:`BUILT_IN`) are imported at the registry's
first use, not at ``import wearcheck``; they import no numerics (``module`` is
imported when the solver is used), so listing the solvers stays light and a
broken solver cannot break the others.

This module is public: a solver outside wearcheck (a notebook, a third-party
package) registers with ``register(Solver(name=..., title=..., module=... or
solve_function=..., history_columns=(Item(...), ...)))``, the entry a built-in
solver keeps in its package's ``registration.py``.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from wearcheck import extras
from wearcheck.cases import Case, CaseError, RunResult, SolverError
from wearcheck.cases.result import Item  # noqa: F401  (registrations import it from here)

__all__ = ["Item", "Solver", "register", "unregister", "get", "names", "supporting", "solve",
           "lazy_attributes"]


@dataclass(frozen=True)
class Solver:
    """One registered solver.

    Parameters
    ----------
    name : short name used on the command line and as a key in outputs ("mdr").
        The solve function is called as ``solve(case, progress=None)`` with
        ``progress(fraction, text)`` or None, and returns a ``RunResult``.
    title : name in figures and reports ("MDR").
    module : import path of the package with ``solve`` and ``supports``.
    section : its case section ("mdr"), whose keys only it reads.
    resolution_key : the case key its refinement studies vary ("mdr.elements").
    default_levels : resolutions of a default refinement study, coarsest first.
    resolution_label : the resolution in words, for figures ("N", "contact nodes").
    description : one line for ``wearcheck solvers`` and the help texts.
    style : matplotlib keyword arguments of its curves in comparison figures.
    export_vtk : "module:function" that writes ParaView files of the solver's own
        ``fields.npz``, ``function(directory, run, revolve=0) -> list[Path]`` (the
        .pvd files; ``run`` a ``rundir.Run``); None: the generic profile,
        pressure and surface series only.
    run_report : "module:function" that adds a report to its run directories,
        ``function(directory, case, result) -> list[Path]`` (it may write nothing).
    history_columns : its extra ``history.csv`` columns (beyond ``cases.result.HISTORY``),
        an :class:`Item` each.
    fields : its ``fields.npz`` arrays, an :class:`Item` each.
    solve_function, supports_function : for solvers that are not packages
        (tests, notebooks): callables used instead of ``module``.
    default : whether ``compare`` runs it when no solvers are named; False for
        an opt-in solver (ccx: an external program), which runs when named.
    """

    name: str
    title: str
    module: str | None = None
    section: str | None = None
    resolution_key: str | None = None
    default_levels: tuple[int, ...] = ()
    resolution_label: str = "resolution"
    description: str = ""
    style: dict = field(default_factory=dict)
    export_vtk: str | None = None
    run_report: str | None = None
    history_columns: tuple = ()
    fields: tuple = ()
    solve_function: Callable | None = None
    supports_function: Callable | None = None
    default: bool = True

    def _function(self, name: str):
        """The solver package's ``name`` (solve, supports; None if it has none),
        imported on first use."""
        try:
            return getattr(importlib.import_module(self.module), name, None)
        except ModuleNotFoundError as exc:
            # an optional module the solver needs (the FEM's scikit-fem): one line
            # naming the extra, which supports() gives as its reason
            found = extras.missing(f"the {self.title}", exc)
            if found is None:
                raise
            raise found from None

    def solve(self, case: Case, progress=None) -> RunResult:
        """Run this solver on ``case`` (refused with a CaseError when unsupported)."""
        fn = self.solve_function or self._function("solve")   # a missing extra said first
        reason = self.supports(case)
        if reason is not None:
            raise CaseError(f"solver '{self.name}' cannot run this case: {reason}")
        try:
            result = fn(case, progress=progress)
        except (ArithmeticError, np.linalg.LinAlgError) as exc:
            # a float overflow, a NaN in an integer, a factorisation or least-squares
            # solve that broke down: the numbers went out of range, a numerical
            # failure (exit 3) rather than a bug (exit 70)
            text = str(exc).splitlines()[0] if str(exc) else ""
            raise SolverError(f"solver '{self.name}': numerical failure ({type(exc).__name__}"
                              f"{': ' + text if text else ''}); the case's numbers (moduli, "
                              "load, wear keys) may lie outside what it can represent") \
                from exc
        if not isinstance(result, RunResult):
            raise TypeError(f"solver '{self.name}' returned {type(result).__name__}, "
                            "not a wearcheck RunResult")
        return result

    def supports(self, case: Case) -> str | None:
        """None when this solver can run ``case``, else the reason it cannot."""
        fn = self.supports_function
        if fn is None and self.module is not None:
            try:
                fn = self._function("supports")
            except extras.MissingExtra as exc:
                return str(exc)
        return fn(case) if fn is not None else None


def lazy_attributes(package: str, attributes: dict[str, str]) -> Callable:
    """A solver package's module ``__getattr__`` that imports on first use.

    ``attributes`` maps a name to the submodule that defines it (``{"solve":
    ".solver"}``); any other name is the package's submodule of that name. The
    registry imports the package for its ``registration.py``, so its
    ``__init__`` must not import its numerics; ``package.solve`` and
    ``package.model`` still work as if it did.
    """
    def __getattr__(name: str):
        if name in attributes:
            return getattr(importlib.import_module(attributes[name], package), name)
        try:
            return importlib.import_module(f".{name}", package)
        except ModuleNotFoundError as exc:
            if exc.name != f"{package}.{name}":
                raise  # the submodule exists and failed to import: say so
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
    return __getattr__


#: the registration modules of the solvers shipped with wearcheck, in the order
#: of ``names()``; each holds ``SOLVER``, registered at the registry's first use
BUILT_IN = ("wearcheck.mdr.registration", "wearcheck.fem.registration",
            "wearcheck.bem.registration", "wearcheck.ccx.registration")

_REGISTRY: dict[str, Solver] = {}
_loaded = False


def _load_built_in() -> None:
    """Register the built-in solvers, once, before anything else."""
    global _loaded
    if _loaded:
        return
    _loaded = True  # first: register() below comes back here
    for module in BUILT_IN:
        register(importlib.import_module(module).SOLVER)


def register(solver: Solver, *, replace: bool = False) -> Solver:
    """Add a solver to the registry; returns it.

    The name becomes a directory and a key in outputs: lower-case letters,
    digits, "_" and "-". ``section``, if given, must be a section declared in
    ``cases/schema.py`` (a solver defined in a notebook has none).
    """
    import re

    from wearcheck.cases.schema import SECTIONS
    if not re.fullmatch(r"[a-z][a-z0-9_-]*", solver.name or ""):
        raise ValueError(f"solver name '{solver.name}': use lower-case letters, digits, '_' "
                         "and '-', starting with a letter (it names directories and keys)")
    if solver.section is not None and solver.section not in SECTIONS:
        raise ValueError(f"solver '{solver.name}': section '{solver.section}' is not declared "
                         "in cases/schema.py (SECTIONS); a notebook solver has none")
    _load_built_in()
    if solver.name in _REGISTRY and not replace:
        raise ValueError(f"a solver named '{solver.name}' is registered already")
    if solver.module is None and solver.solve_function is None:
        raise ValueError(f"solver '{solver.name}': give module or solve_function")
    _REGISTRY[solver.name] = solver
    return solver


def unregister(name: str) -> None:
    """Remove a solver (tests and notebooks that registered their own)."""
    _load_built_in()
    _REGISTRY.pop(name, None)


def names() -> tuple[str, ...]:
    """Names of the registered solvers, in registration order."""
    _load_built_in()
    return tuple(_REGISTRY)


def get(name: str) -> Solver:
    """The registered solver ``name``; a CaseError naming the choices otherwise."""
    _load_built_in()
    try:
        return _REGISTRY[name]
    except KeyError:
        raise CaseError(f"solver '{name}': must be one of " + ", ".join(_REGISTRY)) from None


def supporting(case: Case) -> tuple[str, ...]:
    """Names of the solvers that can run ``case``."""
    _load_built_in()
    return tuple(n for n, s in _REGISTRY.items() if s.supports(case) is None)


def solve(case: Case, solver: str, progress=None) -> RunResult:
    """Run the registered solver named ``solver`` on ``case``."""
    return get(solver).solve(case, progress=progress)
