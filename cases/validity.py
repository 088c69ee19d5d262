"""Where a run stops describing the case's body, and where half-space theory stops holding.

Every solver calls :func:`check_planned` before its run and a
:class:`BodyWatch` at every recorded step (docs/limits.md):

* **the body ends.** A sphere's surface ends at its equator, r = R
  (``indenter.radius``); a tabulated profile at its last radius. The solvers
  would go on past it with a geometry the case does not have (the sphere's
  profile continued flat, the table's continued with its last slope), so a
  contact or scar that reaches it stops the run with a :class:`CaseError`
  naming the key to change. The FEM's body is always a sphere of radius R.
* **half-space theory stretched.** Every solver takes the bodies as elastic
  half-spaces (the FEM's sphere excepted, but its compliance is compared
  with the half-space's): right while the surface is nearly flat over the
  contact. Past a slope of :data:`HALF_SPACE_SLOPE` of the unworn surface at
  the edge of the contact or scar (a/R = 0.1 on a paraboloid, 0.0995 on a
  sphere) the run warns once (:class:`RunWarning`) and goes on.
* **elasticity stretched.** Every solver takes the bodies as elastic. When
  the unworn contact's peak pressure passes the onset of yield estimated from
  ``wear.hardness`` (:func:`yield_remark`) every run keeps the remark; the
  :class:`RunWarning` is said once per process, as the case's own notes.
"""

from __future__ import annotations

import math
import os
import sys
import warnings
from dataclasses import dataclass

import numpy as np

from . import profiles, reference
from .errors import CaseError, RunWarning, warn_once

#: largest slope of the unworn surface at the edge of the contact or scar
#: within which half-space theory is taken to hold: a/R = 0.1 on a paraboloid,
#: the limit the README states for the sphere (the FEM's finite sphere is
#: stiffer than the half-space by ΔF/F ≈ 0.6 a/R there, 6 %)
HALF_SPACE_SLOPE = 0.1
#: a contact or scar counts as past the body's end beyond this relative margin
#: (a table that ends exactly at the unworn contact radius is still inside)
END_MARGIN = 1e-9
#: the onset of yield under a Hertz contact, p0 = 1.60 Y (von Mises, ν = 0.3;
#: Johnson 1985, §6.2), with the yield stress Y from the indentation hardness H
#: by Tabor's H ≈ 2.8-3 Y; the factor 3 (the lower Y) warns first
YIELD_ONSET_P0_OVER_Y = 1.6
HARDNESS_OVER_YIELD = 3.0


@dataclass(frozen=True)
class BodyEnd:
    """Where the body of a case ends, and how to say it."""

    radius: float    # [m]
    kind: str        # "sphere" or "table"
    where: str       # "the sphere's equator (indenter.radius = 0.005 m)"


def body_end(case, fem_sphere: bool = False) -> BodyEnd | None:
    """The radius where the case's body ends (None: it does not, e.g. a paraboloid).

    ``fem_sphere``: the solver's body is a sphere of radius ``indenter.radius``
    whatever the profile (the FEM), the profile being its initial gap.
    """
    ind = case.indenter
    ends = []
    if ind.radius is not None and (ind.profile == "sphere" or fem_sphere):
        ends.append(BodyEnd(float(ind.radius), "sphere",
                            f"the sphere's equator (indenter.radius = {ind.radius:.4g} m)"))
    if ind.profile == "table" and case.table is not None:
        last = float(case.table[0][-1])
        ends.append(BodyEnd(last, "table", f"the last radius of the profile table "
                                           f"({last:.4g} m, indenter.file)"))
    return min(ends, key=lambda e: e.radius) if ends else None


def run_length_key(case) -> tuple[str, object]:
    """The key that sets how long the run goes on, and its value."""
    if getattr(case, "fretting", None) is not None:
        return "fretting.cycles", case.fretting.cycles
    sl = case.sliding
    if sl.until == "cycles":
        return "sliding.cycles", sl.cycles
    if sl.until == "distance":
        return "sliding.distance", sl.distance
    return "sliding.force_fraction", sl.force_fraction


