"""The schema of stability maps over two parameters: every map, one module.

A map is laid out on the grid of its two parameters (dims named after them, their values
as coordinates; attribute ``parameters``, ``"p1,p2"``) in one of two layouts, told apart
by the attribute ``impactcont_dataset``:

``"map"`` (:func:`map_dataset`)
    Every N-1 motion of an oscillator by the closed form (eq. 12-15):
    :func:`impactcont.stability_map` of an oscillator. Dims ``N``, the two parameters
    (``omega``, ``b`` by default: the attribute ``parameters`` is then absent) and
    ``root`` (``+1, -1``: the sign of eq. 15).
``"multi_impact_map"`` (:func:`multi_impact_map_dataset`)
    One motion family followed from a seed, any motion (N-p, several stops):
    :func:`impactcont.stability_map` of a motion. Dims the two parameters, ``impact``
    (impact index ``0 .. p-1``) and ``component`` (the ``2n`` state components
    ``x1..xn, v1..vn``); attributes ``N``, ``impacts`` (p), ``pattern``, ``symmetric``
    (1 when solved on the half system of symmetric motions), ``seed`` (JSON: the grid
    point the family was started from) and ``options``. The map of a motion with
    sticking phases (a lowercase letter in ``pattern``) carries the variables of
    :data:`STICKY_MAP_VARIABLES` as well: each stick's duration and release phase, the
    pressing forces, and ``reason``, why a found point is not physical (flags,
    :data:`MAP_REASONS`).

:func:`validate_map` checks either by its attribute, :func:`map_parameters` reads the
two parameters of either. Layouts documented in ``docs/two_parameter.md`` and
``docs/multi_maps.md``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from impactcont.dataset.attributes import (
    check_attributes,
    check_pattern_attribute,
    extra_stop_names,
    split_parameters,
)
from impactcont.dataset.schema import (
    _N,
    PARAMETERS,
    _options_json,
    _Var,
    check_dataset_kind,
    check_variables,
    provenance_attributes,
    state_component_names,
    variable_array,
)
from impactcont.model.oscillator import ImpactOscillator

__all__ = [
    "MAP_KINDS",
    "MAP_REASONS",
    "MAP_VARIABLES",
    "MULTI_MAP_KIND",
    "MULTI_MAP_VARIABLES",
    "STICKY_MAP_VARIABLES",
    "map_dataset",
    "map_parameters",
    "map_variables",
    "multi_impact_map_dataset",
    "sticky_pattern",
    "validate_map",
    "validate_map_dataset",
    "validate_multi_impact_map_dataset",
]

#: Variables of a map, with their dimensions.
MAP_VARIABLES: dict[str, tuple[_Var, tuple[str, ...]]] = {
    "amplitude_squared": (_Var("c^2 + s^2", "1",
                               "c^2 + s^2 of eq. (14): N-1 motions exist iff it is >= b^2."),
                          ("N", "omega")),
    "exists": (_Var("motion exists", "1", "c^2 + s^2 >= b^2 (eq. 15).", kind="b"),
               ("N", "omega", "b")),
    "n_physical": (_Var("physical motions", "1", "Number of physical roots of eq. (15).",
                        kind="i"), ("N", "omega", "b")),
    "n_stable": (_Var("stable physical motions", "1",
                      "Number of physical and asymptotically stable roots of eq. (15).",
                      kind="i"), ("N", "omega", "b")),
    "delta": (_Var("impact phase", "rad", "Forcing phase at the impact (eq. 15), "
                   "in (-pi, pi]."),
              ("N", "omega", "b", "root")),
    "impact_velocity": (_Var("impact velocity", "1", "x1'(T-), h2 of eq. (22)."),
                        ("N", "omega", "b", "root")),
    "gap_min": (_Var("minimum gap", "1",
                     "Smallest b - x1 at interior maxima of x1 (eq. 16); +inf if none."),
                ("N", "omega", "b", "root")),
    "spectral_radius": (_Var("spectral radius", "1", "rho(G) (eq. 25)."),
                        ("N", "omega", "b", "root")),
    "critical_multiplier": (_Var("critical multiplier", "1",
                                 "The multiplier of largest modulus (real and negative: PD "
                                 "side; complex: NS side; real positive: SN side).", kind="c"),
                            ("N", "omega", "b", "root")),
    "physical": (_Var("physically realisable", "1", "impact_velocity > 0 and gap_min > 0.",
                      kind="b"), ("N", "omega", "b", "root")),
    "stable": (_Var("asymptotically stable", "1", "spectral_radius < 1 (Theorem 3.1).",
                    kind="b"), ("N", "omega", "b", "root")),
}

#: The ``impactcont_dataset`` attribute of a map of one motion family.
MULTI_MAP_KIND = "multi_impact_map"

#: Variables of the map: metadata and dims after the two grid dims.
MULTI_MAP_VARIABLES: dict[str, _Var] = {
    "found": _Var("motion found", "1",
                  "Newton converged at this grid point from a solved neighbour (the closed "
                  "form of an N-1 family: its root of eq. 15 exists there and at grid "
                  "neighbours back to the seed): the family followed from the seed reaches "
                  "it. False: not reached (no motion of the family there, or Newton failed); "
                  "every other value is then NaN.", kind="b"),
    "newton_iterations": _Var("Newton iterations", "1",
                              "Iterations of the Newton solve that found the motion (0 where "
                              "the closed form gave it); -1 where it was not found.",
                              kind="i"),
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

#: Why a found point of a map is not physical: the bits of the variable ``reason`` (CF
#: ``flag_masks``/``flag_meanings``), several at once where several checks fail. The
#: first three are the sides of the points that end a branch of motions with sticking
#: phases (``SE``, ``RG``, ``SO``, :class:`~impactcont.vocabulary.Label`);
#: ``bounce_reaches_stop`` a resolved bounce of the complete chatter that enters a sticking
#: phase reaching another stop (the chatter map sees only its own stop; the motion's
#: ``reason`` names the stop, the coordinate and when); ``other`` is a check the others do
#: not name (a release where the pressing force does not fall through zero, a stop crossed
#: at a section, a chatter that does not accumulate; the motion's ``reason`` says which).
MAP_REASONS: dict[str, int] = {
    "stick_ended": 1,          # a stick time <= 0: past the end of a ride (SE)
    "release_grazing": 2,      # the pressing force <= 0 inside a stick (RG)
    "sticking_onset": 4,       # the pressing force <= 0 where the stick starts (SO)
    "flight_time": 8,          # a flight time <= 0
    "impact_velocity": 16,     # an impact velocity <= 0 (not arriving towards its stop)
    "interior_contact": 32,    # gap_min <= 0: a stop reached in a flight (eq. 16), ride, bounce
    "contact_not_checked": 64,  # the flights were not searched for contact
    "other": 128,              # another check of the motion failed
    "bounce_reaches_stop": 256,  # a bounce of a chatter reaches another stop
}

#: Variables of the map of a motion with sticking phases (a lowercase letter in its
#: pattern), beside :data:`MULTI_MAP_VARIABLES`: metadata and dims after the two grid dims.
STICKY_MAP_VARIABLES: dict[str, _Var] = {
    "stick_time_k": _Var("stick time", "1",
                         "Duration of the sticking phase after impact k (from the landing "
                         "impact, plastic or the first of a complete chatter, to the "
                         "release; <= 0 past the end of a ride, SE); NaN for an impact "
                         "without one and where not found.",
                         extra_dims=("impact",)),
    "release_phase_k": _Var("release phase", "rad",
                            "Forcing phase at the release ending the sticking phase after "
                            "impact k (its impact phase plus omega times its stick time), "
                            "in (-pi, pi]; NaN for an impact without one and where not "
                            "found.", extra_dims=("impact",)),
    "pressing_min_k": _Var("smallest pressing force", "1",
                           "Smallest force with which the stop presses its coordinate inside "
                           "the sticking phase after impact k (its start included, the "
                           "release excluded); NaN for an impact without one, a stick of "
                           "duration <= 0 and where not found.", extra_dims=("impact",)),
    "landing_pressing_k": _Var("pressing force at the landing", "1",
                               "Pressing force where the sticking phase after impact k starts "
                               "(after its plastic impact, or at the accumulation point of "
                               "its chatter; <= 0: the sticking onset, SO, is passed); "
                               "NaN for an impact without one and where not found.",
                               extra_dims=("impact",)),
    "stick_time_min": _Var("smallest stick time", "1",
                           "Shortest sticking phase of the motion (the test of SE: <= 0 "
                           "past the end of a ride); NaN where not found."),
    "pressing_min": _Var("smallest pressing force", "1",
                         "Smallest pressing force over the sticking phases (the test of RG, "
                         "release grazing: a stick of duration <= 0 counts its landing's); "
                         "NaN where not found."),
    "reason": _Var("why not physical", "1",
                   "Why a found point is not physical, as bits (flag_masks, flag_meanings: "
                   "stick_ended = a stick time <= 0, the SE side; release_grazing = the "
                   "pressing force <= 0 inside a stick, the RG side; sticking_onset = the "
                   "pressing force <= 0 at a landing, the SO side; flight_time, "
                   "impact_velocity, interior_contact, contact_not_checked, other, "
                   "bounce_reaches_stop = a bounce of the chatter entering a stick reaches "
                   "another stop); 0 where physical or not found.", kind="i"),
}


def sticky_pattern(pattern: str, extra: str = "") -> bool:
    """Whether the motion of `pattern` has sticking phases: a lowercase stop letter (not
    the name of one of the `extra` stops)."""
    return any(letter.islower() and letter not in extra for letter in str(pattern))


def _reason_attrs() -> dict[str, Any]:
    """The CF flag attributes of the variable ``reason``."""
    return {"flag_masks": np.array(list(MAP_REASONS.values()), dtype=np.int32),
            "flag_meanings": " ".join(MAP_REASONS)}
_ATTRS = ("title", "impactcont_dataset", "oscillator", "N", "impacts", "pattern", "parameters",
          "symmetric", "seed", "options", "impactcont_version", "Conventions", "history")


def _dims(parameters: Sequence[str], spec: _Var) -> tuple[str, ...]:
    return (*parameters, *spec.extra_dims)


_MAP_ATTRS = ("title", "impactcont_dataset", "oscillator", "options", "impactcont_version",
              "Conventions", "history")
#: The ``impactcont_dataset`` attribute of each layout: every N-1 motion by the closed form,
#: one motion family followed from a seed.
MAP_KINDS: tuple[str, str] = ("map", MULTI_MAP_KIND)


def _grid_coord(name: str, values: Any) -> tuple[str, np.ndarray, dict[str, Any]]:
    """The coordinate of the grid of the parameter `name`."""
    return (name, np.asarray(values, dtype=float), PARAMETERS[name].attrs())


def map_variables(parameters: Sequence[str] = ("omega", "b")
                  ) -> dict[str, tuple[_Var, tuple[str, ...]]]:
    """:data:`MAP_VARIABLES` of a map over the grid of `parameters` (default ``omega, b``).

    The grid dims are named after the parameters: ``omega`` becomes ``parameters[0]``,
    ``b`` becomes ``parameters[1]``. ``amplitude_squared`` (eq. 13-14) depends on every
    parameter but ``b``: on ``(N, parameters[0])`` when ``parameters[1]`` is ``b``, else
    on the whole grid ``(N, parameters[0], parameters[1])``.
    """
    first, second = parameters
    rename = {"omega": first, "b": second}
    out = {}
    for key, (spec, dims) in MAP_VARIABLES.items():
        dims = tuple(rename.get(d, d) for d in dims)
        if key == "amplitude_squared" and second != "b":
            dims = ("N", first, second)
        out[key] = (spec, dims)
    return out


_OPTIONAL_MAP_VARIABLES = ("spectral_radius", "critical_multiplier")


def map_dataset(*, oscillator: ImpactOscillator, N: Sequence[int], omega: np.ndarray,
                b: np.ndarray, values: Mapping[str, np.ndarray], options: Any,
                title: str | None = None,
                parameters: tuple[str, str] = ("omega", "b")) -> xr.Dataset:
    """Assemble a map of existence, physicality and stability on ``(N, omega, b)``.

    Parameters
    ----------
    oscillator : ImpactOscillator
    N, omega, b : sequences
        The grid: ``omega`` the values of ``parameters[0]``, ``b`` those of
        ``parameters[1]``.
    values : mapping
        One array per entry of :func:`map_variables` with the dims listed there.
    options : dict
        How the map was computed (executor, chunks), stored as JSON.
    title : str, optional
    parameters : (str, str)
        The grid's parameters, its dims after ``N`` (default ``omega, b``; any other pair
        is stored in the attribute ``parameters``).

    Returns
    -------
    xarray.Dataset
    """
    if not isinstance(oscillator, ImpactOscillator):
        raise TypeError(f"oscillator must be an ImpactOscillator; got {oscillator!r}")
    first, second = parameters
    N = [_N(k) for k in N]
    omega, b = (np.asarray(x, dtype=float) for x in (omega, b))
    if omega.ndim != 1 or b.ndim != 1:
        raise ValueError(f"omega and b must be 1-D grids; got shapes {omega.shape} and {b.shape}")
    if not isinstance(options, Mapping):
        raise TypeError(f"options must be a mapping; got {options!r}")
    sizes = {"N": len(N), first: len(omega), second: len(b), "root": 2}
    data_vars = {}
    for key, (spec, dims) in map_variables(parameters).items():
        if key in _OPTIONAL_MAP_VARIABLES and key not in values:
            continue  # a map computed without eigenvalues
        if key not in values:
            raise ValueError(f"values is missing {key!r}; required {list(MAP_VARIABLES)}")
        shape = tuple(sizes[d] for d in dims)
        data_vars[key] = (dims, variable_array(key, values[key], spec, shape), spec.attrs())
    coords = {
        "N": ("N", np.asarray(N, dtype=np.int64),
              {"long_name": "forcing periods per impact", "units": "1"}),
        first: _grid_coord(first, omega),
        second: _grid_coord(second, b),
        "root": ("root", np.array([1, -1], dtype=np.int64),
                 {"long_name": "root of eq. (15)", "units": "1",
                  "description": "Sign in front of the square root of eq. (15)."}),
    }
    attrs = {"title": title or "Existence, physicality and stability of N-1 motions",
             "impactcont_dataset": "map", "oscillator": oscillator.to_json(),
             "options": json.dumps(dict(options), sort_keys=True), **provenance_attributes()}
    if (first, second) != ("omega", "b"):
        attrs["parameters"] = f"{first},{second}"
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


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
        The stop of each impact (``U``/``L``; lowercase: a plastic impact followed by a
        sticking phase); its length is p.
    parameters : (str, str)
        The two parameters, in grid order.
    grid : mapping
        The 1-D grid of each parameter.
    values : mapping
        One array per entry of :data:`MULTI_MAP_VARIABLES` (``asymmetry`` optional) and,
        for a pattern with sticking phases (lowercase letters), of
        :data:`STICKY_MAP_VARIABLES`, shaped as the grid followed by the variable's own
        dims.
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
    variables = _family_variables(pattern, extra_stop_names(oscillator))
    for key, spec in variables.items():
        if key not in values:
            if key in _OPTIONAL:
                continue
            raise ValueError(f"values is missing {key!r}; required "
                             f"{[k for k in variables if k not in _OPTIONAL]}")
        dims = _dims(parameters, spec)
        shape = tuple(sizes[d] for d in dims)
        # a dask array (a map written to a file) stays lazy: shape and dtype only
        array = values[key] if hasattr(values[key], "dask") else np.asarray(values[key])
        if array.shape != shape:
            raise ValueError(f"values[{key!r}] must have shape {shape} (dims {dims}); got "
                             f"{array.shape}")
        data_vars[key] = (dims, array, {**spec.attrs(), **(
            _reason_attrs() if key == "reason" else {})})
    coords = {name: _grid_coord(name, grid[name]) for name in parameters}
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


def _family_variables(pattern: str, extra: str) -> dict[str, _Var]:
    """The variables of a family's map of `pattern` (`extra`: the names of the extra
    stops): :data:`MULTI_MAP_VARIABLES`, and :data:`STICKY_MAP_VARIABLES` where it has
    sticking phases."""
    if sticky_pattern(pattern, extra):
        return {**MULTI_MAP_VARIABLES, **STICKY_MAP_VARIABLES}
    return dict(MULTI_MAP_VARIABLES)


def map_parameters(ds: xr.Dataset) -> tuple[str, str]:
    """The two parameters of a map's grid (either layout): its attribute ``parameters``, else
    ``omega, b`` (a map of N-1 motions over ``omega, b`` has none).

    Raises
    ------
    ValueError
        The attribute names other than two parameters of the vocabulary.
    """
    text = ds.attrs.get("parameters", "omega,b")
    names = split_parameters(text) if isinstance(text, str) else []
    if len(names) != 2 or names[0] == names[1] or not all(n in PARAMETERS for n in names):
        raise ValueError(f"attribute 'parameters' must name two different parameters of "
                         f"{sorted(PARAMETERS)} or elements (k2, M[1,2], F[2], ...), "
                         f"comma-joined; got {text!r}")
    return names[0], names[1]


def validate_map_dataset(ds: Any) -> xr.Dataset:
    """Check that ``ds`` has the layout of :func:`map_dataset`; return it.

    ``spectral_radius`` and ``critical_multiplier`` are optional (a map computed
    with ``spectral_radius=False`` has neither); the other variables of
    :data:`MAP_VARIABLES` are required.

    Raises
    ------
    TypeError, ValueError
        Naming the missing or malformed attribute or variable.
    """
    check_dataset_kind(ds, "map", _MAP_ATTRS)
    parameters = map_parameters(ds)
    check_variables(ds, {k: (dims, s.kind) for k, (s, dims) in map_variables(parameters).items()
                         if k not in _OPTIONAL_MAP_VARIABLES or k in ds.variables}, "map")
    check_attributes(ds, "map")
    return ds


def validate_multi_impact_map_dataset(ds: Any) -> xr.Dataset:
    """Check that ``ds`` has the layout of :func:`multi_impact_map_dataset`; return it.

    Raises
    ------
    TypeError, ValueError
        Naming the missing or malformed attribute or variable.
    """
    check_dataset_kind(ds, MULTI_MAP_KIND, _ATTRS)
    parameters = map_parameters(ds)
    p = ds.attrs["impacts"]
    if isinstance(p, (bool, np.bool_)) or not isinstance(p, (int, np.integer)) or p < 1 or (
            ds.sizes.get("impact") != p):
        raise ValueError(f"attribute 'impacts' must be p >= 1, the size of dimension 'impact' "
                         f"({ds.sizes.get('impact')}); got {p!r}")
    osc = ImpactOscillator.from_json(ds.attrs["oscillator"])
    pattern = check_pattern_attribute(ds.attrs["pattern"], int(p), osc.stops.two_sided,
                                      extra=extra_stop_names(osc), sticking=True)
    check_variables(ds, {key: (_dims(parameters, spec), spec.kind)
                         for key, spec in _family_variables(pattern, extra_stop_names(osc)).items()
                         if key not in _OPTIONAL or key in ds.variables}, MULTI_MAP_KIND)
    return ds


def validate_map(ds: Any) -> xr.Dataset:
    """Check a map of either layout (:data:`MAP_KINDS`) by its ``impactcont_dataset``; return it.

    Raises
    ------
    TypeError, ValueError
        Not a Dataset, not a map, or naming the missing or malformed attribute or variable.
    """
    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"expected an xarray.Dataset of a map; got {type(ds).__name__}")
    if ds.attrs.get("impactcont_dataset") == MULTI_MAP_KIND:
        return validate_multi_impact_map_dataset(ds)
    return validate_map_dataset(ds)
