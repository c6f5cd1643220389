"""Reproduce section 4 of Cao & Shu (the paper's worked example) and check it with the simulator.

The system (EQUATIONS.md section 6): n = 2, M = I, K = [[1, -1], [-1, 2]], eta = 0.1
(C = 2 eta K), R = 0.6, F = [1, 0].

* Figure 3 (b = 0): the paper claims stable period-1, -2 and -3 motions at
  omega = 1.2, 2.4 and 2.6.
* Figure 4 / robust stability (omega = 1, N = 1, b in [0.2, 1.0], b0 = 0.6): the paper
  gives c^2 + s^2, G0, Gamma, epsilon and epsilon0.

Every number is recomputed with the closed form of :mod:`impactcont`, and every claim
about a motion is checked against the exact event-driven simulator: (a) a closed-form
orbit simulated from its own state returns to itself, (b) a 1e-4 perturbation decays
(stable) or grows (unstable), (c) what the simulator settles to from rest and from
other starts after a long transient.

Writes ``numbers.json``, ``checks.json``, ``figure3.png`` and ``figure4.png`` into the
output directory. Run::

    .venv/bin/python studies/paper_example/run.py [--output DIR] [--quick] [--workers K]
                                                  [--copy-figures]
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import multiprocessing as mp
import os
import shutil
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

import impactcont as ic
from impactcont.plots.branches import fit_text
from impactcont.plots.series import MAX_WIDTH, figure_legend, fit_labels

log = logging.getLogger("paper_example")

HERE = Path(__file__).resolve().parent
DEFAULT_OUTPUT = HERE / "output"
FIGURES_DIR = HERE / "figures"
DPI = 150  # of the PNGs (7 in wide: 1050 pixels)

# ---------------------------------------------------------------------------------------------
# The paper's numbers (section 4; EQUATIONS.md section 6)
# ---------------------------------------------------------------------------------------------
PAPER_AMPLITUDE_SQUARED = 1.74355
PAPER_G0 = np.array([
    [-0.177445, 0.039713, -0.070643, 0.345996],
    [-0.020169, 0.323905, 0.144022, -0.213799],
    [0.262554, -0.049062, -0.179735, -0.154322],
    [0.090393, 0.292730, 0.161324, 0.112559],
])
PAPER_GAMMA = np.array([
    [0.019349, 0.062658, 0.034531, 0.196054],
    [0.067327, 0.218037, 0.120160, 1.000000],
    [0.099814, 0.323237, 0.178136, 0.854205],
    [0.039599, 0.128237, 0.070672, 0.530487],
])
PAPER_EPSILON = 0.313974
PAPER_EPSILON0 = 0.343455
B_BOX = (0.2, 1.0)
B0 = 0.6

#: Figure 3: (omega, N claimed by the paper) at b = 0.
FIGURE3 = [(1.2, 1), (2.4, 2), (2.6, 3)]
#: Figure 4: b at omega = 1, N = 1.
FIGURE4 = [0.2, 0.6, 1.0]

TRANSIENT_PERIODS = 300      # forcing periods discarded before looking at the motion
MEASURE_PERIODS = 60         # forcing periods in which the impact pattern is detected
MAX_PATTERN_PERIOD = 12      # longest pattern (in forcing periods) looked for
PATTERN_TOL = 1e-6           # repetition tolerance on impact times and velocities
RETURN_PERIODS_PER_N = 50    # check (a): 50 N forcing periods
PERTURBATION_PERIODS_PER_N = 30  # check (b): 30 N forcing periods
PERTURBATION = 1e-4          # check (b)
SEED = 19970301


def paper_oscillator(**changes: float) -> ic.ImpactOscillator:
    """The paper's two-degree-of-freedom system, with some parameters changed."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=ic.chain_stiffness([1.0, 1.0]), F=[1.0, 0.0],
                              R=0.6, b=B0, omega=1.0, eta=0.1)
    return osc.replace(**changes) if changes else osc


def _wrap(angle: float | np.ndarray) -> Any:
    """Angle difference wrapped to [-pi, pi]."""
    return np.remainder(np.asarray(angle) + math.pi, 2.0 * math.pi) - math.pi


def _forcing_period(osc: ic.ImpactOscillator) -> float:
    return 2.0 * math.pi / osc.omega


