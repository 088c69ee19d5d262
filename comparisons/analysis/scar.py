"""What an experimenter reads off a wear test: scar diameter, central wear, volume.

Pure functions of a run's history (arrays in, arrays out); the figure is
:func:`wearcheck.comparisons.present.scar_figure.scar_figure`. A laboratory measures the scar diameter D of a worn ball with a
microscope and computes the worn volume from it by the ball formula
V_lab = π D⁴/(64 R) (the volume of a spherical cap of base diameter D, to
leading order in D/R; ASTM G99/G133). That ignores the elastic recovery of
the worn surface: the scar is cut flat under load and springs back as a
shallow crown when unloaded, and early in a test much of the contact is
elastic. :func:`scar_table` gives V_lab beside the true worn volume and
their relative difference, which shows when the formula misleads.
"""

from __future__ import annotations

import math
import numpy as np

from wearcheck.cases import reference


def lab_volume(diameter, radius):
    """The lab's ball formula V = π D⁴/(64 R) [m³] for a scar of diameter D on a ball of radius R."""
    return math.pi * np.asarray(diameter, dtype=float) ** 4 / (64.0 * radius)


def cap_volume(diameter, radius):
    """Exact volume [m³] of the spherical cap of base diameter D cut from a ball of radius R.

    h = R − √(R² − D²/4), V = π h² (3R − h)/3; → π D⁴/(64 R) as D/R → 0.
    """
    b = 0.5 * np.asarray(diameter, dtype=float)
    h = b**2 / (radius + np.sqrt(radius**2 - b**2))  # R − √(R² − b²) without cancellation
    return math.pi * h**2 * (3.0 * radius - h) / 3.0


def scar_table(history: dict, case) -> dict:
    """Scar diameter, central wear depth and volume against cycles (or sliding).

    Parameters
    ----------
    history : a run's history (``s``, ``scar_radius``, ``contact_radius``,
        ``wear_center``, ``wear_volume``; ``cycles`` when the case has a stroke).
    case : the run's case (ball radius, load, wear law).

    Returns
    -------
    dict of arrays over the rows with s > 0: ``cycles`` (NaN without a
    stroke), ``s`` [m], ``scar_diameter`` 2·scar_radius [m], ``wear_center``
    [m], ``wear_volume`` (true) [m³], ``lab_volume`` π D⁴/(64 R) [m³],
    ``lab_volume_deviation`` V_lab/V − 1; under force control also
    ``archard_volume`` K F s [m³] (the exact worn volume for exponent 1),
    ``asymptote_diameter`` 2b of the long-run asymptote
    (:func:`wearcheck.cases.reference.worn_sphere_asymptote`: the exact
    spherical cap for a sphere, b = (4 R K F s/π)^(1/4) for a paraboloid, n = 1)
    [m], ``asymptote_wear_center`` its cap height [m].
    """
    R = case.indenter.radius
    s = np.asarray(history["s"], dtype=float)
    keep = s > 0
    cycles = (np.asarray(history["cycles"], dtype=float)[keep] if "cycles" in history
              else np.full(keep.sum(), np.nan))
    D = 2.0 * np.asarray(history["scar_radius"], dtype=float)[keep]
    V = np.asarray(history["wear_volume"], dtype=float)[keep]
    V_lab = lab_volume(D, R)
    with np.errstate(divide="ignore", invalid="ignore"):
        dev = np.where(V > 0, V_lab / V - 1.0, np.nan)
    out = dict(cycles=cycles, s=s[keep], scar_diameter=D,
               wear_center=np.asarray(history["wear_center"], dtype=float)[keep],
               wear_volume=V, lab_volume=V_lab, lab_volume_deviation=dev)
    if case.loading.control == "force":
        F = case.loading.force
        out["archard_volume"] = case.wear_rate * F * s[keep]
        # the exact spherical cap for a sphere, the paraboloid's law otherwise
        asym = reference.worn_sphere_asymptote(
            R, F, s[keep], case.wear_rate, exponent=case.wear.pressure_exponent,
            hardness=case.wear.hardness,
            profile="sphere" if case.indenter.profile == "sphere" else "paraboloid")
        out["asymptote_diameter"] = 2.0 * asym["scar_radius"]
        out["asymptote_wear_center"] = asym["wear_center"]
    return out


def summary(table: dict) -> dict:
    """The last row of :func:`scar_table` (the end of the test) as plain floats."""
    return {k: float(v[-1]) for k, v in table.items() if len(v)}
