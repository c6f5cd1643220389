"""The schema of a branch dataset: variable names, dimensions, units and attributes.

This module is the one place that knows how a branch of periodic N-1 motions
(one impact every N forcing periods) is laid out in an :class:`xarray.Dataset`.
The continuation code hands it plain arrays (:func:`branch_dataset`); plots,
the CLI and :func:`impactcont.dataset.io.load` check a dataset against it
(:func:`validate_branch_dataset`). ``docs/dataset.md`` documents the layout.

Dimensions
----------
``point``
    Accepted continuation points, with an integer coordinate ``0 .. npoints-1``.
    ``omega``, ``b`` and the continued parameter are variables on it;
    :func:`with_parameter_coords` makes them coordinates (to plot against them:
    ``with_parameter_coords(ds).impact_velocity.plot(x="omega")``) and
    :func:`point_table` gives one row per point. In a file they are CF
    auxiliary coordinates of the variables on ``point``.
``multiplier``
    The ``2n`` eigenvalues of the impact-map Jacobian ``G`` (eq. 25).
``component``
    The ``2n`` entries of the state ``[x1 .. xn, x1' .. xn']`` with a string
    coordinate ``["x1", .., "xn", "v1", .., "vn"]``.
``special``
    Special points (SN, PD, NS, GR, ZV) found on the branch; may be empty.

A branch or curve computed with user events (``events=`` of a driver) has one more
dimension, ``event``: the zeros of the event functions (may be empty); the user's
monitors and event functions are point variables ``monitor_<name>``
(:func:`add_user_functions`).
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import logging
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr
from xarray.indexes import Index, PandasIndex

from impactcont.dataset.attributes import (
    ROBUST_INDEXING,
    ROBUST_INDEXING_ATTRIBUTE,
    check_attributes,
    dataset_tag,
    oscillator_attribute,
    split_parameters,
)
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import ParameterView, model_parameter
from impactcont.vocabulary import (
    ELEMENT_FAMILIES,
    LABELS,
    STATUSES,
    Parameter,
    check_positive_integer,
)
from impactcont.vocabulary import PARAMETERS as _PARAMETER_TABLE

__all__ = [
    "ALLOWED_PARAMETERS",
    "CONVENTIONS",
    "DELTA_ALONG_BRANCH",
    "PARAMETERS",
    "POINT_VARIABLES",
    "REFERENCES",
    "SPECIAL_LABELS",
    "SPECIAL_STATUSES",
    "WRAPPED_DELTA",
    "add_user_functions",
    "branch_dataset",
    "check_dataset_kind",
    "check_user_variables",
    "event_variable",
    "monitor_variable",
    "oscillator_from_dataset",
    "point_table",
    "provenance_attributes",
    "robust_attributes",
    "special_variable",
    "split_parameters",
    "state_component_names",
    "validate_branch_dataset",
    "variable_array",
    "with_parameter_coords",
]

logger = logging.getLogger(__name__)

CONVENTIONS = "CF-1.10"
#: The method every dataset comes from (CF attribute ``references``).
REFERENCES = ("Cao Dengqing and Shu Zhongzhou, Periodic motions and robust stability of the "
              "multi-degree-of-freedom systems with clearances, Acta Mechanica Sinica "
              "(Lixue Xuebao); equation numbers in docs/theory.md are the paper's")

#: Labels of special points: saddle-node, period-doubling, Neimark-Sacker,
#: grazing and zero-velocity impact.
SPECIAL_LABELS: tuple[str, ...] = LABELS
#: ``located``: refined to ``precision``; ``bracketed``: only known to lie
#: between two accepted points.
SPECIAL_STATUSES: tuple[str, ...] = STATUSES

# Fixed-width string dtypes so that labels and statuses compare and round-trip
# through NetCDF with one dtype (xarray reads an empty string array back as <U1).
_LABEL_DTYPE = np.dtype(f"<U{max(map(len, SPECIAL_LABELS))}")
_STATUS_DTYPE = np.dtype(f"<U{max(map(len, SPECIAL_STATUSES))}")


@dataclasses.dataclass(frozen=True)
class _Var:
    """Metadata of one variable: dims after ``point``/``special``, dtype kind, attrs."""

    long_name: str
    units: str
    description: str
    kind: str = "f"  # numpy dtype kind: f float, b bool, c complex, i integer, U string
    extra_dims: tuple[str, ...] = ()

    def attrs(self) -> dict[str, str]:
        return {"long_name": self.long_name, "units": self.units,
                "description": self.description}


def _column(p: Parameter) -> _Var:
    """The metadata of a parameter's column, from its vocabulary record."""
    return _Var(p.long_name, p.unit, p.description)


#: Parameters a branch may be continued in, with their metadata: the named parameters
#: and the element names (1-based: ``m<j>``, ``k<j>``, ``c<j>``, ``M[i,j]``, ``K[i,j]``,
#: ``C[i,j]``, ``F[j]``). ``omega`` and ``b`` are always stored; another continued
#: parameter adds its own column.
PARAMETERS: Mapping[str, _Var] = ParameterView(_column)
#: The names :data:`PARAMETERS` resolves, for error messages.
ALLOWED_PARAMETERS = (f"one of {list(_PARAMETER_TABLE)} or an element name "
                      f"{list(ELEMENT_FAMILIES)} (1-based, e.g. 'k2', 'M[1,2]', 'F[2]')")

#: What ``delta`` of an N-1 branch holds: the continuation's unknown, continuous along
#: the branch, so that a branch through both roots of eq. (15) or once round the circle
#: stays one smooth curve (an N-p branch stores its phases wrapped, ``WRAPPED_DELTA``).
DELTA_ALONG_BRANCH = ("Forcing phase delta at the impact (eq. 15), continuous along each "
                      "connected component of the branch: not wrapped into one turn, it may "
                      "take any value (delta + 2 pi k is the same motion).")
#: What ``delta`` holds where it is wrapped (an N-p branch, the orbits of one point).
WRAPPED_DELTA = "Forcing phase delta at the impact, wrapped to (-pi, pi] (eq. 15)."

