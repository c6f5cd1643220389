"""The stability map of one N-p motion family (:func:`impactcont.multi_maps.multi_impact_map`).

Regions of the grid shaded (not found, found but not physical, physical and unstable,
stable and physical), the boundaries of the found region and of the stable physical
region drawn on top, the seed marked. Reads the dataset only; never calls ``plt.show``.
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

from impactcont.dataset.multi_maps import validate_multi_impact_map_dataset

__all__ = ["MULTI_MAP_REGIONS", "multi_impact_map_diagram", "multi_map_regions"]

logger = logging.getLogger(__name__)

#: Region codes of :func:`multi_map_regions`, with their legend text and shade.
MULTI_MAP_REGIONS: dict[int, tuple[str, str]] = {
    0: ("not found (family not reached)", "#ffffff"),
    1: ("found, not physical", "#e4e4e4"),
    2: ("physical, unstable", "#f6d7a7"),
    3: ("stable physical motion", "#8fc4e8"),
}

_BOUNDARIES = {"found": ("black", "-", "found region"),
               "stable_physical": ("tab:blue", "-", "stable physical region"),
               "physical": ("tab:green", "--", "physical region")}


def multi_map_regions(ds: xr.Dataset) -> xr.DataArray:
    """Region of every grid point of a :func:`~impactcont.multi_maps.multi_impact_map`.

    Returns
    -------
    xarray.DataArray of int, dims (parameter 0, parameter 1)
        0: not found; 1: found, not physical; 2: physical, unstable; 3: stable and
        physical.
    """
    validate_multi_impact_map_dataset(ds)
    found, physical, stable = (ds[k].astype(bool) for k in ("found", "physical", "stable"))
    code = xr.where(physical & stable, 3, xr.where(physical, 2, xr.where(found, 1, 0)))
    return code.rename("region")


def multi_impact_map_diagram(ds: xr.Dataset, *, ax: Axes | None = None,
                             boundaries: bool = True, legend: bool = True) -> Axes:
    """One panel: the map's regions shaded, their boundaries and the seed on top.

    Parameters
    ----------
    ds : xarray.Dataset
        A map of :func:`impactcont.multi_maps.multi_impact_map`.
    ax : matplotlib.axes.Axes, optional
    boundaries : bool
        Draw the boundaries of the found, physical and stable physical regions (the
        0.5 contour of each flag on the grid: within half a grid cell of where the
        flag changes).
    legend : bool

    Returns
    -------
    matplotlib.axes.Axes
    """
    code = multi_map_regions(ds)
    px, py = ds.attrs["parameters"].split(",")
    x, y = ds[px].values, ds[py].values
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5.6, 4.4), layout="constrained")
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
        for key, flag in flags.items():
            if flag.all() or not flag.any():
                continue
            color, style, text = _BOUNDARIES[key]
            ax.contour(x, y, flag.T.astype(float), levels=[0.5], colors=color,
                       linestyles=style, linewidths=1.2)
            handles.append(Line2D([], [], color=color, linestyle=style,
                                  label=f"boundary of the {text}"))
    seed = json.loads(ds.attrs["seed"])
    if px in seed and py in seed:
        ax.plot(seed[px], seed[py], marker="*", markersize=11, color="gold",
                markeredgecolor="black", linestyle="none")
        handles.append(Line2D([], [], marker="*", markersize=10, color="gold",
                              markeredgecolor="black", linestyle="none", label="seed"))
    ax.set_xlabel(px)
    ax.set_ylabel(py)
    kind = "symmetric " if ds.attrs.get("symmetric") else ""
    ax.set_title(f"{kind}{ds.attrs['N']}-{ds.attrs['impacts']} motion {ds.attrs['pattern']}")
    if legend:
        ax.legend(handles=handles, fontsize="x-small", loc="upper right", framealpha=0.85)
    logger.debug("multi-impact map diagram over (%s, %s)", px, py)
    return ax
