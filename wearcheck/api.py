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
from wearcheck.cases import ArgumentError, Case, CaseError, RunResult
from wearcheck.cases import reference as closed_forms
from wearcheck import registry, rundir
from wearcheck.comparisons.present import frames
from wearcheck.comparisons.present.progress import ProgressBar
from wearcheck.references import certified
from wearcheck.external import parse_mapping
from wearcheck.comparisons.present.vtk import export_run

__all__ = ["load_case", "shipped_cases", "solvers", "solve", "Result", "read_run", "compare",
           "refine", "sweep", "fit", "export_vtk", "reference", "verify"]


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
    solve_seconds : wall-clock time in the solver proper.
    path : the run directory, once written or when read from one.
    meta : its meta.json (provenance, scales, data dictionary), when read from one;
        for a certified reference (:func:`reference`), how it was made.
    warnings : remarks on the case and the run (e.g. stages the run did not reach).
    certified : for a certified reference, the reference itself: its history and
        stages at any distance (``history_at(s)``, ``stage_at(s, r)``) and its error
        band (``band_at(s)``, ``band_table()``); else None.
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
    certified: object | None = field(default=None, repr=False)
    _run: RunResult | None = field(default=None, repr=False)

    def __repr__(self) -> str:
        h = self.history
        steps = len(h["s"]) - 1
        end = h["force"][-1] / self.scales["F0"] if steps >= 0 else float("nan")
        where = f", path='{self.path}'" if self.path else ""
        return (f"Result(solver='{self.solver}', case='{Path(self.case.source).name}', "
                f"steps={steps}, stages={len(self.stages['s'])}, F/F0 at the end={end:.4g}, "
                f"solve_seconds={self.solve_seconds:.3g}{where})")

    def _repr_html_(self) -> str:
        """Scales, stages reached and the final values, as tables in Jupyter."""
        import html
        sc, h = self.scales, self.history
        units = dict(a0="m", d0="m", F0="N", p0="Pa", E_star="Pa", G_star="Pa",
                     s_hat_per_m="1/m")

        def table(caption, rows):
            body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r)
                           + "</tr>" for r in rows)
            return (f"<table><caption style='text-align:left'>{caption}</caption>{body}"
                    "</table>")

        hu = frames.dictionary(self)["history_csv"]
        end = [(k, f"{float(np.asarray(v)[-1]):.6g}", hu.get(k, {}).get("unit", ""))
               for k, v in h.items() if np.size(v)]
        parts = [f"<details open><summary><b>Result</b> {html.escape(self.solver)}, "
                 f"{html.escape(Path(self.case.source).name)}</summary>",
                 table("scales of the unworn contact",
                       [(k, f"{v:.6g}", units.get(k, "")) for k, v in sc.items()]),
                 table(f"{len(self.stages['s'])} of {len(self.case.stages.s_hat)} stages "
                       "reached", [("ŝ", ", ".join(f"{v:.3g}" for v in self.stages["s_hat"]))]),
                 table(f"at the end ({len(h['s']) - 1} steps, "
                       f"{self.solve_seconds:.3g} s)", end)]
        if self.warnings:
            parts.append("<p>" + "<br>".join(html.escape(str(w)) for w in self.warnings)
                         + "</p>")
        if self.path:
            parts.append(f"<p>run directory: <code>{html.escape(str(self.path))}</code></p>")
        return "".join(parts) + "</details>"

    @property
    def scales(self) -> dict:
        """E*, G*, a0, d0, F0, p0 of the unworn contact and ŝ per metre of sliding."""
        return closed_forms.scales(self.case)

    def history_frame(self):
        """The history as a pandas DataFrame indexed by the sliding distance s [m];
        ``attrs`` holds each column's unit and meaning, the solver and the scales
        (needs pandas: ``pip install "wearcheck[xarray]"``)."""
        return frames.history_frame(self)

    def to_xarray(self):
        """History and stages as an xarray Dataset with units, meanings and provenance
        as attributes (needs xarray: ``pip install "wearcheck[xarray]"``)."""
        return frames.to_xarray(self)

    def to_netcdf(self, path: str | Path) -> Path:
        """Write :meth:`to_xarray` as a netCDF file (atomically; never over a file that
        is not a wearcheck netCDF file)."""
        return frames.write_netcdf(self, path)

    def write(self, out: str | Path) -> Path:
        """Write the run directory ``out`` atomically (as ``wearcheck run`` does)."""
        if self._run is None:
            raise CaseError("this result was read from a run directory; it is written already "
                            f"at {self.path}")
        extra = None
        if self.certified is not None:
            extra = {"reference": dict(name=self.certified.name, band=self.info.get("band"),
                                       method=self.meta.get("method"),
                                       orders=self.meta.get("orders"),
                                       spread=self.meta.get("spread"),
                                       provenance=self.meta.get("provenance"))}
        self.path = rundir.write_run(out, self.case, self._run, self.solver, extra_meta=extra)
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
        text = (f"the run ended before the stages at {case.stages_from(len(run.stage_s))} "
                f"({case.end_condition}); they are not in result.stages")
        notes.append(text)
        warnings.warn(text, stacklevel=2)
    stages = dict(s=np.asarray(run.stage_s, float),
                  s_hat=np.asarray(run.stage_s, float) * closed_forms.scales(case)["s_hat_per_m"],
                  r=np.asarray(run.r, float), f=np.asarray(run.f, float),
                  p=np.asarray(run.p, float))
    return Result(case=case, solver=solver, history=dict(run.history), stages=stages,
                  fields=run.fields, info=dict(run.info), solve_seconds=run.solve_seconds,
                  warnings=notes, _run=run)


