"""The published single-harmonic closed form of the VI-NES (``source_formula.py``: Weidemann,
Bergman, Vakakis & Krack 2025, as written in their code) against this study's exact
closed form (``closed_form.py``) and the package (``multi_impact_orbit``).

What is compared (the source's quantities, read off each exact motion the same way):

- ``xi``: the primary's fundamental harmonic ``|Q|`` over the clearance ``b`` (the exact
  motion's first Fourier coefficient, Gauss-Legendre on each flight of the linear flow);
- ``theta``: the ball's amplitude over ``b`` (half its travel from wall to wall: a triangle
  wave in the symmetric motion, exactly);
- ``phase``: ``arg Q`` against the force ``cos(r t)``.

Two checks:

1. **The study's machine** (``mu = 0.05, zeta = 0.02, b = 5, R = 0.6``) over a grid of
   ``omega``: every motion of the source's formula against the exact symmetric root
   nearest in ``xi`` and the package's motion seeded by that root.
2. **The source's limit**: the formula is a single-harmonic, small-mass-ratio one, exact
   only as ``mu -> 0`` with ``zeta``, ``r - 1`` of order ``mu`` and ``b zeta`` fixed. Along
   ``mu = 0.05 s, zeta = 0.02 s, b = 5 / s, r = 1 + (r0 - 1) s`` the difference must
   vanish like ``s`` (first order).

Run ``PYTHONPATH=. python studies/vi_nes/source_compare.py [--copy-figures]`` (writes
``output/source_compare.json`` and ``output/source_compare.png``, prints a summary).
"""

from __future__ import annotations

import importlib.util
import itertools
import json
import logging
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

import impactcont as ic

HERE = Path(__file__).resolve().parent
LOG = logging.getLogger("vi_nes.source_compare")

MU, ZETA, B, R = 0.05, 0.02, 5.0, 0.6
OMEGAS = tuple(float(x) for x in np.round(np.arange(0.80, 1.30001, 0.025), 4))
LIMIT_R0 = (0.9, 0.95, 1.0, 1.05, 1.1, 1.2)
LIMIT_S = (1.0, 0.5, 0.25, 0.125)


def load(name: str, path: Path):
    """Import a study file by path (registered under ``name``: dataclasses need it)."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


sf = load("vi_nes_sources_formula", HERE / "source_formula.py")
cf = load("vi_nes_sources_closed_form", HERE / "closed_form.py")

_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(64)


def _flow(t: np.ndarray, zeta: float) -> np.ndarray:
    """``(h, h')(t) = Phi(t) (h, h')(0)`` for ``h'' + 2 zeta h' + h = 0``, shape (n, 2, 2)."""
    wd = math.sqrt(1.0 - zeta * zeta)
    e, c, s = np.exp(-zeta * t), np.cos(wd * t), np.sin(wd * t)
    return e[:, None, None] * np.stack([np.stack([c + zeta / wd * s, s / wd], -1),
                                        np.stack([-s / wd, c - zeta / wd * s], -1)], -2)


def fundamental(r: float, zeta: float, delta: float, flights, states) -> complex:
    """The primary's first harmonic ``Q`` (``x1 ~ Re(Q e^{irt})`` under the force
    ``cos(rt)``) of a periodic motion given by the forcing phase ``delta`` at its first
    impact, its flight times and the state ``(x1, x2, x1', x2')`` after each impact: the
    primary's linear flow ``x1 = Re(A e^{i(rt + delta)}) + h(t)`` on each flight, integrated
    by Gauss-Legendre (the flights are smooth; 64 nodes: rounding)."""
    A = 1.0 / complex(1.0 - r * r, 2.0 * zeta * r)
    P = A * complex(math.cos(delta), math.sin(delta))
    T = float(np.sum(flights))
    c1, t0 = 0j, 0.0
    for tau, X in zip(flights, states, strict=True):
        w0 = P * complex(math.cos(r * t0), math.sin(r * t0))
        h = np.array([X[0] - w0.real, X[2] - (1j * r * w0).real])
        t = t0 + 0.5 * tau * (_NODES + 1.0)
        x1 = (P * np.exp(1j * r * t)).real + (_flow(t - t0, zeta) @ h)[:, 0]
        c1 += 0.5 * tau * np.sum(_WEIGHTS * x1 * np.exp(-1j * r * t))
        t0 += tau
    if abs(t0 - T) > 1e-12 * T:
        raise ValueError("flights do not add up to the period")
    return 2.0 / T * c1 * complex(math.cos(delta), -math.sin(delta))


