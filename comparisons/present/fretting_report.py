"""The report of a fretting run: loops, stick radius, energy and wear against cycles,
each beside its closed form for the unworn sphere (Cattaneo–Mindlin,
Mindlin–Deresiewicz) and the energy–wear identity V = (k/σ0)·W.

``write(directory, case, result)`` is the MDR's ``run_report`` in the registry:
``wearcheck run`` calls it on every run, and it writes only for a fretting case.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.extras import MissingExtra, need

from wearcheck.cases import reference_fretting as rf
from wearcheck.comparisons.present import report


def unworn_checks(case, result) -> dict:
    """The first simulated cycle against the closed forms (paraboloid and sphere only).

    Relative differences: stick radius (Cattaneo–Mindlin, over a), energy per
    cycle (Mindlin–Deresiewicz), tangential force amplitude (virgin curve), and
    the energy–wear identity over the whole run.
    """
    h = result.history
    F = float(h["force"][0])
    a = float(h["contact_radius"][0])
    mu, fr = case.wear.mu, case.fretting
    u_star = rf.gross_slip_displacement(mu, F, case.G_star, a)
    out = dict(u_star=u_star, contact_radius=a, force=F)
    W = np.asarray(h["dissipated_energy"], float)
    V = np.asarray(h["wear_volume"], float)
    K = case.wear.k / case.wear.hardness
    big = max(float(np.max(np.abs(V))), 1e-300)
    out["energy_wear_identity"] = float(np.max(np.abs(V - K * W)) / big)
    if case.indenter.profile not in ("paraboloid", "sphere"):
        return out
    R = case.indenter.radius
    if fr.amplitude is not None:
        u0 = fr.amplitude
        if u0 >= u_star:
            out["regime"] = "gross slip"
            return out
        c = rf.stick_radius(a, R, case.E_star, case.G_star, mu, u0)
        Q = float(rf.tangential_force(u0, mu, F, u_star))
        out.update(force_amplitude_closed_form=Q,
                   force_amplitude=float(h["tangential_force_amplitude"][0]),
                   force_amplitude_difference=abs(float(h["tangential_force_amplitude"][0])
                                                  - Q) / (mu * F))
    else:
        # force-controlled tangential loading: Q* < μF, or the solver refused the run
        Q = fr.force_amplitude
        c = rf.stick_radius_from_force(a, Q, mu, F)
        u0 = float(rf.tangential_displacement(Q, mu, F, u_star))
        out.update(displacement_amplitude_closed_form=u0,
                   displacement_amplitude=float(h["displacement_amplitude"][0]),
                   displacement_amplitude_difference=abs(float(h["displacement_amplitude"][0])
                                                         - u0) / u_star)
    out["regime"] = "partial slip"
    out["amplitude"] = u0
    Wc = rf.energy_per_cycle_displacement(u0, mu, F, u_star)
    # row 0 is the first quarter cycle (virgin loading), row 1 the first full cycle
    k = 1 if len(h["cycles"]) > 1 else 0
    out.update(stick_radius_closed_form=c, stick_radius=float(h["stick_radius"][0]),
               stick_radius_difference=abs(float(h["stick_radius"][0]) - c) / a,
               energy_closed_form=Wc, energy=float(h["energy_per_cycle"][k]),
               energy_difference=abs(float(h["energy_per_cycle"][k]) / Wc - 1.0))
    return out


def _figures(directory: Path, case, result, checks) -> list[str]:
    matplotlib = need("matplotlib", "drawing figures")
    matplotlib.use("Agg")
    # lazy (a): matplotlib, the optional "plot" extra
    import matplotlib.pyplot as plt

    h, fields = result.history, result.fields or {}
    mu = case.wear.mu
    names = []
    if "loop_cycles" in fields and len(fields["loop_cycles"]):
        fig, ax = plt.subplots(figsize=(6, 4.5))
        F = checks["force"]
        u_star = checks["u_star"]
        for n, u, Q in zip(fields["loop_cycles"], fields["loop_displacement"],
                           fields["loop_tangential_force"]):
            ax.plot(np.asarray(u) / u_star, np.asarray(Q) / (mu * F), lw=1.2,
                    label=f"MDR, cycle {n:g}")
        if checks.get("regime") == "partial slip":
            u0 = checks["amplitude"]
            u = np.linspace(-u0, u0, 201)
            for branch in ("unloading", "reloading"):
                ax.plot(u / u_star, rf.loop_force(u, u0, mu, F, u_star, branch) / (mu * F),
                        "k:", lw=1, label="Mindlin–Deresiewicz (unworn)"
                        if branch == "unloading" else None)
        ax.set(xlabel="u_x / u*", ylabel="Q / μF", title="fretting loops")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.savefig(directory / "fretting_loops.png", dpi=130, bbox_inches="tight")
        plt.close(fig)
        names.append("fretting_loops.png")
    n = np.asarray(h["cycles"], float)
    keep = n > 0
    if keep.sum() >= 2:
        fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
        fig.subplots_adjust(wspace=0.4)
        a0 = checks["contact_radius"]
        axes[0].semilogx(n[keep], np.asarray(h["stick_radius"])[keep] / a0)
        if "stick_radius_closed_form" in checks:
            axes[0].axhline(checks["stick_radius_closed_form"] / a0, color="k", ls=":",
                            label="Cattaneo–Mindlin (unworn)")
            axes[0].legend(fontsize=7)
        axes[0].set(xlabel="cycles", ylabel="stick radius c / a0")
        axes[1].semilogx(n[keep], np.asarray(h["energy_per_cycle"])[keep] * 1e9)
        if "energy_closed_form" in checks:
            axes[1].axhline(checks["energy_closed_form"] * 1e9, color="k", ls=":",
                            label="Mindlin–Deresiewicz (unworn)")
            axes[1].legend(fontsize=7)
        axes[1].set(xlabel="cycles", ylabel="energy per cycle [nJ]")
        K = case.wear.k / case.wear.hardness
        axes[2].loglog(n[keep], np.asarray(h["wear_volume"])[keep] * 1e18, label="MDR")
        axes[2].loglog(n[keep], K * np.asarray(h["dissipated_energy"])[keep] * 1e18, "k:",
                       label="(k/σ0)·W")
        axes[2].set(xlabel="cycles", ylabel="worn volume [µm³]")
        axes[2].legend(fontsize=7)
        for ax in axes:
            ax.grid(alpha=0.3)
        fig.savefig(directory / "fretting_history.png", dpi=130, bbox_inches="tight")
        plt.close(fig)
        names.append("fretting_history.png")
    return names


def _cycles_done(fr, info) -> str:
    """How the cycles were done: every one simulated, or by cycle jumping with the
    error estimate that meta.json reports (docs/fretting.md §4)."""
    simulated = info.get("simulated_cycles", "?")
    if fr.jump_tolerance == 0:
        return f"every cycle simulated: {simulated}"
    text = (f"{simulated} simulated, the rest by cycle jumping at "
            f"fretting.jump_tolerance = {fr.jump_tolerance:g}")
    estimate = info.get("cycle_jumping", {}).get("error_estimate")
    if estimate is not None:
        text += (f"; estimated error against every cycle simulated {estimate:.2g} of the "
                 "largest wear, info.cycle_jumping in meta.json")
    return text


def write(directory, case, result) -> list[Path]:
    """Write ``report.md``, ``report.html`` and the fretting figures into a run
    directory; nothing for a case without a ``[fretting]`` section."""
    if getattr(case, "fretting", None) is None:
        return []
    directory = Path(directory)
    checks = unworn_checks(case, result)
    try:
        figures, missing = _figures(directory, case, result, checks), None
    except MissingExtra as exc:   # the core install: the report without its figures
        figures, missing = [], exc
    R, fmt = report, report.fmt
    fr = case.fretting
    load = (f"amplitude u0 = {fr.amplitude:g} m" if fr.amplitude is not None
            else f"force amplitude Q* = {fr.force_amplitude:g} N")
    blocks = [R.heading("Fretting run"),
              R.para(f"Case file: {case.source}. {case.indenter.profile}, "
                     f"{case.loading.control} control, {load}, {fr.cycles:g} cycles "
                     f"({_cycles_done(fr, result.info)}). u* = "
                     f"{checks['u_star']:.4g} m"
                     + (f" ({checks['regime']})." if "regime" in checks else "."))]
    rows = [["energy–wear identity max |V − (k/σ0)W| / max V", fmt(
        checks["energy_wear_identity"]), "to round-off"]]
    if "increment_wear_number" in result.info:
        # the explicit wear within a cycle (docs/fretting.md §5): a run past its
        # limit is refused, so a report shows how close this one came
        rows += [["increment wear number (k/σ0)·μE*·|Δslip|/Δr",
                  fmt(result.info["increment_wear_number"]),
                  f"refused above {result.info.get('increment_wear_number_limit', '?')}; "
                  "more fretting.increments lower it"]]
    if "stick_radius_difference" in checks:
        rows += [["first cycle: |c − c_CM| / a", fmt(checks["stick_radius_difference"]),
                  f"c_CM/a = {checks['stick_radius_closed_form'] / checks['contact_radius']:.4f}"],
                 ["first cycle: |W / W_MD − 1|", fmt(checks["energy_difference"]),
                  f"W_MD = {checks['energy_closed_form']:.4g} J"]]
        if "force_amplitude_difference" in checks:
            rows += [["first cycle: |Q* − Q*_CM| / μF",
                      fmt(checks["force_amplitude_difference"]),
                      f"Q*_CM = {checks['force_amplitude_closed_form']:.4g} N"]]
        else:
            rows += [["first quarter cycle: |u0 − u0_CM| / u*",
                      fmt(checks["displacement_amplitude_difference"]),
                      f"u0_CM = {checks['displacement_amplitude_closed_form']:.4g} m"]]
    blocks += [R.heading("Against the closed forms", 3),
               R.table(["check", "value", "reference"], rows)]
    h = result.history
    stage = [i for i, n in enumerate(h["cycles"]) if n in set(result.info["stage_cycles"])
             or i == len(h["cycles"]) - 1]
    blocks += [R.heading("History at the stored cycles", 3)]
    if len(h["cycles"]) and h["cycles"][0] == 0:
        blocks.append(R.para("The row at 0 cycles is the state after the first quarter "
                             "cycle (the virgin loading from 0 to +U): its wear is that "
                             "quarter cycle's."))
    blocks += [R.table(["cycles", "F [N]", "Q* [N]", "c [m]", "W per cycle [J]",
                        "wear volume [m³]", "central wear [m]"],
                       [[fmt(h["cycles"][i], 6), fmt(h["force"][i], 5),
                         fmt(h["tangential_force_amplitude"][i], 5),
                         fmt(h["stick_radius"][i], 5), fmt(h["energy_per_cycle"][i], 5),
                         fmt(h["wear_volume"][i], 5), fmt(h["wear_center"][i], 5)]
                        for i in stage])]
    blocks += [R.image(name, name.removesuffix(".png").replace("_", " ")) for name in figures]
    if missing is not None:
        blocks.append(R.para(f"No figures: {missing}."))
    md, html = R.write(directory, blocks, f"wearcheck fretting: {Path(case.source).name}")
    return [md, html] + [directory / n for n in figures]
