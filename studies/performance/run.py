"""Performance of the compiled kernel (``impactcont.kernel.closed_form``), side by side in one run.

The machine is shared and noisy, so every number is the best of several repeats
and every reference is timed in the same run. BLAS is pinned to one thread
(``threadpoolctl.threadpool_limits(1)``) except in the thread comparison.

Measured:

1. first call: ``periodic_orbits`` in a fresh interpreter with an empty
   ``NUMBA_CACHE_DIR`` (cold compile) and again with the filled one (on-disk
   cache); ``python -c "import impactcont"`` (the import compiles nothing);
2. one n = 2 orbit of the paper system (N = 1, 2: both roots with state, G,
   multipliers, checks) against ``solve_ivp`` DOP853 shooting of the N = 1 motion
   (``studies/accuracy_vs_runtime/shooting.py``) to about 1e-10;
3. the (N, omega, b) stability map, with and without the spectral radius, against
   one batched ``np.linalg.eigvals`` of as many 4 x 4 matrices as map points;
4. one branch in omega with its special points, against one shooting solve;
5. the PD curve in (omega, b), time per curve point (with a profile);
6. the cost against n for chains, against one dense ``eigvals`` of a 2n x 2n matrix, and
   one orbit's multipliers by the secular function against G and LAPACK's eigenvalues of
   it (the two paths ``orbit.secular.SECULAR_MIN`` chooses between), interleaved rounds;
7. the n = 2 orbit and the map again with two BLAS threads.

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python studies/performance/run.py [--quick | --cost-vs-n]

``--quick`` shrinks the map to 40 x 40, the chains to n <= 20 and the repeats
(about 35 s, half of it the cold compile). Writes ``output/results.json``,
``output/table.md`` (the README's table) and ``figures/cost_vs_n.png`` next to this file;
``--quick`` writes all three to ``output/quick/`` instead. ``--cost-vs-n`` runs 6. alone
(n = 2 ... 200, about 2 min) into ``output/cost_vs_n/`` and the figure.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import logging
import os
import platform
import pstats
import subprocess
import sys
import tempfile
import time
import timeit
from collections.abc import Callable
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import numba
import numpy as np
import scipy
from threadpoolctl import threadpool_info, threadpool_limits

import impactcont as ic

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT / "studies" / "accuracy_vs_runtime"))
import shooting  # noqa: E402

log = logging.getLogger("performance")
BUDGET = 0.1  # seconds per timing round (--quick: 0.02)

CHILD = """
import json, sys, time
t0 = time.perf_counter()
import numpy as np
import impactcont as ic
t1 = time.perf_counter()
compiled_on_import = "numba" in sys.modules or "impactcont.kernel.closed_form" in sys.modules
from numba.core import event
compiles = []
class Count(event.Listener):
    def on_start(self, ev):
        compiles.append(1)
    def on_end(self, ev):
        pass
event.register("numba:compile", Count())  # the import of numba counts in the first call
osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                          b=0.6, omega=1.0, eta=0.1)
orbits = ic.periodic_orbits(osc, 1)
t2 = time.perf_counter()
[o.multipliers for o in orbits]
t3 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "periodic_orbits": t2 - t1, "multipliers": t3 - t2,
                  "compiled_on_import": compiled_on_import, "compilations": len(compiles)}))
"""


def paper() -> ic.ImpactOscillator:
    """The paper's two-mass example (the same system as in ``CHILD``)."""
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.6, omega=1.0, eta=0.1)


def chain(n: int) -> ic.ImpactOscillator:
    F = np.zeros(n)
    F[0] = 1.0
    return ic.ImpactOscillator.chain(masses=np.ones(n), springs=np.ones(n), F=F, R=0.7, b=0.1,
                                     omega=1.1, eta=0.05)


def best(fn: Callable[[], Any], repeat: int) -> float:
    """Best time per call over ``repeat`` rounds of about ``BUDGET`` seconds (>= 1 call each)."""
    start = time.perf_counter()
    fn()  # also the warm-up
    number = max(1, int(BUDGET / max(time.perf_counter() - start, 1e-7)))
    return min(timeit.repeat(fn, number=number, repeat=repeat)) / number


