"""Period-doubling cascades of N-p motions against the brute-force simulator.

For two systems,

* ``paper2dof``: the paper's example (Cao & Shu, section 4): n = 2, M = I,
  K = [[1, -1], [-1, 2]], eta = 0.1 (C = 2 eta K), R = 0.6, F = [1, 0], gap b = 0;
* ``chain3dof``: a chain of three unit masses and unit springs (eq. 2), forced on
  mass 1, with the same eta, R and b,

this study

1. continues the N-1 branches (N = 1, 2, 3) over an omega range;
2. follows the period-doubling cascade that starts at the first PD of the N = 1 branch by
   automatic branch switching (2-2, 4-4, 8-8, ... branches) and reports the PD points and
   the ratios of successive PD intervals;
3. follows the motion with one more impact born at the first grazing of a cascade branch;
4. sweeps omega up and down with the event-driven simulator (state carried from one omega
   to the next; transient discarded, impacts recorded) and classifies every attractor
   against the stable physical motions of the branches;
5. draws both in one bifurcation diagram per system (impact velocities of every impact).

Writes into the output directory ``branches.nc`` (one group per branch),
``brute_force.nc``, ``cascades.json`` (PD tables, ratios, agreement, timings),
``pd_table.md`` and ``<system>.png``. Run::

    .venv/bin/python studies/cascades/run.py [--output DIR] [--quick] [--copy-figures]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # tiny matrices: threads only cost

import argparse
import json
import logging
import math
import multiprocessing as mp
import shutil
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

import impactcont as ic
from impactcont.analysis.branch import multi_impact_continuation
from impactcont.analysis.switching import (
    grazing_switch,
    period_doubling_cascade,
    period_doubling_switch,
    special_orbit,
)
from impactcont.dataset.multi import impacts_of
from impactcont.orbit.multi_impact import multi_impact_orbit, primitive_orbit
from impactcont.plots.impacts import impact_diagram
from impactcont.plots.series import (
    MAX_WIDTH,
    figure_legend,
    fit_labels,
    inside_frame,
    markers_whole,
)

log = logging.getLogger("cascades")

HERE = Path(__file__).resolve().parent
DEFAULT_OUTPUT = HERE / "output"
FIGURES_DIR = HERE / "figures"
WORKERS = 2
DPI = 150  # of the PNGs (7 in wide: 1050 pixels)

SYSTEMS: dict[str, dict[str, Any]] = {
    "paper2dof": {
        "title": r"paper's 2-DOF system, $b = 0$, $R = 0.6$, $\eta = 0.1$",
        "build": {"M": np.eye(2), "K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0],
                  "R": 0.6, "b": 0.0, "eta": 0.1},
        "range": (1.55, 1.95), "zoom": (1.795, 1.825), "doublings": 7,
    },
    "chain3dof": {
        "title": r"3-DOF chain (unit masses and springs), $b = 0$, $R = 0.6$, $\eta = 0.1$",
        "build": {"masses": [1.0, 1.0, 1.0], "springs": [1.0, 1.0, 1.0],
                  "F": [1.0, 0.0, 0.0], "R": 0.6, "b": 0.0, "eta": 0.1},
        "range": (1.15, 1.45), "zoom": (1.325, 1.342), "doublings": 6,
    },
}
N_VALUES = (1, 2, 3)

FULL = {"doublings": None, "n_omega": 70, "transient": 150, "record": 40, "max_pattern": 16,
        "zoom_omega": 30, "full_children": 2, "new_branches": 6,
        "grazing_points": 250}
QUICK = {"doublings": 2, "n_omega": 10, "transient": 60, "record": 12, "max_pattern": 4,
         "zoom_omega": 0, "full_children": 0, "new_branches": 0,
         "grazing_points": 40}
NEW_BRANCH_MAX_PERIODS = 4   # simulated patterns this short seed new branches
PATTERN_TOL = 1e-6     # repetition tolerance of the simulated impact pattern
MATCH_TOL = 1e-5       # simulated and computed impact velocities agree to this
NEAR_TOL = 1e-2        # ... or are within this (slow convergence near a bifurcation)


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------
def oscillator(name: str, omega: float) -> ic.ImpactOscillator:
    """The system ``name`` of :data:`SYSTEMS` at forcing frequency ``omega``."""
    build = dict(SYSTEMS[name]["build"])
    if "masses" in build:
        return ic.ImpactOscillator.chain(omega=omega, **build)
    return ic.ImpactOscillator(omega=omega, **build)


def _clean(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        x = float(obj)
        return x if math.isfinite(x) else str(x)
    return obj


def _run_tasks(fn: Callable[..., Any], argsets: Sequence[tuple[Any, ...]], workers: int
               ) -> list[Any]:
    if workers > 1 and len(argsets) > 1 and "fork" in mp.get_all_start_methods():
        with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("fork")) as pool:
            futures = [pool.submit(fn, *args) for args in argsets]
            return [f.result() for f in futures]
    return [fn(*args) for args in argsets]


# ---------------------------------------------------------------------------------------------
# branches
# ---------------------------------------------------------------------------------------------
def compute_branches(name: str, quick: bool) -> dict[str, Any]:
    """N-1 branches, the cascade from the first N = 1 PD, and the grazing-born branch."""
    t0 = time.perf_counter()
    cfg = QUICK if quick else FULL
    lo, hi = SYSTEMS[name]["range"]
    branches: dict[str, xr.Dataset] = {}
    for N in N_VALUES:
        try:
            ds = ic.continuation(oscillator(name, 0.5 * (lo + hi)), N=N, parameter="omega",
                                 bounds=(lo, hi), components="start")
        except ic.NoPeriodicMotionError as exc:
            log.info("%s: no N=%d motion in range (%s)", name, N, exc)
            continue
        if ds["physical"].any():
            branches[f"{N}-1"] = ds
    t_n1 = time.perf_counter() - t0
    n1 = branches["1-1"]
    doublings = cfg["doublings"] or SYSTEMS[name]["doublings"]
    cascade = period_doubling_cascade(n1, 0, max_doublings=doublings, bounds=(lo, hi))
    # the cascade stops each child a few points after its PD; follow the first ones in full
    children = list(cascade.branches[1:])
    parent = n1
    for level in range(min(cfg["full_children"], len(children))):
        children[level] = period_doubling_switch(parent, _which_pd(parent, cascade.pd_values[
            level]), bounds=(lo, hi), max_points=600, ds_max=0.02)
        parent = children[level]
    for ds in children:
        branches[f"{ds.attrs['N']}-{impacts_of(ds)}"] = ds
    t_cascade = time.perf_counter() - t0 - t_n1
    pd_rows = []
    for i, value in enumerate(cascade.pd_values):
        ds = cascade.branches[i]
        orbit = _pd_orbit(ds, value)
        pd_rows.append({"branch": f"{ds.attrs['N']}-{impacts_of(ds)}", "omega": value,
                        "precision": cascade.pd_precision[i],
                        "physical": bool(cascade.pd_physical[i]),
                        "gap_min": orbit.gap_min, "min_impact_velocity": orbit.impact_velocity,
                        "multiplier_minus_one": float(np.min(np.abs(orbit.multipliers + 1)))})
    # the first grazing of a cascade branch on its physical part
    grazing = None
    for ds in cascade.branches[1:]:
        labels = ds["special_label"].values.tolist()
        if "GR" not in labels:
            continue
        gr_orbit = special_orbit(ds, "GR", 0)
        if abs(gr_orbit.impact_velocity) < 1e-6:
            continue  # a grazing impact (ZV at the same place), not an interior graze
        t1 = time.perf_counter()
        try:
            born = grazing_switch(ds, 0, bounds=(lo, hi), max_points=cfg["grazing_points"],
                                  ds_max=0.005)
        except (ic.NoPeriodicMotionError, ic.ParameterError) as exc:
            log.warning("%s: grazing switch failed: %s", name, exc)
            born = None
        grazing = {"parent": f"{ds.attrs['N']}-{impacts_of(ds)}",
                   "omega": float(ds["special_omega"].values[labels.index("GR")]),
                   "seconds": time.perf_counter() - t1, "found": born is not None}
        if born is not None:
            key = f"{born.attrs['N']}-{impacts_of(born)} (graze)"
            branches[key] = born
            phys = born["physical"].values
            grazing.update({"branch": key, "points": born.sizes["point"],
                            "physical_points": int(phys.sum()),
                            "stable_physical_points": int((phys & born["stable"].values).sum()),
                            "spectral_radius_range_physical": [
                                float(np.min(born["spectral_radius"].values[phys])),
                                float(np.max(born["spectral_radius"].values[phys]))]
                            if phys.any() else None,
                            "omega_range": [float(born["omega"].min()),
                                            float(born["omega"].max())],
                            "special": list(zip(born["special_label"].values.tolist(),
                                                born["special_omega"].values.tolist(),
                                                strict=True))})
        break
    seconds = time.perf_counter() - t0
    log.info("%s: %d branches in %.1f s (N-1 %.1f s, cascade %.1f s)", name, len(branches),
             seconds, t_n1, t_cascade)
    return {"name": name, "branches": branches, "pd": pd_rows,
            "ratios": cascade.ratios.tolist(), "cascade_message": cascade.message,
            "grazing": grazing, "seconds": {"total": seconds, "n1": t_n1,
                                            "cascade": t_cascade}}


def _which_pd(ds: xr.Dataset, value: float) -> int:
    """Index among the PD points of ``ds`` of the one at ``value``."""
    labels = ds["special_label"].values.tolist()
    pds = [k for k, lab in enumerate(labels) if lab == "PD"]
    return int(np.argmin([abs(ds["special_omega"].values[k] - value) for k in pds]))


def _pd_orbit(ds: xr.Dataset, value: float) -> Any:
    return special_orbit(ds, "PD", _which_pd(ds, value))


# ---------------------------------------------------------------------------------------------
# brute force
# ---------------------------------------------------------------------------------------------
def _simulate(osc: ic.ImpactOscillator, X: np.ndarray, phase: float, periods: float
              ) -> ic.SimulationResult:
    try:
        return ic.simulate(osc, X, phase, periods)
    except ValueError as exc:  # an impact on a search-window boundary: shift the windows
        log.warning("simulate at omega=%.6g: %s; retrying in two parts", osc.omega, exc)
        first = ic.simulate(osc, X, phase, 0.37)
        return ic.simulate(osc, first.final_state, first.final_phase, periods - 0.37)


def sweep(name: str, omegas: np.ndarray, quick: bool, start: tuple[np.ndarray, float] | None
          ) -> dict[str, Any]:
    """Simulate at each omega in order, carrying the state; record the impacts."""
    cfg = QUICK if quick else FULL
    t0 = time.perf_counter()
    if start is None:
        osc = oscillator(name, float(omegas[0]))
        orbit = max(ic.periodic_orbits(osc, 1), key=lambda o: (o.physical, o.stable))
        X, phase = orbit.state.copy(), orbit.delta
        X[1:] += 1e-3
    else:
        X, phase = start
    records = []
    for i, w in enumerate(omegas):
        osc = oscillator(name, float(w))
        transient = cfg["transient"] * (2 if i == 0 else 1)
        res = _simulate(osc, X, phase, transient)
        if not res.success:
            log.warning("%s omega=%.5f: %s", name, w, res.message)
        X, phase = res.final_state, res.final_phase
        rec = _simulate(osc, X, phase, cfg["record"])
        X, phase = rec.final_state, rec.final_phase
        T = 2 * math.pi / w
        P, p, resid = impact_pattern(rec.impact_times, rec.impact_velocities, T,
                                     cfg["max_pattern"])
        records.append({"omega": float(w), "velocities": rec.impact_velocities,
                        "times": rec.impact_times, "phases": rec.impact_phases,
                        "states": rec.impact_states, "P": P, "p": p, "residual": resid,
                        "status": rec.status.name})
    return {"records": records, "end": (X, phase), "seconds": time.perf_counter() - t0}


def impact_pattern(times: np.ndarray, velocities: np.ndarray, period: float,
                   max_periods: int) -> tuple[int, int, float]:
    """Smallest P <= max_periods such that the impacts repeat every P forcing periods.

    Returns ``(P, p, residual)``; ``(0, 0, 0)`` without impacts and ``(-1, -1, best)``
    when nothing repeats.
    """
    if times.size == 0:
        return 0, 0, 0.0
    vscale = max(1.0, float(np.max(np.abs(velocities))))
    best = math.inf
    for P in range(1, max_periods + 1):
        p = int(np.sum(times < times[0] + (P - 1e-6) * period))
        if p == 0 or times.size < 2 * p:
            continue
        resid = max(float(np.max(np.abs(times[p:] - times[:-p] - P * period))) / period,
                    float(np.max(np.abs(velocities[p:] - velocities[:-p]))) / vscale)
        best = min(best, resid)
        if resid < PATTERN_TOL:
            return P, p, resid
    return -1, -1, best


# ---------------------------------------------------------------------------------------------
# brute force against branches
# ---------------------------------------------------------------------------------------------
def branch_orbits_at(ds: xr.Dataset, omega: float) -> list[Any]:
    """The motions of a branch at ``omega`` (one per segment crossing it), re-solved exactly."""
    om = ds["omega"].values
    out = []
    N, p = int(ds.attrs["N"]), impacts_of(ds)
    for i in np.flatnonzero((np.minimum(om[:-1], om[1:]) <= omega)
                            & (np.maximum(om[:-1], om[1:]) >= omega)):
        j = i if abs(om[i] - omega) <= abs(om[i + 1] - omega) else i + 1
        if not (ds["physical"].values[i] or ds["physical"].values[i + 1]):
            continue
        osc = ic.dataset.oscillator_from_dataset(ds, int(j)).replace(omega=float(omega))
        if "impact" in ds.dims:
            guess = {"delta": float(ds["delta_k"].values[j, 0]),
                     "flight_times": ds["flight_time_k"].values[j] * om[j] / omega,
                     "states": ds["state_k"].values[j]}
        else:
            guess = {"delta": float(ds["delta"].values[j]),
                     "flight_times": [2 * math.pi * N / omega],
                     "states": ds["state"].values[j][None, :]}
        try:
            out.append(multi_impact_orbit(osc, N, p, guess))
        except ic.NoPeriodicMotionError:
            continue
    return out


def classify(records: list[dict[str, Any]], branches: dict[str, xr.Dataset]
             ) -> list[dict[str, Any]]:
    """For each simulated omega: which stable physical branch motion (if any) it is."""
    out = []
    for rec in records:
        w = rec["omega"]
        predicted = []
        for key, ds in branches.items():
            for orbit in branch_orbits_at(ds, w):
                if orbit.physical and orbit.stable:
                    predicted.append((key, orbit))
        v = np.asarray(rec["velocities"])
        verdict, match, distance = "no stable physical branch motion; ", None, math.inf
        for key, orbit in predicted:
            # distance of the recorded velocities to the motion's set of impact velocities
            d = float(np.max(np.min(np.abs(v[:, None] - orbit.impact_velocities[None, :]),
                                    axis=1))) if v.size else math.inf
            if d < distance:
                distance, match = d, (key, orbit)
        if match is not None and distance < MATCH_TOL and rec["P"] == match[1].N \
                and rec["p"] == match[1].p:
            verdict = f"on {match[0]}"
        elif match is not None and distance < NEAR_TOL:
            verdict = f"near {match[0]} (not settled)"
        else:
            pattern = ("no impact" if rec["P"] == 0 else
                       f"period {rec['P']}, {rec['p']} impacts" if rec["P"] > 0 else
                       "no period found (chaotic or long period)")
            verdict = ("no stable physical branch motion; " if not predicted else
                       "a different attractor than the stable branch motion(s); ") + pattern
        out.append({"omega": w, "verdict": verdict, "P": rec["P"], "p": rec["p"],
                    "distance": distance,
                    "predicted": [f"{k} ({o.N}-{o.p})" for k, o in predicted]})
    return out


def summarize(classes: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Runs of consecutive omegas with the same verdict."""
    runs: list[dict[str, Any]] = []
    for c in classes:
        if runs and runs[-1]["verdict"] == c["verdict"]:
            runs[-1]["omega_to"] = c["omega"]
            runs[-1]["count"] += 1
        else:
            runs.append({"verdict": c["verdict"], "omega_from": c["omega"],
                         "omega_to": c["omega"], "count": 1})
    return runs