def _clean(obj: Any) -> Any:
    """JSON-ready copy: numpy to Python, non-finite floats to the strings 'inf', '-inf', 'nan'."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer, int)):
        return int(obj)
    if isinstance(obj, (np.floating, float)):
        x = float(obj)
        return x if math.isfinite(x) else str(x)
    return obj


def _write_json(path: Path, data: dict[str, Any]) -> None:
    path.write_text(json.dumps(_clean(data), indent=2, allow_nan=False) + "\n")
    log.info("wrote %s", path)


# ---------------------------------------------------------------------------------------------
# Simulation helpers
# ---------------------------------------------------------------------------------------------
def impact_pattern(res: ic.SimulationResult, osc: ic.ImpactOscillator,
                   window_periods: float) -> dict[str, Any]:
    """Detect the periodic impact pattern in the last ``window_periods`` forcing periods.

    The motion is called ``P-p`` (p impacts every P forcing periods) for the smallest P
    such that shifting the impact sequence by p impacts shifts the times by exactly
    P forcing periods and leaves the impact velocities unchanged (to ``PATTERN_TOL``).
    """
    Tf = _forcing_period(osc)
    keep = res.impact_times > res.final_time - window_periods * Tf
    t, v = res.impact_times[keep], res.impact_velocities[keep]
    phases = res.impact_phases[keep]
    out: dict[str, Any] = {"status": res.status.name, "impacts_in_window": int(t.size),
                           "window_periods": window_periods}
    if t.size == 0:
        out.update(label="no impact", P=None, p=0)
        return out
    best = math.inf
    for P in range(1, MAX_PATTERN_PERIOD + 1):
        p = int(np.sum(t < t[0] + P * Tf - 1e-9 * Tf))
        if p == 0 or t.size < 2 * p + 1:
            continue
        resid = max(float(np.max(np.abs(t[p:] - t[:-p] - P * Tf))),
                    float(np.max(np.abs(v[p:] - v[:-p]))))
        best = min(best, resid)
        if resid < PATTERN_TOL:
            out.update(label=f"{P}-{p}", P=P, p=p, residual=resid,
                       impact_velocities=v[:p], impact_phases=phases[:p])
            return out
    out.update(label=f"no period <= {MAX_PATTERN_PERIOD} forcing periods", P=None,
               p=None, residual=best)
    return out


def start_points(osc: ic.ImpactOscillator, rng: np.random.Generator, count: int
                 ) -> list[tuple[str, np.ndarray, float]]:
    """Rest (x = 0, or x1 = b - 0.5 if the stop is at or behind 0) and ``count`` random starts."""
    x1 = 0.0 if osc.b > 0 else osc.b - 0.5
    starts = [("rest", np.array([x1, 0.0, 0.0, 0.0]), 0.0)]
    for k in range(count):
        X = np.array([osc.b - rng.uniform(0.0, 2.0), rng.normal(), rng.normal(), rng.normal()])
        starts.append((f"random{k + 1}", X, float(rng.uniform(-math.pi, math.pi))))
    return starts


# ---------------------------------------------------------------------------------------------
# Closed form
# ---------------------------------------------------------------------------------------------
def orbit_record(orbit: ic.PeriodicOrbit) -> dict[str, Any]:
    """The numbers of one root of eq. (15)."""
    return {"N": orbit.N, "root": orbit.root, "delta": orbit.delta,
            "impact_velocity": orbit.impact_velocity, "gap_min": orbit.gap_min,
            "gap_min_time": orbit.gap_min_time, "spectral_radius": orbit.spectral_radius,
            "stable": orbit.stable, "physical": orbit.physical, "reason": orbit.reason,
            "state": orbit.state, "period": orbit.period}


def _root_orbit(osc: ic.ImpactOscillator, N: int, root: int) -> ic.PeriodicOrbit:
    """The root of eq. (15) with the given sign of the square root."""
    return next(o for o in ic.periodic_orbits(osc, N) if o.root == root)


def physical_orbit(osc: ic.ImpactOscillator, N: int) -> ic.PeriodicOrbit | None:
    """The physical root of eq. (15) (the stable one if both are physical), if any."""
    good = [o for o in ic.periodic_orbits(osc, N) if o.physical]
    good.sort(key=lambda o: o.spectral_radius)
    return good[0] if good else None


# ---------------------------------------------------------------------------------------------
# Checks (a), (b), (c)
# ---------------------------------------------------------------------------------------------
def impact_deviations(orbit: ic.PeriodicOrbit, res: ic.SimulationResult
                      ) -> dict[str, np.ndarray]:
    """Per simulated impact, the distance from the orbit's impact (max-norm over components).

    ``flight``: |time since the previous impact (or the start) - T|; ``state``: state
    right after the impact; ``velocity``: impact velocity; ``phase``: forcing phase
    (wrapped); ``all``: the largest of these.
    """
    flights = np.diff(np.concatenate([[0.0], res.impact_times]))
    dev = {
        "flight": np.abs(flights - orbit.period),
        "state": (np.max(np.abs(res.impact_states - orbit.state), axis=1)
                  if res.impact_times.size else np.zeros(0)),
        "velocity": np.abs(res.impact_velocities - orbit.impact_velocity),
        "phase": np.abs(_wrap(res.impact_phases - orbit.delta)),
    }
    dev["all"] = np.max(np.vstack(list(dev.values())), axis=0) if flights.size else flights
    return dev


def check_return(orbit: ic.PeriodicOrbit) -> dict[str, Any]:
    """(a) Simulate from the orbit's own state; does the simulator repeat the orbit?

    Physical roots: 50 N forcing periods. ``returns_to_itself``: the first simulated
    impact is the orbit's impact to 1e-9 (the closed form is a fixed point of the
    simulated impact map). An unstable orbit then drifts off as round-off grows like
    rho(G)^k, so ``impacts_within_1e-9`` (leading impacts within 1e-9) is also given.
    A non-physical root is refuted by its first flight: 2 N periods are simulated.
    """
    osc, N = orbit.oscillator, orbit.N
    count = RETURN_PERIODS_PER_N if orbit.physical else 2
    res = ic.simulate(osc, orbit.state, orbit.delta, count * N + 0.5)
    dev = impact_deviations(orbit, res)
    out: dict[str, Any] = {"N": N, "root": orbit.root, "physical": orbit.physical,
                           "stable_closed_form": orbit.stable,
                           "periods_simulated": count * N + 0.5, "status": res.status.name,
                           "impacts": int(res.impact_times.size),
                           "impacts_if_periodic": count, "period": orbit.period}
    if res.impact_times.size == 0:
        out["returns_to_itself"] = False
        return out
    out["first_impact_time"] = float(res.impact_times[0])
    out["first_impact_deviation"] = {k: float(v[0]) for k, v in dev.items() if k != "all"}
    bad = np.flatnonzero(dev["all"] >= 1e-9)
    out["impacts_within_1e-9"] = int(bad[0]) if bad.size else int(dev["all"].size)
    out["max_deviation_all_impacts"] = {k: float(v.max()) for k, v in dev.items()
                                        if k != "all"}
    out["returns_to_itself"] = bool(dev["all"][0] < 1e-9)
    out["stays_for_whole_run"] = bool(res.success and res.impact_times.size == count
                                      and not bad.size)
    return out


def check_perturbation(orbit: ic.PeriodicOrbit, rng: np.random.Generator) -> dict[str, Any]:
    """(b) Start 1e-4 off the orbit on the impact surface; does the deviation decay or grow?

    The perturbation is a random direction of ``z = [x2, x1', x2', delta]`` (eq. 19)
    of max-norm 1e-4 (x1 = b is kept). The deviation after impact k is the max-norm
    distance of the impact (state, velocity, phase, flight time) from the orbit's;
    its geometric-mean factor per impact, from the start over the impacts where it stays
    in (1e-11, 1e-2), estimates rho(G). Simulated for 30 N forcing periods.
    """
    osc, N = orbit.oscillator, orbit.N
    dz = rng.normal(size=2 * osc.n)
    dz *= PERTURBATION / np.max(np.abs(dz))
    X = orbit.state.copy()
    X[1:] += dz[:-1]
    res = ic.simulate(osc, X, orbit.delta + dz[-1], PERTURBATION_PERIODS_PER_N * N + 0.5)
    dev = impact_deviations(orbit, res)["all"]
    out: dict[str, Any] = {"N": N, "root": orbit.root, "spectral_radius": orbit.spectral_radius,
                           "stable_closed_form": orbit.stable, "status": res.status.name,
                           "impacts": int(dev.size), "initial_deviation": PERTURBATION}
    if dev.size == 0:
        out.update(verdict="no impact", converged=False, diverged=True,
                   agrees_with_closed_form=not orbit.stable)
        return out
    out["deviation_first_impacts"] = dev[:6]
    out["final_deviation"] = float(dev[-1])
    out["max_deviation"] = float(dev.max())
    above = np.flatnonzero(dev > 1e-2)
    out["first_impact_beyond_1e-2"] = int(above[0]) + 1 if above.size else None
    full = np.concatenate([[PERTURBATION], dev])
    inside = (full > 1e-11) & (full < 1e-2)
    j = int(np.argmin(inside)) - 1 if not inside.all() else full.size - 1
    if j >= 1:
        out["factor_per_impact"] = float((full[j] / full[0]) ** (1.0 / j))
        out["factor_per_impact_over_impacts"] = j
    converged = bool(dev[-1] < 1e-9 and dev.size == PERTURBATION_PERIODS_PER_N)
    diverged = bool(above.size > 0)
    out.update(converged=converged, diverged=diverged,
               verdict="converges (stable)" if converged else
               "diverges (unstable)" if diverged else "inconclusive")
    out["agrees_with_closed_form"] = (converged and orbit.stable) or (diverged and
                                                                      not orbit.stable)
    return out


def settle(osc: ic.ImpactOscillator, state: np.ndarray, delta: float, transient: int
           ) -> tuple[dict[str, Any], ic.SimulationResult]:
    """(c) Simulate ``transient + MEASURE_PERIODS`` forcing periods; detect the impact pattern."""
    res = ic.simulate(osc, state, delta, transient + MEASURE_PERIODS)
    return impact_pattern(res, osc, MEASURE_PERIODS), res


def compare_with_orbit(pattern: dict[str, Any], osc: ic.ImpactOscillator) -> dict[str, Any]:
    """Is a detected P-1 pattern the closed-form N = P motion? (impact velocity, phase)."""
    if pattern.get("p") != 1:
        return {}
    orbit = physical_orbit(osc, pattern["P"])
    if orbit is None:
        return {"closed_form_N": pattern["P"], "closed_form_physical": False}
    return {"closed_form_N": orbit.N, "closed_form_root": orbit.root,
            "dev_impact_velocity": abs(pattern["impact_velocities"][0] - orbit.impact_velocity),
            "dev_impact_phase": abs(float(_wrap(pattern["impact_phases"][0] - orbit.delta)))}


def attractor_survey(osc: ic.ImpactOscillator, claimed_N: int, rng: np.random.Generator,
                     n_random: int, transient: int) -> tuple[dict[str, Any], dict[str, Any]]:
    """(c) at one parameter point: the pattern from rest and from random starts.

    Returns the JSON record and, for the plot, the steady state reached from rest
    (state and phase right after its last impact, and its pattern).
    """
    runs = []
    steady: dict[str, Any] = {}
    for name, X, delta in start_points(osc, rng, n_random):
        pattern, res = settle(osc, X, delta, transient)
        pattern.update(compare_with_orbit(pattern, osc))
        pattern.update(start=name, start_state=X, start_delta=delta)
        runs.append(pattern)
        if name == "rest" and res.impact_times.size:
            steady = {"state": res.impact_states[-1], "phase": float(res.impact_phases[-1]),
                      "pattern": pattern}
        log.info("  omega=%g b=%g start %-8s -> %s", osc.omega, osc.b, name, pattern["label"])
    labels = sorted({r["label"] for r in runs})
    claimed = f"{claimed_N}-1"
    record = {"omega": osc.omega, "b": osc.b, "claimed": claimed, "transient_periods": transient,
              "measure_periods": MEASURE_PERIODS, "runs": runs, "patterns_found": labels,
              "all_starts_settle_on_claim": labels == [claimed],
              "claim_seen_from_some_start": claimed in labels}
    return record, steady


# ---------------------------------------------------------------------------------------------
# Robust stability (eq. 26-29)
# ---------------------------------------------------------------------------------------------
def robust_part() -> dict[str, Any]:
    """Paper's G0, Gamma, epsilon, epsilon0 against ours."""
    osc = paper_oscillator(b=B0, omega=1.0)
    rs = ic.robust_stability(osc, 1, vary={"b": B_BOX}, nominal={"b": B0})
    paper_theta = PAPER_EPSILON * PAPER_GAMMA
    # direct test of the claim: rho(G(b)) on a fine grid of the box, same root followed
    bs = np.linspace(*B_BOX, 81)
    rhos, physical = [], []
    for b in bs:
        orbit = _root_orbit(osc.replace(b=float(b)), 1, rs.root)
        rhos.append(orbit.spectral_radius)
        physical.append(orbit.physical)
    k = int(np.argmax(rhos))
    return {
        "root_followed": rs.root,
        "G0": rs.G0,
        "G0_paper": PAPER_G0,
        "G0_max_abs_deviation": float(np.max(np.abs(rs.G0 - PAPER_G0))),
        "rho_G0": rs.orbit.spectral_radius,
        "epsilon0_paper": PAPER_EPSILON0,
        "epsilon0_paper_Gamma_our_G0": ic.robust_bound(rs.G0, PAPER_GAMMA),
        "epsilon0_paper_Gamma_paper_G0": ic.robust_bound(PAPER_G0, PAPER_GAMMA),
        "epsilon_paper": PAPER_EPSILON,
        "epsilon": rs.epsilon,
        "Gamma": rs.Gamma,
        "Gamma_paper": PAPER_GAMMA,
        "theta": rs.theta,
        "theta_paper": paper_theta,
        "theta_ratio_paper_over_ours": paper_theta / rs.theta,
        "theta_argmax_b": {f"{i},{j}": q["b"] for (i, j), q in rs.argmax.items()},
        "dG_at_box_ends": {f"b={b:g}": np.abs(_root_orbit(osc.replace(b=b), 1, rs.root).G
                                              - rs.G0) for b in B_BOX},
        "refinement_gain": rs.refinement_gain,
        "samples": rs.samples,
        "epsilon0": rs.epsilon0,
        "robust": rs.robust,
        "margin_epsilon0_over_epsilon": rs.margin,
        "message": rs.message,
        "direct_rho_scan": {"b_points": bs.size, "max_rho": rhos[k], "at_b": float(bs[k]),
                            "min_rho": min(rhos), "all_physical": all(physical),
                            "all_stable": max(rhos) < 1.0},
        "summary": rs.summary(),
    }


