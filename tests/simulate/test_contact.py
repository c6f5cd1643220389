"""The contact search of a stop between two masses takes its time scales from the stop
coordinate ``s = x2 - x1`` (weights ``n^T U``, ``n^T V_x``), not from mass 2's row.

The machine: mass 1 on its own stiff spring (``w1 = 50``, lightly damped), masses 2 and 3
a slow chain (``w = 1, sqrt 3``) forced at ``omega = 1``, a clearance ``x2 - x1 <= b``
between masses 2 and 1. Mass 2 does not see the fast mode; ``s`` does, as a ripple of
amplitude ``A1`` on the slow rise of ``x2``. With ``b`` a little below the top of that
rise plus ``A1``, ``s`` first passes the stop in a short excursion at a trough of ``x1``,
shorter than a cell of the grid mass 2's time scales give (``2 pi / (16 sqrt 3)``). The
event-driven simulator must find that impact, as a dense sampling of the exact flow
(``Flow.state`` on 1e5 points) does; a search on mass 2's scales missed it (at 5 of the 8
starting phases of the ripple, on both flows) and reported a later impact or none.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.stops import Stops
from impactcont.orbit.flow import Flow
from impactcont.simulate.contact import flight_clearances, search_window

W1 = 50.0  # the fast mode: mass 1 alone
W_SLOW = math.sqrt(3.0)  # the fastest mode mass 2 sees
A1 = 0.05  # amplitude of mass 1's ripple
K = np.array([[W1**2, 0.0, 0.0], [0.0, 2.0, -1.0], [0.0, -1.0, 2.0]])
DAMPING = {
    "modal": {"alpha": 0.002, "beta": 0.0},  # mass-proportional: the fast mode rings on
    "first-order": {"C": [[0.002, 0.0, 0.0], [0.0, 0.03, -0.01], [0.0, -0.01, 0.02]]},
}
T_SEARCH = 2.0 * math.pi  # one forcing period
DENSE = np.linspace(0.0, T_SEARCH, 100_001)
NORMAL = np.array([-1.0, 1.0, 0.0])


def _pair(damping: str, b: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(3), K=K, F=[0.0, 1.0, 0.0], R=0.7, b=b, omega=1.0,
                               stops=Stops(mass=2, relative_to=1), **DAMPING[damping])


def _machine(damping: str) -> ic.ImpactOscillator:
    """The stop 0.9 A1 above the top of x2's rise from rest: s passes it by < 0.1 A1."""
    x2 = Flow(_pair(damping, 10.0)).state(DENSE, np.zeros(6), 0.0)[:, 1]
    return _pair(damping, float(x2.max()) + 0.9 * A1)


def _start(phase: float) -> np.ndarray:
    """Masses 2, 3 at rest, mass 1 ringing at amplitude A1 from the given phase."""
    return np.array([A1 * math.cos(phase), 0.0, 0.0, -A1 * W1 * math.sin(phase), 0.0, 0.0])


@pytest.mark.parametrize("damping", list(DAMPING))
def test_the_fast_mode_is_seen_by_the_pair_not_by_mass_2(damping):
    flow = Flow(_machine(damping))
    shapes = flow.u if damping == "modal" else flow.V[:3]
    fast = int(np.argmax(np.abs(shapes[0])))
    assert abs(shapes[1, fast]) <= 1e-15 and abs(NORMAL @ shapes[:, fast]) > 1e-3
    rate, _ = flow.time_scales(normal=NORMAL)
    assert rate == pytest.approx(W1, rel=1e-6)
    # the windows follow the pair's scale: a few fast periods, not a few slow ones
    first, longest = search_window(flow, normal=NORMAL)
    assert first == pytest.approx(2 * 2 * math.pi / rate, rel=1e-12)
    assert longest == pytest.approx(T_SEARCH, rel=1e-12)


@pytest.mark.parametrize("damping", list(DAMPING))
def test_the_simulator_finds_the_short_excursion_dense_sampling_finds(damping):
    osc = _machine(damping)
    flow = Flow(osc)
    for phase in np.linspace(0.0, 2.0 * math.pi, 8, endpoint=False):
        X0 = _start(phase)
        s = flow.state(DENSE, X0, 0.0)[:, :3] @ NORMAL - osc.b
        above = np.flatnonzero(s >= 0.0)
        assert above.size, "the construction puts an excursion past the stop in every flight"
        i = int(above[0])
        run = np.flatnonzero(s[i:] < 0.0)
        excursion = DENSE[i + int(run[0])] - DENSE[i - 1]
        assert excursion < 2.0 * math.pi / (16 * W_SLOW)  # shorter than a mass-2 grid cell
        res = ic.simulate(osc, X0, 0.0, 1.0, max_impacts=1)
        assert res.impact_times.size == 1, f"phase {phase:.3f}: impact at s = b missed"
        tc = float(res.impact_times[0])
        assert DENSE[i - 1] - 1e-9 <= tc <= DENSE[i] + 1e-9, (
            f"phase {phase:.3f}: impact at t = {tc:.6f}, the flow first reaches the stop in "
            f"[{DENSE[i - 1]:.6f}, {DENSE[i]:.6f}]")
        s_hit = float(flow.state(tc, X0, 0.0)[0, :3] @ NORMAL)
        assert s_hit == pytest.approx(osc.b, abs=1e-9)


@pytest.mark.parametrize("damping", list(DAMPING))
def test_interior_check_sees_the_excursion(damping):
    """flight_clearances (eq. 16 on the simulator's side) on a flight cut just before the
    impact the dense sampling sees: the highest interior maximum of s is past the stop."""
    osc = _machine(damping)
    flow = Flow(osc)
    X0 = _start(0.0)
    s = flow.state(DENSE, X0, 0.0)[:, :3] @ NORMAL
    top = int(np.argmax(s[: np.flatnonzero(s >= osc.b)[0] + 2000]))
    gap_u, t_u, _, _ = flight_clearances(flow, X0, 0.0, DENSE[top] + 0.01)
    assert gap_u < 0.0 and gap_u == pytest.approx(osc.b - s[top], abs=2e-7)
    assert t_u == pytest.approx(DENSE[top], abs=1e-4)
