"""Vibro-impact energy sink (VI-NES): its two-impact motions against their closed form.

A linear primary (mass 1, stiffness 1, damping ratio ``zeta``) forced near its 1:1
resonance carries a light free ball (mass ratio ``mu = 0.05``) in a cavity
``s = x2 - x1`` in ``[-b_low, b]``. As an :class:`impactcont.ImpactOscillator`::

    M = diag(1, mu), K = diag(1, 0), F = [1, 0], C = 2 eta K (eta = zeta),
    stops = Stops(mass=2, relative_to=1, b_low=b_low, R_low=R_low), R, b,
    F_static = [-g, -mu g]                        # a vertical VI-NES (g = 0: horizontal)

Three machines: symmetric walls; walls of different restitution (``R_low != R``); a
vertical VI-NES (gravity). This study

1. finds every motion with one impact on each wall per forcing period ("UL") in closed
   form (:mod:`closed_form`, derived in the README: one scalar equation in the first
   flight time) on a grid of forcing frequencies, solves each with
   ``multi_impact_orbit`` seeded there, and compares them (phase, states after both
   impacts, flight times, approach speeds, multipliers, stability and physical verdicts);
2. asks the simulator at a few points; checks that an off-centre cavity (``b_low != b``)
   is the centred one translated (the ball is free);
3. continues the symmetric machine's motion in omega and in ``R_low`` (special points,
   checked in the closed form), follows its symmetry-breaking point in (omega, b) with
   ``multi_impact_curve``, and maps (omega, b) with ``multi_impact_map``, checked against
   the closed form on a sub-grid.

Writes ``vi_nes.json``, ``branches.nc``, ``vi_nes.png`` and ``vi_nes_plane.png``. Run::

    PYTHONPATH=. python studies/vi_nes/run.py [--output DIR] [--copy-figures]
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
from matplotlib.ticker import MultipleLocator

import impactcont as ic
from impactcont.plots import SPECIAL_MARKERS
from impactcont.plots.branches import SPECIAL_NAMES, fit_text, label_specials, legend_below
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
from closed_form import VINES, Motion, ul_motions  # noqa: E402

log = logging.getLogger("vi_nes")

MU, ZETA, R, B = 0.05, 0.02, 0.6, 5.0  # mass ratio, primary damping, restitution, half cavity
VARIANTS: dict[str, dict[str, float]] = {
    "symmetric": {},
    "restitution": {"R_low": 0.3},  # the lower wall softer
    "vertical": {"g": 0.5},  # gravity along the cavity, per unit mass, in F/(k) w_n^2
}
OMEGAS = np.linspace(0.7, 1.3, 49)
PLANE = {"omega": (0.7, 1.3), "b": (1.0, 10.0)}
MAP_GRID = (61, 37)
DPI = 150  # of the PNGs (7 in wide: 1050 pixels)
SIMULATED = (("symmetric", 1.2), ("restitution", 1.2), ("vertical", 1.2), ("symmetric", 1.0),
             ("vertical", 0.9))


def params(variant: str, r: float, b: float = B) -> VINES:
    kw = {"r": float(r), "mu": MU, "zeta": ZETA, "b": b, "b_low": b, "R": R, "R_low": R}
    kw.update(VARIANTS[variant])
    return VINES(**kw)


def system(p: VINES, mirror: bool = False) -> ic.ImpactOscillator:
    """The VI-NES as an ImpactOscillator (primary x1, ball x2, walls s = b, -b_low);
    ``mirror=True`` (symmetric walls only): the lower wall at ``-b`` moves with ``b``."""
    if mirror:
        if not (p.b_low == p.b and p.R_low == p.R):
            raise ValueError(f"mirror needs symmetric walls: {p}")
        stops = ic.Stops(mass=2, relative_to=1, mirror=True)
    else:
        stops = ic.Stops(mass=2, relative_to=1, b_low=p.b_low, R_low=p.R_low)
    return ic.ImpactOscillator(M=np.diag([1.0, p.mu]), K=[[1.0, 0.0], [0.0, 0.0]],
                               F=[1.0, 0.0], R=p.R, b=p.b, omega=p.r, eta=p.zeta,
                               F_static=[-p.g, -p.mu * p.g], stops=stops)


def guess(m: Motion) -> dict[str, Any]:
    return {"delta": m.delta, "flight_times": list(m.flight_times),
            "states": [m.state_upper, m.state_lower], "pattern": "UL"}


def compare(variant: str, m: Motion) -> dict[str, Any]:
    """The package's motion seeded by the closed form; the differences."""
    orbit = ic.multi_impact_orbit(system(m.p), 1, 2, guess(m))
    k = orbit.pattern.index("U")
    order = [k, (k + 1) % 2]
    scale = max(1.0, float(np.max(np.abs(m.state_upper))), float(np.max(np.abs(m.state_lower))))
    states = float(max(np.max(np.abs(orbit.states[order[0]] - m.state_upper)),
                       np.max(np.abs(orbit.states[order[1]] - m.state_lower)))) / scale
    approach = np.array([m.approach_upper, m.approach_lower])
    dv = float(np.max(np.abs(orbit.impact_velocities[order] - approach)))
    row = {"variant": variant, "omega": m.p.r, "t1_over_T": m.t1 / m.p.T, "delta": m.delta,
           "phase": abs(math.remainder(orbit.phases[k] - m.delta, 2 * math.pi)),
           "state": states,
           "flight_times": float(np.max(np.abs(orbit.flight_times[order] - m.flight_times))),
           "approach_speed": dv / max(1.0, float(np.max(np.abs(approach)))),
           "amplitude_cf": m.amplitude, "physical_cf": m.physical,
           "physical_pkg": bool(orbit.physical), "error_estimate": orbit.error_estimate,
           "spectral_radius_pkg": orbit.spectral_radius, "stable_pkg": bool(orbit.stable)}
    if m.physical:  # the closed form's map is the impact-to-impact map of a real motion
        row["spectral_radius_cf"] = float(np.max(np.abs(m.multipliers)))
        row["stable_cf"] = m.stable
        row["multipliers"] = max(float(np.min(np.abs(orbit.multipliers - q)))
                                 / max(1.0, abs(q)) for q in m.multipliers)
    return row