#: Variables on the ``point`` dimension, in the order they are stored.
POINT_VARIABLES: dict[str, _Var] = {
    "omega": PARAMETERS["omega"],
    "b": PARAMETERS["b"],
    "delta": _Var("impact phase", "rad", DELTA_ALONG_BRANCH),
    "impact_velocity": _Var("impact velocity", "1",
                            "Velocity x1'(T-) of mass 1 just before the impact (h2 of eq. 22)."),
    "gap_min": _Var("minimum gap", "1",
                    "Smallest b - x1 at the interior maxima of x1 over one period; "
                    "+inf when x1 has none (eq. 16)."),
    "spectral_radius": _Var("spectral radius", "1",
                            "Largest modulus of the multipliers, rho(G) (eq. 25)."),
    "stable": _Var("asymptotically stable", "1",
                   "spectral_radius < 1 (Theorem 3.1).", kind="b"),
    "physical": _Var("physically realisable", "1",
                     "impact_velocity > 0 and gap_min > 0: no contact inside the period "
                     "(eq. 16).", kind="b"),
    "arclength": _Var("pseudo-arclength", "1",
                      "Pseudo-arclength of the continuation at the point."),
    "multipliers": _Var("Floquet multipliers", "1",
                        "Eigenvalues of the impact-map Jacobian G (eq. 25), "
                        "largest modulus first.", kind="c", extra_dims=("multiplier",)),
    "state": _Var("state after impact", "1",
                  "State X(0) = [x1..xn, x1'..xn'] right after the impact (eq. 13).",
                  extra_dims=("component",)),
}

#: Point variables a branch may carry (older files and other drivers do without).
OPTIONAL_POINT_VARIABLES: dict[str, _Var] = {
    "connected_component": _Var("connected component", "1",
                                "Index of the connected component of the solution set the "
                                "point belongs to (continuation order within each).", kind="i"),
}

# Keys of a special-point dict that are not parameter values.
_SPECIAL_FIELDS: dict[str, _Var] = {
    "label": _Var("special point label", "1",
                  "SN saddle-node, PD period-doubling, NS Neimark-Sacker, GR grazing, "
                  "ZV zero-velocity impact.", kind="U"),
    "delta": _Var("impact phase at special point", "rad",
                  "Forcing phase delta at the impact at the special point, continued as "
                  "the branch's delta (not wrapped on an N-1 branch)."),
    "point": _Var("nearest point", "1",
                  "Index on the point dimension of the accepted point nearest to the "
                  "special point.", kind="i"),
    "bracket_lo": _Var("bracket lower end", "1",
                       "Lower end of the interval of the continued parameter that brackets "
                       "the special point."),
    "bracket_hi": _Var("bracket upper end", "1",
                       "Upper end of the interval of the continued parameter that brackets "
                       "the special point."),
    "precision": _Var("location precision", "1",
                      "Precision of the special point in the continued parameter."),
    "status": _Var("location status", "1",
                   "located: refined to precision; bracketed: only bracketed.", kind="U"),
    "multipliers": _Var("Floquet multipliers at special point", "1",
                        "Eigenvalues of G (eq. 25) at the special point.", kind="c",
                        extra_dims=("multiplier",)),
}

#: Special-point fields of the motion at the point (a file written by an older
#: impactcont has none; a special-point dict without them stores NaN).
OPTIONAL_SPECIAL_FIELDS: dict[str, _Var] = {
    "impact_velocity": _Var("impact velocity at special point", "1",
                            "Velocity x1'(T-) of mass 1 before the impact of the motion at the "
                            "special point (h2 of eq. 22; the smallest over the impacts of an "
                            "N-p motion)."),
    "gap_min": _Var("minimum gap at special point", "1",
                    "Smallest b - x1 at the interior maxima of x1 of the motion at the special "
                    "point (eq. 16); +inf when x1 has none."),
}

# Dataset attributes every branch dataset carries.
_REQUIRED_ATTRS = ("title", "N", "parameter", "oscillator", "options", "impactcont_version",
                   "Conventions", "history")


def check_variables(ds: xr.Dataset, expected: Mapping[str, tuple[tuple[str, ...], str]],
                    what: str) -> None:
    """Check that `ds` has every variable of `expected` (``{name: (dims, dtype kind)}``).

    Raises
    ------
    ValueError
        Naming the missing variables, or the variable with other dims or dtype.
    """
    missing = [k for k in expected if k not in ds.variables]
    if missing:
        raise ValueError(f"not a {what} dataset: missing variable(s) {missing}")
    for key, (dims, kind) in expected.items():
        var = ds[key]
        if var.dims != dims:
            raise ValueError(f"variable {key!r} must have dims {dims}; got {var.dims}")
        if var.dtype.kind != kind and not (kind == "f" and var.dtype.kind in "iu"):
            raise ValueError(f"variable {key!r} must have dtype kind {kind!r}; "
                             f"got dtype {var.dtype}")


def check_dataset_kind(ds: Any, kind: str, attrs: Sequence[str]) -> None:
    """Check that `ds` is a Dataset of layout `kind` (its ``impactcont_dataset``) with the
    attributes `attrs`.

    Raises
    ------
    TypeError
        `ds` is not an :class:`xarray.Dataset`.
    ValueError
        Naming the missing attributes, or the layout is another.
    """
    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"expected an xarray.Dataset of a {kind}; got {type(ds).__name__}")
    missing = [a for a in attrs if a not in ds.attrs]
    if missing or dataset_tag(ds) != kind:
        raise ValueError(f"not a {kind} dataset: missing attribute(s) {missing} or "
                         f"impactcont_dataset != {kind!r}")


