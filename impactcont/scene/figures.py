"""Figures of scene outputs: one drawing function per plot kind, and ``plot`` of a file.

Every function reads datasets (never computes orbits, apart from evaluating
the exact flow of eq. 9 along a stored periodic motion to draw it) and
returns a :class:`matplotlib.figure.Figure` built without pyplot, so it
works in any process, with any backend, and leaks no global figure state.
"""

from __future__ import annotations

import json
import logging
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from impactcont.dataset.attributes import split_parameters
from impactcont.dataset.curves import kind_of_curve
from impactcont.dataset.io import atomic_output, check_output_file
from impactcont.errors import ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.flow import Flow
from impactcont.plots.branches import WIDTH_RANGE, check_width
from impactcont.scene.keys import DPI_RANGE

__all__ = ["DEFAULT_KINDS", "MAX_PIXELS", "WIDTH", "WIDTH_RANGE", "check_dpi", "check_width",
           "draw_bifurcation", "draw_curves",
           "draw_map", "draw_multipliers", "draw_orbits", "draw_robust", "draw_simulations",
           "plot_file", "save_figure"]

log = logging.getLogger(__name__)

_MAX_ROWS = 12
#: The largest image written (width x height in pixels): 4e8 bytes of RGBA while drawing.
MAX_PIXELS = 100_000_000


def check_dpi(dpi: Any) -> int:
    """``dpi`` as an int, refused outside :data:`~impactcont.scene.keys.DPI_RANGE`.

    Raises
    ------
    ParameterError
        Naming ``dpi``, the value and the allowed range.
    """
    lo, hi = DPI_RANGE
    if isinstance(dpi, bool) or not isinstance(dpi, (int, np.integer)) or not lo <= dpi <= hi:
        raise ParameterError(f"dpi must be an integer in [{lo}, {hi}] (dots per inch of the "
                             f"image); got {dpi!r}")
    return int(dpi)


def _option(plot: Any, name: str, default: Any) -> Any:
    value = getattr(plot, name, None) if plot is not None else None
    return default if value is None else value


#: Default width of the figures, in inches: a journal's double column (3.5 in: single).
WIDTH = 7.0
def _width(plot: Any) -> float:
    """The figure width in inches (``plot.width``, default :data:`WIDTH`)."""
    return check_width(_option(plot, "width", WIDTH))


def _finish(fig: Figure, plot: Any, default_title: str) -> Figure:
    from impactcont.plots.branches import fit_text

    title = _option(plot, "title", default_title)
    if title:
        text = fig.suptitle(title, fontsize="medium")
        fit_text(text)
    return fig


def _systems(datasets: Mapping[str, xr.Dataset]) -> list[dict[str, xr.Dataset]]:
    """Branches grouped by system: the same oscillator apart from the continued parameter."""
    groups: dict[str, dict[str, xr.Dataset]] = {}
    for name, ds in datasets.items():
        osc = json.loads(ds.attrs["oscillator"])
        osc.pop(ds.attrs.get("parameter"), None)
        groups.setdefault(json.dumps(osc, sort_keys=True), {})[name] = ds
    return list(groups.values())


def draw_bifurcation(datasets: Mapping[str, xr.Dataset], plot: Any = None) -> Figure:
    """Bifurcation diagram of branches (``plot.y``, default ``impact_velocity``).

    One panel per system (branches at b = 0 and at b = 0.5 are not drawn on one
    axis), titled with what differs between them; special-point labels avoid
    each other.
    """
    from impactcont.plots import bifurcation_diagram
    from impactcont.plots.branches import (
        differing_parameters,
        fixed_parameters,
        parameter_text,
    )

    panels = _systems(datasets)
    width = _width(plot)
    fig = Figure(figsize=(width, 0.3 + (0.45 * width + 2.2) * len(panels)),
                 layout="constrained")
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    y = _option(plot, "y", "impact_velocity")
    first = next(iter(datasets.values()))
    names = [first[v].attrs.get("long_name", v) if v in first else v
             for v in (y, first.attrs["parameter"])]
    _finish(fig, plot, f"Bifurcation diagram: {names[0]} against {names[1]}"
            if len(panels) > 1 else "")
    differing = differing_parameters([list(panel.values()) for panel in panels])
    for number, (ax, panel) in enumerate(zip(axes, panels, strict=True), start=1):
        title = None  # one panel: what bifurcation_diagram says it draws
        if len(panels) > 1:
            own = fixed_parameters(list(panel.values()))
            title = parameter_text(own, differing) or f"system {number} (M, K or F differ)"
        bifurcation_diagram(panel, y=y, ax=ax, title=title)
        if ax is not axes[-1]:
            ax.set_xlabel("")
    if len(panels) == 1 and _option(plot, "title", None):
        axes[0].set_title("")
    return fig


