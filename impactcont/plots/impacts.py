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
    SEGMENT_STYLES,
    SPECIAL_MARKERS,
    _branches,
    _new_axes,
    stability_segments,
)

__all__ = ["IMPACT_QUANTITIES", "impact_diagram"]

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


def impact_diagram(datasets: Any, *, y: str = "impact_velocity_k", ax: Axes | None = None,
                   label_special: bool = False, specials: tuple[str, ...] = SPECIAL_LABELS,
                   names: bool = True, nonphysical: bool = True,
                   colors: Sequence[str] | None = None) -> Axes:
    """Draw every impact of every branch against the continued parameter.

    Parameters
    ----------
    datasets : Dataset, sequence or mapping of Datasets, or DataTree
        N-1 and N-p branch datasets, all continued in the same parameter.
    y : str
        A per-impact quantity, one of :data:`IMPACT_QUANTITIES`.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new pyplot figure by default.
    label_special : bool
        Write each special point's label next to its markers.
    specials : tuple of str
        Which special points to mark.
    names : bool
        Add the branch names (mapping keys / groups) to the legend.
    nonphysical : bool
        Draw the non-physical parts of the branches (faint, dotted).
    colors : sequence of str, optional
        One matplotlib colour per branch (cycled); default ``C0 .. C9``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    if y not in IMPACT_QUANTITIES:
        raise ValueError(f"y must be one of {sorted(IMPACT_QUANTITIES)}; got {y!r}")
    unknown = sorted(set(specials) - set(SPECIAL_LABELS))
    if unknown:
        raise ValueError(f"specials must be a subset of {SPECIAL_LABELS}; got unknown {unknown}")
    branches = _branches(datasets, one_parameter=True)
    if ax is None:
        ax = _new_axes()
    kinds_seen: set[str] = set()
    labels_seen: set[str] = set()
    handles = []
    for b, (name, ds) in enumerate(branches):
        parameter = ds.attrs["parameter"]
        x = np.asarray(ds[parameter].values, dtype=float)
        values = _per_impact(ds, y)
        color = colors[b % len(colors)] if colors else f"C{b % 10}"
        for kind, sl in stability_segments(ds):
            if kind == "non-physical" and not nonphysical:
                continue
            ax.plot(x[sl], values[sl], color=color, **SEGMENT_STYLES[kind])
            kinds_seen.add(kind)
        if name and names:
            p = values.shape[1]
            kind = f"{ds.attrs['N']}-{p}"
            text = name if kind in name else f"{name} ({kind})"
            handles.append(Line2D([], [], color=color, label=text))
        labels = np.asarray(ds[special_variable("label")].values).tolist()
        xs = np.asarray(ds[special_variable(parameter)].values, dtype=float)
        for k, label in enumerate(labels):
            if label not in specials:
                continue
            ys = _special_per_impact(ds, y, values, k)
            ax.scatter(np.full(ys.size, xs[k]), ys, marker=SPECIAL_MARKERS[label], s=30,
                       facecolors="white", edgecolors="black", linewidths=0.9, zorder=3)
            labels_seen.add(label)
            if label_special:
                ax.annotate(label, (xs[k], float(np.max(ys))), xytext=(3, 3),
                            textcoords="offset points", fontsize="x-small")
    first = branches[0][1]
    ax.set_xlabel(first[first.attrs["parameter"]].attrs.get("long_name",
                                                             first.attrs["parameter"])
                  + f" ({first.attrs['parameter']})")
    ax.set_ylabel(y)
    legend = [Line2D([], [], color="0.2", label=kind, **SEGMENT_STYLES[kind])
              for kind in SEGMENT_STYLES if kind in kinds_seen]
    legend += [Line2D([], [], linestyle="none", marker=SPECIAL_MARKERS[label],
                      markerfacecolor="white", markeredgecolor="black", label=label)
               for label in SPECIAL_LABELS if label in labels_seen]
    ax.legend(handles=legend + handles, fontsize="x-small", loc="best")
    logger.debug("impact diagram: %d branch(es), y=%s", len(branches), y)
    return ax
