"""The closed-form pieces on the first-order path (:mod:`impactcont.problems.general_pieces`):
on an oscillator with non-proportional damping they give the motions of
``periodic_orbits`` (eq. 14 at their phases, their state, impact velocity and G), their
complex steps in ``b`` and ``F0`` are the derivatives central differences give, and the
pole-free PD matrix has ``det E = -h2 det(G + I)``."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.problems.general_pieces import (
    STEPPED_PARAMETERS,
    GeneralPieces,
    bordered_condition,
    impact_condition_form,
)

C = [[0.25, -0.05], [-0.05, 0.08]]  # not proportional to M and K: the first-order path


def _osc(**changes) -> ic.ImpactOscillator:
    base = {"M": np.eye(2), "K": [[1.0, -1.0], [-1.0, 2.0]], "C": np.array(C),
            "F": [1.0, 0.0], "R": 0.6, "b": 0.5, "omega": 1.0}
    return ic.ImpactOscillator(**{**base, **changes})


@pytest.fixture(scope="module")
def pieces() -> GeneralPieces:
    return GeneralPieces.at(_osc(), 1)


@pytest.fixture(scope="module")
def orbits():
    orbits = ic.periodic_orbits(_osc(), 1)
    assert len(orbits) == 2 and _osc().general
    return orbits


def test_the_pieces_give_the_motions_of_the_closed_form(pieces, orbits) -> None:
    c, s = pieces.S0
    assert abs(pieces.T - 2 * math.pi) < 1e-12  # omega = 1
    for orbit in orbits:
        d = orbit.delta
        assert abs(c * math.cos(d) + s * math.sin(d) - 0.5) < 1e-12  # eq. (14)
        np.testing.assert_allclose(pieces.state(d), orbit.state, rtol=1e-9, atol=1e-11)
        assert pieces.impact_velocity(d) == pytest.approx(orbit.impact_velocity, rel=1e-9)
        G, h2 = pieces.jacobian(d)
        assert h2 == pytest.approx(orbit.impact_velocity, rel=1e-9)
        np.testing.assert_allclose(G, orbit.G, rtol=1e-8, atol=1e-10)
        x1, v1 = pieces.mass1(d, 0.0)
        assert x1 == pytest.approx(0.5, abs=1e-12)  # at the stop right after the impact
        assert v1 == pytest.approx(orbit.state[2], rel=1e-9)  # -R h2 (eq. 4)


def test_the_pole_free_pd_matrix(pieces, orbits) -> None:
    for orbit in orbits:
        G, h2 = pieces.jacobian(orbit.delta)
        E = pieces.pole_free_pd_matrix(orbit.delta)
        assert E.shape == (G.shape[0] + 1,) * 2
        assert np.linalg.det(E) == pytest.approx(-h2 * np.linalg.det(G + np.eye(G.shape[0])),
                                                 rel=1e-9)


@pytest.mark.parametrize("name", STEPPED_PARAMETERS)
def test_a_complex_step_of_b_and_F0_is_the_derivative(pieces, orbits, name) -> None:
    h = 1e-30
    delta = orbits[0].delta
    stepped = pieces.stepped(name, h)
    value = 0.5 if name == "b" else 1.0
    step = 1e-6

    def at(p: float) -> GeneralPieces:
        osc = _osc(b=p) if name == "b" else _osc(F=[p, 0.0])
        return GeneralPieces.at(osc, 1)

    plus, minus = at(value + step), at(value - step)
    fd = (plus.impact_velocity(delta) - minus.impact_velocity(delta)) / (2 * step)
    assert stepped.impact_velocity(delta).imag / h == pytest.approx(fd, rel=1e-6)
    fd_state = (plus.state(delta) - minus.state(delta)) / (2 * step)
    np.testing.assert_allclose(stepped.state(delta).imag / h, fd_state, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(stepped.state(delta).real, pieces.state(delta), rtol=1e-14)


def test_nothing_stepped_and_a_bad_name(pieces, orbits) -> None:
    same = pieces.stepped(None, 1e-30)
    assert same.impact_velocity(orbits[0].delta) == pytest.approx(
        pieces.impact_velocity(orbits[0].delta), rel=1e-15)
    with pytest.raises(ValueError, match=r"name must be None or one of \('b', 'F0'\); got "
                                         r"'omega'"):
        pieces.stepped("omega", 1e-30)


def test_a_complex_time_step_is_the_next_derivative(pieces, orbits) -> None:
    delta, t, h = orbits[0].delta, 0.7, 1e-30
    _, v, a = pieces.mass1_derivatives(delta, t, 3)
    xs, vs, _ = pieces.mass1_derivatives(delta, complex(t, h), 3)
    assert xs.imag / h == pytest.approx(v, rel=1e-12)
    assert vs.imag / h == pytest.approx(a, rel=1e-12)
    fd = (pieces.mass1(delta, t + 1e-6)[0] - pieces.mass1(delta, t - 1e-6)[0]) / 2e-6
    assert v == pytest.approx(fd, rel=1e-7)


def test_dc_ds_in_omega_and_R(pieces) -> None:
    for which, make in (("omega", lambda p: _osc(omega=p)), ("R", lambda p: _osc(R=p))):
        value = 1.0 if which == "omega" else 0.6
        plus, minus = (GeneralPieces.at(make(value + d), 1).S0 for d in (1e-6, -1e-6))
        fd = (np.array(plus) - np.array(minus)) / 2e-6
        np.testing.assert_allclose(pieces.cs_derivative(which), fd, rtol=1e-6, atol=1e-9)


def test_bordered_condition_solves_the_bordered_system() -> None:
    E = np.array([[2.0, 1.0], [0.0, 3.0]])
    left, right = np.array([1.0, 0.0]), np.array([1.0, 1.0])
    A = np.block([[E, left[:, None]], [right[None, :], np.zeros((1, 1))]])
    expected = np.linalg.solve(A, [0.0, 0.0, 1.0])[-1]
    assert bordered_condition(E, left, right) == pytest.approx(expected)
    assert math.isnan(bordered_condition(np.zeros((2, 2)), np.zeros(2), np.zeros(2)))


def test_the_impact_condition_form_is_taken_where_the_other_cancels() -> None:
    # the paper's scale: |rho| = |kappa omega g / Delta| small, the velocity form
    assert not impact_condition_form(1.0, 0.5, 0.3, 0.4, 1.3, 0.6, 0.5)
    # elastic impacts without damping: Delta = 0
    assert impact_condition_form(1.0, 0.5, 0.3, 0.0, 1.3, 1.0, 0.5)
    # far above the natural frequencies: |c, s| >> b, the velocity form cancels
    assert impact_condition_form(1e9, 1e9, 1e3, 1e-6, 300.0, 0.6, 0.3)
