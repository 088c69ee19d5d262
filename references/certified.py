"""A certified reference solution: the shipped file, read back and evaluated anywhere.

One ``NAME.npz`` per benchmark (``references/data/``), written by
:func:`write` from what :mod:`references.derive` computed:

- the history (s, force, depth, contact radius, central wear, worn volume) at
  a few hundred sliding distances;
- the worn profile and the pressure at a few dozen stored stages, each stage
  on radii r = ρ·a(s) that scale with its own contact radius a(s): the wear
  w = f − f0 on ρ ≤ ``rho_f_max`` (zero beyond), the pressure on
  ρ ≤ ``rho_p_max`` (zero beyond);
- the error band of every stored stage and check (unworn units), the orders
  observed, the other solvers' spread, and the command and versions that made it
  (``meta``).

:class:`Reference` evaluates it at any sliding distance up to its last stored
stage: the history by a monotone cubic (PCHIP) in the time variable τ, the
stages by cubic Lagrange interpolation in τ at fixed ρ between the four
nearest stored stages (the band includes what this interpolation costs,
measured on held-out stages), linearly in r. τ is ŝ, or log(1 + ŝ/ŝ_ref) for
runs over decades of sliding.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wearcheck.cases import Case, CaseError, RunResult, profiles, reference
from wearcheck.cases.case import to_dict
from wearcheck.cases.schema import SECTIONS, section_fields
from wearcheck.comparisons.analysis import metrics
from wearcheck import cases

#: the history columns a reference holds (SI), as history.csv names them
HISTORY = ("s", "force", "depth", "contact_radius", "wear_center", "wear_volume")
#: the checks a band is given for: the verdict's, and verify's wear checks
BAND_CHECKS = ("profile_contact_max", "force", "pressure_interior_max", "contact_radius",
               "wear_center", "wear_volume", "depth")
#: the band's parts, summed into "total"
BAND_PARTS = ("space", "time", "resample")
#: relative rounding of a value stored as float32
FLOAT32 = 2.0**-24
#: the folder of the shipped files
DATA_DIR = Path(__file__).resolve().parent / "data"
#: the format of the file (raised when its layout changes)
FORMAT = 1
#: keys of the case that define the physics of a benchmark: a case that differs
#: in any of them is another problem, with no certified reference. Resolution,
#: time scheme, stages and [compare] tolerances are free.
#: How long the run lasts is free too (a shorter run is checked as far as it goes).
PHYSICS = {"indenter": None, "counterface": None, "loading": None, "wear": None,
           "fretting": ("amplitude", "force_amplitude")}


def unworn_profile(case: Case, r) -> np.ndarray:
    """The unworn profile f0(r) as an axisymmetric result gives it: the profile of a
    body of revolution, the average over the circle of radius r for the
    ellipsoid, (x²/2R1 + y²/2R2) averaged = r²(1/R1 + 1/R2)/4."""
    ind = case.indenter
    r = np.asarray(r, float)
    if ind.profile == "ellipsoid":
        return r**2 * (1.0 / ind.radius + 1.0 / ind.radius_y) / 4.0
    return profiles.height(ind, r, case.table)


def physics(case: Case) -> dict:
    """The case keys that make the problem (:data:`PHYSICS`), as a plain dict."""
    raw = to_dict(case)
    out = {}
    for section, keys in PHYSICS.items():
        sec = raw.get(section)
        if not isinstance(sec, dict):
            continue
        out[section] = {k: v for k, v in sorted(sec.items())
                        if (keys is None or k in keys) and v is not None}
    return out


def _default(section: str, key: str):
    """A case key's default (None when it has none or is unknown): a key missing from one
    side of a comparison counts as its default, so that a key added to the schema later
    (with the default that keeps the old behaviour) does not orphan the shipped files."""
    if section not in SECTIONS:
        return None
    for name, f in section_fields(section):
        if name == key and not f.metadata.get("required"):
            return f.default
    return None


def physics_difference(a: dict, b: dict) -> str | None:
    """The first key in which two :func:`physics` dicts differ, as 'section.key: x != y'."""
    for section in sorted(set(a) | set(b)):
        if (section in a) != (section in b):
            which = "here" if section in a else "in the reference"
            return f"[{section}] only {which}"
        sa, sb = a.get(section, {}), b.get(section, {})
        for key in sorted(set(sa) | set(sb)):
            va = sa.get(key, _default(section, key))
            vb = sb.get(key, _default(section, key))
            if isinstance(va, float) and isinstance(vb, (int, float)) and vb is not None:
                if math.isclose(va, float(vb), rel_tol=1e-12, abs_tol=0.0):
                    continue
            if va != vb:
                return f"{section}.{key}: {va!r} here, {vb!r} in the reference"
    return None


def tau(s_hat, s_hat_ref: float | None) -> np.ndarray:
    """The time variable of interpolation: ŝ, or log(1 + ŝ/ŝ_ref)."""
    s_hat = np.asarray(s_hat, float)
    return s_hat if s_hat_ref is None else np.log1p(s_hat / s_hat_ref)


def lagrange_weights(x, nodes) -> np.ndarray:
    """Weights of the interpolating polynomial through ``nodes`` at x (len(nodes),)."""
    nodes = np.asarray(nodes, float)
    w = np.ones(len(nodes))
    for i in range(len(nodes)):
        for j in range(len(nodes)):
            if i != j:
                w[i] *= (x - nodes[j]) / (nodes[i] - nodes[j])
    return w


def stencil(x, nodes, width: int = 4) -> np.ndarray:
    """Indices of the ``width`` nodes nearest to x around it (fewer if there are fewer)."""
    n = len(nodes)
    width = min(width, n)
    i = int(np.searchsorted(nodes, x))            # nodes[i-1] < x <= nodes[i]
    start = min(max(i - width // 2, 0), n - width)
    return np.arange(start, start + width)


@dataclass
class Reference:
    """A certified reference, read by :func:`load`.

    Attributes
    ----------
    name : the benchmark (a shipped case's name); case : that case, loaded.
    history : {column: (H,)} SI values at H sliding distances (``HISTORY``).
    stage_s : (J,) sliding distances [m] of the stored stages; stage_a : their
        contact radii [m].
    rho_f, wear : (Mf,), (J, Mf) the wear depth w = f − f0 at r = ρ·a [m].
    rho_p, pressure : (Mp,), (J, Mp) the pressure at r = ρ·a [Pa].
    band : {check: {part: (J,)}} the error band per stored stage, in the
        unworn units of the check (d, F0, p0, a0, d, π a0² d, d) with part in
        :data:`BAND_PARTS` and "total"; ``interval`` (J - 1,) per check: what
        interpolating between stored stages j and j+1 costs (held-out stages).
    meta : method, levels, observed orders, the other solvers' spread, and the
        provenance (command, versions, date) of the file.
    """

    name: str
    case: Case
    s_hat_ref: float | None
    history: dict
    stage_s: np.ndarray
    stage_a: np.ndarray
    rho_f: np.ndarray
    wear: np.ndarray
    rho_p: np.ndarray
    pressure: np.ndarray
    band: dict
    meta: dict = field(default_factory=dict)
    _pchip: dict | None = field(default=None, repr=False)

    # -- scales and the time variable --------------------------------------
    @property
    def scales(self) -> dict:
        return reference.scales(self.case)

    def tau(self, s) -> np.ndarray:
        return tau(np.asarray(s, float) * self.scales["s_hat_per_m"], self.s_hat_ref)

    @property
    def last_s(self) -> float:
        """The largest sliding distance whose stages it can give [m]."""
        return float(self.stage_s[-1])

    def covers(self, s) -> np.ndarray:
        """Whether each distance lies within the stored stages (and the history)."""
        s = np.asarray(s, float)
        end = min(self.last_s, float(self.history["s"][-1]))
        return (s >= 0.0) & (s <= end * (1 + 1e-9) + 1e-300)

    # -- evaluation ------------------------------------------------------------
    def _interpolants(self) -> dict:
        """The history's PCHIP in τ, one per column (built once)."""
        if self._pchip is None:
            import scipy.interpolate
            t_hist = self.tau(self.history["s"])
            self._pchip = {name: scipy.interpolate.PchipInterpolator(t_hist, self.history[name])
                           for name in HISTORY[1:]}
        return self._pchip

    def history_at(self, s) -> dict:
        """Every history column at the distances s (NaN outside the history)."""
        s = np.atleast_1d(np.asarray(s, float))
        hs = self.history["s"]
        out = {"s": s.copy()}
        inside = (s >= hs[0]) & (s <= hs[-1] * (1 + 1e-12))
        if len(hs) == 1:
            for name in HISTORY[1:]:
                out[name] = np.where(s == hs[0], self.history[name][0], np.nan)
            return out
        t = self.tau(np.clip(s, hs[0], hs[-1]))
        for name, spline in self._interpolants().items():
            out[name] = np.where(inside, spline(t), np.nan)
        return out

    def stage_rho(self, s: float) -> tuple[float, np.ndarray, np.ndarray]:
        """Contact radius, wear (on ``rho_f``) and pressure (on ``rho_p``) at distance s."""
        if not self.covers(s):
            raise ValueError(f"s = {s} m is outside the reference's stages")
        t, nodes = float(self.tau(s)), self.tau(self.stage_s)
        exact = np.flatnonzero(np.abs(nodes - t) <= 1e-12 * max(1.0, abs(t)))
        if exact.size:
            j = int(exact[0])
            return float(self.stage_a[j]), self.wear[j].astype(float), \
                self.pressure[j].astype(float)
        idx = stencil(t, nodes)
        w = lagrange_weights(t, nodes[idx])
        a = float(self.history_at(s)["contact_radius"][0])
        wear = w @ self.wear[idx].astype(float)
        p = w @ self.pressure[idx].astype(float)
        return a, wear, np.maximum(p, 0.0)

    def stage_at(self, s: float, r) -> tuple[np.ndarray, np.ndarray]:
        """Worn profile f and pressure p at distance s on the radii r (any), linearly in r."""
        a, wear, p = self.stage_rho(s)
        r = np.asarray(r, float)
        rho = r / a
        w = np.interp(rho, self.rho_f, wear, right=0.0)
        pp = np.interp(rho, self.rho_p, p, right=0.0)
        return unworn_profile(self.case, r) + w, pp

    def radii(self, s_list) -> np.ndarray:
        """One common set of radii for stages at s_list: the union of each stage's
        ρ-grids scaled by its contact radius (linear interpolation on it loses nothing)."""
        rs = []
        for s in s_list:
            a = self.stage_rho(s)[0]
            rs += [self.rho_f * a, self.rho_p * a]
        return np.unique(np.concatenate(rs)) if rs else self.rho_f * self.stage_a[0]

    def band_at(self, s) -> dict:
        """{check: total band} at distance s [SI]: the stored stages' band interpolated
        linearly in τ, plus the interval's interpolation cost between them, plus the
        rounding of the values to the file's float32 (2⁻²⁴ of their size)."""
        t, nodes = float(self.tau(s)), self.tau(self.stage_s)
        h = self.history_at(s)
        j = int(np.argmin(np.abs(nodes - t)))
        stored = dict(profile_contact_max=float(np.max(np.abs(self.wear[j]))),
                      pressure_interior_max=float(np.max(self.pressure[j])),
                      **{q: abs(float(h[q][0])) for q in HISTORY[1:]})
        out = {}
        for check, parts in self.band.items():
            total = np.asarray(parts["total"], float)
            value = float(np.interp(t, nodes, total))
            on_node = np.any(np.abs(nodes - t) <= 1e-12 * max(1.0, abs(t)))
            if not on_node and len(nodes) > 1:
                i = int(np.clip(np.searchsorted(nodes, t) - 1, 0, len(nodes) - 2))
                value += float(parts["interval"][i])
            out[check] = value + FLOAT32 * stored[check]
        return out

    def run_result(self, stage_s=None) -> RunResult:
        """The reference as a solver's result, with stages at ``stage_s`` [m]
        (default: the case's stages that it covers) on one common set of radii."""
        sc = self.scales
        if stage_s is None:
            stage_s = [sh / sc["s_hat_per_m"] for sh in self._case_stage_s_hat()]
            stage_s = [s for s in stage_s if self.covers(s)]
        stage_s = np.asarray(stage_s, float)
        r = self.radii(stage_s)
        f = np.zeros((len(stage_s), len(r)))
        p = np.zeros_like(f)
        for k, s in enumerate(stage_s):
            f[k], p[k] = self.stage_at(s, r)
        h = {k: np.asarray(v, float) for k, v in self.history.items()}
        h["s_hat"] = h["s"] * sc["s_hat_per_m"]
        cpm = self.case.cycles_per_metre
        if "cycles" not in h:
            h["cycles"] = h["s"] * (cpm if cpm is not None else math.nan)
        info = dict(solver="reference", reference=self.name,
                    method=self.meta.get("method"), band_note=(
                        "the estimated error of these values (band) per stored stage and "
                        "check, in the unworn units: meta.json reference.band"))
        return RunResult(history=h, stage_s=stage_s, r=r, f=f, p=p, solve_seconds=0.0,
                         info=info)

    def _case_stage_s_hat(self) -> list[float]:
        if self.case.fretting is not None:
            # fretting stages are cycles; the history maps them to distances
            cyc = self.case.fretting.stage_cycles or []
            return list(self.cycles_to_s(np.asarray(cyc, float)) * self.scales["s_hat_per_m"])
        return list(self.case.stages.s_hat)

    def cycles_to_s(self, cycles) -> np.ndarray:
        """Distances [m] of the given cycle counts: the case's stroke, or (fretting) the
        history's own cycles column."""
        cycles = np.asarray(cycles, float)
        if "cycles" in self.history and np.all(np.isfinite(self.history["cycles"])):
            return np.interp(cycles, self.history["cycles"], self.history["s"],
                             left=np.nan, right=np.nan)
        cpm = self.case.cycles_per_metre
        if cpm is None:
            raise CaseError(f"the reference '{self.name}' has no cycles: its case has no "
                            "sliding.stroke")
        return cycles / cpm

    def relative_bands(self) -> list[dict]:
        """Per stored stage: ŝ (and cycles where defined) and each check's band relative
        to the stage's own scale, floored, as the verdict judges a difference
        (``[compare]`` of the reference's case)."""
        sc = self.scales
        case = self.case
        tol = dataclasses.asdict(case.compare)
        d = case.loading.depth if case.loading.control == "depth" else sc["d0"]
        units = dict(profile_contact_max=d, force=sc["F0"], pressure_interior_max=sc["p0"],
                     contact_radius=sc["a0"], wear_center=d, depth=d,
                     wear_volume=math.pi * sc["a0"] ** 2 * d)
        exclude = None
        if case.indenter.profile == "truncated_paraboloid":
            exclude = (case.indenter.flat_radius, case.compare.edge_band * sc["a0"])
        rows = []
        for j, s in enumerate(self.stage_s):
            h = {k: float(v[0]) for k, v in self.history_at(s).items()}
            r = self.rho_p * self.stage_a[j]
            peak = metrics.peak_pressure(r, self.pressure[j], *(exclude or (None, 0.0)))
            own = dict(profile_contact_max=max(h["depth"], h["wear_center"]), force=h["force"],
                       pressure_interior_max=peak, contact_radius=h["contact_radius"],
                       wear_center=h["wear_center"], wear_volume=h["wear_volume"],
                       depth=h["depth"])
            row = dict(s=float(s), s_hat=float(s * sc["s_hat_per_m"]))
            if "cycles" in self.history or case.cycles_per_metre is not None:
                row["cycles"] = float(self.s_to_cycles(s))
            for c, parts in self.band.items():
                check = metrics.CHECK_BY_COLUMN[c]
                scale, _ = metrics.stage_scale(own[c] / units[c], tol[check.floor])
                row[c] = float(parts["total"][j]) / units[c] / scale
            rows.append(row)
        return rows

    def s_to_cycles(self, s) -> np.ndarray:
        """Cycles at distances s: the fretting history's own, else s/(2·stroke)."""
        s = np.asarray(s, float)
        if "cycles" in self.history:
            return np.interp(s, self.history["s"], self.history["cycles"])
        cpm = self.case.cycles_per_metre
        return s * (cpm if cpm is not None else math.nan)

    def band_table(self) -> list[dict]:
        """One row per stored stage: ŝ and each check's total band (unworn units)."""
        per_m = self.scales["s_hat_per_m"]
        rows = []
        for j, s in enumerate(self.stage_s):
            row = dict(s=float(s), s_hat=float(s * per_m))
            row.update({c: float(self.band[c]["total"][j]) for c in self.band})
            rows.append(row)
        return rows


# -- the file ----------------------------------------------------------------

def write(path: str | Path, data: dict) -> Path:
    """Write a reference file (compressed npz; the values float32 beside float64 distances).

    ``data``: history (dict of (H,)), stage_s, stage_a, rho_f, wear, rho_p,
    pressure, band (dict), s_hat_ref, meta (JSON-serialisable), name.
    """
    path = Path(path)
    arrays = {f"history_{k}": np.asarray(data["history"][k],
                                         np.float64 if k in ("s", "cycles") else np.float32)
              for k in data["history"]}
    arrays.update(stage_s=np.asarray(data["stage_s"], np.float64),
                  stage_a=np.asarray(data["stage_a"], np.float64),
                  rho_f=np.asarray(data["rho_f"], np.float64),
                  wear=np.asarray(data["wear"], np.float32),
                  rho_p=np.asarray(data["rho_p"], np.float64),
                  pressure=np.asarray(data["pressure"], np.float32))
    head = dict(format=FORMAT, name=data["name"], s_hat_ref=data["s_hat_ref"],
                physics=data["physics"], band=_jsonable(data["band"]),
                meta=_jsonable(data["meta"]))
    arrays["header"] = np.array(json.dumps(head, allow_nan=True))
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    tmp.replace(path)
    return path


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def names() -> list[str]:
    """The benchmarks with a shipped reference."""
    return sorted(p.stem for p in DATA_DIR.glob("*.npz"))


def read(path: str | Path, case: Case | None = None) -> Reference:
    """A reference file; ``case`` the case it is for (default: the shipped case of its name).

    Raises
    ------
    CaseError
        the file is damaged, of another format, or made for other physics than
        ``case`` (naming the first key that differs).
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        head = json.loads(str(arrays.pop("header")))
    except Exception as exc:  # zipfile, numpy, json: a damaged file
        raise CaseError(f"reference file '{path}' is damaged or not a reference "
                        f"({type(exc).__name__}: {exc})") from None
    if head.get("format") != FORMAT:
        raise CaseError(f"reference file '{path}' has format {head.get('format')}, this "
                        f"wearcheck reads {FORMAT}: regenerate it "
                        "(python benchmarks/make_references.py)")
    name = head["name"]
    if case is None:
        case = cases.load(cases.shipped(name))
    diff = physics_difference(physics(case), head["physics"])
    if diff is not None:
        raise CaseError(f"the certified reference '{name}' was made for another problem "
                        f"({diff}); verify against a fresh run instead "
                        "(--reference-solver mdr)")
    hist = {k.removeprefix("history_"): arrays[k].astype(float) for k in arrays
            if k.startswith("history_")}
    band = {c: {p: np.asarray(v, float) for p, v in parts.items()}
            for c, parts in head["band"].items()}
    return Reference(name=name, case=case, s_hat_ref=head["s_hat_ref"], history=hist,
                     stage_s=arrays["stage_s"], stage_a=arrays["stage_a"],
                     rho_f=arrays["rho_f"], wear=arrays["wear"], rho_p=arrays["rho_p"],
                     pressure=arrays["pressure"], band=band, meta=head["meta"])


def load(name: str) -> Reference:
    """The shipped reference of benchmark ``name`` (a shipped case's name)."""
    path = DATA_DIR / f"{cases.shipped(name).stem}.npz" if name not in names() \
        else DATA_DIR / f"{name}.npz"
    if not path.is_file():
        raise CaseError(f"no certified reference for '{name}'; shipped: "
                        + ", ".join(names()))
    return read(path)


def for_case(case: Case) -> Reference | None:
    """The shipped reference whose physics is this case's, or None."""
    mine = physics(case)
    for name in names():
        path = DATA_DIR / f"{name}.npz"
        try:
            with np.load(path, allow_pickle=False) as z:
                head = json.loads(str(z["header"]))
        except Exception:  # noqa: BLE001 - a damaged file is reported when named
            continue
        if physics_difference(mine, head["physics"]) is None:
            return read(path, case)
    return None
