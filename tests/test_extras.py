"""Install by extras: the core (numpy, scipy, threadpoolctl, tqdm) runs the MDR and
the BEM; a command that needs a missing extra says which, in one line.

The optional modules are made missing in a subprocess by a ``sys.meta_path``
finder that raises ModuleNotFoundError for them, as Python does for a package
that is not installed; pyproject.toml is read with tomllib, and the package's own
imports with ast (independent of wearcheck/extras.py, which they check).
"""

import ast
import json
import os
import re
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

from wearcheck import extras

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
#: what the core install holds (issue 27 §5)
CORE = {"numpy", "scipy", "threadpoolctl", "tqdm"}
#: every optional module, as the brief lists them (not read from extras.MODULES)
OPTIONAL = ("skfem", "gmsh", "pyvista", "vtk", "dask", "distributed", "matplotlib", "meshio",
            "pandas", "xarray", "ipywidgets")

BLOCKER = textwrap.dedent("""
    import sys
    BLOCKED = set(sys.argv.pop(1).split(","))

    class Missing:
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in BLOCKED:
                raise ModuleNotFoundError(f"No module named {name!r}", name=name)
            return None

    sys.meta_path.insert(0, Missing())
    if sys.argv[1] == "-c":
        exec(sys.argv[2])
    else:   # command lines (JSON), each through the CLI: [exit code, its stderr] each
        import contextlib, io, json
        from wearcheck.cli import main
        out = []
        for argv in json.loads(sys.argv[1]):
            err = io.StringIO()
            with contextlib.redirect_stderr(err):
                out.append([main(argv), err.getvalue()])
        print(json.dumps(out))
""")
#: short runs: 0.1 mm of sliding on the paper case (the MDR's and BEM's first steps)
SHORT = ["--set", "sliding.until=distance", "--set", "sliding.distance=1e-4", "--quiet"]


@pytest.fixture(scope="module")
def blocked(tmp_path_factory):
    """``blocked(*argv, missing=OPTIONAL)``: the command line (or ``-c code``) in a fresh
    Python in which the ``missing`` modules cannot be imported."""
    script = tmp_path_factory.mktemp("blocker") / "blocked.py"
    script.write_text(BLOCKER, encoding="utf-8")

    def run(*argv, missing=OPTIONAL):
        env = dict(os.environ, MPLBACKEND="Agg")
        return subprocess.run([sys.executable, str(script), ",".join(missing), *argv],
                              capture_output=True, text=True, timeout=600, env=env)
    return run


def _commands(blocked, *argvs):
    """Each command line's [exit code, stderr], run in one blocked process."""
    done = blocked(json.dumps(argvs))
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.splitlines()[-1])


def _one_line(outcome, extra):
    """The command failed with exit 2 and one error line naming ``extra``'s install."""
    code, stderr = outcome
    lines = [line for line in stderr.splitlines() if not line.startswith("note:")]
    assert code == 2, stderr[-2000:]
    assert len(lines) == 1, stderr[-2000:]
    assert f'pip install "wearcheck[{extra}]"' in lines[0], lines[0]
    assert "Traceback" not in stderr
    return lines[0]


