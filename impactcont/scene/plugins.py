"""The one registry of problems: built-in ones and those of other packages.

A *problem* is something impactcont can compute by name. It brings its
:class:`SceneSection`: the scene key of its tables (``[[branches]]``), the
dataclass that declares and validates the keys of one table, and the
*driver* that computes one validated table into an :class:`xarray.Dataset`
(which a scene run writes to ``<key>.nc`` and draws). It may also bring plot
kinds (:class:`PlotKind`) and the continuation problem class it follows. The
built-in tasks (orbits, branches, robust, simulations, multi_impact, switches,
curves, maps) are
registered here the same way as a third-party problem; the scene parser, the
runner, ``impactcont run`` and ``impactcont list-problems`` read this registry
only.

A package adds a problem by declaring an entry point in its ``pyproject.toml``::

    [project.entry-points."impactcont.problems"]
    decay = "my_package.decay:PROBLEM"

where ``PROBLEM`` is a :class:`SceneSection` (see ``docs/plugins.md`` for a
complete example). An entry point may also name a bare class (a problem for
the continuation core without a scene section): it is listed, not run.

Objects are loaded once per process, on first discovery. A plugin that fails
to load (missing module, import error, ...) or whose section is malformed
emits a :class:`PluginWarning` naming the plugin and the error, and is left
out; the built-in problems and the other plugins still work. A plugin may not
take the name or the scene key of another problem, built-in ones first; the
first wins and the clash warns.

Modelled on ``xarray/backends/plugins.py``: a few small functions, the
discovery cached (:func:`refresh_problems` clears the cache).
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import importlib
import importlib.metadata
import inspect
import logging
import re
import warnings
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from impactcont.errors import ParameterError

__all__ = [
    "BUILTIN_PROBLEMS",
    "ENTRY_POINT_GROUP",
    "RESERVED_KEYS",
    "PlotKind",
    "PluginWarning",
    "ProblemInfo",
    "SceneSection",
    "get_problem",
    "list_problems",
    "load_target",
    "plot_kinds",
    "refresh_problems",
    "register_problem",
    "scene_sections",
    "unregister_problem",
]

log = logging.getLogger(__name__)

#: The entry-point group of problem plugins.
ENTRY_POINT_GROUP = "impactcont.problems"

#: Top-level keys of a scene that no section may take.
RESERVED_KEYS = ("title", "description", "oscillator", "output", "plots")

_SECTION_KEY = re.compile(r"^[a-z][a-z0-9_]*$")

#: Problems that ship with impactcont, in the order a scene computes them:
#: name -> ``"module:attribute"`` of their :class:`SceneSection`.
BUILTIN_PROBLEMS: dict[str, str] = {
    name: f"impactcont.scene.sections:{name.upper()}"
    for name in ("orbits", "branches", "robust", "simulations", "multi_impact", "switches",
                 "curves", "maps")
}


class PluginWarning(UserWarning):
    """A problem plugin could not be loaded, is malformed, or its name clashes with another."""


def load_target(target: str | Any) -> Any:
    """The object named by ``"module:attribute.path"``; any other object is returned as is.

    This is the one loader of the package: entry points, built-in sections,
    drivers and drawing functions given as text all go through it (so that
    validating a scene does not import matplotlib).

    Raises
    ------
    ImportError, AttributeError
        The module or the attribute does not exist.
    """
    if not isinstance(target, str):
        return target
    module, _, attribute = target.partition(":")
    obj: Any = importlib.import_module(module)
    for part in filter(None, attribute.split(".")):
        obj = getattr(obj, part)
    return obj


# ---------------------------------------------------------------------------------------------
# What a problem brings
# ---------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class PlotKind:
    """One kind of plot of ``[[plots]]`` (``kind = "bifurcation_diagram"``).

    Attributes
    ----------
    key : str
        The value of ``kind``.
    section : str
        The scene key of the section whose entries it draws.
    many : bool
        Whether it draws several entries at once (else exactly one).
    draw : str or callable
        ``draw(datasets, plot) -> matplotlib.figure.Figure`` with ``datasets``
        an ordered mapping ``entry name -> Dataset``, or its ``"module:function"``.
    doc : str
        One line for the documentation and ``--help``.
    check : callable, optional
        Extra validation ``check(plot, entries, where)`` raising ``where.error``.
    also : tuple of str
        Other sections whose entries it draws too (the bifurcation diagram
        draws ``[[switches]]`` entries beside ``[[branches]]`` ones).
    """

    key: str
    section: str
    many: bool
    draw: str | Callable[..., Any]
    doc: str
    check: Callable[[Any, Sequence[Any], Any], None] | None = None
    also: tuple[str, ...] = ()

    @property
    def sections(self) -> tuple[str, ...]:
        """Every section whose entries it draws, its own first."""
        return (self.section, *self.also)

    def load_draw(self) -> Callable[..., Any]:
        """Import and return the drawing function."""
        return load_target(self.draw)


def _generic_describe(datasets: Mapping[str, Any]) -> list[str]:
    """Markdown table of datasets of a section that brings no ``describe``."""
    rows = ["| entry | dimensions | variables |", "|---|---|---|"]
    for name, ds in datasets.items():
        dims = ", ".join(f"{d}={n}" for d, n in ds.sizes.items()) or "-"
        rows.append(f"| {name} | {dims} | {', '.join(map(str, ds.data_vars)) or '-'} |")
    return rows


@dataclasses.dataclass(frozen=True)
class SceneSection:
    """What a problem brings to scenes: its tables, their validation and its driver.

    Attributes
    ----------
    key : str
        The TOML name of the array of tables (``[[key]]``), also the output
        file ``<key>.nc``: lower-case letters, digits and ``_``.
    entry : type or str
        Dataclass validating one table: a subclass of
        :class:`impactcont.scene.entries.EntrySpec` whose keys are declared
        with :func:`impactcont.scene.keys.declare` (or its ``"module:attribute"``).
    driver : callable or str
        ``driver(entry, context) -> xarray.Dataset``: computes one validated
        table; ``context.datasets`` holds the datasets computed so far
        (``section -> entry name -> Dataset``).
    title : str
        Human-readable name (summary headings, ``impactcont info``).
    describe : callable or str, optional
        ``describe(datasets) -> list of str``: Markdown lines describing
        computed datasets (``entry name -> Dataset``); default a table of
        their dimensions and variables.
    special_points : callable or str, optional
        ``special_points(datasets) -> list of dict``: points found, listed in
        ``summary.md``; default none.
    plots : tuple of PlotKind
        Plot kinds that draw this section's entries.
    problem : type or str, optional
        The continuation problem the driver follows, for the listing.
    """

    key: str
    entry: type | str
    driver: Callable[..., Any] | str
    title: str
    describe: Callable[..., list[str]] | str | None = None
    special_points: Callable[..., list[dict[str, Any]]] | str | None = None
    plots: tuple[PlotKind, ...] = ()
    problem: type | str | None = None

    def load_entry(self) -> type:
        """The entry dataclass."""
        return load_target(self.entry)

    def compute(self, entry: Any, context: Any) -> Any:
        """Run the driver on one validated entry."""
        return load_target(self.driver)(entry, context)

    def describe_datasets(self, datasets: Mapping[str, Any]) -> list[str]:
        """Markdown lines describing computed datasets."""
        func = load_target(self.describe) if self.describe is not None else _generic_describe
        return list(func(datasets))

    def find_points(self, datasets: Mapping[str, Any]) -> list[dict[str, Any]]:
        """The special points found in computed datasets (empty when the section has none)."""
        if self.special_points is None:
            return []
        return list(load_target(self.special_points)(datasets))

    def check(self) -> None:
        """Raise ``TypeError``/``ValueError`` naming what is malformed."""
        if not isinstance(self.key, str) or not _SECTION_KEY.match(self.key):
            raise ValueError(f"section key {self.key!r} is not allowed; allowed: lower-case "
                             "letters, digits and '_', starting with a letter")
        if self.key in RESERVED_KEYS:
            raise ValueError(f"section key {self.key!r} is reserved; allowed: any key but "
                             f"{', '.join(RESERVED_KEYS)}")
        if not (callable(self.driver) or isinstance(self.driver, str)):
            raise TypeError(f"driver of section {self.key!r} must be a callable or "
                            f"'module:attribute'; got {type(self.driver).__name__}")
        entry = self.load_entry()
        if not (isinstance(entry, type) and callable(getattr(entry, "parse", None))):
            raise TypeError(f"entry of section {self.key!r} must be a subclass of "
                            f"impactcont.scene.entries.EntrySpec; got {entry!r}")
        for kind in self.plots:
            if not isinstance(kind, PlotKind) or kind.section != self.key:
                raise ValueError(f"plot kind {getattr(kind, 'key', kind)!r} of section "
                                 f"{self.key!r} must be a PlotKind drawing {self.key!r}")


@dataclasses.dataclass(frozen=True)
class ProblemInfo:
    """A discovered problem.

    Attributes
    ----------
    name : str
        The name it is listed and looked up under.
    target : str
        ``"module:attribute"`` it was loaded from.
    origin : str
        ``"built-in"``, ``"registered"`` or ``"plugin <distribution> <version>"``.
    obj : object
        The loaded object: a :class:`SceneSection`, or a bare class.
    """

    name: str
    target: str
    origin: str
    obj: Any = dataclasses.field(repr=False, compare=False)

    @property
    def section(self) -> SceneSection | None:
        """The scene section the problem brings, if any."""
        return self.obj if isinstance(self.obj, SceneSection) else None

    @property
    def summary(self) -> str:
        """First line of the docstring of the problem (its entry dataclass for a section)."""
        section = self.section
        obj = self.obj
        if section is not None:
            try:
                obj = section.load_entry()
            except Exception:  # a broken entry target is reported when a scene uses it
                return section.title
        doc = inspect.getdoc(obj) or ""
        if doc.startswith(f"{getattr(obj, '__name__', '')}("):  # a dataclass's generated doc
            doc = ""
        return doc.strip().splitlines()[0] if doc.strip() else (
            section.title if section is not None else "")


# ---------------------------------------------------------------------------------------------
# Discovery
# ---------------------------------------------------------------------------------------------
_REGISTERED: dict[str, ProblemInfo] = {}


def _warn(message: str) -> None:
    warnings.warn(message, PluginWarning, stacklevel=3)


@functools.lru_cache(maxsize=1)
def _entry_points() -> tuple[importlib.metadata.EntryPoint, ...]:
    """The entry points of the group, first of each name only (duplicates warn)."""
    seen: dict[str, importlib.metadata.EntryPoint] = {}
    for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in seen:
            _warn(f"impactcont problem plugin {ep.name!r} is declared more than once "
                  f"({seen[ep.name].value} and {ep.value}); using {seen[ep.name].value}")
            continue
        seen[ep.name] = ep
    return tuple(seen.values())


def _origin(ep: importlib.metadata.EntryPoint) -> str:
    dist = getattr(ep, "dist", None)
    if dist is None:
        return "plugin"
    return f"plugin {dist.metadata['Name']} {dist.version}"


def _load_plugin(ep: importlib.metadata.EntryPoint) -> ProblemInfo | None:
    """Load one plugin; warn and return None when it fails or is malformed."""
    try:
        obj = ep.load()
        if isinstance(obj, SceneSection):
            obj.check()
    except Exception as exc:
        _warn(f"impactcont problem plugin {ep.name!r} ({ep.value}) failed to load and is "
              f"skipped: {type(exc).__name__}: {exc}")
        return None
    return ProblemInfo(ep.name, ep.value, _origin(ep), obj)


def _add(problems: dict[str, ProblemInfo], info: ProblemInfo) -> None:
    """Add ``info`` unless its name or scene key is taken (then warn)."""
    if info.name in problems:
        taken = problems[info.name]
        _warn(f"impactcont problem {info.name!r} ({info.target}) has the name of "
              f"{'a built-in problem' if taken.origin == 'built-in' else 'another problem'} "
              f"and is skipped")
        return
    section = info.section
    if section is not None:
        owner = next((p for p in problems.values()
                      if p.section is not None and p.section.key == section.key), None)
        if owner is not None:
            _warn(f"impactcont problem {info.name!r} ({info.target}) brings the scene section "
                  f"[[{section.key}]] of {owner.name!r} and is skipped")
            return
    problems[info.name] = info


@functools.lru_cache(maxsize=1)
def _discover() -> dict[str, ProblemInfo]:
    problems = {name: ProblemInfo(name, target, "built-in", load_target(target))
                for name, target in BUILTIN_PROBLEMS.items()}
    for info in _REGISTERED.values():
        _add(problems, info)
    for ep in _entry_points():
        info = _load_plugin(ep)
        if info is not None:
            _add(problems, info)
            log.debug("loaded problem plugin %r from %s", ep.name, ep.value)
    return problems


def list_problems() -> dict[str, ProblemInfo]:
    """Every available problem, built-in ones first: ``name -> ProblemInfo``.

    Broken plugins are left out with a :class:`PluginWarning` (once per
    process: the discovery is cached).
    """
    return dict(_discover())


def get_problem(name: str) -> Any:
    """The object of the problem called ``name`` (a :class:`SceneSection` or a class).

    Raises
    ------
    ParameterError
        No problem has that name; the message lists the available ones.
    """
    problems = _discover()
    if name not in problems:
        close = difflib.get_close_matches(str(name), list(problems), n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ParameterError(f"unknown problem {name!r}{hint}; available: "
                             f"{', '.join(problems)}")
    return problems[name].obj


def register_problem(name: str, obj: SceneSection | type, *, replace: bool = False) -> None:
    """Register a problem in this process (after the built-in ones, before plugins).

    Parameters
    ----------
    name : str
        The name it is listed under.
    obj : SceneSection or type
        Its scene section (then a scene can run it), or a bare class.
    replace : bool
        Replace a problem registered under that name in this process.

    Raises
    ------
    ValueError
        The name is taken (by a built-in problem, or by a registered one and
        ``replace`` is false), or the section is malformed.
    """
    if name in BUILTIN_PROBLEMS:
        raise ValueError(f"problem name {name!r} is taken by a built-in problem")
    if name in _REGISTERED and not replace:
        raise ValueError(f"a problem {name!r} is already registered")
    if isinstance(obj, SceneSection):
        obj.check()
        for other in _discover().values():
            if (other.name != name and other.section is not None
                    and other.section.key == obj.key):
                raise ValueError(f"scene section [[{obj.key}]] is already brought by problem "
                                 f"{other.name!r}")
    target = f"{getattr(obj, '__module__', '?')}:{getattr(obj, '__qualname__', name)}"
    _REGISTERED[name] = ProblemInfo(name, target, "registered", obj)
    _discover.cache_clear()


def unregister_problem(name: str) -> None:
    """Forget a problem registered with :func:`register_problem` (no error if absent)."""
    if _REGISTERED.pop(name, None) is not None:
        _discover.cache_clear()


def refresh_problems() -> None:
    """Forget the discovered plugins: the next call looks the entry points up again."""
    _entry_points.cache_clear()
    _discover.cache_clear()


# ---------------------------------------------------------------------------------------------
# Views for scenes
# ---------------------------------------------------------------------------------------------
def scene_sections() -> dict[str, SceneSection]:
    """The scene sections of every problem, in the order a run computes them: ``key -> section``."""
    return {info.section.key: info.section for info in _discover().values()
            if info.section is not None}


def plot_kinds() -> dict[str, PlotKind]:
    """The plot kinds the sections bring: ``kind -> PlotKind`` (first of a key wins)."""
    kinds: dict[str, PlotKind] = {}
    for section in scene_sections().values():
        for kind in section.plots:
            kinds.setdefault(kind.key, kind)
    return kinds
