"""Event-driven simulation with the exact flow."""

from impactcont.simulate.simulator import (
    SimulationResult,
    SimulationStatus,
    next_impact,
    simulate,
)

__all__ = ["SimulationResult", "SimulationStatus", "next_impact", "simulate"]
