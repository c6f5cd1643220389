"""Rattle: a free mass driven by a harmonic force and a mean force against stops.

In the frame of a sinusoidally vibrating table this is the bouncing ball (Holmes 1982):
the ball's height above the table ``y`` obeys, in the units of Holmes, Tufillaro et al.
and Luck & Mehta (time ``tau = omega t``, length ``g / omega^2``),

    y'' = -1 + Gamma cos(tau + delta),        y >= 0,        y'+ = -R y'-  at y = 0,

with ``Gamma = A omega^2 / g`` the table's nondimensional acceleration (the table is at
``z = Gamma cos(tau + delta)``: its inertial force is the harmonic force, gravity the
constant force). As an :class:`impactcont.ImpactOscillator`: one free mass ``M = [[1]]``,
``K = [[0]]``, ``F = [Gamma]``, ``F_static = [-1]``, ``omega = 1``, a lower stop at
``x1 = 0`` (``Stops(b_low=0)``, restitution ``R``) and the model's upper stop far away
(``b = 1000``, never reached). With a ceiling at ``x1 = GAP`` the same system is the
gear-rattle model of a free (unloaded) gear in a backlash: the drag torque is the mean
force, the other gear's fluctuating motion the harmonic one.

The study

1. compares the period-N one-impact motions (``multi_impact_orbit``, pattern ``"L"``) with
   the closed form (impact phase from the momentum balance, impact velocity, the impact
   map's multipliers, its fold Gamma_1 and period-doubling threshold Gamma_2) at table
   points, and along the branches in Gamma (``multi_impact_continuation`` in ``F0``) point
   by point; the located SN and PD against Gamma_1 and Gamma_2;
2. checks every flight for interior contact twice (the package does not: a constant
   force pushing a free mode leaves the contact search unchecked): the closed-form flight
   ``y(s)`` on a fine grid, and the simulator started on the motion;
3. continues in omega at fixed force amplitude (Gamma fixed: the phase stays, the impact
   velocity goes as 1/omega);
4. follows the period-doubling cascade of the N = 1 motion (``period_doubling_cascade``),
   each new motion witnessed by the simulator over one period;
5. the two-flank version (a ceiling at ``GAP``): motions with one impact on each stop,
   continued in Gamma, the stable ones witnessed by the simulator.

Writes ``rattle.json``, ``branches.nc`` and ``rattle.png`` into the output directory. Only
the public API is used. Run::

    PYTHONPATH=. python studies/rattle/run.py [--output DIR] [--copy-figures]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # tiny matrices: threads only cost

import argparse
import json
import logging
import math
import shutil
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.figure import Figure

import impactcont as ic
from impactcont.plots.branches import legend_below
from impactcont.plots.impacts import impact_diagram
from impactcont.plots.series import Series, fit_labels, panel_figure, series_plot, take_legend

log = logging.getLogger("rattle")

HERE = Path(__file__).resolve().parent
R = 0.5                      # restitution (table and ceiling)
FAR = 1000.0                 # the model's upper stop, far above any bounce
GAP = 8.0                    # the ceiling of the two-flank (gear rattle) version
TABLE = {1: (1.10, 1.30, 1.50), 2: (2.15, 2.25, 2.35)}   # Gamma of the agreement table
SIM_PERIODS = 60             # motion periods the simulator runs on a stable motion
DPI = 150                    # of the PNG (7 in wide: 1050 pixels)


# ----------------------------------------------------------------------------- closed form

def gamma_1(N: int, R: float = R) -> float:
    """Gamma where the period-N one-impact motions are born (fold): ``N pi (1-R)/(1+R)``."""
    return N * math.pi * (1 - R) / (1 + R)


def gamma_2(N: int, R: float = R) -> float:
    """Period-doubling threshold of the stable period-N motion:
    ``Gamma_2^2 = (N pi (1-R)/(1+R))^2 + (2 (1+R^2)/(1+R)^2)^2``."""
    return math.hypot(gamma_1(N, R), 2 * (1 + R * R) / (1 + R) ** 2)


def closed_form(gamma: float, N: int, root: int = 1, R: float = R) -> dict[str, Any]:
    """The period-N one-impact motion of the bouncing ball in closed form.

    Momentum balance over one flight of duration ``T = 2 pi N`` (the ball's absolute
    take-off velocity is ``T / 2``) and the impact law give the table velocity at impact,
    ``-Gamma sin(delta) = N pi (1-R)/(1+R)`` (Holmes' phase ``phi = delta + pi/2``:
    ``Gamma cos(phi) = N pi (1-R)/(1+R)``), the relative impact velocity ``2 pi N/(1+R)``
    and take-off velocity ``2 pi N R/(1+R)``. The impact map's Jacobian has determinant
    ``R^2`` and trace ``1 + R^2 - (1+R)^2 Gamma cos(delta)``; ``root = +1`` is the motion
    with ``cos(delta) > 0`` (the table decelerating at impact), stable for
    ``Gamma_1 < Gamma < Gamma_2``; ``root = -1`` the saddle.
    """
    s = gamma_1(N, R) / gamma
    if s > 1:
        raise ValueError(f"no period-{N} motion below Gamma_1 = {gamma_1(N, R)}; got {gamma}")
    delta = -math.asin(s) if root > 0 else -math.pi + math.asin(s)
    trace = 1 + R * R - (1 + R) ** 2 * gamma * math.cos(delta)
    mult = np.roots([1.0, -trace, R * R]).astype(complex)
    return {"delta": delta, "impact_velocity": 2 * math.pi * N / (1 + R),
            "takeoff_velocity": 2 * math.pi * N * R / (1 + R), "trace": trace,
            "multipliers": mult[np.argsort(-np.abs(mult), kind="stable")]}


def flight_height(gamma: float, delta: float, v: float, s: np.ndarray) -> np.ndarray:
    """The ball's height above the table ``s`` after an impact at phase ``delta`` with
    take-off velocity ``v`` (exact solution of ``y'' = -1 + Gamma cos(tau + delta)``)."""
    return v * s - s * s / 2 + gamma * (math.cos(delta) - np.cos(s + delta) - s * math.sin(delta))


def flight_margin(gamma: float, ceiling: float, states: np.ndarray, phases: np.ndarray,
                  flight_times: np.ndarray, samples: int = 4001) -> float:
    """Smallest ``min(y, ceiling - y) / (s (T - s))`` over the interior of every flight of a
    motion (closed-form flights; positive: no flight touches a stop before its end)."""
    worst = math.inf
    for (y0, v), ph, T in zip(states, phases, flight_times, strict=True):
        s = np.linspace(0.0, T, samples)[1:-1]
        y = y0 + flight_height(gamma, ph, v, s)
        worst = min(worst, float(np.min(np.minimum(y, ceiling - y) / (s * (T - s)))))
    return worst


# ----------------------------------------------------------------------------- the model

def ball(gamma: float, omega: float = 1.0, ceiling: float = FAR) -> ic.ImpactOscillator:
    """The bouncing ball (``ceiling = FAR``) or the free gear in a backlash (``GAP``)."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[gamma], F_static=[-1.0], R=R,
                               b=ceiling, omega=omega, stops=ic.Stops(b_low=0.0, R_low=R))


