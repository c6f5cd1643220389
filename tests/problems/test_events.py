"""The test functions of the special points (:mod:`impactcont.problems.events`): each changes
sign across the special point the continuation located (on motions of the closed form just
before and after it), the PD and NS products are free of the pole of G at ``h2 = 0`` (against
determinants of ``G = A + x y^T / h2``), and their rounding estimate is far below their
size away from the point."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.core.locate import MotionTest
from impactcont.problems.events import PITCHFORK, event_function, event_noise, pole_free

K = [[1.0, -1.0], [-1.0, 2.0]]


def _paper(b: float, omega: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=K, F=[1.0, 0.0], R=0.6, b=b, omega=omega,
                               eta=0.1)


@pytest.fixture(scope="module")
def specials() -> dict[str, tuple[float, float, float]]:
    """``label -> (b, omega, delta)`` of special points located by the continuation."""
    out = {}
    for b, bounds, detect in ((0.5, (1.1, 1.3), ("NS", "PD", "ZV")), (0.6, (0.5, 3.0), ("GR",))):
        branch = ic.continuation(_paper(b, 1.0), N=1, bounds=bounds, detect=detect)
        for label, omega, delta in zip(branch["special_label"].values,
                                       branch["special_omega"].values,
                                       branch["special_delta"].values, strict=True):
            out.setdefault(str(label), (b, float(omega), float(delta)))
    return out


def _nearest(b: float, omega: float, delta: float):
    """The root of eq. (15) at (b, omega) whose phase is nearest ``delta``."""
    orbits = ic.periodic_orbits(_paper(b, omega), 1)
    return min(orbits, key=lambda o: abs(np.angle(np.exp(1j * (o.delta - delta)))))


@pytest.mark.parametrize("label", ["PD", "NS", "ZV", "GR"])
def test_the_test_function_changes_sign_at_the_located_point(specials, label) -> None:
    b, omega, delta = specials[label]
    before, after = (_nearest(b, omega + dw, delta) for dw in (-1e-4, 1e-4))
    f0, f1 = event_function(label, before), event_function(label, after)
    assert f0 * f1 < 0, (f0, f1)
    for orbit, value in ((before, f0), (after, f1)):
        noise = event_noise(label, orbit)
        assert 0 < noise < 1e-6 * abs(value)  # the sign is certain this far from the point


def test_the_test_functions_are_the_motions_own_numbers(specials) -> None:
    b, omega, delta = specials["PD"]
    orbit = _nearest(b, omega - 1e-3, delta)
    assert event_function("GR", orbit) == orbit.gap_min
    assert event_function("ZV", orbit) == orbit.impact_velocity
    mu = orbit.multipliers
    assert event_function("PD", orbit) == pytest.approx(
        float(np.prod(mu + 1.0).real) * orbit.impact_velocity, rel=1e-12)
    i, j = np.triu_indices(mu.size, 1)
    assert event_function("NS", orbit) == pytest.approx(
        float(np.prod(mu[i] * mu[j] - 1.0).real) * orbit.impact_velocity ** (mu.size - 1),
        rel=1e-12)
    with pytest.raises(ValueError, match=r"label must be one of PD, NS, GR, ZV, FT here; got 'SN'"):
        event_function("SN", orbit)


def test_the_pd_and_ns_products_are_free_of_the_pole_at_h2_zero() -> None:
    """``G = A + x y^T / h``: ``h det(G + I)`` is affine in h (the matrix determinant lemma),
    ``det(A + I) h + y^T adj(A + I) x``; the products stay finite as h -> 0."""
    rng = np.random.default_rng(3)
    A, x, y = 0.3 * rng.standard_normal((4, 4)), rng.standard_normal(4), rng.standard_normal(4)
    limit = float(y @ (np.linalg.det(A + np.eye(4)) * np.linalg.inv(A + np.eye(4))) @ x)
    values = []
    for h in (1e-2, 1e-4, 1e-6):
        G = A + np.outer(x, y) / h
        mu = np.linalg.eigvals(G)
        pd = pole_free("PD", mu, np.array([h]))
        assert pd == pytest.approx(h * np.linalg.det(G + np.eye(4)), rel=1e-6)
        assert pd == pytest.approx(np.linalg.det(A + np.eye(4)) * h + limit, rel=1e-6)
        values.append(pole_free("NS", mu, np.array([h])))
    assert all(math.isfinite(v) for v in values)
    assert values[-1] == pytest.approx(values[-2], rel=1e-2)  # converges as h -> 0
    # an N-p motion: one factor h_k per impact
    mu = np.array([0.5, -0.2, 0.1 + 0.3j, 0.1 - 0.3j])
    assert pole_free("PD", mu, np.array([2.0, 3.0])) == pytest.approx(
        6.0 * float(np.prod(mu + 1).real))


def test_the_noise_of_non_finite_multipliers_is_infinite(specials) -> None:
    b, omega, delta = specials["PD"]
    orbit = _nearest(b, omega - 1e-3, delta)

    class Broken:
        multipliers = np.array([np.inf, 0.5, 0.1, 0.2])
        impact_velocity = orbit.impact_velocity

    assert event_noise("PD", Broken()) == math.inf
    assert event_noise("SN", orbit) == 0.0


def test_the_pitchfork_is_a_motion_test() -> None:
    assert isinstance(PITCHFORK, MotionTest)


def test_the_pitchfork_declares_the_speeds_that_clear_its_poles() -> None:
    """``det(H + I)`` was multiplied by the speeds at the impacts ending the first half's
    flights (``v_1 .. v_h``): those are its pole quantities, where a step is split
    (issue 28, 1.3: a sign change through a pole is no special point)."""
    from types import SimpleNamespace

    orbit = SimpleNamespace(p=4, impact_velocities=np.array([1.0, 2.0, 3.0, 4.0]))
    np.testing.assert_array_equal(PITCHFORK.poles(orbit), [2.0, 3.0])
    orbit = SimpleNamespace(p=2, impact_velocities=np.array([0.5, -0.25]))
    np.testing.assert_array_equal(PITCHFORK.poles(orbit), [-0.25])


def test_each_kind_is_an_object_declared_with_its_test_noise_and_criticality(specials) -> None:
    """Issue 29, 2: PD, NS, GR and ZV are MotionTest objects as BP; the functions by label
    are views of them, and a label without a test is refused, not read as NS."""
    from impactcont.problems.events import BRANCH_TESTS, NEIMARK_SACKER, PERIOD_DOUBLING
    from impactcont.problems.periodic_branch import PeriodicBranchProblem
    from impactcont.problems.symmetric_branch import SymmetricBranchProblem
    from impactcont.vocabulary import Label

    assert list(BRANCH_TESTS) == [Label.PD, Label.NS, Label.GR, Label.ZV, Label.FT]
    assert all(isinstance(test, MotionTest) for test in BRANCH_TESTS.values())
    assert BRANCH_TESTS[Label.GR].checks and not BRANCH_TESTS[Label.ZV].checks
    b, omega, delta = specials["PD"]
    orbit = _nearest(b, omega - 1e-3, delta)
    for label, test in BRANCH_TESTS.items():
        assert event_function(label, orbit) == test.test(orbit)
        assert event_noise(label, orbit) == test.noise(orbit)
    # the criticality of a zero is the kind's: a multiplier at -1, a complex pair on |mu| = 1
    at_pd = type("Motion", (), {"multipliers": np.array([-1.0 + 1e-9, 0.3, 0.1, 0.2])})()
    at_saddle = type("Motion", (), {"multipliers": np.array([2.0, 0.5, 0.1, 0.2])})()
    assert PERIOD_DOUBLING.critical(at_pd) and not NEIMARK_SACKER.critical(at_pd)
    assert not NEIMARK_SACKER.critical(at_saddle)
    # the problems declare their kinds, the fold SN with no test of a motion
    assert PeriodicBranchProblem.events == (Label.SN, *BRANCH_TESTS)
    assert SymmetricBranchProblem.motion_tests[Label.BP] is PITCHFORK
    with pytest.raises(ValueError, match="label must be PD or NS here; got 'GR'"):
        pole_free("GR", orbit.multipliers, np.array([orbit.impact_velocity]))


def test_the_end_of_a_flight_is_the_shortest_flight_time(specials) -> None:
    """FT's test is the shortest flight time: a one-impact motion's flight lasts its period
    (never 0), with its rounding of eps times the period; its zero is declared a singular
    point of the branch's system, past which the motions are not physical."""
    from impactcont.problems.events import FLIGHT_END, flight_end_test
    from impactcont.vocabulary import Label

    b, omega, delta = specials["PD"]
    orbit = _nearest(b, omega, delta)
    period = 2 * np.pi / orbit.oscillator.omega
    assert flight_end_test(orbit) == pytest.approx(period, rel=1e-14)
    assert 0.0 < FLIGHT_END.noise(orbit) < 1e-12 * period
    assert FLIGHT_END.critical is None and not FLIGHT_END.checks
    two = type("Motion", (), {"flight_times": np.array([3.0, -1e-3])})()
    assert flight_end_test(two) == -1e-3
    assert Label.FT.singular and Label.FT.bounds
