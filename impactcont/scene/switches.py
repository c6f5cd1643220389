"""Scene sections of N-p motions: ``[[switches]]`` and ``[[multi_impact]]``.

A switch starts from a computed branch (a ``[[branches]]`` or ``[[multi_impact]]``
entry, or an earlier ``[[switches]]`` entry, so that entries chain into a cascade)
at one of its period-doubling points (:func:`impactcont.period_doubling_switch`: the
2N-2p motion), grazing points (:func:`impactcont.grazing_switch`: the motion with
one more impact) or symmetry-breaking pitchforks of a symmetric N-p branch
(:func:`impactcont.analysis.switching.pitchfork_branch`: one motion of the asymmetric pair,
``side`` +1 or -1), and follows the new branch with
:func:`impactcont.multi_impact_continuation`'s options. The dataset is an N-p
branch (``docs/multi_impact.md``), described and drawn as the branches are.

A ``[[multi_impact]]`` entry continues the branch of N-p motions (p impacts
in N forcing periods) through the motion that Newton finds
(:func:`impactcont.multi_impact_orbit`) from the last p + 1 impacts of a
computed ``[[simulations]]`` entry: an attractor seen by brute force becomes
a branch (:func:`impactcont.multi_impact_continuation`). The simulation must
show that motion: p impacts in its last N forcing periods
(:func:`simulation_seed`).
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Mapping
from typing import Any, ClassVar, NamedTuple

import numpy as np
import xarray as xr

from impactcont.analysis.branch import make_options, multi_impact_continuation
from impactcont.analysis.switching import (
    NOT_SYMMETRIC,
    grazing_switch,
    period_doubling_switch,
    pitchfork_branch,
)
from impactcont.dataset.multi import impacts_of, pattern_of
from impactcont.errors import ImpactcontError, NoPeriodicMotionError, ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import model_parameter
from impactcont.orbit.multi_impact import landing_impacts, multi_impact_orbit
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem
from impactcont.scene.entries import (
    CONTINUATION_KEYS,
    PARAMETER_NAME,
    PARAMETER_RANGES,
    EntrySpec,
    continuation_entry,
    detect_key,
    library_check,
    refuse_changes,
)
from impactcont.scene.keys import (
    ENTRY_NAME,
    Integer,
    Interval,
    Real,
    String,
    Where,
    declare,
    show,
)
from impactcont.scene.tasks import BRANCHES, markdown_table
from impactcont.vocabulary import check_parameter

__all__ = [
    "MULTI_IMPACT",
    "SETTLED",
    "SWITCHES",
    "MultiImpactSpec",
    "SwitchSpec",
    "origin_of",
    "simulation_seed",
]

log = logging.getLogger(__name__)

#: The continuation keys of a switch: it goes one way, away from the special point.
_KEYS = ("ds", "ds_min", "ds_max", "newton_tol", "max_points")


@dataclasses.dataclass(frozen=True, kw_only=True)
class SwitchSpec(continuation_entry(multi_impact_continuation, "SwitchEntry", _KEYS)):
    """``[[switches]]``: the branch born at a PD or grazing point of a computed branch."""

    section: ClassVar[str] = "switches"

    start: str = declare(ENTRY_NAME, "the [[branches]] or [[multi_impact]] entry, or an "
                         "earlier [[switches]] entry, to switch from", required=True)
    at: str = declare(String(("PD", "GR", "BP")), "switch at a period-doubling (PD) point, "
                      "a grazing (GR) point or a symmetry-breaking pitchfork (BP) of the start",
                      "PD")
    which: int = declare(Integer(0), "which point of that kind on the start (branch order)", 0)
    side: int | None = declare(Integer(choices=(1, -1)), "at BP only: which motion of the "
                               "asymmetric pair, +1 or -1 (mirror images; default +1)")
    bounds: tuple[float, float] | None = declare(
        Interval(), "range of the parameter (default: the start's)")
    epsilon: float | None = declare(
        Real(0.0, 1.0, low_open=True, high_open=True),
        "first step away from the point along the new branch (default 1e-3 at PD, 1e-4 at GR)")
    detect: tuple[str, ...] = detect_key()

    def check(self, where: Where, osc: ImpactOscillator) -> None:
        super().check(where, osc)
        refuse_changes(self, where, "a switch uses the oscillator of the branch it starts from")
        if self.side is not None and self.at != "BP":
            raise where.key("side").error(
                f"{self.side:+d} is only used with at = \"BP\" (which motion of a pitchfork's "
                f"mirror pair); at = \"{self.at}\" has one new branch",
                'leave side out, or set at = "BP"')

    def check_scene(self, where: Where, sections: Mapping[str, tuple[EntrySpec, ...]]
                    ) -> None:
        branches = [e.name for e in sections.get("branches", ())] + [
            e.name for e in sections.get("multi_impact", ())]
        earlier = []
        for e in sections.get("switches", ()):
            if e is self:
                break
            earlier.append(e.name)
        if self.start not in branches + earlier:
            raise where.key("start").error(
                f"{self.start!r} is not a [[branches]] or [[multi_impact]] entry nor an earlier "
                "[[switches]] entry",
                ", ".join(branches + earlier) or "the name of a [[branches]] entry")
        if self.at == "BP" and self.start in {e.name for e in sections.get("branches", ())}:
            raise where.key("at").error(
                f"\"BP\" from the [[branches]] entry {self.start!r}: {NOT_SYMMETRIC}",
                "at = \"BP\" from a [[multi_impact]] or [[switches]] entry (N-p motions); "
                "\"PD\" or \"GR\" from a [[branches]] entry")
        start = _origin(self, sections)  # the [[branches]] entry the chain starts from
        lo, hi = self.bounds if self.bounds is not None else start.bounds
        admissible = PARAMETER_RANGES[start.parameter]
        if not (admissible.inside(lo) and admissible.inside(hi)):
            raise where.key("bounds").error(
                f"{show([lo, hi])} leaves the admissible values of {start.parameter} (the "
                f"parameter of branch {start.name!r})", admissible.allowed)
        library_check(where, make_options, (lo, hi), both_directions=False,
                      keys=("bounds", *CONTINUATION_KEYS), **self.continuation_options())


def _origin(entry: SwitchSpec, sections: Mapping[str, tuple[EntrySpec, ...]]) -> Any:
    """The ``[[branches]]`` or ``[[multi_impact]]`` entry a chain of switches starts from."""
    switches = {e.name: e for e in sections.get("switches", ())}
    branches = {e.name: e for e in (*sections.get("branches", ()),
                                    *sections.get("multi_impact", ()))}
    while entry.start in switches:
        entry = switches[entry.start]
    return branches[entry.start]


def origin_of(entry: Any, sections: Mapping[str, tuple[EntrySpec, ...]]
              ) -> tuple[Any, ImpactOscillator]:
    """The entry an N-p branch's chain starts from (a ``[[branches]]`` or ``[[multi_impact]]``
    entry; a ``[[multi_impact]]`` entry is its own) and the oscillator of its motions (a
    ``[[multi_impact]]`` entry's is its simulation's)."""
    origin = _origin(entry, sections) if entry.section == "switches" else entry
    if origin.section == "multi_impact":
        simulations = {e.name: e for e in sections.get("simulations", ())}
        return origin, simulations[origin.start].oscillator
    return origin, origin.oscillator


class Switches:
    """``[[switches]]``: :func:`~impactcont.period_doubling_switch`,
    :func:`~impactcont.grazing_switch` or
    :func:`~impactcont.analysis.switching.pitchfork_branch`."""

    def compute(self, entry: SwitchSpec, context: Any) -> xr.Dataset:
        t0 = time.perf_counter()
        computed = {**context.datasets.get("branches", {}),
                    **context.datasets.get("multi_impact", {}),
                    **context.datasets.get("switches", {})}
        if entry.start not in computed:
            raise ImpactcontError(f"switch {entry.name}: its start {entry.start!r} was not "
                                  f"computed (it failed)")
        kwargs: dict[str, Any] = {"bounds": entry.bounds, "detect": entry.detect,
                                  **entry.continuation_options()}
        if entry.epsilon is not None:
            kwargs["epsilon"] = entry.epsilon
        start = computed[entry.start]
        if entry.at == "PD":
            ds = period_doubling_switch(start, entry.which, **kwargs)
        elif entry.at == "BP":
            ds = pitchfork_branch(start, entry.which, 1 if entry.side is None else entry.side,
                                  **kwargs)
        else:
            ds = grazing_switch(start, entry.which, **kwargs)
            if ds is None:
                raise NoPeriodicMotionError(
                    f"switch {entry.name}: no motion with one more impact is born at GR point "
                    f"{entry.which} of {entry.start!r} (Newton fails there)")
        ds.attrs.update(name=entry.name, start=entry.start)
        log.info("switch %s: %s %d of %s -> N=%d with %d impacts, %d points, %d special "
                 "point(s) (%.1f s)", entry.name, entry.at, entry.which, entry.start,
                 int(ds.attrs["N"]), int(ds.attrs.get("impacts", 1)), ds.sizes["point"],
                 ds.sizes["special"], time.perf_counter() - t0)
        return ds

    def describe(self, datasets: Mapping[str, xr.Dataset]) -> list[str]:
        return BRANCHES.describe(datasets)

    def special_points(self, datasets: Mapping[str, xr.Dataset]) -> list[dict[str, Any]]:
        return BRANCHES.special_points(datasets)


SWITCHES = Switches()


@dataclasses.dataclass(frozen=True, kw_only=True)
class MultiImpactSpec(continuation_entry(multi_impact_continuation, "MultiImpactEntry")):
    """``[[multi_impact]]``: the branch of N-p motions through an attractor a simulation found."""

    section: ClassVar[str] = "multi_impact"

    start: str = declare(ENTRY_NAME, "the [[simulations]] entry whose last p + 1 impacts "
                         "seed Newton", required=True)
    N: int = declare(Integer(1, 1000), "forcing periods of the motion", required=True)
    p: int = declare(Integer(1, 1000), "impacts per motion", required=True)
    parameter: str = declare(PARAMETER_NAME, "the continued parameter (an element: \"k2\", "
                             "\"M[1,2]\", \"F[2]\", ...)", "omega")
    bounds: tuple[float, float] = declare(Interval(), "range of the parameter", required=True)
    detect: tuple[str, ...] = detect_key()

    def check(self, where: Where, osc: ImpactOscillator) -> None:
        super().check(where, osc)
        refuse_changes(self, where,
                       "the motion is found at the oscillator of the simulation it starts from")
        admissible = PARAMETER_RANGES[self.parameter]
        if not all(admissible.inside(v) for v in self.bounds):
            raise where.key("bounds").error(f"{list(self.bounds)} leaves the admissible values "
                                            f"of {self.parameter}", admissible.allowed)

    def check_scene(self, where: Where, sections: Mapping[str, tuple[EntrySpec, ...]]
                    ) -> None:
        simulations = {e.name: e for e in sections.get("simulations", ())}
        if self.start not in simulations:
            raise where.key("start").error(f"{self.start!r} is not a [[simulations]] entry",
                                           ", ".join(simulations) or "a [[simulations]] entry")
        osc = simulations[self.start].oscillator  # the motion is found at its oscillator
        library_check(where.key("parameter"), check_parameter, osc, self.parameter)
        library_check(where.key("parameter"), model_parameter, osc, self.parameter)  # m9, n=2
        library_check(where, make_options, self.bounds, keys=("bounds", *CONTINUATION_KEYS),
                      **self.continuation_options())
        # the stops bound the parameter (b > -b_low with a lower stop), as the run refuses
        library_check(where.key("bounds"), _check_stop_limits, osc, self.N, self.p,
                      self.parameter, self.bounds)
        # the drivers' bounds check on the oscillator (an entry of K keeps K PSD at both ends)
        library_check(where, _check_model_bounds, osc, self.parameter, self.bounds,
                      keys=("bounds",))
        value = model_parameter(osc, self.parameter).value(osc)  # an element, an extra stop's
        lo, hi = self.bounds
        if value is None or not lo <= value <= hi:
            raise where.key("bounds").error(
                f"{list(self.bounds)} does not contain {self.parameter} = {value!r} of "
                f"simulation {self.start!r}", f"bounds around {self.parameter} = {value!r}")


def _check_model_bounds(osc: ImpactOscillator, parameter: str, bounds: tuple[float, float]
                        ) -> None:
    """The check :func:`~impactcont.multi_impact_continuation` makes of bounds on the
    oscillator (:meth:`~impactcont.model.parameters.ModelParameter.check_bounds`)."""
    model_parameter(osc, parameter).check_bounds(osc, tuple(bounds))


def _check_stop_limits(osc: ImpactOscillator, N: int, p: int, parameter: str,
                       bounds: tuple[float, float]) -> None:
    """The check :func:`~impactcont.multi_impact_continuation` makes of bounds against the
    stops (with a lower stop, ``b`` must stay above ``-b_low``)."""
    MultiImpactBranchProblem(osc, N, p, parameter).check_bounds(bounds)


#: How far (in forcing periods) the impact N periods before a simulation's last one may lie
#: from exactly N periods: the p flight times of the seed must add up to the N periods of the
#: motion (the shooting system's condition), and a seed a quarter period off is no N-p motion.
SETTLED = 0.25


def _impacts_in_periods(times: np.ndarray, period: float, N: int) -> tuple[int, float]:
    """``(q, offset)``: the impact nearest ``N`` periods before the last is ``q`` impacts
    before it, ``offset`` periods further back than ``N`` (negative: nearer)."""
    back = (times[-1] - times[:-1]) / period
    i = int(np.argmin(np.abs(back - N)))
    return times.size - 1 - i, float(back[i] - N)


def simulation_seed(sim: xr.Dataset, entry: MultiImpactSpec, osc: ImpactOscillator
                    ) -> _SimulatedImpacts:
    """The Newton guess of an entry's N-p motion: the last p + 1 impacts of its simulation
    and its sticking phases (a motion whose plastic impacts start sticking phases is one
    with sticking phases, its pattern's letters lowercase there). The impacts of a chatter
    after its landing are left out (:func:`~impactcont.orbit.multi_impact.landing_impacts`):
    a sticking phase entered through complete chatter belongs to its landing.

    They seed an N-p motion only if the simulation shows one: p impacts in its last N
    forcing periods, the impact N periods before the last (to within :data:`SETTLED`
    periods) on the same stop as the last. The pattern of the motion is the stops of
    the impacts that start its p flights.

    Raises
    ------
    ParameterError
        The simulation shows another number of impacts in N periods, or no motion
        repeating after N periods, naming its impacts per N periods and their stops.
    """
    N, p = entry.N, entry.p
    what = f"multi_impact {entry.name}: N = {N}, p = {p}"
    times = np.asarray(sim["impact_times"].values, dtype=float)
    stops = str(sim.attrs.get("impact_stops", ""))  # which stop each impact hit
    sticking = tuple(_HeldPhase(float(start), float(end), str(held), str(ended))
                     for start, end, held, ended in zip(
                         *(np.asarray(sim[name].values) if name in sim else ()
                           for name in ("sticking_start", "sticking_end", "sticking_stops",
                                        "sticking_ended_by")), strict=True))
    phases = np.asarray(sim["impact_phases"].values, dtype=float)
    states = np.asarray(sim["impact_states"].values, dtype=float)
    if sticking and times.size:  # a chatter's impacts after its landing are its segment's
        kept = landing_impacts(_SimulatedImpacts(times, phases, states, stops, sticking))[0]
        times, phases, states = times[kept], phases[kept], states[kept]
        stops = "".join(stops[i] for i in kept) if stops else stops
    k = times.size
    if k < p + 1:
        raise NoPeriodicMotionError(f"{what}: simulation {entry.start!r} recorded {k} impacts; "
                                    f"at least p + 1 = {p + 1} are needed")
    period = 2.0 * np.pi / osc.omega
    span = (times[-1] - times[0]) / period
    if span < N - SETTLED:
        raise ParameterError(f"{what}: the {k} impacts of simulation {entry.start!r} span "
                             f"{span:.3g} forcing periods, fewer than N = {N}; allowed: a "
                             "simulation with more periods, or a smaller N")
    q, offset = _impacts_in_periods(times, period, N)
    shown = f"{q} impact(s) in its last N = {N} forcing period(s)" + (
        f" (stops {stops[-q:]!r})" if stops else "")
    if abs(offset) > SETTLED:
        raise ParameterError(
            f"{what}: simulation {entry.start!r} shows {shown}, and no impact N periods before "
            f"its last one (the nearest is {offset:+.3g} periods off): it has not settled on a "
            f"motion that repeats after N = {N} periods; allowed: the N of the motion it "
            "settled on (impactcont info shows its last stops), or a longer simulation")
    if stops and stops[-(q + 1)] != stops[-1]:
        raise ParameterError(
            f"{what}: simulation {entry.start!r} shows {shown}; the impact N periods before "
            f"its last one hit the {'upper' if stops[-(q + 1)] == 'U' else 'lower'} stop and "
            "the last the other: it has not settled on a motion that repeats after N = "
            f"{N} periods; allowed: the N of the motion it settled on, or a longer simulation")
    if q != p:
        raise ParameterError(f"{what}: simulation {entry.start!r} shows {shown}, not p = {p}; "
                             f"allowed: p = {q} with N = {N}")
    return _SimulatedImpacts(
        impact_times=times[-(p + 1):], impact_phases=phases[-(p + 1):],
        impact_states=states[-(p + 1):], impact_stops=stops[-(p + 1):], sticking=sticking)


class _HeldPhase(NamedTuple):
    """A sticking phase of a simulation file, as :func:`~impactcont.multi_impact_orbit`
    reads one of :attr:`impactcont.simulate.SimulationResult.sticking`."""

    start: float
    end: float
    stops: str
    ended_by: str


class _SimulatedImpacts(NamedTuple):
    """The last p + 1 impacts of a simulation file and its sticking phases: a guess that
    :func:`~impactcont.multi_impact_orbit` reads as it reads a
    :class:`~impactcont.simulate.SimulationResult` (a sticking phase that follows an impact
    makes that impact's letter lowercase: a motion with sticking phases)."""

    impact_times: np.ndarray
    impact_phases: np.ndarray
    impact_states: np.ndarray
    impact_stops: str
    sticking: tuple[_HeldPhase, ...]


class MultiImpact:
    """``[[multi_impact]]``: :func:`~impactcont.multi_impact_orbit` from a simulation, then
    :func:`~impactcont.multi_impact_continuation`."""

    def compute(self, entry: MultiImpactSpec, context: Any) -> xr.Dataset:
        t0 = time.perf_counter()
        sim = context.datasets.get("simulations", {}).get(entry.start)
        if sim is None:
            raise ImpactcontError(f"multi_impact {entry.name}: its start {entry.start!r} was "
                                  f"not computed (it failed)")
        p = entry.p
        osc = ImpactOscillator.from_json(sim.attrs["oscillator"])
        orbit = multi_impact_orbit(osc, entry.N, p, simulation_seed(sim, entry, osc))
        ds = multi_impact_continuation(orbit, entry.parameter, entry.bounds,
                                       detect=entry.detect, **entry.continuation_options())
        ds.attrs.update(name=entry.name, start=entry.start)
        log.info("multi_impact %s: %d-%d motion from simulation %s (%s, %s), %d points, %d "
                 "special point(s) (%.1f s)", entry.name, entry.N, p, entry.start,
                 "physical" if orbit.physical else "not physical",
                 "stable" if orbit.stable else "unstable", ds.sizes["point"],
                 ds.sizes["special"], time.perf_counter() - t0)
        return ds

    def describe(self, datasets: Mapping[str, xr.Dataset]) -> list[str]:
        """The branches table, then each branch's motion: N, p and the stop of each impact."""
        rows = [[name, int(ds.attrs["N"]), impacts_of(ds), pattern_of(ds)]
                for name, ds in datasets.items()]
        return [*BRANCHES.describe(datasets), "",
                *markdown_table(["branch", "N", "p", "pattern (U upper, L lower stop)"], rows)]

    special_points = Switches.special_points


MULTI_IMPACT = MultiImpact()