def wrap(a: float) -> float:
    """An angle difference in (-pi, pi]."""
    return float(math.remainder(a, 2 * math.pi))


def simulated(orbit: ic.MultiImpactOrbit, periods: int) -> dict[str, Any]:
    """Start the simulator on the motion (its first impact state and phase) and compare
    its impacts over ``periods`` motion periods with the motion's own."""
    osc = orbit.oscillator
    N = orbit.N
    res = ic.simulate(osc, np.asarray(orbit.states[0], float), float(orbit.delta),
                      N * periods + 0.25)
    times = np.asarray(res.impact_times)
    keep = times < 2 * math.pi * N * periods + 1e-9 * 2 * math.pi
    got_v = np.asarray(res.impact_velocities)[keep]
    got_phase = np.asarray(res.impact_phases)[keep]
    # flight k ends in impact k + 1 (mod p)
    want_v = np.tile(np.roll(np.abs(np.asarray(orbit.impact_velocities)), -1), periods)
    # the motion's impact phases: after flight k at delta + sum of flight times
    phases = float(orbit.delta) + np.cumsum(np.asarray(orbit.flight_times))
    want_phase = np.tile(phases, periods)
    same = got_v.size == want_v.size
    out: dict[str, Any] = {"status": res.status.name, "impacts": int(got_v.size),
                           "expected": int(want_v.size), "same_count": bool(same)}
    if same:
        out["velocity_diff"] = float(np.max(np.abs(np.abs(got_v) - want_v)))
        out["phase_diff"] = float(max(abs(wrap(a - b)) for a, b in zip(got_phase, want_phase,
                                                                       strict=True)))
    return out


