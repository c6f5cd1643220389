"""Branch datasets: the schema (names, units, attributes) and NetCDF I/O.

:func:`branch_dataset` turns the plain arrays of a continued branch into an
:class:`xarray.Dataset`; :func:`save` and :func:`load` write and read one
branch or many (DataTree groups) with complex multipliers and an atomic write.
The layout is documented in ``docs/dataset.md``.
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
    special_variable,
    state_component_names,
    validate_branch_dataset,
)

__all__ = [
    "PARAMETERS",
    "POINT_VARIABLES",
    "SPECIAL_LABELS",
    "SPECIAL_STATUSES",
    "branch_dataset",
    "load",
    "oscillator_from_dataset",
    "save",
    "special_variable",
    "state_component_names",
    "validate_branch_dataset",
]
