"""Tables a user brings (wearcheck.user_tables): units to SI, ± columns, and every
bad file as one line naming the file, the row and the column."""

import math

import numpy as np
import pytest

from wearcheck.cases import CaseError
from wearcheck.studies.fit import MEASUREMENTS
from wearcheck.user_tables import Quantity, from_columns, read_table

HISTORY = (Quantity("force", "force", ("F",), "normal force"),
           Quantity("s", "length", ("sliding distance",), "sliding distance"))


def write(tmp_path, text, name="sheet.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_units_are_converted_to_si(tmp_path):
    path = write(tmp_path, "# a lab sheet\ncycles, D [um], ± D [µm], V [mm^3], h [nm], s [m]\n"
                           "\n1000, 212.5, 3, 0.0128, 850, 2\n10000, 381, 3, , 1500, 20,\n")
    t = read_table(path, MEASUREMENTS)
    # independent: 1 µm = 1e-6 m, 1 mm³ = 1e-9 m³, 1 nm = 1e-9 m; the empty cell is a
    # value not measured, the trailing comma nothing
    assert t["scar_diameter"].values == pytest.approx([212.5e-6, 381e-6], rel=1e-15)
    assert t["scar_diameter"].uncertainty == pytest.approx([3e-6, 3e-6], rel=1e-15)
    assert t["ball_volume"].values[0] == pytest.approx(0.0128e-9, rel=1e-15)
    assert math.isnan(t["ball_volume"].values[1])
    assert t["wear_center"].values == pytest.approx([850e-9, 1500e-9], rel=1e-15)
    assert list(t.rows) == [4, 5]   # the file's lines: a spreadsheet's row numbers


def test_km_is_not_a_unit_here(tmp_path):
    # kilometres are not among the units of a length in a lab sheet; the message lists
    # those that are
    path = write(tmp_path, "cycles, s [km]\n1, 2\n")
    with pytest.raises(CaseError, match=r"unknown unit 'km'.*allowed: m, cm, mm, um, µm, μm, nm"):
        read_table(path, MEASUREMENTS)


def test_a_history_in_newtons_and_millimetres(tmp_path):
    # the verify command's history.csv (issue 23 §2): force [N], s [mm]
    path = write(tmp_path, "force [N],s [mm]\n2.0,0\n2.0,1.5\n1.9,3.0\n")
    t = read_table(path, HISTORY)
    assert t["force"].values == pytest.approx([2.0, 2.0, 1.9])
    assert t["s"].values == pytest.approx([0.0, 1.5e-3, 3.0e-3], rel=1e-15)
    assert read_table(write(tmp_path, "F [mN],s [m]\n20,1\n"), HISTORY)["force"].values[0] \
        == pytest.approx(0.02)


def test_columns_from_python_read_as_a_file():
    t = from_columns({"cycles": [10, 100], "D [um]": np.array([100.0, 150.0]),
                      "+- D": [2, 2]}, MEASUREMENTS)
    assert t["scar_diameter"].values == pytest.approx([1e-4, 1.5e-4])
    assert t["scar_diameter"].uncertainty == pytest.approx([2e-6, 2e-6])   # the value's unit


BAD = [
    ("cycles, D [um]\n10, 100\n20, abc\n", r"row 3, column 'D \[um\]': 'abc' is not a number"),
    ("cycles, D [um]\n10, 1,5\n", r"row 2: 3 cells for 2 columns"),
    ("cycles, D [um]\n10, -100\n", r"row 2, column 'D \[um\]': -100 is negative"),
    ("cycles, D [um]\n10, inf\n", r"row 2, column 'D \[um\]': 'inf' is not a finite number"),
    ("cycles, D [furlong]\n10, 100\n", r"row 1, column 2 'D \[furlong\]': unknown unit "
                                       r"'furlong' for ball scar diameter \(length\)"),
    ("cycles, V [um]\n10, 100\n", r"column 2 'V \[um\]': unknown unit 'um' for ball worn volume "
                                  r"\(volume\); allowed: m\^3"),
    ("cycles, D\n10, 100\n", r"row 1, column 2 'D': no unit; write it in brackets, e.g. 'D \[um\]'"),
    ("cycles, diameter [um]\n10, 100\n", r"column 2 'diameter \[um\]': unknown column "
                                         r"'diameter'; known: cycles, s, scar_diameter"),
    ("cycles, D [um], D [mm]\n10, 1, 1\n", r"column 3 'D \[mm\]': 'scar_diameter' is also "
                                           r"column 2"),
    ("cycles, ± D [um]\n10, 1\n", r"column 2 '± D \[um\]': an uncertainty without its value"),
    ("cycles, D [um], ± D [um]\n10, 100,\n", r"row 2: 'D \[um\]' and '± D \[um\]' go together; "
                                             r"'± D \[um\]' is empty"),
    ("cycles; D [um]\n10; 100\n", r"row 1: columns are separated by commas, not semicolons"),
    ("cycles, D [um]\n10, \"100,5\"\n", r"row 2, column 'D \[um\]': '100,5' is not a number "
                                        r"\(a decimal comma\?"),
    ("cycles, track width [um]\n10, 100\n", r"column 2 'track width \[um\]': a track quantity: "
                                            r"the both-bodies model .* not available yet"),
    ("", r"is empty"),
    ("# only a comment\ncycles, D [um]\n", r"has a header but no rows of numbers"),
]


@pytest.mark.parametrize("text, pattern", BAD)
def test_a_bad_file_is_one_line_naming_file_row_and_column(tmp_path, text, pattern):
    path = write(tmp_path, text)
    with pytest.raises(CaseError, match=pattern) as exc:
        read_table(path, MEASUREMENTS)
    message = str(exc.value)
    assert "\n" not in message and f"file '{path}'" in message


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(CaseError, match="does not exist"):
        read_table(tmp_path / "none.csv", MEASUREMENTS)
    with pytest.raises(CaseError, match="is a directory"):
        read_table(tmp_path, MEASUREMENTS)
    latin = tmp_path / "latin.csv"
    latin.write_bytes("cycles, D [\xb5m]\n1, 2\n".encode("latin-1"))
    with pytest.raises(CaseError, match="is not UTF-8 text"):
        read_table(latin, MEASUREMENTS)
