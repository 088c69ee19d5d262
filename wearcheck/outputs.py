"""Output safety: which paths wearcheck may write, replace or remove.

Every output directory wearcheck writes carries a marker file,
``.wearcheck-output``, holding JSON: the kind of output (``run``,
``comparison``, ``study``, ``vtk``, ``render``; ``mesh`` for the side file of
``wearcheck mesh --out``), whether it is complete, and the writing process
(pid, host). Only that marker makes an existing path replaceable, and only by
an output of the same kind; anything else is refused with one line and never
deleted. Directories are built in a hidden ``.NAME.partial-*`` sibling, marked
complete only when they are, and then exchanged with what is at the path in
one atomic step (:func:`_install`), so that a kill at any instant leaves the
path holding the earlier output or the new one. What a killed writer left
beside the path (same host, pid gone) is put right by the next write to, or
read of, that path (:func:`recover`).

The CLI checks an output path with :func:`check_output` before any solve, so a
path that cannot be written fails in a second, not after the work.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import platform
import shutil
import stat
import struct
import sys
import tempfile
import threading
import time
from pathlib import Path

from wearcheck import cases
from wearcheck import renames, temporaries

try:
    import fcntl
except ImportError:       # not on Windows
    fcntl = None

#: written into every directory wearcheck creates: what may be replaced, and by what
OUTPUT_MARKER = ".wearcheck-output"
KINDS = ("run", "comparison", "study", "vtk", "render", "mesh", "fit")
#: the text marker of wearcheck before the marker said its kind (runs and comparisons)
_LEGACY_MARKER_TEXT = "written by wearcheck"


class OutputError(cases.CaseError):
    """An output path that wearcheck may not, or cannot, write (exit code 2)."""


def marker_data(kind: str, complete: bool) -> dict:
    return dict(wearcheck="output", kind=kind, complete=complete, pid=os.getpid(),
                host=platform.node(), created=time.strftime("%Y-%m-%dT%H:%M:%S%z"))


def write_marker(directory: Path, kind: str, complete: bool = True, files=None,
                 built_in: str | None = None) -> None:
    """Write the marker, by rename (never half written); ``files`` (from
    :func:`inventory`) lists what the output holds, ``built_in`` names the hidden
    ``.partial-*`` directory it was built in (see :func:`left_behind`)."""
    data = marker_data(kind, complete)
    if files is not None:
        data["files"] = files
    if built_in is not None:
        data["built_in"] = built_in
    _rewrite_marker(Path(directory), data)


def _parse_marker(text: str) -> dict | None:
    if text.startswith(_LEGACY_MARKER_TEXT):
        return dict(wearcheck="output", kind="legacy", complete=True)
    try:
        data = json.loads(text)
    except ValueError:
        return None
    if not isinstance(data, dict) or data.get("wearcheck") != "output":
        return None
    return data


def _marker_at(fd: int) -> dict | None:
    """The marker of the directory open as ``fd`` (None when it has none)."""
    try:
        st = os.stat(OUTPUT_MARKER, dir_fd=fd, follow_symlinks=False)
        if not stat.S_ISREG(st.st_mode):      # a regular file, not a link
            return None
        mfd = os.open(OUTPUT_MARKER, os.O_RDONLY, dir_fd=fd)
        with os.fdopen(mfd, encoding="utf-8", errors="replace") as fh:
            return _parse_marker(fh.read())
    except OSError:
        return None


#: files up to this size are fingerprinted by content (SHA-256), larger ones by
#: size and modification time: an edit that keeps both would pass for them
HASH_MAX_BYTES = 64 << 20
#: the parts an output may hold, written later by another command (:func:`_is_part`)
_PARTS = ("vtk", "render")


def _fingerprint(fd: int, name: str, st) -> list:
    """[size, mtime_ns, sha256 or None] of the file ``name`` in the directory ``fd``."""
    digest = None
    if stat.S_ISREG(st.st_mode) and st.st_size <= HASH_MAX_BYTES:
        h = hashlib.sha256()
        ffd = os.open(name, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0), dir_fd=fd)
        with os.fdopen(ffd, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
        digest = h.hexdigest()
    return [st.st_size, st.st_mtime_ns, digest]


def _same(now: list, recorded) -> bool:
    """Whether a file is as it was written: its content, else its size and mtime."""
    if not isinstance(recorded, list) or len(recorded) < 2 or not isinstance(now, list):
        return now == recorded
    if not now or not recorded:          # directories: [] both
        return now == recorded
    if now[0] != recorded[0]:
        return False
    if len(recorded) > 2 and recorded[2] and len(now) > 2 and now[2]:
        return now[2] == recorded[2]     # a copy (tar, cp) may not keep the mtime
    return now[1] == recorded[1]


def _is_part(outer, inner, depth: int, name: str) -> bool:
    """Whether an ``inner`` output ``name``, ``depth`` levels inside an ``outer`` one, is
    one of its parts: a run's (or a comparison's, also in its solver folders)
    ``vtk/`` and ``render/``, and a study's runs. Anything else inside is foreign.
    """
    if inner in _PARTS and name == inner:
        return outer in ("run", "comparison", "legacy") and \
            (depth == 1 or (depth == 2 and outer == "comparison"))
    return outer == "study" and inner in ("run", "comparison") and depth == 1


def _walk(fd: int, prefix: str, files: dict, nested: list, root_kind=None,
          partials: list | None = None) -> None:
    """Fill ``files`` with the inventory below the directory ``fd``; collect nested outputs.

    Everything is read through the open directory, so a concurrent writer that
    renames another directory onto the same path cannot mix two outputs.
    Nested outputs that are this output's own parts are appended to ``nested``
    as (relative path, open descriptor) and left out of ``files``; another
    command's directory being written (``.NAME.partial-*``) goes to
    ``partials`` as (relative path, marker).
    """
    with os.scandir(fd) as it:
        entries = sorted(it, key=lambda e: e.name)
    depth = prefix.count("/") + 1
    for e in entries:
        if not prefix and (e.name == OUTPUT_MARKER or e.name.startswith(OUTPUT_MARKER + ".")):
            continue          # the marker, and a new one being written (_rewrite_marker)
        rel = prefix + e.name
        if e.is_dir(follow_symlinks=False):
            sub = os.open(e.name, os.O_RDONLY | os.O_DIRECTORY, dir_fd=fd)
            marker = _marker_at(sub)
            if marker is not None and partials is not None and e.name.startswith(".") \
                    and (".partial-" in e.name or ".old-" in e.name):
                partials.append((rel, marker))
                os.close(sub)
                continue
            if marker is not None and marker.get("complete", True) \
                    and _is_part(root_kind, marker.get("kind"), depth, e.name):
                nested.append((rel, sub))
                continue
            try:
                files[rel] = []
                _walk(sub, rel + "/", files, nested, root_kind, partials)
            finally:
                os.close(sub)
        else:
            files[rel] = _fingerprint(fd, e.name, e.stat(follow_symlinks=False))


def inventory(directory: Path, kind=None) -> dict:
    """What the ``kind`` output ``directory`` holds: {relative path: [size, mtime_ns,
    sha256]} of its files and links, [] for its directories.

    The marker is left out, and so are the output's own parts written later by
    another command (a run's ``vtk/`` and ``render/``, a comparison's runs):
    they have their own marker and inventory and are checked on their own.
    """
    fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY)
    files, nested = {}, []
    try:
        _walk(fd, "", files, nested, kind)
    finally:
        os.close(fd)
        for _, sub in nested:
            os.close(sub)
    return files


def _shown(names) -> str:
    names = [n if n.isprintable() else repr(n) for n in names]
    return ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")


def foreign_content(directory: Path) -> str | None:
    """Why replacing the wearcheck output ``directory`` would lose something; None if not.

    Compares what it holds now with the inventory its marker recorded when it
    was written: a file or directory added since, or a file changed since
    (content; size and mtime above HASH_MAX_BYTES), would be lost; so would
    anything in one of its parts that fails the same check. A directory that
    another wearcheck process is writing inside it makes it busy; one left by
    a process that died on this host is wearcheck's own debris. An output
    without an inventory (written by an older wearcheck) cannot be checked
    and is not replaced.
    """
    try:
        fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY)
    except (FileNotFoundError, NotADirectoryError):
        return None
    try:
        why = _foreign(fd, str(directory))
        # a concurrent writer may have moved this directory aside (and emptied
        # it) while it was read: then the verdict is about a directory that is
        # no longer there, and the caller looks again (FileNotFoundError). The
        # open descriptor keeps its inode from being reused meanwhile.
        st = os.fstat(fd)
        if st.st_nlink == 0 or os.lstat(directory).st_ino != st.st_ino:
            raise FileNotFoundError(directory)
        return why
    finally:
        os.close(fd)


def _foreign(fd: int, name: str) -> str | None:
    marker = _marker_at(fd) or {}
    recorded = marker.get("files")
    if not isinstance(recorded, dict):
        return (f"output '{name}' was written by an older wearcheck that kept no list of "
                "its files, so it cannot tell whether you added any; remove it yourself or "
                "choose another output path")
    now, nested, partials = {}, [], []
    try:
        _walk(fd, "", now, nested, marker.get("kind"), partials)
        for rel, pm in partials:
            if left_behind(rel.rpartition("/")[2], pm):
                continue              # left by a wearcheck process that died: debris
            pid = pm.get("pid")
            return (f"output '{name}' is being written into by wearcheck process {pid} on "
                    f"{pm.get('host')} ({_shown([rel])}); try again when it has finished")
        added = [k for k in now if k not in recorded]
        changed = [k for k in now if k in recorded and not _same(now[k], recorded[k])]
        for what, names in (("holds files wearcheck did not write", added),
                            ("holds files changed since wearcheck wrote them", changed)):
            if names:
                return (f"output '{name}' {what} ({_shown(names)}); replacing it would lose "
                        "them: move them out or choose another output path")
        for rel, sub in nested:
            why = _foreign(sub, f"{name}/{rel}")
            if why:
                return why
        return None
    finally:
        for _, sub in nested:
            os.close(sub)


def read_marker(directory: Path) -> dict | None:
    """The marker of ``directory`` as a dict, or None when it has none (or it is not ours)."""
    path = Path(directory) / OUTPUT_MARKER
    try:
        if path.is_symlink() or not path.is_file():
            return None
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    return _parse_marker(text)


def _kind_name(kind) -> str:
    return {"legacy": "output (of an older wearcheck)"}.get(kind, str(kind))


def refusal(path: Path, kind: str) -> str | None:
    """Why the existing ``path`` may not be replaced by a ``kind`` output; None if it may."""
    # concurrent writers swap the directory at ``path`` under us: a verdict
    # counts only if the same directory (inode) was there before and after
    why = None
    for _ in range(100):
        try:
            before = os.lstat(path).st_ino
        except (FileNotFoundError, NotADirectoryError):
            return None
        try:
            why = _refusal(path, kind)
        except (FileNotFoundError, NotADirectoryError):
            continue
        try:
            if os.lstat(path).st_ino == before:
                return why
        except (FileNotFoundError, NotADirectoryError):
            return None
    return why


def _refusal(path: Path, kind: str) -> str | None:
    if path.is_symlink():
        return (f"output '{path}' is a symbolic link; give the real path (wearcheck does not "
                "write through or replace links)")
    if not path.exists():
        return None
    if not path.is_dir():
        return (f"output '{path}' exists and is not a wearcheck output (it is a file); "
                "choose another output path or remove it yourself")
    marker = read_marker(path)
    if marker is None:
        if not any(path.iterdir()):
            return None
        return (f"output '{path}' exists and is not a wearcheck output (no "
                f"{OUTPUT_MARKER} marker); choose another output path or remove it yourself")
    if not marker.get("complete", True):
        return (f"output '{path}' is an incomplete wearcheck output; remove it yourself "
                "or choose another path")
    have = marker.get("kind")
    if have == kind and kind == "study":
        return None          # a study directory is reused, never replaced
    if have == kind or (have == "legacy" and kind in ("run", "comparison")):
        return foreign_content(path)
    return (f"output '{path}' is a wearcheck {_kind_name(have)} directory, not a {kind}; "
            "choose another output path or remove it yourself")


def check_output(path, kind: str) -> Path:
    """Check that ``path`` can take a ``kind`` output, before any work; returns it absolute.

    Refused (:class:`OutputError`, one line): a final component ``.`` or
    ``..``, a symbolic link, an existing path that is not a complete
    wearcheck output of this kind (an empty directory is fine), a path under
    a file, and a directory wearcheck cannot create or write.
    """
    raw = str(path)
    parts = Path(raw).parts
    if not raw or raw.endswith(os.sep + ".") or (parts and parts[-1] in (".", "..")) \
            or raw in (".", ".."):
        raise OutputError(f"output '{raw}': name a directory or file of its own, not "
                          "'.' or '..'")
    given = Path(raw).absolute()
    _check_name_length(raw, given)
    for part in [*reversed(given.parents), given]:
        if part.is_symlink() and not part.exists():
            raise OutputError(f"output '{raw}': '{part}' is a broken symbolic link; "
                              "wearcheck does not write through it")
    # the parent as the kernel resolves it ('..' after a link goes where the link leads)
    path = Path(os.path.realpath(given.parent)) / given.name
    why = _inside_output(path, kind) or refusal(path, kind)
    if why:
        raise OutputError(why)
    if kind != "study" and not path.is_symlink() and path.is_dir():
        _refuse_working_directory(path)
    if kind != "study" and not path.is_symlink() and path.is_dir() and os.path.ismount(path):
        # a run or comparison is renamed into place whole, which a mount point cannot
        # take (EBUSY, found only after the solve); a study is written into DIR in place
        raise OutputError(f"output '{path}' is a mount point, which wearcheck cannot replace "
                          f"by its finished output; give a directory inside it, e.g. "
                          f"'{path / 'run'}'")
    if not path.is_symlink() and path.exists():
        why = _pinned(path, whole=kind != "study")
        if why:
            raise OutputError(why)
    _check_writable_ancestor(path, inside=kind == "study")
    return path


#: the longest name wearcheck writes beside an output NAME: '.NAME.partial-' and
#: mkdtemp's 8 characters (a file's side marker '.NAME.wearcheck-output' is as long)
_HIDDEN_EXTRA = len("..partial-") + 8
#: the same for a file wearcheck replaces (:func:`write_file`): its temporary
#: '.NAME.partial-PID@HOST@XXXXXXXX' (:func:`wearcheck.temporaries.new`, a pid of up to 7 digits)
_FILE_HIDDEN_EXTRA = len("..partial-") + 7 + 1 + 8 + 1 + 8
#: room kept below PATH_MAX for the deepest file inside an output
#: ('<solver>/vtk/.vtk.partial-XXXXXXXX/solid_stage000.vtu' and the like)
_INNER_PATH = 120


def _limits(path: Path) -> tuple[int, int]:
    """(NAME_MAX, PATH_MAX) of the file system that holds (or will hold) ``path``."""
    ancestor = path.parent
    while True:
        try:
            os.stat(ancestor)
            break
        except OSError:
            if ancestor == ancestor.parent:
                break
            ancestor = ancestor.parent
    try:
        return os.pathconf(ancestor, "PC_NAME_MAX"), os.pathconf(ancestor, "PC_PATH_MAX")
    except (OSError, ValueError):
        return 255, 4096


def _check_name_length(raw: str, path: Path, extra: int = _HIDDEN_EXTRA) -> None:
    """Refuse, before any work, a name the file system would refuse only when the output
    is written: a component, or the output's hidden sibling (``extra`` bytes longer),
    or the whole path too long."""
    name_max, path_max = _limits(path)
    for part in path.parts[1:-1]:
        if len(os.fsencode(part)) > name_max:
            raise OutputError(f"output '{raw}': the directory name '{part[:40]}...' is "
                              f"{len(os.fsencode(part))} bytes; this file system takes names "
                              f"of at most {name_max}")
    n = len(os.fsencode(path.name))
    if n + extra > name_max:
        raise OutputError(f"output '{raw[:60]}...': its name is {n} bytes, and wearcheck "
                          f"writes it through a hidden '.NAME.partial-...' beside it, "
                          f"{extra} bytes longer; this file system takes names of at "
                          f"most {name_max} bytes: give a name of at most "
                          f"{name_max - extra} bytes")
    total = len(os.fsencode(str(path))) + extra + _INNER_PATH
    if total > path_max:
        raise OutputError(f"output '{raw[:60]}...': the path is {len(os.fsencode(str(path)))} "
                          f"bytes, and the files inside the output would pass the system's "
                          f"limit of {path_max} bytes for a path: give a path of at most "
                          f"{path_max - extra - _INNER_PATH} bytes")


#: Linux inode flags (``chattr``): the file or directory cannot be changed, or
#: only appended to; either way it cannot be renamed or removed
_FS_IOC_GETFLAGS = 0x80006601 | (struct.calcsize("l") << 16)
_PINNING_FLAGS = {0x10: "immutable (chattr +i)", 0x20: "append-only (chattr +a)"}


def _inode_flags(path) -> int:
    """The ``chattr`` flags of a directory or regular file; 0 where unknown."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0))
    except OSError:
        return 0
    try:
        return int.from_bytes(fcntl.ioctl(fd, _FS_IOC_GETFLAGS, bytes(8))[:4], sys.byteorder)
    except (OSError, ValueError):
        return 0          # a file system without the flags (tmpfs, NFS), or not Linux
    finally:
        os.close(fd)


