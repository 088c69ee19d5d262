"""A 3D check of the MDR's partial-slip (fretting) mapping with the BEM.

On one axisymmetric profile f(r) (the unworn sphere or an MDR worn profile)
under the normal force F and a reciprocating tangential displacement ±u0:

- BEM (:func:`bem_fretting`): the normal contact of f on the pixel grid
  (:mod:`bem.contact`, force control), then the tangential contact under that
  pressure with Coulomb discs and the Cerruti coupling (:mod:`bem.tangential`),
  the history 0 -> +u0 -> -u0 -> +u0 incrementally with memory;
- MDR (:func:`mdr_fretting`): the same history with the MDR's tangential
  springs (:mod:`mdr.fretting`, wear switched off so the profile is held);

and :func:`compare` sets their stick zones, shear tractions (along the x and
y axes against the MDR's τ(r)) and dissipated energies per cycle side by side.
See docs/bem-tangential.md.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from wearcheck.bem import contact as bem_contact
from wearcheck.bem import tangential
from wearcheck.bem.operator import HalfSpace


def pixel_grid(contact_radius: float, n: int, box: float):
    """Odd n × n pixel centres of side box·a centred on the tip (a pixel row on each axis)."""
    if n % 2 == 0:
        n += 1
    dx = box * contact_radius / n
    x = (np.arange(n) - (n - 1) // 2) * dx
    return n, dx, x


def profile_on_pixels(r, f, x, R):
    """f(ρ) at the pixel centres; beyond r[-1] the unworn paraboloid continued.

    The MDR grid reaches past the contact; beyond it the profile is the
    sphere's ρ²/2R shifted to meet f at r[-1] (no wear there).
    """
    X, Y = np.meshgrid(x, x, indexing="ij")
    rho = np.hypot(X, Y)
    inside = np.interp(rho, r, f)
    outside = f[-1] + (rho**2 - r[-1] ** 2) / (2.0 * R)
    return np.where(rho <= r[-1], inside, outside)


def bem_fretting(r, f, R, force, E_star, G_star, mu, amplitude, contact_radius, *,
                 n=129, box=2.4, increments=4, tol=1e-7, normal_tol=1e-8) -> dict:
    """The BEM's normal and tangential contact of the profile f(r) over one cycle ±u0.

    Returns the state at +u0 after the cycle (the steady loop), its stick
    zone (area, equivalent radius, extents along x and y), τx along the x
    and y axes, the largest |τy| and the energy dissipated over the cycle.
    """
    n, dx, x = pixel_grid(contact_radius, n, box)
    h = profile_on_pixels(r, f, x, R)
    h = h - h.min()
    normal = bem_contact.solve(HalfSpace(n, dx, E_star), h, force=force,
                               p_scale=force / (math.pi * contact_radius**2),
                               g_scale=contact_radius**2 / R, tol=normal_tol)
    p = normal.pressure
    G, nu = tangential.equivalent_half_space(E_star, G_star)
    op = tangential.TangentialHalfSpace(n, dx, G, nu)
    cyc = tangential.reciprocating(op, p, mu, amplitude, increments=increments, tol=tol)
    st = cyc.at_amplitude
    mid = (n - 1) // 2
    stick = st.stick
    loaded = p > 0
    return dict(
        x=x, pressure=p, traction=st.traction, stick=stick,
        contact_area=float(loaded.sum() * dx * dx),
        contact_radius=math.sqrt(loaded.sum() * dx * dx / math.pi),
        stick_area=float(stick.sum() * dx * dx),
        stick_radius=math.sqrt(stick.sum() * dx * dx / math.pi),
        stick_extent_x=_extent(stick[:, mid], x), stick_extent_y=_extent(stick[mid, :], x),
        tau_x_along_x=st.traction[0][:, mid], tau_x_along_y=st.traction[0][mid, :],
        tau_y_max=float(np.max(np.abs(st.traction[1]))),
        energy_per_cycle=cyc.energy_per_cycle, loop_work=cyc.loop_work,
        tangential_force=st.force[0], first_loading_force=cyc.first_loading.force[0],
        first_stick_radius=math.sqrt(cyc.first_loading.stick.sum() * dx * dx / math.pi),
        iterations=cyc.iterations, pixel=dx, n=n)


def _extent(mask_line, x):
    """Half-width of the stick zone on an axis: the largest |x| of a stick pixel + Δ/2."""
    if not mask_line.any():
        return 0.0
    dx = x[1] - x[0]
    return float(np.max(np.abs(x[mask_line])) + 0.5 * dx)


def mdr_fretting(case, f) -> dict:
    """The MDR's cycle ±u0 on the held profile f (on the MDR grid of ``case``).

    Ramp 0 -> +u0 and one cycle with the case's increments, wear off (k = 0),
    so the profile is the one given; returns x, τ(r) at +u0 after the cycle,
    the stick radius of the last stroke, the energy per cycle, the contact
    radius and the tangential force at +u0.
    """
    from wearcheck.mdr import fretting as F

    model, _ = F.build_model(case)
    model = replace(model, f0=np.asarray(f, dtype=float), k_over_hardness=0.0)
    st = F.initial_state(model)
    ramp = F.run_path(model, st, F.ramp_path(model))
    c_first = F.stick_radius(model, st, ramp, ramp=True)
    acc = F.run_path(model, st, F.cycle_path(model))
    tau = F.tangential.shear_traction(st.v, model.G_star, model.dt)
    return dict(r=model.x, tau=tau, pressure=st.normal["p"].copy(),
                stick_radius=F.stick_radius(model, st, acc, ramp=False),
                first_stick_radius=c_first,
                energy_per_cycle=acc["energy"], contact_radius=st.normal["contact_radius"],
                tangential_force=st.Q, normal_force=st.normal["force"])


def compare(mdr: dict, bem: dict, mu: float) -> dict:
    """Differences of the BEM against the MDR on the same profile and loads.

    Tractions in units of μ max p (the BEM's): the largest difference of τx
    along the x axis and along the y axis from the MDR's τ(|x|), inside the
    contact, and the RMS of τx - τ(ρ) over the BEM's contact.
    """
    scale = mu * float(np.max(bem["pressure"]))
    x = bem["x"]
    t_mdr = np.interp(np.abs(x), mdr["r"], mdr["tau"])
    inside = np.abs(x) < bem["contact_radius"]
    dx_ = np.max(np.abs(bem["tau_x_along_x"] - t_mdr)[inside]) / scale
    dy_ = np.max(np.abs(bem["tau_x_along_y"] - t_mdr)[inside]) / scale
    X, Y = np.meshgrid(x, x, indexing="ij")
    loaded = bem["pressure"] > 0
    t_mdr_2d = np.interp(np.hypot(X, Y), mdr["r"], mdr["tau"])
    rms = math.sqrt(np.mean((bem["traction"][0] - t_mdr_2d)[loaded] ** 2)) / scale
    stick_area_mdr = math.pi * mdr["stick_radius"] ** 2
    return dict(
        stick_radius_mdr=mdr["stick_radius"], stick_radius_bem=bem["stick_radius"],
        stick_extent_x=bem["stick_extent_x"], stick_extent_y=bem["stick_extent_y"],
        stick_area_rel=(bem["stick_area"] - stick_area_mdr) / stick_area_mdr
        if stick_area_mdr > 0 else math.nan,
        tau_diff_x=dx_, tau_diff_y=dy_, tau_rms=rms, tau_y_max=bem["tau_y_max"] / scale,
        energy_mdr=mdr["energy_per_cycle"], energy_bem=bem["energy_per_cycle"],
        energy_rel=(bem["energy_per_cycle"] - mdr["energy_per_cycle"])
        / mdr["energy_per_cycle"],
        force_rel=(bem["tangential_force"] - mdr["tangential_force"])
        / abs(mdr["tangential_force"]),
        pixel=bem["pixel"])
