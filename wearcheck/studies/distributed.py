"""Run many variants of one case on Dask, write each as a run directory.

The runner behind ``wearcheck refine`` and ``wearcheck sweep``. Each task
builds its case from the study's :class:`~wearcheck.cases.Case` and the task's
typed changes (``case.derive({"mdr.elements": 400})``), solves it, and returns
the result with its wall time and peak memory; the client writes each run
directory atomically as results arrive. A task that fails (a rejected case, a
solver error, a crashed worker) comes back as an error outcome; the others go on.

By default the tasks run on an embedded ``LocalCluster`` bound to 127.0.0.1
without a dashboard: one single-threaded worker process per core. Processes,
not threads: an MDR study on threads took more than ten times as long, an
FEM one a little longer (docs/performance.md, "Measurements behind the
code"); and a process of its own is what makes
the peak memory of a task measurable. ``scheduler=ADDRESS`` uses an existing cluster
instead; its workers need wearcheck importable (``pip install .``) and, for a
tabulated profile, the table file at the same path.
"""

from __future__ import annotations

import asyncio
import contextlib
import importlib
import json
import math
import os
import sys
import threading
import time
import traceback
import uuid
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from wearcheck import cases
from wearcheck.comparisons.present.progress import ProgressBar
from wearcheck.studies import scheduler as scheduler_mod
from wearcheck.rundir import jsonable, write_run
from wearcheck.extras import need
from wearcheck import registry
from wearcheck.resources import check_memory
from wearcheck.outputs import (OUTPUT_MARKER, remove_output, study_directory, study_lock,
                               write_study_text)

#: seconds between two samples of a task's resident set size
RSS_INTERVAL = 0.01
#: least seconds between two progress events of one task
PROGRESS_INTERVAL = 0.5
#: seconds to wait for a first worker (an external scheduler may have none);
#: the environment variable WEARCHECK_WORKER_TIMEOUT overrides it
WORKER_TIMEOUT = 30.0
#: most worker processes per core of the embedded cluster (each is a Python process)
WORKERS_PER_CORE = 4


def _worker_timeout() -> float:
    return scheduler_mod.environment_timeout("WEARCHECK_WORKER_TIMEOUT", WORKER_TIMEOUT)


def _answer_timeout() -> float:
    """Seconds an external scheduler may take to answer (10 s, or the worker timeout
    when that is set lower)."""
    return scheduler_mod.answer_timeout(_worker_timeout())


def check_workers(scheduler: str | None, workers) -> None:
    """``workers`` must be a positive count (at most WORKERS_PER_CORE per core), and
    only for the embedded cluster."""
    if scheduler and workers:
        raise cases.ArgumentError("workers", "sizes the embedded cluster; an existing one "
                                  "({scheduler}) has the workers it has", value=workers,
                                  also=("scheduler",))
    if workers is None:
        return
    most = WORKERS_PER_CORE * (os.cpu_count() or 1)
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= most:
        raise cases.ArgumentError("workers", f"must be a whole number from 1 to {most} "
                                  f"({WORKERS_PER_CORE} per core on this machine)",
                                  value=workers)


@dataclass(frozen=True)
class Task:
    """One run: its directory name, solver and the keys it changes in the study's case
    (``{"mdr.elements": 400}``, typed, as :meth:`Case.derive` takes them)."""

    name: str
    solver: str
    changes: dict = field(default_factory=dict)


@dataclass
class Outcome:
    """What came back from one task (``result`` and ``case`` only when ``ok``)."""

    task: Task
    ok: bool
    message: str = ""
    wall_seconds: float = float("nan")
    cpu_seconds: float = float("nan")
    peak_rss_mb: float = float("nan")
    start_rss_mb: float = float("nan")
    worker: str = ""
    case: cases.Case | None = None
    result: cases.RunResult | None = None
    run_dir: Path | None = None
    traceback: str = ""

    @property
    def status(self) -> str:
        """"ok", or "error: <message>" for the tables."""
        return "ok" if self.ok else f"error: {self.message}"