def _pinned(path: Path, whole: bool = True) -> str | None:
    """Why wearcheck could not replace (``whole``: or remove the contents of) the existing
    ``path``: it, or something in it, is immutable or append-only."""
    if fcntl is None:
        return None
    todo = [path]
    if whole and path.is_dir():
        for root, dirs, files in os.walk(path):
            todo += [Path(root) / n for n in dirs + files]
    for item in todo:
        try:
            if item.is_symlink() or not (item.is_dir() or item.is_file()):
                continue
        except OSError:
            continue
        flags = _inode_flags(item)
        for bit, what in _PINNING_FLAGS.items():
            if flags & bit:
                where = "it is" if item == path else f"'{item}' in it is"
                return (f"output '{path}': {where} {what}, so wearcheck could not replace "
                        f"it; clear the flag (chattr -{what[-2]} ...) or choose another "
                        "output path")
    return None


def _refuse_working_directory(path: Path) -> None:
    """An output replaces its directory by a new one: never the one this shell is in.

    ``--out "$PWD"`` (``.`` is refused by name) wrote the run, but the shell it
    was typed in stayed in the replaced, deleted directory, where ``ls`` shows
    nothing and ``wearcheck export .`` fails.
    """
    try:
        cwd = Path(os.getcwd()).resolve()
    except OSError:
        return
    real = path.resolve()
    if cwd == real or real in cwd.parents:
        raise OutputError(f"output '{path}' is the working directory (or holds it); "
                          "wearcheck replaces its output directory by a new one, which would "
                          "leave this shell in a deleted directory: give a directory of its "
                          "own, e.g. 'runs/NAME'")


