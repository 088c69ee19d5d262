"""Never lose a user's file, never hang, never trace back (issue 13).

One test per class of misuse found by hand; each failed on the code before
the fix (a deleted file, a hang, a traceback, a wrong exit code) and checks
the behaviour the "Reliability" table of docs/reliability.md promises. Subprocesses are
used where the failure is a hang, a signal or a process limit.
"""

from __future__ import annotations

import contextlib
import json
import multiprocessing
import os
import platform
import resource
import shutil
import signal
import stat
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

from wearcheck import cases
from wearcheck.cli import main as cli_main

from conftest import TABLE_CASE

HERTZ = str(cases.shipped("hertz"))
#: a small MDR run of the Hertz case (about 0.1 s)
SMALL = ["--set", "mdr.elements=40", "--quiet"]


def _cli(*argv):
    """The command in a fresh interpreter: (exit code, stdout, stderr)."""
    return [sys.executable, "-m", "wearcheck", *argv]


def _snapshot(root: Path, skip=()) -> dict:
    """Every file under root (not under the paths in skip) with its bytes."""
    out = {}
    for p in sorted(root.rglob("*")):
        if any(p == s or s in p.parents for s in skip):
            continue
        out[str(p.relative_to(root))] = p.read_bytes() if p.is_file() else None
    return out


