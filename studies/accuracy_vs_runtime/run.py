"""Work-precision study: impactcont's closed form against scipy shooting and brute force.

For chains of n = 2, 10 and 50 degrees of freedom this measures, side by side
in one run, error against run time of

1. one periodic N-1 motion with its multipliers, by
   (a) impactcont's closed form (``periodic_orbits``: eq. 13-16, G of eq. 25),
   (b) shooting: Newton on the impact map integrated by ``scipy.integrate.solve_ivp``
       (RK45, DOP853, Radau) with a terminal impact event, over a range of tolerances,
       multipliers from a central-difference Jacobian of the map,
   (c) brute force: simulating until the motion settles (``impactcont.simulate``, exact
       flow; and iterating the solve_ivp impact map);
2. the location of one period-doubling (PD) and one grazing (GR) point in omega, by
   (a) the closed form with Brent's method on ``det(G + I)`` / ``gap_min`` (and, as a
       record, ``impactcont.continuation`` over the bracket),
   (b) the same Brent iteration on the shooting orbits,
   (c) brute force: bisection in omega on what the settled simulated motion looks like.

The truth is the 50-digit mpmath evaluation of the closed form in
``tests/reference_mp.py`` (written from the equations, no impactcont code), cached
in ``output/reference_cache.json``. Run::

    .venv/bin/python studies/accuracy_vs_runtime/run.py [--output DIR] [--quick]

``--quick`` keeps n = 2 and 10 and fewer tolerances (a few minutes). Writes
``results.json``, ``table.md``, ``work_precision_orbit.png`` and
``work_precision_location.png`` to the output directory and copies the figures to
``figures/``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # shared 2-core machine: no BLAS threads
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import json
import logging
import math
import shutil
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import mpmath
import numpy as np
from matplotlib.figure import Figure
from scipy.optimize import brentq

import impactcont as ic
from impactcont.plots.series import (
    Series,
    figure_legend,
    fit_labels,
    panel_figure,
    series_plot,
)

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parents[1] / "tests"))
import reference_mp as ref  # noqa: E402
import shooting  # noqa: E402

log = logging.getLogger("accuracy_vs_runtime")

DEFAULT_OUTPUT = HERE / "output"
FIGURES_DIR = HERE / "figures"
METHODS = ("RK45", "DOP853", "Radau")
TWO_PI = 2 * math.pi


# -- systems ----------------------------------------------------------------------------------
def system(n: int) -> ic.ImpactOscillator:
    """n = 2: the paper's example at b = 0; otherwise a uniform chain forced on mass 1."""
    if n == 2:
        return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                                   R=0.6, b=0.0, omega=1.2, eta=0.1)
    F = np.zeros(n)
    F[0] = 1.0
    # n = 50 with eta = 0.02 has no stable N = 1 motion, and its unstable one (rho = 33,
    # impact velocity 0.06 against velocities of 1.5) defeats finite-difference shooting
    eta = 0.02 if n <= 10 else 0.2
    return ic.ImpactOscillator.chain(masses=np.ones(n), springs=np.ones(n), F=F, R=0.6, b=0.0,
                                     omega=1.2, eta=eta)


def stable_orbit(osc: ic.ImpactOscillator) -> ic.PeriodicOrbit:
    """A physical N = 1 motion, stable if there is one: omega scanned down from 1.2."""
    physical = None
    for omega in np.arange(1.2, 0.3, -0.05):
        o = osc.replace(omega=float(omega))
        orbits = [p for p in ic.periodic_orbits(o, 1) if p.physical]
        good = [p for p in orbits if p.stable]
        if good:
            return good[0]
        physical = physical or (orbits[0] if orbits else None)
    if physical is None:
        raise RuntimeError(f"no physical N=1 motion for n={osc.n}")
    log.warning("n=%d: no stable N=1 motion found; using the unstable one at omega=%g "
                "(brute force cannot converge to it)", osc.n, physical.oscillator.omega)
    return physical


