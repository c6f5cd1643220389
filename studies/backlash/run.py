"""Backlash: a two-sided clearance on mass 1 of the paper's 2-DOF chain.

The system is the paper's example (Cao & Shu, section 4: M = I, K = [[1, -1], [-1, 2]],
F = [1, 0], C = 2 eta K with eta = 0.1) with mass 1 between two stops, x1 = b above and
x1 = -b below (a symmetric backlash of width 2b), both with R = 0.6. For each clearance
b in CLEARANCES this study

1. sweeps omega up with the event-driven simulator (state carried from one omega to the
   next, transient discarded, impacts recorded with the stop they hit);
2. takes every attractor of the sweep that is a 1-2 motion with one impact on each stop,
   solves it by shooting and continues its branch in omega (both directions); a
   symmetric motion (X_1 = -X_0, equal flight times) is followed as such by the package
   (its half-motion closed by the reflection), which locates and labels the
   symmetry-breaking pitchforks BP, where a multiplier of the half-map H = S G_0 passes
   -1 (G = H^2 gets a multiplier +1);
3. switches at every BP onto the asymmetric pair born there (`pitchfork_switch`: two
   branches, mirror images of each other); an asymmetric attractor of the sweep on no
   switched branch is continued from the sweep (with its mirror image);
4. checks the diagram against the sweep: at every omega where the simulator settled on a
   1-2 motion, its impact velocities against the stable branch motion there;
5. draws one bifurcation diagram per clearance (impact velocities, lower-stop impacts
   negative) with the sweep overlaid;
6. repeats 1-5 for the b = 0.5 system with a non-proportional damping matrix (only the
   damper between the masses, :data:`JOINT_DAMPER`): the effect of the damping's
   distribution on the same backlash.

Writes into the output directory ``branches.nc`` (one group per branch), ``sweeps.nc``,
``backlash.json`` (pitchforks, ranges, agreement, timings) and ``backlash.png``. Only the
public API of impactcont is used. Run::

    PYTHONPATH=. python studies/backlash/run.py [--output DIR] [--quick] [--copy-figures]
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
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

import impactcont as ic
from impactcont.analysis.curves import multi_impact_curve, multi_impact_curve_crossings
from impactcont.analysis.switching import pitchfork_branch
from impactcont.orbit.symmetry import mirror_image, symmetry_defect
from impactcont.plots.branches import legend_below
from impactcont.plots.impacts import impact_diagram
from impactcont.plots.series import (
    figure_legend,
    fit_labels,
    inside_frame,
    one_per_style,
    panel_figure,
    take_legend,
)

log = logging.getLogger("backlash")

HERE = Path(__file__).resolve().parent
CLEARANCES = (0.3, 0.5, 0.8)
OMEGA = (0.5, 2.5)
TRANSIENT, RECORD = 150.0, 30.0  # forcing periods discarded, recorded per sweep omega
PAPER_DAMPING: dict[str, Any] = {"eta": 0.1}  # C = 2 eta K = [[0.2, -0.2], [-0.2, 0.4]]
JOINT_DAMPER: dict[str, Any] = {"C": [[0.2, -0.2], [-0.2, 0.2]]}
"""Non-proportional: only the damper between the masses (the paper's C without its part to
the ground), as in a gear mesh whose bearings are undamped."""
JOINT_CLEARANCE = 0.5


def system(b: float, omega: float, damping: dict[str, Any] | None = None
           ) -> ic.ImpactOscillator:
    """The paper's 2-DOF chain with mass 1 between x1 = -b and x1 = b (R = R_low = 0.6);
    the paper's damping unless `damping` gives another (``eta``, ``alpha/beta`` or ``C``)."""
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                               R=0.6, b=b, omega=omega, **(damping or PAPER_DAMPING),
                               stops=ic.Stops(b_low=b, R_low=0.6))


# ------------------------------------------------------------------------------------------
# Brute force
# ------------------------------------------------------------------------------------------
def one_two(res: ic.SimulationResult, omega: float) -> bool:
    """The recorded impacts are a 1-2 motion: one impact on each stop per period, repeating."""
    v, s, t = res.impact_velocities, res.impact_stops, res.impact_times
    if v.size < 8 or not res.success:
        return False
    T = 2 * math.pi / omega
    return (set(s[-8:]) == {"U", "L"} and all(a != c for a, c in zip(s[-8:-1], s[-7:], strict=True))
            and float(np.max(np.abs(v[-6:] - v[-8:-2]))) < 1e-6
            and abs(t[-1] - t[-3] - T) < 1e-6 * T)