# --------------------------------------------------------------------------
# Inside a worker

class _PeakRSS:
    """Peak resident set size of this process while the block runs.

    A daemon thread samples ``psutil`` every ``RSS_INTERVAL`` s; a peak
    shorter than that (or inside one call that holds the GIL) can be missed.
    """

    def __enter__(self):
        # lazy (a): psutil comes with the optional "dask" extra
        import psutil  # a dependency of distributed
        self._proc = psutil.Process()
        self.start = self.peak = self._proc.memory_info().rss
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True)
        self._thread.start()
        return self

    def _sample(self):
        while not self._stop.wait(RSS_INTERVAL):
            self.peak = max(self.peak, self._proc.memory_info().rss)

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()
        self.peak = max(self.peak, self._proc.memory_info().rss)
        return False


def _progress_sender(topic: str | None, name: str):
    """A solver progress callback that reports to the client, throttled."""
    try:
        # lazy (a): dask's "distributed", the optional "dask" extra
        from distributed import get_worker
        worker = get_worker()
    except (ImportError, ValueError):
        worker = None
    if worker is None or topic is None:
        return None
    last = [0.0]

    def progress(fraction, text=""):
        now = time.perf_counter()
        if now - last[0] >= PROGRESS_INTERVAL:
            last[0] = now
            worker.log_event(topic, {"name": name, "fraction": float(fraction)})
    return progress


def execute(base: cases.Case, changes: dict, solver: str, name: str,
            topic: str | None = None, solve=None) -> dict:
    """Build the case (``base`` with ``changes``), solve it; never raises. Runs inside a
    worker.

    ``solve(case, solver, progress)`` defaults to ``wearcheck.registry.solve``.
    """
    if solve is None:
        solve = registry.solve
        try:  # a worker's first import of the solver is not part of its cost
            # (a solver package imports its numerics with its solve, on first use)
            getattr(importlib.import_module(registry.get(solver).module), "solve")
        except Exception:
            pass  # solve() meets the same failure below and reports it
    out = dict(ok=False, message="", case=None, result=None, traceback="")
    try:
        # lazy (a): dask's "distributed", the optional "dask" extra
        from distributed import get_worker
        out["worker"] = get_worker().address
    except (ImportError, ValueError):
        out["worker"] = "local"
    t0, c0 = time.perf_counter(), time.process_time()
    # a run's remarks are recorded in its result (meta.json's "warnings"); said as
    # Python warnings here they reached the terminal once per run and worker,
    # attributed to dask's task code
    with _PeakRSS() as rss, warnings.catch_warnings():
        warnings.simplefilter("ignore", cases.RunWarning)
        try:
            case = base.derive(changes) if changes else base
            check_memory(case, solver)  # this worker's memory, before allocating
            result = solve(case, solver, _progress_sender(topic, name))
            out.update(ok=True, case=case, result=result)
        except cases.WearcheckError as exc:
            out["message"] = str(exc)
        except Exception as exc:  # a bug or a library failure: keep the others going
            out["message"] = f"{type(exc).__name__}: {exc}"
            out["traceback"] = traceback.format_exc()
    out.update(wall_seconds=time.perf_counter() - t0, cpu_seconds=time.process_time() - c0,
               peak_rss_mb=rss.peak / 2**20,
               start_rss_mb=rss.start / 2**20)
    return out


# --------------------------------------------------------------------------
# On the client

#: a study started at the top level of a script: Dask's worker processes (spawned)
#: import the script that starts them, which would start the study again in each
_UNGUARDED = ("a study on Dask (wearcheck.sweep, refine, fretting_map, fit) called from "
              "a script must be called under `if __name__ == \"__main__\":` in {script}: "
              "Dask's worker processes import the script that starts them (in a notebook "
              "or the wearcheck command this is not needed)")


