"""Every CSV a study writes loads with ``pandas.read_csv(path)`` and no arguments;
its title, command, notes and units stand in a CSVW sidecar NAME.csv-metadata.json."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from wearcheck import cases
from wearcheck import layout
from wearcheck.cli import main


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as c:
        yield c.scheduler_address


def load(path):
    """The table as pandas reads it with no arguments, and its sidecar; the sidecar
    describes exactly the CSV's columns, in order, and names the CSV."""
    table = pd.read_csv(path)
    side = json.loads(path.with_name(path.name + "-metadata.json").read_text())
    assert side["@context"] == "http://www.w3.org/ns/csvw"
    assert side["url"] == path.name
    assert [c["titles"] for c in side["tableSchema"]["columns"]] == list(table.columns)
    assert side["notes"] and all(isinstance(n, str) for n in side["notes"])
    assert not path.read_text().startswith("#")
    return table, side


def units(side) -> dict:
    return {c["titles"]: c.get("unit") for c in side["tableSchema"]["columns"]}


def test_sweep_csv_loads_as_written_and_matches_its_runs(cluster, tmp_path):
    out = tmp_path / "sweep"
    argv = ["sweep", "hertz", "--set", "mdr.elements=100", "--set", "stages.s_hat=[0.0, 0.2]",
            "--vary", "wear.mu=0.2,0.3", "--scheduler", cluster, "--quiet", "--out", str(out)]
    assert main(argv) == 0
    table, side = load(out / "sweep.csv")
    assert len(table) == 2
    assert list(table.columns) == ["run", "wear.mu", *[c.name for c in layout.SWEEP_COLUMNS
                                                      if c.name != "run"]]
    assert list(table["wear.mu"]) == [0.2, 0.3] and list(table["status"]) == ["ok", "ok"]
    assert "sweep" in side["dc:source"] and "wear.mu=0.2,0.3" in side["dc:source"]
    assert units(side)["final_s"] == "m" and units(side)["wall_seconds"] == "s"
    # each row is its run: the last sliding distance of the run's own history.csv
    for _, row in table.iterrows():
        history = pd.read_csv(out / row["run"] / "history.csv")
        # sweep.csv keeps 10 significant digits, history.csv 13
        assert row["final_s"] == pytest.approx(history["s"].iloc[-1], rel=1e-9)


def test_a_sweep_into_a_study_of_the_previous_version_keeps_its_rows(cluster, tmp_path):
    """A study written before the sidecars has '#' lines above sweep.csv's header:
    a second sweep reads its rows and rewrites the table without them."""
    out = tmp_path / "sweep"
    base = ["sweep", "hertz", "--set", "mdr.elements=100", "--set", "stages.s_hat=[0.0, 0.2]",
            "--scheduler", cluster, "--quiet", "--out", str(out)]
    assert main(base + ["--vary", "wear.mu=0.2"]) == 0
    csv_path = out / "sweep.csv"
    first = csv_path.read_text()
    # the previous version's file: the same table under its '#' preamble, no sidecar
    old = "# wearcheck sweep, solver mdr: wear.mu\n# command: wearcheck sweep ...\n" + first
    _replace_as_the_study(out, "sweep.csv", old)
    (out / "sweep.csv-metadata.json").unlink()
    assert main(base + ["--vary", "wear.mu=0.3"]) == 0
    table, _ = load(csv_path)
    assert list(table["wear.mu"]) == [0.2, 0.3]
    assert csv_path.read_text().splitlines()[1] == first.splitlines()[1]   # as written


def _replace_as_the_study(study, name, text):
    """Write ``study/name`` through the study writer, as the previous version did."""
    from wearcheck.outputs import write_study_text
    write_study_text(study, name, text)


def test_refinement_csvs_load_as_written(cluster, tmp_path):
    out = tmp_path / "refine"
    argv = ["refine", "hertz", "--solver", "mdr", "--levels", "40,80,160",
            "--set", "stages.s_hat=[0.0, 0.2]", "--scheduler", cluster, "--quiet",
            "--out", str(out)]
    assert main(argv) == 0
    own, side = load(out / "refinement-mdr.csv")
    assert len(own) == 3 and list(own["resolution"]) == [40, 80, 160]
    assert {"F/F0 at s_hat=0.2", "force_difference", "peak_rss_mb"} <= set(own.columns)
    assert "refine" in side["dc:source"]
    assert sum(n.startswith("Observed order") for n in side["notes"]) == 4
    # the finest level's differences to itself are zero
    assert own["force_difference"].iloc[-1] == 0.0
    both, _ = load(out / "refinement.csv")
    assert list(both.columns) == ["solver", *own.columns]
    assert list(both["solver"]) == ["mdr"] * 3
    pd.testing.assert_frame_equal(both.drop(columns="solver"), own)