def sweep(b: float, omegas: np.ndarray, damping: dict[str, Any] | None = None, *,
          transient: float = TRANSIENT, record: float = RECORD) -> dict[str, Any]:
    """Omega swept up; per omega the recorded impacts (velocity, stop) and the 1-2 verdict
    (``transient`` forcing periods discarded, ``record`` recorded)."""
    state, phase = np.zeros(4), 0.0
    rows: list[dict[str, Any]] = []
    for om in omegas:
        osc = system(b, float(om), damping)
        res = ic.simulate(osc, state, phase, transient)
        if not res.success:  # sticking or chatter: start again from rest
            res = ic.simulate(osc, np.zeros(4), 0.0, transient)
        rec = ic.simulate(osc, res.final_state, res.final_phase, record) if res.success else res
        state, phase = (rec.final_state, rec.final_phase) if rec.success else (np.zeros(4), 0.0)
        rows.append({"omega": float(om), "velocities": rec.impact_velocities.tolist(),
                     "stops": rec.impact_stops, "status": rec.status.name,
                     "one_two": one_two(rec, float(om)), "result": rec})
    return {"b": b, "rows": rows, "damping": damping}


# ------------------------------------------------------------------------------------------
# Branches, symmetry, pitchforks
# ------------------------------------------------------------------------------------------
def asymmetry(orbit: ic.MultiImpactOrbit) -> float:
    """How far a 1-2 motion is from its mirror image (relative; the package's measure)."""
    return symmetry_defect(orbit)


def orbit_at(ds: xr.Dataset, i: int, omega: float | None = None) -> ic.MultiImpactOrbit:
    """The motion of branch point i (or at ``omega``, seeded by point i), re-solved."""
    osc = ic.dataset.oscillator_from_dataset(ds, i)
    if omega is not None:
        osc = osc.replace(omega=omega)
    return ic.multi_impact_orbit(osc, 1, 2, {
        "delta": float(ds["delta_k"].values[i, 0]), "flight_times": ds["flight_time_k"].values[i],
        "states": ds["state_k"].values[i], "pattern": ds.attrs["pattern"]})


def pitchforks(ds: xr.Dataset) -> list[tuple[float, float]]:
    """``(omega, precision)`` of every BP the package located on a symmetric branch."""
    return [(float(w), float(p)) for lab, w, p, st in zip(
        ds["special_label"].values, ds["special_omega"].values,
        ds["special_precision"].values, ds["special_status"].values, strict=True)
        if lab == "BP" and st == "located"]


def fork_witness(b: float, damping: dict[str, Any] | None, ds: xr.Dataset, which: int,
                 system_of: Any = None, offset: float = 0.005,
                 periods: float = 400.0) -> dict[str, Any]:
    """The simulator either side of a BP: started next to the symmetric motion (nudged
    asymmetrically), does it stay symmetric where the branch says stable and leave it
    for an asymmetric 1-2 motion where the branch says unstable?"""
    fork = ic.special_orbit(ds, "BP", which)
    w = fork.oscillator.omega
    out: dict[str, Any] = {"omega": w, "sides": []}
    if not fork.physical:  # the simulator cannot follow a motion through a stop
        out.update(agrees=None, skipped=f"the motion at the BP is not physical ({fork.reason})")
        return out
    for side in (-1.0, 1.0):
        om = w + side * offset
        osc = system(b, om, damping) if system_of is None else system_of(b, om)
        try:
            sym = ic.multi_impact_orbit(osc, 1, 2, fork)
        except ic.NoPeriodicMotionError as exc:  # the symmetric branch turns before om
            out.update(agrees=None, skipped=f"no symmetric motion next to the BP at omega="
                       f"{om:.6g} ({exc})")
            return out
        if asymmetry(sym) > 1e-8:
            out.update(agrees=None, skipped=f"Newton at omega={om:.6g} found an asymmetric "
                       "motion, not the symmetric one")
            return out
        X = sym.states[0] + np.array([0.0, 1e-4, 1e-4, 0.0])
        res = ic.simulate(osc, X, float(sym.phases[0]), periods)
        settled = None
        if one_two(res, om):
            settled = ic.multi_impact_orbit(osc, 1, 2, res)
        out["sides"].append({
            "omega": om, "branch_stable": bool(sym.stable and sym.physical),
            "simulated_one_two": settled is not None,
            "simulated_asymmetry": asymmetry(settled) if settled is not None else None})
    out["agrees"] = all(
        (s["simulated_one_two"] and s["simulated_asymmetry"] < 1e-6) == s["branch_stable"]
        for s in out["sides"])
    out.setdefault("skipped", "")
    return out