def ball_amplitude(flight: float, state: np.ndarray) -> float:
    """Half the ball's travel on a flight at constant speed (no gravity)."""
    return 0.5 * abs(state[3]) * flight


def quantities(r: float, zeta: float, b: float, delta: float, flights, states
               ) -> dict[str, float]:
    Q = fundamental(r, zeta, delta, flights, states)
    return {"xi": abs(Q) / b, "theta": ball_amplitude(flights[0], states[0]) / b,
            "phase": math.atan2(Q.imag, Q.real)}


def _exact(m) -> dict[str, float]:
    p = m.p
    return quantities(p.r, p.zeta, p.b, m.delta, m.flight_times,
                      [m.state_upper, m.state_lower])


def _package(m) -> dict[str, float]:
    p = m.p
    osc = ic.ImpactOscillator(M=np.diag([1.0, p.mu]), K=[[1.0, 0.0], [0.0, 0.0]],
                              F=[1.0, 0.0], R=p.R, b=p.b, omega=p.r, eta=p.zeta,
                              stops=ic.Stops(mass=2, relative_to=1, mirror=True))
    orbit = ic.multi_impact_orbit(osc, 1, 2, {"delta": m.delta,
                                              "flight_times": list(m.flight_times),
                                              "states": [m.state_upper, m.state_lower],
                                              "pattern": "UL"})
    k = orbit.pattern.index("U")
    order = [k, 1 - k]
    q = quantities(p.r, p.zeta, p.b, float(orbit.phases[k]), orbit.flight_times[order],
                   orbit.states[order])
    q["error_estimate"] = float(orbit.error_estimate)
    return q


def _differences(src, other: dict[str, float]) -> dict[str, float]:
    return {"xi": abs(other["xi"] - src.xi) / src.xi,
            "theta": abs(other["theta"] - abs(src.theta)) / abs(src.theta),
            "phase": abs(math.remainder(other["phase"] - math.atan2(src.Q.imag, src.Q.real),
                                        2 * math.pi))}


def compare(r: float, mu: float = MU, zeta: float = ZETA, b: float = B, R_: float = R,
            package: bool = True, sign: int = 1) -> list[dict[str, Any]]:
    """Each motion of the source's formula at this point, with the exact symmetric root
    nearest in ``xi`` (and the package's motion seeded by it). ``sign = -1``: the other
    root of (W2), which the source discards."""
    p = cf.VINES(r=r, mu=mu, zeta=zeta, b=b, b_low=b, R=R_, R_low=R_)
    exact = [m for m in cf.ul_motions(p, scan=60) if abs(m.t1 - 0.5 * p.T) < 1e-9 * p.T]
    rows = []
    for src in sf.motions(r, mu, zeta, b, R_, sign=sign):
        if not exact:
            rows.append({"r": r, "xi_source": src.xi, "exact": None})
            continue
        qs = [_exact(m) for m in exact]
        i = int(np.argmin([abs(q["xi"] - src.xi) for q in qs]))
        m, q = exact[i], qs[i]
        row = {"r": r, "xi_source": src.xi, "theta_source": src.theta,
               "phase_source": math.atan2(src.Q.imag, src.Q.real),
               "exact": q, "physical": bool(m.physical), "stable": bool(m.stable),
               "exact_index": i,
               "source_vs_exact": _differences(src, q),
               "other_root_xi": [qq["xi"] for j, qq in enumerate(qs) if j != i]}
        if package:
            pk = _package(m)
            row["package"] = pk
            row["source_vs_package"] = _differences(src, pk)
            row["package_vs_exact"] = max(abs(pk["xi"] - q["xi"]) / q["xi"],
                                          abs(pk["theta"] - q["theta"]) / q["theta"],
                                          abs(math.remainder(pk["phase"] - q["phase"],
                                                             2 * math.pi)))
        rows.append(row)
    return rows