def omega_scan(b: float, Ns: range, omegas: np.ndarray) -> dict[str, Any]:
    """Frequencies (on a grid) with a physical, stable N-1 motion at gap b."""
    osc = paper_oscillator(b=b)
    out = {}
    for N in Ns:
        ok = [float(w) for w in omegas
              if any(o.physical and o.stable
                     for o in ic.periodic_orbits(osc.replace(omega=float(w)), N))]
        intervals: list[list[float]] = []
        step = float(omegas[1] - omegas[0])
        for w in ok:
            if intervals and abs(w - intervals[-1][1] - step) < 1e-9:
                intervals[-1][1] = w
            else:
                intervals.append([w, w])
        out[str(N)] = intervals
    return {"b": b, "omega_grid": [float(omegas[0]), float(omegas[-1]), float(omegas[1]
                                                                              - omegas[0])],
            "stable_physical_intervals": out}


# ---------------------------------------------------------------------------------------------
# Plots
# ---------------------------------------------------------------------------------------------
def plot_motion_row(ax_t: Axes, ax_p: Axes, curves: list[dict[str, Any]], b: float,
                    title: str | None) -> None:
    """One row of figure 3/4: x1(t) on the left, phase portrait x1' vs x1 on the right.

    Each curve is a dict with ``t``, ``X`` (state samples), ``label`` and matplotlib
    style keywords under ``style``. The stop is a dashed black line; the legend is the
    figure's (:func:`impactcont.plots.series.figure_legend`).
    """
    for c in curves:
        ax_t.plot(c["t"], c["X"][:, 0], label=c["label"], **c["style"])
        n = c["X"].shape[1] // 2
        ax_p.plot(c["X"][:, 0], c["X"][:, n], label=c["label"], **c["style"])
    stop = r"stop $x_1 = b$"
    ax_t.axhline(b, color="k", ls="--", lw=0.9, label=stop)
    ax_p.axvline(b, color="k", ls="--", lw=0.9, label=stop)
    if title:
        ax_t.set_title(title, fontsize="medium")
    ax_t.set_xlabel("time $t$")
    ax_t.set_ylabel("$x_1$")
    ax_p.set_xlabel("$x_1$")
    ax_p.set_ylabel(r"$\dot{x}_1$")


