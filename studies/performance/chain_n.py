"""The cost of N = 1 motions of a chain against n, and against one dense ``eigh(K, M)``.

Issue 29, item 8: ``periodic_orbits`` on a chain cost 7.8 ms at n = 1400 and 14 s at
n = 1600 (27.6 s at n = 2000), where the impact velocity starts to be polished (its
kernel form loses digits: :func:`impactcont.orbit.dense.polished_velocity`) and the
polished path computed the dense eigenvalues of G, 2n x 2n, inside every call. This
script guards that the cost stays smooth in n.

For each n (BLAS pinned to one thread, best of ``--repeat`` calls where a call is
cheap, one call where it is not):

- ``build``: ``ImpactOscillator.chain(...)`` and its modal basis ``osc.modes`` (what a
  user waits for before the first motion);
- ``eigh``: one dense ``scipy.linalg.eigh(K, M)`` of the n x n problem, the reference;
- ``orbits``: ``periodic_orbits(osc, 1)`` with the modes built (both roots: phase,
  velocity, state, the interior-contact check of eq. 16);
- ``stability``: then the spectral radius of both roots (the multipliers by the secular
  function of :mod:`impactcont.orbit.secular` from n = 40);
- ``polished``: how many roots took the velocity-polished path (counted by wrapping
  ``impactcont.orbit.periodic._repolish``).

Two chains: ``uniform`` (unit masses and springs, F on mass 1, R = 0.7, b = 0.1,
omega = 1.1, eta = 0.05: the chain of ``run.py``) and ``unequal`` (the tests' chain,
``tests/conftest.py``: masses 1 + U(0, 0.5), springs 1 + U(0, 1) from the seed n, F on
mass 1 and 0.3 on mass n). Where the polish starts depends on rounding: on the machine
of the README's run the unequal chain polishes one root from n = 2000 and the uniform
one from n = 3000 (the issue's machine: n = 1600).

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python studies/performance/chain_n.py         # ~2 min
    OPENBLAS_NUM_THREADS=1 .venv/bin/python studies/performance/chain_n.py --full  # + 3000, 4000

Prints the table of the README's "Cost against n up to 4000" section and writes every
number to ``output/chain_n.json`` (``output/chain_n_full.json`` with ``--full``) next to
this file.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import scipy.linalg
from threadpoolctl import threadpool_limits

import impactcont as ic
from impactcont.orbit import periodic

HERE = Path(__file__).resolve().parent
log = logging.getLogger("chain_n")

DEFAULT_N = (100, 400, 1000, 1400, 1600, 2000)
FULL_N = (*DEFAULT_N, 3000, 4000)
# a call above this many seconds is timed once
_ONCE = 1.0


def uniform_chain(n: int) -> ic.ImpactOscillator:
    """Unit masses and springs, F on mass 1 (``run.py``'s chain)."""
    F = np.zeros(n)
    F[0] = 1.0
    return ic.ImpactOscillator.chain(masses=np.ones(n), springs=np.ones(n), F=F, R=0.7, b=0.1,
                                     omega=1.1, eta=0.05)


def unequal_chain(n: int) -> ic.ImpactOscillator:
    """The tests' chain (``tests/conftest.py``): unequal masses and springs from seed n."""
    rng = np.random.default_rng(n)
    masses = 1.0 + 0.5 * rng.random(n)
    springs = 1.0 + rng.random(n)
    F = np.zeros(n)
    F[0] = 1.0
    F[-1] = 0.3
    return ic.ImpactOscillator.chain(masses=masses, springs=springs, F=F, R=0.7, b=0.1,
                                     omega=1.1, eta=0.05)


CHAINS: dict[str, Callable[[int], ic.ImpactOscillator]] = {
    "uniform": uniform_chain, "unequal": unequal_chain}


def timed(fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    """Best wall time of ``repeat`` calls (one when the first takes over ``_ONCE`` s) and
    the last call's value."""
    start = time.perf_counter()
    value = fn()
    best = time.perf_counter() - start
    if best < _ONCE:
        for _ in range(repeat - 1):
            start = time.perf_counter()
            value = fn()
            best = min(best, time.perf_counter() - start)
    return best, value


def measure(kind: str, n: int, repeat: int) -> dict[str, Any]:
    make = CHAINS[kind]
    polished: list[float] = []
    original = periodic._repolish

    def counted(*args: Any, **kwargs: Any) -> Any:
        polished.append(args[3])
        return original(*args, **kwargs)

    t_build, osc = timed(lambda: _built(make(n)), 1)
    t_eigh, _ = timed(lambda: scipy.linalg.eigh(osc.K, osc.M), repeat)
    periodic._repolish = counted
    try:
        t_orbits, orbits = timed(lambda: ic.periodic_orbits(osc, 1), repeat)
        roots_polished = len(set(polished))
        t_stab, rho = timed(lambda: [o.spectral_radius for o in ic.periodic_orbits(osc, 1)],
                            repeat)
    finally:
        periodic._repolish = original
    row = {"chain": kind, "n": n, "build": t_build, "eigh": t_eigh, "orbits": t_orbits,
           "orbits_and_stability": t_stab, "stability": max(t_stab - t_orbits, 0.0),
           "polished": roots_polished, "roots": len(orbits), "rho": rho,
           "physical": [o.physical for o in orbits]}
    row["orbits_over_eigh"] = t_orbits / t_eigh
    row["build_orbits_over_eigh"] = (t_build + t_orbits) / t_eigh
    row["all_over_eigh"] = (t_build + t_stab) / t_eigh
    log.info("%s n=%d: build %.3g s, eigh %.3g s, orbits %.3g s, + stability %.3g s, "
             "polished %d", kind, n, t_build, t_eigh, t_orbits, t_stab, roots_polished)
    return row


def _built(osc: ic.ImpactOscillator) -> ic.ImpactOscillator:
    osc.modes  # noqa: B018 -- the modal basis, built on first access
    return osc


def _duration(seconds: float) -> str:
    return f"{seconds:.3g} s" if seconds >= 1.0 else f"{1e3 * seconds:.3g} ms"


def table(rows: list[dict[str, Any]]) -> str:
    lines = ["| chain | n | build (chain + modes) | `eigh(K, M)` | `periodic_orbits` | "
             "+ spectral radius | roots polished | orbits / eigh | (build + orbits) / eigh "
             "| (build + orbits + stability) / eigh |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['chain']} | {r['n']} | {r['build']:.3g} s | {r['eigh']:.3g} s | "
            f"{_duration(r['orbits'])} | {_duration(r['orbits_and_stability'])} | "
            f"{r['polished']} of {r['roots']} | {r['orbits_over_eigh']:.3g} | "
            f"{r['build_orbits_over_eigh']:.3g} | {r['all_over_eigh']:.3g} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--full", action="store_true",
                        help=f"n = {', '.join(map(str, FULL_N))} (several minutes)")
    parser.add_argument("--n", type=int, nargs="+", help="these n instead")
    parser.add_argument("--chain", choices=[*CHAINS, "both"], default="both")
    parser.add_argument("--repeat", type=int, default=3, help="calls per cheap timing")
    parser.add_argument("--output", type=Path, help="the JSON file (default output/)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    sizes = args.n or (FULL_N if args.full else DEFAULT_N)
    kinds = list(CHAINS) if args.chain == "both" else [args.chain]
    ic.periodic_orbits(uniform_chain(50), 1)[0].spectral_radius  # noqa: B018 -- warm-up
    rows = []
    with threadpool_limits(1):
        for kind in kinds:
            for n in sizes:
                rows.append(measure(kind, n, args.repeat))
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, cwd=HERE).stdout.strip()
    out = args.output or HERE / "output" / ("chain_n_full.json" if args.full else
                                            "chain_n.json")
    out.parent.mkdir(parents=True, exist_ok=True)
    result = {"rows": rows, "commit": commit, "load_average": os.getloadavg(),
              "python": platform.python_version(), "numpy": np.__version__,
              "scipy": scipy.__version__, "impactcont": ic.__file__,
              "date": time.strftime("%Y-%m-%d %H:%M")}
    out.write_text(json.dumps(result, indent=1, default=float))
    print(table(rows))


if __name__ == "__main__":
    main()