def _inside_output(path: Path, kind: str) -> str | None:
    """Why ``path`` may not be written where it lies: inside another wearcheck output.

    A re-run of that output replaces it whole, and with it anything written
    inside; only its own parts are allowed (a run's ``vtk/`` and ``render/``,
    a study's runs) and this process's own directory being written.
    """
    for ancestor in path.parents:
        marker = read_marker(ancestor)
        if marker is None:
            continue
        have = marker.get("kind")
        if marker.get("complete", True) is False:
            if marker.get("pid") == os.getpid() and marker.get("host") == platform.node():
                return None      # this process's output being written (run --vtk)
            return (f"output '{path}' lies inside '{ancestor}', a wearcheck output being "
                    "written or left incomplete; choose a path outside it")
        if _is_part(have, kind, len(path.relative_to(ancestor).parts), path.name):
            return None
        return (f"output '{path}' lies inside the wearcheck {_kind_name(have)} '{ancestor}', "
                "which a re-run replaces whole; choose a path outside it")
    return None


def left_behind(name: str, marker: dict) -> bool:
    """Whether the hidden directory ``name`` (a ``.NAME.partial-*`` or ``.NAME.old-*``)
    with ``marker`` is what a writer that is gone left behind.

    Its writer (the marker's pid) no longer runs on this host. A complete output
    in another's place (its marker names the ``.partial-*`` it was itself built
    in) is an earlier output that a replacement exchanged out of the path:
    the replacing process (``aside_by``) must be gone.
    """
    writer = marker
    if marker.get("complete", True) and marker.get("built_in") not in (None, name):
        writer = marker.get("aside_by")
        if not isinstance(writer, dict):
            return True   # killed right after the exchange, before it said whose it is
    pid = writer.get("pid")
    return writer.get("host") == platform.node() and isinstance(pid, int) \
        and not temporaries.pid_alive(pid)