def motion_curves(osc: ic.ImpactOscillator, orbits: list[tuple[ic.PeriodicOrbit, str, dict]],
                  steady: dict[str, Any], span_periods: int) -> list[dict[str, Any]]:
    """Closed-form orbits and the simulated steady state over ``span_periods`` forcing periods."""
    Tf = _forcing_period(osc)
    curves = []
    for orbit, label, style in orbits:
        reps = max(1, math.ceil(span_periods / orbit.N))
        t, X = orbit.time_series(num=300 * orbit.N, periods=reps)
        keep = t <= span_periods * Tf + 1e-9
        curves.append({"t": t[keep], "X": X[keep], "label": label, "style": style})
    if steady:
        res = ic.simulate(osc, steady["state"], steady["phase"], span_periods,
                             trajectory=True)
        curves.append({"t": res.t, "X": res.X,
                       "label": "simulated steady state from rest",
                       "style": {"color": "tab:red", "lw": 1.0, "ls": "-"}})
    return curves


def make_figure(rows: list[tuple[list[dict[str, Any]], float, str]], path: Path,
                suptitle: str, width: float = 7.0) -> Figure:
    """:func:`motion_figure` written to ``path`` and returned."""
    fig = motion_figure(rows, suptitle, width)
    fig.savefig(path, dpi=DPI)
    log.info("wrote %s", path)
    return fig