def variable_array(key: str, value: Any, spec: _Var, shape: tuple[int, ...]) -> Any:
    """`value` as the array of the variable `key` of `spec` on a grid of `shape`.

    A dask array (a map larger than memory) stays lazy: its shape and dtype only.

    Raises
    ------
    ValueError
        `value` has another shape (named with both shapes).
    """
    a = value if hasattr(value, "dask") else np.asarray(value)
    if a.shape != shape:
        raise ValueError(f"column {key!r} must have shape {shape}; got shape {a.shape}")
    dtype = {"f": np.float64, "b": bool, "c": np.complex128, "i": np.int64}[spec.kind]
    return a.astype(dtype)


def point_coords(npoints: int, n: int) -> dict[str, Any]:
    """The ``point`` and ``component`` coordinates of a branch or curve of an n-mass system."""
    return {
        "point": ("point", np.arange(npoints, dtype=np.int64),
                  {"long_name": "continuation point index", "units": "1"}),
        "component": ("component", np.array(state_component_names(n)),
                      {"long_name": "state component",
                       "description": "x<i>: displacement of mass i; v<i>: its velocity."}),
    }


def provenance_attributes(action: str = "created") -> dict[str, str]:
    """The CF attributes saying where a dataset comes from, and which conventions it follows.

    Parameters
    ----------
    action : str, optional
        What impactcont did, for ``history`` (``"created"``, ``"written"``).

    Returns
    -------
    dict of str to str
        ``impactcont_version``, ``Conventions`` (:data:`CONVENTIONS`), ``history``
        (ISO 8601 UTC time, ``action`` and the version), ``source`` (the package
        and its method) and ``references`` (:data:`REFERENCES`, the paper).
    """
    from impactcont import __version__

    now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    return {"impactcont_version": __version__, "Conventions": CONVENTIONS,
            "history": f"{now} {action} by impactcont {__version__}",
            "source": f"impactcont {__version__}: periodic impacting motions in closed form "
                      "(eq. 12-15), their stability from the impact-map Jacobian G (eq. 25), "
                      "pseudo-arclength continuation, exact event-driven simulation",
            "references": REFERENCES}


def robust_attributes(vary: Mapping[str, Sequence[float]], nominal: Mapping[str, float],
                      argmax: Mapping[tuple[int, int], Mapping[str, float]]) -> dict[str, str]:
    """The attributes of a robust dataset that name parameters: ``vary``, ``nominal`` and
    ``argmax`` as JSON, and ``element_indexing`` (1-based, as every parameter name).

    A robust dataset without ``element_indexing`` is read as written before it existed,
    with 0-based ``F[i]`` (:func:`~impactcont.dataset.attributes.upgrade_robust_attributes`),
    so every writer of a robust dataset writes these together.

    Parameters
    ----------
    vary, nominal : mapping
        :attr:`~impactcont.orbit.robust.RobustStability.vary` and ``nominal``.
    argmax : mapping of (int, int) to mapping
        :attr:`~impactcont.orbit.robust.RobustStability.argmax`, stored under ``"i,j"``.
    """
    return {"vary": json.dumps({k: [float(lo), float(hi)] for k, (lo, hi) in vary.items()}),
            "nominal": json.dumps({k: float(v) for k, v in nominal.items()}),
            "argmax": json.dumps({f"{i},{j}": dict(q) for (i, j), q in argmax.items()}),
            ROBUST_INDEXING_ATTRIBUTE: ROBUST_INDEXING}


def parameter_names(ds: xr.Dataset) -> list[str]:
    """The parameters that label the points of a branch or curve, in the order stored.

    ``omega``, ``b`` and the continued parameter (attribute ``parameter``, a
    branch) or the two parameters (attribute ``parameters``, a curve), where
    the dataset has them as variables on ``point``; none for other datasets.
    """
    names = ["omega", "b"]
    parameter, parameters = ds.attrs.get("parameter"), ds.attrs.get("parameters")
    if isinstance(parameter, str):
        names.append(parameter)
    if isinstance(parameters, str):
        names += split_parameters(parameters)
    if not ({"parameter", "parameters"} & set(ds.attrs)):
        return []
    return [k for k in dict.fromkeys(names)
            if k in ds.variables and ds.variables[k].dims == ("point",)]