def section(orbit_state: np.ndarray, delta: float) -> np.ndarray:
    return np.concatenate([orbit_state[1:], [delta]])


# -- reference (cached) -------------------------------------------------------------------------
class ReferenceCache:
    """50-digit truths, keyed by a readable name, kept in a JSON file between runs."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.data: dict[str, Any] = json.loads(path.read_text()) if path.exists() else {}

    def get(self, key: str, compute: Callable[[], Any]) -> Any:
        if key not in self.data:
            t0 = time.perf_counter()
            self.data[key] = compute()
            log.info("reference %s computed in %.1f s", key, time.perf_counter() - t0)
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.path.write_text(json.dumps(self.data, indent=1))
        return self.data[key]


def mp_system(osc: ic.ImpactOscillator) -> ref.MPSystem:
    return ref.MPSystem(osc.M, osc.K, osc.F, osc.R, osc.b, *osc.rayleigh)


def reference_orbit(osc: ic.ImpactOscillator, root: int) -> dict[str, Any]:
    out = ref.to_float(ref.closed_form(mp_system(osc), osc.omega, 1, roots=(root,), gap=False))
    orbit = out["orbits"][0]
    mu = orbit["multipliers"]
    return {"delta": orbit["delta"], "state": orbit["state"].tolist(),
            "multipliers": [[z.real, z.imag] for z in mu], "cond": out["cond"]}


def reference_pd(osc: ic.ImpactOscillator, root: int, guess: float) -> float:
    system_mp = mp_system(osc)

    def f(omega: Any) -> Any:
        o = ref.closed_form(system_mp, omega, 1, roots=(root,), multipliers=False, gap=False)
        G = o["orbits"][0]["G"]
        return mpmath.det(G + mpmath.eye(G.rows))

    with mpmath.workdps(50):
        return float(mpmath.findroot(f, (mpmath.mpf(guess), mpmath.mpf(guess) * (1 + 1e-6)),
                                     solver="secant", tol=mpmath.mpf(10) ** -40))


def reference_gr(osc: ic.ImpactOscillator, root: int, guess: float, t_guess: float) -> float:
    system_mp = mp_system(osc)
    state = {"t": t_guess}

    def f(omega: Any) -> Any:
        gap, t = ref.gap_near(system_mp, omega, 1, root, state["t"])
        state["t"] = float(t)
        return gap

    with mpmath.workdps(50):
        return float(mpmath.findroot(f, (mpmath.mpf(guess), mpmath.mpf(guess) * (1 + 1e-6)),
                                     solver="secant", tol=mpmath.mpf(10) ** -40))


# -- error measures ------------------------------------------------------------------------------
def orbit_error(z: np.ndarray, truth: dict[str, Any]) -> float:
    """Largest error of the section point, relative to the largest state entry."""
    zt = section(np.array(truth["state"]), truth["delta"])
    d = z - zt
    d[-1] = math.remainder(d[-1], TWO_PI)
    return float(np.abs(d).max() / max(1.0, np.abs(zt).max()))


def multiplier_error(mu: np.ndarray | None, truth: dict[str, Any]) -> float:
    if mu is None:
        return math.nan
    mt = np.array([complex(a, b) for a, b in truth["multipliers"]])
    return ref.matched_error(mu, mt) / max(1.0, float(np.abs(mt).max()))


def timed(fun: Callable[[], Any], repeat: int = 1) -> tuple[Any, float]:
    best, out = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fun()
        best = min(best, time.perf_counter() - t0)
    return out, best


# -- 1. one periodic orbit with its multipliers ------------------------------------------------
def orbit_study(n: int, cache: ReferenceCache, quick: bool) -> dict[str, Any]:
    osc0 = system(n)
    orbit = stable_orbit(osc0)
    osc, root = orbit.oscillator, orbit.root
    truth = cache.get(f"orbit_n{n}_omega{osc.omega:.6f}_root{root}",
                      lambda: reference_orbit(osc, root))
    rows: list[dict[str, Any]] = []

    def closed() -> ic.PeriodicOrbit:
        # a fresh oscillator, so the modal decomposition is part of the measured cost
        fresh = ic.ImpactOscillator(M=osc.M, K=osc.K, F=osc.F, R=osc.R, b=osc.b,
                                    omega=osc.omega, eta=osc.eta)
        return next(o for o in ic.periodic_orbits(fresh, 1) if o.root == root)

    o, t = timed(closed, repeat=5)
    rows.append({"family": "closed form", "method": "impactcont", "tol": None, "time": t,
                 "orbit_error": orbit_error(section(o.state, o.delta), truth),
                 "multiplier_error": multiplier_error(o.multipliers, truth)})
    log.info("n=%d closed form: %.3g s, orbit error %.2e, multipliers %.2e", n, t,
             rows[-1]["orbit_error"], rows[-1]["multiplier_error"])

    rng = np.random.default_rng(1)
    z_true = section(np.array(truth["state"]), truth["delta"])
    # a small start error: n = 50's motion has a low impact velocity, and a 1e-3 kick
    # already misses the stop
    z0 = z_true + 1e-5 * max(1.0, np.abs(z_true).max()) * rng.standard_normal(z_true.size)
    X0 = np.concatenate([[osc.b], z0[:-1]])

    if n <= 10:
        tols = [1e-4, 1e-6, 1e-8, 1e-10, 1e-12] if not quick else [1e-5, 1e-8, 1e-11]
    else:
        tols = [1e-5, 1e-8] if not quick else []
    for method in METHODS:
        for tol in tols:
            if method == "Radau" and (n > 10 or (n == 10 and tol < 1e-10)):
                continue  # n = 10 at 1e-12: 330 s; n = 50: over ten minutes per tolerance
            P = shooting.ImpactMap(osc, 1, method, tol)
            try:
                (z, mu), t = timed(lambda P=P: shooting.shoot(P, z0))
            except shooting.ShootingError as exc:
                log.warning("n=%d %s tol=%g: %s", n, method, tol, exc)
                continue
            rows.append({"family": "shooting", "method": method, "tol": tol, "time": t,
                         "orbit_error": orbit_error(z, truth),
                         "multiplier_error": multiplier_error(mu, truth),
                         "integrations": P.evaluations})
            log.info("n=%d %s tol=%g: %.3g s (%d integrations), orbit %.2e, multipliers %.2e",
                     n, method, tol, t, P.evaluations, rows[-1]["orbit_error"],
                     rows[-1]["multiplier_error"])

    periods = [10, 30, 100, 300] if not quick else [10, 30, 100]
    if n > 10:
        periods = [10, 30, 100]
    for P_count in periods:
        res, t = timed(lambda P_count=P_count: ic.simulate(osc, X0, float(z0[-1]),
                                                           P_count + 0.5))
        if res.impact_states.shape[0] == 0:
            log.warning("n=%d simulate %d periods: no impact (%s)", n, P_count, res.message)
            continue
        z = np.concatenate([res.impact_states[-1][1:], [res.impact_phases[-1]]])
        rows.append({"family": "brute force", "method": "impactcont.simulate",
                     "tol": P_count, "time": t, "orbit_error": orbit_error(z, truth),
                     "multiplier_error": math.nan})
    P = shooting.ImpactMap(osc, 1, "DOP853", 1e-10)
    for count in ([10, 30, 100] if n <= 10 else [10, 30]):
        try:
            z, t = timed(lambda count=count: shooting.iterate(P, z0, count))
        except shooting.ShootingError as exc:  # an unstable motion: iterates run away
            log.warning("n=%d brute force (solve_ivp, %d impacts): %s", n, count, exc)
            continue
        rows.append({"family": "brute force", "method": "solve_ivp DOP853 1e-10",
                     "tol": count, "time": t, "orbit_error": orbit_error(z, truth),
                     "multiplier_error": math.nan})
    return {"n": n, "omega": osc.omega, "root": root, "cond": truth["cond"],
            "spectral_radius": orbit.spectral_radius, "rows": rows}


# -- 2. locating PD and GR ---------------------------------------------------------------------
def find_special(osc: ic.ImpactOscillator, label: str, bounds: tuple[float, float]
                 ) -> tuple[float, int, float, float]:
    """A special point on a physical part of the N = 1 branch: (omega, root, delta, t_gap)."""
    start = osc.replace(omega=0.5 * (bounds[0] + bounds[1]))
    try:
        ds = ic.continuation(start, N=1, parameter="omega", bounds=bounds, detect=(label,),
                             components="start")
    except ic.ImpactcontError as exc:
        # seen with a concurrent version of the continuation core: a corrector iterate left
        # omega > 0; fall back to Brent's method on the closed form over the bracket
        log.warning("continuation failed (%s); bracketing %s directly", exc, label)
        return _bracket_special(osc, label, bounds)
    for i in range(ds.sizes.get("special", 0)):
        sp = ds.isel(special=i)
        if str(sp.special_label.values) != label or str(sp.special_status.values) != "located":
            continue
        w, d = float(sp.special_omega), float(sp.special_delta)
        orbits = ic.periodic_orbits(osc.replace(omega=w), 1)
        o = min(orbits, key=lambda p: abs(math.remainder(p.delta - d, TWO_PI)))
        sides = [min(ic.periodic_orbits(osc.replace(omega=w * (1 + s)), 1),
                     key=lambda p: abs(math.remainder(p.delta - d, TWO_PI)))
                 for s in (-1e-3, 1e-3)]
        if label == "PD":
            usable = o.physical and all(p.physical for p in sides)
        else:
            usable = any(p.physical for p in sides) and all(
                p.impact_velocity > 1e-2 for p in sides)
        if usable:
            return w, o.root, o.delta, o.gap_min_time
    raise RuntimeError(f"no usable {label} in {bounds}")


def _bracket_special(osc: ic.ImpactOscillator, label: str, bounds: tuple[float, float]
                     ) -> tuple[float, int, float, float]:
    grid = np.linspace(bounds[0], bounds[1], 61)
    for root in (1, -1):
        f = closed_test(osc, label, root)
        values = [f(float(w)) for w in grid]
        for k in range(grid.size - 1):
            if np.isfinite(values[k]) and np.isfinite(values[k + 1]) and (
                    values[k] < 0) != (values[k + 1] < 0):
                w = brentq(f, grid[k], grid[k + 1], xtol=1e-13)
                o = pick(ic.periodic_orbits(osc.replace(omega=w), 1), root)
                return w, root, o.delta, o.gap_min_time
    raise RuntimeError(f"no {label} in {bounds}")


def pick(orbits: list[ic.PeriodicOrbit], root: int) -> ic.PeriodicOrbit:
    return next(o for o in orbits if o.root == root)


def closed_test(osc: ic.ImpactOscillator, label: str, root: int) -> Callable[[float], float]:
    def f(w: float) -> float:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ic.IllConditionedWarning)
            o = pick(ic.periodic_orbits(osc.replace(omega=w), 1), root)
        if label == "PD":
            return float(np.prod(o.multipliers + 1.0).real)
        return o.gap_min

    return f


def shooting_test(osc: ic.ImpactOscillator, label: str, method: str, tol: float,
                  z_start: np.ndarray) -> Callable[[float], float]:
    state = {"z": z_start.copy()}

    def f(w: float) -> float:
        P = shooting.ImpactMap(osc.replace(omega=w), 1, method, tol)
        z, _ = shooting.shoot(P, state["z"], multipliers=False)
        state["z"] = z
        if label == "PD":
            J = shooting.jacobian(P, z, central=True)
            return float(np.linalg.det(J + np.eye(z.size)))
        return P.gap_min(z)

    return f


def settled_pattern(osc: ic.ImpactOscillator, X: np.ndarray, delta: float, periods: int,
                    label: str) -> tuple[bool, np.ndarray, float]:
    """Simulate ``periods`` forcing periods; True when the N = 1 motion is still what settles."""
    res = ic.simulate(osc, X, delta, periods + 0.5)
    T = TWO_PI / osc.omega
    if label == "PD":  # period-1: the last impact velocities agree
        v = res.impact_velocities[-6:]
        ok = v.size >= 4 and float(v.max() - v.min()) < 1e-6 * max(1.0, float(v.max()))
    else:  # no grazing contact: impacts exactly one period apart
        gaps = np.diff(res.impact_times[-6:])
        ok = gaps.size >= 4 and bool(np.all(np.abs(gaps - T) < 1e-6 * T))
    return ok, res.final_state, res.final_phase


def brute_locate(osc: ic.ImpactOscillator, label: str, lo: float, hi: float, start: np.ndarray,
                 delta: float, periods: int, steps: int) -> float:
    """Bisection on omega between a side where the N = 1 motion settles and one where not."""
    ok_lo, _, _ = settled_pattern(osc.replace(omega=lo), start, delta, periods, label)
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        ok, _, _ = settled_pattern(osc.replace(omega=mid), start, delta, periods, label)
        if ok == ok_lo:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def location_study(n: int, cache: ReferenceCache, quick: bool) -> dict[str, Any]:
    osc = system(n)
    # n = 10: brackets from a scan of the whole branch (omega in [0.3, 3], 17 special points)
    brackets = {2: {"PD": (0.5, 3.0), "GR": (0.5, 3.0)},
                10: {"PD": (0.90, 0.93), "GR": (0.50, 0.53)}}[n]
    out: dict[str, Any] = {"n": n, "points": {}}
    for label in ("PD", "GR"):
        w0, root, _, t_gap = find_special(osc, label, brackets[label])
        key = f"{label}_n{n}_root{root}_{w0:.8f}"
        if label == "PD":
            w_true = cache.get(key, lambda w0=w0, root=root: reference_pd(osc, root, w0))
        else:
            w_true = cache.get(key, lambda w0=w0, root=root, t_gap=t_gap:
                               reference_gr(osc, root, w0, t_gap))
        half = 0.01 * w0
        lo, hi = w_true - half, w_true + 0.7 * half
        rows: list[dict[str, Any]] = []
        f_closed = closed_test(osc, label, root)
        for xtol in ([1e-4, 1e-7, 1e-10, 1e-13] if not quick else [1e-5, 1e-10, 1e-13]):
            w, t = timed(lambda xtol=xtol, f=f_closed, lo=lo, hi=hi: brentq(
                f, lo, hi, xtol=xtol, rtol=1e-15))
            rows.append({"family": "closed form", "method": "impactcont + brentq",
                         "tol": xtol, "time": t, "error": abs(w - w_true) / w_true})
        ds, t = timed(lambda lo=lo, hi=hi, label=label: ic.continuation(
            osc.replace(omega=lo), N=1, parameter="omega", bounds=(lo, hi), detect=(label,),
            both_directions=False, components="start"))
        found = [float(v) for v, s in zip(ds.special_omega.values, ds.special_label.values,
                                          strict=True) if str(s) == label] if (
            "special" in ds.sizes) else []
        if found:
            w = min(found, key=lambda v: abs(v - w_true))
            rows.append({"family": "closed form", "method": "impactcont.continuation",
                         "tol": None, "time": t, "error": abs(w - w_true) / w_true})
        o_lo = pick(ic.periodic_orbits(osc.replace(omega=lo), 1), root)
        z_lo = section(o_lo.state, o_lo.delta)
        rng = np.random.default_rng(2)
        z_start = z_lo + 1e-6 * max(1.0, np.abs(z_lo).max()) * rng.standard_normal(z_lo.size)
        shoot_tols = [1e-6, 1e-9, 1e-12] if not quick else [1e-6, 1e-10]
        if n > 2:
            shoot_tols = [1e-6, 1e-9]
        for method in METHODS:
            for tol in shoot_tols:
                if method == "Radau" and (tol < 1e-9 or (n > 2 and tol < 1e-6)):
                    continue  # minutes per Brent iteration
                f_shoot = shooting_test(osc, label, method, tol, z_start)
                try:
                    w, t = timed(lambda f_shoot=f_shoot, tol=tol, lo=lo, hi=hi: brentq(
                        f_shoot, lo, hi, xtol=max(tol, 1e-13), rtol=1e-15))
                except (shooting.ShootingError, ValueError) as exc:
                    log.warning("%s n=%d %s tol=%g: %s", label, n, method, tol, exc)
                    continue
                rows.append({"family": "shooting", "method": method, "tol": tol, "time": t,
                             "error": abs(w - w_true) / w_true})
                log.info("%s n=%d %s tol=%g: %.3g s, error %.2e", label, n, method, tol, t,
                         rows[-1]["error"])
        if n == 2:
            start = o_lo.state
            for periods, steps in ([(50, 10), (200, 16), (800, 24)] if not quick
                                   else [(50, 10), (200, 16)]):
                w, t = timed(lambda periods=periods, steps=steps, label=label, lo=lo, hi=hi,
                             start=start, d=o_lo.delta: brute_locate(
                                 osc, label, lo, hi, start, d, periods, steps))
                rows.append({"family": "brute force", "method": "simulate + bisection",
                             "tol": periods, "time": t, "error": abs(w - w_true) / w_true})
        out["points"][label] = {"omega": w_true, "root": root, "rows": rows}
        log.info("%s n=%d at omega=%.15g: %d runs", label, n, w_true, len(rows))
    return out


# -- summary -------------------------------------------------------------------------------------
def speed_ratios(rows: list[dict[str, Any]], err_key: str, cf: dict[str, Any]
                 ) -> dict[str, Any]:
    """Cheapest shooting run reaching each accuracy, divided by the closed form's time."""
    out = {}
    for level in (1e-6, 1e-9, 1e-12):
        ok = [r for r in rows if r["family"] == "shooting" and r[err_key] <= level]
        if ok and cf[err_key] <= level:
            best = min(ok, key=lambda r: r["time"])
            out[f"{level:g}"] = {"ratio": best["time"] / cf["time"], "method": best["method"],
                                 "tol": best["tol"], "time": best["time"]}
        else:
            out[f"{level:g}"] = None
    return out


