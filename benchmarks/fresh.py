"""Timing commands in fresh processes, alternated with a baseline in the same run.

Shared by ``bench_startup.py`` and ``bench_paper.py``. Each round runs every
command once, in the order given, so a change of the machine's load during the
run falls on all of them alike; the table gives the median and the minimum of
each command's wall time and CPU time (user + system of the child) over the
rounds, and each command's ratio to the baseline (the first command) per
round, median and range. The load average is read before and after.

Every process gets Python's bytecode cache in a temporary folder, as an
installed package has its modules compiled: a ``PYTHONDONTWRITEBYTECODE`` in
the environment would otherwise compile wearcheck's modules from source in
every process (0.1-0.2 s of each start-up), which no user's install does.
The warm-up round fills it.
"""

from __future__ import annotations

import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class Timed:
    """One command's timings over the rounds, and what its parser read from each run."""

    name: str
    wall: list = field(default_factory=list)
    cpu: list = field(default_factory=list)
    extra: list = field(default_factory=list)


def run_once(cmd: list, env=None, cwd=None) -> tuple[float, float, str]:
    """Wall seconds, CPU seconds (user + system) and stdout of one fresh process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=cwd, timeout=3600)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} failed ({out.returncode}): "
                           f"{out.stderr.strip()[-500:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, out.stdout


def wearcheck_command(python: str | None = None) -> list:
    """The ``wearcheck`` console script of the environment of ``python`` (this
    interpreter by default), or ``python -m wearcheck`` where it is not installed."""
    python = python or sys.executable
    script = Path(python).with_name("wearcheck")
    return [str(script)] if script.exists() else [python, "-m", "wearcheck"]


def bytecode_env(cache: Path) -> dict:
    """This environment with Python's bytecode cache on, kept in ``cache``."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(cache)
    return env


def alternate(commands: list, rounds: int, warmup: int = 1) -> list[Timed]:
    """Run ``commands`` — (name, argv, parse or None) — in turn, ``rounds`` times.

    ``parse(stdout)`` may return a dict of what the run reported (e.g. its
    ``solve_seconds``), kept per round in ``Timed.extra``. The first
    ``warmup`` rounds (the disk and bytecode caches filling) are not kept.
    """
    timed = [Timed(name) for name, _, _ in commands]
    cache = Path(tempfile.mkdtemp(prefix="bench-pycache-"))
    env = bytecode_env(cache)
    try:
        for k in range(warmup + rounds):
            for t, (_, cmd, parse) in zip(timed, commands):
                wall, cpu, stdout = run_once(cmd, env=env)
                if k < warmup:
                    continue
                t.wall.append(wall)
                t.cpu.append(cpu)
                t.extra.append(parse(stdout) if parse else {})
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    return timed


def load() -> str:
    """The 1-, 5- and 15-minute load averages and the cores."""
    return f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} cores"


def ratios(a: list, b: list) -> list:
    """Per-round ratios a/b."""
    return [x / y for x, y in zip(a, b)]


def spread(values: list, fmt: str = "{:.3f}") -> str:
    """median (min–max) of a list."""
    return (fmt.format(statistics.median(values)) + " (" + fmt.format(min(values)) + "–"
            + fmt.format(max(values)) + ")")


def table(timed: list[Timed], baseline: str) -> str:
    """A Markdown table: wall and CPU seconds, and the ratios to ``baseline``."""
    base = next(t for t in timed if t.name == baseline)
    lines = ["| command | wall s, median (min–max) | CPU s, median (min–max) | "
             f"wall / {baseline}, median (range) | CPU / {baseline}, median (range) |",
             "|---|---|---|---|---|"]
    for t in timed:
        lines.append(f"| {t.name} | {spread(t.wall)} | {spread(t.cpu)} | "
                     f"{spread(ratios(t.wall, base.wall), '{:.2f}')} | "
                     f"{spread(ratios(t.cpu, base.cpu), '{:.2f}')} |")
    return "\n".join(lines)
