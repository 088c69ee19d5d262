"""cases/tables.py: a user's CSV table with units in its header.

Checked against hand-written tables whose SI values are known by construction:
columns in any order with extras, units converted, and every bad file refused
with one line naming the file, the row and the column.
"""

import numpy as np
import pytest

from wearcheck.cases import CaseError
from wearcheck.cases.tables import read_table, split_header, unit_factor

COLUMNS = {"s": "length", "force": "force", "p": "pressure", "wear_volume": "volume",
           "cycles": "number"}


def write(tmp_path, text, name="t.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_units_and_order_and_extras(tmp_path):
    path = write(tmp_path, "# a comment before the header\n"
                           "note,force [kN],s [mm],p [MPa],wear_volume [mm^3],cycles\n"
                           "a,1.5,2,3,4,5\n"
                           "b,0.5,20,30,40,50\n")
    t = read_table(path, COLUMNS, required=[("s", "cycles"), "force"])
    # exact by construction: kN, mm, MPa and mm³ to SI
    assert np.allclose(t["force"], [1500.0, 500.0], rtol=1e-15)
    assert np.allclose(t["s"], [2e-3, 20e-3], rtol=1e-15)
    assert np.allclose(t["p"], [3e6, 30e6], rtol=1e-15)
    assert np.allclose(t["wear_volume"], [4e-9, 40e-9], rtol=1e-15)
    assert np.array_equal(t["cycles"], [5.0, 50.0])
    assert t.ignored == ["note"]
    assert list(t.rows) == [3, 4]            # spreadsheet rows: the header is row 2


@pytest.mark.parametrize("unit,factor", [("µm", 1e-6), ("\u03bcm", 1e-6), ("um", 1e-6),
                                         ("nm", 1e-9), ("m", 1.0)])
def test_micro_spellings(unit, factor):
    assert unit_factor(unit, "length") == factor


def test_header_forms():
    assert split_header("force [N]") == ("force", "N")
    assert split_header(" Force (kN) ") == ("force", "kN")
    assert split_header("s") == ("s", None)


def test_header_forms_of_fe_exports():
    # ANSYS and COMSOL put the unit last, after names that hold brackets of their own
    assert split_header('Force Reaction (Z) [N]') == ("force reaction (z)", "N")
    assert split_header("Worn Volume [mm³]") == ("worn volume", "mm³")
    assert split_header("RF2 PI: BALL-1 N: 1") == ("rf2 pi: ball-1 n: 1", None)


def test_an_fe_export_with_names_mapped_and_units_given(tmp_path):
    # tab-separated, quoted names: the pseudo-time "Time [s]" holds the distance in mm
    # (its unit given by the caller), the Abaqus-style force has no unit (given: kN),
    # "Wear (Y)" is named whole (the (Y) is no unit)
    path = write(tmp_path, '"Steps"\t"Time [s]"\t"RF2 PI: BALL-1 N: 1"\t"Wear (Y)"\n'
                           '1\t0.5\t2.0\t1e-6\n2\t1.5\t1.0\t2e-6\n')
    t = read_table(path, dict(COLUMNS, wear="length"), required=["s", "force"],
                   aliases={"time": "s", "rf2 pi: ball-1 n: 1": "force", "wear (y)": "wear"},
                   units={"s": "mm", "force": "kN"})
    assert np.allclose(t["s"], [0.5e-3, 1.5e-3], rtol=1e-15)
    assert np.allclose(t["force"], [2000.0, 1000.0], rtol=1e-15)
    assert np.allclose(t["wear"], [1e-6, 2e-6], rtol=1e-15) and t.ignored == ["Steps"]
    # the header's unit when none is given
    path = write(tmp_path, '"Time [mm]","Force Reaction (Z) [kN]"\n1,2\n')
    t = read_table(path, COLUMNS, required=["s", "force"],
                   aliases={"time": "s", "force reaction (z)": "force"})
    assert t["s"][0] == pytest.approx(1e-3) and t["force"][0] == pytest.approx(2000.0)


def test_semicolon_and_tab_tables(tmp_path):
    for sep in (";", "\t"):
        path = write(tmp_path, f"s{sep}force\n1{sep}2\n3{sep}4\n")
        t = read_table(path, COLUMNS, required=["s", "force"])
        assert list(t["force"]) == [2.0, 4.0]


def test_optional_empty_cell_is_nan(tmp_path):
    path = write(tmp_path, "s,force,p,cycles\n1,2,,nan\n3,4,5,\n")
    t = read_table(path, COLUMNS, required=[("s", "cycles"), "force"])
    assert np.isnan(t["p"][0]) and t["p"][1] == 5.0
    # a column of a group ("s or cycles") may be empty or "nan": its reader checks the one
    # it uses (wearcheck.external.tables_dir)
    assert np.all(np.isnan(t["cycles"]))


def one_line(exc):
    text = str(exc.value)
    assert "\n" not in text
    return text


@pytest.mark.parametrize("text,expect", [
    ("s,force [lbf]\n1,2\n", ["t.csv", "row 1", "column 'force [lbf]'", "unknown unit 'lbf'",
                              "kN"]),
    ("s,force\n1,2\n3,x\n", ["t.csv", "row 3", "column 'force'", "'x' is not a number"]),
    ("s,force\n1,2\n3\n", ["t.csv", "row 3", "column 'force'", "missing"]),
    ("s,force\n1,2\n3,\n", ["t.csv", "row 3", "column 'force'", "empty"]),
    ("s,force\n1,inf\n", ["t.csv", "row 2", "column 'force'", "not a finite number"]),
    ("s;force\n1;2,5\n", ["row 2", "column 'force'", "decimal comma"]),
    ("s,p\n1,2\n", ["t.csv", "no column 'force'", "columns found: 's', 'p'"]),
    ("force\n1\n", ["no column 's' or 'cycles'"]),
    ("", ["t.csv", "empty"]),
    ("1,2\n3,4\n", ["t.csv", "row 1", "no header row"]),
    ("s,force\n", ["no data rows"]),
    ("s,force,s\n1,2,3\n", ["column 's' appears twice"]),
])
def test_bad_tables_one_line_each(tmp_path, text, expect):
    path = write(tmp_path, text)
    with pytest.raises(CaseError) as exc:
        read_table(path, COLUMNS, required=[("s", "cycles"), "force"])
    msg = one_line(exc)
    for part in expect:
        assert part in msg, msg


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(CaseError, match="does not exist"):
        read_table(tmp_path / "no.csv", COLUMNS)
    with pytest.raises(CaseError, match="is a directory"):
        read_table(tmp_path, COLUMNS)


def test_a_mapped_column_must_exist_and_wins_over_a_column_of_that_name(tmp_path):
    """A mapping to a column not in the header was ignored, and a column literally
    named 'force' (here a friction force) read instead; the right mapping then failed
    with "column 'force' appears twice". The values are known by construction: the
    mapped column's are read, the other is listed as not read."""
    path = write(tmp_path, "s [m],force [N],Fn [N]\n0,0.3,1.0\n1,0.6,2.0\n")
    with pytest.raises(CaseError, match=r"^no column 'Fnn' in file '.*t\.csv' "
                                        r"\(--map force=Fnn\); its columns are 's \[m\]', "
                                        r"'force \[N\]', 'Fn \[N\]'$"):
        read_table(path, COLUMNS, required=["s", "force"], aliases={"Fnn": "force"})
    t = read_table(path, COLUMNS, required=["s", "force"], aliases={"Fn": "force"})
    assert t["force"].tolist() == [1.0, 2.0]
    assert t.ignored == ["force [N]"] and t.headers["force"] == "Fn [N]"
    # a group: the distance mapped as cycles displaces the column 's'
    path = write(tmp_path, "s [m],N,force\n0,10,1\n1,20,2\n", "g.csv")
    t = read_table(path, COLUMNS, required=[("s", "cycles"), "force"],
                   aliases={"N": "cycles"}, groups=[("s", "cycles")])
    assert "s" not in t and t["cycles"].tolist() == [10.0, 20.0]
    # an alias of a name this table does not read is not looked for here
    t = read_table(path, COLUMNS, required=["s"], aliases={"X": "r"})
    assert "r" not in t.columns