def _siblings(path: Path) -> list[Path]:
    """The ``.NAME.partial-*`` and ``.NAME.old-*`` directories beside ``path``."""
    try:
        entries = list(path.parent.iterdir())
    except OSError:
        return []
    return sorted(e for e in entries
                  if (e.name.startswith(f".{path.name}.partial-")
                      or e.name.startswith(f".{path.name}.old-"))
                  and not e.is_symlink() and e.is_dir())


def recover(path) -> list[Path]:
    """Put right what writers of ``path`` that were killed left beside it.

    Only wearcheck's own hidden siblings are touched (a marker), and only those
    :func:`left_behind`:

    - ``.NAME.old-*`` holds the earlier output moved aside (a file system without
      an atomic exchange, see :func:`_install`): if ``path`` is missing it goes
      back there, otherwise it is removed;
    - ``.NAME.partial-*``, complete or not, is removed: a new output that was
      being written, or whose installation the kill stopped (``path`` still
      holds the earlier one), or the earlier one exchanged out of ``path``
      (which holds the new one).

    A complete output holding a file wearcheck did not write (its inventory) is
    left where it is. Returns the directories removed.
    """
    path = Path(path)
    removed = []
    for entry in _siblings(path):
        marker = read_marker(entry)
        if marker is None or not left_behind(entry.name, marker):
            continue
        if entry.name.startswith(f".{path.name}.old-"):
            _settle_graveyard(entry, path)
            if not entry.exists():
                removed.append(entry)
        else:
            done = _remove_unless_foreign(entry)
            if done == "removed":
                removed.append(entry)
            elif done == "foreign":
                _keep_in_sight(entry, path)
    return removed


def _keep_in_sight(entry: Path, path: Path) -> Path | None:
    """A hidden earlier output holding files that reached it while it was replaced
    (the writer was killed before it could put it back): renamed to a visible
    ``NAME.kept-N`` beside ``path``, for the user to take the files from."""
    for n in range(1, 1000):
        keep = path.with_name(f"{path.name}.kept-{n}")
        try:
            renames.rename_noreplace(entry, keep)
        except FileExistsError:
            continue
        except OSError:
            if os.path.lexists(keep):
                continue
            try:
                os.rename(entry, keep)
            except OSError:
                return None
        return keep
    return None


def clean_stale(parent: Path, name: str) -> list[Path]:
    """:func:`recover` of ``parent / name`` (the name of earlier versions)."""
    return recover(Path(parent) / name)


def _remove_unless_foreign(directory: Path, checked: bool = False) -> str:
    """Remove a wearcheck directory, unless it is a complete output holding files
    wearcheck did not write (``checked``: already known not to).

    Returns "removed", "foreign", or "busy" (no marker, gone meanwhile, or being
    removed by another process, which marks it incomplete first).
    """
    marker = read_marker(directory)
    if marker is None:
        return "busy"
    if not checked and marker.get("complete", True):
        try:
            why = foreign_content(directory)
        except FileNotFoundError:
            return "busy"
        if why:
            now = read_marker(directory) or {}
            return "foreign" if now.get("complete", False) else "busy"
    remove_tree(directory)
    return "busy" if directory.exists() else "removed"


def remove_tree(directory: Path) -> None:
    """Remove ``directory``: first its marker says incomplete (this process's
    debris), and it goes last. A removal cut short by a kill leaves a directory
    that says whose it is and that it is no output, which :func:`recover` removes."""
    directory = Path(directory)
    marker = read_marker(directory)
    if marker is not None and marker.get("complete", True):
        with contextlib.suppress(OSError):
            _rewrite_marker(directory, dict(marker_data(marker.get("kind", "run"), False),
                                            removing=True))
    try:
        entries = sorted(os.scandir(directory), key=lambda e: e.name)
    except FileNotFoundError:
        return
    except OSError:
        shutil.rmtree(directory, ignore_errors=True)
        return
    first = True
    for e in entries:
        if e.name == OUTPUT_MARKER:
            continue
        if e.is_dir(follow_symlinks=False):
            shutil.rmtree(e.path, ignore_errors=True)
        else:
            with contextlib.suppress(FileNotFoundError, PermissionError):
                os.unlink(e.path)
        if first:
            first = False
            _step("retiring")
    with contextlib.suppress(OSError):
        os.unlink(directory / OUTPUT_MARKER)
    with contextlib.suppress(OSError):
        os.rmdir(directory)


