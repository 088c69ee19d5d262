"""Parameter sweeps on Dask (``wearcheck sweep``): one run per value of case keys.

One run per value (the cartesian product of several ``--vary``), each in its
own run directory in DIR, on the same Dask runner as ``wearcheck refine``;
``sweep.csv`` summarises them. Values are written as for ``--set``; a value
the case rejects, or a run that fails, is a row with its error.
"""

from __future__ import annotations

import itertools
import math
import re
from pathlib import Path

from wearcheck import cases
from wearcheck.cases.case import parse_override
from wearcheck.cases.reference import scales as case_scales
from wearcheck.cases.schema import section_fields
from wearcheck.comparisons.studies.distributed import Task, fmt, record_study, run_cases
from wearcheck.comparisons.outputs import study_lock, write_study_text
from wearcheck.comparisons.rundir import provenance


def split_values(text: str) -> list[str]:
    """Split at commas outside brackets and quotes: ``[0, 1],[2]`` is two values."""
    values, depth, quote, cur = [], 0, None, ""
    for ch in text:
        if quote:
            quote = None if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch == "[":
            depth += 1
        elif ch == "]":
            depth -= 1
        elif ch == "," and depth == 0:
            values.append(cur.strip())
            cur = ""
            continue
        cur += ch
    values.append(cur.strip())
    return values


def check_varied(varied, overrides, case=None) -> list[str]:
    """The varied key names; a key varied twice, or both set and varied, is refused.

    With ``case``, each value is also tried on it alone: a value its key can
    never take (a word for a number, a negative count) is refused here, before
    the cluster starts, rather than as a failed run per combination. An error
    about another key is left to the runs (the value may be fine in its
    combination).
    """
    names = [n for n, _ in varied]
    if len(set(names)) != len(names):
        raise cases.CaseError("--vary names a key twice: " + ", ".join(names))
    both = set(names) & {o.partition("=")[0].strip() for o in overrides}
    if both:
        raise cases.CaseError(f"key {sorted(both)[0]} is both in --set and --vary")
    if case is not None:
        # a value is refused when every combination holding it fails on its own key
        # (loading.force=1 alone fails on a depth-controlled case, but not beside
        # --vary loading.control=force); the product is validation only, ms each
        refused = {}
        fine = set()
        for combo in itertools.product(*([(n, v) for v in vals] for n, vals in varied)):
            try:
                case.derive([f"{n}={v}" for n, v in combo])
                fine.update(combo)
            except cases.CaseError as exc:
                for n, v in combo:
                    if f"key '{n}'" in str(exc):
                        refused.setdefault((n, v), exc)
                    else:
                        fine.add((n, v))
        for (name, v), exc in refused.items():
            if (name, v) not in fine:
                raise cases.CaseError(f"--vary {name}: {exc}")
    return names


def refuse_unsupported(case, solver: str, runs, every: bool = False) -> None:
    """Refuse, before the cluster starts, a study whose solver cannot run its cases.

    ``runs`` are the override lists of the study's runs. Refused when none of
    them is supported (a sweep over several profiles may hold some the solver
    cannot run: those become error rows) or, with ``every``, when any is not
    (a refinement varies only the resolution, which never makes a case
    supported). A combination the case rejects is left to its row.
    """
    from wearcheck.comparisons import registry
    entry = registry.get(solver)
    reasons = []
    for overrides in runs:
        try:
            reason = entry.supports(case.derive(list(overrides)))
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


def parse_vary(text: str) -> tuple[str, list[str]]:
    """``section.key=v1,v2`` -> (``section.key``, [``v1``, ``v2``]), checked like ``--set``."""
    if "=" not in text:
        raise cases.CaseError(f"--vary '{text}': expected section.key=v1,v2,...")
    name, _, rest = text.partition("=")
    name = name.strip()
    values = split_values(rest)
    if not all(values):
        raise cases.CaseError(f"--vary '{text}': an empty value")
    for v in values:
        section, key, _ = parse_override(f"{name}={v}")
    if key not in {n for n, _ in section_fields(section)}:
        from wearcheck.cases.schema import did_you_mean
        names = [n for n, _ in section_fields(section)]
        raise cases.CaseError(f"--vary '{text}': unknown key '{name}'{did_you_mean(key, names)}"
                              f"; allowed in [{section}]: "
                              + ", ".join(n for n, _ in section_fields(section)))
    return name, values


def _dir_part(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._+-]+", "_", text).strip("_") or "_"


