"""Timing commands and Python callables in fresh processes, against a baseline.

    python benchmarks/harness.py [--rounds 7] [--warmup 1] BASELINE CANDIDATE [...]

Each argument is a command line (split as a shell would, e.g. ``"python -c
pass"``); the first is the baseline. Every round runs every command once, in
the order given (A B A B ...), so a change of the machine's load falls on all
of them alike; the first ``--warmup`` rounds (disk and bytecode caches
filling) are not kept. The table gives, per command, the median and range
(min–max) over the rounds of the wall seconds, the CPU seconds (user +
system) and the peak memory, and the ratio to the baseline of the same round
(median and range). The load averages (``uptime``'s) are printed before and
after.

Peak memory is measured one way: the ``ru_maxrss`` of the measured process
as ``wait4`` returns it. Linux carries the parent's high-water mark over fork
and exec into the child's ``ru_maxrss``, so each command is started by a
small interpreter of its own (``python -S harness.py --spawn``, a few MB) that
times it and reports its usage: the figure is the command's own peak,
whatever the benchmark process had allocated before.

Every process gets Python's bytecode cache in a temporary folder (as an
installed package has its modules compiled), also where the environment sets
``PYTHONDONTWRITEBYTECODE``, unless ``alternate(..., bytecode_cache=False)``.

From Python: :func:`measure` (one command), :func:`call` (one function in a
fresh process: its JSON result and the process's timings), :func:`alternate`
and :func:`table` (rounds and their table), :func:`load`.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time


def _spawn(report: str, argv: list) -> int:
    """Run ``argv`` as a child of this (small) process, write its timings to ``report``."""
    t = time.perf_counter()
    p = subprocess.Popen(argv)
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t
    with open(report, "w") as f:
        json.dump(dict(wall=wall, cpu=usage.ru_utime + usage.ru_stime,
                       peak_mb=usage.ru_maxrss / 1024,          # kB on Linux
                       returncode=os.waitstatus_to_exitcode(status)), f)
    return 0


if __name__ == "__main__" and sys.argv[1:2] == ["--spawn"]:
    # the small process that starts a measured command (see above), before the
    # imports below raise its own peak, which its child's ru_maxrss starts from
    sys.exit(_spawn(sys.argv[2], sys.argv[4:] if sys.argv[3] == "--" else sys.argv[3:]))

import argparse  # noqa: E402
import shlex  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402
from pathlib import Path  # noqa: E402

HERE = Path(__file__).resolve().parent
#: the line a called function's JSON result is printed after, in the child's stdout
RESULT = "HARNESS-RESULT "


@dataclass
class Run:
    """One fresh process: wall and CPU seconds, peak resident memory, its output."""

    wall: float
    cpu: float
    peak_mb: float
    stdout: str
    stderr: str
    returncode: int


@dataclass
class Timed:
    """One command's measurements over the rounds, and what its parser read from each."""

    name: str
    wall: list = field(default_factory=list)
    cpu: list = field(default_factory=list)
    peak_mb: list = field(default_factory=list)
    extra: list = field(default_factory=list)


def measure(argv: list, env=None, cwd=None, timeout: float = 3600.0,
            check: bool = True) -> Run:
    """Run ``argv`` once in a fresh process and measure it.

    Raises ``RuntimeError`` with the end of its stderr if it fails and ``check``.
    """
    with tempfile.TemporaryDirectory(prefix="harness-") as tmp:
        report = Path(tmp) / "usage.json"
        out = subprocess.run([sys.executable, "-S", str(HERE / "harness.py"), "--spawn",
                              str(report), "--", *map(str, argv)],
                             capture_output=True, text=True, env=env, cwd=cwd,
                             timeout=timeout)
        if not report.exists():
            raise RuntimeError(f"harness: could not start {argv[0]}: {out.stderr.strip()[-500:]}")
        usage = json.loads(report.read_text())
    run = Run(usage["wall"], usage["cpu"], usage["peak_mb"], out.stdout, out.stderr,
              usage["returncode"])
    if check and run.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, argv))} failed ({run.returncode}): "
                           f"{run.stderr.strip()[-500:]}")
    return run


def run_once(cmd: list, env=None, cwd=None) -> tuple[float, float, str]:
    """Wall seconds, CPU seconds and stdout of one fresh process (see :func:`measure`)."""
    run = measure(cmd, env=env, cwd=cwd)
    return run.wall, run.cpu, run.stdout


def call_argv(target: str, *args, python: str | None = None) -> list:
    """The command that calls ``target(*args)`` in a fresh process and prints its result.

    ``target`` is ``"module:function"`` or ``"path/to/file.py:function"`` (a
    file's folder goes first on the child's path, as ``python file.py`` would
    do); ``args`` must be JSON. The child prints :data:`RESULT` and the
    function's return value as JSON, with ``"call_seconds"`` (the call's wall
    time, imports of the target's module excluded) added to a dict.
    """
    code = (f"import sys; sys.path.insert(0, {str(HERE)!r}); import harness; "
            "harness._call_main(sys.argv[1], sys.argv[2])")
    return [python or sys.executable, "-c", code, target, json.dumps(list(args))]


