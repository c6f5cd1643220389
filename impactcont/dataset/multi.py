"""Branch datasets of N-p motions: the branch schema plus an ``impact`` dimension.

A branch of periodic N-p motions (p impacts in N forcing periods) is stored
as a branch dataset of :mod:`impactcont.dataset.schema` (so every reader,
plot and :func:`impactcont.dataset.load` takes it unchanged) with:

- the point columns read as follows: ``delta`` and ``state`` are those of
  impact 0, ``impact_velocity`` is the smallest impact velocity over the p
  impacts and ``gap_min`` the smallest clearance over the p flights (interior
  extrema and both ends, every stop; the ZV and GR test functions),
  ``multipliers`` the eigenvalues of ``G = G_{p-1} .. G_0``;
- a dimension ``impact`` (size p, integer coordinate ``0 .. p-1``) and the
  per-impact variables of :data:`IMPACT_VARIABLES` on ``(point, impact)``
  (``state_k`` on ``(point, impact, component)``), and the same at the
  special points (``special_<name>`` on ``(special, impact)``);
- the attribute ``impacts = p``, and ``pattern`` (p letters ``U``/``L``: the stop
  of each impact, see :mod:`impactcont.model.stops`; all ``U`` for the paper's
  single stop, and read so when absent; a lowercase letter: a plastic impact followed
  by a sticking phase on that stop, :func:`~impactcont.model.stops.sticking_pattern`);
- on a branch of motions with sticking phases, the variables of
  :data:`STICKING_VARIABLES` on ``(point, impact)`` (``stick_time_k``, ``pressing_min_k``,
  ``release_state_k`` on ``(point, impact, component)``; 0 and NaN after an impact that no
  sticking phase follows) and ``special_stick_time_k`` at the special points
  (:func:`sticking_columns` makes them from the motions).

A dataset without the ``impact`` dimension (an N-1 branch of
:func:`impactcont.continuation`) is read as ``p = 1``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from impactcont.dataset.attributes import (
    check_pattern_attribute,
    extra_stop_names,
    impacts_attribute,
    oscillator_attribute,
)
from impactcont.dataset.schema import (
    _Var,
    branch_dataset,
    check_variables,
    special_variable,
    validate_branch_dataset,
)
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import UPPER
from impactcont.vocabulary import check_positive_integer

__all__ = ["IMPACT_VARIABLES", "STICKING_VARIABLES", "impacts_of", "multi_impact_dataset",
           "pattern_of", "sticking_columns", "validate_multi_impact_dataset"]

#: Per-impact variables (dims ``(point, impact)``, ``state_k`` adds ``component``).
IMPACT_VARIABLES: dict[str, _Var] = {
    "delta_k": _Var("impact phase of impact k", "rad",
                    "Forcing phase theta_k at impact k, in (-pi, pi]."),
    "impact_velocity_k": _Var("impact velocity of impact k", "1",
                              "Speed of the impacting mass towards the stop just before "
                              "impact k (x1' for the paper's stop; h2 of eq. 22 of the flight "
                              "ending there, signed by the stop)."),
    "flight_time_k": _Var("flight time after impact k", "1",
                          "Time tau_k from impact k to impact k+1; they sum to 2 pi N / omega."),
    "gap_min_k": _Var("minimum gap of flight k", "1",
                      "Smallest clearance on the flight after impact k to every stop, on "
                      "its own coordinate: at the interior extrema of that coordinate (eq. "
                      "16) and at both ends of the flight, the stop of the impact there "
                      "excluded (a coordinate past another stop when the flight ends is "
                      "crossed); negative: the flight crosses a stop; +inf when no stop "
                      "is approached."),
    "state_k": _Var("state after impact k", "1",
                    "State [x1..xn, x1'..xn'] right after impact k (x_j at the stop hit; "
                    "x1 = b for the paper's stop).",
                    extra_dims=("component",)),
}

#: Per-impact variables also stored at the special points (``special_<name>``).
SPECIAL_IMPACT_VARIABLES = ("delta_k", "impact_velocity_k", "flight_time_k", "state_k")

#: Per-impact variables of a branch of motions with sticking phases (dims ``(point,
#: impact)``, ``release_state_k`` adds ``component``): present together or not at all.
STICKING_VARIABLES: dict[str, _Var] = {
    "stick_time_k": _Var("stick time after impact k", "1",
                         "Duration s_k of the sticking phase after impact k (0 where no "
                         "sticking phase follows it): the stick time plus the flight time "
                         "is the time from impact k to impact k+1."),
    "pressing_min_k": _Var("smallest pressing force of sticking phase k", "1",
                           "Smallest force with which the stop presses the held coordinate "
                           "inside the sticking phase after impact k, its start included and "
                           "the release (where it is 0) excluded; > 0 on a physical motion, "
                           "through 0 at release grazing; NaN where no sticking phase "
                           "follows impact k."),
    "release_state_k": _Var("state at the release after impact k", "1",
                            "State [x1..xn, x1'..xn'] at the release that ends the sticking "
                            "phase after impact k (NaN where no sticking phase follows it).",
                            extra_dims=("component",)),
}

#: The sticking variables also stored at the special points (``special_<name>``).
SPECIAL_STICKING_VARIABLES = ("stick_time_k",)


def sticking_columns(orbits: Sequence[Any], p: int, *, special: bool = False,
                     sticky: bool | None = None) -> dict[str, np.ndarray]:
    """The :data:`STICKING_VARIABLES` of a branch's motions, as ``impact_columns`` of
    :func:`multi_impact_dataset` take them (with `special`, those of
    :data:`SPECIAL_STICKING_VARIABLES`, for ``special_impact_columns``).

    Parameters
    ----------
    orbits : sequence of MultiImpactOrbit
        The motions at the points (or at the special points).
    p : int
        Impacts per motion.
    special : bool
    sticky : bool, optional
        Whether the branch's motions have sticking phases; None: whether one of `orbits`
        has one (True: the columns even for no motion, e.g. a branch without special
        points).

    Returns
    -------
    dict of str to ndarray
        Empty when no motion has a sticking phase (the schema of a branch without them is
        unchanged).
    """
    # a sticking phase has its release state (NaN rows elsewhere), whatever its duration
    if sticky is None:
        sticky = any(np.any(np.isfinite(np.asarray(getattr(o, "release_states", np.nan),
                                                   dtype=float))) for o in orbits)
    if not sticky:
        return {}
    names = SPECIAL_STICKING_VARIABLES if special else tuple(STICKING_VARIABLES)
    sources = {"stick_time_k": "stick_times", "pressing_min_k": "pressing_min",
               "release_state_k": "release_states"}
    out = {}
    for name in names:
        rows = [np.asarray(getattr(o, sources[name]), dtype=float) for o in orbits]
        width = (p, *rows[0].shape[1:]) if rows else (p,)
        out[name] = np.array(rows, dtype=float).reshape(len(rows), *width)
    return out


def impacts_of(ds: xr.Dataset) -> int:
    """Impacts per motion of a branch dataset: ``ds.attrs["impacts"]``, 1 for an N-1 branch.

    Raises
    ------
    ValueError
        ``impacts`` is not an integer >= 1 or differs from the size of the
        dimension ``impact``.
    """
    return impacts_attribute(ds)


def pattern_of(ds: xr.Dataset) -> str:
    """The impact sequence of a branch dataset: ``ds.attrs["pattern"]``, all ``U`` if absent.

    Raises
    ------
    ValueError
        ``pattern`` is not p letters ``U``/``L`` (``L`` only with a lower stop).
    """
    p = impacts_of(ds)
    if "pattern" not in ds.attrs:
        return UPPER * p
    try:
        extra = extra_stop_names(oscillator_attribute(ds))
    except ValueError:
        extra = ""
    return check_pattern_attribute(ds.attrs["pattern"], p, _two_sided(ds), extra=extra,
                                   sticking=True)


def _impact_array(key: str, value: Any, shape: tuple[int, ...], what: str) -> np.ndarray:
    a = np.asarray(value)
    if a.shape != shape:
        raise ValueError(f"{what} {key!r} must have shape {shape}; got shape {a.shape}")
    if a.dtype.kind not in "iuf":
        raise ValueError(f"{what} {key!r} must be real numbers; got dtype {a.dtype}")
    return a.astype(np.float64)


def multi_impact_dataset(*, parameter: str, N: int, p: int, oscillator: ImpactOscillator,
                         options: Any, columns: Mapping[str, Any],
                         impact_columns: Mapping[str, Any],
                         special_points: Sequence[Mapping[str, Any]],
                         special_impact_columns: Mapping[str, Any],
                         title: str | None = None,
                         extra_attrs: Mapping[str, Any] | None = None,
                         pattern: str | None = None) -> xr.Dataset:
    """Assemble the dataset of one continued branch of periodic N-p motions.

    Parameters
    ----------
    parameter, N, oscillator, options, columns, special_points
        As for :func:`impactcont.dataset.branch_dataset` (``columns`` hold the
        impact-0 / minimum-over-impacts view described in the module notes).
    p : int
        Impacts per motion (``>= 1``).
    impact_columns : mapping of str to array_like
        Every key of :data:`IMPACT_VARIABLES`, shape ``(npoints, p)``
        (``state_k``: ``(npoints, p, 2n)``), and on a branch of motions with sticking
        phases every key of :data:`STICKING_VARIABLES` (:func:`sticking_columns`).
    special_impact_columns : mapping of str to array_like
        Every key of :data:`SPECIAL_IMPACT_VARIABLES`, shape ``(nspecial, p)``
        (``state_k``: ``(nspecial, p, 2n)``), and with the sticking variables those of
        :data:`SPECIAL_STICKING_VARIABLES`.
    title : str, optional
        Dataset title.
    extra_attrs : mapping, optional
        Further dataset attributes (str, int or float values), e.g. where a
        switched branch was born.
    pattern : str, optional
        The stop of each impact (p letters ``U``/``L``, lowercase where a sticking phase
        follows the impact); all ``U`` by default.

    Returns
    -------
    xarray.Dataset
        A valid branch dataset with the ``impact`` dimension.

    Raises
    ------
    ValueError, TypeError
        As :func:`branch_dataset`, and for a missing or misshapen per-impact column.
    """
    check_positive_integer("p", p, "impacts per motion")
    if not isinstance(impact_columns, Mapping) or not isinstance(special_impact_columns,
                                                                 Mapping):
        raise TypeError("impact_columns and special_impact_columns must be mappings of "
                        "variable name to array")
    n = oscillator.n
    npoints = len(np.atleast_1d(np.asarray(columns.get(parameter, ()))))
    nspecial = len(special_points)
    variables = {}  # built in the dataset's one construction (an assign copies it)
    sticking = any(key in impact_columns for key in STICKING_VARIABLES)
    keys_of = (tuple(IMPACT_VARIABLES) + (tuple(STICKING_VARIABLES) if sticking else ()),
               SPECIAL_IMPACT_VARIABLES + (SPECIAL_STICKING_VARIABLES if sticking else ()))
    specs = {**IMPACT_VARIABLES, **STICKING_VARIABLES}
    for what, cols, keys, dim, size in (
            ("impact column", impact_columns, keys_of[0], "point", npoints),
            ("special impact column", special_impact_columns, keys_of[1], "special",
             nspecial)):
        missing = [k for k in keys if k not in cols]
        unknown = sorted(set(cols) - set(keys))
        if missing or unknown:
            raise ValueError(f"{what}s: missing {missing}, unknown {unknown}; required: "
                             f"{list(keys)}" + (f" (the sticking variables "
                                                f"{list(STICKING_VARIABLES)} go together)"
                                                if sticking else ""))
        for key in keys:
            spec = specs[key]
            shape = (size, p) + (2 * n,) * len(spec.extra_dims)
            arr = _impact_array(key, cols[key], shape, what)
            name = key if dim == "point" else special_variable(key)
            attrs = spec.attrs()
            if dim == "special":
                attrs = {**attrs, "long_name": f"{spec.long_name} at special point"}
            variables[name] = xr.Variable((dim, "impact", *spec.extra_dims), arr, attrs)
    impact = xr.Variable("impact", np.arange(p, dtype=np.int64),
                         {"long_name": "impact index", "units": "1",
                          "description": "Impact k of the motion; impact 0 is the one of "
                          "delta and state."})
    ds = branch_dataset(parameter=parameter, N=N, oscillator=oscillator, options=options,
                        columns=columns, special_points=special_points,
                        title=title if title is not None else
                        f"Branch of periodic {N}-{p} impacting motions continued in "
                        f"{parameter}", more_variables=variables,
                        more_coords={"impact": impact})
    ds.attrs["impacts"] = int(p)
    # the phases of an N-p motion are stored wrapped (those of an N-1 branch are not)
    # (on the variables themselves: a DataArray of each would be built only to reach them)
    ds.variables["delta"].attrs["description"] = ("Forcing phase theta_0 at impact 0, "
                                                  "wrapped to (-pi, pi] (as delta_k).")
    ds.variables[special_variable("delta")].attrs["description"] = (
        "Forcing phase theta_0 at impact 0 at the special point, wrapped to (-pi, pi].")
    pattern = UPPER * int(p) if pattern is None else pattern
    ds.attrs["pattern"] = check_pattern_attribute(pattern, int(p), oscillator.stops.two_sided,
                                                  extra=extra_stop_names(oscillator),
                                                  sticking=True)
    for key, value in (extra_attrs or {}).items():
        if not isinstance(value, (str, int, float, np.integer, np.floating)) \
                or isinstance(value, bool):
            raise TypeError(f"extra_attrs[{key!r}] must be a str, int or float; got {value!r}")
        ds.attrs[str(key)] = value
    return ds


def _two_sided(ds: xr.Dataset) -> bool | None:
    """Whether the dataset's oscillator has a lower stop (None if its attribute is unreadable)."""
    try:
        return oscillator_attribute(ds).stops.two_sided
    except ValueError:
        return None