def branches_for(b: float, sw: dict[str, Any]) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """Branches of the 1-2 motions: the symmetric ones the sweep settled on, the asymmetric
    pairs switched onto at their pitchforks, and any asymmetric attractor left over."""
    out: list[dict[str, Any]] = []
    timing: dict[str, float] = {}
    covered: set[float] = set()  # BPs whose asymmetric pair is followed
    seeds = []
    for row in sw["rows"]:
        if not row["one_two"]:
            continue
        t0 = time.perf_counter()
        orbit = ic.multi_impact_orbit(system(b, row["omega"], sw["damping"]), 1, 2,
                                      row["result"])
        timing.setdefault("orbit_s", time.perf_counter() - t0)
        seeds.append((row["omega"], orbit))
    # symmetric motions first: their pitchforks give the asymmetric pairs
    for omega, orbit in sorted(seeds, key=lambda s: asymmetry(s[1]) >= 1e-8):
        kind = "symmetric" if asymmetry(orbit) < 1e-8 else "asymmetric"
        # one branch per motion: skip seeds on a branch already followed
        kinds = ("symmetric",) if kind == "symmetric" else ("asymmetric", "mirror")
        if any(_on_branch(br, orbit) for br in out if br["kind"] in kinds):
            continue
        t0 = time.perf_counter()
        ds = ic.multi_impact_continuation(orbit, "omega", OMEGA, both_directions=True,
                                          max_points=600, ds_max=0.02)
        timing.setdefault(f"branch_{kind}_s", time.perf_counter() - t0)
        timing.setdefault(f"branch_{kind}_points", ds.sizes["point"])
        out.append({"kind": kind, "ds": ds, "seed": omega, "born_at": "sweep"})
        log.info("b=%g: %s branch from the sweep at omega=%.4f: %d points", b, kind, omega,
                 ds.sizes["point"])
        if kind == "symmetric":
            for which, (w, _) in enumerate(pitchforks(ds)):
                if any(abs(w - v) < 1e-8 for v in covered):
                    continue  # the pair of this BP came from another one (a loop between BPs)
                t0 = time.perf_counter()
                pair = ic.pitchfork_switch(ds, which, max_points=600, ds_max=0.02)
                timing.setdefault("switch_s", time.perf_counter() - t0)
                for sub, side in zip(pair, ("asymmetric", "mirror"), strict=True):
                    out.append({"kind": side, "ds": sub, "seed": w, "born_at": "BP"})
                    covered.update(float(v) for lab, v in zip(
                        sub["special_label"].values, sub["special_omega"].values, strict=True)
                        if lab == "BP")
                covered.add(w)
                log.info("b=%g: asymmetric pair switched onto at the BP omega=%.10f: %d and %d "
                         "points", b, w, pair[0].sizes["point"], pair[1].sizes["point"])
        else:  # an asymmetric attractor on no switched branch: its mirror image too
            mirror = mirror_image(orbit)
            mds = ic.multi_impact_continuation(mirror, "omega", OMEGA, both_directions=True,
                                               max_points=600, ds_max=0.02)
            out.append({"kind": "mirror", "ds": mds, "seed": omega, "born_at": "sweep"})
    # a pair from the sweep (not switched onto) may meet a symmetric branch the sweep never
    # settled on (an unstable one): its BP gives that symmetric motion, followed as such
    known = [w for br in out if br["kind"] == "symmetric" for w, _ in pitchforks(br["ds"])]
    for br in [br for br in out if br["born_at"] == "sweep" and br["kind"] == "asymmetric"]:
        labels = br["ds"]["special_label"].values.tolist()
        for which in range(labels.count("BP")):
            sym = ic.special_orbit(br["ds"], "BP", which)  # solved on the half system
            w = sym.oscillator.omega
            if any(abs(w - v) < 1e-6 for v in known):
                continue
            ds = ic.multi_impact_continuation(sym, "omega", OMEGA, both_directions=True,
                                              max_points=600, ds_max=0.02)
            out.append({"kind": "symmetric", "ds": ds, "seed": w, "born_at": "BP"})
            known.extend(v for v, _ in pitchforks(ds))
            log.info("b=%g: symmetric branch through the BP omega=%.10f of an asymmetric "
                     "branch: %d points, its BPs %s", b, w, ds.sizes["point"], pitchforks(ds))
    return out, timing


def _on_branch(br: dict[str, Any], orbit: ic.MultiImpactOrbit) -> bool:
    """The motion lies on the branch: a point within 0.02 in omega and in both velocities."""
    ds = br["ds"]
    near = np.flatnonzero(np.abs(ds["omega"].values - orbit.oscillator.omega) < 0.02)
    vel = np.sort(ds["impact_velocity_k"].values[near], axis=1)
    return bool(near.size and np.min(np.max(np.abs(
        vel - np.sort(orbit.impact_velocities)), axis=1)) < 0.02)