def read_run(path: str | Path) -> Result:
    """A run directory written by ``wearcheck run``, ``compare``, ``refine`` or ``sweep``."""
    if not Path(path).exists():
        raise CaseError(f"run directory '{path}' does not exist")
    run = rundir.Run(path)
    return Result(case=run.case, solver=run.solver, history=run.history, stages=run.stages,
                  fields=run.fields, info=run.meta.get("info", {}),
                  solve_seconds=run.meta.get("solve_seconds", float("nan")), path=run.path,
                  meta=run.meta, warnings=list(run.meta.get("warnings", [])))


def reference(name: str) -> Result:
    """The certified reference solution of a shipped benchmark, as a :class:`Result`.

    ``name``: hertz, truncated, paper, ellipsoid, ball_on_flat or fretting. The
    stages are the case's; ``result.certified`` evaluates the reference at any
    distance within its stored stages (``history_at``, ``stage_at``) and gives its
    error band (``band_at``, ``band_table``); ``result.meta`` says how it was made
    (method, levels, observed orders, the other solvers' spread, provenance).
    ``result.write(path)`` writes it as a run directory.
    """
    ref = certified.load(name)
    run = ref.run_result()
    sc = ref.scales
    stages = dict(s=np.asarray(run.stage_s, float),
                  s_hat=np.asarray(run.stage_s, float) * sc["s_hat_per_m"],
                  r=np.asarray(run.r, float), f=np.asarray(run.f, float),
                  p=np.asarray(run.p, float))
    info = dict(run.info, band=ref.band_table(),
                band_units="SI: profile and lengths [m], force [N], pressure [Pa], "
                           "volume [m³]")
    return Result(case=ref.case, solver="reference", history=dict(run.history),
                  stages=stages, fields=None, info=info, solve_seconds=0.0,
                  meta=dict(ref.meta), certified=ref, _run=run)


