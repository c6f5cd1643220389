"""Two-parameter curves of N-p motions followed by shooting (``ic.curve`` from an N-p branch or
motion; ``multi_impact_curve`` is its earlier name).

Witnesses: the closed-form N-1 curves (the same motion followed by shooting as a 1-1
motion must give the same PD curve), the one-parameter pitchforks located in omega on
branches at other clearances (the BP curve must pass through them), and the numpy
contact search of the simulator's module (the GR curve grazes).

Curves of N-p motions that turn: a fold of the curve in its second parameter is passed.

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
from impactcont.analysis.curves import multi_impact_curve, multi_impact_curve_crossings
from impactcont.errors import ParameterError
from impactcont.model.parameters import model_parameter
from impactcont.model.stops import Stops
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import initial_unknowns, orbit_from_unknowns
from impactcont.orbit.symmetry import half_map
from impactcont.simulate.contact import flight_clearances

K2 = [[1.0, -1.0], [-1.0, 2.0]]


def paper(**kw) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, eta=0.1, **kw)


def mirrored(omega: float, b: float) -> ic.ImpactOscillator:
    return paper(b=b, omega=omega, stops=Stops(mirror=True))


def symmetric_branch(omega: float, b: float, bounds) -> ic.xr.Dataset:
    res = ic.simulate(mirrored(omega, b), np.zeros(4), 0.0, 150.0)
    o = ic.multi_impact_orbit(mirrored(omega, b), 1, 2, res)
    return ic.multi_impact_continuation(o, "omega", bounds, both_directions=True, ds_max=0.02)


def _bp_omegas(ds) -> list[float]:
    return [float(w) for lab, w in zip(ds["special_label"].values, ds["special_omega"].values,
                                       strict=True) if lab == "BP"]


def test_pd_curve_by_shooting_is_the_closed_form_curve():
    osc = paper(b=0.0, omega=1.75)
    box = {"omega": (1.0, 3.0), "b": (-0.2, 0.3)}
    closed = ic.curve(None, None, "PD", start=ic.continuation(osc, 1, "omega", (1.6, 1.9),
                                                              detect=("PD",)), bounds=box)
    physical = next(q for q in ic.periodic_orbits(osc, 1) if q.physical)
    start = ic.multi_impact_orbit(osc, 1, 1, physical)
    branch = ic.multi_impact_continuation(start, "omega", (1.6, 1.9), detect=("PD",),
                                          both_directions=True)
    cv = multi_impact_curve(branch, "PD", 0, parameter="b", bounds=box)
    assert cv.attrs["curve_kind"] == "PD" and cv.attrs["parameters"] == "omega,b"
    assert cv.sizes["point"] > 10
    assert cv["b"].values.min() == pytest.approx(-0.2) and cv["b"].values.max() == \
        pytest.approx(0.3)
    for omega, b in zip(cv["omega"].values, cv["b"].values, strict=True):
        crossings = ic.curve_crossings(closed, "b", float(b))
        assert min(abs(c["omega"] - omega) for c in crossings) < 1e-9
    assert np.all(np.min(np.abs(cv["multipliers"].values + 1.0), axis=1) < 1e-8)


def _switches(ds) -> list[tuple[float, float, bool]]:
    """Where ``stable_side`` changes along a curve: (omega, b, the value after)."""
    side = ds["stable_side"].values.astype(bool)
    return [(float(ds["omega"].values[i]), float(ds["b"].values[i]), bool(side[i + 1]))
            for i in np.flatnonzero(side[1:] != side[:-1])]


def test_a_shooting_curve_says_where_a_stable_motion_changes_as_the_closed_form():
    """``stable_side`` of the PD curve followed by shooting (the 1-1 motion) against the
    closed form's PD curve of the same motion, over a box where it changes twice inside
    the physical motions (omega 2.96, b -0.70: a second multiplier leaves the unit circle;
    omega 1.27, b 0.42) and once at the box's edge: the same changes, each between
    neighbouring points of both curves (steps about 0.01 apart, so within 0.03)."""
    osc = paper(b=0.0, omega=1.75)
    box = {"omega": (0.5, 4.0), "b": (-1.5, 1.0)}
    closed = ic.curve(None, None, "PD", start=ic.continuation(osc, 1, "omega", (1.6, 1.9),
                                                              detect=("PD",)), bounds=box)
    physical = next(q for q in ic.periodic_orbits(osc, 1) if q.physical)
    branch = ic.multi_impact_continuation(ic.multi_impact_orbit(osc, 1, 1, physical), "omega",
                                          (1.6, 1.9), detect=("PD",), both_directions=True)
    shooting = ic.curve(None, None, "PD", start=branch, parameters=("omega", "b"), bounds=box)
    assert shooting["stable_side"].attrs["long_name"] == "stable on one side"
    expected, found = _switches(closed), _switches(shooting)
    assert len(expected) == len(found) == 3, (expected, found)
    for (w0, b0, after0), (w1, b1, after1) in zip(expected, found, strict=True):
        assert after0 == after1 and abs(w0 - w1) < 0.03 and abs(b0 - b1) < 0.03


@pytest.fixture(scope="module")
def bp_curve():
    branch = symmetric_branch(1.6, 0.5, (0.9, 1.7))
    assert len(_bp_omegas(branch)) == 2
    return multi_impact_curve(branch, "BP", 1, parameter="b",
                              bounds={"omega": (0.5, 2.5), "b": (0.2, 1.0)}, ds_max=0.02)


@pytest.mark.parametrize(("b", "omega", "bounds"), [(0.3, 2.0, (0.9, 2.1)),
                                                    (0.8, 0.9, (0.85, 1.25))])
def test_bp_curve_passes_through_the_pitchforks_at_other_clearances(bp_curve, b, omega,
                                                                    bounds):
    """One curve through both pitchforks of b = 0.5 (it turns at a fold in b near 0.98)
    crosses b = 0.3 and 0.8 exactly at the pitchforks located in omega there."""
    assert bp_curve.attrs["curve_kind"] == "BP"
    crossings = sorted(c["omega"] for c in multi_impact_curve_crossings(bp_curve, "b", b))
    forks = sorted(_bp_omegas(symmetric_branch(omega, b, bounds)))
    assert len(crossings) == len(forks) == 2
    np.testing.assert_allclose(crossings, forks, rtol=0, atol=1e-9)


def test_every_bp_curve_point_has_a_half_map_multiplier_minus_one(bp_curve):
    for i in range(0, bp_curve.sizes["point"], 5):
        osc = ic.dataset.oscillator_from_dataset(bp_curve, i)
        assert osc.stops.mirror and osc.stops.b_low == osc.b
        # the stored motion as it is (Newton on the full system is singular at a BP)
        u = initial_unknowns({"delta": float(bp_curve["delta_k"].values[i, 0]),
                              "flight_times": bp_curve["flight_time_k"].values[i],
                              "states": bp_curve["state_k"].values[i],
                              "pattern": bp_curve.attrs["pattern"]}, osc, 1, 2)
        motion = orbit_from_unknowns(Flow(osc), 1, 2, u, pattern=bp_curve.attrs["pattern"])
        assert motion.residual < 1e-9
        mu = np.linalg.eigvals(half_map(motion))
        assert np.min(np.abs(mu + 1.0)) < 1e-7


def test_gr_curve_grazes():
    branch = symmetric_branch(1.6, 0.5, (0.7, 1.7))
    assert "GR" in branch["special_label"].values.tolist()
    cv = multi_impact_curve(branch, "GR", 0, parameter="F0",
                            bounds={"omega": (0.5, 1.5), "F0": (0.9, 1.1)}, ds_max=0.02)
    assert cv.sizes["point"] > 3 and cv["F0"].values.min() == pytest.approx(0.9)
    for i in (0, cv.sizes["point"] // 2, -1):
        osc = ic.dataset.oscillator_from_dataset(cv, i)
        assert pytest.approx(float(cv["F0"].values[i])) == osc.F0
        flow = Flow(osc)
        gaps = [min(flight_clearances(flow, cv["state_k"].values[i, k],
                                      float(cv["delta_k"].values[i, k]),
                                      float(cv["flight_time_k"].values[i, k]))[::2])
                for k in range(2)]
        assert abs(min(gaps)) < 1e-8


def test_bad_curve_requests():
    branch = symmetric_branch(1.6, 0.5, (1.2, 1.7))
    box = {"omega": (0.5, 2.5), "b": (0.3, 0.8)}
    with pytest.raises(ParameterError, match="kind must be one of"):
        multi_impact_curve(branch, "XX", bounds=box)
    with pytest.raises(ParameterError, match="bounds must be given"):
        multi_impact_curve(branch, "BP")
    with pytest.raises(ParameterError, match="bounds must be a mapping"):
        multi_impact_curve(branch, "BP", bounds={"omega": (0.5, 2.5)})
    with pytest.raises(ParameterError, match="two different parameters"):
        multi_impact_curve(branch, "BP", parameter="omega", bounds={"omega": (0.5, 2.5)})
    with pytest.raises(ParameterError, match="out of range"):
        multi_impact_curve(branch, "PD", bounds=box)
    with pytest.raises(ParameterError, match="must contain the start"):
        multi_impact_curve(branch, "BP", bounds={"omega": (0.5, 2.5), "b": (0.6, 0.8)})
    with pytest.raises(TypeError, match="branch must be"):
        multi_impact_curve({"omega": 1.0}, "BP", bounds=box)
    with pytest.raises(ParameterError, match="curve dataset of multi_impact_curve"):
        multi_impact_curve_crossings(branch, "b", 0.5)


def test_crossing_in_the_first_parameter_returns_the_start(bp_curve):
    start = float(bp_curve.attrs["born_at_value"])
    crossings = multi_impact_curve_crossings(bp_curve, "omega", start)
    assert min(abs(c["b"] - 0.5) for c in crossings) < 1e-9
    with pytest.raises(ParameterError, match="one of the curve's parameters"):
        multi_impact_curve_crossings(bp_curve, "R", 0.5)


def _closed_form():
    """The study's closed-form module under a name of its own (not ``closed_form``, which
    other studies' modules also have)."""
    path = Path(__file__).resolve().parents[2] / "studies" / "impact_damper" / "closed_form.py"
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
    assert message.count("parameter bound reached: b = 1") == 2, message
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