def _one_error_line(err: str) -> str:
    lines = [l for l in err.splitlines() if l.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.fixture
def no_solve(monkeypatch):
    """Fail the test if the CLI starts a solve: refusals must come before the work."""
    def boom(*args, **kwargs):
        raise AssertionError("the solve started before the refusal")
    monkeypatch.setattr("wearcheck.registry.solve", boom)


# -- 1. data loss ----------------------------------------------------------

@pytest.mark.parametrize("name", ["meta.json", "metrics.json"])
def test_a_meta_json_does_not_make_a_user_directory_replaceable(tmp_path, capsys, name):
    d = tmp_path / "mine"
    d.mkdir()
    (d / name).write_text("{}")
    (d / "thesis.tex").write_text("t")
    before = _snapshot(tmp_path)
    assert cli_main(["run", HERTZ, "--out", str(d), *SMALL]) == 2
    assert "not a wearcheck output" in _one_error_line(capsys.readouterr().err)
    assert _snapshot(tmp_path) == before


def test_a_child_of_a_run_directory_is_not_replaceable(tmp_path, capsys):
    run = tmp_path / "run"
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    mine = run / "notes"
    mine.mkdir()
    (mine / "notes.txt").write_text("n")
    before = _snapshot(tmp_path)
    assert cli_main(["run", HERTZ, "--out", str(mine), *SMALL]) == 2
    _one_error_line(capsys.readouterr().err)
    assert _snapshot(tmp_path) == before


def test_a_rerun_never_deletes_what_the_user_added(tmp_path, capsys):
    # a re-run replaces the run it wrote, not the notes and folders added since
    run = tmp_path / "run"
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    (run / "my_notes.txt").write_text("n")
    (run / "myplots").mkdir()
    before = _snapshot(tmp_path)
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "my_notes.txt" in line and "myplots" in line
    assert _snapshot(tmp_path) == before
    # a file wearcheck wrote and the user changed is the user's too
    (run / "my_notes.txt").unlink()
    (run / "myplots").rmdir()
    with open(run / "history.csv", "a") as fh:
        fh.write("# checked by hand\n")
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 2
    assert "history.csv" in _one_error_line(capsys.readouterr().err)
    # as written, it is replaced
    (run / "history.csv").unlink()
    shutil.rmtree(run)
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0


def test_a_file_added_to_an_exported_vtk_folder_survives_a_rerun(tmp_path, capsys):
    run = tmp_path / "run"
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    assert cli_main(["export", str(run)]) == 0
    # the export is the run's own part: a re-run replaces both
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    assert cli_main(["export", str(run)]) == 0
    (run / "vtk" / "state.pvsm").write_text("paraview state")
    capsys.readouterr()
    before = _snapshot(tmp_path)
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 2
    assert "state.pvsm" in _one_error_line(capsys.readouterr().err)
    assert _snapshot(tmp_path) == before


@pytest.mark.parametrize("inner", ["inner", "vtk", "deeper/still"])
def test_an_output_inside_another_output_is_refused(tmp_path, capsys, inner, no_solve):
    # a re-run of the outer output would delete it; only a run's own vtk/
    # (by export) and a study's runs live inside another output
    outer = tmp_path / "outer"
    outer.mkdir()
    from wearcheck import outputs
    outputs.write_marker(outer, "run", files=outputs.inventory(outer))
    before = _snapshot(tmp_path)
    assert cli_main(["run", HERTZ, "--out", str(outer / inner), *SMALL]) == 2
    assert "lies inside" in _one_error_line(capsys.readouterr().err)
    assert cli_main(["compare", HERTZ, "--out", str(outer / inner)]) == 2
    # (after the case's Dundurs note, which every command prints first)
    err = "\n".join(l for l in capsys.readouterr().err.splitlines()
                    if not l.startswith("note:"))
    assert "lies inside" in _one_error_line(err)
    assert _snapshot(tmp_path) == before


def _sums(root: Path) -> dict:
    return {str(p.relative_to(root)): (p.read_bytes() if p.is_file() and not p.is_symlink()
                                       else os.readlink(p) if p.is_symlink() else None)
            for p in sorted(root.rglob("*"))}


@pytest.mark.parametrize("how", ["moved run", "copied vtk"])
def test_an_output_put_inside_another_survives_its_rerun(tmp_path, capsys, how):
    # only a run's own vtk/ and render/ are its parts: another output moved or
    # copied in is the user's
    run = tmp_path / "run"
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    if how == "moved run":
        assert cli_main(["run", HERTZ, "--out", str(tmp_path / "old"), *SMALL]) == 0
        (tmp_path / "old").rename(run / "backup-run")
    else:
        assert cli_main(["export", str(run)]) == 0
        shutil.copytree(run / "vtk", run / "vtk-backup", symlinks=True)
    capsys.readouterr()
    before = _snapshot(tmp_path)
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 2
    assert "backup" in _one_error_line(capsys.readouterr().err)
    assert _snapshot(tmp_path) == before


def test_an_unmarked_vtk_folder_of_the_user_is_not_replaced_by_export(tmp_path, capsys):
    run = tmp_path / "run"
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    (run / "vtk").mkdir()
    (run / "vtk" / "mine.vtu").write_text("user mesh")
    before = _snapshot(tmp_path)
    assert cli_main(["export", str(run)]) == 2
    _one_error_line(capsys.readouterr().err)
    assert _snapshot(tmp_path) == before


def test_a_file_added_while_an_output_is_replaced_is_kept(tmp_path, monkeypatch):
    # the race between the check and the move aside: the occupant is checked
    # again once moved, and goes back with the file
    from wearcheck import outputs
    out = tmp_path / "out"
    with outputs.atomic_directory(out) as tmp:
        (tmp / "payload").write_text("first")
    (out / "user_notes.txt").write_text("notes")           # arrives after the check
    monkeypatch.setattr(outputs, "refusal", lambda path, kind: None)
    with pytest.raises(cases.CaseError, match="user_notes.txt"):
        with outputs.atomic_directory(out) as tmp:
            (tmp / "payload").write_text("second")
    assert (out / "user_notes.txt").read_text() == "notes"
    assert (out / "payload").read_text() == "first"
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_debris_of_a_dead_export_does_not_block_a_rerun(tmp_path):
    from wearcheck import outputs
    run = tmp_path / "run"
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    partial = run / ".vtk.partial-abc"
    partial.mkdir()
    (partial / outputs.OUTPUT_MARKER).write_text(json.dumps(dict(
        wearcheck="output", kind="vtk", complete=False, pid=int(dead), host=platform.node())))
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    assert not partial.exists()


def test_a_copy_that_loses_the_mtime_is_still_replaceable(tmp_path):
    # tar keeps whole seconds only: the content decides, not the mtime
    run = tmp_path / "run"
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    for p in run.iterdir():
        os.utime(p, (1e9, 1e9), follow_symlinks=False)
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    # the same size with other bytes and the mtime put back is a change
    h = run / "history.csv"
    st = h.stat()
    text = h.read_text()
    h.write_text(("X" if text[0] != "X" else "Y") + text[1:])
    os.utime(h, ns=(st.st_atime_ns, st.st_mtime_ns))
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 2


def test_study_files_and_runs_the_user_changed_are_kept(tmp_path):
    from wearcheck import outputs
    study = outputs.study_directory(tmp_path / "study")
    outputs.write_study_text(study, "sweep.csv", "a\n")
    outputs.write_study_text(study, "sweep.csv", "b\n")     # its own file: replaced
    with open(study / "sweep.csv", "a") as fh:
        fh.write("# my notes\n")
    with pytest.raises(cases.CaseError, match="sweep.csv"):
        outputs.study_directory(study)                      # before any work
    with pytest.raises(cases.CaseError, match="sweep.csv"):
        outputs.write_study_text(study, "sweep.csv", "c\n")
    assert not outputs.remove_study_file(study, "sweep.csv")
    assert (study / "sweep.csv").read_text() == "b\n# my notes\n"
    # a link put in place of a study file: refused, its target untouched
    target = tmp_path / "picture.png"
    target.write_text("precious")
    (study / "cost.png").symlink_to(target)
    with pytest.raises(cases.CaseError, match="cost.png"):
        outputs.write_study_text(study, "cost.png", "png")
    assert target.read_text() == "precious"
    # a file of the user's under a name the study will write: refused before the work
    (study / "sweep.csv").unlink()
    (study / "cost.png").unlink()
    (study / "cost.png").write_text("my plot")
    with pytest.raises(cases.CaseError, match="cost.png"):
        outputs.study_directory(study, files=["cost.png"])
    assert (study / "cost.png").read_text() == "my plot"
    # a run of the study with the user's notes: refused before the work, never removed
    (study / "cost.png").unlink()
    with outputs.atomic_directory(study / "r1") as tmp:
        (tmp / "history.csv").write_text("s\n")
    (study / "r1" / "notes.txt").write_text("n")
    with pytest.raises(cases.CaseError, match="notes.txt"):
        outputs.study_directory(study, runs=["r1"])
    assert not outputs.remove_output(study / "r1", "run")
    assert (study / "r1" / "notes.txt").read_text() == "n"


def test_the_mesh_side_marker_is_never_written_through_a_link(tmp_path, monkeypatch):
    from wearcheck import outputs
    source = tmp_path / "src.msh"
    source.write_text("$MeshFormat\n")
    precious = tmp_path / "user_text.txt"
    precious.write_text("precious")
    out = tmp_path / "m.msh"
    (tmp_path / ".m.msh.wearcheck-output").symlink_to(precious)
    with pytest.raises(cases.CaseError, match="side marker"):
        outputs.write_file(out, source)
    assert precious.read_text() == "precious" and not out.exists()
    # nor inside another output
    run = tmp_path / "run"
    run.mkdir()
    outputs.write_marker(run, "run", files=outputs.inventory(run, "run"))
    with pytest.raises(cases.CaseError, match="lies inside"):
        outputs.write_file(run / "sphere.msh", source)


def test_a_comparisons_solver_folder_takes_its_own_export(tmp_path):
    from wearcheck import outputs
    comparison = tmp_path / "cmp"
    (comparison / "mdr").mkdir(parents=True)
    outputs.write_marker(comparison, "comparison",
                         files=outputs.inventory(comparison, "comparison"))
    assert outputs._inside_output(comparison / "mdr" / "vtk", "vtk") is None
    assert outputs._inside_output(comparison / "mdr" / "render", "render") is None
    assert "lies inside" in outputs._inside_output(comparison / "mdr" / "other", "run")


def test_an_output_of_an_older_wearcheck_is_not_replaced(tmp_path, capsys):
    # its marker lists no files: what the user added cannot be told apart
    old = tmp_path / "old"
    old.mkdir()
    (old / ".wearcheck-output").write_text(json.dumps(
        {"wearcheck": "output", "kind": "run", "complete": True}))
    (old / "history.csv").write_text("s\n")
    before = _snapshot(tmp_path)
    assert cli_main(["run", HERTZ, "--out", str(old), *SMALL]) == 2
    assert "older wearcheck" in _one_error_line(capsys.readouterr().err)
    assert _snapshot(tmp_path) == before


def test_an_output_of_another_kind_is_not_replaced(tmp_path):
    from wearcheck import outputs
    run = tmp_path / "run"
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    with pytest.raises(cases.CaseError, match="wearcheck run directory, not a study"):
        outputs.study_directory(run)
    # the same kind is replaced, and only the marker decides
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    assert json.loads((run / outputs.OUTPUT_MARKER).read_text())["kind"] == "run"


@pytest.mark.parametrize("existing", ["file", "device"])
def test_mesh_out_never_overwrites_a_file_it_did_not_write(tmp_path, monkeypatch, capsys,
                                                            existing):
    monkeypatch.setenv("WEARCHECK_CACHE", str(tmp_path / "cache"))
    if existing == "file":
        target = tmp_path / "notes.txt"
        target.write_text("e")
        before = target.read_bytes()
    else:
        target = Path("/dev/null")  # a device node: refused before anything is written
        before = None
    argv = ["mesh", HERTZ, "--set", "fem.contact_nodes=11", "--quiet", "--out", str(target)]
    assert cli_main(argv) == 2
    _one_error_line(capsys.readouterr().err)
    if before is not None:
        assert target.read_bytes() == before
    # a mesh file wearcheck wrote (and nobody changed since) is replaced
    own = tmp_path / "sphere.msh"
    argv[-1] = str(own)
    assert cli_main(argv) == 0 and cli_main(argv) == 0
    assert own.read_text().startswith("$MeshFormat")
    own.write_text(own.read_text() + "% my edit\n")
    assert cli_main(argv) == 2  # changed since: the user's now
    assert own.read_text().endswith("% my edit\n")


@pytest.mark.parametrize("command", ["refine", "sweep"])
def test_refine_and_sweep_refuse_a_user_directory(tmp_path, capsys, command):
    d = tmp_path / "data"
    d.mkdir()
    (d / "refinement-mdr.csv").write_text("mine")
    (d / "sweep.csv").write_text("mine")
    before = _snapshot(tmp_path)
    extra = (["--levels", "40,60"] if command == "refine"
             else ["--vary", "mdr.elements=40,60"])
    assert cli_main([command, HERTZ, "--out", str(d), "--workers", "1", *extra, "--quiet"]) == 2
    _one_error_line(capsys.readouterr().err)
    assert _snapshot(tmp_path) == before  # nothing overwritten, no meta.json added


# -- 2. hangs ----------------------------------------------------------------

def test_negative_worker_count_is_bad_input_not_a_hang(tmp_path):
    out = tmp_path / "study"
    proc = subprocess.run(_cli("refine", HERTZ, "--levels", "50,100", "--workers", "-1",
                               "--out", str(out), "--quiet"),
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert "--workers -1" in _one_error_line(proc.stderr)
    assert not out.exists()


def test_a_scheduler_without_workers_times_out_with_one_line(tmp_path):
    from distributed import LocalCluster
    with LocalCluster(n_workers=0, processes=True, dashboard_address=None,
                      host="127.0.0.1") as cluster:
        env = dict(os.environ, WEARCHECK_WORKER_TIMEOUT="2")
        t0 = time.perf_counter()
        proc = subprocess.run(_cli("refine", HERTZ, "--levels", "50,100", "--scheduler",
                                   cluster.scheduler_address, "--out", str(tmp_path / "s"),
                                   "--quiet"),
                              capture_output=True, text=True, timeout=90, env=env)
        assert time.perf_counter() - t0 < 60
    assert proc.returncode == 1
    assert "no worker" in _one_error_line(proc.stderr)


def _slow_solve(case, solver, progress=None):
    time.sleep(30.0)
    raise cases.SolverError("not reached in the test")


def test_a_study_whose_workers_all_leave_ends_instead_of_hanging(tmp_path, monkeypatch):
    """All workers of an external scheduler go away mid-study: the tasks are
    cancelled after the worker timeout and reported as failed levels."""
    import threading
    from distributed import LocalCluster
    from wearcheck.studies.refine import refine
    monkeypatch.setenv("WEARCHECK_WORKER_TIMEOUT", "2")
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        threading.Timer(2.0, lambda: cluster.scale(0)).start()
        t0 = time.perf_counter()
        summary = refine(cases.load(HERTZ), "mdr", tmp_path / "s", levels=[20, 40], quiet=True,
                         scheduler=cluster.scheduler_address, solve=_slow_solve)
        assert time.perf_counter() - t0 < 25  # well before the 30 s task would end
    assert [lv["status"].startswith("error: no worker left") for lv in summary["levels"]] \
        == [True, True]


# -- 3. bounded resources ----------------------------------------------------

@pytest.mark.parametrize("argv, key", [
    (["--set", "mdr.elements=1000000000"], "mdr.elements"),
    (["--set", "mdr.elements=99999999999999999999"], "mdr.elements"),
    (["--solver", "fem", "--set", "fem.contact_nodes=1000000"], "fem.contact_nodes"),
    (["--solver", "fem", "--revolve", "100000000"], "--revolve"),
])
def test_runs_beyond_the_memory_are_refused_before_solving(tmp_path, capsys, no_solve,
                                                           argv, key):
    code = cli_main(["run", HERTZ, "--out", str(tmp_path / "x"), "--quiet", *argv])
    line = _one_error_line(capsys.readouterr().err)
    assert code == 2
    assert key in line and "the largest" in line and "B of memory" in line
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("scheme", ["adaptive", "implicit"])
def test_the_mdr_memory_estimate_bounds_the_measured_peak(scheme):
    """The peak of a dense-factorisation MDR run (N = 1500, paper case; numpy's
    allocations as tracemalloc sees them, in a fresh process's first run: adaptive
    70 MB, implicit 127 MB on 2026-11-22 with an LU; 62 and 29 MB on 2026-11-27
    with the Cholesky factor)
    against mdr.resources: the estimate must not be below it (else a run that
    does not fit passes), nor far above (within 4x plus the 40 MB fixed
    allowance, else useful runs are refused)."""
    import tracemalloc
    from wearcheck import mdr
    from wearcheck.mdr.resources import memory_bytes
    case = cases.load(cases.shipped("paper"), ["mdr.elements=1500",
                                                f"sliding.scheme={scheme}"])
    # a fresh process's run, the largest: it also builds the compliance matrix
    # that later runs share (measured within a test session, the peak depended
    # on which runs had come before)
    from wearcheck.mdr import wear as mdr_wear
    mdr_wear._UNIT_COMPLIANCE.clear()
    tracemalloc.start()
    try:
        mdr.solve(case)
        used = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    est = memory_bytes(case)
    assert used <= est <= 4 * used + 40e6, (used, est)
    # the estimate's dense limit is the solver's
    from wearcheck.mdr import resources, wear
    assert resources._DENSE_MAX == wear.DENSE_MAX


def test_the_fem_memory_estimate_bounds_the_measured_peak():
    """Peak RSS growth of an FEM run (250 contact nodes, paper case, adaptive
    steps; sparse factor included, so measured as RSS in a fresh process: 58 MB
    when written) against fem.resources, with the same bounds as the MDR's."""
    from wearcheck.fem.resources import memory_bytes
    if not Path("/proc/self/status").exists():
        pytest.skip("needs Linux's /proc/self/status (VmHWM)")
    # VmHWM, not ru_maxrss: Linux carries ru_maxrss over from the parent (pytest)
    # through fork and exec, VmHWM belongs to the new process's memory alone
    code = ("from pathlib import Path; from wearcheck import cases; "
            "from wearcheck import registry; import wearcheck.fem; "
            "hwm = lambda: int([l for l in Path('/proc/self/status').read_text().splitlines() "
            "if l.startswith('VmHWM:')][0].split()[1]); "
            "c = cases.load(cases.shipped('paper'), ['fem.contact_nodes=250']); "
            "b = hwm(); registry.solve(c, 'fem'); print((hwm() - b) * 1024)")
    used = float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                check=True, timeout=300).stdout.split()[-1])
    est = memory_bytes(cases.load(cases.shipped("paper"), ["fem.contact_nodes=250"]))
    assert 0 < used <= est <= 4 * used + 40e6, (used, est)


