"""No simulated motion crosses a stop (issue 28, 1.2): a property over random small machines.

A seeded loop over a few dozen random machines of one to three masses: stops fixed to the
frame and clearances between masses, lower and mirrored stops, extra stops on a mass or a
pair, restitutions 0 (plastic), 1 (elastic) and in between, free masses held by a stop, a
constant force. Each is simulated from a state inside every stop; on the returned
trajectory, at every impact state and at the final state, every stop coordinate stays on its
side of every stop, within a rounding allowance relative to the motion's size. (A plastic
impact on a clearance between masses used to pass through the wall: ``x2 - x1`` climbed to
29.5 past ``b = 1``.)
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError

N_MACHINES = 40
# rounding allowance past a stop, relative to the size of the motion (the largest stop
# coordinate, displacement or stop position seen)
RTOL = 1e-9


def _restitution(rng: np.random.Generator) -> float:
    return float(rng.choice([0.0, 1.0, rng.uniform(0.2, 0.9)]))


def _machine(rng: np.random.Generator) -> ic.ImpactOscillator:
    """A random machine; each of its stops lies on the far side of 0 from where it is met,
    so ``x = 0`` is inside every stop."""
    n = int(rng.choice([1, 2, 2, 3]))
    masses = rng.uniform(0.2, 2.0, n)
    springs = rng.uniform(0.5, 3.0, n)
    mass = int(rng.integers(1, n + 1))
    others = [k for k in range(1, n + 1) if k != mass]
    relative_to = int(rng.choice(others)) if others and rng.random() < 0.6 else None
    if rng.random() < 0.5:  # free masses (held by the stops, or refused by the oscillator)
        springs[rng.random(n) < 0.5] = 0.0
    stops: dict = {"mass": mass, "relative_to": relative_to}
    kind = rng.choice(["one", "low", "mirror"])
    if kind == "low":
        stops.update(b_low=float(rng.uniform(0.1, 1.0)), R_low=_restitution(rng))
    elif kind == "mirror":
        stops["mirror"] = True
    extra = []
    for name in "AB"[: int(rng.integers(0, 3))]:
        j = int(rng.integers(1, n + 1))
        k = rng.choice([0, *[i for i in range(1, n + 1) if i != j]])
        extra.append(ic.Stop(name, mass=j, relative_to=int(k) or None,
                             gap=float(rng.uniform(0.1, 1.0)), side=int(rng.choice([1, -1])),
                             restitution=_restitution(rng)))
    F = np.where(rng.random(n) < 0.5, 0.0, rng.uniform(-1.0, 1.0, n))  # unforced masses too
    F[0] = 1.0
    F_static = rng.uniform(-0.3, 0.3, n) if rng.random() < 0.3 else None
    damping = {"eta": float(rng.uniform(0.0, 0.1))} if rng.random() < 0.6 else {
        "C": float(rng.uniform(0.0, 0.2)) * np.diag(rng.uniform(0.5, 1.0, n))}
    return ic.ImpactOscillator.chain(
        masses=masses, springs=springs, F=F, R=_restitution(rng), b=float(rng.uniform(0.1, 1.0)),
        omega=float(rng.uniform(0.4, 3.0)), stops=ic.Stops(**stops, extra=tuple(extra)),
        F_static=F_static, **damping)


@functools.cache
def _machines() -> tuple[ic.ImpactOscillator]:
    rng = np.random.default_rng(28)
    out: list[ic.ImpactOscillator] = []
    while len(out) < N_MACHINES:
        try:
            out.append(_machine(rng))
        except ParameterError:  # a free mode no stop holds, stops that shadow each other...
            continue
    return tuple(out)


@pytest.mark.parametrize("k", range(N_MACHINES))
def test_every_stop_coordinate_stays_on_its_side(k):
    osc = _machines()[k]
    rng = np.random.default_rng(1000 + k)
    n = osc.n
    X0 = np.concatenate([np.zeros(n), rng.uniform(-2.0, 2.0, n)])
    res = ic.simulate(osc, X0, float(rng.uniform(-3, 3)), 6.0, trajectory=True,
                      max_impacts=400)
    X = np.vstack([res.X, res.impact_states.reshape(-1, 2 * n), res.final_state])[:, :n]
    for name in osc.stops.names:
        view = osc.stops.stop(name, osc.M, osc.b, osc.R)
        s = X @ view.normal
        size = max(1.0, float(np.max(np.abs(X))), abs(view.position))
        past = float(np.max(view.sign * (s - view.position)))
        assert past <= RTOL * size, (
            f"machine {k}: stop {name!r} at {view.normal.tolist()} . x = {view.position} "
            f"crossed by {past:.3g} ({res.status.name}, {res.impact_stops!r}, {osc!r})")
