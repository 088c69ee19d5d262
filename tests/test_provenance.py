"""Provenance: which wearcheck produced an output (version, and the git revision only
when running from a wearcheck checkout)."""

import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from wearcheck import rundir as runio

REPO = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]

needs_git = pytest.mark.skipif(shutil.which("git") is None, reason="git is not installed")


def _git(cwd, *args):
    env = dict(os.environ, GIT_AUTHOR_NAME="u", GIT_AUTHOR_EMAIL="u@example.org",
               GIT_COMMITTER_NAME="u", GIT_COMMITTER_EMAIL="u@example.org")
    return subprocess.run(["git", *args], cwd=cwd, check=True, capture_output=True, text=True,
                          env=env).stdout.strip()


def test_version_is_the_projects():
    # the version comes from the package's metadata, which pyproject.toml declares
    assert runio.wearcheck_version() == PYPROJECT["version"]
    prov = runio.provenance(["wearcheck", "run"])
    assert prov["wearcheck_version"] == PYPROJECT["version"]
    assert prov["versions"]["wearcheck"] == PYPROJECT["version"]


@needs_git
def test_revision_from_a_wearcheck_checkout():
    # the tests run from the source tree: when that is a git checkout whose top level
    # is the repository root, its HEAD is the recorded revision
    top = subprocess.run(["git", "rev-parse", "--show-toplevel"], cwd=REPO,
                         capture_output=True, text=True)
    if top.returncode != 0 or Path(top.stdout.strip()).resolve() != REPO:
        pytest.skip("the tests do not run from a git checkout of wearcheck")
    if Path(runio.__file__).resolve().parent.parent != REPO:
        pytest.skip("wearcheck is not imported from this checkout")
    head = _git(REPO, "rev-parse", "HEAD")
    assert runio.source_checkout() == REPO
    assert runio.git_revision().removesuffix("-dirty") == head


@needs_git
@pytest.mark.slow
def test_installed_inside_another_git_repository_records_no_revision(tmp_path):
    # The reported bug: installed into a user's own project, meta.json named the
    # user's commit (and its "-dirty") as wearcheck's revision.
    user = tmp_path / "userproject"
    user.mkdir()
    _git(user, "init", "-q")
    (user / "notes.txt").write_text("the user's own work\n")
    _git(user, "add", "notes.txt")
    _git(user, "commit", "-q", "-m", "user's commit")
    user_head = _git(user, "rev-parse", "HEAD")
    (user / "notes.txt").write_text("changed, so the user's tree is dirty\n")
    target = user / "site"
    # build from a copy: setuptools leaves build/ in the source tree, whose stale
    # files could leak into later wheels
    source = tmp_path / "source"
    shutil.copytree(REPO, source, ignore=shutil.ignore_patterns(
        ".git", ".venv", "build", "dist", "runs", "*.egg-info", "__pycache__", ".pytest_cache"))
    pip = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps",
                          "--target", str(target), str(source)],
                         capture_output=True, text=True, timeout=600)
    assert pip.returncode == 0, pip.stderr[-2000:]
    # package data: the shipped cases and the case file's JSON Schema
    for name in ("paper.toml", "case.schema.json"):
        assert (target / "wearcheck" / "cases" / name).is_file(), name
    probe = ("import json; from wearcheck import rundir as runio; "
             "print(json.dumps([runio.__file__, runio.git_revision(), "
             "runio.source_checkout() and str(runio.source_checkout()), "
             "runio.provenance(['wearcheck'])]))")
    env = dict(os.environ, PYTHONPATH=str(target))
    done = subprocess.run([sys.executable, "-c", probe], cwd=user, env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    import json
    file, revision, checkout, prov = json.loads(done.stdout)
    # the probe must have imported the installed copy, not this checkout
    assert Path(file).resolve().is_relative_to(target.resolve())
    assert revision is None and checkout is None
    assert prov["git_revision"] is None
    assert user_head not in json.dumps(prov)
    assert prov["wearcheck_version"] == PYPROJECT["version"]
