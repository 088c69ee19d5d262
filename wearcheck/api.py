"""The Python API of wearcheck: what the command line does, from a notebook.

Everything here is re-exported by ``wearcheck`` itself::

    import wearcheck
    case = wearcheck.load_case("paper", {"wear.mu": 0.5})
    result = wearcheck.solve(case, "mdr")
    result.history["force"][-1] / result.scales["F0"]

The command line is built on the same functions, so the two cannot drift apart.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
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
    loaded = case if isinstance(case, Case) else cases.load(cases.resolve(case))
    return loaded.derive(changes) if changes else loaded


def shipped_cases() -> dict[str, Path]:
    """The cases shipped with wearcheck: {name: path} (``wearcheck cases`` describes them)."""
    return cases.shipped_cases()


# -- solving -----------------------------------------------------------------

def solvers(case: Case | None = None) -> tuple[str, ...]:
    """Names of the registered solvers (that support ``case``, if given)."""
    return registry.supporting(case) if case is not None else registry.names()


@dataclass(repr=False)
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
    warnings : remarks on the case and the run (e.g. stages the run did not reach).
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
    warnings: list = field(default_factory=list)
    _run: RunResult | None = field(default=None, repr=False)

    def __repr__(self) -> str:
        h = self.history
        steps = len(h["s"]) - 1
        end = h["force"][-1] / self.scales["F0"] if steps >= 0 else float("nan")
        where = f", path='{self.path}'" if self.path else ""
        return (f"Result(solver='{self.solver}', case='{Path(self.case.source).name}', "
                f"steps={steps}, stages={len(self.stages['s'])}, F/F0 at the end={end:.4g}, "
                f"solve_seconds={self.solve_seconds:.3g}{where})")

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
    """A solver's progress callable (fraction, text) from None, True/False or a
    user's callable of the fraction alone."""
    if callable(progress):
        return (lambda fraction, text="": progress(fraction)), None
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
    progress : True for a progress bar with an ETA (a widget in Jupyter), or a
        callable ``progress(fraction)`` receiving the fraction done in [0, 1].

    Raises
    ------
    CaseError
        bad input, or a solver that does not support the case.
    SolverError
        the run failed numerically (never returned as a result).
    """
    case = load_case(case)
    registry.get(solver)  # an unknown name fails before any work
    call, bar = _progress(progress, solver)
    try:
        run = registry.solve(case, solver, progress=call)
    finally:
        if bar is not None:
            bar.close()
    notes = list(case.warnings) + list(run.info.get("warnings", []))  # (the run's: warned)
    missing = list(case.stages.s_hat)[len(run.stage_s):]
    if missing:
        text = ("the run ended before the stages at ŝ = " + ", ".join(f"{s:g}" for s in missing)
                + f" ({_end_reason(case)}); they are not in result.stages")
        notes.append(text)
        warnings.warn(text, stacklevel=2)
    stages = dict(s=np.asarray(run.stage_s, float),
                  s_hat=np.asarray(run.stage_s, float) * reference.scales(case)["s_hat_per_m"],
                  r=np.asarray(run.r, float), f=np.asarray(run.f, float),
                  p=np.asarray(run.p, float))
    return Result(case=case, solver=solver, history=dict(run.history), stages=stages,
                  fields=run.fields, info=dict(run.info), solve_seconds=run.solve_seconds,
                  warnings=notes, _run=run)


def _end_reason(case) -> str:
    sl = case.sliding
    if sl.until == "force_fraction":
        return f"it stops once F < {sl.force_fraction:g} F0"
    if sl.until == "distance":
        return f"it stops at s = {sl.distance:g} m"
    return f"it stops at its {sl.until}"


def read_run(path: str | Path) -> Result:
    """A run directory written by ``wearcheck run``, ``compare``, ``refine`` or ``sweep``."""
    if not Path(path).exists():
        raise CaseError(f"run directory '{path}' does not exist")
    run = rundir.Run(path)
    return Result(case=run.case, solver=run.solver, history=run.history, stages=run.stages,
                  fields=run.fields, info=run.meta.get("info", {}),
                  solve_seconds=run.meta.get("solve_seconds", float("nan")), path=run.path,
                  meta=run.meta, warnings=list(run.meta.get("warnings", [])))


# -- studies -----------------------------------------------------------------

def compare(case: str | Path | Case, out: str | Path, *, solvers: Iterable[str] | None = None,
            reference_solver: str | None = None, edge_study: bool = False,
            sphere_sweep: bool = False, render: bool = True, quiet: bool = True) -> dict:
    """Run every solver that supports the case (or ``solvers``), compare each with
    the reference (default MDR, or the first exact solver where the MDR solved an
    approximation of the case), write figures, metrics and a report into ``out``.

    Returns the metrics as in ``metrics.json``; ``["passed"]`` is the verdict.
    """
    from wearcheck.comparisons.studies.compare import compare as _compare
    if isinstance(solvers, str):
        # "mdr,fem" as on the command line (--solvers)
        solvers = [name.strip() for name in solvers.split(",") if name.strip()] or [solvers]
    elif solvers is not None:
        solvers = list(solvers)
        if not solvers:
            raise CaseError("solvers = []: name at least two solvers, or None for every "
                            "solver that supports the case")
    return _compare(load_case(case), out, solvers=solvers,
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
    levels = None if levels is None else [_plain(v) for v in _listed(levels, "levels")]
    steps = None if steps is None else [_plain(v) for v in _listed(steps, "steps")]
    return _refine(case, (), solver, out, levels=levels, steps=steps, tolerance=tolerance,
                   scheduler=scheduler, workers=workers, quiet=quiet, case=case)


def sweep(case: str | Path | Case, vary: Mapping[str, Iterable], out: str | Path,
          solver: str = "mdr", *, scheduler: str | None = None, workers: int | None = None,
          quiet: bool = True) -> list[dict]:
    """One run per combination of values on Dask: ``vary={"wear.mu": [0.2, 0.3]}``.

    Returns the rows of ``sweep.csv`` (final ŝ, F/F0, wear depth, status per run).
    """
    from wearcheck.comparisons.studies.sweep import sweep as _sweep
    case = load_case(case)
    registry.get(solver)
    if isinstance(vary, str):
        vary = [vary]
    if not isinstance(vary, Mapping):
        # "wear.mu=0.2,0.3" as on the command line (--vary), or a list of such
        from wearcheck.comparisons.studies.sweep import parse_vary
        try:
            vary = dict(parse_vary(text) for text in vary)
        except TypeError:
            raise CaseError(f"vary = {vary!r}: give a mapping such as {{\"wear.mu\": [0.2, "
                            "0.3]}, or \"section.key=v1,v2\" strings") from None
        vary = {k: [_parsed(k, v) for v in vals] for k, vals in vary.items()}
    if not vary:
        raise CaseError("vary is empty: name at least one key and its values, e.g. "
                        "{\"wear.mu\": [0.2, 0.3]}")
    values = {}
    for key, vals in vary.items():
        if isinstance(vals, (str, bytes)) or np.ndim(vals) == 0:
            vals = [vals]  # one value, not a sequence of characters
        values[key] = [_plain(v) for v in vals]
        if not values[key]:
            raise CaseError(f"vary '{key}': no values")
        # a value its key can never take fails before any run, in the study's own
        # check (as --vary: a value is judged with the other keys' values)
    texts = [f"{key}=" + ",".join(_toml_value(v) for v in vals) for key, vals in values.items()]
    rows = _sweep(case, (), texts, solver, out, scheduler=scheduler, workers=workers,
                  quiet=quiet, case=case)
    for row in rows:  # the values as given, not as text
        for key, vals in values.items():
            text = row.get(key)
            match = [v for v in vals if _toml_value(v) == text]
            if match:
                row[key] = match[0]
    return rows


def _listed(values, name: str) -> list:
    """Levels or steps as a sequence, or as the command line writes them: "50,100"."""
    if isinstance(values, str):
        try:
            return [float(v) if any(c in v for c in ".eE") else int(v)
                    for v in values.split(",") if v.strip()]
        except ValueError:
            raise CaseError(f"{name} = {values!r}: give numbers, e.g. [50, 100] or "
                            "\"50,100\"") from None
    return list(np.ravel(values))


def _parsed(key: str, text: str):
    """A --vary value as TOML reads it, a bare word as itself (as --set does)."""
    from wearcheck.cases.case import parse_override
    return parse_override(f"{key}={text}")[2]


def _plain(v):
    """numpy scalars and arrays as Python numbers and lists."""
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    return v


def _toml_value(v) -> str:
    import json
    if isinstance(v, str):
        return json.dumps(v)  # a TOML basic string
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
