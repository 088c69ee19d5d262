"""Each built-in solver describes itself in its own package (``<package>/registration.py``);
the history columns every solver writes are declared once, in ``cases.result``.

Independent of the registry's code: the entries are read from the solver
packages' files, the declarations counted in the source with ``ast``, and the
registration's import cost seen in a fresh interpreter's ``sys.modules``.
"""

import ast
import importlib
import json
import subprocess
import sys
from pathlib import Path

import pytest

from wearcheck.cases import result
from wearcheck import layout, registry

ROOT = Path(__file__).resolve().parents[1]
#: the project's own source folders (the design card's top level plus the API)
SOURCE = ("wearcheck", "cases", "mdr", "fem", "bem", "ccx", "meshes", "numerics", "comparisons")


def _item_calls(path: Path):
    """(first argument, line) of every ``Item("name", ...)`` call in a file."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "Item" \
                and node.args and isinstance(node.args[0], ast.Constant):
            yield node.args[0].value, node.lineno


def _calls_to(path: Path, name: str) -> list[int]:
    return [n.lineno for n in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
            if isinstance(n, ast.Call) and getattr(n.func, "id", None) == name]


@pytest.mark.parametrize("module", registry.BUILT_IN)
def test_each_solver_declares_its_entry_in_its_own_package(module):
    package = module.rsplit(".", 1)[0]             # wearcheck.mdr
    folder = ROOT / package.split(".")[1]           # mdr/
    mod = importlib.import_module(module)
    assert Path(mod.__file__).resolve() == (folder / "registration.py").resolve()
    entry = mod.SOLVER
    # what the registry serves is the package's declaration, not a copy
    assert registry.get(entry.name) is entry
    assert entry.module == package
    assert entry.section == folder.name and entry.resolution_key.startswith(folder.name + ".")
    # its columns are its own: none of them re-declares a common column
    own = [i.name for i in entry.history_columns]
    assert own and not set(own) & set(result.HISTORY_COLUMNS)
    assert len(own) == len(set(own))


def test_the_registry_declares_no_solver_and_the_common_columns_are_declared_once():
    # the registry module holds the machinery only: no Solver(...) entry, no Item(...)
    central = ROOT / "wearcheck" / "registry.py"
    assert _calls_to(central, "Solver") == [] and _calls_to(central, "Item") == []
    # layout documents the common columns it is given, the very tuple RunResult checks
    assert layout.HISTORY is result.HISTORY
    assert tuple(i.name for i in result.HISTORY) == result.HISTORY_COLUMNS
    # in the whole source, each common column is declared by exactly one Item(...), in
    # cases/result.py; "s", "force" and "contact_radius" also name stage arrays and
    # per-stage metrics, so the columns only the history has are counted
    only_history = {"depth", "wear_center", "wear_volume"}
    assert only_history <= set(result.HISTORY_COLUMNS)
    found = {}
    for folder in SOURCE:
        for path in (ROOT / folder).rglob("*.py"):
            for name, line in _item_calls(path):
                if name in only_history:
                    found.setdefault(name, []).append(f"{path.relative_to(ROOT)}:{line}")
    assert {n: [p.split(":")[0] for p in v] for n, v in found.items()} == \
        {n: ["cases/result.py"] for n in only_history}, found
    # and each solver's extra columns are declared in its package, nowhere else; the
    # study tables of layout.py (the fretting map's CSV summarises each run's last cycle
    # under the MDR's column names) are other tables, with their own meanings
    study_tables = {i.name for i in (*layout.SWEEP_COLUMNS, *layout.REFINEMENT_COLUMNS,
                                     *layout.FRETTING_MAP_COLUMNS)}
    for module in registry.BUILT_IN:
        entry = importlib.import_module(module).SOLVER
        own = {i.name for i in entry.history_columns} - {"s_hat", "cycles", "scar_radius",
                                                        "max_pressure"}
        for path in [*(ROOT / "wearcheck").rglob("*.py"), *(ROOT / "comparisons").rglob("*.py")]:
            declared = {n for n, _ in _item_calls(path)}
            if path.name == "layout.py":
                declared -= study_tables
            assert not own & declared, path


def test_listing_the_solvers_imports_no_solver_numerics():
    # a fresh interpreter, as `wearcheck --help` and `wearcheck solvers` start: the
    # registrations are read, the solvers' modules are not (scikit-fem, the MDR's
    # transforms, the BEM's FFT operator, numerics.stepping stay unimported); the
    # solve functions then resolve on first use
    packages = [m.rsplit(".", 1)[0] for m in registry.BUILT_IN]
    code = ("import sys, json; from wearcheck import registry; names = registry.names(); "
            f"loaded = sorted(m for m in sys.modules if m.startswith({tuple(packages)!r}) "
            "or m.split('.')[0] in ('skfem', 'meshio', 'gmsh') "
            "or m.startswith('wearcheck.numerics')); "
            "import wearcheck.mdr, wearcheck.mdr.solver; "
            "same = wearcheck.mdr.solve is wearcheck.mdr.solver.solve; "
            "print(json.dumps(dict(names=names, loaded=loaded, same=same)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT.parent, check=True)
    got = json.loads(out.stdout)
    assert got["names"][:3] == ["mdr", "fem", "bem"]
    assert got["loaded"] == sorted(p + s for p in packages for s in ("", ".registration"))
    assert got["same"]


def test_a_notebook_solver_registers_beside_the_built_in_ones():
    # the public interface a third party uses: Item and Solver from wearcheck.registry
    from wearcheck.registry import Item, Solver, register, unregister
    entry = register(Solver(name="toy-columns", title="Toy", solve_function=lambda c, p=None: 0,
                            history_columns=(Item("toy_column", "m", "a toy's column"),)))
    try:
        assert registry.names()[:3] == ("mdr", "fem", "bem")
        assert registry.names()[-1] == "toy-columns"
        dictionary = layout.run_dictionary(entry, history_names=("toy_column",))
        assert dictionary["history_csv"]["toy_column"] == dict(unit="m", meaning="a toy's column")
        assert list(dictionary["history_csv"])[:len(result.HISTORY)] == \
            list(result.HISTORY_COLUMNS)
    finally:
        unregister("toy-columns")
    assert "toy-columns" not in registry.names()


def test_a_solver_package_loads_its_solve_and_submodules_on_first_use():
    # the lazy package behaves as the eager one did: solve and supports are the
    # solver module's, a submodule is an attribute, an unknown name is an
    # AttributeError (hasattr, getattr with a default and autodoc rely on that)
    import wearcheck.fem
    solver = importlib.import_module("wearcheck.fem.solver")
    assert wearcheck.fem.solve is solver.solve and wearcheck.fem.supports is solver.supports
    assert wearcheck.fem.model is importlib.import_module("wearcheck.fem.model")
    assert not hasattr(wearcheck.fem, "no_such_name")
    with pytest.raises(AttributeError, match="no_such_name"):
        wearcheck.fem.no_such_name
