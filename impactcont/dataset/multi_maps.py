"""The schema of a stability map of one N-p motion family over two parameters.

:func:`impactcont.analysis.multi_maps.multi_impact_map` follows one family of N-p motions over
a grid of two parameters; this module lays the result out as an
:class:`xarray.Dataset` (:func:`multi_impact_map_dataset`) and checks that layout
(:func:`validate_multi_impact_map_dataset`). Layout documented in
``docs/multi_maps.md``.

Dimensions
----------
``<parameter 0>``, ``<parameter 1>``  the grid (coordinates: the grid values);
``impact``                            impact index ``0 .. p-1``;
``component``                         the ``2n`` state components ``x1..xn, v1..vn``.

The dataset carries ``impactcont_dataset = "multi_impact_map"``, the oscillator as
JSON, ``N``, ``impacts`` (p), ``pattern``, ``parameters`` (``"omega,b"``),
``symmetric`` (1 when solved on the half system of symmetric motions), ``seed`` (JSON:
the grid point the family was started from) and ``options``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from impactcont.dataset.attributes import (
    check_pattern_attribute,
    dataset_tag,
    extra_stop_names,
    split_parameters,
)
from impactcont.dataset.schema import (
    PARAMETERS,
    _options_json,
    _Var,
    check_variables,
    provenance_attributes,
    state_component_names,
)
from impactcont.model.oscillator import ImpactOscillator

__all__ = [
    "MULTI_MAP_KIND",
    "MULTI_MAP_VARIABLES",
    "multi_impact_map_dataset",
    "validate_multi_impact_map_dataset",
]

#: The ``impactcont_dataset`` attribute of these maps.
MULTI_MAP_KIND = "multi_impact_map"

_GRID = "grid"  # stands for the two parameter dims in MULTI_MAP_VARIABLES

#: Variables of the map: metadata and dims after the two grid dims.
MULTI_MAP_VARIABLES: dict[str, _Var] = {
    "found": _Var("motion found", "1",
                  "Newton converged at this grid point from a solved neighbour: the family "
                  "followed from the seed reaches it. False: not reached (no motion of the "
                  "family there, or Newton failed); every other value is then NaN.", kind="b"),
    "newton_iterations": _Var("Newton iterations", "1",
                              "Iterations of the Newton solve that found the motion; -1 where "
                              "it was not found.", kind="i"),
    "stable": _Var("asymptotically stable", "1",
                   "rho(G) < 1 (Theorem 3.1 on G = G_{p-1} .. G_0); False where not found.",
                   kind="b"),
    "physical": _Var("physically realisable", "1",
                     "Every flight time > 0, every impact velocity > 0 and no contact inside a "
                     "flight (eq. 16 against every stop, searched: contact_checked); False "
                     "where not found.", kind="b"),
    "contact_checked": _Var("interior contact checked", "1",
                            "Every flight of the motion was searched for contact with a stop "
                            "(eq. 16). False where found but not searched: checks=False, or a "
                            "constant force F_static pushes a free mode that the stop "
                            "coordinate sees (a polynomial in time the search does not "
                            "represent); such a point is never physical. False where not "
                            "found.", kind="b"),
    "spectral_radius": _Var("spectral radius", "1",
                            "rho(G), G the impact map over the whole motion (eq. 25)."),
    "critical_multiplier": _Var("critical multiplier", "1",
                                "The multiplier of G of largest modulus.", kind="c"),
    "delta": _Var("impact phase", "rad", "Forcing phase at impact 0, in (-pi, pi]."),
    "gap_min": _Var("minimum gap", "1",
                    "Smallest clearance to any stop at the interior extrema of the stop "
                    "coordinate over all flights (eq. 16); +inf when there is none; NaN "
                    "where not searched (contact_checked False)."),
    "impact_velocity_k": _Var("impact velocity", "1",
                              "Speed of the impacting mass towards the stop hit just before "
                              "impact k.", extra_dims=("impact",)),
    "flight_time_k": _Var("flight time", "1", "Time from impact k to impact k+1.",
                          extra_dims=("impact",)),
    "state_k": _Var("state after impact", "1", "State right after impact k.",
                    extra_dims=("impact", "component")),
    "asymmetry": _Var("asymmetry", "1",
                      "symmetry_defect of the motion (impactcont.orbit.symmetry): 0 for a "
                      "symmetric motion. Only in a system that admits symmetric motions of "
                      "the pattern; 0 exactly where solved on the half system."),
}

_OPTIONAL = ("asymmetry",)
_ATTRS = ("title", "impactcont_dataset", "oscillator", "N", "impacts", "pattern", "parameters",
          "symmetric", "seed", "options", "impactcont_version", "Conventions", "history")


def _dims(parameters: Sequence[str], spec: _Var) -> tuple[str, ...]:
    return (*parameters, *spec.extra_dims)


def multi_impact_map_dataset(*, oscillator: ImpactOscillator, N: int, pattern: str,
                             parameters: Sequence[str], grid: Mapping[str, np.ndarray],
                             values: Mapping[str, np.ndarray], symmetric: bool,
                             seed: Mapping[str, Any], options: Mapping[str, Any],
                             title: str | None = None) -> xr.Dataset:
    """Assemble a map of one N-p motion family on a grid of two parameters.

    Parameters
    ----------
    oscillator : ImpactOscillator
        The oscillator of the start (its values of the two parameters are not used).
    N : int
    pattern : str
        The stop of each impact (``U``/``L``); its length is p.
    parameters : (str, str)
        The two parameters, in grid order.
    grid : mapping
        The 1-D grid of each parameter.
    values : mapping
        One array per entry of :data:`MULTI_MAP_VARIABLES` (``asymmetry`` optional),
        shaped as the grid followed by the variable's own dims.
    symmetric : bool
        Solved on the half system of symmetric motions.
    seed : mapping
        Where the family was started (stored as JSON).
    options : mapping
        How the map was computed (stored as JSON).
    title : str, optional

    Returns
    -------
    xarray.Dataset
    """
    if not isinstance(oscillator, ImpactOscillator):
        raise TypeError(f"oscillator must be an ImpactOscillator; got {oscillator!r}")
    parameters = tuple(parameters)
    p, n = len(pattern), oscillator.n
    sizes = {parameters[0]: len(grid[parameters[0]]), parameters[1]: len(grid[parameters[1]]),
             "impact": p, "component": 2 * n}
    data_vars = {}
    for key, spec in MULTI_MAP_VARIABLES.items():
        if key not in values:
            if key in _OPTIONAL:
                continue
            raise ValueError(f"values is missing {key!r}; required "
                             f"{[k for k in MULTI_MAP_VARIABLES if k not in _OPTIONAL]}")
        dims = _dims(parameters, spec)
        shape = tuple(sizes[d] for d in dims)
        # a dask array (a map written to a file) stays lazy: shape and dtype only
        array = values[key] if hasattr(values[key], "dask") else np.asarray(values[key])
        if array.shape != shape:
            raise ValueError(f"values[{key!r}] must have shape {shape} (dims {dims}); got "
                             f"{array.shape}")
        data_vars[key] = (dims, array, spec.attrs())
    coords = {name: (name, np.asarray(grid[name], dtype=float), PARAMETERS[name].attrs())
              for name in parameters}
    coords["impact"] = ("impact", np.arange(p, dtype=np.int64),
                        {"long_name": "impact index", "units": "1"})
    coords["component"] = ("component", np.array(state_component_names(n)),
                           {"long_name": "state component",
                            "description": "x<i>: displacement of mass i; v<i>: its velocity."})
    attrs = {"title": title or f"Stability map of the N={N}, p={p} motion family over "
                               f"({parameters[0]}, {parameters[1]})",
             "impactcont_dataset": MULTI_MAP_KIND, "oscillator": oscillator.to_json(),
             "N": int(N), "impacts": int(p), "pattern": pattern,
             "parameters": ",".join(parameters), "symmetric": int(bool(symmetric)),
             "seed": json.dumps(dict(seed), sort_keys=True),
             "options": _options_json(dict(options)), **provenance_attributes()}
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def validate_multi_impact_map_dataset(ds: Any) -> xr.Dataset:
    """Check that ``ds`` has the layout of :func:`multi_impact_map_dataset`; return it.

    Raises
    ------
    TypeError, ValueError
        Naming the missing or malformed attribute or variable.
    """
    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"expected an xarray.Dataset of a multi_impact_map; got "
                        f"{type(ds).__name__}")
    missing = [a for a in _ATTRS if a not in ds.attrs]
    if missing or dataset_tag(ds) != MULTI_MAP_KIND:
        raise ValueError(f"not a {MULTI_MAP_KIND} dataset: missing attribute(s) {missing} or "
                         f"impactcont_dataset != {MULTI_MAP_KIND!r}")
    text = ds.attrs["parameters"]
    parameters = split_parameters(text) if isinstance(text, str) else []
    if len(parameters) != 2 or parameters[0] == parameters[1] or not all(
            name in PARAMETERS for name in parameters):
        raise ValueError(f"attribute 'parameters' must name two different parameters of "
                         f"{sorted(PARAMETERS)} or elements (k2, M[1,2], F[2], ...); got "
                         f"{text!r}")
    p = ds.attrs["impacts"]
    if isinstance(p, (bool, np.bool_)) or not isinstance(p, (int, np.integer)) or p < 1 or (
            ds.sizes.get("impact") != p):
        raise ValueError(f"attribute 'impacts' must be p >= 1, the size of dimension 'impact' "
                         f"({ds.sizes.get('impact')}); got {p!r}")
    osc = ImpactOscillator.from_json(ds.attrs["oscillator"])
    check_pattern_attribute(ds.attrs["pattern"], int(p), osc.stops.two_sided,
                            extra=extra_stop_names(osc))
    check_variables(ds, {key: (_dims(parameters, spec), spec.kind)
                         for key, spec in MULTI_MAP_VARIABLES.items()
                         if key not in _OPTIONAL or key in ds.variables}, MULTI_MAP_KIND)
    return ds
