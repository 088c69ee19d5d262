"""Run directories: atomic writing, provenance, and reading back.

A run directory holds the files of ``layout.RUN_FILES``: ``case.toml``,
``history.csv``, ``stages.npz`` and ``meta.json`` (and ``fields.npz`` when the
solver provides fields); ``layout`` gives every column and array its unit. It is
built in a hidden sibling directory and renamed into place only when complete,
so an interrupted or failed run leaves nothing that looks complete and never
damages an earlier complete run at the same path.
"""

from __future__ import annotations

import importlib.metadata
import json
import math
import os
import platform
import shlex
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from wearcheck import cases, extras, layout
from wearcheck.cases import reference
from wearcheck.cases.result import HISTORY_COLUMNS, RunResult
from wearcheck.outputs import atomic_directory
from wearcheck import registry
from wearcheck.outputs import is_partial, read_marker, recover

#: the packages whose versions every output records: the core's, then the extras'
#: (None when not installed)
DEPENDENCIES = ("numpy", "scipy", "threadpoolctl", "tqdm",
                *dict.fromkeys(distribution for distribution, _ in extras.MODULES.values()))



def wearcheck_version() -> str | None:
    """The version of the wearcheck package that is running."""
    try:
        return importlib.metadata.version("wearcheck")
    except importlib.metadata.PackageNotFoundError:
        root = source_checkout()
        if root is None:
            return None
        return tomllib.loads((root / "pyproject.toml").read_text(encoding="utf-8"))["project"].get(
            "version")


def versions() -> dict:
    out = {"python": platform.python_version(), "wearcheck": wearcheck_version()}
    for name in DEPENDENCIES:
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            out[name] = None
    return out


def _git(args: list[str], cwd: Path) -> str | None:
    try:
        done = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, timeout=5)
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip() if done.returncode == 0 else None


def source_checkout() -> Path | None:
    """The root of the wearcheck git checkout this package runs from, or None.

    The package's folders sit at the top level of the repository, so the root
    is the folder above this one. It counts as a wearcheck checkout only when it
    holds a pyproject.toml naming the project "wearcheck" and git's top level is
    that very folder: an installed copy (site-packages/wearcheck),
    perhaps inside a user's own git repository, is not one.
    """
    root = Path(__file__).resolve().parent.parent
    pyproject = root / "pyproject.toml"
    try:
        name = tomllib.loads(pyproject.read_text(encoding="utf-8"))["project"]["name"]
    except (OSError, KeyError, TypeError, tomllib.TOMLDecodeError, UnicodeDecodeError):
        return None
    if name != "wearcheck":
        return None
    top = _git(["rev-parse", "--show-toplevel"], root)
    if top is None or Path(top).resolve() != root:
        return None
    return root


def git_revision() -> str | None:
    """wearcheck's git revision, with '-dirty' if the checkout has changes; None
    unless the package runs from a wearcheck checkout (see :func:`source_checkout`)."""
    root = source_checkout()
    if root is None:
        return None
    rev = _git(["rev-parse", "HEAD"], root)
    if rev is None:
        return None
    dirty = _git(["status", "--porcelain", "--untracked-files=no"], root)
    return rev + ("-dirty" if dirty else "")


#: the command line of this process as the user typed it; set by the CLI
_COMMAND: list[str] | None = None


def set_command(argv: list[str]) -> None:
    """Record the command line that outputs of this process will name."""
    global _COMMAND
    _COMMAND = list(argv)


def provenance(argv=None) -> dict:
    """What every output directory records: versions, command line, revision, time."""
    if argv is None:
        argv = _COMMAND if _COMMAND is not None else sys.argv
    return dict(
        command=shlex.join(argv),
        cwd=os.getcwd(),
        wearcheck_version=wearcheck_version(),
        # None unless running from a wearcheck git checkout (never the revision of a
        # user's repository that an installed wearcheck happens to sit in)
        git_revision=git_revision(),
        versions=versions(),
        created=time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        host=platform.node(),
    )