def profile_top(fn: Callable[[], Any], k: int = 8) -> dict[str, Any]:
    """Own time of all functions and the ``k`` largest, from one profiled call of ``fn``."""
    prof = cProfile.Profile()
    prof.runcall(fn)
    stats = pstats.Stats(prof).stats
    rows = sorted(stats.items(), key=lambda kv: -kv[1][2])[:k]
    return {"total": sum(v[2] for v in stats.values()),
            "top": [{"function": f"{Path(f).name}:{line}({name})", "calls": nc, "tottime": tt,
                     "cumtime": ct} for (f, line, name), (_, nc, tt, ct, _) in rows]}


def git(*args: str) -> str:
    """Read-only git query (records which code was timed)."""
    return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True).stdout.strip()


# -- 1. first call --------------------------------------------------------------------------------
def first_call(repeat: int) -> dict[str, Any]:
    def child(cache: str) -> dict[str, Any]:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        start = time.perf_counter()
        run = subprocess.run([sys.executable, "-c", CHILD], env=env, cwd=ROOT,
                             capture_output=True, text=True)
        if run.returncode:
            raise RuntimeError(f"first-call child failed:\n{run.stderr[-3000:]}")
        return {**json.loads(run.stdout.splitlines()[-1]), "wall": time.perf_counter() - start}

    cold, cached = [], []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as cache:
            cold.append(child(cache))
            cached.append(child(cache))
    start_import = [[sys.executable, "-c", "import impactcont"], [sys.executable, "-c", "pass"]]
    walls = [best(lambda cmd=cmd: subprocess.run(cmd, cwd=ROOT, check=True), repeat)
             for cmd in start_import]
    pick = {"cold": min(cold, key=lambda r: r["periodic_orbits"]),
            "cached": min(cached, key=lambda r: r["periodic_orbits"])}
    return {**pick, "python_import_impactcont_wall": walls[0], "python_pass_wall": walls[1],
            "compiled_on_import": any(r["compiled_on_import"] for r in cold + cached)}


# -- 2. one n = 2 orbit --------------------------------------------------------------------------
def one_orbit(osc: ic.ImpactOscillator, N: int) -> None:
    for o in ic.periodic_orbits(osc, N):
        o.state, o.G, o.multipliers, o.physical  # noqa: B018 - the access is the work


def kernel_only(osc: ic.ImpactOscillator, N: int) -> None:
    """The compiled calls of :func:`one_orbit` without the Python wrapper (as in periodic.py)."""
    from impactcont.kernel import closed_form
    from impactcont.orbit.periodic import modal_arrays

    # for small systems one call returns the roots with their G and multipliers
    closed_form.point_orbits(modal_arrays(osc).as_tuple(), osc.R, osc.omega, N, osc.b)