def _script() -> str | None:
    """The file of the running script if it has no ``__main__`` guard (None: a
    notebook, the interpreter's prompt, ``python -c``, ``python -m``, or a script
    that tests ``__name__``, as the ``wearcheck`` console script does)."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if not path or getattr(main, "__spec__", None) is not None:
        return None
    try:
        guarded = "__main__" in Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    return None if guarded else str(path)


def _importing_main_in_a_worker() -> bool:
    """Whether this process is a spawned worker still importing its parent's script
    (multiprocessing's own test, ``_check_not_importing_main``)."""
    import multiprocessing
    return bool(getattr(multiprocessing.current_process(), "_inheriting", False))


class _Client:
    """A distributed Client on ``scheduler``, or on an embedded LocalCluster."""

    def __init__(self, scheduler: str | None, workers: int | None, n_tasks: int):
        dask = need("dask", "a study (sweep, refine, fretting-map, fit: on Dask)")
        # lazy (a): dask's "distributed", the optional "dask" extra
        from distributed import Client, LocalCluster
        self.cluster = None
        self._quiet = None
        check_workers(scheduler, workers)
        if scheduler:
            self._quiet = scheduler_mod.quiet_logs()
            try:
                args = scheduler_mod.check_address(scheduler)
                self.client = scheduler_mod.client(scheduler, _answer_timeout(), args)
            except BaseException:
                self._quiet()
                raise
            try:
                # tasks sent to a scheduler without workers would wait for ever
                scheduler_mod.wait_for_worker(self.client, scheduler, _worker_timeout(),
                                              _answer_timeout())
            except BaseException:
                self.close()
                raise
            return
        n = workers or max(1, min(os.cpu_count() or 1, n_tasks))
        if _importing_main_in_a_worker():
            raise cases.WearcheckError(_UNGUARDED.format(script=_script() or "your script"))
        # a task that kills its worker (out of memory, crash) is reported at once,
        # not retried on the next worker
        with dask.config.set({"distributed.scheduler.allowed-failures": 0}), \
                warnings.catch_warnings():
            # without a dashboard the scheduler still serves /health on 127.0.0.1,
            # port 8787 or, when taken, another one: nothing to warn about
            warnings.filterwarnings("ignore", message="Port .* is already in use")
            try:
                self.cluster = LocalCluster(n_workers=n, threads_per_worker=1,
                                            processes=True, host="127.0.0.1",
                                            dashboard_address=None, silence_logs=40)
            except Exception as exc:   # noqa: BLE001 - distributed's RuntimeError and others
                script = _script()
                if script is None:
                    raise
                raise cases.WearcheckError(
                    "the worker processes of Dask's local cluster failed to start ("
                    f"{type(exc).__name__}: {exc}); " + _UNGUARDED.format(script=script)
                ) from exc
        self.client = Client(self.cluster)

    def close(self, timeout: float | None = None):
        try:
            # bounded: a scheduler that stopped answering is not waited for
            self.client.close(timeout=timeout or _answer_timeout())
        except Exception:  # noqa: BLE001 - TimeoutError, a comm already closed
            pass
        if self.cluster is not None:
            self.cluster.close()
        if self._quiet is not None:
            self._quiet()


class _Watchdog:
    """Cancels the study's tasks when the cluster has had no worker, or its scheduler
    has not answered, for the worker timeout.

    An external scheduler whose workers all died, or that was stopped or
    killed, would otherwise keep the tasks waiting for ever; the embedded
    cluster restarts its workers, so there this never fires.
    """

    def __init__(self, client, futures: dict, interval: float = 1.0):
        self.client, self.futures, self.interval = client, futures, interval
        self.reason = ""
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self):
        limit = _worker_timeout()
        answered = time.monotonic()     # the scheduler's last answer
        workerless = None               # since when it has had no worker
        beats = {}                      # worker: (its last heartbeat, when that changed here)
        while not self._stop.wait(self.interval):
            now = time.monotonic()
            # a request may take what is left of the limit, at most the answer timeout
            wait = max(0.1, min(_answer_timeout(), answered + limit - now))
            try:
                seen = scheduler_mod.heartbeats(self.client, wait)
                answered = time.monotonic()
            except Exception:  # noqa: BLE001 - no answer in time, or the scheduler is gone
                seen = None
            now = time.monotonic()
            workers = None if seen is None else len(seen)
            if seen is not None:
                # a worker whose heartbeat has not moved for the limit (stopped, hung)
                # counts as gone: the scheduler keeps it until its worker-ttl (5 min)
                beats = {w: beats[w] if w in beats and beats[w][0] == b else (b, now)
                         for w, b in seen.items()}
                alive = sum(now - since < limit for _, since in beats.values())
                if seen and not alive:
                    self.reason = (f"no worker of the Dask scheduler has sent a heartbeat "
                                   f"for {limit:g} s (stopped, or hung); the task was "
                                   "cancelled")
                    self._cancel()
                    return
            if workers:
                workerless = None
                continue
            if workers is None:
                if getattr(self.client, "status", "") == "closed":
                    # the connection broke and reconnecting failed: nothing to wait for
                    self.reason = ("the Dask scheduler was lost (it died, or the connection "
                                   "broke); the task was cancelled")
                elif now - answered < limit:
                    continue
                else:
                    self.reason = (f"the Dask scheduler stopped answering for {limit:g} s "
                                   "(stopped, or gone); the task was cancelled")
            else:
                workerless = workerless or now
                if now - workerless < limit:
                    continue
                self.reason = (f"no worker left on the Dask scheduler for {limit:g} s; the "
                               "task was cancelled")
            self._cancel()
            return

    def _cancel(self):
        futures = []
        for _ in range(3):
            try:
                futures = list(self.futures)
                break
            except RuntimeError:  # the dict grew meanwhile
                continue
        for fut in futures:
            with contextlib.suppress(Exception):  # a client already closed
                fut.cancel()

    def stop(self):
        self._stop.set()
        self._thread.join(timeout=5)


