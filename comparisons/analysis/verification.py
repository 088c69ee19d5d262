"""Results produced elsewhere against a reference, stage by stage (pure: arrays in, a
dict out).

The user's data are never interpolated: each stage is judged at the user's own
distance and radii, the reference evaluated there (the certified reference
anywhere within its stored stages, a fresh run at the stages it was asked
for). A stage's history quantities are the user's history row at the stage's
distance; without a row there they are not judged at that stage. Without a
stages table, the stages are the history rows nearest the case's stages.

Each check is the verdict's (``metrics.verdict``): the difference relative to
the stage's own scale, floored, against the case's ``[compare]`` tolerance.
The checks are those of ``compare`` plus the wear checks
(``metrics.WEAR_CHECKS``: central wear, worn volume, depth), each made where
the user gave its quantity; what was not given is listed, not failed. A check
that was given but compared nothing (radii that miss the contact) fails. A
check where the reference's own error band uses more than
:data:`CERTIFIED_SHARE` of the tolerance is not judged (listed with both
numbers), unless the difference exceeds the tolerance by more than the band: that
fails whatever the reference's error.
"""

from __future__ import annotations

import math

import numpy as np

from wearcheck.cases import CaseError

from . import metrics

#: the history quantities and the check each one decides
HISTORY_CHECKS = {"force": "force", "contact_radius": "contact_radius",
                  "wear_center": "wear_center", "wear_volume": "wear_volume", "depth": "depth"}
#: two distances closer than this (relative to the largest) are the same stage
SAME_DISTANCE = 1e-9
#: a check is judged only where the reference's own error (its band, relative to the
#: stage's scale) uses at most this share of the check's tolerance: beyond it a pass
#: or a fail would say as much about the reference as about the results
CERTIFIED_SHARE = 1.0 / 3.0


def unit_scales(scales: dict, depth: float) -> dict:
    """The unworn unit of each check's column, in SI."""
    return dict(profile_contact_max=depth, force=scales["F0"], pressure_interior_max=scales["p0"],
                contact_radius=scales["a0"], wear_center=depth, depth=depth,
                wear_volume=math.pi * scales["a0"] ** 2 * depth)


class RunReference:
    """A fresh run as the reference: its stages where it was asked to keep them, its
    history by monotone cubic interpolation in s; no error band."""

    def __init__(self, result, case, name: str):
        self.result, self.case, self.name = result, case, name
        self.stage_s = np.asarray(result.stage_s, float)
        import scipy.interpolate
        s = np.asarray(result.history["s"], float)
        keep = np.concatenate([[True], np.diff(s) > 0])
        self._s = s[keep]
        self._h = {}
        for q in HISTORY_CHECKS:
            y = np.asarray(result.history[q], float)[keep]
            self._h[q] = (scipy.interpolate.PchipInterpolator(self._s, y) if len(y) > 1
                          else (lambda v: (lambda x: np.full(np.shape(x), v)))(float(y[0])))

    def _stage(self, s):
        tol = SAME_DISTANCE * max(float(np.max(self.stage_s, initial=0.0)), 1e-300)
        hit = np.flatnonzero(np.abs(self.stage_s - s) <= tol)
        return int(hit[0]) if hit.size else None

    def covers(self, s) -> bool:
        return self._stage(s) is not None

    def history_at(self, s) -> dict:
        s = np.atleast_1d(np.asarray(s, float))
        inside = (s >= self._s[0]) & (s <= self._s[-1] * (1 + 1e-12))
        out = {"s": s}
        for q, f in self._h.items():
            out[q] = np.where(inside, f(np.clip(s, self._s[0], self._s[-1])), np.nan)
        return out

    def stage_at(self, s, r):
        k = self._stage(s)
        rr = np.asarray(self.result.r, float)
        r = np.asarray(r, float)
        f = np.interp(r, rr, np.asarray(self.result.f[k], float), right=np.nan)
        p = np.interp(r, rr, np.asarray(self.result.p[k], float), right=0.0)
        return f, p

    def radii(self, s_list):
        return np.asarray(self.result.r, float)

    def band_at(self, s):
        return None

    def cycles_to_s(self, cycles):
        """Distances [m] of cycle counts: the run's own cycles column (fretting), else
        the case's stroke."""
        cycles = np.asarray(cycles, float)
        h = self.result.history
        if "cycles" in h and np.all(np.isfinite(h["cycles"])):
            return np.interp(cycles, h["cycles"], h["s"], left=np.nan, right=np.nan)
        cpm = self.case.cycles_per_metre
        return cycles / cpm if cpm is not None else np.full(np.shape(cycles), np.nan)