def branches_from_simulation(name: str, records: list[dict[str, Any]],
                              classes: list[dict[str, Any]], branches: dict[str, xr.Dataset],
                              limit: int) -> dict[str, Any]:
    """Follow the periodic attractors of the sweep that no computed branch explains.

    Each unexplained pattern of at most :data:`NEW_BRANCH_MAX_PERIODS` periods seeds
    :func:`multi_impact_orbit` with the simulated impacts; a stable physical solution not
    on a known branch is continued over the whole range.
    """
    lo, hi = SYSTEMS[name]["range"]
    found: dict[str, xr.Dataset] = {}
    log_rows = []
    for rec, cls in zip(records, classes, strict=True):
        if len(found) >= limit:
            break
        P, p = rec["P"], rec["p"]
        if not (cls["verdict"].startswith(("no stable", "a different"))
                and 1 <= P <= NEW_BRANCH_MAX_PERIODS):
            continue
        osc = oscillator(name, rec["omega"])
        k = len(rec["times"])
        res = ic.SimulationResult(
            impact_times=rec["times"], impact_velocities=rec["velocities"],
            impact_phases=rec["phases"], impact_states=rec["states"].reshape(k, -1),
            final_time=0.0, final_state=rec["states"][-1], final_phase=0.0,
            status=ic.SimulationStatus.COMPLETED)
        try:
            # a pattern caught while still settling may be a shorter motion repeated
            orbit = primitive_orbit(multi_impact_orbit(osc, P, p, res))
        except ic.NoPeriodicMotionError as exc:
            log_rows.append({"omega": rec["omega"], "pattern": f"{P}-{p}", "result": str(exc)})
            continue
        P, p = orbit.N, orbit.p
        known = any(
            np.max(np.abs(np.sort(o.impact_velocities) - np.sort(orbit.impact_velocities)))
            < MATCH_TOL for ds in {**branches, **found}.values()
            if int(ds.attrs["N"]) == P and impacts_of(ds) == p
            for o in branch_orbits_at(ds, rec["omega"]))
        if known or not (orbit.physical and orbit.stable):
            log_rows.append({"omega": rec["omega"], "pattern": f"{P}-{p}",
                             "result": "already on a branch" if known else
                             f"not stable and physical ({orbit.reason or 'unstable'})"})
            continue
        ds = multi_impact_continuation(orbit, "omega", (lo, hi), max_points=400, ds_max=0.01)
        key = f"{P}-{p} (sim)"
        while key in branches or key in found:
            key += "'"
        found[key] = ds
        log_rows.append({"omega": rec["omega"], "pattern": f"{P}-{p}", "result": f"new {key}",
                         "points": ds.sizes["point"],
                         "special": list(zip(ds["special_label"].values.tolist(),
                                             ds["special_omega"].values.tolist(), strict=True))})
        log.info("%s: new %s branch from the simulation at omega=%.5f (%d points)", name, key,
                 rec["omega"], ds.sizes["point"])
    return {"branches": found, "log": log_rows}