def limit_row(r0: float, s: float) -> dict[str, Any]:
    """Source against exact at ``mu = 0.05 s, zeta = 0.02 s, b = 5/s, r = 1 + (r0-1) s``."""
    rows = compare(1.0 + (r0 - 1.0) * s, MU * s, ZETA * s, B / s, R, package=False)
    if len(rows) != 1 or rows[0]["exact"] is None:
        raise ArithmeticError(f"expected one matched motion at r0 = {r0}, s = {s}: {rows}")
    return {"r0": r0, "s": s, **rows[0]["source_vs_exact"]}


def main() -> dict[str, Any]:
    grid = [row for r in OMEGAS for row in compare(r)]
    matched = [g for g in grid if g["exact"] is not None]
    other = [row for r in OMEGAS for row in compare(r, package=False, sign=-1)]
    other_matched = [g for g in other if g["exact"] is not None]
    limit = [limit_row(r0, s) for r0 in LIMIT_R0 for s in LIMIT_S]
    worst = {k: max(g["source_vs_exact"][k] for g in matched) for k in ("xi", "theta", "phase")}
    worst_pkg = {k: max(g["source_vs_package"][k] for g in matched)
                 for k in ("xi", "theta", "phase")}
    ratios = []
    for r0 in LIMIT_R0:
        rows = [x for x in limit if x["r0"] == r0]
        for a, c in itertools.pairwise(rows):
            ratios += [c[k] / a[k] for k in ("xi", "theta", "phase")]
    out = {"machine": {"mu": MU, "zeta": ZETA, "b": B, "R": R}, "omegas": list(OMEGAS),
           "grid": grid, "other_sign": other, "limit": limit,
           "summary": {"source_motions": len(grid), "matched": len(matched),
                       "worst_source_vs_exact": worst, "worst_source_vs_package": worst_pkg,
                       "worst_package_vs_exact": max(g["package_vs_exact"] for g in matched),
                       "other_sign": {
                           "motions": len(other), "matched": len(other_matched),
                           "worst_xi": max(g["source_vs_exact"]["xi"] for g in other_matched),
                           "worst_phase": max(g["source_vs_exact"]["phase"]
                                              for g in other_matched),
                           "worst_theta_physical": max(
                               [g["source_vs_exact"]["theta"] for g in other_matched
                                if g["physical"]], default=None),
                           "negative_theta": sum(g["theta_source"] < 0 for g in other_matched),
                           "negative_theta_physical": sum(g["theta_source"] < 0 and g["physical"]
                                                          for g in other_matched)},
                       "halving_ratio_range": [min(ratios), max(ratios)],
                       "limit_error_over_s_max": max(max(x["xi"], x["theta"], x["phase"])
                                                     / x["s"] for x in limit)}}
    (HERE / "output").mkdir(exist_ok=True)
    (HERE / "output" / "source_compare.json").write_text(json.dumps(out, indent=1))
    return out