def to_distance(values, kind: str, case, scales: dict, cycles_to_s=None) -> np.ndarray:
    """Distances s [m] of values given as s, ŝ or cycles (a fretting reference maps
    its own cycles to distances: ``cycles_to_s``)."""
    values = np.asarray(values, float)
    if kind == "s":
        return values
    if kind == "s_hat":
        return values / scales["s_hat_per_m"]
    if case.fretting is not None and cycles_to_s is not None:
        return cycles_to_s(values)
    cpm = case.cycles_per_metre
    if cpm is None:
        raise CaseError("the results give 'cycles' but the case has no sliding.stroke to "
                        "turn them into a sliding distance (s = 2·stroke·cycles); give s or "
                        "s_hat, or set sliding.stroke")
    return values / cpm


def select_stages(history: dict, stages: list, case_stage_s,
                  same: float = SAME_DISTANCE) -> list[dict]:
    """The stages to judge: the user's stages, or (none given) the history rows
    nearest the case's stages. Each {s, stage (index into ``stages`` or None),
    row (history row index or None)}. A history row belongs to a stage when their
    distances agree to ``same`` relative (files that print the same time with
    different digits, such as CalculiX's .dat and .frd, need more than round-off)."""
    hs = np.asarray(history["s"], float)
    out = []
    if stages:
        for i, st in enumerate(stages):
            hit = np.flatnonzero(np.abs(hs - st["s"]) <= same * abs(st["s"]))
            out.append(dict(s=st["s"], stage=i, row=int(hit[0]) if hit.size else None))
        return out
    rows = []
    for s in case_stage_s:
        if hs.size:
            i = int(np.argmin(np.abs(hs - s)))
            if i not in rows:
                rows.append(i)
    return [dict(s=float(hs[i]), stage=None, row=i) for i in sorted(rows)]


