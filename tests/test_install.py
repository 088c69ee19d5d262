"""wearcheck installs as one namespace: the wheel holds ``wearcheck/...`` only, the old
top-level names (``cases``, ``mdr``, ...) are not importable, and the command works
from any directory. Built with pip as a user's ``pip install .`` would build it."""

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("install")
    # build from a copy of the sources: a build/ folder left in the checkout would
    # lend the wheel files that the package list forgot
    source = tmp / "source"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(
        ".git", "build", "dist", "*.egg-info", "runs", "__pycache__", ".pytest_cache"))
    wheels = tmp / "wheels"
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q",
                            "-w", str(wheels), str(source)], capture_output=True, text=True,
                           timeout=600)
    assert build.returncode == 0, build.stderr[-2000:]
    wheel = next(wheels.glob("wearcheck-*.whl"))
    target = tmp / "site"
    done = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q",
                           "--target", str(target), str(wheel)], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return wheel, target, tmp


def _python(target, cwd, *args, timeout=300):
    # the wheel's copy first on the path; the working directory holds no wearcheck source
    env = dict(os.environ, PYTHONPATH=str(target), MPLBACKEND="Agg")
    return subprocess.run([sys.executable, *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=timeout)


def test_wheel_holds_one_namespace(installed):
    wheel, _, _ = installed
    names = zipfile.ZipFile(wheel).namelist()
    tops = {n.split("/")[0] for n in names}
    info = {t for t in tops if t.endswith(".dist-info")}
    assert len(info) == 1 and tops - info == {"wearcheck"}
    for package in ("cases", "mdr", "fem", "bem", "meshes", "comparisons", "cli", "studies"):
        assert f"wearcheck/{package}/__init__.py" in names
    assert "wearcheck/cases/paper.toml" in names


def test_old_top_level_names_are_gone_and_wearcheck_imports(installed, tmp_path):
    _, target, _ = installed
    code = ("import importlib.util, wearcheck, wearcheck.mdr, wearcheck.fem\n"
            "import wearcheck.comparisons.present, wearcheck.cli.run\n"
            "assert wearcheck.comparisons.present.__file__.startswith(wearcheck.__path__[0])\n"
            "print(wearcheck.__file__)\n"
            "print([n for n in ('cases', 'mdr', 'fem', 'meshes', 'comparisons')"
            " if importlib.util.find_spec(n)])\n")
    done = _python(target, tmp_path, "-c", code)
    assert done.returncode == 0, done.stderr
    where, found = done.stdout.splitlines()
    assert where.startswith(str(target))
    assert found == "[]"


def test_command_line_from_another_directory(installed, tmp_path):
    _, target, _ = installed
    case = Path(target) / "wearcheck" / "cases" / "hertz.toml"
    done = _python(target, tmp_path, "-m", "wearcheck", "run", str(case), "--solver", "mdr",
                   "--out", "hertz-run", "--quiet")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "hertz-run" / "meta.json").is_file()


def test_certified_references_ship_and_load(installed, tmp_path):
    wheel, target, _ = installed
    names = zipfile.ZipFile(wheel).namelist()
    shipped = sorted(n for n in names if n.startswith("wearcheck/references/data/"))
    assert [n.rsplit("/", 1)[1] for n in shipped] == sorted(
        f"{c}.npz" for c in ("ball_on_flat", "ellipsoid", "fretting", "hertz", "paper",
                             "truncated"))
    code = ("import wearcheck\n"
            "r = wearcheck.reference('hertz')\n"
            "print(r.certified.name, r.history['force'][0] > 0)\n")
    done = _python(target, tmp_path, "-c", code)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["hertz", "True"]
