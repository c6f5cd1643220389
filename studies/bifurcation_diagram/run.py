"""Bifurcation diagram of the paper's two-degree-of-freedom impact oscillator.

The system of Cao & Shu, section 4 (EQUATIONS.md section 6): n = 2, M = I,
K = [[1, -1], [-1, 2]], eta = 0.1 (C = 2 eta K), R = 0.6, F = [1, 0]. For the gaps
b = 0 and b = 0.5 this study

1. finds every branch of periodic N-1 motions (one impact every N forcing periods),
   N = 1..4, over omega in [0.5, 6]: a scan of eq. (14) for where roots exist, one
   continuation started in every existence interval (and from every root there) that no
   branch found so far passes through, duplicates removed;
2. tabulates the special points (SN, PD, NS, GR, ZV) on the physical parts of the branches
   and checks each one independently with the simulator, on both sides of it;
3. sweeps omega up and down with the simulator (brute force: the state is carried from one
   omega to the next, a transient is discarded, the impacts of the following periods are
   recorded and their pattern detected);
4. draws both in one bifurcation diagram per gap.

Writes into the output directory: ``branches.nc`` (DataTree, one group per branch, e.g.
``b0_N1_a``; the gap 0.5 is tagged ``b0p5``), ``brute_force.nc``,
``bifurcation_b0.png``, ``bifurcation_b0p5.png``, ``special_points.json``,
``special_points.md`` and ``summary.json`` (timings, brute force against branches). Run::

    .venv/bin/python studies/bifurcation_diagram/run.py [--output DIR] [--quick]
        [--no-brute-force] [--copy-figures]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import math
import multiprocessing as mp
import os
import shutil
import string
import time
import uuid
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.markers import MarkerStyle

import impactcont as ic
from impactcont.plots import SEGMENT_STYLES, SPECIAL_MARKERS, bifurcation_diagram
from impactcont.plots.branches import (
    NONPHYSICAL_GREY,
    SPECIAL_NAMES,
    label_specials,
    nest_coincident_markers,
)
from impactcont.plots.series import (
    MAX_WIDTH,
    figure_legend,
    fit_labels,
    inside_frame,
    markers_whole,
)

log = logging.getLogger("bifurcation_diagram")

HERE = Path(__file__).resolve().parent
DEFAULT_OUTPUT = HERE / "output"
FIGURES_DIR = HERE / "figures"

GAPS = (0.0, 0.5)
N_VALUES = (1, 2, 3, 4)
OMEGA_RANGE = (0.5, 6.0)
WORKERS = 2

# ---- branches ------------------------------------------------------------------------------
EXISTENCE_SCAN = 1101        # omega values where c^2 + s^2 >= b^2 is tested (step 0.005)
COVERAGE_PROBES = 40         # omega values per existence interval where every root is probed
COVERAGE_TOL = 0.05          # rad: a root this close to a branch's (interpolated) delta is on it
DUPLICATE_FRACTION = 0.95    # a branch with this share of its points on another is a duplicate
CONTINUATION = {"ds": 0.02, "ds_max": 0.05}

# ---- brute force ---------------------------------------------------------------------------
N_OMEGA = 120                # omega values per sweep (full run)
N_OMEGA_QUICK = 25
TRANSIENT = 150              # forcing periods discarded at each omega (twice that at the first)
RECORD = 30                  # forcing periods recorded after the transient
TRANSIENT_QUICK, RECORD_QUICK = 100, 24
MAX_PATTERN = 8              # longest impact pattern looked for, in forcing periods
SWEEP_TOL = 1e-5             # repetition tolerance of the sweep's pattern detection

# ---- independent checks of the special points ----------------------------------------------
OFFSET_FRACTION = 0.3        # offset = this share of the distance to the next special point
OFFSET_MIN, OFFSET_MAX = 1e-4, 0.01
PERTURBATION = 1e-6          # start this far (max-norm, on the impact surface) from the orbit
CHECK_BASE, CHECK_BASE_QUICK = 200, 100   # forcing periods of every check run, plus ...
CHECK_DECADES = 4.0          # ... enough impacts for the closed form's rho to grow/decay 1e4-fold
CHECK_MAX, CHECK_MAX_QUICK = 4000, 200   # ... capped at this many forcing periods
CHECK_RECORD = 16            # forcing periods per N recorded at the end (at least 48)
CHECK_TOL = 1e-6             # pattern tolerance of the checks (relative to the velocity)
NEAR_TOL = 1e-3              # looser tolerance: a pattern still converging ("~2-2")
NEARBY = 0.3                 # a motion "next to" the N-1 one: all v within 30 % of its v
MATCH_TOL = 1e-4             # |v_sim - v_closed_form| / max(1, v) below which they are the same
SEED = 20240601

EXPECTED = {
    "PD": "a real multiplier through -1: the N-1 motion (stable side) gives way to a 2N-2 "
          "motion (two alternating impacts) nearby",
    "SN": "fold: two N-1 motions on one side, none on the other; the simulator must jump",
    "NS": "a complex pair through |mu| = 1: the N-1 motion (stable side) gives way to a "
          "quasi-periodic drift around it",
    "GR": "grazing: on the other side the closed-form motion would cross the stop inside the "
          "period, so the simulator meets an extra impact",
    "ZV": "impact velocity -> 0: on the other side the closed form has v < 0 (not a motion); "
          "the simulator finds no impact where the closed form puts one",
}


# ---------------------------------------------------------------------------------------------
# Small helpers
# ---------------------------------------------------------------------------------------------
def paper_oscillator(b: float, omega: float = 1.0) -> ic.ImpactOscillator:
    """The paper's two-degree-of-freedom system at gap ``b`` and frequency ``omega``."""
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                               R=0.6, b=float(b), omega=float(omega), eta=0.1)


def gap_tag(b: float) -> str:
    """``b0``, ``b0p5``: the gap in group and file names."""
    return "b" + f"{b:g}".replace("-", "m").replace(".", "p")


def _wrap(angle: Any) -> Any:
    """Angle wrapped to [-pi, pi)."""
    return np.remainder(np.asarray(angle) + math.pi, 2.0 * math.pi) - math.pi


def _clean(obj: Any) -> Any:
    """JSON-ready copy: numpy to Python, non-finite floats to the strings 'inf', 'nan'."""
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
    if isinstance(obj, complex):
        return [obj.real, obj.imag]
    return obj


def _write_json(path: Path, data: Any) -> None:
    path.write_text(json.dumps(_clean(data), indent=2, allow_nan=False) + "\n")
    log.info("wrote %s", path)


def _run_tasks(fn: Callable[..., Any], argsets: Sequence[tuple[Any, ...]], workers: int
               ) -> list[Any]:
    """``[fn(*args) for args in argsets]``, in ``workers`` forked processes if more than one."""
    if workers > 1 and len(argsets) > 1 and "fork" in mp.get_all_start_methods():
        with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("fork")) as pool:
            futures = [pool.submit(fn, *args) for args in argsets]
            return [f.result() for f in futures]
    return [fn(*args) for args in argsets]


# ---------------------------------------------------------------------------------------------
# Simulation helpers
# ---------------------------------------------------------------------------------------------
def run_simulation(osc: ic.ImpactOscillator, state: np.ndarray, delta: float,
                   periods: float) -> ic.SimulationResult:
    """:func:`impactcont.simulate`; redone in chunks of 0.9 periods if it raises ValueError.

    A converged N-1 motion with N >= 2 can put an impact exactly on the boundary of the
    simulator's one-period search windows; an earlier version failed there (see
    studies/paper_example). Chunks of 0.9 periods move the windows off the impacts.
    """
    try:
        return ic.simulate(osc, state, delta, periods)
    except ValueError as exc:
        log.warning("simulate failed (%s) at omega=%.6g b=%g; redoing it in chunks", exc,
                    osc.omega, osc.b)
    times, vels, phases, states = [], [], [], []
    X, phase, offset, done = np.asarray(state, float), float(delta), 0.0, 0.0
    status = ic.SimulationStatus.COMPLETED
    while done < periods - 1e-12:
        step = min(0.9, periods - done)
        res = ic.simulate(osc, X, phase, step)
        times.append(res.impact_times + offset)
        vels.append(res.impact_velocities)
        phases.append(res.impact_phases)
        states.append(res.impact_states)
        offset += res.final_time
        X, phase, done, status = res.final_state, res.final_phase, done + step, res.status
        if not res.success:
            break
    return ic.SimulationResult(
        impact_times=np.concatenate(times), impact_velocities=np.concatenate(vels),
        impact_phases=np.concatenate(phases), impact_states=np.vstack(states),
        final_time=offset, final_state=X, final_phase=phase, status=status)