def verify(case: str | Path | Case, results: str | Path, out: str | Path, *,
           mapping: Mapping[str, str] | Iterable[str] | None = None,
           reference_solver: str | None = None, quiet: bool = True) -> dict:
    """Judge results produced elsewhere against the certified reference of the case (or
    a fresh run of ``reference_solver``); write figures, metrics and a report to ``out``.

    ``results``: a directory with history.csv (and stages.csv), a .pvd/.vtu file, or
    CalculiX output; ``mapping``: ``{"p [MPa]": "CONTACT.CPRESS"}`` or
    ``["p [MPa]=CONTACT.CPRESS"]`` as ``--map``. Returns the metrics as in
    ``metrics.json``; ``["passed"]`` is the verdict.
    """
    if mapping is not None and not isinstance(mapping, Mapping):
        mapping = parse_mapping([mapping] if isinstance(mapping, str) else list(mapping))
    # lazy (b): the studies' modules made `import wearcheck` 1.10x slower (measured:
    # docs/performance.md, "Measurements behind the code")
    from wearcheck.studies.verify import verify as _verify
    return _verify(load_case(case), results, out, mapping=dict(mapping or {}),
                   reference_solver=reference_solver, quiet=quiet)


# -- studies -----------------------------------------------------------------

def compare(case: str | Path | Case, out: str | Path, *, solvers: Iterable[str] | None = None,
            reference_solver: str | None = None, edge_study: bool = False,
            sphere_sweep: bool = False, render: bool = True, quiet: bool = True) -> dict:
    """Run every solver that supports the case (or ``solvers``), compare each with
    the reference (default MDR, or the first exact solver where the MDR solved an
    approximation of the case), write figures, metrics and a report into ``out``.

    Returns the metrics as in ``metrics.json``; ``["passed"]`` is the verdict.
    """
    if isinstance(solvers, str):
        # "mdr,fem" as on the command line (--solvers)
        solvers = [name.strip() for name in solvers.split(",") if name.strip()] or [solvers]
    elif solvers is not None:
        solvers = list(solvers)
        if not solvers:
            raise CaseError("solvers = []: name at least two solvers, or None for every "
                            "solver that supports the case")
    # lazy (b): the studies' modules made `import wearcheck` 1.10x slower (measured:
    # docs/performance.md, "Measurements behind the code")
    from wearcheck.studies.compare import compare as _compare
    return _compare(load_case(case), out, solvers=solvers,
                    reference_solver=reference_solver, edge=edge_study, sphere=sphere_sweep,
                    render=render, quiet=quiet)


def refine(case: str | Path | Case, out: str | Path, solver: str = "mdr", *,
           levels: Iterable[int] | None = None, steps: Iterable[float] | None = None,
           tolerance: float = 0.01, scheduler: str | None = None, workers: int | None = None,
           quiet: bool = True) -> dict:
    """A refinement study on Dask (paper Fig. 4): returns its summary (observed orders,
    Richardson's estimate, coarsest converged level); run directories go to ``out``."""
    # lazy (b): the studies load asyncio (refine also scipy.optimize), which `import
    # wearcheck` leaves out (tests/test_cli_startup.py; docs/performance.md, "Start-up")
    from wearcheck.studies.refine import refine as _refine
    case = load_case(case)
    levels = None if levels is None else [_plain(v) for v in _listed(levels, "levels")]
    steps = None if steps is None else [_plain(v) for v in _listed(steps, "steps")]
    return _refine(case, solver, out, levels=levels, steps=steps, tolerance=tolerance,
                   scheduler=scheduler, workers=workers, quiet=quiet)


def sweep(case: str | Path | Case, vary: Mapping[str, Iterable], out: str | Path,
          solver: str = "mdr", *, scheduler: str | None = None, workers: int | None = None,
          quiet: bool = True) -> list[dict]:
    """One run per combination of values on Dask: ``vary={"wear.mu": [0.2, 0.3]}``.

    Parameters
    ----------
    vary : case keys and their values, as :meth:`Case.derive` takes them (several
        keys: every combination); a list key takes a list of lists. Or the
        command line's text, ``"wear.mu=0.2,0.3"`` or a list of such (as ``--vary``).

    Returns the rows of ``sweep.csv`` (the varied values, final ŝ, F/F0, wear
    depth, status per run).
    """
    # lazy (b): the studies load asyncio (refine also scipy.optimize), which `import
    # wearcheck` leaves out (tests/test_cli_startup.py; docs/performance.md, "Start-up")
    from wearcheck.studies.sweep import sweep as _sweep
    case = load_case(case)
    if isinstance(vary, str):
        vary = [vary]
    if isinstance(vary, (list, tuple)) and vary and all(isinstance(v, str) for v in vary):
        # "wear.mu=0.2,0.3" as on the command line (--vary), typed here once
        vary = dict(cases.case.parse_vary(text) for text in vary)
    return _sweep(case, vary, solver, out, scheduler=scheduler, workers=workers, quiet=quiet)


