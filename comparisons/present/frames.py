"""A run as the objects notebooks analyse: a pandas DataFrame of its history and an
xarray Dataset of history and stages, units and provenance as attributes, and the
Dataset's netCDF file.

pandas and xarray are optional (``pip install "wearcheck[xarray]"``); each is
imported only when asked for. Units and meanings come from the run's data
dictionary (``wearcheck.layout``), the same one meta.json carries.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck import cases
from wearcheck.cases import CaseError, reference
from wearcheck import layout, registry
from wearcheck.extras import need
from wearcheck import rundir, temporaries

#: the global attribute that marks a netCDF file as wearcheck's (only such a file is
#: ever replaced)
MARK = "wearcheck_output"


def dictionary(result) -> dict:
    """The run's data dictionary: its meta.json's when read from a run directory,
    else built from the solver's registry entry (as ``rundir`` writes it)."""
    if result.meta and "data_dictionary" in result.meta:
        return result.meta["data_dictionary"]
    try:
        entry = registry.get(result.solver)
    except CaseError:    # a solver registered in another process
        entry = None
    return layout.run_dictionary(entry, list(result.history),
                                 stage_names=[k for k in result.stages
                                              if k not in ("s", "s_hat", "r", "f", "p")])


def history_frame(result):
    """The history as a DataFrame indexed by the sliding distance ``s`` [m].

    ``attrs``: ``units`` and ``meanings`` per column (the index's under "s"),
    ``solver``, ``case`` (the shipped name or file), ``scales`` (a0, d0, F0, p0...).
    """
    pd = need("pandas", "history_frame()")
    h = {k: np.asarray(v, float) for k, v in result.history.items()}
    table = dictionary(result)["history_csv"]
    frame = pd.DataFrame({k: v for k, v in h.items() if k != "s"},
                         index=pd.Index(h["s"], name="s"))
    frame.attrs.update(units={k: table.get(k, {}).get("unit", "?") for k in h},
                       meanings={k: table.get(k, {}).get("meaning", "") for k in h},
                       solver=result.solver, case=str(result.case.source),
                       scales=reference.scales(result.case))
    return frame


def _provenance(result) -> dict:
    """What the Dataset records of where it came from: the run directory's meta.json
    provenance when read from one, else this process's."""
    if result.meta and "command" in result.meta:   # meta.json holds it at its top level
        return result.meta
    return rundir.provenance()


def to_xarray(result):
    """History and stages as an xarray Dataset, CF-style ``units`` and ``long_name``.

    Dimensions: ``step`` (the history; coordinate ``s``), ``stage`` (coordinates
    ``stage_s`` [m] and ``stage_s_hat``) and ``r`` [m]. Global attributes: solver,
    the resolved case as TOML text (``case_toml``), the scales (``scale_F0``...),
    the command line, versions and git revision, and the :data:`MARK`.
    """
    xr = need("xarray", "to_xarray()")
    d = dictionary(result)
    hist, stages = d["history_csv"], d["stages_npz"]

    def attrs(table, name):
        item = table.get(name, {})
        return dict(units=item.get("unit", "?") or "1", long_name=item.get("meaning", name))

    h = {k: np.asarray(v, float) for k, v in result.history.items()}
    data = {k: ("step", v, attrs(hist, k)) for k, v in h.items() if k != "s"}
    st = result.stages
    for k, v in st.items():
        if k in ("s", "s_hat", "r"):
            continue
        data[k] = (("stage", "r"), np.asarray(v, float), attrs(stages, k))
    coords = dict(s=("step", h["s"], attrs(hist, "s")),
                  stage_s=("stage", np.asarray(st["s"], float), attrs(stages, "s")),
                  stage_s_hat=("stage", np.asarray(st["s_hat"], float), attrs(stages, "s_hat")),
                  r=("r", np.asarray(st["r"], float), attrs(stages, "r")))
    prov = _provenance(result)
    glob = {MARK: "result", "solver": result.solver, "case": str(result.case.source),
            "case_toml": cases.to_toml(result.case),
            "command": str(prov.get("command", "")),
            "wearcheck_version": str(prov.get("wearcheck_version", "")),
            "git_revision": str(prov.get("git_revision", "")),
            "versions": ", ".join(f"{k} {v}" for k, v in (prov.get("versions") or {}).items()),
            "created": str(prov.get("created", "")),
            "solve_seconds": float(result.solve_seconds)}
    glob.update({f"scale_{k}": float(v) for k, v in reference.scales(result.case).items()})
    if result.warnings:
        glob["warnings"] = "\n".join(str(w) for w in result.warnings)
    return xr.Dataset(data, coords=coords, attrs=glob)


def write_netcdf(result, path: str | Path) -> Path:
    """Write :func:`to_xarray` to the netCDF file ``path`` (netCDF 3 through scipy:
    no netCDF library needed), atomically; an existing file is replaced only when it
    is a wearcheck netCDF file."""
    xr = need("xarray", "to_netcdf()")
    path = Path(path)
    if path.exists() or path.is_symlink():
        if not path.is_file() or path.is_symlink():
            raise CaseError(f"'{path}' exists and is not a regular file; wearcheck writes "
                            "the netCDF file only to a new path or over its own")
        try:
            with xr.open_dataset(path, engine="scipy") as old:
                ours = old.attrs.get(MARK) == "result"
        except Exception:       # anything xarray cannot read as netCDF 3
            ours = False
        if not ours:
            raise CaseError(f"'{path}' exists and is not a wearcheck netCDF file: not "
                            "replaced (choose another path)")
    if not path.parent.is_dir():
        raise CaseError(f"cannot write '{path}': its directory '{path.parent}' does not exist")
    ds = to_xarray(result)
    # through a temporary that names its writer: what a killed writer left is removed
    return temporaries.atomic_write(path, lambda tmp: ds.to_netcdf(tmp, engine="scipy"))
