"""The command line's manners: quiet on a closed pipe, examples in every
subcommand's help (each one a valid command line), ``run --json``."""

import argparse
import json
import math
import os
import shlex
import subprocess
import sys

import pytest

from wearcheck import cli


def _choices():
    parser = cli.build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return parser, action.choices


def test_a_closed_pipe_ends_the_command_quietly_and_successfully():
    # the reader is gone before the command writes (the child takes a few
    # hundred ms to start): its first line fails with EPIPE, as in
    # `wearcheck cases --paths | head -1` once head has exited. Before, it
    # printed "cannot write or read: Broken pipe" and exited 4
    read, write = os.pipe()
    proc = subprocess.Popen([sys.executable, "-m", "wearcheck", "cases", "--paths"],
                            stdout=write, stderr=subprocess.PIPE)
    os.close(write)
    os.close(read)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0 and err == b"", err


def test_a_broken_pipe_elsewhere_is_still_an_io_error(monkeypatch, capsys):
    # a pipe other than our standard output (stdout here is fine): exit 4 with
    # the one-line message, as for any file that cannot be written
    from wearcheck.cli import cases as cases_command

    def broken(args):
        raise BrokenPipeError(32, "Broken pipe")
    monkeypatch.setattr(cases_command, "main", broken)
    assert cli.main(["cases"]) == cli.EXIT_IO
    assert "cannot write or read: Broken pipe" in capsys.readouterr().err


@pytest.mark.parametrize("name", sorted(cli.SUBCOMMANDS))
def test_every_subcommand_shows_examples_that_parse(name):
    parser, choices = _choices()
    text = choices[name].format_help()
    assert name in cli.EXAMPLES and "examples:" in text
    for line, what in cli.EXAMPLES[name]:
        assert line in text and what in text
        argv = shlex.split(line.split(" > ")[0])   # a shell redirection is not an argument
        assert argv[:2] == ["wearcheck", name]
        args = parser.parse_args(argv[1:])         # exits 2 on an invalid example
        assert args.command == name


def test_run_json_is_the_summary_with_units(tmp_path):
    out = tmp_path / "hertz"
    done = subprocess.run([sys.executable, "-m", "wearcheck", "run", "hertz", "--solver", "mdr",
                           "--quiet", "--json", "--out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)          # stdout holds the JSON only
    meta = json.loads((out / "meta.json").read_text(encoding="utf-8"))
    assert summary["solve_seconds"] == meta["solve_seconds"]
    assert summary["stages_reached"] == meta["stages_reached"] == 1
    # Hertz: F = (4/3) E* sqrt(R) d^(3/2), E* = E/(1 - ν²) against a rigid plane
    # (hertz.toml: R = 10 mm, E = 210 GPa, ν = 0.3, d = 1 µm); the MDR is exact
    # for a paraboloid on its grid (uniform in r²), so to round-off
    E_star = 210e9 / (1 - 0.3**2)
    F = 4.0 / 3.0 * E_star * math.sqrt(0.01) * 1e-6**1.5
    assert summary["last"]["force"] == pytest.approx(F, rel=1e-9)
    assert summary["scales"]["F0"] == pytest.approx(F, rel=1e-12)
    assert summary["units"]["force"] == "N" and summary["units"]["wear_volume"] == "m^3"
    assert summary["last"]["cycles"] is None       # NaN in history.csv: JSON null


def test_jsonable_is_strict_json():
    # NaN and inf are not JSON: null; numpy numbers and arrays as Python's; paths as text
    import numpy as np
    from pathlib import Path
    from wearcheck.cli._common import jsonable

    value = {"a": np.float64("nan"), "b": [np.int64(3), np.array([1.5, np.inf])],
             "c": Path("runs") / "x", 4: (1, "t")}
    text = json.dumps(jsonable(value), allow_nan=False)      # raises on a NaN left in
    assert json.loads(text) == {"a": None, "b": [3, [1.5, None]], "c": str(Path("runs/x")),
                                "4": [1, "t"]}


@pytest.mark.parametrize("name", ["run", "sweep", "refine", "fretting-map", "mesh", "fit",
                                  "compare", "verify"])
def test_commands_that_print_numbers_take_json(name):
    _, choices = _choices()
    assert "--json" in choices[name].format_help()



def test_mesh_json_sizes(capsys):
    # paper.toml: a0 = sqrt(R d) = sqrt(10 mm · 1 µm) = 0.1 mm (Hertz; the sphere's
    # a0 differs by ~(a0/R)²/6 = 1.7e-5 relative, hence 1e-4); the contact nodes
    # split the meshed contact radius into equal spacings
    assert cli.main(["mesh", "paper", "--quiet", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["contact_radius"] == pytest.approx(out["contact_radius_over_a0"] * 1e-4, rel=1e-4)
    assert out["spacing"] * (out["contact_nodes"] - 1) == pytest.approx(out["contact_radius"],
                                                                      rel=1e-12)
    assert out["dofs"] == 2 * out["nodes"] and out["vertices"] < out["nodes"]


def test_compare_json_is_the_verdict_and_agrees_with_the_exit_code(tmp_path, capsys):
    # the MDR against itself on Hertz's unworn contact (passes), then with the coarsest
    # MDR grid against the FEM on a short paper run (fails on the profile:
    # tests/test_compare.py): stdout is one JSON line whose "passed" is the exit code's
    from wearcheck.cli import main
    small = ["--set", "stages.s_hat=[0.0, 0.5]", "--set", 'sliding.until="distance"',
             "--set", "sliding.distance=0.015", "--set", "fem.contact_nodes=60"]
    for elements, code_wanted in ((200, 0), (32, 1)):
        out = tmp_path / f"c{elements}"
        code = main(["compare", "paper", "--solvers", "mdr,fem", "--no-render", "--json",
                     "--out", str(out), "--set", f"mdr.elements={elements}", *small])
        lines = capsys.readouterr().out.strip().splitlines()
        assert len(lines) == 1
        verdict = json.loads(lines[0])
        assert code == code_wanted and verdict["passed"] is (code == 0)
        assert verdict["pairs"] == {"fem": code == 0}
        assert json.loads(open(verdict["metrics"]).read())["passed"] is verdict["passed"]
        assert (verdict["diagnosis"] is None) is (code == 0)



def test_run_json_of_a_jumped_fretting_run_gives_its_error_estimate(tmp_path):
    # review finding: --json left out the error estimate that meta.json and report.md
    # give; it is the same number, and within the tolerance the run promises
    out = tmp_path / "fretting"
    done = subprocess.run([sys.executable, "-m", "wearcheck", "run", "fretting", "--solver", "mdr",
                           "--set", "fretting.cycles=300", "--set", "mdr.elements=200",
                           "--quiet", "--json", "--out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    meta = json.loads((out / "meta.json").read_text(encoding="utf-8"))["info"]["cycle_jumping"]
    assert summary["cycle_jumping"] == {k: meta[k] for k in
                                        ("error_estimate", "tolerance", "simulated_cycles")}
    assert 0.0 < summary["cycle_jumping"]["error_estimate"] <= summary["cycle_jumping"]["tolerance"]
    assert summary["cycle_jumping"]["simulated_cycles"] < 300
