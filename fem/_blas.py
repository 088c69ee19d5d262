"""Run a block with single-threaded OpenBLAS (best effort, Linux).

The wear loop does thousands of small dense operations (matrix-vector
products, triangular solves, Cholesky of at most ~1000²). OpenBLAS threads
them, and on a 2-core machine shared with other processes its threads spin
against each other: measured here, the 1001-node paper case took 26 s with
2 BLAS threads under load against 5.7 s with 1 (250 nodes: 4.2 s against
1.3 s). This does what threadpoolctl does, without the dependency: find the
OpenBLAS libraries loaded into the process (numpy and scipy each bundle one)
and call their ``*openblas_set_num_threads*``; restore the previous counts
afterwards. Anything unexpected leaves BLAS untouched.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import os
import threading


#: (setter, getter) symbol names: numpy's and scipy's bundled OpenBLAS, plain OpenBLAS
_NAMES = (("scipy_openblas_set_num_threads64_", "scipy_openblas_get_num_threads64_"),
          ("scipy_openblas_set_num_threads", "scipy_openblas_get_num_threads"),
          ("openblas_set_num_threads64_", "openblas_get_num_threads64_"),
          ("openblas_set_num_threads", "openblas_get_num_threads"))


@functools.lru_cache(maxsize=1)
def _openblas_handles():
    # numpy and scipy.linalg (imported by fem) have loaded their libraries by
    # the first call, so the search runs once
    try:
        with open("/proc/self/maps", encoding="utf-8") as fh:
            paths = {line.split()[-1] for line in fh if "openblas" in line and ".so" in line}
    except OSError:
        return []
    handles = []
    for path in sorted(paths):
        try:
            lib = ctypes.CDLL(path, mode=os.RTLD_NOLOAD | os.RTLD_LOCAL)
        except (OSError, AttributeError):
            continue
        for name_set, name_get in _NAMES:
            setter, getter = getattr(lib, name_set, None), getattr(lib, name_get, None)
            if setter is not None and getter is not None:
                getter.restype = ctypes.c_int
                handles.append((setter, getter))
                break
    return tuple(handles)


_lock = threading.Lock()
_depth = 0
_saved: list = []


@contextlib.contextmanager
def single_threaded_blas():
    """Context manager: OpenBLAS uses one thread inside the block.

    Re-entrant and thread-safe: the first block to enter saves the thread
    counts, the last to leave restores them.
    """
    global _depth
    with _lock:
        if _depth == 0:
            _saved.clear()
            try:
                for setter, getter in _openblas_handles():
                    _saved.append((setter, int(getter())))
                    setter(ctypes.c_int(1))
            except Exception:  # never let a thread-count tweak break a solve
                pass
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                for setter, n in _saved:
                    with contextlib.suppress(Exception):
                        setter(ctypes.c_int(n))
