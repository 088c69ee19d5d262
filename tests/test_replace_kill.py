"""A SIGKILL at every step of replacing an output loses nothing (issue 20, item 1).

The writer runs in a child process that kills itself (SIGKILL, no clean-up
runs) when it reaches a given step of ``outputs.REPLACE_STEPS``: every step in
turn, with the atomic exchange of Linux and with the plain-rename fallback of
file systems without it. After each kill the invariant is checked as the kill
left it: the path holds the earlier output or the new one, whole (the
fallback: or it is missing while the earlier one waits, complete, in its
``.NAME.old-*``), and nothing hidden says complete unless it is. Then a later
write (and a read) must put everything right: the path whole again, no
``.partial-*`` or ``.old-*`` left. SIGINT and SIGTERM at every step (the
clean-up runs) the same, through the command line, whose message claims no more.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from wearcheck import outputs, temporaries

def _payload(out: Path, payload: str) -> None:
    with outputs.atomic_directory(out, "run") as tmp:
        (tmp / "payload.txt").write_text(payload)
        for i in range(20):
            (tmp / f"stage{i:02d}.bin").write_bytes(bytes([i]) * 50000)


def _writer(step, exchange, work, before=None):
    """The child: ``work()``, killing itself (SIGKILL) when it reaches ``step``;
    ``before(name)`` runs at every step first."""
    from wearcheck import renames
    if not exchange:
        renames._RENAMEAT2 = None          # as on NFS: no atomic exchange

    def hook(name):
        if before is not None:
            before(name)
        if name == step:
            os.kill(os.getpid(), signal.SIGKILL)
    outputs.STEP_HOOK = hook
    work()


#: the steps each way of replacing passes through
STEPS = {
    True: ("built", "checked", "complete", "exchanged", "retiring", "retired"),
    False: ("built", "checked", "complete", "graveyard", "aside", "installed", "retiring",
            "retired"),
}


def _fork(step, exchange, work, before=None) -> int:
    """Exit code of a forked child (quicker than a new interpreter): 0, or
    -SIGKILL where it killed itself."""
    proc = multiprocessing.get_context("fork").Process(
        target=_writer, args=(step, exchange, work, before))
    proc.start()
    proc.join(60)
    return proc.exitcode


def _write(out: Path, payload: str, step: str = "", exchange: bool = True) -> int:
    return _fork(step, exchange, lambda: _payload(out, payload))


def _content(directory: Path) -> str | None:
    """'old' or 'new' if ``directory`` holds that output whole and marked complete, else None."""
    marker = outputs.read_marker(directory)
    if not marker or marker.get("complete") is not True:
        return None
    try:
        payload = (directory / "payload.txt").read_text()
    except FileNotFoundError:
        return None
    names = sorted(p.name for p in directory.iterdir())
    whole = names == sorted([outputs.OUTPUT_MARKER, "payload.txt"]
                            + [f"stage{i:02d}.bin" for i in range(20)])
    if not whole or set(marker.get("files", {})) != set(names) - {outputs.OUTPUT_MARKER}:
        return None
    return payload


def _hidden(parent: Path) -> list[Path]:
    return sorted(p for p in parent.iterdir() if p.name.startswith(".out."))


@pytest.mark.parametrize("exchange", [True, False], ids=["exchange", "rename-fallback"])
def test_a_kill_at_each_step_leaves_the_old_or_the_new_output(tmp_path, exchange):
    out = tmp_path / "out"
    for step in outputs.REPLACE_STEPS:
        if out.exists():
            outputs.remove_tree(out)
        assert _write(out, "old", exchange=exchange) == 0
        code = _write(out, "new", step, exchange)
        if step not in STEPS[exchange]:
            assert code == 0, step     # a step of the other way
            continue
        assert code == -signal.SIGKILL, (step, code)
        # as the kill left it
        now = _content(out) if out.exists() else None
        if exchange or step not in ("aside",):
            assert now in ("old", "new"), (step, now)
        else:
            # between the two renames of the fallback: missing, the old one aside
            assert not out.exists()
            held = [p for g in _hidden(tmp_path) if ".old-" in g.name
                    for p in g.iterdir() if p.name != outputs.OUTPUT_MARKER]
            assert [_content(p) for p in held] == ["old"], step
        before = step in ("built", "checked", "complete", "graveyard")
        assert now == ("old" if before else "new" if step != "aside" else None), step
        for hidden in _hidden(tmp_path):
            marker = outputs.read_marker(hidden) or {}
            if marker.get("complete") is True:
                # nothing says complete unless it is a whole output
                assert _content(hidden) in ("old", "new"), (step, hidden.name)
        # a later read or write puts everything right
        outputs.recover(out)
        assert _content(out) == (now or "old"), step
        assert _hidden(tmp_path) == [], (step, _hidden(tmp_path))
        assert _write(out, "third", exchange=exchange) == 0
        assert _content(out) == "third"
        assert sorted(p.name for p in tmp_path.iterdir()) == ["out"], step


def test_a_kill_before_the_first_install_leaves_nothing_that_looks_complete(tmp_path):
    """No earlier output: a kill at each step leaves no output, or the whole new one."""
    out = tmp_path / "out"
    for step in ("built", "checked", "complete", "installed"):
        assert _write(out, "new", step) == -signal.SIGKILL, step
        assert (_content(out) if out.exists() else None) == (
            "new" if step == "installed" else None), step
        outputs.recover(out)
        assert _hidden(tmp_path) == [], step
        assert [p.name for p in tmp_path.iterdir()] in ([], ["out"])
        if out.exists():
            outputs.remove_tree(out)


def test_a_file_that_reached_the_old_output_survives_a_kill_after_the_swap(tmp_path):
    """The user adds a file to the earlier output after the check, the writer dies
    right after the exchange: the next write keeps the file (in sight), never deletes it."""
    out = tmp_path / "out"
    assert _write(out, "old") == 0
    def notes(name):
        if name == "checked":
            (out / "notes.txt").write_text("mine")
    assert _fork("exchanged", True, lambda: _payload(out, "new"), notes) == -signal.SIGKILL
    assert _content(out) == "new"
    assert _write(out, "third") == 0
    kept = [p for p in tmp_path.iterdir() if (p / "notes.txt").exists()]
    assert [p.name for p in kept] == ["out.kept-1"]
    assert (kept[0] / "notes.txt").read_text() == "mine"
    assert _hidden(tmp_path) == []


def test_a_complete_partial_of_an_older_wearcheck_is_removed(tmp_path):
    """What the reviewer found: a killed writer of an earlier version left a
    complete-marked ``.partial`` (no ``built_in``); the next write removes it."""
    out = tmp_path / "out"
    assert _write(out, "old") == 0
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    stale = tmp_path / ".out.partial-legacy"
    stale.mkdir()
    (stale / "payload.txt").write_text("new")
    files = outputs.inventory(stale, "run")
    (stale / outputs.OUTPUT_MARKER).write_text(json.dumps(dict(
        wearcheck="output", kind="run", complete=True, pid=int(dead),
        host=__import__("platform").node(), files=files)))
    assert _write(out, "third") == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_a_read_restores_an_output_a_kill_left_aside(tmp_path):
    """The fallback's window: the run is missing, the earlier one in ``.NAME.old-*``;
    reading the run (``export``, ``compare``'s reading) puts it back first."""
    from wearcheck import cases
    from wearcheck.cli import main as cli_main
    from wearcheck.rundir import Run
    out = tmp_path / "out"
    hertz = str(cases.shipped("hertz"))
    assert cli_main(["run", hertz, "--out", str(out), "--set", "mdr.elements=40",
                     "--quiet"]) == 0
    work = lambda: cli_main(["run", hertz, "--out", str(out), "--set", "mdr.elements=41",
                             "--quiet"])
    assert _fork("aside", False, work) == -signal.SIGKILL
    assert not out.exists()
    run = Run(out)
    assert run.case.mdr.elements == 40
    assert _hidden(tmp_path) == []


def _cli_signalled(step, exchange, signum, argv, err: Path):
    """The child: ``wearcheck`` with ``argv``, sending itself ``signum`` at ``step``;
    its stderr into ``err``, its exit code the command's."""
    from wearcheck import renames
    from wearcheck.cli import main as cli_main
    if not exchange:
        renames._RENAMEAT2 = None
    # Python's Ctrl-C handler, which it does not install where SIGINT came ignored
    # (pytest started by a non-interactive shell's `&`): the test then failed there
    signal.signal(signal.SIGINT, signal.default_int_handler)

    def hook(name):
        if name == step:
            os.kill(os.getpid(), signum)
    outputs.STEP_HOOK = hook
    fd = os.open(err, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    os.dup2(fd, 2)
    sys.stderr = open(2, "w", closefd=False)
    code = cli_main(argv)
    sys.stderr.flush()
    os._exit(code)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
@pytest.mark.parametrize("exchange", [True, False], ids=["exchange", "rename-fallback"])
def test_an_interrupt_at_each_step_leaves_the_old_or_the_new_run(tmp_path, exchange, signum):
    """SIGINT (Ctrl-C) or SIGTERM at each step of replacing a run, the fallback's
    ``aside`` (the run moved away, the new one not yet in) among them: the clean-up
    that runs puts the old run back or keeps the new one, whole, nothing hidden is
    left, and the message says no more than that (the new run may be in place)."""
    from wearcheck import cases
    from wearcheck.cli import main as cli_main
    from wearcheck.rundir import Run
    out, err = tmp_path / "out", tmp_path.parent / f"err-{tmp_path.name}"
    hertz = str(cases.shipped("hertz"))
    argv = ["run", hertz, "--out", str(out), "--quiet", "--set"]
    assert cli_main(argv + ["mdr.elements=40"]) == 0
    for step in STEPS[exchange]:
        proc = multiprocessing.get_context("fork").Process(
            target=_cli_signalled, args=(step, exchange, signum, argv + ["mdr.elements=41"], err))
        proc.start()
        proc.join(60)
        assert proc.exitcode == 128 + signum, (step, proc.exitcode)   # 130, 143
        said = err.read_text()
        assert "nothing incomplete was written" in said and "nothing was written" not in said
        before = step in ("built", "checked", "complete", "graveyard", "aside")
        # once the new run is in place the message says so, naming it (before: the same
        # words as for an interrupt that left the earlier run)
        after = f"after its output was complete: '{out}' holds it, whole"
        assert (after in said) == (not before), (step, said)
        left = [p.name for p in tmp_path.iterdir() if p.name != "out"]
        if step == "retiring":
            # interrupted while removing the old run (new one in place): what is left
            # of it does not say complete, and the next read removes it, as after a kill
            assert all((outputs.read_marker(tmp_path / n) or {}).get("complete") is not True
                       for n in left), left
            outputs.recover(out)
        else:
            assert left == [], (step, signum, left)
        assert sorted(p.name for p in tmp_path.iterdir()) == ["out"], (step, signum)
        assert Run(out).case.mdr.elements == (40 if before else 41), (step, signum)
        if not before:
            assert cli_main(argv + ["mdr.elements=40"]) == 0


_PROGRAM = """
import os, signal, sys
from wearcheck import outputs
from wearcheck.cli import main
when, out = sys.argv[1], sys.argv[2]


class AtClose:
    def __del__(self):         # runs while the interpreter closes (its modules torn down)
        os.kill(os.getpid(), signal.SIGINT)


if when == "installed":          # the new run in place, its last messages not yet written
    outputs.STEP_HOOK = lambda step: step in ("exchanged", "installed") and os.kill(
        os.getpid(), signal.SIGINT)
elif when == "closing":
    at_close = AtClose()
sys.argv = ["wearcheck", "run", "hertz", "--out", out, "--set", "mdr.elements=40"]
code = main()                    # as the console script: sys.exit(main())
if when == "returned":
    os.kill(os.getpid(), signal.SIGINT)
sys.exit(code)
"""


@pytest.mark.parametrize("when", ["installed", "returned", "closing"])
def test_a_ctrl_c_once_the_run_is_in_place_is_said_in_one_line_or_ignored(tmp_path, when):
    """Ctrl-C once the new run is installed, as the command (the console script's
    ``sys.exit(main())``) finishes: while it writes its last lines, one line naming the
    output, whole, and exit 130; after its last line, as main returns or while the
    interpreter closes (about 0.2 s, with Ctrl-C at its default), it is ignored and the
    command's own code stands. Before: a traceback, or the process ended by the signal
    with no word. The child gets SIGINT's default disposition: started from a
    non-interactive shell's ``&`` it would inherit it ignored."""
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-c", _PROGRAM, when, str(out)],
                          capture_output=True, text=True, timeout=120,
                          preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert "Traceback" not in proc.stderr, proc.stderr
    lines = proc.stderr.strip().splitlines()
    if when == "installed":
        assert proc.returncode == 130, proc.stderr
        assert lines[-1] == (f"wearcheck run: interrupted after its output was complete: "
                             f"'{out}' holds it, whole; nothing incomplete was written")
    else:
        assert proc.returncode == 0, proc.stderr
        assert lines[-1].startswith("mdr: ") and lines[-1].endswith(f"-> {out}")
    from wearcheck.rundir import Run
    assert Run(out).case.mdr.elements == 40          # the run, whole
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_an_interrupt_once_the_comparison_is_in_place_names_it(tmp_path, monkeypatch,
                                                                capsys):
    """``compare`` the same way: Ctrl-C (here raised at the step that put the new
    comparison in place) says the comparison directory is whole, exit 130."""
    from wearcheck.cli import main as cli_main

    def hook(step):
        if step == "installed":
            raise KeyboardInterrupt
    monkeypatch.setattr(outputs, "STEP_HOOK", hook)
    out = tmp_path / "cmp"
    code = cli_main(["compare", "hertz", "--solvers", "mdr,bem", "--no-render", "--quiet",
                     "--set", "mdr.elements=50", "--set", "bem.grid=32", "--out", str(out)])
    assert code == 130
    assert capsys.readouterr().err.strip().splitlines()[-1] == (
        f"wearcheck compare: interrupted after its output was complete: '{out}' holds it, "
        "whole; nothing incomplete was written")
    assert _content_is_whole(out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cmp"]


def _content_is_whole(directory: Path) -> bool:
    """Complete, and holding exactly the files its marker lists (nothing missing or added)."""
    marker = outputs.read_marker(directory) or {}
    listed = set(marker.get("files", {}))
    present = {str(p.relative_to(directory)) for p in directory.rglob("*")
               if p.name != outputs.OUTPUT_MARKER}
    return marker.get("complete") is True and "metrics.json" in listed and listed == present \
        and outputs.foreign_content(directory) is None


@pytest.mark.parametrize("step", outputs.STUDY_FILE_STEPS)
def test_a_kill_while_a_study_file_is_replaced_leaves_one_the_next_study_takes(tmp_path,
                                                                              step):
    """A study's sweep.csv replaced by a second sweep, the writer killed between the
    file and its marker: the file is the old or the new, and the next study into
    the directory takes it as its own (before, the marker listed the old file's
    fingerprint only, and every later study refused the new one as foreign)."""
    study = outputs.study_directory(tmp_path / "study")
    outputs.write_study_text(study, "sweep.csv", "old\n")
    code = _fork(step, True, lambda: outputs.write_study_text(study, "sweep.csv", "new\n"))
    assert code == -signal.SIGKILL
    assert (study / "sweep.csv").read_text() in ("old\n", "new\n")
    outputs.study_directory(study, files=["sweep.csv"])        # accepted, not refused
    # and the killed writer's temporary file is gone with it
    assert sorted(p.name for p in study.iterdir()) == [".wearcheck-output", "sweep.csv"]
    outputs.write_study_text(study, "sweep.csv", "third\n")
    assert (study / "sweep.csv").read_text() == "third\n"
    outputs.study_directory(study, files=["sweep.csv"])
    # a file the user changed is still refused
    (study / "sweep.csv").write_text("mine\n")
    with pytest.raises(outputs.OutputError, match="not a file wearcheck wrote"):
        outputs.study_directory(study, files=["sweep.csv"])


@pytest.mark.parametrize("step", outputs.FILE_STEPS)
def test_a_kill_while_a_mesh_file_is_replaced_leaves_one_the_next_write_takes(tmp_path, step):
    """``mesh --out FILE`` replaced, the writer killed between the file and its side
    marker: the file is the old or the new one, whole, and the next write replaces
    it (before, the side marker still held the old file's SHA-256 and every later
    write refused the new file as not wearcheck's)."""
    old, new, out = tmp_path / "old.msh", tmp_path / "new.msh", tmp_path / "m.msh"
    old.write_text("$MeshFormat old\n")
    new.write_text("$MeshFormat new\n")
    outputs.write_file(out, old)
    code = _fork(step, True, lambda: outputs.write_file(out, new))
    assert code == -signal.SIGKILL
    assert out.read_text() in (old.read_text(), new.read_text())
    outputs.write_file(out, old)                      # accepted, not refused
    assert out.read_text() == old.read_text()
    # the killed writer's temporary file is gone
    assert sorted(p.name for p in tmp_path.iterdir()) == [".m.msh.wearcheck-output",
                                                          "m.msh", "new.msh", "old.msh"]
    side = json.loads((tmp_path / ".m.msh.wearcheck-output").read_text())
    assert "replacing" not in side                    # the write finished: one file only
    # a file the user changed is still refused, and so is the one it replaced
    out.write_text("mine\n")
    with pytest.raises(outputs.OutputError, match="not a file wearcheck wrote"):
        outputs.write_file(out, new)
    assert out.read_text() == "mine\n"


def test_only_the_temporary_files_of_dead_writers_of_this_host_are_removed(tmp_path):
    """A temporary file names its writer (pid and host): one of a process that is
    gone is debris, one of a running process or of another host (a directory shared
    over NFS) is left alone, and so is a file of the same shape without that name."""
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    names = {
        "dead": temporaries.new(tmp_path, "sweep.csv", ".csv").name.replace(
            f"-{os.getpid()}@", f"-{dead.pid}@"),
        "alive": temporaries.new(tmp_path, "sweep.csv", ".csv").name,
        "other host": f".sweep.csv.partial-{dead.pid}@00000000@abcdefgh.csv",
        "user": ".sweep.csv.partial-notes.csv",
    }
    for name in names.values():
        (tmp_path / name).write_text("x")
    assert temporaries.remove_dead(tmp_path) == [tmp_path / names["dead"]]
    assert {p.name for p in tmp_path.iterdir()} >= {names["alive"], names["other host"],
                                                    names["user"]}
    assert not (tmp_path / names["dead"]).exists()


def _record_study_slowly(study, name, entered, released):
    """The child: records its study, pausing (up to 3 s) once it has read meta.json and
    listed its new file, until the parent says its own study has been recorded."""
    from wearcheck import cases
    from wearcheck.studies.distributed import record_study

    def hook(step):
        if step == "study-file-listed" and not entered.is_set():
            entered.set()
            released.wait(3.0)
    outputs.STEP_HOOK = hook
    record_study(study, name, cases.load(cases.shipped("hertz")), dict(command=name))


def test_two_studies_ending_at_once_into_one_directory_keep_both(tmp_path):
    """Two studies (a sweep and a refinement, or two sweeps) that end at the same time
    each read meta.json, add their entry and write it back: without a lock the one
    that writes last drops the other's entry (seen with two concurrent sweeps, whose
    sweep.csv kept the rows of one). The child pauses between its read and its
    write while the parent records its own study: the parent must wait for it."""
    import threading
    from wearcheck import cases
    from wearcheck.studies.distributed import record_study, study_meta
    study = outputs.study_directory(tmp_path / "s")
    ctx = multiprocessing.get_context("fork")
    entered, released = ctx.Event(), ctx.Event()
    child = ctx.Process(target=_record_study_slowly,
                        args=(study, "sweep-mdr", entered, released))
    child.start()
    assert entered.wait(60)
    parent = threading.Thread(target=record_study, args=(study, "refine-mdr",
                                                         cases.load(cases.shipped("hertz")),
                                                         dict(command="refine-mdr")))
    parent.start()
    parent.join(30)
    released.set()
    child.join(60)
    parent.join(30)
    assert child.exitcode == 0 and not parent.is_alive()
    assert set(study_meta(study)["studies"]) == {"sweep-mdr", "refine-mdr"}
    outputs.study_directory(study, files=["meta.json"])     # and the marker agrees