def judge(reference, history: dict, stages: list, *, case_stage_s, scales: dict, depth: float,
          tolerances: dict, edge_band: float, exclude_radius=None, exclude_width=0.0,
          same_distance: float = SAME_DISTANCE) -> dict:
    """Judge a user's results against ``reference``.

    Parameters
    ----------
    reference : :class:`references.certified.Reference` or :class:`RunReference`
        (history_at, stage_at, covers, band_at, radii).
    history : {"s": (n,) [m], quantity: (n,)}: the user's history in SI (NaN: not given).
    stages : [{s, r, f, p, origin}]: the user's stages (f, p None when not given).
    case_stage_s : the case's stage distances (stages chosen from the history when
        ``stages`` is empty).
    same_distance : how closely (relative) a history row's distance must match a
        stage's for the row to be that stage's (:func:`select_stages`).
    scales, depth, tolerances, edge_band : as ``metrics.compare_results``.

    Returns
    -------
    dict like a pair of ``compare``: ``stages`` (each with its differences,
    ``stage_scales``, ``checks``, ``band`` and ``passed``), ``worst``,
    ``checks_used``, ``not_given``, ``not_judged``, ``history`` and ``passed``.
    """
    units = unit_scales(scales, depth)
    per_m = scales["s_hat_per_m"]
    chosen = select_stages(history, stages, case_stage_s, same_distance)
    given = [q for q in HISTORY_CHECKS if q in history and np.any(np.isfinite(history[q]))]
    has_f = any(st.get("f") is not None for st in stages)
    has_p = any(st.get("p") is not None for st in stages)
    out_stages, not_judged = [], []
    for sel in chosen:
        s = sel["s"]
        parts = []
        if sel["stage"] is not None:
            parts.append(stages[sel["stage"]]["origin"])
        if sel["row"] is not None and "origin" in history:
            parts.append(history["origin"][sel["row"]])
        where = "; ".join(parts)
        if not reference.covers(s):
            not_judged.append(f"ŝ = {s * per_m:.4g} ({where}): beyond the reference's "
                              "stages")
            continue
        ref = {k: float(v[0]) for k, v in reference.history_at(s).items()}
        st = dict(index=len(out_stages), s=s, s_hat_reference=s * per_m, s_hat_solver=s * per_m,
                  origin=where, reference=ref, results={}, checks={}, row=sel["row"])
        checks = []
        row = sel["row"]
        if row is None and given:
            not_judged.append(f"ŝ = {s * per_m:.4g} ({where}): no history row at this "
                              "distance; its force, contact radius, wear and depth are not "
                              "judged")
        for q in given if row is not None else []:
            v = float(history[q][row])
            if not np.isfinite(v):
                continue
            st["results"][q] = v
            st[q] = abs(v - ref[q]) / units[q]
            checks.append(metrics.CHECK_BY_COLUMN[HISTORY_CHECKS[q]])
        a_ref = ref["contact_radius"]
        a_user = st["results"].get("contact_radius", a_ref)
        st["force_reference"] = ref["force"] / scales["F0"]
        st["force_solver"] = st["results"].get("force", math.nan) / scales["F0"]
        st["contact_radius_reference"] = a_ref / scales["a0"]
        st["contact_radius_solver"] = st["results"].get("contact_radius", math.nan) / scales["a0"]
        user = stages[sel["stage"]] if sel["stage"] is not None else None
        peak = _peak(reference, s, a_ref, edge_band, exclude_radius, exclude_width)
        if user is not None and (user.get("f") is not None or user.get("p") is not None):
            r = np.asarray(user["r"], float)
            f_ref, p_ref = reference.stage_at(s, r)
            nan = np.full(len(r), np.nan)
            f_u = nan if user.get("f") is None else np.asarray(user["f"], float)
            p_u = nan if user.get("p") is None else np.asarray(user["p"], float)
            exclude = (np.abs(r - exclude_radius) < exclude_width
                       if exclude_radius is not None else None)
            st.update(metrics.stage_differences(r, f_ref, f_u, p_ref, p_u, a_ref, a_user,
                                                depth=depth, p0=scales["p0"],
                                                edge_band=edge_band, exclude=exclude))
            if user.get("f") is not None:
                checks.append(metrics.CHECK_BY_COLUMN["profile_contact_max"])
            if user.get("p") is not None:
                checks.append(metrics.CHECK_BY_COLUMN["pressure_interior_max"])
        st["stage_scales"] = dict(
            profile_contact_max=max(abs(ref["depth"]), abs(ref["wear_center"])) / depth,
            force=abs(ref["force"]) / scales["F0"], pressure_interior_max=peak / scales["p0"],
            contact_radius=a_ref / scales["a0"], wear_center=abs(ref["wear_center"]) / depth,
            wear_volume=abs(ref["wear_volume"]) / units["wear_volume"],
            depth=abs(ref["depth"]) / depth)
        checks = [c for c in metrics.CHECKS + metrics.WEAR_CHECKS if c in checks]
        if not checks:
            not_judged.append(f"ŝ = {s * per_m:.4g} ({where}): nothing to judge")
            continue
        st["checks"] = metrics.verdict(st, tolerances, checks)
        st["band"] = _band(reference, s, st, units)
        st["uncertified"] = {}
        for name in list(st["checks"]):
            tol, value = st["checks"][name]["tolerance"], st["checks"][name]["value"]
            band = st["band"].get(name, 0.0)
            # an uncertain reference decides nothing, unless the difference is beyond
            # the tolerance by more than the reference's error: that fails for certain
            if band > CERTIFIED_SHARE * tol and not value > tol + band:
                st["uncertified"][name] = dict(band=st["band"][name], tolerance=tol,
                                               value=st["checks"].pop(name)["value"])
        if st["uncertified"]:
            not_judged.append(f"ŝ = {s * per_m:.4g} ({where}): " + ", ".join(
                f"{metrics.CHECK_BY_COLUMN[n].label} (the reference's own error "
                f"{u['band']:.2g} is more than {CERTIFIED_SHARE:.2g} of the tolerance "
                f"{u['tolerance']:g}; the difference was {u['value']:.2g})"
                for n, u in st["uncertified"].items()) + " not judged")
        if not st["checks"]:
            continue
        st["passed"] = all(c["passed"] for c in st["checks"].values())
        out_stages.append(st)
    used = [c for c in metrics.CHECKS + metrics.WEAR_CHECKS
            if any(c.column in st["checks"] for st in out_stages)]
    not_given = [q for q in HISTORY_CHECKS if q not in given]
    if not has_f:
        not_given.append("f")
    if not has_p:
        not_given.append("p")
    stage_rows = {sel["row"] for sel in chosen if sel["row"] is not None}
    rows = judge_rows(reference, history, given, scales=scales, units=units,
                      tolerances=tolerances, skip=stage_rows)
    return dict(stages=out_stages, stages_compared=len(out_stages),
                worst=metrics.worst(out_stages, used), checks_used=[c.column for c in used],
                not_given=not_given, not_judged=not_judged,
                history=history_differences(reference, history, scales, depth, given),
                rows=rows,
                reach=(reach := reached(history, stages, case_stage_s, same_distance)),
                last_stage=(last := judged_near_last([st["s"] for st in out_stages], history,
                                                     stages, case_stage_s, reference.covers,
                                                     same_distance)),
                passed=(bool(out_stages) and all(st["passed"] for st in out_stages)
                        and reach["passed"] and last["passed"] and rows["passed"]))