def orbit_n2(repeat: int) -> dict[str, Any]:
    osc = paper()
    out: dict[str, Any] = {}
    for N in (1, 2):
        out[f"N{N}"] = {"closed_form": best(lambda N=N: one_orbit(osc, N), 3 * repeat),
                        "kernel_calls_only": best(lambda N=N: kernel_only(osc, N), 3 * repeat),
                        "physical_roots": sum(o.physical for o in ic.periodic_orbits(osc, N))}
    # shooting of the physical N = 1 motion, from the closed form perturbed by 1e-3
    orbit = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    z_true = np.append(orbit.state[1:], orbit.delta)
    z0 = z_true + 1e-3 * np.random.default_rng(1).standard_normal(z_true.size)
    scale = max(1.0, float(np.abs(z_true).max()))
    for rtol in (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12):  # the loosest that agrees
        P = shooting.ImpactMap(osc, 1, "DOP853", rtol)
        z, mu = shooting.shoot(P, z0)
        deviation = float(np.abs(z - z_true).max()) / scale
        if deviation <= 3e-10:
            break
    evaluations = P.evaluations  # of one solve with its multipliers
    t = best(lambda P=P: shooting.shoot(P, z0), max(2, repeat // 2))
    out["shooting_N1"] = {"time": t, "rtol": rtol, "orbit_deviation": deviation,
                          "multiplier_deviation": float(np.abs(mu - orbit.multipliers).max()),
                          "map_evaluations_per_solve": evaluations,
                          "ratio_to_closed_form": t / out["N1"]["closed_form"]}
    return out


# -- 3. the (N, omega, b) map ----------------------------------------------------------------------
def stability_map(size: int, repeat: int) -> dict[str, Any]:
    osc = paper()
    omega, b = np.linspace(0.5, 6.0, size), np.linspace(-1.0, 1.5, size)
    points = 4 * size * size
    out: dict[str, Any] = {"grid": [4, size, size], "points": points}
    for rho in (False, True):
        def run(rho=rho):
            return ic.stability_map(osc, [1, 2, 3, 4], omega, b, spectral_radius=rho)

        t = best(run, repeat)
        out[f"spectral_radius_{rho}"] = {"time": t, "points_per_s": points / t,
                                         "profile": profile_top(run, 4)}
    stack = np.random.default_rng(2).standard_normal((points, 4, 4))
    t_eig = best(lambda: np.linalg.eigvals(stack), repeat)
    out["batched_eigvals_4x4"] = {"time": t_eig, "points_per_s": points / t_eig}
    for rho in (False, True):
        out[f"spectral_radius_{rho}"]["fraction_of_eigvals"] = (
            out[f"spectral_radius_{rho}"]["time"] / t_eig)
    return out


# -- 4. branch and 5. codim-1 curve ----------------------------------------------------------------
def branch_and_curve(repeat: int, shooting_time: float) -> tuple[dict, dict]:
    osc = paper()

    def branch():
        # the component through the start, as the issue measured it (components="all", the
        # default, also follows the second root's branch at b = 0)
        return ic.continuation(osc.replace(b=0.0), N=1, parameter="omega", bounds=(0.5, 6.0),
                               components="start")

    br = branch()
    t_br = best(branch, repeat)
    specials = [{"label": str(lab), "omega": float(w), "precision": float(p), "status": str(s)}
                for lab, w, p, s in zip(br.special_label.values, br.special_omega.values,
                                        br.special_precision.values, br.special_status.values,
                                        strict=True)]
    branch_out = {"time": t_br, "points": br.sizes["point"], "special_points": specials,
                  "time_per_point": t_br / br.sizes["point"],
                  "ratio_shooting_one_orbit_to_branch": shooting_time / t_br,
                  "profile": profile_top(branch)}

    box = {"omega": (0.6, 2.0), "b": (-0.2, 1.2)}

    def pd_curve():
        return ic.curve(osc, None, "PD", start=br, bounds=box)

    c = pd_curve()
    t_c = best(pd_curve, max(2, repeat // 2))
    curve_out = {"time": t_c, "points": c.sizes["point"], "time_per_point": t_c / c.sizes["point"],
                 "codim2_points": int(c.sizes.get("codim2", 0)), "profile": profile_top(pd_curve)}
    # every other kind from the b = 0.5 branch (its SN, NS, GR and ZV points)
    at_half = ic.continuation(osc.replace(b=0.5), N=1, parameter="omega", bounds=(0.5, 6.0))
    kinds = {}
    for kind in ("SN", "NS", "GR", "ZV"):
        def run(kind=kind):
            return ic.curve(osc.replace(b=0.5), None, kind, start=at_half, bounds=box)

        c = run()
        t = best(run, max(2, repeat // 2))
        kinds[kind] = {"time": t, "points": c.sizes["point"],
                       "time_per_point": t / c.sizes["point"],
                       "codim2_points": int(c.sizes.get("codim2", 0))}
    curve_out["other_kinds"] = kinds
    return branch_out, curve_out


# -- 6. cost against n -----------------------------------------------------------------------------
def _matched_distance(mu: np.ndarray, reference: np.ndarray) -> float:
    """Largest distance from a multiplier of either set to the nearest of the other."""
    d = np.abs(mu[:, None] - reference[None, :])
    return float(max(d.min(axis=0).max(), d.min(axis=1).max()))


def interleaved_best(fns: list[Callable[[], Any]], repeat: int) -> list[float]:
    """Best time per call of each of ``fns`` over ``repeat`` rounds, the functions taking
    turns within each round (the machine's noise falls on all alike)."""
    numbers = []
    for fn in fns:
        start = time.perf_counter()
        fn()  # also the warm-up
        numbers.append(max(1, int(BUDGET / max(time.perf_counter() - start, 1e-7))))
    out = [np.inf] * len(fns)
    for _ in range(repeat):
        for i, (fn, number) in enumerate(zip(fns, numbers, strict=True)):
            out[i] = min(out[i], timeit.timeit(fn, number=number) / number)
    return out


def cost_vs_n(sizes: tuple[int, ...], repeat: int) -> list[dict[str, Any]]:
    from impactcont.kernel import stability
    from impactcont.orbit import secular
    from impactcont.orbit.periodic import modal_arrays, modal_jacobian

    rng = np.random.default_rng(3)
    rows = []
    for n in sizes:
        osc = chain(n)

        def orbits(osc=osc):
            return ic.periodic_orbits(osc, 1)

        def with_g():
            return [o.G for o in orbits()]

        def with_mult():
            return [(o.G, o.spectral_radius, o.multipliers[0]) for o in orbits()]

        def with_dense_mult():  # the path below secular.SECULAR_MIN: eigenvalues of G
            return [stability.multipliers(o.G) for o in orbits()]

        roots = len(with_mult())  # compiles and computes the modal basis once
        with_dense_mult()
        A = rng.standard_normal((2 * n, 2 * n))
        G = orbits()[0].G
        row = {"n": n, "roots": roots,
               "orbits": best(orbits, repeat), "orbits_G": best(with_g, repeat),
               "orbits_G_multipliers": best(with_mult, repeat),
               "orbits_G_dense_multipliers": best(with_dense_mult, repeat),
               "dense_eigvals_2n": best(lambda A=A: np.linalg.eigvals(A), repeat),
               "numpy_eigvals_of_G": best(lambda G=G: np.linalg.eigvals(G), repeat)}
        row["per_orbit_G_multipliers"] = row["orbits_G_multipliers"] / roots
        # the two ways to the multipliers of one orbit, side by side (what SECULAR_MIN
        # chooses between): the secular function (numpy, G not formed) against G and
        # LAPACK's eigenvalues of it
        first = orbits()[0]
        arrays = modal_arrays(osc)
        args = (first.modal, arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0, osc.omega,
                osc.R, first.delta, first.impact_velocity)
        row["secular_accepted"] = bool(secular.secular_multipliers(*args)[1])
        row["secular_alone"], row["G_and_lapack_alone"] = interleaved_best(
            [lambda args=args: secular.secular_multipliers(*args),
             lambda osc=osc, o=first: stability.multipliers(
                 modal_jacobian(osc, o.modal, o.delta, o.impact_velocity)[0])],
            max(repeat, 7))
        row["secular_over_dense"] = row["secular_alone"] / row["G_and_lapack_alone"]
        # the multipliers reported (secular from SECULAR_MIN on) against LAPACK's of G
        row["multipliers_vs_dense"] = max(
            _matched_distance(o.multipliers, stability.multipliers(o.G))
            / max(1.0, abs(o.multipliers[0])) for o in orbits())
        row["secular"] = n >= secular.SECULAR_MIN
        rows.append(row)
        log.info("n=%3d: orbits %.3g ms, +G %.3g ms, +multipliers %.3g ms (%d roots); dense "
                 "eigvals(%d x %d) %.3g ms, of G %.3g ms; one orbit's multipliers: secular "
                 "%.3g ms, G + LAPACK %.3g ms", n, 1e3 * row["orbits"],
                 1e3 * row["orbits_G"], 1e3 * row["orbits_G_multipliers"], roots, 2 * n, 2 * n,
                 1e3 * row["dense_eigvals_2n"], 1e3 * row["numpy_eigvals_of_G"],
                 1e3 * row["secular_alone"], 1e3 * row["G_and_lapack_alone"])
    return rows


def cost_figure(rows: list[dict[str, Any]], width: float = 7.0) -> Any:
    """``cost_vs_n.png``: the time of one N = 1 call for a chain of ``n`` masses (both
    roots) and of its parts, against one dense ``eigvals`` of a 2n x 2n matrix; the
    target at n = 200 as a star. ``width`` in inches (3.5: one journal column, 7: two);
    one legend under the axes, off the data."""
    from impactcont.plots.series import (
        Series,
        figure_legend,
        fit_labels,
        panel_figure,
        series_plot,
    )

    n = np.array([r["n"] for r in rows], dtype=float)
    fig, (ax,) = panel_figure(1, width, extra_height=2.2 if width < 5.0 else 1.4)
    series = []
    for i, (key, label, ls) in enumerate((
            ("orbits", "periodic_orbits (both roots)", "-"),
            ("orbits_G", "+ $G$", "-"),
            ("orbits_G_multipliers", "+ multipliers, spectral radius", "-"),
            ("per_orbit_G_multipliers", "the same per orbit (call / roots)", ":"),
            ("orbits_G_dense_multipliers", "+ $G$, multipliers by LAPACK from $G$", "-"),
            ("dense_eigvals_2n", "one eigvals of a random $2n \\times 2n$ matrix", "--"),
            ("secular_alone", "one orbit's multipliers, secular function", "-."),
            ("G_and_lapack_alone", "one orbit's multipliers, $G$ + LAPACK", "-."))):
        series.append(Series(n, [1e3 * r[key] for r in rows], label, color=f"C{i}",
                             linestyle=ls, marker="o", markersize=3))
    series.append(Series([200.0], [50.0], "target at $n = 200$ (50 ms per orbit)",
                         color="k", linestyle="none", marker="*", markersize=8, filled=True))
    series_plot(ax, series, xlabel="degrees of freedom $n$",
                ylabel="time per call $t$ [ms] (best of repeats)", xscale="log",
                yscale="log", title="One $N = 1$ call for a chain, both roots, 1 BLAS thread")
    ax.grid(True, which="both", alpha=0.3)
    figure_legend(fig)
    fit_labels(fig)
    return fig


def plot(rows: list[dict[str, Any]], path: Path) -> None:
    fig = cost_figure(rows)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)


# -- 7. BLAS threads -------------------------------------------------------------------------------
def blas_threads(size: int, repeat: int) -> dict[str, Any]:
    """The n = 2 orbit and the map with 1 and 2 BLAS threads, rounds interleaved (same noise)."""
    osc = paper()
    omega, b = np.linspace(0.5, 6.0, size), np.linspace(-1.0, 1.5, size)
    work = {"orbit_N1": lambda: one_orbit(osc, 1),
            "map_spectral_radius": lambda: ic.stability_map(osc, [1, 2, 3, 4], omega, b)}
    times: dict[str, list[float]] = {f"{k}_{th}": [] for k in work for th in (1, 2)}
    threads = {}
    for _ in range(repeat):
        for th in (1, 2):
            with threadpool_limits(th):
                threads[th] = sorted({lib["num_threads"] for lib in threadpool_info()})
                for k, fn in work.items():
                    times[f"{k}_{th}"].append(best(fn, 1))
    out: dict[str, Any] = {k: min(v) for k, v in times.items()}
    out["blas_threads"] = threads
    for k in work:
        out[f"ratio_{k}_2_to_1"] = out[f"{k}_2"] / out[f"{k}_1"]
    return out


# -- the table of the README -----------------------------------------------------------------------
def table(res: dict[str, Any]) -> str:
    """The README's table from one run: work | measured | target | met? | reference."""
    fc, o, m, br, cu, bt = (res[k] for k in ("first_call", "orbit_n2", "map", "branch", "curve",
                                             "blas_threads"))
    sh, big = o["shooting_N1"], res["cost_vs_n"][-1]
    cold, cached = fc["cold"], fc["cached"]
    nf, nt = m["spectral_radius_False"], m["spectral_radius_True"]
    per_orbit = big["per_orbit_G_multipliers"]
    specials = ", ".join(f"{p['label']} omega={p['omega']:.10f} ({p['status']}, precision "
                         f"{p['precision']:.1e})" for p in br["special_points"])
    rows = [
        ("first call, empty cache (`periodic_orbits`)", f"{cold['periodic_orbits']:.1f} s",
         "<= 10 s", cold["periodic_orbits"] <= 10,
         f"+{cold['multipliers']:.1f} s at the first `multipliers`; whole subprocess "
         f"{cold['wall']:.1f} s; {cold['compilations']} numba compilations (kernel functions "
         "and numba's own array helpers)"),
        ("first call, from the disk cache", f"{cached['periodic_orbits']:.2f} s", "<= 1 s",
         cached["periodic_orbits"] <= 1, f"+{cached['multipliers']:.3f} s `multipliers`; "
         f"whole subprocess {cached['wall']:.2f} s"),
        ("`import impactcont`", f"{cached['import']:.2f} s (`python -c`: "
         f"{fc['python_import_impactcont_wall']:.2f} s)", "compiles nothing",
         not fc["compiled_on_import"], f"numba not imported; `python -c pass` "
         f"{fc['python_pass_wall']:.2f} s"),
        ("one n = 2 orbit, N = 1 (both roots, state, G, multipliers, physical)",
         f"{1e6 * o['N1']['closed_form']:.1f} us", "<= 20 us", o["N1"]["closed_form"] <= 20e-6,
         f"shooting DOP853 rtol {sh['rtol']:g} (deviation {sh['orbit_deviation']:.1e}) "
         f"{1e3 * sh['time']:.0f} ms: ratio {sh['ratio_to_closed_form']:.0f} (target >= 1500: "
         f"{'met' if sh['ratio_to_closed_form'] >= 1500 else 'missed'}); kernel calls alone "
         f"{1e6 * o['N1']['kernel_calls_only']:.1f} us"),
        ("one n = 2 orbit, N = 2", f"{1e6 * o['N2']['closed_form']:.1f} us", "<= 20 us",
         o["N2"]["closed_form"] <= 20e-6, f"kernel calls alone "
         f"{1e6 * o['N2']['kernel_calls_only']:.1f} us; no physical N = 2 motion here, "
         "so no shooting reference"),
        (f"map {' x '.join(map(str, m['grid']))}, no spectral radius",
         f"{nf['points_per_s']:.2e} points/s", ">= 1e6 points/s", nf["points_per_s"] >= 1e6,
         f"one batched `eigvals` of {m['points']} 4 x 4: {m['batched_eigvals_4x4']['time']:.2f} "
         f"s ({m['batched_eigvals_4x4']['points_per_s']:.2e} matrices/s)"),
        ("the same map against one batched 4 x 4 `eigvals` per point",
         f"map / eigvals = {nf['fraction_of_eigvals']:.2f}", "<= 0.5",
         nf["fraction_of_eigvals"] <= 0.5, "the issue's \"at most half the cost of one "
         "batched 4 x 4 eigvals per point\", timed in the same run"),
        ("the same map with the spectral radius", f"{nt['points_per_s']:.2e} points/s",
         ">= 3e5 points/s", nt["points_per_s"] >= 3e5,
         f"map / eigvals = {nt['fraction_of_eigvals']:.2f}"),
        ("omega-branch, b = 0, N = 1, with special points",
         f"{1e3 * br['time']:.1f} ms ({br['points']} points)", "<= 50 ms", br["time"] <= 0.05,
         f"one shooting solve {1e3 * sh['time']:.0f} ms = "
         f"{br['ratio_shooting_one_orbit_to_branch']:.1f} x the branch; {specials}"),
        ("PD curve in (omega, b)", f"{1e3 * cu['time_per_point']:.2f} ms per point "
         f"({cu['points']} points, {cu['time']:.2f} s)", "<= 1 ms per point",
         cu["time_per_point"] <= 1e-3, f"{cu['codim2_points']} codim-2 points located on it; "
         "exact Jacobians (complex steps)"),
        ("SN, NS, GR, ZV curves in (omega, b)", ", ".join(
            f"{k} {1e3 * v['time_per_point']:.2f}" for k, v in cu["other_kinds"].items())
         + " ms per point", "<= 1 ms per point",
         all(v["time_per_point"] <= 1e-3 for v in cu["other_kinds"].values()),
         "; ".join(f"{k}: {v['points']} points, {v['codim2_points']} codim-2"
                   for k, v in cu["other_kinds"].items())),
        (f"n = {big['n']} chain: orbit + G + spectral radius + critical multiplier",
         f"{1e3 * per_orbit:.1f} ms per orbit ({1e3 * big['orbits_G_multipliers']:.1f} ms "
         f"for both roots)", "<= 50 ms and < one dense `eigvals` of 2n x 2n",
         (per_orbit <= 0.05 and per_orbit < big["dense_eigvals_2n"]) if big["n"] == 200 else None,
         f"dense `eigvals` {2 * big['n']} x {2 * big['n']}: {1e3 * big['dense_eigvals_2n']:.1f}"
         f" ms; numpy `eigvals` of this G {1e3 * big['numpy_eigvals_of_G']:.1f} ms; orbit "
         f"alone {1e3 * big['orbits']:.2f} ms, + G {1e3 * big['orbits_G']:.2f} ms"),
        ("2 BLAS threads against 1 (n = 2 orbit, map with spectral radius)",
         f"x{bt['ratio_orbit_N1_2_to_1']:.2f}, x{bt['ratio_map_spectral_radius_2_to_1']:.2f}",
         "no dependence (within 10 %)", all(abs(bt[k] - 1) < 0.1 for k in ("ratio_orbit_N1_2_to_1",
                                                             "ratio_map_spectral_radius_2_to_1")),
         "rounds interleaved"),
    ]
    lines = ["| work | measured | target | met? | ratio / side-by-side reference |",
             "|---|---|---|---|---|"]
    lines += [f"| {w} | {v} | {t} | {'n/a' if ok is None else 'yes' if ok else '**no**'} | {r}"
              f"{'' if ok in (True, None) else '; see Notes'} |" for w, v, t, ok, r in rows]
    return "\n".join(lines) + "\n\n" + cost_table(res["cost_vs_n"])


def cost_table(rows: list[dict[str, Any]]) -> str:
    """The README's "Cost against n" table (times in ms)."""
    lines = ["| n | `periodic_orbits` (ms, both roots) | + G | + multipliers, spectral radius "
             "| that per orbit | + G and LAPACK multipliers of G | one dense `eigvals`, 2n x 2n "
             "| numpy `eigvals` of one G | one orbit's multipliers: secular | the same: G + "
             "LAPACK | secular / (G + LAPACK) | multipliers | max distance to LAPACK's "
             "(relative) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    lines += ["| {n} | {orbits:.3g} | {orbits_G:.3g} | {orbits_G_multipliers:.3g} | "
              "{per_orbit_G_multipliers:.3g} | {orbits_G_dense_multipliers:.3g} | "
              "{dense_eigvals_2n:.3g} | {numpy_eigvals_of_G:.3g} | {secular_alone:.3g} | "
              "{G_and_lapack_alone:.3g} | {ratio:.2f} | {how} | {distance:.1e} |"
              .format(**{k: 1e3 * v for k, v in r.items() if isinstance(v, float)
                         and k not in ("multipliers_vs_dense", "secular_over_dense")},
                      n=r["n"], ratio=r["secular_over_dense"],
                      how="secular" if r["secular"] else "in-kernel QR" if r["n"] <= 8
                      else "LAPACK", distance=r["multipliers_vs_dense"])
              for r in rows]
    return "\n".join(lines) + "\n"


def main() -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes, fewer repeats")
    parser.add_argument("--cost-vs-n", action="store_true",
                        help="only the cost against n (6.): output/cost_vs_n/ and the figure")
    parser.add_argument("--figure-from-readme", action="store_true",
                        help="only redraw figures/cost_vs_n.png from the README's cost table")
    args = parser.parse_args()
    global BUDGET
    if args.figure_from_readme:
        plot(rows_from_readme(), HERE / "figures" / "cost_vs_n.png")
        return {}
    if args.cost_vs_n:
        return cost_vs_n_only()
    size, sizes, repeat, BUDGET = ((40, (2, 5, 10, 20), 3, 0.02) if args.quick else
                                   (200, (2, 5, 10, 20, 50, 100, 200), 7, 0.1))
    started = time.perf_counter()
    # the compiled kernel, split by concern (flights, roots, contact, stability, shooting, ...)
    kernel_files = sorted((ROOT / "impactcont" / "kernel").glob("*.py"))
    mtimes = {path: path.stat().st_mtime for path in kernel_files}
    res: dict[str, Any] = {"quick": args.quick, "machine": {
        "python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
        "numba": numba.__version__, "impactcont": ic.__version__, "cpus": os.cpu_count(),
        "loadavg_start": os.getloadavg()}}
    res["first_call"] = first_call(1 if args.quick else 2)
    fc = res["first_call"]
    log.info("first call: cold %.2f s (+%.2f s multipliers), cached %.3f s; import %.3f s "
             "(compiles on import: %s)", fc["cold"]["periodic_orbits"], fc["cold"]["multipliers"],
             fc["cached"]["periodic_orbits"], fc["cached"]["import"], fc["compiled_on_import"])
    with threadpool_limits(1):
        res["orbit_n2"] = orbit_n2(repeat)
        o = res["orbit_n2"]
        log.info("n=2 orbit: N=1 %.2f us (kernel calls %.2f us), N=2 %.2f us; shooting "
                 "(rtol %g, deviation %.1e) %.1f ms, ratio %.0f", 1e6 * o["N1"]["closed_form"],
                 1e6 * o["N1"]["kernel_calls_only"], 1e6 * o["N2"]["closed_form"],
                 o["shooting_N1"]["rtol"], o["shooting_N1"]["orbit_deviation"],
                 1e3 * o["shooting_N1"]["time"], o["shooting_N1"]["ratio_to_closed_form"])
        res["map"] = stability_map(size, max(3, repeat // 2))
        m = res["map"]
        log.info("map %d points: %.3g pts/s without rho, %.3g with; batched eigvals %.3g pts/s",
                 m["points"], m["spectral_radius_False"]["points_per_s"],
                 m["spectral_radius_True"]["points_per_s"],
                 m["batched_eigvals_4x4"]["points_per_s"])
        res["branch"], res["curve"] = branch_and_curve(repeat, o["shooting_N1"]["time"])
        log.info("branch %.1f ms (%d points); PD curve %.2f ms per point (%d points)",
                 1e3 * res["branch"]["time"], res["branch"]["points"],
                 1e3 * res["curve"]["time_per_point"], res["curve"]["points"])
        res["cost_vs_n"] = cost_vs_n(sizes, max(3, repeat // 2))
    res["blas_threads"] = bt = blas_threads(size, max(3, repeat // 2))
    log.info("BLAS threads 2 against 1 (%s): orbit x%.2f, map x%.2f", bt["blas_threads"],
             bt["ratio_orbit_N1_2_to_1"], bt["ratio_map_spectral_radius_2_to_1"])
    res["machine"]["loadavg_end"] = os.getloadavg()
    res["code"] = {"git_head": git("rev-parse", "HEAD"),
                   "uncommitted_in_impactcont": git("status", "--porcelain", "impactcont"),
                   "kernel_changed_during_run": sorted(
                       path.name for path, mtime in mtimes.items()
                       if not path.exists() or path.stat().st_mtime != mtime)}
    res["elapsed_s"] = time.perf_counter() - started
    out = HERE / "output" / ("quick" if args.quick else "") / "results.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(res, indent=1))
    (out.parent / "table.md").write_text(table(res))
    figure = out.parent / "cost_vs_n.png" if args.quick else HERE / "figures" / "cost_vs_n.png"
    plot(res["cost_vs_n"], figure)
    log.info("wrote %s, table.md and %s in %.0f s", out, figure, res["elapsed_s"])
    return res


COST_SIZES = (2, 5, 10, 16, 20, 24, 32, 38, 48, 64, 100, 200)


#: The columns of the README's cost table (`cost_table`), in order: times in ms there.
COST_COLUMNS = ("n", "orbits", "orbits_G", "orbits_G_multipliers", "per_orbit_G_multipliers",
                "orbits_G_dense_multipliers", "dense_eigvals_2n", "numpy_eigvals_of_G",
                "secular_alone", "G_and_lapack_alone")


def rows_from_readme(path: Path = HERE / "README.md") -> list[dict[str, Any]]:
    """The rows of the cost table the README shows (its "Cost against n" section), in the
    units of :func:`cost_vs_n` (seconds), to redraw ``cost_vs_n.png`` from the published
    numbers without timing again (``--figure-from-readme``)."""
    lines = path.read_text().splitlines()
    start = next(i for i, line in enumerate(lines)
                 if line.startswith("| n | `periodic_orbits` (ms, both roots)"))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip("|").split("|")]
        row: dict[str, Any] = {"n": int(cells[0])}
        row |= {k: 1e-3 * float(v) for k, v in zip(COST_COLUMNS[1:], cells[1:], strict=False)}
        rows.append(row)
    if not rows:
        raise ValueError(f"{path}: the cost table has no rows")
    return rows


def cost_vs_n_only() -> dict[str, Any]:
    """Section 6 alone (``--cost-vs-n``): writes ``output/cost_vs_n/results.json``,
    ``output/cost_vs_n/table.md`` and ``figures/cost_vs_n.png``."""
    started = time.perf_counter()
    res: dict[str, Any] = {"machine": {
        "python": platform.python_version(), "numpy": np.__version__, "numba": numba.__version__,
        "impactcont": ic.__version__, "cpus": os.cpu_count(), "loadavg_start": os.getloadavg()}}
    with threadpool_limits(1):
        res["cost_vs_n"] = cost_vs_n(COST_SIZES, 7)
    res["machine"]["loadavg_end"] = os.getloadavg()
    res["code"] = {"git_head": git("rev-parse", "HEAD"),
                   "uncommitted_in_impactcont": git("status", "--porcelain", "impactcont")}
    res["elapsed_s"] = time.perf_counter() - started
    out = HERE / "output" / "cost_vs_n" / "results.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(res, indent=1))
    (out.parent / "table.md").write_text(cost_table(res["cost_vs_n"]))
    plot(res["cost_vs_n"], HERE / "figures" / "cost_vs_n.png")
    log.info("wrote %s and table.md in %.0f s", out, res["elapsed_s"])
    return res


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    logging.getLogger("impactcont").setLevel(logging.WARNING)
    main()
