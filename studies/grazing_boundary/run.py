"""The (omega, b) diagram of the paper's system for N = 1..4: regions, boundaries, checks.

System (EQUATIONS.md section 6): n = 2, M = I, K = [[1, -1], [-1, 2]], eta = 0.1,
R = 0.6, F = [1, 0]; omega in [0.5, 6], b in [-1, 2].

1. A grid map of existence, physicality and stability (batched closed form,
   :func:`impactcont.analysis.maps.stability_map`), timed serially and on a process pool.
2. Seeds for the boundaries read off the map: every sign change of the relevant
   quantity between two neighbouring grid cells along omega (on every
   ``SEED_STRIDE``-th row of b) where a physical motion is involved, unless a
   curve already computed passes through that cell.
3. Each seed continued as a codim-1 curve (:func:`impactcont.analysis.curves.curve`): SN,
   PD, NS, GR (and ZV once: it does not depend on N), with its codim-2 points.
4. Checks: SN against b^2 = c^2 + s^2; ZV against the linear response; every
   curve crossing of every grid row against the map's edges; and the simulator on
   both sides of sampled curve points (returns / hits early for GR and ZV, decay /
   growth of a perturbation for PD and NS, motion present / absent for SN).

Writes ``map.nc``, ``curves.nc``, ``checks.json``, ``timings.json`` and
``grazing_boundary.png`` into the output directory. Run::

    .venv/bin/python studies/grazing_boundary/run.py [--output DIR] [--quick] [--copy-figures]
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import shutil
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # tiny matrices: BLAS threads only contend

import matplotlib

matplotlib.use("Agg")
import numpy as np
import xarray as xr

import impactcont as ic
from impactcont.analysis.curves import curve, curve_crossings
from impactcont.analysis.maps import stability_map
from impactcont.orbit.periodic import orbit_at_phase
from impactcont.plots.maps import two_parameter_figure

log = logging.getLogger("grazing_boundary")

HERE = Path(__file__).resolve().parent
DEFAULT_OUTPUT = HERE / "output"
FIGURES_DIR = HERE / "figures"
DPI = 150  # of the PNG (7 in wide: 1050 pixels)

OMEGA_RANGE = (0.5, 6.0)
B_RANGE = (-1.0, 2.0)
FULL = {"N": [1, 2, 3, 4], "n_omega": 221, "n_b": 121, "stride": 8, "per_kind": 6,
        "samples": 2}
QUICK = {"N": [1], "n_omega": 56, "n_b": 31, "stride": 5, "per_kind": 2, "samples": 1}
KINDS = ("SN", "PD", "NS", "GR")


def paper_oscillator() -> ic.ImpactOscillator:
    """The paper's two-degree-of-freedom example."""
    return ic.ImpactOscillator(M=np.eye(2), K=ic.chain_stiffness([1.0, 1.0]), F=[1.0, 0.0],
                               R=0.6, b=0.5, omega=1.0, eta=0.1)


def _clean(obj: Any) -> Any:
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


# -- seeds from the map -------------------------------------------------------------------------
def _edge(kind: str, a: xr.Dataset, c: xr.Dataset, r: int) -> bool:
    """Whether the cell between grid points a and c (same b) is an edge of ``kind`` for root r."""
    if kind == "SN":
        side = c if bool(c.exists) else a
        return bool(a.exists) != bool(c.exists) and bool(side.physical.any())
    if not (bool(a.exists) and bool(c.exists)):
        return False
    ra, rc = a.isel(root=r), c.isel(root=r)
    if kind == "GR":
        ga, gc = float(ra.gap_min), float(rc.gap_min)
        return (math.isfinite(ga) and math.isfinite(gc) and (ga > 0) != (gc > 0)
                and float(ra.impact_velocity) > 0 and float(rc.impact_velocity) > 0)
    if kind == "ZV":
        return (float(ra.impact_velocity) > 0) != (float(rc.impact_velocity) > 0) \
            and (bool(ra.physical) or bool(rc.physical))
    if not (bool(ra.physical) and bool(rc.physical)) or bool(ra.stable) == bool(rc.stable):
        return False
    unstable = rc if not bool(rc.stable) else ra
    mu = complex(unstable.critical_multiplier)
    is_pd = mu.real < 0 and abs(mu.imag) < 1e-9
    is_sn_like = mu.real > 0 and abs(mu.imag) < 1e-9
    return (kind == "PD" and is_pd) or (kind == "NS" and not is_pd and not is_sn_like)


