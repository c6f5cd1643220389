"""impactcont: bifurcation analysis of multi-degree-of-freedom vibro-impact oscillators.

The closed-form periodic N-1 motions of Cao & Shu (eq. 12-16), their stability
(eq. 25) and robust stability (eq. 26-29), with an exact event-driven
simulator as the independent witness; branches of these motions continued in
a parameter with their special points, stored as xarray datasets / NetCDF.
Plots live in :mod:`impactcont.plots` (imported on demand: it loads matplotlib).
"""

from __future__ import annotations

import sys
from importlib.metadata import PackageNotFoundError, version

from impactcont import core
from impactcont.branch import continuation, continuation_from, extend
from impactcont.core import ContinuationOptions, ContinuationStatus
from impactcont.curves import curve, curve_crossings
from impactcont.dataset import load, save
from impactcont.dataset.io import open_lazy
from impactcont.errors import (
    IllConditionedWarning,
    ImpactcontError,
    LowImpactVelocityWarning,
    NearFoldWarning,
    NearResonanceWarning,
    NoPeriodicMotionError,
    ParameterError,
    ResonanceError,
    UnresolvedMotionWarning,
)
from impactcont.maps import stability_map
from impactcont.model.modal import ModalBasis
from impactcont.model.oscillator import ImpactOscillator, chain_stiffness
from impactcont.model.stops import Stops
from impactcont.multi_branch import multi_impact_continuation
from impactcont.multi_curves import multi_impact_curve, multi_impact_curve_crossings
from impactcont.multi_maps import multi_impact_map, multi_impact_map_orbit
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import MultiImpactOrbit, multi_impact_orbit, primitive_orbit
from impactcont.orbit.periodic import (
    PeriodicOrbit,
    amplitude_squared,
    periodic_orbits,
)
from impactcont.orbit.robust import RobustStability, lyapunov_matrix, robust_bound, robust_stability
from impactcont.progress import Progress
from impactcont.simulate.simulator import SimulationResult, SimulationStatus, simulate
from impactcont.switching import (
    Cascade,
    grazing_switch,
    period_doubling_cascade,
    period_doubling_switch,
    pitchfork_switch,
    special_orbit,
)

# The continuation core was the subpackage ``impactcont.continuation``, hidden by the
# function of the same name; it is ``impactcont.core`` now. Old imports
# (``from impactcont.continuation import ContinuationOptions``) keep working.
sys.modules.setdefault("impactcont.continuation", core)
for _name in ("corrector", "driver", "events", "locate", "options", "point", "problem",
              "stepper"):
    sys.modules.setdefault(f"impactcont.continuation.{_name}",
                           sys.modules[f"impactcont.core.{_name}"])
del _name

try:
    __version__ = version("impactcont")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

__all__ = [
    "Cascade",
    "ContinuationOptions",
    "ContinuationStatus",
    "Flow",
    "IllConditionedWarning",
    "ImpactOscillator",
    "ImpactcontError",
    "LowImpactVelocityWarning",
    "ModalBasis",
    "MultiImpactOrbit",
    "NearFoldWarning",
    "NearResonanceWarning",
    "NoPeriodicMotionError",
    "ParameterError",
    "PeriodicOrbit",
    "Progress",
    "ResonanceError",
    "RobustStability",
    "SimulationResult",
    "SimulationStatus",
    "Stops",
    "UnresolvedMotionWarning",
    "__version__",
    "amplitude_squared",
    "chain_stiffness",
    "continuation",
    "continuation_from",
    "curve",
    "curve_crossings",
    "extend",
    "grazing_switch",
    "load",
    "lyapunov_matrix",
    "multi_impact_continuation",
    "multi_impact_curve",
    "multi_impact_curve_crossings",
    "multi_impact_map",
    "multi_impact_map_orbit",
    "multi_impact_orbit",
    "open_lazy",
    "period_doubling_cascade",
    "period_doubling_switch",
    "periodic_orbits",
    "pitchfork_switch",
    "primitive_orbit",
    "robust_bound",
    "robust_stability",
    "save",
    "simulate",
    "special_orbit",
    "stability_map",
]