def agreement() -> dict[str, Any]:
    rows, failures = [], []
    for variant in VARIANTS:
        for r in OMEGAS:
            for m in ul_motions(params(variant, r)):
                try:
                    rows.append(compare(variant, m))
                except ic.NoPeriodicMotionError as exc:
                    failures.append({"variant": variant, "omega": float(r),
                                     "t1_over_T": m.t1 / m.p.T, "error": str(exc)})
    keys = ("phase", "state", "flight_times", "approach_speed")
    worst = {key: max(row[key] for row in rows) for key in keys}
    phys = [r for r in rows if r["physical_cf"]]
    worst["multipliers (physical)"] = max(r["multipliers"] for r in phys)
    # central differences lose digits where the map expands strongly (rho ~ 1e3 .. 1e4)
    worst["multipliers (physical, rho < 100)"] = max(r["multipliers"] for r in phys
                                                     if r["spectral_radius_cf"] < 100)
    decided = [r for r in phys if abs(r["spectral_radius_cf"] - 1.0) > 1e-4]
    summary = {
        "motions": len(rows), "physical": len(phys),
        "asymmetric_t1": sum(abs(r["t1_over_T"] - 0.5) > 1e-6 for r in rows),
        "newton_failures": failures, "max_relative_difference": worst,
        "stable_verdict_agrees": [int(sum(r["stable_cf"] == r["stable_pkg"] for r in decided)),
                                  len(decided)],
        "physical_verdict_agrees": [int(sum(r["physical_cf"] == r["physical_pkg"] for r in rows)),
                                    len(rows)],
        "physical_verdict_disagrees_at": [(r["variant"], r["omega"], r["t1_over_T"])
                                          for r in rows
                                          if r["physical_cf"] != r["physical_pkg"]],
        "largest_error_estimate": max(r["error_estimate"] for r in rows),
    }
    log.info("closed form vs package: %d motions, worst %s", len(rows), worst)
    return {"summary": summary, "rows": rows}


