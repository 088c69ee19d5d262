"""Shared test helpers."""

TABLE_CASE = """
[indenter]
profile = "table"
file = "profile.csv"
youngs_modulus = 210e9
poisson_ratio = 0.3
[loading]
control = "depth"
depth = 1e-6
[wear]
k = 1e-4
mu = 0.3
hardness = 2e9
"""


def write_table_case(directory, csv_text):
    """A case file with a tabulated profile read from ``profile.csv`` beside it.

    ``csv_text`` None leaves the CSV file missing.
    """
    if csv_text is not None:
        (directory / "profile.csv").write_text(csv_text)
    case = directory / "case.toml"
    case.write_text(TABLE_CASE)
    return case
