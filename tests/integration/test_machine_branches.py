"""Branches and curves of the machines of issue 21: an impact damper (a free ball in a cavity,
a symmetric clearance between masses), an impact pair on two springs (an asymmetric
clearance between masses) and a pair under a constant force ``F_static``.

Independent witnesses: central finite differences of the shooting residual on freshly built
oscillators (``dF/dlam``), Newton on a freshly built oscillator at every branch point, the
multipliers of the Poincare map (or half-map) from central differences of the event-driven
simulator at each located PD, SN and BP, and the exact scaling of a linear system without a
constant force (``x, b, F -> s x, s b, s F``), which puts the pitchfork in ``b`` at the
reciprocal of the one in ``F0``.
"""

from __future__ import annotations

import logging
import math
import warnings

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.branch import multi_impact_continuation
from impactcont.analysis.curves import multi_impact_curve
from impactcont.analysis.switching import grazing_split, grazing_switch, special_orbit
from impactcont.model.stops import Stops
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import multi_impact_orbit
from impactcont.orbit.periodic import IllConditionedWarning
from impactcont.orbit.stop_geometry import stop_geometry
from impactcont.orbit.symmetry import half_map
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem

MU = 0.2  # mass ratio ball / primary
PAIR_K = [[2.0, -1.0], [-1.0, 2.0]]


