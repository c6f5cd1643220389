"""N-p, two-sided and any-C motions against the compiled N-1 closed form, side by side.

The ratios of issue 20 ("one motion model"), measured in one process with BLAS pinned
to one thread; every number is the best of interleaved rounds (each round times every
workload once, so all see the same load):

1. one 2-2 ``multi_impact_orbit`` Newton solve of the paper system (b = 0, omega = 1.75,
   on the branch born at the N = 1 period doubling) from the motion at omega = 1.749
   against ``periodic_orbits(osc, 2)`` (both roots with state, G, multipliers, physical),
   also per impact (the 2-2 solve over twice the closed form);
2. ``multi_impact_continuation`` of that 2-2 motion over omega in [1.65, 1.85], per point,
   against a point of the N = 1 branch ``continuation(b = 0, N = 1, omega in [0.5, 6])``;
3. the two-sided symmetric 1-2 motion of the backlash system (``studies/backlash``,
   b = b_low = 0.8, omega = 0.8) continued over omega in [0.7, 0.9], per point, against
   the same N = 1 branch point; and what sets it on so short a branch (9 points): the
   same branch without detection (``detect=()``) and without the dataset (the core's
   ``follow`` on its problem alone);
4. one N = 1 orbit of the paper system with a damping matrix that is not proportional
   (only the damper between the masses: the first-order path, compiled in
   ``kernel/general.py``) against the proportional one (``periodic_orbits``, both
   roots, as in 1; b = 0.6, omega = 1), and the omega continuation of that N = 1 motion
   over [0.5, 6], per point, against the same continuation with proportional damping;
5. one 1-2 backlash solve with that damping matrix against the proportional one (the
   shooting kernel's first-order flow against its modal flow);
6. the curve of a symmetry-breaking pitchfork of the symmetric 1-2 backlash motion in
   ``(omega, b)`` (mirrored stops; ``multi_impact_curve``), per point, against a point of
   the closed-form N = 1 PD curve of the paper system (``curve``); the issue's target is
   2 ms per point (``--only bp-paired`` and ``--only bp-half-map``: that curve with one
   change on and off, paired in one process);
7. the cold compile the shooting kernel adds: in a fresh interpreter with an empty
   ``NUMBA_CACHE_DIR``, the N = 1 verbs first (compiling the kernel they share), then the
   first N-p solve and the first N-p continuation (CPU seconds); and, in another fresh
   interpreter, what the first any-C orbit compiles after the N = 1 verbs (the four
   entry points of ``kernel/general.py``).

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python studies/performance/np_motions.py [--rounds 7]

Prints the table of the README's "N-p motions" section and writes it with every number
to ``output/np_motions.json`` next to this file.
"""

from __future__ import annotations

import argparse
import functools
import json
import logging
import os
import subprocess
import sys
import tempfile
import time
import types
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

import impactcont as ic
from impactcont.analysis.branch import branch_problem, make_options, multi_impact_continuation
from impactcont.analysis.switching import period_doubling_switch
from impactcont.core import follow
from impactcont.orbit.multi_impact import multi_impact_orbit

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
log = logging.getLogger("np_motions")
K2 = [[1.0, -1.0], [-1.0, 2.0]]
JOINT_DAMPER = [[0.2, -0.2], [-0.2, 0.2]]

COLD = """
import json, time
import numpy as np
import impactcont as ic
from impactcont.analysis.branch import multi_impact_continuation
from impactcont.orbit.multi_impact import multi_impact_orbit
osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                          b=0.0, omega=1.5, eta=0.1)
c0 = time.process_time()
ic.continuation(osc, N=1, parameter="omega", bounds=(1.4, 2.0), components="start")
orbits = ic.periodic_orbits(osc, 1)
[(o.state, o.G, o.multipliers, o.physical) for o in orbits]
orbit = next(o for o in orbits if o.physical)
c1 = time.process_time()
motion = multi_impact_orbit(osc, 1, 1, orbit)
c2 = time.process_time()
multi_impact_continuation(motion, "omega", (1.45, 1.55), max_points=5)
c3 = time.process_time()
print(json.dumps({"n1_verbs": c1 - c0, "np_solve": c2 - c1, "np_continuation": c3 - c2}))
"""

COLD_ANY_C = """
import json, time
import numpy as np
import impactcont as ic
osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                          b=0.6, omega=1.0, eta=0.1)
c0 = time.process_time()
ic.continuation(osc, N=1, parameter="omega", bounds=(0.9, 1.1), components="start")
[(o.state, o.G, o.multipliers, o.physical) for o in ic.periodic_orbits(osc, 1)]
c1 = time.process_time()
[(o.state, o.G, o.multipliers, o.physical)
 for o in ic.periodic_orbits(osc.replace(eta=None, C=[[0.2, -0.2], [-0.2, 0.2]]), 1)]
c2 = time.process_time()
print(json.dumps({"n1_verbs": c1 - c0, "any_C_orbit": c2 - c1}))
"""


