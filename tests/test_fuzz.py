"""Property-based fuzzing of case files and ``--set`` values (Hypothesis).

Whatever the case file or override, ``wearcheck run`` ends with exit 0
(solved), 2 (bad input) or 3 (numerical failure); for 2 and 3 stderr is one
line; never a traceback; no file outside --out is touched. A run that would
take long is stopped by a time budget (through the solver's progress
callback) and then only the no-traceback and no-debris properties are kept.
The budgets are small (tens of examples, deadline off) so the file runs in
well under 30 s; raise ``max_examples`` locally to fuzz harder.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
import tomllib
from pathlib import Path

import pytest

from hypothesis import HealthCheck, given, settings, strategies as st  # noqa: E402

from wearcheck import cases  # noqa: E402
from wearcheck.cases.schema import SECTIONS, section_fields, toml_string  # noqa: E402
from wearcheck.cli import main as cli_main  # noqa: E402

BASE = tomllib.loads(cases.shipped("hertz").read_text())
#: seconds one fuzzed solve may take before it is stopped
BUDGET = 0.5
FUZZ = settings(max_examples=int(os.environ.get("WEARCHECK_FUZZ_EXAMPLES", 40)), deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])


class _OverBudget(KeyboardInterrupt):
    """Stops a slow fuzzed solve; the CLI reports it as an interrupt (exit 130)."""


@pytest.fixture
def budgeted(monkeypatch):
    from wearcheck import registry
    real = registry.solve
    hit = []

    def solve(case, solver, progress=None):
        t0 = time.perf_counter()

        def check(fraction, text=""):
            if time.perf_counter() - t0 > BUDGET:
                hit.append(True)
                raise _OverBudget()
        return real(case, solver, progress=check)
    monkeypatch.setattr("wearcheck.registry.solve", solve)
    return hit


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return toml_string(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) \
            else repr(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{toml_string(k)} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(v)


def _toml(doc: dict) -> str:
    lines = []
    for section, table in doc.items():
        if isinstance(table, dict):
            lines.append(f"[{toml_string(section)}]")
            lines += [f"{toml_string(k)} = {_toml_value(v)}" for k, v in table.items()]
        else:
            lines.insert(0, f"{toml_string(section)} = {_toml_value(table)}")
    return "\n".join(lines) + "\n"


KEYS = [f"{s}.{n}" for s in SECTIONS for n, _ in section_fields(s)]
scalars = st.one_of(
    st.booleans(),
    st.integers(min_value=-10**25, max_value=10**25),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-320, 1e-300, 1e300, 5e-324, 1e-6, 0.5, 2.0, 3, 800]),
    st.text(max_size=12),
    st.sampled_from(["auto", "depth", "force", "sphere", "table", "implicit", "bdf2",
                     "explicit", "distance", "force_fraction", "cone", "power_law"]))
values = st.one_of(scalars, st.lists(scalars, max_size=4),
                   st.dictionaries(st.text(max_size=5), scalars, max_size=2))


@st.composite
def case_documents(draw):
    doc = {k: dict(v) for k, v in BASE.items()}
    # keep fuzzed runs small unless a resolution key itself is fuzzed
    doc.setdefault("mdr", {})["elements"] = 60
    for _ in range(draw(st.integers(1, 4))):
        action = draw(st.sampled_from(["set", "set", "delete", "unknown", "section"]))
        key = draw(st.sampled_from(KEYS))
        section, name = key.split(".")
        if not isinstance(doc.get(section, {}), dict):
            continue  # replaced by a scalar earlier in this draw
        if action == "set":
            doc.setdefault(section, {})[name] = draw(values)
        elif action == "delete":
            doc.get(section, {}).pop(name, None)
        elif action == "unknown":
            doc.setdefault(section, {})[draw(st.text(min_size=1, max_size=8))] = draw(scalars)
        else:
            doc[section] = draw(scalars)  # a section that is not a table
    return doc


def _check(argv, case_text: bytes | None, hit) -> None:
    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        case = root / "case.toml"
        case.write_bytes(case_text if case_text is not None else
                         cases.shipped("hertz").read_bytes())
        (root / "keep.txt").write_text("user data")
        before = {p.name: p.read_bytes() for p in root.iterdir()}
        out = root / "out"
        hit.clear()
        import contextlib
        import io
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            try:
                code = cli_main(["run", str(case), "--out", str(out), "--quiet", *argv])
            except SystemExit as exc:  # argparse: a usage error
                code = exc.code
        text = err.getvalue()
        assert "Traceback" not in text
        after = {p.name: p.read_bytes() for p in root.iterdir() if p.name != "out"}
        assert after == before  # nothing outside --out touched, no debris beside it
        if os.environ.get("WEARCHECK_FUZZ_LOG"):
            with open(os.environ["WEARCHECK_FUZZ_LOG"], "a") as log:
                log.write(f"{code} {bool(hit)} {text.strip()[:150]!r}\n")
        if hit:
            assert code == 130 and not out.exists()
            return
        assert code in (0, 2, 3), text
        if code:
            assert len([l for l in text.splitlines() if l.strip()]) == 1, text
            assert not out.exists()
        else:
            assert tomllib.loads((out / "case.toml").read_text(encoding="utf-8"))


@FUZZ
@given(doc=case_documents())
def test_fuzzed_case_files(budgeted, doc):
    _check([], _toml(doc).encode("utf-8"), budgeted)


@FUZZ
@given(data=st.binary(max_size=64), at=st.integers(0, 400))
def test_corrupted_case_files(budgeted, data, at):
    text = cases.shipped("hertz").read_bytes()
    _check([], text[:at] + data + text[at:], budgeted)


@FUZZ
@given(key=st.one_of(st.sampled_from(KEYS), st.text(max_size=15)),
       value=st.one_of(st.text(max_size=20), values.map(_toml_value)))
def test_fuzzed_set_values(budgeted, key, value):
    _check(["--set", "mdr.elements=60", "--set", f"{key}={value}"], None, budgeted)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.text())
def test_toml_strings_round_trip(text):
    """The escape against tomllib (an independent TOML reader) over any text."""
    assert tomllib.loads(f"v = {toml_string(text)}")["v"] == text