def draw_multipliers(datasets: Mapping[str, xr.Dataset], plot: Any = None) -> Figure:
    """Multipliers along one branch."""
    from impactcont.plots import multipliers_plot
    from impactcont.plots.branches import motion_text, system_text

    ds = next(iter(datasets.values()))
    width = _width(plot)
    narrow = width < 5.0  # one panel above the other
    fig = Figure(figsize=(width, 1.7 * width + 1.2 if narrow else 0.5 * width + 1.4),
                 layout="constrained")
    axes = fig.subplots(2 if narrow else 1, 1 if narrow else 2).ravel()
    multipliers_plot(ds, ax=tuple(axes), yscale=_option(plot, "yscale", "auto"))
    where = system_text([ds], skip=[ds.attrs["parameter"]])
    motion = motion_text([ds])
    return _finish(fig, plot, f"Multipliers along the {motion[0].lower()}{motion[1:]}, {where}")


def _orbit_rows(datasets: Mapping[str, xr.Dataset]) -> list[tuple[str, xr.Dataset, int | None]]:
    """One row per physical orbit; an entry with none: its root nearest to physical, or None.

    A root of eq. (15) that is not physical is no motion of the machine: it is
    drawn only when its entry has no physical one, to show why.
    """
    rows: list[tuple[str, xr.Dataset, int | None]] = []
    for name, ds in datasets.items():
        n = ds.sizes["orbit"]
        physical = [k for k in range(n) if bool(ds["physical"][k])]
        if physical:
            rows += [(name, ds, k) for k in physical]
        elif n:
            gap = np.nan_to_num(np.asarray(ds["gap_min"].values, dtype=float), nan=-np.inf) \
                if "gap_min" in ds else np.zeros(n)
            rows.append((name, ds, int(np.argmax(gap))))
        else:
            rows.append((name, ds, None))
    if len(rows) > _MAX_ROWS:
        log.warning("orbits plot: drawing the first %d of %d orbits", _MAX_ROWS, len(rows))
    return rows[:_MAX_ROWS]


def _entry_rows(count: int, plot: Any, extra: float) -> tuple[Figure, np.ndarray, float]:
    """A figure of ``count`` rows of subfigures (one an entry, two panels side by side).

    Each row is ``0.3 width + 0.75`` inches high and ``extra`` inches more hold the
    title and the legend (the width is :func:`_width`'s). Without rows the figure is
    one row high and has no subfigure, for :func:`_empty`.

    Returns
    -------
    fig : matplotlib.figure.Figure
    subfigs : ndarray of SubFigure, shape (count,)
    width : float
    """
    width = _width(plot)
    fig = Figure(figsize=(width, (0.3 * width + 0.75) * max(count, 1) + extra),
                 layout="constrained")
    subfigs = (np.atleast_1d(fig.subfigures(count, 1, squeeze=False)[:, 0]) if count
               else np.empty(0, dtype=object))
    return fig, subfigs, width


def _empty(fig: Figure, text: str) -> Figure:
    ax = fig.add_subplot()
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, wrap=True)
    ax.set_axis_off()
    return fig


def _no_orbit(fig: Any, ds: xr.Dataset) -> None:
    """An entry that kept no orbit: say why across its row."""
    from impactcont.plots.branches import fit_text, motion_text

    note = ds.attrs.get("note") or f"no motion kept (which = {ds.attrs.get('which')})"
    motion = motion_text([ds]).replace(" motions ", " motion ", 1)
    text = fig.text(0.5, 0.5, f"{motion}: {note}", ha="center", va="center", fontsize="small")
    fit_text(text)


