"""Cost of one closed-form periodic orbit with G, for n = 2 and n = 20 (issue: foundation).

Measured side by side in one run (the machine is shared and noisy): the
closed form (eq. 13-15 + G of eq. 25 + multipliers, the eq. 16 interior-contact
check included) against simulating the same orbit for one period with the
event-driven simulator. Run:

    .venv/bin/python studies/orbit_cost/run.py
"""

from __future__ import annotations

import logging
import timeit

import numpy as np

import impactcont as ic

log = logging.getLogger("orbit_cost")


def chain(n: int) -> ic.ImpactOscillator:
    F = np.zeros(n)
    F[0] = 1.0
    return ic.ImpactOscillator.chain(masses=np.ones(n), springs=np.ones(n), F=F, R=0.6,
                                     b=0.0, omega=1.2, eta=0.1)


def measure(n: int, repeat: int = 5) -> dict[str, float]:
    osc = chain(n)
    orbits = ic.periodic_orbits(osc, 1)
    orbit = next(o for o in orbits if o.physical)

    def closed_form() -> None:
        ic.periodic_orbits(osc.replace(omega=1.2), 1)  # fresh oscillator: modes recomputed

    def simulated() -> None:
        ic.simulate(osc, orbit.state, orbit.delta, 1.0)

    number = 20
    t_cf = min(timeit.repeat(closed_form, number=number, repeat=repeat)) / number
    t_sim = min(timeit.repeat(simulated, number=number, repeat=repeat)) / number
    return {"n": n, "closed_form_s": t_cf, "simulate_one_period_s": t_sim,
            "ratio": t_sim / t_cf, "roots": len(orbits)}


def main() -> list[dict[str, float]]:
    rows = [measure(n) for n in (2, 20)]
    for r in rows:
        log.info("n=%2d: periodic_orbits (both roots, G, multipliers, gap_min) %.2f ms; "
                 "simulate one period %.2f ms; ratio %.1f", r["n"], 1e3 * r["closed_form_s"],
                 1e3 * r["simulate_one_period_s"], r["ratio"])
    return rows


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main()
