"""The dataset of a simulation: impacts, sticking phases with their contact forces, the
accumulation points of complete chatter and the sampled trajectory.

One builder serves :func:`impactcont.save` (a :class:`~impactcont.SimulationResult` is
written as this dataset) and a scene's ``[[simulations]]`` section (``simulations.nc``).
The variables are those of :meth:`impactcont.SimulationResult.sticking_arrays` and the
result's impact arrays; ``impactcont_dataset = "simulation"``.
"""

from __future__ import annotations

import math
from typing import Any

import xarray as xr

from impactcont.dataset.schema import state_component_names
from impactcont.errors import ParameterError
from impactcont.simulate.simulator import SimulationResult

__all__ = ["simulation_dataset"]


#: Each data variable: its dimensions, long name and description (units "1" but
#: ``impact_phases``'s). The sticking, force-sample and chatter variables are the arrays of
#: :meth:`impactcont.SimulationResult.sticking_arrays` (``contact_force`` is its ``force``).
_VARIABLES: dict[str, tuple[tuple[str, ...], str, str]] = {
    "impact_times": (("impact",), "impact time", "Time of each impact since the start."),
    "impact_velocities": (("impact",), "impact velocity",
                          "Speed of the impacting mass towards the stop hit just before "
                          "each impact: x_j' at the upper stop, -x_j' at the lower "
                          "(impact_stops)."),
    "impact_phases": (("impact",), "impact phase",
                      "Forcing phase at each impact, in (-pi, pi]."),
    "impact_states": (("impact", "component"), "state after impact",
                      "State right after each impact."),
    "start_state": (("component",), "start state", "State at t = 0 (perturbation included)."),
    "sticking_start": (("sticking",), "sticking start", "Time a sticking phase starts."),
    "sticking_end": (("sticking",), "sticking end",
                     "Time it ends (a release, an impact on another stop, another stop "
                     "holding, or the end of the run)."),
    "sticking_stops": (("sticking",), "stops held", "The stops held in the phase (their names)."),
    "sticking_ended_by": (("sticking",), "ended by", "release, impact, stick, chatter or end."),
    "force_time": (("force_sample",), "force sample time",
                   "Times of the contact-force samples of the sticking phases."),
    "contact_force": (("force_sample",), "contact force",
                      "Pressing force of a held stop (>= 0; zero at a release)."),
    "force_phase": (("force_sample",), "sticking phase",
                    "Index of the sticking phase of each force sample."),
    "force_stop": (("force_sample",), "stop pressed",
                   "The held stop each force sample belongs to."),
    "chatter_time": (("chatter",), "accumulation time",
                     "Accumulation point of a complete chatter (a sticking phase starts "
                     "there)."),
    "chatter_stop": (("chatter",), "chatter stop", "The stop chattered on."),
    "chatter_last_impact": (("chatter",), "last impact resolved",
                            "Time of the last impact resolved before the accumulation "
                            "point."),
    "chatter_last_velocity": (("chatter",), "last impact velocity",
                              "Its impact velocity (the jump's error is of its square)."),
    "t": (("sample",), "time", "Trajectory sample times."),
    "X": (("sample", "component"), "state", "Sampled state (both sides of each impact)."),
}
_UNITS = {"impact_phases": "rad"}


def _var(dims: tuple[str, ...], data: Any, long_name: str, description: str,
         units: str = "1") -> xr.Variable:
    return xr.Variable(dims, data, attrs={"long_name": long_name, "units": units,
                                          "description": description})


def simulation_dataset(result: SimulationResult, *, name: str = "simulation",
                       start: str = "state", perturbation: float = 0.0) -> xr.Dataset:
    """The dataset of one simulation (eq. 1-4 integrated through its impacts, sticking
    phases and accumulation points).

    Parameters
    ----------
    result : SimulationResult
        From :func:`impactcont.simulate` (it records its oscillator, start state, start
        phase and the forcing periods asked for).
    name : str
        The dataset's ``name`` (a scene entry's name).
    start : str
        Where the start state came from (``"state"``, or the motion it was taken from).
    perturbation : float
        The velocity perturbation added to that state (a scene entry's), recorded only.

    Returns
    -------
    xarray.Dataset
        On ``impact``: ``impact_times``, ``impact_velocities``, ``impact_phases``,
        ``impact_states`` (with ``component``); on ``sticking``: ``sticking_start``,
        ``sticking_end``, ``sticking_stops``, ``sticking_ended_by``; on ``force_sample``:
        ``force_time``, ``contact_force``, ``force_phase``, ``force_stop``; on
        ``chatter``: ``chatter_time``, ``chatter_stop``, ``chatter_last_impact``,
        ``chatter_last_velocity``; ``start_state``; with a trajectory ``t`` and ``X`` on
        ``sample``. Scalar coordinates ``omega`` and ``b``; attributes ``oscillator``
        (JSON), ``status``, ``message``, ``final_time``, ``periods``, ``start``,
        ``start_delta``, ``impact_stops``.

    Raises
    ------
    ParameterError
        `result` is not a SimulationResult, or one made without its oscillator.
    """
    if not isinstance(result, SimulationResult):
        raise ParameterError(f"result must be a SimulationResult of impactcont.simulate; "
                             f"got {type(result).__name__}")
    osc = result.oscillator
    if osc is None or result.start_state is None:
        raise ParameterError("result does not record its oscillator and start state (a "
                             "SimulationResult made by hand): simulate it with "
                             "impactcont.simulate")
    n = osc.n
    events = result.sticking_arrays()
    values = {"impact_times": result.impact_times,
              "impact_velocities": result.impact_velocities,
              "impact_phases": result.impact_phases,
              "impact_states": result.impact_states.reshape(-1, 2 * n),
              "start_state": result.start_state,
              **{k: v for k, v in events.items() if k != "force"},
              "contact_force": events["force"],
              "t": result.t, "X": result.X}  # None: no trajectory recorded
    data = {var: _var(dims, values[var], long_name, description, _UNITS.get(var, "1"))
            for var, (dims, long_name, description) in _VARIABLES.items()
            if values[var] is not None}
    coords = {"component": state_component_names(n),
              "omega": _var((), osc.omega, "forcing frequency",
                            "Nondimensional forcing frequency omega of eq. (1)."),
              "b": _var((), osc.b, "gap", "Position b of the stop met by mass 1 (eq. 3).")}
    periods = result.periods if math.isfinite(result.periods) else (
        result.final_time * osc.omega / (2.0 * math.pi))
    return xr.Dataset(data, coords=coords, attrs={
        "title": f"Simulation {name}", "name": name, "impactcont_dataset": "simulation",
        "start": start, "start_delta": float(result.start_phase), "periods": float(periods),
        "perturbation": float(perturbation), "status": result.status.name,
        "message": result.message, "final_time": float(result.final_time),
        "oscillator": osc.to_json(), "impact_stops": result.impact_stops})

