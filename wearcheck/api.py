"""The Python API of wearcheck: what the command line does, from a notebook.

Everything here is re-exported by ``wearcheck`` itself::

    import wearcheck
    case = wearcheck.load_case("paper", {"wear.mu": 0.5})
    result = wearcheck.solve(case, "mdr")
    result.history["force"][-1] / result.scales["F0"]

The command line is built on the same functions, so the two cannot drift apart.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Mapping

import numpy as np

from wearcheck import cases
from wearcheck.cases import Case, CaseError, RunResult, reference
from wearcheck.comparisons import registry, rundir

__all__ = ["load_case", "shipped_cases", "solvers", "solve", "Result", "read_run", "compare",
           "refine", "sweep", "export_vtk"]


# -- cases -------------------------------------------------------------------

def load_case(case: str | Path | Case, changes: Mapping | Iterable[str] | None = None) -> Case:
    """Load a case file, or a shipped case by name, and apply changes.

    Parameters
    ----------
    case : a path to a TOML case file, the name of a shipped case (``"paper"``,
        see :func:`shipped_cases`), or a :class:`Case` to derive from.
    changes : ``{"wear.mu": 0.5}`` or ``["wear.mu=0.5"]``: keys to change,
        validated like the file (see :meth:`Case.derive`).

    Raises
    ------
    CaseError
        one message naming the key, the value and what is allowed.
    """
    if isinstance(case, Case):
        loaded = case
    else:
        path = Path(case)
        if not path.exists() and path.suffix == "" and path.name == str(case):
            try:
                path = cases.shipped(str(case))
            except CaseError:
                raise CaseError(f"case '{case}' is neither a file nor a shipped case; shipped: "
                                + ", ".join(shipped_cases())) from None
        loaded = cases.load(path)
    return loaded.derive(changes) if changes else loaded


def shipped_cases() -> dict[str, Path]:
    """The cases shipped with wearcheck: {name: path}."""
    folder = Path(cases.__file__).parent
    return {p.stem: p for p in sorted(folder.glob("*.toml"))}


# -- solving -----------------------------------------------------------------

def solvers(case: Case | None = None) -> tuple[str, ...]:
    """Names of the registered solvers (that support ``case``, if given)."""
    return registry.supporting(case) if case is not None else registry.names()


@dataclass
class Result:
    """One solver's run of one case, fresh from :func:`solve` or read by :func:`read_run`.

    Attributes
    ----------
    case : the resolved case.
    solver : the solver's registry name.
    history : dict of 1D arrays, one value per step (SI units; columns as in
        ``history.csv``, see :data:`rundir.HISTORY`).
    stages : dict with ``s`` and ``s_hat`` (K,), ``r`` (M,), ``f`` and ``p`` (K, M):
        sliding distance, radii, worn profile and pressure at the stored stages.
    fields : the solver's own arrays (FEM: mesh, displacement, stress), or None.
    info : what the solver reports about its run (steps, step size, grid, ...).
    solve_seconds : time in the solver proper.
    path : the run directory, once written or when read from one.
    meta : its meta.json (provenance, scales, data dictionary), when read from one.
    """

    case: Case
    solver: str
    history: dict
    stages: dict
    fields: dict | None
    info: dict
    solve_seconds: float
    path: Path | None = None
    meta: dict | None = None
    _run: RunResult | None = None

    @property
    def scales(self) -> dict:
        """E*, G*, a0, d0, F0, p0 of the unworn contact and ŝ per metre of sliding."""
        return reference.scales(self.case)

    def history_frame(self):
        """The history as a pandas DataFrame (needs pandas)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("history_frame() needs pandas: pip install pandas") from None
        return pd.DataFrame({k: np.asarray(v) for k, v in self.history.items()})

    def write(self, out: str | Path) -> Path:
        """Write the run directory ``out`` atomically (as ``wearcheck run`` does)."""
        if self._run is None:
            raise CaseError("this result was read from a run directory; it is written already "
                            f"at {self.path}")
        self.path = rundir.write_run(out, self.case, self._run, self.solver)
        return self.path

    def export_vtk(self, revolve: int = 0) -> Path:
        """ParaView files into ``<run directory>/vtk`` (write the run first)."""
        if self.path is None:
            raise CaseError("write the run directory first: result.write(path)")
        return export_vtk(self.path, revolve=revolve)


def _progress(progress, label):
    """A progress callable from None, True/False or a callable."""
    if callable(progress):
        return progress, None
    if progress:
        from wearcheck.comparisons.present.progress import ProgressBar
        bar = ProgressBar(label)
        return bar, bar
    return None, None