def _quiet(fn, *args, **kwargs):
    """Call a package function with its 'interior contact not checked' warnings (logged
    once per branch; counted in the study) kept out of the log."""
    logger = logging.getLogger("impactcont")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return fn(*args, **kwargs)
    finally:
        logger.setLevel(level)


# ----------------------------------------------------------------------------- 1. the table

def generic_guess(N: int, delta: float) -> dict[str, Any]:
    """A guess that knows nothing of the closed form: an impact at phase ``delta``, one
    flight of N periods, the ball leaving the table at ``pi N`` (the mean launch speed)."""
    return {"delta": delta, "flight_times": [2 * math.pi * N], "states": [[0.0, math.pi * N]]}


def solve(gamma: float, N: int, delta0: float) -> ic.MultiImpactOrbit:
    """Newton from :func:`generic_guess`; a result whose residual is not at rounding level
    is refused (``multi_impact_orbit`` can stop with the phase run off to ~1e14, where its
    relative tolerance no longer bites: see the README)."""
    orb = _quiet(ic.multi_impact_orbit, ball(gamma), N, 1, generic_guess(N, delta0),
                 pattern="L")
    if not orb.residual < 1e-10:
        raise RuntimeError(f"Newton stopped at residual {orb.residual:.3g} (Gamma = {gamma}, "
                           f"N = {N}, delta = {orb.delta:.6g})")
    return orb


def agreement_table() -> list[dict[str, Any]]:
    """Both roots at the table's Gamma values, Newton from the generic guesses with
    ``delta = 0`` (it lands on the stable root) and ``delta = pi`` (on the saddle)."""
    rows = []
    for N, gammas in TABLE.items():
        for gamma in gammas:
            for delta0 in (0.0, math.pi):
                orb = solve(gamma, N, delta0)
                root = 1 if math.cos(orb.delta) > 0 else -1
                rows.append(_row(orb, closed_form(gamma, N, root=root), gamma, N,
                                 "stable" if root > 0 else "saddle"))
    return rows


def _row(orb: ic.MultiImpactOrbit, cf: dict[str, Any], gamma: float, N: int,
         which: str) -> dict[str, Any]:
    mult = np.asarray(orb.multipliers, complex)
    mult = mult[np.argsort(-np.abs(mult), kind="stable")]
    return {"N": N, "Gamma": gamma, "root": which,
            "delta": float(orb.delta), "delta_cf": cf["delta"],
            "delta_diff": abs(wrap(float(orb.delta) - cf["delta"])),
            "impact_velocity": float(orb.impact_velocities[0]),
            "impact_velocity_cf": cf["impact_velocity"],
            "velocity_diff": abs(float(orb.impact_velocities[0]) - cf["impact_velocity"]),
            "takeoff_diff": abs(float(orb.states[0][1]) - cf["takeoff_velocity"]),
            "multipliers": [str(complex(m)) for m in mult],
            "multiplier_diff": float(np.max(np.abs(mult - cf["multipliers"]))),
            "stable": bool(orb.stable), "residual": float(orb.residual),
            "error_estimate": float(orb.error_estimate), "reason": orb.reason}


# ----------------------------------------------------------------------------- 2. branches