def test_the_core_runs_the_mdr_and_the_bem_and_says_what_the_others_need(blocked, tmp_path):
    mdr, bem = tmp_path / "mdr", tmp_path / "bem"
    vtu = tmp_path / "elsewhere.vtu"
    vtu.write_text("<VTKFile/>", encoding="utf-8")
    ran_mdr, ran_bem, fem, compare, render, export, vtk, sweep, mesh, verify = _commands(
        blocked,
        ["run", "paper", "--solver", "mdr", "--set", "mdr.elements=200", *SHORT, "--out", str(mdr)],
        ["run", "paper", "--solver", "bem", "--set", "bem.grid=32", *SHORT, "--out", str(bem)],
        ["run", "paper", "--solver", "fem", *SHORT, "--out", str(tmp_path / "fem")],
        ["compare", "paper", "--out", str(tmp_path / "c")],
        ["render", str(mdr)], ["export", str(mdr)],
        ["run", "paper", "--solver", "mdr", "--vtk", "--out", str(tmp_path / "v")],
        ["sweep", "paper", "--vary", "wear.mu=0.2,0.3", "--solver", "mdr",
         "--out", str(tmp_path / "s")],
        ["mesh", "paper"], ["verify", "paper", str(vtu), "--out", str(tmp_path / "w")])
    assert ran_mdr == [0, ""] and ran_bem == [0, ""]
    for run in (mdr, bem):   # complete run directories, recording the missing versions
        meta = json.loads((run / "meta.json").read_text(encoding="utf-8"))
        assert (run / "history.csv").is_file() and (run / "stages.npz").is_file()
        # every optional package's version recorded (None where not installed; here
        # hidden from import only, so its metadata still gives one)
        assert meta["versions"]["numpy"] and "scikit-fem" in meta["versions"]
    assert "the FEM needs scikit-fem" in _one_line(fem, "fem")
    # compare draws figures: said before any solve
    assert "matplotlib" in _one_line(compare, "plot")
    for said in (render, export, vtk):
        assert "pyvista" in _one_line(said, "vtk")
    assert "distributed" in _one_line(sweep, "dask")
    assert "scikit-fem" in _one_line(mesh, "fem")
    assert "meshio" in _one_line(verify, "vtk")
    for nothing in ("fem", "c", "v", "s", "w"):   # refused before anything was written
        assert not (tmp_path / nothing).exists()


def test_run_reports_without_their_figures_say_which_extra(blocked, tmp_path):
    """The MDR's fretting report and the BEM's both-bodies report draw figures and
    write ParaView files; on the core they are written without them, saying why."""
    fretting, track = tmp_path / "fretting", tmp_path / "track"
    outcomes = _commands(
        blocked,
        ["run", "fretting", "--solver", "mdr", "--set", "mdr.elements=100",
         "--set", "fretting.cycles=10", "--quiet", "--out", str(fretting)],
        # (the moving-contact model: the long-stroke one fails on main at the time of
        # writing, 'TrackOperator' object has no attribute 'single', with every extra)
        ["run", "ball_on_flat_steel", "--solver", "bem", "--set", "bem.grid=32",
         "--set", "bem.track_model=moving", "--set", "sliding.until=distance", "--set", "sliding.distance=1e-3", "--quiet",
         "--out", str(track)])
    assert outcomes == [[0, ""], [0, ""]]
    said = (fretting / "report.md").read_text(encoding="utf-8")
    assert 'No figures: drawing figures needs matplotlib: pip install "wearcheck[plot]"' in said
    said = (track / "report.md").read_text(encoding="utf-8")
    assert 'needs pyvista: pip install "wearcheck[vtk]"' in said
    assert 'needs matplotlib: pip install "wearcheck[plot]"' in said
    assert (track / "track_profile.csv").is_file()


def test_a_solver_without_its_extra_is_listed_as_skipped_with_the_reason(blocked):
    code = ("import json, wearcheck\n"
            "from wearcheck import registry\n"
            "from wearcheck.studies.compare import skipped_solvers\n"
            "case = wearcheck.load_case('paper')\n"
            "print(json.dumps(dict(supporting=registry.supporting(case),\n"
            "                      skipped=skipped_solvers(case, ['mdr', 'bem']))))\n"
            "try:\n"
            "    wearcheck.solve(case, 'fem')\n"
            "except ModuleNotFoundError as exc:\n"
            "    print(type(exc).__name__, exc.name, exc)\n")
    done = blocked("-c", code, missing=("skfem", "gmsh"))
    assert done.returncode == 0, done.stderr[-2000:]
    first, second = done.stdout.splitlines()
    listed = json.loads(first)
    assert "fem" not in listed["supporting"] and {"mdr", "bem"} <= set(listed["supporting"])
    assert listed["skipped"]["fem"] == 'the FEM needs scikit-fem: pip install "wearcheck[fem]"'
    # the Python API raises it as a ModuleNotFoundError (a WearcheckError too)
    assert second.startswith("MissingExtra skfem the FEM needs scikit-fem")


