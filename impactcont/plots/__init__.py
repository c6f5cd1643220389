"""Plots of branch datasets: bifurcation diagrams and multipliers.

They take datasets (see :mod:`impactcont.dataset`), never compute orbits and
never call ``plt.show``.
"""

from __future__ import annotations

from impactcont.plots.branches import (
    SEGMENT_STYLES,
    SPECIAL_MARKERS,
    bifurcation_diagram,
    multipliers_plot,
    stability_segments,
)

__all__ = [
    "SEGMENT_STYLES",
    "SPECIAL_MARKERS",
    "bifurcation_diagram",
    "multipliers_plot",
    "stability_segments",
]