# ---------------------------------------------------------------------------------------------
# figure and tables
# ---------------------------------------------------------------------------------------------
def draw(name: str, branches: dict[str, xr.Dataset], up: list[dict[str, Any]],
         down: list[dict[str, Any]], zoom_up: list[dict[str, Any]], path: Path,
         width: float = 7.0) -> None:
    """Save :func:`figure` to ``path``."""
    fig = figure(name, branches, up, down, zoom_up, width)
    fig.savefig(path, dpi=DPI)
    log.info("wrote %s", path)


def figure(name: str, branches: dict[str, xr.Dataset], up: list[dict[str, Any]],
           down: list[dict[str, Any]], zoom_up: list[dict[str, Any]], width: float = 7.0
           ) -> Figure:
    """Branches (physical parts) and the simulator's impacts, full range over the zoom on
    the cascade (its box marked), ``width`` inches wide, one legend under both."""
    if not 2.0 <= width <= MAX_WIDTH:
        raise ValueError(f"width must be in [2, {MAX_WIDTH}] inches; got {width!r}")
    fig = Figure(figsize=(width, 1.15 * width + 1.2), layout="constrained")
    axes = fig.subplots(2, 1)
    lo, hi = SYSTEMS[name]["zoom"]
    palette = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
               "tab:pink", "tab:gray", "tab:olive", "tab:cyan", "navy", "magenta", "lime",
               "teal", "maroon", "gold"]
    handles: dict[str, Any] = {}
    dots: list[tuple[Any, np.ndarray, np.ndarray, dict[str, Any]]] = []
    for ax, zoom in zip(axes, (False, True), strict=True):
        impact_diagram(branches, ax=ax, specials=("PD", "GR", "SN"), nonphysical=False,
                       colors=palette, legend="inside", zoom=False)
        legend = ax.get_legend()
        for h, text in zip(legend.legend_handles, legend.get_texts(), strict=True):
            h.set_label(text.get_text())
            handles.setdefault(text.get_text(), h)
        legend.remove()
        for recs, style, label in ((up + zoom_up, {"color": "black", "marker": "."},
                                    r"simulator, $\omega$ up"),
                                   (down, {"color": "0.55", "marker": "+"},
                                    r"simulator, $\omega$ down")):
            if not recs:
                continue
            x = np.concatenate([np.full(len(r["velocities"]), r["omega"]) for r in recs])
            y = np.concatenate([r["velocities"] for r in recs])
            dots.append((ax, x, y, style))  # drawn once the layout is final
            handles.setdefault(label, Line2D([], [], linestyle="none", label=label, **style))
        if zoom:
            ax.set_xlim(lo, hi)
            ax.set_ylim(bottom=-0.03)
            ax.set_title(rf"zoom, ${lo:g} \leq \omega \leq {hi:g}$", fontsize="medium")
        else:
            start, end = SYSTEMS[name]["range"]
            margin = 0.015 * (end - start)  # the sweeps' first and last omega off the frame
            ax.set_xlim(start - margin, end + margin)
            ax.set_ylim(bottom=-0.03)
            ax.set_title(SYSTEMS[name]["title"], fontsize="medium")
        ax.set_ylabel(r"impact velocity $\dot{x}_1(T_k^-)$ of every impact")
    figure_legend(fig, list(handles.values()))
    fit_labels(fig)
    for ax in axes:
        markers_whole(ax)
    (x0, x1), (y0, y1) = axes[1].get_xlim(), axes[1].get_ylim()
    axes[0].indicate_inset((x0, y0, x1 - x0, y1 - y0), edgecolor="0.35")
    for ax, x, y, style in dots:  # the layout is final: a dot the frame would cut is left out
        inside = inside_frame(ax, x, y, math.sqrt(7.0))
        ax.scatter(x[inside], y[inside], s=7, linewidths=0.6, alpha=0.7, zorder=4, **style)
    return fig


