"""Start-up: what ``import wearcheck`` and ``wearcheck --help`` load, and the
subcommand table the parser is built from without importing the subcommands
(docs/performance.md, "Start-up"; timings: benchmarks/bench_startup.py)."""

import argparse
import importlib
import json
import pkgutil
import subprocess
import sys

import pytest

from wearcheck import cli

#: what no command's start-up may load: plotting, 3D export, the cluster, the mesher
HEAVY = ("matplotlib", "pyvista", "vtk", "dask", "distributed", "gmsh")


def _loaded_after(code: str) -> dict:
    """The top-level packages and the wearcheck modules a fresh interpreter holds
    after running ``code``."""
    probe = code + "\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    return set(json.loads(out.stdout.strip().splitlines()[-1]))


def _heavy(modules: set) -> list:
    return sorted(m for m in modules if m.split(".")[0] in HEAVY)


def test_import_wearcheck_loads_no_plotting_export_cluster_or_mesher():
    modules = _loaded_after("import wearcheck")
    assert _heavy(modules) == []
    # nor a solver: the public API imports them when a case is solved
    assert not any(m.startswith(("wearcheck.mdr", "wearcheck.fem", "wearcheck.bem"))
                   for m in modules)


def test_help_loads_no_subcommand_and_nothing_heavy():
    code = ("import sys\nfrom wearcheck.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit as e:\n    assert e.code == 0\n")
    modules = _loaded_after(code)
    assert _heavy(modules) == []
    subcommands = sorted(m for m in modules if m.startswith("wearcheck.cli."))
    assert subcommands == [], subcommands
    # nor the studies' or the solvers' dependencies
    assert not {"scipy.optimize", "scipy.fft", "wearcheck.mdr", "asyncio"} & modules


def test_a_subcommand_loads_only_its_own_module():
    # run's parser (--help exits after parsing) without the studies' modules
    code = ("from wearcheck.cli import main\n"
            "try:\n    main(['run', '--help'])\nexcept SystemExit as e:\n    assert e.code == 0\n")
    modules = _loaded_after(code)
    subcommands = {m for m in modules if m.startswith("wearcheck.cli.")
                   and not m.endswith("._common")}
    assert subcommands == {"wearcheck.cli.run"}
    assert _heavy(modules) == []


@pytest.mark.parametrize("name", ["sweep", "refine", "fit", "fretting-map"])
def test_a_dask_study_builds_its_parser_without_the_study(name):
    # the study (scipy.optimize, asyncio) is imported when the command runs: its
    # --help costs what the bare --help does (docs/performance.md, "Start-up")
    code = ("from wearcheck.cli import main\n"
            f"try:\n    main([{name!r}, '--help'])\nexcept SystemExit as e:\n"
            "    assert e.code == 0\n")
    modules = _loaded_after(code)
    assert {m for m in modules if m.startswith("wearcheck.cli.")
            and not m.endswith("._common")} == {cli.module_name(name)}
    assert [m for m in modules if m.startswith("wearcheck.studies")] == []
    assert not {"scipy.optimize", "asyncio"} & modules
    assert _heavy(modules) == []


def test_an_mdr_run_loads_only_what_it_uses(tmp_path):
    # the whole command, run directory written: none of the heavy packages,
    # no other solver, and no psutil (the memory check reads /proc/meminfo
    # where there is one)
    out = tmp_path / "hertz"
    code = ("from wearcheck.cli import main\n"
            f"assert main(['run', 'hertz', '--solver', 'mdr', '--quiet', '--out', {str(out)!r}]) == 0\n")
    modules = _loaded_after(code)
    assert (out / "meta.json").is_file()
    assert _heavy(modules) == []
    # the other solvers' registrations are read (their package and registration.py,
    # which import nothing of their code: tests/test_registry_entries.py), their code is not
    others = ("wearcheck.fem", "wearcheck.bem", "wearcheck.ccx")
    assert [m for m in modules if m.startswith(others)
            and m not in others and not m.endswith(".registration")] == []
    if sys.platform.startswith("linux"):
        assert "psutil" not in modules


def test_every_subcommand_module_is_in_the_table():
    modules = {i.name for i in pkgutil.iter_modules(cli.__path__) if not i.name.startswith("_")}
    assert {name.replace("-", "_") for name in cli.SUBCOMMANDS} == modules
    assert cli._unlisted() == []


@pytest.mark.parametrize("name", sorted(cli.SUBCOMMANDS))
def test_table_help_is_the_modules_help(name):
    # the line --help shows without importing the module is the one the module gives
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    importlib.import_module(cli.module_name(name)).add_parser(sub)
    listed = {a.dest: a.help for a in sub._choices_actions}
    assert listed == {name: cli.SUBCOMMANDS[name]}


def test_full_and_dispatch_parsers_list_the_same_commands():
    def listing(parser):
        action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        return [(a.dest, a.help) for a in action._choices_actions]

    assert listing(cli.build_parser()) == listing(cli.build_parser(set()))
    assert cli.build_parser(set()).format_help() == cli.build_parser().format_help()


def test_version_is_looked_up_when_asked(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["--version"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    from importlib.metadata import version
    assert out.strip() == f"wearcheck {version('wearcheck')}"


def test_unknown_command_is_one_line_exit_2(capsys):
    assert _exit_code(["runn", "paper"]) == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'runn'" in err and len(err.strip().splitlines()) == 1


def _exit_code(argv):
    try:
        return cli.main(argv)
    except SystemExit as exc:
        return exc.code
