"""Parameter sweeps on Dask (``wearcheck sweep``): one run per value of case keys.

One run per combination of the values of ``vary`` (``{"wear.k": [1e-5, 1e-4]}``;
several keys: their cartesian product), each in its own run directory in
``out``, on the same Dask runner as ``wearcheck refine``; ``sweep.csv``
summarises them. The values are Python values, as :meth:`Case.derive` takes
them (the command line types its ``--vary`` text once, with
``cases.case.parse_vary``); a value the case rejects in its combination, or a
run that fails, is a row with its error.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np

from wearcheck import cases
from wearcheck.cases import ArgumentError
from wearcheck.cases.reference import scales as case_scales
from wearcheck.cases.schema import format_value, key_problem
from wearcheck.studies.distributed import Task, fmt, record_study, run_cases
from wearcheck import csv_metadata
from wearcheck.csv_metadata import describer, sidecar_name, write_table
from wearcheck.layout import SWEEP_COLUMNS
from wearcheck.outputs import study_lock
from wearcheck.rundir import provenance


def plain(value):
    """numpy scalars and arrays as Python numbers and lists; tuples as lists."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, tuple):
        return [plain(v) for v in value]
    return value


def varied_values(vary) -> dict[str, list]:
    """``vary`` as ``{"section.key": [values]}`` of plain Python values.

    A key takes a sequence of values, or one value (a string is one value); a
    list key (``stages.s_hat``) takes a list of lists. Refused naming ``vary``.
    """
    example = '{"wear.mu": [0.2, 0.3]}'
    if not isinstance(vary, Mapping):
        raise ArgumentError("vary", f"give a mapping of case keys to values, e.g. {example}",
                            value=vary)
    if not vary:
        raise ArgumentError("vary", f"name at least one key and its values, e.g. {example}",
                            value=dict(vary))
    out = {}
    for key, values in vary.items():
        problem = key_problem(key)
        if problem:
            raise ArgumentError("vary", problem, key=key)
        if isinstance(values, np.ndarray):
            values = values.tolist() if values.ndim else [values.item()]
        elif isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
            values = [values]  # one value, not a sequence of characters
        out[key] = [plain(v) for v in values]
        if not out[key]:
            raise ArgumentError("vary", "no values", key=key)
    return out


def value_text(value) -> str:
    """A varied value as run directory names and ``sweep.csv`` show it."""
    if isinstance(value, str):
        return value
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(value_text(v) for v in value) + "]"
    return format_value(value)


def dir_part(text: str) -> str:
    """``text`` as a piece of a directory name."""
    return re.sub(r"[^A-Za-z0-9._+-]+", "_", text).strip("_") or "_"


def check_varied(case, values: dict[str, list]) -> None:
    """Refuse, before the cluster starts, a value its key can never take.

    Each value is tried in every combination with the others' (validation only,
    ms each): it is refused when every combination holding it fails on its own
    key (``loading.force=1`` alone fails on a depth-controlled case, but not
    beside ``loading.control = "force"``). An error about another key is left to
    the runs (the value may be fine in its combination).
    """
    names = list(values)
    refused, fine = {}, set()
    for combo in itertools.product(*(range(len(values[n])) for n in names)):
        picked = list(zip(names, combo))
        try:
            case.derive({n: values[n][i] for n, i in picked})
            fine.update(picked)
        except cases.CaseError as exc:
            for n, i in picked:
                if f"key '{n}'" in str(exc):
                    refused.setdefault((n, i), exc)
                else:
                    fine.add((n, i))
    for (name, i), exc in refused.items():
        if (name, i) not in fine:
            raise ArgumentError("vary", str(exc), key=name)


def task_changes(changes: dict) -> dict:
    """A task's changes as any worker reads them: a relative ``indenter.file`` made
    absolute here, where :meth:`Case.derive` would read it (a worker's working
    directory may differ)."""
    out = dict(changes)
    file = out.get("indenter.file")
    if isinstance(file, str) and not Path(file).is_absolute():
        out["indenter.file"] = str(Path.cwd() / file)
    return out


