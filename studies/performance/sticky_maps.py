"""The cost of a stability map of a motion with sticking phases against a plain one.

The impact damper of ``studies/sticking_motions`` (case (c), ``eta = 0.3``): its ball
riding each wall (``"lu"``, R = 0, seed omega 1.2, b 0.3) against the same machine's
``"UL"`` motion at R = 0.6 (seed omega 2.5, b 0.3), the same two impacts per period, each
mapped over a 41 x 41 grid of (b, omega) around its seed (b in [0.28, 0.32], omega
+-0.1), serially (one task: ``rows_per_task`` 41); the whole ``ic.stability_map`` call,
the best of 3 rounds after a warm-up run of each (the compiled kernels)::

    python studies/performance/sticky_maps.py

Prints, for each map, the grid points per second, the points found and the ratio of its
time to the plain map's. The motions are those of ``studies/sticking_motions/
branch_cost.py`` (imported from it: one builder). The sticky map is swept in Python:
at each grid point the compiled Newton of ``multi_impact_orbit``
(``orbit.sticky.sticky_newton``) on the flow of the branch problem of its b at that omega,
and the motion evaluated from that Newton's shot
(``orbit.sticky.sticky_orbit_from_unknowns``: G, the sticking phases' checks, the contact
search; the third line, ``checks=False``, shows how much is the contact search); the
plain map is one compiled sweep (``kernel.sweep.sweep_stops``).

Measured 2026-12-07 (two cores shared with other jobs, so each figure within a factor of
about 1.5). Before (6d886d3, the Newton of the branch problem's compiled ``palc_step`` on
the hyperplane of each omega, then the problem's ``orbit`` from a second shot): at load 8,
sticky 194 points/s, plain 15442 (79x); at load 5-6, 243 against 30116 (124x). After
(f98fc57), interleaved with a ``git archive`` of 76f5528, twice, best of 3 each: before
405 and 361 points/s against plain 35583 and 28775 (88x, 80x; load 4.5-5.0), after 326
and 277 against 39809 and 35909 (122x, 130x; load 4.8-5.7). The after tree also holds
the other stops' clearance along each stick (544b9a3, 921be33) and the other changes of
orbit/ between the two commits; this module's change alone (HEAD's ``family_maps`` against
the new one on the same tree, one process, interleaved, best of 3, load 9.3): 133 against
143 points/s (1.07x), ``checks=False`` 212 against 194 (noise). **Not** a few times a
plain point: about 100x. What sets the floor (the new sweep, per point at load 9, best
of 180 calls): the compiled Newton 0.08 ms; the flow at the new omega with its held
systems (``MultiImpactBranchProblem.flow_at``) 0.5 ms and their ``held_segments`` rebuilt
from the held flows 1.4 ms; the motion's evaluation 2.7 ms, of which the sticking phases'
checks (``orbit.sticky._sticks``: pressing minimum, other stops along the stick, chatter
bounces, each stop's restitution through ``Stops.stop`` several times) 2.0 ms and G
(``sticky_jacobians``) 0.14 ms; a plain point is 0.03-0.07 ms all told. Only a compiled
sticky sweep (the held segments' amplitudes at each omega, the stick checks and G in the
kernel, as ``kernel.sweep`` does for plain motions) would close it; the modules it needs
(``kernel/``, ``orbit/sticky.py``) were not this change's.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

import impactcont as ic

# the two motions as the branch cost of studies/sticking_motions builds them (one builder)
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "sticking_motions"))
from branch_cost import starts

POINTS = 41


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