def motion_figure(rows: list[tuple[list[dict[str, Any]], float, str]], suptitle: str,
                  width: float = 7.0) -> Figure:
    """Figure with one row per parameter point (see :func:`plot_motion_row`), ``width``
    inches wide, one legend under the rows."""
    if not 2.0 <= width <= MAX_WIDTH:
        raise ValueError(f"width must be in [2, {MAX_WIDTH}] inches; got {width!r}")
    narrow = width < 5.0  # one column: taller rows, fewer ticks
    row = 0.36 * width if not narrow else 0.5 * width
    fig = Figure(figsize=(width, row * len(rows) + 1.4), layout="constrained")
    subs = np.atleast_1d(fig.subfigures(len(rows), 1))
    for sub, (curves, b, title) in zip(subs, rows, strict=True):
        ax_t, ax_p = sub.subplots(1, 2, width_ratios=(1.6, 1.0) if not narrow else (1.2, 1.0))
        plot_motion_row(ax_t, ax_p, curves, b, None)
        sub.suptitle(title, fontsize="medium")  # over the row: as wide as the figure
        if narrow:
            for axis, n in ((ax_t.xaxis, 3), (ax_t.yaxis, 3), (ax_p.xaxis, 2), (ax_p.yaxis, 3)):
                axis.set_major_locator(MaxNLocator(n))
    figure_legend(fig)
    fig.suptitle(suptitle, fontsize="medium")
    fit_labels(fig)
    for sub in subs:
        fit_text(sub._suptitle, fig.bbox.width - 8.0)
    fig.draw_without_rendering()
    return fig


