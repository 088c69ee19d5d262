"""Which optional extra installs each optional module, and the one-line message
when one is missing.

The core install (``pip install wearcheck``: numpy, scipy, threadpoolctl, tqdm)
runs the MDR and the BEM. Everything else is an extra of ``pyproject.toml``;
:data:`MODULES` is the one place that says which (tests/test_extras.py checks
it against pyproject.toml). A part of wearcheck that needs an optional module
imports it through :func:`need`; a module missing deeper down (a solver
package's import) is named by :func:`missing`.
"""

from __future__ import annotations

import importlib

from wearcheck.cases.errors import WearcheckError

#: import name -> (distribution on PyPI, extra of pyproject.toml that installs it)
MODULES = {
    "skfem": ("scikit-fem", "fem"),
    "gmsh": ("gmsh", "fem"),
    "pyvista": ("pyvista", "vtk"),
    "meshio": ("meshio", "vtk"),        # wearcheck verify reading .pvd/.vtu series
    "vtk": ("vtk", "vtk"),              # pyvista's own dependency
    "dask": ("dask", "dask"),
    "distributed": ("distributed", "dask"),
    "matplotlib": ("matplotlib", "plot"),
    "pandas": ("pandas", "xarray"),
    "xarray": ("xarray", "xarray"),
    "ipywidgets": ("ipywidgets", "notebook"),
    "pyfftw": ("pyfftw", "fftw"),
    "psutil": ("psutil", "dask"),       # distributed's; a study's memory watch uses it
}


class MissingExtra(WearcheckError, ModuleNotFoundError):
    """An optional module is not installed; the message names the extra that installs it.

    A :class:`ModuleNotFoundError` too, so ``except ImportError`` still catches it;
    the command line prints it as one line and exits 2 (as for bad input: the
    command cannot run as installed).
    """

    exit_code = 2


def message(what: str, module: str) -> str:
    """``the FEM needs scikit-fem: pip install "wearcheck[fem]"``."""
    distribution, extra = MODULES[module.split(".")[0]]
    return f"{what} needs {distribution}: pip install \"wearcheck[{extra}]\""


def missing(what: str, exc: BaseException) -> MissingExtra | None:
    """The :class:`MissingExtra` for ``exc`` if it is an optional module that is not
    installed (``exc.name`` in :data:`MODULES`), else None (a real error)."""
    if isinstance(exc, MissingExtra):
        return exc
    name = getattr(exc, "name", None) or ""
    if not isinstance(exc, ModuleNotFoundError) or name.split(".")[0] not in MODULES:
        return None
    return MissingExtra(message(what, name), name=name)


def need(module: str, what: str):
    """``module`` imported, or a :class:`MissingExtra` saying that ``what`` needs it
    and which extra to install."""
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as exc:
        found = missing(what, exc)
        if found is None:
            raise
        raise found from None
