"""Points per second: impactcont's closed form against scipy shooting, n = 2, 20, 200.

A "point" is one periodic N = 1 motion with its multipliers at one value of
omega (what a continuation step or a bifurcation-diagram column needs). Timed
side by side in one run, on the same sweep of omega values:

- ``periodic_orbits``: the single-point API (both roots of eq. 15, state, G,
  multipliers, the eq. 16 interior-contact check), modes reused along the sweep;
- ``batched_orbits``: the batch API over the whole omega sweep at once (same
  content per point: roots, h2, gap_min, spectral radius);
- the profile of one ``periodic_orbits`` call (where the time goes);
- scipy shooting (DOP853, the fastest variant in the work-precision study), warm
  started from the previous omega's orbit as in a continuation, at the
  tolerance that gives its best orbit accuracy (rtol 1e-11, about 1e-11 on the
  orbit and 1e-6 .. 1e-9 on the multipliers); the closed form is at 1e-14 or
  better, so the ratio is a lower bound on the speed-up at equal accuracy.

Run::

    .venv/bin/python studies/accuracy_vs_runtime/benchmark.py [--output DIR] [--quick]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # shared machine: no BLAS threads
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import cProfile
import io
import json
import logging
import math
import pstats
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

import impactcont as ic
from impactcont.orbit.batched import batched_orbits

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import shooting  # noqa: E402

log = logging.getLogger("benchmark")


def chain(n: int) -> ic.ImpactOscillator:
    """The paper's system for n = 2; a uniform chain (eta = 0.02) forced on mass 1 otherwise."""
    if n == 2:
        return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                                   R=0.6, b=0.0, omega=1.2, eta=0.1)
    F = np.zeros(n)
    F[0] = 1.0
    return ic.ImpactOscillator.chain(masses=np.ones(n), springs=np.ones(n), F=F, R=0.6, b=0.0,
                                     omega=0.6, eta=0.02)


def sweep(osc: ic.ImpactOscillator, count: int) -> np.ndarray:
    """omega values around the oscillator's, where the N = 1 motion exists."""
    return osc.omega * (1.0 + 0.01 * np.linspace(-1.0, 1.0, count))


def per_point(osc: ic.ImpactOscillator, omegas: np.ndarray) -> float:
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ic.IllConditionedWarning)
        for w in omegas:
            ic.periodic_orbits(osc.replace(omega=float(w)), 1)
    return (time.perf_counter() - t0) / omegas.size


def batched(osc: ic.ImpactOscillator, omegas: np.ndarray) -> float:
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ic.IllConditionedWarning)
        batched_orbits(osc, 1, omegas, np.array([osc.b]))
    return (time.perf_counter() - t0) / omegas.size


def shooting_per_point(osc: ic.ImpactOscillator, omegas: np.ndarray, rtol: float) -> float:
    orbit = next(o for o in ic.periodic_orbits(osc.replace(omega=float(omegas[0])), 1)
                 if o.physical)
    z = np.concatenate([orbit.state[1:], [orbit.delta]])
    t0 = time.perf_counter()
    for w in omegas:
        P = shooting.ImpactMap(osc.replace(omega=float(w)), 1, "DOP853", rtol)
        z, _ = shooting.shoot(P, z)
    return (time.perf_counter() - t0) / omegas.size


def profile(osc: ic.ImpactOscillator) -> str:
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(3):
        ic.periodic_orbits(osc.replace(omega=osc.omega * 1.001), 1)
    prof.disable()
    buf = io.StringIO()
    pstats.Stats(prof, stream=buf).sort_stats("tottime").print_stats(8)
    return buf.getvalue()


def main(output_dir: str | Path = HERE / "output", quick: bool = False) -> list[dict[str, Any]]:
    """Measure and write ``benchmark.json`` and ``benchmark.md`` into ``output_dir``."""
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    profiles = {}
    for n in (2, 20, 200):
        osc = chain(n)
        osc.modes  # noqa: B018 - the modal basis is shared by the sweep; computed once here
        count = {2: 200, 20: 100, 200: 10}[n] // (4 if quick else 1)
        omegas = sweep(osc, count)
        t_point = per_point(osc, omegas)
        t_batch = batched(osc, omegas)
        shoot_count = {2: 10, 20: 4, 200: 0}[n] // (2 if quick else 1)
        t_shoot = (shooting_per_point(osc, omegas[:shoot_count], 1e-11)
                   if shoot_count else math.nan)
        profiles[n] = profile(osc)
        row = {"n": n, "points": int(count), "periodic_orbits_per_s": 1.0 / t_point,
               "batched_orbits_per_s": 1.0 / t_batch,
               "shooting_DOP853_1e-11_per_s": 1.0 / t_shoot if shoot_count else None,
               "ratio_shooting_to_closed_form": t_shoot / t_point if shoot_count else None,
               "ratio_per_point_to_batched": t_point / t_batch}
        rows.append(row)
        log.info("n=%d: periodic_orbits %.1f points/s, batched %.1f points/s, shooting %s "
                 "points/s (closed form x%s faster)", n, row["periodic_orbits_per_s"],
                 row["batched_orbits_per_s"],
                 f"{row['shooting_DOP853_1e-11_per_s']:.3g}" if shoot_count else "-",
                 f"{row['ratio_shooting_to_closed_form']:.0f}" if shoot_count else "-")
    (out / "benchmark.json").write_text(json.dumps({"rows": rows, "profiles": profiles},
                                                   indent=1))
    lines = ["| n | periodic_orbits points/s | batched_orbits points/s | batch gain | "
             "shooting DOP853 rtol 1e-11 points/s | closed form speed-up |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        shoot = (f"{r['shooting_DOP853_1e-11_per_s']:.3g}"
                 if r["shooting_DOP853_1e-11_per_s"] else "not run (minutes per point)")
        ratio = (f"x{r['ratio_shooting_to_closed_form']:.0f}"
                 if r["ratio_shooting_to_closed_form"] else "-")
        lines.append(f"| {r['n']} | {r['periodic_orbits_per_s']:.3g} | "
                     f"{r['batched_orbits_per_s']:.3g} | x{r['ratio_per_point_to_batched']:.1f} | "
                     f"{shoot} | {ratio} |")
    (out / "benchmark.md").write_text("\n".join(lines) + "\n")
    log.info("\n%s", "\n".join(lines))
    for n, text in profiles.items():
        log.info("profile n=%d:\n%s", n, text)
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=str(HERE / "output"))
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.output, quick=args.quick)
