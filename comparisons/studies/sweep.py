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
from wearcheck.comparisons.studies.distributed import Task, fmt, record_study, run_cases
from wearcheck.comparisons.outputs import write_study_text
from wearcheck.comparisons.rundir import provenance


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
    from wearcheck.comparisons import registry
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
    from wearcheck.comparisons import registry
    registry.get(solver)  # an unknown solver is refused before the cluster starts
    values = varied_values(vary)
    check_varied(case, values)
    names = list(values)
    tasks = tasks_for(solver, solver, values)
    refuse_unsupported(case, solver, [t.changes for t in tasks])
    prov = provenance()
    out = Path(out)
    outcomes = run_cases(case, tasks, out, scheduler=scheduler, workers=workers,
                         quiet=quiet, solve=solve, extra_meta=dict(study=f"sweep-{solver}"),
                         study_files=("meta.json", "sweep.csv"))
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
    record_study(out, f"sweep-{solver}", case, prov, dict(solver=solver, vary=values))
    head = [f"# wearcheck sweep, solver {solver}: {', '.join(names)}",
            f"# command: {prov['command']}",
            f"# git revision: {prov['git_revision']}; versions and resolved case: meta.json",
            "# final_*: end of each run, in that run's own scales (d0, a0, F0 of its unworn "
            "contact); peak_rss_mb: worker process RSS sampled every 10 ms during the task",
            ",".join(rows[0])]
    body = [",".join(csv_cell(v) for v in r.values()) for r in rows]
    write_study_text(out, "sweep.csv", "\n".join(head + body) + "\n")
    return rows
