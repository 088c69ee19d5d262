"""The hidden temporary files of atomic writes, and the removal of those a killed writer left.

A file is written under a hidden name in its own directory and renamed over
its path when whole. The name says who writes it,
``.NAME.partial-PID@HOST@XXXXXXXX[SUFFIX]`` (the process id, 8 hex digits of
the host's name, mkstemp's random part): a writer killed mid-write (SIGKILL, a
crash, a power cut) leaves its temporary behind, and the next write into the
directory removes those of processes of this host that have ended. Those of a
writer still at work, or of another host sharing the directory over NFS, are
kept.

One mechanism for every such file: the output files and markers
(:mod:`wearcheck.outputs`), the mesh and compliance caches (``meshes``) and a
result's netCDF file (``Result.to_netcdf``). Standard library only, so that
every layer may use it.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import platform
import re
import tempfile
from pathlib import Path

#: a temporary file of :func:`new`: '.NAME.partial-PID@HOST@XXXXXXXX[SUFFIX]'
PATTERN = re.compile(r"\.partial-(\d+)@([0-9a-f]{8})@[^@/]*$")


def host_tag() -> str:
    """8 hex digits naming this host in the name of a temporary file."""
    return hashlib.sha256(platform.node().encode("utf-8", "replace")).hexdigest()[:8]


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` of this host is running (another user's counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True
    return True


def umask() -> int:
    """The process's umask (files made by mkstemp are 0600 whatever it is)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def new(directory: Path, name: str, suffix: str = "") -> Path:
    """A new empty temporary file for ``name`` in ``directory`` whose name says which
    process writes it (``suffix`` kept for writers that choose the format by it)."""
    fd, tmp = tempfile.mkstemp(prefix=f".{name}.partial-{os.getpid()}@{host_tag()}@",
                               suffix=suffix, dir=directory)
    os.close(fd)
    return Path(tmp)


def remove_dead(directory: Path, names=None) -> list[Path]:
    """Remove the temporary files (:func:`new`) in ``directory`` (those of ``names``
    only, if given) that a process of this host left when it was killed; those of
    running processes and of other hosts are left. Returns the files removed."""
    removed = []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    prefixes = None if names is None else tuple(f".{n}.partial-" for n in names)
    for e in entries:
        m = PATTERN.search(e.name)
        if not m or not e.name.startswith(".") or \
                (prefixes is not None and not e.name.startswith(prefixes)):
            continue
        try:
            if not e.is_file(follow_symlinks=False):
                continue
        except OSError:
            continue
        if m.group(2) == host_tag() and not pid_alive(int(m.group(1))):
            with contextlib.suppress(FileNotFoundError):
                os.unlink(e.path)
                removed.append(Path(e.path))
    return removed


def atomic_write(path: Path, write, *, mode: int | None = None, clean=None) -> Path:
    """Write ``path`` by ``write(temporary)`` and a rename: never half written.

    What killed writers left in the directory goes first: the temporaries of
    ``path``'s name, or of the names in ``clean`` (``"all"``: every name, a
    cache's directory). ``mode``: the file's permissions (default those of a
    new file under the umask; mkstemp's are 0600). The temporary is removed on
    any failure or interrupt.
    """
    path = Path(path)
    remove_dead(path.parent, None if clean == "all" else (clean or [path.name]))
    tmp = new(path.parent, path.name, path.suffix)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~umask() if mode is None else mode)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
    return path
