"""The contact nodes' compliance computed by CalculiX, cached.

One ``*GREEN`` step (:func:`ccx.deck.compliance`) gives, for a unit axial
force on the wedge at each contact node off the axis, the axial displacement
of every such node: one column of the compliance per node, from one
factorisation. C [m/N, force on the ring] = u [mm] · 1e-3 / 180 (the unit
force acts on the 2° wedge). The .dat file's seven digits make C symmetric
to about 1e-6 of its largest entry; an asymmetry above :data:`SYMMETRY_TOLERANCE`
means the columns do not belong to the nodes they were read for, an error.

C is cached beside the meshes (``meshes.cache_dir()``) as
``ccx-compliance-<hash>.npz``, the hash taken over the mesh (points and
elements), the material, the CalculiX version and :data:`RECIPE`; written
atomically, a damaged entry is recomputed.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np

from wearcheck import meshes
from wearcheck.cases import SolverError

from . import deck
from .output import dat_blocks, select

#: bump when the deck or the extraction changes (invalidates the cache)
RECIPE = 1
#: largest |C - Cᵀ| / max|C| accepted: the .dat file's seven digits allow ~1e-6
SYMMETRY_TOLERANCE = 1e-5


def cache_key(sphere, youngs_modulus: float, poisson_ratio: float, version) -> str:
    """Hash of everything the compliance depends on."""
    h = hashlib.sha256()
    h.update(json.dumps(dict(recipe=RECIPE, E=float(youngs_modulus), nu=float(poisson_ratio),
                             ccx=list(version or ()), nc=len(sphere.contact))).encode())
    h.update(np.ascontiguousarray(sphere.points, np.float64).tobytes())
    h.update(np.ascontiguousarray(sphere.elements, np.int64).tobytes())
    return h.hexdigest()[:20]


def from_green_functions(text: str, n_loaded: int, source: str = "compliance.dat"):
    """C (n_loaded × n_loaded) [m/N] and its asymmetry, from the .dat text of the *GREEN job.

    The Green functions come in the order of the nodes of LOADED (node
    numbers 2 .. n_loaded + 1, by r); block k holds the displacements of
    every node of LOADED under the force at the k-th.
    """
    blocks = select(dat_blocks(text, source), "displacements", "LOADED")
    if len(blocks) != n_loaded:
        raise SolverError(f"{source}: {len(blocks)} Green functions for {n_loaded} loaded "
                          "contact nodes")
    ids = np.arange(2, n_loaded + 2)
    C = np.empty((n_loaded, n_loaded))
    for k, b in enumerate(blocks):
        if b.mode != k + 1 or not np.array_equal(b.ids, ids):
            raise SolverError(f"{source}: Green function {k + 1} is not the displacement of "
                              "the loaded nodes in order (mode or node numbers differ)")
        C[:, k] = b.values[:, 1]
    C *= 1.0 / (deck.MM * deck.WEDGES)
    scale = np.max(np.abs(C))
    if not (np.all(np.isfinite(C)) and scale > 0):
        raise SolverError(f"{source}: the Green functions are not finite and non-zero")
    asymmetry = float(np.max(np.abs(C - C.T)) / scale)
    if not asymmetry <= SYMMETRY_TOLERANCE:
        raise SolverError(f"{source}: the compliance is not symmetric (max |C - Cᵀ| = "
                          f"{asymmetry:.2e} of max |C|, above {SYMMETRY_TOLERANCE:g})")
    return C, asymmetry


def compliance(sphere, youngs_modulus: float, poisson_ratio: float, jobs, version,
               use_cache: bool = True) -> tuple[np.ndarray, dict]:
    """C of the contact nodes off the axis [m/N], symmetrised, and facts about it.

    ``jobs`` (:class:`ccx.run.Jobs`) runs the *GREEN job on a cache miss and
    records the deck either way. The facts: cache file, whether it was a hit,
    asymmetry, CalculiX seconds.
    """
    n = len(sphere.contact) - 1
    text = deck.compliance(title="wearcheck: compliance of the sphere's contact nodes")
    key = cache_key(sphere, youngs_modulus, poisson_ratio, version)
    path = meshes.cache_dir() / f"ccx-compliance-{key}.npz"
    if use_cache and path.is_file():
        try:
            with np.load(path, allow_pickle=False) as z:
                C, asymmetry, seconds = z["C"], float(z["asymmetry"]), float(z["seconds"])
            if C.shape == (n, n) and np.all(np.isfinite(C)):
                jobs.decks["compliance.inp"] = text
                return C, dict(cache_file=str(path), cached=True, asymmetry=asymmetry,
                               ccx_seconds_when_built=seconds)
        except Exception:  # a damaged (e.g. truncated) entry: recompute it
            pass
    job = jobs.run("compliance", text)
    C, asymmetry = from_green_functions(job.dat, n)
    C = 0.5 * (C + C.T)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        meshes.atomic_save(path, lambda tmp: np.savez(tmp, C=C, asymmetry=asymmetry,
                                                      seconds=job.seconds))
    except OSError as exc:
        raise SolverError(f"cannot write the compliance cache '{path}' (set "
                          f"WEARCHECK_CACHE): {exc}") from None
    return C, dict(cache_file=str(path), cached=False, asymmetry=asymmetry,
                   ccx_seconds=job.seconds)