def figure(out: dict[str, Any], path: Path | None = None, width: float = 7.0,
           omegas: tuple[float, ...] = OMEGAS, points: int = 201) -> Any:
    """Left: ``xi`` against omega, the source's formula (its root of (W2): solid; the
    other: dashed) over the exact symmetric roots (filled: stable and physical). Right: the
    difference along the source's limit against ``s`` (slope 1: first order). Side by side
    from 5 in, stacked below; one legend under both. Saved to ``path`` if given; returns
    the figure. ``omegas``: where the left panel's exact motions are computed (the study's
    grid by default), ``points``: of the source's curves between the first and the last of
    them; the right panel draws the ``r0`` and ``s`` of ``out["limit"]``."""
    import matplotlib.ticker

    from impactcont.plots.series import (
        Series,
        figure_legend,
        fit_labels,
        panel_figure,
        series_plot,
    )

    fig, (ax, bx) = panel_figure(2, width, extra_height=1.3)
    series = []
    dense = np.linspace(omegas[0], omegas[-1], points)
    for sign, style, label in ((1, "-", "source (W1-W7)"),
                               (-1, "--", "source, other root of (W2)")):
        pts = np.array([(r, m.xi) for r in dense for m in sf.motions(float(r), MU, ZETA, B, R,
                                                                     sign=sign)])
        series.append(Series(*pts.T, label, color="C0", linestyle=style, linewidth=1.0))
    good, bad = [], []
    for r in omegas:
        p = cf.VINES(r=r, mu=MU, zeta=ZETA, b=B, b_low=B, R=R, R_low=R)
        for m in cf.ul_motions(p, scan=60):
            if abs(m.t1 - 0.5 * p.T) < 1e-9 * p.T:
                (good if m.physical and m.stable else bad).append((r, _exact(m)["xi"]))
    for pts, label, filled in ((bad, "exact closed form", False),
                               (good, "exact closed form, stable and physical", True)):
        if pts:
            series.append(Series(*np.array(pts).T, label, color="k", linestyle="none",
                                 marker="o", markersize=4, filled=filled))
    series_plot(ax, series, xlabel=r"$\omega/\omega_n$",
                ylabel=r"$\xi = |Q_1| / b$ (fundamental of $x_1$)",
                title="Symmetric motions")
    limit = []
    for i, r0 in enumerate(sorted({x["r0"] for x in out["limit"]})):
        rows = [x for x in out["limit"] if x["r0"] == r0]
        limit.append(Series([x["s"] for x in rows], [max(x["xi"], x["theta"]) for x in rows],
                            f"$r_0 = {r0:g}$", color=f"C{i + 1}", marker="o", markersize=3))
    s_ = np.array(sorted({x["s"] for x in out["limit"]}, reverse=True))
    limit.append(Series(s_, 0.02 * s_, "slope 1", color="k", linestyle=":"))
    series_plot(bx, limit, xlabel=r"$s$", ylabel=r"max relative difference of $\xi$, $\theta$",
                xscale="log", yscale="log",
                title=r"Along the source's limit: $\mu = 0.05 s$, $b = 5/s$, "
                      r"$\omega = 1 + (r_0 - 1) s$")
    bx.set_xticks(s_, [f"{x:g}" for x in s_])
    bx.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    figure_legend(fig)
    fig.suptitle(rf"Symmetric vibro-impact NES, $\mu = {MU:g}$, $\zeta = {ZETA:g}$, "
                 rf"$b = {B:g}$, $R = {R:g}$: the source's formula against the exact motions",
                 fontsize="medium")
    fit_labels(fig)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig


if __name__ == "__main__":
    import argparse
    import shutil

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--copy-figures", action="store_true",
                        help="also refresh figures/source_compare.png (tracked)")
    parser.add_argument("--figures-only", action="store_true",
                        help="only redraw the figure from output/source_compare.json")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    if args.figures_only:
        result = json.loads((HERE / "output" / "source_compare.json").read_text())
    else:
        result = main()
    LOG.info(json.dumps(result["summary"], indent=1))
    png = HERE / "output" / "source_compare.png"
    figure(result, png)
    if args.copy_figures:
        shutil.copy(png, HERE / "figures" / "source_compare.png")
