"""impactcont: bifurcation analysis of multi-degree-of-freedom vibro-impact oscillators.

The closed-form periodic N-1 motions of Cao & Shu (eq. 12-16), their stability
(eq. 25) and robust stability (eq. 26-29), with an exact event-driven
simulator as the independent witness; branches of these motions continued in
a parameter with their special points, stored as xarray datasets / NetCDF.
Plots live in :mod:`impactcont.plots` (imported on demand: it loads matplotlib).

The names below are imported on first use (PEP 562), so that ``import impactcont``
and the command line's ``--help`` do not load numpy, scipy and xarray.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import types
from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING, Any

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    **dict.fromkeys(("continuation", "continuation_from", "extend"), "impactcont.analysis.branch"),
    **dict.fromkeys(("ContinuationOptions", "ContinuationStatus"), "impactcont.core"),
    **dict.fromkeys(("curve", "curve_crossings"), "impactcont.analysis.curves"),
    **dict.fromkeys(("load", "point_table", "save"), "impactcont.dataset"),
    "open_lazy": "impactcont.dataset.io",
    **dict.fromkeys(("IllConditionedWarning", "ImpactcontError", "LowImpactVelocityWarning",
                     "NearFoldWarning", "NearResonanceWarning", "NoPeriodicMotionError",
                     "ParameterError", "ResonanceError", "UnresolvedMotionWarning"),
                    "impactcont.errors"),
    "stability_map": "impactcont.analysis.maps",
    "ModalBasis": "impactcont.model.modal",
    **dict.fromkeys(("ImpactOscillator", "chain_stiffness"), "impactcont.model.oscillator"),
    **dict.fromkeys(("Stop", "Stops"), "impactcont.model.stops"),
    "multi_impact_continuation": "impactcont.analysis.branch",
    **dict.fromkeys(("multi_impact_curve", "multi_impact_curve_crossings"),
                    "impactcont.analysis.curves"),
    **dict.fromkeys(("multi_impact_map", "multi_impact_map_orbit"),
                    "impactcont.analysis.maps"),
    "Flow": "impactcont.orbit.flow",
    **dict.fromkeys(("displacement_extrema", "max_displacement", "min_displacement"),
                    "impactcont.orbit.extrema"),
    **dict.fromkeys(("MultiImpactOrbit", "multi_impact_orbit", "primitive_orbit"),
                    "impactcont.orbit.multi_impact"),
    **dict.fromkeys(("PeriodicOrbit", "amplitude_squared", "periodic_orbits"),
                    "impactcont.orbit.periodic"),
    **dict.fromkeys(("RobustStability", "lyapunov_matrix", "robust_bound", "robust_stability"),
                    "impactcont.orbit.robust"),
    "Progress": "impactcont.progress",
    **dict.fromkeys(("SimulationResult", "SimulationStatus", "simulate"),
                    "impactcont.simulate.simulator"),
    **dict.fromkeys(("Cascade", "grazing_switch", "period_doubling_cascade",
                     "period_doubling_switch", "pitchfork_switch", "special_orbit"),
                    "impactcont.analysis.switching"),
    "core": "impactcont.core",
}


def __getattr__(name: str) -> Any:
    """Import a public name, or a submodule (``impactcont.dataset``), on first use (PEP 562)."""
    module = _EXPORTS.get(name)
    if module is None:
        if not name.startswith("_") and importlib.util.find_spec(f"impactcont.{name}"):
            return importlib.import_module(f"impactcont.{name}")  # sets the attribute
        raise AttributeError(f"module 'impactcont' has no attribute {name!r}")
    value = importlib.import_module(module)
    if name != "core":
        value = getattr(value, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})


class _Package(types.ModuleType):
    """The package module: a submodule named like a public function (``simulate``, and the
    former ``continuation`` alias) does not hide the function when it is imported (the
    import system binds every submodule as an attribute of its package)."""

    def __setattr__(self, name: str, value: Any) -> None:
        target = _EXPORTS.get(name)
        if isinstance(value, types.ModuleType) and target not in (None, f"impactcont.{name}"):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


# The continuation core was the subpackage ``impactcont.continuation``, hidden by the
# function of the same name; it is ``impactcont.core`` now. Old imports
# (``from impactcont.continuation import ContinuationOptions``,
# ``impactcont.continuation.options``) keep working, loading the core on first use.
class _FormerCore(types.ModuleType):
    """``impactcont.continuation``: forwards to :mod:`impactcont.core` when first used."""

    def __getattr__(self, name: str) -> Any:
        return getattr(importlib.import_module("impactcont.core"), name)


class _FormerCoreFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``impactcont.continuation.X`` as the module ``impactcont.core.X``."""

    prefix = "impactcont.continuation."

    def find_spec(self, fullname: str, path: Any, target: Any = None) -> Any:
        if not fullname.startswith(self.prefix):
            return None
        if importlib.util.find_spec("impactcont.core." + fullname[len(self.prefix):]) is None:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec: Any) -> types.ModuleType:
        return importlib.import_module("impactcont.core." + spec.name[len(self.prefix):])

    def exec_module(self, module: types.ModuleType) -> None:
        """The module is the core's, already executed."""


