"""A checkout imports from its own root without being installed (issue 22 §9).

The copy is made of the folders ``pyproject.toml`` maps into the wearcheck
namespace (its ``package-dir``), so the test follows the packaging, not a list
of its own. Each check runs in a fresh interpreter started in the copy, and
asks where the modules were found.
"""

import json
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _copy_checkout(dest: Path, with_pyproject: bool = True) -> Path:
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    folders = set(pyproject["tool"]["setuptools"]["package-dir"].values())
    for folder in folders:
        shutil.copytree(ROOT / folder, dest / folder,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    if with_pyproject:
        shutil.copy(ROOT / "pyproject.toml", dest / "pyproject.toml")
    return dest


def _run(code: str, cwd: Path) -> dict:
    out = subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_a_clone_imports_and_solves_from_its_root(tmp_path):
    clone = _copy_checkout(tmp_path / "clone")
    got = _run("import json, wearcheck, wearcheck.cases, wearcheck.mdr.solver, "
               "wearcheck.cli\n"
               "r = wearcheck.solve('hertz')\n"
               "print(json.dumps(dict(files=[m.__file__ for m in (wearcheck, wearcheck.cases, "
               "wearcheck.mdr.solver, wearcheck.cli)], "
               "force=float(r.history['force'][0] / r.scales['F0']))))", clone)
    # every module from the clone's own folders, none from an installed wearcheck
    for file in got["files"]:
        assert Path(file).resolve().is_relative_to(clone.resolve()), file
    # the unworn Hertz case holds F = F0 (the MDR is exact for it up to its grid; the
    # shipped resolution's spatial error is ~1e-4, docs/limits.md): 1e-3 is far from
    # any import accident (which would not run at all) and loose for the grid
    assert abs(got["force"] - 1.0) < 1e-3


def test_an_installed_wearcheck_does_not_search_its_parent(tmp_path):
    # site-packages holds wearcheck/ beside other packages (even one named "cases")
    # but no pyproject.toml: the parent must not join wearcheck's search path
    site = _copy_checkout(tmp_path / "site", with_pyproject=False)
    code = ("import importlib.util, json, sys\n"
            "spec = importlib.util.find_spec('wearcheck')\n"
            "module = importlib.util.module_from_spec(spec)\n"
            "sys.modules['wearcheck'] = module\n"
            "try:\n    spec.loader.exec_module(module)\n"
            "except ImportError:\n    pass  # an un-installed copy without pyproject: expected\n"
            "print(json.dumps(list(module.__path__)))")
    path = _run(code, site)
    assert [Path(p).resolve() for p in path] == [(site / "wearcheck").resolve()]