# ------------------------------------------------------------------------------------------
# Agreement with the sweep
# ------------------------------------------------------------------------------------------
def agreement(b: float, sw: dict[str, Any], branches: list[dict[str, Any]]) -> dict[str, Any]:
    """Every 1-2 attractor of the sweep against the stable physical branch motions there."""
    worst, explained, total, mismatch = 0.0, 0, 0, []
    for row in sw["rows"]:
        if not row["one_two"]:
            continue
        total += 1
        v = np.array(row["velocities"][-2:])
        s = row["stops"][-2:]
        sim = {s[0]: v[0], s[1]: v[1]}
        best = math.inf
        for br in branches:
            ds = br["ds"]
            stable = ds["stable"].values & ds["physical"].values
            om = ds["omega"].values
            near = np.flatnonzero(stable & (np.abs(om - row["omega"]) < 0.03))
            if near.size == 0:
                continue
            # the nearest stored motion in (omega, both velocities): a loop through both
            # mirror images passes every omega twice
            stored = ds["impact_velocity_k"].values[near]
            order = [sim[c] for c in ds.attrs["pattern"]]
            i = near[np.argmin(np.max(np.abs(stored - order), axis=1)
                               + np.abs(om[near] - row["omega"]))]
            o = orbit_at(ds, int(i), row["omega"])
            if not (o.physical and o.stable):
                continue
            mine = dict(zip(o.pattern, o.impact_velocities, strict=True))
            best = min(best, max(abs(mine["U"] - sim["U"]), abs(mine["L"] - sim["L"])))
        if best < 1e-6:
            explained += 1
            worst = max(worst, best)
        else:
            mismatch.append([row["omega"], best])
    return {"one_two_attractors": total, "explained": explained, "worst_velocity_error": worst,
            "unexplained_omegas": mismatch}


# ------------------------------------------------------------------------------------------
# Figure
# ------------------------------------------------------------------------------------------
STYLE = {"symmetric": "C0", "asymmetric": "C3", "mirror": "C3"}
#: One name and one colour per kind of motion: the two asymmetric motions of a pair are
#: mirror images, with the same impact speeds (the stops swapped), so their curves coincide.
KIND_NAMES = {"symmetric": "symmetric", "asymmetric": "asymmetric pair (mirror images)",
              "mirror": "asymmetric pair (mirror images)"}
OMEGA_LABEL = r"$\omega$"
DPI = 150  # of the PNGs (7 in wide: 1050 pixels)


def draw(ax: Any, branches: dict[str, xr.Dataset], sweep: xr.Dataset, title: str
         ) -> list[Any]:
    """One system: its branches (``impact_diagram``: every impact, the speed towards the
    stop hit, special points marked) with the simulated sweep's impacts on top; returns the
    legend handles. ``branches`` maps ``<i>_<kind>`` to a branch."""
    names = {}
    for key, ds in branches.items():
        kind = key.split("_", 1)[1]
        name = KIND_NAMES[kind]
        n = sum(k == name or k.startswith(f"{name} ") for k in names)
        names[name if n == 0 else f"{name} {n + 1}"] = (kind, ds)  # unique keys; one entry
        # per style in the legend (one_per_style): the first branch of a kind names it
    impact_diagram({k: v[1] for k, v in names.items()}, ax=ax, legend="inside",
                   colors=[STYLE[v[0]] for v in names.values()], title=title, zoom=False)
    handles = one_per_style(take_legend(ax))
    ax.set_ylabel(r"impact speed $|\dot{x}_1(T_k^-)|$")  # the stop hit: in the suptitle
    margin = 0.02 * (OMEGA[1] - OMEGA[0])  # the sweep's first and last omega off the frame
    ax.set_xlim(OMEGA[0] - margin, OMEGA[1] + margin)
    handles.append(Line2D([], [], label="simulated sweep, every impact", **SWEEP_DOTS))
    ax.set_xlabel(OMEGA_LABEL)
    return handles


SWEEP_DOTS = {"linestyle": "none", "marker": ".", "markersize": 2.0, "color": "k"}


def draw_sweep(ax: Any, sweep: xr.Dataset) -> None:
    """The simulated sweep's impacts (their speeds) on ``ax``, once its layout is final: a
    dot the frame would cut in half is left out."""
    speed = np.abs(sweep["speed"].values)
    om = np.broadcast_to(sweep["omega"].values[:, None], speed.shape)
    ok = np.isfinite(speed) & inside_frame(ax, om, speed, SWEEP_DOTS["markersize"])
    ax.plot(om[ok], speed[ok], zorder=1.5, **SWEEP_DOTS)


def diagrams_figure(groups: dict[str, xr.Dataset], sweeps: dict[str, xr.Dataset],
                    width: float = 7.0) -> Figure:
    """``backlash.png``: one panel per system (each clearance, the joint damper case), a
    2 x 2 grid at a double column, one column below 5 in; one legend under them."""
    keys = list(sweeps)
    fig, axes = panel_figure(len(keys), width, extra_height=1.6)
    handles: dict[str, Any] = {}
    for ax, key in zip(axes, keys, strict=True):
        b = float(sweeps[key].attrs["b"])
        own = {name[len(key) + 1:]: ds for name, ds in groups.items()
               if name.startswith(key + "_") and name[len(key) + 1:].split("_")[0].isdigit()}
        title = rf"$b = b_{{low}} = {b:g}$" + (", joint damper only" if "joint" in key else "")
        for h in draw(ax, own, sweeps[key], title):
            handles.setdefault(h.get_label(), h)
    figure_legend(fig, one_per_style(list(handles.values())))
    fig.suptitle(r"Backlash on mass 1 of the paper's 2-DOF chain, $R = 0.6$: motions with "
                 "one impact on each stop, impact speeds towards the stop hit",
                 fontsize="medium")
    fit_labels(fig)
    for ax, key in zip(axes, keys, strict=True):  # the layout is final: no dot cut in half
        draw_sweep(ax, sweeps[key])
    return fig