def impact_pattern(times: np.ndarray, velocities: np.ndarray, period: float, *,
                   tol: float, max_periods: int = MAX_PATTERN) -> tuple[int, int, float]:
    """Detect a periodic impact pattern: p impacts every P forcing periods.

    Parameters
    ----------
    times, velocities : ndarray, shape (k,)
        Impact times and velocities in the recorded window.
    period : float
        Forcing period ``2 pi / omega``.
    tol : float
        Repetition tolerance, relative to ``max(1, max velocity)`` for velocities and to the
        forcing period for times.
    max_periods : int
        Longest pattern looked for.

    Returns
    -------
    (P, p, residual)
        ``(0, 0, 0)`` if there is no impact; ``(-1, -1, best residual)`` if no pattern of at
        most `max_periods` periods repeats; else the smallest such P, its impact count p and
        the repetition residual.
    """
    if times.size == 0:
        return 0, 0, 0.0
    vscale = max(1.0, float(np.max(np.abs(velocities))))
    best = math.inf
    for P in range(1, max_periods + 1):
        p = int(np.sum(times < times[0] + (P - 1e-6) * period))
        if p == 0 or times.size < 2 * p + 1:
            continue
        resid = max(float(np.max(np.abs(times[p:] - times[:-p] - P * period))) / period,
                    float(np.max(np.abs(velocities[p:] - velocities[:-p]))) / vscale)
        best = min(best, resid)
        if resid < tol:
            return P, p, resid
    return -1, -1, best


def pattern_label(P: int, p: int) -> str:
    """``"2-1"`` (one impact every 2 periods), ``"no impact"`` or ``"aperiodic"``."""
    if P == 0:
        return "no impact"
    if P < 0:
        return f"no period <= {MAX_PATTERN}T"
    return f"{P}-{p}"


# ---------------------------------------------------------------------------------------------
# Branches
# ---------------------------------------------------------------------------------------------
def existence_intervals(osc: ic.ImpactOscillator, N: int, omegas: np.ndarray
                        ) -> list[np.ndarray]:
    """Runs of consecutive ``omegas`` where eq. (15) has roots (``c^2 + s^2 >= b^2``)."""
    exists = np.array([ic.amplitude_squared(osc.replace(omega=float(w)), N) >= osc.b ** 2
                       for w in omegas])
    edges = np.flatnonzero(np.diff(exists.astype(int))) + 1
    return [run for run in np.split(omegas, edges) if exists[np.searchsorted(omegas, run[0])]]


def on_branch(ds: xr.Dataset, omega: float, delta: float, tol: float = COVERAGE_TOL) -> bool:
    """Does the branch pass through ``(omega, delta)`` (delta interpolated between points)?"""
    om = ds["omega"].values
    de = ds["delta"].values
    k = np.flatnonzero((np.minimum(om[:-1], om[1:]) <= omega)
                       & (np.maximum(om[:-1], om[1:]) >= omega))
    if k.size == 0:
        return False
    span = om[k + 1] - om[k]
    t = np.where(span != 0, (omega - om[k]) / np.where(span != 0, span, 1.0), 0.0)
    d = de[k] + t * _wrap(de[k + 1] - de[k])
    return bool(np.any(np.abs(_wrap(d - delta)) < tol))


def _share_on(ds: xr.Dataset, other: xr.Dataset) -> float:
    """Share of the points of ``ds`` that lie on ``other``."""
    hits = [on_branch(other, w, d) for w, d in zip(ds["omega"].values, ds["delta"].values,
                                                   strict=True)]
    return float(np.mean(hits))


def branches_for(b: float, N: int, scan: int = EXISTENCE_SCAN) -> dict[str, Any]:
    """Every branch of N-1 motions at gap ``b`` over :data:`OMEGA_RANGE`.

    Scans ``c^2 + s^2 >= b^2`` on ``scan`` omega values for the existence intervals; in each,
    every root of eq. (15) at up to :data:`COVERAGE_PROBES` omega values is checked against
    the branches found so far and a continuation is started from the first root that no
    branch passes through. Branches that lie on a longer one are dropped.

    Returns
    -------
    dict
        ``branches`` (list of Dataset), ``intervals``, ``starts`` and ``seconds``.
    """
    t0, c0 = time.perf_counter(), time.process_time()
    osc = paper_oscillator(b)
    grid = np.linspace(*OMEGA_RANGE, scan)
    intervals = existence_intervals(osc, N, grid)
    found: list[xr.Dataset] = []
    starts = []
    for run in intervals:
        probes = run[np.unique(np.linspace(0, run.size - 1, min(run.size, COVERAGE_PROBES))
                               .round().astype(int))]
        for w in probes:
            for orbit in ic.periodic_orbits(osc.replace(omega=float(w)), N):
                if any(on_branch(ds, float(w), orbit.delta) for ds in found):
                    continue
                ds = ic.continuation(osc, N=N, parameter="omega", bounds=OMEGA_RANGE,
                                     start=float(w), root=orbit.root, components="start",
                                     **CONTINUATION)
                if not on_branch(ds, float(w), orbit.delta):
                    log.warning("b=%g N=%d: the branch started at omega=%.4f, delta=%.4f does "
                                "not pass through its start; kept", b, N, w, orbit.delta)
                found.append(ds)
                starts.append({"omega": float(w), "root": orbit.root, "delta": orbit.delta,
                               "points": ds.sizes["point"]})
    kept = []
    for i, ds in enumerate(found):
        longer = [o for j, o in enumerate(found) if j != i and (
            o.sizes["point"] > ds.sizes["point"] or (o.sizes["point"] == ds.sizes["point"]
                                                     and j < i))]
        if any(_share_on(ds, o) >= DUPLICATE_FRACTION for o in longer):
            log.info("b=%g N=%d: dropped a duplicate branch (%d points)", b, N,
                     ds.sizes["point"])
            continue
        kept.append(ds)
    # physical branches first, then by where they start
    kept.sort(key=lambda d: (not bool(d["physical"].any()), float(d["omega"].min())))
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    log.info("b=%g N=%d: %d branch(es), %d points, %d existence interval(s), %.1f s "
             "(%.1f s CPU)", b, N, len(kept), sum(d.sizes["point"] for d in kept),
             len(intervals), seconds, cpu)
    return {"b": b, "N": N, "branches": kept, "seconds": seconds, "cpu_seconds": cpu,
            "starts": starts,
            "intervals": [[float(r[0]), float(r[-1])] for r in intervals]}


def compute_branches(gaps: Sequence[float], workers: int, scan: int
                     ) -> tuple[dict[str, xr.Dataset], dict[str, Any]]:
    """All branches of every gap and N, named ``<gap tag>_N<N>_<letter>``."""
    t0 = time.perf_counter()
    jobs = [(b, N, scan) for b in gaps for N in N_VALUES]
    results = _run_tasks(branches_for, jobs, workers)
    named: dict[str, xr.Dataset] = {}
    info = []
    for res in results:
        for letter, ds in zip(string.ascii_lowercase, res["branches"], strict=False):
            named[f"{gap_tag(res['b'])}_N{res['N']}_{letter}"] = ds
        info.append({k: v for k, v in res.items() if k != "branches"}
                    | {"branches": len(res["branches"])})
    wall = time.perf_counter() - t0
    points = sum(ds.sizes["point"] for ds in named.values())
    timing = {"seconds": wall, "branches": len(named), "points": points,
              "branches_per_second": len(named) / wall, "points_per_second": points / wall,
              "cpu_seconds": sum(r["cpu_seconds"] for r in results), "workers": workers,
              "per_gap_and_N": info}
    timing["points_per_cpu_second"] = points / timing["cpu_seconds"]
    log.info("continuation: %d branches, %d points in %.1f s wall (%.2f branches/s, %.0f "
             "points/s; %.1f s CPU, %.0f points per CPU second; includes the existence "
             "scans)", len(named), points, wall, timing["branches_per_second"],
             timing["points_per_second"], timing["cpu_seconds"],
             timing["points_per_cpu_second"])
    return named, timing


