"""Problems from other packages: discovery through the entry-point group ``impactcont.problems``.

A package adds a problem (a model or a problem the continuation core can
follow) by declaring an entry point in its ``pyproject.toml``::

    [project.entry-points."impactcont.problems"]
    my_problem = "my_package.problems:MyProblem"

The object it names is loaded once per process, on first discovery. A plugin
that fails to load (missing module, import error, ...) emits a
:class:`PluginWarning` naming the plugin and the error, and is left out; the
built-in problems and the other plugins still work. A plugin may not take the
name of a built-in problem, and of two plugins with one name the first wins;
both cases warn.

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
import warnings
from typing import Any

from impactcont.errors import ParameterError

__all__ = [
    "BUILTIN_PROBLEMS",
    "ENTRY_POINT_GROUP",
    "PluginWarning",
    "ProblemInfo",
    "get_problem",
    "list_problems",
    "refresh_problems",
]

log = logging.getLogger(__name__)

#: The entry-point group of problem plugins.
ENTRY_POINT_GROUP = "impactcont.problems"

#: Problems that ship with impactcont: name -> ``"module:attribute"``.
BUILTIN_PROBLEMS: dict[str, str] = {
    "periodic_n1": "impactcont.problems.periodic_branch:PeriodicBranchProblem",
}


class PluginWarning(UserWarning):
    """A problem plugin could not be loaded, or its name clashes with another problem."""


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
        ``"built-in"`` or ``"plugin <distribution> <version>"``.
    obj : object
        The loaded object (a class or a factory).
    """

    name: str
    target: str
    origin: str
    obj: Any = dataclasses.field(repr=False, compare=False)

    @property
    def summary(self) -> str:
        """First line of the object's docstring."""
        doc = inspect.getdoc(self.obj) or ""
        return doc.strip().splitlines()[0] if doc.strip() else ""


def _load_target(target: str) -> Any:
    module, _, attribute = target.partition(":")
    obj: Any = importlib.import_module(module)
    for part in filter(None, attribute.split(".")):
        obj = getattr(obj, part)
    return obj


@functools.lru_cache(maxsize=1)
def _entry_points() -> tuple[importlib.metadata.EntryPoint, ...]:
    """The entry points of the group, first of each name only (duplicates warn)."""
    seen: dict[str, importlib.metadata.EntryPoint] = {}
    for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in seen:
            warnings.warn(f"impactcont problem plugin {ep.name!r} is declared more than once "
                          f"({seen[ep.name].value} and {ep.value}); using {seen[ep.name].value}",
                          PluginWarning, stacklevel=2)
            continue
        seen[ep.name] = ep
    return tuple(seen.values())


def _origin(ep: importlib.metadata.EntryPoint) -> str:
    dist = getattr(ep, "dist", None)
    if dist is None:
        return "plugin"
    return f"plugin {dist.metadata['Name']} {dist.version}"


def _load_plugin(ep: importlib.metadata.EntryPoint) -> ProblemInfo | None:
    """Load one plugin; warn and return None when it fails."""
    try:
        obj = ep.load()
    except Exception as exc:
        warnings.warn(f"impactcont problem plugin {ep.name!r} ({ep.value}) failed to load and "
                      f"is skipped: {type(exc).__name__}: {exc}", PluginWarning, stacklevel=2)
        return None
    return ProblemInfo(ep.name, ep.value, _origin(ep), obj)


@functools.lru_cache(maxsize=1)
def _discover() -> dict[str, ProblemInfo]:
    problems = {name: ProblemInfo(name, target, "built-in", _load_target(target))
                for name, target in BUILTIN_PROBLEMS.items()}
    for ep in _entry_points():
        if ep.name in problems:
            warnings.warn(f"impactcont problem plugin {ep.name!r} ({ep.value}) has the name of "
                          f"a built-in problem and is skipped", PluginWarning, stacklevel=2)
            continue
        info = _load_plugin(ep)
        if info is not None:
            problems[ep.name] = info
            log.debug("loaded problem plugin %r from %s", ep.name, ep.value)
    return problems


def list_problems() -> dict[str, ProblemInfo]:
    """Every available problem, built-in ones first: ``name -> ProblemInfo``.

    Broken plugins are left out with a :class:`PluginWarning` (once per
    process: the discovery is cached).
    """
    return dict(_discover())


def get_problem(name: str) -> Any:
    """The object of the problem called ``name``.

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


def refresh_problems() -> None:
    """Forget the discovered plugins: the next call looks the entry points up again."""
    _entry_points.cache_clear()
    _discover.cache_clear()
