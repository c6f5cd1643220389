"""The cost of a branch point of a motion with sticking phases against a plain one.

The impact damper of case (c) (``eta = 0.3``): its ball riding each wall (``"lu"``, R = 0,
omega 1.2) against the same machine's ``"UL"`` motion at R = 0.6 (omega 2.5), each followed
in omega over +-0.2 with ``ds_max = 0.02``; the whole ``ic.continuation`` call divided by
its points, without and with the default special-point detection, in one process, the two
interleaved, the best of 5 rounds after a warm-up run of each::

    python studies/sticking_motions/branch_cost.py

Prints one line per detection setting: ms per point of each and its ratio to the plain
one. The sticky branch's ``dF/domega`` is exact
(:func:`impactcont.orbit.sticky.sticky_omega_column`) and its corrector step
compiled (:func:`impactcont.orbit.sticky.sticky_palc_step`). With ``--before`` the
route before these is timed in the same rounds too: ``dF/domega`` the parameter's central
difference and the continuation core's corrector (patched in for its run only)::

    python studies/sticking_motions/branch_cost.py --before

Measured with both routes patched in before they were wired (two runs, load 1.7-1.8): no
detection, central difference and core corrector 6.33-6.60 ms per point (9.0-9.5x plain),
exact column 3.51-3.67 (5.0-5.3x), exact column and compiled corrector 1.75-1.77 (2.5x),
plain 0.70; default detection 6.51-6.57 (6.4-6.8x), 3.67-3.70 (3.6-3.8x), 1.96-2.01
(2.0-2.1x), plain 0.96-1.02.
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from collections.abc import Iterator

import numpy as np

import impactcont as ic
from impactcont.model.stops import Stops
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem


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
    """The sticky and the plain motion, each from its simulated steady state (also the
    motions of ``studies/performance/sticky_maps.py``)."""
    sticky = damper(1.2, 0.0)
    plain = damper(2.5, 0.6)
    return {
        "sticky 'lu' (R 0)": ic.multi_impact_orbit(
            sticky, 1, 2, ic.simulate(sticky, riding_start(sticky), 0.0, 16.0)),
        "plain 'UL' (R 0.6)": ic.multi_impact_orbit(
            plain, 1, 2, ic.simulate(plain, np.array([0.0, 0.3, 0.0, 0.0]), 0.0, 150.0),
            pattern="UL"),
    }


def per_point(start: ic.MultiImpactOrbit, detect) -> tuple[float, int]:
    """Seconds per point of the branch through `start` and its number of points."""
    omega = start.oscillator.omega
    begin = time.perf_counter()
    ds = ic.continuation(start, parameter="omega", bounds=(omega - 0.2, omega + 0.2),
                         ds_max=0.02, detect=detect)
    points = ds.sizes["point"]
    return (time.perf_counter() - begin) / points, points


_PACKAGE_DPARAM = MultiImpactBranchProblem.dparam
_PACKAGE_PALC_STEP = MultiImpactBranchProblem.palc_step


def _difference_dparam(self: MultiImpactBranchProblem, u: np.ndarray, lam: float
                       ) -> np.ndarray:
    """``dparam`` of a sticky motion as before the exact column: the parameter's central
    difference."""
    if self.sticky:
        return self._difference_quotient(u, lam)
    return _PACKAGE_DPARAM(self, u, lam)


def _core_palc_step(self: MultiImpactBranchProblem, *args, **kwargs) -> object:
    """``palc_step`` of a sticky motion as before the compiled corrector: none (the
    continuation core corrects with ``linearize``)."""
    return None if self.sticky else _PACKAGE_PALC_STEP(self, *args, **kwargs)


@contextlib.contextmanager
def route(before: bool) -> Iterator[None]:
    """The package's route, or (`before`) the one before the exact omega column and the
    compiled corrector, for one run."""
    if before:
        MultiImpactBranchProblem.dparam = _difference_dparam
        MultiImpactBranchProblem.palc_step = _core_palc_step
    try:
        yield
    finally:
        MultiImpactBranchProblem.dparam = _PACKAGE_DPARAM
        MultiImpactBranchProblem.palc_step = _PACKAGE_PALC_STEP


def main(rounds: int = 5, before: bool = False) -> None:
    motions = starts()
    runs = [(name, start, False) for name, start in motions.items()]
    if before:
        runs[1:1] = [("sticky, central difference and core corrector",
                      motions["sticky 'lu' (R 0)"], True)]
    for name, start, patched in runs:
        assert start.physical, (name, start.reason)
        with route(patched):
            per_point(start, ())  # warm: the compiled kernels
    for detect, label in (((), "no detection"), (ic.detection.LABELS, "default detection")):
        best: dict[str, tuple[float, int]] = {}
        for _ in range(rounds):
            for name, start, patched in runs:
                with route(patched):
                    cost, points = per_point(start, detect)
                best[name] = min(best.get(name, (np.inf, 0)), (cost, points))
        plain = best["plain 'UL' (R 0.6)"][0]
        print(f"{label}: " + ", ".join(
            f"{name} {cost * 1e3:.2f} ms/point ({points} points, ratio {cost / plain:.1f})"
            for name, (cost, points) in best.items()))
    print(f"load {os.getloadavg()[0]:.1f}")


def chatter_starts() -> dict[str, ic.MultiImpactOrbit]:
    """The damper's ball riding each wall entered through complete chatter (``"lu"``, R =
    0.3, omega 0.2, studies/chatter_sticking) and the plain ``"UL"`` motion of
    :func:`starts`, each from its simulated steady state."""
    osc = damper(0.2, 0.3)
    return {"chatter 'lu' (R 0.3)": ic.multi_impact_orbit(
                osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0, 12.0)),
            "plain 'UL' (R 0.6)": starts()["plain 'UL' (R 0.6)"]}


def solve_cost(start: ic.MultiImpactOrbit, rounds: int, osc: ic.ImpactOscillator | None = None
               ) -> tuple[float, float]:
    """Seconds of ``ic.multi_impact_orbit`` at omega + 0.005 (`osc`, by default made here)
    seeded by `start` (a Newton solve of a few iterations) and of one branch point (omega
    +- 0.02, ``ds_max = 0.005``, no detection): the best of `rounds`, in CPU time of this
    process (single-threaded with ``OPENBLAS_NUM_THREADS=1``: the wall clock of a machine
    loaded beyond its cores counts the other processes' time slices too)."""
    if osc is None:
        osc = start.oscillator.replace(omega=start.oscillator.omega + 0.005)
    solve = branch = np.inf
    for _ in range(rounds):
        begin = time.process_time()
        ic.multi_impact_orbit(osc, start.N, start.p, start)
        solve = min(solve, time.process_time() - begin)
        omega = start.oscillator.omega
        begin = time.process_time()
        ds = ic.continuation(start, parameter="omega", bounds=(omega - 0.02, omega + 0.02),
                             ds_max=0.005, detect=())
        branch = min(branch, (time.process_time() - begin) / ds.sizes["point"])
    return solve, branch


def chatter(rounds: int = 5) -> None:
    """``--chatter``: the Newton solve and the branch point of the chatter-entered riding
    motion against the plain one (issue 30's target: within 3x)::

        python studies/sticking_motions/branch_cost.py --chatter

    Measured at c4ecacb and at 077a366 (a bounce's return searched on the stop coordinate
    alone, the bounces' flights in one scratch, G compiled), each tree from an archive,
    five alternated runs at load 4.0-4.5 (other jobs on both cores): chatter-entered solve
    1.72-1.93 ms (3.4-4.1x the plain solve's 0.42-0.57 ms) -> 1.36-1.54 ms (2.5-3.6x of
    0.38-0.59 ms); branch point 2.1-2.5x -> 1.9-2.0x. The same solve repeated at one
    oscillator (warm caches): 1.77 -> 1.2 ms against 0.17 ms plain, of which the compiled
    Newton 0.38-0.40 ms (6 shots of two 10-bounce chatters), the two chatter checks about
    0.1 ms and the motion's Python checks (pressing minima, held clearances, G's
    multipliers) most of the rest.
    """
    motions = chatter_starts()
    for name, start in motions.items():
        assert start.physical, (name, start.reason)
    # each solved at one oscillator in every round (its flow built in the warm-up)
    oscs = {name: start.oscillator.replace(omega=start.oscillator.omega + 0.005)
            for name, start in motions.items()}
    costs = {name: (np.inf, np.inf) for name in motions}
    for name, start in motions.items():
        solve_cost(start, 1, oscs[name])  # warm: the compiled kernels, the flows
    for _ in range(rounds):  # interleaved: the load moves both alike
        for name, start in motions.items():
            costs[name] = tuple(np.minimum(costs[name], solve_cost(start, 1, oscs[name])))
    plain = costs["plain 'UL' (R 0.6)"]
    for name, (solve, branch) in costs.items():
        print(f"{name}: solve {solve * 1e3:.2f} ms (ratio {solve / plain[0]:.1f}), branch "
              f"point {branch * 1e3:.2f} ms (ratio {branch / plain[1]:.1f})")
    print(f"load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    if "--chatter" in sys.argv[1:]:
        chatter()
    else:
        main(before="--before" in sys.argv[1:])
