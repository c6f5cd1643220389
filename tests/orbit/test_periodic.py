"""Closed-form N-1 motions (eq. 12-16) and G (eq. 25) against the simulator.

Elastic impacts without damping (R = 1, C = 0): eq. (12) is singular, the motions are not.

For R = 1 and no damping ``I - D U W(T) U^-1`` is singular at every omega (in modal
form ``Delta = (1 - R)/2 + kappa sum c_i h_i = 0``); the periodic motions are
isolated and fixed by ``x1p'(delta) = 0`` and the impact condition. Witnesses:
the published closed form for one mass (Budd & Dux), the exact event-driven
impact map (fixed point, finite-difference G), and the limit of vanishing damping.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont import Flow, ParameterError, amplitude_squared, periodic_orbits, simulate
from impactcont.simulate import next_impact

PAPER_G0 = np.array([
    [-0.177445, 0.039713, -0.070643, 0.345996],
    [-0.020169, 0.323905, 0.144022, -0.213799],
    [0.262554, -0.049062, -0.179735, -0.154322],
    [0.090393, 0.292730, 0.161324, 0.112559],
])


def simulated_impact_map(osc, N, z):
    """The impact map on the section x1 = b, by the event-driven simulator.

    z = [x2..xn, x1'..xn', delta] right after an impact -> the same right after the next one.
    """
    n = osc.n
    X = np.concatenate([[osc.b], z[: 2 * n - 1]])
    delta = z[-1]
    T = 2 * math.pi * N / osc.omega
    hit = next_impact(Flow(osc), X, delta, 1.5 * T)
    assert hit is not None, "the simulated orbit has no next impact"
    tc, X_minus = hit
    X_plus = X_minus.copy()
    X_plus[n] *= -osc.R
    return np.concatenate([X_plus[1:], [delta + osc.omega * tc - 2 * math.pi * N]])


def section_point(orbit):
    return np.concatenate([orbit.state[1:], [orbit.delta]])


def simulated_map_jacobian(osc, N, z0, h=1e-6):
    """Central differences (step h) of :func:`simulated_impact_map` at ``z0``: the witness
    of G (eq. 25)."""
    fd = np.empty((z0.size, z0.size))
    for j in range(z0.size):
        e = np.zeros_like(z0)
        e[j] = h
        fd[:, j] = (simulated_impact_map(osc, N, z0 + e)
                    - simulated_impact_map(osc, N, z0 - e)) / (2 * h)
    return fd


def test_paper_amplitude_and_G0(paper):
    assert amplitude_squared(paper, 1) == pytest.approx(1.74355, abs=5e-6)
    orbits = periodic_orbits(paper, 1)
    physical = [o for o in orbits if o.physical]
    assert len(orbits) == 2 and len(physical) == 1
    np.testing.assert_allclose(physical[0].G, PAPER_G0, atol=5e-7)
    assert physical[0].stable


def test_roots_satisfy_eq14_and_periodicity(paper):
    flow = Flow(paper)
    for orbit in periodic_orbits(paper, 1):
        assert orbit.state[0] == pytest.approx(paper.b, abs=1e-14)
        X_T = flow.state(orbit.period, orbit.state, orbit.delta)[0]
        X_plus = X_T.copy()
        X_plus[paper.n] *= -paper.R
        np.testing.assert_allclose(X_plus, orbit.state, atol=1e-13)
        assert X_T[paper.n] == pytest.approx(orbit.impact_velocity, rel=1e-14)


def test_no_motion_when_gap_exceeds_amplitude(paper):
    r = math.sqrt(amplitude_squared(paper, 1))
    assert periodic_orbits(paper.replace(b=1.001 * r), 1) == []
    assert len(periodic_orbits(paper.replace(b=0.999 * r), 1)) == 2


def test_bad_N_raises(paper):
    for bad in (0, -1, 1.5, "2", True):
        with pytest.raises(ParameterError, match="N must be an integer >= 1"):
            periodic_orbits(paper, bad)


CASES = [
    # (n, params, N)
    (1, {"omega": 1.3, "b": 0.2, "R": 0.8, "eta": 0.05}, 1),
    (2, {"omega": 1.0, "b": 0.6}, 1),
    (2, {"omega": 1.2, "b": 0.0}, 1),
    (2, {"omega": 2.4, "b": 0.0}, 2),
    (3, {"omega": 1.1, "b": 0.1}, 1),
    (3, {"omega": 3.0, "b": -0.2}, 2),
    (12, {"omega": 0.7, "b": 0.05}, 1),
]


def _system(n, params, paper, make_chain):
    if n == 2:
        return paper.replace(**params)
    return make_chain(n, **params)


def _all_orbits(paper, make_chain):
    for n, params, N in CASES:
        osc = _system(n, params, paper, make_chain)
        orbits = periodic_orbits(osc, N)
        assert orbits, (n, params, N)
        yield from orbits


@pytest.mark.parametrize("case", range(len(CASES)))
def test_G_against_finite_differences_of_simulated_map(case, paper, make_chain):
    n, params, N = CASES[case]
    osc = _system(n, params, paper, make_chain)
    for orbit in periodic_orbits(osc, N):
        if not orbit.impact_velocity > 0.05 or not orbit.gap_min > 0.01:
            continue  # the simulated map is the physical one only
        z0 = section_point(orbit)
        np.testing.assert_allclose(simulated_impact_map(osc, N, z0), z0, atol=1e-11)
        fd = simulated_map_jacobian(osc, N, z0)
        scale = max(1.0, np.abs(orbit.G).max())
        assert np.abs(fd - orbit.G).max() < 1e-7 * scale, (orbit, fd - orbit.G)


def test_liouville_determinant(paper, make_chain):
    """det G = R^2 exp(-T tr(M^-1 C)) for every root, physical or not."""
    for orbit in _all_orbits(paper, make_chain):
        osc = orbit.oscillator
        trace = np.trace(np.linalg.solve(osc.M, osc.C))
        expected = osc.R**2 * math.exp(-orbit.period * trace)
        assert np.linalg.det(orbit.G) == pytest.approx(expected, rel=1e-9, abs=1e-300)
        assert np.prod(orbit.multipliers).real == pytest.approx(expected, rel=1e-8)


def test_physical_orbits_are_reproduced_by_simulation(paper, make_chain):
    for orbit in _all_orbits(paper, make_chain):
        if not orbit.physical:
            continue
        res = simulate(orbit.oscillator, orbit.state, orbit.delta, 5 * orbit.N + 0.5)
        assert res.success
        assert res.impact_times.size == 5
        np.testing.assert_allclose(res.impact_times, orbit.period * np.arange(1, 6),
                                   rtol=0, atol=1e-9 * orbit.period)
        np.testing.assert_allclose(res.impact_velocities, orbit.impact_velocity, rtol=1e-9)
        np.testing.assert_allclose(res.impact_states[-1], orbit.state, atol=1e-9)


def test_non_physical_roots_are_flagged_with_a_reason(paper):
    orbits = periodic_orbits(paper, 1)
    bad = [o for o in orbits if not o.physical]
    assert len(bad) == 1
    assert bad[0].impact_velocity < 0
    assert "impact velocity" in bad[0].reason


def test_gap_min_against_dense_sampling(paper, make_chain):
    for orbit in _all_orbits(paper, make_chain):
        _, X = orbit.time_series(num=200_001)
        x1 = X[:, 0]
        inner = (x1[1:-1] > x1[:-2]) & (x1[1:-1] >= x1[2:])
        peaks = x1[1:-1][inner]
        if peaks.size == 0:
            assert math.isinf(orbit.gap_min)
            continue
        sampled = orbit.oscillator.b - peaks.max()
        # the located maximum is at least as high as any sample, and close to the best one
        assert orbit.gap_min <= sampled + 1e-14
        assert orbit.gap_min == pytest.approx(sampled, abs=1e-8)


def test_grazing_orbit_is_flagged_by_interior_contact(paper):
    """At b = 0, omega = 2.6 the N = 3 roots enter the stop inside the period (eq. 16)."""
    for orbit in periodic_orbits(paper.replace(b=0.0, omega=2.6), 3):
        assert not orbit.physical
        assert orbit.gap_min < 0
        # the simulator from the same start sees an earlier impact
        res = simulate(orbit.oscillator, orbit.state, orbit.delta, 3.0)
        if orbit.impact_velocity > 0:
            assert res.impact_times[0] < 0.99 * orbit.period


def _perturbed_start(orbit, size):
    rng = np.random.default_rng(3)
    z = section_point(orbit) + size * rng.normal(size=orbit.state.size)
    return np.concatenate([[orbit.oscillator.b], z[:-1]]), z[-1]


def _section_distance(orbit, res, k):
    z = np.concatenate([res.impact_states[k][1:], [res.impact_phases[k]]])
    d = z - section_point(orbit)
    d[-1] = math.remainder(d[-1], 2 * math.pi)
    return np.abs(d).max()


def test_stable_orbit_attracts_a_nearby_start(paper):
    orbit = next(o for o in periodic_orbits(paper, 1) if o.physical)
    X, delta = _perturbed_start(orbit, 1e-3)
    res = simulate(paper, X, delta, 30.5)
    d0, d_end = _section_distance(orbit, res, 0), _section_distance(orbit, res, -1)
    assert d_end < 1e-9 and d_end < d0 * orbit.spectral_radius**20


def test_unstable_orbit_repels_a_nearby_start(paper):
    """A physical but unstable N-1 motion: find one on a branch and check it repels."""
    osc = None
    for omega in np.linspace(2.0, 4.0, 81):
        for orbit in periodic_orbits(paper.replace(b=0.0, omega=float(omega)), 1):
            if orbit.physical and orbit.spectral_radius > 1.2 and orbit.impact_velocity > 0.1:
                osc = orbit.oscillator
                break
        if osc is not None:
            break
    assert osc is not None, "no physical unstable N=1 motion found on the scan"
    X, delta = _perturbed_start(orbit, 1e-7)
    res = simulate(osc, X, delta, 40.5)
    distances = [_section_distance(orbit, res, k) for k in range(min(res.impact_times.size, 30))]
    assert max(distances) > 1e3 * distances[0]


def _one_mass(omega: float, b: float, **params) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[1.0], R=1.0, b=b, omega=omega, **params)


def _budd_dux(omega: float, b: float, N: int) -> list[float]:
    """V = -(b -+ gamma)(1 - cos T)/sin T, gamma = 1/(1 - omega^2), T = 2 pi N / omega."""
    gamma = 1.0 / (1.0 - omega**2)
    T = 2.0 * math.pi * N / omega
    return [-(b - sign * gamma) * (1.0 - math.cos(T)) / math.sin(T) for sign in (+1, -1)]


@pytest.mark.parametrize(("omega", "b", "N"), [(2.8, 0.05, 1), (2.8, 0.05, 2), (1.5, -0.2, 1),
                                               (0.7, 0.3, 1), (3.3, -0.1, 3)])
def test_one_mass_matches_the_published_closed_form(omega, b, N):
    osc = _one_mass(omega, b)
    orbits = ic.periodic_orbits(osc, N)
    assert len(orbits) == 2
    expected = sorted(_budd_dux(omega, b, N))
    for orbit, v in zip(sorted(orbits, key=lambda o: o.impact_velocity), expected, strict=True):
        assert orbit.impact_velocity == pytest.approx(v, rel=1e-12)
        assert orbit.state[0] == pytest.approx(b, abs=1e-14)
        # the phase: the forced motion gamma cos(omega t + delta) of the mass is at rest
        assert math.sin(orbit.delta) == pytest.approx(0.0, abs=1e-15)


def test_one_mass_issue_case_is_the_published_velocity():
    """The case reported wrong before: omega = 2.8, b = 0.05 -> 0.19976 (was 0.1429)."""
    physical = [o for o in ic.periodic_orbits(_one_mass(2.8, 0.05), 1) if o.physical]
    assert len(physical) == 1
    assert physical[0].impact_velocity == pytest.approx(0.19976, abs=5e-6)


def _elastic_chain(n: int, omega: float, b: float) -> ic.ImpactOscillator:
    rng = np.random.default_rng(7 + n)
    F = np.zeros(n)
    F[0] = 1.0
    return ic.ImpactOscillator.chain(masses=1.0 + 0.5 * rng.random(n),
                                     springs=1.0 + rng.random(n), F=F, R=1.0, b=b, omega=omega)


@pytest.mark.parametrize(("n", "omega", "b"), [(1, 2.8, 0.05), (2, 2.3, 0.1), (3, 2.9, 0.05),
                                               (3, 1.7, -0.1)])
def test_elastic_motions_are_fixed_points_of_the_exact_impact_map(n, omega, b):
    osc = _elastic_chain(n, omega, b)
    orbits = ic.periodic_orbits(osc, 1)
    assert len(orbits) == 2
    checked = 0
    for orbit in orbits:
        # periodicity through the exact flow, whatever the physical flag
        X_T = ic.Flow(osc).state(orbit.period, orbit.state, orbit.delta)[0]
        assert X_T[0] == pytest.approx(b, abs=1e-12)
        assert X_T[n] == pytest.approx(orbit.impact_velocity, rel=1e-12, abs=1e-13)
        X_plus = X_T.copy()
        X_plus[n] *= -1.0
        np.testing.assert_allclose(X_plus, orbit.state, atol=1e-12)
        if not (orbit.physical and orbit.impact_velocity > 0.05 and orbit.gap_min > 0.01):
            continue
        checked += 1
        z0 = section_point(orbit)
        np.testing.assert_allclose(simulated_impact_map(osc, 1, z0), z0, atol=1e-11)
        fd = simulated_map_jacobian(osc, 1, z0)
        assert np.abs(fd - orbit.G).max() < 1e-7 * max(1.0, np.abs(orbit.G).max())
        # area preserving: det G = R^2 exp(-T tr M^-1 C) = 1
        assert abs(np.prod(orbit.multipliers)) == pytest.approx(1.0, rel=1e-9)
    assert checked >= 1 or n == 3


@pytest.mark.parametrize("eta", [1e-6, 1e-9])
def test_vanishing_damping_tends_to_the_elastic_motions(eta):
    """Light damping is a regular case; its motions converge to the elastic ones (O(eta))."""
    elastic = ic.periodic_orbits(_elastic_chain(2, 2.3, 0.1), 1)
    damped = ic.periodic_orbits(_elastic_chain(2, 2.3, 0.1).replace(eta=eta), 1)
    by_velocity = sorted(damped, key=lambda o: o.impact_velocity)
    for e, d in zip(sorted(elastic, key=lambda o: o.impact_velocity), by_velocity, strict=True):
        assert abs(math.remainder(e.delta - d.delta, 2 * math.pi)) < 1e3 * eta
        assert d.impact_velocity == pytest.approx(e.impact_velocity, rel=1e3 * eta)


def test_no_forced_motion_of_mass_one_is_refused():
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[2.0, 0.0], [0.0, 3.0]], F=[0.0, 1.0], R=1.0, b=0.1,
                              omega=1.3)
    with pytest.raises(ic.ParameterError, match="no forced motion of mass 1"):
        ic.periodic_orbits(osc, 1)


@pytest.mark.parametrize(("parameter", "bounds", "params"), [
    ("omega", (2.0, 3.0), {}), ("b", (0.0, 0.2), {}), ("R", (0.5, 1.0), {}),
    ("eta", (0.0, 0.1), {"eta": 0.05})])
def test_continuation_into_the_elastic_undamped_case_is_refused(parameter, bounds, params):
    osc = _one_mass(2.8, 0.05, **params)
    if parameter == "R":
        osc = osc.replace(R=0.7)
    with pytest.raises(ic.ParameterError, match="elastic impacts without damping"):
        ic.continuation(osc, 1, parameter, bounds)


def test_continuation_with_restitution_below_one_is_not_refused():
    osc = _one_mass(2.8, 0.05).replace(R=0.7)
    assert ic.continuation(osc, 1, "R", (0.5, 0.9)).sizes["point"] > 1


@pytest.mark.parametrize("damping", ["modal", "general"])
def test_impact_states_are_the_states_of_periodic_orbits(damping):
    """impact_states, the states after the impact of many N-1 motions at once (the family
    map of an N-1 motion by the closed form), equals each motion's own state (eq. 13) on the
    modal path (proportional damping) and on the first-order path (a general damping
    matrix), for both roots at several frequencies, to rounding."""
    from impactcont.orbit.periodic import impact_states

    C = {"modal": None, "general": [[0.3, -0.1], [-0.1, 0.05]]}[damping]
    damped = {"eta": 0.1} if C is None else {"C": C}
    base = ic.ImpactOscillator(M=np.eye(2), K=[[2.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.3, omega=1.0, **damped)
    assert base.general == (damping == "general")
    checked = 0
    for omega in (0.8, 1.2, 2.5):
        osc = base.replace(omega=omega)
        for N in (1, 2):
            orbits = periodic_orbits(osc, N)
            if not orbits:
                continue
            X = impact_states(osc, N, np.array([o.delta for o in orbits]),
                              np.array([o.impact_velocity for o in orbits]))
            assert X.shape == (len(orbits), 4)
            for x, o in zip(X, orbits, strict=True):
                np.testing.assert_allclose(x, o.state, rtol=0, atol=1e-12)
                checked += 1
    assert checked >= 6
    with pytest.raises(ParameterError, match=r"delta and sigma must be 1-D arrays of the same "
                                             r"length; got shapes \(2,\) and \(1,\)"):
        impact_states(base, 1, np.zeros(2), np.zeros(1))


def test_physical_transition_of_complex_pieces_is_two_real_ones():
    """Complex-stepped modal pieces (the N-1 curves' Jacobian) take two real transitions:
    the same sums as the compiled loops in complex arithmetic, to the last bit."""
    from impactcont.kernel import closed_form, flights
    from impactcont.orbit.periodic import modal_arrays, physical_transition

    osc = ic.ImpactOscillator.chain(masses=[1.0, 0.5, 2.0], springs=[1.0, 2.0, 0.7],
                                    F=[1.0, 0.0, 0.2], R=0.7, b=0.1, omega=1.3, eta=0.05)
    arrays = modal_arrays(osc)
    modal, _ = closed_form.omega_setup(arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0,
                                       arrays.eig_err, osc.R, osc.omega, 1)
    stepped = modal + 1j * 1e-30 * np.arange(1.0, 1.0 + modal.size).reshape(modal.shape)
    tr = physical_transition(osc, stepped)
    assert tr.dtype == complex
    np.testing.assert_array_equal(tr, flights.transition(stepped, arrays.u, arrays.ui))