def solve(case: str | Path | Case, solver: str = "mdr", *,
          progress: bool | Callable[[float], None] | None = None) -> Result:
    """Run one solver on a case.

    Parameters
    ----------
    case : a :class:`Case`, a case file or a shipped case's name.
    solver : a registered solver's name (see :func:`solvers`).
    progress : True for a progress bar (a widget in Jupyter), or a callable
        receiving the fraction done in [0, 1].

    Raises
    ------
    CaseError
        bad input, or a solver that does not support the case.
    SolverError
        the run failed numerically (never returned as a result).
    """
    case = load_case(case)
    call, bar = _progress(progress, solver)
    try:
        run = registry.solve(case, solver, progress=call)
    finally:
        if bar is not None:
            bar.close()
    stages = dict(s=np.asarray(run.stage_s, float),
                  s_hat=np.asarray(run.stage_s, float) * reference.scales(case)["s_hat_per_m"],
                  r=np.asarray(run.r, float), f=np.asarray(run.f, float),
                  p=np.asarray(run.p, float))
    return Result(case=case, solver=solver, history=dict(run.history), stages=stages,
                  fields=run.fields, info=dict(run.info), solve_seconds=run.solve_seconds,
                  _run=run)


def read_run(path: str | Path) -> Result:
    """A run directory written by ``wearcheck run``, ``compare``, ``refine`` or ``sweep``."""
    run = rundir.Run(path)
    return Result(case=run.case, solver=run.solver, history=run.history, stages=run.stages,
                  fields=run.fields, info=run.meta.get("info", {}),
                  solve_seconds=run.meta.get("solve_seconds", float("nan")), path=run.path,
                  meta=run.meta)


# -- studies -----------------------------------------------------------------

def compare(case: str | Path | Case, out: str | Path, *, solvers: Iterable[str] | None = None,
            reference_solver: str | None = None, edge_study: bool = False,
            sphere_sweep: bool = False, render: bool = True, quiet: bool = True) -> dict:
    """Run every solver that supports the case (or ``solvers``), compare each with
    the reference (default MDR), write figures, metrics and a report into ``out``.

    Returns the metrics as in ``metrics.json``; ``["passed"]`` is the verdict.
    """
    from wearcheck.comparisons.studies.compare import compare as _compare
    return _compare(load_case(case), out, solvers=list(solvers) if solvers else None,
                    reference_solver=reference_solver, edge=edge_study, sphere=sphere_sweep,
                    render=render, quiet=quiet)


def refine(case: str | Path | Case, out: str | Path, solver: str = "mdr", *,
           levels: Iterable[int] | None = None, steps: Iterable[float] | None = None,
           tolerance: float = 0.01, scheduler: str | None = None, workers: int | None = None,
           quiet: bool = True) -> dict:
    """A refinement study on Dask (paper Fig. 4): returns its summary (observed orders,
    Richardson's estimate, coarsest converged level); run directories go to ``out``."""
    from wearcheck.comparisons.studies.refine import refine as _refine
    case = load_case(case)
    return _refine(case, (), solver, out, levels=list(levels) if levels else None,
                   steps=list(steps) if steps else None, tolerance=tolerance,
                   scheduler=scheduler, workers=workers, quiet=quiet, case=case)


def sweep(case: str | Path | Case, vary: Mapping[str, Iterable], out: str | Path,
          solver: str = "mdr", *, scheduler: str | None = None, workers: int | None = None,
          quiet: bool = True) -> list[dict]:
    """One run per combination of values on Dask: ``vary={"wear.mu": [0.2, 0.3]}``.

    Returns the rows of ``sweep.csv`` (final ŝ, F/F0, wear depth, status per run).
    """
    from wearcheck.comparisons.studies.sweep import sweep as _sweep
    case = load_case(case)
    texts = [f"{key}=" + ",".join(_toml_value(v) for v in values)
             for key, values in vary.items()]
    return _sweep(case, (), texts, solver, out, scheduler=scheduler, workers=workers,
                  quiet=quiet, case=case)


def _toml_value(v) -> str:
    if isinstance(v, str):
        return v
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(float(v)) if isinstance(v, float) else str(v)


def export_vtk(run_dir: str | Path, revolve: int = 0) -> Path:
    """ParaView files (``.pvd`` series of ``.vtu``) of a run directory into ``RUN_DIR/vtk``.

    ``revolve`` N >= 3 also writes the FEM fields revolved into a 3D solid.
    """
    from wearcheck.comparisons.present.vtk import export_run
    return export_run(run_dir, revolve=revolve)