# -- 4. file-system failures -------------------------------------------------

def test_out_paths_that_cannot_be_written_are_refused_before_solving(tmp_path, capsys,
                                                                     no_solve):
    a_file = tmp_path / "a_file"
    a_file.write_text("f")
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    (tmp_path / "runs" / "x").mkdir(parents=True)
    before = _snapshot(tmp_path)
    for out in (a_file / "run", tmp_path / "dangling", tmp_path / "dangling" / "run",
                f"{tmp_path}/runs/x/.."):
        assert cli_main(["run", HERTZ, "--out", str(out), *SMALL]) == 2, out
        _one_error_line(capsys.readouterr().err)
    assert _snapshot(tmp_path) == before
    assert not (tmp_path / "nowhere").exists()


@pytest.fixture
def read_only_dir(tmp_path):
    """A directory this process cannot write: chmod for a user, a read-only tmpfs for root."""
    d = tmp_path / "ro"
    d.mkdir()
    if os.geteuid() != 0:
        d.chmod(0o555)
        yield d
        d.chmod(0o755)
        return
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "none", str(d)],
                      capture_output=True).returncode != 0:
        pytest.skip("running as root without a way to make a read-only directory")
    try:
        yield d
    finally:
        subprocess.run(["umount", str(d)], capture_output=True)


