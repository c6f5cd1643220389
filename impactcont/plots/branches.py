"""Bifurcation diagrams and multiplier plots of continued branches.

The functions read branch datasets (see :mod:`impactcont.dataset`) and never
compute orbits. They draw on the Axes given, or on a new figure, and return
the Axes; they never call ``plt.show`` so they work with any backend (Agg).
"""

from __future__ import annotations

import json
import logging
import math
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
from impactcont.plots.labels import place_labels

__all__ = ["SEGMENT_STYLES", "SPECIAL_MARKERS", "SPECIAL_NAMES", "axis_label",
           "bifurcation_diagram", "differing_parameters", "fixed_parameters",
           "multipliers_plot", "stability_segments"]

logger = logging.getLogger(__name__)

#: Line style of each kind of segment: stable and physical, unstable and
#: physical, not physical (whatever the stability).
#: Every figure of impactcont draws motions with these styles.
SEGMENT_STYLES: dict[str, dict[str, Any]] = {
    "stable": {"linestyle": "-", "linewidth": 1.6, "alpha": 1.0},
    "unstable": {"linestyle": "--", "linewidth": 1.2, "alpha": 1.0},
    "non-physical": {"linestyle": ":", "linewidth": 1.0, "alpha": 0.45},
}

#: Marker of each special-point label.
SPECIAL_MARKERS: dict[str, str] = {"SN": "o", "PD": "s", "NS": "D", "GR": "^", "ZV": "v",
                                   "BP": "P"}
#: What each special-point label stands for (legends).
SPECIAL_NAMES: dict[str, str] = {"SN": "saddle-node", "PD": "period doubling",
                                 "NS": "Neimark-Sacker", "GR": "grazing",
                                 "ZV": "zero-velocity impact",
                                 "BP": "symmetry-breaking pitchfork"}

# Symbols of the paper next to the long names on axes (mathtext).
_SYMBOLS = {"omega": r"$\omega$", "b": "$b$", "R": "$R$", "eta": r"$\eta$",
            "alpha": r"$\alpha$", "beta": r"$\beta$", "delta": r"$\delta$",
            "impact_velocity": r"$\dot{x}_1(T^-)$", "spectral_radius": r"$\rho(G)$"}
_OUTSIDE = {"loc": "upper left", "bbox_to_anchor": (1.02, 1.0), "borderaxespad": 0.0}

_KINDS = tuple(SEGMENT_STYLES)


def _new_axes(ncols: int = 1) -> Any:
    # pyplot so that notebooks display the figure; nothing here calls show().
    import matplotlib.pyplot as plt

    _, axes = plt.subplots(1, ncols, figsize=(5.0 * ncols, 4.0), layout="constrained")
    return axes


def _branches(datasets: Any, one_parameter: bool = False) -> list[tuple[str, xr.Dataset]]:
    """``(name, dataset)`` pairs from a Dataset, a sequence, a mapping or a DataTree.

    With `one_parameter`, the branches must all be continued in the same parameter.
    """
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
    parameters = {ds.attrs["parameter"] for _, ds in out}
    if one_parameter and len(parameters) > 1:
        raise ValueError(f"datasets must all be continued in one parameter; got "
                         f"{sorted(parameters)}")
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


def axis_label(ds: xr.Dataset, name: str) -> str:
    """``long name symbol [units]`` of variable ``name``, e.g. ``impact phase $\\delta$ [rad]``."""
    attrs = ds[name].attrs
    text = str(attrs.get("long_name", name))
    if name in _SYMBOLS:
        text = f"{text} {_SYMBOLS[name]}"
    units = attrs.get("units")
    return f"{text} [{units}]" if units and units != "1" else text


def fixed_parameters(datasets: Sequence[xr.Dataset]) -> dict[str, float]:
    """``omega``, ``b``, ``R`` and the damping held fixed and equal along all ``datasets``.

    Read from each dataset's ``oscillator`` attribute, without the continued
    ``parameter`` of a branch (or the ``parameters`` of a curve).
    """
    values: dict[str, set[float]] = {}
    for ds in datasets:
        free = {ds.attrs.get("parameter"), *str(ds.attrs.get("parameters", "")).split(",")}
        osc = json.loads(ds.attrs.get("oscillator", "{}"))
        for key in ("omega", "b", "R", "eta", "alpha", "beta"):
            if key not in free and isinstance(osc.get(key), (int, float)):
                values.setdefault(key, set()).add(float(osc[key]))
            else:
                values.setdefault(key, set()).add(float("nan"))
    return {k: v.pop() for k, v in values.items() if len(v) == 1 and not np.isnan(next(iter(v)))}


def differing_parameters(groups: Sequence[Sequence[xr.Dataset]]) -> list[str]:
    """The parameters of :func:`fixed_parameters` whose values differ between ``groups``."""
    fixed = [fixed_parameters(list(g)) for g in groups]
    keys = dict.fromkeys(k for f in fixed for k in f)
    return [k for k in keys if len({f.get(k) for f in fixed}) > 1]