class _Reporter:
    """Per-level progress on stderr: a bar while running, a line per finished task."""

    def __init__(self, label: str, names: list[str], quiet: bool):
        self.quiet = quiet
        self.bar = ProgressBar(label, quiet=quiet)
        self.fraction = dict.fromkeys(names, 0.0)
        self.done = 0
        self.lock = threading.Lock()

    def event(self, event):
        _, msg = event
        with self.lock:
            if self.fraction.get(msg["name"], 1.0) < 1.0:
                self.fraction[msg["name"]] = min(msg["fraction"], 0.999)
                self._draw()

    def _draw(self):
        running = [f"{n} {100 * f:.0f}%" for n, f in self.fraction.items() if 0 < f < 1]
        self.bar(sum(self.fraction.values()) / len(self.fraction),
                 f"{self.done}/{len(self.fraction)} done " + ", ".join(running))

    def finished(self, outcome: Outcome):
        with self.lock:
            self.fraction[outcome.task.name] = 1.0
            self.done += 1
            if not self.quiet:
                if self.bar.enabled:
                    sys.stderr.write("\r\033[K")
                mem = f", peak {outcome.peak_rss_mb:.0f} MB" if outcome.ok else ""
                print(f"[{self.done}/{len(self.fraction)}] {outcome.task.name}: {outcome.status}"
                      f" ({outcome.wall_seconds:.3g} s{mem})", file=sys.stderr, flush=True)
            self._draw()

    def close(self):
        self.bar.close()


def _unclaim(out: Path, remove_directory: bool) -> None:
    """Remove the study marker of ``out`` (and ``out``) if it holds nothing else."""
    try:
        if [p.name for p in out.iterdir()] == [OUTPUT_MARKER]:
            (out / OUTPUT_MARKER).unlink()
            if remove_directory:
                out.rmdir()
    except OSError:
        pass