def test_a_read_only_directory_is_refused_before_solving(read_only_dir, capsys, no_solve):
    assert cli_main(["run", HERTZ, "--out", str(read_only_dir / "run"), *SMALL]) == 2
    assert "not writable" in _one_error_line(capsys.readouterr().err)


def _limit_file_size():
    # a full disk, as the process sees it: writes beyond 4 kB fail with EFBIG
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))


def test_a_full_disk_is_one_line_exit_4_and_no_debris(tmp_path):
    out = tmp_path / "runs" / "x"
    out.parent.mkdir()
    proc = subprocess.run(_cli("run", HERTZ, "--out", str(out), "--set", "mdr.elements=400",
                               "--quiet"), capture_output=True, text=True, timeout=120,
                          preexec_fn=_limit_file_size)
    assert proc.returncode == 4, proc.stderr
    assert "cannot write" in _one_error_line(proc.stderr)
    assert list(out.parent.iterdir()) == []


def test_sigterm_is_handled_like_sigint(tmp_path):
    out = tmp_path / "x"
    proc = subprocess.Popen(_cli("run", cases.shipped("paper"), "--out", str(out),
                                 "--set", "mdr.elements=3000", "--quiet"),
                            stderr=subprocess.PIPE, text=True)
    # once the CLI's handler is installed (Linux: SigCgt in /proc), i.e. inside
    # the solve, which takes over 10 s
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        status = Path(f"/proc/{proc.pid}/status")
        if not status.exists():
            time.sleep(4.0)
            break
        caught = [l for l in status.read_text().splitlines() if l.startswith("SigCgt:")]
        if caught and int(caught[0].split()[1], 16) & (1 << (signal.SIGTERM - 1)):
            time.sleep(0.5)
            break
        time.sleep(0.1)
    proc.send_signal(signal.SIGTERM)
    err = proc.communicate(timeout=60)[1]
    assert proc.returncode == 143
    assert "terminated" in _one_error_line(err)
    assert list(tmp_path.iterdir()) == []