def fit(case: str | Path | Case, data, keys: str | Iterable[str] = ("wear.specific_rate",), *,
        out: str | Path | None = None, exponents: Iterable[float] | None = None,
        scheduler: str | None = None, workers: int | None = None, quiet: bool = True):
    """Fit a ball's (and a wearing counterface's) wear coefficients to measurements, as
    ``wearcheck fit`` does.

    Parameters
    ----------
    case : the ball test (a sphere or paraboloid under a constant force): a
        :class:`Case`, a case file or a shipped case's name.
    data : a measurement CSV (``cycles, D [um], ± D [um]``: docs/fitting.md), or a
        mapping of such headers to columns, ``{"cycles": [...], "D [um]": [...]}``
        (a pandas DataFrame works).
    keys : ``"wear.specific_rate"``, optionally with ``"wear.pressure_exponent"``
        (then one run per exponent of ``exponents``, default 1, 1.25, ..., 4, on
        Dask: ``scheduler``, ``workers`` as for :func:`sweep`); with a counterface
        that wears, ``"counterface.specific_rate"`` and/or ``"wear.specific_rate"``
        against the BEM's long-stroke model (one run per ratio K_flat/K_ball of a
        scan; on Dask when ``scheduler`` or ``workers`` is given).
    out : also write a fit directory there (fit.json, measurements.csv, fit.png,
        the fitted case, meta.json).

    Returns
    -------
    FitResult
        ``.parameters[KEY]["value"]`` and ``["ci95"]``, ``.measurements`` (each with
        its model value and residual), ``.lab`` (the lab formula's K),
        ``.goodness_of_fit``, ``.fitted_case``; ``.to_dict()`` is the JSON of
        ``wearcheck fit --json``. A warning is issued when the residuals say the
        model does not fit.

    Raises
    ------
    CaseError
        bad keys, case or data (one message naming the file, row and column).
    """
    # lazy (b): loads numerics.stepping and the fit's tables, which `import wearcheck` and
    # listing the solvers leave out (tests/test_registry_entries.py)
    from wearcheck.studies import fit as _fit
    result = _fit.fit(load_case(case), data, keys, exponents=exponents, scheduler=scheduler,
                      workers=workers, quiet=quiet)
    for text in result.warnings:
        if text.startswith(_fit.WARNING_STARTS):
            warnings.warn(text, stacklevel=2)
    if out is not None:
        _fit.write(result, out, data_path=data if isinstance(data, (str, Path)) else None)
    return result


def _listed(values, name: str) -> list:
    """Levels or steps as a sequence, or as the command line writes them: "50,100"."""
    if isinstance(values, str):
        try:
            return [float(v) if any(c in v for c in ".eE") else int(v)
                    for v in values.split(",") if v.strip()]
        except ValueError:
            raise ArgumentError(name, 'give numbers, e.g. [50, 100] or "50,100"',
                                value=values) from None
    return list(np.ravel(values))


def _plain(v):
    """numpy scalars and arrays as Python numbers and lists."""
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    return v



def export_vtk(run_dir: str | Path, revolve: int = 0) -> Path:
    """ParaView files (``.pvd`` series of ``.vtu``) of a run directory into ``RUN_DIR/vtk``.

    ``revolve`` N >= 3 also writes the FEM fields revolved into a 3D solid.
    """
    return export_run(run_dir, revolve=revolve)
