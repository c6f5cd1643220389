"""Bifurcation diagrams and multiplier plots of continued branches.

The functions read branch datasets (see :mod:`impactcont.dataset`) and never
compute orbits. They draw on the Axes given, or on a new figure, and return
the Axes; they never call ``plt.show`` so they work with any backend (Agg).
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.lines import Line2D

from impactcont.dataset.schema import (
    SPECIAL_LABELS,
    special_variable,
    validate_branch_dataset,
)

__all__ = ["SEGMENT_STYLES", "SPECIAL_MARKERS", "bifurcation_diagram", "multipliers_plot",
           "stability_segments"]

logger = logging.getLogger(__name__)

#: Line style of each kind of segment: stable and physical, unstable and
#: physical, not physical (whatever the stability).
SEGMENT_STYLES: dict[str, dict[str, Any]] = {
    "stable": {"linestyle": "-", "linewidth": 1.6, "alpha": 1.0},
    "unstable": {"linestyle": "--", "linewidth": 1.2, "alpha": 1.0},
    "non-physical": {"linestyle": ":", "linewidth": 0.8, "alpha": 0.25},
}

#: Marker of each special-point label.
SPECIAL_MARKERS: dict[str, str] = {"SN": "o", "PD": "s", "NS": "D", "GR": "^", "ZV": "v"}

_KINDS = tuple(SEGMENT_STYLES)


def _new_axes(ncols: int = 1) -> Any:
    # pyplot so that notebooks display the figure; nothing here calls show().
    import matplotlib.pyplot as plt

    _, axes = plt.subplots(1, ncols, figsize=(5.0 * ncols, 4.0), layout="constrained")
    return axes


def _branches(datasets: Any) -> list[tuple[str, xr.Dataset]]:
    """``(name, dataset)`` pairs from a Dataset, a sequence, a mapping or a DataTree."""
    if isinstance(datasets, xr.Dataset):
        items: Iterable[tuple[str, Any]] = [("", datasets)]
    elif isinstance(datasets, xr.DataTree):
        items = [(node.path.strip("/") or node.name or "", node.to_dataset(inherit=False))
                 for node in datasets.subtree if node.has_data]
    elif isinstance(datasets, Mapping):
        items = [(str(k), v) for k, v in datasets.items()]
    elif isinstance(datasets, Sequence) and not isinstance(datasets, str):
        items = [("", v) for v in datasets]
    else:
        raise TypeError(f"datasets must be a branch Dataset, a sequence or mapping of them, or "
                        f"a DataTree; got {type(datasets).__name__}")
    out = []
    for name, ds in items:
        if not isinstance(ds, xr.Dataset):
            raise TypeError(f"datasets must hold xarray.Dataset branches; got "
                            f"{type(ds).__name__} for {name!r}")
        out.append((name, validate_branch_dataset(ds)))
    if not out:
        raise ValueError("datasets holds no branch dataset")
    return out


def stability_segments(ds: xr.Dataset) -> list[tuple[str, slice]]:
    """Split a branch into runs of one kind: stable, unstable or non-physical.

    Parameters
    ----------
    ds : xarray.Dataset
        A branch dataset.

    Returns
    -------
    list of (str, slice)
        ``(kind, points)``: each run of consecutive points of one kind, its
        slice extended by one point into the next run so the drawn segments
        join; runs never join across two connected components of the branch
        (variable ``connected_component``). ``kind`` is a key of :data:`SEGMENT_STYLES`.
    """
    physical = np.asarray(ds["physical"].values, dtype=bool)
    stable = np.asarray(ds["stable"].values, dtype=bool)
    code = np.where(~physical, 2, np.where(stable, 0, 1))
    npoints = code.size
    part = (np.asarray(ds["connected_component"].values) if "connected_component" in ds
            else np.zeros(npoints, dtype=int))
    new_part = np.diff(part) != 0
    starts = np.concatenate([[0], np.flatnonzero((np.diff(code) != 0) | new_part) + 1])
    ends = np.concatenate([starts[1:], [npoints]])
    return [(_KINDS[code[s]], slice(int(s), int(e + 1 if e < npoints and not new_part[e - 1]
                                                else e)))
            for s, e in zip(starts, ends, strict=True)]


def _label(ds: xr.Dataset, name: str) -> str:
    attrs = ds[name].attrs
    text = f"{attrs.get('long_name', name)} ({name})" if attrs.get("long_name") else name
    units = attrs.get("units")
    return f"{text} [{units}]" if units and units != "1" else text


def _y_variable(ds: xr.Dataset, y: Any) -> str:
    if not isinstance(y, str) or y not in ds.data_vars or ds[y].dims != ("point",) \
            or ds[y].dtype.kind not in "iuf":
        allowed = [k for k, v in ds.data_vars.items()
                   if v.dims == ("point",) and v.dtype.kind in "iuf"]
        raise ValueError(f"y must name a real 1-D variable on 'point'; got {y!r}; "
                         f"allowed: {allowed}")
    return y


def _special_xy(ds: xr.Dataset, x: np.ndarray, y: np.ndarray, yname: str, k: int
                ) -> tuple[float, float]:
    """Where to draw special point ``k``: on the drawn polyline, at its parameter value."""
    parameter = ds.attrs["parameter"]
    xs = float(ds[special_variable(parameter)].values[k])
    exact = special_variable(yname)
    if exact in ds.data_vars and ds[exact].dims == ("special",):
        return xs, float(ds[exact].values[k])
    p = int(ds[special_variable("point")].values[k])
    for i, j in ((p - 1, p), (p, p + 1)):
        if i >= 0 and j < x.size and min(x[i], x[j]) <= xs <= max(x[i], x[j]) and x[i] != x[j]:
            t = (xs - x[i]) / (x[j] - x[i])
            return xs, float(y[i] + t * (y[j] - y[i]))
    # A fold in the parameter (SN) is not bracketed in x: use the nearest point.
    return float(x[p]), float(y[p])


def bifurcation_diagram(datasets: Any, *, y: str = "impact_velocity", ax: Axes | None = None,
                        label_special: bool = True) -> Axes:
    """Draw branches against their continued parameter, styled by stability.

    Stable physical motions are solid, unstable physical ones dashed and
    non-physical ones faint and dotted (:data:`SEGMENT_STYLES`); the line is
    split wherever the kind changes. Special points get one marker per label
    (:data:`SPECIAL_MARKERS`) and, optionally, a text label.

    Parameters
    ----------
    datasets : Dataset, sequence or mapping of Datasets, or DataTree
        Branch datasets, all continued in the same parameter.
    y : str, optional
        Name of a real variable on ``point`` (``impact_velocity``, ``delta``,
        ``gap_min``, ``spectral_radius``, ...).
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new pyplot figure by default.
    label_special : bool, optional
        Write each special point's label next to its marker.

    Returns
    -------
    matplotlib.axes.Axes
    """
    branches = _branches(datasets)
    parameters = {ds.attrs["parameter"] for _, ds in branches}
    if len(parameters) > 1:
        raise ValueError(f"datasets must all be continued in one parameter; got "
                         f"{sorted(parameters)}")
    if ax is None:
        ax = _new_axes()
    kinds_seen: set[str] = set()
    labels_seen: set[str] = set()
    branch_handles = []
    for b, (name, ds) in enumerate(branches):
        yname = _y_variable(ds, y)
        parameter = ds.attrs["parameter"]
        x = np.asarray(ds[parameter].values, dtype=float)
        yv = np.asarray(ds[yname].values, dtype=float)
        color = f"C{b % 10}"
        for kind, sl in stability_segments(ds):
            ax.plot(x[sl], yv[sl], color=color, **SEGMENT_STYLES[kind])
            kinds_seen.add(kind)
        if name:
            branch_handles.append(Line2D([], [], color=color, label=name))
        labels = np.asarray(ds[special_variable("label")].values).tolist()
        for label in SPECIAL_LABELS:
            ks = [k for k, lab in enumerate(labels) if lab == label]
            if not ks:
                continue
            pts = np.array([_special_xy(ds, x, yv, yname, k) for k in ks])
            ax.scatter(pts[:, 0], pts[:, 1], marker=SPECIAL_MARKERS[label], s=36,
                       facecolors="white", edgecolors="black", linewidths=1.0, zorder=3)
            labels_seen.add(label)
            if label_special:
                for px, py in pts:
                    ax.annotate(label, (px, py), xytext=(4, 4), textcoords="offset points",
                                fontsize="small")
    first = branches[0][1]
    ax.set_xlabel(_label(first, first.attrs["parameter"]))
    ax.set_ylabel(_label(first, y))
    handles = [Line2D([], [], color="0.2", label=kind, **SEGMENT_STYLES[kind])
               for kind in _KINDS if kind in kinds_seen]
    handles += [Line2D([], [], linestyle="none", marker=SPECIAL_MARKERS[label],
                       markerfacecolor="white", markeredgecolor="black", label=label)
                for label in SPECIAL_LABELS if label in labels_seen]
    ax.legend(handles=handles + branch_handles, fontsize="small", loc="best")
    logger.debug("bifurcation diagram: %d branch(es), y=%s", len(branches), y)
    return ax


def multipliers_plot(ds: xr.Dataset, *, ax: Sequence[Axes] | None = None,
                     yscale: str = "linear", label_special: bool = True
                     ) -> tuple[Axes, Axes]:
    """Multipliers of a branch: moduli against the parameter, and the complex plane.

    Left: ``|multipliers|`` of every point (dots coloured by the parameter),
    the spectral radius (line) and the stability boundary ``|mu| = 1``. Right:
    the multipliers in the complex plane with the unit circle, coloured by the
    parameter; special points are marked with :data:`SPECIAL_MARKERS`.

    Parameters
    ----------
    ds : xarray.Dataset
        One branch dataset.
    ax : pair of matplotlib.axes.Axes, optional
        Where to draw; a new figure with two panels by default.
    yscale : {"linear", "log"}, optional
        Scale of the moduli axis.
    label_special : bool, optional
        Mark special points with a vertical line and their label on the left.

    Returns
    -------
    (Axes, Axes)
        The moduli panel and the complex-plane panel.
    """
    validate_branch_dataset(ds)
    if yscale not in ("linear", "log"):
        raise ValueError(f"yscale must be 'linear' or 'log'; got {yscale!r}")
    if ax is None:
        ax_abs, ax_c = _new_axes(2)
    else:
        if isinstance(ax, Axes) or not isinstance(ax, Sequence) or len(ax) != 2 \
                or not all(isinstance(a, Axes) for a in ax):
            raise TypeError(f"ax must be a pair of matplotlib Axes; got {ax!r}")
        ax_abs, ax_c = ax
    parameter = ds.attrs["parameter"]
    x = np.asarray(ds[parameter].values, dtype=float)
    mult = np.asarray(ds["multipliers"].values, dtype=complex)
    xx = np.broadcast_to(x[:, None], mult.shape).ravel()
    norm_range = (float(np.min(x)), float(np.max(x)))
    common = {"c": xx, "cmap": "viridis", "vmin": norm_range[0], "vmax": norm_range[1],
              "s": 6, "linewidths": 0}
    ax_abs.scatter(xx, np.abs(mult).ravel(), **common)
    ax_abs.plot(x, ds["spectral_radius"].values, color="black", linewidth=1.0,
                label="spectral radius")
    ax_abs.axhline(1.0, color="0.4", linestyle="--", linewidth=1.0, label="|mu| = 1")
    ax_abs.set_yscale(yscale)
    ax_abs.set_xlabel(_label(ds, parameter))
    ax_abs.set_ylabel("|multipliers|")

    theta = np.linspace(0.0, 2.0 * np.pi, 361)
    ax_c.plot(np.cos(theta), np.sin(theta), color="0.4", linestyle="--", linewidth=1.0)
    sc = ax_c.scatter(mult.real.ravel(), mult.imag.ravel(), **common)
    labels = np.asarray(ds[special_variable("label")].values).tolist()
    smult = np.asarray(ds[special_variable("multipliers")].values, dtype=complex)
    sx = np.asarray(ds[special_variable(parameter)].values, dtype=float)
    for label in SPECIAL_LABELS:
        ks = [k for k, lab in enumerate(labels) if lab == label]
        if not ks:
            continue
        m = smult[ks].ravel()
        ax_c.scatter(m.real, m.imag, marker=SPECIAL_MARKERS[label], s=36, facecolors="none",
                     edgecolors="black", linewidths=1.0, zorder=3, label=label)
        if label_special:
            for k in ks:
                ax_abs.axvline(sx[k], color="0.6", linestyle=":", linewidth=0.8)
                ax_abs.annotate(label, (sx[k], 1.0), xytext=(2, 4), textcoords="offset points",
                                fontsize="small")
    ax_c.set_aspect("equal", adjustable="datalim")
    ax_c.set_xlabel("Re multiplier")
    ax_c.set_ylabel("Im multiplier")
    if labels:
        ax_c.legend(fontsize="small", loc="best")
    ax_abs.legend(fontsize="small", loc="best")
    ax_c.figure.colorbar(sc, ax=ax_c, label=_label(ds, parameter))
    logger.debug("multipliers plot: %d points", x.size)
    return ax_abs, ax_c