def _dead_pid() -> int:
    p = subprocess.Popen(["true"])
    p.wait()
    return p.pid


def _marker(kind, complete, pid, host=None):
    return json.dumps(dict(wearcheck="output", kind=kind, complete=complete, pid=pid,
                           host=host or platform.node()))


def test_stale_partials_of_dead_writers_are_cleaned_and_no_others(tmp_path):
    from wearcheck.outputs import OUTPUT_MARKER
    stale, live, foreign, unmarked = (tmp_path / f".x.partial-{n}" for n in "abcd")
    for d, marker in ((stale, _marker("run", False, _dead_pid())),
                      (live, _marker("run", False, os.getppid())),
                      (foreign, _marker("run", False, _dead_pid(), host="elsewhere")),
                      (unmarked, None)):
        d.mkdir()
        (d / "history.csv").write_text("s\n0\n")
        if marker:
            (d / OUTPUT_MARKER).write_text(marker)
    assert cli_main(["run", HERTZ, "--out", str(tmp_path / "x"), *SMALL]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [".x.partial-b", ".x.partial-c", ".x.partial-d", "x"])


@pytest.mark.parametrize("command", ["export", "render"])
def test_export_and_render_refuse_a_partial_directory(tmp_path, capsys, command):
    from wearcheck.outputs import OUTPUT_MARKER
    run = tmp_path / "x"
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL]) == 0
    partial = tmp_path / ".x.partial-abc"
    shutil.copytree(run, partial)
    (partial / OUTPUT_MARKER).write_text(_marker("run", False, _dead_pid()))
    assert cli_main([command, str(partial), "--quiet"]) == 2
    assert "incomplete" in _one_error_line(capsys.readouterr().err)
    assert sorted(p.name for p in partial.iterdir()) == sorted(p.name for p in run.iterdir())


def _writer(path, worker, count, queue):
    from wearcheck import outputs
    try:
        for i in range(count):
            with outputs.atomic_directory(path) as tmp:
                (tmp / "payload").write_text(f"{worker} {i}\n" * 50)
        queue.put(None)
    except BaseException as exc:  # reported to the parent
        queue.put(f"{type(exc).__name__}: {exc}")


@pytest.mark.parametrize("exchange", [True, False], ids=["exchange", "rename-fallback"])
def test_concurrent_writers_to_one_path_never_fail_nor_leave_debris(tmp_path, monkeypatch,
                                                                     exchange):
    """4 processes x 150 atomic writes to one path: no OSError, no leftover
    directory, and the path holds one complete write (the last to land); with
    the atomic exchange and with the renames of file systems without it."""
    from wearcheck.outputs import OUTPUT_MARKER
    if not exchange:
        monkeypatch.setattr("wearcheck.renames._RENAMEAT2", None)
    path = tmp_path / "out"
    ctx = multiprocessing.get_context("fork")
    queue = ctx.Queue()
    procs = [ctx.Process(target=_writer, args=(path, w, 150, queue)) for w in range(4)]
    for p in procs:
        p.start()
    errors = [queue.get(timeout=120) for _ in procs]
    for p in procs:
        p.join(timeout=60)
    assert errors == [None] * 4
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    assert sorted(p.name for p in path.iterdir()) == sorted([OUTPUT_MARKER, "payload"])
    lines = set((path / "payload").read_text().splitlines())
    assert len(lines) == 1 and lines.pop().endswith(" 149")  # a writer's last, complete


# -- 5. inputs and run directories --------------------------------------------

