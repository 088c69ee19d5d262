"""What the command line says: help without reST markup or internal module names,
the elastic-similarity note once per command."""

import argparse
import re

import pytest

from wearcheck import cases
from wearcheck.cli import build_parser, main as cli_main, plain


def _subparsers():
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return parser, action.choices


def test_every_subcommand_has_help():
    parser, choices = _subparsers()
    assert {"run", "compare", "refine", "sweep", "mesh", "export", "render", "cases"} <= set(choices)


@pytest.mark.parametrize("name", sorted(_subparsers()[1]))
def test_help_has_no_markup_and_no_internal_module_names(name):
    parser, choices = _subparsers()
    text = choices[name].format_help() + parser.format_help()
    assert "``" not in text
    assert not re.search(r":(mod|func|class|meth|attr|data|ref):", text)
    # internal modules: wearcheck.x, comparisons.x, cases.x, mdr/, *.py
    assert not re.search(r"\b(wearcheck|comparisons|cases)\.[a-z_]+\b", text), text
    assert not re.search(r"\b[a-z_]+\.py\b", text), text


@pytest.mark.parametrize("name", sorted(_subparsers()[1]))
def test_help_examples_are_one_command_a_line(name):
    # an example in a description is reflowed by argparse into one paragraph
    # (fit's help once ran four commands together); examples belong in the
    # "examples:" epilog, which keeps its lines
    text = _subparsers()[1][name].format_help()
    for line in text.splitlines():
        assert line.count("wearcheck ") <= 1, line
    examples = text.split("examples:\n", 1)[1] if "examples:\n" in text else ""
    for line in examples.splitlines():
        assert not line.strip().startswith("wearcheck ") or line.startswith("  wearcheck "), line


def test_plain_removes_roles_and_literals():
    assert plain("``wearcheck run``: see :func:`~x.y` and :mod:`z`") == "wearcheck run: see x.y and z"
    assert plain(None) is None


def _note_count(text):
    return text.count("elastic similarity (paper Eq. 7) does not hold")


def test_hertz_case_has_the_note():
    # the shipped hertz case (elastic sphere on a rigid plane) is not elastically
    # similar: Dundurs' beta = (1 - 2ν) / (2 (1 - ν)) = 0.2857 for ν = 0.3
    case = cases.load(cases.shipped("hertz"))
    assert cases.dundurs_beta(case.indenter, case.counterface) == pytest.approx(0.4 / 1.4)
    assert sum(_note_count(w) for w in case.warnings) == 1


@pytest.mark.parametrize("argv", [
    ["run", "hertz", "--set", "mdr.elements=50"],
    ["run", "hertz", "--solver", "fem", "--set", "fem.contact_nodes=30"],
    ["compare", "hertz", "--no-render", "--set", "mdr.elements=100",
     "--set", "fem.contact_nodes=30"],
])
def test_the_similarity_note_is_printed_once_per_command(argv, tmp_path, capsys):
    code = cli_main(argv + ["--out", str(tmp_path / "out")])
    assert code in (0, 1)  # a coarse comparison may fail its tolerances; not the point here
    assert _note_count(capsys.readouterr().err) == 1
    cli_main(argv + ["--out", str(tmp_path / "out"), "--quiet"])
    assert _note_count(capsys.readouterr().err) == 0


def test_set_with_a_space_for_the_equals_sign_gets_the_spelling_that_works(capsys):
    """``--set wear.mu 0.5`` said "wearcheck: error: unrecognized arguments: 0.5 (see
    wearcheck --help)": neither the subcommand nor what was wrong."""
    from wearcheck.cli import main
    with pytest.raises(SystemExit) as exit_:
        main(["run", "paper", "--set", "wear.mu", "0.5", "--quiet"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("wearcheck run: error:")
    assert "--set wear.mu=0.5" in err and "wearcheck run --help" in err


@pytest.mark.parametrize("argv", [
    ["compare", "fretting"],
    ["compare", "fretting", "--reference", "fem"],
    ["compare", "hertz", "--solvers", "mdr"],
    ["compare", "hertz", "--out", "{notours}"],
    ["run", "fretting", "--solver", "fem"],
    ["run", "fretting", "--solver", "bem"],
    ["run", "hertz", "--solver", "nosuch"],
    ["run", "hertz", "--out", "{notours}"],
    ["run", "hertz", "--set", "mdr.elements=1000000000"],
    ["verify", "fretting", "{missing}"],
    ["verify", "hertz", "{missing}", "--reference-solver", "mdr"],
])
def test_a_refusal_is_one_line_with_no_remark_before_it(argv, tmp_path, capsys):
    """``compare fretting`` printed the elastic-similarity note, then refused the case:
    a refusal (exit 2) is the one line the command prints, whichever check made it."""
    case = cases.load(cases.shipped(argv[1]))
    assert _note_count("".join(case.warnings)) == 1   # the case has a note to hold back
    (tmp_path / "notours").mkdir()
    (tmp_path / "notours" / "mine.txt").write_text("not a wearcheck output")
    words = [w.format(notours=tmp_path / "notours", missing=tmp_path / "missing")
             for w in argv]
    if "--out" not in words:
        words += ["--out", str(tmp_path / "out")]
    code = cli_main(words)
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and err.startswith(f"wearcheck {argv[0]}: error: "), err


def test_compare_names_the_one_solver_it_allows(capsys):
    """A case only one solver can run: the refusal says which, and how to run it alone,
    before the reasons the others cannot."""
    assert cli_main(["compare", "fretting"]) == 2
    err = capsys.readouterr().err
    allowed = "only mdr can: run it alone (wearcheck run --solver mdr)"
    assert allowed in err and err.index(allowed) < err.index("fem:") < err.index("bem:")
    assert cli_main(["compare", "hertz", "--solvers", "mdr"]) == 2
    assert "only mdr was named (those that can run this case: mdr, fem, bem" in \
        capsys.readouterr().err