def _style_legend(fig: Figure, kinds: set[str], j: int, fontsize: str) -> None:
    from matplotlib.lines import Line2D

    from impactcont.plots import SEGMENT_STYLES

    handles = [Line2D([], [], color="C0", label=kind, **SEGMENT_STYLES[kind])
               for kind in SEGMENT_STYLES if kind in kinds]
    handles += [Line2D([], [], color="C3", linewidth=0.8, label="impact"),
                Line2D([], [], color="0.3", linewidth=0.8, linestyle=":",
                       label=f"stop $x_{j} = b$")]
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles),
               fontsize=fontsize, frameon=False, handlelength=1.8, columnspacing=1.0)


def _orbit_text(ds: xr.Dataset, k: int) -> str:
    """``Period-1 motion with 1 impact, the − root of eq. (15)``: orbit ``k`` in words."""
    from impactcont.plots.branches import motion_text

    text = motion_text([ds]).replace(" motions ", " motion ", 1)
    if "root" in ds and ds.sizes.get("orbit", 0) > 1:
        text += f", the {'−' if int(ds['root'][k]) < 0 else '+'} root of eq. (15)"
    return text


def _verdict(ds: xr.Dataset, k: int) -> str:
    """``stable``, ``unstable`` or why a root is no motion (eq. 16-17)."""
    if bool(ds["physical"][k]):
        return "stable" if bool(ds["stable"][k]) else "unstable"
    if "gap_min" in ds and float(ds["gap_min"][k]) < 0:
        return f"no physical motion, crosses the stop (min gap {float(ds['gap_min'][k]):.3g})"
    if "impact_velocity" in ds and float(ds["impact_velocity"][k]) < 0:
        return (f"no physical motion, impact velocity {float(ds['impact_velocity'][k]):.3g} "
                f"< 0")
    return "no physical motion"


def draw_orbits(datasets: Mapping[str, xr.Dataset], plot: Any = None) -> Figure:
    """$x_j(t)$ over one period and the phase portrait of every physical orbit.

    Line styles are those of the bifurcation diagrams (stable, unstable,
    non-physical). A root of eq. (15) that is not physical is no motion: it is
    drawn (dotted) only for an entry without a physical one, titled with the
    reason; an entry that kept no orbit says why. Each row is titled with its
    entry, N, omega, b and the verdict.
    """
    from impactcont.plots import SEGMENT_STYLES
    from impactcont.plots.branches import fit_text, legend_fontsize

    rows = _orbit_rows(datasets)
    fig, subfigs, width = _entry_rows(len(rows), plot, 0.9)
    if not rows:
        return _finish(_empty(fig, "no periodic orbit in these entries"), plot, "Orbits")
    kinds = set()
    j = 1
    for sub, (_name, ds, k) in zip(subfigs, rows, strict=True):
        if k is None:
            _no_orbit(sub, ds)
            continue
        ax_t, ax_p = sub.subplots(1, 2)
        osc = ImpactOscillator.from_json(ds.attrs["oscillator"])
        n, i = osc.n, osc.stops.index
        j = i + 1
        T = float(ds["period"][k])
        tau = np.linspace(0.0, T, 600)
        X = Flow(osc).state(tau, np.asarray(ds["state"][k].values), float(ds["delta"][k]))
        stable, physical = bool(ds["stable"][k]), bool(ds["physical"][k])
        kind = "non-physical" if not physical else "stable" if stable else "unstable"
        kinds.add(kind)
        ax_t.plot(tau, X[:, i], color="C0", **SEGMENT_STYLES[kind])
        ax_t.axhline(osc.b, color="0.3", linewidth=0.8, linestyle=":")
        ax_t.set_xlabel("time since the impact $t$")
        ax_t.set_ylabel(f"$x_{j}$")
        ax_p.plot(X[:, i], X[:, n + i], color="C0", **SEGMENT_STYLES[kind])
        ax_p.plot([X[-1, i], X[0, i]], [X[-1, n + i], X[0, n + i]], color="C3", linewidth=0.8)
        ax_p.axvline(osc.b, color="0.3", linewidth=0.8, linestyle=":")
        ax_p.set_xlabel(f"$x_{j}$")
        ax_p.set_ylabel(rf"$\dot{{x}}_{j}$")
        ticks = 3 if width < 5.0 else 6
        for ax in (ax_t, ax_p):
            ax.xaxis.set_major_locator(MaxNLocator(ticks))
            ax.yaxis.set_major_locator(MaxNLocator(ticks))
        title = sub.suptitle(f"{_orbit_text(ds, k)}, $\\omega = {osc.omega:g}$, "
                             f"$b = {osc.b:g}$: {_verdict(ds, k)}", fontsize="medium")
        fit_text(title)
    if kinds:
        _style_legend(fig, kinds, j, legend_fontsize(fig))
    return _finish(fig, plot, "Periodic impacting motions")