def case(b: float, damping: dict[str, Any] | None, omegas: np.ndarray, key: str,
         groups: dict[str, xr.Dataset]) -> tuple[dict[str, Any], xr.Dataset]:
    """One system: sweep, branches, pitchforks, agreement; returns its summary and its
    sweep (the branches go into `groups` under `key`)."""
    t0 = time.perf_counter()
    sw = sweep(b, omegas, damping)
    t_sweep = time.perf_counter() - t0
    branches, timing = branches_for(b, sw)
    best: dict[float, tuple[float, float, xr.Dataset, int]] = {}  # one entry per BP
    for br in branches:
        if br["kind"] == "symmetric":
            for which, (w, prec) in enumerate(pitchforks(br["ds"])):
                rounded = round(w, 9)
                if rounded not in best or prec < best[rounded][1]:
                    best[rounded] = (w, prec, br["ds"], which)
    located = sorted(best.values(), key=lambda item: item[0])
    forks = [w for w, *_ in located]
    witness = [fork_witness(b, damping, ds, which) for _, _, ds, which in located]
    agree = agreement(b, sw, branches)
    info: dict[str, Any] = {"damping": damping or PAPER_DAMPING, "sweep_s": t_sweep,
                            **timing, "pitchforks": forks,
                            "pitchfork_precision": [p for _, p, *_ in located],
                            "pitchfork_simulated": witness, "agreement": agree,
                            "branches": []}
    for i, br in enumerate(branches):
        ds = br["ds"]
        ok = ds["physical"].values & ds["stable"].values
        om = ds["omega"].values
        specials = [(str(lab), float(w)) for lab, w in zip(
            ds["special_label"].values, ds["special_omega"].values, strict=True)]
        info["branches"].append({
            "kind": br["kind"], "born_at": br["born_at"], "seed_omega": br["seed"],
            "points": int(ds.sizes["point"]),
            "pattern": ds.attrs["pattern"],
            "stable_physical_omega": [float(om[ok].min()), float(om[ok].max())]
            if ok.any() else None, "special_points": specials})
        groups[f"{key}_{i}_{br['kind']}"] = ds
    log.info("%s: pitchforks %s, agreement %s", key, forks, agree)
    return info, sweep_dataset(sw)


def sweep_dataset(sw: dict[str, Any]) -> xr.Dataset:
    """The dataset ``sweeps.nc`` stores of one :func:`sweep`: per omega the speed of every
    recorded impact (NaN past the last), the 1-2 verdict and the last stops hit."""
    width = max(1, max(len(r["velocities"]) for r in sw["rows"]))
    speed = np.full((len(sw["rows"]), width), np.nan)
    for i, r in enumerate(sw["rows"]):
        speed[i, :len(r["velocities"])] = r["velocities"]
    return xr.Dataset({
        "omega": ("row", [r["omega"] for r in sw["rows"]]),
        "one_two": ("row", [r["one_two"] for r in sw["rows"]]),
        "impacts_recorded": ("row", [len(r["velocities"]) for r in sw["rows"]]),
        "pattern_tail": ("row", [r["stops"][-8:] for r in sw["rows"]]),
        "speed": (("row", "impact"), speed, {"long_name": "impact speed of each recorded "
                                             "impact (NaN: fewer impacts)", "units": "1"})},
        attrs={"b": sw["b"], "damping": json.dumps(sw["damping"] or PAPER_DAMPING)})


# ------------------------------------------------------------------------------------------
# The (omega, b) plane: where the symmetric and asymmetric motions exist and switch
# ------------------------------------------------------------------------------------------
PLANE = {"omega": (0.5, 2.5), "b": (0.2, 1.0)}
PLANE_WITNESS_B = (0.35, 0.6, 0.9)  # clearances where the simulator checks the BP curve
PLANE_WITNESS_OFFSET, PLANE_WITNESS_PERIODS = 0.01, 800.0
PLANE_GRID = (401, 161)  # omega x b points of the stability maps (b step 0.005)
ASYMMETRIC = 1e-6  # symmetry_defect above which a motion of the maps counts as asymmetric


def mirrored(b: float, omega: float) -> ic.ImpactOscillator:
    """The backlash with mirrored stops: continued in b, both stops move (x1 = +-b)."""
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                               R=0.6, b=b, omega=omega, **PAPER_DAMPING,
                               stops=ic.Stops(mirror=True))


