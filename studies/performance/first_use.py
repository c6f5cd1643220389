"""First use on a fresh install: CPU seconds and compiled signatures per first call.

Each round starts fresh interpreters with an empty ``NUMBA_CACHE_DIR`` (a new temporary
directory) and measures, in CPU seconds of the process (``time.process_time``):

- ``verbs``: the four main verbs once each on the paper's two-mass example
  (``periodic_orbits``, ``continuation``, ``curve``, ``stability_map``; issue 29's target:
  at most 12 s of CPU in total on a quiet machine);
- ``np``: after the N = 1 start of the N-p tests (``tests/_multi_impact_cases.py``: the
  paper's system at b = 0, R = 0.6, eta = 0.1, omega = 1.5, its N = 1 orbit and branch
  start), the first N-p solve (``multi_impact_orbit`` of the N = 1 motion as a 1-1
  motion) and the first N-p branch (``multi_impact_continuation`` over omega in
  [1.45, 1.55], 5 points).

Every compile numba runs is recorded through its event API (``numba:compile``): the
number of compiled signatures of each step and the functions that took longest
(exclusive CPU seconds, a callee's own compile not counted in its caller's). Run::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python studies/performance/first_use.py --rounds 2

It prints a table and writes ``output/first_use.json`` (every round, the machine's load
average before each child, the top compiles). ``--warm`` repeats each child with the
cache it just filled (the cost from the disk cache). The machine is shared: read the
load column before comparing two runs.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
log = logging.getLogger("first_use")

PRELUDE = """
import json, sys, time
from collections import Counter
_t0 = time.process_time()
from numba.core import event

class _Compiles(event.Listener):
    def __init__(self):
        self.stack, self.own, self.count = [], Counter(), Counter()
    def on_start(self, ev):
        now = time.process_time()
        if self.stack:
            self.stack[-1][1] += now - self.stack[-1][2]
        d = ev.data["dispatcher"]
        self.stack.append([f"{d.py_func.__module__}.{d.py_func.__qualname__}", 0.0, now])
    def on_end(self, ev):
        now = time.process_time()
        name, own, since = self.stack.pop()
        self.own[name] += own + now - since
        self.count[name] += 1
        if self.stack:
            self.stack[-1][2] = now

_rec = _Compiles()
event.register("numba:compile", _rec)
import numpy as np
import impactcont as ic
_steps = {"import": [time.process_time() - _t0, 0]}
_tops = {}
def _step(name, fn):
    n0, own0 = sum(_rec.count.values()), Counter(_rec.own)
    t = time.process_time()
    out = fn()
    _steps[name] = [time.process_time() - t, sum(_rec.count.values()) - n0]
    mine = Counter(_rec.own)
    mine.subtract(own0)
    _tops[name] = [[k, round(v, 3)] for k, v in mine.most_common(12) if v > 0]
    return out
def _done():
    top = sorted(_rec.own.items(), key=lambda kv: -kv[1])[:25]
    print(json.dumps({"steps": _steps, "compiles": sum(_rec.count.values()),
                      "top": [[k, round(v, 3), _rec.count[k]] for k, v in top],
                      "top_by_step": _tops,
                      "functions": sorted(f"{k} x{v}" for k, v in _rec.count.items())}))
"""

VERBS = PRELUDE + """
osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                          eta=0.05, R=0.8, b=0.5, omega=1.2)
_step("periodic_orbits", lambda: ic.periodic_orbits(osc, 1))
branch = _step("continuation",
               lambda: ic.continuation(osc, N=1, parameter="omega", bounds=(0.5, 3.0)))
_step("curve", lambda: ic.curve(None, kind=str(branch.special_label.values[0]), start=branch,
                                special=0, max_points=20,
                                bounds={"omega": (0.5, 3.0), "b": (0.0, 1.5)}))
_step("stability_map", lambda: ic.stability_map(osc, N=1, omega=np.linspace(1.0, 1.6, 20),
                                                b=np.linspace(0.1, 0.8, 20)))