# ------------------------------------------------------------------------------------------
# The machines, built afresh from their data (the witnesses never reuse a continued model)
# ------------------------------------------------------------------------------------------
def damper(omega=1.5, b=1.0, R=0.8, F0=1.0, m2=MU) -> ic.ImpactOscillator:
    """Primary mass on a spring, a free ball of mass m2 in a cavity s = x2 - x1 in [-b, b]."""
    return ic.ImpactOscillator(M=np.diag([1.0, m2]), K=[[1.0, 0.0], [0.0, 0.0]],
                               F=[F0, 0.0], R=R, b=b, omega=omega, eta=0.05,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def pair(omega=1.6, b_low=0.4, K11=2.0) -> ic.ImpactOscillator:
    """Two masses on springs (K positive definite) with a clearance -b_low < x2 - x1 < b."""
    K = np.array(PAIR_K)
    K[0, 0] = K11
    return ic.ImpactOscillator(M=np.eye(2), K=K, F=[1.0, 0.0], R=0.7, b=0.5, omega=omega,
                               eta=0.05, stops=Stops(mass=2, relative_to=1, b_low=b_low,
                                                     R_low=0.6))


def loaded(omega=1.6, F0=1.0) -> ic.ImpactOscillator:
    """The pair with one stop, under a constant force F_static (a preload)."""
    return ic.ImpactOscillator(M=np.eye(2), K=PAIR_K, F=[F0, 0.0], F_static=[0.3, -0.2],
                               R=0.7, b=0.5, omega=omega, eta=0.05,
                               stops=Stops(mass=2, relative_to=1))


def settled(osc, N, p, X0, periods):
    return multi_impact_orbit(osc, N, p, ic.simulate(osc, np.asarray(X0, float), 0.0, periods))


@pytest.fixture(scope="module")
def damper_orbit():
    return settled(damper(), 1, 2, [0.0, 0.0, 0.0, 1.0], 150.0)


@pytest.fixture(scope="module")
def pair_orbit():
    return settled(pair(), 1, 1, [0.0, 0.0, 0.0, 0.5], 200.0)


@pytest.fixture(scope="module")
def loaded_orbit():
    return settled(loaded(), 1, 1, [0.0, 0.0, 0.0, 0.5], 200.0)


# ------------------------------------------------------------------------------------------
# Witnesses
# ------------------------------------------------------------------------------------------
def _specials(ds, label):
    return [k for k, lab in enumerate(ds["special_label"].values) if lab == label]


def _simulated_map(orbit, impacts, h=1e-6):
    """``d(impact 0 -> impact `impacts`)/d[z, theta]`` by central differences of the simulator.

    ``z`` is the state without the pivot position ``x_j``, which the section
    ``n . x = c_0`` gives (a clearance between masses: ``x2 = x1 + c``)."""
    osc = orbit.oscillator
    geo = stop_geometry(osc, orbit.pattern)
    j, normal = geo.pivot, geo.normal
    X0, theta0 = orbit.states[0], float(orbit.phases[0])
    rest = np.delete(np.arange(2 * osc.n), j)
    m = rest.size + 1
    ref = theta0 + osc.omega * float(np.sum(orbit.flight_times[:impacts]))
    out = np.empty((m, m))
    for c in range(m):
        ends = []
        for sign in (1.0, -1.0):
            X, th = X0.copy(), theta0
            if c < m - 1:
                X[rest[c]] += sign * h
                X[j] += (geo.positions[0] - normal @ X[:osc.n]) / normal[j]
            else:
                th += sign * h
            res = ic.simulate(osc, X, th, 10.0 * orbit.N, max_impacts=impacts)
            assert res.impact_stops[-1] == orbit.pattern[impacts % orbit.p]
            t = ref + math.remainder(float(res.impact_phases[-1]) - ref, 2 * math.pi)
            ends.append(np.append(res.impact_states[-1][rest], t))
        out[:, c] = (ends[0] - ends[1]) / (2 * h)
    return out


def _simulated_multipliers(orbit, half=False):
    """Eigenvalues of G (or of the half-map ``H = S G_{h-1}..G_0``) from the simulator."""
    if not half:
        return np.linalg.eigvals(_simulated_map(orbit, orbit.p))
    A = _simulated_map(orbit, orbit.p // 2)
    return np.linalg.eigvals(np.append(-np.ones(A.shape[0] - 1), 1.0)[:, None] * A)


def _special_guess(ds, k):
    """The motion of special point k of a branch dataset as a Newton guess."""
    return {"delta": float(ds["special_delta_k"].values[k, 0]),
            "flight_times": ds["special_flight_time_k"].values[k],
            "states": ds["special_state_k"].values[k], "pattern": str(ds.attrs["pattern"])}


def _solve_quietly(osc, N, p, guess):
    """Newton at a fold or pitchfork, where the full shooting Jacobian is singular (it warns
    that the motion is known only to the size of the error it reports)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IllConditionedWarning)
        return multi_impact_orbit(osc, N, p, guess)


def _resolve_every_point(ds, build, names, N, p):
    """Each branch point re-solved by Newton on an oscillator built afresh from its data."""
    worst = 0.0
    for i in range(ds.sizes["point"]):
        osc = build(**{key: float(ds[name].values[i]) for key, name in names.items()})
        guess = {"delta": float(ds["delta_k"].values[i, 0]),
                 "flight_times": ds["flight_time_k"].values[i],
                 "states": ds["state_k"].values[i], "pattern": str(ds.attrs["pattern"])}
        fresh = multi_impact_orbit(osc, N, p, guess)
        worst = max(worst, float(np.max(np.abs(fresh.states - ds["state_k"].values[i]))))
        assert bool(ds["physical"].values[i]) == fresh.physical
    return worst


# ------------------------------------------------------------------------------------------
# The flow's arrays and the exact derivatives
# ------------------------------------------------------------------------------------------
def test_static_arrays_are_built_once():
    for osc in (loaded(), damper()):
        flow = Flow(osc)
        first = flow.static_arrays()
        assert flow.static_arrays() is first
        np.testing.assert_array_equal(first[0], flow.u.T @ osc.F_static)


@pytest.mark.parametrize("machine, names", [
    ("damper_orbit", ("omega", "b", "R", "gap", "F0", "m2")),
    ("pair_orbit", ("omega", "b_low", "R_low", "K[1,2]")),
    ("loaded_orbit", ("omega", "b", "R", "F[2]", "K[2,2]")),
])
def test_dparam_matches_differences_on_fresh_oscillators(machine, names, request):
    """dF/dlam (exact for omega and the stops on the stop coordinate n . x with the full
    impact matrices D_k; the fallback for the rest) against central differences of the
    residual of oscillators built with lam +- h, off the solution."""
    orbit = request.getfixturevalue(machine)
    u = orbit.unknowns + 1e-3 * np.sin(np.arange(orbit.unknowns.size))
    for name in names:
        problem = MultiImpactBranchProblem(orbit.oscillator, orbit.N, orbit.p, name,
                                           pattern=orbit.pattern)
        lam = problem.param.value(orbit.oscillator)
        h = 1e-5 * max(1.0, abs(lam))
        sides = [MultiImpactBranchProblem(problem.param.at(orbit.oscillator, v), orbit.N,
                                          orbit.p, name, pattern=orbit.pattern).residual(u, v)
                 for v in (lam + h, lam - h)]
        fd = (sides[0] - sides[1]) / (2 * h)
        # central differences: error ~ h^2 f''' ~ 1e-10 of the data
        assert np.max(np.abs(problem.dparam(u, lam) - fd)) < 1e-8 * max(1.0, np.abs(fd).max()), \
            name


# ------------------------------------------------------------------------------------------
# The impact damper: symmetric UL motions, BP and NS, the pitchfork curve
# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def damper_branch(damper_orbit):
    return multi_impact_continuation(damper_orbit, "omega", (1.2, 1.95), progress=False,
                                     both_directions=True, ds_max=0.05)


def test_impact_damper_branch_in_omega(damper_branch):
    ds = damper_branch
    assert '"symmetric": true' in ds.attrs["options"]
    assert ds.sizes["point"] < 60
    bp, ns = _specials(ds, "BP"), _specials(ds, "NS")
    assert len(bp) == 1 and len(ns) == 1
    assert all(ds["special_status"].values[k] == "located" for k in bp + ns)
    # the NS point: a complex pair on the unit circle
    mu = ds["special_multipliers"].values[ns[0]]
    assert np.min(np.abs(np.abs(mu[np.abs(mu.imag) > 1e-3]) - 1.0)) < 1e-7
    assert _resolve_every_point(ds, damper, {"omega": "omega"}, 1, 2) < 1e-8


def test_impact_damper_pitchfork_witnessed_by_the_simulator(damper_branch):
    ds = damper_branch
    k = _specials(ds, "BP")[0]
    omega = float(ds["special_omega"].values[k])
    guess = {"delta": float(ds["special_delta_k"].values[k, 0]),
             "flight_times": ds["special_flight_time_k"].values[k],
             "states": ds["special_state_k"].values[k], "pattern": "UL"}
    orbit = _solve_quietly(damper(omega=omega), 1, 2, guess)
    assert np.min(np.abs(np.linalg.eigvals(half_map(orbit)) + 1.0)) < 1e-8
    # the simulator's half-map has the multiplier -1, its full map +1
    assert np.min(np.abs(_simulated_multipliers(orbit, half=True) + 1.0)) < 1e-5
    assert np.min(np.abs(_simulated_multipliers(orbit) - 1.0)) < 1e-5


def test_impact_damper_scaling_puts_the_pitchfork_in_b_at_one_over_the_one_in_f0(
        damper_orbit):
    """Without a constant force the system is linear between impacts and the stops scale
    with the motion: (x, b, F) -> (s x, s b, s F) maps motions to motions, so at F0 = 1 the
    pitchfork in b sits at 1 / (the pitchfork in F0 at b = 1). 'gap' of mirrored stops is
    b, and the mass ratio m2 is an element parameter (finite-difference fallback)."""
    found = {}
    for name, bounds in (("b", (0.5, 1.5)), ("F0", (0.6, 1.6)), ("gap", (0.5, 1.5)),
                         ("m2", (0.1, 0.3))):
        ds = multi_impact_continuation(damper_orbit, name, bounds, progress=False,
                                       both_directions=True, ds_max=0.1)
        bp = _specials(ds, "BP")
        assert len(bp) == 1 and ds["special_status"].values[bp[0]] == "located", name
        found[name] = float(ds[f"special_{name}"].values[bp[0]])
        if name in ("b", "m2"):
            assert _resolve_every_point(ds, damper, {name: name}, 1, 2) < 1e-8
        if name == "m2":  # the mass ratio's pitchfork, witnessed by the simulator
            orbit = _solve_quietly(damper(m2=found[name]), 1, 2, _special_guess(ds, bp[0]))
            assert np.min(np.abs(_simulated_multipliers(orbit, half=True) + 1.0)) < 1e-5
    assert found["b"] * found["F0"] == pytest.approx(1.0, abs=1e-8)
    assert found["gap"] == pytest.approx(found["b"], abs=1e-10)


def test_impact_damper_pitchfork_curve_in_omega_and_b(damper_branch):
    curve = multi_impact_curve(damper_branch, "BP", 0, parameter="b",
                               bounds={"omega": (1.0, 2.5), "b": (0.6, 1.6)}, max_points=8,
                               progress=False)
    assert curve.sizes["point"] >= 8
    b = curve["b"].values
    assert b.max() - b.min() > 0.2
    for i in range(0, curve.sizes["point"], 3):
        # the full shooting Jacobian is singular at the pitchfork (to rounding, which may
        # refuse the solve there): solved 1e-9 off it in omega, where the half map's
        # multiplier is -1 to about 1e-9
        osc = damper(omega=float(curve["omega"].values[i]) * (1.0 + 1e-9), b=float(b[i]))
        guess = {"delta": float(curve["delta_k"].values[i, 0]),
                 "flight_times": curve["flight_time_k"].values[i],
                 "states": curve["state_k"].values[i], "pattern": "UL"}
        orbit = _solve_quietly(osc, 1, 2, guess)
        assert np.min(np.abs(np.linalg.eigvals(half_map(orbit)) + 1.0)) < 1e-6
    assert np.min(np.abs(_simulated_multipliers(orbit, half=True) + 1.0)) < 1e-5


# ------------------------------------------------------------------------------------------
# The impact pair (p = 1 on the lower stop) and the loaded pair
# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def pair_branch(pair_orbit):
    with pytest.warns(RuntimeWarning, match="stopped at max_points=60"):  # kept short
        return multi_impact_continuation(pair_orbit, "omega", (1.0, 2.9), progress=False,
                                         both_directions=True, max_points=60)


def test_impact_pair_branch_in_omega(pair_branch):
    ds = pair_branch
    labels = set(ds["special_label"].values.tolist())
    assert {"SN", "PD", "GR", "ZV"} <= labels
    for label in ("SN", "PD", "GR", "ZV"):
        k = _specials(ds, label)[0]
        assert ds["special_status"].values[k] == "located", label
    zv = _specials(ds, "ZV")[0]
    assert abs(ds["special_impact_velocity"].values[zv]) < 1e-8
    gr = _specials(ds, "GR")[0]
    assert abs(ds["special_gap_min"].values[gr]) < 1e-8
    assert _resolve_every_point(ds, pair, {"omega": "omega"}, 1, 1) < 1e-8


@pytest.fixture(scope="module")
def loaded_branch(loaded_orbit):
    with pytest.warns(RuntimeWarning, match="stopped at max_points=60"):  # kept short
        return multi_impact_continuation(loaded_orbit, "omega", (0.8, 3.0), progress=False,
                                         both_directions=True, max_points=60)


@pytest.mark.parametrize("label, target", [("PD", -1.0), ("SN", 1.0)])
def test_loaded_pair_pd_and_sn_witnessed_by_the_simulator(loaded_branch, label, target):
    """The physical PD and SN of the loaded pair in omega: the multiplier of G of the motion
    re-solved there, and of the simulator's Poincare map by central differences."""
    ds = loaded_branch
    k = next(k for k in _specials(ds, label) if ds["special_impact_velocity"].values[k] > 0
             and ds["special_gap_min"].values[k] > 0)
    orbit = _solve_quietly(loaded(omega=float(ds["special_omega"].values[k])), 1, 1,
                           _special_guess(ds, k))
    assert orbit.physical
    assert np.min(np.abs(orbit.multipliers - target)) < 1e-6
    assert np.min(np.abs(_simulated_multipliers(orbit) - target)) < 1e-5
    assert _resolve_every_point(ds, loaded, {"omega": "omega"}, 1, 1) < 1e-8


def test_impact_pair_lower_stop_and_element_branches(pair_orbit):
    """b_low moves the lower stop only; K[1,1] is an element (finite-difference fallback)."""
    ds = multi_impact_continuation(pair_orbit, "b_low", (0.1, 1.0), progress=False,
                                   both_directions=True)
    pd = _specials(ds, "PD")
    assert len(pd) == 1
    assert _resolve_every_point(ds, pair, {"b_low": "b_low"}, 1, 1) < 1e-8
    orbit = _solve_quietly(pair(b_low=float(ds["special_b_low"].values[pd[0]])), 1, 1,
                           _special_guess(ds, pd[0]))
    assert np.min(np.abs(orbit.multipliers + 1.0)) < 1e-6
    ds = multi_impact_continuation(pair_orbit, "K[1,1]", (1.0, 4.0), progress=False,
                                   both_directions=True)
    assert "GR" in ds["special_label"].values.tolist()
    assert _resolve_every_point(ds, pair, {"K11": "K[1,1]"}, 1, 1) < 1e-8


def test_loaded_pair_branch_in_the_forcing_amplitude(loaded_orbit):
    """The constant force (held by the springs: the contact search applies): SN, ZV, PD in
    F0, every point re-solved, the PD witnessed by the simulator."""
    with pytest.warns(RuntimeWarning, match="stopped at max_points=50"):  # kept short
        ds = multi_impact_continuation(loaded_orbit, "F0", (0.2, 3.0), progress=False,
                                       both_directions=True, max_points=50)
    assert {"SN", "PD", "ZV"} <= set(ds["special_label"].values.tolist())
    assert bool(ds["physical"].values.any())
    assert _resolve_every_point(ds, loaded, {"F0": "F0"}, 1, 1) < 1e-8
    k = _specials(ds, "PD")[0]
    orbit = _solve_quietly(loaded(F0=float(ds["special_F0"].values[k])), 1, 1,
                           _special_guess(ds, k))
    assert orbit.physical
    assert np.min(np.abs(_simulated_multipliers(orbit) + 1.0)) < 1e-5


# ------------------------------------------------------------------------------------------
# What cannot be checked yet is said, not computed wrong
# ------------------------------------------------------------------------------------------
def test_a_pushed_free_mode_is_checked(caplog):
    """A ball under gravity bouncing on the primary: the constant force moves the free mode
    by a polynomial in time, which the interior-contact search represents exactly
    (tests/kernel/test_contact.py). The motion is physical (the simulated flight lasts
    the whole period: no contact inside it) and the branch reports no unchecked contact."""
    osc = ic.ImpactOscillator(M=np.diag([1.0, MU]), K=[[1.0, 0.0], [0.0, 0.0]],
                              F=[1.0, 0.0], F_static=[0.0, -MU * 0.5], R=0.7, b=50.0,
                              omega=1.3, eta=0.05,
                              stops=Stops(mass=2, relative_to=1, b_low=0.0, R_low=0.7))
    T = 2 * math.pi / osc.omega
    A = 1.0 / (1.0 - osc.omega ** 2)
    x1 = -A
    orbit = multi_impact_orbit(osc, 1, 1, {"delta": -math.pi, "flight_times": [T],
                                           "states": [[x1, x1, 0.0, 0.25 * T]],
                                           "pattern": "L"})
    assert orbit.impact_velocity > 0 and orbit.residual < 1e-10
    assert orbit.physical and 0 < orbit.flight_gap_min[0] < math.inf
    res = ic.simulate(osc, orbit.states[0], float(orbit.phases[0]), 1.5)
    assert res.impact_stops[0] == "L"
    assert res.impact_times[0] == pytest.approx(T, rel=0, abs=1e-8)
    with (caplog.at_level(logging.WARNING, logger="impactcont.analysis.branch"),
          pytest.warns(RuntimeWarning, match="stopped at max_points=6")):  # a few points
        ds = multi_impact_continuation(orbit, "omega", (1.2, 1.4), progress=False,
                                       max_points=6)
    assert ds["physical"].values.all()
    assert "not checked" not in ds.attrs["options"]
    assert not [r for r in caplog.records if "not checked" in r.getMessage()]


def test_grazing_of_a_clearance_between_masses_becomes_an_impact(pair_branch):
    """The graze of the pair clearance as a new impact: on the stop s = x2 - x1 = b (not
    x2 = b), with the two-body law (momentum kept); the N-2 branch born there is physical
    with a small new impact velocity, and its motions solve on fresh oscillators."""
    orbit = special_orbit(pair_branch, "GR", 0)
    guess, new = grazing_split(orbit)
    X = guess["states"][new]
    osc = orbit.oscillator
    normal = osc.stops.normal(osc.n)
    stop = guess["pattern"][new]
    assert normal @ X[:2] == pytest.approx(osc.stops.position(stop, osc.b), abs=1e-12)
    assert abs(normal @ X[2:]) < 1e-6  # a graze: no relative velocity
    ds = grazing_switch(pair_branch, 0, max_points=4)
    assert ds is not None and bool(ds["physical"].values.all())
    v = ds["impact_velocity_k"].values[:, new]
    assert 0 < v[0] < 1e-3 and np.all(np.diff(v) > 0)
    assert _resolve_every_point(ds, pair, {"omega": "omega"}, 1, 2) < 1e-8
