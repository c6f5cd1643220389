"""Extreme and stiff cases: impactcont's closed form against the 50-digit reference.

Every case is evaluated by ``impactcont.periodic_orbits`` (warnings recorded)
and by the mpmath reference of ``tests/reference_mp.py`` (written from the
equations, no impactcont code). For each root it reports the relative errors of
the state, the impact phase, G, the multipliers and gap_min, the 1-norm
condition number of ``I - D U W(T) U^-1`` (reference), and what impactcont said
(warnings, errors). The fast cases are also tests (``tests/integration/test_extreme.py``);
this study adds the slow ones and the table. Run::

    .venv/bin/python studies/extreme_cases/run.py [--output DIR] [--quick]

Writes ``cases.json`` and ``table.md`` to the output directory (default
``studies/extreme_cases/output``).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import json
import logging
import math
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import impactcont as ic

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "tests"))
import reference_mp as ref  # noqa: E402

log = logging.getLogger("extreme_cases")


def paper(**params: Any) -> ic.ImpactOscillator:
    base = {"R": 0.6, "b": 0.0, "omega": 1.2, "eta": 0.1}
    base.update(params)
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], **base)


def chain(n: int, *, masses: Any = None, springs: Any = None, **params: Any
          ) -> ic.ImpactOscillator:
    F = np.zeros(n)
    F[0] = 1.0
    base = {"R": 0.6, "b": 0.0, "omega": 1.2, "eta": 0.05, "F": F}
    base.update(params)
    return ic.ImpactOscillator.chain(masses=np.ones(n) if masses is None else masses,
                                     springs=np.ones(n) if springs is None else springs, **base)


def grazing_omega() -> float:
    """A grazing point (gap_min = 0, eq. 16) of the paper's N = 1 branch at b = 0."""
    ds = ic.continuation(paper(), N=1, parameter="omega", bounds=(0.5, 3.0), detect=("GR",),
                         components="start")
    labels = [str(v) for v in ds.special_label.values]
    return float(ds.special_omega.values[labels.index("GR")])