def judge_rows(reference, history: dict, given, *, scales: dict, units: dict, tolerances: dict,
               skip=()) -> dict:
    """Judge every history row between the stages as a stage's history quantities are.

    Each row the reference covers (except those in ``skip``, judged as stages) is
    compared with the reference's history at its distance, each quantity relative to
    the reference's own value there (or the tolerance's floor) as at a stage, and a
    check is left out where the reference's error band there takes more than
    :data:`CERTIFIED_SHARE` of the tolerance (unless the difference is beyond the
    tolerance by more than the band). Rows are judged, not only stages, so a history
    that is right at the stages and wrong between them fails.

    Returns
    -------
    dict: ``judged`` (rows), ``failed`` (rows with a failed check), ``failed_rows``
    {quantity: [row indices from 0 in ``history``]} (the rows that failed it), ``worst``
    {quantity: {value, tolerance, s, index, origin}} (value relative to the tolerance's
    scale, at the row where it uses the largest share of the tolerance; ``index`` from
    0 in ``history``, ``origin`` where it was read, e.g. "history.csv row 169" as a
    spreadsheet counts rows) and ``passed``.
    """
    s = np.asarray(history["s"], float)
    origin = history.get("origin")
    ref = reference.history_at(s)
    checks = [metrics.CHECK_BY_COLUMN[HISTORY_CHECKS[q]] for q in given]
    judged, failed, worst, failed_rows = 0, 0, {}, {}
    for i in range(len(s)):
        if i in skip or not np.isfinite(s[i]) or not np.isfinite(ref["force"][i]):
            continue
        st = {"stage_scales": {}}
        cols = []
        for c, q in zip(checks, given):
            v = float(history[q][i])
            if not np.isfinite(v):
                continue
            st[c.column] = abs(v - float(ref[q][i])) / units[q]
            st["stage_scales"][c.column] = abs(float(ref[q][i])) / units[q]
            cols.append(c)
        if not cols:
            continue
        out = metrics.verdict(st, tolerances, cols)
        band = reference.band_at(s[i]) if hasattr(reference, "band_at") else None
        row_failed = False
        for name, c in out.items():
            b = (band or {}).get(name, 0.0) / units[name] / c["scale"]
            if b > CERTIFIED_SHARE * c["tolerance"] and not c["value"] > c["tolerance"] + b:
                continue
            row_failed |= not c["passed"]
            if not c["passed"]:
                failed_rows.setdefault(name, []).append(i)
            used = c["value"] / c["tolerance"]
            if name not in worst or used > worst[name]["used"]:
                worst[name] = dict(value=c["value"], tolerance=c["tolerance"], used=used,
                                   scale=c["scale"], s=float(s[i]), index=i,
                                   origin=(str(origin[i]) if origin is not None
                                           else f"history row {i + 1}"),
                                   passed=c["passed"])
        judged += 1
        failed += int(row_failed)
    return dict(judged=judged, failed=failed, failed_rows=failed_rows, worst=worst,
                passed=failed == 0)