def test_a_missing_extra_in_python_is_a_module_not_found_error_and_a_wearcheck_error():
    exc = extras.missing("rendering", ModuleNotFoundError("No module named 'vtk'", name="vtk"))
    assert isinstance(exc, ModuleNotFoundError) and exc.exit_code == 2
    assert str(exc) == 'rendering needs vtk: pip install "wearcheck[vtk]"'
    # a module that is not optional stays the error it is (a bug, not an install)
    assert extras.missing("x", ModuleNotFoundError("No module named 'nope'", name="nope")) is None
    assert extras.missing("x", ImportError("cannot import name 'y'", name="numpy")) is None


def _extra_requirements(extra, seen=()):
    """The distributions an extra installs, self-references (wearcheck[a,b]) followed."""
    out = set()
    for requirement in PYPROJECT["project"]["optional-dependencies"][extra]:
        name = re.match(r"[A-Za-z0-9_.-]+", requirement).group(0).lower()
        if name == "wearcheck":
            for other in re.search(r"\[(.*)\]", requirement).group(1).split(","):
                if other.strip() not in seen:
                    out |= _extra_requirements(other.strip(), (*seen, extra))
        else:
            out.add(name)
            out |= {f"{name}[{e.strip()}]" for e in
                    (re.search(r"\[(.*)\]", requirement) or [None, ""])[1].split(",") if e}
    return out


def test_pyproject_core_is_the_four_and_every_extra_is_declared():
    core = {re.match(r"[A-Za-z0-9_.-]+", r).group(0).lower()
            for r in PYPROJECT["project"]["dependencies"]}
    assert core == CORE
    declared = PYPROJECT["project"]["optional-dependencies"]
    for module in OPTIONAL:
        distribution, extra = extras.MODULES[module]
        assert extra in declared, (module, extra)
        if module == "vtk":           # pyvista's dependency: named for a broken pyvista
            assert "pyvista" in _extra_requirements(extra)
        elif module == "distributed":
            assert "dask[distributed]" in _extra_requirements(extra)
        else:
            assert distribution.lower() in _extra_requirements(extra), (module, extra)
    everything = _extra_requirements("all")
    for extra in ("fem", "vtk", "dask", "plot", "xarray", "notebook"):
        assert _extra_requirements(extra) <= everything, extra
    # the tests and the docs (which run every tutorial) install everything
    assert everything <= _extra_requirements("test")
    assert everything <= _extra_requirements("docs")
    assert "pyfftw" in _extra_requirements("test")


def _package_imports():
    """Top-level names of every module imported by the installed package's sources:
    import statements and ``need("module", ...)`` (wearcheck.extras) calls."""
    dirs = [ROOT / d for d in PYPROJECT["tool"]["setuptools"]["package-dir"].values()]
    found = {}
    for folder in dirs:
        for path in folder.rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                names = []
                if isinstance(node, ast.Import):
                    names = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names = [node.module]
                elif (isinstance(node, ast.Call) and getattr(node.func, "id", getattr(
                        node.func, "attr", None)) == "need" and node.args
                        and isinstance(node.args[0], ast.Constant)):
                    names = [node.args[0].value]
                for name in names:
                    found.setdefault(name.split(".")[0], set()).add(str(path.relative_to(ROOT)))
    return found


def test_every_dependency_earns_its_place_by_an_import():
    imports = _package_imports()
    third_party = {n for n in imports if n not in sys.stdlib_module_names and n != "wearcheck"}
    # every core package is imported by the package itself
    import_names = {"numpy": "numpy", "scipy": "scipy", "threadpoolctl": "threadpoolctl",
                    "tqdm": "tqdm"}
    assert set(import_names.values()) <= third_party
    # every other third-party import is an optional module with its extra, and each
    # extra's module but vtk (pyvista's own) and ipywidgets (tqdm.auto's, in Jupyter)
    # is imported
    assert third_party - set(import_names.values()) <= set(extras.MODULES), \
        {n: imports[n] for n in third_party - set(import_names.values()) - set(extras.MODULES)}
    assert set(extras.MODULES) - {"vtk", "ipywidgets"} <= third_party
    assert "meshio" in third_party      # wearcheck verify reads VTU series through it