def _system_text(values: Mapping[str, float], keys: Iterable[str]) -> str:
    return ", ".join(f"{k} = {values[k]:g}" for k in keys if k in values)


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
    if exact in ds.data_vars and ds[exact].dims == ("special",) and math.isfinite(
            float(ds[exact].values[k])):  # a file from before these were stored holds NaN
        return xs, float(ds[exact].values[k])
    p = int(ds[special_variable("point")].values[k])
    for i, j in ((p - 1, p), (p, p + 1)):
        if i >= 0 and j < x.size and min(x[i], x[j]) <= xs <= max(x[i], x[j]) and x[i] != x[j]:
            t = (xs - x[i]) / (x[j] - x[i])
            return xs, float(y[i] + t * (y[j] - y[i]))
    # A fold in the parameter (SN) is not bracketed in x: use the nearest point.
    return float(x[p]), float(y[p])


def _borders_physical(ds: xr.Dataset, physical: np.ndarray, k: int) -> bool:
    """Special point ``k`` lies on, or at the edge of, physical motions (GR and ZV are edges)."""
    p = int(ds[special_variable("point")].values[k])
    return bool(np.any(physical[max(p - 1, 0):p + 2]))


def bifurcation_diagram(datasets: Any, *, y: str = "impact_velocity", ax: Axes | None = None,
                        label_special: bool = True, title: str | None = None,
                        physical_range: bool = True) -> Axes:
    """Draw branches against their continued parameter, styled by stability.

    Stable physical motions are solid, unstable physical ones dashed and
    non-physical ones faint and dotted (:data:`SEGMENT_STYLES`); the line is
    split wherever the kind changes. Each branch has its colour, named in the
    legend with its N (and the parameters that differ, if the branches belong
    to different systems: draw those on separate axes for a clear figure).
    Special points get one marker per label (:data:`SPECIAL_MARKERS`) and,
    optionally, a text label placed clear of the others; those of non-physical
    motions (not even at the edge of a physical one) are small, grey and
    unlabelled. The legend sits outside the axes, so it never hides a curve.

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
    title : str, optional
        Axes title; by default what is drawn (``Periodic N-1 motions at b = 0.5``),
        ``""`` for none.
    physical_range : bool, optional
        Fit the vertical range to the physical motions (default), clipping
        non-physical ones at the frame; False fits everything drawn.

    Returns
    -------
    matplotlib.axes.Axes
    """
    branches = _branches(datasets, one_parameter=True)
    parameters = {ds.attrs["parameter"] for _, ds in branches}
    if ax is None:
        ax = _new_axes()
    fixed = fixed_parameters([ds for _, ds in branches])
    differing = differing_parameters([[ds] for _, ds in branches])
    kinds_seen: set[str] = set()
    labels_seen: set[str] = set()
    branch_handles = []
    specials: list[tuple[float, float, str]] = []
    seen: list[np.ndarray] = []  # y of the physical motions
    for b, (name, ds) in enumerate(branches):
        yname = _y_variable(ds, y)
        parameter = ds.attrs["parameter"]
        x = np.asarray(ds[parameter].values, dtype=float)
        yv = np.asarray(ds[yname].values, dtype=float)
        color = f"C{b % 10}"
        for kind, sl in stability_segments(ds):
            ax.plot(x[sl], yv[sl], color=color, **SEGMENT_STYLES[kind])
            kinds_seen.add(kind)
        seen.append(yv[np.asarray(ds["physical"].values, dtype=bool)])
        own = fixed_parameters([ds])
        about = ", ".join([f"N = {int(ds.attrs['N'])}",
                           *([_system_text(own, differing)] if differing else [])])
        branch_handles.append(Line2D([], [], color=color, linewidth=1.6,
                                     label=f"{name} ({about})" if name else about))
        labels = np.asarray(ds[special_variable("label")].values).tolist()
        physical = np.asarray(ds["physical"].values, dtype=bool)
        for label in SPECIAL_LABELS:
            ks = [k for k, lab in enumerate(labels) if lab == label]
            if not ks:
                continue
            shown = [_borders_physical(ds, physical, k) for k in ks]
            pts = np.array([_special_xy(ds, x, yv, yname, k) for k in ks])
            for keep, size, edge in ((True, 36, "black"), (False, 16, "0.6")):
                sel = np.array(shown) == keep
                if np.any(sel):  # special points of non-physical motions: small, grey, unlabelled
                    ax.scatter(pts[sel, 0], pts[sel, 1], marker=SPECIAL_MARKERS[label], s=size,
                               facecolors="white", edgecolors=edge, linewidths=1.0, zorder=3)
            labels_seen.add(label)
            specials += [(float(px), float(py), label)
                         for (px, py), keep in zip(pts, shown, strict=True) if keep]
    shown = np.concatenate([*seen, [py for _, py, _ in specials]])
    shown = shown[np.isfinite(shown)]
    if physical_range and shown.size:
        lo, hi = float(shown.min()), float(shown.max())
        pad = 0.08 * (hi - lo) if hi > lo else 0.1 * max(abs(hi), 1.0)
        ax.set_ylim(lo - pad, hi + pad)
    first = branches[0][1]
    ax.set_xlabel(axis_label(first, first.attrs["parameter"]))
    ax.set_ylabel(axis_label(first, y))
    if title is None:
        Ns = sorted({int(ds.attrs["N"]) for _, ds in branches})
        where = _system_text(fixed, [k for k in ("omega", "b") if k not in parameters])
        title = (f"Periodic {Ns[0] if len(Ns) == 1 else 'N'}-1 motions"
                 + (f" at {where}" if where else ""))
    if title:
        ax.set_title(title, fontsize="medium")
    handles = [Line2D([], [], color="0.2", label=kind, **SEGMENT_STYLES[kind])
               for kind in _KINDS if kind in kinds_seen]
    handles += [Line2D([], [], linestyle="none", marker=SPECIAL_MARKERS[label],
                       markerfacecolor="white", markeredgecolor="black",
                       label=f"{label} {SPECIAL_NAMES[label]}")
                for label in SPECIAL_LABELS if label in labels_seen]
    ax.legend(handles=handles + branch_handles, fontsize="small", **_OUTSIDE)
    if label_special and specials:
        place_labels(ax, [(px, py) for px, py, _ in specials], [t for _, _, t in specials])
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
    # one line per connected component of the branch, never a chord between two
    rho = np.asarray(ds["spectral_radius"].values, dtype=float)
    if "connected_component" in ds:
        cut = np.flatnonzero(np.diff(np.asarray(ds["connected_component"].values)) != 0) + 1
        x, rho = np.insert(x, cut, np.nan), np.insert(rho, cut, np.nan)
    ax_abs.plot(x, rho, color="black", linewidth=1.0, label="spectral radius")
    ax_abs.axhline(1.0, color="0.4", linestyle="--", linewidth=1.0, label=r"$|\mu| = 1$")
    ax_abs.set_yscale(yscale)
    ax_abs.set_xlabel(axis_label(ds, parameter))
    ax_abs.set_ylabel(r"moduli of the multipliers $|\mu|$")

    theta = np.linspace(0.0, 2.0 * np.pi, 361)
    ax_c.plot(np.cos(theta), np.sin(theta), color="0.4", linestyle="--", linewidth=1.0)
    sc = ax_c.scatter(mult.real.ravel(), mult.imag.ravel(), **common)
    labels = np.asarray(ds[special_variable("label")].values).tolist()
    smult = np.asarray(ds[special_variable("multipliers")].values, dtype=complex)
    sx = np.asarray(ds[special_variable(parameter)].values, dtype=float)
    at_one: list[tuple[float, str]] = []
    for label in SPECIAL_LABELS:
        ks = [k for k, lab in enumerate(labels) if lab == label]
        if not ks:
            continue
        m = smult[ks].ravel()
        ax_c.scatter(m.real, m.imag, marker=SPECIAL_MARKERS[label], s=36, facecolors="none",
                     edgecolors="black", linewidths=1.0, zorder=3,
                     label=f"{label} {SPECIAL_NAMES[label]}")
        if label_special:
            for k in ks:
                ax_abs.axvline(sx[k], color="0.6", linestyle=":", linewidth=0.8)
                at_one.append((float(sx[k]), label))
    # near a ZV point G has a pole (multipliers ~ 1/h2): frame the bulk, say what is cut
    moduli = np.abs(mult[np.isfinite(mult)])
    reach = max(1.25, float(np.percentile(moduli, 95)) * 1.05) if moduli.size else 1.25
    ax_c.set_xlim(-reach, reach)
    ax_c.set_ylim(-reach, reach)
    ax_c.set_aspect("equal", adjustable="box")
    if moduli.size and (moduli.max() > reach or np.any(np.abs(smult) > reach)):
        ax_c.text(0.02, 0.02, rf"$|\mu| > {reach:.3g}$ outside the frame", fontsize="x-small",
                  color="0.35", transform=ax_c.transAxes)
    ax_c.set_xlabel(r"Re $\mu$")
    ax_c.set_ylabel(r"Im $\mu$")
    if labels:
        ax_c.legend(fontsize="small", loc="best")
    ax_abs.legend(fontsize="small", loc="best")
    ax_c.figure.colorbar(sc, ax=ax_c, label=axis_label(ds, parameter))
    if at_one:
        place_labels(ax_abs, [(px, 1.0) for px, _ in at_one], [t for _, t in at_one])
    logger.debug("multipliers plot: %d points", x.size)
    return ax_abs, ax_c
