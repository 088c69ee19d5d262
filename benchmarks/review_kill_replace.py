"""Issue 20, item 1, the reviewer's procedure: SIGKILL while ``run`` replaces an output.

    python benchmarks/review_kill_replace.py [--workdir DIR] [--polls N]

1. ``wearcheck run paper --solver fem --out d --vtk --revolve 64`` (a 128 MB
   run directory with its ParaView files), once.
2. For every step of ``outputs.REPLACE_STEPS``, with the atomic exchange and
   with the plain-rename fallback (as on NFS):
   ``wearcheck run paper --solver mdr --out d`` in a child that SIGKILLs
   itself on reaching the step. Checked as the kill left it: ``d`` holds the
   FEM run or the MDR run, whole (the fallback, between its two renames: ``d``
   missing and the FEM run whole in ``.d.old-*``); nothing hidden says
   complete unless it is whole. Then ``wearcheck export d`` (a read) and a
   further ``wearcheck run ... --out d``: ``d`` whole, no ``.d.partial-*``,
   ``.d.old-*`` left.
3. The reviewer's own timing (``--polls`` times): the child is SIGKILLed from
   outside as soon as a ``.d.partial-*`` marked complete (or a ``.d.old-*``)
   appears, polled every 2 ms; the same checks.

Prints one line per case and PASS/FAIL; exits 1 on any failure.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from wearcheck import outputs

CHILD = r"""
import os, signal, sys
from wearcheck import outputs, renames
from wearcheck.cli import main
out, step, exchange = sys.argv[1:4]
if exchange == "0":
    renames._RENAMEAT2 = None
def hook(name):
    if name == step:
        os.kill(os.getpid(), signal.SIGKILL)
outputs.STEP_HOOK = hook
sys.exit(main(["run", "paper", "--solver", "mdr", "--out", out, "--quiet"]))
"""


def whole(directory: Path) -> str | None:
    """The solver of the complete, whole run at ``directory``, else None."""
    marker = outputs.read_marker(directory)
    if not marker or marker.get("complete") is not True:
        return None
    try:
        if set(outputs.inventory(directory, "run")) != set(marker.get("files", {})):
            return None
        if outputs.foreign_content(directory):
            return None
        return json.loads((directory / "meta.json").read_text())["solver"]
    except (OSError, ValueError, KeyError):
        return None


def hidden(parent: Path) -> list[Path]:
    return sorted(p for p in parent.iterdir() if p.name.startswith(".d."))


def wearcheck(*argv) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "wearcheck", *argv], capture_output=True,
                          text=True, timeout=600)


def check(label: str, work: Path, kill_state_ok) -> bool:
    d = work / "d"
    now = whole(d) if d.exists() else None
    problems = []
    if not kill_state_ok(now):
        problems.append(f"after the kill d holds {now!r}")
    for h in hidden(work):
        m = outputs.read_marker(h) or {}
        if m.get("complete") is True and whole(h) is None:
            problems.append(f"{h.name} says complete and is not whole")
    state = now
    export = wearcheck("export", str(d), "--quiet")
    if export.returncode != 0:
        problems.append(f"export: {export.stderr.strip()}")
    after = whole(d)
    if after not in ("fem", "mdr") or (now is not None and after != now):
        problems.append(f"after a read d holds {after!r}")
    rerun = wearcheck("run", "paper", "--solver", "mdr", "--out", str(d), "--quiet")
    if rerun.returncode != 0 or whole(d) != "mdr" or hidden(work):
        problems.append(f"a further run: exit {rerun.returncode}, left "
                        f"{[h.name for h in hidden(work)]}")
    print(f"{label:<34} killed: {str(state):<5} read: {str(after):<5} "
          f"{'PASS' if not problems else 'FAIL: ' + '; '.join(problems)}", flush=True)
    return not problems


def restore(work: Path, original: Path) -> None:
    d = work / "d"
    if d.exists():
        outputs.remove_tree(d)
    for h in hidden(work):
        shutil.rmtree(h)
    shutil.copytree(original, d, copy_function=shutil.copy2)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--workdir", type=Path, default=None)
    ap.add_argument("--polls", type=int, default=10)
    args = ap.parse_args()
    base = Path(args.workdir or tempfile.mkdtemp(prefix="review-kill-"))
    work, keep = base / "work", base / "fem-original"
    work.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    first = wearcheck("run", "paper", "--solver", "fem", "--out", str(work / "d"), "--vtk",
                      "--revolve", "64", "--quiet")
    assert first.returncode == 0, first.stderr
    size = sum(p.stat().st_size for p in (work / "d").rglob("*") if p.is_file())
    print(f"FEM run with --revolve 64: {size / 2**20:.0f} MiB in "
          f"{time.perf_counter() - t0:.1f} s", flush=True)
    shutil.copytree(work / "d", keep, copy_function=shutil.copy2)
    ok = True
    for exchange in (True, False):
        for step in outputs.REPLACE_STEPS:
            restore(work, keep)
            proc = subprocess.run([sys.executable, "-c", CHILD, str(work / "d"), step,
                                   "1" if exchange else "0"], capture_output=True, text=True,
                                  timeout=600)
            if proc.returncode != -signal.SIGKILL:
                continue          # a step the other way of replacing takes
            missing_ok = not exchange and step == "aside"
            ok &= check(f"{'exchange' if exchange else 'fallback'} kill at {step}", work,
                        lambda now: now in ("fem", "mdr") or (missing_ok and now is None))
    for i in range(args.polls):
        restore(work, keep)
        child = subprocess.Popen([sys.executable, "-m", "wearcheck", "run", "paper",
                                  "--solver", "mdr", "--out", str(work / "d"), "--quiet"])
        killed = False
        while child.poll() is None:
            for h in hidden(work):
                m = outputs.read_marker(h) or {}
                if ".old-" in h.name or m.get("complete") is True:
                    os.kill(child.pid, signal.SIGKILL)
                    killed = True
                    break
            if killed:
                break
            time.sleep(0.002)
        child.wait()
        ok &= check(f"poll {i + 1}: {'killed' if killed else 'not killed'}", work,
                    lambda now: now in ("fem", "mdr"))
    shutil.rmtree(base, ignore_errors=True)
    print("ALL PASS" if ok else "FAILURES")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
