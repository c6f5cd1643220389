"""The registry of scene sections and plot kinds.

A *section* is one array of tables of a scene (``[[branches]]``): the
dataclass that validates one table (a subclass of
:class:`~impactcont.scene.schema.EntrySpec`) and a *handler* that computes
one entry into an :class:`xarray.Dataset` and describes computed datasets in
Markdown. A run writes the datasets of a section to ``<section>.nc``, one
group per entry. A *plot kind* (``kind = "bifurcation_diagram"`` in
``[[plots]]``) draws entries of one section.

The registry is small on purpose: new computations (two-parameter curves,
maps) plug in with :func:`register_section` and :func:`register_plot_kind`
without touching the scene parser or the runner. Handlers and drawing
functions are named as ``"module:attribute"`` and imported on first use, so
that validating a scene does not import matplotlib.
"""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Protocol

import xarray as xr

from impactcont.scene.schema import (
    BranchSpec,
    EntrySpec,
    OrbitSpec,
    RobustSpec,
    SimulationSpec,
)

__all__ = [
    "PlotKind",
    "RunContext",
    "SceneSection",
    "SectionHandler",
    "plot_kinds",
    "register_plot_kind",
    "register_section",
    "scene_sections",
]


@dataclasses.dataclass(frozen=True)
class RunContext:
    """What a handler may read while computing an entry.

    Attributes
    ----------
    datasets : mapping of str to mapping of str to xarray.Dataset
        ``section -> entry name -> dataset`` of the entries computed so far
        (sections run in registry order, so ``[[curves]]`` can start from a
        computed ``[[branches]]`` entry).
    """

    datasets: Mapping[str, Mapping[str, xr.Dataset]]


class SectionHandler(Protocol):
    """What a section computes and how it describes its results."""

    def compute(self, entry: Any, context: RunContext) -> xr.Dataset:
        """Compute one entry (a validated table of the section) into a dataset."""

    def describe(self, datasets: Mapping[str, xr.Dataset]) -> list[str]:
        """Markdown lines describing computed datasets (``entry name -> dataset``)."""

    def special_points(self, datasets: Mapping[str, xr.Dataset]) -> list[dict[str, Any]]:
        """Special points found, one dict per point (empty for most sections)."""


def _load(target: str) -> Any:
    module, _, attribute = target.partition(":")
    obj: Any = importlib.import_module(module)
    for part in attribute.split("."):
        obj = getattr(obj, part)
    return obj


@dataclasses.dataclass(frozen=True)
class SceneSection:
    """One section of the scene format.

    Attributes
    ----------
    key : str
        The TOML name of the array of tables, also the output file ``<key>.nc``.
    entry : type
        Dataclass validating one table (subclass of :class:`EntrySpec`).
    handler : str
        ``"module:attribute"`` of the :class:`SectionHandler`.
    title : str
        Human-readable name.
    """

    key: str
    entry: type[EntrySpec]
    handler: str
    title: str

    def load_handler(self) -> SectionHandler:
        """Import and return the handler."""
        return _load(self.handler)


@dataclasses.dataclass(frozen=True)
class PlotKind:
    """One kind of plot of ``[[plots]]``.

    Attributes
    ----------
    key : str
        The value of ``kind``.
    section : str
        The section whose entries it draws.
    many : bool
        Whether it draws several entries at once (else exactly one).
    draw : str
        ``"module:function"``: ``draw(datasets, plot) -> matplotlib.figure.Figure``
        with ``datasets`` an ordered mapping ``entry name -> Dataset``.
    doc : str
        One line for the documentation and ``--help``.
    check : callable, optional
        Extra validation ``check(plot, entries, where)`` raising ``where.error``.
    """

    key: str
    section: str
    many: bool
    draw: str
    doc: str
    check: Callable[[Any, Sequence[Any], Any], None] | None = None

    def load_draw(self) -> Callable[..., Any]:
        """Import and return the drawing function."""
        return _load(self.draw)