def jsonable(obj):
    """``obj`` with numpy arrays and scalars as lists and Python numbers, for json.dumps."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def write_json(path: Path, data: dict) -> None:
    Path(path).write_text(json.dumps(jsonable(data), indent=2, allow_nan=True) + "\n",
                          encoding="utf-8")


def history_csv_text(history: dict) -> str:
    names = list(HISTORY_COLUMNS) + [k for k in history if k not in HISTORY_COLUMNS]
    cols = np.column_stack([np.asarray(history[k], dtype=float) for k in names])
    lines = [",".join(names)]
    lines += [",".join(f"{v:.12e}" for v in row) for row in cols]
    return "\n".join(lines) + "\n"


def write_run_files(directory: Path, case: cases.Case, result: RunResult, solver: str,
                    argv=None, extra_meta: dict | None = None) -> None:
    """Write one run's files into an (already temporary) directory."""
    directory = Path(directory)
    scales = reference.scales(case)
    (directory / "case.toml").write_text(cases.to_toml(case), encoding="utf-8")
    (directory / "history.csv").write_text(history_csv_text(result.history), encoding="utf-8")
    np.savez(directory / "stages.npz", s=np.asarray(result.stage_s, float),
             s_hat=np.asarray(result.stage_s, float) * scales["s_hat_per_m"],
             r=np.asarray(result.r, float), f=np.asarray(result.f, float),
             p=np.asarray(result.p, float),
             **{k: np.asarray(v, float) for k, v in (result.stage_extra or {}).items()})
    if result.fields:
        np.savez(directory / "fields.npz", **result.fields)
    meta = dict(solver=solver, scales=scales, solve_seconds=result.solve_seconds,
                stages_requested_s_hat=list(case.stages.s_hat),
                stages_reached=len(result.stage_s),
                warnings=list(case.warnings) + list(result.info.get("warnings", [])),
                info=result.info)
    meta.update(provenance(argv))
    if case.table_file is not None:   # the tabulated profile read, by content
        meta["profile_table"] = dict(case.table_file)
    if extra_meta:
        meta.update(extra_meta)
    meta["data_dictionary"] = layout.run_dictionary(_registered(solver), list(result.history),
                                                    list(result.fields or {}),
                                                    list(result.stage_extra or {}), list(meta))
    write_json(directory / "meta.json", meta)
    entry = _registered(solver)
    if entry is not None and entry.run_report:  # e.g. the MDR's fretting report
        import importlib
        module, _, function = entry.run_report.partition(":")
        getattr(importlib.import_module(module), function)(directory, case, result)


def _registered(solver: str):
    try:
        return registry.get(solver)
    except cases.CaseError:  # e.g. a stand-in solver of a test
        return None


def write_run(out: str | Path, case: cases.Case, result: RunResult, solver: str,
              argv=None, extra_meta: dict | None = None) -> Path:
    """Write a complete run directory at ``out`` atomically."""
    with atomic_directory(out, "run") as tmp:
        write_run_files(tmp, case, result, solver, argv, extra_meta)
    return Path(out)


# -- reading back ----------------------------------------------------------

