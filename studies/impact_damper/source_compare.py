"""The published single-harmonic closed form of a free mass in a cavity of a forced primary
(Weidemann, Bergman, Vakakis & Krack 2025, as written in their code; implemented in
``studies/vi_nes/source_formula.py``, where the source and its equations (W1-W7) are
cited) against this study's exact closed form (``closed_form.py``) and the package.

The impact damper is the same machine as the VI-NES of that source (a primary, a free
mass of ratio ``mu`` between two walls, Newton's restitution, the two-body law); the
formula is exact only for a light mass (its limit is checked in ``studies/vi_nes``).
Here, at this study's heavier particle (``mu = 0.2``):

1. **The study's grid** (``omega`` = 0.6, 0.7, ..., 3.0; ``d`` = 1, 2, 4): every motion of
   the source's formula against the exact symmetric root nearest in ``xi`` (the
   primary's fundamental harmonic over ``b = d/2``) and the package's motion seeded by it;
   ``theta`` (the particle's amplitude over ``b``) and the phase of the fundamental.
2. **Its order in the mass ratio** at four ``(omega, d)`` of the study, ``mu`` halved from
   0.2 to 0.0125 (``zeta`` fixed): off the linear resonance the particle's amplitude
   ``theta`` is the formula's first-order quantity (error ~ ``mu``), the primary's
   fundamental and phase its second-order ones (the particle's effect on the primary is
   itself ``O(mu)``; error ~ ``mu^2``).

Run ``PYTHONPATH=. python studies/impact_damper/source_compare.py`` (writes
``output/source_compare.json``, prints a summary).
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
LOG = logging.getLogger("impact_damper.source_compare")

MU, E, ZETA = 0.2, 0.8, 0.05
CLEARANCES = (1.0, 2.0, 4.0)
OMEGAS = tuple(float(x) for x in np.round(np.arange(0.6, 3.0001, 0.1), 4))
ORDER_POINTS = ((0.7, 2.0), (1.2, 4.0), (1.5, 2.0), (2.0, 1.0))
ORDER_MU = (0.2, 0.1, 0.05, 0.025, 0.0125)


def _load(name: str, path: Path):
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look the module up by name
    spec.loader.exec_module(module)
    return module


# the comparison helpers (fundamental harmonic, particle amplitude) and the source's formula
sc = _load("vi_nes_sources_compare", HERE.parent / "vi_nes" / "source_compare.py")
sf = sc.sf
cfd = _load("impact_damper_sources_closed_form", HERE / "closed_form.py")


def _exact(m) -> dict[str, float]:
    T2 = math.pi / m.r
    return sc.quantities(m.r, m.zeta, 0.5 * m.d, m.delta, [T2, T2], [m.state, -m.state])


def _package(m) -> dict[str, float]:
    osc = ic.ImpactOscillator(M=np.diag([1.0, m.mu]), K=[[1.0, 0.0], [0.0, 0.0]],
                              F=[1.0, 0.0], R=m.e, b=0.5 * m.d, omega=m.r, eta=m.zeta,
                              stops=ic.Stops(mass=2, relative_to=1, mirror=True))
    T2 = math.pi / m.r
    orbit = ic.multi_impact_orbit(osc, 1, 2, {"delta": m.delta, "flight_times": [T2, T2],
                                              "states": [m.state, -m.state],
                                              "pattern": "UL"})
    k = orbit.pattern.index("U")
    order = [k, 1 - k]
    q = sc.quantities(m.r, m.zeta, 0.5 * m.d, float(orbit.phases[k]),
                      orbit.flight_times[order], orbit.states[order])
    q["error_estimate"] = float(orbit.error_estimate)
    return q


def compare(r: float, d: float, mu: float = MU, package: bool = True, sign: int = 1
            ) -> list[dict[str, Any]]:
    """Each motion of the source's formula at ``(r, d)``, with the exact symmetric root
    nearest in ``xi`` (and the package's motion seeded by it). ``sign = -1``: the other
    root of (W2), which the source discards."""
    exact = cfd.symmetric_motions(r, d, mu, E, ZETA)
    rows = []
    for src in sf.motions(r, mu, ZETA, 0.5 * d, E, sign=sign):
        if not exact:
            rows.append({"r": r, "d": d, "xi_source": src.xi, "exact": None})
            continue
        qs = [_exact(m) for m in exact]
        i = int(np.argmin([abs(q["xi"] - src.xi) for q in qs]))
        m, q = exact[i], qs[i]
        row = {"r": r, "d": d, "mu": mu, "xi_source": src.xi, "theta_source": src.theta,
               "phase_source": math.atan2(src.Q.imag, src.Q.real), "exact": q,
               "physical": bool(m.physical), "stable": bool(m.stable),
               "source_vs_exact": sc._differences(src, q)}
        if package:
            pk = _package(m)
            row["package"] = pk
            row["source_vs_package"] = sc._differences(src, pk)
            row["package_vs_exact"] = max(abs(pk["xi"] - q["xi"]) / q["xi"],
                                          abs(pk["theta"] - q["theta"]) / q["theta"],
                                          abs(math.remainder(pk["phase"] - q["phase"],
                                                             2 * math.pi)))
        rows.append(row)
    return rows


def order_rows(r: float, d: float) -> list[dict[str, Any]]:
    """Source against exact at ``(r, d)`` for each ``mu`` of ``ORDER_MU``."""
    out = []
    for mu in ORDER_MU:
        rows = compare(r, d, mu, package=False)
        if len(rows) != 1 or rows[0]["exact"] is None:
            raise ArithmeticError(f"expected one matched motion at {r, d, mu}: {rows}")
        out.append({"r": r, "d": d, "mu": mu, **rows[0]["source_vs_exact"]})
    return out


def main() -> dict[str, Any]:
    grid = [row for d in CLEARANCES for r in OMEGAS for row in compare(r, d)]
    matched = [g for g in grid if g["exact"] is not None]
    other = [row for d in CLEARANCES for r in OMEGAS
             for row in compare(r, d, package=False, sign=-1)]
    other_matched = [g for g in other if g["exact"] is not None]
    exact_points = [(r, d, [(m.physical, m.stable) for m in cfd.symmetric_motions(r, d, MU, E,
                                                                                ZETA)])
                    for d in CLEARANCES for r in OMEGAS]
    with_source = {(g["r"], g["d"]) for g in grid}
    missed = [(r, d, flags) for r, d, flags in exact_points
              if flags and (r, d) not in with_source]
    order = [row for r, d in ORDER_POINTS for row in order_rows(r, d)]

    def worst(rows, key="source_vs_exact"):
        return {k: max(g[key][k] for g in rows) for k in ("xi", "theta", "phase")}

    ratios: dict[str, list[float]] = {"xi": [], "theta": [], "phase": []}
    for r, d in ORDER_POINTS:
        rows = [x for x in order if x["r"] == r and x["d"] == d]
        for a, c in itertools.pairwise(rows):
            for k in ratios:
                ratios[k].append(c[k] / a[k])
    stable = [g for g in matched if g["physical"] and g["stable"]]
    out = {"machine": {"mu": MU, "e": E, "zeta": ZETA, "clearances": list(CLEARANCES)},
           "omegas": list(OMEGAS), "grid": grid, "other_sign": other, "order": order,
           "summary": {"source_motions": len(grid), "matched": len(matched),
                       "per_d": {str(d): worst([g for g in matched if g["d"] == d])
                                 for d in CLEARANCES},
                       "stable_physical": len(stable),
                       "worst_stable_physical": worst(stable) if stable else None,
                       "worst_source_vs_package": worst(matched, "source_vs_package"),
                       "worst_package_vs_exact": max(g["package_vs_exact"] for g in matched),
                       "exact_points": sum(bool(f) for _, _, f in exact_points),
                       "exact_without_source": [[r, d] for r, d, _ in missed],
                       "exact_without_source_stable": sum(any(p and s for p, s in f)
                                                          for _, _, f in missed),
                       "other_sign": {
                           "motions": len(other), "matched": len(other_matched),
                           "covers_missed": sum((g["r"], g["d"]) in {(r, d) for r, d, _ in
                                                                     missed}
                                                for g in other_matched),
                           "worst_xi": max(g["source_vs_exact"]["xi"] for g in other_matched),
                           "worst_phase": max(g["source_vs_exact"]["phase"]
                                              for g in other_matched)},
                       "halving_ratio_range": {k: [min(v), max(v)] for k, v in ratios.items()}}}
    (HERE / "output").mkdir(exist_ok=True)
    (HERE / "output" / "source_compare.json").write_text(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    LOG.info(json.dumps(main()["summary"], indent=1))