def validate_multi_impact_dataset(ds: Any) -> xr.Dataset:
    """Check a branch dataset and, if it has the ``impact`` dimension, its per-impact layout.

    Returns
    -------
    xarray.Dataset
        ``ds`` itself.

    Raises
    ------
    TypeError, ValueError
        As :func:`validate_branch_dataset`, and for a per-impact variable that is
        missing or has the wrong dimensions, or ``impacts`` that does not match.
    """
    validate_branch_dataset(ds)  # with the attributes impacts and pattern
    if "impact" not in ds.dims:
        return ds
    expected: dict[str, tuple[tuple[str, ...], str]] = {}
    for key, spec in IMPACT_VARIABLES.items():
        expected[key] = (("point", "impact", *spec.extra_dims), spec.kind)
        if key in SPECIAL_IMPACT_VARIABLES:
            expected[special_variable(key)] = (("special", "impact", *spec.extra_dims),
                                               spec.kind)
    if any(key in ds.variables for key in STICKING_VARIABLES):
        for key, spec in STICKING_VARIABLES.items():
            expected[key] = (("point", "impact", *spec.extra_dims), spec.kind)
            if key in SPECIAL_STICKING_VARIABLES:
                expected[special_variable(key)] = (("special", "impact", *spec.extra_dims),
                                                   spec.kind)
    check_variables(ds, expected, "N-p branch")
    return ds
