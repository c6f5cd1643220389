"""The schema of codim-1 curves, and the validation of every continuation dataset.

The one place that knows how a continued curve (:func:`impactcont.analysis.curves.curve`)
is laid out in an :class:`xarray.Dataset`; maps are laid out by
:mod:`impactcont.dataset.maps`. Curves and maps carry the attribute
``impactcont_dataset`` (``"curve"``, ``"map"``, ``"multi_impact_map"``); a branch dataset
has none. :func:`validate_dataset` dispatches on it, so :func:`impactcont.dataset.save` /
``load`` handle them all.
Layout documented in ``docs/two_parameter.md``.

Curve dimensions
----------------
``point``       accepted continuation points, in curve order;
``multiplier``  the ``2n`` eigenvalues of ``G`` (eq. 25);
``component``   the ``2n`` state components ``x1..xn, v1..vn``;
``codim2``      codimension-two points found on the curve (may be empty).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from impactcont.dataset.attributes import check_attributes, dataset_tag, split_parameters
from impactcont.dataset.maps import MAP_KINDS, validate_map
from impactcont.dataset.multi import validate_multi_impact_dataset
from impactcont.dataset.schema import (
    _N,
    PARAMETERS,
    _options_json,
    _parameter_name,
    _Var,
    check_dataset_kind,
    check_user_variables,
    check_variables,
    point_coords,
    provenance_attributes,
    variable_array,
    with_parameter_coords,
)
from impactcont.model.oscillator import ImpactOscillator
from impactcont.vocabulary import CODIM2_LABELS, CURVE_KINDS, STATUSES, Label

__all__ = [
    "CODIM2_FORMER_LABELS",
    "CODIM2_LABELS",
    "CODIM2_STATUSES",
    "CURVE_VARIABLES",
    "codim2_data",
    "codim2_variable",
    "curve_dataset",
    "kind_of_curve",
    "normalise_dataset",
    "validate_any_curve",
    "validate_curve_dataset",
    "validate_dataset",
]

logger = logging.getLogger(__name__)

CODIM2_STATUSES: tuple[str, ...] = STATUSES

#: Codim-2 labels of files written before one point had one name: the 1:1 and 1:2
#: resonances met on SN and PD curves. :func:`normalise_dataset` (run by
#: :func:`impactcont.load`) gives them their name.
CODIM2_FORMER_LABELS: dict[str, str] = {"SN+SN": "R1", "PD+PD": "R2"}

_LABEL_DTYPE = np.dtype(f"<U{max(map(len, CODIM2_LABELS))}")
_STATUS_DTYPE = np.dtype(f"<U{max(map(len, CODIM2_STATUSES))}")

#: Variables on ``point`` of a curve (parameters other than omega/b add a column).
CURVE_VARIABLES: dict[str, _Var] = {
    "omega": PARAMETERS["omega"],
    "b": PARAMETERS["b"],
    "delta": _Var("impact phase", "rad", "Forcing phase delta at the impact (eq. 15), "
                  "wrapped to [-pi, pi]."),
    "root": _Var("root of eq. (15)", "1",
                 "+1 or -1: sign in front of the square root of eq. (15), -sign(dr/d delta); "
                 "0 on a saddle-node curve (double root).", kind="i"),
    "impact_velocity": _Var("impact velocity", "1",
                            "x1'(T-), h2 of eq. (22); 0 on a zero-velocity curve."),
    "gap_min": _Var("minimum gap", "1",
                    "Smallest b - x1 at interior maxima of x1 (eq. 16); on a grazing curve "
                    "the tangency itself is excluded; +inf when there is none."),
    "spectral_radius": _Var("spectral radius", "1",
                            "rho(G) (eq. 25); NaN on a zero-velocity curve (G has a pole)."),
    "multipliers": _Var("Floquet multipliers", "1",
                        "Eigenvalues of G (eq. 25), largest modulus first; NaN on a "
                        "zero-velocity curve.", kind="c", extra_dims=("multiplier",)),
    "state": _Var("state after impact", "1", "X(0) right after the impact (eq. 13).",
                  extra_dims=("component",)),
    "physical": _Var("physically realisable", "1",
                     "impact_velocity > 0 and gap_min > 0 (on a grazing curve: no contact "
                     "inside the period other than the tangency).", kind="b"),
    "stable_side": _Var("stable on one side", "1",
                        "The motion is physical and every multiplier except the critical "
                        "one(s) of the curve lies inside the unit circle: crossing the curve "
                        "changes an observable stable motion.", kind="b"),
    "arclength": _Var("arclength", "1",
                      "Length of the curve in the plane of its two parameters."),
    "residual": _Var("residual", "1",
                     "Largest |component| of the augmented system at the point."),
    "tangency_time": _Var("tangency time", "1",
                          "t* of a grazing curve: x1(t*) = b, x1'(t*) = 0, 0 < t* < T; NaN "
                          "on other curves."),
    "angle": _Var("Neimark-Sacker angle", "rad",
                  "theta of the critical multipliers exp(+-i theta) of an NS curve; NaN on "
                  "other curves."),
}

_CODIM2_FIELDS: dict[str, _Var] = {
    "label": _Var("codim-2 label", "1",
                  "A+B: the curve (kind A) meets a curve of kind B; R1/R2: 1:1 / 1:2 "
                  "resonance (a double multiplier +1 / -1), on any curve.", kind="U"),
    "delta": _Var("impact phase at codim-2 point", "rad", "Forcing phase at the impact, "
                  "wrapped to [-pi, pi]."),
    "point": _Var("nearest point", "1", "Index on point of the nearest accepted point.",
                  kind="i"),
    "precision": _Var("location precision", "1",
                      "Bound on the error of the point in the plane of the two parameters."),
    "status": _Var("location status", "1",
                   "located: the test function vanishes there; bracketed: it changes sign "
                   "with a jump (e.g. the highest interior maximum changes).", kind="U"),
    "multipliers": _Var("multipliers at codim-2 point", "1", "Eigenvalues of G (eq. 25).",
                        kind="c", extra_dims=("multiplier",)),
}

_CURVE_ATTRS = ("title", "impactcont_dataset", "kind", "N", "parameters", "oscillator",
                "options", "end_status", "impactcont_version", "Conventions", "history")


def codim2_variable(key: str) -> str:
    """Name of the dataset variable of codim-2 field ``key`` (``codim2_<key>``)."""
    return f"codim2_{key}"


def _curve_variables(parameters: Sequence[str]) -> dict[str, _Var]:
    out = {name: PARAMETERS[name] for name in parameters if name not in ("omega", "b")}
    return {**out, **CURVE_VARIABLES}


def _codim2_fields(parameters: Sequence[str]) -> dict[str, _Var]:
    fields = {"label": _CODIM2_FIELDS["label"]}
    for name in dict.fromkeys(["omega", "b", *parameters]):
        p = PARAMETERS[name]
        fields[name] = _Var(f"{p.long_name} at codim-2 point", p.units,
                            f"{p.description.rstrip('.')} at the codim-2 point.")
    fields.update({k: v for k, v in _CODIM2_FIELDS.items() if k != "label"})
    return fields




def codim2_data(codim2_points: Sequence[Mapping[str, Any]], parameters: Sequence[str],
                n: int) -> dict[str, tuple[tuple[str, ...], np.ndarray, dict[str, Any]]]:
    """The variables ``codim2_*`` on the dimension ``codim2`` of a curve's codim-2 points.

    The same on every curve: of N-1 motions (:func:`curve_dataset`) and of N-p motions
    (:func:`impactcont.multi_impact_curve`, whose dataset is a branch dataset).

    Parameters
    ----------
    codim2_points : sequence of dict
        Keys ``label``, ``omega``, ``b`` (and the curve's parameters), ``delta``,
        ``point``, ``precision``, ``status``, ``multipliers`` (``2n`` each).
    parameters : (str, str)
        The curve's parameters.
    n : int
        Degrees of freedom.

    Returns
    -------
    dict
        ``name: (dims, values, attrs)``, ready for :class:`xarray.Dataset`.

    Raises
    ------
    TypeError, ValueError
        A point that is not a mapping, has other keys, a label not in
        :data:`CODIM2_LABELS` or a status not in :data:`CODIM2_STATUSES`.
    """
    fields = _codim2_fields(parameters)
    count = len(codim2_points)
    data_vars: dict[str, tuple[tuple[str, ...], np.ndarray, dict[str, Any]]] = {}
    for key, spec in fields.items():
        values = []
        for i, cp in enumerate(codim2_points):
            if not isinstance(cp, Mapping):
                raise TypeError(f"codim2_points[{i}] must be a dict; got {cp!r}")
            if set(cp) != set(fields):
                raise ValueError(f"codim2_points[{i}] must have keys {sorted(fields)}; got "
                                 f"{sorted(cp)}")
            values.append(cp[key])
        if key == "label":
            bad = [v for v in values if v not in CODIM2_LABELS]
            if bad:
                raise ValueError(f"codim2 labels must be in {CODIM2_LABELS}; got {bad}")
            arr = np.array(values, dtype=_LABEL_DTYPE).reshape(count)
        elif key == "status":
            bad = [v for v in values if v not in CODIM2_STATUSES]
            if bad:  # a longer text would be cut to the dtype's width
                raise ValueError(f"codim2 statuses must be in {CODIM2_STATUSES}; got {bad}")
            arr = np.array(values, dtype=_STATUS_DTYPE).reshape(count)
        elif spec.kind == "c":
            arr = np.array(values, dtype=np.complex128).reshape(count, 2 * n)
        elif spec.kind == "i":
            arr = np.array(values, dtype=np.int64).reshape(count)
        else:
            arr = np.array(values, dtype=np.float64).reshape(count)
        data_vars[codim2_variable(key)] = (("codim2", *spec.extra_dims), arr, spec.attrs())
    return data_vars


def curve_dataset(*, kind: str, N: int, parameters: Sequence[str], oscillator: ImpactOscillator,
                  options: Any, columns: Mapping[str, Any],
                  codim2_points: Sequence[Mapping[str, Any]], end_status: str,
                  title: str | None = None) -> xr.Dataset:
    """Assemble the dataset of one continued codim-1 curve.

    Parameters
    ----------
    kind : str
        ``"SN"``, ``"PD"``, ``"NS"``, ``"GR"`` or ``"ZV"``.
    N : int
        Forcing periods per impact.
    parameters : (str, str)
        The two parameters of the curve.
    oscillator : ImpactOscillator
        Stored as JSON (the columns hold the parameter values).
    options : dict
        Continuation options, stored as JSON.
    columns : mapping
        One entry per variable of :data:`CURVE_VARIABLES` (plus a column for a
        parameter other than omega/b), shape ``(npoints,)``, ``multipliers`` and
        ``state`` ``(npoints, 2n)``.
    codim2_points : sequence of dict
        Keys ``label``, ``omega``, ``b`` (and the curve's parameters),
        ``delta``, ``point``, ``precision``, ``status``, ``multipliers``.
    end_status : str
        Why the continuation stopped in each direction.
    title : str, optional

    Returns
    -------
    xarray.Dataset
    """
    if kind not in CURVE_KINDS:
        raise ValueError(f"kind must be one of {CURVE_KINDS}; got {kind!r}")
    if not isinstance(oscillator, ImpactOscillator):
        raise TypeError(f"oscillator must be an ImpactOscillator; got {oscillator!r}")
    N = _N(N)
    parameters = [_parameter_name(name) for name in parameters]
    if len(parameters) != 2 or parameters[0] == parameters[1]:
        raise ValueError(f"parameters must be two different parameters; got {parameters!r}")
    n = oscillator.n
    specs = _curve_variables(parameters)
    missing = [k for k in specs if k not in columns]
    unknown = sorted(set(columns) - set(specs))
    if missing or unknown:
        raise ValueError(f"columns: missing {missing}, unknown {unknown}; required {list(specs)}")
    npoints = np.asarray(columns["omega"]).shape[0]
    data_vars: dict[str, Any] = {}
    for key, spec in specs.items():
        shape = (npoints,) + (2 * n,) * len(spec.extra_dims)
        data_vars[key] = (("point", *spec.extra_dims),
                          variable_array(key, columns[key], spec, shape), spec.attrs())
    data_vars.update(codim2_data(codim2_points, parameters, n))
    coords = point_coords(npoints, n)
    attrs = {
        "title": title or f"{kind} curve of periodic {N}-1 motions in "
                          f"({parameters[0]}, {parameters[1]})",
        "impactcont_dataset": "curve",
        "kind": kind,
        "N": N,
        "parameters": ",".join(parameters),
        "oscillator": oscillator.to_json(),
        "options": _options_json(options),
        "end_status": str(end_status),
        **provenance_attributes(),
    }
    return with_parameter_coords(xr.Dataset(data_vars, coords=coords, attrs=attrs))


def validate_curve_dataset(ds: Any) -> xr.Dataset:
    """Check that ``ds`` has the layout of :func:`curve_dataset`; return it.

    Raises
    ------
    TypeError, ValueError
        Naming the missing or malformed attribute or variable.
    """
    check_dataset_kind(ds, "curve", _CURVE_ATTRS)
    kind = ds.attrs["kind"]
    if not isinstance(kind, str) or kind not in CURVE_KINDS:
        raise ValueError(f"attribute 'kind' must be one of {CURVE_KINDS}; got {kind!r}")
    text = ds.attrs["parameters"]
    parameters = split_parameters(text) if isinstance(text, str) else []
    if len(parameters) != 2 or not all(name in PARAMETERS for name in parameters):
        raise ValueError(f"attribute 'parameters' must name two of {sorted(PARAMETERS)}; got "
                         f"{text!r}")
    expected = {k: (("point", *s.extra_dims), s.kind)
                for k, s in _curve_variables(parameters).items()}
    expected.update({codim2_variable(k): (("codim2", *s.extra_dims), s.kind)
                     for k, s in _codim2_fields(parameters).items()})
    check_variables(ds, expected, "curve")
    for key, allowed in (("label", CODIM2_LABELS), ("status", CODIM2_STATUSES)):
        values = set(np.asarray(ds[codim2_variable(key)].values).tolist())
        if not values <= set(allowed):
            raise ValueError(f"{codim2_variable(key)} must hold values in {allowed}; got "
                             f"{sorted(values)}")
    check_user_variables(ds)
    check_attributes(ds, "curve")
    return ds


def kind_of_curve(ds: xr.Dataset) -> str:
    """The kind of a curve dataset: its attribute ``kind`` (a curve in closed form) or
    ``curve_kind`` (a curve followed by shooting, an N-p branch dataset in ``p2``)."""
    return str(ds.attrs["curve_kind"] if "curve_kind" in ds.attrs else ds.attrs["kind"])


def validate_any_curve(ds: Any) -> xr.Dataset:
    """Check a curve dataset of either evaluator; return it.

    A curve in closed form is checked by :func:`validate_curve_dataset`; one followed by
    shooting (attribute ``curve_kind``) as an N-p branch dataset
    (:func:`~impactcont.dataset.multi.validate_multi_impact_dataset`) with the curve's
    ``parameters`` columns and ``stable_side``. A shooting curve written before it had
    ``stable_side`` gets one of False (a WARNING says so): its plots then mark no stable
    motion changing across it.

    Raises
    ------
    TypeError, ValueError
        Naming the missing or malformed attribute or variable.
    """
    if not (isinstance(ds, xr.Dataset) and "curve_kind" in ds.attrs):
        return validate_curve_dataset(ds)
    validate_multi_impact_dataset(ds)
    kind = ds.attrs["curve_kind"]
    kinds = [label.value for label in Label if label.codimension == 1]
    if kind not in kinds:
        raise ValueError(f"attribute 'curve_kind' must be one of {kinds}; got {kind!r}")
    text = ds.attrs.get("parameters")
    parameters = split_parameters(text) if isinstance(text, str) else []
    missing = [name for name in parameters if name not in ds.variables]
    if len(parameters) != 2 or missing:
        raise ValueError(f"attribute 'parameters' must name the curve's two parameter "
                         f"columns 'p1,p2'; got {text!r}" + (f" (no column {missing})"
                                                             if missing else ""))
    if "stable_side" not in ds.variables:
        logger.warning("the %s curve in (%s) has no stable_side (written before it was "
                       "stored): drawn as if no stable motion changed across it", kind, text)
        ds = ds.assign(stable_side=("point", np.zeros(ds.sizes["point"], dtype=bool),
                                    CURVE_VARIABLES["stable_side"].attrs()))
    return ds


def validate_dataset(ds: Any) -> xr.Dataset:
    """Validate a branch (N-1 or N-p), curve or map (either layout of
    :mod:`impactcont.dataset.maps`) dataset by its ``impactcont_dataset``."""
    kind = dataset_tag(ds) if isinstance(ds, xr.Dataset) else None
    if kind == "curve":
        return validate_curve_dataset(ds)
    if kind in MAP_KINDS:
        return validate_map(ds)
    return validate_multi_impact_dataset(ds)


def normalise_dataset(ds: xr.Dataset) -> xr.Dataset:
    """Give the string variables of a curve read from NetCDF their schema dtype, and the
    codim-2 labels of older files their name (:data:`CODIM2_FORMER_LABELS`)."""
    if dataset_tag(ds) == "curve":
        for key, dtype in (("label", _LABEL_DTYPE), ("status", _STATUS_DTYPE)):
            name = codim2_variable(key)
            if name in ds.variables and ds[name].dtype != dtype:
                ds[name] = ds[name].astype(dtype)
        name = codim2_variable("label")
        if name in ds.variables:
            labels = np.asarray(ds[name].values)
            former = np.isin(labels, list(CODIM2_FORMER_LABELS))
            if former.any():
                renamed = labels.copy()
                renamed[former] = [CODIM2_FORMER_LABELS[str(v)] for v in labels[former]]
                ds[name] = ds[name].copy(data=renamed)
    return ds