def _call_main(target: str, args: str) -> None:
    import importlib

    where, name = target.rsplit(":", 1)
    if where.endswith(".py"):
        path = Path(where).resolve()
        sys.path.insert(0, str(path.parent))
        module = importlib.import_module(path.stem)
    else:
        module = importlib.import_module(where)
    function = getattr(module, name)
    t = time.perf_counter()
    result = function(*json.loads(args))
    seconds = time.perf_counter() - t
    if isinstance(result, dict):
        result = dict(result, call_seconds=seconds)
    print(RESULT + json.dumps(result), flush=True)


def result(stdout: str):
    """The JSON result a :func:`call_argv` child printed."""
    for line in reversed(stdout.splitlines()):
        if line.startswith(RESULT):
            return json.loads(line[len(RESULT):])
    raise RuntimeError(f"harness: no result in the child's output: {stdout.strip()[-500:]}")


def call(target: str, *args, python: str | None = None, env=None, cwd=None,
         timeout: float = 3600.0) -> tuple:
    """``target(*args)`` in a fresh process: its result and the process's :class:`Run`."""
    run = measure(call_argv(target, *args, python=python), env=env, cwd=cwd, timeout=timeout)
    return result(run.stdout), run


def wearcheck_command(python: str | None = None) -> list:
    """The ``wearcheck`` console script of the environment of ``python`` (this
    interpreter by default), or ``python -m wearcheck`` where it is not installed."""
    python = python or sys.executable
    script = Path(python).with_name("wearcheck")
    return [str(script)] if script.exists() else [python, "-m", "wearcheck"]


def bytecode_env(cache: Path, env=None) -> dict:
    """``env`` (this environment by default) with Python's bytecode cache on, in ``cache``."""
    env = dict(os.environ if env is None else env)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = str(cache)
    return env


def alternate(commands: list, rounds: int, warmup: int = 1, bytecode_cache: bool = True,
              env=None, cwd=None) -> list[Timed]:
    """Run ``commands`` — (name, argv, parse or None) — in turn, ``rounds`` times.

    ``parse(stdout)`` may return a dict of what the run reported (e.g. its
    ``solve_seconds``), kept per round in ``Timed.extra``. The first
    ``warmup`` rounds are not kept.
    """
    timed = [Timed(name) for name, _, _ in commands]
    cache = Path(tempfile.mkdtemp(prefix="harness-pycache-"))
    if bytecode_cache:
        env = bytecode_env(cache, env)
    try:
        for k in range(warmup + rounds):
            for t, (_, argv, parse) in zip(timed, commands):
                run = measure(argv, env=env, cwd=cwd)
                if k < warmup:
                    continue
                t.wall.append(run.wall)
                t.cpu.append(run.cpu)
                t.peak_mb.append(run.peak_mb)
                t.extra.append(parse(run.stdout) if parse else {})
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    return timed


def load() -> str:
    """The 1-, 5- and 15-minute load averages (``uptime``'s) and the cores."""
    return (f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} "
            f"on {os.cpu_count()} cores")


def ratios(a: list, b: list) -> list:
    """Per-round ratios a/b."""
    return [x / y for x, y in zip(a, b)]


def spread(values: list, fmt: str = "{:.3f}") -> str:
    """median (min–max) of a list."""
    return (fmt.format(statistics.median(values)) + " (" + fmt.format(min(values)) + "–"
            + fmt.format(max(values)) + ")")


def table(timed: list[Timed], baseline: str | None = None) -> str:
    """A Markdown table: wall and CPU seconds, peak MB, and the wall and CPU
    ratios to ``baseline`` (the first command by default), per round."""
    base = next(t for t in timed if t.name == baseline) if baseline else timed[0]
    lines = ["| command | wall s, median (min–max) | CPU s | peak MB | "
             f"wall / {base.name}, median (range) | CPU / {base.name} |",
             "|---|---|---|---|---|---|"]
    for t in timed:
        lines.append(f"| {t.name} | {spread(t.wall)} | {spread(t.cpu)} | "
                     f"{spread(t.peak_mb, '{:.0f}')} | "
                     f"{spread(ratios(t.wall, base.wall), '{:.2f}')} | "
                     f"{spread(ratios(t.cpu, base.cpu), '{:.2f}')} |")
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("commands", nargs="+", metavar="COMMAND",
                    help="a command line; the first is the baseline")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--warmup", type=int, default=1)
    args = ap.parse_args(argv)
    commands = [(c, shlex.split(c), None) for c in args.commands]
    print(f"# harness: {args.rounds} rounds after {args.warmup} warm-up; {load()} (before)\n")
    timed = alternate(commands, args.rounds, args.warmup)
    print(table(timed))
    print(f"\n{load()} (after)")


if __name__ == "__main__":
    main()
