"""Event-driven simulation with the exact flow, through sticking phases and chatter."""

from impactcont.simulate.chatter import ChatterPoint
from impactcont.simulate.simulator import (
    SimulationResult,
    SimulationStatus,
    next_impact,
    simulate,
)
from impactcont.simulate.sticking import StickingPhase

__all__ = ["ChatterPoint", "SimulationResult", "SimulationStatus", "StickingPhase",
           "next_impact", "simulate"]