def simulator_checks() -> list[dict[str, Any]]:
    """The simulator from each physical closed-form motion: a stable one repeats its
    impacts (200 periods), an unstable one leaves."""
    out = []
    for variant, r in SIMULATED:
        p = params(variant, r)
        for m in ul_motions(p):
            if not m.physical:
                continue
            res = ic.simulate(system(p), m.state_upper, m.delta, 200.0)
            n = res.impact_times.size
            expect = [m.state_lower, m.state_upper]
            dev = [float(np.max(np.abs(res.impact_states[k] - expect[k % 2])))
                   for k in range(n)]
            stays = bool(n >= 399 and max(dev) < 1e-6)
            out.append({"variant": variant, "omega": r, "t1_over_T": m.t1 / p.T,
                        "stable_cf": m.stable, "impacts": int(n), "status": res.status.name,
                        "max_deviation": max(dev) if dev else None, "stays": stays,
                        "agrees": stays == m.stable})
            log.info("simulator %s r=%g t1/T=%.4f (%s): %d impacts, deviation %.2e, %s",
                     variant, r, m.t1 / p.T, "stable" if m.stable else "unstable", n,
                     max(dev) if dev else math.nan,
                     "agrees" if stays == m.stable else "DISAGREES")
    return out


def offset_cavity() -> dict[str, Any]:
    """An off-centre cavity (b = 6, b_low = 4) is the centred one (5, 5) with the ball
    translated by 1: the package's motions, primary identical, ball shifted."""
    p = params("restitution", 1.2)
    m = next(m for m in ul_motions(p) if m.physical)
    o1 = ic.multi_impact_orbit(system(p), 1, 2, guess(m))
    shifted = VINES(**{**p.__dict__, "b": 6.0, "b_low": 4.0})
    g = guess(m)
    g["states"] = [s + np.array([0.0, 1.0, 0.0, 0.0]) for s in g["states"]]
    o2 = ic.multi_impact_orbit(system(shifted), 1, 2, g)
    d = o2.states - o1.states
    return {"primary_and_velocities": float(np.max(np.abs(d[:, [0, 2, 3]]))),
            "ball_shift": [float(np.min(d[:, 1])), float(np.max(d[:, 1]))],
            "phase": abs(o2.delta - o1.delta),
            "multipliers": float(np.max(np.abs(np.sort_complex(o2.multipliers)
                                               - np.sort_complex(o1.multipliers))))}


def specials(ds: xr.Dataset, parameter: str) -> list[dict[str, Any]]:
    return [{"label": str(lab), parameter: float(v), "precision": float(pr)}
            for lab, v, pr in zip(ds["special_label"].values, ds[f"special_{parameter}"].values,
                                  ds["special_precision"].values, strict=True)]


def _cf_root(p: VINES, delta: float, t1_over_T: float = 0.5) -> Motion | None:
    """The closed-form UL motion nearest to a phase and a flight-time split."""
    ms = ul_motions(p)
    if not ms:
        return None
    return min(ms, key=lambda m: abs(math.remainder(m.delta - delta, 2 * math.pi))
               + abs(m.t1 / p.T - t1_over_T))


