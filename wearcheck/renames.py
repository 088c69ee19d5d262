"""Atomic renames Python's ``os`` lacks: exchange two directories, rename without replacing.

Linux's ``renameat2`` (since 3.15, glibc 2.28) swaps two paths in one step
(``RENAME_EXCHANGE``) or refuses to replace the target (``RENAME_NOREPLACE``);
ext4, xfs, btrfs, tmpfs, f2fs and overlayfs take both, NFS, CIFS and most
FUSE file systems neither. Where a flag is not available :class:`Unsupported`
is raised, and the caller falls back to plain renames.
"""

from __future__ import annotations

import ctypes
import errno
import os
import sys

RENAME_NOREPLACE, RENAME_EXCHANGE = 1, 2
_AT_FDCWD = -100


class Unsupported(OSError):
    """This system or file system cannot do the rename asked for atomically."""


def _renameat2():
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        function = libc.renameat2
    except (OSError, AttributeError):
        return None
    function.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                         ctypes.c_uint]
    function.restype = ctypes.c_int
    return function


_RENAMEAT2 = _renameat2()


def _call(src, dst, flags: int) -> None:
    if _RENAMEAT2 is None:
        raise Unsupported(errno.ENOSYS, "renameat2 is not available here")
    if _RENAMEAT2(_AT_FDCWD, os.fsencode(src), _AT_FDCWD, os.fsencode(dst), flags) == 0:
        return
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP, errno.EOPNOTSUPP):
        # EINVAL is also what a file system without the flag says
        raise Unsupported(code, f"{os.strerror(code)} (renameat2 flags {flags})", str(dst))
    raise OSError(code, os.strerror(code), str(src), None, str(dst))


def exchange(a, b) -> None:
    """Swap the paths ``a`` and ``b`` (both must exist) in one atomic step."""
    _call(a, b, RENAME_EXCHANGE)


def rename_noreplace(src, dst) -> None:
    """Rename ``src`` to ``dst``; ``FileExistsError`` if ``dst`` exists (even empty)."""
    _call(src, dst, RENAME_NOREPLACE)
