"""The product of flight Jacobians and its exact derivatives (impactcont.kernel.half_map).

At generic unknowns (no motion: the product is defined at any shot), the product is the
shooting kernel's ``jacobian_product`` operation for operation, and its derivatives along
every unknown, the stops' positions and omega agree with central differences of that
product over new shots (the moved stops and omega by a new flow and stop geometry): within
what differences of step 1e-6 give (1e-6 relative to the largest entry). The two factors
of the BP test, ``sign(det A)`` and ``s_min(A)``, are numpy's (the smallest singular value
within rounding of the largest) with singular vectors that satisfy ``A b = s_min a``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel.half_map import jacobian_product_derivative, smallest_singular_value
from impactcont.kernel.shooting import jacobian_product
from impactcont.model.parameters import model_parameter
from impactcont.model.stops import Stops
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import impact_sequence, shooting, shot_flights
from impactcont.orbit.stop_geometry import stop_geometry

K2 = [[1.0, -1.0], [-1.0, 2.0]]
K3 = [[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]]
CASES = {
    # (oscillator, N, pattern, flights of the product, the parameters moving the stops)
    "backlash 1-2, the half-map's one flight": (
        ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.8, omega=0.8, eta=0.1,
                            stops=Stops(b_low=0.8)), 1, "LU", 1, ("b", "b_low")),
    "mass 2, unequal stops, two flights": (
        ic.ImpactOscillator(M=np.eye(3), K=K3, F=[1.0, 0.0, 0.0], R=0.7, b=0.5, omega=1.4,
                            eta=0.15, stops=Stops(mass=2, b_low=0.4, R_low=0.8)),
        2, "ULU", 2, ("b", "b_low")),
    "paper 3-3, two flights": (
        ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.1, omega=1.9, eta=0.1),
        3, "UUU", 2, ("b",)),
}


def _unknowns(osc: ic.ImpactOscillator, N: int, p: int) -> np.ndarray:
    """Generic unknowns: a phase, equal flight times and small section coordinates."""
    rng = np.random.default_rng(7)
    taus = np.full(p - 1, 2.0 * math.pi * N / (osc.omega * p)) * (1.0 + 0.1 * rng.random(p - 1))
    z = 0.2 * rng.standard_normal(p * (2 * osc.n - 1))
    return np.concatenate([[0.3], taus, z])


def _product(osc: ic.ImpactOscillator, N: int, pattern: str, u: np.ndarray, count: int
             ) -> np.ndarray:
    """``G_{count-1} .. G_0`` of a new shot of `u` on `osc`."""
    flow = Flow(osc)
    sh = shooting(flow, N, len(pattern), u, pattern=pattern)
    return jacobian_product(tuple(impact_sequence(stop_geometry(osc, pattern))), osc.omega,
                            tuple(shot_flights(sh)), count)


def _derivative(osc: ic.ImpactOscillator, N: int, pattern: str, u: np.ndarray, count: int,
                directions: tuple[np.ndarray, np.ndarray, np.ndarray]
                ) -> tuple[np.ndarray, np.ndarray]:
    du, dc, dw = directions
    flow = Flow(osc)
    sh = shooting(flow, N, len(pattern), u, pattern=pattern)
    n = osc.n
    Minv = np.linalg.inv(osc.M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ osc.K, -Minv @ osc.C]])
    dG = np.empty((du.shape[0], 2 * n, 2 * n))
    G = jacobian_product_derivative(
        tuple(flow.shooting_arrays()), tuple(flow.forcing_arrays()), tuple(flow.omega_arrays()),
        tuple(impact_sequence(stop_geometry(osc, pattern))), tuple(shot_flights(sh)), A,
        Minv @ np.asarray(osc.F, dtype=float), du, dc, dw, count, dG)
    return G, dG


@pytest.mark.parametrize("case", CASES)
def test_the_derivatives_agree_with_central_differences(case):
    osc, N, pattern, count, moving = CASES[case]
    p = len(pattern)
    u = _unknowns(osc, N, p)
    size = u.size
    params = [model_parameter(osc, name) for name in moving]
    d = size + len(params) + 1  # every unknown, each parameter moving the stops, omega
    du = np.zeros((d, size))
    du[:size] = np.eye(size)
    dc = np.zeros((d, p))
    for i, par in enumerate(params):
        dc[size + i] = par.stop_rates(pattern)
    dw = np.zeros(d)
    dw[-1] = 1.0
    G, dG = _derivative(osc, N, pattern, u, count, (du, dc, dw))
    np.testing.assert_array_equal(G, _product(osc, N, pattern, u, count))
    scale = np.abs(dG).max()

    def check(i: int, plus: np.ndarray, minus: np.ndarray, h: float) -> None:
        fd = (plus - minus) / (2.0 * h)
        np.testing.assert_allclose(dG[i], fd, rtol=1e-6, atol=1e-6 * scale, err_msg=str(i))

    for i in range(size):
        h = 1e-6 * max(1.0, abs(u[i]))
        e = np.zeros(size)
        e[i] = h
        check(i, _product(osc, N, pattern, u + e, count),
              _product(osc, N, pattern, u - e, count), h)
    for i, par in enumerate(params):
        h = 1e-6
        value = par.value(osc)
        check(size + i, _product(par.at(osc, value + h), N, pattern, u, count),
              _product(par.at(osc, value - h), N, pattern, u, count), h)
    h = 1e-6
    check(d - 1, _product(osc.replace(omega=osc.omega + h), N, pattern, u, count),
          _product(osc.replace(omega=osc.omega - h), N, pattern, u, count), h)
    # the first `count` flights' unknowns and starting stops and omega move the product; the
    # later flights' do not
    q = 2 * osc.n - 1
    moves = np.ones(d, dtype=bool)
    moves[1 + count:p] = False
    moves[p + count * q:size] = False
    moves[size:d - 1] = np.abs(dc[size:d - 1, :count]).max(axis=1) > 0.0
    size_of = np.abs(dG).max(axis=(1, 2))
    assert np.all(size_of[moves] > 1e-6 * scale) and np.all(size_of[~moves] == 0.0)


def test_no_direction_gives_the_product_alone():
    osc, N, pattern, count, _ = CASES["backlash 1-2, the half-map's one flight"]
    u = _unknowns(osc, N, len(pattern))
    G, dG = _derivative(osc, N, pattern, u, count,
                        (np.zeros((0, u.size)), np.zeros((0, 2)), np.zeros(0)))
    assert dG.shape == (0, 4, 4)
    np.testing.assert_array_equal(G, _product(osc, N, pattern, u, count))


@pytest.mark.parametrize("matrix", [
    np.diag([2.0, -3.0, 0.5, 4.0]),
    np.random.default_rng(3).standard_normal((4, 4)),
    np.array([[0.0, -1.0], [1.0, 0.0]]) * 0.5,
    np.eye(3) + np.outer([1.0, 2.0, 3.0], [1.0, 0.0, -1.0]) * 1e-3,
])
def test_the_smallest_singular_value_is_numpys(matrix):
    left, right = np.empty(matrix.shape[0]), np.empty(matrix.shape[0])
    sign, smallest = smallest_singular_value(matrix.copy(), left, right)
    singular = np.linalg.svd(matrix, compute_uv=False)
    assert sign == np.linalg.slogdet(matrix)[0]
    assert abs(smallest - singular[-1]) <= 1e-14 * singular[0]
    np.testing.assert_allclose(matrix @ right, smallest * left, atol=1e-14 * singular[0])
    assert np.linalg.norm(left) == pytest.approx(1.0) and np.linalg.norm(right) == \
        pytest.approx(1.0)


def test_the_smallest_singular_value_of_a_matrix_not_finite_is_nan():
    matrix = np.eye(3)
    matrix[1, 2] = np.inf
    left, right = np.zeros(3), np.zeros(3)
    sign, smallest = smallest_singular_value(matrix, left, right)
    assert math.isnan(sign) and math.isnan(smallest)
    assert np.isnan(left).all() and np.isnan(right).all()