# -- a curve whose first parameter (the branch's) is an element ---------------------------
@pytest.fixture(scope="module")
def paper_motion():
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                              eta=0.1, R=0.6, b=0.6, omega=1.0)
    return next(o for o in ic.periodic_orbits(osc, 1) if o.physical)


@pytest.mark.parametrize("p1", ["k2", "M[1,2]"])
def test_a_pd_curve_in_an_element_and_omega_is_stored_and_exact(paper_motion, p1, tmp_path):
    lo, hi = (0.2, 5.0) if p1 == "k2" else (-0.4, 0.4)
    branch = ic.multi_impact_continuation(paper_motion, parameter=p1, bounds=(lo, hi))
    labels = [str(v) for v in branch.special_label.values]
    if "PD" not in labels:
        pytest.skip(f"no PD on the {p1} branch: {labels}")
    curve = ic.multi_impact_curve(branch, kind="PD", parameter="omega",
                                  bounds={p1: (lo, hi), "omega": (0.5, 3.0)}, max_points=12)
    assert p1 in curve and curve[p1].dims == ("point",)
    assert np.all(np.isfinite(curve[p1].values))
    osc = paper_motion.oscillator
    for k in range(0, curve.sizes["point"], 4):  # the witness: the closed form's G there
        at = model_parameter(osc, p1).at(osc, float(curve[p1].values[k]))
        at = at.replace(omega=float(curve.omega.values[k]))
        orbits = ic.periodic_orbits(at, 1)
        near = min(orbits, key=lambda o: abs(o.delta - float(curve.delta.values[k])))
        assert np.min(np.abs(np.asarray(near.multipliers) + 1.0)) < 1e-6
    path = tmp_path / "curve.nc"
    ic.save(curve, path)
    back = ic.load(path)
    np.testing.assert_array_equal(back[p1].values, curve[p1].values)