def cases(quick: bool) -> list[tuple[str, str, Callable[[], ic.ImpactOscillator], int,
                                     dict | str | None]]:
    """(group, label, oscillator factory, N, reference options or ``"elastic"``)."""
    out: list[tuple[str, str, Callable[[], ic.ImpactOscillator], int, dict | str | None]] = []
    for ratio in (1e2, 1e4, 1e6, 1e8):
        for eta in (0.0, 0.01):
            gap = eta > 0 or ratio <= 1e2
            out.append(("stiffness", f"springs 1, {math.sqrt(ratio):g}, {ratio:g}; eta={eta}",
                        lambda ratio=ratio, eta=eta: chain(
                            3, springs=[1, math.sqrt(ratio), ratio], eta=eta, omega=1.2,
                            R=0.6), 1, {"gap": gap}))
    out.append(("stiffness", "n=20 springs logspace(0, 8); eta=0.01",
                lambda: chain(20, springs=np.logspace(0, 8, 20), eta=0.01), 1,
                {"gap": False, "multipliers": False}))
    for n in ((50,) if quick else (50, 100)):
        out.append(("size", f"n={n} uniform chain, eta=0.05", lambda n=n: chain(n), 1,
                    {"gap": n <= 50, "multipliers": False}))
    out.append(("size", "n=200 uniform chain, eta=0.05 (no reference: periodicity residual)",
                lambda: chain(200), 1, None))
    for eta in (0.0, 1e-6, 0.1, 1.0, 10.0, 1e3):
        out.append(("damping", f"n=10 chain, eta={eta:g}", lambda eta=eta: chain(10, eta=eta),
                    1, {"gap": True, "multipliers": True}))
    for R in (0.0, 1e-8, 1.0):
        for eta in (0.0, 0.1):
            if R == 1.0 and eta == 0.0:
                continue  # elastic and undamped: the reference's eq. (12) is singular; below
            out.append(("restitution", f"paper, R={R:g}, eta={eta}",
                        lambda R=R, eta=eta: paper(R=R, eta=eta), 1, {}))
    # elastic impacts without damping: eq. (12) is singular for every omega (the
    # reference's closed form with it), the motions are not. Witnesses: the published
    # formula for one mass, the exact flow's periodicity, det G = R^2 = 1
    for omega, b, N in ((2.8, 0.05, 1), (1.5, -0.2, 1), (3.3, -0.1, 3)):
        out.append(("elastic undamped", f"one mass, omega={omega}, b={b}, N={N}",
                    lambda omega=omega, b=b: ic.ImpactOscillator(
                        M=[[1.0]], K=[[1.0]], F=[1.0], R=1.0, b=b, omega=omega), N, "elastic"))
    for b in (0.0, 0.3):
        out.append(("elastic undamped", f"paper, R=1, eta=0, b={b}",
                    lambda b=b: paper(R=1.0, eta=0.0, b=b), 1, "elastic"))
    for n in (3, 10, 50):
        out.append(("elastic undamped", f"n={n} chain, R=1, eta=0, omega=1.9",
                    lambda n=n: chain(n, R=1.0, eta=0.0, omega=1.9, b=0.05), 1, "elastic"))
    r = math.sqrt(ic.amplitude_squared(paper(omega=1.0), 1))
    for b, name in ((-1e6, "-1e6"), (-10.0, "-10"), (-0.999 * r, "-0.999 r"), (0.0, "0"),
                    (0.5 * r, "0.5 r"), (r * (1 - 1e-6), "r (1 - 1e-6)"),
                    (r * (1 - 1e-10), "r (1 - 1e-10)"), (r * (1 - 1e-14), "r (1 - 1e-14)"),
                    (r, "r (fold, c^2+s^2 = b^2 in floats)")):
        out.append(("gap", f"paper omega=1, b = {name}", lambda b=b: paper(omega=1.0, b=b), 1,
                    {"gap": False}))
    w = paper().modes.natural_frequencies
    for i, wi in enumerate(w):
        for eta in (0.0, 0.1):
            for rel in (0.0, 1e-14, 1e-10, 1e-6, 1e-3):
                out.append(("resonance", f"mode {i + 1}, eta={eta}, omega = w(1+{rel:g})",
                            lambda wi=wi, eta=eta, rel=rel: paper(eta=eta,
                                                                  omega=float(wi * (1 + rel))),
                            1, {"gap": False}))
    for N in (1, 5, 10, 20, 50):
        for eta in (0.0, 0.1):
            out.append(("periods", f"paper, N={N}, eta={eta}",
                        lambda N=N, eta=eta: paper(eta=eta, omega=1.2 * N + 0.01), N,
                        {"gap": N <= 10, "multipliers": N <= 20}))
    osc = paper(omega=1.0)
    Z = np.linalg.solve(osc.K - osc.M + 1j * osc.C, osc.F)
    top = abs(Z[0])
    for gap in (1e-2, 1e-4, 1e-7, 1e-10, 1e-12, 1e-15):
        out.append(("impact velocity", f"paper omega=1, b = top (1 - {gap:g})",
                    lambda gap=gap: paper(omega=1.0, b=top * (1 - gap)), 1, {"gap": False}))
    w_gr = grazing_omega()
    for d in (-1e-4, -1e-8, -1e-12, 0.0, 1e-12, 1e-8, 1e-4):
        out.append(("grazing", f"paper b=0, omega = omega_GR (1 {d:+g})",
                    lambda d=d: paper(omega=w_gr * (1 + d)), 1, {"multipliers": False}))
    for m in ([1, 1e2], [1e2, 1], [1, 1e4], [1e4, 1], [1, 1e6], [1e6, 1], [1e-6, 1]):
        out.append(("mass ratio", f"masses {m}", lambda m=m: chain(2, masses=m), 1, {}))
    return out


def _errors(orbits: list[ic.PeriodicOrbit], truth: dict[str, Any], N: int) -> list[dict]:
    rows = []
    for o, r in zip(orbits, truth["orbits"], strict=False):
        e = {"root": o.root,
             "delta": abs(math.remainder(o.delta - r["delta"], 2 * math.pi)),
             "state": float(np.abs(o.state - r["state"]).max() / np.abs(r["state"]).max()),
             "G": float(np.abs(o.G - r["G"]).max() / np.abs(r["G"]).max()),
             "h2": o.impact_velocity}
        if "multipliers" in r:
            e["multipliers"] = ref.matched_error(o.multipliers, r["multipliers"]) / max(
                1.0, float(np.abs(np.asarray(r["multipliers"])).max()))
        if "gap_min" in r:
            e["gap_min"] = (0.0 if math.isinf(r["gap_min"]) and math.isinf(o.gap_min)
                            else abs(o.gap_min - r["gap_min"]))
        rows.append(e)
    return rows


def _budd_dux(omega: float, b: float, N: int) -> list[float]:
    """Impact velocities of the elastic single mass, ``V = -(b -+ gamma)(1 - cos T)/sin T``
    with ``gamma = 1/(1 - omega^2)``, ``T = 2 pi N / omega`` (Budd & Dux)."""
    gamma = 1.0 / (1.0 - omega**2)
    T = 2.0 * math.pi * N / omega
    return sorted(-(b - sign * gamma) * (1.0 - math.cos(T)) / math.sin(T) for sign in (1, -1))