def run_cases(case: cases.Case, tasks: list[Task], out: str | Path, *,
              scheduler: str | None = None, workers: int | None = None, quiet: bool = False,
              solve=None, extra_meta: dict | None = None,
              study_files=("meta.json",)) -> list[Outcome]:
    """Run every task on Dask; write each successful one to ``out/<task.name>``.

    ``study_files``: the files the study will write into ``out`` itself,
    checked (with the runs' directories) before the cluster starts.

    Each task's case is ``case`` with the task's changes, built in its worker
    (the case travels pickled, typed: no text on the way). Returns the outcomes
    in the order of ``tasks``; each run directory is written (atomically, by
    ``rundir.write_run``) as soon as its result arrives, so an interrupted study
    keeps the levels already done.
    """
    # the studies run on Dask: said before anything is checked or started
    need("distributed", "a study (sweep, refine, fretting-map, fit: on Dask)")
    # lazy (a): dask's "distributed", the optional "dask" extra
    from distributed import KilledWorker, as_completed

    check_workers(scheduler, workers)
    if scheduler:
        scheduler_mod.check_address(scheduler)  # before the study directory is made
    names = [t.name for t in tasks]
    if len(set(names)) != len(names):
        raise cases.CaseError("two runs would share a directory: " + ", ".join(names))
    existed = Path(out).is_dir()
    was_empty = not existed or not any(Path(out).iterdir())
    out = study_directory(out, runs=[t.name for t in tasks], files=study_files)
    reporter = _Reporter(tasks[0].solver if tasks else "", names, quiet)
    topic = f"wearcheck-progress-{uuid.uuid4().hex}"
    outcomes: dict[str, Outcome] = {}
    try:
        conn = _Client(scheduler, workers, len(tasks))
    except BaseException:
        # no cluster, no run: take back the marker (and the directory) this study made,
        # which would otherwise claim the path as a study holding nothing
        if was_empty:
            _unclaim(out, remove_directory=not existed)
        raise
    state = {"watchdog": None}
    try:
        client = conn.client
        client.subscribe_topic(topic, reporter.event)
        pending, futures, running = list(tasks), {}, as_completed()

        def fill():
            # no more tasks out than worker threads: a task queued on a worker
            # that dies would be lost with it
            if state["watchdog"] is not None and state["watchdog"].reason:
                return  # no worker left: the pending tasks fail below
            try:
                slots = max(1, sum(scheduler_mod.nthreads(client, _answer_timeout()).values()))
            except Exception:  # noqa: BLE001 - no answer: the watchdog decides when to give up
                return
            while pending and running.count() < slots:
                t = pending.pop(0)
                fut = client.submit(execute, case, t.changes, t.solver, t.name, topic, solve,
                                    pure=False,
                                    key=f"{t.name}-{uuid.uuid4().hex[:8]}")
                futures[fut] = t
                running.add(fut)
        fill()
        watchdog = state["watchdog"] = _Watchdog(client, futures)

        def completed():
            # polled, not a blocking as_completed: a study whose workers all
            # left must end once the watchdog gives up on it
            handled = set()
            while True:
                batch = running.next_batch(block=False)
                if batch:
                    handled.update(batch)
                    yield from batch
                elif watchdog.reason:
                    stuck = [f for f in list(futures) if f not in handled]
                    running.clear()
                    handled.update(stuck)
                    yield from stuck
                    return
                elif running.is_empty() and not pending:
                    return
                else:
                    if running.is_empty():
                        fill()  # the scheduler did not answer the last time: ask again
                    time.sleep(0.05)

        for fut in completed():
            t = futures[fut]
            try:
                rec = fut.result()
                outcome = Outcome(task=t, **rec)
            except KilledWorker:
                outcome = Outcome(task=t, ok=False, message="its worker died while running it "
                                  "(a crash, or memory beyond the worker's limit)")
            except (Exception, asyncio.CancelledError) as exc:  # the scheduler or workers lost
                text = " ".join(str(exc).split())
                if "scheduler-connection-lost" in text:
                    text = ("the Dask scheduler was lost while the task ran (it died, or the "
                            "connection broke); the task was cancelled")
                else:
                    text = f"{type(exc).__name__}: {text}"
                outcome = Outcome(task=t, ok=False, message=watchdog.reason or text)
            fut.release()
            if outcome.ok:
                meta = dict(task=t.name, changes=dict(t.changes),
                            wall_seconds=outcome.wall_seconds,
                            cpu_seconds=outcome.cpu_seconds, peak_rss_mb=outcome.peak_rss_mb,
                            worker=outcome.worker)
                meta.update(extra_meta or {})
                try:
                    outcome.run_dir = write_run(out / t.name, outcome.case, outcome.result,
                                                t.solver, extra_meta=meta)
                except OSError as exc:
                    outcome.ok, outcome.message = False, f"writing the run failed: {exc}"
            if not outcome.ok:
                # a complete run left from an earlier study would pass for this one's
                discard_run(out / t.name)
            outcomes[t.name] = outcome
            reporter.finished(outcome)
            fill()
        for t in pending:  # never started: no worker was left to run them
            outcomes[t.name] = Outcome(task=t, ok=False, message=watchdog.reason or
                                       "never started: the Dask scheduler gave it no worker")
            discard_run(out / t.name)
            reporter.finished(outcomes[t.name])
        with contextlib.suppress(Exception):  # a scheduler that is gone
            client.unsubscribe_topic(topic)
    finally:
        given_up = state.get("watchdog") is not None and state["watchdog"].reason
        if state.get("watchdog") is not None:
            state["watchdog"].stop()
        reporter.close()
        conn.close(1.0 if given_up else None)
    return [outcomes[t.name] for t in tasks]