def test_a_case_path_with_quotes_backslashes_and_newlines_writes_valid_toml(tmp_path):
    odd = tmp_path / 'we"ird\\na\nme'
    odd.mkdir()
    case = odd / 'c"a\\se\n.toml'
    shutil.copy(HERTZ, case)
    out = tmp_path / "run"
    assert cli_main(["run", str(case), "--out", str(out), *SMALL]) == 0
    tomllib.loads((out / "case.toml").read_text(encoding="utf-8"))
    assert cases.load(out / "case.toml").mdr.elements == 40
    assert cli_main(["export", str(out), "--quiet"]) == 0


def test_a_bom_prefixed_case_file_runs_in_sweep(tmp_path):
    case = tmp_path / "bom.toml"
    case.write_bytes(b"\xef\xbb\xbf" + Path(HERTZ).read_bytes())
    assert cli_main(["sweep", str(case), "--vary", "mdr.elements=40,50", "--workers", "1",
                     "--out", str(tmp_path / "s"), "--quiet"]) == 0
    assert (tmp_path / "s" / "sweep.csv").is_file()


def test_a_latin1_profile_table_is_one_line(tmp_path, capsys):
    (tmp_path / "profile.csv").write_bytes("# Höhe\n0,0\n1e-4,1e-8\n2e-4,4e-8\n"
                                           .encode("latin-1"))
    (tmp_path / "case.toml").write_text(TABLE_CASE)
    assert cli_main(["run", str(tmp_path / "case.toml"), "--out", str(tmp_path / "x"),
                     *SMALL]) == 2
    assert "not UTF-8" in _one_error_line(capsys.readouterr().err)


def test_a_bom_in_a_profile_table_keeps_the_first_row(tmp_path):
    (tmp_path / "profile.csv").write_bytes(b"\xef\xbb\xbf0,0\n1e-4,1e-6\n2e-4,4e-6\n")
    (tmp_path / "case.toml").write_text(TABLE_CASE)
    r, f = cases.load(tmp_path / "case.toml").table
    np.testing.assert_array_equal(r, [0.0, 1e-4, 2e-4])