def paper(**kw: Any) -> ic.ImpactOscillator:
    args = {"M": np.eye(2), "K": K2, "F": [1.0, 0.0], "R": 0.6, "b": 0.0, "omega": 1.5,
            "eta": 0.1}
    return ic.ImpactOscillator(**{**args, **kw})


def backlash(**kw: Any) -> ic.ImpactOscillator:
    return paper(**{"b": 0.8, "omega": 0.8, "stops": ic.Stops(b_low=0.8), **kw})


def closed_form(osc: ic.ImpactOscillator, N: int) -> None:
    for o in ic.periodic_orbits(osc, N):
        o.state, o.G, o.multipliers, o.physical  # noqa: B018 - the access is the work


def interleaved(work: dict[str, Callable[[], Any]], rounds: int, budget: float = 0.1
                ) -> dict[str, float]:
    """Best time per call of each workload over `rounds` interleaved rounds."""
    numbers = {}
    for name, fn in work.items():
        start = time.perf_counter()
        fn()
        numbers[name] = max(1, int(budget / max(time.perf_counter() - start, 1e-7)))
    best = dict.fromkeys(work, np.inf)
    for _ in range(rounds):
        for name, fn in work.items():
            start = time.perf_counter()
            for _ in range(numbers[name]):
                fn()
            best[name] = min(best[name], (time.perf_counter() - start) / numbers[name])
    return best


def cold_compile(script: str = COLD) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        run = subprocess.run([sys.executable, "-c", script], env=env, cwd=ROOT,
                             capture_output=True, text=True, check=True)
    return json.loads(run.stdout.splitlines()[-1])


def _bp_per_point(sym_branch: Any) -> float:
    """Seconds per point of the BP curve of the symmetric 1-2 motion in (omega, b)."""
    start = time.perf_counter()
    ds = ic.multi_impact_curve(sym_branch, "BP", 1, parameter="b",
                               bounds={"omega": (0.5, 2.5), "b": (0.2, 1.0)}, ds_max=0.02)
    return (time.perf_counter() - start) / ds.sizes["point"]


def paired(per_point: Callable[[], float], switch: Callable[[bool], None],
           pairs: int = 30) -> dict[str, Any]:
    """`per_point` with `switch` on and off (off: the code before), timed back to back in one
    process, the order alternating: the median and quartiles of the paired ratios on/off."""
    times: dict[bool, list[float]] = {False: [], True: []}
    ratios = []
    for on in (False, True):  # warm
        switch(on)
        per_point()
    for i in range(pairs):
        pair = {}
        for on in ((False, True) if i % 2 == 0 else (True, False)):
            switch(on)
            pair[on] = per_point()
            times[on].append(pair[on])
        ratios.append(pair[True] / pair[False])
    q = np.percentile(ratios, [25, 50, 75])
    return {"median_ratio": float(q[1]), "quartiles": [float(q[0]), float(q[2])],
            "before_ms_best_median": [1e3 * min(times[False]),
                                      1e3 * float(np.median(times[False]))],
            "after_ms_best_median": [1e3 * min(times[True]),
                                     1e3 * float(np.median(times[True]))],
            "loadavg": os.getloadavg()}


def bp_paired(sym_branch: Any, pairs: int = 30) -> dict[str, Any]:
    """The BP curve per point with the BP row from the shot and moved stop geometry
    (``problems/codim1.py``, ``orbit/stop_geometry.py``) on and off (the forward-difference
    row and each stop geometry built afresh: the code before), :func:`paired`."""
    import impactcont.problems.codim1 as codim1
    import impactcont.problems.multi_impact_branch as branch
    from impactcont.orbit.stop_geometry import stop_geometry

    init, moved = codim1.ShootingCurve.__init__, branch.moved_stop_geometry

    def switch(on: bool) -> None:
        def patched(self: Any, *args: Any, **kw: Any) -> None:
            init(self, *args, **kw)
            self._exact_pitchfork = self._exact_pitchfork and on
        codim1.ShootingCurve.__init__ = patched
        branch.moved_stop_geometry = moved if on else (
            lambda geometry, before, osc, pattern: stop_geometry(osc, pattern))

    try:
        return paired(lambda: _bp_per_point(sym_branch), switch, pairs)
    finally:
        codim1.ShootingCurve.__init__, branch.moved_stop_geometry = init, moved


