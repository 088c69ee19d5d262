"""CSV on the Web sidecars for the tables a study writes.

Each table ``NAME.csv`` is its header line and its rows, nothing else, so that
``pandas.read_csv(path)`` (or any CSV reader) reads it with no arguments; its
title, the command that wrote it, the remarks that once stood in ``#`` lines
above the header, and each column's meaning and unit go to
``NAME.csv-metadata.json`` beside it, in the W3C CSVW form
(https://www.w3.org/TR/tabular-metadata/), which CSVW tools find by that name.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from urllib.parse import quote

CSVW_CONTEXT = "http://www.w3.org/ns/csvw"


def sidecar_name(csv_name: str) -> str:
    """The metadata file of ``csv_name`` (CSVW's default location)."""
    return f"{csv_name}-metadata.json"


def header(text: str) -> list[str]:
    """The column names of a CSV text (its first line that is not a ``#`` remark)."""
    for line in text.splitlines():
        if not line.startswith("#"):
            return next(csv.reader([line]))
    return []


def metadata(csv_name: str, title: str, command: str, notes, columns, describe) -> dict:
    """The CSVW metadata of the table ``csv_name``.

    ``columns``: its header; ``describe(column)``: an ``Item`` (unit, meaning) or
    None. A column's ``name`` is its title percent-encoded as CSVW requires of
    names (``F/F0 at s_hat=1`` -> ``F%2FF0%20at%20s_hat%3D1``); ``titles`` is the
    header cell as written.
    """
    cols = []
    for title_ in columns:
        item = describe(title_)
        col = {"name": quote(title_, safe="._"), "titles": title_}
        if item is not None:
            col["dc:description"] = item.meaning
            col["unit"] = item.unit
        cols.append(col)
    return {"@context": CSVW_CONTEXT, "url": csv_name, "dc:title": title,
            "dc:source": command, "notes": list(notes),
            "tableSchema": {"columns": cols}}


def write_table(study, csv_name: str, text: str, *, title: str, command: str, notes,
                describe) -> None:
    """Write ``text`` as ``study/csv_name`` and its sidecar, each atomically as a
    study file (:func:`outputs.write_study_text`)."""
    from wearcheck.outputs import write_study_text
    meta = metadata(csv_name, title, command, notes, header(text), describe)
    write_study_text(study, csv_name, text)
    write_study_text(study, sidecar_name(csv_name),
                     json.dumps(meta, indent=2, ensure_ascii=False) + "\n")


def read_rows(path) -> list[dict]:
    """The rows of a study's CSV, as text; ``#`` lines (the preamble wearcheck
    wrote above the header before the sidecars) are skipped."""
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(line for line in fh if not line.startswith("#")))


def read_notes(path) -> list[str]:
    """The notes of a study's CSV: its sidecar's, or its ``#`` lines when an earlier
    version wrote it (no sidecar)."""
    path = Path(path)
    side = path.with_name(sidecar_name(path.name))
    if side.is_file():
        try:
            return [str(n) for n in json.loads(side.read_text(encoding="utf-8"))
                    .get("notes", [])]
        except (OSError, ValueError, AttributeError):
            return []
    return [line.lstrip("#").strip() for line in path.read_text(encoding="utf-8").splitlines()
            if line.startswith("#")]


def rows_text(columns, rows) -> str:
    """A CSV text of ``rows`` (dicts of text) under ``columns``; missing cells empty."""
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=list(columns), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return text.getvalue()


def describer(items, patterns=()):
    """``describe(column)`` for :func:`metadata`: the item named ``column``, else the
    first of ``patterns`` (``(prefix, item)``) whose prefix it starts with."""
    by_name = {i.name: i for i in items}

    def describe(column):
        if column in by_name:
            return by_name[column]
        for prefix, item in patterns:
            if column.startswith(prefix):
                return item
        return None
    return describe
