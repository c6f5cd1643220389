"""First use on a fresh install: the four main verbs once each, CPU seconds per verb.

Run it with an empty numba cache to measure the compile a new user meets (issue 20's
target: the four verbs within 15 s of CPU in total)::

    export NUMBA_CACHE_DIR=$(mktemp -d) OPENBLAS_NUM_THREADS=1
    .venv/bin/python studies/performance/first_use.py

Run it again with the same ``NUMBA_CACHE_DIR`` for the cost from the disk cache. Writes
one JSON line: ``import``, ``periodic_orbits``, ``continuation``, ``curve``,
``stability_map`` and ``total`` (CPU seconds of this process, ``time.process_time``).
"""

from __future__ import annotations

import json
import sys
import time

_start = time.process_time()
import numpy as np  # noqa: E402

import impactcont as ic  # noqa: E402

_IMPORT = time.process_time() - _start


def main() -> dict[str, float]:
    """CPU seconds of each verb's first call (the paper's two-mass example)."""
    out = {"import": _IMPORT}
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                              eta=0.05, R=0.8, b=0.5, omega=1.2)
    t = time.process_time()
    ic.periodic_orbits(osc, 1)
    out["periodic_orbits"] = time.process_time() - t
    t = time.process_time()
    branch = ic.continuation(osc, N=1, parameter="omega", bounds=(0.5, 3.0))
    out["continuation"] = time.process_time() - t
    t = time.process_time()
    ic.curve(None, kind=str(branch.special_label.values[0]), start=branch, special=0,
             max_points=20, bounds={"omega": (0.5, 3.0), "b": (0.0, 1.5)})
    out["curve"] = time.process_time() - t
    t = time.process_time()
    ic.stability_map(osc, N=1, omega=np.linspace(1.0, 1.6, 20), b=np.linspace(0.1, 0.8, 20))
    out["stability_map"] = time.process_time() - t
    out["total"] = sum(out.values())
    return {k: round(v, 2) for k, v in out.items()}


if __name__ == "__main__":
    sys.stdout.write(json.dumps(main()) + "\n")
