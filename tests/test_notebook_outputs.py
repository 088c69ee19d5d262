"""A run as notebooks and the ecosystem read it: pandas, xarray/netCDF, matplotlib Axes,
HTML representations, the progress bar's static state (issue 27 §4, §7)."""

import html.parser
import sys

import numpy as np
import pytest

import wearcheck
from wearcheck import layout
from wearcheck.comparisons.present import progress

pd = pytest.importorskip("pandas")
xr = pytest.importorskip("xarray")

# the paper case to ŝ = 1 with a small grid: a few dozen steps, two stages
SMALL = {"mdr.elements": 100, "sliding.until": "distance", "sliding.distance": 0.03,
         "stages.s_hat": [0.0, 0.5, 1.0]}


@pytest.fixture(scope="module")
def result():
    return wearcheck.solve(wearcheck.load_case("paper", SMALL), "mdr")


def test_history_frame_is_indexed_by_sliding_distance_with_units(result):
    frame = result.history_frame()
    assert frame.index.name == "s"
    np.testing.assert_array_equal(frame.index.to_numpy(), result.history["s"])
    np.testing.assert_array_equal(frame["force"].to_numpy(), result.history["force"])
    # the units are layout's, the one definition of what the files hold
    for item in layout.HISTORY:
        assert frame.attrs["units"][item.name] == item.unit
    assert frame.attrs["scales"]["F0"] == pytest.approx(result.scales["F0"])


def test_history_csv_loads_with_default_arguments(result, tmp_path):
    run = wearcheck.read_run(result.write(tmp_path / "run"))
    table = pd.read_csv(run.path / "history.csv")
    assert list(table.columns[:6]) == [i.name for i in layout.HISTORY]
    np.testing.assert_allclose(table["force"], result.history["force"], rtol=1e-11)
    # the frame of a run read back carries meta.json's dictionary: the same units
    assert run.history_frame().attrs["units"] == result.history_frame().attrs["units"]


def test_netcdf_holds_the_run_with_units_and_provenance(result, tmp_path):
    path = result.to_netcdf(tmp_path / "run.nc")
    with xr.open_dataset(path, engine="scipy") as ds:
        np.testing.assert_array_equal(ds["force"].values, result.history["force"])
        np.testing.assert_array_equal(ds["s"].values, result.history["s"])
        np.testing.assert_array_equal(ds["p"].values, result.stages["p"])
        np.testing.assert_array_equal(ds["stage_s"].values, result.stages["s"])
        assert ds["p"].dims == ("stage", "r")
        assert ds["force"].attrs["units"] == "N" and ds["p"].attrs["units"] == "Pa"
        assert ds["r"].attrs["units"] == "m"
        assert ds.attrs["solver"] == "mdr" and ds.attrs["wearcheck_output"] == "result"
        assert ds.attrs["scale_F0"] == pytest.approx(result.scales["F0"])
        # the resolved case in the file is the case that ran
        back = wearcheck.load_case(_written(tmp_path / "back.toml", ds.attrs["case_toml"]))
        assert wearcheck.cases.to_dict(back) == wearcheck.cases.to_dict(result.case)
        assert "python" in ds.attrs["versions"]


def _written(path, text):
    path.write_text(text, encoding="utf-8")
    return path


def test_netcdf_never_replaces_a_file_that_is_not_its_own(result, tmp_path):
    mine = result.to_netcdf(tmp_path / "run.nc")
    assert result.to_netcdf(mine) == mine             # its own: replaced
    theirs = tmp_path / "notes.nc"
    theirs.write_text("a user's file\n")
    with pytest.raises(wearcheck.CaseError, match="not a wearcheck netCDF file"):
        result.to_netcdf(theirs)
    assert theirs.read_text() == "a user's file\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.nc", "run.nc"]


def test_netcdf_into_a_missing_directory_is_one_clear_error(result, tmp_path):
    """A path whose directory does not exist raised FileNotFoundError naming the hidden
    temporary ('.run.nc.XXXX.partial'), a name the user never gave: a CaseError names
    the directory."""
    with pytest.raises(wearcheck.CaseError, match=r"its directory '.*nowhere' does not exist"):
        result.to_netcdf(tmp_path / "nowhere" / "run.nc")
    assert not (tmp_path / "nowhere").exists()


