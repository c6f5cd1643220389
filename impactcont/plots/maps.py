"""Two-parameter diagrams: map regions shaded per N, continued curves drawn on top.

The functions read map datasets (:func:`impactcont.maps.stability_map`) and
curve datasets (:func:`impactcont.curves.curve`); they never compute orbits and
never call ``plt.show``.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from impactcont.dataset.curves import (
    codim2_variable,
    validate_curve_dataset,
    validate_map_dataset,
)
from impactcont.plots.labels import place_labels

__all__ = ["CURVE_STYLES", "REGIONS", "region_codes", "two_parameter_diagram",
           "two_parameter_figure"]

logger = logging.getLogger(__name__)

#: Colour and line style of each kind of curve.
CURVE_STYLES: dict[str, dict[str, Any]] = {
    "SN": {"color": "black", "linestyle": "-"},
    "PD": {"color": "tab:red", "linestyle": "-"},
    "NS": {"color": "tab:purple", "linestyle": "-"},
    "GR": {"color": "tab:green", "linestyle": "-"},
    "ZV": {"color": "tab:blue", "linestyle": "--"},
}

#: Region codes of :func:`region_codes`, with their legend text and shade.
REGIONS: dict[int, tuple[str, str]] = {
    0: ("no N-1 motion", "#ffffff"),
    1: ("motions exist, none physical", "#e4e4e4"),
    2: ("physical, unstable", "#f6d7a7"),
    3: ("stable physical motion", "#8fc4e8"),
}


def region_codes(map_ds: xr.Dataset, N: int) -> xr.DataArray:
    """Region of every (omega, b) grid point for one N.

    Returns
    -------
    xarray.DataArray of int, dims (omega, b)
        0: no motion (``c^2 + s^2 < b^2``); 1: motions exist, none physical;
        2: a physical motion, none stable; 3: a stable physical motion.
    """
    validate_map_dataset(map_ds)
    if N not in map_ds["N"].values:
        raise ValueError(f"N must be one of the map's {map_ds['N'].values.tolist()}; got {N!r}")
    m = map_ds.sel(N=N)
    code = xr.where(m["n_stable"] > 0, 3, xr.where(m["n_physical"] > 0, 2,
                                                   xr.where(m["exists"], 1, 0)))
    return code.rename("region")


def _new_axes(nrows: int = 1, ncols: int = 1) -> Any:
    import matplotlib.pyplot as plt

    _, axes = plt.subplots(nrows, ncols, figsize=(5.2 * ncols, 4.2 * nrows),
                           layout="constrained", squeeze=False)
    return axes


def _curves(curves: Any) -> list[xr.Dataset]:
    if curves is None:
        return []
    if isinstance(curves, xr.Dataset):
        items: Iterable[Any] = [curves]
    elif isinstance(curves, xr.DataTree):
        items = [node.to_dataset(inherit=False) for node in curves.subtree if node.has_data]
    elif isinstance(curves, Mapping):
        items = curves.values()
    elif isinstance(curves, Sequence) and not isinstance(curves, str):
        items = curves
    else:
        raise TypeError(f"curves must be a curve Dataset, a sequence or mapping of them or a "
                        f"DataTree; got {type(curves).__name__}")
    return [validate_curve_dataset(c) for c in items]


def _segments(mask: np.ndarray) -> list[slice]:
    """Runs of True in ``mask`` (each extended by one point to join the next run)."""
    out, start = [], None
    for i, flag in enumerate(mask):
        if flag and start is None:
            start = i
        if not flag and start is not None:
            out.append(slice(start, min(i + 1, mask.size)))
            start = None
    if start is not None:
        out.append(slice(start, mask.size))
    return out


def two_parameter_diagram(map_ds: xr.Dataset | None = None, curves: Any = None, *,
                          N: int | None = None, ax: Axes | None = None,
                          label_curves: bool = True, label_codim2: bool = True,
                          legend: bool = True) -> Axes:
    """One panel: the regions of one N shaded, the curves of that N (and ZV) on top.

    Curves are drawn bold where crossing them changes an observable stable
    motion (``stable_side``), thin where the motion is physical but unstable
    on both sides, and dotted where it is not physical. Codim-2 points are
    stars, gold and labelled where the motion is physical, small and grey
    where it is not.

    Parameters
    ----------
    map_ds : xarray.Dataset, optional
        A map; its regions for ``N`` are shaded (:func:`region_codes`).
    curves : Dataset, sequence, mapping or DataTree of curve datasets, optional
        Curves in (omega, b); those with another ``N`` are skipped, except ZV
        curves, which do not depend on N.
    N : int, optional
        Which N; default the map's first (or the first curve's).
    ax : matplotlib.axes.Axes, optional
    label_curves, label_codim2 : bool
        Write the kind next to each curve / the label next to each codim-2 point.
    legend : bool
        Draw the legend.

    Returns
    -------
    matplotlib.axes.Axes
    """
    curve_list = _curves(curves)
    if map_ds is None and not curve_list:
        raise ValueError("give map_ds or curves (or both); got neither")
    if N is None:
        N = int(map_ds["N"].values[0]) if map_ds is not None else int(curve_list[0].attrs["N"])
    if ax is None:
        ax = _new_axes()[0, 0]
    handles: list[Any] = []
    if map_ds is not None:
        code = region_codes(map_ds, N)
        cmap = ListedColormap([REGIONS[k][1] for k in sorted(REGIONS)])
        ax.pcolormesh(map_ds["omega"].values, map_ds["b"].values, code.values.T, cmap=cmap,
                      vmin=-0.5, vmax=len(REGIONS) - 0.5, shading="nearest", rasterized=True)
        present = set(np.unique(code.values).tolist())
        handles += [Patch(facecolor=REGIONS[k][1], edgecolor="0.6", label=REGIONS[k][0])
                    for k in sorted(REGIONS) if k in present]
    kinds_seen = []
    codim2_labels: dict[tuple[float, float], str] = {}  # one label per place
    for c in curve_list:
        kind = c.attrs["kind"]
        if kind != "ZV" and int(c.attrs["N"]) != N:
            continue
        px, py = str(c.attrs["parameters"]).split(",")
        if {px, py} != {"omega", "b"}:
            raise ValueError(f"two_parameter_diagram draws curves in (omega, b); got a curve in "
                             f"({px}, {py})")
        x, y = c["omega"].values, c["b"].values
        style = CURVE_STYLES[kind]
        physical = c["physical"].values.astype(bool)
        strong = c["stable_side"].values.astype(bool)
        ax.plot(x, y, color=style["color"], linestyle=":", linewidth=0.8, alpha=0.6)
        for sl in _segments(physical):
            ax.plot(x[sl], y[sl], color=style["color"], linestyle=style["linestyle"],
                    linewidth=1.0)
        for sl in _segments(strong):
            ax.plot(x[sl], y[sl], color=style["color"], linestyle=style["linestyle"],
                    linewidth=2.2)
        if kind not in kinds_seen:
            kinds_seen.append(kind)
        if label_curves and x.size:
            pick = np.flatnonzero(physical)
            k = int(pick[pick.size // 2]) if pick.size else x.size // 2
            ax.annotate(kind, (x[k], y[k]), xytext=(3, 3), textcoords="offset points",
                        color=style["color"], fontsize="small", fontweight="bold")
        labels = c[codim2_variable("label")].values
        if labels.size:
            cx, cy = c[codim2_variable("omega")].values, c[codim2_variable("b")].values
            seen = physical[c[codim2_variable("point")].values]
            ax.scatter(cx[seen], cy[seen], marker="*", s=70, color="gold", edgecolors="black",
                       linewidths=0.6, zorder=4)
            ax.scatter(cx[~seen], cy[~seen], marker="*", s=25, color="0.6", zorder=3)
            if label_codim2:  # only where the motion is physical: the others crowd the panel
                for lab, xx, yy in zip(labels[seen], cx[seen], cy[seen], strict=True):
                    # the same point found from both curves (PD+SN and SN+PD): one label
                    codim2_labels.setdefault((round(float(xx), 6), round(float(yy), 6)),
                                             str(lab))
    handles += [Line2D([], [], linewidth=2.0, label=kind, **CURVE_STYLES[kind])
                for kind in kinds_seen]
    if any(c[codim2_variable("label")].size for c in curve_list):
        handles.append(Line2D([], [], linestyle="none", marker="*", markerfacecolor="gold",
                              markeredgecolor="black", markersize=9, label="codim-2"))
    ax.set_xlabel("forcing frequency omega")
    ax.set_ylabel("gap b")
    ax.set_title(f"N = {N}")
    if map_ds is not None:
        ax.set_xlim(float(map_ds["omega"].min()), float(map_ds["omega"].max()))
        ax.set_ylim(float(map_ds["b"].min()), float(map_ds["b"].max()))
    if legend:
        ax.legend(handles=handles, fontsize="x-small", loc="upper right", framealpha=0.85)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    inside = {xy: t for xy, t in codim2_labels.items()
              if x0 <= xy[0] <= x1 and y0 <= xy[1] <= y1}
    place_labels(ax, list(inside), list(inside.values()), fontsize="x-small")
    logger.debug("two-parameter diagram N=%d: %d curve(s)", N, len(curve_list))
    return ax


def two_parameter_figure(map_ds: xr.Dataset, curves: Any = None, *, ncols: int = 2) -> Any:
    """One :func:`two_parameter_diagram` panel per N of the map; returns the Figure."""
    validate_map_dataset(map_ds)
    Ns = [int(k) for k in map_ds["N"].values]
    nrows = -(-len(Ns) // ncols)
    axes = _new_axes(nrows, min(ncols, len(Ns)))
    for i, N in enumerate(Ns):
        two_parameter_diagram(map_ds, curves, N=N, ax=axes.flat[i], legend=i == 0)
    for j in range(len(Ns), axes.size):
        axes.flat[j].set_visible(False)
    return axes.flat[0].figure
