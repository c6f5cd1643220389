"""The stability map of one N-p motion family (:func:`~impactcont.multi_impact_map`).

Regions of the grid shaded (not found, found but not physical, physical and unstable,
stable and physical, found with its interior contact not checked), the boundaries of the
found region and of the stable physical region drawn on top, the seed marked. Reads the
dataset only; never calls ``plt.show``.
"""

from __future__ import annotations

import json
import logging
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from impactcont.dataset.attributes import split_parameters
from impactcont.dataset.multi_maps import validate_multi_impact_map_dataset
from impactcont.plots.branches import (
    _stops,
    axis_label,
    fit_text,
    legend_below,
    motion_text,
    parameter_text,
)

__all__ = ["MULTI_MAP_BOUNDARIES", "MULTI_MAP_REGIONS", "multi_impact_map_diagram",
           "multi_map_regions", "multi_map_title"]

logger = logging.getLogger(__name__)

#: Region codes of :func:`multi_map_regions`, with their legend text and shade.
MULTI_MAP_REGIONS: dict[int, tuple[str, str]] = {
    0: ("not found (family not reached)", "#ffffff"),
    1: ("found, not physical", "#e4e4e4"),
    2: ("physical, unstable", "#f6d7a7"),
    3: ("stable physical motion", "#8fc4e8"),
    4: ("found, interior contact not checked", "#d8c6e6"),
}

#: Colour and line style of the boundary of each region, and its legend text.
MULTI_MAP_BOUNDARIES: dict[str, tuple[str, str, str]] = {
    "found": ("black", "-", "found region"),
    "physical": ("tab:red", "--", "physical region"),
    "stable_physical": ("navy", "-", "stable physical region"),
}
_SEED = {"marker": "*", "markersize": 10.0, "color": "gold", "markeredgecolor": "black",
         "linestyle": "none"}


def multi_map_regions(ds: xr.Dataset) -> xr.DataArray:
    """Region of every grid point of a :func:`~impactcont.analysis.multi_maps.multi_impact_map`.

    Returns
    -------
    xarray.DataArray of int, dims (parameter 0, parameter 1)
        0: not found; 1: found, not physical; 2: physical, unstable; 3: stable and
        physical; 4: found, but its interior contact was not searched
        (``contact_checked`` False: ``checks=False``, or a constant force pushing a free
        mode), so whether it is physical is not known (it is never reported physical).
    """
    validate_multi_impact_map_dataset(ds)
    found, physical, stable, checked = (ds[k].astype(bool) for k in (
        "found", "physical", "stable", "contact_checked"))
    code = xr.where(physical & stable, 3, xr.where(physical, 2, xr.where(
        found & ~checked, 4, xr.where(found, 1, 0))))
    return code.rename("region")


def multi_map_title(ds: xr.Dataset) -> str:
    """The motion and the system of a map: ``Period-1 symmetric motions with 2 impacts, ...``.

    The parameters held fixed (those not on the map's axes) in mathtext, and
    the stops: a mirrored lower stop moves with ``b``.
    """
    axes = set(split_parameters(str(ds.attrs["parameters"])))
    osc = json.loads(ds.attrs["oscillator"])
    stops = _stops(ds)
    mirror = bool((osc.get("stops") or {}).get("mirror"))
    values = {k: float(osc[k]) for k in ("b", "R", "omega", "eta", "alpha", "beta", "F0")
              if isinstance(osc.get(k), (int, float)) and k not in axes}
    if not mirror:
        values.update({k: stops[k] for k in ("b_low", "R_low") if k in stops})
    text = motion_text([ds], adjective="symmetric" if ds.attrs.get("symmetric") else "")
    where = parameter_text(values, ("b", "b_low", "R", "R_low", "omega", "eta", "alpha",
                                    "beta", "F0"))
    parts = [text, *([where] if where else [])]
    if mirror:
        parts.append(rf"mirror stops $x_{stops['mass']} = \pm b$")
    return ", ".join(parts)