def test_messages_show_plain_numbers(tmp_path, capsys):
    (tmp_path / "profile.csv").write_text("0.001,0\n0.002,1e-8\n0.003,4e-8\n")
    (tmp_path / "case.toml").write_text(TABLE_CASE)
    assert cli_main(["run", str(tmp_path / "case.toml"), "--out", str(tmp_path / "x"),
                     *SMALL]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "got 0.001" in line and "np." not in line


@pytest.mark.parametrize("damage", ["truncate stages.npz", "remove stages.npz",
                                    "break meta.json", "truncate fields.npz",
                                    "break history.csv"])
@pytest.mark.parametrize("command", ["export", "render"])
def test_a_damaged_run_directory_is_one_line_naming_the_file(tmp_path, capsys, damage,
                                                             command):
    run = tmp_path / "run"
    solver = ["--solver", "fem", "--set", "fem.contact_nodes=11"] if "fields" in damage else []
    assert cli_main(["run", HERTZ, "--out", str(run), *SMALL, *solver]) == 0
    what, name = damage.split()
    path = run / name
    if what == "truncate":
        path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    elif what == "remove":
        path.unlink()
    else:
        path.write_text("{ not json" if name.endswith("json") else "garbage\n\x00\x01")
    assert cli_main([command, str(run), "--quiet"]) == 2
    assert name in _one_error_line(capsys.readouterr().err)


def test_a_truncated_mesh_cache_entry_is_rebuilt(tmp_path, monkeypatch):
    from wearcheck import meshes
    monkeypatch.setenv("WEARCHECK_CACHE", str(tmp_path))
    params = meshes.SphereMeshParameters(radius=1e-2, contact_radius=1e-4, contact_edges=5)
    first = meshes.sphere_mesh(params)
    npz = first.path.with_suffix(".npz")
    npz.write_bytes(npz.read_bytes()[:100])
    again = meshes.sphere_mesh(params)
    np.testing.assert_array_equal(again.points, first.points)
    assert again.generate_seconds > 0  # regenerated, not read


def test_fem_with_an_extreme_modulus_is_the_numerical_failure_exit(tmp_path, capsys):
    code = cli_main(["run", HERTZ, "--solver", "fem", "--set", "fem.contact_nodes=11",
                     "--set", "indenter.youngs_modulus=1e-300", "--quiet",
                     "--out", str(tmp_path / "x")])
    line = _one_error_line(capsys.readouterr().err)  # and no RuntimeWarning lines
    assert code == 3 and "np." not in line
    assert list(tmp_path.iterdir()) == []


def test_refine_rerun_where_every_level_fails_removes_the_old_figures(tmp_path, capsys):
    from wearcheck.studies.refine import refine
    from wearcheck.comparisons.present.study_figures import FIGURES
    out = tmp_path / "study"
    refine(cases.load(HERTZ), "mdr", out, levels=[20, 40, 80], workers=1, quiet=True)
    umask = os.umask(0)
    os.umask(umask)
    for name in FIGURES:
        assert stat.S_IMODE((out / name).stat().st_mode) == 0o666 & ~umask

    def failing(case, solver, progress=None):
        raise cases.SolverError("made to fail")
    summary = refine(cases.load(HERTZ), "mdr", out, levels=[20, 40, 80], workers=1, quiet=True,
                     solve=failing)
    assert all(lv["status"] != "ok" for lv in summary["levels"])
    assert not any((out / name).exists() for name in FIGURES)


def test_refine_interrupt_message_says_what_was_written(tmp_path, capsys, monkeypatch):
    def interrupted(out):
        raise KeyboardInterrupt
    # where the study calls it (wearcheck.studies.refine imports it by name at its top)
    monkeypatch.setattr("wearcheck.studies.refine.write_figures", interrupted)
    out = tmp_path / "study"
    assert cli_main(["refine", HERTZ, "--levels", "20,40", "--workers", "1", "--quiet",
                     "--out", str(out)]) == 130
    line = _one_error_line(capsys.readouterr().err)
    assert (out / "refinement-mdr.json").is_file()
    assert "the summary was written" in line


# -- an existing empty directory as --out (found by a new-user review) ------

def test_an_empty_directory_keeps_its_permissions_and_group(tmp_path, capsys):
    """``mkdir -m 700 results`` then ``--out results``: the output replaces the
    directory by a new one, which came back 0755 and in the process's group,
    readable by everyone. It now takes the mode and group of what it replaces,
    at the first run and at a re-run after the user changed them."""
    out = tmp_path / "results"
    out.mkdir(mode=0o700)
    os.chmod(out, 0o700)                 # whatever the umask
    groups = [g for g in os.getgroups() if g != os.stat(out).st_gid]
    gid = os.stat(out).st_gid
    if groups:
        with contextlib.suppress(OSError):
            os.chown(out, -1, groups[0])
            gid = groups[0]
    assert cli_main(["run", HERTZ, "--solver", "mdr", "--out", str(out), *SMALL]) == 0
    assert (out / "meta.json").is_file() and (out / ".wearcheck-output").is_file()
    assert stat.S_IMODE(out.stat().st_mode) == 0o700
    assert out.stat().st_gid == gid
    os.chmod(out, 0o750)
    assert cli_main(["run", HERTZ, "--solver", "mdr", "--out", str(out), *SMALL]) == 0
    assert stat.S_IMODE(out.stat().st_mode) == 0o750
    fresh = tmp_path / "fresh"           # a new path still gets the umask's mode
    assert cli_main(["run", HERTZ, "--solver", "mdr", "--out", str(fresh), *SMALL]) == 0
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(fresh.stat().st_mode) == 0o777 & ~umask


def _acl(*entries):
    """A POSIX access ACL as Linux stores it (xattr system.posix_acl_access):
    version 2, then (tag, permissions, id) per entry."""
    blob = (2).to_bytes(4, "little")
    for tag, perm, uid in entries:
        blob += tag.to_bytes(2, "little") + perm.to_bytes(2, "little") + uid.to_bytes(4, "little")
    return blob


def _results_acl(colleague_permissions):
    """A colleague (a uid that is not ours) and the ACL user::rwx,
    user:colleague:<permissions>, group::r-x, mask::r-x, other::---."""
    any_id = 0xFFFFFFFF
    colleague = os.getuid() + 4242
    return colleague, _acl((0x01, 7, any_id), (0x02, colleague_permissions, colleague),
                           (0x04, 5, any_id), (0x10, 5, any_id), (0x20, 0, any_id))


def test_an_empty_directory_keeps_its_acl(tmp_path):
    """``setfacl -m u:colleague:rx results`` then ``--out results``: the output
    replaced the directory and the colleague's entry was gone (the last
    session's note: only the ACLs were still lost). The ACL and the user's
    own extended attributes now come along, at the first run and a re-run."""
    out = tmp_path / "results"
    out.mkdir()
    _, acl = _results_acl(5)              # the colleague may read and enter
    try:
        os.setxattr(out, "system.posix_acl_access", acl)
        os.setxattr(out, "user.project", b"rig-7")
    except (OSError, AttributeError):
        pytest.skip("no ACLs or user extended attributes on this file system")
    mode = stat.S_IMODE(out.stat().st_mode)
    for _ in range(2):
        assert cli_main(["run", HERTZ, "--solver", "mdr", "--out", str(out), *SMALL]) == 0
        assert (out / "meta.json").is_file()
        assert os.getxattr(out, "system.posix_acl_access") == acl
        assert os.getxattr(out, "user.project") == b"rig-7"
        assert stat.S_IMODE(out.stat().st_mode) == mode == 0o750


def test_an_empty_directory_shares_its_files_by_its_default_acl(tmp_path):
    """``setfacl -d -m u:colleague:r results``: files made in the directory
    give the colleague read access. The output's files were written in a new
    directory without it and came back readable by the owner and umask only;
    the new directory now takes the default ACL before anything is written."""
    out = tmp_path / "results"
    out.mkdir()
    colleague, default = _results_acl(4)  # the colleague may read what is made here
    try:
        os.setxattr(out, "system.posix_acl_default", default)
    except (OSError, AttributeError):
        pytest.skip("no default ACLs on this file system")
    assert cli_main(["run", HERTZ, "--solver", "mdr", "--out", str(out), *SMALL]) == 0
    assert os.getxattr(out, "system.posix_acl_default") == default
    acl = os.getxattr(out / "meta.json", "system.posix_acl_access")
    entries = [(int.from_bytes(acl[i:i + 2], "little"), int.from_bytes(acl[i + 2:i + 4], "little"),
                int.from_bytes(acl[i + 4:i + 8], "little")) for i in range(4, len(acl), 8)]
    assert (0x02, 4, colleague) in entries


def test_a_mount_point_is_refused_before_solving(tmp_path, capsys, no_solve, monkeypatch):
    """An empty mount point (a scratch disk) as --out failed with exit 4 and an
    error about a '.partial' path after the whole solve: rename(2) cannot put
    a directory onto a mount point (EBUSY). Now refused at once, naming a
    directory inside it; a study, written into its directory in place, is fine."""
    out = tmp_path / "scratch"
    out.mkdir()
    real = os.path.ismount
    monkeypatch.setattr(os.path, "ismount", lambda p: str(p) == str(out) or real(p))
    for argv in (["run", HERTZ, "--solver", "mdr"], ["compare", HERTZ]):
        assert cli_main([*argv, "--out", str(out), *SMALL]) == 2
        line = _one_error_line(capsys.readouterr().err)
        assert "mount point" in line and str(out / "run") in line
    assert list(out.iterdir()) == []
    from wearcheck.outputs import study_directory
    assert study_directory(out) == out


@pytest.mark.skipif(os.geteuid() != 0 or shutil.which("mount") is None,
                    reason="mounting a tmpfs needs root")
def test_a_real_mount_point_is_refused(tmp_path, capsys, no_solve):
    out = tmp_path / "mnt"
    out.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "none", str(out)],
                      capture_output=True).returncode != 0:
        pytest.skip("this container may not mount")
    try:
        assert cli_main(["run", HERTZ, "--solver", "mdr", "--out", str(out), *SMALL]) == 2
        assert "mount point" in _one_error_line(capsys.readouterr().err)
    finally:
        subprocess.run(["umount", str(out)], check=True)