CLOSED_STYLE = {"color": "tab:blue", "lw": 3.0, "alpha": 0.45}
N_COLORS = {1: "tab:blue", 2: "tab:green", 3: "tab:purple", 4: "tab:brown", 5: "tab:olive"}
NONPHYS_STYLE = {"color": "0.4", "lw": 0.9, "ls": ":"}


# ---------------------------------------------------------------------------------------------
# Main
# ---------------------------------------------------------------------------------------------
def check_point(fig: str, omega: float, b: float, N: int, n_random: int, transient: int,
                seed: int) -> dict[str, Any]:
    """Checks (a), (b), (c) at one of the paper's parameter points (a unit of parallel work)."""
    osc = paper_oscillator(b=b, omega=omega)
    rng = np.random.default_rng(seed)
    log.info("checking omega=%g, b=%g (paper: stable %d-1)", omega, b, N)
    # (a), (b) for every root of the claimed N and, at b = 0, of N = 1..3
    roots = [o for M in sorted(set(range(1, 4) if b == 0.0 else ()) | {N})
             for o in ic.periodic_orbits(osc, M)]
    returns = [check_return(o) for o in roots]
    perturb = [check_perturbation(o, rng) for o in roots if o.physical]
    survey, steady = attractor_survey(osc, N, rng, n_random, transient)
    claimed = physical_orbit(osc, N)
    claimed_perturb = [p for p in perturb if p["N"] == N and claimed is not None
                       and p["root"] == claimed.root]
    record = {
        "figure": fig, "omega": omega, "b": b, "claim": f"stable {N}-1 motion",
        "closed_form_claim_physical": claimed is not None,
        "closed_form_claim_stable": bool(claimed is not None and claimed.stable),
        "a_return": returns, "b_perturbation": perturb, "c_attractors": survey,
        "closed_form_stability_agrees_with_simulator": all(p["agrees_with_closed_form"]
                                                           for p in perturb),
        "claim_confirmed": bool(claimed is not None and claimed.stable
                                and survey["claim_seen_from_some_start"]
                                and all(p["converged"] for p in claimed_perturb)),
    }
    return {"record": record, "steady": steady}


def _run_tasks(tasks: dict[str, tuple[Any, ...]], workers: int) -> dict[str, Any]:
    """Run ``{key: (function, *args)}``, in ``workers`` forked processes if more than one."""
    if workers > 1 and "fork" in mp.get_all_start_methods():
        with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("fork")) as pool:
            futures = {key: pool.submit(fn, *args) for key, (fn, *args) in tasks.items()}
            return {key: f.result() for key, f in futures.items()}
    return {key: fn(*args) for key, (fn, *args) in tasks.items()}


