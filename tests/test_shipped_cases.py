"""Shipped cases by name: cases.resolve, `wearcheck cases`, CASE arguments that name one."""

import tomllib
from pathlib import Path

import pytest

from wearcheck import cases
from wearcheck.cases import CaseError, catalog
from wearcheck.cli import main as cli_main

CASES_DIR = Path(cases.__file__).resolve().parent
#: every TOML file in the package folder is a shipped case: the list is independent
#: of shipped_cases(), which it checks
ON_DISK = sorted(p.stem for p in CASES_DIR.glob("*.toml"))


def test_the_shipped_cases_are_the_toml_files_and_each_loads():
    assert ON_DISK, "no shipped case found beside cases/"
    assert list(cases.shipped_cases()) == ON_DISK
    for name, path in cases.shipped_cases().items():
        case = cases.load(path)
        assert case.source == str(path)


def test_each_shipped_case_describes_itself_in_one_sentence():
    for name, path in cases.shipped_cases().items():
        first = path.read_text(encoding="utf-8").splitlines()[0]
        text = cases.describe(path)
        assert first.startswith("# ") and first[2:] == text, name
        assert text.endswith(".") and 20 < len(text) <= 100, (name, text)


def test_describe_skips_editor_directives(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text("#:schema ./case.schema.json\n\n# What this case is.\n[indenter]\n")
    assert cases.describe(f) == "What this case is."
    f.write_text("[indenter]\n# a comment after the first table is no description\n")
    assert cases.describe(f) == ""


@pytest.mark.parametrize("text", ["paper", "paper.toml", "pap", "pa"])
def test_names_and_unambiguous_starts_resolve(text, monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)  # nothing called paper here
    assert cases.resolve(text) == CASES_DIR / "paper.toml"


def test_an_existing_path_wins_over_a_shipped_name(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "paper.toml").write_text((CASES_DIR / "hertz.toml").read_text())
    assert cases.resolve("paper.toml") == Path("paper.toml")
    assert cases.resolve(Path("paper.toml")) == Path("paper.toml")
    # the bare name is no path here, so it is the shipped case
    assert cases.resolve("paper") == CASES_DIR / "paper.toml"


@pytest.mark.parametrize("text", ["nosuch", "nosuch.toml"])
def test_an_unknown_name_lists_the_shipped_ones(text, monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(CaseError) as err:
        cases.resolve(text)
    message = str(err.value)
    assert f"'{text}'" in message and "\n" not in message
    assert all(name in message for name in ON_DISK)


def test_a_missing_path_is_not_taken_for_a_name(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(CaseError, match=r"case file 'sub/paper.toml' does not exist"):
        cases.resolve("sub/paper.toml")


def test_an_ambiguous_start_is_one_error(monkeypatch, tmp_path):
    shipped_dir = tmp_path / "shipped"
    shipped_dir.mkdir()
    for name in ("paper", "paper-bdf2", "hertz"):
        (shipped_dir / f"{name}.toml").write_text(f"# {name}.\n")
    monkeypatch.setattr(catalog, "SHIPPED_DIR", shipped_dir)
    monkeypatch.chdir(tmp_path)
    assert cases.resolve("paper") == shipped_dir / "paper.toml"  # exact beats prefix
    with pytest.raises(CaseError, match=r"'pa' is ambiguous.*paper, paper-bdf2"):
        cases.resolve("pa")
    with pytest.raises(CaseError, match=r"'pa' is ambiguous"):
        cases.shipped("pa")


def test_cli_runs_a_shipped_case_by_name_from_any_directory(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    assert cli_main(["run", "hertz", "--quiet", "--set", "mdr.elements=50"]) == 0
    # the default output is named after the case file, not after what was typed
    run = tmp_path / "runs" / "hertz-mdr"
    assert (run / "meta.json").is_file()
    resolved = tomllib.loads((run / "case.toml").read_text())
    assert resolved["indenter"]["profile"] == "paraboloid"
    first = (run / "case.toml").read_text().splitlines()[0]
    assert first.startswith("# resolved case") and str(CASES_DIR / "hertz.toml") in first


def test_cli_unknown_case_name_is_one_line(monkeypatch, tmp_path, capsys):
    monkeypatch.chdir(tmp_path)
    assert cli_main(["run", "nosuch", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "nosuch" in err
    assert all(name in err for name in ON_DISK)
    assert not (tmp_path / "runs").exists()


def test_cases_command_lists_every_shipped_case(capsys):
    assert cli_main(["cases"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == ON_DISK
    for line, name in zip(lines, ON_DISK):
        assert cases.describe(CASES_DIR / f"{name}.toml") in line


def test_cases_command_prints_one_case_that_loads(capsys, tmp_path):
    assert cli_main(["cases", "truncated"]) == 0
    text = capsys.readouterr().out
    assert text == (CASES_DIR / "truncated.toml").read_text(encoding="utf-8")
    copy = tmp_path / "mine.toml"
    copy.write_text(text)
    assert cases.load(copy).indenter.profile == "truncated_paraboloid"
    assert cli_main(["cases", "nosuch"]) == 2


def test_cases_command_names_the_schema_file(capsys):
    assert cli_main(["cases", "--schema"]) == 0
    path = Path(capsys.readouterr().out.strip())
    assert path == CASES_DIR / "case.schema.json" and path.is_file()
