"""The cost of a branch point of a motion with sticking phases against a plain one.

The impact damper of case (c) (``eta = 0.3``): its ball riding each wall (``"lu"``, R = 0,
omega 1.2) against the same machine's ``"UL"`` motion at R = 0.6 (omega 2.5), each followed
in omega over +-0.2 with ``ds_max = 0.02``; the whole ``ic.continuation`` call divided by
its points, without and with the default special-point detection, in one process, the two
interleaved, the best of 5 rounds after a warm-up run of each::

    python studies/sticking_motions/branch_cost.py

Prints one line per detection setting: ms per point of each and their ratio.
"""

from __future__ import annotations

import os
import time

import numpy as np

import impactcont as ic
from impactcont.model.stops import Stops


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


def per_point(start: ic.MultiImpactOrbit, detect) -> tuple[float, int]:
    """Seconds per point of the branch through `start` and its number of points."""
    omega = start.oscillator.omega
    begin = time.perf_counter()
    ds = ic.continuation(start, parameter="omega", bounds=(omega - 0.2, omega + 0.2),
                         ds_max=0.02, detect=detect)
    points = ds.sizes["point"]
    return (time.perf_counter() - begin) / points, points


def main(rounds: int = 5) -> None:
    motions = starts()
    for name, start in motions.items():
        assert start.physical, (name, start.reason)
        per_point(start, ())  # warm: the compiled kernels
    for detect, label in (((), "no detection"), (ic.detection.LABELS, "default detection")):
        best = {}
        for _ in range(rounds):
            for name, start in motions.items():
                cost, points = per_point(start, detect)
                best[name] = min(best.get(name, (np.inf, 0)), (cost, points))
        (sticky, ns), (plain, npl) = best.values()
        print(f"{label}: sticky {sticky * 1e3:.2f} ms/point ({ns} points), plain "
              f"{plain * 1e3:.2f} ms/point ({npl} points), ratio {sticky / plain:.1f}")
    print(f"load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