_former = _FormerCore("impactcont.continuation")
_former.__path__ = []  # a package whose submodules only _FormerCoreFinder finds
sys.modules.setdefault("impactcont.continuation", _former)
del _former
if not any(isinstance(f, _FormerCoreFinder) for f in sys.meta_path):
    sys.meta_path.append(_FormerCoreFinder())

try:
    __version__ = version("impactcont")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

if TYPE_CHECKING:  # for type checkers and IDEs: the names __getattr__ gives
    from impactcont import core  # noqa: F401
    from impactcont.analysis.branch import (
        continuation,
        continuation_from,
        extend,
        multi_impact_continuation,
    )
    from impactcont.analysis.curves import (
        curve,
        curve_crossings,
        multi_impact_curve,
        multi_impact_curve_crossings,
    )
    from impactcont.analysis.maps import multi_impact_map, multi_impact_map_orbit, stability_map
    from impactcont.analysis.switching import (
        Cascade,
        grazing_switch,
        period_doubling_cascade,
        period_doubling_switch,
        pitchfork_switch,
        special_orbit,
    )
    from impactcont.core import ContinuationOptions, ContinuationStatus
    from impactcont.dataset import load, point_table, save
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
    from impactcont.model.modal import ModalBasis
    from impactcont.model.oscillator import ImpactOscillator, chain_stiffness
    from impactcont.model.stops import Stop, Stops
    from impactcont.orbit.extrema import (
        displacement_extrema,
        max_displacement,
        min_displacement,
    )
    from impactcont.orbit.flow import Flow
    from impactcont.orbit.multi_impact import (
        MultiImpactOrbit,
        multi_impact_orbit,
        primitive_orbit,
    )
    from impactcont.orbit.periodic import (
        PeriodicOrbit,
        amplitude_squared,
        periodic_orbits,
    )
    from impactcont.orbit.robust import (
        RobustStability,
        lyapunov_matrix,
        robust_bound,
        robust_stability,
    )
    from impactcont.progress import Progress
    from impactcont.simulate.simulator import (
        SimulationResult,
        SimulationStatus,
        simulate,
    )

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
    "Stop",
    "Stops",
    "UnresolvedMotionWarning",
    "__version__",
    "amplitude_squared",
    "chain_stiffness",
    "continuation",
    "continuation_from",
    "curve",
    "curve_crossings",
    "displacement_extrema",
    "extend",
    "grazing_switch",
    "load",
    "lyapunov_matrix",
    "max_displacement",
    "min_displacement",
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
    "point_table",
    "primitive_orbit",
    "robust_bound",
    "robust_stability",
    "save",
    "simulate",
    "special_orbit",
    "stability_map",
]