# ---------------------------------------------------------------------------------------------
# Special points: table and independent checks
# ---------------------------------------------------------------------------------------------
def _bracket_partner(ds: xr.Dataset, k: int) -> int:
    """Index of the other accepted point of the pair that brackets special point ``k``.

    Parameters
    ----------
    ds : xarray.Dataset
        One branch (the schema of :func:`impactcont.continuation`).
    k : int
        Index of the special point on the ``special`` dimension.

    Returns
    -------
    int
        The neighbour ``q`` (``p - 1`` or ``p + 1``) of the special point's nearest
        accepted point ``p``.

    Raises
    ------
    ValueError
        If neither neighbour of ``p`` spans the stored bracket.

    Notes
    -----
    The detection brackets a special point between two consecutive accepted points and
    stores as its bracket the range of omega the branch covers between them, which also
    holds the located omega (``impactcont.dataset.records.special_record``). At a fold
    (SN), and at a point between the last accepted point before a fold and the fold, the
    located omega lies beyond both points and is an end of the bracket. So the partner is
    the neighbour ``q`` with ``min``/``max`` of (omega_p, omega_q, omega*) equal to the
    bracket. When both neighbours fit (the branch turns twice within the step), the one
    whose segment to ``p`` passes nearer the located (omega, delta) is taken.
    """
    p = int(ds["special_point"].values[k])
    om, de = ds["omega"].values, ds["delta"].values
    lo, hi = float(ds["special_bracket_lo"].values[k]), float(ds["special_bracket_hi"].values[k])
    omega, delta = float(ds["special_omega"].values[k]), float(ds["special_delta"].values[k])

    def same(a: float, b: float) -> bool:
        return math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-14)

    def detour(q: int) -> float:
        """How much longer the way p -> special point -> q is than p -> q."""
        d = [complex(om[i] - omega, float(_wrap(de[i] - delta))) for i in (p, q)]
        return abs(d[0]) + abs(d[1]) - abs(complex(om[q] - om[p], float(_wrap(de[q] - de[p]))))

    fits = [q for q in (p - 1, p + 1) if 0 <= q < om.size
            and same(min(om[p], om[q], omega), lo) and same(max(om[p], om[q], omega), hi)]
    if not fits:
        raise ValueError(
            f"special point {k} ({ds['special_label'].values[k]} at omega={omega:.12g}) of "
            f"the branch: no neighbour of its point {p} (omega={om[p]:.12g}) spans its "
            f"bracket [{lo:.12g}, {hi:.12g}] with it; a bracket must be the omega range of "
            "two consecutive points and the location")
    return min(fits, key=detour)


def special_records(branches: dict[str, xr.Dataset]) -> list[dict[str, Any]]:
    """One record per special point, with where it sits (physical part or not)."""
    records = []
    for name, ds in branches.items():
        om = ds["omega"].values
        physical = ds["physical"].values
        labels = ds["special_label"].values
        for k in range(ds.sizes["special"]):
            p = int(ds["special_point"].values[k])
            q = _bracket_partner(ds, k)
            n_phys = int(physical[p]) + int(physical[q])
            omega = float(ds["special_omega"].values[k])
            others = np.delete(ds["special_omega"].values, k)
            d_next = float(np.min(np.abs(others - omega))) if others.size else math.inf
            records.append({
                "b": float(ds["special_b"].values[k]), "N": int(ds.attrs["N"]),
                "branch": name, "label": str(labels[k]), "omega": omega,
                "delta": float(ds["special_delta"].values[k]), "point": p, "partner": q,
                "precision": float(ds["special_precision"].values[k]),
                "status": str(ds["special_status"].values[k]),
                "bracket": [float(ds["special_bracket_lo"].values[k]),
                            float(ds["special_bracket_hi"].values[k])],
                "multiplier_moduli": np.abs(ds["special_multipliers"].values[k]),
                "impact_velocity_near": float(ds["impact_velocity"].values[p]),
                "part": {2: "physical", 1: "boundary", 0: "non-physical"}[n_phys],
                "distance_to_next_special": d_next,
                "omega_range_of_branch": [float(om.min()), float(om.max())],
            })
    records.sort(key=lambda r: (r["b"], r["N"], r["omega"]))
    return records


def _branch_deltas(ds: xr.Dataset, p: int, omega: float) -> list[float]:
    """delta of the branch at ``omega``, reached from point ``p`` backwards and forwards.

    A direction is walked only while it approaches ``omega``: the pieces of the branch
    beyond a fold are other motions, except at the fold itself (SN), where both
    directions reach the same side.
    """
    om, de = ds["omega"].values, ds["delta"].values
    out = []
    for step in (-1, 1):
        i = p
        while 0 <= i + step < om.size:
            j = i + step
            if min(om[i], om[j]) <= omega <= max(om[i], om[j]) and om[i] != om[j]:
                t = (omega - om[i]) / (om[j] - om[i])
                out.append(float(de[i] + t * _wrap(de[j] - de[i])))
                break
            if abs(om[j] - omega) > abs(om[i] - omega):
                break
            i = j
    return out


def _describe(P: int, p: int, v: np.ndarray) -> str:
    if P == 0:
        return "no impact"
    if P < 0:
        return (f"no period <= {MAX_PATTERN}T, v in [{np.min(v):.4f}, {np.max(v):.4f}] "
                f"({v.size} impacts)")
    vals = " / ".join(f"{x:.4f}" for x in v[:p][:4]) + (" / ..." if p > 4 else "")
    return f"{p} impact{'s' if p > 1 else ''}/{P} period{'s' if P > 1 else ''}, v = {vals}"


def _one_flight(osc: ic.ImpactOscillator, orbit: ic.PeriodicOrbit) -> dict[str, Any]:
    """Simulate one period of the closed-form motion from its own state: does it return?"""
    N = orbit.N
    res = run_simulation(osc, orbit.state, orbit.delta, N + 0.5)
    out: dict[str, Any] = {"impacts": int(res.impact_times.size)}
    if res.impact_times.size:
        out["first_impact_over_T"] = float(res.impact_times[0] / orbit.period)
        out["state_deviation"] = float(np.max(np.abs(res.impact_states[0] - orbit.state)))
    out["returns"] = bool(res.impact_times.size == 1
                          and abs(out["first_impact_over_T"] - 1.0) < 1e-8
                          and out["state_deviation"] < 1e-8)
    return out


def _attractor(osc: ic.ImpactOscillator, N: int, state: np.ndarray, delta: float,
               rho: float, quick: bool, rng: np.random.Generator) -> dict[str, Any]:
    """Simulate from near ``state`` long enough for ``rho`` to act; detect the pattern."""
    dz = rng.normal(size=state.size)
    dz *= PERTURBATION / np.max(np.abs(dz))
    X = np.asarray(state, float).copy()
    X[1:] += dz[1:]                      # stay on the impact surface x1 = b
    cap = CHECK_MAX_QUICK if quick else CHECK_MAX
    log_rho = abs(math.log(rho)) if math.isfinite(rho) and rho > 0 else 0.0
    # the deviation needs `needed` periods to grow or decay 10^CHECK_DECADES-fold; a motion
    # born at the special point (a 2N-2 motion at a PD) converges about as slowly: twice that
    needed = CHECK_DECADES * math.log(10) / max(log_rho, 1e-12) * N
    record = max(48, CHECK_RECORD * N)
    base = CHECK_BASE_QUICK if quick else CHECK_BASE
    periods = int(min(cap, base + 2 * needed)) + record
    res = run_simulation(osc, X, delta + dz[0], periods)
    T = 2 * math.pi / osc.omega
    keep = res.impact_times > res.final_time - record * T
    t, v = res.impact_times[keep], res.impact_velocities[keep]
    P, p, resid = impact_pattern(t, v, T, tol=CHECK_TOL)
    near = None
    if P < 0 and resid < NEAR_TOL:
        Pn, pn, _ = impact_pattern(t, v, T, tol=NEAR_TOL)
        near = (Pn, pn)
    text = _describe(P, p, v)
    if near is not None:
        text = (f"~{near[1]} impacts/{near[0]} periods, still converging (repeats to "
                f"{resid:.0e}), v in [{np.min(v):.4f}, {np.max(v):.4f}]")
    return {"periods": periods, "record_periods": record, "status": res.status.name,
            "P": P, "p": p, "pattern": pattern_label(P, p) if near is None else
            f"~{near[0]}-{near[1]}", "near_pattern": near, "residual": resid,
            "velocities": v[:max(p, 0)] if P > 0 else v,
            "growth_or_decay_decades": log_rho * (periods - record) / N / math.log(10),
            "text": text}