def beyond(groups: dict[str, xr.Dataset]) -> dict[str, Any]:
    info: dict[str, Any] = {}
    p = params("symmetric", 1.2)
    m = next(m for m in ul_motions(p) if m.physical and m.stable)
    seed = ic.multi_impact_orbit(system(p, mirror=True), 1, 2, guess(m))
    t0 = time.perf_counter()
    br = ic.multi_impact_continuation(seed, "omega", PLANE["omega"], ds_max=0.01,
                                      max_points=3000)
    groups["branch_omega"] = br
    sp = specials(br, "omega")
    info["omega_branch"] = {"points": int(br.sizes["point"]),
                            "seconds": time.perf_counter() - t0, "special_points": sp}
    # the closed form either side of each BP: the verdict changes, a multiplier near +1
    checks = []
    for s in sp:
        if s["label"] != "BP":
            continue
        k = int(np.argmin(np.abs(br["omega"].values - s["omega"])))
        delta = float(br["delta"].values[k])
        side = [(_cf_root(params("symmetric", s["omega"] + e), delta)) for e in (-1e-3, 1e-3)]
        at = _cf_root(params("symmetric", s["omega"]), delta)
        checks.append({**s, "closed_form_stable_either_side": [bool(q.stable) for q in side],
                       "closed_form_multiplier_minus_1_at_BP":
                           float(np.min(np.abs(at.multipliers - 1.0)))})
    info["omega_branch_closed_form"] = checks
    # the restitution of the lower wall as the parameter
    t0 = time.perf_counter()
    try:
        seed_low = ic.multi_impact_orbit(system(p), 1, 2, guess(m))  # b_low, R_low own
        bl = ic.multi_impact_continuation(seed_low, "R_low", (0.02, 0.99), ds_max=0.02,
                                          max_points=1500)
        groups["branch_R_low"] = bl
        sl = specials(bl, "R_low")
        info["R_low_branch"] = {"points": int(bl.sizes["point"]),
                                "seconds": time.perf_counter() - t0, "special_points": sl}
        rows = []
        for s in sl:
            if s["label"] != "PD":
                continue
            k = int(np.argmin(np.abs(bl["R_low"].values - s["R_low"])))
            delta = float(bl["delta"].values[k])
            t1 = float(bl["flight_time_k"].values[k, 0]) / p.T \
                if "flight_time_k" in bl else 0.5
            q = _cf_root(VINES(**{**p.__dict__, "R_low": s["R_low"]}), delta, t1)
            rows.append({**s, "closed_form_multiplier_plus_1": float(
                np.min(np.abs(q.multipliers + 1.0)))})
        info["R_low_branch_closed_form"] = rows
    except Exception as exc:  # report what the package says
        log.warning("continuation in R_low: %s: %s", type(exc).__name__, exc)
        info["R_low_branch_error"] = f"{type(exc).__name__}: {exc}"
    # the BP curves in (omega, b); about a dozen points of each re-solved by the closed form
    labels = br["special_label"].values.tolist()
    info["curves"] = {}
    for which in range(labels.count("BP")):
        t0 = time.perf_counter()
        name = f"BP{which}"
        try:
            cv = ic.multi_impact_curve(br, "BP", which, parameter="b", bounds=PLANE,
                                       ds_max=0.05, max_points=800)
        except Exception as exc:
            log.warning("curve %s: %s: %s", name, type(exc).__name__, exc)
            info["curves"][name] = {"error": f"{type(exc).__name__}: {exc}"}
            continue
        groups[f"curve_{name}"] = cv
        om, bb, dl = cv["omega"].values, cv["b"].values, cv["delta"].values
        err = []
        for i in range(0, om.size, max(1, om.size // 12)):
            q = _cf_root(params("symmetric", float(om[i]), float(bb[i])), float(dl[i]))
            if q is not None:
                err.append(float(np.min(np.abs(q.multipliers - 1.0))))
        info["curves"][name] = {"points": int(om.size), "seconds": time.perf_counter() - t0,
                                "omega_range": [float(om.min()), float(om.max())],
                                "b_range": [float(bb.min()), float(bb.max())],
                                "closed_form_multiplier_minus_1": err}
    # the stability map; a sub-grid re-solved by the closed form
    t0 = time.perf_counter()
    grid = {"omega": np.linspace(*PLANE["omega"], MAP_GRID[0]),
            "b": np.linspace(*PLANE["b"], MAP_GRID[1])}
    try:
        mp = ic.multi_impact_map(seed, ("omega", "b"), grid)
        groups["map"] = mp
        info["map"] = {"cells": int(mp["found"].size), "found": int(mp["found"].sum()),
                       "seconds": time.perf_counter() - t0}
        same, cells, worst = 0, 0, 0.0
        for i in range(0, MAP_GRID[0], 6):
            for j in range(0, MAP_GRID[1], 6):
                if not bool(mp["found"].values[i, j]):
                    continue
                r, b = float(grid["omega"][i]), float(grid["b"][j])
                t1 = float(mp["flight_time_k"].values[i, j, 0]) * r / (2 * math.pi)
                q = _cf_root(params("symmetric", r, b), float(mp["delta"].values[i, j]), t1)
                if q is None:
                    continue
                worst = max(worst, abs(math.remainder(q.delta - float(mp["delta"].values[i, j]),
                                                      2 * math.pi)))
                if q.physical:
                    cells += 1
                    same += int(q.stable == bool(mp["stable"].values[i, j]))
        info["map_vs_closed_form"] = {"max_phase_difference": worst,
                                      "physical_cells_checked": cells,
                                      "same_stability": same}
    except Exception as exc:
        log.warning("multi_impact_map: %s: %s", type(exc).__name__, exc)
        info["map_error"] = f"{type(exc).__name__}: {exc}"
    return info


#: Each machine in the figures: its name and what differs from the symmetric one.
VARIANT_TITLES = {"symmetric": rf"symmetric: $R = R_{{low}} = {R:g}$, $g = 0$",
                  "restitution": r"softer lower wall: $R_{low} = 0.3$",
                  "vertical": r"vertical cavity: $g = 0.5$"}
OMEGA_LABEL = r"$\omega/\omega_n$"


def agreement_figure(rows: list[dict[str, Any]], width: float = 7.0) -> Figure:
    """The closed form against the package (``rows.json``): a 2 x 2 grid (one column below
    5 in). Three panels of amplitudes, one per machine (closed form's physical UL motions
    filled: stable, hollow: unstable; the package's stable motions +; the primary alone
    dashed), and the differences package - closed form on a log axis (exact zeros in their
    own row)."""
    fig, axes = panel_figure(4, width, extra_height=1.1)
    rows = [{**r, **{k: str(r.get(k)) == "True"  # rows.json holds numpy's booleans as text
                     for k in ("physical_cf", "stable_cf", "stable_pkg")}} for r in rows]
    r0 = np.linspace(*PLANE["omega"], 400)
    bare = 1 / np.abs(1 - r0 ** 2 + 2j * ZETA * r0)
    ylabel = r"amplitude $\max|x_1 - x_{1,s}|$ [$F/k$]"  # about the static position
    for ax, variant in zip(axes[:3], VARIANTS, strict=True):
        rr = [r for r in rows if r["variant"] == variant and r["physical_cf"]]

        def pick(cond: Any, rr: list[dict[str, Any]] = rr) -> tuple[list[float], list[float]]:
            sel = [r for r in rr if cond(r)]
            return [r["omega"] for r in sel], [r["amplitude_cf"] for r in sel]

        series_plot(ax, [
            Series(r0, bare, "primary alone (no ball)", color="k", linestyle="--",
                   linewidth=0.8),
            Series(*pick(lambda r: not r["stable_cf"]), "closed form, unstable", color="0.45",
                   linestyle="none", marker="o", markersize=5),
            Series(*pick(lambda r: r["stable_cf"]), "closed form, stable", color="0.45",
                   linestyle="none", marker="o", filled=True, markersize=5),
            Series(*pick(lambda r: r["stable_pkg"]), "package, stable", color="k",
                   linestyle="none", marker="+", markersize=7)],
            xlabel=OMEGA_LABEL, ylabel=ylabel, title=VARIANT_TITLES[variant])
        ax.set_ylim(0, 30)
    series = [Series([r["omega"] for r in rows if r["variant"] == v],
                     [max(r["phase"], r["state"], r["flight_times"]) for r in rows
                      if r["variant"] == v], f"difference, {v}", color=f"C{i}",
                     linestyle="none", marker="os^"[i], markersize=3.5)
              for i, v in enumerate(VARIANTS)]
    series_plot(axes[3], series, xlabel=OMEGA_LABEL, yscale="log",
                ylabel=r"$\max |\Delta|$ of phase, states, flights",
                title="Package against closed form, every root")
    figure_legend(fig)
    fig.suptitle(rf"Vibro-impact NES, $\mu = {MU:g}$, $\zeta = {ZETA:g}$, "
                 rf"$b = b_{{low}} = {B:g}$: motions with one impact on each wall",
                 fontsize="medium")
    fit_labels(fig)
    return fig


def plane_figure(groups: dict[str, xr.Dataset], width: float = 7.0) -> Figure:
    """The symmetric machine in (omega, b): the package's map of the UL motion (regions and
    boundaries, :func:`impactcont.plots.maps.multi_impact_map_diagram`), the BP curves
    on top and the special points of the branch in omega at ``b = B``, labelled."""
    # one column: the legend below takes one line per entry (about 10)
    fig, (ax,) = panel_figure(1, width, aspect=0.62, extra_height=1.6 if width >= 5.0 else 3.0)
    handles: list[Any] = []
    if "map" in groups:
        multi_impact_map_diagram(groups["map"], ax=ax, title="")
        handles = take_legend(ax)
    curves = [groups[n] for n in groups if n.startswith("curve_BP")]
    for cv in curves:
        ax.plot(cv["omega"].values, cv["b"].values, "-", color="C3", lw=1.6, zorder=3)
    if curves:
        handles.append(Line2D([], [], color="C3", lw=1.6, label="BP curves (continued)"))
    marks = []
    if "branch_omega" in groups:
        marks = [(s["omega"], B, s["label"]) for s in specials(groups["branch_omega"], "omega")]
        for label in dict.fromkeys(m[2] for m in marks):
            xy = np.array([m[:2] for m in marks if m[2] == label])
            style = {"linestyle": "none", "marker": SPECIAL_MARKERS[label], "markersize": 6,
                     "markerfacecolor": "white", "markeredgecolor": "k"}
            ax.plot(xy[:, 0], xy[:, 1], zorder=4, **style)
            handles.append(Line2D([], [], label=f"{label} {SPECIAL_NAMES[label]} "
                                  rf"(branch at $b = {B:g}$)", **style))
    ax.set_xlim(*PLANE["omega"])
    ax.set_ylim(*PLANE["b"])
    # fixed ticks: the layout makes room for the tick at the right edge (an automatic
    # locator added it after the layout had widened the axes: cut at 3.5 in)
    ax.xaxis.set_major_locator(MultipleLocator(0.1))
    ax.set_xlabel(OMEGA_LABEL)
    ax.set_ylabel(r"half cavity $b = b_{low}$ [$F/k$]")
    ax.set_title(rf"Symmetric vibro-impact NES, $\mu = {MU:g}$, $\zeta = {ZETA:g}$, "
                 rf"$R = {R:g}$: motions with one impact on each wall", fontsize="medium")
    legend_below(ax, handles)
    fig.draw_without_rendering()
    fit_text(ax.title)
    if marks:
        label_specials(ax, marks)
    return fig


def draw_figures(output: Path, width: float = 7.0) -> list[Path]:
    """Draw ``vi_nes.png`` and ``vi_nes_plane.png`` from the stored ``rows.json`` and
    ``branches.nc`` of ``output``."""
    rows = json.loads((output / "rows.json").read_text())
    groups = {}
    if (output / "branches.nc").exists():
        tree = ic.load(output / "branches.nc")
        groups = {name: node.to_dataset() for name, node in tree.children.items()}
    paths = []
    for name, fig in (("vi_nes.png", agreement_figure(rows, width)),
                      ("vi_nes_plane.png", plane_figure(groups, width))):
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
    offset = offset_cavity()
    log.info("off-centre cavity: %s", offset)
    groups: dict[str, xr.Dataset] = {}
    t0 = time.perf_counter()
    more = beyond(groups)
    timings["beyond_s"] = time.perf_counter() - t0
    if groups:
        ic.save(groups, output / "branches.nc")
    summary = {"parameters": {"mu": MU, "zeta": ZETA, "R": R, "b": B, "variants": VARIANTS,
                              "omega": [float(OMEGAS[0]), float(OMEGAS[-1]), OMEGAS.size]},
               "agreement": agree["summary"], "simulator": sim, "offset_cavity": offset,
               "beyond": more, "timings": timings, "total_s": time.perf_counter() - t_start}
    (output / "vi_nes.json").write_text(json.dumps(summary, indent=2, default=str))
    (output / "rows.json").write_text(json.dumps(agree["rows"], indent=1, default=str))
    draw_figures(output)
    return summary


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=HERE / "output")
    parser.add_argument("--copy-figures", action="store_true",
                        help="copy the figures into figures/ (tracked)")
    parser.add_argument("--figures-only", action="store_true",
                        help="only redraw the figures from the output's rows.json and "
                        "branches.nc (seconds)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    if args.figures_only:
        draw_figures(args.output)
    else:
        result = main(args.output)
        log.info("done in %.1f s", result["total_s"])
    if args.copy_figures:
        (HERE / "figures").mkdir(exist_ok=True)
        for name in ("vi_nes.png", "vi_nes_plane.png"):
            shutil.copy(args.output / name, HERE / "figures" / name)