def branch_in_gamma(N: int, ds_max: float = 0.02) -> tuple[xr.Dataset, dict[str, Any]]:
    """The period-N branch in Gamma (``F0``) through the stable motion at mid-window,
    compared point by point with the closed form (the root chosen by the sign of
    cos delta), its SN and PD against Gamma_1 and Gamma_2 (steps at most ``ds_max``)."""
    g1, g2 = gamma_1(N), gamma_2(N)
    orb = solve(0.5 * (g1 + g2), N, 0.0)
    bounds = (0.95 * g1, g2 + 0.3)
    t0 = time.perf_counter()
    br = _quiet(ic.multi_impact_continuation, orb, "F0", bounds, ds=min(0.01, ds_max),
                ds_max=ds_max, progress=False)
    elapsed = time.perf_counter() - t0
    worst = {"delta": 0.0, "velocity": 0.0, "multipliers": 0.0}
    stable_wrong = 0
    for i in range(br.sizes["point"]):
        gamma = float(br["F0"][i])
        delta = float(br["delta"][i])
        root = 1 if math.cos(delta) > 0 else -1
        cf = closed_form(max(gamma, g1), N, root=root)
        mult = np.asarray(br["multipliers"][i].values, complex)
        mult = mult[np.argsort(-np.abs(mult), kind="stable")]
        worst["delta"] = max(worst["delta"], abs(wrap(delta - cf["delta"])))
        worst["velocity"] = max(worst["velocity"],
                                abs(float(br["impact_velocity"][i]) - cf["impact_velocity"]))
        worst["multipliers"] = max(worst["multipliers"],
                                   float(np.max(np.abs(mult - cf["multipliers"]))))
        stable_cf = root > 0 and g1 < gamma < g2
        stable_wrong += int(bool(br["stable"][i]) != stable_cf)
    specials = [{"label": str(lab), "Gamma": float(v), "precision": float(pr)}
                for lab, v, pr in zip(br["special_label"].values, br["special_F0"].values,
                                      br["special_precision"].values, strict=True)]
    sn = [s["Gamma"] for s in specials if s["label"] == "SN"]
    pd = [s["Gamma"] for s in specials if s["label"] == "PD"]
    info = {"N": N, "points": int(br.sizes["point"]), "seconds": elapsed,
            "Gamma_1": g1, "Gamma_2": g2, "specials": specials,
            "SN_diff": abs(sn[0] - g1) if sn else None,
            "PD_diff": abs(pd[0] - g2) if pd else None,
            "max_diff": worst, "stability_flag_disagreements": stable_wrong,
            "physical_points": int(br["physical"].sum()),
            "message": json.loads(br.attrs["options"]).get("message", "")}
    log.info("N = %d branch in Gamma: %d points in %.2f s, SN %s (Gamma_1 = %.12f), "
             "PD %s (Gamma_2 = %.12f); worst delta %.1e, velocity %.1e, multipliers %.1e",
             N, info["points"], elapsed, sn, g1, pd, g2, worst["delta"], worst["velocity"],
             worst["multipliers"])
    return br, info


def contact_checks(gammas: dict[int, tuple[float, ...]]) -> list[dict[str, Any]]:
    """Interior contact of both roots (closed-form flight on a grid) and, on the stable
    root, the simulator over SIM_PERIODS periods; on the saddle over one period."""
    out = []
    for N, gs in gammas.items():
        for gamma in gs:
            for root in (1, -1):
                cf = closed_form(gamma, N, root=root)
                margin = flight_margin(gamma, FAR, np.array([[0.0, cf["takeoff_velocity"]]]),
                                       np.array([cf["delta"]]), np.array([2 * math.pi * N]))
                orb = solve(gamma, N, 0.0 if root > 0 else math.pi)
                sim = simulated(orb, SIM_PERIODS if root > 0 else 1)
                out.append({"N": N, "Gamma": gamma, "root": root,
                            "flight_margin": margin, "above_table": bool(margin > 0),
                            "simulator": sim})
    return out


def omega_branch() -> tuple[xr.Dataset, dict[str, Any]]:
    """N = 1 in omega at fixed force amplitude (Gamma = F0 / g fixed): the closed form keeps
    delta and gives the impact velocity ``2 pi g / (omega (1 + R))``."""
    gamma = 1.3
    orb = solve(gamma, 1, 0.0)
    br = _quiet(ic.multi_impact_continuation, orb, "omega", (0.5, 3.0), ds=0.02, ds_max=0.05,
                progress=False)
    om = br["omega"].values
    cf = closed_form(gamma, 1)
    info = {"Gamma": gamma, "points": int(om.size),
            "delta_diff": float(np.max(np.abs([wrap(d - cf["delta"])
                                               for d in br["delta"].values]))),
            "velocity_diff": float(np.max(np.abs(br["impact_velocity"].values
                                                 - 2 * math.pi / (om * (1 + R))))),
            "specials": [str(x) for x in br["special_label"].values]}
    log.info("N = 1 in omega at Gamma = %.2f: %d points, worst delta %.1e, velocity %.1e",
             gamma, om.size, info["delta_diff"], info["velocity_diff"])
    return br, info