def _settle_graveyard(graveyard: Path, path: Path, restore: bool = True) -> None:
    """Empty a ``.NAME.old-*`` directory of :func:`_install`'s fallback.

    It holds the earlier occupants of ``path``, moved aside as ``0``, ``1``, ...
    (one per attempt; concurrent writers may have installed several). With
    ``restore`` (the new output was not installed), when ``path`` is missing
    the last of them goes back there. The others are removed unless they hold
    files wearcheck did not write, which are kept in sight. The directory goes
    when it is empty.
    """
    held = []
    with contextlib.suppress(OSError):
        held = sorted((p for p in graveyard.iterdir() if p.name != OUTPUT_MARKER),
                      key=lambda p: (len(p.name), p.name))
    if restore and held and not os.path.lexists(path):
        marker = read_marker(held[-1])
        if marker is not None and marker.get("complete", True):
            with contextlib.suppress(OSError):
                os.rename(held[-1], path)
    for aside in held:
        if aside.is_dir() and not aside.is_symlink() \
                and _remove_unless_foreign(aside) == "foreign":
            _keep_in_sight(aside, path)
    with contextlib.suppress(OSError):
        if [p.name for p in graveyard.iterdir()] in ([], [OUTPUT_MARKER]):
            remove_tree(graveyard)


def is_partial(path: Path) -> bool:
    """A ``.partial`` directory of another process: being written, or abandoned.

    This process's own partial directory (e.g. ``run --vtk`` exporting the run
    it is writing) is not refused.
    """
    path = Path(path)
    marker = read_marker(path)
    if marker is not None and marker.get("complete", True) is False:
        return not (marker.get("pid") == os.getpid() and marker.get("host") == platform.node())
    return marker is None and path.name.startswith(".") and ".partial-" in path.name


#: the steps of replacing an output, in the order they happen; :func:`_step` marks
#: each, and the tests kill the writer at every one of them in turn
REPLACE_STEPS = ("built", "checked", "complete", "installed", "exchanged", "graveyard",
                 "aside", "retiring", "retired")
#: the steps of replacing a file of a study directory (:func:`write_study_file`)
STUDY_FILE_STEPS = ("study-file-listed", "study-file-replaced")
#: the steps of replacing a single file (``mesh --out FILE``, :func:`write_file`)
FILE_STEPS = ("file-listed", "file-replaced")
#: called with the name of each step when set (a test's kill); None in use
STEP_HOOK = None
#: devices (st_dev) whose file system refused an atomic exchange: plain renames there
_NO_EXCHANGE: set = set()


def _step(name: str) -> None:
    if STEP_HOOK is not None:
        STEP_HOOK(name)