def pd_markdown(results: dict[str, dict[str, Any]]) -> str:
    lines = []
    for name, res in results.items():
        lines += [f"### {SYSTEMS[name]['title']}", "",
                  "| # | branch | PD at omega | precision | physical | gap_min | "
                  "interval | ratio |", "|---|---|---|---|---|---|---|---|"]
        pds = res["pd"]
        for i, row in enumerate(pds):
            interval = (f"{pds[i]['omega'] - pds[i - 1]['omega']:.6g}" if i else "")
            ratio = (f"{res['ratios'][i - 2]:.4f}" if i >= 2 else "")
            gap = row["gap_min"]
            gap_text = "inf" if not math.isfinite(gap) else f"{gap:.3g}"
            lines.append(f"| {i + 1} | {row['branch']} | {row['omega']:.11f} | "
                         f"{row['precision']:.1e} | {'yes' if row['physical'] else 'no'} | "
                         f"{gap_text} | {interval} | {ratio} |")
        lines.append("")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# main
# ---------------------------------------------------------------------------------------------
def main(output_dir: str | Path = DEFAULT_OUTPUT, quick: bool = False,
         workers: int = WORKERS, copy_figures: bool = False) -> dict[str, Any]:
    """Run the study; return the summary written to ``cascades.json``."""
    t0 = time.perf_counter()
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    cfg = QUICK if quick else FULL
    names = list(SYSTEMS)
    computed = _run_tasks(compute_branches, [(n, quick) for n in names], workers)
    t_branches = time.perf_counter() - t0
    sweeps_up = _run_tasks(
        sweep, [(n, np.linspace(*SYSTEMS[n]["range"], cfg["n_omega"]), quick, None)
                for n in names], workers)
    extra = []
    if cfg["zoom_omega"]:
        extra = _run_tasks(
            sweep, [(n, np.linspace(*SYSTEMS[n]["zoom"], cfg["zoom_omega"]), quick, None)
                    for n in names], workers)
    sweeps_down = _run_tasks(
        sweep, [(n, np.linspace(*SYSTEMS[n]["range"], cfg["n_omega"])[::-1], quick,
                 sweeps_up[i]["end"]) for i, n in enumerate(names)], workers)
    t_sweeps = time.perf_counter() - t0 - t_branches
    summary: dict[str, Any] = {"quick": quick, "config": cfg, "systems": {}}
    tree: dict[str, xr.Dataset] = {}
    brute: dict[str, xr.Dataset] = {}
    results = {}
    for i, name in enumerate(names):
        res = computed[i]
        results[name] = res
        for key, ds in res["branches"].items():
            tree[f"{name}_{key}"] = ds
        up, down = sweeps_up[i]["records"], sweeps_down[i]["records"]
        zoom_up = extra[i]["records"] if extra else []
        t1 = time.perf_counter()
        new = {"branches": {}, "log": []}
        if cfg["new_branches"]:
            first = classify(up + down, res["branches"])
            new = branches_from_simulation(name, up + down, first, res["branches"],
                                           cfg["new_branches"])
            res["branches"].update(new["branches"])
            for key, ds in new["branches"].items():
                tree[f"{name}_{key}"] = ds
        t_new = time.perf_counter() - t1
        classes_up = classify(up, res["branches"])
        classes_down = classify(down, res["branches"])
        disagreements = [
            {"omega": a["omega"], "up": a["verdict"], "down": b["verdict"]}
            for a, b in zip(classes_up, classes_down[::-1], strict=True)
            if a["verdict"] != b["verdict"]]
        draw(name, res["branches"], up, down, zoom_up, out / f"{name}.png")
        for label, recs in (("up", up), ("down", down), ("zoom_up", zoom_up)):
            if not recs:
                continue
            width = max(len(r["velocities"]) for r in recs)
            v = np.full((len(recs), width), np.nan)
            for j, r in enumerate(recs):
                v[j, :len(r["velocities"])] = r["velocities"]
            brute[f"{name}_{label}"] = xr.Dataset(
                {"impact_velocity": (("omega", "impact"), v,
                                     {"long_name": "impact velocity", "units": "1"}),
                 "pattern_periods": ("omega", np.array([r["P"] for r in recs])),
                 "pattern_impacts": ("omega", np.array([r["p"] for r in recs]))},
                coords={"omega": np.array([r["omega"] for r in recs])},
                attrs={"system": name, "sweep": label, "transient": cfg["transient"],
                       "record": cfg["record"]})
        summary["systems"][name] = {
            "title": SYSTEMS[name]["title"], "range": SYSTEMS[name]["range"],
            "branches": {k: {"N": int(v.attrs["N"]), "p": impacts_of(v),
                             "points": v.sizes["point"],
                             "special": list(zip(v["special_label"].values.tolist(),
                                                 v["special_omega"].values.tolist(),
                                                 strict=True))}
                         for k, v in res["branches"].items()},
            "pd": res["pd"], "ratios": res["ratios"], "cascade_message": res["cascade_message"],
            "grazing": res["grazing"], "seconds_branches": res["seconds"],
            "sweep_seconds": {"up": sweeps_up[i]["seconds"], "down": sweeps_down[i]["seconds"]},
            "agreement_up": summarize(classes_up), "agreement_down": summarize(classes_down),
            "up_down_differ": disagreements,
            "branches_from_simulation": new["log"], "seconds_new_branches": t_new,
        }
    ic.save(tree, out / "branches.nc")
    xr.DataTree.from_dict({f"/{k}": v for k, v in brute.items()}).to_netcdf(
        out / "brute_force.nc", engine="netcdf4")
    (out / "pd_table.md").write_text(pd_markdown(results))
    summary["seconds"] = {"total": time.perf_counter() - t0, "branches": t_branches,
                          "sweeps": t_sweeps, "workers": workers}
    (out / "cascades.json").write_text(json.dumps(_clean(summary), indent=2) + "\n")
    if copy_figures:
        FIGURES_DIR.mkdir(exist_ok=True)
        for name in names:
            shutil.copy(out / f"{name}.png", FIGURES_DIR / f"{name}.png")
    log.info("done in %.1f s (branches %.1f s, sweeps %.1f s)", summary["seconds"]["total"],
             t_branches, t_sweeps)
    return summary


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT))
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--workers", type=int, default=WORKERS)
    parser.add_argument("--copy-figures", action="store_true")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    logging.getLogger("impactcont.core").setLevel(logging.WARNING)
    main(args.output, quick=args.quick, workers=args.workers, copy_figures=args.copy_figures)