def _boundary(x: np.ndarray, y: np.ndarray, flag: np.ndarray) -> list[np.ndarray]:
    """The 0.5 contour of ``flag`` (dims x, y) as polylines ``(m, 2)`` in (x, y)."""
    from contourpy import contour_generator

    lines = contour_generator(x, y, flag.T.astype(float), line_type="Separate").lines(0.5)
    return [np.asarray(line, dtype=float) for line in lines]


def multi_impact_map_diagram(ds: xr.Dataset, *, ax: Axes | None = None,
                             boundaries: bool = True, legend: bool = True,
                             title: str | None = None) -> Axes:
    """One panel: the map's regions shaded, their boundaries and the seed on top.

    Every shade, boundary and the seed are named in the legend under the axes
    (:data:`MULTI_MAP_REGIONS`, :data:`MULTI_MAP_BOUNDARIES`); the axes are
    named in symbols and the title names the motion, the system and the stops
    (:func:`multi_map_title`).

    Parameters
    ----------
    ds : xarray.Dataset
        A map of :func:`impactcont.analysis.multi_maps.multi_impact_map`.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new pyplot figure by default. With ``legend`` its
        figure should use the constrained layout (the default figure does).
    boundaries : bool
        Draw the boundaries of the found, physical and stable physical regions (the
        0.5 contour of each flag on the grid: within half a grid cell of where the
        flag changes).
    legend : bool
        Draw the legend (under the axes).
    title : str, optional
        Axes title; by default :func:`multi_map_title`, ``""`` for none.

    Returns
    -------
    matplotlib.axes.Axes
    """
    code = multi_map_regions(ds)
    px, py = split_parameters(str(ds.attrs["parameters"]))
    x, y = ds[px].values, ds[py].values
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5.0, 5.6), layout="constrained")
    cmap = ListedColormap([MULTI_MAP_REGIONS[k][1] for k in sorted(MULTI_MAP_REGIONS)])
    ax.pcolormesh(x, y, code.values.T, cmap=cmap, vmin=-0.5,
                  vmax=len(MULTI_MAP_REGIONS) - 0.5, shading="nearest", rasterized=True)
    present = set(np.unique(code.values).tolist())
    handles: list[Any] = [Patch(facecolor=MULTI_MAP_REGIONS[k][1], edgecolor="0.6",
                                label=MULTI_MAP_REGIONS[k][0])
                          for k in sorted(MULTI_MAP_REGIONS) if k in present]
    if boundaries and x.size > 1 and y.size > 1:
        flags = {"found": ds["found"].values, "physical": ds["physical"].values,
                 "stable_physical": ds["physical"].values & ds["stable"].values}
        for order, (key, flag) in enumerate(flags.items()):
            if flag.all() or not flag.any():
                continue
            color, style, text = MULTI_MAP_BOUNDARIES[key]
            for line in _boundary(x, y, np.asarray(flag, dtype=bool)):  # where they coincide,
                ax.plot(line[:, 0], line[:, 1], color=color, linestyle=style,  # found on top
                        linewidth=1.2, zorder=2.3 - 0.1 * order)
            handles.append(Line2D([], [], color=color, linestyle=style, linewidth=1.2,
                                  label=f"boundary of the {text}"))
    seed = json.loads(ds.attrs["seed"])
    if px in seed and py in seed:
        ax.plot(seed[px], seed[py], zorder=4, **_SEED)
        handles.append(Line2D([], [], label="seed", **_SEED))
    ax.set_xlabel(axis_label(ds, px))
    ax.set_ylabel(axis_label(ds, py))
    if legend:
        legend_below(ax, handles)
    title = multi_map_title(ds) if title is None else title
    if title:
        ax.set_title(title, fontsize="medium")
        ax.figure.draw_without_rendering()
        fit_text(ax.title)
    logger.debug("multi-impact map diagram over (%s, %s)", px, py)
    return ax
