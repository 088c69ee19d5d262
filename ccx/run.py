"""Running CalculiX: finding it, its version, one job in a work directory, its failures.

A CalculiX job is a deck (:mod:`ccx.deck`) run as ``ccx -i JOB`` in a fresh
directory with one thread (CalculiX takes every core unless told, and the
solvers here run beside others). CalculiX reports failure inconsistently: an
``*ERROR`` line in its standard output, return code 201, a crash (139, 255),
or, for some errors (an input file it cannot open), return code 0: a job
counts as failed on a non-zero return code, on any ``*ERROR`` line or when it
wrote no .dat file. A failed job's directory is kept and named in the error.
Every deck a solve ran is recorded (:class:`Jobs`) and written into the run
directory (:func:`write_decks`).
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from wearcheck.cases import RunResult, SolverError

from .deck import MODEL_FILE
from .output import read_frd

#: oldest CalculiX this package was built and checked with
MINIMUM_VERSION = (2, 20)
#: one thread for every parallel part of CalculiX
THREAD_VARIABLES = ("OMP_NUM_THREADS", "CCX_NPROC_EQUATION_SOLVER", "CCX_NPROC_RESULTS",
                    "CCX_NPROC_STIFFNESS", "NUMBER_OF_CPUS")
#: longest one job may take [s] before it is stopped
TIMEOUT = 3600.0
#: the install line the messages give
INSTALL = ("install CalculiX: 'apt-get install calculix-ccx' on Debian and Ubuntu, "
           "'conda install -c conda-forge calculix' elsewhere (docs/ccx.md)")


def find(executable: str) -> str | None:
    """The full path of ``executable`` (a command on PATH or a path), or None."""
    if not executable:
        return None
    return shutil.which(executable)


@functools.lru_cache(maxsize=8)
def _version(path: str, mtime: float) -> tuple[int, int] | None:
    try:
        done = subprocess.run([path, "-v"], capture_output=True, text=True, timeout=30,
                              env=_environment())
    except (OSError, subprocess.SubprocessError):
        return None
    m = re.search(r"Version\s+(\d+)\.(\d+)", done.stdout + done.stderr)
    return (int(m.group(1)), int(m.group(2))) if m else None


def version(path: str) -> tuple[int, int] | None:
    """(major, minor) of the CalculiX at ``path`` (``ccx -v``), None if it does not say."""
    try:
        mtime = os.stat(path).st_mtime
    except OSError:
        return None
    return _version(path, mtime)


def unavailable(executable: str) -> str | None:
    """None when ``executable`` is a CalculiX of version 2.20 or later, else why not."""
    path = find(executable)
    if path is None:
        return (f"key 'ccx.executable' = \"{executable}\": no such command or file "
                f"(CalculiX is not installed or not on PATH); {INSTALL}")
    found = version(path)
    if found is None:
        return (f"key 'ccx.executable' = \"{executable}\": '{path}' does not answer "
                "'-v' with a CalculiX version; is it CalculiX's ccx?")
    if found < MINIMUM_VERSION:
        need = ".".join(map(str, MINIMUM_VERSION))
        return (f"'{path}' is CalculiX {found[0]}.{found[1]}; wearcheck needs {need} or "
                f"later; {INSTALL}")
    return None


def _environment() -> dict:
    env = dict(os.environ)
    env.update({name: "1" for name in THREAD_VARIABLES})
    return env


@dataclass
class Job:
    """One finished CalculiX job: its deck, .dat text, .frd nodal results (when kept),
    standard output and cost."""

    name: str
    deck: str
    dat: str
    frd: list | None
    stdout: str
    seconds: float


@dataclass
class Jobs:
    """The decks of a solve, in the order they ran, with the model they include."""

    executable: str
    model: str
    decks: dict = field(default_factory=dict)
    seconds: dict = field(default_factory=dict)

    def run(self, name: str, deck: str, *, keep_frd: bool = False) -> Job:
        """Run ``deck`` as job ``name`` in a fresh directory; the outputs parsed by the caller.

        With ``keep_frd`` the .frd file's nodal results are read
        (:func:`ccx.output.read_frd`) before the directory goes.
        Raises SolverError on failure, naming the kept directory.
        """
        workdir = Path(tempfile.mkdtemp(prefix=f"wearcheck-ccx-{name}-"))
        (workdir / MODEL_FILE).write_text(self.model, encoding="ascii")
        (workdir / f"{name}.inp").write_text(deck, encoding="ascii")
        t0 = time.perf_counter()
        try:
            done = subprocess.run([self.executable, "-i", name], cwd=workdir,
                                  capture_output=True, text=True, errors="replace",
                                  timeout=TIMEOUT, env=_environment())
        except subprocess.TimeoutExpired:
            raise SolverError(f"CalculiX job '{name}' ran longer than {TIMEOUT:g} s and was "
                              f"stopped; its files are in {workdir}") from None
        except OSError as exc:
            raise SolverError(f"CalculiX ('{self.executable}') could not be started: "
                              f"{exc}") from None
        seconds = time.perf_counter() - t0
        self.decks[f"{name}.inp"] = deck
        self.seconds[name] = seconds
        failure = failure_of(done.returncode, done.stdout)
        dat = workdir / f"{name}.dat"
        if failure is None and not dat.is_file():
            failure = "it wrote no .dat file"
        if failure is not None:
            (workdir / f"{name}.stdout").write_text(done.stdout + done.stderr)
            raise SolverError(f"CalculiX job '{name}' failed: {failure}; deck, output and "
                              f"CalculiX's messages ({name}.stdout) are in {workdir}")
        frd = read_frd(workdir / f"{name}.frd")[1] if keep_frd else None
        job = Job(name=name, deck=deck, dat=dat.read_text(errors="replace"), frd=frd,
                  stdout=done.stdout, seconds=seconds)
        shutil.rmtree(workdir, ignore_errors=True)
        return job


def failure_of(returncode: int, stdout: str) -> str | None:
    """Why a CalculiX job failed (from its return code and output), or None.

    CalculiX writes an error over two lines: the first three are quoted, each
    with its sequel.
    """
    lines = stdout.splitlines()
    errors = [i for i, line in enumerate(lines) if "*ERROR" in line]
    if errors:
        quoted = [" ".join(filter(None, [lines[i].strip(),
                                         lines[i + 1].strip() if i + 1 < len(lines) else ""]))
                  for i in errors[:3]]
        more = f" (and {len(errors) - 3} more)" if len(errors) > 3 else ""
        return f"return code {returncode}, " + "; ".join(quoted) + more
    if returncode != 0:
        return f"return code {returncode} without an *ERROR line (a crash?)"
    return None


@dataclass
class CcxResult(RunResult):
    """A RunResult that carries the decks of the CalculiX jobs behind it.

    ``decks``: file name -> text (``sphere.inp`` and one deck per job),
    written into the run directory's ``ccx/`` by :func:`write_decks`.
    """

    decks: dict = field(default_factory=dict)


def write_decks(directory, case, result) -> list[Path]:
    """Write a result's CalculiX decks into ``directory/ccx`` (the registry's run_report)."""
    decks = getattr(result, "decks", None)
    if not decks:
        return []
    folder = Path(directory) / "ccx"
    folder.mkdir(exist_ok=True)
    written = []
    for name, text in decks.items():
        path = folder / name
        path.write_text(text, encoding="ascii")
        written.append(path)
    return written