class Run:
    """A run directory read back: case, history, stages, meta."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if is_partial(self.path):
            raise cases.CaseError(f"'{self.path}' is an incomplete run directory (a .partial "
                                  "directory of a wearcheck process that was stopped or is "
                                  "still writing); use the complete run")
        if not self.path.exists():
            # a writer killed while it replaced the run may have left it aside
            recover(self.path)
        if not self.path.exists():
            raise cases.CaseError(f"run directory '{self.path}' does not exist")
        if not self.path.is_dir():
            raise cases.CaseError(f"'{self.path}' is a file, not a run directory")
        _refuse_other_output(self.path)
        meta = self.path / "meta.json"
        if not meta.is_file():
            raise cases.CaseError(f"'{self.path}' is not a complete run directory "
                                  "(no meta.json)")
        self.meta = _read(meta, lambda p: json.loads(p.read_text(encoding="utf-8")))
        if not isinstance(self.meta, dict) or not isinstance(self.meta.get("scales"), dict):
            raise cases.CaseError(f"run directory file '{meta}' is damaged (no scales)")
        why = meta_damage(self.meta)
        if why:
            raise cases.CaseError(f"run directory file '{meta}' is damaged: {why}")
        self.case = cases.load(self.path / "case.toml")
        self.history = _read(self.path / "history.csv", _read_history)
        self.stages = _read(self.path / "stages.npz", _read_npz)
        missing = {"s", "s_hat", "r", "f", "p"} - set(self.stages)
        if missing:
            raise cases.CaseError(f"run directory file '{self.path / 'stages.npz'}' is damaged: "
                                  f"no {', '.join(sorted(missing))}")
        why = stages_damage(self.stages)
        if why:
            raise cases.CaseError(f"run directory file '{self.path / 'stages.npz'}' is "
                                  f"damaged: {why}")
        fields = self.path / "fields.npz"
        self.fields = _read(fields, _read_npz) if fields.is_file() else None

    @property
    def scales(self) -> dict:
        return self.meta["scales"]

    @property
    def solver(self) -> str:
        return self.meta["solver"]


#: the scales every reader of a run divides by: finite and positive
POSITIVE_SCALES = ("E_star", "a0", "d0", "F0", "p0")


def meta_damage(meta: dict) -> str | None:
    """What is wrong with a run's meta.json for reading it back, or None: the solver's
    name, and the scales (layout.META) as finite numbers, positive where divided by."""
    if not isinstance(meta.get("solver"), str) or not meta["solver"]:
        return "no solver name"
    scales = meta["scales"]
    for name in ("E_star", "G_star", "a0", "d0", "F0", "p0", "s_hat_per_m"):
        value = scales.get(name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value):
            return f"scale '{name}' is {value!r}, not a finite number"
        if name in POSITIVE_SCALES and value <= 0:
            return f"scale '{name}' is {value!r}, not positive"
    return None


def stages_damage(stages: dict) -> str | None:
    """What is wrong with the arrays of a stages.npz (layout.STAGES), or None.

    s and s_hat are (K,), r is (M,), f, p and the optional per-stage arrays are
    (K, M) (an empty table when no stage was stored), every value finite:
    wearcheck never writes a run with a non-finite value (a numerical failure
    is reported instead), so one is damage, which exporting or drawing would
    turn into empty pictures.
    """
    arrays = {k: np.asarray(v) for k, v in stages.items()}
    for name, arr in arrays.items():
        if not np.issubdtype(arr.dtype, np.number):
            return f"'{name}' holds {arr.dtype} values, not numbers"
    K, M = np.shape(arrays["s"]), np.shape(arrays["r"])
    if len(K) != 1 or len(M) != 1:
        return f"'s' has shape {K} and 'r' {M}; both must be lists (one dimension)"
    K, M = K[0], M[0]
    expected = {"s": (K,), "s_hat": (K,), "r": (M,)}
    for name, arr in arrays.items():
        want = expected.get(name, (K, M))
        if arr.shape != want and not (K == 0 and arr.size == 0 and name not in expected):
            return (f"'{name}' has shape {arr.shape}, not {want} ({K} stages x {M} radii, "
                    "as 's' and 'r' say)")
        bad = int(np.size(arr) - np.count_nonzero(np.isfinite(arr)))
        if bad:
            return f"'{name}' holds {bad} values that are not finite (NaN or infinite)"
    r = arrays["r"]
    # every solver writes its radii from the axis outwards; reversed or shuffled radii
    # would be drawn and exported as a scrambled profile without a word
    if M and (r[0] < 0 or np.any(np.diff(r) <= 0)):
        return "'r' is not increasing from r >= 0 (as wearcheck writes its radii)"
    return None


def _refuse_other_output(path: Path) -> None:
    """A comparison or a study holds run directories but is none: say so, and name them.

    Their ``meta.json`` (a study's) or ``metrics.json`` would otherwise be read
    as a damaged run, which sends the user looking for damage that is not there.
    """
    marker = read_marker(path)
    kind = marker.get("kind") if marker else None
    if kind in (None, "run", "legacy"):
        return
    runs = sorted(str(child) for child in path.iterdir()
                  if child.is_dir() and not child.name.startswith(".")
                  and (child / "meta.json").is_file())
    shown = ", ".join(runs[:3]) + (f" (and {len(runs) - 3} more)" if len(runs) > 3 else "")
    hint = f"; its runs: {shown}" if runs else ""
    raise cases.CaseError(f"'{path}' is a wearcheck {kind} directory, not a run "
                          f"directory{hint}")


def _read_history(path: Path) -> dict:
    data = np.genfromtxt(path, delimiter=",", names=True)
    if data.dtype.names is None or "s" not in data.dtype.names:
        raise ValueError("no header with a column 's'")
    return {n: np.atleast_1d(data[n]) for n in data.dtype.names}


def _read_npz(path: Path) -> dict:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _read(path: Path, reader):
    """``reader(path)``, any failure to read or parse it as one line naming the file."""
    if not path.is_file():
        raise cases.CaseError(f"run directory file '{path}' is missing")
    try:
        return reader(path)
    except cases.WearcheckError:
        raise
    except Exception as exc:  # zipfile, numpy, json, OS: all mean a damaged file
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise cases.CaseError(f"run directory file '{path}' is damaged or truncated "
                              f"({text})") from None