def _figure3_rows(steadies: dict[tuple[float, float], dict[str, Any]]) -> list[tuple]:
    rows = []
    for omega, N in FIGURE3:
        osc = paper_oscillator(b=0.0, omega=omega)
        steady = steadies[(omega, 0.0)]
        P = steady.get("pattern", {}).get("P") or N
        orbits = []
        for M in sorted({N, P}):
            for o in ic.periodic_orbits(osc, M):
                if o.physical:
                    tag = "stable" if o.stable else "unstable"
                    orbits.append((o, f"closed form $N = {M}$, {tag}",
                                   {**CLOSED_STYLE, "color": N_COLORS[M]}))
                elif M == N and o.impact_velocity > 0:
                    orbits.append((o, f"closed form $N = {M}$, not physical (crosses the stop)",
                                   NONPHYS_STYLE))
        title = (rf"$\omega = {omega:g}$, paper: stable $N = {N}$, simulated from rest: "
                 f"{steady.get('pattern', {}).get('label', '?')}")
        rows.append((motion_curves(osc, orbits, steady, max(2 * N, 2 * P)), 0.0, title))
    return rows


def _figure4_rows(steadies: dict[tuple[float, float], dict[str, Any]]) -> list[tuple]:
    rows = []
    for b in FIGURE4:
        osc = paper_oscillator(b=b, omega=1.0)
        steady = steadies[(1.0, b)]
        orbit = physical_orbit(osc, 1)
        orbits = [] if orbit is None else [(orbit, "closed form $N = 1$, "
                                            + ("stable" if orbit.stable else "unstable"),
                                            CLOSED_STYLE)]
        title = (f"$b = {b:g}$, paper: stable $N = 1$, simulated from rest: "
                 f"{steady.get('pattern', {}).get('label', '?')}")
        rows.append((motion_curves(osc, orbits, steady, 3), b, title))
    return rows