#: The commit before the half-map's derivative was compiled (``kernel/half_map.py``): its
#: ``problems/symmetric_branch.py`` has the numpy complex step.
NUMPY_HALF_MAP = "d6bf099^"


def half_map_paired(sym_branch: Any, pairs: int = 30) -> dict[str, Any]:
    """The BP curve per point with the half-map's derivative compiled and as it was before
    (``SymmetricBranchProblem.half_map_derivative`` of ``problems/symmetric_branch.py`` at
    :data:`NUMPY_HALF_MAP`, read from git: the complex step in numpy), :func:`paired`.
    Each variant's results are the same curve (the points within 2e-15)."""
    from impactcont.problems.symmetric_branch import SymmetricBranchProblem

    source = subprocess.run(
        ["git", "show", f"{NUMPY_HALF_MAP}:impactcont/problems/symmetric_branch.py"],
        cwd=ROOT, capture_output=True, text=True, check=True).stdout
    before = types.ModuleType("symmetric_branch_before")
    exec(compile(source, "symmetric_branch_before.py", "exec"), before.__dict__)
    compiled = SymmetricBranchProblem.half_map_derivative
    state = functools.cached_property(lambda self: before._state_matrix(self.osc))
    state.__set_name__(SymmetricBranchProblem, "_state")
    SymmetricBranchProblem._state = state

    def switch(on: bool) -> None:
        SymmetricBranchProblem.half_map_derivative = (
            compiled if on else before.SymmetricBranchProblem.half_map_derivative)

    try:
        return paired(lambda: _bp_per_point(sym_branch), switch, pairs)
    finally:
        SymmetricBranchProblem.half_map_derivative = compiled
        del SymmetricBranchProblem._state