def plane(summary: dict[str, Any], groups: dict[str, xr.Dataset]) -> dict[str, Any]:
    """The curves of the pitchforks (BP) and of the grazings (GR) of the symmetric and the
    asymmetric motions in (omega, b), checked against the pitchforks located in omega at
    each clearance and against the simulator either side of the BP curve."""
    t0 = time.perf_counter()
    seed = ic.multi_impact_orbit(mirrored(0.5, 1.6), 1, 2,
                                 ic.simulate(mirrored(0.5, 1.6), np.zeros(4), 0.0, TRANSIENT))
    sym = ic.multi_impact_continuation(seed, "omega", OMEGA, both_directions=True,
                                       ds_max=0.02, max_points=600)
    labels = sym["special_label"].values.tolist()
    curves = {"BP": multi_impact_curve(sym, "BP", 0, parameter="b", bounds=PLANE, ds_max=0.02,
                                       max_points=800)}
    if "GR" in labels:
        curves["GR symmetric"] = multi_impact_curve(sym, "GR", 0, parameter="b", bounds=PLANE,
                                                    ds_max=0.02, max_points=800)
    asym = pitchfork_branch(sym, 0, 1, max_points=600, ds_max=0.02)
    grazing = [float(w) for lab, w in zip(asym["special_label"].values,
                                          asym["special_omega"].values, strict=True)
               if lab == "GR"]
    for which, w in enumerate(grazing):
        # the loop passes each graze twice (both mirror images): one curve per graze
        if any(abs(c["omega"] - w) < 1e-7 for name, ds in curves.items()
               if name.startswith("GR asymmetric")
               for c in multi_impact_curve_crossings(ds, "b", 0.5)):
            continue
        try:
            curves[f"GR asymmetric {which}"] = multi_impact_curve(
                asym, "GR", which, parameter="b", bounds=PLANE, ds_max=0.02, max_points=800)
        except (ic.NoPeriodicMotionError, ic.ParameterError) as exc:
            log.warning("GR %d of the asymmetric branch: no curve (%s)", which, exc)
    t_curves = time.perf_counter() - t0
    # stability maps of the symmetric family and of the asymmetric pair over the plane
    t0 = time.perf_counter()
    grid = {"omega": np.linspace(*PLANE["omega"], PLANE_GRID[0]),
            "b": np.linspace(*PLANE["b"], PLANE_GRID[1])}
    maps = {"symmetric": ic.multi_impact_map(seed, ("omega", "b"), grid)}
    # the asymmetric pair from one seed per clearance branch (a grid sweep from one seed
    # passes a pitchfork onto the symmetric motions and does not come back)
    for name, ds in groups.items():
        if not (name.startswith("b0.") and name.endswith("_asymmetric")
                and "joint" not in name):
            continue
        ok = ds["stable"].values & ds["physical"].values
        if not ok.any():
            continue
        om = ds["omega"].values
        mid = 0.5 * (om[ok].min() + om[ok].max())  # mid-window: far from its pitchforks
        i = int(np.flatnonzero(ok)[np.argmin(np.abs(om[ok] - mid))])
        b = float(ds["b"].values[i])
        motion = ic.multi_impact_orbit(mirrored(b, float(ds["omega"].values[i])), 1, 2, {
            "delta": float(ds["delta_k"].values[i, 0]),
            "flight_times": ds["flight_time_k"].values[i], "states": ds["state_k"].values[i],
            "pattern": ds.attrs["pattern"]})
        maps[f"asymmetric {name}"] = ic.multi_impact_map(motion, ("omega", "b"), grid)
    t_maps = time.perf_counter() - t0
    # the symmetric map's stability changes where the BP curve crosses a grid row
    map_check = []
    sym_map = maps["symmetric"]
    for j, b in enumerate(grid["b"]):
        if j % 10:
            continue
        ok = (sym_map["stable"].values[:, j] & sym_map["physical"].values[:, j]
              & sym_map["found"].values[:, j])
        flips = grid["omega"][:-1][ok[:-1] != ok[1:]]
        physical = sym_map["physical"].values[:, j]
        for c in multi_impact_curve_crossings(curves["BP"], "b", float(b)):
            cell = float(np.min(np.abs(flips - c["omega"]))) if flips.size else math.inf
            k = int(np.searchsorted(grid["omega"], c["omega"]))
            map_check.append({"b": float(b), "bp_omega": float(c["omega"]),
                              "physical_there": bool(physical[max(k - 1, 0)]
                                                     or physical[min(k, physical.size - 1)]),
                              "nearest_flip_in_cells": float(cell / (grid["omega"][1]
                                                                     - grid["omega"][0]))})
    # the BP curve against the pitchforks located in omega on each clearance's branch
    located = {b: info["pitchforks"] for b, info in summary["clearances"].items()}
    check = {}
    for b, forks in located.items():
        crossing = [c["omega"] for c in multi_impact_curve_crossings(curves["BP"], "b",
                                                                     float(b))]
        check[b] = {"located_in_omega": forks, "curve_crossings": crossing,
                    "distance_to_curve": [min((abs(w - c) for c in crossing), default=None)
                                          for w in forks]}
    # the simulator either side of the BP curve at other clearances
    witness = []
    for b in PLANE_WITNESS_B:
        for c in multi_impact_curve_crossings(curves["BP"], "b", b):
            branch = ic.multi_impact_continuation(
                ic.multi_impact_orbit(mirrored(b, c["omega"] + 0.02), 1, 2, _nearest_symmetric(
                    curves["BP"], b, c["omega"])), "omega", (c["omega"] - 0.03, c["omega"] + 0.03),
                both_directions=True, ds_max=0.005)
            forks = pitchforks(branch)
            if not forks:
                continue
            which = int(np.argmin([abs(w - c["omega"]) for w, _ in forks]))
            result = fork_witness(b, None, branch, which, system_of=mirrored,
                                  offset=PLANE_WITNESS_OFFSET, periods=PLANE_WITNESS_PERIODS)
            result["b"] = b
            witness.append(result)
    for name, ds in curves.items():
        groups[f"plane_{name.replace(' ', '_')}"] = ds
    for name, ds in maps.items():
        groups[f"plane_map_{name.replace(' ', '_')}"] = ds
    return {"curves": {name: {"points": int(ds.sizes["point"]),
                              "omega": [float(ds["omega"].min()), float(ds["omega"].max())],
                              "b": [float(ds["b"].min()), float(ds["b"].max())]}
                       for name, ds in curves.items()},
            "bp_curve_vs_located": check, "simulated": witness, "curves_s": t_curves,
            "maps_s": t_maps, "map_points": int(sum(m["found"].size for m in maps.values())),
            "map_flips_within_one_cell_of_the_bp_curve": [
                int(sum(c["nearest_flip_in_cells"] <= 1.0 for c in map_check
                        if c["physical_there"])),
                int(sum(c["physical_there"] for c in map_check))],
            "map_vs_bp_curve": map_check, "datasets": curves, "maps": maps, "symmetric": sym}