def _shorter(case, s: float, cycle: float | None) -> str:
    """How to end the run by sliding s [m] (cycle: the fretting cycle there)."""
    key, _ = run_length_key(case)
    if key == "fretting.cycles":
        return f"fretting.cycles <= {cycle:.4g}"
    if key == "sliding.cycles":
        return f"sliding.cycles <= {s * case.cycles_per_metre:.4g}"
    return f"sliding.distance <= {s:.4g} m" + (
        " with sliding.until = \"distance\"" if key != "sliding.distance" else "")


def _lighter(case) -> str:
    control = case.loading.control
    if case.indenter.profile == "table":   # (a smaller wear.k only delays the same contact)
        return f"lower loading.{control}"
    return f"lower loading.{control} or wear.k"


def yield_remark(case) -> str | None:
    """The remark when the unworn contact's peak pressure passes a yield estimate, else None.

    The peak pressure is p0 = 3F0/(2π a0²) (Hertz's maximum; 1.5 times the mean
    pressure for other profiles), the largest of the run (wear spreads the
    contact); the estimate the onset of yield of the worn body, 1.6 Y with
    Y = H/3 from ``wear.hardness`` = H.
    """
    p0, H = reference.scales(case)["p0"], case.wear.hardness
    onset = YIELD_ONSET_P0_OVER_Y * H / HARDNESS_OVER_YIELD
    if not p0 > onset:
        return None
    return (f"the peak pressure of the unworn contact, p0 = {p0:.4g} Pa, passes the onset of "
            f"yield, p0 ≈ 1.6 Y = {onset:.4g} Pa with Y ≈ H/3 (Tabor, H ≈ 2.8-3 Y) from "
            f"wear.hardness = {H:.4g} Pa: the worn body yields, which the elastic model leaves "
            "out; results are approximate")


def check_planned(case, fem_sphere: bool = False) -> None:
    """Refuse, before the run, a sphere that the run would wear past its equator.

    The scar's radius at the run's end is predicted as the FEM sizes its mesh
    (:func:`reference.predicted_scar_radius`: √2·a0 under depth control, the
    long-run asymptote under force control, which the scar runs up to 2 %
    beyond); a table's end is checked step by step (:class:`BodyWatch`), as
    nothing predicts a measured profile's worn contact.
    """
    end = body_end(case, fem_sphere)
    if end is None or end.kind != "sphere" or getattr(case, "fretting", None) is not None:
        return
    s_end = case.end_distance or 0.0
    predicted = reference.predicted_scar_radius(case, s_end)
    if predicted < end.radius:
        return
    if case.loading.control == "depth":
        raise CaseError(
            f"key 'loading.depth' = {case.loading.depth!r}: the run would wear the sphere past "
            f"its equator: the completely worn contact reaches √2·a0 = {predicted:.4g} m, "
            f"beyond {end.where}; lower loading.depth (half-space theory wants a0/R <= 0.1)")
    from .case import implausible_values
    slips = implausible_values(case)
    if slips:   # the key the user most likely got wrong names it, not the run's length
        raise CaseError(
            f"{slips[0][1]}. With it the run would wear the sphere past its equator (the scar "
            f"radius predicted at its end, {predicted:.4g} m, is beyond {end.where})")
    key, value = run_length_key(case)
    a0 = reference.scales(case)["a0"]
    n = case.wear.pressure_exponent
    p = 2.0 * (n + 1.0)
    # the paraboloid law's b^p grows linearly in s: the sliding at which it reaches R
    # (the law predicted_scar_radius sizes with; it lies above the exact cap, so the
    # cycles proposed err on the safe side)
    unit = reference.worn_sphere_asymptote(end.radius, case.loading.force, 1.0, case.wear_rate,
                                           exponent=n, hardness=case.wear.hardness,
                                           profile="paraboloid")
    s_reach = (end.radius**p - a0**p) / float(unit["scar_radius"]) ** p
    # the scar runs up to 2 % beyond the asymptote: a run kept 2 % inside it stays on the sphere
    s_safe = max((end.radius / 1.02) ** p - a0**p, 0.0) / float(unit["scar_radius"]) ** p
    raise CaseError(
        f"key '{key}' = {value!r}: the run would wear the sphere past its equator: the scar "
        f"radius predicted at its end, {predicted:.4g} m (long-run asymptote), is beyond "
        f"{end.where}, which the scar reaches after about s = {s_reach:.4g} m; end the run "
        f"earlier ({_shorter(case, s_safe, None)}) or {_lighter(case)}")