def sweep(case_path, overrides, vary, solver, out, *, scheduler=None, workers=None,
          quiet=False, solve=None, case=None) -> list[dict]:
    """Run every combination of the varied values into ``out``; return sweep.csv's rows."""
    case = case or cases.load(case_path, overrides)
    from wearcheck.comparisons import registry
    registry.get(solver)  # an unknown solver is refused before the cluster starts
    varied = [parse_vary(v) for v in vary]
    names = check_varied(varied, overrides, case)
    tasks = []
    for combo in itertools.product(*(vals for _, vals in varied)):
        run = "-".join([solver] + [f"{n}-{_dir_part(v)}" for n, v in zip(names, combo)])
        tasks.append(Task(run, solver, tuple(f"{n}={v}" for n, v in zip(names, combo))))
    refuse_unsupported(case, solver, [t.overrides for t in tasks])
    if len({t.name for t in tasks}) != len(tasks):
        tasks = [Task(f"{t.name}-{i}", t.solver, t.overrides) for i, t in enumerate(tasks)]
    prov = provenance()
    out = Path(out)
    earlier_rows(out, solver, case)      # refused now, before the cluster, if it must be
    outcomes = run_cases(case_path, overrides, tasks, out, scheduler=scheduler, workers=workers,
                         quiet=quiet, solve=solve, extra_meta=dict(study=f"sweep-{solver}"),
                         study_files=("meta.json", "sweep.csv"))
    rows = []
    for t, o in zip(tasks, outcomes):
        row = dict(run=t.name)
        row.update({n: o.partition("=")[2] for n, o in zip(names, t.overrides)})
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
        record_study(out, f"sweep-{solver}", case, overrides, prov)
        write_study_text(out, "sweep.csv", table_text(earlier, rows, solver, case, prov))
    return rows


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
    from wearcheck.comparisons.outputs import read_marker
    from wearcheck.comparisons.studies.distributed import base_difference, study_meta
    marker = read_marker(out) if Path(out).is_dir() else None
    if not marker or marker.get("kind") != "study":
        return []
    studies = study_meta(out).get("studies", {})
    for name, entry in studies.items():
        if not name.startswith("sweep-") or not isinstance(entry, dict):
            continue
        if name != f"sweep-{solver}":
            raise cases.CaseError(f"study '{out}' holds a sweep by solver '{name[6:]}' "
                                  f"(sweep.csv); a sweep by '{solver}' would mix with it in "
                                  "one table: choose another --out")
        why = base_difference(entry.get("resolved_case", ""), case)
        if why:
            raise cases.CaseError(f"study '{out}' holds a sweep of another base case "
                                  f"({why}); its sweep.csv would mix two studies: choose "
                                  "another --out, or the same case file and --set")
    path = Path(out) / "sweep.csv"
    if not path.is_file():
        return []
    import csv
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(line for line in fh if not line.startswith("#")))


def table_text(earlier: list[dict], rows: list[dict], solver: str, case, prov) -> str:
    """sweep.csv: the rows of earlier sweeps into the study (as they were written), then
    this sweep's; a run of both appears once, as this sweep wrote it. A key an earlier
    sweep did not vary holds the base case's value in its rows, and vice versa."""
    import tomllib
    base = tomllib.loads(cases.to_toml(case))

    def base_value(key: str) -> str:
        section, _, name = key.partition(".")
        value = base.get(section, {}).get(name)
        return "" if value is None else str(value).lower() if isinstance(value, bool) \
            else str(value)

    fixed = [k for k in rows[0] if k != "run" and "." not in k]
    keys = list(dict.fromkeys([k for r in earlier + rows for k in r if "." in k]))
    columns = ["run", *keys, *fixed]
    texts = {"run", "status", *keys}       # written quoted; numbers as they are

    def line(r: dict, old: bool) -> str:
        cells = []
        for k in columns:
            v = r.get(k)
            if v is None and k in keys:
                v = base_value(k)
            if k in texts:
                cells.append(_quoted("" if v is None else v))
            else:        # an earlier row's cell as it was written, this sweep's formatted
                cells.append(("" if v is None else v) if old else fmt(v, ".10g"))
        return ",".join(cells)

    done = {r["run"] for r in rows}
    body = [line(r, True) for r in earlier if r.get("run") not in done]
    body += [line(r, False) for r in rows]
    head = [f"# wearcheck sweep, solver {solver}: {', '.join(keys)}",
            f"# command: {prov['command']}"
            + (f" (with the rows of earlier sweeps into this directory: their commands "
               f"in meta.json, studies.sweep-{solver}.earlier)" if earlier else ""),
            f"# git revision: {prov['git_revision']}; versions and resolved case: meta.json",
            "# final_*: end of each run, in that run's own scales (d0, a0, F0 of its unworn "
            "contact); peak_rss_mb: worker process RSS sampled every 10 ms during the task",
            ",".join(columns)]
    return "\n".join(head + body) + "\n"
