"""Impact damper: the symmetric two-impact motion against its closed form, and beyond.

The system of Masri & Caughey (1966): a primary mass on a spring and a damper, forced
harmonically, with a free particle (mass ratio ``mu``) in a cavity of length ``d`` of the
primary. As an :class:`impactcont.ImpactOscillator` (units: ``F/k`` for lengths, ``1/w_n``
for time)::

    M = diag(1, mu), K = diag(1, 0), F = [1, 0], C = 2 eta K (eta = zeta), R = e,
    b = d/2, stops = Stops(mass=2, relative_to=1, mirror=True)     # s = x2 - x1 in [-b, b]

This study

1. solves the symmetric two-impact motion ("UL", one impact on each wall per forcing
   period, ``X(t + T/2) = -X(t)``) in closed form (:mod:`closed_form`, derived in the
   README) over a grid of forcing frequencies and three clearances, and solves the same
   motion with the package (``multi_impact_orbit`` seeded by the closed form); compares
   them point by point (impact phase, particle and primary velocities before and after
   the impact, amplitude of the primary, multipliers and the stability verdict);
2. asks the event-driven simulator at a few points (a stable motion repeats, an unstable
   one leaves);
3. continues the motion with the package in omega and in the clearance (special points),
   follows its stability boundary in (omega, b) with ``multi_impact_curve`` against the
   closed form's boundary, and computes the package's stability map of the plane
   (``multi_impact_map``), compared with the closed form cell by cell (existence of the
   motion, its phase, spectral radius, physical and stable flags) and drawn with the
   closed form's boundary and the package's curves on top.

Writes ``impact_damper.json``, ``branches.nc``, ``impact_damper.png`` and
``impact_damper_plane.png`` into the output directory. Run::

    PYTHONPATH=. python studies/impact_damper/run.py [--output DIR] [--copy-figures]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # tiny matrices: threads only cost

import argparse
import json
import logging
import math
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

import impactcont as ic
from impactcont.analysis.curves import multi_impact_curve_crossings
from impactcont.plots.branches import SPECIAL_NAMES, fit_text, legend_below
from impactcont.plots.maps import multi_impact_map_diagram
from impactcont.plots.series import (
    Series,
    figure_legend,
    fit_labels,
    panel_figure,
    series_plot,
    take_legend,
)

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from closed_form import SymmetricMotion, symmetric_motions  # noqa: E402

log = logging.getLogger("impact_damper")

MU, E, ZETA = 0.2, 0.8, 0.05  # mass ratio, restitution, damping ratio of the primary
CLEARANCES = (1.0, 2.0, 4.0)  # d = 2 b, in units of F/k
OMEGAS = np.linspace(0.6, 3.0, 49)
PLANE = {"omega": (0.5, 3.5), "b": (0.1, 3.0)}
PLANE_GRID = (151, 59)  # omega x b, for the closed form's and the package's maps
MAP_MAX_CHANGE = 2.0  # multi_impact_map's max_change (default 0.5: README, stability map)
CURVE_POINTS = 600  # enough for each curve of the study's box (the NS curve: 260)
DPI = 150  # of the PNGs (7 in wide: 1050 pixels)
SIMULATED = ((1.5, 2.0), (2.5, 2.0), (1.0, 1.0), (2.0, 4.0))  # (r, d) for the simulator


def system(omega: float, b: float) -> ic.ImpactOscillator:
    """The impact damper as an ImpactOscillator (primary x1, particle x2, walls s = +-b)."""
    return ic.ImpactOscillator(M=np.diag([1.0, MU]), K=[[1.0, 0.0], [0.0, 0.0]],
                               F=[1.0, 0.0], R=E, b=b, omega=omega, eta=ZETA,
                               stops=ic.Stops(mass=2, relative_to=1, mirror=True))


def guess(m: SymmetricMotion) -> dict[str, Any]:
    """The closed-form motion as a Newton guess for the package (the exact motion)."""
    T2 = math.pi / m.r
    return {"delta": m.delta, "flight_times": [T2, T2], "states": [m.state, -m.state],
            "pattern": "UL"}


def package_amplitude(orbit: ic.MultiImpactOrbit, num: int = 4001) -> float:
    """``max |x1|`` from the package's exact time series: per flight, the largest interior
    sample refined by the vertex of the parabola through it and its neighbours (error
    O(h^3)), and the values at the impacts (where ``x1'`` jumps: a corner)."""
    _, X = orbit.time_series(num)
    best = float(np.max(np.abs(orbit.states[:, 0])))
    for x in np.abs(X[:, 0]).reshape(orbit.p, num):
        i = int(np.argmax(x))
        if 0 < i < num - 1:
            a, b, c = x[i - 1], x[i], x[i + 1]
            best = max(best, float(b + (a - c) ** 2 / (8.0 * (2 * b - a - c))))
    return best


def compare(m: SymmetricMotion) -> dict[str, Any]:
    """The package's motion seeded by the closed form; the differences."""
    orbit = ic.multi_impact_orbit(system(m.r, 0.5 * m.d), 1, 2, guess(m))
    k = orbit.pattern.index("U")  # the upper-wall impact: the closed form's t = 0
    X = orbit.states[k]
    pre_rel = orbit.impact_velocities[k]  # s' just before the upper-wall impact
    scale = max(1.0, float(np.max(np.abs(m.state))))
    rho_cf = float(np.max(np.abs(m.multipliers)))
    # each closed-form multiplier against the nearest of the package's
    mult = max(float(np.min(np.abs(orbit.multipliers - q))) / max(1.0, abs(q))
               for q in m.multipliers)
    amp = package_amplitude(orbit)
    return {
        "omega": m.r, "d": m.d, "root_delta": m.delta,
        "phase": abs(math.remainder(orbit.phases[k] - m.delta, 2 * math.pi)),
        "state": float(np.max(np.abs(X - m.state))) / scale,
        "impact_velocity": abs(pre_rel - m.impact_velocity) / max(1.0, m.impact_velocity),
        "amplitude": abs(amp - m.amplitude) / m.amplitude,
        "multipliers": mult,
        "spectral_radius_cf": rho_cf, "spectral_radius_pkg": orbit.spectral_radius,
        "stable_cf": bool(m.stable), "stable_pkg": bool(orbit.stable),
        "physical_cf": bool(m.physical), "physical_pkg": bool(orbit.physical),
        "flight_times": float(np.max(np.abs(orbit.flight_times - math.pi / m.r))),
        "error_estimate": orbit.error_estimate,
        "amplitude_cf": m.amplitude, "v1_before": m.v1_before, "u_before": m.u_before,
    }


def agreement() -> dict[str, Any]:
    """Closed form against the package on OMEGAS x CLEARANCES (both roots)."""
    rows, failures = [], []
    for d in CLEARANCES:
        for r in OMEGAS:
            for m in symmetric_motions(float(r), d, MU, E, ZETA):
                try:
                    rows.append(compare(m))
                except ic.NoPeriodicMotionError as exc:
                    failures.append({"omega": float(r), "d": d, "delta": m.delta,
                                     "error": str(exc)})
    keys = ("phase", "state", "impact_velocity", "amplitude", "multipliers", "flight_times")
    worst = {key: max(row[key] for row in rows) for key in keys}
    # the stability verdict where it is not on the knife edge (|rho - 1| > 1e-9)
    decided = [r for r in rows if abs(r["spectral_radius_cf"] - 1.0) > 1e-9]
    summary = {
        "motions": len(rows), "newton_failures": failures, "max_relative_difference": worst,
        "stable_verdict_agrees": [int(sum(r["stable_cf"] == r["stable_pkg"] for r in decided)),
                                  len(decided)],
        "physical_verdict_agrees": [int(sum(r["physical_cf"] == r["physical_pkg"]
                                            for r in rows)), len(rows)],
        "largest_error_estimate": max(r["error_estimate"] for r in rows),
    }
    log.info("closed form vs package: %d motions, worst %s", len(rows), worst)
    return {"summary": summary, "rows": rows}


def simulator_checks() -> list[dict[str, Any]]:
    """The simulator from each closed-form motion: where stable and physical it repeats
    the motion's impacts; where unstable it leaves (rounding grows)."""
    out = []
    for r, d in SIMULATED:
        for m in symmetric_motions(r, d, MU, E, ZETA):
            if not m.physical:
                continue
            osc = system(r, 0.5 * d)
            res = ic.simulate(osc, m.state, m.delta, 300.0)
            n = res.impact_times.size
            # impact k + 1 (k = 0, 1, ...) alternates between -X0 and X0
            dev = [float(np.max(np.abs(res.impact_states[k] - (-1) ** (k + 1) * m.state)))
                   for k in range(n)]
            stays = bool(n > 500 and max(dev) < 1e-6)
            out.append({"omega": r, "d": d, "stable_cf": m.stable, "impacts": int(n),
                        "status": res.status.name, "max_deviation": max(dev) if dev else None,
                        "deviation_first_100": max(dev[:100]) if dev else None,
                        "stays": stays, "agrees": stays == m.stable})
            log.info("simulator at r=%g d=%g (%s): %d impacts, max deviation %.2e, %s", r, d,
                     "stable" if m.stable else "unstable", n, max(dev) if dev else math.nan,
                     "agrees" if stays == m.stable else "DISAGREES")
    return out


def stable_root(r: float, d: float) -> SymmetricMotion:
    return next(m for m in symmetric_motions(r, d, MU, E, ZETA) if m.stable and m.physical)


def specials(ds: xr.Dataset, parameter: str) -> list[dict[str, Any]]:
    return [{"label": str(lab), parameter: float(v), "precision": float(p),
             "status": str(st)}
            for lab, v, p, st in zip(ds["special_label"].values,
                                     ds[f"special_{parameter}"].values,
                                     ds["special_precision"].values,
                                     ds["special_status"].values, strict=True)]


def closed_form_plane() -> dict[str, np.ndarray]:
    """The closed form on the (omega, b) grid: is there a stable physical symmetric motion
    (either root), is there a physical one, and every root's phase, flags and spectral
    radius (``roots_*``, shape (omega, b, 2), NaN / False where a cell has fewer roots)."""
    om = np.linspace(*PLANE["omega"], PLANE_GRID[0])
    bb = np.linspace(*PLANE["b"], PLANE_GRID[1])
    ok = np.zeros((om.size, bb.size), bool)
    exists = np.zeros_like(ok)
    count = np.zeros(ok.shape, int)
    delta = np.full((*ok.shape, 2), np.nan)
    rho = np.full_like(delta, np.nan)
    phys = np.zeros(delta.shape, bool)
    stab = np.zeros_like(phys)
    for i, r in enumerate(om):
        for j, b in enumerate(bb):
            roots = symmetric_motions(float(r), 2 * float(b), MU, E, ZETA)
            count[i, j] = len(roots)
            for k, m in enumerate(roots):
                delta[i, j, k], phys[i, j, k], stab[i, j, k] = m.delta, m.physical, m.stable
                rho[i, j, k] = float(np.max(np.abs(m.multipliers)))
            ms = [m for m in roots if m.physical]
            exists[i, j] = bool(ms)
            ok[i, j] = any(m.stable for m in ms)
    return {"omega": om, "b": bb, "stable": ok, "physical": exists, "roots": count,
            "roots_delta": delta, "roots_rho": rho, "roots_physical": phys,
            "roots_stable": stab}


def _on_boundary(flag: np.ndarray) -> np.ndarray:
    """Cells with a grid neighbour (one step, diagonals included) of another value."""
    pad = np.pad(flag, 1, mode="edge")
    out = np.zeros(flag.shape, bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            out |= pad[1 + di:pad.shape[0] - 1 + di, 1 + dj:pad.shape[1] - 1 + dj] != flag
    return out


def map_vs_closed_form(mp: xr.Dataset, cf: dict[str, np.ndarray],
                       default: xr.Dataset) -> dict[str, Any]:
    """The package's map against the closed form, cell by cell.

    Each found cell is matched to the closed-form root of nearest impact phase (the map
    follows one family: one root per cell); compared are the phase, the spectral radius
    and the physical and stable flags of that root, and the region the study shades
    (a stable physical motion among either root). Existence: found where the closed form
    has a root. A cell whose verdict differs is located: its grid neighbours (one step)
    with another closed-form verdict put it on a boundary, and ``|rho - 1|`` says how
    close it is to the unit circle. ``default`` is the map with the package's default
    ``max_change``: the cells it does not find, and where they lie.
    """
    om, bb = cf["omega"], cf["b"]
    found = mp["found"].values
    has_root = cf["roots"] > 0
    pkg_phys, pkg_stab = mp["physical"].values, mp["stable"].values
    d_pkg = mp["delta"].values
    # the matched root (nearest phase) of every found cell
    gap = np.abs(np.remainder(cf["roots_delta"] - d_pkg[..., None] + np.pi, 2 * np.pi)
                 - np.pi)
    k = np.argmin(np.where(np.isnan(gap), np.inf, gap), axis=-1)[..., None]
    take = lambda a: np.take_along_axis(a, k, axis=-1)[..., 0]  # noqa: E731
    phase = np.where(found, take(gap), np.nan)
    cf_phys, cf_stab, cf_rho = take(cf["roots_physical"]), take(cf["roots_stable"]), \
        take(cf["roots_rho"])
    rho_diff = np.where(found, np.abs(mp["spectral_radius"].values - cf_rho)
                        / np.maximum(1.0, cf_rho), np.nan)
    region_pkg = found & pkg_phys & pkg_stab

    def located(mask: np.ndarray, verdict: np.ndarray) -> list[dict[str, Any]]:
        out = []
        for i, j in zip(*np.nonzero(mask), strict=True):
            near = verdict[max(i - 1, 0):i + 2, max(j - 1, 0):j + 2]
            out.append({"omega": float(om[i]), "b": float(bb[j]),
                        "on_boundary": bool(near.min() != near.max()),
                        "closed_form_rho": float(cf_rho[i, j]) if found[i, j] else None})
        return out

    n = int(found.size)
    same = lambda a, b, where: [int(np.sum((a == b) & where)), int(np.sum(where))]  # noqa: E731
    dfound = default["found"].values
    missed = has_root & ~dfound
    steps = [float(np.max(np.abs(mp["state_k"].values[i + 1, j, 0]
                                 - mp["state_k"].values[i, j, 0])))
             for i, j in zip(*np.nonzero(found[:-1] & found[1:] & missed[:-1]), strict=True)]
    return {
        "cells": n, "max_change": float(json.loads(mp.attrs["options"])["max_change"]),
        "found": int(found.sum()), "closed_form_has_root": int(has_root.sum()),
        "existence_agrees": [int(np.sum(found == has_root)), n],
        "phase_max": float(np.nanmax(phase)),
        "spectral_radius_max_relative": float(np.nanmax(rho_diff)),
        "physical_agrees": same(pkg_phys, cf_phys, found),
        "stable_agrees": same(pkg_stab, cf_stab, found),
        "region_agrees": [int(np.sum(region_pkg == cf["stable"])), n],
        # how hard the test is: cells one grid step from a change of the closed form's
        # verdict (region, stability of the matched root), the closest to |rho| = 1
        "region_boundary_cells": int(np.sum(_on_boundary(cf["stable"]))),
        "stability_boundary_cells": int(np.sum(found & _on_boundary(np.where(found, cf_stab,
                                                                           False)))),
        "closest_to_unit_circle": float(np.nanmin(np.where(found, np.abs(cf_rho - 1), np.nan))),
        "disagreements": {
            "existence": located(found != has_root, has_root),
            "physical": located(found & (pkg_phys != cf_phys), cf["physical"]),
            "stable": located(found & (pkg_stab != cf_stab), cf["stable"]),
            "region": located(region_pkg != cf["stable"], cf["stable"]),
        },
        "default_max_change": {
            "max_change": float(json.loads(default.attrs["options"])["max_change"]),
            "found": int(dfound.sum()),
            "not_found_with_root": int(missed.sum()),
            "of_which_stable_physical": int(np.sum(missed & cf["stable"])),
            "found_cells_agree": [int(np.sum(default["found"].values & found
                                             & (default["stable"].values == pkg_stab)
                                             & (default["physical"].values == pkg_phys))),
                                  int(dfound.sum())],
            "omega_range": ([float(om[np.nonzero(missed)[0].min()]),
                             float(om[np.nonzero(missed)[0].max()])] if missed.any()
                            else None),
            "largest_state_step_there": max(steps, default=None),
        },
    }


def boundary_crossings(b: float, lo: float, hi: float, num: int = 200
                       ) -> list[dict[str, Any]]:
    """Where the closed form's stable physical motion appears or disappears along omega
    at clearance b (the verdict bisected to 1e-10), and why: ``stability`` (a multiplier
    crosses the unit circle) or ``physical`` (a grazing or a zero-velocity impact)."""
    def flags(r: float) -> tuple[bool, bool]:
        ms = [m for m in symmetric_motions(r, 2 * b, MU, E, ZETA) if m.physical]
        return any(m.stable for m in ms), bool(ms)

    om = np.linspace(lo, hi, num)
    f = [flags(float(r))[0] for r in om]
    out = []
    for i in range(num - 1):
        if f[i] != f[i + 1]:
            a, c = float(om[i]), float(om[i + 1])
            while c - a > 1e-10:
                mid = 0.5 * (a + c)
                a, c = (mid, c) if flags(mid)[0] == f[i] else (a, mid)
            why = "stability" if flags(a)[1] and flags(c)[1] else "physical"
            out.append({"omega": 0.5 * (a + c), "why": why})
    return out


def beyond(summary: dict[str, Any], groups: dict[str, xr.Dataset]) -> dict[str, Any]:
    """What the package finds beyond the closed form: branches with special points in
    omega and in b, curves of the boundary of stable symmetric motion, a stability map."""
    info: dict[str, Any] = {}
    seed = ic.multi_impact_orbit(system(1.5, 1.0), 1, 2, guess(stable_root(1.5, 2.0)))
    t0 = time.perf_counter()
    try:
        br = ic.multi_impact_continuation(seed, "omega", PLANE["omega"], ds_max=0.02,
                                          max_points=1500)
    except Exception as exc:  # report what the package says; the comparison stands
        log.warning("continuation in omega failed: %s: %s", type(exc).__name__, exc)
        info["omega_branch_error"] = f"{type(exc).__name__}: {exc}"
        return info
    info["omega_branch"] = {"points": int(br.sizes["point"]),
                            "seconds": time.perf_counter() - t0,
                            "special_points": specials(br, "omega")}
    groups["branch_omega_b1"] = br
    # the special points against the closed form: re-solved there by the closed form
    checks = []
    for sp in info["omega_branch"]["special_points"]:
        ms = symmetric_motions(sp["omega"], 2.0, MU, E, ZETA)
        if sp["label"] in ("NS", "BP", "SN") and ms:
            rho = [float(np.max(np.abs(m.multipliers))) for m in ms]
            checks.append({**sp, "closed_form_rho": rho})
    info["special_points_in_closed_form"] = checks
    t0 = time.perf_counter()
    try:
        bb = ic.multi_impact_continuation(seed, "b", PLANE["b"], ds_max=0.02, max_points=1500)
        info["b_branch"] = {"points": int(bb.sizes["point"]),
                            "seconds": time.perf_counter() - t0,
                            "special_points": specials(bb, "b")}
        groups["branch_b_omega1.5"] = bb
    except Exception as exc:
        log.warning("continuation in b failed: %s: %s", type(exc).__name__, exc)
        info["b_branch_error"] = f"{type(exc).__name__}: {exc}"
    # curves of the stability boundary (NS, BP, SN of the symmetric motion) and GR
    info["curves"] = {}
    labels = br["special_label"].values.tolist()
    for kind in ("NS", "BP", "SN", "GR"):
        for which in range(labels.count(kind)):
            name = f"{kind}{which}"
            t0 = time.perf_counter()
            try:
                cv = ic.multi_impact_curve(br, kind, which, parameter="b", bounds=PLANE,
                                           ds_max=0.02, max_points=CURVE_POINTS)
            except Exception as exc:
                log.warning("curve %s: %s: %s", name, type(exc).__name__, exc)
                info["curves"][name] = {"error": f"{type(exc).__name__}: {exc}"}
                continue
            groups[f"curve_{name}"] = cv
            info["curves"][name] = {"points": int(cv.sizes["point"]),
                                    "seconds": time.perf_counter() - t0}
    # the stability map of the package over the same grid as the closed form's: with
    # MAP_MAX_CHANGE (the family's state moves up to ~1.5 per omega step near resonance)
    # and with the package's default max_change (which stops there: README)
    grid = {"omega": np.linspace(*PLANE["omega"], PLANE_GRID[0]),
            "b": np.linspace(*PLANE["b"], PLANE_GRID[1])}
    for name, options in (("map", {"max_change": MAP_MAX_CHANGE}), ("map_default", {})):
        t0 = time.perf_counter()
        try:
            mp = ic.multi_impact_map(seed, ("omega", "b"), grid, **options)
        except Exception as exc:
            log.warning("multi_impact_map: %s: %s", type(exc).__name__, exc)
            info[f"{name}_error"] = f"{type(exc).__name__}: {exc}"
            continue
        groups[name] = mp
        info[name] = {"points": int(mp["found"].size), "found": int(mp["found"].sum()),
                      "seconds": time.perf_counter() - t0, **options}
    return info


def curve_vs_closed_form(groups: dict[str, xr.Dataset]) -> list[dict[str, Any]]:
    """Where the package's curves cross b = const against the closed form's boundary of
    stable physical motion (bisected) at the same b: each closed-form crossing and the
    nearest curve crossing (NS/BP/SN for a change of stability, GR for one of physics)."""
    out = []
    for b in (0.5, 1.0, 1.5, 2.0):
        cf = boundary_crossings(b, *PLANE["omega"])
        pkg = []
        for name, ds in groups.items():
            if name.startswith("curve_"):
                pkg.extend({"curve": name[6:], "omega": float(c["omega"])}
                           for c in multi_impact_curve_crossings(ds, "b", b))
        for c in cf:
            kinds = ("GR",) if c["why"] == "physical" else ("NS", "BP", "SN")
            near = [p for p in pkg if p["curve"].startswith(kinds)]
            best = min(near, key=lambda p: abs(p["omega"] - c["omega"]), default=None)
            c["nearest_curve"] = best["curve"] if best else None
            c["distance"] = abs(best["omega"] - c["omega"]) if best else None
        out.append({"b": b, "closed_form_boundary": cf, "package_curves": pkg})
    return out


R_LABEL = r"$r = \omega/\omega_n$"


def agreement_figure(rows: list[dict[str, Any]], width: float = 7.0) -> Figure:
    """Left: the symmetric two-impact motion's amplitude, the closed form's lines (solid:
    stable, dotted: unstable) over the package's motions (hollow circles), the primary
    without the particle dashed. Right: package - closed form on a log axis, exact zeros in
    their own row. Side by side from 5 in, stacked below."""
    fig, (left, right) = panel_figure(2, width, extra_height=1.3)
    series = []
    for d, color in zip(CLEARANCES, ("C0", "C1", "C2"), strict=True):
        om = np.linspace(OMEGAS[0], OMEGAS[-1], 400)
        amp = np.full((2, om.size), np.nan)
        stab = np.zeros((2, om.size), bool)
        for i, r in enumerate(om):
            ms = sorted(symmetric_motions(float(r), d, MU, E, ZETA), key=lambda m: m.delta)
            for root, m in enumerate([m for m in ms if m.physical][:2]):
                amp[root, i], stab[root, i] = m.amplitude, m.stable
        pts = [r for r in rows if r["d"] == d and r["physical_pkg"]]
        series.append(Series([r["omega"] for r in pts],
                             [r["amplitude_cf"] * (1 + r["amplitude"]) for r in pts],
                             f"$d = {d:g}$: package", color=color, linestyle="none",
                             marker="o", markersize=4))
        for root in (0, 1):
            series.append(Series(om, np.where(stab[root], amp[root], np.nan),
                                 f"$d = {d:g}$: closed form, stable", color=color))
            series.append(Series(om, np.where(~stab[root], amp[root], np.nan),
                                 f"$d = {d:g}$: closed form, unstable", color=color,
                                 linestyle=":"))
    om = np.linspace(0.3, OMEGAS[-1], 400)
    series.append(Series(om, 1.0 / np.abs(1 - om ** 2 + 2j * ZETA * om),
                         "without the particle", color="k", linestyle="--", linewidth=0.8))
    series_plot(left, series, xlabel=R_LABEL,
                ylabel=r"primary's amplitude $\max|x_1|$ [$F/k$]",
                title="Symmetric two-impact motion")
    left.set_ylim(0, 4)
    worst = {k: max(r[k] for r in rows) for k in ("phase", "state", "amplitude", "multipliers")}
    om = [r["omega"] for r in rows]
    series_plot(right, [
        Series(om, [max(r["phase"], r["state"]) for r in rows],
               f"phase, state (max {max(worst['phase'], worst['state']):.1e})", color="C4",
               linestyle="none", marker="o", markersize=3),
        Series(om, [r["multipliers"] for r in rows],
               f"multipliers (max {worst['multipliers']:.1e})", color="C5", linestyle="none",
               marker="x", markersize=4),
        Series(om, [r["amplitude"] for r in rows],
               f"amplitude, sampled (max {worst['amplitude']:.1e})", color="C6",
               linestyle="none", marker="+", markersize=5)],
        xlabel=R_LABEL, ylabel=r"relative difference $|\Delta|$", yscale="log",
        title="Package against closed form")
    figure_legend(fig)
    fig.suptitle(rf"Impact damper, $\mu = {MU:g}$, $e = {E:g}$, $\zeta = {ZETA:g}$, "
                 r"cavity $d = 1, 2, 4$", fontsize="medium")
    fit_labels(fig)
    return fig


def _level_lines(ax: Any, omega: np.ndarray, b: np.ndarray, flag: np.ndarray,
                 **style: Any) -> None:
    """The boundary of the cells where ``flag`` (shape (omega, b)) holds, drawn as lines
    (``Line2D``, as the legend's entry for it; ``ax.contour`` draws a collection)."""
    import contourpy

    lines = contourpy.contour_generator(omega, b, flag.T.astype(float)).lines(0.5)
    for xy in lines:
        ax.plot(xy[:, 0], xy[:, 1], **style)


def plane_figure(cf: dict[str, np.ndarray], groups: dict[str, xr.Dataset],
                 info: dict[str, Any], width: float = 7.0) -> Figure:
    """The package's map (its regions and boundaries, ``multi_impact_map_diagram``), the
    closed form's boundary of stable physical motion and the package's curves on top."""
    fig, (ax,) = panel_figure(1, width, aspect=0.75, extra_height=1.8)
    handles: list[Any] = []
    if "map" in groups:
        multi_impact_map_diagram(groups["map"], ax=ax, title="")
        handles = take_legend(ax)
    else:  # no map: the closed form's region shaded
        ax.contourf(cf["omega"], cf["b"], cf["stable"].T.astype(float), levels=[0.5, 1.5],
                    colors=["C0"], alpha=0.2)
    _level_lines(ax, cf["omega"], cf["b"], cf["stable"], color="k", lw=1.6,
                 ls=(0, (2, 2)), zorder=3)
    handles.append(Line2D([], [], color="k", lw=1.6, ls=(0, (2, 2)),
                          label="closed form: boundary of stable physical motion"))
    if "map_default" in groups:
        found = groups["map_default"]["found"].values
        _level_lines(ax, cf["omega"], cf["b"], found, color="0.3", lw=1.0, ls=":", zorder=3)
        handles.append(Line2D([], [], color="0.3", lw=1.0, ls=":",
                              label="edge of the map with the default step limit "
                              "(4 times smaller)"))
    styles = {"NS": "C3", "BP": "C2", "SN": "C4", "GR": "C1"}
    seen = set()
    for name, ds in groups.items():
        if not name.startswith("curve_"):
            continue
        kind = name[6:8]
        ax.plot(ds["omega"].values, ds["b"].values, "-", color=styles[kind], lw=1.4,
                zorder=4)
        if kind not in seen:
            handles.append(Line2D([], [], color=styles[kind], lw=1.4,
                                  label=f"{kind} curve ({SPECIAL_NAMES[kind]})"))
        seen.add(kind)
    ax.set_xlim(*PLANE["omega"])
    ax.set_ylim(*PLANE["b"])
    ax.set_xlabel(R_LABEL)
    ax.set_ylabel(r"half the cavity $b = d/2$ [$F/k$]")
    legend_below(ax, handles)
    agree = info.get("map_vs_closed_form")
    note = "" if agree is None else (
        f", map and closed form agree at {agree['region_agrees'][0]} of "
        f"{agree['region_agrees'][1]} cells")
    ax.set_title(rf"Impact damper in $(\omega, b)$, $\mu = {MU:g}$, $e = {E:g}$, "
                 rf"$\zeta = {ZETA:g}$: symmetric two-impact motion{note}",
                 fontsize="medium")
    fig.draw_without_rendering()
    fit_text(ax.title)
    return fig


def draw_figures(output: Path, width: float = 7.0) -> list[Path]:
    """Draw ``impact_damper.png`` and ``impact_damper_plane.png`` from the stored
    ``rows.json``, ``closed_form_plane.npz``, ``branches.nc`` and ``impact_damper.json``."""
    rows = json.loads((output / "rows.json").read_text())
    with np.load(output / "closed_form_plane.npz") as stored:
        cf = {k: stored[k] for k in stored.files}
    groups = {}
    if (output / "branches.nc").exists():
        tree = ic.load(output / "branches.nc")
        groups = {name: node.to_dataset() for name, node in tree.children.items()}
    info = json.loads((output / "impact_damper.json").read_text())["beyond"]
    paths = []
    for name, fig in (("impact_damper.png", agreement_figure(rows, width)),
                      ("impact_damper_plane.png", plane_figure(cf, groups, info, width))):
        fig.savefig(output / name, dpi=DPI)
        paths.append(output / name)
        log.info("wrote %s", output / name)
    return paths


def main(output: Path) -> dict[str, Any]:
    output.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    agree = agreement()
    timings["agreement_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    sim = simulator_checks()
    timings["simulator_s"] = time.perf_counter() - t0
    groups: dict[str, xr.Dataset] = {}
    t0 = time.perf_counter()
    more = beyond(agree["summary"], groups)
    timings["package_beyond_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    cf = closed_form_plane()
    timings["closed_form_plane_s"] = time.perf_counter() - t0
    crossings = curve_vs_closed_form(groups)
    if "map" in groups and "map_default" in groups:
        more["map_vs_closed_form"] = map_vs_closed_form(groups["map"], cf,
                                                        groups["map_default"])
        log.info("map vs closed form: %s", {k: v for k, v in
                                            more["map_vs_closed_form"].items()
                                            if k != "disagreements"})
    (output / "rows.json").write_text(json.dumps(agree["rows"], indent=1, default=str))
    np.savez(output / "closed_form_plane.npz", **cf)
    if groups:
        ic.save(groups, output / "branches.nc")
    summary = {"parameters": {"mu": MU, "e": E, "zeta": ZETA, "d": CLEARANCES,
                              "omega": [float(OMEGAS[0]), float(OMEGAS[-1]), OMEGAS.size]},
               "agreement": agree["summary"], "simulator": sim, "beyond": more,
               "boundary_vs_curves": crossings, "timings": timings,
               "total_s": time.perf_counter() - t_start}
    (output / "impact_damper.json").write_text(json.dumps(summary, indent=2, default=str))
    draw_figures(output)
    return summary


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=HERE / "output")
    parser.add_argument("--copy-figures", action="store_true",
                        help="copy the figures into figures/ (tracked)")
    parser.add_argument("--figures-only", action="store_true",
                        help="only redraw the figures from the files of a finished run in "
                        "the output directory (seconds)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    if args.figures_only:
        draw_figures(args.output)
    else:
        result = main(args.output)
        log.info("done in %.1f s", result["total_s"])
    if args.copy_figures:
        (HERE / "figures").mkdir(exist_ok=True)
        for name in ("impact_damper.png", "impact_damper_plane.png"):
            shutil.copy(args.output / name, HERE / "figures" / name)
