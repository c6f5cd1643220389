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