class BodyWatch:
    """Called at every recorded step: stop at the body's end, warn once past half-space theory.

    ``watch(s, contact_radius, scar_radius)`` raises a :class:`CaseError` when
    the contact or the scar passes :func:`body_end` by more than ``spacing``
    (the solver's node or pixel spacing: its contact radius is read between
    nodes, the BEM's from the area in contact), and issues one
    :class:`RunWarning` per run when the unworn surface's slope at the outer of
    the two passes :data:`HALF_SPACE_SLOPE`, and at the first step, when the
    peak pressure passes the yield estimate (:func:`yield_remark`), one per
    process; ``watch.remarks`` holds their texts for the run's ``info["warnings"]``
    (:func:`remark`).
    """

    def __init__(self, case, fem_sphere: bool = False, spacing: float = 0.0):
        self.case = case
        self.end = body_end(case, fem_sphere)
        self.spacing = float(spacing)
        self.inside = None          # (s, cycle) of the last recorded step inside the body
        self.remarks: list[str] = []
        self.stretched = False      # the half-space remark issued
        self.started = False        # the yield estimate checked

    def _at(self, s: float, cycle: float | None) -> str:
        # (the scales only here: a table case's cost a quadrature)
        text = f"ŝ = {s * reference.scales(self.case)['s_hat_per_m']:.4g} (s = {s:.4g} m"
        cpm = getattr(self.case, "cycles_per_metre", None)
        if cycle is None and cpm is not None and self.case.fretting is None:
            cycle = s * cpm
        return text + (f", cycle {cycle:.4g})" if cycle is not None else ")")

    def __call__(self, s: float, contact_radius: float, scar_radius: float,
                 cycle: float | None = None) -> None:
        radii = {name: r for name, r in (("contact", contact_radius), ("scar", scar_radius))
                 if r is not None and math.isfinite(r)}
        if not self.started:
            self.started = True
            plastic = yield_remark(self.case)
            if plastic:
                remark(self.remarks, plastic, once="yield")
        if not radii:
            return
        what = max(radii, key=radii.get)     # (the contact where the two are equal)
        edge = radii[what]
        end = self.end
        if end is not None and edge > end.radius * (1.0 + END_MARGIN) + self.spacing:
            self._stop(s, cycle, what, edge)
        self.inside = (s, cycle)
        if self.stretched:
            return
        ind = self.case.indenter
        slope = float(profiles.slope(ind, np.array([edge]), self.case.table)[0])
        if slope > HALF_SPACE_SLOPE:
            self.stretched = True
            start = "the unworn contact" if s == 0.0 else f"from {self._at(s, cycle)} on, the {what}"
            remark(self.remarks,
                   f"half-space theory is stretched: {start} reaches r = {edge:.4g} m, where the "
                   f"unworn surface's slope is {slope:.4g} > {HALF_SPACE_SLOPE:g} (a/R = 0.1 on "
                   "a sphere); the solvers take the bodies as half-spaces, valid for contacts "
                   "small and flat against them, so the results past this point are approximate")

    def rows(self, s, contact_radius, scar_radius) -> None:
        """The calls ``self(s[i], contact_radius[i], scar_radius[i])`` in order, with
        their verdicts, for many recorded steps at once: the steps where nothing
        happens are found together, and only the others called one by one."""
        s = list(s)
        contact = np.asarray(contact_radius, dtype=float)
        scar = np.asarray(scar_radius, dtype=float)
        i = 0
        if s and not self.started:
            self(s[0], contact[0], scar[0])
            i = 1
        end = None if self.end is None else self.end.radius * (1.0 + END_MARGIN) + self.spacing
        while i < len(s):
            c, w = contact[i:], scar[i:]
            fc, fw = np.isfinite(c), np.isfinite(w)
            seen = fc | fw
            # the outer of the finite radii (NaN where neither is)
            edge = np.where(fc & fw, np.maximum(c, w), np.where(fc, c, w))
            event = np.zeros(len(c), dtype=bool)
            if end is not None:
                event[seen] |= edge[seen] > end
            if not self.stretched and seen.any():
                slope = profiles.slope(self.case.indenter, edge[seen], self.case.table)
                event[seen] |= slope > HALF_SPACE_SLOPE
            k = int(np.argmax(event)) if event.any() else len(c)
            quiet = np.flatnonzero(seen[:k])
            if len(quiet):
                self.inside = (s[i + int(quiet[-1])], None)
            if k == len(c):
                return
            self(s[i + k], contact[i + k], scar[i + k])
            i += k + 1

    def _stop(self, s, cycle, what, edge):
        end, case = self.end, self.case
        at = f"the unworn {what}" if s == 0.0 else f"the {what}, at {self._at(s, cycle)},"
        remedy = _lighter(case)
        if self.inside is not None and self.inside[0] > 0.0:
            remedy = (f"end the run where it was still inside ({_shorter(case, *self.inside)}) "
                      f"or {remedy}")
        if end.kind == "table":
            raise CaseError(
                f"key 'indenter.file' = {case.indenter.file!r}: {at} reaches r = {edge:.4g} m, "
                f"past {end.where}; wearcheck does not extrapolate a measured profile: give "
                f"the table further out, or {remedy}")
        key, value = run_length_key(case)
        raise CaseError(
            f"key '{key}' = {value!r}: {at} reaches r = {edge:.4g} m, past {end.where}, where "
            f"the worn body stops being the case's sphere; {remedy}")


