"""Scene sections for two-parameter studies: ``[[curves]]`` and ``[[maps]]``.

``[[curves]]`` continues a codim-1 curve (SN, PD, NS, GR or ZV) in two
parameters with :func:`impactcont.analysis.curves.curve`, started from a special point
of a computed ``[[branches]]`` entry, from explicit values, or from a
one-parameter continuation; ``[[maps]]`` evaluates the existence,
physicality and stability of motions over a grid of any two parameters with
:func:`impactcont.analysis.maps.stability_map`: every N-1 motion of the entry's
oscillator (closed form), or the N-p family through the motion a ``[[simulations]]``
entry settled on (``start``, ``N``, ``p``, as ``[[multi_impact]]`` takes it). The
datasets follow :mod:`impactcont.dataset.curves` and :mod:`impactcont.dataset.maps`
(``docs/two_parameter.md``, ``docs/scenes.md``). The sections are
registered by :mod:`impactcont.scene.sections`.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import re
import time
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
import xarray as xr

from impactcont.analysis.curves import check_curve_arguments, curve
from impactcont.analysis.map_runner import SCHEDULER_PROTOCOLS
from impactcont.analysis.maps import map_plane, stability_map
from impactcont.dataset.attributes import split_parameters
from impactcont.dataset.curves import kind_of_curve
from impactcont.dataset.maps import MULTI_MAP_KIND, map_parameters
from impactcont.errors import ImpactcontError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import model_parameter
from impactcont.orbit.multi_impact import multi_impact_orbit
from impactcont.problems.codim1 import SHOOTING_KINDS, curve_problem
from impactcont.scene.entries import (
    CONTINUATION_KEYS,
    PARAMETER_RANGES,
    EntrySpec,
    check_closed_form,
    check_continuation,
    continuation_entry,
    defaults_of,
    library_check,
    refuse_changes,
)
from impactcont.scene.keys import (
    ENTRY_NAME,
    NAME_ALLOWED,
    Boolean,
    Integer,
    Interval,
    Real,
    String,
    ValueType,
    Where,
    declare,
    show,
)
from impactcont.scene.switches import origin_of, simulation_seed
from impactcont.scene.tasks import markdown_table
from impactcont.vocabulary import CURVE_KINDS

__all__ = ["CURVES", "MAPS", "CurveSpec", "MapSpec", "check_curves_plot"]

log = logging.getLogger(__name__)

_CURVE_KINDS = CURVE_KINDS  # the curves of N-1 motions (closed form)
#: The curves of N-p motions (followed by shooting from a [[multi_impact]] or [[switches]]
#: entry): the N-1 kinds, BP of symmetric motions, SE, RG and SO of motions with sticking
#: phases.
_NP_KINDS = tuple(str(kind) for kind in SHOOTING_KINDS)
#: What ``kind`` may be, in words: from the kinds themselves.
_KIND_HELP = (f"the curve: {', '.join(_CURVE_KINDS)}; from an N-p branch also "
              + ", ".join(f"{kind} ({kind.words})" for kind in SHOOTING_KINDS
                          if kind not in _CURVE_KINDS))
#: The sections whose branches are of N-p motions (a curve from them is followed by
#: shooting).
_NP_SECTIONS = ("multi_impact", "switches")


_CURVE = defaults_of(curve)


class _ParameterPair(ValueType):
    allowed = ("a pair of distinct parameter names [p1, p2] from " +
               ", ".join(json.dumps(p) for p in PARAMETER_RANGES))

    def check(self, value: Any, where: Where) -> tuple[str, str]:
        if (not isinstance(value, list) or len(value) != 2
                or not all(isinstance(v, str) and v in PARAMETER_RANGES for v in value)
                or value[0] == value[1]):
            raise self.fail(value, where, "not a pair of distinct parameters")
        return value[0], value[1]


class _Bounds(ValueType):
    allowed = "a table {p1 = [lo, hi], p2 = [lo, hi]} for the two parameters"

    def check(self, value: Any, where: Where) -> dict[str, tuple[float, float]]:
        if not isinstance(value, dict) or not value:
            raise self.fail(value, where, "wrong type or empty")
        out = {}
        for name, interval in value.items():
            if name not in PARAMETER_RANGES:
                raise where.key(name).error(f"unknown parameter {name!r}",
                                            ", ".join(PARAMETER_RANGES))
            out[name] = Interval(PARAMETER_RANGES[name]).check(interval, where.key(name))
        return out


class _Start(ValueType):
    allowed = (f"the name of a [[branches]] entry ({NAME_ALLOWED}), or a table "
               "{p1 = value, p2 = value, delta = value} (delta optional)")

    def check(self, value: Any, where: Where) -> str | dict[str, float]:
        if isinstance(value, str):
            return ENTRY_NAME.check(value, where)
        if isinstance(value, dict) and value:
            return {k: Real().check(v, where.key(k)) for k, v in value.items()}
        raise self.fail(value, where, "wrong type")


class _NList(ValueType):
    allowed = "an integer >= 1 or an array of distinct integers >= 1"

    def check(self, value: Any, where: Where) -> tuple[int, ...]:
        items = value if isinstance(value, list) else [value]
        if not items or any(isinstance(v, bool) or not isinstance(v, int) or v < 1
                            for v in items) or len(set(items)) != len(items):
            raise self.fail(value, where, "invalid")
        return tuple(int(v) for v in items)


@dataclasses.dataclass(frozen=True, kw_only=True)
class CurveSpec(continuation_entry(curve, "CurveEntry")):
    """``[[curves]]``: a codim-1 curve in two parameters, of N-1 motions (closed form) or,
    from a ``[[multi_impact]]`` or ``[[switches]]`` entry, of its N-p motions (shooting)."""

    section: ClassVar[str] = "curves"

    kind: str = declare(String(_NP_KINDS), _KIND_HELP, required=True)
    N: int | None = declare(Integer(1, 1000), "one impact every N forcing periods (default: "
                            "the start branch's, else 1; an N-p start's N and p are its own)")
    parameters: tuple[str, str] = declare(_ParameterPair(), "the two parameters [p1, p2]",
                                          ("omega", "b"))
    bounds: Mapping[str, tuple[float, float]] = declare(
        _Bounds(), "the box of the two parameters", required=True)
    start: str | Mapping[str, float] | None = declare(
        _Start(), "a [[branches]], [[multi_impact]] or [[switches]] entry, or values "
        "{p1, p2, delta}; default: found by a one-parameter continuation in p1")
    special: int | None = declare(Integer(0), "which special point of the kind on the start")
    root: int | None = declare(Integer(choices=(1, -1)), "root of eq. (15) to start on")
    codim2: bool = declare(Boolean(), "detect and locate codimension-two points",
                           _CURVE["detect_codim2_points"])

    def check(self, where: Where, osc: ImpactOscillator) -> None:
        super().check(where, osc)
        if set(self.bounds) != set(self.parameters):
            raise where.key("bounds").error(
                f"gives {sorted(self.bounds)} for parameters {list(self.parameters)}",
                f"exactly the two parameters {list(self.parameters)}")
        if isinstance(self.start, dict):
            allowed = {*self.parameters, "delta"}
            extra = sorted(set(self.start) - allowed)
            missing = [p for p in self.parameters if p not in self.start]
            if extra or missing:
                raise where.key("start").error(
                    f"{show(self.start)} " + (f"has unknown {extra}" if extra
                                              else f"lacks {missing}"),
                    f"values of {', '.join(sorted(allowed))} (delta optional)")
        if not isinstance(self.start, str):  # a start from a branch: check_scene
            self._check_n1_kind(where, "a start that is not a branch")
            self._check_arguments(where, osc)

    def _check_n1_kind(self, where: Where, start: str) -> None:
        if self.kind not in _CURVE_KINDS:
            raise where.key("kind").error(
                f"{self.kind!r} is a curve of N-p motions only ({start} gives N-1 motions)",
                f"one of {list(_CURVE_KINDS)}, or start from a [[multi_impact]] or "
                "[[switches]] entry")

    def _check_arguments(self, where: Where, osc: ImpactOscillator) -> None:
        """The checks :func:`impactcont.analysis.curves.curve` makes before it computes, on the
        arguments :meth:`Curves.compute` passes (``osc`` is the branch's for a start from a
        branch)."""
        keys = ("kind", "N", "parameters", "bounds", "start", "special", "root",
                *CONTINUATION_KEYS)
        N = self.N if self.N is not None else 1
        _, (p1, p2), box, _, _ = library_check(
            where, check_curve_arguments, osc, N, self.kind, parameters=self.parameters,
            bounds=dict(self.bounds), keys=keys, **self.continuation_options())
        check_closed_form(osc, where, f"the {self.kind} curve")
        if self.start is None:  # a branch in p1 at the oscillator's p2 finds the start
            check_continuation(osc, where, N, p1, box[p1], detect=(self.kind,))
            start = {p2: getattr(osc, p2)}
        elif isinstance(self.start, Mapping):
            library_check(where, curve_problem, self.kind, osc, N, (p1, p2), keys=keys)
            start = {name: v for name, v in self.start.items() if name in box}
        else:
            start = {}
        for name, value in start.items():
            lo, hi = box[name]
            if value is None or not lo <= value <= hi:
                raise where.key("start" if self.start is not None else "bounds").error(
                    f"the start {name} = {value!r} lies outside bounds.{name} = [{lo:g}, {hi:g}]"
                    + ("" if self.start is not None else f" (the oscillator's {name}: the curve "
                       f"starts on the branch in {p1} at this {name})"),
                    f"bounds.{name} containing {value!r}" if value is not None
                    else f"a parameter the oscillator has ({name} = None)")

    def check_scene(self, where: Where, sections: Mapping[str, tuple[EntrySpec, ...]]
                    ) -> None:
        if not isinstance(self.start, str):
            return
        branches = {e.name: e for e in sections.get("branches", ())}
        np_entries = {e.name: e for key in _NP_SECTIONS for e in sections.get(key, ())}
        if self.start in np_entries:
            self._check_np_start(where, sections, np_entries[self.start])
            return
        if self.start not in branches:
            raise where.key("start").error(
                f"{self.start!r} is not a [[branches]], [[multi_impact]] or [[switches]] "
                "entry", ", ".join([*branches, *np_entries]) or "a [[branches]] entry")
        self._check_n1_kind(where, f"the [[branches]] entry {self.start!r}")
        branch = branches[self.start]
        if branch.parameter not in self.parameters:
            raise where.key("start").error(
                f"branch {self.start!r} is continued in {branch.parameter!r}",
                f"a branch continued in one of {list(self.parameters)}")
        if self.N is not None and self.N != branch.N:
            raise where.key("N").error(f"{self.N} differs from N = {branch.N} of branch "
                                       f"{self.start!r}", f"{branch.N}, or leave it out")
        refuse_changes(self, where, "a curve started from a branch uses the branch's oscillator")
        self._check_arguments(where, branch.oscillator)

    def _check_np_start(self, where: Where, sections: Mapping[str, tuple[EntrySpec, ...]],
                        start: EntrySpec) -> None:
        """A curve from an N-p branch: ``p1`` is the branch's parameter, ``p2`` one of its
        oscillator's, N and p the branch's; what :func:`~impactcont.analysis.curves.curve`
        checks further (the special point of the kind, the start inside the bounds) is
        known once the branch is computed."""
        origin, osc = origin_of(start, sections)
        parameter = origin.parameter
        if self.parameters[0] != parameter:
            raise where.key("parameters").error(
                f"{list(self.parameters)} from the N-p branch {self.start!r}, continued in "
                f"{parameter!r}", f"[{parameter!r}, p2]: p1 is the branch's parameter")
        if self.N is not None:
            raise where.key("N").error(
                f"{self.N} given with the N-p branch {self.start!r}",
                "no N: the curve follows the branch's motion (its N and p)")
        library_check(where.key("parameters"), model_parameter, osc, self.parameters[1])
        refuse_changes(self, where, "a curve started from a branch uses the branch's oscillator")


def _span(v: np.ndarray) -> str:
    return f"[{v.min():.6g}, {v.max():.6g}]" if v.size else "-"


class Curves:
    """``[[curves]]``: :func:`impactcont.analysis.curves.curve`."""

    def compute(self, entry: CurveSpec, context: Any = None) -> xr.Dataset:
        t0 = time.perf_counter()
        osc: ImpactOscillator | None = entry.oscillator
        start: Any = entry.start
        N: int | None = entry.N if entry.N is not None else 1
        if isinstance(start, str):
            datasets = context.datasets if context is not None else {}
            branches = {name: ds for key in ("branches", *_NP_SECTIONS)
                        for name, ds in datasets.get(key, {}).items()}
            if start not in branches:
                raise ImpactcontError(f"curve {entry.name}: its start branch {start!r} was "
                                      f"not computed (it failed)")
            start, osc, N = branches[start], None, entry.N
        ds = curve(osc, N, entry.kind, start=start, special=entry.special,
                   parameters=entry.parameters, bounds=dict(entry.bounds), root=entry.root,
                   detect_codim2_points=entry.codim2, **entry.continuation_options())
        ds.attrs["name"] = entry.name
        log.info("curve %s: %s in %s, %d points, %d codim-2 point(s) (%.1f s)", entry.name,
                 entry.kind, "/".join(entry.parameters), ds.sizes["point"],
                 ds.sizes.get("codim2", 0), time.perf_counter() - t0)
        return ds

    def describe(self, datasets: Mapping[str, xr.Dataset]) -> list[str]:
        rows = []
        for name, ds in datasets.items():
            p1, p2 = split_parameters(str(ds.attrs["parameters"]))
            x, y = np.asarray(ds[p1].values), np.asarray(ds[p2].values)
            rows.append([name, kind_of_curve(ds), int(ds.attrs["N"]), f"{p1}, {p2}",
                         int(ds.sizes["point"]), _span(x), _span(y),
                         int(ds.sizes.get("codim2", 0)),
                         str(ds.attrs.get("end_status", "-")).replace("|", "/")])
        return markdown_table(["curve", "kind", "N", "parameters", "points", "p1 range", "p2 range",
                       "codim-2 points", "end"], rows)

    def special_points(self, datasets: Mapping[str, xr.Dataset]) -> list[dict[str, Any]]:
        out = []
        for name, ds in datasets.items():
            p1, p2 = split_parameters(str(ds.attrs["parameters"]))
            for k in range(ds.sizes.get("codim2", 0)):
                out.append({"curve": name, "kind": kind_of_curve(ds),
                            "label": str(ds["codim2_label"].values[k]),
                            p1: float(ds[f"codim2_{p1}"].values[k]),
                            p2: float(ds[f"codim2_{p2}"].values[k]),
                            "status": str(ds["codim2_status"].values[k]),
                            "precision": float(ds["codim2_precision"].values[k])})
        return out


CURVES = Curves()


#: Where a map of a scene runs: this process, a process pool, a dask cluster.
MAP_EXECUTORS = ("serial", "process", "dask")
#: A dask scheduler's address: ``protocol://host:port``.
SCHEDULER = re.compile("^(" + "|".join(map(re.escape, SCHEDULER_PROTOCOLS))
                       + r")(\[[0-9A-Fa-f:.]+\]|[^\s/:\[\]]+)(:\d{1,5})?(/[^\s/]+)*$")
SCHEDULER_ALLOWED = ("a dask scheduler address, protocol://host:port (protocol one of "
                     + ", ".join(p[:-3] for p in SCHEDULER_PROTOCOLS) + "), e.g. "
                     "\"tcp://10.0.0.5:8786\"")


def check_map_executor(entry: Any, where: Where) -> None:
    """``executor``, ``max_workers`` and ``scheduler`` of a map entry agree: a scheduler
    exactly with ``executor = "dask"``, and no processes for a dask cluster."""
    if entry.executor == "dask" and entry.scheduler is None:
        raise where.key("scheduler").error(
            'executor = "dask" needs the address of the dask scheduler', SCHEDULER_ALLOWED)
    if entry.executor != "dask" and entry.scheduler is not None:
        raise where.key("scheduler").error(
            f"a scheduler is used by executor = \"dask\" only; executor is "
            f"{json.dumps(entry.executor)}", 'executor = "dask", or no scheduler')
    if entry.executor == "dask" and entry.max_workers is not None:
        raise where.key("max_workers").error(
            'max_workers sets the processes of executor = "process"; on a dask cluster its '
            "workers decide (as many tasks at once as they have threads)",
            'executor = "process", or no max_workers')


def map_executor(entry: Any) -> str:
    """The ``executor=`` of the map function for a map entry: the scheduler's address
    for ``"dask"`` (the map connects to it and disconnects at its end)."""
    return entry.scheduler if entry.executor == "dask" else entry.executor


class _Points(ValueType):
    allowed = "an array [n1, n2] of grid points of the two parameters, each 2 .. 100000"

    def check(self, value: Any, where: Where) -> tuple[int, int]:
        if not isinstance(value, list) or len(value) != 2:
            raise self.fail(value, where, "not two numbers of points")
        return (Integer(2, 100_000).check(value[0], where.key("0")),
                Integer(2, 100_000).check(value[1], where.key("1")))


#: The keys of the (omega, b) spelling of a map's grid, and what replaces them in any plane.
_OMEGA_B_KEYS = ("omega_range", "omega_points", "b_range", "b_points")


@dataclasses.dataclass(frozen=True, kw_only=True)
class MapSpec(EntrySpec):
    """``[[maps]]``: existence, physicality and stability of motions over a grid of two
    parameters: every N-1 motion (closed form), or the N-p family through a simulated
    motion (``start``, ``p``)."""

    section: ClassVar[str] = "maps"

    N: tuple[int, ...] = declare(_NList(), "forcing periods per impact (one N with start)",
                                 (1, 2, 3, 4))
    parameters: tuple[str, str] = declare(_ParameterPair(), "the two parameters [p1, p2] "
                                          "(elements too: \"k2\", \"gap[A]\", ...)",
                                          ("omega", "b"))
    ranges: Mapping[str, tuple[float, float]] | None = declare(
        _Bounds(), "the box of the two parameters {p1 = [lo, hi], p2 = [lo, hi]}")
    points: tuple[int, int] | None = declare(_Points(), "grid points [n1, n2] of the two "
                                             "parameters (default 101 each)")
    omega_range: tuple[float, float] | None = declare(
        Interval(PARAMETER_RANGES["omega"]), "[lo, hi] of the omega grid (the (omega, b) "
        "plane; or ranges)")
    omega_points: int | None = declare(Integer(2, 100_000), "points of the omega grid (101)")
    b_range: tuple[float, float] | None = declare(Interval(), "[lo, hi] of the b grid (the "
                                                  "(omega, b) plane; or ranges)")
    b_points: int | None = declare(Integer(2, 100_000), "points of the b grid (101)")
    start: str | None = declare(ENTRY_NAME, "a [[simulations]] entry whose last p + 1 impacts "
                                "seed the N-p motion whose family is mapped")
    p: int | None = declare(Integer(1, 1000), "impacts per motion (with start)")
    executor: str = declare(String(MAP_EXECUTORS),
                            "run in this process, in a process pool or on a dask cluster",
                            "serial")
    max_workers: int | None = declare(Integer(1, 1024), "processes of the pool")
    scheduler: str | None = declare(String(pattern=SCHEDULER, pattern_text=SCHEDULER_ALLOWED),
                                    "address of the dask scheduler (executor \"dask\")")
    memory_limit: float = declare(Real(0, low_open=True), "bytes the map may take before it "
                                  "goes to a temporary file", 1e9)

    def grid(self) -> dict[str, np.ndarray]:
        """``{parameter: grid}`` of the entry, in the order of ``parameters``."""
        first, second = self.parameters
        if self.ranges is not None:
            n1, n2 = self.points or (101, 101)
            return {first: np.linspace(*self.ranges[first], n1),
                    second: np.linspace(*self.ranges[second], n2)}
        return {"omega": np.linspace(*self.omega_range, self.omega_points or 101),
                "b": np.linspace(*self.b_range, self.b_points or 101)}

    def check(self, where: Where, osc: ImpactOscillator) -> None:
        for key in self.parameters:
            if key in self.changes:
                raise where.key(key).error(f"a map spans {key}; the entry's {key} is not used",
                                           "the grid of the map's parameters: ranges, or "
                                           f"{key}_range and {key}_points" if key in ("omega", "b")
                                           else "ranges and points")
        self._check_grid_keys(where)
        if self.start is None:
            for key in ("p",):
                if getattr(self, key) is not None:
                    raise where.key(key).error(f"{key} is the impacts of the motion of start",
                                               "start = a [[simulations]] entry, with p")
            check_closed_form(osc, where, "the N-1 stability map")
            library_check(where.key("ranges"), map_plane, osc, self.parameters, self.grid())
        else:
            if self.p is None:
                raise where.key("p").error("a map from a simulated motion needs its impacts",
                                           "p = the impacts of the motion in N periods")
            if len(self.N) != 1:
                raise where.key("N").error(f"{list(self.N)}: the family of one motion has one N",
                                           "one integer N, the forcing periods of the motion")
        n1, n2 = (g.size for g in self.grid().values())
        if len(self.N) * n1 * n2 > 50_000_000:
            raise where.key("points" if self.ranges is not None else "omega_points").error(
                "the grid is too large", "at most 5e7 points over N x p1 x p2")
        check_map_executor(self, where)

    def _check_grid_keys(self, where: Where) -> None:
        """The grid is given once: ``ranges`` (and ``points``) for any pair, or the (omega, b)
        keys for the (omega, b) plane."""
        given = [key for key in _OMEGA_B_KEYS if getattr(self, key) is not None]
        if self.ranges is not None:
            if given:
                raise where.key(given[0]).error(
                    "the grid is given by ranges; this key is the (omega, b) spelling",
                    "ranges and points, without omega_range, omega_points, b_range, b_points")
            if set(self.ranges) != set(self.parameters):
                raise where.key("ranges").error(
                    f"gives {sorted(self.ranges)} for parameters {list(self.parameters)}",
                    f"exactly the two parameters {list(self.parameters)}")
            return
        if self.parameters != ("omega", "b"):
            raise where.key(given[0] if given else "ranges").error(
                f"a map over {list(self.parameters)} needs the grid of both",
                "ranges = {" + ", ".join(f"{json.dumps(n) if not n.isidentifier() else n} = "
                                         "[lo, hi]" for n in self.parameters)
                + "} and points = [n1, n2]")
        if self.points is not None:
            raise where.key("points").error("points go with ranges",
                                            "omega_points and b_points, or ranges and points")
        for key in ("omega_range", "b_range"):
            if getattr(self, key) is None:
                raise where.key(key).error("a map of the (omega, b) plane needs the range of both",
                                           f"{key} = [lo, hi], or ranges")

    def check_scene(self, where: Where, sections: Mapping[str, tuple[EntrySpec, ...]]
                    ) -> None:
        if self.start is None:
            return
        simulations = {e.name: e for e in sections.get("simulations", ())}
        if self.start not in simulations:
            raise where.key("start").error(f"{self.start!r} is not a [[simulations]] entry",
                                           ", ".join(simulations) or "a [[simulations]] entry")
        refuse_changes(self, where, "the motion is found at the oscillator of the simulation "
                       "it starts from")
        osc = simulations[self.start].oscillator
        library_check(where.key("ranges"), map_plane, osc, self.parameters, self.grid())


class Maps:
    """``[[maps]]``: :func:`impactcont.analysis.maps.stability_map` of the entry's oscillator
    (every N-1 motion) or of the motion its simulation settled on (that motion's family)."""

    def compute(self, entry: MapSpec, context: Any = None) -> xr.Dataset:
        t0 = time.perf_counter()
        grid = entry.grid()
        run = {"executor": map_executor(entry), "max_workers": entry.max_workers,
               "memory_limit": entry.memory_limit}
        if entry.start is None:
            ds = stability_map(entry.oscillator, N=list(entry.N), parameters=entry.parameters,
                               grid=grid, **run)
            what = f"N = {list(entry.N)}"
        else:
            sim = context.datasets.get("simulations", {}).get(entry.start) \
                if context is not None else None
            if sim is None:
                raise ImpactcontError(f"map {entry.name}: its start {entry.start!r} was not "
                                      f"computed (it failed)")
            osc = ImpactOscillator.from_json(sim.attrs["oscillator"])
            seed = _MotionOf(name=entry.name, start=entry.start, N=entry.N[0], p=entry.p)
            motion = multi_impact_orbit(osc, seed.N, seed.p, simulation_seed(sim, seed, osc))
            ds = stability_map(motion, parameters=entry.parameters, grid=grid, **run)
            ds.attrs["start"] = entry.start
            what = f"the {seed.N}-{seed.p} family of simulation {entry.start}"
        ds.attrs["name"] = entry.name
        log.info("map %s: %s over %s on %d x %d points (%.1f s)", entry.name, what,
                 "/".join(entry.parameters), *(g.size for g in grid.values()),
                 time.perf_counter() - t0)
        return ds

    def describe(self, datasets: Mapping[str, xr.Dataset]) -> list[str]:
        rows = []
        for name, ds in datasets.items():
            first, second = map_parameters(ds)
            x, y = np.asarray(ds[first].values), np.asarray(ds[second].values)
            grid = [f"{first} in [{x.min():.6g}, {x.max():.6g}] x {x.size}",
                    f"{second} in [{y.min():.6g}, {y.max():.6g}] x {y.size}"]
            if ds.attrs.get("impactcont_dataset") == MULTI_MAP_KIND:
                found = np.asarray(ds["found"].values, dtype=bool)
                stable = found & np.asarray(ds["stable"].values & ds["physical"].values,
                                            dtype=bool)
                rows.append([name, f"{int(ds.attrs['N'])}-{int(ds.attrs['impacts'])} family "
                             f"({ds.attrs['pattern']})", *grid,
                             f"{100 * found.mean():.1f}%", f"{100 * stable.mean():.1f}%"])
                continue
            for N in np.asarray(ds["N"].values):
                stable = np.asarray(ds["n_stable"].sel(N=N).values) > 0
                exists = np.asarray(ds["exists"].sel(N=N).values, dtype=bool)
                rows.append([name, f"N = {int(N)}, every N-1 motion", *grid,
                             f"{100 * exists.mean():.1f}%", f"{100 * stable.mean():.1f}%"])
        return markdown_table(["map", "motions", "first parameter", "second parameter",
                               "motion exists (found)", "stable physical motion"], rows)

    def special_points(self, datasets: Mapping[str, xr.Dataset]) -> list[dict[str, Any]]:
        return []


@dataclasses.dataclass(frozen=True)
class _MotionOf:
    """What :func:`~impactcont.scene.switches.simulation_seed` reads of an entry."""

    name: str
    start: str
    N: int
    p: int


MAPS = Maps()



def check_curves_plot(plot: Any, entries: list[CurveSpec], where: Where) -> None:
    """A ``curves`` plot draws curves in one parameter plane."""
    planes = {tuple(e.parameters) for e in entries}
    if len(planes) > 1:
        raise where.key("data").error(f"curves in different parameter planes {sorted(planes)}",
                                      "curves with the same parameters [p1, p2]")
