"""Quick figures of a :class:`~wearcheck.Result` in a notebook: each helper draws into
the matplotlib Axes it is given (a new one when ``ax`` is None) and returns it, so
that results of several runs share one figure::

    import matplotlib.pyplot as plt
    import wearcheck
    from wearcheck import plot
    fig, ax = plt.subplots()
    for mu in (0.3, 0.6):
        r = wearcheck.solve(wearcheck.load_case("paper", {"wear.mu": mu}))
        plot.history(r, "wear_volume", ax=ax, label=f"μ = {mu}")
    ax.legend()

``scaled=True`` draws in the case's dimensionless scales (ŝ; F/F0, d/d0, a/a0,
p/p0), the paper's axes. matplotlib is imported only when a helper is called.
"""

from __future__ import annotations

import numpy as np

from wearcheck.extras import need
from wearcheck.comparisons.present import frames

__all__ = ["history", "stages"]

#: the scale each quantity is divided by under ``scaled=True``, and its symbol
_SCALED = {"force": ("F0", "F/F0"), "depth": ("d0", "d/d0"),
           "contact_radius": ("a0", "a/a0"), "wear_center": ("d0", "w(0)/d0"),
           "scar_radius": ("a0", "b/a0"), "max_pressure": ("p0", "p_max/p0"),
           "f": ("d0", "f/d0"), "p": ("p0", "p/p0"), "tau": ("p0", "τ/p0"),
           "r": ("a0", "r/a0")}
#: plain-language names of the usual columns, for axis labels
_NAMES = {"s": "sliding distance s", "force": "normal force F", "depth": "depth d",
          "contact_radius": "contact radius a", "wear_center": "central wear",
          "wear_volume": "worn volume", "scar_radius": "scar radius b",
          "max_pressure": "peak pressure", "f": "worn profile f", "p": "pressure p",
          "tau": "shear traction τ", "r": "radius r", "cycles": "cycles"}


def _axes(ax):
    if ax is not None:
        return ax
    plt = need("matplotlib.pyplot", "wearcheck.plot")
    return plt.figure().add_subplot()


def _label(name: str, unit: str, scaled: bool) -> str:
    if scaled and name in _SCALED:
        return _SCALED[name][1]
    text = _NAMES.get(name, name)
    return f"{text} [{unit}]" if unit else text


def _units(result) -> dict:
    d = frames.dictionary(result)
    return {**{k: v.get("unit", "") for k, v in d["stages_npz"].items()},
            **{k: v.get("unit", "") for k, v in d["history_csv"].items()}}


def history(result, y: str = "force", *, x: str = "s", scaled: bool = False, ax=None,
            **style):
    """One history column against another (default: against the sliding distance).

    Parameters
    ----------
    result : a :class:`~wearcheck.Result`.
    y, x : history columns (``result.history``); ``x="s_hat"`` or ``"cycles"`` too.
    scaled : divide by the case's scales (ŝ for ``s``; F0, d0, a0, p0).
    ax : the Axes to draw into, or None for a new figure.
    style : passed to ``Axes.plot`` (``label``, ``color``, ...).

    Returns
    -------
    The Axes.
    """
    h = result.history
    for name in (x, y):
        if name not in h:
            raise KeyError(f"'{name}' is not a history column of this run: "
                           f"{', '.join(h)}")
    sc, units = result.scales, _units(result)
    xv, yv = np.asarray(h[x], float), np.asarray(h[y], float)
    if scaled:
        if x == "s":
            xv, x = xv * sc["s_hat_per_m"], "s_hat"
        if y in _SCALED:
            yv = yv / sc[_SCALED[y][0]]
    ax = _axes(ax)
    ax.plot(xv, yv, **style)
    ax.set_xlabel("ŝ" if x == "s_hat" else _label(x, units.get(x, ""), scaled))
    ax.set_ylabel(_label(y, units.get(y, ""), scaled))
    return ax


def stages(result, field: str = "f", *, scaled: bool = False, ax=None, **style):
    """A stage array (worn profile ``f``, pressure ``p``, ...) against the radius, one
    line per stored stage, labelled by its sliding distance (or ŝ when scaled).

    Returns
    -------
    The Axes.
    """
    st = result.stages
    if field not in st or np.ndim(st[field]) != 2:
        raise KeyError(f"'{field}' is not a stage array of this run: "
                       f"{', '.join(k for k in st if np.ndim(st[k]) == 2)}")
    sc, units = result.scales, _units(result)
    r = np.asarray(st["r"], float) / (sc["a0"] if scaled else 1.0)
    values = np.asarray(st[field], float) / (sc[_SCALED[field][0]]
                                             if scaled and field in _SCALED else 1.0)
    ax = _axes(ax)
    plt = need("matplotlib.pyplot", "wearcheck.plot")
    colours = plt.get_cmap("viridis")(np.linspace(0.0, 0.9, max(len(values), 1)))
    for k, row in enumerate(values):
        tag = f"ŝ = {st['s_hat'][k]:.3g}" if scaled else f"s = {st['s'][k]:.3g} m"
        ax.plot(r, row, color=colours[k], **{"label": tag, **style})
    ax.set_xlabel(_label("r", units.get("r", "m"), scaled))
    ax.set_ylabel(_label(field, units.get(field, ""), scaled))
    return ax