def row_differences(reference, history: dict, given, *, scales: dict, depth: float,
                    tolerances: dict) -> dict:
    """Each given history quantity's signed difference from the reference at every
    row, relative to the scale its check judges it against (the reference's own value
    there, or the tolerance's floor where that is larger), as :func:`judge_rows` and
    the stages judge it.

    Returns {quantity: {"value": (n,) (user − reference) / scale, NaN where the
    reference does not cover the row or the row leaves the quantity out,
    "tolerance": the check's tolerance}}.
    """
    units = unit_scales(scales, depth)
    s = np.asarray(history["s"], float)
    ref = reference.history_at(s)
    out = {}
    for q in given:
        c = metrics.CHECK_BY_COLUMN[HISTORY_CHECKS[q]]
        r = np.asarray(ref[q], float)
        scale = np.maximum(np.abs(r) / units[q], tolerances[c.floor])
        value = (np.asarray(history[q], float) - r) / units[q] / scale
        out[q] = dict(value=value, tolerance=float(tolerances[c.tolerance]))
    return out


def reached(history: dict, stages: list, case_stage_s, same: float = SAME_DISTANCE) -> dict:
    """Whether the user's results reach the case's last stage.

    Results that stop early would otherwise pass on the stages they hold (a one-row
    history judged at ŝ = 0). The results end at the largest distance of the history
    or of the stages; a case stage beyond that end (relative ``same``, the precision
    of the written distances) is not reached. Returns {passed, end_s, not_reached
    (the case's stage distances [m] beyond the end)}.
    """
    hs = np.asarray(history.get("s", []), float)
    ends = [float(np.nanmax(hs))] if hs.size and np.isfinite(hs).any() else []
    ends += [float(st["s"]) for st in stages]
    end = max(ends) if ends else math.nan
    late = [float(s) for s in case_stage_s
            if not (np.isfinite(end) and end >= s - same * abs(s))]
    return dict(passed=not late, end_s=end, not_reached=late)