def check_special(record: dict[str, Any], branch: xr.Dataset, quick: bool, seed: int
                  ) -> dict[str, Any]:
    """Simulate on both sides of one special point and compare with the closed form.

    The offset ``h`` is :data:`OFFSET_FRACTION` of the distance to the nearest other special
    point of the branch, within [OFFSET_MIN, OFFSET_MAX]. On each side every closed-form
    motion of the branch at ``omega -/+ h`` (two on the near side of a fold) is checked by

    * one flight: simulated from its own state for N + 1/2 periods, does it return to itself
      after exactly one impact at T (it does iff it is physical)?
    * its attractor: from 1e-6 off the motion, long enough for the closed form's spectral
      radius to shrink or grow a deviation 1e4-fold (capped), which pattern does the
      simulator show in the last 48 periods, and is it this N-1 motion?

    Where the branch has no motion (beyond a fold) the simulator starts from the motion at
    the special point.
    """
    c0 = time.process_time()
    rng = np.random.default_rng(seed)
    b, N, omega0 = record["b"], record["N"], record["omega"]
    h = float(np.clip(OFFSET_FRACTION * record["distance_to_next_special"], OFFSET_MIN,
                      OFFSET_MAX))
    p = record["point"]
    start_state = branch["state"].values[p]
    start_delta = float(branch["delta"].values[p])
    sides = {}
    for side, omega in (("below", omega0 - h), ("above", omega0 + h)):
        omega = float(np.clip(omega, *OMEGA_RANGE))
        osc = paper_oscillator(b, omega)
        roots = ic.periodic_orbits(osc, N)
        candidates = []
        for d in _branch_deltas(branch, p, omega):
            if not roots:
                break
            orbit = min(roots, key=lambda o, d=d: abs(float(_wrap(o.delta - d))))
            if abs(float(_wrap(orbit.delta - d))) < 0.2 and all(
                    orbit is not c["orbit"] for c in candidates):
                candidates.append({"orbit": orbit})
        runs = []
        for cand in candidates:
            orbit = cand["orbit"]
            att = _attractor(osc, N, orbit.state, orbit.delta, orbit.spectral_radius, quick, rng)
            v_cf = orbit.impact_velocity
            holds = bool(att["P"] == N and att["p"] == 1 and abs(
                att["velocities"][0] - v_cf) <= MATCH_TOL * max(1.0, abs(v_cf)))
            predicted = bool(orbit.physical and orbit.stable)
            conclusive = predicted == holds or att["growth_or_decay_decades"] >= 1.0 or \
                not orbit.physical
            flight = _one_flight(osc, orbit)
            runs.append({
                "closed_form": {"delta": orbit.delta, "impact_velocity": v_cf,
                                "gap_min": orbit.gap_min, "spectral_radius":
                                orbit.spectral_radius, "physical": orbit.physical,
                                "stable": orbit.stable, "reason": orbit.reason},
                "one_flight": flight, "attractor": att, "holds_N1": holds,
                "predicted_holds_N1": predicted,
                "one_flight_agrees": flight["returns"] == orbit.physical,
                "attractor_agrees": holds == predicted, "conclusive": bool(conclusive)})
        if not candidates:
            att = _attractor(osc, N, start_state, start_delta, math.nan, quick, rng)
            v0 = record["impact_velocity_near"]
            holds = bool(att["P"] == N and att["p"] == 1
                         and abs(att["velocities"][0] - v0) < 0.02)
            runs.append({"closed_form": None, "attractor": att, "holds_N1": holds,
                         "predicted_holds_N1": False, "one_flight_agrees": True,
                         "attractor_agrees": not holds, "conclusive": True})
        sides[side] = {"omega": omega, "runs": runs}
    out = dict(record)
    out.update(offset=h, sides=sides, expected_change=EXPECTED[record["label"]])
    out.update(_verdict(record["label"], N, sides))
    out["cpu_seconds"] = time.process_time() - c0
    return out


def _side_text(side: dict[str, Any]) -> str:
    parts = []
    for run in side["runs"]:
        cf = run["closed_form"]
        att = run["attractor"]
        if cf is None:
            head = "no N-1 motion"
        else:
            kind = ("stable" if cf["stable"] else "unstable") if cf["physical"] else \
                "NOT physical"
            flight = run["one_flight"]
            ret = "returns" if flight["returns"] else f"no return: {_flight_text(flight)}"
            head = f"closed form {kind}, v={cf['impact_velocity']:.4f}, {ret}"
        sim = att["text"] + (" [= this N-1 motion]" if run["holds_N1"] else "")
        parts.append(f"{head}; sim: {sim}")
    return "<br>".join(parts)


def _flight_text(flight: dict[str, Any]) -> str:
    if not flight["impacts"]:
        return "no impact within N + 1/2 periods"
    ratio = flight["first_impact_over_T"]
    if ratio < 1e-6:
        return "re-impacts at once (leaves the stop moving into it)"
    return f"first impact at {ratio:.3f}T"


def _verdict(label: str, N: int, sides: dict[str, Any]) -> dict[str, Any]:
    """Is what the simulator shows on the two sides the change ``label`` predicts?

    Every run must agree with the closed form (one flight returns iff physical; the
    simulator stays on the motion iff physical and stable). The change itself is
    observable for PD, NS and SN when the motion is held on one side only, for GR and ZV
    when it returns after one flight on one side only.
    """
    runs = [r for s in sides.values() for r in s["runs"]]
    agrees = all(r["one_flight_agrees"] and r["attractor_agrees"] for r in runs
                 if r["conclusive"])
    inconclusive = any(not r["conclusive"] for r in runs)
    holds = {k: any(r["holds_N1"] for r in s["runs"]) for k, s in sides.items()}
    returns = {k: any(r.get("one_flight", {}).get("returns", False) for r in s["runs"])
               for k, s in sides.items()}
    if label in ("GR", "ZV"):
        observable = returns["below"] != returns["above"]
    else:
        observable = holds["below"] != holds["above"]
    note = ""
    pattern_seen = True
    if label in ("PD", "NS") and observable:
        lost = "below" if not holds["below"] else "above"
        lost_runs = [r for r in sides[lost]["runs"] if r["closed_form"] is not None]

        def near(r: dict[str, Any]) -> bool:
            """All recorded impact velocities within 30 % of the closed form's."""
            v, vc = np.asarray(r["attractor"]["velocities"]), r["closed_form"]["impact_velocity"]
            return bool(v.size and np.max(np.abs(v - vc)) <= NEARBY * max(abs(vc), 0.05))

        if label == "PD":
            doubled = [r for r in lost_runs if (2 * N, 2) in (
                (r["attractor"]["P"], r["attractor"]["p"]),
                tuple(r["attractor"]["near_pattern"] or ()))]
            pattern_seen = any(near(r) for r in doubled)
            note = ("2N-2 motion next to the N-1 one seen" if pattern_seen
                    else "a 2N-2 motion, but far from the N-1 one" if doubled else
                    "no 2N-2 motion: the simulator leaves (subcritical PD, or the 2N-2 "
                    "motion is already unstable at this offset)")
        else:
            drift = [r for r in lost_runs if r["attractor"]["P"] < 0]
            pattern_seen = any(near(r) for r in drift)
            note = ("quasi-periodic drift around the N-1 motion seen" if pattern_seen else
                "no period, but far from the N-1 motion (not a small invariant circle at "
                "this offset: a jump to an irregular motion)" if drift else
                "a periodic motion instead of a drift (locking or jump)")
    elif label in ("GR", "ZV"):
        bad = [r for r in runs if r["closed_form"] is not None
               and not r["closed_form"]["physical"]]
        if bad:
            note = "non-physical side, one flight: " + ", ".join(
                _flight_text(r["one_flight"]) for r in bad)
    elif label == "SN":
        counts = {k: sum(r["closed_form"] is not None for r in s["runs"])
                  for k, s in sides.items()}
        note = f"closed-form motions below/above: {counts['below']}/{counts['above']}"
        if not observable and returns["below"] != returns["above"]:
            note += ("; the unstable pair returns after one flight on its side only, no "
                     "stable motion to watch disappear")
    if not agrees:
        verdict = "DISAGREES"
    elif inconclusive:
        verdict = "inconclusive (rho too close to 1 for the simulated time)"
    elif observable and pattern_seen:
        verdict = "confirmed"
    elif observable:
        verdict = "stability change confirmed, expected motion beyond it not seen"
    else:
        verdict = "consistent, change not observable"
    return {"verdict": verdict, "agrees": bool(agrees), "observable": bool(observable),
            "expected_motion_seen": bool(pattern_seen), "note": note,
            "below_text": _side_text(sides["below"]), "above_text": _side_text(sides["above"])}