# ----------------------------------------------------------------------------- 3. the cascade

def cascade(branch: xr.Dataset, max_doublings: int = 5) -> tuple[Any, dict[str, Any]]:
    """The period-doubling cascade from the first PD of ``branch`` (at most
    ``max_doublings``), the simulator at each PD motion after the first."""
    t0 = time.perf_counter()
    cas = _quiet(ic.period_doubling_cascade, branch, 0, max_doublings=max_doublings,
                 progress=False)
    elapsed = time.perf_counter() - t0
    sims = []
    for k, br in enumerate(cas.branches[:-1]):
        if int((br["special_label"] == "PD").sum()) == 0:
            continue
        orb = _quiet(ic.special_orbit, br, "PD", 0)
        if k == 0:
            continue  # the parent's PD motion: a period-1 motion (checked above)
        sims.append({"N": orb.N, "Gamma": float(orb.oscillator.F[0].real),
                     **simulated(orb, 1)})
    info = {"pd_values": [float(v) for v in cas.pd_values],
            "pd_precision": [float(v) for v in cas.pd_precision],
            "ratios": [float(v) for v in cas.ratios], "message": cas.message,
            "seconds": elapsed, "simulator_at_pd": sims}
    log.info("cascade: PD at %s; ratios %s (%.1f s)", np.round(cas.pd_values, 9),
             np.round(cas.ratios, 3), elapsed)
    return cas, info


# ----------------------------------------------------------------------------- 4. two flanks

