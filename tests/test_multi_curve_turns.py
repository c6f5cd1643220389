"""Curves of N-p motions that turn: a fold of the curve in its second parameter is passed.

The impact damper (a free ball of mass ratio 0.2 in a cavity of half-length ``b`` of a
primary mass on a spring; ``studies/impact_damper``) has two Neimark-Sacker points on
its symmetric two-impact branch in omega at ``b = 1``. Followed in ``(omega, b)`` they
are one NS curve: the boundary of an island of unstable motion whose lowest clearance
(the fold of the curve in ``b``) is at ``b = 0.51668``.

Witness: the study's closed form of the symmetric motion and its half-map (derived
independently of the package, ``studies/impact_damper/closed_form.py``): the island's
bottom is the clearance below which no omega has a multiplier outside the unit circle
(bisected on the closed form), and at any clearance above it the island's two edges are
where the closed form's spectral radius is 1.
"""

from __future__ import annotations

import importlib.util
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

import impactcont as ic
from impactcont.analysis.multi_curves import multi_impact_curve, multi_impact_curve_crossings
from impactcont.model.stops import Stops


def _closed_form():
    """The study's closed-form module under a name of its own (not ``closed_form``, which
    other studies' modules also have)."""
    path = Path(__file__).resolve().parents[1] / "studies" / "impact_damper" / "closed_form.py"
    spec = importlib.util.spec_from_file_location("impact_damper_closed_form_turns", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look the module up by name
    spec.loader.exec_module(module)
    return module


symmetric_motions = _closed_form().symmetric_motions
MU, E, ZETA = 0.2, 0.8, 0.05  # the study's mass ratio, restitution, damping ratio
NEAR_BOTTOM = (2.36, 2.43)  # omega around the island's bottom


def damper(omega: float, b: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.diag([1.0, MU]), K=[[1.0, 0.0], [0.0, 0.0]],
                               F=[1.0, 0.0], R=E, b=b, omega=omega, eta=ZETA,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def closed_form_radius(omega: float, b: float) -> float:
    """Spectral radius of G of the closed form's symmetric motion on the NS curve (of its
    two roots, the one with the smaller radius: the other has a multiplier near 50)."""
    motions = [m for m in symmetric_motions(omega, 2.0 * b, MU, E, ZETA) if m.physical]
    return min(float(np.max(np.abs(m.multipliers))) for m in motions)


def island_peak(b: float) -> tuple[float, float]:
    """``max_omega rho - 1`` near the island's bottom at clearance ``b``, and its omega."""
    found = minimize_scalar(lambda w: -closed_form_radius(w, b), bounds=NEAR_BOTTOM,
                            method="bounded", options={"xatol": 1e-10})
    return -float(found.fun) - 1.0, float(found.x)


@pytest.fixture(scope="module")
def island_bottom() -> float:
    """The lowest clearance of the island in the closed form (0.5166777)."""
    return brentq(lambda b: island_peak(b)[0], 0.5165, 0.5170, xtol=1e-12)


@pytest.fixture(scope="module")
def ns_curve():
    """The NS curve from the lower NS point of the branch at b = 1, both directions."""
    omega = 2.0
    T2 = math.pi / omega
    m = min(symmetric_motions(omega, 2.0, MU, E, ZETA),
            key=lambda m: float(np.max(np.abs(m.multipliers))))
    seed = ic.multi_impact_orbit(damper(omega, 1.0), 1, 2,
                                 {"delta": m.delta, "flight_times": [T2, T2],
                                  "states": [m.state, -m.state], "pattern": "UL"})
    branch = ic.multi_impact_continuation(seed, "omega", (1.8, 2.2), both_directions=True,
                                          ds_max=0.02, progress=False)
    ns = [float(w) for lab, w in zip(branch["special_label"].values,
                                     branch["special_omega"].values, strict=True)
          if lab == "NS"]
    assert len(ns) == 2
    curve = multi_impact_curve(branch, "NS", 0, parameter="b",
                               bounds={"omega": (1.5, 2.6), "b": (0.4, 1.0)},
                               ds_max=0.02, max_points=250, progress=False)
    return ns, curve


def test_island_bottom_of_the_closed_form(island_bottom):
    assert 0.5165 < island_bottom < 0.5170  # the study's bracket (README)
    assert island_peak(island_bottom - 1e-4)[0] < 0.0 < island_peak(island_bottom + 1e-4)[0]


def test_ns_curve_goes_round_the_bottom_of_the_island(ns_curve, island_bottom):
    ns, curve = ns_curve
    # both directions end on b = 1, at the two NS points of the branch (not a stall)
    message = json.loads(curve.attrs["options"])["message"]
    assert message.count("parameter bound reached: lam = 1") == 2, message
    b, omega = curve["b"].values, curve["omega"].values
    assert abs(b[0] - 1.0) < 1e-12 and abs(b[-1] - 1.0) < 1e-12
    assert sorted([omega[0], omega[-1]]) == pytest.approx(ns, abs=1e-7)
    # it reaches the island's bottom (to the spacing of its points) and never goes below it
    assert island_bottom - 1e-9 < b.min() < island_bottom + 1e-4


@pytest.mark.parametrize("above", [3e-4, 3e-3])
def test_both_edges_of_the_island_near_its_bottom(ns_curve, island_bottom, above):
    _, curve = ns_curve
    b = island_bottom + above
    crossings = multi_impact_curve_crossings(curve, "b", b)
    near = sorted(c["omega"] for c in crossings if NEAR_BOTTOM[0] < c["omega"] < NEAR_BOTTOM[1])
    assert len(near) == 2
    top = island_peak(b)[1]
    edges = [brentq(lambda w: closed_form_radius(w, b) - 1.0, lo, hi, xtol=1e-13)
             for lo, hi in ((NEAR_BOTTOM[0], top), (top, NEAR_BOTTOM[1]))]
    assert near == pytest.approx(edges, abs=1e-8)