def _occupant_refusal(path: Path, kind: str) -> str | None:
    """:func:`refusal` without reading the occupant's files: the kind of what is
    at ``path`` only (its content is checked once it is out of the way)."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return None
    if not stat.S_ISDIR(st.st_mode):
        return _refusal(path, kind)
    marker = read_marker(path)
    if marker is None or not marker.get("complete", True):
        return _refusal(path, kind)
    if marker.get("kind") == kind or (marker.get("kind") == "legacy"
                                      and kind in ("run", "comparison")):
        return None
    return _refusal(path, kind)


def _install(tmp: Path, path: Path, kind: str) -> None:
    """Put the complete output ``tmp`` in the place of ``path``, crash-safely.

    ``path`` holds the earlier output or the new one at every instant: the two
    are swapped in one step (``renameat2(RENAME_EXCHANGE)``); the earlier one,
    now at ``tmp``'s name, is checked for files that reached it since the
    check before (those go back with it, in a second swap) and removed, its
    marker last. A kill at any point leaves ``path`` whole, and the hidden
    sibling to :func:`recover`. Concurrent writers each swap atomically: the
    last one wins, nothing is lost, nothing fails.

    Where the file system cannot exchange (NFS, CIFS, FUSE), the earlier output
    is renamed into a private ``.NAME.old-*`` directory and the new one renamed
    into place: between the two renames ``path`` is missing, and a kill there
    leaves the earlier output in ``.NAME.old-*``, where :func:`recover` (the
    next write to, or read of, ``path``) puts it back.

    ``tmp`` is this function's from the call on: installed, or removed.
    """
    graveyard = None
    swapped = False       # tmp holds what was at path (after an exchange)
    checked = False       # ... and it holds nothing wearcheck did not write
    installed = False
    try:
        for attempt in range(100000):
            try:
                os.rename(tmp, path)  # path missing, or an empty directory
                installed = True
                _step("installed")
                return
            except OSError as exc:
                if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST, errno.ENOTDIR,
                                     errno.EISDIR):
                    raise
            why = _occupant_refusal(path, kind)
            if why:
                raise OutputError(why)
            if graveyard is None and os.stat(path.parent).st_dev not in _NO_EXCHANGE:
                try:
                    renames.exchange(tmp, path)
                except FileNotFoundError:
                    continue      # another writer moved it meanwhile
                except renames.Unsupported:
                    _NO_EXCHANGE.add(os.stat(path.parent).st_dev)
                else:
                    swapped = True
                    _step("exchanged")
                    _claim_aside(tmp)
                    checked = _check_swapped(tmp, path)
                    return
            if graveyard is None:
                graveyard = Path(tempfile.mkdtemp(prefix=f".{path.name}.old-",
                                                  dir=path.parent))
                write_marker(graveyard, kind, complete=False)
                _step("graveyard")
            aside = graveyard / f"{attempt}"
            try:
                os.rename(path, aside)
            except FileNotFoundError:
                continue          # another writer moved it first
            _step("aside")
            why = foreign_content(aside)
            if why:
                # files reached it while it was being replaced: it goes back
                try:
                    os.rename(aside, path)
                except OSError:
                    keep = path.with_name(f"{path.name}.kept-{os.getpid()}-{attempt}")
                    os.rename(aside, keep)
                    raise OutputError(f"output '{path}': files reached it while it was being "
                                      f"replaced; it was kept as '{keep}'") from None
                raise OutputError(why.replace(str(aside), str(path)))
        raise OSError(errno.EBUSY, f"could not install '{path}': too many concurrent writers")
    finally:
        if swapped:
            _remove_unless_foreign(tmp, checked=checked)
            _step("retired")
        elif tmp.exists():
            remove_tree(tmp)  # not installed: this process's own directory
        if graveyard is not None:
            _settle_graveyard(graveyard, path, restore=not installed)
            _step("retired")


def _claim_aside(aside: Path) -> None:
    """Say in the marker of the earlier output, just exchanged out of its path, which
    process moved it: :func:`recover` of another leaves it to that one while it runs."""
    marker = read_marker(aside)
    if marker is not None and marker.get("complete", True):
        with contextlib.suppress(OSError):
            _rewrite_marker(aside, dict(marker, aside_by=dict(pid=os.getpid(),
                                                              host=platform.node())))


def _check_swapped(aside: Path, path: Path) -> bool:
    """After the exchange: True if the earlier output, now at ``aside``, holds only what
    wearcheck wrote; otherwise swap it back into ``path`` and refuse (OutputError)."""
    try:
        why = foreign_content(aside)
    except FileNotFoundError:
        why, gone = None, True
    else:
        gone = not (read_marker(aside) or {}).get("complete", False)
    if gone:
        # another writer's recover() is removing it (remove_tree marks it
        # incomplete first, and it removes only an output holding nothing foreign)
        return False
    if not why:
        return True
    try:
        renames.exchange(aside, path)
    except FileNotFoundError:
        os.rename(aside, path)   # path went meanwhile
    raise OutputError(why.replace(str(aside), str(path)))


def _directory_stat(path: Path):
    """The stat of the directory at ``path`` that an output will replace, else None."""
    try:
        st = os.lstat(path)
    except OSError:
        return None
    return st if stat.S_ISDIR(st.st_mode) else None


def _take_permissions(tmp: Path, occupant, path: Path) -> None:
    """Give the new output the permissions, group and ACLs of the directory it replaces.

    An output replaces a directory by renaming a new one onto it; without this,
    an empty directory made ``chmod 700`` (or group-shared, or given to a
    colleague by ``setfacl``) for the results, or an output the user
    restricted after the run, would come back with the umask's mode, readable
    by everyone. The owner is left alone: the files inside are this process's.
    The ACLs are copied after the mode, which would otherwise rewrite the
    ACL's mask.
    """
    with contextlib.suppress(OSError):      # a group we are not in: keep ours
        if occupant.st_gid != os.stat(tmp).st_gid:
            os.chown(tmp, -1, occupant.st_gid)
    os.chmod(tmp, stat.S_IMODE(occupant.st_mode))
    _copy_attributes(path, tmp)


def _copy_attributes(path: Path, tmp: Path) -> None:
    """The extended attributes of ``path`` (its ACLs among them) onto ``tmp``,
    those this process may set (security.* labels need privileges: ``tmp``
    keeps its own)."""
    if not hasattr(os, "listxattr"):        # (not on macOS or Windows)
        return
    try:
        names = os.listxattr(path, follow_symlinks=False)
    except OSError:                         # a file system without them, or gone
        return
    for name in names:
        with contextlib.suppress(OSError):
            os.setxattr(tmp, name, os.getxattr(path, name, follow_symlinks=False),
                        follow_symlinks=False)


#: sets to which :func:`atomic_directory` adds the name of each directory it builds
#: an output in (:func:`watching_builds`)
_BUILD_WATCHERS: list[set] = []


@contextlib.contextmanager
def watching_builds():
    """Collect the names of the hidden directories :func:`atomic_directory` builds
    outputs in while inside; :func:`installed_from` then tells whether a path holds,
    complete, one of them (the command line: an interrupt that came after its output
    was in place says so)."""
    names: set = set()
    _BUILD_WATCHERS.append(names)
    try:
        yield names
    finally:
        _BUILD_WATCHERS.remove(names)


def installed_from(path, names) -> bool:
    """Whether ``path`` holds a complete output built in one of the hidden directories
    ``names`` (its marker names the directory it was built in)."""
    marker = read_marker(Path(path))
    return marker is not None and marker.get("complete") is True \
        and marker.get("built_in") in names


@contextlib.contextmanager
def atomic_directory(path, kind: str = "run"):
    """Yield a fresh temporary directory that replaces ``path`` on success.

    On an exception (or interrupt) the temporary directory is removed and
    ``path`` is left as it was. An existing ``path`` that is not a complete
    wearcheck output of ``kind`` is refused (:class:`OutputError`), never deleted.
    """
    if kind not in KINDS:
        raise ValueError(f"unknown output kind {kind!r}")
    path = check_output(path, kind)
    path.parent.mkdir(parents=True, exist_ok=True)
    recover(path)
    occupant = _directory_stat(path)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.partial-", dir=path.parent))
    for names in list(_BUILD_WATCHERS):
        names.add(tmp.name)
    handed_over = False
    try:
        os.chmod(tmp, 0o777 & ~temporaries.umask())  # mkdtemp: 0700; outputs are shared
        if occupant is not None:
            # now, so that a default ACL of the directory replaced reaches the
            # files written into the new one, as it would have there
            _copy_attributes(path, tmp)
        write_marker(tmp, kind, complete=False, built_in=tmp.name)
        yield tmp
        _step("built")
        # the occupant's files are read (hashed) while this output still says it is
        # incomplete: a kill during the check leaves nothing that looks complete
        why = refusal(path, kind)
        if why:
            raise OutputError(why)
        _step("checked")
        occupant = _directory_stat(path)
        if occupant is not None:
            _take_permissions(tmp, occupant, path)
        write_marker(tmp, kind, complete=True, files=inventory(tmp, kind), built_in=tmp.name)
        _step("complete")
        handed_over = True
        _install(tmp, path, kind)
    except BaseException:
        if not handed_over:
            remove_tree(tmp)
        raise


#: the study directories this process holds locked: {real path: [descriptor, depth]}
_STUDY_LOCKS: dict = {}
_STUDY_LOCKS_GUARD = threading.RLock()


@contextlib.contextmanager
def study_lock(study):
    """Hold the study directory ``study`` for this process alone (``flock`` of the
    directory; re-entrant within the process).

    Studies write into their directory in place, reading what is there first (the
    marker's list of files, ``meta.json``, an earlier ``sweep.csv``): two studies
    into one directory at once would each write what it read plus its own, and
    the last would drop the other's. Under the lock each reads what the other
    wrote. Where the file system has no locks (some NFS) it goes unlocked.
    """
    key = os.path.realpath(study)
    with _STUDY_LOCKS_GUARD:
        held = _STUDY_LOCKS.get(key)
        if held is not None:
            held[1] += 1
    if held is None:
        fd = os.open(key, os.O_RDONLY | os.O_DIRECTORY)
        if fcntl is not None:
            with contextlib.suppress(OSError):
                fcntl.flock(fd, fcntl.LOCK_EX)
        with _STUDY_LOCKS_GUARD:
            _STUDY_LOCKS[key] = held = [fd, 1]
    try:
        yield
    finally:
        with _STUDY_LOCKS_GUARD:
            held[1] -= 1
            if held[1] == 0:
                del _STUDY_LOCKS[key]
                os.close(held[0])       # releases the flock


def study_directory(path, runs=(), files=()) -> Path:
    """Create (or reuse) the study directory ``path`` of ``wearcheck refine``/``sweep``.

    A new or empty directory gets a ``study`` marker; an existing one must
    already be a wearcheck study, the files the studies wrote into it
    (:func:`write_study_file`) as they wrote them, each of ``files`` (the
    names this study will write there) absent or one of those, and each of
    ``runs`` (the names of its run directories) absent or a run it may
    replace: all checked here, before any work. Its runs are written
    inside, each atomically.
    """
    path = check_output(path, "study")
    for run in runs:      # before anything is made: a new study directory too
        _check_name_length(str(path / run), path / run)
    path.mkdir(parents=True, exist_ok=True)
    marker = read_marker(path)
    if marker is None:
        write_marker(path, "study", complete=True, files={})
        return path
    recorded = marker.get("files")
    if not isinstance(recorded, dict):
        raise OutputError(f"study '{path}' was written by an older wearcheck that kept no list "
                          "of its files, so it cannot tell whether you changed any; remove it "
                          "yourself or choose another output path")
    # the study's files (and its marker) half written by a study that was killed
    temporaries.remove_dead(path)
    for name in sorted({*recorded, *files}):
        if (path / name).exists() or (path / name).is_symlink():
            _check_study_file(path, name, recorded, marker)
    for run in runs:
        why = refusal(path / run, "run") or (
            _pinned(path / run) if (path / run).is_dir() else None)
        if why:
            raise OutputError(why)
    return path


def _path_fingerprint(path: Path) -> list:
    fd = os.open(path.parent, os.O_RDONLY | os.O_DIRECTORY)
    try:
        return _fingerprint(fd, path.name, os.stat(path.name, dir_fd=fd, follow_symlinks=False))
    finally:
        os.close(fd)


def _check_study_file(study: Path, name: str, recorded: dict, marker=None) -> None:
    """``study/name`` exists: it must be a file the studies wrote there, unchanged since
    (or the one a write killed half-way was replacing: the marker's ``replacing``)."""
    path = study / name
    before = ((marker or {}).get("replacing") or {}).get(name) \
        if isinstance((marker or {}).get("replacing"), dict) else None
    if path.is_symlink() or not path.is_file() or name not in recorded:
        ok = False
    else:
        now = _path_fingerprint(path)
        ok = _same(now, recorded[name]) or (before is not None and _same(now, before))
    if not ok:
        raise OutputError(f"'{path}' is not a file wearcheck wrote into this study, or it "
                          "changed since; move it out (or rename it) and run again")


def write_study_file(study, name: str, write) -> Path:
    """Write the file ``study/name`` by ``write(temporary path)``, atomically.

    Only a file this study directory's marker lists, unchanged since, is
    replaced; the marker then lists the new one. Never written through a link.
    """
    study = Path(study)
    with study_lock(study):
        return _write_study_file(study, name, write)


def _write_study_file(study: Path, name: str, write) -> Path:
    path = study / name
    marker = read_marker(study) or marker_data("study", True)
    recorded = marker.get("files") if isinstance(marker.get("files"), dict) else {}
    current = None        # the fingerprint of the file this write replaces
    if path.exists() or path.is_symlink():
        _check_study_file(study, name, recorded, marker)
        current = _path_fingerprint(path)
    # (the suffix kept: writers choose the format by it, e.g. a figure's .png)
    tmp = temporaries.new(study, name, Path(name).suffix)
    try:
        write(Path(tmp))
        os.chmod(tmp, 0o666 & ~temporaries.umask())  # mkstemp makes 0600; study files are shared
        # the marker lists the new file before it takes the old one's place, and keeps
        # the old one's as it is replaced: a kill in between leaves a file the
        # marker accepts (either), never one a later study refuses as not its own
        new = _path_fingerprint(Path(tmp))
        replacing = marker.get("replacing") if isinstance(marker.get("replacing"), dict) \
            else {}
        replacing.pop(name, None)
        if current is not None:
            # what is on disk, not what the marker listed: an earlier write that
            # failed after listing its file left the old one in place
            replacing[name] = current
        _rewrite_marker(study, dict(marker, files=dict(recorded, **{name: new}),
                                    replacing=replacing))
        _step("study-file-listed")
        os.replace(tmp, path)
        _step("study-file-replaced")
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    recorded[name] = new
    replacing.pop(name, None)
    _rewrite_marker(study, dict(marker, files=recorded, replacing=replacing))
    return path


def write_study_text(study, name: str, text: str) -> Path:
    """:func:`write_study_file` of a UTF-8 text."""
    return write_study_file(study, name, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def remove_study_file(study, name: str) -> bool:
    """Remove ``study/name`` if the study wrote it and it is unchanged; else leave it."""
    study = Path(study)
    with study_lock(study):
        return _remove_study_file(study, name)


def _remove_study_file(study: Path, name: str) -> bool:
    marker = read_marker(study) or {}
    recorded = marker.get("files") if isinstance(marker.get("files"), dict) else {}
    path = study / name
    if not (path.exists() or path.is_symlink()):
        return False
    try:
        _check_study_file(study, name, recorded, marker)
    except OutputError:
        return False
    path.unlink()
    recorded.pop(name, None)
    replacing = marker.get("replacing") if isinstance(marker.get("replacing"), dict) else {}
    replacing.pop(name, None)
    _rewrite_marker(study, dict(marker, files=recorded, replacing=replacing))
    return True


def _rewrite_marker(directory: Path, data: dict) -> None:
    tmp = temporaries.new(Path(directory), OUTPUT_MARKER[1:])
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(json.dumps(data) + "\n")
    os.chmod(tmp, 0o666 & ~temporaries.umask())
    os.replace(tmp, Path(directory) / OUTPUT_MARKER)


def remove_output(path: Path, kind: str) -> bool:
    """Remove ``path`` if, and only if, it is a complete wearcheck output of ``kind``
    holding nothing but what wearcheck wrote (:func:`foreign_content`)."""
    path = Path(path)
    if path.is_symlink() or not path.is_dir():
        return False
    marker = read_marker(path)
    if marker is None or marker.get("kind") != kind or not marker.get("complete", True):
        return False
    try:
        if foreign_content(path):
            return False
    except FileNotFoundError:
        return False
    shutil.rmtree(path)
    return True


# -- single files (wearcheck mesh --out FILE) --------------------------------

def _sidecar(path: Path) -> Path:
    return path.with_name(f".{path.name}{OUTPUT_MARKER}")


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def check_output_file(path, kind: str = "mesh") -> Path:
    """Check that the file ``path`` may be (over)written; returns it absolute.

    An existing file is replaceable only if wearcheck wrote it and it is
    unchanged since: its side marker ``.NAME.wearcheck-output`` names the kind
    and the SHA-256 of the content.
    """
    path = check_output_path_common(path)
    why = _inside_output(Path(os.path.realpath(path.parent)) / path.name, kind)
    if why:
        raise OutputError(why)
    side = _sidecar(path)
    if side.is_symlink() or (side.exists() and not side.is_file()):
        raise OutputError(f"output '{path}': its side marker '{side}' exists and is not a "
                          "regular file; remove it yourself or choose another output path")
    if side.exists():
        data = None
        with contextlib.suppress(OSError, ValueError):
            data = json.loads(side.read_text(encoding="utf-8"))
        if not (isinstance(data, dict) and data.get("wearcheck") == "output"):
            raise OutputError(f"output '{path}': '{side}' exists and is not a wearcheck side "
                              "marker; remove it yourself or choose another output path")
    if path.is_symlink():
        raise OutputError(f"output '{path}' is a symbolic link; give the real path")
    if path.is_dir():
        raise OutputError(f"output '{path}' is a directory; give the path of the file")
    if path.exists():
        if not path.is_file():
            raise OutputError(f"output '{path}' exists and is not a regular file; "
                              "choose another output path")
        ok = False
        side = _sidecar(path)
        with contextlib.suppress(OSError, ValueError):
            data = json.loads(side.read_text(encoding="utf-8"))
            # "replacing": the file a write killed half-way was replacing (write_file)
            ok = (isinstance(data, dict) and data.get("kind") == kind
                  and _sha256(path) in (data.get("sha256"), data.get("replacing")))
        if not ok:
            raise OutputError(f"output '{path}' exists and is not a file wearcheck wrote "
                              "(or it has changed since); choose another output path or "
                              "remove it yourself")
    return path


def check_output_path_common(path) -> Path:
    raw = str(path)
    if raw.endswith(os.sep) and raw.strip(os.sep):
        raise OutputError(f"output '{raw}' ends with '{os.sep}', a directory; give the path "
                          f"of the file, e.g. '{raw}sphere.msh'")
    if not raw or Path(raw).name in ("", ".", "..") or raw.endswith(os.sep):
        raise OutputError(f"output '{raw}': name a file of its own")
    path = Path(raw).absolute()
    _check_name_length(raw, path, _FILE_HIDDEN_EXTRA)
    if path.is_file() and not path.is_symlink():
        why = _pinned(path, whole=False)
        if why:
            raise OutputError(why)
    _check_writable_ancestor(path)
    return path


def write_file(path, source: Path, kind: str = "mesh") -> Path:
    """Copy ``source`` to ``path`` atomically, with its side marker."""
    path = check_output_file(path, kind)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporaries.remove_dead(path.parent, [path.name])    # of a write that was killed
    tmp = temporaries.new(path.parent, path.name)
    try:
        shutil.copyfile(source, tmp)
        os.chmod(tmp, 0o666 & ~temporaries.umask())
        side = dict(marker_data(kind, True), sha256=_sha256(Path(tmp)))
        # the side marker names the new file before it takes the old one's place, and
        # the old one's until it has: a kill in between leaves a file it accepts
        old = _sha256(path) if path.is_file() and not path.is_symlink() else None
        _write_sidecar(path, dict(side, replacing=old) if old else side)
        _step("file-listed")
        os.replace(tmp, path)
        _step("file-replaced")
        if old:
            _write_sidecar(path, side)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    return path


def _write_sidecar(path: Path, data: dict) -> None:
    """The side marker of ``path`` by rename: never half written, never written
    through a link put in its place."""
    stmp = temporaries.new(path.parent, path.name)
    try:
        with open(stmp, "w", encoding="utf-8") as fh:
            fh.write(json.dumps(data) + "\n")
        # mkstemp makes 0600: others sharing the file could not read that wearcheck wrote it
        os.chmod(stmp, 0o666 & ~temporaries.umask())
        os.replace(stmp, _sidecar(path))
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(stmp)
        raise


def _check_writable_ancestor(path: Path, inside: bool = False) -> None:
    """The nearest existing ancestor of ``path`` must be a directory we can write into
    (``inside``: ``path`` itself when it exists, as a study is written into)."""
    ancestor = path if inside and path.is_dir() else path.parent
    while not ancestor.exists() and not ancestor.is_symlink():
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise OutputError(f"output '{path}': '{ancestor}' is not a directory (it is a file or "
                          "a broken link), so nothing can be written under it")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise OutputError(f"output '{path}': directory '{ancestor}' is not writable "
                          "(permissions or a read-only file system)")
    # access() answers for the permission bits only: root passes them everywhere, and
    # /proc, /sys or a file system that refuses new entries fail only when written,
    # after the solve. A directory made and removed at once asks the file system.
    # The probe has the name of the hidden directory the output is written through
    # (file systems with a shorter limit on names refuse it here).
    prefix = ".wearcheck-probe-" if ancestor == path else f".{path.name}.partial-"
    try:
        os.rmdir(tempfile.mkdtemp(prefix=prefix, dir=ancestor))
    except OSError as exc:
        if exc.errno == errno.ENAMETOOLONG:
            raise OutputError(f"output '{path}': the file system refuses the name of the "
                              f"hidden '.{path.name[:20]}....partial-XXXXXXXX' it is written "
                              "through; give a shorter name") from None
        raise OutputError(f"output '{path}': nothing can be created in '{ancestor}' "
                          f"({exc.strerror or exc})") from None
