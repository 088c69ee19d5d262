"""Check a case against the machine before solving: memory, and export sizes.

Each solver package estimates its own needs in ``<solver>/resources.py``
(pure functions: ``memory_bytes(case, value)`` and ``RESOURCE_KEY``, the case
key the estimate grows with); this module compares the estimate with the
memory available now and refuses, with one line naming the key, the estimate
and the largest value that fits, what would not fit.
"""

from __future__ import annotations

import importlib
import math
import shutil
from pathlib import Path

from wearcheck import cases

#: share of the available memory one run may plan to use (the estimates are
#: rough, and the OS, Dask and the other workers need some)
MEMORY_SHARE = 0.8


def available_memory() -> float:
    """Bytes of memory available to a new allocation now (/proc/meminfo, else psutil).

    Linux's MemAvailable is what psutil reports there too; read directly, since
    importing psutil is a noticeable part of a small run's start-up.
    """
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return float(line.split()[1]) * 1024.0
    except (OSError, ValueError, IndexError):
        pass
    try:
        import psutil
        return float(psutil.virtual_memory().available)
    except Exception:  # psutil comes with distributed; be safe without it
        return math.inf


def human(nbytes: float) -> str:
    """``nbytes`` as a short text, e.g. ``3.2 GiB``."""
    if not math.isfinite(nbytes):
        return "unbounded"
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(nbytes) < 1024.0 or unit == "PiB":
            return f"{nbytes:.3g} {unit}"
        nbytes /= 1024.0
    return f"{nbytes:.3g} EiB"


def _largest(fits, lo: int, hi: int) -> int | None:
    """Largest integer n in [lo, hi] with fits(n) (fits monotone); None if none."""
    if not fits(lo):
        return None
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return lo


def _estimator(solver: str):
    """The solver package's ``resources`` module (next to its ``solve``), or None."""
    module = f"wearcheck.{solver}"
    try:
        from wearcheck import registry
        module = registry.get(solver).module or module
    except Exception:  # an unknown name: the solve reports it
        pass
    try:
        return importlib.import_module(f"{module}.resources")
    except ImportError:
        return None  # a solver without an estimate is not checked


def check_memory(case, solver: str, available: float | None = None) -> float | None:
    """Refuse (CaseError) a run of ``solver`` on ``case`` that would not fit in memory.

    Returns the estimate in bytes (None when the solver gives none).
    """
    est = _estimator(solver)
    if est is None:
        return None
    need = float(est.memory_bytes(case))
    budget = MEMORY_SHARE * (available_memory() if available is None else available)
    if need <= budget:
        return need
    key = est.RESOURCE_KEY
    section, name = key.split(".")
    value = getattr(getattr(case, section), name)
    largest = _largest(lambda n: est.memory_bytes(case, n) <= budget, 2, max(int(value), 3))
    allowed = (f"the largest {key} that fits is about {largest}" if largest is not None
               else "even the smallest grid does not fit; free memory first")
    raise cases.CaseError(f"key '{key}' = {value}: the {solver.upper()} run needs about "
                          f"{human(need)} of memory, more than the {human(budget)} available "
                          f"({MEMORY_SHARE:.0%} of what is free now); {allowed}")


def export_bytes(section_points: float, profile_points: float, segments: int,
                 stages: int) -> float:
    """Bytes of the VTU files (and about the memory) of an export with ``segments``.

    The revolved surface has profile_points × segments points and as many
    quads; a revolved FEM section section_points × segments points with about
    2 linear wedges per point; point data of about 20 doubles per point.
    """
    per_segment = profile_points * (24.0 + 8.0 * 4 + 40.0) + section_points * (
        24.0 + 8.0 * 20 + 2 * 64.0)
    return float(segments) * per_segment * max(int(stages), 1)


def check_export(section_points: float, profile_points: float, segments: int, stages: int,
                 directory: Path, available: float | None = None) -> None:
    """Refuse (CaseError) a ``--revolve`` whose files would not fit in memory or on disk."""
    one = export_bytes(section_points, profile_points, segments, 1)
    total = export_bytes(section_points, profile_points, segments, stages)
    budget = MEMORY_SHARE * (available_memory() if available is None else available)
    ancestor = Path(directory).absolute()
    while not ancestor.exists():
        ancestor = ancestor.parent
    try:
        disk = float(shutil.disk_usage(ancestor).free)
    except OSError:
        disk = math.inf
    if one <= budget and total <= disk:
        return
    per = one / max(segments, 1)
    largest = int(min(budget / per, disk / (per * max(stages, 1))))
    what = (f"about {human(one)} of memory per stage, more than the {human(budget)} available"
            if one > budget else f"about {human(total)} of files, more than the {human(disk)} "
            f"free on '{ancestor}'")
    raise cases.CaseError(f"--revolve {segments}: the revolved solid needs {what}; the largest "
                          f"--revolve that fits is about {max(largest, 0)}")