def _covered(curves: list[xr.Dataset], kind: str, N: int, b: float, lo: float, hi: float
             ) -> bool:
    for c in curves:
        if c.attrs["kind"] != kind or (kind != "ZV" and int(c.attrs["N"]) != N):
            continue
        try:
            crossings = curve_crossings(c, "b", b)
        except Exception as exc:  # a failed crossing only means "not covered"
            log.debug("crossing failed: %s", exc)
            continue
        if any(lo - 1e-9 <= x["omega"] <= hi + 1e-9 for x in crossings):
            return True
    return False


def compute_curves(osc: ic.ImpactOscillator, m: xr.Dataset, cfg: dict[str, Any]
                   ) -> tuple[list[xr.Dataset], list[dict[str, Any]]]:
    """Continue every boundary seeded from the map; return the curves and a seed log."""
    box = {"omega": OMEGA_RANGE, "b": B_RANGE}
    omega, bs = m.omega.values, m.b.values
    curves: list[xr.Dataset] = []
    seeds: list[dict[str, Any]] = []
    rows = range(cfg["stride"] // 2, bs.size, cfg["stride"])
    plan = [(int(N), kind) for N in m.N.values for kind in KINDS] + [(int(m.N.values[0]), "ZV")]
    for N, kind in plan:
        mN = m.sel(N=N)
        count = 0
        for j in rows:
            for i in range(omega.size - 1):
                if count >= cfg["per_kind"]:
                    break
                a, c = mN.isel(omega=i, b=j), mN.isel(omega=i + 1, b=j)
                for r in ((0,) if kind == "SN" else (0, 1)):
                    if not _edge(kind, a, c, r):
                        continue
                    b = float(bs[j])
                    if _covered(curves, kind, N, b, omega[i], omega[i + 1]):
                        continue
                    start: dict[str, float] = {"omega": 0.5 * (omega[i] + omega[i + 1]), "b": b}
                    if kind != "SN":
                        da, dc = float(a.delta[r]), float(c.delta[r])
                        start["delta"] = da + 0.5 * math.remainder(dc - da, 2 * math.pi)
                    record = {"N": N, "kind": kind, "seed": start}
                    t0 = time.perf_counter()
                    try:
                        ds = curve(osc, N, kind, start=start, bounds=box, ds_max=0.05)
                    except Exception as exc:  # a failed seed is logged, not fatal
                        record.update(status="failed", error=str(exc))
                        log.warning("seed %s failed: %s", record, exc)
                        seeds.append(record)
                        continue
                    record.update(status="continued", seconds=time.perf_counter() - t0,
                                  points=ds.sizes["point"], end=ds.attrs["end_status"],
                                  codim2=ds.codim2_label.values.tolist())
                    seeds.append(record)
                    curves.append(ds)
                    count += 1
                    log.info("N=%d %s curve %d: %d points, %.1f s", N, kind, count,
                             ds.sizes["point"], record["seconds"])
    return curves, seeds


# -- checks -------------------------------------------------------------------------------------
def _crossing_counts(curves: list[xr.Dataset], m: xr.Dataset
                     ) -> tuple[dict[tuple, int], list[tuple]]:
    """Crossings of every grid row by every curve, counted per (N, kind, root, row, cell).

    Only crossings where the curve is a boundary the map can see are kept: the
    motion physical (for GR: grazing at its highest maximum, ``gap_min`` of the
    other maxima > 0) and, for PD/NS, every other multiplier inside the circle.
    """
    omega, bs = m.omega.values, m.b.values
    counts: dict[tuple, int] = {}
    visible = []
    for c in curves:
        kind = c.attrs["kind"]
        Ns = [int(k) for k in m.N.values] if kind == "ZV" else [int(c.attrs["N"])]
        for j, b in enumerate(bs):
            for cr in curve_crossings(c, "b", float(b)):
                i = int(np.searchsorted(omega, cr["omega"])) - 1
                if not 0 <= i < omega.size - 1:
                    continue
                k = cr["point"]
                pair = slice(k, k + 2)
                if kind in ("PD", "NS") and not bool(c.stable_side[pair].all()):
                    continue
                if kind == "GR" and not (bool((c.gap_min[pair] > 0).all())
                                         and bool((c.impact_velocity[pair] > 0).all())):
                    continue
                root = 0 if kind == "SN" else cr["root"]
                for N in Ns:
                    key = (N, kind, root, j, i)
                    counts[key] = counts.get(key, 0) + 1
                    visible.append((key, {**cr, "N": int(c.attrs["N"])}))
    return counts, visible


def map_edge_check(curves: list[xr.Dataset], m: xr.Dataset) -> dict[str, Any]:
    """A grid cell crossed an odd number of times by a visible boundary must be an edge.

    The quantity of the curve (``exists`` for SN, ``stable`` for PD/NS, the sign of
    ``gap_min`` for GR and of ``impact_velocity`` for ZV, of the curve's root) must
    differ between the two grid points of the cell. Cells crossed twice (a boundary
    turning inside the cell, or two boundaries closer than the grid) are counted apart.
    """
    counts, visible = _crossing_counts(curves, m)
    root_N = {key: cr["N"] for key, cr in visible}
    checked = agree = 0
    failures = []
    for key, count in counts.items():
        if count % 2 == 0:
            continue
        N, kind, root, j, i = key
        lo, hi = m.sel(N=N).isel(omega=i, b=j), m.sel(N=N).isel(omega=i + 1, b=j)
        r = 0 if root >= 0 else 1
        if kind == "SN":
            ok = bool(lo.exists) != bool(hi.exists)
        elif not (bool(lo.exists) and bool(hi.exists)):
            continue  # a fold inside the cell as well: the root is not defined on both sides
        elif kind == "GR":
            ok = float(lo.gap_min[r]) * float(hi.gap_min[r]) < 0
        elif kind == "ZV":  # root labels are those of the curve's N: for another N, either
            ok = any(float(lo.impact_velocity[q]) * float(hi.impact_velocity[q]) < 0
                     for q in ((r,) if root_N[key] == N else (0, 1)))
        else:
            ok = bool(lo.stable[r]) != bool(hi.stable[r])
        checked += 1
        agree += ok
        if not ok:
            failures.append({"N": N, "kind": kind, "root": root, "b": float(m.b.values[j]),
                             "omega_cell": [float(m.omega.values[i]),
                                            float(m.omega.values[i + 1])]})
    return {"cells_crossed_once_checked": checked, "on_an_edge": agree,
            "cells_crossed_twice": sum(1 for v in counts.values() if v % 2 == 0),
            "visible_crossings": len(visible), "failures": failures[:30]}


def _orbit(osc: ic.ImpactOscillator, N: int, root: int) -> ic.PeriodicOrbit | None:
    orbits = [o for o in ic.periodic_orbits(osc, N) if o.root == root]
    return orbits[0] if orbits else None


def _growth(osc: ic.ImpactOscillator, orbit: ic.PeriodicOrbit) -> float:
    impacts = min(max(math.ceil(3.0 / abs(math.log(orbit.spectral_radius))) + 8, 16), 120)
    X = orbit.state.copy()
    X[1] += 1e-7
    X[osc.n] += 1e-7
    res = ic.simulate(osc, X, orbit.delta, float(impacts * orbit.N) + 0.5)
    v = res.impact_velocities - orbit.impact_velocity
    if v.size < 12:
        return math.inf
    return float(np.max(np.abs(v[-4:])) / np.max(np.abs(v[4:8])))


def simulate_sides(osc0: ic.ImpactOscillator, c: xr.Dataset, cr: dict[str, Any]
                   ) -> dict[str, Any]:
    """Simulator on both sides of one curve point (same b, omega -+ eps)."""
    kind, N = c.attrs["kind"], int(c.attrs["N"])
    b, w = cr["b"], cr["omega"]
    out: dict[str, Any] = {"kind": kind, "N": N, "omega": w, "b": b}
    for eps in ((0.004, 0.008, 0.016) if kind == "SN" else (0.001, 0.002, 0.004, 0.008, 0.016)):
        sides = {}
        for sign in (-1, 1):
            osc = osc0.replace(b=b, omega=w + sign * eps)
            sides[sign] = (osc, ic.periodic_orbits(osc, N) if kind == "SN"
                           else _orbit(osc, N, cr["root"]))
        if kind == "SN":
            exist = [s for s in sides if sides[s][1]]
            if len(exist) != 1:
                continue
            osc, orbits = sides[exist[0]]
            stable = [o for o in orbits if o.physical and o.stable]
            if not stable:
                continue
            fold = orbit_at_phase(osc0.replace(b=b, omega=w), N, cr["delta"])
            osc_none = sides[-exist[0]][0]
            res = ic.simulate(osc_none, fold.state, fold.delta, 40.0 * N)
            Tn = 2 * math.pi * N / osc_none.omega
            if res.impact_times.size > 4:  # an N-1 motion: intervals N T and one phase
                steps = np.abs(np.remainder(np.diff(res.impact_phases[-4:]) + math.pi,
                                            2 * math.pi) - math.pi)
                gaps = np.abs(np.diff(res.impact_times[-4:]) / Tn - 1.0)
                settled = bool(steps.max() < 1e-6 and gaps.max() < 1e-6)
                rhythm = {"phase_step": float(steps.max()), "interval_error": float(gaps.max())}
            else:  # the impacts die out: no impacting motion at all
                settled, rhythm = False, {}
            impacts = min(max(math.ceil(3.0 / abs(math.log(stable[0].spectral_radius))) + 8,
                              16), 120)
            decay = _growth(osc, stable[0])
            # the perturbation shrinks as predicted by rho (within a factor 3)
            expected = stable[0].spectral_radius ** (impacts - 9)
            out.update(eps=eps, prediction="stable motion on one side, no N-1 motion on the "
                                           "other",
                       existing_side_decay=decay, existing_side_decay_expected=expected,
                       other_side_impacts=int(res.impact_times.size),
                       other_side_last_impacts=rhythm,
                       confirmed=bool(decay < min(0.9, 3.0 * expected) and not settled))
            return out
        if any(s[1] is None for s in sides.values()):
            continue
        if kind in ("GR", "ZV"):
            phys = {s: sides[s][1].physical for s in sides}
            if phys[-1] == phys[1]:
                continue
            first = {}
            for osc, o in sides.values():
                res = ic.simulate(osc, o.state, o.delta, 1.5 * N)
                first[o.physical] = float(res.impact_times[0] / o.period)
            out.update(eps=eps, prediction="physical on one side only",
                       first_impact_over_T=first,
                       confirmed=bool(abs(first[True] - 1.0) < 1e-9 and first[False] < 0.999))
            return out
        orbits = {s: sides[s][1] for s in sides}
        if not all(o.physical for o in orbits.values()) \
                or orbits[-1].stable == orbits[1].stable \
                or min(abs(o.spectral_radius - 1) for o in orbits.values()) < 0.02:
            continue
        growth = {orbits[s].stable: _growth(sides[s][0], orbits[s]) for s in sides}
        out.update(eps=eps, prediction="stable on one side, unstable on the other",
                   perturbation_growth={"stable_side": growth[True],
                                        "unstable_side": growth[False]},
                   confirmed=bool(growth[True] < 0.2 and growth[False] > 5.0))
        return out
    out.update(confirmed=None, note="no offset up to 0.016 gives a clean two-sided test "
                                    "(another boundary or the fold too close)")
    return out


def simulation_checks(osc: ic.ImpactOscillator, curves: list[xr.Dataset], samples: int
                      ) -> list[dict[str, Any]]:
    """Simulate both sides of up to ``samples`` points per curve (physical, observable)."""
    out = []
    rng = np.random.default_rng(20261122)
    for c in curves:
        kind = c.attrs["kind"]
        good = c.stable_side.values if kind in ("PD", "NS") else c.physical.values
        if kind == "SN":
            good = np.ones(c.sizes["point"], dtype=bool)
        idx = np.flatnonzero(good[1:-1]) + 1
        if idx.size == 0:
            continue
        done = 0
        for k in rng.permutation(idx)[:4 * samples]:
            b = round(float(c.b.values[k]), 3)
            crossings = [x for x in curve_crossings(c, "b", b) if abs(x["point"] - k) <= 1]
            if not crossings:
                continue
            check = simulate_sides(osc, c, crossings[0])
            if check.get("confirmed") is None:
                continue
            out.append(check)
            done += 1
            if done >= samples:
                break
    return out


def closed_form_checks(osc: ic.ImpactOscillator, curves: list[xr.Dataset]) -> dict[str, Any]:
    sn_err = zv_err = res = 0.0
    for c in curves:
        res = max(res, float(c.residual.max()))
        if c.attrs["kind"] == "SN":
            N = int(c.attrs["N"])
            amp = np.array([ic.amplitude_squared(osc.replace(omega=float(w)), N)
                            for w in c.omega.values])
            sn_err = max(sn_err, float(np.max(np.abs(c.b.values ** 2 - amp))))
        if c.attrs["kind"] == "ZV":
            for w, b in zip(c.omega.values, c.b.values, strict=True):
                X = np.linalg.solve(osc.K - w**2 * osc.M + 1j * w * osc.C, osc.F)
                zv_err = max(zv_err, abs(abs(X[0]) - abs(b)))
    return {"sn_closed_form_max_error": sn_err, "zv_linear_response_max_error": zv_err,
            "max_residual": res}


# -- main ---------------------------------------------------------------------------------------
def draw_figures(out: Path, width: float = 7.0) -> Path:
    """Draw ``grazing_boundary.png`` (one panel per N, ``two_parameter_figure``) ``width``
    inches wide from the stored ``map.nc`` and ``curves.nc`` of ``out``."""
    m = ic.load(out / "map.nc")
    tree = ic.load(out / "curves.nc")
    curves = [node.to_dataset() for node in tree.children.values()]
    fig = two_parameter_figure(m, curves, width=width)
    path = out / "grazing_boundary.png"
    fig.savefig(path, dpi=DPI)
    import matplotlib.pyplot as plt

    plt.close(fig)
    log.info("wrote %s", path)
    return path


def main(output_dir: str | os.PathLike = DEFAULT_OUTPUT, quick: bool = False,
         copy_figures: bool = False) -> dict[str, Any]:
    """Run the study; write its files into ``output_dir``; return the summary."""
    cfg = QUICK if quick else FULL
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    osc = paper_oscillator()
    omega = np.linspace(*OMEGA_RANGE, cfg["n_omega"])
    bs = np.linspace(*B_RANGE, cfg["n_b"])
    timings: dict[str, Any] = {"grid": [len(cfg["N"]), omega.size, bs.size],
                               "cpus": os.cpu_count()}

    t0 = time.perf_counter()
    m = stability_map(osc, cfg["N"], omega, bs)
    timings["map_serial_seconds"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    m_pool = stability_map(osc, cfg["N"], omega, bs, executor="process", max_workers=2)
    timings["map_process_pool_2_seconds"] = time.perf_counter() - t0
    xr.testing.assert_identical(m.drop_attrs(), m_pool.drop_attrs())
    # the same grid one motion at a time (orbit_at_phase per root), extrapolated from a sample
    sample = np.random.default_rng(1).integers(0, [omega.size, bs.size], size=(40, 2))
    t0 = time.perf_counter()
    for i, j in sample:
        ic.periodic_orbits(osc.replace(omega=float(omega[i]), b=float(bs[j])), cfg["N"][0])
    per_point = (time.perf_counter() - t0) / len(sample)
    timings["map_one_point_at_a_time_estimated_seconds"] = per_point * m.exists.size

    t0 = time.perf_counter()
    curves, seeds = compute_curves(osc, m, cfg)
    timings["curves_seconds"] = time.perf_counter() - t0
    timings["curves"] = len(curves)
    timings["curve_points"] = int(sum(c.sizes["point"] for c in curves))

    t0 = time.perf_counter()
    edge = map_edge_check(curves, m)
    sims = simulation_checks(osc, curves, cfg["samples"])
    timings["checks_seconds"] = time.perf_counter() - t0

    names = {f"N{c.attrs['N']}_{c.attrs['kind']}_{k}": c for k, c in enumerate(curves)}
    ic.save(names, out / "curves.nc")
    ic.save(m, out / "map.nc")
    draw_figures(out)
    summary_curves = [{"name": name, "kind": c.attrs["kind"], "N": int(c.attrs["N"]),
                       "points": c.sizes["point"], "end": c.attrs["end_status"],
                       "physical_points": int(c.physical.sum()),
                       "stable_side_points": int(c.stable_side.sum()),
                       "omega_range": [float(c.omega.min()), float(c.omega.max())],
                       "b_range": [float(c.b.min()), float(c.b.max())],
                       "codim2": [{"label": str(lab), "omega": float(w), "b": float(b),
                                   "status": str(st)} for lab, w, b, st in zip(
                                       c.codim2_label.values, c.codim2_omega.values,
                                       c.codim2_b.values, c.codim2_status.values, strict=True)]}
                      for name, c in names.items()]
    checks = {"closed_form": closed_form_checks(osc, curves), "map_edges": edge,
              "simulation": sims,
              "simulation_confirmed": sum(bool(s["confirmed"]) for s in sims),
              "simulation_checked": len(sims), "seeds": seeds, "curves": summary_curves,
              "regions": {int(N): {"stable_physical_fraction":
                                   float((m.sel(N=N).n_stable > 0).mean()),
                                   "exists_fraction": float(m.sel(N=N).exists.mean())}
                          for N in m.N.values}}
    _write_json(out / "checks.json", checks)
    _write_json(out / "timings.json", timings)
    if copy_figures:
        FIGURES_DIR.mkdir(exist_ok=True)
        shutil.copy(out / "grazing_boundary.png", FIGURES_DIR / "grazing_boundary.png")
    log.info("map %.2f s serial, %.2f s on 2 processes; %d curves in %.1f s",
             timings["map_serial_seconds"], timings["map_process_pool_2_seconds"], len(curves),
             timings["curves_seconds"])
    return {"checks": checks, "timings": timings}


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT))
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--copy-figures", action="store_true")
    parser.add_argument("--figures-only", action="store_true",
                        help="only redraw the figure from the output's map.nc and curves.nc")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    if args.figures_only:
        draw_figures(Path(args.output))
        if args.copy_figures:
            FIGURES_DIR.mkdir(exist_ok=True)
            shutil.copy(Path(args.output) / "grazing_boundary.png",
                        FIGURES_DIR / "grazing_boundary.png")
    else:
        main(args.output, quick=args.quick, copy_figures=args.copy_figures)