def write_table(results: dict[str, Any], path: Path) -> None:
    lines = ["| n | quantity | closed form: error, time | best shooting reaching 1e-6 | "
             "reaching 1e-9 | reaching 1e-12 | most accurate shooting | brute force best |",
             "|---|---|---|---|---|---|---|---|"]

    def cell(entry: dict[str, Any] | None) -> str:
        if entry is None:
            return "not reached"
        return f"{entry['method']} {entry['tol']:g}: x{entry['ratio']:.0f} slower"

    for block in results["orbits"]:
        rows = block["rows"]
        cf = rows[0]
        for key, name in (("orbit_error", "orbit"), ("multiplier_error", "multipliers")):
            shoot = [r for r in rows if r["family"] == "shooting"]
            best = min(shoot, key=lambda r: r[key]) if shoot else None
            brute = [r for r in rows if r["family"] == "brute force"
                     and not math.isnan(r[key])]
            bb = min(brute, key=lambda r: r[key]) if brute else None
            ratios = speed_ratios(rows, key, cf)
            lines.append(
                f"| {block['n']} | {name} | {cf[key]:.1e}, {1e3 * cf['time']:.2f} ms | "
                f"{cell(ratios['1e-06'])} | {cell(ratios['1e-09'])} | {cell(ratios['1e-12'])} | "
                + (f"{best['method']} {best['tol']:g}: {best[key]:.1e} in {best['time']:.2f} s"
                   if best else "-") + " | "
                + (f"{bb['method']} {bb['tol']}: {bb[key]:.1e} in {bb['time']:.2f} s"
                   if bb else "-") + " |")
    for block in results["locations"]:
        for label, point in block["points"].items():
            rows = point["rows"]
            cf = min((r for r in rows if r["method"] == "impactcont + brentq"),
                     key=lambda r: r["error"])
            shoot = [r for r in rows if r["family"] == "shooting"]
            best = min(shoot, key=lambda r: r["error"]) if shoot else None
            brute = [r for r in rows if r["family"] == "brute force"]
            bb = min(brute, key=lambda r: r["error"]) if brute else None
            ratios = speed_ratios(rows, "error", cf)
            lines.append(
                f"| {block['n']} | {label} (omega = {point['omega']:.12g}) | "
                f"{cf['error']:.1e}, {1e3 * cf['time']:.1f} ms | "
                f"{cell(ratios['1e-06'])} | {cell(ratios['1e-09'])} | {cell(ratios['1e-12'])} | "
                + (f"{best['method']} {best['tol']:g}: {best['error']:.1e} in "
                   f"{best['time']:.2f} s" if best else "-") + " | "
                + (f"{bb['tol']} periods: {bb['error']:.1e} in {bb['time']:.1f} s"
                   if bb else "-") + " |")
    path.write_text("\n".join(lines) + "\n")


