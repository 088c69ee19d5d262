"""Issue 20, item 5, the reviewer's procedure: ``sweep --scheduler`` at schedulers that fail.

    python benchmarks/review_bad_scheduler.py [--limit SECONDS]

With the default limits (no WEARCHECK_WORKER_TIMEOUT: a scheduler has 10 s
to answer, 30 s to offer a worker or to answer again mid-study) it runs

    wearcheck sweep paper --vary wear.mu=0.2,0.3 --solver mdr --scheduler ADDRESS

against: a Dask dashboard's port (accepts TCP, serves HTTP); a scheduler
stopped with SIGSTOP; a server that greets first (an SSH banner); tls://
without certificates; ucx://; a scheduler stopped, and one killed, while
the first run is on its worker (``--set mdr.elements=3000``, so that the
run takes a few seconds). Each must end within the limit (30 s, plus the
start of Python and Dask, measured here as a sweep that fails at once) with
one error line (the mid-study cases: the error rows' lines) and the exit
code documented: 2 for an address this machine cannot use, 1 otherwise.

Prints one line per case and PASS/FAIL; exits 1 on any failure.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

SWEEP = ["sweep", "paper", "--vary", "wear.mu=0.2,0.3", "--solver", "mdr"]


def start_scheduler(directory: Path, worker: bool, dashboard: bool = False):
    file = directory / f"scheduler-{time.monotonic_ns()}.json"
    args = [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
            "--port", "0", "--scheduler-file", str(file)]
    args += ["--dashboard-address", "127.0.0.1:0"] if dashboard else ["--no-dashboard"]
    procs = [subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    while not (file.exists() and file.read_text().strip()):
        time.sleep(0.1)
    info = json.loads(file.read_text())
    if worker:
        procs.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker",
                                       info["address"], "--nthreads", "1", "--no-dashboard"],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from distributed import Client
        with Client(info["address"], timeout="60s") as c:
            c.wait_for_workers(1, timeout=120)
    return info, procs


def stop_all(procs):
    for p in procs:
        if p.poll() is None:
            os.kill(p.pid, signal.SIGCONT)
            p.kill()
        p.wait()


def banner_server() -> str:
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    sock.listen(8)

    def serve():
        while True:
            conn, _ = sock.accept()
            conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
    threading.Thread(target=serve, daemon=True).start()
    return f"tcp://127.0.0.1:{sock.getsockname()[1]}"


def sweep(address: str, out: Path, extra=(), during=None, env=None):
    """(exit code, stderr lines, seconds): the sweep; ``during(process)`` runs alongside."""
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "wearcheck", *SWEEP, *extra, "--scheduler",
                             address, "--out", str(out), "--quiet"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    if during is not None:
        during(proc)
    try:
        _, err = proc.communicate(timeout=300)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
        return None, ["no exit after 300 s"], time.perf_counter() - t0
    return proc.returncode, [l for l in err.splitlines() if l.strip()], \
        time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--limit", type=float, default=30.0,
                    help="the documented limit, seconds (default 30)")
    args = ap.parse_args()
    env = {k: v for k, v in os.environ.items() if k != "WEARCHECK_WORKER_TIMEOUT"}
    work = Path(tempfile.mkdtemp(prefix="review-scheduler-"))
    ok = True
    # the start of Python, Dask and the case: a sweep that fails at once
    _, _, startup = sweep("tcp://127.0.0.1:99999", work / "x", env=env)
    print(f"start-up (a sweep refused at once): {startup:.1f} s", flush=True)
    budget = args.limit + startup + 5.0

    def report(label, code, lines, wall, codes, n_lines=1):
        nonlocal ok
        good = code in codes and len(lines) == n_lines and wall < budget \
            and not any("Traceback" in line or "out of memory" in line for line in lines)
        ok &= good
        print(f"{label:<30} exit {code}  {wall:5.1f} s  {'PASS' if good else 'FAIL'}: "
              f"{lines[-1] if lines else ''}", flush=True)

    info, procs = start_scheduler(work, worker=False, dashboard=True)
    try:
        dashboard = f"tcp://127.0.0.1:{info['services']['dashboard']}"
        report("a dashboard's port", *sweep(dashboard, work / "a", env=env), {1})
        os.kill(procs[0].pid, signal.SIGSTOP)
        report("a stopped scheduler", *sweep(info["address"], work / "b", env=env), {1})
    finally:
        stop_all(procs)
    report("a server with a banner", *sweep(banner_server(), work / "c", env=env), {1})
    report("tls:// (no certificates)", *sweep("tls://127.0.0.1:8786", work / "d", env=env), {2})
    report("ucx://", *sweep("ucx://127.0.0.1:8786", work / "e", env=env), {2})
    for how in (signal.SIGSTOP, signal.SIGKILL):
        info, procs = start_scheduler(work, worker=True)
        killed = {}
        try:
            def lose(proc, pid=procs[0].pid, how=how):
                time.sleep(startup + 6.0)      # the first run is on the worker by then
                os.kill(pid, how)
                killed["at"] = time.perf_counter()
            t0 = time.perf_counter()
            out = work / f"f{how}"
            code, lines, wall = sweep(info["address"], out, ("--set", "mdr.elements=3000"),
                                      lose, env)
            after = wall - (killed["at"] - t0)
            import csv
            with open(out / "sweep.csv", newline="") as fh:
                rows = list(csv.DictReader(l for l in fh if not l.startswith("#")))
            said = all("the Dask scheduler" in r["status"] for r in rows) and len(rows) == 2
            # the time from the loss; the error rows name the scheduler
            report(f"scheduler {how.name} mid-study", code, lines if said else lines + ["?"],
                   after, {1})
            if said:
                print(f"{'':<30} rows: {rows[0]['status']}", flush=True)
        finally:
            stop_all(procs)
    print("ALL PASS" if ok else "FAILURES")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