def _elastic_witness(osc: ic.ImpactOscillator, orbits: list[ic.PeriodicOrbit]
                     ) -> dict[str, Any]:
    """Errors against the witnesses that hold for elastic undamped impacts."""
    flow = ic.Flow(osc)
    out: dict[str, Any] = {"residual": 0.0, "det_G": 0.0}
    for o in orbits:
        X = flow.state(o.period, o.state, o.delta)[0]
        X[osc.n] *= -osc.R
        out["residual"] = max(out["residual"],
                              float(np.abs(X - o.state).max() / np.abs(o.state).max()))
        out["det_G"] = max(out["det_G"], abs(abs(np.prod(o.multipliers)) - 1.0))
    if osc.n == 1:
        published = _budd_dux(osc.omega, osc.b, orbits[0].N)
        found = sorted(o.impact_velocity for o in orbits)
        out["budd_dux"] = max(abs(f - p) / abs(p) for f, p in zip(found, published, strict=True))
    return out


def run_case(group: str, label: str, make: Callable[[], ic.ImpactOscillator], N: int,
             options: dict | str | None) -> dict[str, Any]:
    row: dict[str, Any] = {"group": group, "case": label, "N": N}
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        try:
            osc = make()
            orbits = ic.periodic_orbits(osc, N)
            row["outcome"] = f"{len(orbits)} roots"
        except ic.ImpactcontError as exc:
            orbits, osc = [], None
            row["outcome"] = f"{type(exc).__name__}: {str(exc)[:90]}"
    row["time_s"] = time.perf_counter() - t0
    row["warnings"] = sorted({f"{w.category.__name__}" for w in record})
    row["warning_text"] = [str(w.message)[:160] for w in record][:3]
    if not orbits:
        return row
    if options == "elastic":
        row.update(_elastic_witness(osc, orbits))
        return row
    if options is None:  # no reference: periodicity residual of the exact flow
        flow = ic.Flow(osc)
        res = 0.0
        for o in orbits:
            X = flow.state(o.period, o.state, o.delta)[0]
            X[osc.n] *= -osc.R
            res = max(res, float(np.abs(X - o.state).max() / np.abs(o.state).max()))
        row["residual"] = res
        return row
    t1 = time.perf_counter()
    system = ref.MPSystem(osc.M, osc.K, osc.F, osc.R, osc.b, *osc.rayleigh)
    truth = ref.to_float(ref.closed_form(system, osc.omega, N, **options))
    row["reference_time_s"] = time.perf_counter() - t1
    row["cond"] = truth["cond"]
    row["errors"] = _errors(orbits, truth, N)
    if len(truth["orbits"]) != len(orbits):
        row["outcome"] += f" (reference: {len(truth['orbits'])})"
    return row


def _fmt(x: float | None) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return f"{x:.1e}"


def write_table(rows: list[dict[str, Any]], path: Path) -> None:
    lines = ["| group | case | outcome | warnings | cond (ref) | max rel. error state / "
             "delta / G / multipliers / gap_min (worst root) |", "|---|---|---|---|---|---|"]
    for r in rows:
        errs = r.get("errors", [])
        if errs:
            worst = {k: max(e.get(k, math.nan) for e in errs)
                     for k in ("state", "delta", "G", "multipliers", "gap_min")}
            err = " / ".join(_fmt(worst[k]) for k in ("state", "delta", "G", "multipliers",
                                                      "gap_min"))
        elif "det_G" in r:
            err = (f"periodicity residual {r['residual']:.1e}, abs(det G) - 1: {r['det_G']:.1e}"
                   + (f", impact velocity vs Budd & Dux {r['budd_dux']:.1e}"
                      if "budd_dux" in r else ""))
        elif "residual" in r:
            err = f"periodicity residual {r['residual']:.1e}"
        else:
            err = "-"
        lines.append(f"| {r['group']} | {r['case']} | {r['outcome']} | "
                     f"{', '.join(r['warnings']) or '-'} | {_fmt(r.get('cond'))} | {err} |")
    path.write_text("\n".join(lines) + "\n")


def main(output_dir: str | Path = HERE / "output", quick: bool = False,
         groups: list[str] | None = None) -> list[dict[str, Any]]:
    """Run every case (of `groups`, default all); write ``cases.json`` and ``table.md``."""
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for group, label, make, N, options in cases(quick):
        if groups and group not in groups:
            continue
        row = run_case(group, label, make, N, options)
        log.info("%s | %s | %s | %s | %.2f s", group, label, row["outcome"], row["warnings"],
                 row["time_s"])
        rows.append(row)
    (out / "cases.json").write_text(json.dumps(rows, indent=1, default=float))
    write_table(rows, out / "table.md")
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=str(HERE / "output"))
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--group", action="append", help="run only this group (repeatable)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.output, quick=args.quick, groups=args.group)