def refuse_unsupported(case, solver: str, runs, every: bool = False) -> None:
    """Refuse, before the cluster starts, a study whose solver cannot run its cases.

    ``runs`` are the changes of the study's runs. Refused when none of them is
    supported (a sweep over several profiles may hold some the solver cannot
    run: those become error rows) or, with ``every``, when any is not (a
    refinement varies only the resolution, which never makes a case
    supported). A combination the case rejects is left to its row.
    """
    from wearcheck import registry
    entry = registry.get(solver)
    reasons = []
    for changes in runs:
        try:
            reason = entry.supports(case.derive(changes))
        except cases.CaseError:
            continue
        if reason is None and not every:
            return
        if reason is not None:
            reasons.append(reason)
            if every:
                break
    if reasons:
        raise cases.CaseError(f"solver '{solver}' cannot run this case: {reasons[0]}")


def tasks_for(prefix: str, solver: str, values: dict[str, list]) -> list[Task]:
    """One task per combination of the varied values, named by them."""
    names = list(values)
    tasks = []
    for combo in itertools.product(*values.values()):
        name = "-".join([prefix] + [f"{n}-{dir_part(value_text(v))}"
                                    for n, v in zip(names, combo)])
        tasks.append(Task(name, solver, task_changes(dict(zip(names, combo)))))
    if len({t.name for t in tasks}) != len(tasks):
        tasks = [Task(f"{t.name}-{i}", t.solver, t.changes) for i, t in enumerate(tasks)]
    return tasks


def csv_cell(value) -> str:
    """A cell of a study's table: text and varied values quoted, numbers to 10 digits."""
    if isinstance(value, (str, list, tuple, bool)):
        return '"' + value_text(value).replace('"', "'") + '"'
    return fmt(value, ".10g")


def sweep(case: cases.Case, vary: Mapping[str, Iterable], solver: str, out, *,
          scheduler=None, workers=None, quiet=False, solve=None) -> list[dict]:
    """Run every combination of the varied values into ``out``; return sweep.csv's rows.

    Parameters
    ----------
    case : the base case; each run is ``case.derive`` of its combination.
    vary : ``{"section.key": [values]}``, Python values as ``Case.derive`` takes them.
    solver : a registered solver's name.
    out : the sweep directory.

    The rows hold the varied values (typed; a relative ``indenter.file`` made
    absolute), the status, times and the end of each run in its own scales.
    """
    from wearcheck import registry
    registry.get(solver)  # an unknown solver is refused before the cluster starts
    values = varied_values(vary)
    check_varied(case, values)
    names = list(values)
    tasks = tasks_for(solver, solver, values)
    refuse_unsupported(case, solver, [t.changes for t in tasks])
    prov = provenance()
    out = Path(out)
    earlier_rows(out, solver, case)      # refused now, before the cluster, if it must be
    outcomes = run_cases(case, tasks, out, scheduler=scheduler, workers=workers,
                         quiet=quiet, solve=solve, extra_meta=dict(study=f"sweep-{solver}"),
                         study_files=("meta.json", "sweep.csv", sidecar_name("sweep.csv")))
    rows = []
    for t, o in zip(tasks, outcomes):
        row = dict(run=t.name, **t.changes)
        row.update(status=o.status, wall_seconds=o.wall_seconds, cpu_seconds=o.cpu_seconds,
                   solve_seconds=o.result.solve_seconds if o.ok else math.nan,
                   peak_rss_mb=o.peak_rss_mb)
        final = dict(steps=None, final_s=math.nan, final_s_hat=math.nan, final_F_over_F0=math.nan,
                     final_wear_center_over_d0=math.nan, final_contact_radius_over_a0=math.nan)
        if o.ok:
            h, sc = o.result.history, case_scales(o.case)
            final.update(steps=len(h["s"]) - 1, final_s=float(h["s"][-1]),
                         final_s_hat=float(h["s"][-1]) * sc["s_hat_per_m"],
                         final_F_over_F0=float(h["force"][-1]) / sc["F0"],
                         final_wear_center_over_d0=float(h["wear_center"][-1]) / sc["d0"],
                         final_contact_radius_over_a0=float(h["contact_radius"][-1]) / sc["a0"])
        row.update(final)
        rows.append(row)
    with study_lock(out):
        # read again: a sweep into the directory may have ended since this one began
        earlier = earlier_rows(out, solver, case)
        record_study(out, f"sweep-{solver}", case, prov, dict(solver=solver, vary=values))
        text = table_text(earlier, rows, case)
        keys = [k for k in csv_metadata.header(text) if "." in k]
        write_table(out, "sweep.csv", text, title=f"wearcheck sweep, solver {solver}",
                    command=prov["command"], notes=table_notes(earlier, keys, solver, prov),
                    describe=lambda c: varied_column(c) if "." in c else describe(c))
    return rows