def judged_near_last(judged_s, history: dict, stages: list, case_stage_s, covers,
                     same: float = SAME_DISTANCE) -> dict:
    """Whether a judged stage lies near the case's last stage.

    Results that reach past the case's end (:func:`reached`) may still hold no row
    near it: distances written in mm or µm under a header that says metres put
    every row but the unworn one far beyond the reference, which judges nothing
    there, and the unworn row alone would pass. A judged stage, or a row of the
    results the reference covers (``covers(s)``; a history beside stages that end
    earlier), must lie at or past the midpoint between the case's last two stages
    (nearer to the last than to the one before; the last stage itself, to ``same``,
    when the case has one). Returns
    {passed, last_s, from_s (that midpoint), below_s and above_s (the results'
    distances nearest it on either side, NaN where none)}.
    """
    case_s = sorted(float(s) for s in case_stage_s)
    if not case_s:
        return dict(passed=True, last_s=math.nan, from_s=math.nan, below_s=math.nan,
                    above_s=math.nan)
    last = case_s[-1]
    start = 0.5 * (case_s[-2] + last) if len(case_s) > 1 else last
    start -= same * abs(start)
    given = np.concatenate([np.asarray(history.get("s", []), float),
                            np.asarray([st["s"] for st in stages], float)])
    given = given[np.isfinite(given)]
    below, above = given[given < start], given[given >= start]
    passed = any(s >= start for s in judged_s) or any(covers(float(s)) for s in above)
    return dict(passed=bool(passed), last_s=last, from_s=start,
                below_s=float(below.max()) if below.size else math.nan,
                above_s=float(above.min()) if above.size else math.nan)


def _peak(reference, s, a, edge_band, exclude_radius, exclude_width) -> float:
    """The reference's peak pressure at the stage, on its own radii (outside a singular band)."""
    r = reference.radii([s])
    _, p = reference.stage_at(s, r)
    return metrics.peak_pressure(r, p, exclude_radius, exclude_width)


def _band(reference, s, st, units) -> dict:
    """The reference's error band at the stage, relative to each check's scale (None
    for a fresh run, which has none)."""
    band = reference.band_at(s)
    if band is None:
        return {}
    out = {}
    for name, c in st["checks"].items():
        if name in band:
            out[name] = band[name] / units[name] / c["scale"]
    return out


def history_differences(reference, history: dict, scales: dict, depth: float, given) -> dict:
    """Largest difference of each given quantity over every history row the reference
    covers (its history interpolated at the user's rows), in the unworn units."""
    s = np.asarray(history["s"], float)
    ref = reference.history_at(s)
    units = unit_scales(scales, depth)
    out = {}
    inside = np.isfinite(ref["force"])
    for q in given:
        d = np.abs(np.asarray(history[q], float) - ref[q])[inside]
        d = d[np.isfinite(d)]
        out[q] = float(np.max(d)) / units[q] if d.size else math.nan
    out["rows"] = int(np.count_nonzero(inside))
    out["rows_beyond"] = int(np.count_nonzero(~inside))
    return out


def distance_factor(reference, history: dict, scales: dict, depth: float) -> dict | None:
    """The factor λ on the user's distances that best fits the reference: the
    reference at λ·s against the user's force, central wear and worn volume (each
    relative to its own value, floored), by bounded minimisation over λ in
    [0.5, 2]. A λ away from 1 points at the wear coefficient K = kμ/σ0 (or at the
    distance the model slides); None when no quantity that changes with sliding
    is given. Also the misfit at the unit factors :data:`UNIT_FACTORS` (distances
    written in mm or µm under a header in metres), where the reference covers at
    least half of the rows (``unit_misfits``: [{factor, misfit}], misfit None where
    it covers fewer), and ``bounds``."""
    import scipy.optimize
    units = unit_scales(scales, depth)
    s = np.asarray(history["s"], float)
    cols = [q for q in ("force", "wear_center", "wear_volume")
            if q in history and np.any(np.isfinite(history[q]))]
    moving = s > 0
    if not cols or np.count_nonzero(moving) < 2:
        return None

    def misfit(lam, coverage=0.0):
        ref = reference.history_at(lam * s[moving])
        if np.count_nonzero(np.isfinite(ref["force"])) < coverage * np.count_nonzero(moving):
            return math.inf
        total, n = 0.0, 0
        for q in cols:
            u = np.asarray(history[q], float)[moving]
            scale = np.maximum(np.abs(ref[q]), 0.01 * units[q])
            d = ((u - ref[q]) / scale)[np.isfinite(u) & np.isfinite(ref[q])]
            total += float(np.sum(d**2))
            n += d.size
        return math.sqrt(total / n) if n else math.inf

    at_one = misfit(1.0)
    best = scipy.optimize.minimize_scalar(misfit, bounds=FACTOR_BOUNDS, method="bounded",
                                          options=dict(xatol=1e-5))
    if not np.isfinite(best.fun) or not np.isfinite(at_one):
        return None
    return dict(factor=float(best.x), misfit=float(best.fun), misfit_at_one=at_one,
                quantities=cols, bounds=list(FACTOR_BOUNDS),
                unit_misfits=[dict(factor=f, misfit=_finite(misfit(f, coverage=0.5)))
                              for f in UNIT_FACTORS])