def two_flank(ds_max: float = 0.05) -> tuple[xr.Dataset | None, dict[str, Any]]:
    """The free gear in a backlash ``0 <= x1 <= GAP``: the motion with one impact on each
    flank per period (pattern ``"LU"``), found by Newton from a grid of guesses at
    Gamma = 4 (a simulation from rest ends in chatter on the lower flank) and kept only
    if its closed-form flights stay inside the clearance; continued in Gamma, each branch
    point checked by :func:`flight_margin`, a few points witnessed by the simulator
    (continuation steps at most ``ds_max``)."""
    gamma0 = 4.0
    osc = ball(gamma0, ceiling=GAP)
    found, rejected = None, 0
    for d in np.linspace(-math.pi, math.pi, 16, endpoint=False):
        for t1 in np.linspace(0.4, 2 * math.pi - 0.4, 10):
            v1 = (GAP + t1 * t1 / 2 - gamma0 * (math.cos(d) - math.cos(t1 + d)
                                               - t1 * math.sin(d))) / t1
            d2, t2 = d + t1, 2 * math.pi - t1
            v2 = (-GAP + t2 * t2 / 2 - gamma0 * (math.cos(d2) - math.cos(t2 + d2)
                                                - t2 * math.sin(d2))) / t2
            guess = {"delta": d, "flight_times": [t1, t2],
                     "states": [[0.0, v1], [GAP, v2]]}
            try:
                orb = _quiet(ic.multi_impact_orbit, osc, 1, 2, guess, pattern="LU")
            except ic.ImpactcontError:
                continue
            if not (orb.residual < 1e-10 and min(orb.flight_times) > 0
                    and min(np.asarray(orb.impact_velocities)) > 0):
                continue
            if flight_margin(gamma0, GAP, np.asarray(orb.states), np.asarray(orb.phases),
                             np.asarray(orb.flight_times)) > 0:
                found = orb
                break
            rejected += 1
        if found is not None:
            break
    if found is None:
        return None, {"found": False, "rejected_crossing_a_stop": rejected}
    t0 = time.perf_counter()
    br = _quiet(ic.multi_impact_continuation, found, "F0", (1.0, 10.0), ds=min(0.02, ds_max),
                ds_max=ds_max, progress=False)
    elapsed = time.perf_counter() - t0
    gam = br["F0"].values
    margin = np.array([flight_margin(float(gam[i]), GAP, br["state_k"][i].values,
                                     br["delta_k"][i].values, br["flight_time_k"][i].values,
                                     samples=801)
                       for i in range(gam.size)])
    physical = margin > 0
    br["flights_inside"] = ("point", physical)
    specials = [{"label": str(lab), "Gamma": float(v), "precision": float(pr),
                 "flights_inside": bool(physical[int(i)])}
                for lab, v, pr, i in zip(br["special_label"].values, br["special_F0"].values,
                                         br["special_precision"].values,
                                         br["special_point"].values, strict=True)]
    sims = []
    for i in np.flatnonzero(physical)[::max(1, int(physical.sum()) // 5)]:
        guess = {"delta": float(br["delta"][i]),
                 "flight_times": br["flight_time_k"][i].values.tolist(),
                 "states": br["state_k"][i].values.tolist()}
        orb = _quiet(ic.multi_impact_orbit, ball(float(gam[i]), ceiling=GAP), 1, 2, guess,
                     pattern="LU")
        sims.append({"Gamma": float(gam[i]), "stable": bool(orb.stable),
                     "simulator": simulated(orb, SIM_PERIODS if orb.stable else 1)})
    inside = gam[physical]
    info = {"found": True, "Gamma_seed": gamma0, "seed_delta": float(found.delta),
            "seed_flight_times": [float(v) for v in found.flight_times],
            "seed_impact_velocities": [float(v) for v in found.impact_velocities],
            "seed_stable": bool(found.stable), "rejected_crossing_a_stop": rejected,
            "points": int(gam.size), "range": [float(gam.min()), float(gam.max())],
            "flights_inside_range": ([float(inside.min()), float(inside.max())]
                                     if inside.size else None),
            "stable_and_inside": int((physical & br["stable"].values).sum()),
            "seconds": elapsed, "specials": specials, "simulator": sims,
            "message": json.loads(br.attrs["options"]).get("message", "")}
    log.info("two flanks: %d points in %.2f s, flights inside for Gamma in %s, specials %s",
             gam.size, elapsed, info["flights_inside_range"],
             [(s["label"], round(s["Gamma"], 9)) for s in specials])
    return br, info


# ----------------------------------------------------------------------------- figure

GAMMA = r"$\Gamma = A\omega^2/g$"


def _closed_form_panel(ax: Axes, branches: dict[int, xr.Dataset]) -> list[Any]:
    """Impact phase against Gamma: the closed form's lines over the package's points."""
    series = []
    for N, br in branches.items():
        g = np.linspace(gamma_1(N), gamma_2(N) + 0.3, 400)
        for root, style, name in ((1, "-", ""), (-1, "--", ", saddle")):
            d = np.mod([closed_form(x, N, root)["delta"] for x in g], 2 * np.pi)
            series.append(Series(g, d, f"closed form, $N = {N}${name}", color=f"C{N - 1}",
                                 linestyle=style, linewidth=1.0))
        series.append(Series([gamma_2(N)] * 2, [0.0, 2 * np.pi],
                             rf"$\Gamma_2$ of $N = {N}$ (closed form)", color=f"C{N - 1}",
                             linestyle=":", linewidth=0.8))
        st = br["stable"].values
        gam, delta = br["F0"].values, np.mod(br["delta"].values, 2 * np.pi)
        series.append(Series(gam[st], delta[st], "package, stable", linestyle="none",
                             marker="o", filled=True, markersize=2.5))
        series.append(Series(gam[~st], delta[~st], "package, unstable", linestyle="none",
                             marker="o", markersize=3.0))
    series_plot(ax, series, xlabel=GAMMA, ylabel=r"impact phase $\delta$ (mod $2\pi$)",
                title="Period-$N$ one-impact motions")
    ax.set_ylim(0.0, 2 * np.pi)
    return [s.handle() for s in {s.label: s for s in series}.values()]


def figure(groups: dict[str, xr.Dataset], pd_values: list[float], width: float = 7.0
           ) -> Figure:
    """The study's figure from its stored branches (``branches.nc``) and cascade PDs.

    Top left: the period-N motions in closed form (lines) and from the package (dots);
    top right: the period-doubling cascade of the N = 1 motion (every impact of each
    branch, :func:`impactcont.plots.impacts.impact_diagram`); bottom: the two-flank motion,
    a motion with a flight through a stop drawn as not physical.

    Parameters
    ----------
    groups : dict of str to xarray.Dataset
        ``N1_gamma``, ``N2_gamma``, ``cascade_<k>`` and (if found) ``two_flank``.
    pd_values : list of float
        Gamma of the cascade's period doublings (``rattle.json``).
    width : float
        Inches, at most :data:`impactcont.plots.series.MAX_WIDTH`.
    """
    two = groups.get("two_flank")
    # one column: a legend under each panel, the panels kept high enough for their labels
    fig, axes = panel_figure(3 if two is not None else 2, width,
                             extra_height=1.6 if width >= 5.0 else 3.4)
    branches = {N: groups[f"N{N}_gamma"] for N in TABLE}
    legend_below(axes[0], _closed_form_panel(axes[0], branches), span="axes")
    cascade = [groups["N1_gamma"], *(groups[k] for k in sorted(
        (k for k in groups if k.startswith("cascade_")), key=lambda k: int(k.split("_")[1])))]
    ax = impact_diagram(cascade, ax=axes[1], specials=("PD",), nonphysical=False,
                        names=False, legend="inside", title="Period-doubling cascade of $N = 1$",
                        zoom=False)
    ax.set_xlim(gamma_2(1) - 0.15, pd_values[-1] + 0.03)
    ax.set_xlabel(GAMMA)
    ax.set_ylabel(r"impact velocity $\dot{y}(T_k^-)$")
    legend_below(ax, take_legend(ax), span="axes")
    if two is not None:
        ax = impact_diagram(two.assign(physical=two["physical"] & two["flights_inside"]),
                            ax=axes[2], label_special=True, names=False, legend="inside",
                            title=f"Two flanks (clearance {GAP:g}), one impact on each per "
                            "period")  # not physical: a flight crosses a stop (README)
        ax.set_xlabel(GAMMA)
        ax.set_ylabel(r"impact speed $|\dot{y}(T_k^-)|$")
        legend_below(ax, take_legend(ax), span="axes")
    fig.suptitle(f"Bouncing ball and gear rattle, $R = {R:g}$", fontsize="medium")
    fit_labels(fig)
    return fig


def draw_figures(output: Path, width: float = 7.0) -> Path:
    """Draw ``rattle.png`` from the stored ``branches.nc`` and ``rattle.json`` of ``output``."""
    tree = ic.load(output / "branches.nc")
    groups = {name: node.to_dataset() for name, node in tree.children.items()}
    summary = json.loads((output / "rattle.json").read_text())
    fig = figure(groups, summary["cascade"]["pd_values"], width)
    path = output / "rattle.png"
    fig.savefig(path, dpi=DPI)
    log.info("wrote %s", path)
    return path


def main(output: Path) -> dict[str, Any]:
    output.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    summary: dict[str, Any] = {"R": R, "Gamma_1": {N: gamma_1(N) for N in TABLE},
                               "Gamma_2": {N: gamma_2(N) for N in TABLE}}
    summary["table"] = agreement_table()
    for row in summary["table"]:
        log.info("N = %d Gamma = %.2f: delta %.12f (closed form %.12f), velocity diff %.1e, "
                 "multipliers diff %.1e", row["N"], row["Gamma"], row["delta"],
                 row["delta_cf"], row["velocity_diff"], row["multiplier_diff"])
    groups: dict[str, xr.Dataset] = {}
    branches = {}
    summary["branches"] = {}
    for N in TABLE:
        br, info = branch_in_gamma(N)
        branches[N] = br
        groups[f"N{N}_gamma"] = br
        summary["branches"][N] = info
    summary["contact"] = contact_checks(TABLE)
    br, summary["omega_branch"] = omega_branch()
    groups["N1_omega"] = br
    cas, summary["cascade"] = cascade(branches[1])
    for k, b in enumerate(cas.branches[1:], start=1):
        groups[f"cascade_{k}"] = b
    two, summary["two_flank"] = two_flank()
    if two is not None:
        groups["two_flank"] = two
    ic.save(groups, output / "branches.nc")
    summary["total_s"] = time.perf_counter() - t_start
    (output / "rattle.json").write_text(json.dumps(summary, indent=2, default=str))
    draw_figures(output)
    return summary


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=HERE / "output")
    parser.add_argument("--copy-figures", action="store_true",
                        help="copy the figure into figures/ (tracked)")
    parser.add_argument("--figures-only", action="store_true",
                        help="only redraw the figure from the output's branches.nc and "
                        "rattle.json (seconds)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    if args.figures_only:
        draw_figures(args.output)
    else:
        result = main(args.output)
        log.info("done in %.1f s", result["total_s"])
    if args.copy_figures:
        (HERE / "figures").mkdir(exist_ok=True)
        shutil.copy(args.output / "rattle.png", HERE / "figures" / "rattle.png")