_SECTIONS: dict[str, SceneSection] = {}
_PLOT_KINDS: dict[str, PlotKind] = {}


def register_section(section: SceneSection, *, replace: bool = False) -> None:
    """Add a section to the scene format.

    Raises
    ------
    ValueError
        A section of that key exists and ``replace`` is false, or the key is
        a reserved top-level key.
    """
    if section.key in ("title", "description", "oscillator", "output", "plots"):
        raise ValueError(f"section key {section.key!r} is reserved")
    if section.key in _SECTIONS and not replace:
        raise ValueError(f"a scene section {section.key!r} is already registered")
    _SECTIONS[section.key] = section


def register_plot_kind(kind: PlotKind, *, replace: bool = False) -> None:
    """Add a plot kind to ``[[plots]]``.

    Raises
    ------
    ValueError
        A kind of that key exists and ``replace`` is false.
    """
    if kind.key in _PLOT_KINDS and not replace:
        raise ValueError(f"a plot kind {kind.key!r} is already registered")
    _PLOT_KINDS[kind.key] = kind


def scene_sections() -> dict[str, SceneSection]:
    """The registered sections, in the order a run computes them."""
    return dict(_SECTIONS)


def plot_kinds() -> dict[str, PlotKind]:
    """The registered plot kinds."""
    return dict(_PLOT_KINDS)


_TASKS = "impactcont.scene.tasks"
_FIGURES = "impactcont.scene.figures"

for _section in (
    SceneSection("orbits", OrbitSpec, f"{_TASKS}:ORBITS", "Periodic orbits"),
    SceneSection("branches", BranchSpec, f"{_TASKS}:BRANCHES", "Branches"),
    SceneSection("robust", RobustSpec, f"{_TASKS}:ROBUST", "Robust stability"),
    SceneSection("simulations", SimulationSpec, f"{_TASKS}:SIMULATIONS", "Simulations"),
):
    register_section(_section)

for _kind in (
    PlotKind("bifurcation_diagram", "branches", True, f"{_FIGURES}:draw_bifurcation",
             "branches against their parameter, styled by stability, special points marked"),
    PlotKind("multipliers", "branches", False, f"{_FIGURES}:draw_multipliers",
             "multiplier moduli along one branch and the multipliers in the complex plane"),
    PlotKind("orbits", "orbits", True, f"{_FIGURES}:draw_orbits",
             "x1(t) over one period and the phase portrait (x1, x1') of each orbit"),
    PlotKind("simulation", "simulations", True, f"{_FIGURES}:draw_simulations",
             "x1(t) and phase portrait of simulated trajectories (impacts if no trajectory)"),
    PlotKind("robust", "robust", True, f"{_FIGURES}:draw_robust",
             "Gamma of eq. (28) as a heat map, with epsilon and epsilon0"),
):
    register_plot_kind(_kind)


def _two_parameter_available() -> bool:
    """Whether the two-parameter modules (issue 4) are installed in this tree."""
    return all(importlib.util.find_spec(m) is not None
               for m in ("impactcont.curves", "impactcont.maps"))


if _two_parameter_available():
    from impactcont.scene.twoparam import CurveSpec, MapSpec, check_curves_plot

    register_section(SceneSection("curves", CurveSpec, "impactcont.scene.twoparam:CURVES",
                                  "Two-parameter curves"))
    register_section(SceneSection("maps", MapSpec, "impactcont.scene.twoparam:MAPS",
                                  "Stability maps"))
    register_plot_kind(PlotKind("curves", "curves", True, f"{_FIGURES}:draw_curves",
                                "codim-1 curves in their parameter plane, codim-2 points "
                                "marked", check=check_curves_plot))
    register_plot_kind(PlotKind("map", "maps", False, f"{_FIGURES}:draw_map",
                                "number of stable physical motions on the (omega, b) grid, "
                                "one panel per N"))