_NETCDF_WRITER = """
import sys, time
from pathlib import Path
import xarray
import wearcheck
def blocked(ds, path, **kw):       # half the file written, then the writer waits
    Path(path).write_bytes(b"CDF half a file")
    Path(sys.argv[2]).write_text("writing")
    time.sleep(120)
xarray.Dataset.to_netcdf = blocked
result = wearcheck.solve(wearcheck.load_case("hertz", {"mdr.elements": 40}), "mdr")
result.to_netcdf(sys.argv[1])
"""


def test_netcdf_temporaries_of_killed_writers_are_removed_those_of_live_ones_kept(
        result, tmp_path):
    """Two writers of the same netCDF path stopped mid-write: one killed (SIGKILL, no
    clean-up runs), one still at work. The next write removes the killed one's hidden
    temporary (before, '.run.nc.XXXX.partial' stayed for ever) and leaves the live
    one's, as the mesh cache does (wearcheck.temporaries). The file gets the
    permissions of a new file (mkstemp's 0600 before)."""
    import os
    import signal
    import stat
    import subprocess
    import time
    path = tmp_path / "run.nc"
    writers = {}
    for name in ("live", "dead"):
        ready = tmp_path.parent / f"{tmp_path.name}-{name}.ready"
        writers[name] = (subprocess.Popen([sys.executable, "-c", _NETCDF_WRITER, str(path),
                                           str(ready)]), ready)
    try:
        deadline = time.monotonic() + 120
        while not all(r.exists() for _, r in writers.values()):
            assert time.monotonic() < deadline and all(p.poll() is None
                                                       for p, _ in writers.values())
            time.sleep(0.05)
        dead = writers["dead"][0]
        dead.send_signal(signal.SIGKILL)
        assert dead.wait() == -signal.SIGKILL
        left = {p.name for p in tmp_path.iterdir()}
        assert len(left) == 2 and all(n.startswith(".run.nc.") for n in left), left
        live = {n for n in left if f"-{writers['live'][0].pid}@" in n}
        assert len(live) == 1, left
        result.to_netcdf(path)
        assert {p.name for p in tmp_path.iterdir()} == live | {"run.nc"}
        mask = os.umask(0)
        os.umask(mask)
        assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~mask
        with xr.open_dataset(path, engine="scipy") as ds:
            np.testing.assert_array_equal(ds["force"].values, result.history["force"])
    finally:
        for proc, ready in writers.values():
            proc.kill()
            proc.wait()
            ready.unlink(missing_ok=True)


def test_plot_helpers_draw_into_the_given_axes(result):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from wearcheck import plot
    fig, ax = plt.subplots()
    assert plot.history(result, "force", ax=ax, label="a") is ax
    assert plot.history(result, "force", scaled=True, ax=ax) is ax
    raw, scaled = ax.get_lines()
    np.testing.assert_allclose(raw.get_ydata(), result.history["force"])
    np.testing.assert_allclose(scaled.get_ydata(), result.history["force"] / result.scales["F0"])
    np.testing.assert_allclose(scaled.get_xdata(),
                               result.history["s"] * result.scales["s_hat_per_m"])
    assert ax.get_ylabel() == "F/F0"
    fig2, ax2 = plt.subplots()
    assert plot.stages(result, "p", ax=ax2) is ax2
    assert len(ax2.get_lines()) == len(result.stages["s"])
    assert ax2.get_ylabel() == "pressure p [Pa]"
    with pytest.raises(KeyError, match="not a history column"):
        plot.history(result, "wear")
    plt.close("all")


class _Cells(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.cells = []

    def handle_data(self, data):
        self.cells.append(data)


def test_case_and_result_have_html_and_readable_reprs(result):
    case = result.case
    parser = _Cells()
    parser.feed(case._repr_html_())
    text = " ".join(parser.cells)
    for section, keys in wearcheck.cases.to_dict(case).items():
        assert f"[{section}]" in text
        for k in keys:
            assert k in parser.cells, (section, k)
    lines = repr(case).splitlines()
    assert lines[0] == 'Case("paper.toml")' and all(len(s) < 250 for s in lines)
    parser = _Cells()
    parser.feed(result._repr_html_())
    assert f"{len(result.stages['s'])} of 3 stages reached" in parser.cells


def test_a_notebook_bar_prints_its_final_state_when_it_closes(monkeypatch, capsys):
    monkeypatch.setattr(progress, "in_notebook", lambda: True)
    bar = progress.ProgressBar("mdr", stream=sys.stderr)
    bar(0.5, "ŝ = 1")
    bar(1.0, "ŝ = 2")
    bar.close()
    out = capsys.readouterr().out
    assert out.startswith("mdr: 100.0 % in ") and out.rstrip().endswith("(ŝ = 2)")