def main(output_dir: str | Path = DEFAULT_OUTPUT, *, quick: bool = False,
         workers: int | None = None) -> dict[str, Any]:
    """Run the study and write its files into ``output_dir``.

    Parameters
    ----------
    output_dir : path
        Created if needed.
    quick : bool
        Only the start from rest (no random starts), a 100-period transient instead
        of 300 and no frequency scan; every closed-form number is the same. For tests.
    workers : int, optional
        Processes for the independent checks (default: CPU count, at most 4; 1 runs
        everything in this process).

    Returns
    -------
    dict
        ``{"numbers": ..., "checks": ...}`` as written to the JSON files.
    """
    t_start = time.perf_counter()
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    workers = min(os.cpu_count() or 1, 4) if workers is None else max(1, int(workers))
    transient = 100 if quick else TRANSIENT_PERIODS
    n_random, n_random_26 = (0, 0) if quick else (2, 6)

    # ---- the independent pieces of work, heaviest first -----------------------------------
    tasks: dict[str, tuple[Any, ...]] = {}
    points = ([("figure3", w, 0.0, N) for w, N in FIGURE3]
              + [("figure4", 1.0, b, 1) for b in FIGURE4])
    points.sort(key=lambda p: -p[3])
    for k, (fig, omega, b, N) in enumerate(points):
        n_rand = n_random_26 if N == 3 else n_random
        tasks[f"point {omega:g} {b:g}"] = (check_point, fig, omega, b, N, n_rand, transient,
                                           SEED + k)
    tasks["robust"] = (robust_part,)
    if not quick:
        tasks["scan"] = (omega_scan, 0.0, range(1, 4), np.round(np.arange(0.5, 4.5001, 0.05), 10))
    results = _run_tasks(tasks, workers)

    # ---- numbers ---------------------------------------------------------------------------
    base = paper_oscillator()
    amp2 = ic.amplitude_squared(base, 1)
    robust = results["robust"]
    log.info("c^2 + s^2 (omega=1, N=1) = %.9f (paper %.5f)", amp2, PAPER_AMPLITUDE_SQUARED)
    log.info("G0 max |ours - paper| = %.3g", robust["G0_max_abs_deviation"])
    log.info("eps0 with the paper's Gamma: our G0 %.7f, paper's G0 %.7f (paper %.6f)",
             robust["epsilon0_paper_Gamma_our_G0"], robust["epsilon0_paper_Gamma_paper_G0"],
             PAPER_EPSILON0)
    log.info("ours: epsilon %.6f (paper %.6f), eps0 %.6f, robust %s",
             robust["epsilon"], PAPER_EPSILON, robust["epsilon0"], robust["robust"])
    fig3_roots, fig4_roots = [], []
    for omega, N in FIGURE3:
        osc = paper_oscillator(b=0.0, omega=omega)
        fig3_roots.append({"omega": omega, "b": 0.0, "N": N, "amplitude_squared":
                           ic.amplitude_squared(osc, N),
                           "roots": [orbit_record(o) for o in ic.periodic_orbits(osc, N)]})
    for b in FIGURE4:
        osc = paper_oscillator(b=b, omega=1.0)
        fig4_roots.append({"omega": 1.0, "b": b, "N": 1,
                           "roots": [orbit_record(o) for o in ic.periodic_orbits(osc, 1)]})
    numbers = {
        "system": {"M": base.M, "K": base.K, "F": base.F, "R": base.R, "eta": base.eta},
        "amplitude_squared_omega1_N1": amp2,
        "amplitude_squared_paper": PAPER_AMPLITUDE_SQUARED,
        "amplitude_squared_abs_deviation": abs(amp2 - PAPER_AMPLITUDE_SQUARED),
        "robust": robust,
        "figure3": fig3_roots,
        "figure4": fig4_roots,
    }

    # ---- checks ----------------------------------------------------------------------------
    checks: dict[str, Any] = {"settings": {
        "quick": quick, "workers": workers, "transient_periods": transient,
        "measure_periods": MEASURE_PERIODS, "pattern_tolerance": PATTERN_TOL,
        "max_pattern_period": MAX_PATTERN_PERIOD, "return_periods_per_N": RETURN_PERIODS_PER_N,
        "perturbation": PERTURBATION, "perturbation_periods_per_N": PERTURBATION_PERIODS_PER_N,
        "seed": SEED}}
    per_point = sorted((r for k, r in results.items() if k.startswith("point")),
                       key=lambda r: (r["record"]["figure"], r["record"]["omega"],
                                      r["record"]["b"]))
    checks["points"] = [r["record"] for r in per_point]
    steadies = {(r["record"]["omega"], r["record"]["b"]): r["steady"] for r in per_point}

    # the period-3 claim at omega = 2.6, b = 0: every root N = 1..5
    osc26 = paper_oscillator(b=0.0, omega=2.6)
    checks["omega2.6_b0_roots_N1_to_5"] = [
        {"N": N, "amplitude_squared": ic.amplitude_squared(osc26, N),
         "roots": [orbit_record(o) for o in ic.periodic_orbits(osc26, N)]} for N in range(1, 6)]
    checks["omega2.6_b0_physical_stable"] = [
        f"N={o['N']} root {o['root']:+d}" for entry in checks["omega2.6_b0_roots_N1_to_5"]
        for o in entry["roots"] if o["physical"] and o["stable"]]
    if "scan" in results:
        checks["omega_scan_b0"] = results["scan"]

    # ---- figures ---------------------------------------------------------------------------
    system = r"$R = 0.6$, $\eta = 0.1$"
    make_figure(_figure3_rows(steadies), out / "figure3.png",
                f"Cao and Shu's figure 3: periodic motions at $b = 0$, {system}")
    make_figure(_figure4_rows(steadies), out / "figure4.png",
                rf"Cao and Shu's figure 4: periodic motions at $\omega = 1$, {system}")

    elapsed = time.perf_counter() - t_start
    checks["elapsed_seconds"] = elapsed
    numbers["elapsed_seconds"] = elapsed
    _write_json(out / "numbers.json", numbers)
    _write_json(out / "checks.json", checks)
    for point in checks["points"]:
        log.info("omega=%g b=%g claim %s: confirmed=%s; simulator patterns %s", point["omega"],
                 point["b"], point["claim"], point["claim_confirmed"],
                 point["c_attractors"]["patterns_found"])
    log.info("done in %.1f s (%d worker processes)", elapsed, workers)
    return {"numbers": _clean(numbers), "checks": _clean(checks)}


def _parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--output", type=Path, default=DEFAULT_OUTPUT,
                        help=f"output directory (default {DEFAULT_OUTPUT})")
    parser.add_argument("--quick", action="store_true",
                        help="fewer starts, shorter transient, no frequency scan")
    parser.add_argument("--workers", type=int, default=None,
                        help="processes for the independent checks (default: CPUs, at most 4)")
    parser.add_argument("--copy-figures", action="store_true",
                        help=f"also copy figure3.png and figure4.png to {FIGURES_DIR}")
    return parser.parse_args(argv)


if __name__ == "__main__":
    args = _parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s")
    main(args.output, quick=args.quick, workers=args.workers)
    if args.copy_figures:
        FIGURES_DIR.mkdir(exist_ok=True)
        for name in ("figure3.png", "figure4.png"):
            shutil.copy2(Path(args.output) / name, FIGURES_DIR / name)
            log.info("copied %s to %s", name, FIGURES_DIR)