def draw_simulations(datasets: Mapping[str, xr.Dataset], plot: Any = None) -> Figure:
    """Simulated trajectories ($x_j(t)$, phase portrait) or, without one, the impacts.

    A trajectory with sticking phases is drawn as its time history instead
    (:func:`impactcont.plots.series.time_history`): the held intervals shaded, the
    contact force under the motion, the accumulation points of complete chatter marked.
    """
    from matplotlib.lines import Line2D

    from impactcont.plots.branches import fit_text, legend_fontsize
    from impactcont.plots.series import Series, time_history

    items = list(datasets.items())[:_MAX_ROWS]
    stacked = sum("X" in ds and ds.sizes.get("sticking", 0) > 0 for _, ds in items)
    fig, subfigs, width = _entry_rows(len(items), plot, 0.8 + 1.0 * stacked)
    if not items:
        return _finish(_empty(fig, "no simulation"), plot, "Simulations")
    trajectories = False
    held: dict[str, Any] = {}  # the legend entries of the rows with sticking phases
    symbol = "x_1"
    ticks = 3 if width < 5.0 else 6
    for sub, (_name, ds) in zip(subfigs, items, strict=True):
        osc = ImpactOscillator.from_json(ds.attrs["oscillator"])
        n = osc.n
        # the stop coordinate s = n . x (x_j, or x_j - x_k for a clearance between masses)
        normal = osc.stops.normal(n)
        symbol = _coordinate_symbol(osc.stops.coordinate)
        walls = [osc.b] + ([-osc.stops.b_low] if osc.stops.two_sided else [])
        if "X" in ds and ds.sizes.get("sticking", 0):
            # held on a stop: the motion over its sticking phases and the contact force
            # under it (the phase portrait would draw a held interval as one point)
            trajectories = True
            ax_l, ax_r = sub.subplots(2, 1, sharex=True, height_ratios=(3, 2))
            motion = Series(np.asarray(ds["t"].values),
                            np.asarray(ds["X"].values)[:, :n] @ normal,
                            "simulated trajectory", color="C0", linestyle="-",
                            linewidth=0.8)
            entries = time_history(ax_l, ax_r, [motion], ds, xlabel="time $t$",
                                   ylabel=f"${symbol}$", force_label="$p$",
                                   force_entry="contact force $p$ on stop {stop}")
            for wall in walls:
                ax_l.axhline(wall, color="0.3", linewidth=0.8, linestyle=":")
            ax_l.margins(y=0.12)  # the accumulation points sit on the stop
            held |= {h.get_label(): h for h in entries[1:]}
        elif "X" in ds:
            ax_l, ax_r = sub.subplots(1, 2)
            trajectories = True
            t = np.asarray(ds["t"].values)
            X = np.asarray(ds["X"].values)
            s, s_dot = X[:, :n] @ normal, X[:, n:] @ normal
            ax_l.plot(t, s, color="C0", linewidth=0.8)
            ax_l.set_xlabel("time $t$")
            ax_l.set_ylabel(f"${symbol}$")
            ax_r.plot(s, s_dot, color="C0", linewidth=0.8)
            for wall in walls:
                ax_l.axhline(wall, color="0.3", linewidth=0.8, linestyle=":")
                ax_r.axvline(wall, color="0.3", linewidth=0.8, linestyle=":")
            ax_r.set_xlabel(f"${symbol}$")
            ax_r.set_ylabel(f"${_coordinate_symbol(osc.stops.coordinate, dot=True)}$")
        else:
            ax_l, ax_r = sub.subplots(1, 2)
            k = np.arange(ds.sizes["impact"])
            ax_l.plot(k, ds["impact_phases"].values, ".", color="C0", markersize=3)
            ax_l.set_xlabel("impact number")
            ax_l.set_ylabel("impact phase [rad]")
            ax_r.plot(k, ds["impact_velocities"].values, ".", color="C0", markersize=3)
            ax_r.set_xlabel("impact number")
            ax_r.set_ylabel("impact velocity")
        for ax in (ax_l, ax_r):
            ax.xaxis.set_major_locator(MaxNLocator(ticks))
            ax.yaxis.set_major_locator(MaxNLocator(ticks))
        title = sub.suptitle(rf"Simulation at $\omega = {osc.omega:g}$, $b = {osc.b:g}$, "
                             f"{ds.sizes['impact']} impacts, {ds.attrs.get('status', '')}",
                             fontsize="medium")
        fit_text(title)
    if trajectories:
        stop = "stops" if len(walls) > 1 else f"stop ${symbol} = b$"
        handles = [Line2D([], [], color="C0", linewidth=0.8, label="simulated trajectory"),
                   Line2D([], [], color="0.3", linewidth=0.8, linestyle=":", label=stop)]
    else:
        handles = [Line2D([], [], color="C0", linestyle="none", marker=".", label="impact")]
    handles += list(held.values())
    fig.legend(handles=handles, loc="outside lower center",
               ncols=min(len(handles), 2 if width < 5.0 else 3),
               fontsize=legend_fontsize(fig), frameon=False)
    return _finish(fig, plot, "Simulations")


