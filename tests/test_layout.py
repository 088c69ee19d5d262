"""Every output describes itself: each column, array and key that a run or a comparison
writes has a unit and a meaning in ``wearcheck.layout`` (and in the file's own data
dictionary), and nothing is described that is not written."""

import csv
from pathlib import Path
import json

import numpy as np
import pytest

import wearcheck
from wearcheck import layout


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


def test_docs_show_the_generated_tables():
    # docs/outputs.md includes every table layout.py defines, generated at each docs build
    # (docs/_ext/wearcheck_docs.py), so the documentation shows what is written
    import sys
    docs = Path(__file__).resolve().parents[1] / "docs"
    sys.path.insert(0, str(docs / "_ext"))
    try:
        import wearcheck_docs
    finally:
        sys.path.remove(str(docs / "_ext"))
    pages = wearcheck_docs.generated_pages()
    outputs = (docs / "outputs.md").read_text(encoding="utf-8")
    for name, table in layout.doc_tables().items():
        assert f"```{{include}} _generated/layout-{name}.md" in outputs, name
        assert pages[f"layout-{name}.md"].strip() == table
    for items in (layout.RUN_FILES, layout.HISTORY, layout.STAGES, layout.META,
                  layout.COMPARISON_FILES, layout.METRICS, layout.STAGE_METRICS):
        assert all(f"`{i.name}`" in "".join(pages.values()) for i in items)