_done()
"""

NP = PRELUDE + """
from impactcont.analysis.branch import multi_impact_continuation
from impactcont.orbit.multi_impact import multi_impact_orbit
osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                          b=0.0, omega=1.5, eta=0.1)
def _n1():
    ic.continuation(osc, N=1, parameter="omega", bounds=(1.4, 2.0), components="start")
    orbits = ic.periodic_orbits(osc, 1)
    [(o.state, o.G, o.multipliers, o.physical) for o in orbits]
    return next(o for o in orbits if o.physical)
orbit = _step("n1_start", _n1)
motion = _step("np_solve", lambda: multi_impact_orbit(osc, 1, 1, orbit))
_step("np_branch", lambda: multi_impact_continuation(motion, "omega", (1.45, 1.55),
                                                     max_points=5))
_done()
"""

#: Warm per-call CPU microseconds (best of 7 rounds of ~0.2 s each) of the calls whose
#: compiled code a first-use change touches: the N-1 orbit of the paper's example and of a
#: 10-mass chain, a 1-1 N-p solve and the interior-contact check of an N-1 motion.
CALLS = """
import json, time
import numpy as np
import impactcont as ic
from impactcont.orbit.multi_impact import multi_impact_orbit
paper = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                            eta=0.05, R=0.8, b=0.5, omega=1.2)
n = 10
chain = ic.ImpactOscillator(M=np.eye(n), K=2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1),
                            F=np.r_[1.0, np.zeros(n - 1)], eta=0.05, R=0.8, b=0.3, omega=1.1)
b0 = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                         b=0.0, omega=1.5, eta=0.1)
start = next(o for o in ic.periodic_orbits(b0, 1) if o.physical)
motion = multi_impact_orbit(b0, 1, 1, start)
def orbits(osc):
    for o in ic.periodic_orbits(osc, 1):
        o.state, o.G, o.multipliers, o.physical
work = {"periodic_orbits paper": lambda: orbits(paper),
        "periodic_orbits chain10": lambda: orbits(chain),
        "multi_impact_orbit 1-1": lambda: multi_impact_orbit(b0, 1, 1, motion)}
best = {k: float("inf") for k in work}
for _ in range(7):
    for k, f in work.items():
        f()
        t0 = time.process_time()
        count = 0
        while time.process_time() - t0 < 0.2:
            f()
            count += 1
        best[k] = min(best[k], (time.process_time() - t0) / count * 1e6)
print(json.dumps({"calls_us": best}))
"""

CHILDREN = {"verbs": VERBS, "np": NP}


def _load() -> float:
    return os.getloadavg()[0]


def run_child(name: str, cache: str, root: Path = ROOT) -> dict[str, Any]:
    """One fresh interpreter running child `name` in `root` with `cache` as numba's cache."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache, "OPENBLAS_NUM_THREADS": "1",
           "PYTHONPATH": str(root)}
    load = _load()
    run = subprocess.run([sys.executable, "-c", CHILDREN[name]], env=env, cwd=root,
                         capture_output=True, text=True, check=False)
    if run.returncode:
        raise RuntimeError(f"child {name!r} failed:\n{run.stderr[-3000:]}")
    out = json.loads(run.stdout.splitlines()[-1])
    out["load"] = load
    return out