def check_all(records: list[dict[str, Any]], branches: dict[str, xr.Dataset], quick: bool,
              workers: int) -> tuple[list[dict[str, Any]], float]:
    """Run :func:`check_special` for every record (in ``workers`` processes)."""
    t0 = time.perf_counter()
    jobs = [(r, branches[r["branch"]], quick, SEED + k) for k, r in enumerate(records)]
    checked = _run_tasks(check_special, jobs, workers)
    seconds = time.perf_counter() - t0
    for c in checked:
        log.info("b=%g N=%d %s omega=%.6f: %s (%s)", c["b"], c["N"], c["label"], c["omega"],
                 c["verdict"], c["note"])
    log.info("checks of %d special points: %.1f s wall, %.1f s CPU", len(checked), seconds,
             sum(c["cpu_seconds"] for c in checked))
    return checked, seconds


def special_points_markdown(checked: list[dict[str, Any]], skipped: list[dict[str, Any]]
                            ) -> str:
    """The special-point table with its checks, as Markdown."""
    lines = [
        "| b | N | label | omega | precision | status | part | h | below (omega - h) | "
        "above (omega + h) | verdict |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in checked:
        verdict = c["verdict"] + (f"; {c['note']}" if c["note"] else "")
        lines.append(
            f"| {c['b']:g} | {c['N']} | {c['label']} | {c['omega']:.6f} | "
            f"{c['precision']:.1e} | {c['status']} | {c['part']} | {c['offset']:.1e} | "
            f"{c['below_text']} | {c['above_text']} | {verdict} |")
    lines += ["", f"{len(skipped)} special points lie on non-physical parts of branches "
              "(both bracketing points non-physical) and are not checked:", ""]
    lines += [f"- b={s['b']:g} N={s['N']} {s['label']} at omega={s['omega']:.6f} "
              f"({s['branch']})" for s in skipped]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# Brute force
# ---------------------------------------------------------------------------------------------
def _start_state(b: float) -> np.ndarray:
    return np.array([min(0.0, b - 0.5), 0.0, 0.0, 0.0])


def sweep(b: float, direction: str, omegas: np.ndarray, transient: int, record: int
          ) -> dict[str, Any]:
    """Sweep omega in one direction carrying the state: impacts after each transient.

    The state is continuous across a change of omega; so is the forcing phase
    ``omega t + delta``, which is why the next run starts at ``final_phase``.
    """
    t0, c0 = time.perf_counter(), time.process_time()
    order = omegas if direction == "up" else omegas[::-1]
    X, phase = _start_state(b), 0.0
    rows = {}
    for i, w in enumerate(order):
        osc = paper_oscillator(b, float(w))
        skip = transient * (2 if i == 0 else 1)
        res = run_simulation(osc, X, phase, skip + record)
        T = 2 * math.pi / osc.omega
        keep = res.impact_times > res.final_time - record * T
        t, v, ph = (res.impact_times[keep], res.impact_velocities[keep],
                    res.impact_phases[keep])
        if res.success:
            P, p, resid = impact_pattern(t, v, T, tol=SWEEP_TOL)
            converged = P >= 0
            if not converged and resid < NEAR_TOL:  # a pattern still converging
                P, p, _ = impact_pattern(t, v, T, tol=NEAR_TOL)
            X, phase = res.final_state, res.final_phase
        else:  # chatter or sticking: outside the model; restart the sweep from rest
            P, p, resid, converged = -2, -2, math.nan, False
            X, phase = _start_state(b), 0.0
        rows[float(w)] = {"v": v, "phase": ph, "P": P, "p": p, "residual": resid,
                          "converged": converged, "status": res.status.name}
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    log.info("sweep b=%g %s: %d omegas in %.1f s (%.1f s CPU)", b, direction, len(order),
             seconds, cpu)
    return {"b": b, "direction": direction, "rows": rows, "seconds": seconds, "cpu_seconds": cpu,
            "periods": len(order) * (transient + record) + transient}


def brute_force_sweeps(gaps: Sequence[float], n_omega: int, transient: int, record: int,
                workers: int) -> tuple[xr.Dataset, dict[str, Any]]:
    """Sweeps up and down for every gap, as one Dataset (gap, sweep, omega, sample)."""
    t0 = time.perf_counter()
    omegas = np.linspace(*OMEGA_RANGE, n_omega)
    jobs = [(b, d, omegas, transient, record) for b in gaps for d in ("up", "down")]
    results = _run_tasks(sweep, jobs, workers)
    wall = time.perf_counter() - t0
    sweeps = ["up", "down"]
    nsample = max(1, max(r["rows"][float(w)]["v"].size for r in results for w in omegas))
    shape = (len(gaps), 2, n_omega)
    vel = np.full((*shape, nsample), np.nan)
    pha = np.full((*shape, nsample), np.nan)
    P = np.zeros(shape, dtype=np.int64)
    p = np.zeros(shape, dtype=np.int64)
    resid = np.full(shape, np.nan)
    converged = np.zeros(shape, dtype=bool)
    status = np.empty(shape, dtype=object)
    for r in results:
        g, s = list(gaps).index(r["b"]), sweeps.index(r["direction"])
        for k, w in enumerate(omegas):
            row = r["rows"][float(w)]
            vel[g, s, k, :row["v"].size] = row["v"]
            pha[g, s, k, :row["phase"].size] = row["phase"]
            P[g, s, k], p[g, s, k], status[g, s, k] = row["P"], row["p"], row["status"]
            resid[g, s, k], converged[g, s, k] = row["residual"], row["converged"]
    dims = ("gap", "sweep", "omega")
    ds = xr.Dataset(
        {
            "impact_velocity": ((*dims, "sample"), vel, {
                "long_name": "impact velocity", "units": "1",
                "description": "x1' just before each impact in the recorded window, in order; "
                               "NaN-padded"}),
            "impact_phase": ((*dims, "sample"), pha, {
                "long_name": "forcing phase at impact", "units": "rad",
                "description": "omega t + delta at each recorded impact, wrapped to (-pi, pi]"}),
            "pattern_periods": (dims, P, {
                "long_name": "forcing periods of the impact pattern", "units": "1",
                "description": f"P of a P-p motion (p impacts every P forcing periods); 0: "
                               f"no impact; -1: no period <= {MAX_PATTERN}; -2: the "
                               f"simulation stopped (chatter/sticking)"}),
            "pattern_impacts": (dims, p, {
                "long_name": "impacts per pattern", "units": "1",
                "description": "p of a P-p motion; same codes as pattern_periods"}),
            "pattern_residual": (dims, resid, {
                "long_name": "repetition residual of the impact pattern", "units": "1",
                "description": "smallest repetition residual over the patterns tried (impact "
                               "times / T and velocities / max(1, v))"}),
            "pattern_converged": (dims, converged, {
                "long_name": "pattern repeats to the tolerance", "units": "1",
                "description": f"True: residual < {SWEEP_TOL:g}; False with "
                               f"pattern_periods > 0: it repeats only to {NEAR_TOL:g} "
                               f"(still converging)"}),
            "status": (dims, status.astype(str), {
                "long_name": "simulation status", "units": "1",
                "description": "impactcont.SimulationStatus name"}),
        },
        coords={"gap": ("gap", np.asarray(gaps, float), {"long_name": "gap b", "units": "1"}),
                "sweep": ("sweep", sweeps, {"long_name": "sweep direction"}),
                "omega": ("omega", omegas, {"long_name": "forcing frequency", "units": "1"}),
                "sample": ("sample", np.arange(nsample))},
        attrs={"title": "Brute-force bifurcation diagram: simulated omega sweeps",
               "transient_periods": transient, "record_periods": record,
               "first_transient_periods": 2 * transient, "pattern_tolerance": SWEEP_TOL,
               "near_pattern_tolerance": NEAR_TOL,
               "max_pattern_periods": MAX_PATTERN,
               "oscillator": paper_oscillator(gaps[0]).to_json(),
               "impactcont_version": ic.__version__, "Conventions": "CF-1.10",
               "history": f"{time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime())} "
                          "studies/bifurcation_diagram/run.py"})
    periods = sum(r["periods"] for r in results)
    cpu = sum(r["cpu_seconds"] for r in results)
    timing = {"seconds": wall, "cpu_seconds": cpu, "sweeps": len(results), "n_omega": n_omega,
              "transient_periods": transient, "record_periods": record,
              "simulated_periods": periods, "ms_per_period_cpu": 1e3 * cpu / periods,
              "workers": workers}
    log.info("brute force: %d sweeps x %d omegas, %d forcing periods in %.1f s wall, %.1f s "
             "CPU (%.2f ms CPU per forcing period)", len(results), n_omega, periods, wall, cpu,
             timing["ms_per_period_cpu"])
    return ds, timing


def write_netcdf_atomic(ds: xr.Dataset, path: Path) -> None:
    """``ds.to_netcdf`` (engine netcdf4) to a temporary file moved onto ``path``."""
    tmp = path.parent / f".{path.name}.{uuid.uuid4().hex}.tmp"
    try:
        ds.to_netcdf(tmp, mode="w", engine="netcdf4")
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    log.info("wrote %s", path)


def seeded_run(b: float, omega: float, N: int, v_cf: float, transient: int, record: int,
               seed: int) -> dict[str, Any]:
    """Start 1e-4 off a stable physical closed-form motion: does the simulator stay on it?"""
    osc = paper_oscillator(b, omega)
    orbit = min((o for o in ic.periodic_orbits(osc, N) if o.physical and o.stable),
                key=lambda o: abs(o.impact_velocity - v_cf))
    rng = np.random.default_rng(seed)
    dz = rng.normal(size=orbit.state.size)
    dz *= 1e-4 / np.max(np.abs(dz))
    X = orbit.state.copy()
    X[1:] += dz[1:]
    res = run_simulation(osc, X, orbit.delta + dz[0], transient + record)
    T = 2 * math.pi / omega
    keep = res.impact_times > res.final_time - record * T
    t, v = res.impact_times[keep], res.impact_velocities[keep]
    P, p, resid = impact_pattern(t, v, T, tol=NEAR_TOL)
    # still on the motion: one impact every N periods, every velocity close to it (a slowly
    # converging motion may repeat after 2 impacts first, so the pattern is not the test)
    dev = float(np.max(np.abs(v - v_cf))) if v.size else math.inf
    stays = bool(abs(v.size - record / N) <= 1 and dev < 1e-3 * max(1.0, v_cf))
    return {"omega": omega, "N": N, "impact_velocity": v_cf,
            "spectral_radius": orbit.spectral_radius, "simulated": pattern_label(P, p),
            "residual": resid, "max_deviation": dev,
            "stays": stays}


def _pattern_at(sel: xr.Dataset, k: int) -> tuple[int, int, bool, np.ndarray]:
    v = sel["impact_velocity"].values[k]
    return (int(sel["pattern_periods"].values[k]), int(sel["pattern_impacts"].values[k]),
            bool(sel["pattern_converged"].values[k]), v[np.isfinite(v)])


def compare(bf: xr.Dataset, workers: int) -> dict[str, Any]:
    """Brute force against the closed form.

    For every gap: what each sweep point is (an N-1 motion of a stable physical branch, a
    multi-impact motion, no period, no impact, ...); the stable physical closed-form
    motions (N = 1..4) at the sweep's omegas that neither sweep found, each re-simulated
    from 1e-4 off the closed form to see whether it is a coexisting attractor; and the
    omegas where the two sweeps end on different patterns, or on one periodic pattern
    with different impact velocities (coexisting attractors: hysteresis).
    """
    transient = int(bf.attrs["transient_periods"])
    record = int(bf.attrs["record_periods"])
    out: dict[str, Any] = {}
    jobs = []
    for b in bf["gap"].values:
        per_gap: dict[str, Any] = {}
        stable_cf: dict[float, list[tuple[int, float]]] = {}
        for w in bf["omega"].values:
            osc = paper_oscillator(float(b), float(w))
            stable_cf[float(w)] = [(N, o.impact_velocity) for N in N_VALUES
                                   for o in ic.periodic_orbits(osc, N)
                                   if o.physical and o.stable]

        def matches(P: int, p: int, conv: bool, v: np.ndarray, N: int, vc: float) -> bool:
            """Is the sweep point the N-1 motion with impact velocity vc?

            A motion still converging with alternating deviations (a multiplier near -1)
            repeats after 2 impacts before it repeats after 1: accept P = kN, p = k then.
            """
            if not v.size or P <= 0:
                return False
            if conv:
                return bool(P == N and p == 1 and abs(v[0] - vc) < 1e-3 * max(1.0, vc))
            return bool(P % N == 0 and p == P // N
                        and np.max(np.abs(v[:p] - vc)) < 1e-2 * max(1.0, vc))

        for s in bf["sweep"].values:
            sel = bf.sel(gap=b, sweep=s)
            counts: dict[str, int] = {}
            for k, w in enumerate(sel["omega"].values):
                P, p, conv, v = _pattern_at(sel, k)
                if P == 0:
                    kind = "no impact"
                elif P == -1:
                    kind = f"no period <= {MAX_PATTERN}T (chaotic, quasi-periodic or long " \
                           "transient)"
                elif P == -2:
                    kind = "stopped (chatter/sticking)"
                elif any(matches(P, p, conv, v, N, vc) for N, vc in stable_cf[float(w)]):
                    kind = "N-1 on a stable physical branch"
                elif p >= 2:
                    kind = "P-p with p >= 2 impacts (not an N-1 motion)"
                elif max(N_VALUES) < P:
                    kind = f"N-1 with N > {max(N_VALUES)} (not computed)"
                else:
                    kind = "N-1 NOT on a stable physical branch"
                if P > 0 and not conv:
                    kind += " (still converging)"
                counts[kind] = counts.get(kind, 0) + 1
            per_gap[f"sweep_{s}"] = dict(sorted(counts.items()))
        missed = []
        for k, w in enumerate(bf["omega"].values):
            for N, vc in stable_cf[float(w)]:
                if not any(matches(*_pattern_at(bf.sel(gap=b, sweep=s), k), N, vc)
                           for s in bf["sweep"].values):
                    missed.append((float(b), float(w), N, vc))
        jobs += [(*m, transient, record, SEED + 7 * i) for i, m in enumerate(missed)]
        up, down = bf.sel(gap=b, sweep="up"), bf.sel(gap=b, sweep="down")
        differ = []
        for k, w in enumerate(bf["omega"].values):
            Pu, pu, _, vu = _pattern_at(up, k)
            Pd, pd, _, vd = _pattern_at(down, k)
            if (Pu, pu) != (Pd, pd) or (
                    Pu > 0 and not np.allclose(np.sort(vu[:pu]), np.sort(vd[:pd]), atol=1e-3)):
                differ.append(float(w))
        per_gap["stable_physical_closed_form_motions"] = sum(len(v) for v in stable_cf.values())
        per_gap["omega_where_sweeps_differ"] = differ
        out[gap_tag(float(b))] = per_gap
    seeded = _run_tasks(seeded_run, jobs, workers)
    for b in bf["gap"].values:
        per_gap = out[gap_tag(float(b))]
        mine = [r for r, j in zip(seeded, jobs, strict=True) if j[0] == float(b)]
        per_gap["stable_physical_missed_by_both_sweeps"] = mine
        per_gap["missed_but_attractor_when_seeded"] = sum(r["stays"] for r in mine)
        log.info("b=%g: up %s; down %s", b, per_gap["sweep_up"], per_gap["sweep_down"])
        log.info("b=%g: %d of %d stable physical closed-form motions missed by both sweeps "
                 "(%d of them stay when seeded); the sweeps end on different patterns "
                 "at %d omegas", b, len(mine),
                 per_gap["stable_physical_closed_form_motions"],
                 per_gap["missed_but_attractor_when_seeded"],
                 len(per_gap["omega_where_sweeps_differ"]))
    return out


# ---------------------------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------------------------
N_COLORS = {1: "tab:blue", 2: "tab:orange", 3: "tab:green", 4: "tab:red"}
#: Zoom panels (omega range, impact-velocity range) where special points crowd.
DPI = 150  # of the PNGs (7 in wide: 1050 pixels)
ZOOMS = {0.5: ((1.205, 1.265), (-0.005, 0.2))}
SWEEP_STYLES = {"up": {"marker": "o", "s": 12, "facecolors": "none", "edgecolors": "0.45",
                       "linewidths": 0.6},
                "down": {"marker": "x", "s": 6, "color": "0.1", "linewidths": 0.5}}


def _draw_gap(ax: Any, b: float, branches: dict[str, xr.Dataset],
              checked_keys: set[tuple[str, float]], bf: xr.Dataset | None
              ) -> tuple[float, set[str]]:
    """Draw one gap's branches and sweeps on ``ax``; return the largest physical v, labels."""
    tag = gap_tag(b)
    vmax = 0.0
    labels: set[str] = set()
    for N in N_VALUES:
        group = {}
        for name, ds in branches.items():
            if not name.startswith(f"{tag}_N{N}_"):
                continue
            keep = [k for k in range(ds.sizes["special"])
                    if (name, float(ds["special_omega"].values[k])) in checked_keys]
            group[name] = ds.isel(special=keep)
            labels |= {str(x) for x in group[name]["special_label"].values}
            phys = ds["impact_velocity"].values[ds["physical"].values]
            if phys.size:
                vmax = max(vmax, float(phys.max()))
        if not group:
            continue
        before = len(ax.lines)
        bifurcation_diagram(group, y="impact_velocity", ax=ax, legend=None, title="",
                            label_special=False)  # labelled together, once laid out
        for line in ax.lines[before:]:
            line.set_color(N_COLORS[N])
            if line.get_markeredgecolor() != NONPHYSICAL_GREY:  # special points: colour of N
                line.set_markeredgecolor(N_COLORS[N])
            if line.get_linestyle() in ("None", "none", " ", ""):
                # open: a special point drawn over the simulated points hides none of them
                line.set_markerfacecolor("none")
    if bf is not None:
        sel = bf.sel(gap=b)
        for sweep_name in SWEEP_STYLES:
            v = sel["impact_velocity"].sel(sweep=sweep_name).values
            ok = np.isfinite(v)
            if ok.any():
                vmax = max(vmax, float(np.percentile(v[ok], 99)))
    return vmax, labels


def _sweeps(ax: Any, b: float, bf: xr.Dataset) -> None:
    """The brute-force sweeps' impacts on ``ax``, once laid out: a point the frame would
    cut in half is left out."""
    sel = bf.sel(gap=b)
    for sweep_name, style in SWEEP_STYLES.items():
        v = sel["impact_velocity"].sel(sweep=sweep_name).values
        w = np.broadcast_to(sel["omega"].values[:, None], v.shape)
        # smaller at one column (area in proportion to the width): at 3.5 in, markers of
        # the full size buried the special points in the windows between N-1 windows
        style = {**style, "s": style["s"] * min(1.0, ax.figure.get_figwidth() / 7.0)}
        ok = np.isfinite(v) & inside_frame(ax, w, v, math.sqrt(style["s"]))
        ax.scatter(w[ok], v[ok], zorder=1, **style)


def _label_all(ax: Any) -> None:
    """One labelling of every special point drawn on ``ax`` (all N together: labels of one
    N placed before the next N was drawn covered its points)."""
    names = {str(MarkerStyle(m).get_marker()): lab for lab, m in SPECIAL_MARKERS.items()}
    x0, x1 = sorted(ax.get_xlim())
    y0, y1 = sorted(ax.get_ylim())
    points = []
    for line in ax.get_lines():
        lab = names.get(str(line.get_marker()))
        if lab is None or line.get_markeredgecolor() == NONPHYSICAL_GREY \
                or line.get_linestyle() not in ("None", "none", " ", ""):
            continue
        points += [(float(x), float(y), lab) for x, y in line.get_xydata()
                   if x0 <= x <= x1 and y0 <= y <= y1]
    # at one column, "small" labels crowd the panel
    label_specials(ax, points, zoom=False,
                   fontsize="x-small" if ax.figure.get_figwidth() < 5.0 else "small")


def gap_figure(b: float, branches: dict[str, xr.Dataset], checked_keys: set[tuple[str, float]],
               bf: xr.Dataset | None, width: float = 7.0) -> Figure:
    """Branches of one gap (colour per N) with the brute-force points and special points.

    Only the special points of the table (physical parts) are marked, their kind by the
    marker's shape and their N by its colour, both named in the legend; points at one
    place are one combined marker (each inside the one before). A zoom panel is added
    under the diagram where they crowd (:data:`ZOOMS`), and names them there; one legend
    under both.

    Notes
    -----
    The diagram itself carries no text labels: on a full run's sweeps (120 omega values,
    every impact of 30 periods) the simulated points fill the windows between the N-1
    windows where the grazings and period doublings lie, and a label there covered them
    (98 simulated points under the GR labels at b = 0, 7 in).
    """
    if not 2.0 <= width <= MAX_WIDTH:
        raise ValueError(f"width must be in [2, {MAX_WIDTH}] inches; got {width!r}")
    zoom = ZOOMS.get(b)
    fig = Figure(figsize=(width, 0.62 * width + 1.4 + (0.4 * width if zoom else 0.0)),
                 layout="constrained")
    if zoom is None:
        axes = [fig.add_subplot()]
    else:
        grid = fig.add_gridspec(2, 1, height_ratios=(1.6, 1.0))
        axes = [fig.add_subplot(grid[0]), fig.add_subplot(grid[1])]
    ax = axes[0]
    vmax, labels = _draw_gap(ax, b, branches, checked_keys, bf)
    ax.set_ylim(-0.05 * vmax, 1.1 * vmax)
    margin = 0.015 * (OMEGA_RANGE[1] - OMEGA_RANGE[0])  # the sweeps' ends off the frame
    ax.set_xlim(OMEGA_RANGE[0] - margin, OMEGA_RANGE[1] + margin)
    ax.set_title(rf"$b = {b:g}$, $R = 0.6$, $\eta = 0.1$: periodic motions with one impact "
                 r"in $N$ periods, continued, and simulated sweeps in $\omega$",
                 fontsize="medium")
    handles = [Line2D([], [], color=N_COLORS[N], label=f"$N = {N}$") for N in N_VALUES]
    handles += [Line2D([], [], color="0.2", label=kind, **style)  # a style in any colour
                for kind, style in SEGMENT_STYLES.items()]
    handles += [Line2D([], [], linestyle="none", marker=m, markerfacecolor="none",
                       markeredgecolor="black", label=f"{lab} {SPECIAL_NAMES[lab]}")
                for lab, m in SPECIAL_MARKERS.items() if lab in labels]
    if bf is not None:
        handles += [Line2D([], [], linestyle="none", marker="o", markerfacecolor="none",
                           markeredgecolor="0.45", label=r"simulated, $\omega$ swept up"),
                    Line2D([], [], linestyle="none", marker="x", color="0.1",
                           label=r"simulated, $\omega$ swept down")]
    if zoom is not None:
        zax = axes[1]
        _draw_gap(zax, b, branches, checked_keys, bf)
        zax.set_xlim(*zoom[0])
        zax.set_ylim(*zoom[1])
        zax.set_title(rf"zoom: ${zoom[0][0]:g} \leq \omega \leq {zoom[0][1]:g}$",
                      fontsize="medium")
    figure_legend(fig, handles)
    fit_labels(fig)
    # at one column the title and the legend take several lines: the figure grows so that
    # the diagram keeps its height (squashed, its labels found no room)
    fig.draw_without_rendering()
    short = 0.6 * width - ax.get_window_extent().height / fig.dpi
    if short > 0.05:
        fig.set_size_inches(width, fig.get_size_inches()[1] + short * (1.0 if zoom is None
                                                                        else 1.6))
    for a in axes:  # the layout is final
        markers_whole(a)
        nest_coincident_markers(a)
        if bf is not None:
            _sweeps(a, b, bf)
    if zoom is not None:  # the zoom's limits are final
        _label_all(axes[1])
    if zoom is not None:
        (x0, x1), (y0, y1) = axes[1].get_xlim(), axes[1].get_ylim()
        ax.indicate_inset((x0, y0, x1 - x0, y1 - y0), edgecolor="0.4")
    return fig


def plot_gap(b: float, branches: dict[str, xr.Dataset], checked_keys: set[tuple[str, float]],
             bf: xr.Dataset | None, path: Path, width: float = 7.0) -> None:
    """Write :func:`gap_figure` to ``path``."""
    gap_figure(b, branches, checked_keys, bf, width).savefig(path, dpi=DPI)
    log.info("wrote %s", path)


def draw_figures(out: Path, width: float = 7.0) -> list[Path]:
    """Redraw the figures from the stored ``branches.nc``, ``special_points.json`` and
    ``brute_force.nc`` (if the sweeps were run) of ``out``."""
    tree = ic.load(out / "branches.nc")
    branches = {name: node.to_dataset() for name, node in tree.children.items()}
    checked = json.loads((out / "special_points.json").read_text())["checked"]
    keys = {(c["branch"], c["omega"]) for c in checked}
    bf = xr.load_dataset(out / "brute_force.nc") if (out / "brute_force.nc").exists() else None
    gaps = sorted({float(ds["b"].values[0]) for ds in branches.values()})
    paths = []
    for b in gaps:
        path = out / f"bifurcation_{gap_tag(b)}.png"
        plot_gap(b, branches, keys, bf, path, width)
        paths.append(path)
    return paths


# ---------------------------------------------------------------------------------------------
# Main
# ---------------------------------------------------------------------------------------------
def _one_blas_thread() -> Any:
    """Limit BLAS to one thread: the matrices are 4 x 4, and OpenBLAS threads spinning in two
    worker processes on two cores triple the CPU time. A no-op without threadpoolctl."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - threadpoolctl comes with scipy's test stack
        return contextlib.nullcontext()
    return threadpool_limits(limits=1, user_api="blas")


def main(output_dir: str | Path = DEFAULT_OUTPUT, *, brute_force: bool = True,
         n_omega: int | None = None, quick: bool = False, gaps: Sequence[float] = GAPS,
         workers: int = WORKERS) -> dict[str, Any]:
    """Run the study and write its files into ``output_dir``.

    Parameters
    ----------
    output_dir : path
        Created if needed.
    brute_force : bool
        Run the simulated omega sweeps (the longest part).
    n_omega : int, optional
        Omega values per sweep; default 120, or 25 with `quick`.
    quick : bool
        Reduced brute-force grid and transient, and check runs capped at 200 periods
        instead of 4000 (some checks may then be inconclusive); the branches and special
        points are the same. For tests/CI.
    gaps : sequence of float
        The gaps b.
    workers : int
        Worker processes (1 runs everything in this process).

    Returns
    -------
    dict
        The summary written to ``summary.json``.
    """
    with _one_blas_thread():  # inherited by the forked workers
        return _main(Path(output_dir), brute_force, n_omega, quick, gaps, workers)


def _main(out: Path, brute_force: bool, n_omega: int | None, quick: bool,
          gaps: Sequence[float], workers: int) -> dict[str, Any]:
    t_start = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    gaps = tuple(float(b) for b in gaps)
    n_omega = (N_OMEGA_QUICK if quick else N_OMEGA) if n_omega is None else int(n_omega)
    transient, record = (TRANSIENT_QUICK, RECORD_QUICK) if quick else (TRANSIENT, RECORD)

    branches, cont_timing = compute_branches(gaps, workers, EXISTENCE_SCAN)
    ic.save(branches, out / "branches.nc")

    records = special_records(branches)
    to_check = [r for r in records if r["part"] != "non-physical"]
    skipped = [r for r in records if r["part"] == "non-physical"]
    checked, check_seconds = check_all(to_check, branches, quick, workers)
    _write_json(out / "special_points.json",
                {"checked": checked, "skipped_non_physical": skipped,
                 "settings": {"offset_fraction": OFFSET_FRACTION, "offset_min": OFFSET_MIN,
                              "offset_max": OFFSET_MAX, "perturbation": PERTURBATION,
                              "check_base_periods": CHECK_BASE_QUICK if quick else CHECK_BASE,
                              "check_decades": CHECK_DECADES,
                              "check_max_periods": CHECK_MAX_QUICK if quick else CHECK_MAX,
                              "check_record_periods_per_N": CHECK_RECORD, "pattern_tol": CHECK_TOL,
                              "match_tol": MATCH_TOL}})
    (out / "special_points.md").write_text(special_points_markdown(checked, skipped))
    log.info("wrote %s", out / "special_points.md")

    bf, bf_timing, comparison = None, None, None
    if brute_force:
        bf, bf_timing = brute_force_sweeps(gaps, n_omega, transient, record, workers)
        write_netcdf_atomic(bf, out / "brute_force.nc")
        t_cmp = time.perf_counter()
        comparison = compare(bf, workers)
        comparison["seconds"] = time.perf_counter() - t_cmp

    t_plot = time.perf_counter()
    keys = {(c["branch"], c["omega"]) for c in checked}
    for b in gaps:
        plot_gap(b, branches, keys, bf, out / f"bifurcation_{gap_tag(b)}.png")
    plot_seconds = time.perf_counter() - t_plot

    summary = {
        "settings": {"quick": quick, "gaps": gaps, "N": N_VALUES, "omega_range": OMEGA_RANGE,
                     "n_omega": n_omega, "workers": workers, "continuation": CONTINUATION,
                     "existence_scan": EXISTENCE_SCAN, "coverage_probes": COVERAGE_PROBES},
        "timing": {"continuation": cont_timing, "special_point_checks_seconds": check_seconds,
                   "special_point_checks_cpu_seconds": sum(c["cpu_seconds"] for c in checked),
                   "brute_force": bf_timing, "plots_seconds": plot_seconds,
                   "total_seconds": time.perf_counter() - t_start},
        "branches": {name: {"N": int(ds.attrs["N"]), "b": float(ds["b"].values[0]),
                            "points": ds.sizes["point"],
                            "omega_range": [float(ds["omega"].min()), float(ds["omega"].max())],
                            "physical_share": float(ds["physical"].mean()),
                            "stable_physical_share": float((ds["physical"] & ds["stable"]).mean()),
                            "special": [str(x) for x in ds["special_label"].values]}
                     for name, ds in branches.items()},
        "verdicts": {v: sum(c["verdict"] == v for c in checked)
                     for v in sorted({c["verdict"] for c in checked})},
        "brute_force_vs_branches": comparison,
    }
    _write_json(out / "summary.json", summary)
    log.info("done in %.1f s", summary["timing"]["total_seconds"])
    return _clean(summary)


def _parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--output", type=Path, default=DEFAULT_OUTPUT,
                        help=f"output directory (default {DEFAULT_OUTPUT})")
    parser.add_argument("--quick", action="store_true",
                        help=f"reduced brute-force grid ({N_OMEGA_QUICK} omegas) and shorter "
                             "simulations, for tests/CI")
    parser.add_argument("--n-omega", type=int, default=None, help="omega values per sweep")
    parser.add_argument("--no-brute-force", action="store_true", help="skip the sweeps")
    parser.add_argument("--workers", type=int, default=WORKERS, help="worker processes")
    parser.add_argument("--copy-figures", action="store_true",
                        help=f"also copy the PNGs to {FIGURES_DIR}")
    parser.add_argument("--figures-only", action="store_true",
                        help="only redraw the PNGs from the files of a finished run in the "
                        "output directory (seconds)")
    return parser.parse_args(argv)


if __name__ == "__main__":
    args = _parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s")
    logging.captureWarnings(True)
    if args.figures_only:
        draw_figures(Path(args.output))
    else:
        main(args.output, brute_force=not args.no_brute_force, n_omega=args.n_omega,
             quick=args.quick, workers=args.workers)
    if args.copy_figures:
        FIGURES_DIR.mkdir(exist_ok=True)
        for b in GAPS:
            name = f"bifurcation_{gap_tag(b)}.png"
            shutil.copy2(Path(args.output) / name, FIGURES_DIR / name)
            log.info("copied %s to %s", name, FIGURES_DIR)