def discard_run(path: Path) -> None:
    """Remove an earlier run directory at ``path`` (only ever a wearcheck run)."""
    remove_output(path, "run")


# --------------------------------------------------------------------------
# The study directory

def study_meta(out) -> dict:
    """DIR/meta.json of a study directory ({} when there is none, or it is unreadable)."""
    path = Path(out) / "meta.json"
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return meta if isinstance(meta, dict) else {}


def record_study(out: Path, study: str, case, prov, arguments: dict | None = None) -> None:
    """Add this study's provenance, resolved case and ``arguments`` (what it varied, as
    given) to DIR/meta.json (kept for the other studies).

    A study of the same name recorded before (a re-run, or a sweep that adds
    values) stays, under ``earlier`` in the new entry, latest first.
    """
    with study_lock(out):       # read and written by one study at a time
        meta = study_meta(out)
        studies = meta.setdefault("studies", {})
        entry = dict(prov, case_file=str(getattr(case, "source", "")),
                     arguments=arguments or {}, resolved_case=cases.to_toml(case))
        previous = studies.get(study)
        if isinstance(previous, dict):
            earlier = previous.pop("earlier", [])
            entry["earlier"] = [previous] + (earlier if isinstance(earlier, list) else [])
        studies[study] = entry
        write_study_text(out, "meta.json", json.dumps(jsonable(meta), indent=2) + "\n")


def _flat(table: dict, prefix: str = "") -> dict:
    out = {}
    for key, value in table.items():
        if isinstance(value, dict):
            out.update(_flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def base_difference(recorded_toml: str, case) -> str | None:
    """The first key (``section.key: here vs there``) in which ``case`` differs from a
    resolved case recorded as TOML; None when they are the same case."""
    import tomllib
    try:
        there = _flat(tomllib.loads(recorded_toml))
    except (tomllib.TOMLDecodeError, TypeError):
        return "the case recorded there cannot be read"
    here = _flat(tomllib.loads(cases.to_toml(case)))
    for key in sorted(set(here) | set(there)):
        if here.get(key) != there.get(key):
            return f"{key} = {here.get(key, '(unset)')!r} here, {there.get(key, '(unset)')!r} there"
    return None


def fmt(v, spec=".4g"):
    """A table cell: '' for None, ``spec`` for a float."""
    if v is None:
        return ""
    if isinstance(v, float):
        return "nan" if math.isnan(v) else format(v, spec)
    return str(v)
