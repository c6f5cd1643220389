"""The cost of a stability map of a motion with sticking phases against a plain one.

The impact damper of ``studies/sticking_motions`` (case (c), ``eta = 0.3``): its ball
riding each wall (``"lu"``, R = 0, seed omega 1.2, b 0.3) against the same machine's
``"UL"`` motion at R = 0.6 (seed omega 2.5, b 0.3), the same two impacts per period, each
mapped over a 41 x 41 grid of (b, omega) around its seed (b in [0.28, 0.32], omega
+-0.1), serially (one task: ``rows_per_task`` 41); the whole ``ic.stability_map`` call,
the best of 3 rounds after a warm-up run of each (the compiled kernels)::

    python studies/performance/sticky_maps.py

Prints, for each map, the grid points per second, the points found and the ratio of its
time to the plain map's. The sticky map is swept in Python over the compiled Newton of
its branch problem (``MultiImpactBranchProblem.palc_step`` on the hyperplane of each omega)
and evaluates each motion found by the problem's ``orbit`` (its G, sticking phases and
contact search: most of its time, the third line, ``checks=False``, shows how much is the
contact search); the plain map is one compiled sweep (``kernel.sweep.sweep_stops``).

Measured 2026-12-07 (two cores shared with other jobs, so each figure within a factor of
about 1.5), two runs: at load 8, sticky 194 points/s (8.6 s for 41 x 41, all found),
plain 15442 points/s (0.11 s), 79x; at load 5-6, sticky 243 points/s (6.9 s), plain
30116 (0.06 s), 124x. ``checks=False``: 154 and 275 points/s (no faster within the
noise: the contact search is not what costs). A profile of the sticky
map (48 points, warm) puts about two thirds of its time in the problem's ``orbit`` (the
sticking phases' checks and G, in Python) and a quarter in the compiled Newton and the
flows at each omega: a compiled sticky sweep (Newton and evaluation in one kernel, as
``kernel.sweep`` does for plain motions) is what would close the gap.
"""

from __future__ import annotations

import os
import time

import numpy as np

import impactcont as ic
from impactcont.model.stops import Stops

POINTS = 41


def damper(omega: float, R: float) -> ic.ImpactOscillator:
    """Case (c): primary 1 on spring 1 (eta 0.3), ball 0.2 in |x2 - x1| <= 0.3."""
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               R=R, b=0.3, omega=omega, eta=0.3,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def riding_start(osc: ic.ImpactOscillator) -> np.ndarray:
    """The ball on the upper wall, the pair on the held system's forced response."""
    m, c, omega = osc.M[1, 1], osc.C[0, 0], osc.omega
    amplitude = 1.0 / (1.0 - (1.0 + m) * omega**2 + 1j * c * omega)
    x1, v1 = amplitude.real, (1j * omega * amplitude).real
    return np.array([x1, x1 + osc.b, v1, v1])


def starts() -> dict[str, ic.MultiImpactOrbit]:
    """The sticky and the plain motion, each from its simulated steady state."""
    sticky = damper(1.2, 0.0)
    plain = damper(2.5, 0.6)
    return {
        "sticky 'lu' (R 0)": ic.multi_impact_orbit(
            sticky, 1, 2, ic.simulate(sticky, riding_start(sticky), 0.0, 16.0)),
        "plain 'UL' (R 0.6)": ic.multi_impact_orbit(
            plain, 1, 2, ic.simulate(plain, np.array([0.0, 0.3, 0.0, 0.0]), 0.0, 150.0),
            pattern="UL"),
    }


def one_map(start: ic.MultiImpactOrbit, points: int, **options) -> tuple[float, int]:
    """Seconds of the map around `start` on a `points` x `points` grid, and points found."""
    omega = start.oscillator.omega
    grid = {"b": np.linspace(0.28, 0.32, points),
            "omega": np.linspace(omega - 0.1, omega + 0.1, points)}
    begin = time.perf_counter()
    ds = ic.stability_map(start, parameters=("b", "omega"), grid=grid, progress=False,
                          rows_per_task=points, **options)
    return time.perf_counter() - begin, int(ds["found"].sum())


def main(rounds: int = 3) -> None:
    motions = starts()
    runs = [(name, start, {}) for name, start in motions.items()]
    runs.append(("sticky 'lu', checks=False", motions["sticky 'lu' (R 0)"],
                 {"checks": False}))
    for name, start, options in runs:
        assert start.physical, (name, start.reason)
        one_map(start, 5, **options)  # warm: the compiled kernels
    best: dict[str, tuple[float, int]] = {}
    for _ in range(rounds):
        for name, start, options in runs:
            seconds, found = one_map(start, POINTS, **options)
            best[name] = min(best.get(name, (np.inf, 0)), (seconds, found))
    plain = best["plain 'UL' (R 0.6)"][0]
    total = POINTS * POINTS
    for name, (seconds, found) in best.items():
        print(f"{name}: {total / seconds:.0f} points/s ({seconds:.2f} s for {POINTS}x{POINTS},"
              f" {found} found), {seconds / plain:.1f}x the plain map")
    print(f"load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