def _nearest_symmetric(curve: xr.Dataset, b: float, omega: float) -> dict[str, Any]:
    """The stored motion of the BP curve point nearest (omega, b), as a Newton guess."""
    i = int(np.argmin(np.hypot(curve["omega"].values - omega, curve["b"].values - b)))
    return {"delta": float(curve["delta_k"].values[i, 0]),
            "flight_times": curve["flight_time_k"].values[i],
            "states": curve["state_k"].values[i], "pattern": curve.attrs["pattern"]}


def plane_figure(groups: dict[str, xr.Dataset], summary: dict[str, Any], width: float = 7.0
                 ) -> Figure:
    """``backlash_plane.png``: where the symmetric and the asymmetric motions are stable
    and physical (the maps, shaded), the BP and GR curves, the pitchforks located in omega
    and the simulator either side of the BP curve."""
    fig, (ax,) = panel_figure(1, width, aspect=0.6, extra_height=1.7)
    styles = {"BP": ("k", "-", "BP curve (symmetry-breaking pitchfork)"),
              "GR_symmetric": ("C0", "--", "GR curve of the symmetric motion"),
              "GR_asymmetric": ("C3", "--", "GR curves of the asymmetric pair")}
    handles: list[Any] = []
    maps = {n[len("plane_map_"):]: ds for n, ds in groups.items() if n.startswith("plane_map_")}
    regions: dict[str, Any] = {}
    for name, m in maps.items():
        kind = "asymmetric" if name.startswith("asymmetric") else "symmetric"
        ok = m["stable"] & m["physical"] & m["found"]
        if kind == "asymmetric":  # past a BP the grid sweep reaches the symmetric motions
            ok = ok & (m["asymmetry"] > ASYMMETRIC)
        regions[kind] = ok if kind not in regions else regions[kind] | ok
    for kind, color in (("symmetric", "C0"), ("asymmetric", "C3")):
        if kind not in regions or not bool(regions[kind].any()):
            continue  # no legend entry for a region not drawn
        m = maps["symmetric"]
        ax.contourf(m["omega"].values, m["b"].values, regions[kind].values.T.astype(float),
                    levels=[0.5, 1.5], colors=[color], alpha=0.18)
        handles.append(Patch(facecolor=color, alpha=0.35,
                             label=f"{kind} motion stable and physical (map)"))
    for name, ds in groups.items():
        if not name.startswith("plane_") or name.startswith("plane_map_"):
            continue
        key = "GR_asymmetric" if name.startswith("plane_GR_asymmetric") else name[6:]
        color, ls, label = styles[key]
        ax.plot(ds["omega"].values, ds["b"].values, ls, color=color, lw=1.4, zorder=3)
        if label not in [h.get_label() for h in handles]:
            handles.append(Line2D([], [], color=color, ls=ls, lw=1.4, label=label))
    bp = {"linestyle": "none", "marker": "o", "markersize": 5, "markerfacecolor": "white",
          "markeredgecolor": "k"}
    for b, info in summary["clearances"].items():
        ax.plot(info["pitchforks"], [float(b)] * len(info["pitchforks"]), zorder=4, **bp)
    handles.append(Line2D([], [], label="BP located on a branch in $\\omega$", **bp))
    sim = {True: {"marker": "s", "label": "simulated: stays symmetric"},
           False: {"marker": "x", "label": "simulated: leaves the symmetric motion"}}
    seen = set()
    for w in summary.get("plane", {}).get("simulated", []):
        for side in w.get("sides", []):
            sym = bool(side["simulated_one_two"] and side["simulated_asymmetry"] < 1e-6)
            style = {"linestyle": "none", "marker": sim[sym]["marker"], "markersize": 4,
                     "color": "C2", "markerfacecolor": "white"}
            ax.plot(side["omega"], w["b"], zorder=4, **style)
            if sym not in seen:
                handles.append(Line2D([], [], label=sim[sym]["label"], **style))
                seen.add(sym)
    ax.set_xlabel(OMEGA_LABEL)
    ax.set_ylabel(r"clearance on each side $b = b_{low}$")
    ax.set_xlim(*PLANE["omega"])
    ax.set_ylim(*PLANE["b"])
    legend_below(ax, handles)
    ax.set_title(r"Backlash, $R = 0.6$, $\eta = 0.1$: motions with one impact on each stop "
                 r"in $(\omega, b)$", fontsize="medium")
    fit_labels(fig)
    return fig