def test_refinement_csv_takes_a_per_solver_table_of_the_previous_version(cluster, tmp_path):
    """refinement.csv combines every refinement-<solver>.csv in the directory, also one
    an earlier version wrote with '#' lines and no sidecar (its notes: those lines)."""
    from wearcheck.studies.refine import combined_csv_text, combined_notes
    out = tmp_path / "refine"
    assert main(["refine", "hertz", "--solver", "mdr", "--levels", "40,80",
                 "--set", "stages.s_hat=[0.0, 0.2]", "--scheduler", cluster, "--quiet",
                 "--out", str(out)]) == 0
    mdr_text = (out / "refinement-mdr.csv").read_text()
    (out / "refinement-fem.csv").write_text(
        "# wearcheck refine, solver fem: differences to the finest level fem-h2\n"
        "# observed order force: 2.000\n" + mdr_text.replace("mdr-", "fem-"))
    (out / "refinement.csv").write_text(combined_csv_text(out))
    both = pd.read_csv(out / "refinement.csv")
    assert list(both["solver"]) == ["fem", "fem", "mdr", "mdr"]
    assert all(level.startswith(solver) for level, solver in zip(both["level"], both["solver"]))
    notes = combined_notes(out)
    assert notes[:2] == ["wearcheck refine, solver fem: differences to the finest level fem-h2",
                         "observed order force: 2.000"]
    assert any("solver mdr" in n for n in notes[2:])


def test_fretting_map_csv_loads_as_written(cluster, tmp_path):
    out = tmp_path / "map"
    assert main(["fretting-map", str(cases.shipped("fretting")),
                 "--vary", "fretting.amplitude=1e-7,6e-7", "--set", "mdr.elements=60",
                 "--set", "fretting.cycles=2", "--set", "fretting.stage_cycles=[0, 2]",
                 "--scheduler", cluster, "--quiet", "--out", str(out)]) == 0
    table, side = load(out / "fretting_map.csv")
    assert len(table) == 2
    assert list(table.columns) == ["fretting.amplitude",
                                   *[c.name for c in layout.FRETTING_MAP_COLUMNS]]
    assert units(side)["u_star"] == "m" and units(side)["wear_volume_per_cycle"] == "m^3"
    # u* = 3 μ F0/(4 G* a0) is the amplitude over the ratio, for every row
    np.testing.assert_allclose(table["fretting.amplitude"] / table["amplitude_over_u_star"],
                               table["u_star"], rtol=1e-9)


@pytest.mark.parametrize("name", ["history.csv", "measurements.csv", "track_profile.csv"])
def test_the_other_csv_writers_write_no_preamble(name):
    """history.csv, fit's measurements.csv and track_profile.csv: header first (their
    units are in the directory's meta.json data dictionary)."""
    from wearcheck.comparisons.present.track_report import profile_csv_text
    from wearcheck.rundir import history_csv_text
    from wearcheck.studies.fit import measurements_csv
    import io
    text = {"history.csv": lambda: history_csv_text({k: [0.0, 1.0] for k in (
                "s", "force", "depth", "contact_radius", "wear_center", "wear_volume")}),
            "measurements.csv": lambda: measurements_csv([dict(row=3, s=1.0, quantity="x",
                                                               unit="m", measured=1e-3)]),
            "track_profile.csv": lambda: profile_csv_text([0.0], [0.0], [0.0, 1e-5],
                                                          [[0.0, 1e-7]])}[name]()
    table = pd.read_csv(io.StringIO(text))
    assert len(table) >= 1 and not text.startswith("#")


def test_verify_results_history_loads_with_a_comma_in_a_file_name(tmp_path):
    """results/history.csv names each row's origin, a file name that may hold a comma."""
    from wearcheck.studies.verify import write_results
    hist = dict(s=[0.0, 1.0], force=[2.0, 1.0], origin=["run 1, final.csv row 2",
                                                         'say "hi".csv row 3'])
    write_results(tmp_path, hist, [], per_m=2.0)
    table = pd.read_csv(tmp_path / "history.csv")
    assert list(table.columns) == ["s", "s_hat", "force", "origin"]
    assert list(table["origin"]) == hist["origin"] and list(table["s_hat"]) == [0.0, 2.0]
    assert len(pd.read_csv(tmp_path / "stages.csv")) == 0