def with_parameter_coords(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` with ``omega``, ``b`` and the continued parameter(s) as coordinates on ``point``.

    As coordinates every variable on ``point`` carries them, so that it plots
    against them: ``branch.impact_velocity.plot(x="omega")``. The datasets the
    package builds and loads have them so already (this function makes them so);
    a dataset built by hand with them as data variables gets them here. The values
    are not copied.

    Parameters
    ----------
    ds : xarray.Dataset
        A branch or curve dataset.

    Returns
    -------
    xarray.Dataset

    Raises
    ------
    TypeError
        ``ds`` is not an :class:`xarray.Dataset`.
    ValueError
        ``ds`` has no parameter column on ``point`` (not a branch or curve).
    """
    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"ds must be an xarray.Dataset; got {type(ds).__name__}")
    names = parameter_names(ds)
    if not names:
        raise ValueError("ds must be a branch or curve dataset (attribute 'parameter' or "
                         "'parameters', with the parameters' columns on 'point'); got a "
                         f"dataset with attributes {sorted(ds.attrs)} and variables "
                         f"{sorted(map(str, ds.variables))}")
    return ds.set_coords(names)


def point_table(ds: xr.Dataset, dim: str = "point") -> Any:
    """One row per entry of ``dim`` (per point of a branch or curve): a pandas DataFrame.

    ``ds.to_dataframe()`` of a branch crosses every dimension (``point`` x
    ``multiplier`` x ``component`` x ``special``); this table has one row per
    point and one column per value there: each variable on ``dim`` alone, and
    one column per entry of the further dimensions of the others
    (``state_x1``, ..., ``multipliers_0``, ...; ``state_k_1_v2`` for impact 1 of
    an N-p branch; the labels ``component_label`` of a file opened with plain xarray
    name its columns as well). The parameters (:func:`parameter_names`: ``omega``, ``b``,
    the continued parameter) come first. ``dim="special"`` gives the special
    points.

    Parameters
    ----------
    ds : xarray.Dataset
        A branch, curve or any dataset with the dimension ``dim``.
    dim : str, optional
        The dimension of the rows (``"point"`` by default).

    Returns
    -------
    pandas.DataFrame
        Indexed by the coordinate of ``dim`` (``0 .. npoints-1``).

    Raises
    ------
    TypeError
        ``ds`` is not an :class:`xarray.Dataset`.
    ValueError
        ``ds`` has no dimension ``dim``.
    """
    import pandas as pd

    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"ds must be an xarray.Dataset; got {type(ds).__name__}")
    if not isinstance(dim, str) or dim not in ds.dims:
        raise ValueError(f"dim must be a dimension of the dataset, one of {sorted(ds.dims)}; "
                         f"got {dim!r}")
    index = ds.indexes[dim] if dim in ds.indexes else pd.RangeIndex(ds.sizes[dim], name=dim)
    columns: dict[str, np.ndarray] = {}
    first = parameter_names(ds) if dim == "point" else []
    names = dict.fromkeys([*first, *(k for k in ds.coords if k != dim), *ds.data_vars])
    for name in names:
        var = ds[name].variable
        if var.dims[:1] != (dim,) or dim in var.dims[1:]:
            continue
        values = np.asarray(var.values)
        if var.ndim == 1:
            columns[str(name)] = values
            continue
        labels = [_entry_labels(ds, d) for d in var.dims[1:]]
        flat = values.reshape(values.shape[0], -1)
        for j, where in enumerate(np.ndindex(*values.shape[1:])):
            suffix = "_".join(str(labels[axis][i]) for axis, i in enumerate(where))
            columns[f"{name}_{suffix}"] = flat[:, j]
    return pd.DataFrame(columns, index=index)


def _entry_labels(ds: xr.Dataset, dim: Any) -> np.ndarray:
    """The names of the entries of ``dim`` in column names: its text labels ``<dim>_label``
    where the dataset has them (a file opened with plain xarray: ``component_label``
    ``x1, v1`` beside the index ``0, 1``), else its coordinate, else ``0 .. k-1``."""
    label = f"{dim}_label"
    if label in ds.coords and ds[label].dims == (dim,):
        return np.asarray(ds[label].values)
    return np.asarray(ds[dim].values) if dim in ds.coords else np.arange(ds.sizes[dim])


def special_variable(key: str) -> str:
    """Name of the dataset variable holding special-point field ``key`` (``special_<key>``)."""
    return f"special_{key}"


def state_component_names(n: int) -> list[str]:
    """Names of the state components ``[x1..xn, v1..vn]`` (``v`` for ``x'``)."""
    return [f"x{i}" for i in range(1, n + 1)] + [f"v{i}" for i in range(1, n + 1)]


def _point_variables(parameter: str) -> dict[str, _Var]:
    """The point variables of a branch continued in ``parameter``."""
    out = dict(POINT_VARIABLES)
    if parameter not in out:
        out = {parameter: PARAMETERS[parameter], **out}
    return out


def _special_variables(parameter: str) -> dict[str, _Var]:
    """Special-point fields (dict keys) of a branch continued in ``parameter``."""
    fields = {"label": _SPECIAL_FIELDS["label"]}
    for name in dict.fromkeys(["omega", "b", parameter]):
        p = PARAMETERS[name]
        fields[name] = _Var(f"{p.long_name} at special point", p.units,
                            f"{p.description.rstrip('.')} at the special point.")
    fields.update({k: v for k, v in _SPECIAL_FIELDS.items() if k != "label"})
    return fields


def _parameter_name(parameter: Any) -> str:
    if not isinstance(parameter, str):
        raise TypeError(f"parameter must be a str, {ALLOWED_PARAMETERS}; got {parameter!r}")
    if parameter not in PARAMETERS:
        raise ValueError(f"parameter must be {ALLOWED_PARAMETERS}; got {parameter!r}")
    return parameter


def _N(N: Any) -> int:
    return check_positive_integer("N", N, "forcing periods per impact")


def _json_default(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (tuple, set, frozenset)):
        return list(value)
    raise TypeError(f"options must be JSON-serialisable; got {value!r} "
                    f"of type {type(value).__name__}")


def _options_json(options: Any) -> str:
    if dataclasses.is_dataclass(options) and not isinstance(options, type):
        options = dataclasses.asdict(options)
    if not isinstance(options, Mapping):
        raise TypeError(f"options must be a mapping (or a dataclass instance); got {options!r}")
    return json.dumps(dict(options), default=_json_default, sort_keys=True)


def _column(key: str, value: Any, spec: _Var, shape: tuple[int, ...], what: str) -> np.ndarray:
    """``value`` as an array of ``spec.kind`` and ``shape``; ValueError naming ``key`` if not."""
    try:
        a = np.asarray(value)
    except (TypeError, ValueError) as exc:  # pragma: no cover - ragged input
        raise ValueError(f"{what} {key!r} must be array_like; got {value!r}") from exc
    if a.shape != shape:
        raise ValueError(f"{what} {key!r} must have shape {shape}; got shape {a.shape}")
    if spec.kind == "b":
        if a.dtype.kind == "b":
            return a.astype(bool)
        if a.dtype.kind in "iuf" and np.all(np.isin(a, (0, 1))):
            return a.astype(bool)
        raise ValueError(f"{what} {key!r} must be boolean (or 0/1); got dtype {a.dtype} "
                         f"with values {np.unique(a)[:5].tolist()}")
    if spec.kind == "c":
        if a.dtype.kind not in "iufc":
            raise ValueError(f"{what} {key!r} must be numeric (complex); got dtype {a.dtype}")
        return a.astype(np.complex128)
    if spec.kind == "f":
        if a.dtype.kind not in "iuf":
            raise ValueError(f"{what} {key!r} must be real numbers; got dtype {a.dtype}")
        return a.astype(np.float64)
    if spec.kind == "i":
        if a.dtype.kind not in "iu":
            raise ValueError(f"{what} {key!r} must be integers; got dtype {a.dtype}")
        return a.astype(np.int64)
    raise AssertionError(f"unhandled kind {spec.kind}")  # pragma: no cover - schema bug


def _special_arrays(special_points: Any, parameter: str, n: int, npoints: int
                    ) -> dict[str, np.ndarray]:
    """Columns (on ``special``) of the special-point dicts, validated."""
    if isinstance(special_points, (str, Mapping)) or not isinstance(special_points, Sequence):
        raise TypeError(f"special_points must be a list of dicts; got {special_points!r}")
    fields = _special_variables(parameter)
    cols: dict[str, list[Any]] = {key: [] for key in fields}
    for i, sp in enumerate(special_points):
        where = f"special_points[{i}]"
        if not isinstance(sp, Mapping):
            raise TypeError(f"{where} must be a dict; got {sp!r}")
        missing = [k for k in fields if k not in sp]
        if missing:
            raise ValueError(f"{where} is missing key(s) {missing}; required: {list(fields)}")
        unknown = sorted(set(sp) - set(fields) - set(OPTIONAL_SPECIAL_FIELDS))
        if unknown:
            raise ValueError(f"{where} has unknown key(s) {unknown}; allowed: {list(fields)}")
        label = sp["label"]
        if label not in SPECIAL_LABELS:
            raise ValueError(f"{where}['label'] must be one of {list(SPECIAL_LABELS)}; "
                             f"got {label!r}")
        status = sp["status"]
        if status not in SPECIAL_STATUSES:
            raise ValueError(f"{where}['status'] must be one of {list(SPECIAL_STATUSES)}; "
                             f"got {status!r}")
        point = sp["point"]
        if (isinstance(point, bool) or not isinstance(point, (int, np.integer))
                or not 0 <= point < npoints):
            raise ValueError(f"{where}['point'] must be an integer index in [0, {npoints}); "
                             f"got {point!r}")
        for key, spec in fields.items():
            if spec.kind != "f":
                continue
            value = sp[key]
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer,
                                                                 np.floating)):
                raise ValueError(f"{where}[{key!r}] must be a real number; got {value!r}")
        precision = float(sp["precision"])
        if not (precision >= 0 or math.isnan(precision)):
            raise ValueError(f"{where}['precision'] must be >= 0 (or NaN); got {precision!r}")
        lo, hi = float(sp["bracket_lo"]), float(sp["bracket_hi"])
        if lo > hi:
            raise ValueError(f"{where} must have bracket_lo <= bracket_hi; got "
                             f"bracket_lo={lo!r}, bracket_hi={hi!r}")
        mult = _column("multipliers", sp["multipliers"], fields["multipliers"], (2 * n,),
                       f"{where} key")
        for key in fields:
            cols[key].append(mult if key == "multipliers" else sp[key])
        for key in OPTIONAL_SPECIAL_FIELDS:
            value = sp.get(key, math.nan)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer,
                                                                 np.floating)):
                raise ValueError(f"{where}[{key!r}] must be a real number; got {value!r}")
            cols.setdefault(key, []).append(float(value))
    out: dict[str, np.ndarray] = {key: np.array(cols.get(key, []), dtype=np.float64).reshape(
        len(special_points)) for key in OPTIONAL_SPECIAL_FIELDS}
    count = len(special_points)
    for key, spec in fields.items():
        if spec.kind == "U":
            dtype = _LABEL_DTYPE if key == "label" else _STATUS_DTYPE
            out[key] = np.array(cols[key], dtype=dtype).reshape(count)
        elif spec.kind == "i":
            out[key] = np.array(cols[key], dtype=np.int64).reshape(count)
        elif spec.kind == "c":
            out[key] = np.array(cols[key], dtype=np.complex128).reshape(count, 2 * n)
        else:
            out[key] = np.array(cols[key], dtype=np.float64).reshape(count)
    return out


def _assembled(variables: Mapping[str, xr.Variable], coord_names: Sequence[str],
               attrs: dict[str, Any]) -> xr.Dataset:
    """The dataset of checked `variables` (in their order; those in `coord_names` are
    coordinates, a variable named as its one dimension with its default index), built at
    once.

    What ``xr.Dataset(data_vars, coords=coords, attrs=attrs).set_coords(...)`` builds from
    the same variables, without its merge and alignment (and the copy of
    :func:`with_parameter_coords`): a branch dataset's variables share their dimensions by
    construction (:func:`branch_dataset` checks every shape), and the general constructor
    took most of the time of a short branch (a 9-point symmetric branch: 1.1 of its 1.9 ms
    of dataset; tests/dataset/test_schema.py compares both constructions).
    ``xr.Dataset._construct_direct`` is private to xarray: where a release has it no more
    or changes its arguments, :func:`_constructed` builds the same dataset publicly (the
    test checks that too).
    """
    direct = _direct_constructor()
    if direct is not None:
        indexes: dict[str, Index] = {}
        assembled: dict[str, xr.Variable] = {}
        for name, variable in variables.items():
            if variable.dims == (name,):  # a dimension coordinate: its default (pandas) index
                index = PandasIndex.from_variables({name: variable}, options={})
                assembled.update(index.create_variables({name: variable}))
                indexes[name] = index
            else:
                assembled[name] = variable
        try:
            return direct(assembled, set(coord_names), attrs=attrs, indexes=indexes)
        except TypeError:  # a private API whose signature changed: the public way below
            logger.debug("xr.Dataset._construct_direct refused its arguments; built by "
                         "xr.Dataset")
    return _constructed(variables, coord_names, attrs)


def _direct_constructor() -> Callable[..., xr.Dataset] | None:
    """xarray's private ``xr.Dataset._construct_direct``, or None where a release has it no
    more."""
    return getattr(xr.Dataset, "_construct_direct", None)


def _constructed(variables: Mapping[str, xr.Variable], coord_names: Sequence[str],
                 attrs: dict[str, Any]) -> xr.Dataset:
    """:func:`_assembled` by xarray's public constructor (its merge and alignment): where
    the private ``xr.Dataset._construct_direct`` is gone or takes other arguments."""
    coords = set(coord_names)
    return xr.Dataset({k: v for k, v in variables.items() if k not in coords},
                      coords={k: v for k, v in variables.items() if k in coords},
                      attrs=attrs)


def branch_dataset(*, parameter: str, N: int, oscillator: ImpactOscillator, options: Any,
                   columns: Mapping[str, Any], special_points: Sequence[Mapping[str, Any]],
                   title: str | None = None,
                   more_variables: Mapping[str, xr.Variable] | None = None,
                   more_coords: Mapping[str, Any] | None = None) -> xr.Dataset:
    """Assemble the dataset of one continued branch of periodic N-1 motions.

    Parameters
    ----------
    parameter : str
        The continued parameter, a name of :data:`PARAMETERS` (``"omega"``, ``"b"``,
        ``"R"``, ..., or an element: ``"k2"``, ``"M[1,2]"``, ``"F[2]"``).
    N : int
        Forcing periods per impact (``>= 1``).
    oscillator : ImpactOscillator
        The oscillator; stored as JSON (its continued parameter is the value
        at the start of the branch, or any value: the columns are authoritative).
    options : dict or dataclass instance
        Continuation options, stored as JSON text.
    columns : mapping of str to array_like
        One entry per variable of :data:`POINT_VARIABLES`, each of shape
        ``(npoints,)`` except ``multipliers`` (``(npoints, 2n)``, complex) and
        ``state`` (``(npoints, 2n)``, real). ``stable`` and ``physical`` are
        boolean. A ``parameter`` other than ``omega``/``b`` needs its own column.
    special_points : sequence of dict
        Each with keys ``label`` (one of :data:`SPECIAL_LABELS`), ``omega``,
        ``b`` (and the continued parameter), ``delta``, ``point`` (index of the
        nearest point), ``bracket_lo <= bracket_hi`` (parameter values),
        ``precision`` (``>= 0`` or NaN), ``status`` (one of
        :data:`SPECIAL_STATUSES`) and ``multipliers`` (shape ``(2n,)``).
    title : str, optional
        Dataset title; a description of the branch by default.
    more_variables, more_coords : mapping, optional
        Further variables (checked by the caller) and coordinates, added in the one
        construction of the dataset (the N-p per-impact layout,
        :func:`impactcont.dataset.multi.multi_impact_dataset`).

    Returns
    -------
    xarray.Dataset
        Dimensions ``point``, ``multiplier``, ``component``, ``special``;
        see ``docs/dataset.md``.

    Raises
    ------
    ValueError
        A column or special-point key is missing, unknown, of the wrong
        shape or dtype, or a label/status/index is out of range.
    TypeError
        ``oscillator``, ``options``, ``columns`` or ``special_points`` has the
        wrong type.
    """
    parameter = _parameter_name(parameter)
    N = _N(N)
    if not isinstance(oscillator, ImpactOscillator):
        raise TypeError(f"oscillator must be an ImpactOscillator; got {oscillator!r}")
    if not isinstance(columns, Mapping):
        raise TypeError(f"columns must be a mapping of variable name to array; got {columns!r}")
    n = oscillator.n
    specs = _point_variables(parameter)
    missing = [k for k in specs if k not in columns]
    if missing:
        raise ValueError(f"columns is missing key(s) {missing}; required: {list(specs)}")
    specs.update({k: v for k, v in OPTIONAL_POINT_VARIABLES.items() if k in columns})
    # another parameter's column (a curve's first parameter, e.g. 'k2' or 'gap[A]')
    specs.update({k: PARAMETERS[k] for k in columns if k not in specs and k in PARAMETERS})
    unknown = sorted(set(columns) - set(specs))
    if unknown:
        raise ValueError(f"columns has unknown key(s) {unknown}; allowed: {list(specs)}")
    first = np.asarray(columns[parameter])
    if first.ndim != 1:
        raise ValueError(f"column {parameter!r} must be 1-D (npoints,); got shape {first.shape}")
    npoints = first.shape[0]
    if npoints == 0:
        raise ValueError(f"column {parameter!r} must have at least one point; got length 0")

    data_vars: dict[str, xr.Variable] = {}
    for key, spec in specs.items():
        shape = (npoints,) + (2 * n,) * len(spec.extra_dims)
        arr = _column(key, columns[key], spec, shape, "column")
        data_vars[key] = xr.Variable(("point", *spec.extra_dims), arr, spec.attrs())
    for key in (parameter, "arclength"):
        bad = ~np.isfinite(data_vars[key].values)
        if np.any(bad):
            raise ValueError(f"column {key!r} must be finite; got non-finite values at points "
                             f"{np.flatnonzero(bad)[:10].tolist()}")

    special = _special_arrays(special_points, parameter, n, npoints)
    for key, spec in {**_special_variables(parameter), **OPTIONAL_SPECIAL_FIELDS}.items():
        data_vars[special_variable(key)] = xr.Variable(("special", *spec.extra_dims),
                                                       special[key], spec.attrs())

    data_vars.update(more_variables or {})
    coords = {name: xr.as_variable(value)
              for name, value in {**point_coords(npoints, n), **(more_coords or {})}.items()}
    attrs = {
        "title": title if title is not None else
        f"Branch of periodic {N}-1 impacting motions continued in {parameter}",
        "N": N,
        "parameter": parameter,
        "oscillator": oscillator.to_json(),
        "options": _options_json(options),
        **provenance_attributes(),
    }
    # omega, b and the continued parameter as coordinates (what with_parameter_coords makes)
    on_point = [k for k in dict.fromkeys(["omega", "b", parameter])
                if k in data_vars and data_vars[k].dims == ("point",)]
    ds = _assembled({**data_vars, **coords}, [*on_point, *coords], attrs)
    logger.debug("branch dataset: parameter=%s N=%d npoints=%d special=%d", parameter, N,
                 npoints, ds.sizes["special"])
    return ds


# -- user events and monitors -------------------------------------------------------------------
#: Fields of a user event (dimension ``event``), besides the parameters' values there
#: (``event_omega``, ``event_b``, ``event_<parameter>``: those of :func:`parameter_names`).
EVENT_FIELDS: dict[str, _Var] = {
    "name": _Var("event name", "1", "Name of the user event (its key in the driver's "
                 "events=) whose function vanishes here.", kind="U"),
    "delta": _Var("impact phase at event", "rad",
                  "Forcing phase delta at the impact (impact 0 of an N-p motion) at the event."),
    "point": _Var("nearest point", "1", "Index on the point dimension of the accepted point "
                  "nearest to the event.", kind="i"),
    "precision": _Var("location precision", "1",
                      "Bound on the error of the event's location in the continued "
                      "parameter (in both parameters of a curve, max-norm)."),
    "status": _Var("location status", "1",
                   "located: refined to precision; bracketed: only bracketed (the function "
                   "jumps there, or the location failed).", kind="U"),
}
#: Dataset attributes naming the user's events and monitors (comma-separated names).
USER_EVENTS_ATTR, USER_MONITORS_ATTR = "user_events", "user_monitors"


def event_variable(key: str) -> str:
    """Name of the dataset variable holding user-event field ``key`` (``event_<key>``)."""
    return f"event_{key}"


def monitor_variable(name: str) -> str:
    """Name of the point variable holding the user's monitor (or event function) `name`."""
    return f"monitor_{name}"


def _names(ds: xr.Dataset, attr: str) -> list[str]:
    value = ds.attrs.get(attr, "")
    if not isinstance(value, str):
        raise ValueError(f"attribute {attr!r} must be comma-separated names; got {value!r}")
    return [name for name in value.split(",") if name]


def _event_parameters(ds: xr.Dataset) -> list[str]:
    names = parameter_names(ds)
    if not names:
        raise ValueError("a dataset with user events must be a branch or curve (attribute "
                         "'parameter' or 'parameters', their columns on 'point')")
    return names


def add_user_functions(ds: xr.Dataset, *, monitors: Mapping[str, Any],
                       events: Sequence[str], event_points: Sequence[Mapping[str, Any]]
                       ) -> xr.Dataset:
    """`ds` (a branch or curve) with the user's monitors and located events.

    Parameters
    ----------
    ds : xarray.Dataset
        A branch or curve dataset (its parameters: :func:`parameter_names`).
    monitors : mapping of str to array_like
        ``name -> values`` at every point, shape ``(npoints,)``: every monitor and every
        event function, stored as ``monitor_<name>``.
    events : sequence of str
        The names of the events asked for (attribute ``user_events``); the dimension
        ``event`` is added, empty when none was found.
    event_points : sequence of dict
        Each with the keys of :data:`EVENT_FIELDS` and the value of every parameter.

    Returns
    -------
    xarray.Dataset
        A new dataset; ``user_monitors`` names the monitors (those not events).

    Raises
    ------
    ValueError
        A misshapen or non-finite monitor, a missing key, an unknown event name or
        status, or a point index out of range.
    """
    npoints = ds.sizes["point"]
    out = ds.copy()
    for name, values in monitors.items():
        column = np.asarray(values, dtype=float)
        if column.shape != (npoints,) or not np.all(np.isfinite(column)):
            raise ValueError(f"monitor {name!r} must be {npoints} finite values; got shape "
                             f"{column.shape}")
        kind = "event function" if name in events else "monitor"
        out[monitor_variable(name)] = ("point", column, {
            "long_name": f"user {kind} {name}", "units": "1",
            "description": f"Value of the user's {kind} {name!r} (a function of the motion) "
                           "at each point" + (": its zeros are the events of that name."
                                              if name in events else ".")})
    parameters = _event_parameters(ds)
    fields = {**{name: PARAMETERS[name] for name in parameters}, **EVENT_FIELDS}
    columns: dict[str, list[Any]] = {key: [] for key in fields}
    for i, record in enumerate(event_points):
        missing = [key for key in fields if key not in record]
        if missing:
            raise ValueError(f"event_points[{i}] is missing key(s) {missing}")
        for key in fields:
            columns[key].append(record[key])
    for key, spec in fields.items():
        if spec.kind == "U":
            width = max([1, *map(len, columns[key]), *(map(len, events) if key == "name"
                                                         else map(len, SPECIAL_STATUSES))])
            data = np.array(columns[key], dtype=f"<U{width}")
        else:
            data = np.array(columns[key], dtype=np.int64 if spec.kind == "i" else np.float64)
        attrs = spec.attrs() if key in EVENT_FIELDS else {
            "long_name": f"{spec.long_name} at event", "units": spec.units,
            "description": f"{spec.description.rstrip('.')} at the event."}
        out[event_variable(key)] = ("event", data, attrs)
    out.attrs[USER_EVENTS_ATTR] = ",".join(events)
    out.attrs[USER_MONITORS_ATTR] = ",".join(name for name in monitors if name not in events)
    check_user_variables(out)
    return out


def check_user_variables(ds: xr.Dataset) -> None:
    """Check the user's events and monitors of a branch or curve, where it has them.

    Raises
    ------
    ValueError
        A monitor named by ``user_events`` or ``user_monitors`` missing or not real on
        ``point``; an event variable missing or with other dims or dtype; an event name
        not in ``user_events``, a status not in :data:`SPECIAL_STATUSES`, or a point
        index out of range.
    """
    events, monitors = _names(ds, USER_EVENTS_ATTR), _names(ds, USER_MONITORS_ATTR)
    check_variables(ds, {monitor_variable(name): (("point",), "f")
                         for name in [*events, *monitors]}, "branch or curve")
    if not events and "event" not in ds.dims:
        return
    fields = {**{name: PARAMETERS[name] for name in _event_parameters(ds)}, **EVENT_FIELDS}
    check_variables(ds, {event_variable(key): (("event",), spec.kind)
                         for key, spec in fields.items()}, "branch or curve with user events")
    names = set(np.asarray(ds[event_variable("name")].values).tolist())
    if not names <= set(events):
        raise ValueError(f"variable 'event_name' must hold the names of attribute "
                         f"{USER_EVENTS_ATTR!r} {events}; got {sorted(names)}")
    statuses = set(np.asarray(ds[event_variable("status")].values).tolist())
    if not statuses <= set(SPECIAL_STATUSES):
        raise ValueError(f"variable 'event_status' must hold statuses in "
                         f"{list(SPECIAL_STATUSES)}; got {sorted(statuses)}")
    point = np.asarray(ds[event_variable("point")].values)
    if point.size and not (point.min() >= 0 and point.max() < ds.sizes["point"]):
        raise ValueError(f"variable 'event_point' must hold indices in [0, "
                         f"{ds.sizes['point']}); got {point.tolist()}")


def validate_branch_dataset(ds: Any) -> xr.Dataset:
    """Check that ``ds`` has the layout of :func:`branch_dataset`.

    Parameters
    ----------
    ds : xarray.Dataset

    Returns
    -------
    xarray.Dataset
        ``ds`` itself, for chaining.

    Raises
    ------
    TypeError
        ``ds`` is not an :class:`xarray.Dataset`.
    ValueError
        An attribute, variable or dimension is missing or has the wrong
        dimensions or dtype, a special point has an unknown label or status, or
        an attribute impactcont reads has a wrong value
        (:func:`~impactcont.dataset.attributes.check_attributes`: the oscillator
        JSON, N, the impacts and pattern of an N-p branch, ...); the message
        names it.
    """
    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"expected an xarray.Dataset of a branch; got {type(ds).__name__}")
    missing = [a for a in _REQUIRED_ATTRS if a not in ds.attrs]
    if missing:
        raise ValueError(f"not a branch dataset: missing attribute(s) {missing}")
    parameter = ds.attrs["parameter"]
    if not isinstance(parameter, str) or parameter not in PARAMETERS:
        raise ValueError(f"not a branch dataset: attribute 'parameter' must be "
                         f"{ALLOWED_PARAMETERS}; got {parameter!r}")
    expected: dict[str, tuple[tuple[str, ...], str]] = {}
    present = {k: v for k, v in OPTIONAL_POINT_VARIABLES.items() if k in ds.variables}
    for key, spec in {**_point_variables(parameter), **present}.items():
        expected[key] = (("point", *spec.extra_dims), spec.kind)
    for key, spec in _special_variables(parameter).items():
        expected[special_variable(key)] = (("special", *spec.extra_dims), spec.kind)
    for key, spec in OPTIONAL_SPECIAL_FIELDS.items():
        if special_variable(key) in ds.variables:
            expected[special_variable(key)] = (("special", *spec.extra_dims), spec.kind)
    check_variables(ds, expected, "branch")
    if ds.sizes["multiplier"] != ds.sizes["component"] or ds.sizes["component"] % 2:
        raise ValueError(f"dims 'multiplier' and 'component' must both have size 2n; got "
                         f"{ds.sizes['multiplier']} and {ds.sizes['component']}")
    labels = set(np.asarray(ds["special_label"]).tolist())
    if not labels <= set(SPECIAL_LABELS):
        raise ValueError(f"variable 'special_label' must hold labels in "
                         f"{list(SPECIAL_LABELS)}; got {sorted(labels)}")
    statuses = set(np.asarray(ds["special_status"]).tolist())
    if not statuses <= set(SPECIAL_STATUSES):
        raise ValueError(f"variable 'special_status' must hold statuses in "
                         f"{list(SPECIAL_STATUSES)}; got {sorted(statuses)}")
    check_attributes(ds, "branch")
    check_user_variables(ds)
    return ds


def oscillator_from_dataset(ds: xr.Dataset, point: int | None = None) -> ImpactOscillator:
    """The oscillator stored in a branch dataset.

    Parameters
    ----------
    ds : xarray.Dataset
        A branch dataset (its ``oscillator`` attribute holds the JSON).
    point : int, optional
        If given, return the oscillator at that point of the branch: ``omega``,
        ``b`` and the continued parameter(s) set to their values there (each as
        :meth:`~impactcont.model.parameters.ModelParameter.at` sets it: an element
        name changes that element of M, K, C or F, ``b_low`` the lower stop).

    Returns
    -------
    ImpactOscillator

    Raises
    ------
    TypeError
        ``ds`` is not an xarray.Dataset.
    ValueError
        The ``oscillator`` attribute is missing or is not an oscillator's JSON
        (:func:`~impactcont.dataset.attributes.oscillator_attribute`); ``point``
        is not an integer index of the branch; with ``point``, the dataset has no
        column (on ``point``) of omega, b or the continued parameter.
    ParameterError
        The stored oscillator has no such parameter (an element past its masses).
    """
    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"ds must be an xarray.Dataset; got {type(ds).__name__}")
    osc = oscillator_attribute(ds)
    if point is None:
        return osc
    npoints = ds.sizes.get("point", 0)
    if isinstance(point, bool) or not isinstance(point, (int, np.integer)) \
            or not -npoints <= point < npoints:
        raise ValueError(f"point must be an integer index in [{-npoints}, {npoints}); "
                         f"got {point!r}")
    parameter = ds.attrs.get("parameter", "omega")
    names = dict.fromkeys(["omega", "b", parameter if isinstance(parameter, str) else "?"])
    # a two-parameter curve stores its other parameter too (attribute "parameters")
    names.update(dict.fromkeys(
        name for name in split_parameters(str(ds.attrs.get("parameters", "")))
        if name in PARAMETERS and name in ds.variables and ds[name].dims == ("point",)))
    missing = [k for k in names if k not in ds.variables or ds[k].dims != ("point",)]
    if missing:
        raise ValueError(f"the dataset has no column (on 'point') of {missing}: the values of "
                         f"omega, b and the continued parameter (attribute 'parameter') "
                         f"at each point are needed")
    values = {k: float(ds[k].values[point]) for k in names}
    osc = osc.replace(omega=values.pop("omega"), b=values.pop("b"))
    for name, value in values.items():
        osc = model_parameter(osc, name, "parameter").at(osc, value)
    return osc
