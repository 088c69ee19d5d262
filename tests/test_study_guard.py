"""A study on Dask called at the top level of a script: Dask's worker processes
import the script that starts them, which started the study again in each; the
user got pages of multiprocessing tracebacks ending in "Nanny failed to start"."""

import subprocess
import sys
import types

import pytest

from wearcheck.studies import distributed


@pytest.mark.filterwarnings("ignore")
def test_an_unguarded_script_is_told_to_guard_its_study(tmp_path):
    pytest.importorskip("distributed")
    script = tmp_path / "my_sweep.py"
    script.write_text(
        "import wearcheck\n"
        "case = wearcheck.load_case('hertz', {'mdr.elements': 50})\n"
        "wearcheck.sweep(case, {'wear.mu': [0.2, 0.4]}, 'out', workers=1)\n",
        encoding="utf-8")
    run = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300)
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
