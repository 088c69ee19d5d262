"""Every output describes itself: each column, array and key that a run or a comparison
writes has a unit and a meaning in ``comparisons.layout`` (and in the file's own data
dictionary), and nothing is described that is not written."""

import csv
from pathlib import Path
import json

import numpy as np
import pytest

import wearcheck
from wearcheck.comparisons import layout


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = {}
    for solver, changes in (("mdr", {"mdr.elements": 200}), ("fem", {"fem.contact_nodes": 40}),
                            ("bem", {"bem.grid": 32})):
        case = wearcheck.load_case("paper", {**changes, "stages.s_hat": [0.0, 1.0],
                                             "sliding.until": "distance",
                                             "sliding.distance": 0.04})
        out[solver] = wearcheck.solve(case, solver).write(tmp_path_factory.mktemp(solver) / "r")
    return out


@pytest.mark.parametrize("solver", ["mdr", "fem", "bem"])
def test_run_directory_matches_its_data_dictionary(runs, solver):
    path = runs[solver]
    meta = json.loads((path / "meta.json").read_text())
    d = meta["data_dictionary"]
    with open(path / "history.csv") as fh:
        header = next(csv.reader(fh))
    assert set(header) == set(d["history_csv"])
    with np.load(path / "stages.npz") as z:
        assert set(z.files) == set(d["stages_npz"])
    if (path / "fields.npz").exists():
        with np.load(path / "fields.npz") as z:
            assert set(z.files) == set(d["fields_npz"])
    else:
        assert d["fields_npz"] == {}
    assert set(meta) == set(d["meta_json"])
    written = {p.name for p in path.iterdir()}
    assert written <= set(d["files"])
    for table in ("history_csv", "stages_npz", "fields_npz", "meta_json"):
        assert all(v["meaning"] for v in d[table].values())


def test_comparison_metrics_match_the_dictionary(tmp_path):
    case = wearcheck.load_case("paper", {"mdr.elements": 200, "fem.contact_nodes": 40,
                                         "stages.s_hat": [0.0, 0.5],
                                         "sliding.until": "distance",
                                         "sliding.distance": 0.01})
    m = wearcheck.compare(case, tmp_path / "cmp", render=False, edge_study=True)
    written = json.loads((tmp_path / "cmp" / "metrics.json").read_text())
    d = written["data_dictionary"]
    assert set(written) <= set(d["metrics_json"])
    assert set(d["metrics_json"]) - set(written) == set(layout.METRICS_OPTIONAL) - {"edge_study",
                                                                                   "scar"}
    for stage in m["pairs"]["fem"]["stages"]:
        assert set(stage) - {"index"} - {k for k in stage if k.endswith("_points")} \
            <= set(d["stage_metrics"])


def test_markdown_tables_list_every_item():
    text = layout.markdown(layout.HISTORY)
    assert all(f"`{i.name}`" in text for i in layout.HISTORY)


def test_readme_tables_are_the_generated_ones(tmp_path):
    readme = Path(__file__).resolve().parents[1] / "README.md"
    copy = tmp_path / "README.md"
    copy.write_text(readme.read_text(encoding="utf-8"), encoding="utf-8")
    # regenerating changes nothing: the README shows what layout.py defines
    assert not layout.update_readme(copy), \
        "README tables are stale: run layout.update_readme('README.md')"
    text = copy.read_text(encoding="utf-8")
    for table in layout.readme_sections().values():
        assert table in text
