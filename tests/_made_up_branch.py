"""A made-up but consistent branch dataset (no continuation run): the columns, special
points and fixtures the tests of the dataset schema, its files and its figures share."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from impactcont import ImpactOscillator
from impactcont.dataset import branch_dataset

__all__ = ["NPOINTS", "N_DOF", "_columns", "_radius", "_special", "_specials", "branch", "osc"]

NPOINTS = 50


N_DOF = 2


@pytest.fixture
def osc() -> ImpactOscillator:
    return ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.0,
                            omega=1.0, eta=0.1)


def _radius() -> np.ndarray:
    """Spectral radius with runs: stable 0-19, unstable 20-34, (non-physical 35-44), stable."""
    r = np.empty(NPOINTS)
    r[:20] = np.linspace(0.4, 0.95, 20)
    r[20:35] = np.linspace(1.05, 1.3, 15)
    r[35:45] = 1.1
    r[45:] = np.linspace(0.9, 0.6, 5)
    return r


def _columns(n: int = N_DOF, npoints: int = NPOINTS) -> dict[str, np.ndarray]:
    """Made-up but consistent columns of a branch in omega."""
    p = np.arange(npoints)
    omega = np.linspace(0.8, 2.0, npoints)
    r = _radius()[:npoints]
    mult = np.empty((npoints, 2 * n), dtype=complex)
    mult[:, 0] = r * np.exp(0.4j)
    mult[:, 1] = r * np.exp(-0.4j)
    mult[:, 2:] = 0.05 * np.linspace(1.0, -1.0, 2 * n - 2)
    physical = np.ones(npoints, dtype=bool)
    physical[35:45] = False
    state = np.zeros((npoints, 2 * n))
    state[:, 0] = 0.0  # x1 = b right after impact
    state[:, 1:] = np.sin(p[:, None] * 0.1 + np.arange(1, 2 * n))
    return {
        "omega": omega,
        "b": np.zeros(npoints),
        "delta": np.linspace(-3.0, 3.0, npoints),
        "impact_velocity": 1.0 + 0.5 * np.sin(omega),
        "gap_min": np.where(physical, 0.2, -0.1),
        "spectral_radius": np.abs(mult).max(axis=1),
        "stable": np.abs(mult).max(axis=1) < 1.0,
        "physical": physical,
        "arclength": np.cumsum(np.full(npoints, 0.03)),
        "multipliers": mult,
        "state": state,
    }


def _special(label: str, point: int, columns: dict[str, np.ndarray], status: str = "located"
             ) -> dict:
    omega = columns["omega"]
    return {
        "label": label,
        "omega": 0.5 * (omega[point - 1] + omega[point]),
        "b": 0.0,
        "delta": float(columns["delta"][point]),
        "point": point,
        "bracket_lo": float(omega[point - 1]),
        "bracket_hi": float(omega[point]),
        "precision": 1e-9 if status == "located" else float(omega[point] - omega[point - 1]),
        "status": status,
        "multipliers": columns["multipliers"][point],
    }


def _specials(columns: dict[str, np.ndarray]) -> list[dict]:
    return [_special("NS", 20, columns), _special("GR", 35, columns, "bracketed"),
            _special("ZV", 45, columns)]


@pytest.fixture
def branch(osc) -> xr.Dataset:
    cols = _columns()
    return branch_dataset(parameter="omega", N=1, oscillator=osc,
                          options={"ds": 0.03, "max_steps": 50, "tol": np.float64(1e-10)},
                          columns=cols, special_points=_specials(cols))