STYLE = {"closed form": ("*", 8), "shooting": ("o", 4), "brute force": ("s", 4)}
COLORS = {"impactcont": "k", "impactcont + brentq": "k", "impactcont.continuation": "0.5",
          "RK45": "tab:blue", "DOP853": "tab:orange", "Radau": "tab:green",
          "impactcont.simulate": "tab:red", "solve_ivp DOP853 1e-10": "tab:purple",
          "simulate + bisection": "tab:red"}
DPI = 150  # of the PNGs (7 in wide: 1050 pixels)
TIME_LABEL = "run time $t$ [s]"


def _series(rows: list[dict[str, Any]], key: str) -> list[Series]:
    """One line per (family, method): error against run time; an error of exactly 0 goes
    to the axis' ``exact 0`` row (never to an invented floor)."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in rows:
        if not math.isnan(r[key]):
            groups.setdefault((r["family"], r["method"]), []).append(r)
    out = []
    for (family, method), rs in groups.items():
        rs = sorted(rs, key=lambda r: r["time"])
        marker, size = STYLE[family]
        out.append(Series([r["time"] for r in rs], [r[key] for r in rs],
                          f"{family}: {method}", color=COLORS.get(method, "0.3"),
                          marker=marker, markersize=size, linewidth=1.0))
    return out


def _panel(ax: Any, rows: list[dict[str, Any]], key: str, ylabel: str, title: str) -> None:
    series = _series(rows, key)
    times = [t for s in series for t in s.x]
    if times:  # the 1e-12 mark the table counts as "converged"
        series.append(Series([min(times), max(times)], [1e-12, 1e-12],
                             "relative error $10^{-12}$", color="0.6", linestyle=":",
                             linewidth=0.8))
    series_plot(ax, series, xlabel=TIME_LABEL, ylabel=ylabel, xscale="log", yscale="log",
                title=title)
    ax.grid(True, which="major", alpha=0.3)


def orbit_figure(results: dict[str, Any], width: float = 7.0) -> Figure:
    """Error against run time of one periodic motion: a row per n (orbit, multipliers)."""
    blocks = results["orbits"]
    one_column = width < 5.0  # six panels in one column: flatter, to stay within a page
    fig, axes = panel_figure(2 * len(blocks), width, ncols=1 if one_column else 2,
                             aspect=0.36 if one_column else 0.62, extra_height=1.6)
    for j, block in enumerate(blocks):
        _panel(axes[2 * j], block["rows"], "orbit_error", r"relative error $\epsilon$",
               f"$n = {block['n']}$: orbit (state, phase)")
        _panel(axes[2 * j + 1], block["rows"], "multiplier_error",
               r"relative error $\epsilon$", f"$n = {block['n']}$: multipliers")
    figure_legend(fig)
    fig.suptitle("Work and precision of one periodic motion (truth: 50 digits)",
                 fontsize="medium")
    fit_labels(fig)
    return fig


def location_figure(results: dict[str, Any], width: float = 7.0) -> Figure:
    """Error against run time of locating a PD and a GR point in omega: a 2 x 2 grid."""
    panels = [(b["n"], label, pt) for b in results["locations"]
              for label, pt in b["points"].items()]
    fig, axes = panel_figure(len(panels), width, extra_height=1.6)
    for ax, (n, label, pt) in zip(axes, panels, strict=True):
        _panel(ax, pt["rows"], "error", r"relative error of $\omega$",
               rf"$n = {n}$: locate {label} in $\omega$")
    figure_legend(fig)
    fig.suptitle("Work and precision of locating a special point (truth: 50 digits)",
                 fontsize="medium")
    fit_labels(fig)
    return fig


def plot(results: dict[str, Any], out: Path, width: float = 7.0) -> list[Path]:
    """Write ``work_precision_orbit.png`` and ``work_precision_location.png`` into ``out``."""
    paths = []
    for name, make in (("work_precision_orbit.png", orbit_figure),
                       ("work_precision_location.png", location_figure)):
        make(results, width).savefig(out / name, dpi=DPI)
        paths.append(out / name)
    return paths


def rerun_orbit(output_dir: str | Path, n: int) -> dict[str, Any]:
    """Redo the orbit study of one n and merge it into an existing ``results.json``."""
    out = Path(output_dir)
    results = json.loads((out / "results.json").read_text())
    cache = ReferenceCache(HERE / "output" / "reference_cache.json")
    block = orbit_study(n, cache, quick=bool(results.get("quick")))
    results["orbits"] = [b for b in results["orbits"] if b["n"] != n] + [block]
    results["orbits"].sort(key=lambda b: b["n"])
    (out / "results.json").write_text(json.dumps(results, indent=1, default=float))
    write_table(results, out / "table.md")
    figures = plot(results, out)
    if out.resolve() != FIGURES_DIR.resolve():
        FIGURES_DIR.mkdir(exist_ok=True)
        for p in figures:
            shutil.copy(p, FIGURES_DIR / p.name)
    return results


def main(output_dir: str | Path = DEFAULT_OUTPUT, quick: bool = False) -> dict[str, Any]:
    """Run the study and write its results, table and figures into ``output_dir``."""
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    cache = ReferenceCache(HERE / "output" / "reference_cache.json")
    sizes = (2, 10) if quick else (2, 10, 50)
    t0 = time.perf_counter()
    results: dict[str, Any] = {"quick": quick, "orbits": [], "locations": []}
    for n in sizes:
        results["orbits"].append(orbit_study(n, cache, quick))
        (out / "results.json").write_text(json.dumps(results, indent=1, default=float))
    for n in (2, 10):
        results["locations"].append(location_study(n, cache, quick))
        (out / "results.json").write_text(json.dumps(results, indent=1, default=float))
    results["wall_time_s"] = time.perf_counter() - t0
    (out / "results.json").write_text(json.dumps(results, indent=1, default=float))
    write_table(results, out / "table.md")
    figures = plot(results, out)
    if out.resolve() != FIGURES_DIR.resolve():
        FIGURES_DIR.mkdir(exist_ok=True)
        for p in figures:
            shutil.copy(p, FIGURES_DIR / p.name)
    log.info("done in %.0f s; table:\n%s", results["wall_time_s"],
             (out / "table.md").read_text())
    return results


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT))
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--rerun-orbit", type=int, default=None, metavar="N_DOF",
                        help="redo only the orbit study of this n into existing results")
    parser.add_argument("--figures-only", action="store_true",
                        help="only redraw the figures from the output's results.json and "
                        "copy them to figures/")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    if args.figures_only:
        out = Path(args.output)
        for p in plot(json.loads((out / "results.json").read_text()), out):
            if out.resolve() != FIGURES_DIR.resolve():
                FIGURES_DIR.mkdir(exist_ok=True)
                shutil.copy(p, FIGURES_DIR / p.name)
    elif args.rerun_orbit is not None:
        rerun_orbit(args.output, args.rerun_orbit)
    else:
        main(args.output, quick=args.quick)
