"""The built-in scene sections, registered in the one problem registry.

A *section* is one array of tables of a scene (``[[branches]]``): the
dataclass that validates one table (a subclass of
:class:`~impactcont.scene.entries.EntrySpec`) and the driver that computes
one entry into an :class:`xarray.Dataset`, with how computed datasets are
described in Markdown and the plot kinds that draw them. Each is a
:class:`~impactcont.scene.plugins.SceneSection`; the registry
(:mod:`impactcont.scene.plugins`) lists the objects below as the built-in
problems, before those of other packages, so that the scene parser, the
runner and the command line see built-in and plugin sections the same way.

Drawing functions are named as ``"module:function"`` and imported on first
use, so that validating a scene does not import matplotlib.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import xarray as xr

from impactcont.scene import switches, twoparam
from impactcont.scene.entries import BranchSpec, OrbitSpec, RobustSpec, SimulationSpec
from impactcont.scene.plugins import (
    PlotKind,
    SceneSection,
    plot_kinds,
    register_problem,
    scene_sections,
)

__all__ = [
    "BRANCHES",
    "CURVES",
    "MAPS",
    "MULTI_IMPACT",
    "ORBITS",
    "ROBUST",
    "SIMULATIONS",
    "SWITCHES",
    "PlotKind",
    "RunContext",
    "SceneSection",
    "plot_kinds",
    "register_section",
    "scene_sections",
]

_FIGURES = "impactcont.scene.figures"
_TASKS = "impactcont.scene.tasks"
_TWO = "impactcont.scene.twoparam"
_SWITCH = "impactcont.scene.switches"


@dataclasses.dataclass(frozen=True)
class RunContext:
    """What a driver may read while computing an entry.

    Attributes
    ----------
    datasets : mapping of str to mapping of str to xarray.Dataset
        ``section -> entry name -> dataset`` of the entries computed so far
        (sections run in registry order, so ``[[curves]]`` can start from a
        computed ``[[branches]]``, ``[[multi_impact]]`` or ``[[switches]]`` entry).
    """

    datasets: Mapping[str, Mapping[str, xr.Dataset]]


_NP_PROBLEM = "impactcont.problems.multi_impact_branch:MultiImpactBranchProblem"


def _section(key: str, entry: type, handler: str, title: str,
             plots: tuple[tuple[Any, ...], ...], problem: str | None = None) -> SceneSection:
    """A built-in section whose driver, description and points are a handler's methods.

    ``handler`` is ``"module:OBJECT"`` (its methods are looked up at each call);
    ``plots`` holds ``(kind, many, drawing function of scene.figures, doc[, options])``
    with ``options`` the other keywords of :class:`PlotKind`.
    """
    kinds = tuple(PlotKind(kind, key, many, f"{_FIGURES}:{draw}", doc, **(rest[0] if rest else {}))
                  for kind, many, draw, doc, *rest in plots)
    return SceneSection(key, entry, f"{handler}.compute", title, describe=f"{handler}.describe",
                        special_points=f"{handler}.special_points", plots=kinds,
                        problem=problem)


ORBITS = _section("orbits", OrbitSpec, f"{_TASKS}:ORBITS", "Periodic orbits", (
    ("orbits", True, "draw_orbits",
     "x1(t) over one period and the phase portrait (x1, x1') of each orbit"),))
BRANCHES = _section("branches", BranchSpec, f"{_TASKS}:BRANCHES", "Branches", (
    ("bifurcation_diagram", True, "draw_bifurcation",
     "branches (and switches) against their parameter, styled by stability, special points "
     "marked", {"also": ("switches", "multi_impact")}),
    ("multipliers", False, "draw_multipliers",
     "multiplier moduli along one branch and the multipliers in the complex plane")),
    problem="impactcont.problems.periodic_branch:PeriodicBranchProblem")
ROBUST = _section("robust", RobustSpec, f"{_TASKS}:ROBUST", "Robust stability", (
    ("robust", True, "draw_robust", "Gamma of eq. (28) as a heat map, with epsilon and "
     "epsilon0"),))
SIMULATIONS = _section("simulations", SimulationSpec, f"{_TASKS}:SIMULATIONS", "Simulations", (
    ("simulation", True, "draw_simulations",
     "x1(t) and phase portrait of simulated trajectories (impacts if no trajectory)"),))
CURVES = _section("curves", twoparam.CurveSpec, f"{_TWO}:CURVES", "Two-parameter curves", (
    ("curves", True, "draw_curves",
     "codim-1 curves in their parameter plane, codim-2 points marked",
     {"check": twoparam.check_curves_plot}),))
MAPS = _section("maps", twoparam.MapSpec, f"{_TWO}:MAPS", "Stability maps", (
    ("map", False, "draw_map",
     "number of stable physical N-1 motions on the grid of the two parameters, one panel "
     "per N; the regions of a motion family's map"),))
SWITCHES = _section("switches", switches.SwitchSpec, f"{_SWITCH}:SWITCHES",
                    "Branches switched at special points", (
    ("switch_multipliers", False, "draw_multipliers",
     "multiplier moduli along one switched branch and the multipliers in the complex plane"),),
    problem=_NP_PROBLEM)
MULTI_IMPACT = _section("multi_impact", switches.MultiImpactSpec, f"{_SWITCH}:MULTI_IMPACT",
                        "Branches of N-p motions from simulations", (
    ("multi_impact_multipliers", False, "draw_multipliers",
     "multiplier moduli along one N-p branch and the multipliers in the complex plane"),),
    problem=_NP_PROBLEM)


def register_section(section: SceneSection, *, replace: bool = False) -> None:
    """Add a section to the scene format in this process: a problem named after its key.

    The same as ``register_problem(section.key, section)``; a package
    declares an entry point instead (``docs/plugins.md``).

    Raises
    ------
    ValueError
        The key is reserved or taken, or the section is malformed.
    """
    register_problem(section.key, section, replace=replace)
