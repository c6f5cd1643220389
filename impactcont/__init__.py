"""impactcont: bifurcation analysis of multi-degree-of-freedom vibro-impact oscillators.

The closed-form periodic N-1 motions of Cao & Shu (eq. 12-16), their stability
(eq. 25) and robust stability (eq. 26-29), with an exact event-driven
simulator as the independent witness; branches of these motions continued in
a parameter with their special points, stored as xarray datasets / NetCDF.
Plots live in :mod:`impactcont.plots` (imported on demand: it loads matplotlib).
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from impactcont.branch import continuation
from impactcont.dataset import load, save
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
from impactcont.model.modal import ModalBasis
from impactcont.model.oscillator import ImpactOscillator, chain_stiffness
from impactcont.orbit.flow import Flow
from impactcont.orbit.periodic import (
    PeriodicOrbit,
    amplitude_squared,
    periodic_orbits,
)
from impactcont.orbit.robust import RobustStability, lyapunov_matrix, robust_bound, robust_stability
from impactcont.simulate.simulator import SimulationResult, SimulationStatus, simulate

try:
    __version__ = version("impactcont")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

__all__ = [
    "Flow",
    "IllConditionedWarning",
    "ImpactOscillator",
    "ImpactcontError",
    "LowImpactVelocityWarning",
    "ModalBasis",
    "NearFoldWarning",
    "NearResonanceWarning",
    "NoPeriodicMotionError",
    "ParameterError",
    "PeriodicOrbit",
    "ResonanceError",
    "RobustStability",
    "SimulationResult",
    "SimulationStatus",
    "UnresolvedMotionWarning",
    "__version__",
    "amplitude_squared",
    "chain_stiffness",
    "continuation",
    "load",
    "lyapunov_matrix",
    "periodic_orbits",
    "robust_bound",
    "robust_stability",
    "save",
    "simulate",
]
