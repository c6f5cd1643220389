"""Typed results to dataset columns: the one place where drivers' results become records.

The drivers hand over the motions they computed (:class:`~impactcont.PeriodicOrbit`
or :class:`~impactcont.MultiImpactOrbit`, one per accepted point) and their special
points; :func:`orbit_columns` and :func:`special_record` turn them into the columns
and dicts of the branch schema (``docs/dataset.md``), so that every driver stores
the same variables.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["orbit_columns", "reserved_names", "special_record", "user_event_record"]


def orbit_columns(orbits: Any, parameter: str, values: Any) -> dict[str, np.ndarray]:
    """The ``point`` columns of a branch from the motion at each point.

    Parameters
    ----------
    orbits : sequence of PeriodicOrbit or MultiImpactOrbit
        The motion at each accepted point, in branch order.
    parameter : str
        The continued parameter; its column is added when it is not ``omega`` or ``b``.
    values : array_like
        The continued parameter's value at each point.

    Returns
    -------
    dict of str to ndarray
        ``omega, b, delta, impact_velocity, gap_min, spectral_radius, stable,
        physical, multipliers, state`` (and the continued parameter).
    """
    columns = {
        "omega": np.array([o.oscillator.omega for o in orbits]),
        "b": np.array([o.oscillator.b for o in orbits]),
        "delta": np.array([o.delta for o in orbits]),
        "impact_velocity": np.array([o.impact_velocity for o in orbits]),
        "gap_min": np.array([o.gap_min for o in orbits]),
        "spectral_radius": np.array([o.spectral_radius for o in orbits]),
        "stable": np.array([o.stable for o in orbits]),
        "physical": np.array([o.physical for o in orbits]),
        "multipliers": np.array([o.multipliers for o in orbits]),
        "state": np.array([o.state for o in orbits]),
    }
    columns.setdefault(parameter, np.asarray(values, dtype=float))
    return columns


def special_record(special: Any, parameter: str, *, point: int,
                   bracket: tuple[float, float]) -> dict[str, Any]:
    """The special-point dict of the branch schema for a located (or bracketed) point.

    Parameters
    ----------
    special : SpecialPoint
        The one record (:mod:`impactcont.detection.points`), with ``label``,
        ``value`` (of the continued parameter), ``delta``, ``precision``, ``status``
        and ``orbit`` (the motion at the point).
    parameter : str
        The continued parameter.
    point : int
        Index of the nearest accepted point in the dataset.
    bracket : (float, float)
        The continued parameter's values at the two bracketing points. The record's
        bracket is the range of the parameter the branch covers between them: it also
        holds the located value, which at a fold (SN) lies beyond both (the branch
        turns there), so a location always lies in its bracket.

    Returns
    -------
    dict
        Keys of the schema's special points, with the motion's ``impact_velocity``
        and ``gap_min`` at the point.
    """
    orbit = special.orbit
    ends = [*bracket, special.value] if np.isfinite(special.value) else list(bracket)
    record = {"label": str(special.label), "omega": orbit.oscillator.omega,
              "b": orbit.oscillator.b, "delta": special.delta, "point": point,
              "bracket_lo": min(ends), "bracket_hi": max(ends),
              "precision": special.precision, "status": special.status,
              "multipliers": orbit.multipliers,
              "impact_velocity": float(orbit.impact_velocity),
              "gap_min": float(orbit.gap_min)}
    record.setdefault(parameter, special.value)
    return record


@functools.cache
def reserved_names() -> frozenset[str]:
    """Names a user event or monitor may not take: the built-in variables and dimensions.

    Those of branches (N-1 and N-p, their special points and events) and curves, and the
    parameters; the labels of special points are refused by
    :func:`~impactcont.detection.special_points.check_user_functions`.
    """
    from impactcont.dataset import curves, multi, schema

    tables = (schema.POINT_VARIABLES, schema.OPTIONAL_POINT_VARIABLES, schema.PARAMETERS,
              schema._SPECIAL_FIELDS, schema.OPTIONAL_SPECIAL_FIELDS, schema.EVENT_FIELDS,
              multi.IMPACT_VARIABLES, curves.CURVE_VARIABLES)
    dims = ("point", "multiplier", "component", "special", "impact", "event", "codim2")
    return frozenset(name for table in (*tables, dims) for name in table)


def user_event_record(event: Any, parameters: Sequence[str]) -> dict[str, Any]:
    """The event dict of :func:`~impactcont.dataset.schema.add_user_functions` for a user event.

    Parameters
    ----------
    event : SpecialPoint
        A user event's zero (the one record), with ``name``, ``point``, ``precision``,
        ``status`` and ``orbit`` (the motion there).
    parameters : sequence of str
        The parameters stored (``omega``, ``b`` and the continued one(s)): their values
        are the motion's oscillator's.

    Returns
    -------
    dict
    """
    osc = event.orbit.oscillator
    record: dict[str, Any] = {name: float(getattr(osc, name) or 0.0) for name in parameters}
    record.update({"name": event.name, "delta": float(event.orbit.delta),
                   "point": int(event.point), "precision": float(event.precision),
                   "status": event.status})
    return record
