"""What a study on Dask says when a script runs it: called at the top level of a
script, Dask's worker processes import the script that starts them, which
started the study again in each (pages of multiprocessing tracebacks ending in
"Nanny failed to start"); the runs' remarks were said by every worker,
attributed to dask's task code."""

import json

import subprocess
import sys
import types

import pytest

from wearcheck.studies import distributed


def _run_script(tmp_path, text):
    """Write ``text`` as a script in tmp_path and run it there: (its path, the run)."""
    script = tmp_path / "my_sweep.py"
    script.write_text(text, encoding="utf-8")
    return script, subprocess.run([sys.executable, str(script)], cwd=tmp_path,
                                  capture_output=True, text=True, timeout=300)


@pytest.mark.filterwarnings("ignore")
def test_an_unguarded_script_is_told_to_guard_its_study(tmp_path):
    pytest.importorskip("distributed")
    script, run = _run_script(
        tmp_path,
        "import wearcheck\n"
        "case = wearcheck.load_case('hertz', {'mdr.elements': 50})\n"
        "wearcheck.sweep(case, {'wear.mu': [0.2, 0.4]}, 'out', workers=1)\n")
    assert run.returncode != 0
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith("wearcheck.cases.errors.WearcheckError:"), run.stderr[-3000:]
    assert 'if __name__ == "__main__":' in last and str(script) in last
    # the workers said it too, instead of multiprocessing's bootstrapping error
    assert "bootstrapping phase" not in run.stderr


def test_a_guarded_script_or_no_script_is_not_blamed(tmp_path, monkeypatch):
    guarded = tmp_path / "guarded.py"
    guarded.write_text("if __name__ == '__main__':\n    pass\n", encoding="utf-8")
    bare = tmp_path / "bare.py"
    bare.write_text("import wearcheck\n", encoding="utf-8")
    for path, expected in ((guarded, None), (bare, str(bare))):
        main = types.ModuleType("__main__")
        main.__file__, main.__spec__ = str(path), None
        monkeypatch.setitem(sys.modules, "__main__", main)
        assert distributed._script() == expected
    # a notebook's or a prompt's __main__ has no file
    monkeypatch.setitem(sys.modules, "__main__", types.ModuleType("__main__"))
    assert distributed._script() is None


@pytest.mark.filterwarnings("ignore")
def test_the_runs_remarks_are_in_their_runs_not_said_by_the_workers(tmp_path):
    pytest.importorskip("distributed")
    # the paper case passes the onset of yield: every run has that remark
    _, run = _run_script(
        tmp_path,
        "import wearcheck\n"
        "if __name__ == '__main__':\n"
        "    case = wearcheck.load_case('paper', {'mdr.elements': 100, "
        "'sliding.force_fraction': 0.5})\n"
        "    rows = wearcheck.sweep(case, {'wear.mu': [0.2, 0.4]}, 'out', workers=1)\n"
        "    print([r['status'] for r in rows])\n")
    assert run.returncode == 0, run.stderr[-3000:]
    assert "['ok', 'ok']" in run.stdout
    assert "_task_spec" not in run.stderr and "onset of yield" not in run.stderr, run.stderr
    for mu in ("0.2", "0.4"):
        meta = json.loads((tmp_path / "out" / f"mdr-wear.mu-{mu}" / "meta.json").read_text())
        assert any("onset of yield" in w for w in meta["warnings"])