def remark(remarks: list, text: str, once: str | None = None) -> None:
    """Issue ``text`` as a :class:`RunWarning` and keep it in ``remarks`` (a run's info["warnings"]).

    The warning reaches a Python caller; the list reaches meta.json, the
    reports and the command line's ``note:`` lines (which ignore Python
    warnings), also from Dask workers. Runs in several threads keep their
    remarks apart. ``once``: a remark on the case rather than on this run's
    course (the yield estimate), said through :mod:`warnings` once per process
    under that kind (:func:`~wearcheck.cases.errors.warn_once`, as the case's
    own notes); every run keeps it in ``remarks``.
    """
    remarks.append(text)
    if once:
        warn_once(once, text + " (said once per process; each run keeps it in "
                  "Result.warnings and meta.json)")
    else:
        warnings.warn(text, RunWarning, stacklevel=_caller_level())


def _caller_level() -> int:
    """The stacklevel of the first frame outside wearcheck (the warning points at its caller).

    wearcheck's files are those of its imported modules (its packages sit in
    several directories of a source checkout, beside tests/ and examples/).
    """
    ours = {os.path.dirname(m.__file__) for name, m in list(sys.modules.items())
            if (name == "wearcheck" or name.startswith("wearcheck."))
            and getattr(m, "__file__", None)}
    level, frame = 2, sys._getframe(2)
    while frame is not None and os.path.dirname(frame.f_code.co_filename) in ours:
        level, frame = level + 1, frame.f_back
    return level