def _coordinate_symbol(coordinate: str, *, dot: bool = False) -> str:
    r"""Mathtext (without dollars) of a stop coordinate's text (``Stops.coordinate``):
    ``"x2 - x1"`` -> ``x_2 - x_1``, its velocity (`dot`) ``\dot{x}_2 - \dot{x}_1``."""
    import re

    return re.sub(r"x(\d+)", r"\\dot{x}_\1" if dot else r"x_\1", coordinate)


def _component_symbol(name: str) -> str:
    r"""Mathtext of a component of eq. (19): ``dv1`` -> ``$\Delta \dot{x}_1$``, ``ddelta``..."""
    import re

    if name == "ddelta":
        return r"$\Delta\delta$"
    match = re.fullmatch(r"d([xv])(\d+)", name)
    if match is None:
        return name
    symbol = "x" if match[1] == "x" else r"\dot{x}"
    return rf"$\Delta {symbol}_{{{match[2]}}}$"


def draw_robust(datasets: Mapping[str, xr.Dataset], plot: Any = None) -> Figure:
    r"""Gamma of eq. (28) of each robust-stability entry, with epsilon and epsilon0.

    Rows and columns are the components of the perturbed impact state of
    eq. (19) (``\Delta x_2 .. \Delta \dot x_n, \Delta\delta``); one panel per entry.
    """
    items = list(datasets.items())[:_MAX_ROWS]
    width = _width(plot)
    cols = max(1, min(len(items), int(width // 3.4)))
    rows = -(-max(len(items), 1) // cols)
    fig = Figure(figsize=(width, rows * (width / cols * 0.85 + 0.5) + 0.4),
                 layout="constrained")
    if not items:
        return _finish(_empty(fig, "no robust-stability entry"), plot, "Robust stability")
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False).ravel())
    for ax in axes[len(items):]:
        ax.set_visible(False)
    from impactcont.plots.branches import motion_text

    for ax, (_name, ds) in zip(axes, items, strict=False):
        gamma = np.asarray(ds["Gamma"].values, dtype=float)
        im = ax.imshow(gamma, cmap="viridis", vmin=0.0, vmax=1.0)
        labels = [_component_symbol(str(v)) for v in ds["g_row"].values]
        ax.set_xticks(range(len(labels)), labels)
        ax.set_yticks(range(len(labels)), labels)
        ax.set_xlabel("perturbed component $j$")
        ax.set_ylabel("component $i$ of the impact state")
        if len(labels) <= 6:
            for (i, j), v in np.ndenumerate(gamma):
                # 8 pt on a page-wide figure, 7 pt on a column (the journal's least)
                ax.text(j, i, f"{v:.2f}", ha="center", va="center",
                        fontsize=8.0 if width / cols >= 5.0 else 7.0,
                        color="white" if v < 0.6 else "black")
        vary = ", ".join(f"${k}$ in [{lo:g}, {hi:g}]"
                         for k, (lo, hi) in json.loads(ds.attrs.get("vary", "{}")).items())
        verdict = "robustly stable" if bool(ds["robust"]) else "not established"
        motion = motion_text([ds]).replace(" motions ", " motion ", 1)
        text = ax.set_title(f"{motion}, {vary}, "
                            rf"$\epsilon = {float(ds['epsilon']):.4g}$, "
                            rf"$\epsilon_0 = {float(ds['epsilon0']):.4g}$: {verdict}",
                            fontsize="small")
        fig.colorbar(im, ax=ax, label=r"$\Gamma_{ij}$", shrink=0.9)
        from impactcont.plots.branches import fit_text

        fit_text(text)
    return _finish(fig, plot, r"Robust stability: perturbation pattern $\Gamma$ (eq. 28)")


def _motions_of(ds: xr.Dataset) -> str:
    """``period-N motions`` of a closed-form curve, ``N-p motions "pattern"`` of one
    followed by shooting."""
    N = int(ds.attrs["N"])
    if "curve_kind" not in ds.attrs:
        return f"period-{N} motions"
    return f"{N}-{int(ds.attrs['impacts'])} motions \"{ds.attrs['pattern']}\""


def draw_curves(datasets: Mapping[str, xr.Dataset], plot: Any = None) -> Figure:
    """Codim-1 curves in their parameter plane; dotted where no stable motion changes.

    Codim-2 points are named by their standard abbreviations where one exists
    (:data:`~impactcont.plots.maps.CODIM2_NAMES`: LPPD, PDNS, R2, ...), by their
    label ``A+B`` otherwise (non-smooth points, which have none; the legend says so).
    """
    from matplotlib.lines import Line2D

    from impactcont.plots.branches import axis_label, legend_below
    from impactcont.plots.maps import codim2_legend, codim2_name

    width = _width(plot)
    fig = Figure(figsize=(width, 0.6 * width + 1.2), layout="constrained")
    ax = fig.add_subplot()
    p1 = p2 = ""
    codim2: list[tuple[float, float, str]] = []
    handles = []
    for k, (_name, ds) in enumerate(datasets.items()):
        p1, p2 = split_parameters(str(ds.attrs["parameters"]))
        x, y = np.asarray(ds[p1].values), np.asarray(ds[p2].values)
        observable = np.asarray(ds["stable_side"].values, dtype=bool)
        color = f"C{k % 10}"
        ax.plot(x, y, color=color, linewidth=0.8, linestyle=":")
        ax.plot(np.where(observable, x, np.nan), np.where(observable, y, np.nan),
                color=color, linewidth=1.8)
        handles.append(Line2D([], [], color=color, linewidth=1.8,
                              label=f"{kind_of_curve(ds)} curve, "
                                    f"{_motions_of(ds)}"))
        for c in range(ds.sizes.get("codim2", 0)):
            cx, cy = float(ds[f"codim2_{p1}"].values[c]), float(ds[f"codim2_{p2}"].values[c])
            ax.plot(cx, cy, "o", markerfacecolor="white", markeredgecolor="black", zorder=3)
            codim2.append((cx, cy, str(ds["codim2_label"].values[c])))
    names = codim2_legend([lab for _, _, lab in codim2])
    codim2 = [(cx, cy, codim2_name(lab)) for cx, cy, lab in codim2]
    handles[:0] = [Line2D([], [], color="0.2", linewidth=1.8, label="a stable motion changes"),
                   Line2D([], [], color="0.2", linewidth=0.8, linestyle=":",
                          label="no stable motion changes")]
    if codim2:
        handles.append(Line2D([], [], linestyle="none", marker="o", markerfacecolor="white",
                              markeredgecolor="black", label=f"codim-2 point:\n{names}"))
    if p1:
        first = next(iter(datasets.values()))
        ax.set_xlabel(axis_label(first, p1))
        ax.set_ylabel(axis_label(first, p2))
    legend_below(ax, handles)
    _finish(fig, plot, "Codim-1 curves")
    if codim2:
        from impactcont.plots.branches import label_specials

        label_specials(ax, codim2, zoom=False)  # one place, one label: no inset
    return fig


def draw_map(datasets: Mapping[str, xr.Dataset], plot: Any = None) -> Figure:
    """Number of stable physical N-1 motions (period N, one impact) on the grid of the map's
    two parameters ((omega, b), or those of its attribute ``parameters``), one panel per N;
    the map of one motion family: its regions (found, physical, stable physical) and seed
    (:func:`impactcont.plots.maps.multi_impact_map_diagram`)."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    from impactcont.dataset.maps import MULTI_MAP_KIND, map_parameters
    from impactcont.plots.branches import axis_label

    ds = next(iter(datasets.values()))
    if ds.attrs.get("impactcont_dataset") == MULTI_MAP_KIND:
        from impactcont.plots.maps import multi_impact_map_diagram

        width = _width(plot)
        fig = Figure(figsize=(width, 0.8 * width + 1.0), layout="constrained")
        multi_impact_map_diagram(ds, ax=fig.add_subplot(), title="")
        return _finish(fig, plot, f"The N={int(ds.attrs['N'])}, p={int(ds.attrs['impacts'])} "
                                  f"motion family ({ds.attrs['pattern']})")
    first, second = map_parameters(ds)
    Ns = [int(N) for N in np.asarray(ds["N"].values)]
    cols = min(len(Ns), 2)
    rows = -(-len(Ns) // cols)
    width = _width(plot)
    fig = Figure(figsize=(width, rows * (0.75 * width / cols + 0.3) + 0.5), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False).ravel())
    w, b = np.asarray(ds[first].values), np.asarray(ds[second].values)
    cmap = ListedColormap(["0.92", "tab:blue", "tab:orange"])
    norm = BoundaryNorm([-0.5, 0.5, 1.5, 2.5], cmap.N)
    mesh = None
    for ax, N in zip(axes, Ns, strict=False):
        n_stable = np.asarray(ds["n_stable"].sel(N=N).transpose(first, second).values,
                              dtype=float)
        exists = np.asarray(ds["exists"].sel(N=N).transpose(first, second).values, dtype=bool)
        mesh = ax.pcolormesh(w, b, n_stable.T, cmap=cmap, norm=norm, shading="nearest")
        ax.contour(w, b, exists.T.astype(float), levels=[0.5], colors="0.3",
                   linewidths=0.8)
        ax.set_title(f"$N = {N}$", fontsize="medium")
        ax.set_xlabel(axis_label(ds, first))
        ax.set_ylabel(axis_label(ds, second))
        ax.xaxis.set_major_locator(MaxNLocator(3 if width / cols < 3.0 else 6))
    for ax in axes[len(Ns):]:
        ax.set_axis_off()
    if mesh is not None:
        fig.colorbar(mesh, ax=list(axes[:len(Ns)]), ticks=[0, 1, 2],
                     label="stable motions")
    return _finish(fig, plot,
                   "Stable physical period-$N$ motions with 1 impact, dark line: existence "
                   "boundary")


#: The plot kind ``impactcont plot`` draws by default for each kind of file.
DEFAULT_KINDS = {"branches": "bifurcation_diagram", "orbits": "orbits",
                 "simulations": "simulation", "robust": "robust", "curves": "curves",
                 "maps": "map", "switches": "bifurcation_diagram",
                 "multi_impact": "bifurcation_diagram"}


class _Options:
    def __init__(self, **kw: Any) -> None:
        self.__dict__.update(kw)


def plot_file(path: str | os.PathLike, output: str | os.PathLike | None = None, *,
              kind: str | None = None, y: str | None = None, dpi: int = 150,
              width: float = WIDTH) -> list[Path]:
    """Draw the contents of a NetCDF file written by a scene run (or :func:`impactcont.save`).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    output : str or os.PathLike, optional
        PNG to write; default the file name with ``.png``. When branches
        continued in different parameters are drawn, one PNG per parameter is
        written, the parameter added to the name.
    kind : str, optional
        A plot kind that reads this file's section; default the section's
        first (e.g. ``bifurcation_diagram`` for branches).
    y : str, optional
        Variable on the vertical axis of a bifurcation diagram.
    dpi : int
        Resolution.
    width : float
        Figure width in inches, in :data:`WIDTH_RANGE` (3.5: a journal's column).

    Returns
    -------
    list of pathlib.Path
        The PNG files written.

    Raises
    ------
    ValueError
        The file is not an impactcont file, or ``kind`` does not read it.
    ParameterError
        ``dpi`` outside [10, 1200], ``width`` outside :data:`WIDTH_RANGE`, or a figure
        that would exceed :data:`MAX_PIXELS`.
    FileNotFoundError, NotADirectoryError, PermissionError
        The file does not exist, or the figure cannot be written where asked
        (checked before drawing; the message names the path).
    """
    from impactcont.scene.files import read_output
    from impactcont.scene.plugins import plot_kinds

    dpi = check_dpi(dpi)
    width = check_width(width)
    out = read_output(path)
    kinds = {k: v for k, v in plot_kinds().items() if out.kind in v.sections}
    if not kinds:
        raise ValueError(f"no plot kind draws {out.kind!r} files")
    chosen = kind or DEFAULT_KINDS.get(out.kind, next(iter(kinds)))
    if chosen not in kinds:
        raise ValueError(f"kind {chosen!r} does not draw {out.kind!r} files; allowed: "
                         f"{', '.join(kinds)}")
    draw = kinds[chosen].load_draw()
    target = Path(output) if output is not None else out.path.with_suffix(".png")
    check_output_file(target)  # before drawing
    groups: list[tuple[str, dict[str, xr.Dataset]]]
    if chosen == "bifurcation_diagram":
        by_parameter: dict[str, dict[str, xr.Dataset]] = {}
        for name, ds in out.datasets.items():
            by_parameter.setdefault(ds.attrs["parameter"], {})[name] = ds
        groups = list(by_parameter.items())
    elif not kinds[chosen].many:
        groups = [(name, {name: ds}) for name, ds in out.datasets.items()]
    else:
        groups = [("", dict(out.datasets))]
    written = []
    for suffix, datasets in groups:
        png = target if len(groups) == 1 else target.with_name(
            f"{target.stem}_{suffix}{target.suffix}")
        fig = draw(datasets, _Options(y=y, title=None, yscale=None, width=width))
        written.append(save_figure(fig, png, dpi))
        log.info("wrote %s", png)
    return written


def save_figure(fig: Figure, path: Path, dpi: int) -> Path:
    """Write a figure atomically (temporary file + :func:`os.replace`), PNG unless
    ``path`` names another format matplotlib writes (``.pdf``, ``.svg``, ...).

    Raises
    ------
    ParameterError
        ``dpi`` outside [10, 1200], or a figure of more than :data:`MAX_PIXELS` pixels at
        that ``dpi`` (named with the largest ``dpi`` the figure allows).
    """
    dpi = check_dpi(dpi)
    width, height = (float(x) for x in fig.get_size_inches())
    if width * height * dpi * dpi > MAX_PIXELS:
        largest = int((MAX_PIXELS / (width * height)) ** 0.5)
        raise ParameterError(f"dpi={dpi} draws this {width:.3g} x {height:.3g} inch figure on "
                             f"{width * dpi:.0f} x {height * dpi:.0f} pixels, more than "
                             f"{MAX_PIXELS:.0e}; allowed: dpi <= {largest} for it")
    path = Path(path)
    with atomic_output(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=path.suffix.lstrip(".").lower() or "png")
    return path

