"""Branch datasets: the schema (names, units, attributes) and NetCDF I/O.

:func:`branch_dataset` turns the plain arrays of a continued branch into an
:class:`xarray.Dataset`; :func:`save` and :func:`load` write and read any
dataset of impactcont, one or many (DataTree groups): atomically, safe to
interrupt with Ctrl-C, readable by plain NetCDF tools (complex multipliers as
real and imaginary parts, an index of the groups in the root group), and read
back by :func:`load` as they were written. Both check the attributes impactcont
reads back (:mod:`impactcont.dataset.attributes`) whatever their ``validate``,
which switches the check of the schema. The layout is documented in
``docs/dataset.md`` and ``docs/outputs.md``. :func:`point_table` gives a branch or
curve as a table of one row per point, :func:`with_parameter_coords` with its
parameters as coordinates (to plot against them).
"""

from __future__ import annotations

from impactcont.dataset.io import load, save
from impactcont.dataset.schema import (
    PARAMETERS,
    POINT_VARIABLES,
    SPECIAL_LABELS,
    SPECIAL_STATUSES,
    branch_dataset,
    oscillator_from_dataset,
    point_table,
    special_variable,
    state_component_names,
    validate_branch_dataset,
    with_parameter_coords,
)

__all__ = [
    "PARAMETERS",
    "POINT_VARIABLES",
    "SPECIAL_LABELS",
    "SPECIAL_STATUSES",
    "branch_dataset",
    "load",
    "oscillator_from_dataset",
    "point_table",
    "save",
    "special_variable",
    "state_component_names",
    "validate_branch_dataset",
    "with_parameter_coords",
]