def test_mesh_out_with_a_trailing_slash_is_not_written_as_a_file(tmp_path, monkeypatch,
                                                                capsys):
    """``wearcheck mesh paper --out meshes/`` wrote a FILE named ``meshes`` (argparse's
    Path dropped the slash): the user asked for a directory. Refused, naming a file path.
    The side marker is readable like the file (mkstemp made it 0600, so another user
    sharing the mesh could not tell that wearcheck wrote it)."""
    monkeypatch.setenv("WEARCHECK_CACHE", str(tmp_path / "cache"))
    argv = ["mesh", HERTZ, "--set", "fem.contact_nodes=11", "--quiet", "--out"]
    assert cli_main([*argv, str(tmp_path / "meshes") + os.sep]) == 2
    assert "meshes/sphere.msh" in _one_error_line(capsys.readouterr().err)
    assert not (tmp_path / "meshes").exists()
    assert cli_main([*argv, str(tmp_path / "sphere.msh")]) == 0
    umask = os.umask(0)
    os.umask(umask)
    for name in ("sphere.msh", ".sphere.msh.wearcheck-output"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o666 & ~umask


def test_a_study_that_never_reached_its_scheduler_leaves_no_study_behind(tmp_path, capsys):
    """``sweep --scheduler`` with a bad address ended (exit 1) leaving DIR as an empty
    directory marked a study, which then refused a ``run`` there ("is a wearcheck study
    directory"). The marker, and a directory the study made, go when nothing ran."""
    import socket
    with socket.socket() as s:           # a port nobody listens on: refused, exit 1
        s.bind(("127.0.0.1", 0))
        refused = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    new, empty = tmp_path / "new", tmp_path / "empty"
    empty.mkdir()
    # a malformed address is bad input (exit 2), refused before DIR is touched
    for address, code in (("nonsense", 2), (refused, 1)):
        for out in (new, empty):
            assert cli_main(["sweep", HERTZ, "--vary", "wear.mu=0.2", "--scheduler", address,
                             "--out", str(out), "--quiet"]) == code
            assert "scheduler" in _one_error_line(capsys.readouterr().err)
    assert not new.exists()
    assert empty.is_dir() and list(empty.iterdir()) == []
    assert cli_main(["run", HERTZ, "--solver", "mdr", "--out", str(empty), *SMALL]) == 0


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux's /proc")
def test_a_place_that_takes_no_new_entry_is_refused_before_solving(tmp_path, capsys,
                                                                   no_solve):
    """``--out /proc/x`` passed the permission check (access() looks at the mode bits,
    and root passes them anywhere) and failed with exit 4 after the solve. The check
    now asks the file system itself, before any work."""
    for argv in (["run", HERTZ, "--solver", "mdr"], ["mesh", HERTZ]):
        out = "/proc/wearcheck-out" + (".msh" if argv[0] == "mesh" else "")
        assert cli_main([*argv, "--out", out, *SMALL]) == 2
        assert "nothing can be created in '/proc'" in _one_error_line(capsys.readouterr().err)
    # an ordinary directory is probed and left as it was
    from wearcheck.outputs import check_output
    assert check_output(tmp_path / "r", "run") == tmp_path / "r"
    assert list(tmp_path.iterdir()) == []


def test_the_working_directory_is_not_replaced_under_the_shell(tmp_path, monkeypatch,
                                                                capsys):
    """``mkdir results; cd results; wearcheck run ... --out "$PWD"``: the run replaced the
    directory by a new one and the shell stayed in the deleted one (``ls`` empty,
    ``export .`` failing). Refused, like ``--out .``, also from inside an earlier run
    (its ``vtk/``); a study, written in place, is not."""
    here = tmp_path / "results"
    here.mkdir()
    monkeypatch.chdir(here)
    assert cli_main(["run", HERTZ, "--solver", "mdr", "--out", str(here), *SMALL]) == 2
    assert "is the working directory" in _one_error_line(capsys.readouterr().err)
    assert list(here.iterdir()) == []
    run = tmp_path / "run"
    assert cli_main(["run", HERTZ, "--solver", "mdr", "--vtk", "--out", str(run), *SMALL]) == 0
    monkeypatch.chdir(run / "vtk")
    assert cli_main(["run", HERTZ, "--solver", "mdr", "--out", str(run), *SMALL]) == 2
    assert "(or holds it)" in _one_error_line(capsys.readouterr().err)
    from wearcheck.outputs import study_directory
    monkeypatch.chdir(here)
    assert study_directory(here) == here
