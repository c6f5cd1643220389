"""Bifurcation diagrams with one curve per impact: N-1 and N-p branches together.

:func:`impact_diagram` draws a per-impact quantity (impact velocity, phase,
flight time, gap) of every impact of every branch against the continued
parameter, styled by stability like
:func:`impactcont.plots.bifurcation_diagram`; an N-p branch contributes p
curves, an N-1 branch (no ``impact`` dimension) one. This is the picture a
brute-force simulator diagram (every impact velocity after the transient) is
compared with.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.lines import Line2D

from impactcont.dataset.schema import SPECIAL_LABELS, special_variable
from impactcont.plots.branches import (
    _borders_physical,
    _finish_diagram,
    _start_diagram,
    _stops,
    fixed_parameters,
    parameter_text,
)

__all__ = ["IMPACT_QUANTITIES", "impact_diagram", "impact_label"]

logger = logging.getLogger(__name__)

#: Per-impact variable -> the variable of an N-1 branch (one impact) holding it.
IMPACT_QUANTITIES: dict[str, str] = {
    "impact_velocity_k": "impact_velocity",
    "delta_k": "delta",
    "gap_min_k": "gap_min",
}


def _per_impact(ds: xr.Dataset, y: str) -> np.ndarray:
    """``(npoints, p)`` values of ``y`` (an N-1 branch gives one column)."""
    if y in ds.data_vars and ds[y].dims == ("point", "impact"):
        return np.asarray(ds[y].values, dtype=float)
    return np.asarray(ds[IMPACT_QUANTITIES[y]].values, dtype=float)[:, None]


def _special_per_impact(ds: xr.Dataset, y: str, values: np.ndarray, k: int) -> np.ndarray:
    name = special_variable(y)
    if name in ds.data_vars and ds[name].dims == ("special", "impact"):
        return np.asarray(ds[name].values[k], dtype=float)
    base = special_variable(IMPACT_QUANTITIES[y])
    if base in ds.data_vars:
        return np.array([float(ds[base].values[k])])
    return values[int(ds[special_variable("point")].values[k])]


def impact_label(ds: xr.Dataset, y: str) -> str:
    r"""The vertical axis of an impact diagram, in symbols: ``impact velocity $\dot{x}_1(T_k^-)$``.

    Between two stops the stored velocity is the speed towards the stop hit.
    """
    stops = _stops(ds)
    j = stops["mass"]
    if y == "impact_velocity_k":
        if "b_low" in stops:
            return rf"impact speed towards the stop hit $|\dot{{x}}_{j}(T_k^-)|$"
        return rf"impact velocity $\dot{{x}}_{j}(T_k^-)$"
    if y == "delta_k":
        return r"impact phase $\theta_k$ [rad]"
    return rf"minimum gap of flight $k$ (mass {j})"


def impact_diagram(datasets: Any, *, y: str = "impact_velocity_k", ax: Axes | None = None,
                   label_special: bool = False, specials: tuple[str, ...] = SPECIAL_LABELS,
                   names: bool = True, nonphysical: bool = True,
                   colors: Sequence[str] | None = None, title: str | None = None,
                   physical_range: bool = True, legend: str | None = "below",
                   zoom: bool = True) -> Axes:
    """Draw every impact of every branch against the continued parameter.

    Styled as :func:`impactcont.plots.bifurcation_diagram`: stable physical
    motions solid, unstable dashed, non-physical faint and dotted
    (:data:`~impactcont.plots.SEGMENT_STYLES`); one colour per branch, its p
    impacts p curves of that colour; special points marked on every impact
    (:data:`~impactcont.plots.SPECIAL_MARKERS`) in the colour of their branch,
    small and grey (:data:`~impactcont.plots.branches.NONPHYSICAL_GREY`) on
    non-physical motions; every mark named in the legend, the title naming
    the motions and the system.

    Parameters
    ----------
    datasets : Dataset, sequence or mapping of Datasets, or DataTree
        N-1 and N-p branch datasets, all continued in the same parameter.
    y : str
        A per-impact quantity, one of :data:`IMPACT_QUANTITIES`.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new pyplot figure by default. With ``legend="below"``
        its figure should use the constrained layout (the default figure does).
    label_special : bool
        Write each special point's label next to its markers (placed clear of
        the others; crowded ones in a zoomed inset, see ``zoom``).
    specials : tuple of str
        Which special points to mark.
    names : bool
        Add the branch names (mapping keys / groups) to the legend.
    nonphysical : bool
        Draw the non-physical parts of the branches (faint, dotted) and their
        special points.
    colors : sequence of str, optional
        One matplotlib colour per branch (cycled); default ``C0 .. C9``.
    title : str, optional
        Axes title; by default the motions and the system drawn
        (``Period-$N$ motions with $p$ impacts, $b = 0$, $R = 0.6$, ...``), ``""`` for none.
    physical_range : bool
        Fit the vertical range to the physical motions (default), clipping
        non-physical ones at the frame; False fits everything drawn.
    legend : {"below", "right", "inside", None}
        Under the axes (default), outside on the right, inside the axes, or none.
    zoom : bool
        With ``label_special``, draw crowded special points again in an inset.

    Returns
    -------
    matplotlib.axes.Axes
        As :func:`impactcont.plots.bifurcation_diagram`: ``ax`` or the new figure's, with
        the zoomed inset, if one was drawn, as its child axes (``ax.child_axes``).

    Raises
    ------
    ValueError
        ``y``, ``specials`` or ``legend`` is not allowed, or the branches are
        continued in different parameters.
    """
    if y not in IMPACT_QUANTITIES:
        raise ValueError(f"y must be one of {sorted(IMPACT_QUANTITIES)}; got {y!r}")
    unknown = sorted(set(specials) - set(SPECIAL_LABELS))
    if unknown:
        raise ValueError(f"specials must be a subset of {SPECIAL_LABELS}; got unknown {unknown}")
    drawing = _start_diagram(datasets, ax, legend)
    ax, branches, differing = drawing.ax, drawing.branches, drawing.differing
    for b, (name, ds) in enumerate(branches):
        parameter = ds.attrs["parameter"]
        x = np.asarray(ds[parameter].values, dtype=float)
        values = _per_impact(ds, y)
        color = colors[b % len(colors)] if colors else f"C{b % 10}"
        drawn, physical = drawing.draw_curves(ds, x, values, color, nonphysical)
        about = ", ".join([f"{int(ds.attrs['N'])}-{values.shape[1]}",
                           *([parameter_text(fixed_parameters([ds]), differing)]
                             if differing else [])])
        text = f"{name} ({about})" if name and names and about not in name else \
            name if name and names else about
        if drawn:  # a legend names what is drawn: not a branch without physical motions
            drawing.branch_handles.append(Line2D([], [], color=color, linewidth=1.6, label=text))
        labels = np.asarray(ds[special_variable("label")].values).tolist()
        xs = np.asarray(ds[special_variable(parameter)].values, dtype=float)
        for k, label in enumerate(labels):
            shown = _borders_physical(ds, physical, k)
            if label not in specials or not (shown or nonphysical):
                continue
            for yk in _special_per_impact(ds, y, values, k):
                if np.isfinite(yk) and np.isfinite(xs[k]):
                    drawing.specials.append((float(xs[k]), float(yk), str(label), color, shown))
    _finish_diagram(drawing, impact_label(branches[0][1], y), physical_range=physical_range,
                    legend=legend, title=title, label_special=label_special, zoom=zoom,
                    nest=False)
    logger.debug("impact diagram: %d branch(es), y=%s", len(branches), y)
    return ax