def _finite(value: float) -> float | None:
    """None for a misfit that could not be computed (metrics.json holds no Infinity)."""
    return value if math.isfinite(value) else None


#: the range of factors on the user's distances searched by :func:`distance_factor`
FACTOR_BOUNDS = (0.5, 2.0)
#: factors a unit slip puts on the distances: mm or µm written under a header in
#: metres (the reference matches at 1e-3 or 1e-6 of the values), metres under "mm"
UNIT_FACTORS = (1e-3, 1e-6, 1e3)


def stage_unit_slips(reference, stages: list, unworn, depth: float, p0: float) -> list[str]:
    """Unit slips that explain the user's stages, in words (empty when none does).

    * the pressure ~10⁶ times too small (MPa written under a header in Pa) or too
      large (Pa under "MPa"): the median ratio of the user's pressure to the
      reference's, where the reference's exceeds a tenth of p0, within a factor 2
      of 10⁻⁶ or 10⁶;
    * the wear depth written as the profile ``f``: the user's f matches the
      reference's wear f − f0 (``unworn(r)`` is f0) at least four times better
      than its f, at every stage with a profile, where it does not match f
      (max difference beyond 1 % of ``depth``).
    """
    ratios, as_wear, as_f = [], [], []
    for st in stages:
        if st.get("p") is None and st.get("f") is None:
            continue
        if not reference.covers(st["s"]):
            continue
        r = np.asarray(st["r"], float)
        f_ref, p_ref = reference.stage_at(st["s"], r)
        if st.get("p") is not None:
            p = np.asarray(st["p"], float)
            on = (p_ref > 0.1 * p0) & np.isfinite(p) & (p != 0)
            if np.any(on):
                ratios.append(float(np.median(p[on] / p_ref[on])))
        if st.get("f") is not None:
            f = np.asarray(st["f"], float)
            as_f.append(float(np.nanmax(np.abs(f - f_ref))))
            as_wear.append(float(np.nanmax(np.abs(f - (f_ref - unworn(r))))))
    out = []
    if ratios:
        ratio = float(np.median(ratios))
        for factor, what in ((1e-6, "MPa written under a header in Pa ('p' is in Pa: "
                                     "write 'p [MPa]')"),
                             (1e6, "Pa written under a header in MPa")):
            if 0.5 * factor < ratio < 2.0 * factor:
                out.append(f"your pressure is {ratio:.3g} times the reference's: {what}")
    if as_f and all(w < 0.25 * d and d > 0.01 * depth for w, d in zip(as_wear, as_f)):
        out.append("your profile 'f' matches the reference's wear depth f − f0 (within "
                   f"{max(as_wear) / depth:.2g} of the depth d, against {max(as_f) / depth:.2g} "
                   "as a profile): a wear depth given as the profile; name that column "
                   "'wear' (or --map wear=COLUMN)")
    return out