def main() -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--pairs", type=int, default=30,
                        help="pairs of the bp-paired and bp-half-map timings")
    parser.add_argument("--only", choices=("bp-symmetric", "bp-paired", "bp-half-map"),
                        default=None,
                        help="bp-symmetric: only the BP curve point and the symmetric 1-2 "
                        "branch with their references (the N = 1 PD curve and branch point), "
                        "no cold compiles; prints per-point times. bp-paired: the BP curve "
                        "with the exact BP row and the moved stop geometry on and off in one "
                        "process (off is the code before them), 30 alternating pairs. "
                        "bp-half-map: the BP curve with the half-map's derivative compiled and "
                        "in numpy (as at NUMPY_HALF_MAP), the same way")
    args = parser.parse_args()
    threadpool_limits(1)
    # the 2-2 motion of the period-doubled branch, and a guess at a nearby omega
    n1 = ic.continuation(paper(), N=1, parameter="omega", bounds=(1.4, 2.0), components="start")
    b22 = period_doubling_switch(n1, bounds=(1.6, 1.9))
    i = int(np.argmin(np.abs(b22.omega.values - 1.75)))
    seed = {"delta": float(b22.delta_k.values[i, 0]), "flight_times": b22.flight_time_k.values[i],
            "states": b22.state_k.values[i]}
    osc22 = paper(omega=1.75)
    guess = multi_impact_orbit(paper(omega=1.749), 2, 2, seed)
    motion22 = multi_impact_orbit(osc22, 2, 2, guess)
    res = ic.simulate(backlash(), np.zeros(4), 0.0, 200.0)
    symmetric = multi_impact_orbit(backlash(), 1, 2, res)
    general_backlash = backlash(eta=None, C=JOINT_DAMPER)
    res_c = ic.simulate(general_backlash, np.zeros(4), 0.0, 200.0)
    symmetric_c = multi_impact_orbit(general_backlash, 1, 2, res_c)
    near_c = multi_impact_orbit(general_backlash.replace(omega=0.801), 1, 2, symmetric_c)
    near = multi_impact_orbit(backlash(omega=0.801), 1, 2, symmetric)
    proportional_backlash = backlash()
    points = {}
    # the symmetric 1-2 motion of the backlash with mirrored stops (b moves both) and its
    # branch in omega with both pitchforks (BP), for the curve of a pitchfork in (omega, b)
    mirrored = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.5, omega=1.6,
                                   eta=0.1, stops=ic.Stops(mirror=True))
    sym_m = multi_impact_orbit(mirrored, 1, 2, ic.simulate(mirrored, np.zeros(4), 0.0, 150.0))
    sym_branch = multi_impact_continuation(sym_m, "omega", (0.9, 1.7), both_directions=True,
                                           ds_max=0.02)
    pd_branch = ic.continuation(paper(b=0.0, omega=1.75), N=1, parameter="omega",
                                bounds=(1.6, 1.9), detect=("PD",))

    def curve_bp():
        ds = ic.multi_impact_curve(sym_branch, "BP", 1, parameter="b",
                                   bounds={"omega": (0.5, 2.5), "b": (0.2, 1.0)}, ds_max=0.02)
        points["bp"] = ds.sizes["point"]

    def curve_pd_n1():
        ds = ic.curve(None, None, "PD", start=pd_branch,
                      bounds={"omega": (0.5, 3.0), "b": (-0.2, 0.3)})
        points["pd_n1"] = ds.sizes["point"]

    def branch_n1():
        ds = ic.continuation(paper(b=0.0), N=1, parameter="omega", bounds=(0.5, 6.0),
                             components="start")
        points["n1"] = ds.sizes["point"]

    def branch_22():
        ds = multi_impact_continuation(motion22, "omega", (1.65, 1.85))
        points["22"] = ds.sizes["point"]

    def branch_12():
        ds = multi_impact_continuation(symmetric, "omega", (0.7, 0.9))
        points["12"] = ds.sizes["point"]

    def branch_12_no_detection():
        multi_impact_continuation(symmetric, "omega", (0.7, 0.9), detect=())

    options_12 = make_options((0.7, 0.9))

    def branch_12_core():  # a new problem each time, as each continuation builds one
        problem_12, v_12 = branch_problem(symmetric, "omega")
        follow(problem_12, v_12, 0.8, options_12)

    general = paper(b=0.6, omega=1.0, eta=None, C=JOINT_DAMPER)
    proportional = paper(b=0.6, omega=1.0)

    def branch_any_C():
        ds = ic.continuation(general, N=1, parameter="omega", bounds=(0.5, 6.0))
        points["any_C"] = ds.sizes["point"]

    def branch_proportional():
        ds = ic.continuation(proportional, N=1, parameter="omega", bounds=(0.5, 6.0))
        points["proportional"] = ds.sizes["point"]
    work = {
        "solve_22": lambda: multi_impact_orbit(osc22, 2, 2, guess),
        "closed_form_N2": lambda: closed_form(osc22, 2),
        "branch_n1": branch_n1,
        "branch_22": branch_22,
        "branch_12": branch_12,
        "branch_12_no_detection": branch_12_no_detection,
        "branch_12_core": branch_12_core,
        "orbit_any_C": lambda: closed_form(general, 1),
        "orbit_proportional": lambda: closed_form(proportional, 1),
        "branch_any_C": branch_any_C,
        "branch_proportional": branch_proportional,
        "solve_12_any_C": lambda: multi_impact_orbit(general_backlash, 1, 2, near_c),
        "solve_12_proportional": lambda: multi_impact_orbit(proportional_backlash, 1, 2, near),
        "curve_bp": curve_bp,
        "curve_pd_n1": curve_pd_n1,
    }
    if args.only in ("bp-paired", "bp-half-map"):
        out = (bp_paired if args.only == "bp-paired" else half_map_paired)(sym_branch,
                                                                           args.pairs)
        print(json.dumps(out))
        return out
    if args.only == "bp-symmetric":
        keep = ("branch_n1", "branch_12", "branch_12_no_detection", "curve_bp", "curve_pd_n1")
        t = interleaved({k: work[k] for k in keep}, args.rounds)
        out = {"per_point_ms": {"bp": 1e3 * t["curve_bp"] / points["bp"],
                                "pd_n1": 1e3 * t["curve_pd_n1"] / points["pd_n1"],
                                "12": 1e3 * t["branch_12"] / points["12"],
                                "12_no_detection": 1e3 * t["branch_12_no_detection"]
                                / points["12"],
                                "n1": 1e3 * t["branch_n1"] / points["n1"]},
               "points": points, "loadavg": os.getloadavg(), "impactcont": ic.__file__}
        out["ratio_12_n1"] = out["per_point_ms"]["12"] / out["per_point_ms"]["n1"]
        print(json.dumps(out))
        return out
    t = interleaved(work, args.rounds)
    per_point = {k: t[f"branch_{k}"] / points[k]
                 for k in ("n1", "22", "12", "any_C", "proportional")}
    per_point.update({k: t[f"curve_{k}"] / points[k] for k in ("bp", "pd_n1")})
    cold = cold_compile()
    cold_any_c = cold_compile(COLD_ANY_C)
    res_out = {"times": t, "points": points, "per_point": per_point, "cold_compile_cpu": cold,
               "cold_compile_any_C_cpu": cold_any_c, "loadavg": os.getloadavg()}
    rows = [
        ("one 2-2 `multi_impact_orbit` Newton solve from a nearby guess",
         f"{1e6 * t['solve_22']:.0f} us", f"{1e6 * t['closed_form_N2']:.1f} us "
         "(`periodic_orbits(osc, 2)`)",
         t["solve_22"] / t["closed_form_N2"], t["solve_22"] / (2 * t["closed_form_N2"]), 3.0),
        ("2-2 `multi_impact_continuation`, per point",
         f"{1e3 * per_point['22']:.2f} ms ({points['22']} points)",
         f"{1e3 * per_point['n1']:.2f} ms (N = 1 branch, {points['n1']} points)",
         per_point["22"] / per_point["n1"], None, 3.0),
        ("two-sided symmetric 1-2 continuation, per point",
         f"{1e3 * per_point['12']:.2f} ms ({points['12']} points)",
         f"{1e3 * per_point['n1']:.2f} ms", per_point["12"] / per_point["n1"], None, 3.0),
        ("one N = 1 orbit with a damping matrix (damper between the masses)",
         f"{1e6 * t['orbit_any_C']:.1f} us", f"{1e6 * t['orbit_proportional']:.1f} us",
         t["orbit_any_C"] / t["orbit_proportional"], None, 2.0),
        ("omega continuation with that damping matrix, per point",
         f"{1e3 * per_point['any_C']:.2f} ms ({points['any_C']} points)",
         f"{1e3 * per_point['proportional']:.2f} ms (proportional, {points['proportional']} "
         "points)", per_point["any_C"] / per_point["proportional"], None, None),
        ("one 1-2 backlash solve with that damping matrix",
         f"{1e6 * t['solve_12_any_C']:.0f} us",
         f"{1e6 * t['solve_12_proportional']:.0f} us (proportional)",
         t["solve_12_any_C"] / t["solve_12_proportional"], None, 2.0),
    ]
    lines = ["| work | measured | compiled reference | ratio | target | met? |",
             "|---|---|---|---|---|---|"]
    for name, meas, ref, ratio, per_impact, target in rows:
        shown = f"{ratio:.1f}x" + (f" ({per_impact:.1f}x per impact)" if per_impact else "")
        judged = per_impact if per_impact is not None else ratio
        if target is None:  # measured, no target of its own
            lines.append(f"| {name} | {meas} | {ref} | {shown} | - | |")
            continue
        lines.append(f"| {name} | {meas} | {ref} | {shown} | <= {target:g}x | "
                     f"{'yes' if judged <= target else '**no**'} |")
    lines.append(f"| that branch: without detection; the core's `follow` alone (no orbits, no "
                 f"dataset) | {1e3 * t['branch_12_no_detection'] / points['12']:.2f} ms; "
                 f"{1e3 * t['branch_12_core'] / points['12']:.2f} ms per point | "
                 f"{1e3 * per_point['n1']:.2f} ms | "
                 f"{t['branch_12_no_detection'] / points['12'] / per_point['n1']:.1f}x; "
                 f"{t['branch_12_core'] / points['12'] / per_point['n1']:.1f}x | - | |")
    bp_ms = 1e3 * per_point["bp"]
    lines.append(f"| BP curve of the symmetric 1-2 backlash motion in (omega, b), per point | "
                 f"{bp_ms:.2f} ms ({points['bp']} points) | {1e3 * per_point['pd_n1']:.2f} ms "
                 f"(N = 1 PD curve, closed form, {points['pd_n1']} points) | "
                 f"{per_point['bp'] / per_point['pd_n1']:.1f}x | <= 2 ms | "
                 f"{'yes' if bp_ms <= 2.0 else '**no**'} |")
    lines.append(f"| cold compile added by the shooting kernel (empty cache, after the N = 1 "
                 f"continuation and orbits) | first N-p solve {cold['np_solve']:.1f} s, first "
                 f"N-p continuation {cold['np_continuation']:.1f} s CPU | N = 1 branch and "
                 f"orbits (their own compile) {cold['n1_verbs']:.1f} s | | | |")
    lines.append(f"| cold compile added by the any-C kernel (empty cache, after the N = 1 "
                 f"continuation and orbits) | first any-C orbit {cold_any_c['any_C_orbit']:.1f} s "
                 f"CPU | N = 1 branch and orbits {cold_any_c['n1_verbs']:.1f} s | | | |")
    table = "\n".join(lines)
    res_out["table"] = table
    out = HERE / "output" / "np_motions.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(res_out, indent=1))
    print(table)
    return res_out


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    logging.getLogger("impactcont").setLevel(logging.WARNING)
    main()
