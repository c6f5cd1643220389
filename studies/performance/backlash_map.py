"""The stability map of the backlash's symmetric 1-2 motion: grid points per second.

Issue 20's target, kept by issue 29: at least 1e5 grid points/s for the map of
``docs/multi_maps.md`` ("How fast": omega in [0.5, 2.5] x b in [0.2, 1.0], 1001 x 501,
the symmetric 1-2 motion of the backlash with mirrored stops, solved on its half system,
81 % of the grid found), "met with the machine loaded, not only at its quietest". Each
figure is the whole call (setup, sweep, dataset) after a first call that compiles or
loads the kernel; wall and CPU seconds (``time.process_time``) are both recorded, with
the load average: on the shared 2-core machine the wall time of a loaded run is the CPU
time stretched by the other jobs.

Run in this tree::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python studies/performance/backlash_map.py --rounds 3

or side by side, each tree (a ``git archive`` of a commit) in its own interpreter in turn,
``--repeat`` times::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python studies/performance/backlash_map.py \\
        --rounds 3 --repeat 2 --root /tmp/before --root /tmp/after

It prints one line per run and writes ``output/backlash_map.json``.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
log = logging.getLogger("backlash_map")

#: The measured map, as ``docs/multi_maps.md`` gives it; prints one JSON line.
CHILD = """
import json, os, sys, time
import numpy as np
import impactcont as ic

multi_impact_map = ic.multi_impact_map  # the package's name at every commit since a8588cd
rounds, n0, n1 = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.5,
                          omega=1.6, eta=0.1, stops=ic.Stops(mirror=True))
start = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))
grid = {"omega": np.linspace(0.5, 2.5, n0), "b": np.linspace(0.2, 1.0, n1)}
multi_impact_map(start, grid=grid)  # compiles the kernel or loads it from the cache
wall, cpu, load = [], [], []
for _ in range(rounds):
    load.append(os.getloadavg()[0])
    t, c = time.perf_counter(), time.process_time()
    ds = multi_impact_map(start, grid=grid)
    wall.append(time.perf_counter() - t)
    cpu.append(time.process_time() - c)
options = json.loads(ds.attrs.get("options", "{}"))
print(json.dumps({"package": os.path.dirname(ic.__file__), "points": n0 * n1,
                  "found": float(ds["found"].mean()), "wall": wall, "cpu": cpu, "load": load,
                  "sweep_seconds": options.get("sweep_seconds")}))
"""


def run(root: Path, rounds: int, shape: tuple[int, int]) -> dict[str, Any]:
    """One interpreter timing the map with the package of `root`."""
    env = {**os.environ, "PYTHONPATH": str(root), "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", CHILD, str(rounds), *map(str, shape)],
                         cwd=root, env=env, capture_output=True, text=True, check=True)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res["root"] = str(root)
    res["wall_rate"] = res["points"] / min(res["wall"])
    res["cpu_rate"] = res["points"] / min(res["cpu"])
    return res


def main() -> list[dict[str, Any]]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3, help="timed calls per interpreter")
    parser.add_argument("--repeat", type=int, default=1, help="runs of each tree, in turn")
    parser.add_argument("--root", action="append", type=Path,
                        help="a tree to time (repeatable; default: this one)")
    parser.add_argument("--grid", default="1001x501", help="omega x b points")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    shape = tuple(int(v) for v in args.grid.split("x"))
    roots = args.root or [ROOT]
    runs = []
    for _ in range(args.repeat):
        for root in roots:
            res = run(root, args.rounds, shape)
            runs.append(res)
            log.info("%s: %.3g points/s wall (best of %d: %s s), %.3g points/s CPU, load %s",
                     root, res["wall_rate"], args.rounds,
                     ", ".join(f"{w:.2f}" for w in res["wall"]), res["cpu_rate"],
                     ", ".join(f"{x:.1f}" for x in res["load"]))
    (HERE / "output").mkdir(exist_ok=True)
    (HERE / "output" / "backlash_map.json").write_text(json.dumps(runs, indent=1))
    return runs


if __name__ == "__main__":
    main()