describe = describer(SWEEP_COLUMNS)


def _quoted(v: str) -> str:
    return '"' + str(v).replace('"', "'") + '"'


def earlier_rows(out: Path, solver: str, case) -> list[dict]:
    """The rows of the ``sweep.csv`` an earlier sweep wrote into the study ``out``, to keep.

    A second sweep into a study adds its runs to the first's table (more values,
    or another key; a run done again replaces its row), so that nothing the
    first wrote is lost: the table covers every run in the directory. It must
    then be a sweep of the same solver on the same base case (the case file
    with its ``--set``): refused, before the cluster starts, otherwise, as one
    table would present the runs of two different studies as one.
    """
    from wearcheck.outputs import read_marker
    from wearcheck.studies.distributed import base_difference, study_meta
    marker = read_marker(out) if Path(out).is_dir() else None
    if not marker or marker.get("kind") != "study":
        return []
    studies = study_meta(out).get("studies", {})
    for name, entry in studies.items():
        if not name.startswith("sweep-") or not isinstance(entry, dict):
            continue
        if name != f"sweep-{solver}":
            raise ArgumentError("out", f"holds a sweep by solver '{name[6:]}' (sweep.csv); a "
                                f"sweep by '{solver}' would mix with it in one table: choose "
                                "another directory", value=str(out))
        why = base_difference(entry.get("resolved_case", ""), case)
        if why:
            raise ArgumentError("out", f"holds a sweep of another base case ({why}); its "
                                "sweep.csv would mix two studies: choose another directory, "
                                "or the same base case", value=str(out))
    path = Path(out) / "sweep.csv"
    if not path.is_file():
        return []
    return csv_metadata.read_rows(path)


def table_text(earlier: list[dict], rows: list[dict], case) -> str:
    """sweep.csv: the rows of earlier sweeps into the study (as they were written), then
    this sweep's; a run of both appears once, as this sweep wrote it. A key an earlier
    sweep did not vary holds the base case's value in its rows, and vice versa."""
    import tomllib
    base = tomllib.loads(cases.to_toml(case))

    def base_cell(key: str) -> str:
        section, _, name = key.partition(".")
        value = base.get(section, {}).get(name)
        return '""' if value is None else csv_cell(value)

    def old_cell(key: str, text: str) -> str:
        """An earlier row's cell, as it was written: quoted unless a number."""
        if key not in ("run", "status"):
            try:
                float(text)
                return text
            except ValueError:
                pass
        return _quoted(text)

    fixed = [k for k in rows[0] if k != "run" and "." not in k]
    keys = list(dict.fromkeys([k for r in earlier + rows for k in r if "." in k]))
    columns = ["run", *keys, *fixed]

    def line(r: dict, old: bool) -> str:
        cells = []
        for k in columns:
            if k not in r or (old and k in keys and r[k] in (None, "")):
                cells.append(base_cell(k) if k in keys else '""')
            else:
                cells.append(old_cell(k, r[k] or "") if old else csv_cell(r[k]))
        return ",".join(cells)

    done = {r["run"] for r in rows}
    body = [line(r, True) for r in earlier if r.get("run") not in done]
    body += [line(r, False) for r in rows]
    return "\n".join([",".join(columns)] + body) + "\n"


def table_notes(earlier: list[dict], keys, solver: str, prov) -> list[str]:
    """sweep.csv's notes (its sidecar's): what the ``#`` lines above the table said."""
    return [f"wearcheck sweep, solver {solver}: {', '.join(keys)}.",
            f"Command: {prov['command']}"
            + (f" (with the rows of earlier sweeps into this directory: their commands "
               f"in meta.json, studies.sweep-{solver}.earlier)." if earlier else "."),
            f"Git revision: {prov['git_revision']}; versions and resolved case: meta.json.",
            "final_*: end of each run, in that run's own scales (d0, a0, F0 of its unworn "
            "contact); peak_rss_mb: worker process RSS sampled every 10 ms during the task."]


def varied_column(key: str):
    """The sidecar's description of a varied case key's column."""
    from wearcheck.cases.result import Item
    return Item(key, "(case units)", f"the case key {key} of the run, in the case file's "
                                     "units (docs: the case reference)")