def warm_calls(roots: list[Path], rounds: int, output: Path) -> dict[str, Any]:
    """Warm per-call times (:data:`CALLS`) in each tree of `roots`, one fresh interpreter a
    round and tree, trees interleaved; each tree keeps its own numba cache."""
    caches = {root: tempfile.mkdtemp(prefix="first_use_calls_") for root in roots}
    runs: dict[str, list[dict[str, float]]] = {str(root): [] for root in roots}
    for _ in range(rounds):
        for root in roots:
            env = {**os.environ, "NUMBA_CACHE_DIR": caches[root], "OPENBLAS_NUM_THREADS": "1",
                   "PYTHONPATH": str(root)}
            load = _load()
            run = subprocess.run([sys.executable, "-c", CALLS], env=env, cwd=root,
                                 capture_output=True, text=True, check=False)
            if run.returncode:
                raise RuntimeError(f"calls in {root} failed:\n{run.stderr[-3000:]}")
            out = json.loads(run.stdout.splitlines()[-1])["calls_us"]
            runs[str(root)].append({**out, "load": load})
            log.info("%s (load %.2f): %s", root, load,
                     ", ".join(f"{k} {v:.1f} us" for k, v in out.items()))
    for root, mine in runs.items():
        for key in mine[0]:
            if key != "load":
                values = [r[key] for r in mine]
                log.info("%-40s %-28s %.1f-%.1f us", root, key, min(values), max(values))
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(json.dumps({"calls": runs}, indent=1) + "\n")
    return runs


def main() -> dict[str, Any]:
    """Run the rounds, print the table and write ``output/first_use.json``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=1, help="fresh caches per child")
    parser.add_argument("--only", choices=sorted(CHILDREN), default=None,
                        help="run one child only")
    parser.add_argument("--warm", action="store_true",
                        help="also rerun each child from the cache it filled")
    parser.add_argument("--calls", type=Path, nargs="*", default=None, metavar="ROOT",
                        help="instead: warm per-call microseconds of the touched calls in each "
                             "source tree ROOT, rounds interleaved (compiles first)")
    parser.add_argument("--root", type=Path, nargs="+", default=[ROOT],
                        help="the source trees to import impactcont from (e.g. `git archive`s "
                             "of two commits, for a before/after comparison: the rounds run "
                             "them in turn)")
    parser.add_argument("--output", type=Path, default=HERE / "output" / "first_use.json")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    if args.calls is not None:
        return warm_calls(args.calls or [ROOT], args.rounds, args.output)
    names = [args.only] if args.only else list(CHILDREN)
    rounds: list[dict[str, Any]] = []
    for r in range(args.rounds):
        for root in args.root:
            for name in names:
                with tempfile.TemporaryDirectory() as cache:
                    cold = run_child(name, cache, root)
                    warm = run_child(name, cache, root) if args.warm else None
                rounds.append({"round": r, "root": str(root), "child": name, "cold": cold,
                               "warm": warm})
                steps = ", ".join(f"{k} {v[0]:.2f} s/{v[1]}" for k, v in cold["steps"].items())
                log.info("round %d %s %s (load %.2f): %s; %d compiles", r, root, name,
                         cold["load"], steps, cold["compiles"])
    for root, name in [(root, name) for root in args.root for name in names]:
        mine = [x for x in rounds if x["child"] == name and x["root"] == str(root)]
        log.info("\n%s\n%-16s %-28s %-20s %s", root, "step", "CPU s cold (min-max)",
                 "compiles", "load")
        for step in mine[0]["cold"]["steps"]:
            cpu = [x["cold"]["steps"][step][0] for x in mine]
            n = [x["cold"]["steps"][step][1] for x in mine]
            load = [x["cold"]["load"] for x in mine]
            log.info("%-16s %-28s %-20s %s", step, f"{min(cpu):.2f}-{max(cpu):.2f}",
                     f"{min(n)}-{max(n)}", f"{min(load):.2f}-{max(load):.2f}")
        total = [sum(v[0] for v in x["cold"]["steps"].values()) for x in mine]
        count = [x["cold"]["compiles"] for x in mine]
        log.info("%-16s %-28s %-20s", f"{name} total", f"{min(total):.2f}-{max(total):.2f}",
                 f"{min(count)}-{max(count)}")
        if mine[0]["warm"]:
            warm = [sum(v[0] for v in x["warm"]["steps"].values()) for x in mine]
            log.info("%-16s %-28s", f"{name} warm", f"{min(warm):.2f}-{max(warm):.2f}")
    result = {"rounds": rounds}
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(result, indent=1) + "\n")
    log.info("written %s", args.output)
    return result


if __name__ == "__main__":
    main()