def draw_figures(output: Path, width: float = 7.0) -> list[Path]:
    """Draw ``backlash.png`` (and ``backlash_plane.png`` after a full run) from the stored
    ``branches.nc``, ``sweeps.nc`` and ``backlash.json`` of ``output``."""
    tree = ic.load(output / "branches.nc")
    groups = {name: node.to_dataset() for name, node in tree.children.items()}
    stree = ic.load(output / "sweeps.nc", validate=False)
    sweeps = {name: node.to_dataset() for name, node in stree.children.items()}
    summary = json.loads((output / "backlash.json").read_text())
    figures = {"backlash.png": diagrams_figure(groups, sweeps, width)}
    if any(name.startswith("plane_map_") for name in groups):
        figures["backlash_plane.png"] = plane_figure(groups, summary, width)
    paths = []
    for name, fig in figures.items():
        fig.savefig(output / name, dpi=DPI)
        paths.append(output / name)
        log.info("wrote %s", output / name)
    return paths


def main(output: Path, quick: bool = False) -> dict[str, Any]:
    output.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    omegas = np.linspace(OMEGA[0], OMEGA[1], 21 if quick else 81)
    clearances = CLEARANCES[1:2] if quick else CLEARANCES
    cases = [(b, None, f"b{b}") for b in clearances]
    cases.append((JOINT_CLEARANCE, JOINT_DAMPER, f"b{JOINT_CLEARANCE}_joint_damper"))
    summary: dict[str, Any] = {"clearances": {}, "joint_damper": {}, "quick": quick}
    groups: dict[str, xr.Dataset] = {}
    sweeps = {}
    for b, damping, key in cases:
        info, sweep_ds = case(b, damping, omegas, key, groups)
        if damping is None:
            summary["clearances"][str(b)] = info
        else:
            summary["joint_damper"][str(b)] = info
        sweeps[key] = sweep_ds
    if not quick:
        info = plane(summary, groups)
        summary["plane"] = {k: v for k, v in info.items()
                            if k not in ("datasets", "maps", "symmetric")}
    ic.save(groups, output / "branches.nc")
    ic.save(sweeps, output / "sweeps.nc", validate=False)
    summary["total_s"] = time.perf_counter() - t_start
    (output / "backlash.json").write_text(json.dumps(summary, indent=2))
    draw_figures(output)
    return summary


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=HERE / "output")
    parser.add_argument("--quick", action="store_true", help="one clearance, 21 omegas")
    parser.add_argument("--copy-figures", action="store_true",
                        help="copy the figure into figures/ (tracked)")
    parser.add_argument("--figures-only", action="store_true",
                        help="only redraw the figures from the output's branches.nc, "
                        "sweeps.nc and backlash.json (seconds)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    if args.figures_only:
        draw_figures(args.output)
    else:
        result = main(args.output, quick=args.quick)
        log.info("done in %.1f s", result["total_s"])
    if args.copy_figures:
        (HERE / "figures").mkdir(exist_ok=True)
        for name in ("backlash.png", "backlash_plane.png"):
            if (args.output / name).exists():
                shutil.copy(args.output / name, HERE / "figures" / name)
